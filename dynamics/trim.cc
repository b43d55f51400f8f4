#include "dynamics/trim.h"

#include <cmath>
#include <vector>

#include <Eigen/Dense>
#include <ceres/jet.h>

#include "core/errors.h"

namespace coaxid {
namespace {

// Unknowns: omega1, omega2, delta_cx, delta_cy, phi, theta.
constexpr int kUnknowns = 6;
using Jet = ceres::Jet<double, kUnknowns>;

// The six accelerations (u, v, w, p, q, r rates) at zero velocity and rates.
template <typename T>
void Accelerations(const VehicleModel& model, const std::vector<T>& theta, const T* z,
                   double height, double heading, T* out) {
  // Effect states (a stabilizer bar's tilt) rest at 0 at zero rates.
  std::vector<T> state(model.NumStates(), T(0)), xdot(model.NumStates());
  T* x = state.data();
  x[kZ] = T(-height);
  x[kPsi] = T(heading);
  x[kPhi] = z[4];
  x[kTheta] = z[5];
  const T input[kNumInputs] = {z[0], z[1], z[2], z[3]};
  model.Derivative(theta.data(), x, input, xdot.data());
  for (int i = 0; i < 3; ++i) out[i] = xdot[kU + i];
  for (int i = 0; i < 3; ++i) out[3 + i] = xdot[kP + i];
}

}  // namespace

HoverTrim TrimHover(const VehicleModel& model, const Eigen::VectorXd& theta, double height,
                    double heading, double tolerance) {
  // Start: equal thrust share, yaw balance ignored, level.
  const double mg = theta[kMass] * theta[kGravity];
  const double k = std::fabs(theta[kAlpha]) + std::fabs(theta[kBeta]);
  const double omega0 = std::sqrt(mg / std::max(k, 1e-12));
  Eigen::Matrix<double, kUnknowns, 1> z;
  z << omega0, omega0, 0, 0, 0, 0;

  std::vector<Jet> theta_jet(theta.size());
  for (int i = 0; i < theta.size(); ++i) theta_jet[i] = Jet(theta[i]);
  std::vector<double> theta_d(theta.data(), theta.data() + theta.size());

  HoverTrim trim;
  // Scale the equations so forces and moments weigh alike: accelerations in
  // m/s^2 and rad/s^2 are already comparable.
  auto residual_norm = [&](const Eigen::Matrix<double, kUnknowns, 1>& zz) {
    double r[kUnknowns];
    Accelerations(model, theta_d, zz.data(), height, heading, r);
    double n = 0;
    for (double v : r) n = std::max(n, std::fabs(v));
    return std::isfinite(n) ? n : std::numeric_limits<double>::infinity();
  };
  double norm = residual_norm(z);
  for (int it = 0; it < 100 && norm > tolerance; ++it) {
    Jet zj[kUnknowns], rj[kUnknowns];
    for (int i = 0; i < kUnknowns; ++i) zj[i] = Jet(z[i], i);
    Accelerations(model, theta_jet, zj, height, heading, rj);
    Eigen::Matrix<double, kUnknowns, kUnknowns> J;
    Eigen::Matrix<double, kUnknowns, 1> r;
    for (int i = 0; i < kUnknowns; ++i) {
      r[i] = rj[i].a;
      J.row(i) = rj[i].v.transpose();
    }
    const Eigen::Matrix<double, kUnknowns, 1> step = J.colPivHouseholderQr().solve(-r);
    // Backtracking line search on the max-norm keeps the iteration safe far
    // from the solution (rotor speeds must stay positive).
    double t = 1.0;
    Eigen::Matrix<double, kUnknowns, 1> trial = z + step;
    double trial_norm = residual_norm(trial);
    while ((trial_norm >= norm || trial[0] <= 0 || trial[1] <= 0) && t > 1e-6) {
      t *= 0.5;
      trial = z + t * step;
      trial_norm = residual_norm(trial);
    }
    if (!(trial_norm < norm)) break;
    z = trial;
    norm = trial_norm;
    trim.iterations = it + 1;
  }
  if (!(norm <= tolerance)) {
    throw ComputationError("hover trim did not converge: largest acceleration left " +
                           std::to_string(norm) + " (the vehicle may not be able to hover)");
  }
  trim.state = Eigen::VectorXd::Zero(model.NumStates());
  trim.state[kZ] = -height;
  trim.state[kPsi] = heading;
  trim.state[kPhi] = z[4];
  trim.state[kTheta] = z[5];
  trim.input = {z[0], z[1], z[2], z[3]};
  trim.residual = norm;
  return trim;
}

}  // namespace coaxid
