#include "dynamics/model_jacobian.h"

#include <ceres/jet.h>
#include <glog/logging.h>

namespace coaxid {
namespace {

// Derivative directions are taken kChunk at a time: 12 states plus P
// parameters need ceil((12 + P) / kChunk) evaluations with Jets.
constexpr int kChunk = 16;
using Jet = ceres::Jet<double, kChunk>;

}  // namespace

bool DerivativeJacobians(const VehicleModel& model, const Eigen::VectorXd& theta,
                         const double* x, const InputVector& input,
                         const std::vector<int>& parameter_indices, Eigen::MatrixXd* dfdx,
                         Eigen::MatrixXd* dfdp) {
  CHECK(dfdx != nullptr);
  const int num_params = dfdp ? static_cast<int>(parameter_indices.size()) : 0;
  const int num_directions = kNumStates + num_params;
  dfdx->resize(kNumStates, kNumStates);
  if (dfdp) dfdp->resize(kNumStates, num_params);

  std::vector<Jet> theta_jet(theta.size());
  Jet x_jet[kNumStates], u_jet[kNumInputs], xdot_jet[kNumStates];
  for (int i = 0; i < kNumInputs; ++i) u_jet[i] = Jet(input[i]);

  for (int first = 0; first < num_directions; first += kChunk) {
    for (int i = 0; i < theta.size(); ++i) theta_jet[i] = Jet(theta[i]);
    for (int i = 0; i < kNumStates; ++i) x_jet[i] = Jet(x[i]);
    const int last = std::min(first + kChunk, num_directions);
    for (int dir = first; dir < last; ++dir) {
      if (dir < kNumStates) {
        x_jet[dir].v[dir - first] = 1.0;
      } else {
        theta_jet[parameter_indices[dir - kNumStates]].v[dir - first] = 1.0;
      }
    }
    model.Derivative(theta_jet.data(), x_jet, u_jet, xdot_jet);
    for (int row = 0; row < kNumStates; ++row) {
      if (!std::isfinite(xdot_jet[row].a)) return false;
      for (int dir = first; dir < last; ++dir) {
        const double value = xdot_jet[row].v[dir - first];
        if (!std::isfinite(value)) return false;
        if (dir < kNumStates) {
          (*dfdx)(row, dir) = value;
        } else {
          (*dfdp)(row, dir - kNumStates) = value;
        }
      }
    }
  }
  return true;
}

}  // namespace coaxid
