#include "experiments/studies/spec.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/yaml_util.h"
#include "dynamics/vehicle.h"
#include "dynamics/effects/effect_library.h"
#include "experiments/simulation/outside_library_loads.h"
#include "experiments/simulation/simulate_experiment.h"
#include "experiments/studies/points.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

std::string Resolve(const std::string& path, const std::string& spec_path) {
  if (path.empty() || fs::path(path).is_absolute()) return path;
  return (fs::path(spec_path).parent_path() / path).lexically_normal().string();
}

StudyMethod ParseMethod(const std::string& name, const std::string& where) {
  if (name == "linear_kf") return StudyMethod::kLinearKf;
  if (name == "output_error") return StudyMethod::kOutputError;
  if (name == "ekf") return StudyMethod::kEkf;
  if (name == "discover") return StudyMethod::kDiscover;
  throw InputError(where + ": unknown method '" + name +
                   "' (expected linear_kf, output_error, ekf or discover)");
}

SweepSetting ParseSetting(const std::string& name, const std::string& where) {
  for (SweepSetting s :
       {SweepSetting::kNone, SweepSetting::kNoiseScale, SweepSetting::kExcitationScale,
        SweepSetting::kExcitationType, SweepSetting::kLogLength, SweepSetting::kSampleRate,
        SweepSetting::kInitialError, SweepSetting::kEffectStrength}) {
    if (name == SweepSettingName(s)) return s;
  }
  throw InputError(where + ": unknown setting '" + name +
                   "' (expected none, noise_scale, excitation_scale, excitation_type, "
                   "log_length_s, sample_rate_hz, initial_error or effect_strength)");
}

StudySweep ParseSweep(const YAML::Node& node, const std::string& where, const StudySpec& spec) {
  StudySweep sweep;
  if (!node) return sweep;
  CheckKeys(node, {"setting", "parameter", "values"}, where);
  if (!node["setting"]) throw InputError(where + ": missing 'setting'");
  sweep.setting = ParseSetting(ReadString(node["setting"], where + ".setting"), where + ".setting");
  const bool needs_parameter = sweep.setting == SweepSetting::kEffectStrength;
  if (needs_parameter != static_cast<bool>(node["parameter"])) {
    throw InputError(where + ".parameter: " +
                     (needs_parameter ? "effect_strength needs the truth effect parameter, "
                                        "e.g. parameter: wake_interference.k_T"
                                      : "only effect_strength takes a parameter"));
  }
  if (needs_parameter) {
    sweep.parameter = ReadString(node["parameter"], where + ".parameter");
    if (sweep.parameter.find('.') == std::string::npos) {
      throw InputError(where + ".parameter: '" + sweep.parameter + "' is not EFFECT.PARAMETER");
    }
  }
  if (sweep.setting == SweepSetting::kNone) {
    if (node["values"]) throw InputError(where + ".values: a sweep of none takes no values");
    return sweep;
  }
  const YAML::Node values = node["values"];
  if (!values || !values.IsSequence() || values.size() == 0) {
    throw InputError(where + ".values: expected a non-empty list");
  }
  const std::string w = where + ".values";
  if (sweep.setting == SweepSetting::kExcitationType) {
    for (size_t i = 0; i < values.size(); ++i) {
      const std::string type = ReadString(values[i], w);
      if (type != "multisine" && type != "3211" && type != "doublet" && type != "none") {
        throw InputError(w + ": '" + type + "' is not multisine, 3211, doublet or none");
      }
      sweep.types.push_back(type);
    }
  } else {
    sweep.values = ReadDoubleList(values, w);
    for (double v : sweep.values) {
      const bool ok = sweep.setting == SweepSetting::kEffectStrength ? true
                      : sweep.setting == SweepSetting::kInitialError ? (v >= 0 && v < 1)
                      : sweep.setting == SweepSetting::kNoiseScale   ? v >= 0
                                                                     : v > 0;
      if (!ok) {
        char text[64];
        std::snprintf(text, sizeof text, "%g", v);
        throw InputError(w + ": " + text + " is out of range for " +
                         SweepSettingName(sweep.setting) +
                         (sweep.setting == SweepSetting::kInitialError ? " (needs 0 <= e < 1)"
                          : sweep.setting == SweepSetting::kNoiseScale ? " (needs >= 0)"
                                                                       : " (needs > 0)"));
      }
    }
  }
  const bool flight_only =
      sweep.setting == SweepSetting::kExcitationType || sweep.setting == SweepSetting::kLogLength;
  if (flight_only && !spec.HasFlight()) {
    throw InputError(where + ".setting: " + SweepSettingName(sweep.setting) +
                     " applies to flight scenarios and the study has none");
  }
  return sweep;
}

