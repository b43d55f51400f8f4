#include "experiments/design/balance_design.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/errors.h"
#include "dynamics/trim.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/baseline/balance_holds.h"
#include "ident/baseline/linear_baseline.h"
#include "ident/free_parameters.h"
#include "ident/output_error/costs.h"

namespace coaxid {
namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Candidates: 0 and five speeds over the planned range per rotor; swashplate
// angles -m, -m/2, 0, m/2, m on each axis where the lower rotor turns.
std::vector<InputVector> CandidateHolds(const std::vector<InputVector>& planned, double hover_speed,
                                        double max_delta) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (const InputVector& h : planned) {
    for (int i = 0; i < 2; ++i) {
      if (h[i] > 1.0) {
        lo = std::min(lo, h[i]);
        hi = std::max(hi, h[i]);
      }
    }
  }
  if (!(hi > 0) || hi - lo < 1.0) {
    lo = 0.7 * hover_speed;
    hi = 1.1 * hover_speed;
  }
  std::vector<double> speeds = {0};
  for (int i = 0; i < 5; ++i) speeds.push_back(lo + (hi - lo) * i / 4.0);
  const double deltas[5] = {-max_delta, -0.5 * max_delta, 0, 0.5 * max_delta, max_delta};
  std::vector<InputVector> out;
  for (double w1 : speeds) {
    for (double w2 : speeds) {
      if (w1 == 0 && w2 == 0) continue;
      if (w2 == 0) {
        out.push_back({w1, 0, 0, 0});
        continue;
      }
      for (double dx : deltas) {
        for (double dy : deltas) out.push_back({w1, w2, dx, dy});
      }
    }
  }
  return out;
}

std::string HoldText(const InputVector& h) {
  char text[96];
  std::snprintf(text, sizeof text, "[%g, %g, %g, %g]", h[0], h[1], h[2], h[3]);
  return text;
}

ExcitationReport Lemma1(const Vehicle& vehicle, const Log& balance_log) {
  return CheckBalanceExcitation(vehicle.parameters, {MakeBalanceData(balance_log)});
}

}  // namespace

