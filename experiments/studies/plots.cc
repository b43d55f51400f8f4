#include "experiments/studies/plots.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "experiments/studies/summary.h"

namespace coaxid {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// Where a sweep point goes on the x axis: its value, or its number (1, 2, ...)
// for excitation types and plain Monte Carlo.
double PointX(const nlohmann::json& point) {
  return point["value"].is_number() ? point["value"].get<double>()
                                    : point["point"].get<int>() + 1.0;
}

std::string SweepAxis(const StudySpec& spec) {
  if (spec.sweep.setting != SweepSetting::kExcitationType) {
    return SweepSettingName(spec.sweep.setting) +
           (spec.sweep.parameter.empty() ? std::string() : " (" + spec.sweep.parameter + ")");
  }
  std::string axis = "excitation type (";
  for (int p = 0; p < spec.sweep.NumPoints(); ++p) {
    axis += (p ? ", " : "") + std::to_string(p + 1) + " " + spec.sweep.Label(p);
  }
  return axis + ")";
}

// Vertical bars [y - e, y + e] at x, as one line series with NaN gaps.
void AddBar(PlotSeries* bars, double x, double y, double e) {
  bars->x.insert(bars->x.end(), {x, x, kNan});
  bars->y.insert(bars->y.end(), {y - e, y + e, kNan});
}

// Parameters with statistics, in first-seen order over points and methods.
std::vector<std::string> ParameterNames(const nlohmann::json& summary) {
  std::vector<std::string> names;
  std::set<std::string> seen;
  for (const auto& point : summary["points"]) {
    for (const auto& [method, m] : point["methods"].items()) {
      for (const auto& [name, p] : m["parameters"].items()) {
        if (seen.insert(name).second) names.push_back(name);
      }
    }
  }
  return names;
}

const char* const kMethodColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};

Figure Estimates(const StudySpec& spec, const nlohmann::json& summary,
                 const std::vector<nlohmann::json>& records) {
  const bool per_run = spec.sweep.setting == SweepSetting::kNone;
  const std::vector<std::string> names = ParameterNames(summary);
  Figure f;
  f.title = per_run ? "Estimate / truth, every run (+- its reported std)"
                    : "Estimate / truth, mean +- spread over the seeds per point";
  f.columns = 3;
  const int methods = static_cast<int>(spec.methods.size());
  for (const std::string& name : names) {
    PlotPanel panel;
    panel.title = name;
    panel.x_label = per_run ? "seed index" : SweepAxis(spec);
    panel.y_label = "estimate / truth";
    PlotSeries truth{"truth", {}, {}, "lines lc rgb 'black' dt 2"};
    for (int k = 0; k < methods; ++k) {
      const std::string method = StudyMethodName(spec.methods[k]);
      const std::string colour = std::string("lc rgb '") + kMethodColours[k % 4] + "'";
      PlotSeries mean{method, {}, {}, "points pt 7 ps 0.6 " + colour};
      PlotSeries bars{"", {}, {}, "lines " + colour};
      // Side by side: each method offset by a fraction of the spacing.
      const double offset = 0.15 * (k - 0.5 * (methods - 1));
      if (per_run) {
        for (const nlohmann::json& r : records) {
          if (!r["methods"].contains(method)) continue;
          const nlohmann::json& m = r["methods"][method];
          if (!m["ok"].get<bool>() || !m["parameters"].contains(name)) continue;
          const nlohmann::json& p = m["parameters"][name];
          if (!p["estimate"].is_number()) continue;
          if (!p["truth"].is_number() || p["truth"].get<double>() == 0) continue;
          const double t = p["truth"].get<double>();
          const double x = r["seed_index"].get<int>() + offset;
          mean.x.push_back(x);
          mean.y.push_back(p["estimate"].get<double>() / t);
          if (p["std"].is_number()) {
            AddBar(&bars, x, mean.y.back(), p["std"].get<double>() / std::fabs(t));
          }
          if (k == 0) {
            truth.x.push_back(r["seed_index"].get<int>());
            truth.y.push_back(1.0);
          }
        }
      } else {
        const double spacing =
            spec.sweep.NumPoints() > 1
                ? std::fabs(PointX(summary["points"][1]) - PointX(summary["points"][0]))
                : 1.0;
        for (const auto& point : summary["points"]) {
          const nlohmann::json& m = point["methods"][method];
          if (!m["parameters"].contains(name)) continue;
          const nlohmann::json& p = m["parameters"][name];
          const double t = p["truth"].get<double>();
          if (!p["mean"].is_number() || t == 0) continue;
          const double x = PointX(point) + offset * spacing;
          mean.x.push_back(x);
          mean.y.push_back(p["mean"].get<double>() / t);
          if (p["spread"].is_number()) {
            AddBar(&bars, x, mean.y.back(), p["spread"].get<double>() / std::fabs(t));
          }
          truth.x.push_back(PointX(point));
          truth.y.push_back(1.0);
        }
      }
      if (!mean.x.empty()) {
        panel.series.push_back(mean);
        if (!bars.x.empty()) panel.series.push_back(bars);
      }
    }
    if (!truth.x.empty()) panel.series.insert(panel.series.begin(), truth);
    f.panels.push_back(panel);
  }
  return f;
}

