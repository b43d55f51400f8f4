// The linear_kf baseline's outputs: report.json (cli-and-reports.md, with
// the extra sections "noise_covariance", "excitation", "thrust_map",
// "interference", "kalman", "diagnostics", "notes") and the CSV tables behind
// the paper's Figs. 8-13. Pure functions from results to text; the caller
// writes the files.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/parameters.h"
#include "ident/baseline/linear_baseline.h"

namespace coaxid {

struct BaselineReportContext {
  std::vector<std::string> logs;                      // estimation logs as given
  std::vector<std::string> validation_logs;           // --validate logs (empty: held-out parts)
  std::string validation_description;                 // which rows were held out, or which logs
  nlohmann::json outputs = nlohmann::json::object();  // files written, plots (or why skipped)
  std::vector<std::string> notes;                     // the caller's notes, added to the result's
};

// report.json. config: the vehicle's parameters (known constants, d, and the
// unknowns the balance does not determine, reported with estimated = false).
nlohmann::json LinearBaselineReportJson(const LinearBaselineResult& result,
                                        const ParameterSet& config,
                                        const BaselineReportContext& context);

// thrust_map.csv: one row per delta = 0 hold (Fig. 8), with its sigma (Fig. 9).
std::string ThrustMapCsv(const LinearBaselineResult& result);
// sigma_map.csv: the table cells, their source and the parametric value.
std::string SigmaMapCsv(const LinearBaselineResult& result);
// kf_history.csv: estimate and trace(P) (scaled) after each kept update (Fig. 11).
std::string KfHistoryCsv(const LinearBaselineResult& result);
// reconstruction_NAME.csv: t, row, part (estimation/validation), measured and
// model per channel (Figs. 10, 12, 13). parts: the reconstructions of one log.
std::string ReconstructionCsv(const std::vector<const Reconstruction*>& parts,
                              const std::vector<std::string>& part_labels);

}  // namespace coaxid
