#include "experiments/reports/demo_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/report_values.h"
#include "experiments/reports/compare_table.h"

namespace coaxid {
namespace {

using json = nlohmann::json;

// A command's report as a section: its title dropped, every other heading
// one level deeper.
std::string AsSection(const std::string& markdown) {
  std::istringstream in(markdown);
  std::string out;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("# ", 0) == 0) continue;
    out += (line.rfind("#", 0) == 0 ? "#" : "") + line + "\n";
  }
  return out;
}

// The plots of a report ("outputs": {"plots": [...]}) whose file name holds
// one of the keys, in the keys' order, at most max; folder prefixes them.
std::vector<std::string> KeyPlots(const json& report, const std::string& folder,
                                  const std::vector<std::string>& keys, size_t max) {
  std::vector<std::string> out;
  if (!report.contains("outputs") || !report["outputs"].contains("plots")) return out;
  for (const std::string& key : keys) {
    for (const json& p : report["outputs"]["plots"]) {
      const std::string path = folder + "/" + p.get<std::string>();
      if (out.size() < max && p.get<std::string>().find(key) != std::string::npos &&
          std::find(out.begin(), out.end(), path) == out.end()) {
        out.push_back(path);
      }
    }
  }
  return out;
}

// Each plot as a figure captioned "what: file name".
void Images(std::ostringstream& o, const std::string& what, const std::vector<std::string>& plots) {
  for (const std::string& p : plots) {
    const std::string stem = p.substr(p.rfind('/') + 1, p.size() - p.rfind('/') - 5);
    o << "\n![" << what << ": " << stem << "](" << p << ")\n";
  }
}

const json* MethodOf(const json& comparison, const std::string& method) {
  for (const json& m : comparison["methods"]) {
    if (m["method"] == method) return &m;
  }
  return nullptr;
}

// One method's estimates against the truth, from the comparison's rows.
void EstimatesTable(std::ostringstream& o, const json& comparison, const std::string& method) {
  const bool truth = comparison.value("reference", "") == "truth";
  o << "\n| parameter | " << (truth ? "truth | " : "") << "estimate ± std |"
    << (truth ? " error [sigma] |" : "") << "\n|---|---|" << (truth ? "---|---|" : "") << "\n";
  for (const json& row : comparison["parameters"]) {
    if (!row["estimates"].contains(method)) continue;
    const json& e = row["estimates"][method];
    const std::string kind = e.value("kind", "");
    if (kind != "estimated" && kind != "not identifiable") continue;
    // The rows on the linear method's Cz split repeat the others' one Cz.
    if (method != "linear_kf" && row.contains("description")) continue;
    o << "| " << row["name"].get<std::string>() << " | ";
    if (truth) o << NumberText(JsonNumber(row, "truth"), "%.5g") << " | ";
    o << EstimateText(e) << " |";
    if (truth)
      o << " " << NumberText(JsonNumber(row.value("error_sigma", json()), method), "%+.2f") << " |";
    o << "\n";
  }
}

// The plausibility verdict of a report (core/plausibility.h), one paragraph.
void PlausibilityLine(std::ostringstream& o, const json& plausibility) {
  if (!plausibility.is_object()) return;
  o << "\nPlausibility: " << (plausibility.value("describes_vehicle", true) ? "" : "**")
    << plausibility.value("verdict", "") << (plausibility.value("describes_vehicle", true) ? "" : "**")
    << "\n";
}

void MethodSection(std::ostringstream& o, const DemoRecord& r, const std::string& method,
                   const std::string& heading, const std::string& what,
                   const std::vector<std::string>& plot_keys) {
  o << "\n## " << heading << "\n\n" << what << "\n";
  const json* m = MethodOf(r.comparison, method);
  if (m == nullptr || (*m)["status"] != "ran") {
    o << "\nNot run: " << (m == nullptr ? "not part of the comparison" : m->value("reason", ""))
      << "\n";
    return;
  }
  std::string logs;
  for (const json& l : (*m)["logs"])
    logs += (logs.empty() ? "`" : ", `") + l.get<std::string>() + "`";
  const std::string folder = r.compare_folder + "/" + method;
  o << "\nLogs: " << logs << ". Held out: " << m->value("validation_data", "-") << ". Wall time "
    << NumberText(JsonNumber(*m, "wall_s"), "%.2f") << " s. Full output: `" << folder
    << "/report.json`. Overall nrmse: fit "
    << NumberText(JsonNumber((*m)["fit"], "overall_nrmse"), "%.3f") << ", validation "
    << NumberText(JsonNumber((*m)["validation"], "overall_nrmse"), "%.3f") << ".\n";
  const auto report = r.reports.find(method);
  if (report != r.reports.end()) PlausibilityLine(o, report->second.value("plausibility", json()));
  EstimatesTable(o, r.comparison, method);
  if (report != r.reports.end()) Images(o, method, KeyPlots(report->second, folder, plot_keys, 3));
}

