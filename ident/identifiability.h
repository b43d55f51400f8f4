// Covariance and identifiability from the Fisher information at a solution
// (Cramér-Rao bounds). The information is analysed in scaled coordinates
// (value / scale) by a symmetric eigen-decomposition (the SVD of a symmetric
// positive semi-definite matrix), so a rank-deficient information breaks
// nothing: a near-null direction names the parameter combination the data
// do not see, the parameters in it are reported as not identifiable (never
// with a made-up std), and the others get their std from the pseudo-inverse
// on the identifiable subspace.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace coaxid {

struct NullDirection {
  double relative_eigenvalue;          // eigenvalue / largest eigenvalue
  std::vector<std::string> parameters; // those with a significant share of the direction
  std::vector<double> components;      // their components (scaled coordinates)
  std::string explanation;             // for people
};

struct IdentifiabilityReport {
  std::vector<std::string> names;
  Eigen::VectorXd eigenvalues;         // of the scaled information, descending
  Eigen::VectorXd std;                 // per parameter, unscaled; NaN if not identifiable
  std::vector<bool> identifiable;
  Eigen::MatrixXd covariance;          // unscaled, on the identifiable subspace
  Eigen::MatrixXd correlation;
  std::vector<NullDirection> null_directions;
  double condition_number = 0;         // of the information restricted to the identifiable subspace

  // Replaces the covariance (unscaled; e.g. corrected for coloured
  // residuals) and the std and correlation that follow from it, for the
  // identifiable parameters.
  void SetCovariance(const Eigen::MatrixXd& covariance);

  nlohmann::json ToJson() const;
};

// information_scaled: P x P, in coordinates value / scale. A direction whose
// eigenvalue is below relative_threshold times the largest is a null
// direction (1e-10 by default: structural rank loss shows at round-off
// level, weak but real information stays far above it).
IdentifiabilityReport AnalyzeIdentifiability(const Eigen::MatrixXd& information_scaled,
                                             const std::vector<std::string>& names,
                                             const Eigen::VectorXd& scales,
                                             double relative_threshold = 1e-10);

}  // namespace coaxid
