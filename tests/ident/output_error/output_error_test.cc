// Output-error estimation against the truth it was simulated from.
#include "ident/output_error/output_error.h"

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "dynamics/outputs.h"
#include "dynamics/simulator.h"
#include "dynamics/vehicle.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/free_parameters.h"
#include "ident/output_error/costs.h"
#include "tests/mixed_rate_log.h"

namespace coaxid {
namespace {

Vehicle Nominal() { return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml"); }

// The truth of the shipped scenarios: off the nominal config.
Scenario TruthScenario() {
  return LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml");
}

Log FlightLog(const Vehicle& truth, double seconds, uint64_t seed, bool noisy) {
  FlightScenario s = TruthScenario().flight;
  s.duration_s = seconds;
  s.excitation.start_s = 0.0;
  if (!noisy) s.noise_std.clear();
  return SimulateFlight(truth, s, seed);
}

Log BalanceLog(const Vehicle& truth, uint64_t seed, bool noisy, double hold_s = 0.5) {
  BalanceScenario b;  // the default staircase
  b.hold_s = hold_s;
  b.rate_hz = 50;
  if (!noisy) b.noise_std.clear();
  return SimulateBalance(truth, b, seed);
}

// Every free parameter 30 % off the truth (the start).
Vehicle StartOff(const Vehicle& nominal, const Vehicle& truth, double factor) {
  Vehicle start = nominal;
  for (int i : start.parameters.FreeIndices()) {
    Parameter& p = start.parameters.mutable_parameter(i);
    p.value = std::clamp(truth.parameters[i].value * factor, p.lower, p.upper);
  }
  return start;
}

OutputErrorOptions FastOptions() {
  OutputErrorOptions o;
  o.num_threads = 2;
  return o;
}

// The segments' integrator (OutputErrorOptions::DefaultIntegrator) takes the
// fastest mode the bounds allow (the stabilizer bar's T_b at its lower bound,
// 0.05 s) by one RK4 step a 5 ms hold, and refuses a mode too fast for that
// step (stiff_holds_fail): T_b at 1 ms (50 times faster than the bound) and
// at 10 us (as a restart's wild trial point can make) fail the run at once.
// Without the refusal the integrator takes the stiff intervals, up to its cap
// of 50 steps a hold: 1 ms integrates, 10 us fails, though ten times the cap
// would integrate it (measured, seed 20468 of bench/discover_speed.sh: 332 s
// of restarts at 500 steps, 33 s at 50, the same answer).
TEST(OutputError, TheSegmentIntegratorTakesStiffModesAndRefusesNonPhysicalOnes) {
  VehicleConfig config = LoadVehicleConfig(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  config.effects.emplace_back("stabilizer_bar", std::map<std::string, ParameterOverride>{});
  const Vehicle vehicle = MakeVehicle(config);
  FlightScenario scenario;
  scenario.duration_s = 1.5;
  scenario.excitation.start_s = 0.0;
  const EstimationLog log = MakeEstimationLog(SimulateFlight(vehicle, scenario, 5));
  const int bar = vehicle.model.EffectStateOffset(EffectIndex("stabilizer_bar"));
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(vehicle.model.NumStates());
  x0.head(kNumStates) = InitialStateFromLog(log, 20).head(kNumStates);
  x0[bar] = 0.01;  // the bar off the shaft: its mode is excited
  std::vector<int> all(vehicle.parameters.size());
  for (int i = 0; i < vehicle.parameters.size(); ++i) all[i] = i;
  const int t_b = vehicle.parameters.IndexOrThrow("stabilizer_bar.T_b");
  ASSERT_EQ(vehicle.parameters[t_b].lower, 0.05);
  const IntegratorOptions fits = OutputErrorOptions::DefaultIntegrator();
  ASSERT_TRUE(fits.stiff_holds_fail);
  IntegratorOptions integrating = fits;
  integrating.stiff_holds_fail = false;
  IntegratorOptions ten_times = integrating;
  ten_times.max_steps_per_interval *= 10;
  struct Case {
    double time_constant;
    const IntegratorOptions* options;
    bool runs;
  };
  const std::vector<Case> cases = {{0.05, &fits, true},        {1e-3, &fits, false},
                                   {1e-5, &fits, false},       {1e-3, &integrating, true},
                                   {1e-5, &integrating, false}, {1e-5, &ten_times, true}};
  for (const Case& c : cases) {
    Eigen::VectorXd theta = vehicle.parameters.Values();
    theta[t_b] = c.time_constant;
    Simulator plain(vehicle.model, theta, *c.options);
    Simulator sensitive(vehicle.model, theta, *c.options, {true, true}, all,
                        SensitivityMethod::kRungeKuttaPerHold);
    Trajectory a, b;
    const std::string what = "T_b " + std::to_string(c.time_constant) + ", stiff holds fail " +
                             std::to_string(c.options->stiff_holds_fail) + ", cap " +
                             std::to_string(c.options->max_steps_per_interval) + ": ";
    EXPECT_EQ(plain.Run(log.inputs, 20, 220, x0, &a), c.runs) << what << plain.last_error();
    EXPECT_EQ(sensitive.Run(log.inputs, 20, 220, x0, &b), c.runs) << what
                                                                   << sensitive.last_error();
  }
}

TEST(OutputError, NoiseFreeFlightAndBalanceRecoverTheTruth) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  // Cx and Cy are only weakly seen near hover (body airflow ~ 0.1 m/s against
  // a 6.7 m/s wake); held at the truth here so the test is about the rest.
  Vehicle start = StartOff(nominal, truth, 1.3);
  for (const char* name : {"Cx", "Cy"}) {
    start.parameters.SetEstimated(name, false);
    start.parameters.SetValue(name, truth.parameters.Value(name));
  }
  const std::vector<EstimationLog> logs = {MakeEstimationLog(FlightLog(truth, 3.0, 1, false)),
                                           MakeEstimationLog(BalanceLog(truth, 2, false))};
  OutputErrorOptions options = FastOptions();
  // Noise-free data: unit weights, no relaxation (residuals go to zero).
  for (const auto& log : logs) {
    for (const auto& name : log.channel_names) options.noise.std[name] = 1e-3;
  }
  options.noise_relaxations = 0;
  options.function_tolerance = 1e-16;
  const OutputErrorResult r = FitOutputError(start, logs, options);
  ASSERT_TRUE(r.usable) << r.why_not_usable;
  for (int i : start.parameters.FreeIndices()) {
    const double t = truth.parameters[i].value;
    // 1e-6 relative: the requirement; the integrator (rtol 1e-7) and
    // the 1e-6 smoothing of the model limit what noise-free data can give.
    EXPECT_NEAR(r.parameters[i].value, t, 1e-6 * std::fabs(t)) << truth.parameters[i].name;
  }
}

TEST(OutputError, NoisyFlightAndBalanceEstimatesWithinThreeStd) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  const Vehicle start = StartOff(nominal, truth, 1.3);
  const std::vector<EstimationLog> logs = {MakeEstimationLog(FlightLog(truth, 4.0, 3, true)),
                                           MakeEstimationLog(BalanceLog(truth, 4, true))};
  const OutputErrorResult r = FitOutputError(start, logs, FastOptions());
  ASSERT_TRUE(r.usable) << r.why_not_usable;
  const FreeParameters free(start.parameters);
  for (int k = 0; k < free.size(); ++k) {
    const int i = free.indices()[k];
    if (!r.identifiability.identifiable[k]) continue;  // reported as such, checked below
    const double err = r.parameters[i].value - truth.parameters[i].value;
    // 3 std: a false alarm for one of 12 parameters has probability ~3 %.
    EXPECT_LT(std::fabs(err), 3 * r.identifiability.std[k])
        << free.names()[k] << " estimate " << r.parameters[i].value << " truth "
        << truth.parameters[i].value << " std " << r.identifiability.std[k];
  }
  // d and the inertias are identifiable once a balance log is in.
  for (const char* name : {"d", "Ixx", "Iyy", "Izz", "gamma1", "gamma2"}) {
    const auto& names = r.identifiability.names;
    const int k = std::find(names.begin(), names.end(), name) - names.begin();
    EXPECT_TRUE(r.identifiability.identifiable[k]) << name;
  }
}

// Mixed rates (issue 14): the same flight and balance logs, the flight as a
// real logger writes it (positions at 20 Hz, no velocities:
// tests/mixed_rate_log.h), the noise estimated from the data: every
// identifiable parameter within 1 std (the full-rate fit's) of the full-rate
// estimate, and no std smaller than the full-rate one.
TEST(OutputError, MixedRateFlightAgreesWithFullRate) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  const Log flight = FlightLog(truth, 6.0, 21, true);
  const EstimationLog balance = MakeEstimationLog(BalanceLog(truth, 22, true));
  const OutputErrorResult full =
      FitOutputError(nominal, {MakeEstimationLog(flight), balance}, FastOptions());
  const OutputErrorResult mixed =
      FitOutputError(nominal, {MakeEstimationLog(MixedRateLog(flight)), balance}, FastOptions());
  ASSERT_TRUE(full.usable) << full.why_not_usable;
  ASSERT_TRUE(mixed.usable) << mixed.why_not_usable;
  const IdentifiabilityReport& a = full.identifiability;
  const IdentifiabilityReport& b = mixed.identifiability;
  ASSERT_EQ(a.names, b.names);
  for (size_t k = 0; k < a.names.size(); ++k) {
    if (!a.identifiable[k]) continue;
    const double x = full.parameters.Value(a.names[k]), y = mixed.parameters.Value(a.names[k]);
    EXPECT_LE(std::fabs(y - x), a.std[k]) << a.names[k] << ": full rate " << x << " +- "
                                          << a.std[k] << ", mixed " << y << " +- " << b.std[k];
    EXPECT_GE(b.std[k], 0.99 * a.std[k]) << a.names[k];
  }
}

// The fit is the same, to the last bit, on one thread and on three: the
// segments run side by side but Ceres adds them up in one fixed order
// (parallel_segments.h). Ceres' own threads sum in the order its workers
// happen to finish, and a solve off its optimum amplifies the last bits
// (issue 13: one discover restart ended at 5.47e6 and at 3.03e6 on two runs).
// A coarse-to-fine start 30 % off the truth, flight and balance logs.
TEST(OutputError, TheFitIsTheSameOnOneThreadAndOnThree) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  const Vehicle start = StartOff(nominal, truth, 1.3);
  const std::vector<EstimationLog> logs = {MakeEstimationLog(FlightLog(truth, 3.0, 31, true)),
                                           MakeEstimationLog(BalanceLog(truth, 32, true))};
  OutputErrorOptions options = FastOptions();  // coarse-to-fine: 0.25 s, then 1 s segments
  options.num_threads = 1;
  const OutputErrorResult one = FitOutputError(start, logs, options);
  options.num_threads = 3;
  const OutputErrorResult three = FitOutputError(start, logs, options);
  ASSERT_TRUE(one.usable) << one.why_not_usable;
  ASSERT_TRUE(three.usable) << three.why_not_usable;
  EXPECT_EQ(one.iterations, three.iterations);
  EXPECT_EQ(one.final_cost, three.final_cost);
  for (int i : start.parameters.FreeIndices()) {
    EXPECT_EQ(one.parameters[i].value, three.parameters[i].value) << start.parameters[i].name;
  }
  ASSERT_EQ(one.predictions.size(), three.predictions.size());
  for (size_t k = 0; k < one.predictions.size(); ++k) {
    const Eigen::ArrayXXd a = one.predictions[k].array(), b = three.predictions[k].array();
    ASSERT_EQ(a.rows(), b.rows());
    ASSERT_EQ(a.cols(), b.cols());
    EXPECT_TRUE(((a == b) || (a.isNaN() && b.isNaN())).all()) << "log " << k;
  }
}

