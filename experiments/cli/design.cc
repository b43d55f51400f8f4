#include "experiments/cli/design.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include <gflags/gflags.h>

#include "core/errors.h"
#include "core/stopwatch.h"
#include "core/vehicle_config.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/design/design_report.h"
#include "experiments/simulation/simulate_experiment.h"

DEFINE_string(design_parameters, "",
              "design: the parameters to estimate best, comma-separated (default: every free "
              "parameter)");
DEFINE_string(criterion, "D",
              "design: D (log det of the named parameters' relative covariance) or A (sum of "
              "their relative variances)");
DEFINE_double(max_attitude_rad, -1,
              "design: the largest |phi|, |theta| the designed flight may reach (< 0: the "
              "planned flight's own peak)");
DEFINE_double(max_rotor_speed_deviation_rad_s, -1,
              "design: the largest rotor-speed deviation from hover trim (< 0: 20 %% of the "
              "hover speed, or the planned flight's peak if larger)");
DEFINE_double(max_swashplate_rad, -1,
              "design: the largest swashplate angle, in flight and in balance holds (< 0: 0.1 "
              "rad or the planned flight's peak in flight, the campaign's largest in holds)");
DEFINE_double(max_height_deviation_m, -1,
              "design: the largest height off the waypoints' heights (< 0: 0.5 m, or the "
              "planned flight's peak if larger)");
DEFINE_string(design_bands, "0.1:0.5,0.5:1.5,1.5:4",
              "design: the multisine's frequency bands [Hz], LOW:HIGH,... (each input gets an rms "
              "per band)");
DEFINE_bool(design_excitation, true, "design: design the flight's excitation");
DEFINE_string(design_signal, "multisine",
              "design: the excitation designed, multisine (shaped by --design_bands) or 3211 "
              "(pulse width among --design_pulse_widths_s and level per input)");
DEFINE_string(design_pulse_widths_s, "0.1,0.15,0.25,0.4,0.6,1",
              "design: the 3211's unit pulse widths tried [s]");
DEFINE_double(quiet_after_waypoint_s, 3.0,
              "design: the excitation is off from 0.5 s before each waypoint change to this long "
              "after it (0: always on)");
DEFINE_int32(add_holds, -1,
             "design: balance holds to add (< 0: 4 when a balance scenario is planned, else 0)");
DEFINE_string(design_at, "config",
              "design: the parameter values the prediction is made at: config (the vehicle as "
              "known) or truth (the scenarios' truth sections, e.g. to check a prediction "
              "against a Monte Carlo study of the same scenarios)");
DECLARE_double(segment_s);