std::array<double, 2> ReadRange(const YAML::Node& node, const std::string& where, double min) {
  const std::vector<double> v = ReadDoubleList(node, where);
  if (v.size() != 2 || !(v[0] <= v[1]) || v[0] < min) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", min);
    throw InputError(where + ": expected [lo, hi] with " + text + " <= lo <= hi");
  }
  return {v[0], v[1]};
}

double ReadShare(const YAML::Node& node, const std::string& where) {
  const double v = ReadDouble(node, where);
  if (!(v >= 0 && v <= 1)) throw InputError(where + ": must lie in [0, 1]");
  return v;
}

StudyRandomisation ParseRandomisation(const YAML::Node& node, const std::string& where,
                                      const StudySpec& spec) {
  StudyRandomisation r;
  if (!node) return r;
  r.enabled = true;
  CheckKeys(
      node,
      {"truth_offset", "rigid_body_inertias", "truths", "effects", "effect_strength",
       "outside_strength", "excitation", "swashplate_rms_rad", "omega_difference_rad_s",
       "gyroscopic_omega_difference_rad_s", "duration_s", "hover_height_m", "low_height_m",
       "low_share", "balance_share", "held_out_s", "controller_gain_factor", "sensor_noise_factor"},
      where);
  if (spec.sweep.setting != SweepSetting::kNone) {
    throw InputError(where + ": a randomised study draws its settings per seed and takes no sweep");
  }
  int flights = 0, balances = 0;
  for (const Scenario& s : spec.scenarios) (s.kind == Scenario::Kind::kFlight ? flights : balances)++;
  if (flights != 1 || balances > 1) {
    throw InputError(where + ": needs exactly one flight scenario (the template of every drawn "
                     "flight) and at most one balance scenario");
  }
  auto range = [&](const char* key, std::array<double, 2>* out, double min) {
    if (node[key]) *out = ReadRange(node[key], where + "." + key, min);
  };
  range("truth_offset", &r.truth_offset, 0);
  if (node["rigid_body_inertias"]) {
    r.rigid_body_inertias = ReadBool(node["rigid_body_inertias"], where + ".rigid_body_inertias");
  }
  range("effect_strength", &r.effect_strength, 0);
  range("swashplate_rms_rad", &r.swashplate_rms_rad, 0);
  range("omega_difference_rad_s", &r.omega_difference_rad_s, 0);
  range("gyroscopic_omega_difference_rad_s", &r.gyroscopic_omega_difference_rad_s, 0);
  range("duration_s", &r.duration_s, 5);
  range("hover_height_m", &r.hover_height_m, 0.05);
  range("low_height_m", &r.low_height_m, 0.05);
  range("controller_gain_factor", &r.controller_gain_factor, 1e-3);
  range("sensor_noise_factor", &r.sensor_noise_factor, 1e-3);
  if (r.truth_offset[1] >= 1) throw InputError(where + ".truth_offset: must stay below 1");
  if (const YAML::Node t = node["truths"]) {
    const std::string w = where + ".truths";
    CheckKeys(t, {"none", "single", "pair", "outside"}, w);
    r.truth_weights.clear();
    double total = 0;
    for (const auto& kv : t) {
      const std::string key = kv.first.as<std::string>();
      const double weight = ReadDouble(kv.second, w + "." + key);
      if (weight < 0) throw InputError(w + "." + key + ": must be >= 0");
      r.truth_weights[key] = weight;
      total += weight;
    }
    if (!(total > 0)) throw InputError(w + ": needs a positive weight");
  }
  if (const YAML::Node e = node["effects"]) {
    for (size_t i = 0; i < e.size(); ++i) {
      const std::string name = ReadString(e[i], where + ".effects");
      if (EffectIndex(name) < 0) {
        throw InputError(where + ".effects: '" + name + "' is not an effect of the library");
      }
      r.effects.push_back(name);
    }
  } else {
    for (const auto& effect : EffectLibrary()) r.effects.push_back(effect.name);
  }
  const bool pairs = r.truth_weights.count("pair") && r.truth_weights.at("pair") > 0;
  if (r.effects.size() < (pairs ? 2u : 1u)) {
    throw InputError(where + ".effects: too few effects for the truth classes drawn");
  }
  if (const YAML::Node o = node["outside_strength"]) {
    const std::string w = where + ".outside_strength";
    CheckKeys(o, OutsideLibraryNames(), w);
    for (const auto& kv : o) {
      const std::string key = kv.first.as<std::string>();
      r.outside_strength[key] = ReadRange(kv.second, w + "." + key, 0);
    }
  }
  if (const YAML::Node e = node["excitation"]) {
    r.excitations.clear();
    for (size_t i = 0; i < e.size(); ++i) {
      const std::string type = ReadString(e[i], where + ".excitation");
      if (type != "multisine" && type != "3211" && type != "doublet") {
        throw InputError(where + ".excitation: '" + type + "' is not multisine, 3211 or doublet");
      }
      r.excitations.push_back(type);
    }
    if (r.excitations.empty()) throw InputError(where + ".excitation: expected a non-empty list");
  }
  if (node["low_share"]) r.low_share = ReadShare(node["low_share"], where + ".low_share");
  if (node["balance_share"]) {
    r.balance_share = ReadShare(node["balance_share"], where + ".balance_share");
    if (r.balance_share > 0 && balances == 0) {
      throw InputError(where + ".balance_share: the study lists no balance scenario");
    }
  } else if (balances == 0) {
    r.balance_share = 0;
  }
  if (node["held_out_s"]) {
    r.held_out_s = ReadDouble(node["held_out_s"], where + ".held_out_s");
    if (!(r.held_out_s == 0 || r.held_out_s >= 5)) {
      throw InputError(where + ".held_out_s: 0 (none) or at least 5 s");
    }
  }
  return r;
}

