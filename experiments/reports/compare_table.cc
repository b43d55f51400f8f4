#include "experiments/reports/compare_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "core/report_values.h"

namespace coaxid {
namespace {

using json = nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// model.md's unknowns, in its order; effect parameters follow.
const char* const kModelUnknowns[] = {"alpha",  "beta",   "sigma0", "Cx",  "Cy",  "Cz",
                                      "gamma1", "gamma2", "d",      "Ixx", "Iyy", "Izz"};

json NumberJson(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// One method's entry for one parameter, from its report.json "parameters"
// entry: kind estimated (value, std), not identifiable (value), config (value
// held at the config's) or absent.
json Entry(const json& p) {
  if (!p.is_object() || !p.contains("value")) return {{"kind", "absent"}};
  const double value = JsonNumber(p, "value");
  if (p.value("held_for_the_scale", false)) {
    return {{"kind", "held for the scale"}, {"value", NumberJson(value)}, {"std", nullptr}};
  }
  if (p.contains("estimated") && p["estimated"] == false) {
    return {{"kind", "config"}, {"value", NumberJson(value)}, {"std", nullptr}};
  }
  const double std = JsonNumber(p, "std");
  if (std::isfinite(std) && std >= 0 && std::isfinite(value)) {
    return {{"kind", "estimated"}, {"value", value}, {"std", std}};
  }
  return {{"kind", "not identifiable"}, {"value", NumberJson(value)}, {"std", nullptr}};
}

bool HasStd(const json& e) { return e.value("kind", "") == "estimated"; }

const json& Parameters(const MethodRun& run) {
  static const json kNone = json::object();
  return run.status == "ran" && run.report.contains("parameters") ? run.report["parameters"]
                                                                  : kNone;
}

const MethodRun* Find(const std::vector<MethodRun>& runs, const std::string& method) {
  for (const MethodRun& r : runs) {
    if (r.method == method) return &r;
  }
  return nullptr;
}

// A table row: entries per method, pairwise agreement, error against truth.
json Row(const std::string& name, const std::string& description, double truth,
         const json& estimates) {
  json row = {{"name", name}, {"truth", NumberJson(truth)}, {"estimates", estimates}};
  if (!description.empty()) row["description"] = description;
  json agreement = json::object(), error = json::object();
  const std::vector<std::string>& methods = CompareMethods();
  for (size_t i = 0; i < methods.size(); ++i) {
    if (!estimates.contains(methods[i])) continue;
    const json& a = estimates[methods[i]];
    if (!HasStd(a)) continue;
    const double va = a["value"].get<double>(), sa = a["std"].get<double>();
    if (std::isfinite(truth) && sa > 0) error[methods[i]] = (va - truth) / sa;
    for (size_t j = i + 1; j < methods.size(); ++j) {
      if (!estimates.contains(methods[j]) || !HasStd(estimates[methods[j]])) continue;
      const json& b = estimates[methods[j]];
      const double vb = b["value"].get<double>(), sb = b["std"].get<double>();
      const double combined = std::hypot(sa, sb);
      if (combined > 0) {
        agreement[methods[i] + " vs " + methods[j]] = std::fabs(va - vb) / combined;
      }
    }
  }
  row["agreement_sigma"] = agreement;
  if (std::isfinite(truth)) row["error_sigma"] = error;
  return row;
}

// A scale-free ratio's truth from truth.json's parameters: its name is
// "a*b/c" (ident/scale_gauge.h).
double RatioTruth(const json& truth, const std::string& name) {
  const size_t slash = name.rfind('/');
  if (slash == std::string::npos) return kNaN;
  double value = 1 / JsonNumber(truth, name.substr(slash + 1));
  std::string numerator = name.substr(0, slash);
  for (size_t start = 0; start <= numerator.size();) {
    const size_t star = std::min(numerator.find('*', start), numerator.size());
    value *= JsonNumber(truth, numerator.substr(start, star - start));
    start = star + 1;
  }
  return value;
}

// The scale-free ratios (report.json "ratios") the methods give, one row each.
json RatioRows(const std::vector<MethodRun>& runs, const json& truth) {
  std::vector<std::string> names;
  for (const MethodRun& run : runs) {
    if (run.status != "ran" || !run.report.contains("ratios")) continue;
    for (const auto& [name, r] : run.report["ratios"].items()) {
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    }
  }
  json rows = json::array();
  for (const std::string& name : names) {
    json estimates = json::object();
    for (const MethodRun& run : runs) {
      if (run.status != "ran" || !run.report.contains("ratios")) continue;
      estimates[run.method] = Entry(run.report["ratios"].value(name, json()));
    }
    rows.push_back(Row(name, "", truth.is_object() ? RatioTruth(truth, name) : kNaN, estimates));
  }
  return rows;
}

// Per-channel {rms, nrmse} of a report's "fit" or "validation" section.
json ChannelErrors(const json& section) {
  json out = json::object();
  if (!section.is_object()) return out;
  for (const auto& [channel, e] : section.items()) {
    if (!e.is_object() || !e.contains("nrmse")) continue;
    out[channel] = {{"rms", NumberJson(JsonNumber(e, "rms"))},
                    {"nrmse", NumberJson(JsonNumber(e, "nrmse"))}};
  }
  return out;
}

std::string ValidationData(const json& report) {
  if (!report.contains("validation") || !report["validation"].is_object()) return "";
  const json& v = report["validation"];
  for (const char* key : {"data", "description"}) {
    if (v.contains(key) && v[key].is_string()) return v[key].get<std::string>();
  }
  return "";
}

// What "fit" and "validation" mean for each method (cli-and-reports.md).
const char* FitDefinition(const std::string& method) {
  if (method == "linear_kf") return "the paper's static linear balance model at the estimates";
  if (method == "output_error") {
    return "balance logs: the static load model; flight logs: predictions over consecutive "
           "windows, each from the fitted (held-out: re-estimated) state at its start";
  }
  return "predictions over consecutive windows, each from the smoothed EKF state at its start";
}

json MethodJson(const MethodRun& run) {
  json m = {{"method", run.method},
            {"status", run.status},
            {"logs", run.logs},
            {"validate", run.validate},
            {"wall_s", NumberJson(run.wall_s)}};
  if (!run.reason.empty()) m["reason"] = run.reason;
  if (!run.prior.empty()) m["prior"] = run.prior;
  if (run.status != "ran") return m;
  m["report"] = run.folder + "/report.json";
  m["fit"] = ChannelErrors(run.report.value("fit", json()));
  m["fit"]["overall_nrmse"] =
      NumberJson(JsonNumber(run.report.value("fit", json()), "overall_nrmse"));
  m["validation"] = ChannelErrors(run.report.value("validation", json()));
  m["validation"]["overall_nrmse"] =
      NumberJson(JsonNumber(run.report.value("validation", json()), "overall_nrmse"));
  m["validation_data"] = ValidationData(run.report);
  m["fit_definition"] = FitDefinition(run.method);
  return m;
}

}  // namespace

std::string EstimateText(const json& e) {
  const std::string kind = e.value("kind", "absent");
  const double value = JsonNumber(e, "value");
  if (kind == "estimated")
    return NumberText(value, "%.5g") + " ± " + NumberText(JsonNumber(e, "std"), "%.2g");
  if (kind == "not identifiable") return NumberText(value, "%.5g") + " (not identifiable)";
  if (kind == "config") return NumberText(value, "%.5g") + " (config)";
  if (kind == "held for the scale") return NumberText(value, "%.5g") + " (held for the scale)";
  if (kind == "over-parameterised") return "two values: Cz_alpha, Cz_beta rows";
  return "-";
}

namespace {

std::string Sigma(const json& object, const std::string& key) {
  const double z = JsonNumber(object, key);
  if (!std::isfinite(z)) return "-";
  const std::string text = NumberText(z, "%.2f");
  return std::fabs(z) > 3 ? "**" + text + "**" : text;
}

std::vector<std::string> Pairs() {
  std::vector<std::string> pairs;
  const std::vector<std::string>& m = CompareMethods();
  for (size_t i = 0; i < m.size(); ++i) {
    for (size_t j = i + 1; j < m.size(); ++j) pairs.push_back(m[i] + " vs " + m[j]);
  }
  return pairs;
}

const char* Color(const std::string& method) {
  if (method == "linear_kf") return "#1f77b4";
  if (method == "output_error") return "#d62728";
  return "#2ca02c";
}

}  // namespace

const std::vector<std::string>& CompareMethods() {
  static const std::vector<std::string> kMethods = {"linear_kf", "output_error", "ekf"};
  return kMethods;
}

json ComparisonJson(const std::vector<MethodRun>& runs, const json& truth) {
  json out;
  out["methods"] = json::array();
  for (const std::string& method : CompareMethods()) {
    if (const MethodRun* run = Find(runs, method)) out["methods"].push_back(MethodJson(*run));
  }
  const MethodRun* linear = Find(runs, "linear_kf");
  const bool linear_ran = linear != nullptr && linear->status == "ran";
  const MethodRun* oe = Find(runs, "output_error");
  out["reference"] = truth.is_object()                      ? "truth"
                     : oe != nullptr && oe->status == "ran" ? "output_error"
                                                            : "none";
  auto truth_of = [&](const std::string& name) { return JsonNumber(truth, name); };

  // The parameters some method estimated, model.md's first, then effects'.
  std::vector<std::string> names(std::begin(kModelUnknowns), std::end(kModelUnknowns));
  std::set<std::string> extra;
  for (const MethodRun& run : runs) {
    for (const auto& [name, p] : Parameters(run).items()) {
      if (name.find('.') != std::string::npos) extra.insert(name);
    }
  }
  names.insert(names.end(), extra.begin(), extra.end());
  json rows = json::array();
  for (const std::string& name : names) {
    json estimates = json::object();
    bool any_estimated = false;
    for (const std::string& method : CompareMethods()) {
      const MethodRun* run = Find(runs, method);
      if (run == nullptr || run->status != "ran") continue;
      json e = Entry(Parameters(*run).value(name, json()));
      if (method == "linear_kf" && name == "Cz") {
        e = {{"kind", "over-parameterised"}};
      }
      const std::string kind = e["kind"];
      any_estimated = any_estimated || kind == "estimated" || kind == "not identifiable";
      estimates[method] = e;
    }
    if (any_estimated) rows.push_back(Row(name, "", truth_of(name), estimates));
  }

  // The linear method's two coefficients where the nonlinear model has one Cz.
  if (linear_ran) {
    const json& lp = Parameters(*linear);
    const double Cz = truth_of("Cz");
    const json& cz = lp.value("Cz", json::object());
    rows.push_back(Row("Cz_alpha",
                       "linear_kf only: Cz_alpha = Cz alpha (paper eqs. 64, 69-70); the "
                       "nonlinear model has no such parameter",
                       Cz * truth_of("alpha"),
                       {{"linear_kf", Entry(lp.value("Cz_alpha", json()))}}));
    rows.push_back(Row("Cz_beta",
                       "linear_kf only: Cz_beta = Cz beta (paper eqs. 65, 69-70); collinear with "
                       "beta in Z_bar, separated only through L and M (model.md decision 6)",
                       Cz * truth_of("beta"), {{"linear_kf", Entry(lp.value("Cz_beta", json()))}}));
    for (const auto& [label, key] :
         {std::pair<const char*, const char*>{"Cz = Cz_alpha / alpha", "from_Cz_alpha"},
          std::pair<const char*, const char*>{"Cz = Cz_beta / beta", "from_Cz_beta"}}) {
      json estimates = {{"linear_kf", Entry(cz.value(key, json()))}};
      for (const std::string& method : {std::string("output_error"), std::string("ekf")}) {
        const MethodRun* run = Find(runs, method);
        if (run != nullptr && run->status == "ran") {
          estimates[method] = Entry(Parameters(*run).value("Cz", json()));
        }
      }
      rows.push_back(Row(label,
                         "the linear method's Cz one way, against the nonlinear methods' one Cz",
                         Cz, estimates));
    }
    out["over_parameterisation"] = {
        {"explanation",
         "linear_kf estimates Theta = (beta, Cz_alpha, Cz_beta, gamma1, gamma2) (paper eqs. "
         "69-70): Cz_alpha = Cz alpha and Cz_beta = Cz beta are two free coefficients where "
         "the nonlinear model (output_error, ekf) has one Cz. Each implies a Cz (Cz_alpha / "
         "alpha, Cz_beta / beta); nothing forces them to agree. Cz_beta is collinear with beta "
         "in Z_bar, and beta is fixed through L and M with d taken from the config (model.md "
         "decision 6): a wrong d biases beta in proportion and Cz_beta absorbs the difference "
         "in Z_bar."},
        {"Cz_from_Cz_alpha", cz.value("from_Cz_alpha", json())},
        {"Cz_from_Cz_beta", cz.value("from_Cz_beta", json())},
        {"difference_in_std", cz.value("difference_in_std", json())},
        {"disagree", cz.value("disagree", json())}};
  }
  out["parameters"] = rows;
  out["ratios"] = RatioRows(runs, truth);
  return out;
}

std::string ComparisonMarkdown(const json& c, const std::string& plot) {
  const std::vector<std::string>& methods = CompareMethods();
  const bool has_truth = c.value("reference", "") == "truth";
  std::ostringstream o;
  o << "# coaxid compare: linear_kf, output_error and ekf on the same logs\n\n";
  o << "## Methods\n\n| method | logs | held-out data | wall time [s] | status |\n"
       "|---|---|---|---|---|\n";
  for (const json& m : c["methods"]) {
    std::string logs;
    for (const json& l : m["logs"])
      logs += (logs.empty() ? "`" : ", `") + l.get<std::string>() + "`";
    const bool ran = m["status"] == "ran";
    o << "| " << m["method"].get<std::string>() << " | " << (logs.empty() ? "-" : logs) << " | "
      << (ran ? m.value("validation_data", "") : "-") << " | "
      << NumberText(JsonNumber(m, "wall_s"), "%.2f") << " | "
      << (ran ? "ran: `" + m.value("report", "") + "`"
              : m["status"].get<std::string>() + ": " + m.value("reason", ""))
      << " |\n";
  }

  o << "\n## Estimates (value ± std)\n\n| parameter |" << (has_truth ? " truth |" : "");
  for (const std::string& m : methods) o << " " << m << " |";
  o << "\n|---|" << (has_truth ? "---|" : "");
  for (size_t i = 0; i < methods.size(); ++i) o << "---|";
  o << "\n";
  for (const json& row : c["parameters"]) {
    o << "| " << row["name"].get<std::string>() << " |";
    if (has_truth) o << " " << NumberText(JsonNumber(row, "truth"), "%.5g") << " |";
    for (const std::string& m : methods) {
      o << " " << EstimateText(row["estimates"].value(m, json::object())) << " |";
    }
    o << "\n";
  }
  o << "\n\"config\": held at the config's value by that method; \"not identifiable\": "
       "the logs do not determine it (no std is made up). An estimate made with a parameter "
       "held inherits that parameter's error: linear_kf's beta scales with its d (model.md "
       "decision 6). \"held for the scale\": flight logs alone fix only ratios, so the method "
       "held d, and its moment parameters (gamma1, gamma2, Ixx, Iyy, Izz) scale with it "
       "(decision 8); compare them through the scale-free ratios below.\n";
  if (!c.value("ratios", json::array()).empty()) {
    o << "\n## Scale-free ratios (what flight logs determine; model.md decision 8)\n\n"
      << "| ratio |" << (has_truth ? " truth |" : "");
    for (const std::string& m : methods) o << " " << m << " |";
    for (const std::string& p : Pairs()) o << " " << p << " |";
    o << "\n|---|" << (has_truth ? "---|" : "");
    for (size_t i = 0; i < methods.size() + Pairs().size(); ++i) o << "---|";
    o << "\n";
    for (const json& row : c["ratios"]) {
      o << "| " << row["name"].get<std::string>() << " |";
      if (has_truth) o << " " << NumberText(JsonNumber(row, "truth"), "%.5g") << " |";
      for (const std::string& m : methods) {
        o << " " << EstimateText(row["estimates"].value(m, json::object())) << " |";
      }
      for (const std::string& p : Pairs()) o << " " << Sigma(row["agreement_sigma"], p) << " |";
      o << "\n";
    }
  }

  o << "\n## Agreement in sigma units, |a - b| / sqrt(s_a^2 + s_b^2)"
    << (has_truth ? ", and error against the truth, (estimate - truth) / s" : "") << "\n\n";
  o << "| parameter |";
  for (const std::string& p : Pairs()) o << " " << p << " |";
  if (has_truth) {
    for (const std::string& m : methods) o << " error " << m << " |";
  }
  o << "\n|---|";
  for (size_t i = 0; i < Pairs().size() + (has_truth ? methods.size() : 0); ++i) o << "---|";
  o << "\n";
  for (const json& row : c["parameters"]) {
    o << "| " << row["name"].get<std::string>() << " |";
    for (const std::string& p : Pairs()) o << " " << Sigma(row["agreement_sigma"], p) << " |";
    if (has_truth) {
      for (const std::string& m : methods) o << " " << Sigma(row["error_sigma"], m) << " |";
    }
    o << "\n";
  }
  o << "\nBold: beyond 3 sigma. Methods that share logs are not independent, so their "
       "agreement is a consistency check, not a test.\n";

  if (c.contains("over_parameterisation")) {
    const json& op = c["over_parameterisation"];
    o << "\n## The linear method's over-parameterisation\n\n"
      << op["explanation"].get<std::string>() << "\n\n";
    for (const json& row : c["parameters"]) {
      const std::string name = row["name"];
      if (!row.contains("description") || name.rfind("Cz", 0) != 0) continue;
      o << "- **" << name << "** = " << EstimateText(row["estimates"]["linear_kf"]);
      if (has_truth) o << " (truth " << NumberText(JsonNumber(row, "truth"), "%.5g") << ")";
      for (const auto& [pair, z] : row["agreement_sigma"].items()) {
        o << "; " << pair << ": " << NumberText(z.get<double>(), "%.2f") << " sigma";
      }
      o << ". " << row["description"].get<std::string>() << ".\n";
    }
    const double difference = JsonNumber(op, "difference_in_std");
    if (std::isfinite(difference)) {
      o << "\nThe two values of Cz differ by " << NumberText(difference, "%.2f")
        << " std of their difference" << (op.value("disagree", false) ? ": they DISAGREE." : ".")
        << "\n";
    }
  }

  o << "\n## Fit and validation errors per channel\n\n"
       "| method | channel | fit rms | fit nrmse | validation rms | validation nrmse |\n"
       "|---|---|---|---|---|---|\n";
  for (const json& m : c["methods"]) {
    if (m["status"] != "ran") continue;
    for (const auto& [channel, fit] : m["fit"].items()) {
      if (!fit.is_object()) continue;
      const json v = m["validation"].value(channel, json::object());
      o << "| " << m["method"].get<std::string>() << " | " << channel << " | "
        << NumberText(JsonNumber(fit, "rms"), "%.4g") << " | "
        << NumberText(JsonNumber(fit, "nrmse"), "%.4f") << " | "
        << NumberText(JsonNumber(v, "rms"), "%.4g") << " | "
        << NumberText(JsonNumber(v, "nrmse"), "%.4f") << " |\n";
    }
    o << "| " << m["method"].get<std::string>() << " | overall nrmse | | "
      << NumberText(JsonNumber(m["fit"], "overall_nrmse"), "%.4f") << " | | "
      << NumberText(JsonNumber(m["validation"], "overall_nrmse"), "%.4f") << " |\n";
  }
  o << "\nnrmse = rms(measured - model) / rms(measured - mean). The model each method is "
       "judged by:\n\n";
  for (const json& m : c["methods"]) {
    if (m["status"] == "ran") {
      o << "- " << m["method"].get<std::string>() << ": " << m.value("fit_definition", "") << "\n";
    }
  }
  if (!plot.empty()) {
    o << "\n## Estimates against the " << (has_truth ? "truth" : "output_error estimate")
      << "\n\n![estimates](" << plot << ")\n";
  }
  return o.str();
}

Figure EstimatesFigure(const json& c) {
  const std::vector<std::string>& methods = CompareMethods();
  const std::string reference = c.value("reference", "none");
  Figure f;
  f.columns = 4;
  f.title =
      "Estimates with +-1 std bars; x: 1 linear_kf (blue), 2 output_error (red), 3 ekf "
      "(green); open circle: not identifiable; dashed: " +
      (reference == "none" ? std::string("no reference") : reference);
  for (const json& row : c["parameters"]) {
    PlotPanel panel;
    panel.title = row["name"].get<std::string>();
    panel.key = "off";
    double lowest = HUGE_VAL, highest = -HUGE_VAL;
    auto extend = [&](double y) {
      lowest = std::min(lowest, y);
      highest = std::max(highest, y);
    };
    for (size_t i = 0; i < methods.size(); ++i) {
      const json e = row["estimates"].value(methods[i], json::object());
      const double value = JsonNumber(e, "value");
      const std::string kind = e.value("kind", "");
      if (!std::isfinite(value) || (kind != "estimated" && kind != "not identifiable")) continue;
      const double x = i + 1.0;
      const std::string color = std::string(" lc rgb '") + Color(methods[i]) + "'";
      if (kind == "estimated") {
        const double s = JsonNumber(e, "std");
        panel.series.push_back({"", {x, x}, {value - s, value + s}, "lines lw 2" + color});
        extend(value - s);
        extend(value + s);
      }
      panel.series.push_back(
          {methods[i],
           {x},
           {value},
           (kind == "estimated" ? "points pt 7 ps 1.2" : "points pt 6 ps 1.5") + color});
      extend(value);
    }
    if (panel.series.empty()) continue;
    double ref = JsonNumber(row, "truth");
    if (reference == "output_error") {
      const json e = row["estimates"].value("output_error", json::object());
      ref = e.value("kind", "") == "estimated" ? JsonNumber(e, "value") : kNaN;
    }
    if (std::isfinite(ref)) {
      panel.series.push_back({reference, {0.5, 3.5}, {ref, ref}, "lines dt 2 lc rgb 'black'"});
      extend(ref);
    }
    // Values of 1e-5 and such in units of their power of ten, so the tick
    // labels keep their digits; the range padded so nothing sits on the frame.
    const double magnitude = std::max(std::fabs(lowest), std::fabs(highest));
    const int exponent = magnitude > 0 ? static_cast<int>(std::floor(std::log10(magnitude))) : 0;
    const double unit = std::abs(exponent) >= 3 ? std::pow(10.0, exponent) : 1.0;
    if (unit != 1.0) panel.title += " [1e" + std::to_string(exponent) + "]";
    for (PlotSeries& series : panel.series) {
      for (double& y : series.y) y /= unit;
    }
    const double pad = 0.1 * std::max(highest - lowest, 1e-3 * magnitude) / unit;
    panel.y_min = lowest / unit - pad;
    panel.y_max = highest / unit + pad;
    f.panels.push_back(panel);
  }
  return f;
}

}  // namespace coaxid
