#include "core/parameters.h"

#include <cmath>

#include <glog/logging.h>

#include "core/errors.h"

namespace coaxid {
namespace {

constexpr const char* kBaseNames[kNumBaseParameters] = {
    "m",      "g",      "rho", "R",   "D",   "l",   "alpha", "beta", "sigma0",
    "Cx",     "Cy",     "Cz",  "gamma1", "gamma2", "d", "Ixx", "Iyy",  "Izz"};

}  // namespace

const char* BaseParameterName(int index) {
  CHECK(index >= 0 && index < kNumBaseParameters) << index;
  return kBaseNames[index];
}

std::vector<std::string> UnknownBaseParameterNames() {
  std::vector<std::string> names;
  for (int i = kAlpha; i < kNumBaseParameters; ++i) names.push_back(kBaseNames[i]);
  return names;
}

int ParameterSet::Add(const Parameter& p) {
  if (p.name.empty()) throw InputError("parameter with an empty name");
  if (Has(p.name)) throw InputError("parameter '" + p.name + "' defined twice");
  if (!std::isfinite(p.value)) throw InputError("parameter '" + p.name + "': value is not finite");
  if (!std::isfinite(p.scale) || p.scale <= 0) {
    throw InputError("parameter '" + p.name + "': scale must be a positive number");
  }
  if (p.lower > p.upper) throw InputError("parameter '" + p.name + "': lower bound above upper");
  if (p.value < p.lower || p.value > p.upper) {
    throw InputError("parameter '" + p.name + "': value " + std::to_string(p.value) +
                     " outside its bounds [" + std::to_string(p.lower) + ", " +
                     std::to_string(p.upper) + "]");
  }
  parameters_.push_back(p);
  return size() - 1;
}

int ParameterSet::Index(const std::string& name) const {
  for (int i = 0; i < size(); ++i) {
    if (parameters_[i].name == name) return i;
  }
  return -1;
}

int ParameterSet::IndexOrThrow(const std::string& name) const {
  const int i = Index(name);
  if (i < 0) throw InputError("unknown parameter '" + name + "'");
  return i;
}

void ParameterSet::SetValue(const std::string& name, double value) {
  parameters_[IndexOrThrow(name)].value = value;
}

void ParameterSet::SetEstimated(const std::string& name, bool estimated) {
  parameters_[IndexOrThrow(name)].estimated = estimated;
}

Eigen::VectorXd ParameterSet::Values() const {
  Eigen::VectorXd v(size());
  for (int i = 0; i < size(); ++i) v[i] = parameters_[i].value;
  return v;
}

void ParameterSet::SetValues(const Eigen::VectorXd& values) {
  CHECK_EQ(values.size(), size());
  for (int i = 0; i < size(); ++i) parameters_[i].value = values[i];
}

std::vector<int> ParameterSet::FreeIndices() const {
  std::vector<int> free;
  for (int i = 0; i < size(); ++i) {
    if (parameters_[i].estimated) free.push_back(i);
  }
  return free;
}

std::vector<std::string> ParameterSet::FreeNames() const {
  std::vector<std::string> names;
  for (int i : FreeIndices()) names.push_back(parameters_[i].name);
  return names;
}

Eigen::VectorXd ParameterSet::FreeVector() const {
  const std::vector<int> free = FreeIndices();
  Eigen::VectorXd v(free.size());
  for (size_t k = 0; k < free.size(); ++k) v[k] = parameters_[free[k]].value;
  return v;
}

void ParameterSet::SetFreeVector(const Eigen::VectorXd& free_values) {
  const std::vector<int> free = FreeIndices();
  CHECK_EQ(free_values.size(), static_cast<int>(free.size()));
  for (size_t k = 0; k < free.size(); ++k) parameters_[free[k]].value = free_values[k];
}

Eigen::VectorXd ParameterSet::ScaledFreeVector() const {
  const std::vector<int> free = FreeIndices();
  Eigen::VectorXd v(free.size());
  for (size_t k = 0; k < free.size(); ++k) {
    v[k] = parameters_[free[k]].value / parameters_[free[k]].scale;
  }
  return v;
}

void ParameterSet::SetScaledFreeVector(const Eigen::VectorXd& scaled) {
  const std::vector<int> free = FreeIndices();
  CHECK_EQ(scaled.size(), static_cast<int>(free.size()));
  for (size_t k = 0; k < free.size(); ++k) {
    parameters_[free[k]].value = scaled[k] * parameters_[free[k]].scale;
  }
}

std::vector<std::string> ParametersAtBounds(const ParameterSet& parameters) {
  std::vector<std::string> out;
  for (int i : parameters.FreeIndices()) {
    const Parameter& p = parameters[i];
    const double tolerance = 1e-6 * (p.upper - p.lower);
    if (p.value <= p.lower + tolerance || p.value >= p.upper - tolerance) out.push_back(p.name);
  }
  return out;
}

}  // namespace coaxid