bool SameParameters(const ParameterSet& a, const ParameterSet& b) {
  if (a.size() != b.size()) return false;
  for (int i = 0; i < a.size(); ++i) {
    if (a[i].name != b[i].name || a[i].value != b[i].value) return false;
  }
  return true;
}

void CheckMethodsFitLogs(const StudySpec& spec, const std::string& where) {
  for (StudyMethod m : spec.methods) {
    if (m == StudyMethod::kLinearKf && !spec.HasBalance()) {
      throw InputError(where +
                       ": linear_kf estimates from balance logs and the study has no "
                       "balance scenario");
    }
    if (m == StudyMethod::kEkf && !spec.HasFlight()) {
      throw InputError(where +
                       ": ekf estimates from flight logs and the study has no flight "
                       "scenario");
    }
  }
}

}  // namespace

const char* StudyMethodName(StudyMethod method) {
  switch (method) {
    case StudyMethod::kLinearKf:
      return "linear_kf";
    case StudyMethod::kOutputError:
      return "output_error";
    case StudyMethod::kEkf:
      return "ekf";
    case StudyMethod::kDiscover:
      return "discover";
  }
  return "?";
}

const char* SweepSettingName(SweepSetting setting) {
  switch (setting) {
    case SweepSetting::kNone:
      return "none";
    case SweepSetting::kNoiseScale:
      return "noise_scale";
    case SweepSetting::kExcitationScale:
      return "excitation_scale";
    case SweepSetting::kExcitationType:
      return "excitation_type";
    case SweepSetting::kLogLength:
      return "log_length_s";
    case SweepSetting::kSampleRate:
      return "sample_rate_hz";
    case SweepSetting::kInitialError:
      return "initial_error";
    case SweepSetting::kEffectStrength:
      return "effect_strength";
  }
  return "?";
}