// Threads lent by fits that finished (spare_threads.h) speed a fit up and
// change nothing in it: one thread of its own plus two borrowed gives the
// one-thread fit bit for bit, and the threads go back to the pool.
TEST(OutputError, BorrowedThreadsChangeNothingInTheFit) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  const Vehicle start = StartOff(nominal, truth, 1.3);
  const std::vector<EstimationLog> logs = {MakeEstimationLog(FlightLog(truth, 3.0, 33, true))};
  OutputErrorOptions options = FastOptions();
  options.num_threads = 1;
  const OutputErrorResult alone = FitOutputError(start, logs, options);
  options.spare_threads = std::make_shared<SpareThreads>();
  options.spare_threads->Add(2);
  const OutputErrorResult lent = FitOutputError(start, logs, options);
  ASSERT_TRUE(alone.usable) << alone.why_not_usable;
  ASSERT_TRUE(lent.usable) << lent.why_not_usable;
  EXPECT_GT(options.spare_threads->lent(), 0);
  EXPECT_EQ(options.spare_threads->idle(), 2);
  EXPECT_EQ(alone.iterations, lent.iterations);
  EXPECT_EQ(alone.final_cost, lent.final_cost);
  for (int i : start.parameters.FreeIndices()) {
    EXPECT_EQ(alone.parameters[i].value, lent.parameters[i].value) << start.parameters[i].name;
  }
}

