#include "ident/parameter_prior.h"

#include <algorithm>

namespace coaxid {

std::vector<std::string> PriorNames(const std::vector<ParameterPrior>& priors) {
  std::vector<std::string> names;
  for (const ParameterPrior& p : priors) names.push_back(p.name);
  return names;
}

void StartAtPriors(const std::vector<ParameterPrior>& priors, ParameterSet* parameters) {
  for (const ParameterPrior& prior : priors) {
    const Parameter& p = parameters->Get(prior.name);
    parameters->SetValue(prior.name, std::clamp(prior.value, p.lower, p.upper));
  }
}

ScaledPriorRows PriorRows(const std::vector<ParameterPrior>& priors,
                          const std::vector<std::string>& free_names,
                          const Eigen::VectorXd& free_scales) {
  const int P = static_cast<int>(free_names.size());
  std::vector<std::pair<int, const ParameterPrior*>> rows;
  for (const ParameterPrior& prior : priors) {
    const auto it = std::find(free_names.begin(), free_names.end(), prior.name);
    if (it != free_names.end()) rows.push_back({static_cast<int>(it - free_names.begin()), &prior});
  }
  ScaledPriorRows out;
  out.A = Eigen::MatrixXd::Zero(rows.size(), P);
  out.b = Eigen::VectorXd::Zero(P);
  for (size_t j = 0; j < rows.size(); ++j) {
    const auto& [k, prior] = rows[j];
    out.A(j, k) = free_scales[k] / prior->std;
    out.b[k] = prior->value / free_scales[k];
  }
  return out;
}

}  // namespace coaxid
