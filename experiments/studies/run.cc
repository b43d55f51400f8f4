#include "experiments/studies/run.h"

#include <algorithm>
#include <cmath>

#include "core/errors.h"
#include "core/log.h"
#include "dynamics/vehicle.h"
#include "experiments/simulation/simulate_experiment.h"
#include "experiments/studies/points.h"
#include "experiments/studies/random_draw.h"
#include "ident/baseline/balance_holds.h"
#include "ident/baseline/linear_baseline.h"
#include "ident/discover/discovery.h"
#include "ident/ekf/ekf.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"
#include "ident/output_error/output_error.h"
#include "ident/scale_gauge.h"

namespace coaxid {
namespace {

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json Truth(const Vehicle& truth, const std::string& name) {
  return truth.parameters.Has(name) ? Number(truth.parameters.Value(name)) : nlohmann::json();
}

nlohmann::json Entry(double estimate, double std, bool identifiable, const nlohmann::json& truth) {
  return {{"estimate", Number(estimate)},
          {"std", identifiable ? Number(std) : nlohmann::json()},
          {"truth", truth}};
}

struct RunLogs {
  std::vector<Log> balance, flight;
  std::vector<EstimationLog> all, flight_estimation;
  std::vector<EstimationLog> held_out;  // discover's validation (randomised studies)
};

OutputErrorOptions FitOptions(const StudySpec& spec) {
  OutputErrorOptions o;
  o.segment_schedule_s = {std::min(0.25, spec.segment_s), spec.segment_s};
  if (spec.segment_s <= 0.25) o.segment_schedule_s = {spec.segment_s};
  o.noise_relaxations = spec.noise_relaxations;
  o.num_threads = 1;  // the study runs in parallel; one run, one thread
  return o;
}

nlohmann::json LinearKf(const Vehicle& start, const Vehicle& truth, const RunLogs& logs) {
  std::vector<BalanceData> data;
  for (const Log& log : logs.balance) data.push_back(MakeBalanceData(log));
  const LinearBaselineResult r = RunLinearBaseline(start.parameters, data, {}, {});
  nlohmann::json p = nlohmann::json::object();
  auto add = [&](const char* name, const BaselineEstimate& e) {
    p[name] = Entry(e.value, e.std, std::isfinite(e.std), Truth(truth, name));
  };
  add("alpha", r.Parameter(kPsiAlpha));
  add("beta", r.Parameter(kThetaBeta));
  add("gamma1", r.Parameter(kThetaGamma1));
  add("gamma2", r.Parameter(kThetaGamma2));
  add("Cz", r.Cz_from_beta);
  add("sigma0", {r.thrust_map.sigma0, r.thrust_map.sigma0_std});
  return {{"ok", true}, {"parameters", p}};
}

// The truth an estimate is judged against. Flight logs alone fix only the
// scale-free ratios; a fit whose scale one held member sets (d held for the
// scale, model.md decision 8, or held by the model it refits, as discover's
// refits are) reports every member of the scale group on that scale, so its
// truth is the truth moved along the scale line onto the held value: each
// member times held / truth of the held member (every member scales as the
// common factor, scale_gauge.h). Marked "truth_on_held_scale" in the record.
nlohmann::json JudgedTruth(const ScaleGauge& gauge, const ParameterSet& estimates,
                           const Vehicle& truth, const std::string& name, bool* on_held_scale) {
  *on_held_scale = false;
  const nlohmann::json t = Truth(truth, name);
  const std::string& held = gauge.held_member;
  if (held.empty() || t.is_null() || !truth.parameters.Has(held) ||
      std::find(gauge.group.begin(), gauge.group.end(), name) == gauge.group.end()) {
    return t;
  }
  *on_held_scale = true;
  return Number(t.get<double>() * estimates.Value(held) / truth.parameters.Value(held));
}

nlohmann::json ParametersOnScale(const std::vector<std::string>& names,
                                 const Eigen::VectorXd& estimate, const Eigen::VectorXd& stds,
                                 const std::vector<bool>& identifiable, const ScaleGauge& gauge,
                                 const ParameterSet& estimates, const Vehicle& truth) {
  nlohmann::json p = nlohmann::json::object();
  for (size_t k = 0; k < names.size(); ++k) {
    bool on_held_scale = false;
    p[names[k]] = Entry(estimate[k], stds[k], identifiable[k],
                        JudgedTruth(gauge, estimates, truth, names[k], &on_held_scale));
    if (on_held_scale) p[names[k]]["truth_on_held_scale"] = true;
  }
  return p;
}

nlohmann::json IdentifiabilityParameters(const ParameterSet& estimates,
                                         const IdentifiabilityReport& id, const ScaleGauge& gauge,
                                         const Vehicle& truth) {
  Eigen::VectorXd values(id.names.size());
  for (size_t k = 0; k < id.names.size(); ++k) values[k] = estimates.Value(id.names[k]);
  return ParametersOnScale(id.names, values, id.std, id.identifiable, gauge, estimates, truth);
}

// The scale-free ratios (ident/scale_gauge.h) as more entries of a record's
// "parameters", so the summary gives their bias, spread and coverage too:
// from flight logs alone they are what the fits determine.
void AddRatios(const std::vector<ScaleFreeRatio>& ratios, const ParameterSet& estimates,
               const Vehicle& truth, nlohmann::json* p) {
  for (const ScaleFreeRatio& q : ratios) {
    double value = 1;
    for (const auto& [index, power] : q.powers) {
      const std::string& name = estimates[index].name;
      value *= truth.parameters.Has(name) ? std::pow(truth.parameters.Value(name), power) : NAN;
    }
    (*p)[q.name] = Entry(q.value, q.std, std::isfinite(q.std), Number(value));
  }
}

nlohmann::json OutputError(const StudySpec& spec, const Vehicle& start, const Vehicle& truth,
                           const RunLogs& logs) {
  const OutputErrorResult r = FitOutputError(start, logs.all, FitOptions(spec));
  if (!r.usable) return {{"ok", false}, {"error", r.why_not_usable}};
  nlohmann::json p = IdentifiabilityParameters(r.parameters, r.identifiability, r.gauge, truth);
  AddRatios(r.ratios, r.parameters, truth, &p);
  return {{"ok", true}, {"parameters", p}};
}

nlohmann::json Ekf(const Vehicle& start, const Vehicle& truth, const RunLogs& logs) {
  EkfOptions o;
  o.smoother = false;       // the parameters do not need the smoothed states
  o.noise_adaptations = 1;  // as `coaxid identify --method=ekf`
  const EkfResult r =
      RunEkf(start, logs.flight_estimation, NoiseFromData(logs.flight_estimation), o);
  if (!r.usable) return {{"ok", false}, {"error", r.failure}};
  nlohmann::json p = ParametersOnScale(r.free_names, r.estimate, r.estimate_std, r.identifiable,
                                       r.gauge, r.parameters, truth);
  AddRatios(r.ratios, r.parameters, truth, &p);
  return {{"ok", true}, {"parameters", p}};
}

nlohmann::json DiscoverRun(const StudySpec& spec, const Vehicle& start, const Vehicle& truth,
                           const RunLogs& logs, const StudyRunDetail& detail) {
  DiscoveryOptions o;
  o.progress = detail.progress;
  o.alpha = spec.discover_alpha;
  o.max_added = spec.discover_max_added;
  o.window_s = spec.segment_s;
  o.fit = FitOptions(spec);
  const DiscoveryResult r = Discover(start, logs.all, logs.held_out, o);
  nlohmann::json unexplained = nlohmann::json::array();
  for (const UnexplainedChannel& u : r.unexplained) unexplained.push_back(u.channel);
  nlohmann::json p = IdentifiabilityParameters(
      r.final.result.parameters, r.final.result.identifiability, r.final.result.gauge, truth);
  AddRatios(r.final.result.ratios, r.final.result.parameters, truth, &p);
  // How far the declared model misses: the largest channel rms over its
  // sample-to-sample noise (an effect too weak to raise it is invisible to
  // any method).
  double declared_rms_ratio = 0;
  for (const ChannelResidualTest& t : r.baseline.residual_tests) {
    if (t.noise_std > 0) declared_rms_ratio = std::max(declared_rms_ratio, t.rms / t.noise_std);
  }
  // Every refit's gates and shares: the study judges the practical-significance
  // threshold on them (ShareThresholdSummary).
  nlohmann::json refits = nlohmann::json::array();
  for (const CandidateScore& c : r.candidates) {
    if (!c.refitted) continue;
    refits.push_back({{"round", c.round},
                      {"beside", c.beside.empty() ? nlohmann::json() : nlohmann::json(c.beside)},
                      {"effect", c.effect},
                      {"significant", c.significant},
                      {"confirmed", c.confirmed},
                      {"share", c.share_of_excess},
                      {"share_held_out", std::isfinite(c.share_of_excess_held_out)
                                             ? nlohmann::json(c.share_of_excess_held_out)
                                             : nlohmann::json(nullptr)},
                      {"excess_removed_all_channels", c.excess_removed_all_channels}});
  }
  nlohmann::json removed = nlohmann::json::array();  // step 5 judged again
  for (const RemovedEffect& e : r.removed) {
    removed.push_back({{"round", e.round}, {"effect", e.effect}});
  }
  // The search on a window of the flight (DiscoveryOptions::search_window_s):
  // null if the flight was searched whole from the start.
  const DiscoveryResult::SearchWindow& w = r.search_window;
  const nlohmann::json search_window =
      w.logs.empty() ? nlohmann::json()
                     : nlohmann::json{{"used", w.used}, {"rounds", w.rounds}, {"added", w.added}};
  return {{"ok", true},
          {"added", r.added},
          {"search_window", search_window},
          {"removed", removed},
          {"refits", refits},
          {"unexplained", unexplained},
          {"declared_rms_over_noise", declared_rms_ratio},
          {"seconds", r.seconds},
          {"seconds_by_step", SecondsByStepJson(r.seconds_by_step)},
          {"parameters", p}};
}

}  // namespace

nlohmann::json RunStudyRun(const StudySpec& spec, const StudyRunId& id,
                           const StudyRunDetail& detail) {
  nlohmann::json record = {{"key", RunKey(id.point, id.seed_index)},
                           {"point", id.point},
                           {"point_label", spec.sweep.Label(id.point)},
                           {"seed_index", id.seed_index},
                           {"seed", id.seed},
                           {"spec_hash", spec.hash}};
  RunLogs logs;
  std::vector<Scenario> scenarios;
  Vehicle truth;
  try {
    if (spec.randomise.enabled) {
      const RandomDraw draw = DrawRun(spec, id.seed);
      record["draw"] = draw.description;
      scenarios = draw.scenarios;
      if (draw.has_held_out) {
        const Scenario& h = draw.held_out;
        Log log = SimulateScenario(MakeTruthVehicle(spec.config, h), h);
        log.source = h.name + " seed " + std::to_string(h.seed);
        if (!detail.logs_dir.empty()) WriteLog(detail.logs_dir + "/held_out_flight.csv", log);
        logs.held_out.push_back(MakeEstimationLog(log));
      }
    } else {
      scenarios = PointScenarios(spec, id.point, id.seed);
    }
    truth = MakeTruthVehicle(spec.config, scenarios.front());
    for (const Scenario& s : scenarios) {
      Log log = SimulateScenario(MakeTruthVehicle(spec.config, s), s);
      log.source = s.name + " seed " + std::to_string(s.seed);
      if (!detail.logs_dir.empty()) {
        WriteLog(detail.logs_dir + "/" + LogKindName(log.kind) + "_" +
                     std::to_string(log.kind == LogKind::kBalance ? logs.balance.size()
                                                                  : logs.flight.size()) +
                     ".csv",
                 log);
      }
      logs.all.push_back(MakeEstimationLog(log));
      if (log.kind == LogKind::kFlight) logs.flight_estimation.push_back(logs.all.back());
      (log.kind == LogKind::kBalance ? logs.balance : logs.flight).push_back(std::move(log));
    }
  } catch (const ComputationError& e) {
    record["simulation"] = e.what();
    record["methods"] = nlohmann::json::object();
    return record;
  }
  record["simulation"] = "ok";
  if (detail.logs_only) {
    record["methods"] = nlohmann::json::object();
    return record;
  }
  const Vehicle start = StartVehicle(spec, id.point, id.seed);
  nlohmann::json methods = nlohmann::json::object();
  for (StudyMethod m : spec.methods) {
    nlohmann::json result;
    try {
      switch (m) {
        case StudyMethod::kLinearKf:
          result = LinearKf(start, truth, logs);
          break;
        case StudyMethod::kOutputError:
          result = OutputError(spec, start, truth, logs);
          break;
        case StudyMethod::kEkf:
          result = Ekf(start, truth, logs);
          break;
        case StudyMethod::kDiscover:
          result = DiscoverRun(spec, start, truth, logs, detail);
          break;
      }
    } catch (const InputError& e) {
      result = {{"ok", false}, {"error", e.what()}};
    } catch (const ComputationError& e) {
      result = {{"ok", false}, {"error", e.what()}};
    }
    methods[StudyMethodName(m)] = result;
  }
  record["methods"] = methods;
  return record;
}

}  // namespace coaxid