// model.md, decision 8: flight alone sees only ratios.
// Without the scale anchor (model.md decision 8 held off), the null direction
// is found and no std is made up for the parameters along it.
TEST(OutputError, FlightOnlyReportsTheMomentScaleAsNotIdentifiable) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  Vehicle start = StartOff(nominal, truth, 1.1);
  for (const char* name : {"Cx", "Cy"}) start.parameters.SetEstimated(name, false);
  const std::vector<EstimationLog> logs = {MakeEstimationLog(FlightLog(truth, 3.0, 5, true))};
  OutputErrorOptions options = FastOptions();
  options.scale_anchor = ScaleAnchor::kNone;
  const OutputErrorResult r = FitOutputError(start, logs, options);
  EXPECT_EQ(r.gauge.fixed_by, "nothing");
  ASSERT_TRUE(r.usable) << r.why_not_usable;
  ASSERT_FALSE(r.identifiability.null_directions.empty());
  bool found = false;
  for (const NullDirection& n : r.identifiability.null_directions) {
    const auto has = [&](const char* p) {
      return std::find(n.parameters.begin(), n.parameters.end(), p) != n.parameters.end();
    };
    found = found || (has("d") && has("Ixx") && has("Izz") && has("gamma1"));
  }
  EXPECT_TRUE(found) << r.identifiability.ToJson().dump(1);
  const auto& names = r.identifiability.names;
  for (const char* name : {"d", "Ixx", "Iyy", "Izz", "gamma1", "gamma2"}) {
    const int k = std::find(names.begin(), names.end(), name) - names.begin();
    EXPECT_FALSE(r.identifiability.identifiable[k]) << name;
    EXPECT_TRUE(std::isnan(r.identifiability.std[k])) << name << ": no made-up std";
  }
}

