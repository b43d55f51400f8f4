#include "core/plausibility.h"

#include <cmath>
#include <cstdio>
#include <limits>

namespace coaxid {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A channel whose variation (rms of measured - mean) is within this factor
// of its noise std holds nothing the model could explain (a position
// channel through a short hover: nrmse 11 on noise alone).
constexpr double kSignalOverNoise = 2.0;

std::string Number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

std::string WithUnit(double v, const std::string& unit) {
  return unit.empty() ? Number(v) : Number(v) + " " + unit;
}

const char* KindName(PlausibilityFinding::Kind k) {
  switch (k) {
    case PlausibilityFinding::Kind::kAtBound: return "at_bound";
    case PlausibilityFinding::Kind::kOutsidePhysicalRange: return "outside_physical_range";
    case PlausibilityFinding::Kind::kUnexplainedChannel: return "unexplained_channel";
  }
  return "?";
}

class Judge {
 public:
  Judge(const ParameterSet& declared, const std::map<std::string, double>& estimates)
      : declared_(declared), estimates_(estimates) {}

  bool Estimated(const std::string& name) const {
    return declared_.Has(name) && estimates_.count(name) > 0;
  }
  double Value(const std::string& name) const {
    const auto it = estimates_.find(name);
    return it != estimates_.end() ? it->second : declared_.Value(name);
  }

  // A value (a parameter's or a derived quantity's) against [lower, upper].
  void Range(const std::string& subject, double value, double lower, double upper,
             const std::string& unit, const std::string& why) {
    if (value >= lower && value <= upper) return;
    PlausibilityFinding f;
    f.kind = PlausibilityFinding::Kind::kOutsidePhysicalRange;
    f.subject = subject;
    f.value = value;
    f.lower = lower;
    f.upper = upper;
    f.text = subject + " = " + WithUnit(value, unit) + (value > upper ? " above " : " below ") +
             WithUnit(value > upper ? upper : lower, unit) + " (" + why + ")";
    findings.push_back(f);
  }

  std::vector<PlausibilityFinding> findings;

 private:
  const ParameterSet& declared_;
  const std::map<std::string, double>& estimates_;
};

void JudgeChannels(const nlohmann::json& fit, const char* where,
                   const std::map<std::string, double>& noise_std,
                   std::vector<PlausibilityFinding>* out) {
  if (!fit.is_object()) return;
  for (auto it = fit.begin(); it != fit.end(); ++it) {
    const nlohmann::json& c = it.value();
    if (!c.is_object() || !c.contains("nrmse") || !c["nrmse"].is_number()) continue;
    const double nrmse = c["nrmse"].get<double>();
    if (!(nrmse >= kUnexplainedNrmse)) continue;
    const auto noise = noise_std.find(it.key());
    if (noise != noise_std.end() && c.contains("rms") && c["rms"].is_number() &&
        !(c["rms"].get<double>() / nrmse > kSignalOverNoise * noise->second)) {
      continue;  // rms / nrmse: the channel's own variation
    }
    PlausibilityFinding f;
    f.kind = PlausibilityFinding::Kind::kUnexplainedChannel;
    f.subject = it.key();
    f.value = nrmse;
    f.lower = 0;
    f.upper = kUnexplainedNrmse;
    f.where = where;
    f.text = it.key() + " is not explained on the " + where + " data: nrmse " + Number(nrmse) +
             " (the model predicts it no better than its mean)";
    out->push_back(f);
  }
}

}  // namespace