BalanceDesign DesignBalanceHolds(const Vehicle& vehicle, const std::vector<Scenario>& plan,
                                 const DesignCriterion& criterion,
                                 const BalanceDesignOptions& options) {
  if (options.add_holds < 1) throw InputError("--add_holds must be at least 1");
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress("balance design: " + line);
  };
  BalanceDesign out;
  for (size_t i = 0; i < plan.size() && out.balance_index < 0; ++i) {
    if (plan[i].kind == Scenario::Kind::kBalance) out.balance_index = static_cast<int>(i);
  }
  // The campaign the holds join: the planned one, or a new one with the
  // default rig (holds of 2 s at 100 Hz, the default load noise).
  Scenario campaign;
  if (out.balance_index >= 0) {
    campaign = plan[out.balance_index];
  } else {
    out.new_campaign = true;
    campaign.kind = Scenario::Kind::kBalance;
    campaign.name = "designed_balance";
    campaign.seed = 1;
    campaign.balance.omega1.clear();
    campaign.balance.omega2.clear();
  }
  const std::vector<InputVector> planned = BalanceHolds(campaign.balance);
  double max_delta = options.max_swashplate_rad;
  if (std::isnan(max_delta)) {
    max_delta = 0;
    for (const InputVector& h : planned) {
      max_delta = std::max({max_delta, std::fabs(h[2]), std::fabs(h[3])});
    }
    if (max_delta == 0) max_delta = 0.15;
  }
  if (!(max_delta > 0 && max_delta <= 0.2)) {
    throw InputError("--max_swashplate_rad must be in (0, 0.2] (model.md: angles within +-0.2 rad)");
  }
  const HoverTrim trim = TrimHover(vehicle.model, vehicle.parameters.Values(), 1.5, 0.0);
  const std::vector<InputVector> candidates =
      CandidateHolds(planned, 0.5 * (trim.input[0] + trim.input[1]), max_delta);
  out.candidates = static_cast<int>(candidates.size());

  // Everything planned, on the free set with nothing held (the holds fix the
  // scale of a flight-only plan).
  OutputErrorOptions all_free = options.output_error;
  all_free.scale_anchor = ScaleAnchor::kNone;
  SimulatedExperiment planned_run;
  PredictedPrecision fixed;
  if (!plan.empty()) {
    planned_run = SimulatePlannedExperiment(vehicle, plan);
    out.before = PredictPrecision(vehicle, planned_run, options.output_error);
    fixed = PredictPrecision(vehicle, planned_run, all_free);
  }
  if (out.balance_index >= 0) {
    out.has_lemma_before = true;
    out.lemma_before = Lemma1(vehicle, planned_run.raw[out.balance_index]);
  }

  // Each candidate's information: its hold alone, as a campaign of one.
  Scenario probe = campaign;
  probe.balance.omega1.clear();
  probe.balance.omega2.clear();
  probe.balance.holds.clear();
  for (const InputVector& h : candidates) probe.balance.holds.push_back({h[0], h[1], h[2], h[3]});
  const SimulatedExperiment candidate_run = SimulatePlannedExperiment(vehicle, {probe});
  const EstimationLog& log = candidate_run.logs[0];
  const FreeParameters free(vehicle.parameters);
  if (!plan.empty() && free.names() != fixed.names) {
    throw InputError("the balance design needs the same free parameters in every planned log");
  }
  std::vector<double> channel_std;
  for (const std::string& name : log.channel_names) channel_std.push_back(candidate_run.noise.For(name));
  const Eigen::VectorXd theta_scaled = free.ScaledValues();
  const double* theta = theta_scaled.data();
  std::vector<Eigen::MatrixXd> info(candidates.size());
  for (int first = 0, c = 0; first < log.NumRows(); ++c) {
    int end = first + 1;
    while (end < log.NumRows() && log.inputs.input(end) == log.inputs.input(first)) ++end;
    const BalanceRowsCost cost(vehicle.model, free, log, first, end, channel_std);
    RowMajor J(cost.num_residuals(), free.size());
    Eigen::VectorXd r(cost.num_residuals());
    double* jacobians[] = {J.data()};
    if (!cost.Evaluate(&theta, r.data(), jacobians)) {
      throw ComputationError("the balance model cannot be evaluated at hold " +
                             HoldText(candidates[c]));
    }
    info[c] = J.transpose() * J;
    first = end;
  }

  // Greedy selection.
  // The criterion's bookkeeping (names, scales) from the plan, or from the
  // candidates' campaign when nothing else is planned.
  const CriterionOnInformation objective(
      criterion, plan.empty() ? PredictPrecision(vehicle, candidate_run, options.output_error)
                              : fixed);
  Eigen::MatrixXd M = plan.empty() ? Eigen::MatrixXd::Zero(free.size(), free.size())
                                   : fixed.information_scaled;
  out.criterion_before = objective.Value(M);
  // While the campaign fails the paper's excitation check, only holds that
  // mend a failing condition are candidates (the nonlinear fit may not need
  // them; the linear method does).
  std::vector<InputVector> campaign_holds = planned;
  auto lemma_of = [&](const std::vector<InputVector>& holds) {
    Scenario s = campaign;
    s.balance.omega1.clear();
    s.balance.omega2.clear();
    s.balance.holds.clear();
    for (const InputVector& h : holds) s.balance.holds.push_back({h[0], h[1], h[2], h[3]});
    return Lemma1(vehicle, SimulateBalance(vehicle, s.balance, s.seed));
  };
  auto mends = [&](const ExcitationReport& lemma, const InputVector& h) {
    if (!lemma.swashplate && h[1] > 1.0 && (std::fabs(h[2]) > 1e-3 || std::fabs(h[3]) > 1e-3)) {
      return true;
    }
    // Conditions 71 and 72: a vector (w1, w2 c) resp. (w1, w2) not parallel to the others'.
    auto not_parallel = [&](bool with_c) {
      const double c = with_c ? std::cos(h[2]) * std::cos(h[3]) : 1.0;
      const Eigen::Vector2d v(h[0] * h[0], h[1] * h[1] * c);
      for (const InputVector& p : campaign_holds) {
        const double cp = with_c ? std::cos(p[2]) * std::cos(p[3]) : 1.0;
        const Eigen::Vector2d u(p[0] * p[0], p[1] * p[1] * cp);
        if (u.norm() > 0 && v.norm() > 0 &&
            std::fabs(u[0] * v[1] - u[1] * v[0]) > 1e-3 * u.norm() * v.norm()) {
          return true;
        }
      }
      return false;
    };
    return (!lemma.condition71 && not_parallel(true)) || (!lemma.condition72 && not_parallel(false));
  };
  ExcitationReport lemma = campaign_holds.empty() ? ExcitationReport{} : lemma_of(campaign_holds);
  for (int n = 0; n < options.add_holds; ++n) {
    const bool mending = !(lemma.condition71 && lemma.condition72 && lemma.swashplate);
    int best = -1;
    double best_value = std::numeric_limits<double>::infinity();
    for (size_t c = 0; c < candidates.size(); ++c) {
      if (mending && !mends(lemma, candidates[c])) continue;
      const double value = objective.Value(M + info[c]);
      if (value < best_value) {
        best_value = value;
        best = static_cast<int>(c);
      }
    }
    if (best < 0) break;  // nothing mends it (cannot happen with the candidate grid)
    M += info[best];
    out.added.push_back(candidates[best]);
    campaign_holds.push_back(candidates[best]);
    if (mending) lemma = lemma_of(campaign_holds);
    out.criterion_path.push_back(best_value);
    char line[160];
    std::snprintf(line, sizeof line, "hold %d of %d: %s, criterion %.4g", n + 1, options.add_holds,
                  HoldText(candidates[best]).c_str(), best_value);
    say(line);
  }

  // The designed campaign, predicted as a whole with the rest of the plan.
  out.designed = plan;
  for (const InputVector& h : out.added) campaign.balance.holds.push_back({h[0], h[1], h[2], h[3]});
  if (out.new_campaign) {
    out.designed.push_back(campaign);
    out.balance_index = static_cast<int>(out.designed.size()) - 1;
  } else {
    out.designed[out.balance_index] = campaign;
  }
  const SimulatedExperiment designed_run = SimulatePlannedExperiment(vehicle, out.designed);
  out.after = PredictPrecision(vehicle, designed_run, options.output_error);
  out.criterion_after = CriterionOnInformation(criterion, out.after)
                            .Value(out.after.information_scaled);
  out.lemma_after = Lemma1(vehicle, designed_run.raw[out.balance_index]);
  return out;
}

}  // namespace coaxid
