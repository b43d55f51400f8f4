// The output-error problem linearised at a fit: the Gauss-Newton model the
// candidate tests of candidate_scores.h work on (fast: one sensitivity pass
// instead of one nonlinear refit per candidate).
//
// With r the noise-weighted residuals of the output-error problem
// (ident/output_error/costs.h: flight segments started from their fitted states,
// their continuity ties, balance holds) and J = dr/d[s, theta] the Jacobian
// w.r.t. every segment start state s and every free parameter of `vehicle`
// (scaled, value / scale), this holds
//   N = J^T J,   b = J^T r,   and b_c = J_c^T r_c for every cluster c,
// a cluster being a group of residuals taken as independent of the others
// (the unit of the cluster-robust covariance of the score): a run of
// consecutive rows of a flight log, a few times longer than the correlation
// time of its residuals (ClusterRows) and never straddling a
// multiple-shooting segment (a segment's continuity tie goes with its last
// cluster); one constant-input hold of a balance log. Each log is a stratum. Candidate effects enter as extra free
// parameters at the values where they are absent, so r is the fit's own
// residual and their columns are the candidate's output sensitivities along
// the fitted trajectory (the same costs as the fit); a lag's column comes
// from just beside absence, where it has a derivative, with r still taken
// at absence (LineariseFit's residual_values).
#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "dynamics/state.h"
#include "dynamics/vehicle.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"
#include "ident/output_error/output_error.h"

namespace coaxid {

struct LinearisedFit {
  // Columns: the segment start states, states_per_segment (the model's
  // states, effect states included) per segment in log order, then the free
  // parameters (scaled: column = d r / d(value / scale)).
  int states_per_segment = kNumStates;
  int num_state_columns = 0;
  std::vector<std::string> parameter_names;
  Eigen::VectorXd parameter_scales;
  // N = J^T J by blocks. A segment's start state enters its own rows and the
  // continuity tie to the next segment of its log, nothing else, so N_ss is
  // block tridiagonal: memory and work grow linearly with the log's length
  // (a dense N of a 20-minute flight's 1200 segments held 14,000^2 entries).
  using StateBlock = Eigen::MatrixXd;  // states_per_segment square
  std::vector<StateBlock> state_diagonal;  // N_jj, per segment
  std::vector<StateBlock> state_next;      // N_j,j+1 (zero for a log's last segment)
  Eigen::MatrixXd state_parameter;         // N_s,theta (state columns x parameters)
  Eigen::MatrixXd parameter_normal;        // N_theta,theta
  // b_c = J_c^T r_c of one cluster. It is zero outside its segment's states
  // (and the next segment's, for the cluster that holds the tie) and the
  // parameters.
  struct Cluster {
    int first_state_column = 0;
    Eigen::VectorXd states;      // b_c on the columns from first_state_column (empty: a balance hold)
    Eigen::VectorXd parameters;  // b_c on the parameter columns
    int stratum = 0;             // index of its log
  };
  std::vector<Cluster> clusters;
  double rss = 0;                // r^T r
  int num_residuals = 0;

  // An empty fit (N = 0, no cluster) over these columns.
  LinearisedFit() = default;
  LinearisedFit(int num_segments, int states_per_segment, std::vector<std::string> names,
                Eigen::VectorXd scales);