PlausibilityVerdict JudgePlausibility(const ParameterSet& declared,
                                      const std::map<std::string, double>& estimates,
                                      const nlohmann::json& fit, const nlohmann::json& validation,
                                      const std::map<std::string, double>& noise_std,
                                      const std::set<std::string>& undetermined) {
  PlausibilityVerdict verdict;
  JudgeChannels(fit, "estimation", noise_std, &verdict.findings);
  JudgeChannels(validation, "held-out", noise_std, &verdict.findings);

  for (const auto& [name, value] : estimates) {
    if (!declared.Has(name) || undetermined.count(name)) continue;
    const Parameter& p = declared.Get(name);
    const double tolerance = 1e-6 * (p.upper - p.lower);  // as ParametersAtBounds
    const bool lower = value <= p.lower + tolerance, upper = value >= p.upper - tolerance;
    if (!lower && !upper) continue;
    PlausibilityFinding f;
    f.kind = PlausibilityFinding::Kind::kAtBound;
    f.subject = name;
    f.value = value;
    f.lower = p.lower;
    f.upper = p.upper;
    const bool beyond = value < p.lower || value > p.upper;
    f.text = name + " = " + WithUnit(value, p.unit) + (beyond ? " is beyond" : " sits at") +
             " its " + (lower ? "lower" : "upper") + " bound " +
             WithUnit(lower ? p.lower : p.upper, p.unit) + " (the data pushed it to the limit)";
    verdict.findings.push_back(f);
  }

  Judge j(declared, estimates);
  const double m = declared.Value(BaseParameterName(kMass));
  const double R = declared.Value(BaseParameterName(kRotorRadius));
  const double l = declared.Value(BaseParameterName(kBodyLength));
  const double r = std::sqrt(R * R + 0.25 * l * l);
  const std::string sphere = "m r^2, r = sqrt(R^2 + (l/2)^2) = " + Number(r) +
                             " m: no body of mass " + Number(m) + " kg inside that sphere has more";
  const char* inertias[] = {"Ixx", "Iyy", "Izz"};
  bool any_inertia = false;
  for (const char* I : inertias) {
    if (!j.Estimated(I)) continue;
    any_inertia = true;
    j.Range(I, j.Value(I), 0, m * r * r, "kg m^2", sphere);
  }
  if (any_inertia) {
    for (int k = 0; k < 3; ++k) {
      const std::string a = inertias[k], b = inertias[(k + 1) % 3], c = inertias[(k + 2) % 3];
      j.Range(a + " + " + b + " - " + c, j.Value(a) + j.Value(b) - j.Value(c), 0, kInf, "kg m^2",
              "principal moments of inertia obey the triangle inequality");
    }
  }
  if (j.Estimated("d")) {
    j.Range("d", j.Value("d"), 0, r, "m",
            "the lower hub lies within r = sqrt(R^2 + (l/2)^2) of G");
  }
  for (const char* C : {"Cx", "Cy", "Cz"}) {
    if (j.Estimated(C)) {
      j.Range(C, j.Value(C), 0.05, 3.0, "", "bluff-body drag coefficients lie in [0.05, 3]");
    }
  }
  if (j.Estimated("sigma0")) {
    j.Range("sigma0", j.Value("sigma0"), 0, 0.4, "",
            "a coaxial rotor's interference loss at equal speeds lies in [0, 0.4]");
  }
  const std::pair<const char*, const char*> rotors[] = {{"gamma1", "alpha"}, {"gamma2", "beta"}};
  for (const auto& [gamma, thrust] : rotors) {
    if (!j.Estimated(gamma) && !j.Estimated(thrust)) continue;
    const double ratio = std::fabs(j.Value(gamma) / j.Value(thrust));
    j.Range(std::string("|") + gamma + " / " + thrust + "|", ratio, 0.02 * R, 0.5 * R, "m",
            "a rotor's torque-to-thrust ratio (C_Q / C_T) R, C_Q / C_T in [0.02, 0.5]");
  }
  for (PlausibilityFinding& f : j.findings) verdict.findings.push_back(std::move(f));
  return verdict;
}

std::string PlausibilityVerdict::Summary() const {
  if (findings.empty()) {
    return "plausible: no estimated parameter at a bound or outside its physical range, and "
           "every channel explained (nrmse < " + Number(kUnexplainedNrmse) + ")";
  }
  std::string channels, at_bound, outside;
  for (const PlausibilityFinding& f : findings) {
    std::string* list = f.kind == PlausibilityFinding::Kind::kUnexplainedChannel ? &channels
                        : f.kind == PlausibilityFinding::Kind::kAtBound        ? &at_bound
                                                                                : &outside;
    if (f.kind == PlausibilityFinding::Kind::kUnexplainedChannel) {
      *list += (list->empty() ? "" : ", ") + f.subject + " (nrmse " + Number(f.value) + ", " +
               f.where + ")";
    } else {
      *list += (list->empty() ? "" : "; ") + f.text;
    }
  }
  std::string s = "the model does not describe this vehicle";
  if (!channels.empty()) s += "; channels it does not explain: " + channels;
  if (!at_bound.empty()) s += "; parameters at a bound: " + at_bound;
  if (!outside.empty()) s += "; values outside physical ranges: " + outside;
  return s + ". Estimates from such a fit are not the vehicle's: the model lacks something "
             "(try `coaxid discover`), or the logs do not excite what it needs.";
}

std::map<std::string, double> EstimatesOfReport(const nlohmann::json& parameters,
                                                const ParameterSet& declared,
                                                std::set<std::string>* undetermined) {
  std::map<std::string, double> out;
  if (!parameters.is_object()) return out;
  for (auto it = parameters.begin(); it != parameters.end(); ++it) {
    const nlohmann::json& p = it.value();
    if (!p.is_object() || !p.value("estimated", false) || !p.contains("value") ||
        !p["value"].is_number()) {
      continue;
    }
    const double value = p["value"].get<double>();
    if (p.contains("std") && p["std"].is_null()) {
      if (!declared.Has(it.key())) continue;
      const Parameter& d = declared.Get(it.key());
      const double tolerance = 1e-6 * (d.upper - d.lower);  // as ParametersAtBounds
      if (value > d.lower + tolerance && value < d.upper - tolerance) continue;
      if (undetermined) undetermined->insert(it.key());
    }
    out[it.key()] = value;
  }
  return out;
}

nlohmann::json PlausibilityVerdict::ToJson() const {
  nlohmann::json list = nlohmann::json::array();
  auto bound = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  for (const PlausibilityFinding& f : findings) {
    nlohmann::json j = {{"kind", KindName(f.kind)},
                        {"subject", f.subject},
                        {"value", f.value},
                        {"range", {bound(f.lower), bound(f.upper)}},
                        {"text", f.text}};
    if (!f.where.empty()) j["where"] = f.where;
    list.push_back(j);
  }
  return {{"describes_vehicle", DescribesVehicle()}, {"verdict", Summary()}, {"findings", list}};
}

}  // namespace coaxid
