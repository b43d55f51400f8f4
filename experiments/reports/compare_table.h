// The table of `coaxid compare`: every parameter each method gives, their
// pairwise agreement in sigma units, the error against the truth when it is
// known, the fit and validation errors and the wall time of each method.
// Pure functions from the methods' report.json documents to compare.json,
// compare.md and the estimate figure; the caller runs the methods and writes.
//
// Agreement of methods a and b on one parameter (both with a std):
//     z_ab = |a - b| / sqrt(s_a^2 + s_b^2)
// (independent estimates: below ~2 they agree at about the 95 % level; the
// methods that share logs are correlated, so z_ab understates a real
// disagreement less than it overstates it). Error against the truth:
//     e = (estimate - truth) / s.
//
// The linear method's over-parameterisation (model.md decision 6; paper eqs.
// 64-65, 69-70): it estimates Cz_alpha = Cz alpha and Cz_beta = Cz beta as two
// free coefficients where the nonlinear model has one Cz. The table shows
// both, their truth Cz alpha and Cz beta when known, and the two values of Cz
// they imply (Cz_alpha / alpha and Cz_beta / beta), each compared with the
// other methods' one Cz.
#pragma once

#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/plot.h"

namespace coaxid {

// One method's run inside compare.
struct MethodRun {
  std::string method;                 // linear_kf, output_error, ekf
  std::string status = "skipped";     // ran, skipped, failed
  std::string reason;                 // why skipped or failed
  std::vector<std::string> logs;      // estimation logs given to it
  std::vector<std::string> validate;  // held-out logs given to it (may be empty)
  std::string folder;                 // its output folder, relative to compare's
  std::string prior;                  // the prior it was given, in words (empty: none)
  double wall_s = std::numeric_limits<double>::quiet_NaN();  // wall time of the run [s]
  nlohmann::json report;                                     // its report.json (status ran)
};

// The order the methods appear in every table.
const std::vector<std::string>& CompareMethods();

// compare.json. truth: the "parameters" object of truth.json, or null.
nlohmann::json ComparisonJson(const std::vector<MethodRun>& runs, const nlohmann::json& truth);

// compare.md (also what compare prints): the tables of comparison.
// plot: the estimate figure's path relative to compare.md, empty if none.
std::string ComparisonMarkdown(const nlohmann::json& comparison, const std::string& plot);

// One table cell: "value ± std", "value (not identifiable)", "value (config)"
// or "-", from an entry of a row's "estimates".
std::string EstimateText(const nlohmann::json& entry);

// Estimate vs truth (or vs the output_error estimate when there is no
// truth) with +-1 std bars, one panel per parameter, the methods side by side.
Figure EstimatesFigure(const nlohmann::json& comparison);

}  // namespace coaxid