  int NumColumns() const { return num_state_columns + NumParameters(); }
  int NumParameters() const { return static_cast<int>(parameter_names.size()); }
  // Index of a free parameter among parameter_names, or -1.
  int ParameterIndex(const std::string& name) const;
  // Adds a residual block's J^T J, given over `columns` (its local order;
  // the states of one segment or of two neighbours, and parameters).
  void AddNormal(const std::vector<int>& columns, const Eigen::MatrixXd& block);
  // Adds a cluster: its J^T r over `columns`, as AddNormal.
  void AddCluster(const std::vector<int>& columns, const Eigen::VectorXd& block_gradient,
                  int stratum);
};

// Linearises the problem of `vehicle`'s free parameters on `logs` at the
// vehicle's parameter values and the fitted flight segments (one
// FittedSegments per log, empty for balance logs; from OutputErrorResult).
// False with the reason if a segment cannot be simulated.
// cluster_rows: rows per cluster of each flight log (ignored for balance logs).
// residual_values: free parameters whose Jacobian columns are taken at the
// vehicle's values but whose residual r is taken at these (a lag has no
// derivative at its absence, T = 0: its column comes from just beside it,
// while r must stay the fit's own, every candidate absent; measured: with
// the lags' 2 ms in r, a 20-minute flight with no undeclared effect had
// motor_lag, servo_lag, rotor_damping and wind pass at F 170-2000, each
// undoing the inserted lags).
bool LineariseFit(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                  const std::vector<FittedSegments>& segments, const NoiseWeights& noise,
                  const std::vector<int>& cluster_rows, const OutputErrorOptions& options,
                  const std::map<std::string, double>& residual_values, LinearisedFit* out,
                  std::string* why);

// Rows per cluster for a flight log whose model outputs are `prediction`:
// three times the largest integrated autocorrelation time of its channels'
// residuals, tau = 1 + 2 sum_l rho_l (summed while rho_l > 0, up to 200
// lags), at least 10 rows. Adjacent clusters' scores then correlate by a
// few percent at most (for an AR(1) residual, ~tau / (4 n)).
int ClusterRows(const EstimationLog& log, const Eigen::MatrixXd& prediction);

// A group of columns tested against the others of a linearised fit, the
// nuisance columns (those already estimated) projected out:
//   Z~ = Z - J_0 (J_0^T J_0)^+ J_0^T Z,  g_c = Z~_c^T r_c (cluster scores),
//   G = sum_c g_c = Z~^T r,  S = Z~^T Z~ = N_ZZ - N_Z0 N_00^+ N_0Z.
// Score test (the group at zero, i.e. absent): Hotelling's T^2 with the
// covariance of G estimated from the cluster scores, centred within each
// stratum (log) l of M_l clusters,
//   C = sum_l M_l / (M_l - 1) sum_{c in l} (g_c - gbar_l)(g_c - gbar_l)^T,
//   T^2 = G^T C^-1 G,   F = (nu - q + 1) / (q nu) T^2 ~ F(q, nu - q + 1),
// nu = sum of (M_l - 1) over the strata that carry the score (> 1 % of
// trace C). With one stratum this is the one-sample Hotelling test, exact
// for independent Gaussian cluster scores whatever the correlation of the
// residuals within a cluster: it stays honest on coloured flight residuals.
// The Gauss-Newton step of the nested model is delta = -S^-1 G (r = model -
// measured), its predicted drop of the RSS G^T S^-1 G; the white-noise score
// statistic (G^T S^-1 G / q) / (RSS / (N - P)) is kept for comparison.
// Wald test (the group present at `values_scaled`, after a refit): the same
// F with T^2 = delta^T S C^-1 S delta, delta = values_scaled (the sandwich
// Cov(delta) = S^-1 C S^-1).
struct ColumnTest {
  bool ok = false;
  std::string why_not;           // not ok: e.g. "explained by the parameters already estimated"
  int q = 0, clusters = 0;
  double covariance_dof = 0;     // nu
  double statistic = 0;          // cluster-robust F(q, M - q)
  double p_value = 1;
  double white_statistic = 0;    // white-noise score F(q, N - P)
  double white_p_value = 1;
  double predicted_rss_drop = 0;
  Eigen::VectorXd step;          // Gauss-Newton step of the tested columns (scaled)
};

class ColumnTester {
 public:
  // nuisance: the parameters (indices into fit.parameter_names) estimated
  // under the null; every segment state is estimated too.
  ColumnTester(const LinearisedFit& fit, const std::vector<int>& nuisance);
  // tested: parameter indices. values_scaled: null for the score test, else
  // the group's scaled values (Wald).
  ColumnTest Test(const std::vector<int>& tested, const Eigen::VectorXd* values_scaled = nullptr) const;

 private:
  const LinearisedFit& fit_;
  std::vector<int> nuisance_;
  // The states projected out first (block-tridiagonal elimination, exact
  // nested projection): the parameters' normal matrix and cluster scores
  //   N~ = N_tt - N_ts N_ss^-1 N_st,   b~_c = b_c[theta] - N_ts N_ss^-1 b_c[s].
  Eigen::MatrixXd reduced_normal_;
  Eigen::MatrixXd reduced_scores_;  // b~_c, one column per cluster
  // |N_ts|^T |N_ss^-1 N_st| per parameter, and |N~_00|: what cancels in S
  // (ColumnTester::Test's separation floor).
  Eigen::VectorXd state_cancellation_;
  Eigen::MatrixXd abs_nuisance_normal_;
  // N~_00^+ = D^-1 V diag(1 / lambda) V^T D^-1, D^2 the diagonal of the
  // nuisance parameters' own N (so the rank threshold counts what the states
  // leave of each column).
  int rank_ = 0;
  Eigen::VectorXd inverse_scale_;  // D^-1
  Eigen::MatrixXd basis_;          // V, rank_ columns
  Eigen::VectorXd inverse_eigenvalues_;
};

// Indices of every free parameter of a linearised fit except the listed ones.
std::vector<int> ParametersExcept(const LinearisedFit& fit, const std::vector<std::string>& parameters);
// Indices of the listed parameters (every name must be free in the fit).
std::vector<int> ParameterIndices(const LinearisedFit& fit, const std::vector<std::string>& parameters);

}  // namespace coaxid