// The reported std against the spread over seeds (balance logs: the static
// model makes each fit take milliseconds).
TEST(OutputError, MonteCarloSpreadMatchesReportedStd) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  const Vehicle start = StartOff(nominal, truth, 1.2);
  const int seeds = 40;
  const FreeParameters free(start.parameters);
  std::vector<std::vector<double>> estimates(free.size());
  std::vector<double> mean_std(free.size(), 0.0);
  std::vector<bool> identifiable;
  for (int s = 0; s < seeds; ++s) {
    OutputErrorOptions o = FastOptions();
    o.noise_relaxations = 1;
    const OutputErrorResult r =
        FitOutputError(start, {MakeEstimationLog(BalanceLog(truth, 100 + s, true, 0.2))}, o);
    ASSERT_TRUE(r.usable) << r.why_not_usable;
    identifiable = r.identifiability.identifiable;
    for (int k = 0; k < free.size(); ++k) {
      estimates[k].push_back(r.parameters[free.indices()[k]].value);
      mean_std[k] += r.identifiability.std[k] / seeds;
    }
  }
  int checked = 0;
  for (int k = 0; k < free.size(); ++k) {
    if (!identifiable[k]) continue;  // inertias, Cx, Cy: a balance does not see them
    double mean = 0, var = 0;
    for (double e : estimates[k]) mean += e / seeds;
    for (double e : estimates[k]) var += (e - mean) * (e - mean) / (seeds - 1);
    const double spread = std::sqrt(var);
    // With 40 seeds the sample std itself scatters by ~11 % (1/sqrt(2 n)),
    // so a factor of 1.5 is a ~4-sigma bound on an honest std.
    EXPECT_LT(spread, 1.5 * mean_std[k]) << free.names()[k];
    EXPECT_GT(spread, mean_std[k] / 1.5) << free.names()[k];
    ++checked;
  }
  EXPECT_GE(checked, 6);  // alpha, beta, sigma0, Cz, gamma1, gamma2, d
}

