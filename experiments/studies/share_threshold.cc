#include "experiments/studies/share_threshold.h"

#include <algorithm>
#include <cstdio>
#include <set>

#include "experiments/studies/confusion.h"

namespace coaxid {
namespace {

constexpr double kThresholds[] = {0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9};

struct Refit {
  bool in_truth = false, significant = false;
  double share = 0, share_held_out = 0, excess_removed_all_channels = 0;
  bool Qualifies(double t) const {
    return significant && share >= t && share_held_out >= t;
  }
};

}  // namespace

nlohmann::json ShareThresholdSummary(const std::vector<nlohmann::json>& records) {
  std::vector<std::vector<Refit>> runs;  // each run's round-1 refits
  for (const nlohmann::json& r : records) {
    if (!r.contains("draw") || !r.contains("methods") || !r["methods"].contains("discover")) {
      continue;
    }
    const nlohmann::json& m = r["methods"]["discover"];
    if (!m["ok"].get<bool>() || !m.contains("refits")) continue;
    const std::set<std::string> truth = TruthEffectsOfDraw(r["draw"]);
    std::vector<Refit> refits;
    for (const nlohmann::json& c : m["refits"]) {
      // A paired refit's (beside a provisional effect) is judged against
      // another model than the round's.
      if (c["round"].get<int>() != 1 || c.value("beside", nlohmann::json()).is_string()) continue;
      Refit f;
      f.in_truth = truth.count(c["effect"].get<std::string>()) > 0;
      f.significant = c["significant"].get<bool>();
      f.share = c["share"].get<double>();
      // Not computed (no held-out log, or below the study's threshold on
      // the estimation data): the estimation share stands in, as in the loop.
      f.share_held_out = c["share_held_out"].is_number() ? c["share_held_out"].get<double>() : f.share;
      f.excess_removed_all_channels = c["excess_removed_all_channels"].get<double>();
      refits.push_back(f);
    }
    runs.push_back(refits);
  }
  int true_significant = 0, false_significant = 0;
  for (const auto& run : runs) {
    for (const Refit& f : run) {
      true_significant += f.significant && f.in_truth;
      false_significant += f.significant && !f.in_truth;
    }
  }
  nlohmann::json rows = nlohmann::json::array();
  for (double t : kThresholds) {
    int true_qualify = 0, false_qualify = 0, wrong_choice = 0, true_lost = 0;
    for (const auto& run : runs) {
      const Refit* choice = nullptr;
      bool true_significant_here = false;
      for (const Refit& f : run) {
        true_significant_here = true_significant_here || (f.significant && f.in_truth);
        if (!f.Qualifies(t)) continue;
        (f.in_truth ? true_qualify : false_qualify) += 1;
        if (!choice || f.excess_removed_all_channels > choice->excess_removed_all_channels) {
          choice = &f;
        }
      }
      wrong_choice += choice && !choice->in_truth;
      true_lost += true_significant_here && !choice;
    }
    rows.push_back({{"threshold", t},
                    {"true_qualify", true_qualify},
                    {"false_qualify", false_qualify},
                    {"wrong_choice", wrong_choice},
                    {"true_lost", true_lost}});
  }
  return {{"runs", runs.size()},
          {"true_significant", true_significant},
          {"false_significant", false_significant},
          {"thresholds", rows}};
}

std::string ShareThresholdMarkdown(const nlohmann::json& s) {
  if (s["runs"].get<int>() == 0) return "";
  std::string md =
      "\n## discover: the practical-significance threshold\n\nRound-1 refits of " +
      std::to_string(s["runs"].get<int>()) + " runs, replayed at other thresholds of the share of "
      "their channels' excess error removed (estimation and held out): " +
      std::to_string(s["true_significant"].get<int>()) + " refits of a true effect and " +
      std::to_string(s["false_significant"].get<int>()) +
      " of a false one pass every other gate. Below the study's own threshold the held-out "
      "share was not computed and the estimation share stands in (an upper bound on what would "
      "qualify).\n\n| threshold | true refits qualifying | false refits qualifying | runs "
      "choosing a false effect | runs losing a true effect |\n|---|---|---|---|---|\n";
  for (const nlohmann::json& r : s["thresholds"]) {
    char line[160];
    std::snprintf(line, sizeof line, "| %.2f | %d | %d | %d | %d |\n",
                  r["threshold"].get<double>(), r["true_qualify"].get<int>(),
                  r["false_qualify"].get<int>(), r["wrong_choice"].get<int>(),
                  r["true_lost"].get<int>());
    md += line;
  }
  return md;
}

}  // namespace coaxid
