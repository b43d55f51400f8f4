#include "ident/free_parameters.h"

namespace coaxid {

FreeParameters::FreeParameters(const ParameterSet& parameters)
    : base_(parameters.Values()),
      indices_(parameters.FreeIndices()),
      names_(parameters.FreeNames()) {
  scales_.resize(size());
  lower_.resize(size());
  upper_.resize(size());
  for (int k = 0; k < size(); ++k) {
    const Parameter& p = parameters[indices_[k]];
    scales_[k] = p.scale;
    lower_[k] = p.lower / p.scale;
    upper_[k] = p.upper / p.scale;
  }
}

Eigen::VectorXd FreeParameters::ScaledValues() const {
  Eigen::VectorXd v(size());
  for (int k = 0; k < size(); ++k) v[k] = base_[indices_[k]] / scales_[k];
  return v;
}

Eigen::VectorXd FreeParameters::ScaledLower() const { return lower_; }
Eigen::VectorXd FreeParameters::ScaledUpper() const { return upper_; }

Eigen::VectorXd FreeParameters::Theta(const double* scaled) const {
  std::vector<double> theta;
  Fill(scaled, &theta);
  return Eigen::Map<const Eigen::VectorXd>(theta.data(), theta.size());
}

void FreeParameters::WriteBack(const double* scaled, ParameterSet* parameters) const {
  for (int k = 0; k < size(); ++k) {
    parameters->mutable_parameter(indices_[k]).value = scaled[k] * scales_[k];
  }
}

}  // namespace coaxid