// Coloured output noise (first order autoregressive, correlation 0.9 between
// 5 ms samples, like slow model error or filtered sensors): the white-noise
// Cramér-Rao std is optimistic, the corrected one (Morelli & Klein) matches
// the spread of the estimates over noise seeds.
TEST(OutputError, ColouredResidualCorrectionMatchesMonteCarloSpread) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  // Parameters a flight log determines once d and the rotor constants are
  // known (model.md, decision 8); the fits start at the truth.
  Vehicle start = truth;
  const std::vector<std::string> estimated = {"Cz", "Ixx", "Iyy", "Izz"};  // config order
  for (int i : truth.parameters.FreeIndices()) {
    const std::string& name = truth.parameters[i].name;
    start.parameters.SetEstimated(
        name, std::find(estimated.begin(), estimated.end(), name) != estimated.end());
  }
  const EstimationLog clean = MakeEstimationLog(FlightLog(truth, 2.0, 11, false));
  const std::map<std::string, double> sensor_std = FlightScenario{}.noise_std;
  OutputErrorOptions options = FastOptions();
  options.segment_schedule_s = {1.0};
  options.noise_relaxations = 0;  // the true noise std: the bounds are for a known R
  for (const std::string& name : clean.channel_names) options.noise.std[name] = sensor_std.at(name);
  options.coloured_residual_correction = true;
  const double a = 0.9;
  const int seeds = 30;
  const int P = static_cast<int>(estimated.size());
  std::vector<std::vector<double>> estimates(P);
  Eigen::VectorXd white = Eigen::VectorXd::Zero(P), corrected = Eigen::VectorXd::Zero(P);
  for (int seed = 0; seed < seeds; ++seed) {
    std::mt19937_64 rng(1000 + seed);
    std::normal_distribution<double> normal;
    EstimationLog log = clean;
    for (int c = 0; c < log.NumChannels(); ++c) {
      const double sigma = options.noise.std[log.channel_names[c]];
      double e = sigma * normal(rng);  // stationary from the first row
      for (int k = 0; k < log.NumRows(); ++k) {
        log.values(k, c) += e;
        e = a * e + std::sqrt(1 - a * a) * sigma * normal(rng);
      }
    }
    const OutputErrorResult r = FitOutputError(start, {log}, options);
    ASSERT_TRUE(r.usable) << r.why_not_usable;
    ASSERT_TRUE(r.coloured_residuals.applied);
    for (int k = 0; k < P; ++k) {
      ASSERT_EQ(r.identifiability.names[k], estimated[k]);
      estimates[k].push_back(r.parameters.Value(estimated[k]));
      white[k] += r.coloured_residuals.white_std[k] / seeds;
      corrected[k] += r.identifiability.std[k] / seeds;
    }
  }
  for (int k = 0; k < P; ++k) {
    double mean = 0, var = 0;
    for (double e : estimates[k]) mean += e / seeds;
    for (double e : estimates[k]) var += (e - mean) * (e - mean) / (seeds - 1);
    const double spread = std::sqrt(var);
    // 30 seeds: the sample std scatters by ~13 %, so 1.5 is a ~3-sigma band.
    EXPECT_LT(spread, 1.5 * corrected[k]) << estimated[k] << " white " << white[k];
    EXPECT_GT(spread, corrected[k] / 1.5) << estimated[k] << " white " << white[k];
    // The white-noise bound is far too small for this noise (what the
    // correction is for): for a sensitivity that varies slowly against the
    // noise, the variance is (1 + a) / (1 - a) = 19 times the white one.
    EXPECT_GT(spread, 1.5 * white[k]) << estimated[k] << " corrected " << corrected[k];
  }
}

