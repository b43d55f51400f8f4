#include "ident/ekf.h"

#include <gtest/gtest.h>

#include <chrono>

#include <glog/logging.h>
#include <cstdio>

#include "dynamics/trim.h"
#include "experiments/scenario.h"
#include "experiments/simulate_experiment.h"

namespace coaxid {
namespace {

std::string Source(const std::string& rel) { return std::string(COAXID_SOURCE_DIR) + "/" + rel; }

struct SimulatedFlight {
  Vehicle config;     // the config's vehicle (nominal values)
  Vehicle truth;
  FlightScenario scenario;
  Log log;
  std::vector<State> truth_states;  // at every row
};

// The truth states at every row, replayed with exactly the arithmetic of
// SimulateFlight (same integrator, same times, same inputs): bit-identical.
std::vector<State> ReplayTruth(const Vehicle& truth, const FlightScenario& s, const Log& log) {
  const Eigen::VectorXd theta = truth.parameters.Values();
  const Waypoint start = s.waypoints.front();
  const HoverTrim trim = TrimHover(truth.model, theta, start.height, start.heading);
  VehicleOde ode(truth.model, theta);
  Integrator integrator(ode, IntegratorOptions{});
  const InputHold inputs = InputHold::FromLog(log);
  const double dt = 1.0 / s.rate_hz;
  std::vector<State> states;
  Eigen::VectorXd x = trim.state;
  for (int k = 0; k < inputs.size(); ++k) {
    states.push_back(x);
    if (k + 1 == inputs.size()) break;
    const double t = k * dt;
    ode.SetInput(inputs.input(k));
    Eigen::VectorXd next;
    CHECK(integrator.Reset(t, x) && integrator.AdvanceTo(t + dt, &next));
    x = next;
  }
  return states;
}

SimulatedFlight Simulate(double duration_s, uint64_t seed) {
  SimulatedFlight f;
  const VehicleConfig config = LoadVehicleConfig(Source("configs/glmav.yaml"));
  const Scenario scenario = LoadScenario(Source("configs/scenarios/flight.yaml"));
  f.config = MakeVehicle(config);
  f.truth = MakeTruthVehicle(config, scenario);
  f.scenario = scenario.flight;
  f.scenario.duration_s = duration_s;
  f.log = SimulateFlight(f.truth, f.scenario, seed);
  f.log.source = "simulated";
  f.truth_states = ReplayTruth(f.truth, f.scenario, f.log);
  return f;
}

NoiseWeights TruthNoise(const FlightScenario& s) {
  NoiseWeights w;
  for (const std::string& c : s.columns) w.std[c] = s.noise_std.at(c);
  return w;
}

double Env(const char* name, double fallback) { return getenv(name) ? atof(getenv(name)) : fallback; }

TEST(EkfDiagnostics, Run) {
  EkfOptions options;
  options.smoother = getenv("SMOOTH") != nullptr;
  for (int i : {3, 4, 5}) options.state_psd[i] = Env("QV", options.state_psd[i]);
  for (int i : {9, 10, 11}) options.state_psd[i] = Env("QR", options.state_psd[i]);
  for (int i : {0, 1, 2, 6, 7, 8}) options.state_psd[i] = Env("QA", options.state_psd[i]);
  options.parameter_psd = Env("QP", options.parameter_psd);
  if (getenv("RTOL")) {
    options.integrator.relative_tolerance = Env("RTOL", 0);
    options.integrator.absolute_tolerance = Env("RTOL", 0) * 1e-2;
  }
  if (getenv("ONEPASS")) options.covariance_pass = false;
  if (getenv("FREE")) options.scale_anchor = EkfOptions::ScaleAnchor::kNone;
  if (getenv("SENS")) options.transition = EkfTransitionMethod::kSensitivities;
  SimulatedFlight f = Simulate(Env("DUR", 60), static_cast<uint64_t>(Env("SEED", 5)));
  if (getenv("NOACC")) {
    for (const char* c : {"ax", "ay", "az"}) {
      for (double& x : f.log.values[f.log.ColumnIndex(c)]) x = NAN;
    }
  }
  Vehicle v = f.config;
  auto anchored_truth = [&](const std::string& nm) {
    double val = f.truth.parameters.Value(nm);
    if (nm == "gamma1" || nm == "gamma2" || nm[0] == 'I') val *= 0.1 / 0.11;
    return val;
  };
  if (getenv("ATTRUTH")) {
    for (const char* name : {"alpha", "beta", "sigma0", "Cx", "Cy", "Cz", "gamma1", "gamma2",
                             "Ixx", "Iyy", "Izz"}) {
      v.parameters.SetValue(name, anchored_truth(name));
    }
    options.initial_parameter_std = Env("ATTRUTH", 0.5);
  }
  const std::vector<EstimationLog> logs{MakeEstimationLog(f.log)};
  if (getenv("PROFILE")) {
    for (double s0 : {0.08, 0.09, 0.10, 0.11, 0.12, 0.13, 0.14}) {
      Vehicle w = f.config;
      w.parameters.SetValue("sigma0", s0);
      w.parameters.SetEstimated("sigma0", false);
      EkfOptions o = options; o.smoother = false;
      const EkfResult a = RunEkf(w, logs, TruthNoise(f.scenario), o);
      for (size_t k = 0; k < a.free_names.size(); ++k) w.parameters.SetValue(a.free_names[k], a.estimate[k]);
      for (int i = 0; i < w.parameters.size(); ++i) w.parameters.mutable_parameter(i).estimated = false;
      w.parameters.SetEstimated("d", false);
      const EkfResult b = RunEkf(w, logs, TruthNoise(f.scenario), o);
      printf("sigma0 %.2f  filter LL %.2f fixed LL %.2f alpha %.4e beta %.4e\n", s0, a.log_likelihood, b.log_likelihood, a.estimate[0], a.estimate[1]);
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  EkfResult r = RunEkf(v, logs, TruthNoise(f.scenario), options);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  printf("usable %d %s total %.3f s (prop %.3f upd %.3f smooth %.3f) wall %.3f clamped %ld loglik %.3f\n",
         r.usable, r.failure.c_str(), r.total_s, r.propagation_s, r.update_s, r.smoother_s, secs,
         r.clamped, r.log_likelihood);
  for (size_t k = 0; k < r.free_names.size(); ++k) {
    const double truth = anchored_truth(r.free_names[k]);
    printf("%-8s %+.5e +- %.2e truth(d-anchored) %+.5e  z=%+.2f ident %d settled %.1f\n",
           r.free_names[k].c_str(), r.estimate[k], r.estimate_std[k], truth,
           (r.estimate[k] - truth) / r.estimate_std[k], (int)r.identifiable[k],
           r.settled_after_s[k]);
  }
  for (const auto& n : r.notes) printf("note: %s\n", n.c_str());
  for (const auto& q : r.ratios) printf("ratio %s %g +- %g\n", q.name.c_str(), q.value, q.std);
  for (const auto& s : r.channel_nis) {
    printf("NIS %-6s %.4f [%.4f %.4f] n %ld rms %.4g\n", s.channel.c_str(), s.mean, s.lower,
           s.upper, s.dof, s.innovation_rms);
  }
  printf("NIS all %.4f [%.4f %.4f]\n", r.total_nis.mean, r.total_nis.lower, r.total_nis.upper);
  if (getenv("LL")) {
    Vehicle at_truth = f.config, at_est = f.config;
    for (size_t k = 0; k < r.free_names.size(); ++k) {
      at_truth.parameters.SetValue(r.free_names[k], anchored_truth(r.free_names[k]));
      at_est.parameters.SetValue(r.free_names[k], r.estimate[k]);
    }
    for (Vehicle* w : {&at_truth, &at_est}) {
      for (int i = 0; i < w->parameters.size(); ++i) w->parameters.mutable_parameter(i).estimated = false;
    }
    EkfOptions o2 = options;
    o2.smoother = false;
    const EkfResult rt = RunEkf(at_truth, logs, TruthNoise(f.scenario), o2);
    const EkfResult re = RunEkf(at_est, logs, TruthNoise(f.scenario), o2);
    printf("loglik fixed truth %.3f fixed estimate %.3f\n", rt.log_likelihood, re.log_likelihood);
  }
  if (getenv("COVPASS")) {
    Vehicle w = v;
    for (size_t k = 0; k < r.free_names.size(); ++k) w.parameters.SetValue(r.free_names[k], r.estimate[k]);
    const EkfResult& c = r;
    for (size_t k = 0; k < r.free_names.size(); ++k) {
      const double truth = anchored_truth(r.free_names[k]);
      printf("COV %-8s %+.5e +- %.2e (pass-1 std %.2e) z=%+.2f\n", r.free_names[k].c_str(), r.estimate[k], c.estimate_std[k], r.estimate_std[k], (r.estimate[k] - truth) / c.estimate_std[k]);
    }
  }
  if (getenv("HIST")) {
    const auto& h = r.logs[0];
    for (size_t row = 0; row < h.times.size(); row += 1000) {
      printf("t %5.1f", h.times[row]);
      for (int k = 0; k < 3; ++k) printf("  %s %+.4e +- %.2e", r.free_names[k].c_str(), h.parameters(row, k), h.parameter_std(row, k));
      printf("\n");
    }
  }
}

}  // namespace
}  // namespace coaxid
