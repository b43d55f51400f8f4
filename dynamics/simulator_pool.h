// Simulators of one model shared by many users that never need one at the
// same time in more threads than there are: the multiple-shooting segments
// of an output-error fit (an hour of flight has 3600 of them; a simulator
// with sensitivities holds CVODE's history of its 300 variational states,
// tens of kB). Acquire lends an idle simulator (or makes one) until the
// lease ends; a pool holds at most as many as were ever in use at once.
// Thread-safe.
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "dynamics/simulator.h"

namespace coaxid {

class SimulatorPool {
 public:
  // The arguments of every simulator made (Simulator's constructor). The
  // model must outlive the pool. A lent simulator's theta is whatever its
  // last user set: set it before a run.
  SimulatorPool(const VehicleModel& model, const Eigen::VectorXd& theta,
                const IntegratorOptions& options, const SensitivityOptions& sensitivities = {},
                std::vector<int> sensitivity_parameters = {},
                SensitivityMethod method = SensitivityMethod::kVariationalEquations);

  class Lease {
   public:
    Lease(SimulatorPool* pool, std::unique_ptr<Simulator> simulator)
        : pool_(pool), simulator_(std::move(simulator)) {}
    Lease(Lease&&) = default;
    Lease& operator=(Lease&&) = delete;
    ~Lease();
    Simulator& operator*() const { return *simulator_; }
    Simulator* operator->() const { return simulator_.get(); }

   private:
    SimulatorPool* pool_;
    std::unique_ptr<Simulator> simulator_;
  };

  Lease Acquire();
  // Simulators made so far.
  int size() const;

 private:
  const VehicleModel& model_;
  Eigen::VectorXd theta_;
  IntegratorOptions options_;
  SensitivityOptions sensitivities_;
  std::vector<int> sensitivity_parameters_;
  SensitivityMethod method_;
  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<Simulator>> idle_;
  int made_ = 0;
};

}  // namespace coaxid