// The sensitivity-based Jacobian of a segment block against central
// differences of its residuals: the paper's model (states read directly),
// and with the measurement effects gyro_bias and accel_bias declared (every
// channel then through the output model, the bias columns included).
TEST(OutputError, SegmentJacobianEqualsFiniteDifferences) {
  const Vehicle nominal = Nominal();
  const Vehicle truth = MakeTruthVehicle(nominal.config, TruthScenario());
  const EstimationLog log = MakeEstimationLog(FlightLog(truth, 1.0, 9, true));
  std::map<std::string, ParameterOverride> gyro, accel;
  gyro["b_q"].value = 0.01;
  accel["b_ax"].value = 0.1;
  const Vehicle biased =
      WithEffect(WithEffect(nominal, "gyro_bias", gyro), "accel_bias", accel);
  ASSERT_TRUE(biased.model.ChangesFlightMeasurements());
  for (const Vehicle* model : {&nominal, &biased}) {
    SCOPED_TRACE(model->model.ChangesFlightMeasurements() ? "with sensor biases" : "paper's model");
    const FreeParameters free(model->parameters);
    std::vector<double> channel_std(log.NumChannels(), 0.01);
    IntegratorOptions integrator = OutputErrorOptions::DefaultIntegrator();
    integrator.relative_tolerance = 1e-10;
    integrator.absolute_tolerance = 1e-12;
    FlightSegmentCost cost(model->model, free, log, 20, 120, true, channel_std, 1e-3, integrator);
    Eigen::VectorXd s0 = InitialStateFromLog(log, 20), s1 = InitialStateFromLog(log, 120);
    Eigen::VectorXd theta = free.ScaledValues();
    std::vector<double*> blocks = {s0.data(), theta.data(), s1.data()};
    const int m = cost.num_residuals();
    std::vector<int> sizes = {kNumStates, free.size(), kNumStates};
    std::vector<std::vector<double>> J(3);
    std::vector<double*> jac(3);
    for (int b = 0; b < 3; ++b) {
      J[b].resize(m * sizes[b]);
      jac[b] = J[b].data();
    }
    std::vector<double> r(m), rp(m), rm(m);
    ASSERT_TRUE(cost.Evaluate(blocks.data(), r.data(), jac.data()));
    for (int b = 0; b < 3; ++b) {
      for (int j = 0; j < sizes[b]; ++j) {
        const double saved = blocks[b][j];
        // States in SI units and scaled parameters are O(1): step 1e-6 gives
        // truncation ~1e-12 and round-off ~1e-10/1e-6 = 1e-4 relative at worst.
        const double h = 1e-6;
        blocks[b][j] = saved + h;
        ASSERT_TRUE(cost.Evaluate(blocks.data(), rp.data(), nullptr));
        blocks[b][j] = saved - h;
        ASSERT_TRUE(cost.Evaluate(blocks.data(), rm.data(), nullptr));
        blocks[b][j] = saved;
        double scale = 1e-8, err = 0;
        for (int i = 0; i < m; ++i) {
          const double fd = (rp[i] - rm[i]) / (2 * h);
          scale = std::max(scale, std::fabs(fd));
          err = std::max(err, std::fabs(fd - J[b][i * sizes[b] + j]));
        }
        EXPECT_LT(err, 1e-4 * scale) << "block " << b << " column " << j;
      }
    }
  }
}

}  // namespace
}  // namespace coaxid