int StudySweep::NumPoints() const {
  if (setting == SweepSetting::kNone) return 1;
  return static_cast<int>(setting == SweepSetting::kExcitationType ? types.size() : values.size());
}

std::string StudySweep::Label(int point) const {
  if (setting == SweepSetting::kNone) return "-";
  if (setting == SweepSetting::kExcitationType) return types[point];
  char text[32];
  std::snprintf(text, sizeof text, "%g", values[point]);
  return text;
}

double StudySweep::Value(int point) const {
  if (setting == SweepSetting::kNone || setting == SweepSetting::kExcitationType) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return values[point];
}

bool StudySpec::HasFlight() const {
  for (const Scenario& s : scenarios) {
    if (s.kind == Scenario::Kind::kFlight) return true;
  }
  return false;
}

bool StudySpec::HasBalance() const {
  for (const Scenario& s : scenarios) {
    if (s.kind == Scenario::Kind::kBalance) return true;
  }
  return false;
}

StudyRunId RunIdAt(const StudySpec& spec, int run_index) {
  StudyRunId id;
  id.point = run_index / spec.seed_count;
  id.seed_index = run_index % spec.seed_count;
  id.seed = spec.base_seed + static_cast<uint64_t>(id.seed_index);
  return id;
}

std::string RunKey(int point, int seed_index) {
  return "p" + std::to_string(point) + "_s" + std::to_string(seed_index);
}

std::string Fnv1aHex(const std::string& text, uint64_t hash) {
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  char out[17];
  std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(hash));
  return out;
}

