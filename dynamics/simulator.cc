#include "dynamics/simulator.h"

#include <glog/logging.h>

namespace coaxid {

Simulator::Simulator(const VehicleModel& model, const Eigen::VectorXd& theta,
                     const IntegratorOptions& options, const SensitivityOptions& sensitivities,
                     std::vector<int> sensitivity_parameters)
    : ode_(model, theta, std::move(sensitivity_parameters)),
      integrator_(ode_, options, sensitivities),
      sensitivity_options_(sensitivities),
      with_sensitivities_(sensitivities.wrt_initial_state || sensitivities.wrt_parameters) {}

bool Simulator::Run(const InputHold& inputs, int first, int last, const Eigen::VectorXd& x0,
                    Trajectory* out) {
  CHECK(first >= 0 && first <= last && last < inputs.size());
  CHECK_EQ(x0.size(), kNumStates);
  out->times.assign(1, inputs.time(first));
  out->states.assign(1, x0);
  out->sensitivities.clear();
  Eigen::VectorXd x = x0;
  Eigen::MatrixXd S;
  if (with_sensitivities_) {
    // The natural initial sensitivities: [I | 0] (initial-state columns come
    // first when carried, SensitivityOptions).
    S = Eigen::MatrixXd::Zero(kNumStates, integrator_.num_sensitivities());
    if (sensitivity_options_.wrt_initial_state) {
      S.leftCols(kNumStates).setIdentity();
    }
    out->sensitivities.push_back(S);
  }
  for (int k = first; k < last; ++k) {
    ode_.SetInput(inputs.input(k));
    // Restart at every input change: the right-hand side jumps there.
    if (!integrator_.Reset(inputs.time(k), x, with_sensitivities_ ? &S : nullptr) ||
        !integrator_.AdvanceTo(inputs.time(k + 1), &x, with_sensitivities_ ? &S : nullptr)) {
      error_ = "integration failed between t = " + std::to_string(inputs.time(k)) + " and " +
               std::to_string(inputs.time(k + 1)) + " s: " + integrator_.last_error();
      return false;
    }
    if (!x.allFinite()) {
      error_ = "state not finite at t = " + std::to_string(inputs.time(k + 1)) + " s";
      return false;
    }
    if (with_sensitivities_) out->sensitivities.push_back(S);
    out->times.push_back(inputs.time(k + 1));
    out->states.push_back(x);
  }
  return true;
}

}  // namespace coaxid
