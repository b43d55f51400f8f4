#include "dynamics/simulator_pool.h"

namespace coaxid {

SimulatorPool::SimulatorPool(const VehicleModel& model, const Eigen::VectorXd& theta,
                             const IntegratorOptions& options,
                             const SensitivityOptions& sensitivities,
                             std::vector<int> sensitivity_parameters,
                             SensitivityMethod method)
    : model_(model),
      theta_(theta),
      options_(options),
      sensitivities_(sensitivities),
      sensitivity_parameters_(std::move(sensitivity_parameters)),
      method_(method) {}

SimulatorPool::Lease SimulatorPool::Acquire() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!idle_.empty()) {
      std::unique_ptr<Simulator> simulator = std::move(idle_.back());
      idle_.pop_back();
      return Lease(this, std::move(simulator));
    }
    ++made_;
  }
  return Lease(this, std::make_unique<Simulator>(model_, theta_, options_, sensitivities_,
                                                 sensitivity_parameters_, method_));
}

int SimulatorPool::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return made_;
}

SimulatorPool::Lease::~Lease() {
  if (!simulator_) return;  // moved from
  std::lock_guard<std::mutex> lock(pool_->mutex_);
  pool_->idle_.push_back(std::move(simulator_));
}

}  // namespace coaxid
