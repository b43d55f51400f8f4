#include "experiments/design/design_report.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/report_values.h"
#include "core/log.h"
#include "core/plot.h"
#include "core/report.h"
#include "core/yaml_util.h"
#include "dynamics/state.h"

namespace coaxid {
namespace {

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; }

// The predicted std of a parameter, NaN where not free or not identifiable.
double StdOf(const PredictedPrecision& p, const std::string& name) {
  const auto& id = p.identifiability;
  for (size_t k = 0; k < id.names.size(); ++k) {
    if (id.names[k] == name) return id.identifiable[k] ? id.std[k] : NAN;
  }
  return NAN;
}

std::string Sci(double v) {
  if (!std::isfinite(v)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

std::string Percent(double relative) {
  if (!std::isfinite(relative)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, "%.3g %%", 100 * relative);
  return text;
}

// Every parameter free in any of the predictions, in the first's order.
std::vector<std::string> ParameterNames(const std::vector<const PredictedPrecision*>& ps) {
  std::vector<std::string> names;
  for (const PredictedPrecision* p : ps) {
    for (const std::string& n : p->names) {
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
    }
  }
  return names;
}

// A number as the shortest text that reads back as the same double.
YAML::Node ShortestNumber(double v) {
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof text, v);
  return YAML::Node(std::string(text, end));
}

YAML::Node ExcitationNode(const Excitation& e) {
  YAML::Node node;
  const bool pulses = e.type == Excitation::Type::k3211;
  node["type"] = pulses ? "3211" : "multisine";
  node["start_s"] = ShortestNumber(e.start_s);
  if (pulses) {
    node["pulse_s"] = ShortestNumber(e.pulse_s);
    YAML::Node amplitude(YAML::NodeType::Map);
    for (const char* input : {"omega1", "omega2", "delta_cx", "delta_cy"}) {
      amplitude[input] = ShortestNumber(e.amplitude.at(input));
    }
    amplitude.SetStyle(YAML::EmitterStyle::Flow);
    node["amplitude"] = amplitude;
  } else {
    node["period_s"] = ShortestNumber(e.period_s);
  }
  YAML::Node bands(YAML::NodeType::Sequence);
  for (const Excitation::Band& band : e.bands) {
    YAML::Node b;
    b["min_hz"] = ShortestNumber(band.min_hz);
    b["max_hz"] = ShortestNumber(band.max_hz);
    YAML::Node rms(YAML::NodeType::Map);
    for (const char* input : {"omega1", "omega2", "delta_cx", "delta_cy"}) {
      auto it = band.rms.find(input);
      if (it != band.rms.end()) rms[input] = ShortestNumber(it->second);
    }
    b["rms"] = rms;
    b.SetStyle(YAML::EmitterStyle::Flow);
    bands.push_back(b);
  }
  if (!pulses) node["bands"] = bands;
  if (!e.quiet.empty()) {
    YAML::Node quiet(YAML::NodeType::Sequence);
    for (const auto& window : e.quiet) {
      YAML::Node w(YAML::NodeType::Sequence);
      w.push_back(ShortestNumber(window[0]));
      w.push_back(ShortestNumber(window[1]));
      w.SetStyle(YAML::EmitterStyle::Flow);
      quiet.push_back(w);
    }
    node["quiet"] = quiet;
  }
  return node;
}

std::string Yaml(const YAML::Node& root, const std::string& header) {
  YAML::Emitter emitter;
  emitter << root;
  return header + emitter.c_str() + "\n";
}

// The predictions to show side by side: as planned, then after each design.
void PlanColumns(const DesignRun& run, std::vector<const PredictedPrecision*>* columns,
                 std::vector<std::string>* titles) {
  *columns = {&run.planned};
  *titles = {"as planned"};
  if (run.excitation) {
    columns->push_back(&run.excitation->after);
    titles->push_back("designed excitation");
  }
  if (run.balance) {
    columns->push_back(&run.balance->after);
    titles->push_back(run.excitation ? "excitation + holds" : "with the added holds");
  }
}

std::vector<std::string> MarkdownPlanTable(const DesignRun& run) {
  std::vector<const PredictedPrecision*> columns;
  std::vector<std::string> titles;
  PlanColumns(run, &columns, &titles);
  std::vector<std::string> lines;
  std::string header = "| parameter | value |", rule = "|---|---|";
  for (const std::string& t : titles) {
    header += " std, " + t + " |";
    rule += "---|";
  }
  header += " before / after |";
  rule += "---|";
  lines.push_back(header);
  lines.push_back(rule);
  const std::vector<std::string> targets =
      run.criterion.parameters.empty() ? run.planned.names : run.criterion.parameters;
  for (const std::string& name : ParameterNames(columns)) {
    const double value = run.planned.parameters.Value(name);
    const bool target = std::find(targets.begin(), targets.end(), name) != targets.end();
    std::string row = "| " + (target ? "**" + name + "**" : name) + " | " + Sci(value) + " |";
    for (const PredictedPrecision* p : columns) {
      const double s = StdOf(*p, name);
      row += " " + Sci(s) + " (" + Percent(s / std::fabs(value)) + ") |";
    }
    const double ratio = StdOf(run.planned, name) / StdOf(*columns.back(), name);
    char text[32];
    std::snprintf(text, sizeof text, "%.2fx", ratio);
    row += " " + (std::isfinite(ratio) ? std::string(text) : std::string("-")) + " |";
    lines.push_back(row);
  }
  return lines;
}

std::vector<NamedFigure> Figures(const DesignRun& run) {
  std::vector<NamedFigure> figures;
  {
    std::vector<const PredictedPrecision*> columns;
    std::vector<std::string> titles;
    PlanColumns(run, &columns, &titles);
    PlotPanel panel;
    panel.title = "predicted relative std (spread of output-error estimates over noise seeds)";
    panel.y_label = "std / |value|";
    panel.log_y = true;
    panel.x_categories = ParameterNames(columns);
    const char* styles[] = {"points pt 7 ps 1.2", "points pt 5 ps 1.2", "points pt 9 ps 1.4"};
    for (size_t c = 0; c < columns.size(); ++c) {
      PlotSeries s;
      s.title = titles[c];
      s.style = styles[c % 3];
      for (size_t i = 0; i < panel.x_categories.size(); ++i) {
        const std::string& name = panel.x_categories[i];
        s.x.push_back(static_cast<double>(i));
        s.y.push_back(StdOf(*columns[c], name) / std::fabs(run.planned.parameters.Value(name)));
      }
      panel.series.push_back(s);
    }
    figures.push_back({"std_before_after.png", Figure{"experiment design: predicted precision", {panel}}});
  }
  if (!run.excitation) return figures;
  const ExcitationDesign& d = *run.excitation;
  const int fi = d.flight_index;
  {
    const Log before = ExcitationTimeSeries(d.reference[fi].flight);
    const Log after = ExcitationTimeSeries(d.designed[fi].flight);
    Figure figure{"excitation added to the controller's outputs (first 20 s of excitation)", {}};
    figure.columns = 2;
    const char* units[] = {"rad/s", "rad/s", "rad", "rad"};
    const double t_end = d.designed[fi].flight.excitation.start_s + 20.0;
    for (int c = 0; c < 4; ++c) {
      PlotPanel panel;
      panel.title = before.columns[1 + c];
      panel.x_label = "t [s]";
      panel.y_label = units[c];
      for (const auto& [log, title, style] :
           {std::tuple{&before, "as planned", "lines lw 1 dt 2"},
            std::tuple{&after, "designed", "lines lw 1.5"}}) {
        PlotSeries s;
        s.title = title;
        s.style = style;
        for (int k = 0; k < log->NumRows(); ++k) {
          if (log->values[0][k] > t_end) break;
          s.x.push_back(log->values[0][k]);
          s.y.push_back(log->values[1 + c][k]);
        }
        panel.series.push_back(s);
      }
      figure.panels.push_back(panel);
    }
    figures.push_back({"designed_inputs.png", figure});
  }
  {
    Figure figure{"predicted attitude envelope of the closed-loop flight (true attitude)", {}};
    figure.columns = 2;
    const double limit = d.limits.max_attitude_rad;
    for (const auto& [run_ptr, title] :
         {std::pair{&d.reference_run, "as planned"}, std::pair{&d.designed_run, "designed"}}) {
      PlotPanel panel;
      panel.title = title;
      panel.x_label = "t [s]";
      panel.y_label = "rad";
      const std::vector<Eigen::VectorXd>& states = run_ptr->true_states[fi];
      const std::vector<double>& t = run_ptr->raw[fi].Column("t");
      PlotSeries phi{"phi", {}, {}, "lines lw 1"}, theta{"theta", {}, {}, "lines lw 1"};
      for (size_t k = 0; k < states.size(); ++k) {
        phi.x.push_back(t[k]);
        phi.y.push_back(states[k][kPhi]);
        theta.x.push_back(t[k]);
        theta.y.push_back(states[k][kTheta]);
      }
      PlotSeries up{"attitude limit", {t.front(), t.back()}, {limit, limit}, "lines lw 1 dt 3 lc rgb 'red'"};
      PlotSeries down{"", {t.front(), t.back()}, {-limit, -limit}, "lines lw 1 dt 3 lc rgb 'red'"};
      panel.series = {phi, theta, up, down};
      panel.y_min = -1.2 * limit;
      panel.y_max = 1.2 * limit;
      figure.panels.push_back(panel);
    }
    figures.push_back({"attitude_envelope.png", figure});
  }
  return figures;
}

// How a design was made, for the scenario files' first line.
std::string How(const DesignRun& run) {
  std::string how = run.criterion.Name() + "-optimal for ";
  const std::vector<std::string>& names =
      run.criterion.parameters.empty() ? run.planned.names : run.criterion.parameters;
  for (size_t i = 0; i < names.size(); ++i) how += (i ? "," : "") + names[i];
  return how + " at the " + run.design_at + "'s values";
}

std::string CsvNumber(double v) { return Significant(v, 10); }

}  // namespace

nlohmann::json PredictionJson(const PredictedPrecision& p) {
  nlohmann::json parameters = nlohmann::json::object();
  for (size_t k = 0; k < p.names.size(); ++k) {
    const double value = p.parameters.Value(p.names[k]);
    const double s = StdOf(p, p.names[k]);
    nlohmann::json e = {{"value", value}, {"std", Number(s)},
                        {"relative_std", Number(s / std::fabs(value))},
                        {"fit_reports_std", Number(p.bound_std[k])}};
    if (!std::isfinite(s)) e["identifiable"] = false;
    parameters[p.names[k]] = e;
  }
  if (!p.gauge.held.empty()) parameters[p.gauge.held] = {{"value", p.parameters.Value(p.gauge.held)}};
  MarkHeldForTheScale(p.gauge, &parameters);
  nlohmann::json out = {{"std", "the predicted spread of output-error estimates over noise "
                               "seeds, M^-1 D M^-1; fit_reports_std: the Cramér-Rao bound M^-1 "
                               "a fit of such logs reports (its continuity residuals counted as "
                               "measurements: larger)"},
                        {"parameters", parameters},
                        {"identifiability", p.identifiability.ToJson()},
                        {"scale", p.gauge.ToJson()}};
  if (!p.ratios.empty()) out["ratios"] = RatiosJson(p.ratios);
  return out;
}

nlohmann::json DesignJson(const DesignRun& run) {
  nlohmann::json out;
  out["command"] = "design";
  out["config"] = run.config_path;
  out["scenarios"] = run.scenario_paths;
  out["design_at"] = run.design_at;
  out["vehicle"] = run.design_at == "truth"
                       ? "the scenarios' truth values (--design_at=truth)"
                       : "the config's parameter values (a design is made for the vehicle as it "
                         "is known; the scenarios' truth sections are not used)";
  out["method"] = "Cramér-Rao bound of output_error: Fisher information of the multiple-shooting "
                  "problem along the simulated closed-loop flight, noise std from the scenarios' "
                  "sensor models";
  out["criterion"] = {{"kind", run.criterion.Name()},
                      {"parameters", run.criterion.parameters.empty() ? run.planned.names
                                                                      : run.criterion.parameters},
                      {"on", "relative std (std / |value|)"},
                      {"planned", run.criterion_planned}};
  out["predicted"] = PredictionJson(run.planned);
  if (run.excitation) {
    const ExcitationDesign& d = *run.excitation;
    nlohmann::json components = nlohmann::json::array();
    const bool pulses = d.type == Excitation::Type::k3211;
    for (const auto& c : d.components) {
      if (pulses) {
        components.push_back({{"channel", c.channel},
                              {"pulse_s", d.pulse_s},
                              {"planned_level", c.planned_level},
                              {"designed_level", c.designed_level}});
      } else {
        components.push_back({{"channel", c.channel},
                              {"min_hz", c.band.min_hz},
                              {"max_hz", c.band.max_hz},
                              {"planned_rms", c.planned_rms},
                              {"designed_rms", c.designed_rms}});
      }
    }
    nlohmann::json rounds = nlohmann::json::array();
    for (const auto& r : d.rounds) {
      rounds.push_back({{"predicted_criterion", r.predicted_criterion},
                        {"flown_criterion", Number(r.flown_criterion)},
                        {"envelope", r.envelope.ToJson()},
                        {"within_limits", r.within_limits}});
    }
    nlohmann::json ratio = nlohmann::json::object();
    for (const std::string& name : d.after.names) {
      ratio[name] = Number(StdOf(d.before, name) / StdOf(d.after, name));
    }
    const int fi = d.flight_index;
    out["excitation"] = {{"flight", d.reference[fi].name},
                         {"duration_s", d.designed[fi].flight.duration_s},
                         {"limits", d.limits.ToJson()},
                         {"envelope_planned", d.reference_run.envelopes[fi].ToJson()},
                         {"envelope_designed", d.designed_run.envelopes[fi].ToJson()},
                         {"components", components},
                         {"rounds", rounds},
                         {"criterion_planned", d.criterion_before},
                         {"criterion_designed", d.criterion_after},
                         {"std_planned_over_designed", ratio},
                         {"predicted", PredictionJson(d.after)},
                         {"seconds", d.seconds},
                         {"scenario_file", "designed_" + d.reference[fi].name + ".yaml"},
                         {"time_series", "designed_excitation.csv"}};
  }
  if (run.balance) {
    const BalanceDesign& b = *run.balance;
    nlohmann::json holds = nlohmann::json::array();
    for (const InputVector& h : b.added) holds.push_back({h[0], h[1], h[2], h[3]});
    nlohmann::json lemma = {{"after", {{"exciting", b.lemma_after.Exciting()},
                                       {"message", b.lemma_after.message}}}};
    if (b.has_lemma_before) {
      lemma["before"] = {{"exciting", b.lemma_before.Exciting()},
                         {"message", b.lemma_before.message}};
    }
    out["balance"] = {{"campaign", b.designed[b.balance_index].name},
                      {"new_campaign", b.new_campaign},
                      {"added_holds", holds},
                      {"hold_columns", {"omega1", "omega2", "delta_cx", "delta_cy"}},
                      {"candidates", b.candidates},
                      {"criterion_path", b.criterion_path},
                      {"criterion_before", b.criterion_before},
                      {"criterion_after", b.criterion_after},
                      {"lemma1", lemma},
                      {"predicted", PredictionJson(b.after)},
                      {"scenario_file", "designed_" + b.designed[b.balance_index].name + ".yaml"}};
  }
  out["final"] = PredictionJson(run.final_precision);
  out["seconds"] = run.seconds;
  return out;
}

std::string DesignMarkdown(const DesignRun& run, const std::vector<std::string>& plots,
                           const std::string& plot_note) {
  std::string md = "# Experiment design\n\n";
  md += "Config `" + run.config_path + "`; planned: ";
  for (size_t i = 0; i < run.scenario_paths.size(); ++i) {
    md += (i ? ", `" : "`") + run.scenario_paths[i] + "`";
  }
  md += ".\n\nPredicted std are the Cramér-Rao bounds an output-error fit of the planned logs "
        "would report (segments, noise and scale as `identify --method=output_error` has them), "
        "at the " + std::string(run.design_at == "truth" ? "scenarios' truth" : "config's") +
        " parameter values. Criterion: " + run.criterion.Name() +
        "-optimal on the relative std of ";
  const std::vector<std::string> targets =
      run.criterion.parameters.empty() ? run.planned.names : run.criterion.parameters;
  for (size_t i = 0; i < targets.size(); ++i) md += (i ? ", " : "") + targets[i];
  md += " (in bold below).\n\n";
  if (!run.planned.gauge.held.empty()) {
    md += "No balance log fixes the scale: " + run.planned.gauge.held +
          " is held and flight logs fix only ratios (model.md decision 8); their predicted std "
          "are in design.json `predicted.ratios`.\n\n";
  }
  md += "## Predicted std\n\n";
  for (const std::string& line : MarkdownPlanTable(run)) md += line + "\n";
  if (run.excitation) {
    const ExcitationDesign& d = *run.excitation;
    const int fi = d.flight_index;
    const FlightEnvelope& a = d.reference_run.envelopes[fi];
    const FlightEnvelope& b = d.designed_run.envelopes[fi];
    char text[1024];
    md += "\n## Designed excitation (`designed_" + d.reference[fi].name + ".yaml`)\n\n";
    std::snprintf(text, sizeof text,
                  "Flight `%s`, %g s, criterion %.4g as planned, %.4g designed (%zu closed-loop "
                  "rounds, %.0f s).\n\n"
                  "| peak | limit | as planned | designed |\n|---|---|---|---|\n"
                  "| attitude [rad] | %.3g | %.3g | %.3g |\n"
                  "| rotor-speed deviation [rad/s] | %.3g | %.3g | %.3g |\n"
                  "| swashplate angle [rad] | %.3g | %.3g | %.3g |\n"
                  "| height off the waypoints [m] | %.3g | %.3g | %.3g |\n\n",
                  d.reference[fi].name.c_str(), d.designed[fi].flight.duration_s,
                  d.criterion_before, d.criterion_after, d.rounds.size(), d.seconds,
                  d.limits.max_attitude_rad, a.max_attitude_rad, b.max_attitude_rad,
                  d.limits.max_rotor_speed_deviation_rad_s, a.max_rotor_speed_deviation_rad_s,
                  b.max_rotor_speed_deviation_rad_s, d.limits.max_swashplate_rad,
                  a.max_swashplate_rad, b.max_swashplate_rad, d.limits.max_height_deviation_m,
                  a.max_height_deviation_m, b.max_height_deviation_m);
    md += text;
    if (d.type == Excitation::Type::k3211) {
      std::snprintf(text, sizeof text,
                    "A 3211 pulse train, unit pulse %.3g s (inputs take turns, 10 units each).\n\n",
                    d.pulse_s);
      md += text;
      md += "| input | planned level | designed level |\n|---|---|---|\n";
      for (const auto& c : d.components) {
        std::snprintf(text, sizeof text, "| %s | %.3g | %.3g |\n", c.channel.c_str(),
                      c.planned_level, c.designed_level);
        md += text;
      }
    } else {
      md += "| input | band [Hz] | designed rms |\n|---|---|---|\n";
      for (const auto& c : d.components) {
        std::snprintf(text, sizeof text, "| %s | %g-%g | %.3g |\n", c.channel.c_str(),
                      c.band.min_hz, c.band.max_hz, c.designed_rms);
        md += text;
      }
    }
    md += "\nThe excitation as a time series to add to the controller's outputs: "
          "`designed_excitation.csv` (t, omega1, omega2 [rad/s], delta_cx, delta_cy [rad]).\n";
    if (d.criterion_after >= d.criterion_before) {
      md += "\n**The designed excitation does not improve on the plan** within these limits: "
            "keep the planned one.\n";
    }
  }
  if (run.balance) {
    const BalanceDesign& b = *run.balance;
    md += "\n## Balance holds to add (`designed_" + b.designed[b.balance_index].name + ".yaml`)\n\n";
    md += "| # | omega1 [rad/s] | omega2 [rad/s] | delta_cx [rad] | delta_cy [rad] | criterion |\n"
          "|---|---|---|---|---|---|\n";
    for (size_t i = 0; i < b.added.size(); ++i) {
      char text[256];
      std::snprintf(text, sizeof text, "| %zu | %.4g | %.4g | %.4g | %.4g | %.4g |\n", i + 1,
                    b.added[i][0], b.added[i][1], b.added[i][2], b.added[i][3],
                    b.criterion_path[i]);
      md += text;
    }
    md += "\nThe paper's excitation check (Lemma 1 and the swashplate condition: can the linear "
          "method separate beta from Cz_beta?): ";
    if (b.has_lemma_before) {
      md += std::string("as planned ") + (b.lemma_before.Exciting() ? "passes" : "fails") + ", ";
    }
    md += std::string("with the added holds ") + (b.lemma_after.Exciting() ? "passes" : "fails") +
          ".\n\n> " + b.lemma_after.message + "\n";
  }
  if (!plots.empty()) {
    md += "\n## Plots\n\n";
    for (const std::string& p : plots) md += "![" + p + "](plots/" + p + ")\n\n";
  }
  if (!plot_note.empty()) md += "\nPlots skipped: " + plot_note + "\n";
  return md;
}

std::string DesignedScenarioYaml(const std::string& original, const Scenario& designed,
                                 const std::string& how) {
  YAML::Node root;
  const bool file = original != "balance" && original != "flight" && !original.empty();
  if (file) {
    root = ParseYaml(ReadFile(original), original);
  } else {
    root["scenario"] = designed.kind == Scenario::Kind::kFlight ? "flight" : "balance";
    root["seed"] = designed.seed;
  }
  if (designed.kind == Scenario::Kind::kFlight) {
    root["flight"]["excitation"] = ExcitationNode(designed.flight.excitation);
  } else {
    if (!file) {
      root["balance"]["omega1"] = YAML::Node(YAML::NodeType::Sequence);
      root["balance"]["omega2"] = YAML::Node(YAML::NodeType::Sequence);
    }
    YAML::Node holds(YAML::NodeType::Sequence);
    for (const auto& h : designed.balance.holds) {
      YAML::Node hold(YAML::NodeType::Sequence);
      for (double v : h) hold.push_back(ShortestNumber(v));
      hold.SetStyle(YAML::EmitterStyle::Flow);
      holds.push_back(hold);
    }
    root["balance"]["holds"] = holds;
  }
  const std::string header =
      "# Designed by `coaxid design` from " + (file ? original : "the built-in '" + original + "'") +
      (designed.kind == Scenario::Kind::kFlight ? ": the excitation is the design's"
                                                : ": the holds are the plan's and the design's") +
      (how.empty() ? std::string() : " (" + how + ")") + ".\n";
  return Yaml(root, header);
}

void WriteDesign(const DesignRun& run, const std::string& out) {
  // Everything is made in memory first; then written file by file, each atomically.
  std::vector<std::pair<std::string, std::string>> files;
  if (run.excitation) {
    const ExcitationDesign& d = *run.excitation;
    const int fi = d.flight_index;
    files.emplace_back("designed_" + d.reference[fi].name + ".yaml",
                       DesignedScenarioYaml(run.scenario_paths[fi], d.designed[fi], How(run)));
    const Log series = ExcitationTimeSeries(d.designed[fi].flight);
    std::string csv = "t,omega1,omega2,delta_cx,delta_cy\n";
    for (int k = 0; k < series.NumRows(); ++k) {
      for (int c = 0; c < 5; ++c) csv += (c ? "," : "") + CsvNumber(series.values[c][k]);
      csv += "\n";
    }
    files.emplace_back("designed_excitation.csv", csv);
  }
  if (run.balance) {
    const BalanceDesign& b = *run.balance;
    const std::string original =
        b.new_campaign ? std::string() : run.scenario_paths[b.balance_index];
    files.emplace_back("designed_" + b.designed[b.balance_index].name + ".yaml",
                       DesignedScenarioYaml(original.empty() ? "balance" : original,
                                            b.designed[b.balance_index], How(run)));
  }
  MakeOutputFolder(out);
  MakeOutputFolder(out + "/plots");
  std::string plot_error;
  std::vector<std::string> plots;
  if (GnuplotAvailable()) {
    plots = RenderFigures(Figures(run), out + "/plots", &plot_error);
  } else {
    plot_error = "gnuplot is not installed";
  }
  for (const auto& [name, text] : files) WriteFileAtomically(out + "/" + name, text);
  WriteJson(out + "/design.json", DesignJson(run));
  WriteFileAtomically(out + "/report.md", DesignMarkdown(run, plots, plot_error));
}

}  // namespace coaxid
