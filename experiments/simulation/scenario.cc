#include "experiments/simulation/scenario.h"

#include <algorithm>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/yaml_util.h"
#include "experiments/simulation/outside_library_loads.h"

namespace coaxid {
namespace {

void ReadNamedDoubles(const YAML::Node& node, const std::vector<std::string>& allowed,
                      const std::string& where, std::map<std::string, double>* out) {
  CheckKeys(node, allowed, where);
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    (*out)[key] = ReadDouble(kv.second, where + "." + key);
  }
}

void CheckPositive(double v, const std::string& where) {
  if (!(v > 0)) throw InputError(where + ": must be positive");
}

void ParseBalance(const YAML::Node& node, const std::string& where, BalanceScenario* b) {
  CheckKeys(node,
            {"rate_hz", "hold_s", "omega1", "omega2", "delta_cx", "delta_cy", "steady_points",
             "per_rotor", "noise_std", "holds"},
            where);
  if (node["rate_hz"]) b->rate_hz = ReadDouble(node["rate_hz"], where + ".rate_hz");
  if (node["hold_s"]) b->hold_s = ReadDouble(node["hold_s"], where + ".hold_s");
  CheckPositive(b->rate_hz, where + ".rate_hz");
  CheckPositive(b->hold_s, where + ".hold_s");
  for (const char* key : {"omega1", "omega2", "delta_cx", "delta_cy"}) {
    if (!node[key]) continue;
    std::vector<double> v = ReadDoubleList(node[key], where + "." + key);
    // An empty speed list means no grid: the holds are those listed under `holds`.
    const bool speed = std::string(key) == "omega1" || std::string(key) == "omega2";
    if (v.empty() && !speed) throw InputError(where + "." + key + ": needs at least one value");
    if (std::string(key) == "omega1") b->omega1 = v;
    if (std::string(key) == "omega2") b->omega2 = v;
    if (std::string(key) == "delta_cx") b->delta_cx = v;
    if (std::string(key) == "delta_cy") b->delta_cy = v;
  }
  if (const YAML::Node holds = node["holds"]) {
    if (!holds.IsSequence()) throw InputError(where + ".holds: expected a list of [omega1, omega2, delta_cx, delta_cy]");
    for (size_t i = 0; i < holds.size(); ++i) {
      const std::string wh = where + ".holds[" + std::to_string(i) + "]";
      const std::vector<double> v = ReadDoubleList(holds[i], wh);
      if (v.size() != 4) throw InputError(wh + ": expected [omega1, omega2, delta_cx, delta_cy]");
      if (!(v[0] >= 0 && v[1] >= 0)) throw InputError(wh + ": rotor speeds must be >= 0");
      b->holds.push_back({v[0], v[1], v[2], v[3]});
    }
  }
  if (b->omega1.empty() != b->omega2.empty()) {
    throw InputError(where + ": omega1 and omega2 are both empty (holds only) or both given");
  }
  if (b->omega1.empty() && b->holds.empty()) {
    throw InputError(where + ": no holds: give the omega1 x omega2 grid or a list under holds");
  }
  if (node["steady_points"]) b->steady_points = ReadBool(node["steady_points"], where);
  if (node["per_rotor"]) b->per_rotor = ReadBool(node["per_rotor"], where);
  if (node["noise_std"]) {
    ReadNamedDoubles(node["noise_std"], {"X", "Y", "Z", "L", "M", "N", "Z1", "Z2", "N1", "N2"},
                     where + ".noise_std", &b->noise_std);
  }
}

const std::vector<std::string>& FlightColumnNames() {
  static const std::vector<std::string> names{"x", "y", "z", "u", "v", "w", "phi", "theta",
                                              "psi", "p", "q", "r", "ax", "ay", "az"};
  return names;
}

void ParseFlight(const YAML::Node& node, const std::string& where, FlightScenario* f) {
  CheckKeys(node,
            {"duration_s", "rate_hz", "waypoints", "controller", "excitation", "columns",
             "noise_std", "bias"},
            where);
  if (node["duration_s"]) f->duration_s = ReadDouble(node["duration_s"], where + ".duration_s");
  if (node["rate_hz"]) f->rate_hz = ReadDouble(node["rate_hz"], where + ".rate_hz");
  CheckPositive(f->duration_s, where + ".duration_s");
  CheckPositive(f->rate_hz, where + ".rate_hz");
  if (const YAML::Node wps = node["waypoints"]) {
    if (!wps.IsSequence() || wps.size() == 0) {
      throw InputError(where + ".waypoints: expected a non-empty list");
    }
    f->waypoints.clear();
    for (size_t i = 0; i < wps.size(); ++i) {
      const std::string w = where + ".waypoints[" + std::to_string(i) + "]";
      CheckKeys(wps[i], {"t_s", "north", "east", "height", "heading"}, w);
      Waypoint p;
      if (wps[i]["t_s"]) p.t_s = ReadDouble(wps[i]["t_s"], w + ".t_s");
      if (wps[i]["north"]) p.north = ReadDouble(wps[i]["north"], w + ".north");
      if (wps[i]["east"]) p.east = ReadDouble(wps[i]["east"], w + ".east");
      if (wps[i]["height"]) p.height = ReadDouble(wps[i]["height"], w + ".height");
      if (wps[i]["heading"]) p.heading = ReadDouble(wps[i]["heading"], w + ".heading");
      if (!f->waypoints.empty() && p.t_s <= f->waypoints.back().t_s) {
        throw InputError(w + ".t_s: waypoint times must increase");
      }
      f->waypoints.push_back(p);
    }
  }
  if (const YAML::Node c = node["controller"]) {
    const std::string w = where + ".controller";
    const auto fields = f->gains.Fields();
    std::vector<std::string> keys;
    for (const auto& [key, ptr] : fields) keys.push_back(key);
    CheckKeys(c, keys, w);
    for (const auto& [key, ptr] : fields) {
      if (c[key]) *ptr = ReadDouble(c[key], w + "." + key);
    }
  }
  if (const YAML::Node e = node["excitation"]) {
    const std::string w = where + ".excitation";
    CheckKeys(e,
              {"type", "start_s", "amplitude", "min_hz", "max_hz", "period_s", "pulse_s", "bands",
               "quiet"},
              w);
    Excitation& x = f->excitation;
    if (e["type"]) {
      const std::string type = ReadString(e["type"], w + ".type");
      if (type == "none") {
        x.type = Excitation::Type::kNone;
      } else if (type == "multisine") {
        x.type = Excitation::Type::kMultisine;
      } else if (type == "3211") {
        x.type = Excitation::Type::k3211;
      } else if (type == "doublet") {
        x.type = Excitation::Type::kDoublet;
      } else {
        throw InputError(w + ".type: '" + type + "' is not none, multisine, 3211 or doublet");
      }
    }
    if (e["start_s"]) x.start_s = ReadDouble(e["start_s"], w + ".start_s");
    if (e["amplitude"]) {
      ReadNamedDoubles(e["amplitude"], {"omega1", "omega2", "delta_cx", "delta_cy"},
                       w + ".amplitude", &x.amplitude);
    }
    if (e["min_hz"]) x.min_hz = ReadDouble(e["min_hz"], w + ".min_hz");
    if (e["max_hz"]) x.max_hz = ReadDouble(e["max_hz"], w + ".max_hz");
    if (e["period_s"]) x.period_s = ReadDouble(e["period_s"], w + ".period_s");
    if (e["pulse_s"]) x.pulse_s = ReadDouble(e["pulse_s"], w + ".pulse_s");
    CheckPositive(x.period_s, w + ".period_s");
    CheckPositive(x.pulse_s, w + ".pulse_s");
    if (!(x.min_hz > 0 && x.max_hz > x.min_hz)) {
      throw InputError(w + ": need 0 < min_hz < max_hz");
    }
    if (const YAML::Node quiet = e["quiet"]) {
      if (!quiet.IsSequence()) throw InputError(w + ".quiet: expected a list of [from_s, to_s]");
      for (size_t i = 0; i < quiet.size(); ++i) {
        const std::string wq = w + ".quiet[" + std::to_string(i) + "]";
        const std::vector<double> v = ReadDoubleList(quiet[i], wq);
        if (v.size() != 2 || !(v[1] >= v[0])) throw InputError(wq + ": expected [from_s, to_s], from <= to");
        x.quiet.push_back({v[0], v[1]});
      }
    }
    if (const YAML::Node bands = e["bands"]) {
      if (x.type != Excitation::Type::kMultisine) {
        throw InputError(w + ".bands: only a multisine is shaped by bands");
      }
      for (const char* key : {"amplitude", "min_hz", "max_hz"}) {
        if (e[key]) throw InputError(w + ".bands: replaces '" + key + "'; give one or the other");
      }
      if (!bands.IsSequence() || bands.size() == 0) {
        throw InputError(w + ".bands: expected a non-empty list");
      }
      for (size_t i = 0; i < bands.size(); ++i) {
        const std::string wb = w + ".bands[" + std::to_string(i) + "]";
        CheckKeys(bands[i], {"min_hz", "max_hz", "rms"}, wb);
        Excitation::Band band;
        if (!bands[i]["min_hz"] || !bands[i]["max_hz"]) {
          throw InputError(wb + ": needs min_hz and max_hz");
        }
        band.min_hz = ReadDouble(bands[i]["min_hz"], wb + ".min_hz");
        band.max_hz = ReadDouble(bands[i]["max_hz"], wb + ".max_hz");
        if (!(band.min_hz > 0 && band.max_hz > band.min_hz)) {
          throw InputError(wb + ": need 0 < min_hz < max_hz");
        }
        if (!x.bands.empty() && band.min_hz < x.bands.back().max_hz) {
          throw InputError(wb + ": bands must be in increasing order and not overlap");
        }
        if (bands[i]["rms"]) {
          ReadNamedDoubles(bands[i]["rms"], {"omega1", "omega2", "delta_cx", "delta_cy"},
                           wb + ".rms", &band.rms);
        }
        for (const auto& [channel, rms] : band.rms) {
          if (!(rms >= 0)) throw InputError(wb + ".rms." + channel + ": must be >= 0");
        }
        x.bands.push_back(band);
      }
    }
  }
  if (node["columns"]) {
    const YAML::Node cols = node["columns"];
    if (!cols.IsSequence()) throw InputError(where + ".columns: expected a list");
    f->columns.clear();
    for (size_t i = 0; i < cols.size(); ++i) {
      const std::string c = ReadString(cols[i], where + ".columns");
      const auto& known = FlightColumnNames();
      if (std::find(known.begin(), known.end(), c) == known.end()) {
        throw InputError(where + ".columns: unknown column '" + c + "'");
      }
      f->columns.push_back(c);
    }
    for (const char* required : {"phi", "theta", "psi", "p", "q", "r"}) {
      if (std::find(f->columns.begin(), f->columns.end(), required) == f->columns.end()) {
        throw InputError(where + ".columns: '" + required +
                         "' is required in a flight log (log-format.md)");
      }
    }
  }
  std::vector<std::string> noisy = FlightColumnNames();
  for (const char* in : {"omega1", "omega2", "delta_cx", "delta_cy"}) noisy.push_back(in);
  if (node["noise_std"]) ReadNamedDoubles(node["noise_std"], noisy, where + ".noise_std", &f->noise_std);
  if (node["bias"]) ReadNamedDoubles(node["bias"], noisy, where + ".bias", &f->bias);
}

}  // namespace

