// Scores of the library's candidate effects against a fitted model
// (effects.md, step 3), by linearised tests around the current fit.
//
// Every effect not yet in the model is added at once, its parameters free
// at the values where it is absent (ground_effect's k_ge at 0, bounds
// [0, 3]); one sensitivity pass along the fitted trajectory gives the
// output-error problem linearised there (linearised_fit.h), with each
// candidate's output sensitivities as extra columns. A candidate is scored by
// the score (Lagrange multiplier) test of the nested model: the regression of
// the weighted residuals on its columns with every direction already
// estimated (segment states, current parameters) projected out, the
// Gauss-Newton step of the model with it. The p-value comes from the
// cluster-robust (Hotelling) form of the test, clusters being runs of flight
// rows three residual correlation times long and the holds of balance logs, so
// autocorrelated flight residuals do not inflate it the way the white-noise
// F-test does (kept in the table for comparison). p-values are corrected for
// the candidates tried with Holm's step-down method (family-wise error rate
// like Bonferroni, less conservatively). Its regressors along the data also
// say which channels it can reach, hence the physical reason it would show
// there.
//
// The linearised score ranks and shortlists; it does not decide. The
// shortlisted candidates are refitted (RefitCandidate): a joint nonlinear
// refit with the effect, every declared parameter free (free to leave a bound
// the declared fit pressed it against), then the cluster-robust Wald test of
// its parameters at the refit (linearised there, which is also the next
// round's scoring pass). The loop (discovery.h) decides on the refits.
//
// Linearisations hold what the fit held: the scale member of a flight-only
// fit (model.md decision 8; a moment-type candidate is then judged in the
// identifiable subspace, by its ratio to the held scale) and the declared
// parameters the fit left at a bound (they cannot absorb what the candidate
// explains in the direction the bound blocks).
#pragma once

#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/plausibility.h"
#include "dynamics/vehicle.h"
#include "ident/discover/linearised_fit.h"
#include "ident/estimation_log.h"
#include "ident/output_error/output_error.h"