StudySpec ParseStudySpec(const std::string& yaml_text, const std::string& source) {
  const YAML::Node root = ParseYaml(yaml_text, source);
  if (!root.IsMap()) throw InputError(source + ": expected a YAML map");
  CheckKeys(root,
            {"study", "config", "scenarios", "estimate", "methods", "seeds", "sweep",
             "randomise", "output_error", "discover"},
            source);
  StudySpec spec;
  spec.source = source;
  spec.name = root["study"] ? ReadString(root["study"], source + ": study")
                            : fs::path(source).stem().string();
  std::string hashed = yaml_text;

  if (!root["config"]) throw InputError(source + ": missing 'config' (the vehicle config file)");
  spec.config_path = Resolve(ReadString(root["config"], source + ": config"), source);
  const std::string config_text = ReadFile(spec.config_path);
  spec.config = ParseVehicleConfig(config_text, spec.config_path);
  hashed += config_text;

  const YAML::Node scenarios = root["scenarios"];
  if (!scenarios || !scenarios.IsSequence() || scenarios.size() == 0) {
    throw InputError(source + ": scenarios: expected a non-empty list of scenario files");
  }
  for (size_t i = 0; i < scenarios.size(); ++i) {
    const std::string path = Resolve(
        ReadString(scenarios[i], source + ": scenarios[" + std::to_string(i) + "]"), source);
    const std::string text = ReadFile(path);
    spec.scenarios.push_back(ParseScenario(text, path));
    spec.scenario_paths.push_back(path);
    hashed += text;
  }

  const Vehicle vehicle = MakeVehicle(spec.config);
  if (const YAML::Node estimate = root["estimate"]) {
    if (!estimate.IsSequence() || estimate.size() == 0) {
      throw InputError(source + ": estimate: expected a non-empty list of parameter names");
    }
    for (size_t i = 0; i < estimate.size(); ++i) {
      const std::string name = ReadString(estimate[i], source + ": estimate");
      if (!vehicle.parameters.Has(name) || !vehicle.parameters.Get(name).estimated) {
        throw InputError(source + ": estimate: '" + name + "' is not a free parameter of " +
                         spec.config_path);
      }
      spec.estimate.push_back(name);
    }
  }

  const YAML::Node methods = root["methods"];
  if (!methods || !methods.IsSequence() || methods.size() == 0) {
    throw InputError(source +
                     ": methods: expected a non-empty list (linear_kf, output_error, "
                     "ekf, discover)");
  }
  for (size_t i = 0; i < methods.size(); ++i) {
    const StudyMethod m =
        ParseMethod(ReadString(methods[i], source + ": methods"), source + ": methods");
    for (StudyMethod seen : spec.methods) {
      if (seen == m) {
        throw InputError(source + ": methods: '" + StudyMethodName(m) + "' given twice");
      }
    }
    spec.methods.push_back(m);
  }
  CheckMethodsFitLogs(spec, source + ": methods");

  const YAML::Node seeds = root["seeds"];
  if (!seeds) throw InputError(source + ": missing 'seeds: {count: N, base: S}'");
  CheckKeys(seeds, {"count", "base"}, source + ": seeds");
  if (!seeds["count"]) throw InputError(source + ": seeds: missing 'count'");
  spec.seed_count = ReadInt(seeds["count"], source + ": seeds.count");
  if (spec.seed_count < 1) throw InputError(source + ": seeds.count: must be at least 1");
  if (seeds["base"]) {
    const int base = ReadInt(seeds["base"], source + ": seeds.base");
    if (base < 0) throw InputError(source + ": seeds.base: must be >= 0");
    spec.base_seed = static_cast<uint64_t>(base);
  }

  spec.sweep = ParseSweep(root["sweep"], source + ": sweep", spec);
  spec.randomise = ParseRandomisation(root["randomise"], source + ": randomise", spec);

  if (const YAML::Node oe = root["output_error"]) {
    const std::string w = source + ": output_error";
    CheckKeys(oe, {"segment_s", "noise_relaxations"}, w);
    if (oe["segment_s"]) spec.segment_s = ReadDouble(oe["segment_s"], w + ".segment_s");
    if (oe["noise_relaxations"]) {
      spec.noise_relaxations = ReadInt(oe["noise_relaxations"], w + ".noise_relaxations");
    }
    if (!(spec.segment_s > 0)) throw InputError(w + ".segment_s: must be positive");
    if (spec.noise_relaxations < 0) throw InputError(w + ".noise_relaxations: must be >= 0");
  }
  if (const YAML::Node d = root["discover"]) {
    const std::string w = source + ": discover";
    CheckKeys(d, {"alpha", "max_added"}, w);
    if (d["alpha"]) spec.discover_alpha = ReadDouble(d["alpha"], w + ".alpha");
    if (d["max_added"]) spec.discover_max_added = ReadInt(d["max_added"], w + ".max_added");
    if (!(spec.discover_alpha > 0 && spec.discover_alpha < 1)) {
      throw InputError(w + ".alpha: must lie in (0, 1)");
    }
    if (spec.discover_max_added < 1) throw InputError(w + ".max_added: must be at least 1");
  }

  // Every point's scenarios and truth must build (unknown effect or
  // parameter, a sweep that leaves nothing to simulate): found now, not in
  // the middle of the study.
  // The scenarios are experiments on one vehicle: their truths must agree.
  for (int p = 0; p < spec.sweep.NumPoints(); ++p) {
    std::vector<Vehicle> truths;
    for (const Scenario& s : PointScenarios(spec, p, spec.base_seed)) {
      try {
        truths.push_back(MakeTruthVehicle(spec.config, s));
      } catch (const InputError& e) {
        throw InputError(source + ": sweep point " + spec.sweep.Label(p) + ", scenario " + s.name +
                         ": " + e.what());
      }
      if (!SameParameters(truths.front().parameters, truths.back().parameters)) {
        throw InputError(source + ": scenarios: " + spec.scenarios.front().name + " and " + s.name +
                         " describe different truth vehicles (parameters or effects)");
      }
    }
  }
  spec.hash = Fnv1aHex(hashed);
  return spec;
}

StudySpec LoadStudySpec(const std::string& path) { return ParseStudySpec(ReadFile(path), path); }

}  // namespace coaxid
