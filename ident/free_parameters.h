// The estimated (free) parameters of a ParameterSet as the scaled vector an
// optimiser works on (value / scale, so every coordinate is of order one), and
// the map back to the full theta vector the model reads. Shared by every
// estimator.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/parameters.h"

namespace coaxid {

class FreeParameters {
 public:
  explicit FreeParameters(const ParameterSet& parameters);

  int size() const { return static_cast<int>(indices_.size()); }
  const std::vector<int>& indices() const { return indices_; }
  const std::vector<std::string>& names() const { return names_; }
  const Eigen::VectorXd& scales() const { return scales_; }
  // Scaled start values and bounds (infinite where unbounded).
  Eigen::VectorXd ScaledValues() const;
  Eigen::VectorXd ScaledLower() const;
  Eigen::VectorXd ScaledUpper() const;

  // theta with the free entries replaced by scaled[i] * scale[i]; the others
  // from the set's values. T may be double or a ceres::Jet.
  template <typename T>
  void Fill(const T* scaled, std::vector<T>* theta) const {
    theta->resize(base_.size());
    for (int i = 0; i < base_.size(); ++i) (*theta)[i] = T(base_[i]);
    for (int k = 0; k < size(); ++k) (*theta)[indices_[k]] = scaled[k] * scales_[k];
  }
  Eigen::VectorXd Theta(const double* scaled) const;
  // Writes scaled values back into a parameter set.
  void WriteBack(const double* scaled, ParameterSet* parameters) const;

 private:
  Eigen::VectorXd base_;
  std::vector<int> indices_;
  std::vector<std::string> names_;
  Eigen::VectorXd scales_, lower_, upper_;
};

}  // namespace coaxid