namespace coaxid {
namespace {

const char* const kDesignUsage =
    "usage: coaxid design --config=F --scenario=S[,S2...] --out=DIR [--design_parameters=Cz,sigma0]\n"
    "       [--criterion=D|A] [--max_attitude_rad=R] [--max_rotor_speed_deviation_rad_s=W]\n"
    "       [--max_swashplate_rad=D] [--max_height_deviation_m=H] [--design_bands=0.1:0.5,0.5:1.5,1.5:4] [--add_holds=N]\n"
    "       [--design_signal=multisine|3211] [--design_pulse_widths_s=0.1,0.15,0.25,0.4,0.6,1]\n"
    "       [--design_excitation=false] [--quiet_after_waypoint_s=3] [--design_at=config|truth]\n";

std::vector<FrequencyBand> ParseBands(const std::string& text) {
  std::vector<FrequencyBand> bands;
  for (const std::string& part : SplitList(text)) {
    FrequencyBand band;
    char colon = 0;
    char rest = 0;
    if (std::sscanf(part.c_str(), "%lf%c%lf%c", &band.min_hz, &colon, &band.max_hz, &rest) != 3 ||
        colon != ':') {
      throw InputError("--design_bands: '" + part + "' is not LOW:HIGH in Hz");
    }
    if (!(band.min_hz > 0 && band.max_hz > band.min_hz)) {
      throw InputError("--design_bands: '" + part + "': need 0 < LOW < HIGH");
    }
    if (!bands.empty() && band.min_hz < bands.back().max_hz) {
      throw InputError("--design_bands: bands must be in increasing order and not overlap");
    }
    bands.push_back(band);
  }
  if (bands.empty()) throw InputError("--design_bands: no band given");
  return bands;
}

double LimitFlag(double value) { return value < 0 ? std::nan("") : value; }

void PrintPrediction(const char* title, const PredictedPrecision& p) {
  std::printf("%s\n  %-22s %12s %12s %9s %12s\n", title, "parameter", "value", "std", "relative",
              "fit reports");
  const auto& id = p.identifiability;
  for (size_t k = 0; k < id.names.size(); ++k) {
    const double value = p.parameters.Value(id.names[k]);
    if (id.identifiable[k]) {
      std::printf("  %-22s % .5e % .5e %8.3g%% %12.5e\n", id.names[k].c_str(), value, id.std[k],
                  100 * id.std[k] / std::fabs(value), p.bound_std[k]);
    } else {
      std::printf("  %-22s % .5e %12s\n", id.names[k].c_str(), value, "not identifiable");
    }
  }
  if (!p.gauge.held.empty()) std::printf("%s", ScaleTableText(p.gauge, p.parameters, p.ratios).c_str());
}

}  // namespace

int RunDesign() {
  const auto start = std::chrono::steady_clock::now();
  RequireFlag(FLAGS_config, "config", kDesignUsage);
  RequireFlag(FLAGS_scenario, "scenario", kDesignUsage);
  RequireFlag(FLAGS_out, "out", kDesignUsage);
  CheckOutputFolder(FLAGS_out);
  DesignRun run;
  if (FLAGS_criterion == "D") {
    run.criterion.kind = DesignCriterion::Kind::kD;
  } else if (FLAGS_criterion == "A") {
    run.criterion.kind = DesignCriterion::Kind::kA;
  } else {
    throw InputError("--criterion: '" + FLAGS_criterion + "' is not D or A");
  }
  run.criterion.parameters = SplitList(FLAGS_design_parameters);
  if (!(FLAGS_segment_s > 0)) throw InputError("--segment_s must be positive");
  ExcitationDesignOptions excitation_options;
  excitation_options.bands = ParseBands(FLAGS_design_bands);
  if (FLAGS_design_signal == "3211") {
    excitation_options.excitation = Excitation::Type::k3211;
  } else if (FLAGS_design_signal != "multisine") {
    throw InputError("--design_signal: '" + FLAGS_design_signal + "' is not multisine or 3211");
  }
  excitation_options.pulse_widths_s.clear();
  for (const std::string& part : SplitList(FLAGS_design_pulse_widths_s)) {
    char* end = nullptr;
    const double width = std::strtod(part.c_str(), &end);
    if (end == part.c_str() || *end != '\0' || !(width > 0)) {
      throw InputError("--design_pulse_widths_s: '" + part + "' is not a positive width in s");
    }
    excitation_options.pulse_widths_s.push_back(width);
  }
  if (excitation_options.pulse_widths_s.empty()) {
    throw InputError("--design_pulse_widths_s: no width given");
  }
  if (!(FLAGS_quiet_after_waypoint_s >= 0)) throw InputError("--quiet_after_waypoint_s must be >= 0");
  excitation_options.quiet_after_waypoint_s = FLAGS_quiet_after_waypoint_s;
  excitation_options.limits.max_attitude_rad = LimitFlag(FLAGS_max_attitude_rad);
  excitation_options.limits.max_rotor_speed_deviation_rad_s =
      LimitFlag(FLAGS_max_rotor_speed_deviation_rad_s);
  excitation_options.limits.max_swashplate_rad = LimitFlag(FLAGS_max_swashplate_rad);
  excitation_options.limits.max_height_deviation_m = LimitFlag(FLAGS_max_height_deviation_m);
  if (FLAGS_max_swashplate_rad > 0.2) {
    throw InputError("--max_swashplate_rad: the model's swashplate range is +-0.2 rad (model.md)");
  }
  auto progress = [](const std::string& line) { std::cerr << line << "\n"; };

  if (FLAGS_design_at != "config" && FLAGS_design_at != "truth") {
    throw InputError("--design_at: '" + FLAGS_design_at + "' is not config or truth");
  }
  run.config_path = FLAGS_config;
  const VehicleConfig config = LoadVehicleConfig(FLAGS_config);
  run.scenario_paths = SplitList(FLAGS_scenario);
  bool has_flight = false, has_balance = false;
  for (const std::string& path : run.scenario_paths) {
    run.plan.push_back(LoadScenario(path));
    has_flight |= run.plan.back().kind == Scenario::Kind::kFlight;
    has_balance |= run.plan.back().kind == Scenario::Kind::kBalance;
  }
  Vehicle vehicle = MakeVehicle(config);
  if (FLAGS_design_at == "truth") {
    const Scenario& first = run.plan.front();
    for (const Scenario& s : run.plan) {
      if (s.truth_parameters != first.truth_parameters || !s.truth_effects.empty() ||
          !s.truth_outside_library.empty()) {
        throw InputError("--design_at=truth: the scenarios' truths differ or switch effects on "
                         "(" + s.name + "); give them one truth.parameters section");
      }
    }
    vehicle = MakeTruthVehicle(config, first);
  }
  run.design_at = FLAGS_design_at;
  const int add_holds = FLAGS_add_holds < 0 ? (has_balance ? 4 : 0) : FLAGS_add_holds;
  if (!FLAGS_design_excitation && add_holds == 0) {
    std::cerr << "design: predicting only (no excitation design, no holds to add)\n";
  }

  OutputErrorOptions oe;
  oe.segment_schedule_s = {FLAGS_segment_s};
  oe.num_threads = 1;
  std::cerr << "design: simulating the planned experiment\n";
  const SimulatedExperiment planned = SimulatePlannedExperiment(vehicle, run.plan);
  run.planned = PredictPrecision(vehicle, planned, oe);
  run.criterion_planned =
      CriterionOnInformation(run.criterion, run.planned).Value(run.planned.information_scaled);
  PrintPrediction("predicted std of an output-error fit, as planned:", run.planned);

  std::vector<Scenario> plan = run.plan;
  run.final_precision = run.planned;
  if (has_flight && FLAGS_design_excitation) {
    excitation_options.output_error = oe;
    excitation_options.progress = progress;
    run.excitation = DesignExcitation(vehicle, plan, run.criterion, excitation_options);
    plan = run.excitation->designed;
    run.final_precision = run.excitation->after;
    PrintPrediction("with the designed excitation:", run.excitation->after);
  }
  if (add_holds > 0) {
    BalanceDesignOptions balance_options;
    balance_options.add_holds = add_holds;
    balance_options.max_swashplate_rad = LimitFlag(FLAGS_max_swashplate_rad);
    balance_options.output_error = oe;
    balance_options.progress = progress;
    run.balance = DesignBalanceHolds(vehicle, plan, run.criterion, balance_options);
    run.final_precision = run.balance->after;
    PrintPrediction("with the balance holds added:", run.balance->after);
  }
  run.seconds = SecondsSince(start);
  WriteDesign(run, FLAGS_out);
  std::fprintf(stderr, "design: done in %.1f s -> %s/design.json, %s/report.md\n", run.seconds,
               FLAGS_out.c_str(), FLAGS_out.c_str());
  return 0;
}

}  // namespace coaxid