Figure Coverage(const StudySpec& spec, const nlohmann::json& summary) {
  // One point (no sweep, or a sweep of one value): coverage per parameter.
  const bool per_parameter =
      spec.sweep.setting == SweepSetting::kNone || summary["points"].size() == 1;
  const std::vector<std::string> names = ParameterNames(summary);
  Figure f;
  f.title = "Coverage of the 95 % intervals (nominal: dashed; binomial 95 % band: grey)";
  f.columns = 2;
  for (StudyMethod method : spec.methods) {
    const std::string m = StudyMethodName(method);
    PlotPanel panel;
    panel.title = m;
    panel.y_label = "coverage";
    panel.y_min = 0;
    panel.y_max = 1.05;
    if (per_parameter) {
      panel.x_label = "parameter (";
      for (size_t i = 0; i < names.size(); ++i) {
        panel.x_label += (i ? ", " : "") + std::to_string(i + 1) + " " + names[i];
      }
      panel.x_label += ")";
    } else {
      panel.x_label = SweepAxis(spec);
    }
    PlotSeries nominal{"nominal 95 %", {}, {}, "lines lc rgb 'black' dt 2"};
    PlotSeries band{"", {}, {}, "lines lc rgb '#aaaaaa' lw 6"};
    std::map<std::string, PlotSeries> series;
    for (const auto& point : summary["points"]) {
      for (size_t i = 0; i < names.size(); ++i) {
        const nlohmann::json& parameters = point["methods"][m]["parameters"];
        if (!parameters.contains(names[i])) continue;
        const nlohmann::json& c = parameters[names[i]]["coverage"];
        if (!c.contains("rate")) continue;
        const double x = per_parameter ? i + 1.0 : PointX(point);
        const double lo = c["band"][0].get<double>(), hi = c["band"][1].get<double>();
        AddBar(&band, x, 0.5 * (lo + hi), 0.5 * (hi - lo));
        nominal.x.push_back(x);
        nominal.y.push_back(kNominalCoverage);
        PlotSeries& s = series[per_parameter ? "coverage" : names[i]];
        if (s.title.empty())
          s = {per_parameter ? "coverage" : names[i], {}, {}, "linespoints pt 7 ps 0.6"};
        s.x.push_back(x);
        s.y.push_back(c["rate"].get<double>());
      }
    }
    if (nominal.x.empty()) continue;
    panel.series.push_back(band);
    panel.series.push_back(nominal);
    for (auto& [name, s] : series) panel.series.push_back(s);
    f.panels.push_back(panel);
  }
  return f;
}

Figure Detection(const StudySpec& spec, const nlohmann::json& summary) {
  Figure f;
  f.title = "discover: detection probability vs effect strength";
  PlotPanel panel;
  panel.title = "effect " + spec.sweep.parameter.substr(0, spec.sweep.parameter.find('.'));
  panel.x_label = spec.sweep.parameter;
  panel.y_label = "probability (95 % interval)";
  panel.y_min = 0;
  panel.y_max = 1.05;
  PlotSeries detected{"detected", {}, {}, "linespoints pt 7 lc rgb '#1f77b4'"};
  PlotSeries false_alarm{"false alarm", {}, {}, "points pt 5 lc rgb '#d62728'"};
  PlotSeries bars{"", {}, {}, "lines lc rgb '#1f77b4'"};
  for (const auto& point : summary["points"]) {
    const nlohmann::json& d = point["methods"]["discover"];
    const double x = PointX(point);
    for (const auto& [effect, rate] : d["detection"].items()) {
      if (!rate["rate"].is_number()) continue;
      detected.x.push_back(x);
      detected.y.push_back(rate["rate"].get<double>());
      const double lo = rate["interval"][0].get<double>(), hi = rate["interval"][1].get<double>();
      AddBar(&bars, x, 0.5 * (lo + hi), 0.5 * (hi - lo));
    }
    if (d["false_alarm"]["rate"].is_number()) {
      false_alarm.x.push_back(x);
      false_alarm.y.push_back(d["false_alarm"]["rate"].get<double>());
    }
  }
  for (PlotSeries* s : {&detected, &bars, &false_alarm}) {
    if (!s->x.empty()) panel.series.push_back(*s);
  }
  f.panels.push_back(panel);
  return f;
}