Scenario ParseScenario(const std::string& yaml_text, const std::string& source) {
  const YAML::Node root = ParseYaml(yaml_text, source);
  if (!root.IsMap()) throw InputError(source + ": expected a YAML map");
  CheckKeys(root, {"scenario", "seed", "balance", "flight", "truth"}, source);
  Scenario s;
  s.name = std::filesystem::path(source).stem().string();
  if (!root["scenario"]) throw InputError(source + ": missing 'scenario: balance|flight'");
  const std::string kind = ReadString(root["scenario"], source + ": scenario");
  if (kind == "balance") {
    s.kind = Scenario::Kind::kBalance;
  } else if (kind == "flight") {
    s.kind = Scenario::Kind::kFlight;
  } else {
    throw InputError(source + ": scenario: '" + kind + "' is not balance or flight");
  }
  if (root["seed"]) s.seed = static_cast<uint64_t>(ReadInt(root["seed"], source + ": seed"));
  if (root["balance"]) ParseBalance(root["balance"], source + ": balance", &s.balance);
  if (root["flight"]) ParseFlight(root["flight"], source + ": flight", &s.flight);
  if (const YAML::Node truth = root["truth"]) {
    const std::string w = source + ": truth";
    CheckKeys(truth, {"parameters", "effects", "outside_library"}, w);
    if (const YAML::Node params = truth["parameters"]) {
      if (!params.IsMap()) throw InputError(w + ".parameters: expected a map");
      for (const auto& kv : params) {
        const std::string key = kv.first.as<std::string>();
        s.truth_parameters[key] = ReadDouble(kv.second, w + ".parameters." + key);
      }
    }
    if (const YAML::Node effects = truth["effects"]) {
      if (!effects.IsMap()) throw InputError(w + ".effects: expected a map");
      for (const auto& kv : effects) {
        const std::string name = kv.first.as<std::string>();
        std::map<std::string, ParameterOverride> overrides;
        if (kv.second.IsMap()) {
          for (const auto& pv : kv.second) {
            const std::string pname = pv.first.as<std::string>();
            overrides[pname] =
                ReadParameterOverride(pv.second, w + ".effects." + name + "." + pname);
          }
        }
        s.truth_effects.emplace_back(name, std::move(overrides));
      }
    }
    if (const YAML::Node outside = truth["outside_library"]) {
      if (!outside.IsMap()) throw InputError(w + ".outside_library: expected a map");
      for (const auto& kv : outside) {
        const std::string key = kv.first.as<std::string>();
        s.truth_outside_library[key] = ReadDouble(kv.second, w + ".outside_library." + key);
      }
      ParseOutsideLibrary(s.truth_outside_library, w + ".outside_library");
    }
  }
  return s;
}

Scenario LoadScenario(const std::string& path_or_name) {
  if (path_or_name == "balance" || path_or_name == "flight") {
    Scenario s;
    s.name = path_or_name;
    s.kind = path_or_name == "balance" ? Scenario::Kind::kBalance : Scenario::Kind::kFlight;
    return s;
  }
  return ParseScenario(ReadFile(path_or_name), path_or_name);
}

}  // namespace coaxid
