// What `coaxid design` writes: design.json (for programs), report.md (for
// people), the designed scenario files ready for `coaxid simulate`, the
// designed excitation as a time series for a flight computer, and plots.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/design/balance_design.h"
#include "experiments/design/excitation_design.h"

namespace coaxid {

struct DesignRun {
  std::string config_path;
  std::string design_at = "config";  // or "truth": the scenarios' truth values
  std::vector<std::string> scenario_paths;  // as given (a path, or a built-in name)
  std::vector<Scenario> plan;
  DesignCriterion criterion;
  PredictedPrecision planned;  // the plan as given
  double criterion_planned = 0;
  std::optional<ExcitationDesign> excitation;
  std::optional<BalanceDesign> balance;
  PredictedPrecision final_precision;  // with every designed change
  double seconds = 0;
};

// report.json-style parameters of a prediction: value, predicted std,
// relative std, identifiable; the held member marked; plus correlation,
// ratios and the scale.
nlohmann::json PredictionJson(const PredictedPrecision& precision);

nlohmann::json DesignJson(const DesignRun& run);
std::string DesignMarkdown(const DesignRun& run, const std::vector<std::string>& plots,
                           const std::string& plot_note);

// The scenario file of a designed scenario: the original file (or a built-in
// name's defaults) with its flight excitation or balance holds replaced by
// the design's.
// how: one line on how it was designed (criterion, parameters), or empty.
std::string DesignedScenarioYaml(const std::string& original_path_or_name, const Scenario& designed,
                                 const std::string& how = "");

// Writes everything into out (created); plots are skipped (with the reason
// in the report) where gnuplot is missing.
void WriteDesign(const DesignRun& run, const std::string& out);

}  // namespace coaxid