Figure ErrorVersusLength(const StudySpec& spec, const nlohmann::json& summary) {
  Figure f;
  f.title = "rms error / |truth| vs flight log length";
  f.columns = 2;
  for (StudyMethod method : spec.methods) {
    const std::string m = StudyMethodName(method);
    PlotPanel panel;
    panel.title = m;
    panel.x_label = "log length [s]";
    panel.y_label = "rms error / |truth|";
    panel.log_y = true;
    std::map<std::string, PlotSeries> series;
    for (const auto& point : summary["points"]) {
      for (const auto& [name, p] : point["methods"][m]["parameters"].items()) {
        if (!p["rmse"].is_number() || p["truth"].get<double>() == 0) continue;
        const double y = p["rmse"].get<double>() / std::fabs(p["truth"].get<double>());
        if (!(y > 0)) continue;
        PlotSeries& s = series[name];
        if (s.title.empty()) s = {name, {}, {}, "linespoints pt 7 ps 0.6"};
        s.x.push_back(PointX(point));
        s.y.push_back(y);
      }
    }
    for (auto& [name, s] : series) panel.series.push_back(s);
    if (!panel.series.empty()) f.panels.push_back(panel);
  }
  return f;
}

// discover's share of right answers per truth (randomised study): each
// single effect, each outside-library load, no effect; pairs pooled.
Figure Confusion(const nlohmann::json& confusion) {
  Figure f;
  f.title = "discover on randomised truths: share of runs right (Wilson 95 % interval)";
  f.height_px = 520;
  PlotPanel panel;
  panel.x_label = "truth";
  panel.y_label = "share of runs";
  panel.y_min = 0;
  panel.y_max = 1.05;
  panel.key = "off";  // one series: the title says what it is
  PlotSeries right{"right", {}, {}, "points pt 7 ps 1.2 lc rgb '#1f77b4'"};
  PlotSeries bars{"", {}, {}, "lines lc rgb '#1f77b4'"};
  auto add = [&](const std::string& label, const nlohmann::json& rate) {
    if (!rate["rate"].is_number()) return;
    const double x = static_cast<double>(panel.x_categories.size());
    panel.x_categories.push_back(label + " (" + std::to_string(rate["runs"].get<int>()) + ")");
    right.x.push_back(x);
    right.y.push_back(rate["rate"].get<double>());
    const double lo = rate["interval"][0].get<double>(), hi = rate["interval"][1].get<double>();
    AddBar(&bars, x, 0.5 * (lo + hi), 0.5 * (hi - lo));
  };
  for (const auto& row : confusion["matrix"]) {
    const std::string truth = row["truth"].get<std::string>();
    if (truth.find('+') == std::string::npos) add(truth, row["right"]);
  }
  add("two effects", confusion["all"]["pair_both_found"]);
  if (!right.x.empty()) {
    panel.series = {right, bars};
    f.panels.push_back(panel);
  }
  return f;
}

}  // namespace

std::vector<NamedFigure> StudyFigures(const StudySpec& spec, const nlohmann::json& summary,
                                      const std::vector<nlohmann::json>& records) {
  std::vector<NamedFigure> out;
  auto add = [&](const char* file, Figure f) {
    if (!f.panels.empty()) out.push_back({file, std::move(f)});
  };
  add("estimates.png", Estimates(spec, summary, records));
  add("coverage.png", Coverage(spec, summary));
  const bool discover = std::find(spec.methods.begin(), spec.methods.end(),
                                  StudyMethod::kDiscover) != spec.methods.end();
  if (discover && spec.sweep.setting == SweepSetting::kEffectStrength) {
    add("detection.png", Detection(spec, summary));
  }
  if (summary.contains("confusion")) add("confusion.png", Confusion(summary["confusion"]));
  if (spec.sweep.setting == SweepSetting::kLogLength) {
    add("error_vs_length.png", ErrorVersusLength(spec, summary));
  }
  return out;
}

}  // namespace coaxid
