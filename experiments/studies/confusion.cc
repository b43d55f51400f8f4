#include "experiments/studies/confusion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "core/report_values.h"
#include "experiments/studies/summary.h"

namespace coaxid {
namespace {

struct Tally {
  int runs = 0, count = 0;
  void Add(bool hit) {
    ++runs;
    count += hit;
  }
  nlohmann::json Json() const { return RateJson(count, runs); }
};

struct Rates {
  std::map<std::string, Tally> single_found_alone, single_found_alone_visible;
  Tally nothing_wrong_added, outside_unexplained, outside_unexplained_visible, outside_nothing_added,
      none_false_alarm,
      pair_both_found;
  nlohmann::json Json() const {
    auto map = [](const std::map<std::string, Tally>& m) {
      nlohmann::json out = nlohmann::json::object();
      for (const auto& [effect, t] : m) out[effect] = t.Json();
      return out;
    };
    return {{"single_found_alone", map(single_found_alone)},
            {"single_found_alone_visible", map(single_found_alone_visible)},
            {"nothing_wrong_added", nothing_wrong_added.Json()},
            {"outside_unexplained", outside_unexplained.Json()},
            {"outside_unexplained_visible", outside_unexplained_visible.Json()},
            {"outside_nothing_added", outside_nothing_added.Json()},
            {"none_false_alarm", none_false_alarm.Json()},
            {"pair_both_found", pair_both_found.Json()}};
  }
};

std::string Join(const std::vector<std::string>& names, const char* empty) {
  return names.empty() ? empty : Joined(names, "+");
}

std::string Percent(const nlohmann::json& rate) {
  if (!rate["rate"].is_number()) return "-";
  char text[96];
  std::snprintf(text, sizeof text, "%d/%d = %.0f %% (%.0f-%.0f)", rate["count"].get<int>(),
                rate["runs"].get<int>(), 100 * rate["rate"].get<double>(),
                100 * rate["interval"][0].get<double>(), 100 * rate["interval"][1].get<double>());
  return text;
}

std::string Fixed(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2g", v);
  return text;
}

}  // namespace

std::set<std::string> TruthEffectsOfDraw(const nlohmann::json& draw) {
  std::set<std::string> effects;
  const std::string truth = draw["truth"].get<std::string>();
  const std::string truth_class = draw["truth_class"].get<std::string>();
  if (truth_class != "single" && truth_class != "pair") return effects;
  for (size_t start = 0; start <= truth.size();) {
    const size_t plus = std::min(truth.find('+', start), truth.size());
    effects.insert(truth.substr(start, plus - start));
    start = plus + 1;
  }
  return effects;
}

// discover's wall time per run (s): median, 90th percentile and largest.
// Under a study's parallel jobs, not an idle machine's.
nlohmann::json SecondsJson(std::vector<double> seconds) {
  if (seconds.empty()) return {{"runs", 0}};
  std::sort(seconds.begin(), seconds.end());
  auto at = [&](double q) {
    return seconds[static_cast<size_t>(std::lround(q * (seconds.size() - 1)))];
  };
  return {{"runs", seconds.size()}, {"median", at(0.5)}, {"p90", at(0.9)}, {"max", seconds.back()}};
}

nlohmann::json ConfusionSummary(const std::vector<nlohmann::json>& records) {
  std::map<std::string, std::map<std::string, int>> matrix;  // truth -> added -> runs
  std::map<std::string, Tally> right_by_truth, unexplained_by_truth, visible_by_truth;
  Rates all, flight_only, with_balance;
  std::vector<double> seconds_all, seconds_flight_only;
  int failed = 0;
  for (const nlohmann::json& r : records) {
    if (!r.contains("draw") || !r["methods"].contains("discover") ||
        !r["methods"]["discover"]["ok"].get<bool>()) {
      ++failed;
      continue;
    }
    const nlohmann::json& draw = r["draw"];
    const nlohmann::json& m = r["methods"]["discover"];
    const std::string truth = draw["truth"].get<std::string>();
    const std::string truth_class = draw["truth_class"].get<std::string>();
    const std::set<std::string> truth_effects = TruthEffectsOfDraw(draw);
    std::vector<std::string> added = m["added"].get<std::vector<std::string>>();
    std::sort(added.begin(), added.end());
    const bool unexplained = !m["unexplained"].empty();
    bool wrong = false;
    for (const std::string& a : added) wrong = wrong || !truth_effects.count(a);
    const bool exact = !wrong && added.size() == truth_effects.size();
    const bool right = truth_class == "outside" ? added.empty() && unexplained : exact;
    const bool visible = m.contains("declared_rms_over_noise") &&
                         m["declared_rms_over_noise"].get<double>() >= kVisibleRmsOverNoise;
    if (m.contains("seconds")) {
      seconds_all.push_back(m["seconds"].get<double>());
      if (!draw["balance"].get<bool>()) seconds_flight_only.push_back(seconds_all.back());
    }
    visible_by_truth[truth].Add(visible);
    ++matrix[truth][Join(added, "nothing")];
    right_by_truth[truth].Add(right);
    unexplained_by_truth[truth].Add(unexplained);
    for (Rates* rates : {&all, draw["balance"].get<bool>() ? &with_balance : &flight_only}) {
      rates->nothing_wrong_added.Add(!wrong);
      if (truth_class == "single") rates->single_found_alone[truth].Add(exact);
      if (truth_class == "single" && visible) rates->single_found_alone_visible[truth].Add(exact);
      if (truth_class == "outside") rates->outside_nothing_added.Add(added.empty());
      if (truth_class == "pair") rates->pair_both_found.Add(exact);
      if (truth_class == "outside") rates->outside_unexplained.Add(added.empty() && unexplained);
      if (truth_class == "outside" && visible) {
        rates->outside_unexplained_visible.Add(added.empty() && unexplained);
      }
      if (truth_class == "none") rates->none_false_alarm.Add(!added.empty());
    }
  }
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& [truth, columns] : matrix) {
    rows.push_back({{"truth", truth},
                    {"added", columns},
                    {"right", right_by_truth[truth].Json()},
                    {"unexplained_reported", unexplained_by_truth[truth].Json()},
                    {"visible", visible_by_truth[truth].Json()}});
  }
  return {{"runs_judged", static_cast<int>(records.size()) - failed},
          {"visible_rms_over_noise", kVisibleRmsOverNoise},
          {"runs_failed", failed},
          {"matrix", rows},
          {"all", all.Json()},
          {"flight_only", flight_only.Json()},
          {"flight_and_balance", with_balance.Json()},
          {"seconds", {{"all", SecondsJson(seconds_all)},
                       {"flight_only", SecondsJson(seconds_flight_only)}}}};
}