namespace coaxid {

// One start of a candidate's refit (RefitCandidate) and where it ended.
struct RefitStart {
  std::string from;     // e.g. "its linearised step, the rest at the current fit"
  double cost;          // the fit's objective (output and continuity residuals); inf: failed
  double weighted_rss;  // of the outputs, at the current fit's noise weights
  bool kept;
  double seconds = 0;   // wall time of this start's solve
};

struct CandidateScore {
  std::string effect, description;
  int round = 0;                      // loop round (1 = against the declared model)
  bool testable = false;              // some channel of these logs depends on it, separably
  std::string why_not_testable;
  std::vector<std::string> channels;  // channels its regressors reach
  std::string reason;                 // the physical reason it would show in those channels
  int num_parameters = 0;
  double rss_before = 0, rss_after = 0;  // after: predicted by the linearisation (or the refit), >= 0
  double bic_change = 0;              // predicted: q ln N - (rss_before - rss_after)
  int num_residuals = 0, num_free_parameters = 0;
  int clusters = 0;                   // clusters of the robust test
  double covariance_dof = 0;          // nu of its score covariance
  double statistic = 0;               // cluster-robust score F(q, M - q)
  double p_value = 1;                 // uncorrected
  double p_corrected = 1;             // Holm over the candidates tried this round
  double white_statistic = 0, white_p_value = 1;  // the white-noise score F, for comparison
  bool passes = false;
  // Absent value + Gauss-Newton step, clipped into the parameter bounds;
  // beyond_linear_range when the step left them (the linearisation is then
  // only a direction: the refit decides).
  std::map<std::string, double> linearised_estimates;
  bool beyond_linear_range = false;
  // Predicted drop of the weighted RSS over the weighted excess of every
  // channel (sum of rms^2 - noise^2, in the fit's weights): the shortlist's key.
  double predicted_share = 0;
  // Blind at the bounds (effects.md step 7): a declared parameter the
  // current fit left at a bound distorts channels it reaches only with that
  // parameter back inside (wind acts on u, v through Cx, Cy: with them at 0
  // its sensitivities there vanish and its linearised score says nothing).
  // Its channels include the ones it reaches from there.
  bool blind_at_bounds = false;
  // Declared parameters at a bound whose channels the candidate reaches:
  // its refit starts them at these (config) values, and the candidate at
  // absence (one-sided parameters at typical).
  std::map<std::string, double> restart_values;
  // The refit's starts: one, or two when the first ended above the current
  // fit's objective or at a bound beside declared parameters at theirs, or
  // restarted declared parameters though the candidate passes its score test.
  std::vector<RefitStart> refit_starts;
  // The refit (shortlisted candidates): joint refit, Wald test.
  bool refitted = false;
  double wald_statistic = 0, wald_p_value = 1;
  ParameterSet parameters;            // the refit's estimates (refitted only)
  IdentifiabilityReport identifiability;
  // Physically meaningful values: none of its parameters at a bound.
  bool plausible = true;
  std::string why_implausible;
  // Practical significance (effects.md step 5): the share of its channels'
  // excess error, sum over them of (rms^2 - noise^2) / noise^2, that the
  // refit removes, on the estimation and the held-out data (NaN: no
  // held-out data, or none that can judge it: HeldOutShareOfExcessRemoved),
  // and per channel (estimation data).
  double share_of_excess = 0;
  double share_of_excess_held_out = std::numeric_limits<double>::quiet_NaN();
  std::map<std::string, double> excess_removed;
  // The channels' excess before the refit, sum of (rms^2 - noise^2) / noise^2
  // (estimation data): a share of almost nothing means nothing.
  double channels_excess = 0;
  // The excess removed over every channel, sum of (ms_before - ms_after) /
  // noise^2: how the qualifying refits are ranked (two candidates that
  // remove all of their own channels' excess differ in what else they fix).
  double excess_removed_all_channels = 0;
  // The refit passes every gate before practical significance: Wald,
  // physical meaning, an excess in its channels (how a study judges the
  // share threshold: experiments/studies/confusion.h).
  bool significant = false;
  // The loop's decision on the refit (every criterion of discovery.h).
  bool confirmed = false;
  std::string why_not_confirmed;
  // A paired refit (paired_refit.h): scored and refitted with this effect
  // provisionally in the model (empty: against the current model) ...
  std::string beside;
  // ... and, of the candidate at its bound, the effect it was added with.
  std::string added_with;
  nlohmann::json ToJson() const;
};

// Whether any of `channels` is in `of`.
bool ReachesAny(const std::vector<std::string>& channels, const std::vector<std::string>& of);

// A declared parameter this many times beyond a limit of its physical range
// (core/plausibility.h) is far outside it (effects.md step 7). Measured: an
// undeclared stabilizer bar with the balance log, Ixx fitted at 4.4 x the
// most a body of the vehicle's mass and size can have; the bar's refit
// restarted from the config's Ixx removed 100 % of its channels' excess,
// from the fit's 2 %. A drag coefficient a little under the bluff-body 0.05
// (an undeclared rotor drag in fast transits) is no symptom.
inline constexpr double kFarOutsidePhysicalRange = 2.0;

// The physical-range findings (core/plausibility.h) of the declared
// parameters `fit` estimates whose value lies kFarOutsidePhysicalRange times
// beyond a limit of the range; and, when the largest principal moment of
// inertia is kFarOutsidePhysicalRange times the sum of the other two, one
// for each estimated inertia, its range the triangle inequality leaves it.
std::vector<PlausibilityFinding> FarOutsidePhysicalRange(const ParameterSet& fit,
                                                         const ParameterSet& declared);

// Effects.md step 7: the declared parameters `fit` left at a bound or far
// outside their physical range, each once.
std::vector<std::string> SymptomaticParameters(const ParameterSet& fit, const ParameterSet& declared);

// The symptomatic parameters of `fit` whose config value (in `declared`)
// lies inside the bounds, with that value: where a restart starts them.
std::map<std::string, double> ConfigValuesOfSymptomaticParameters(const ParameterSet& fit,
                                                                  const Vehicle& declared);

// Which symptomatic parameters of the current fit (`fitted`) each
// candidate's refit restarts at its value in `declared` (the config)
// (CandidateScore::restart_values): those distorting (`distorted`, channels
// per parameter) a channel the candidate reaches. A candidate that reaches
// such a channel only with the parameter back there is blind at the bounds
// (CandidateScore::blind_at_bounds); the channels it reaches from there are
// added to its own.
void MarkRestartsAtBounds(const Vehicle& fitted, const Vehicle& declared,
                          const std::map<std::string, std::vector<std::string>>& distorted,
                          const std::vector<EstimationLog>& logs, const NoiseWeights& noise,
                          std::vector<CandidateScore>* scores);

// Noise-weighted residual sum of squares and its sample count.
double WeightedRss(const std::vector<EstimationLog>& logs,
                   const std::vector<Eigen::MatrixXd>& model, const NoiseWeights& noise,
                   int* count);

// The effect's parameter names ("effect.param").
std::vector<std::string> EffectParameterNames(const std::string& effect);

// The vehicle with `effect` added for scoring (parameters free, absent).
Vehicle CandidateVehicle(const Vehicle& vehicle, const std::string& effect);

// A fitted model linearised with every library effect it lacks as candidate
// columns: the scoring pass of one round.
struct CandidatePass {
  Vehicle fitted;                      // the model with its estimates
  OutputErrorResult fit;
  std::vector<std::string> candidates;  // effects not in the model
  LinearisedFit linearised;            // of fitted + every candidate (absent)
  double seconds = 0;
};

// Throws ComputationError if the model cannot be simulated along the fit.
CandidatePass LinearisePass(const Vehicle& fitted, const OutputErrorResult& fit,
                            const std::vector<EstimationLog>& logs,
                            const OutputErrorOptions& fit_options);

// Scores every candidate of the pass. Sorted: passing first, best first (the
// largest fall of the BIC the linearisation predicts, q ln N - drop of the
// weighted RSS), then the others by p-value. weighted_excess: the current
// fit's excess error in the fit's weights (PredictedShare's denominator).
std::vector<CandidateScore> ScoreCandidates(const CandidatePass& pass,
                                            const std::vector<EstimationLog>& logs,
                                            double alpha, int round, double weighted_excess);

// Channels of the logs whose outputs (or, for flight states, their
// derivatives) depend on the named parameters of `vehicle`.
std::vector<std::string> ChannelsReachedBy(const Vehicle& vehicle,
                                           const std::vector<std::string>& parameters,
                                           const std::vector<EstimationLog>& logs,
                                           const NoiseWeights& noise);


// A fit of `vehicle` near the current fit (`current`, fitted as
// `current_fit`), at the current fit's noise weights, kept (no relaxation:
// the loop compares every refit with the current fit at those weights).
// Either from its values at the final segment length, each segment starting
// at the current fit's trajectory (a model nested in `vehicle` from the
// current fit's values then starts exactly at the current fit), or,
// coarse_to_fine, through the fit's whole segment schedule from the
// measurements (a refit with parameters restarted away from the current fit:
// from there the final length alone stopped in a wrong minimum). With the
// scale held in the solve when moving it onto the held member fails.
OutputErrorResult WarmRefit(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                            const OutputErrorOptions& fit_options, const Vehicle& current,
                            const OutputErrorResult& current_fit, bool coarse_to_fine = false);

// Whether a parameter of `effect` sits at a bound in `parameters`.
bool OwnParameterAtBound(const std::string& effect, const ParameterSet& parameters);

// The cluster-robust Wald test of `effect`'s parameters at a refit, from the
// pass linearised there (`at_refit`: its model holds the effect, with the
// refit's values): their scaled distance from absence, every other
// parameter and segment state estimated (the pass's candidates aside). A
// parameter held at its bound has no column and is left out. Not ok, with
// *why_not, when nothing is left to test or the test fails.
ColumnTest EffectWaldTest(const CandidatePass& at_refit, const std::string& effect,
                          std::string* why_not);

// Refits `score.effect` jointly into the pass's model (starting at its
// linearised estimates, or at absence with score.restart_values restarted;
// noise weights of the current fit) and tests its parameters at the refit
// (cluster-robust Wald). A refit that ends above the current fit's objective
// (its model holds the current one, so it stopped short), or with a
// parameter of the effect at a bound while declared parameters sit at theirs
// (`declared_at_bounds`: their config values), or that restarted declared
// parameters though the candidate passes its score test, runs again from
// the other start (restarted <-> at the current fit) and the lower objective
// is kept (score.refit_starts); the kept refit then re-estimates its noise
// weights once (an output-error relaxation). Fills the
// score's refit fields (Wald, estimates, plausibility); on success returns
// the refit in *refit and the pass at the refit (the next round's scoring
// pass, if it is accepted) in *next. False, with why_not_confirmed, when the
// refit or the test fails.
//
// `reweighting` (optional) keeps a hopeless refit from its re-weighting: a
// kept start whose share of its channels' excess error, at the current fit's
// noise weights (`reweighting.share`, ShareOfExcessRemoved of the refit's
// predictions), is below `reweighting.min_share` is rejected there as
// practically insignificant, without re-weighting and without its Wald test.
struct ReweightingGate {
  std::function<double(const OutputErrorResult&)> share;  // nullptr: every refit re-weights
  double min_share = 0;
};
bool RefitCandidate(const CandidatePass& pass, const std::vector<EstimationLog>& logs,
                    const OutputErrorOptions& fit_options,
                    const std::map<std::string, double>& declared_at_bounds,
                    CandidateScore* score, OutputErrorResult* refit, CandidatePass* next,
                    const ReweightingGate& reweighting = {});

}  // namespace coaxid