void DiscoverySection(std::ostringstream& o, const DemoDiscovery& d) {
  const json& j = d.discovery;
  o << "\n### " << d.title << "\n\nLogs: ";
  for (const std::string& l : d.logs) o << "`" << l << "` ";
  std::string added;
  for (const json& a : j["added"]) added += (added.empty() ? "" : ", ") + a.get<std::string>();
  o << "\n\nAdded: **" << (added.empty() ? "nothing" : added) << "**";
  const json added_parameters = j.value("added_parameters", json::object());
  for (const auto& [name, p] : added_parameters.items()) {
    o << "; " << name << " = " << NumberText(JsonNumber(p, "value"), "%.4g");
    if (p.contains("std") && p["std"].is_number())
      o << " ± " << NumberText(p["std"].get<double>(), "%.2g");
  }
  o << ". Full report: `" << d.folder << "/report.md`.\n";
  PlausibilityLine(o, j["final"].value("plausibility", json()));
  for (const json& u : j.value("unexplained", json::array())) {
    o << "\nStill unexplained: **" << u.value("channel", "") << "**: " << u.value("why", "")
      << "\n";
  }
  const json& before = j["baseline"];
  const json& after = j["final"];
  const bool validation = before["validation"].size() > 1;
  o << "\n| channel | rms before | rms after | nrmse before | nrmse after |"
    << (validation ? " held-out nrmse before | held-out nrmse after |" : "")
    << "\n|---|---|---|---|---|" << (validation ? "---|---|" : "") << "\n";
  for (const auto& [channel, b] : before["fit"].items()) {
    if (!b.is_object()) continue;
    const json a = after["fit"].value(channel, json::object());
    o << "| " << channel << " | " << NumberText(JsonNumber(b, "rms")) << " | "
      << NumberText(JsonNumber(a, "rms")) << " | " << NumberText(JsonNumber(b, "nrmse"), "%.3f")
      << " | " << NumberText(JsonNumber(a, "nrmse"), "%.3f") << " |";
    if (validation) {
      o << " "
        << NumberText(JsonNumber(before["validation"].value(channel, json()), "nrmse"), "%.3f")
        << " | "
        << NumberText(JsonNumber(after["validation"].value(channel, json()), "nrmse"), "%.3f")
        << " |";
    }
    o << "\n";
  }
  Images(o, "discover", KeyPlots(j, d.folder, {"fit_1", "residual_autocorrelation"}, 2));
}

}  // namespace

std::string DemoReportMarkdown(const DemoRecord& r) {
  std::ostringstream o;
  o << "# coaxid demo: identifying a coaxial MAV from its logs, end to end\n\n"
    << "Vehicle: `" << r.config
    << "` (the reference GLMAV of model.md; the simulated truth is off-nominal: a real vehicle "
       "differs from its config). The steps: simulate the shipped scenarios and check they "
       "reproduce the shipped logs; identify the model three ways (the paper's linear Kalman "
       "baseline, nonlinear output error, the EKF) and compare them; then let `discover` find "
       "what a declared model lacks, on a simulated log and on measured test-stand data.\n\n"
    << "| step | wall time [s] |\n|---|---|\n";
  for (const auto& [step, seconds] : r.step_seconds) {
    o << "| " << step << " | " << NumberText(seconds, "%.1f") << " |\n";
  }
  o << "| total | " << NumberText(r.total_s, "%.1f") << " |\n";

  o << "\n## 1. Simulation: the shipped logs from their seeds\n\n"
    << "| scenario | seed | rows | simulated [s] | log | truth | against the shipped log |\n"
       "|---|---|---|---|---|---|---|\n";
  for (const DemoSimulatedLog& s : r.simulated) {
    o << "| " << s.scenario << " | " << s.seed << " | " << s.rows << " | "
      << NumberText(s.duration_s, "%.1f") << " | `" << s.log << "` | `" << s.truth << "` | "
      << s.reproduced << " |\n";
  }

  MethodSection(o, r, "linear_kf", "2. The paper's linear Kalman baseline (linear_kf)",
                "The balance experiment of sects. 3-5: thrust map and alpha from single-rotor "
                "holds (Fig. 8), the sigma map (Fig. 9), the Kalman filter on (beta, Cz_alpha, "
                "Cz_beta, gamma1, gamma2) with d taken from the config (model.md decision 6), "
                "reconstruction and validation (Figs. 10-13).",
                {"fig08", "fig11", "fig12", "fig10"});
  MethodSection(o, r, "output_error", "3. Nonlinear output error (output_error)",
                "Every free parameter of the nonlinear model fitted jointly to the flight and "
                "balance logs (multiple shooting over CVODES simulations, Cramér-Rao stds, "
                "identifiability verdict).",
                {"fit_flight", "validation_flight", "fit_"});
  MethodSection(o, r, "ekf", "4. Extended Kalman filter (ekf)",
                "States and parameters together from the flight log (continuous-discrete EKF, "
                "RTS smoother, a covariance pass at the estimates). Flight logs alone fix only "
                "ratios (model.md decision 8), so ekf starts d from output_error's estimate "
                "and std (fixed by the balance log) as a prior.",
                {"parameters", "fit", "innovations"});

  o << "\n## 5. The three compared (`coaxid compare`)\n\nReport paths in this section's tables are "
       "relative to `"
    << r.compare_folder << "/`.\n\n"
    << AsSection(ComparisonMarkdown(r.comparison, r.compare_folder + "/plots/estimates.png"));

  o << "\n## 6. The closing loop: what the declared model lacks (`coaxid discover`)\n";
  for (const DemoDiscovery& d : r.discoveries) DiscoverySection(o, d);
  return o.str();
}

}  // namespace coaxid