std::string ConfusionMarkdown(const nlohmann::json& c) {
  std::string md = "\n## discover: truth -> added (" + std::to_string(c["runs_judged"].get<int>()) +
                   " runs judged, " + std::to_string(c["runs_failed"].get<int>()) +
                   " failed)\n\nRates as count/runs = share (Wilson 95 % interval, in %). A "
                   "run is *visible* when the declared model's fit leaves some channel's rms at "
                   "least " + Fixed(c["visible_rms_over_noise"].get<double>()) +
                   " x its sample-to-sample noise: below that the data do not show the effect "
                   "to any method.\n\n"
                   "| rate | all | flight only | flight + balance |\n|---|---|---|---|\n";
  auto row = [&](const std::string& name, const std::string& key, const std::string& sub = "") {
    auto get = [&](const char* group) -> nlohmann::json {
      const nlohmann::json& g = c[group];
      if (sub.empty()) return g[key];
      return g[key].contains(sub) ? g[key][sub] : RateJson(0, 0);
    };
    md += "| " + name + " | " + Percent(get("all")) + " | " + Percent(get("flight_only")) + " | " +
          Percent(get("flight_and_balance")) + " |\n";
  };
  for (const auto& [effect, rate] : c["all"]["single_found_alone"].items()) {
    row(effect + " alone: found, nothing else", "single_found_alone", effect);
    row(effect + " alone, visible: found, nothing else", "single_found_alone_visible", effect);
  }
  row("two effects: both found, nothing else", "pair_both_found");
  row("outside the library: nothing added", "outside_nothing_added");
  row("outside the library: nothing added, unexplained reported", "outside_unexplained");
  row("outside the library, visible: nothing added, unexplained reported",
      "outside_unexplained_visible");
  row("no effect: false alarm", "none_false_alarm");
  row("nothing wrong added (all runs)", "nothing_wrong_added");
  for (const char* group : {"all", "flight_only"}) {
    if (!c.contains("seconds")) break;  // a summary written before the records had it
    const nlohmann::json& t = c["seconds"][group];
    if (t["runs"].get<int>() == 0) continue;
    char line[200];
    std::snprintf(line, sizeof line,
                  "\ndiscover's wall time, %s (%d runs, the study's jobs in parallel): median "
                  "%.1f s, 90th percentile %.1f s, largest %.1f s.\n",
                  std::string(group) == "all" ? "all runs" : "flight only", t["runs"].get<int>(),
                  t["median"].get<double>(), t["p90"].get<double>(), t["max"].get<double>());
    md += line;
  }
  md += "\n| truth | runs | right | visible | unexplained reported | added (runs) |\n"
        "|---|---|---|---|---|---|\n";
  for (const auto& r : c["matrix"]) {
    std::string added;
    for (const auto& [name, n] : r["added"].items()) {
      added += (added.empty() ? "" : ", ") + name + " " + std::to_string(n.get<int>());
    }
    md += "| " + r["truth"].get<std::string>() + " | " +
          std::to_string(r["right"]["runs"].get<int>()) + " | " + Percent(r["right"]) + " | " +
          Percent(r["visible"]) + " | " + Percent(r["unexplained_reported"]) + " | " + added +
          " |\n";
  }
  return md;
}

}  // namespace coaxid
