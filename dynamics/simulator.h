// Open-loop simulation of the vehicle over logged zero-order-hold inputs:
// CVODE(S) restarted at every input change, never stepping across one, with
// optional forward sensitivities of the state with respect to the initial
// state and chosen parameters. The output-error segments and the EKF's
// propagation build on this.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/input_hold.h"
#include <memory>

#include "dynamics/integrator.h"
#include "dynamics/variational_system.h"
#include "dynamics/vehicle_ode.h"

namespace coaxid {

struct Trajectory {
  std::vector<double> times;                     // the hold's sample times first..last
  std::vector<Eigen::VectorXd> states;           // x(t_k), 12 each
  std::vector<Eigen::MatrixXd> sensitivities;    // dx(t_k)/d[x0 | params], if asked
  std::vector<HeldInput> inputs;                 // each sample's interval as applied
};

// How sensitivities are computed: CVODES's forward sensitivity module, or
// CVODE on the state augmented with its variational equations (same
// equations, one vector; sensitivities follow the state's steps). Both use the
// autodiff Jacobians of the one model.
enum class SensitivityMethod { kCvodes, kVariationalEquations };

class Simulator {
 public:
  // sensitivity_parameters: indices into theta of the parameters whose
  // sensitivities are carried when sensitivities.wrt_parameters is set.
  Simulator(const VehicleModel& model, const Eigen::VectorXd& theta,
            const IntegratorOptions& options = {}, const SensitivityOptions& sensitivities = {},
            std::vector<int> sensitivity_parameters = {},
            SensitivityMethod method = SensitivityMethod::kVariationalEquations);

  void SetTheta(const Eigen::VectorXd& theta) { ode_.SetTheta(theta); }

  // Integrates from x0 at inputs.time(first) to inputs.time(last), one hold
  // interval at a time (a lagged input starts where the log's rows before
  // `first` left it, dynamics/held_input.h), and records the state (and sensitivities) at every
  // sample first..last. Returns false with last_error() if CVODE fails or the
  // state stops being finite (blown-up parameters): never throws or aborts.
  // *out is then unspecified. Reusing one Trajectory for many runs of the
  // same length allocates nothing after the first.
  // start: row `first` as applied, when the caller has it (HeldInputPath);
  // null walks the lag from row 0.
  bool Run(const InputHold& inputs, int first, int last, const Eigen::VectorXd& x0,
           Trajectory* out, const HeldInput* start = nullptr);

  const std::string& last_error() const { return error_; }
  const Integrator& integrator() const { return *integrator_; }
  // Number of sensitivity columns (0 without sensitivities).
  int num_sensitivities() const { return columns_; }

 private:
  VehicleOde ode_;
  std::unique_ptr<VariationalSystem> variational_;  // set for kVariationalEquations
  std::unique_ptr<Integrator> integrator_;
  SensitivityOptions sensitivity_options_;
  int columns_ = 0;
  std::string error_;
};

}  // namespace coaxid
