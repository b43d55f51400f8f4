// Cost of simulating one minute of flight the way the identification code does: the input is
// held for 5 ms, so the integrator is restarted (Reset + AdvanceTo) 12,000 times per simulated
// minute. Compares Adams + fixed-point with BDF + Newton, with and without the initial-step
// hint, with and without forward sensitivities (all 12 initial states and 8 parameters).
//
// The system is a 12-state rigid body with smooth nonlinear forces, written once templated on
// the scalar and differentiated with ceres::Jet (STYLE.md, items 1 and 3):
//   p_E' = v_E
//   v_E' = (R_EB [0, 0, -kT u0] - kD v_E sqrt(|v_E|^2 + eps)) / m + [0, 0, g]
//   eta' = T(eta) w_B                      (ZYX Euler angles eta = (phi, theta, psi))
//   w_B' = J^-1 (kQ u_123 - w_B x J w_B - kW w_B),  J = diag(Jx, Jy, Jz)
// with parameters (m, Jx, Jy, Jz, kD, kW, kT, kQ) and a held input u (thrust and three torque
// commands) that changes every 5 ms.
//
// Reported time per iteration = time per simulated minute. Counters are per 5 ms interval.
#include <benchmark/benchmark.h>
#include <ceres/jet.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <string>

#include "dynamics/integrator.h"
#include "dynamics/ode_system.h"

namespace coaxid {

namespace {

constexpr int kStates = 12;
constexpr int kParams = 8;
constexpr double kInterval = 0.005;  // [s] input hold.
constexpr int kIntervals = 12000;    // 60 s.
constexpr double kGravity = 9.81;    // [m/s^2], z down.
constexpr double kTwoPi = 6.283185307179586;

class RigidBodyOde : public OdeSystem {
 public:
  RigidBodyOde() { theta_ << 0.3, 1.5e-3, 1.6e-3, 0.9e-3, 0.02, 2e-3, 1.0, 0.05; }
  int NumStates() const override { return kStates; }
  int NumSensitivityParameters() const override { return kParams; }
  void SetInput(const std::array<double, 4>& u) { u_ = u; }
  const Eigen::Matrix<double, kParams, 1>& theta() const { return theta_; }

  template <typename T>
  void Derivative(const T* x, const T* th, T* xdot) const {
    using std::cos;
    using std::sin;
    using std::sqrt;
    using std::tan;
    const T &m = th[0], &jx = th[1], &jy = th[2], &jz = th[3], &kd = th[4], &kw = th[5],
            &kt = th[6], &kq = th[7];
    const T* v = x + 3;
    const T &phi = x[6], &tht = x[7], &psi = x[8];
    const T &p = x[9], &q = x[10], &r = x[11];
    const T cf = cos(phi), sf = sin(phi), ct = cos(tht), st = sin(tht), cp = cos(psi),
            sp = sin(psi);
    // Third column of R_EB (ZYX): thrust acts along -z_B.
    const T thrust = kt * u_[0];
    const T r13 = cp * st * cf + sp * sf, r23 = sp * st * cf - cp * sf, r33 = ct * cf;
    const T speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + 1e-4);
    for (int i = 0; i < 3; ++i) xdot[i] = v[i];
    xdot[3] = (-thrust * r13 - kd * v[0] * speed) / m;
    xdot[4] = (-thrust * r23 - kd * v[1] * speed) / m;
    xdot[5] = (-thrust * r33 - kd * v[2] * speed) / m + kGravity;
    xdot[6] = p + tan(tht) * (q * sf + r * cf);
    xdot[7] = q * cf - r * sf;
    xdot[8] = (q * sf + r * cf) / ct;
    xdot[9] = (kq * u_[1] - (jz - jy) * q * r - kw * p) / jx;
    xdot[10] = (kq * u_[2] - (jx - jz) * r * p - kw * q) / jy;
    xdot[11] = (kq * u_[3] - (jy - jx) * p * q - kw * r) / jz;
  }

  bool Rhs(double t, const double* x, double* xdot) const override {
    Derivative(x, theta_.data(), xdot);
    return true;
  }

  bool Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                 Eigen::MatrixXd* dfdp) const override {
    if (dfdp == nullptr) {
      JacobiansWith<kStates>(x, dfdx, nullptr);
    } else {
      JacobiansWith<kStates + kParams>(x, dfdx, dfdp);
    }
    return true;
  }

 private:
  template <int N>
  void JacobiansWith(const double* x, Eigen::MatrixXd* dfdx, Eigen::MatrixXd* dfdp) const {
    using Jet = ceres::Jet<double, N>;
    Jet xj[kStates], thj[kParams], fj[kStates];
    for (int i = 0; i < kStates; ++i) xj[i] = Jet(x[i], i);
    for (int i = 0; i < kParams; ++i) {
      thj[i] = N > kStates ? Jet(theta_[i], kStates + i) : Jet(theta_[i]);
    }
    Derivative(xj, thj, fj);
    for (int i = 0; i < kStates; ++i) {
      dfdx->row(i) = fj[i].v.template head<kStates>().transpose();
      if (dfdp != nullptr) dfdp->row(i) = fj[i].v.template tail<N - kStates>().transpose();
    }
  }

  Eigen::Matrix<double, kParams, 1> theta_;
  std::array<double, 4> u_ = {0.0, 0.0, 0.0, 0.0};
};

// The held input of interval k: hover thrust with a slow modulation and three small torque
// sinusoids, sampled (zero-order hold) at the interval start.
std::array<double, 4> InputAt(const RigidBodyOde& system, int k) {
  const double t = k * kInterval;
  const double hover = system.theta()[0] * kGravity / system.theta()[6];
  return {hover * (1.0 + 0.1 * std::sin(kTwoPi * 0.7 * t)), 0.02 * std::sin(kTwoPi * 1.3 * t),
          0.02 * std::sin(kTwoPi * 0.9 * t + 1.0), 0.01 * std::sin(kTwoPi * 0.4 * t + 2.0)};
}

// Args: {bdf_newton, hint, sensitivities}.
void BM_SimulateMinute(benchmark::State& state) {
  const bool bdf_newton = state.range(0) != 0;
  IntegratorOptions options;
  options.method = bdf_newton ? IntegratorOptions::Method::kBdf : IntegratorOptions::Method::kAdams;
  options.newton = bdf_newton;
  options.initial_step_hint = state.range(1) != 0;
  const bool sens = state.range(2) != 0;
  RigidBodyOde system;
  Integrator integrator(system, options, {sens, sens});
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(kStates), x(kStates);
  Eigen::MatrixXd S;
  Integrator::Stats before = integrator.stats();
  double checksum = 0.0;
  for (auto _ : state) {
    x = x0;
    for (int k = 0; k < kIntervals; ++k) {
      system.SetInput(InputAt(system, k));
      if (!integrator.Reset(k * kInterval, x, k == 0 || !sens ? nullptr : &S) ||
          !integrator.AdvanceTo((k + 1) * kInterval, &x, sens ? &S : nullptr)) {
        state.SkipWithError(integrator.last_error().c_str());
        return;
      }
    }
    checksum += x.norm();
    benchmark::DoNotOptimize(checksum);
  }
  const Integrator::Stats after = integrator.stats();
  const double intervals = static_cast<double>(state.iterations()) * kIntervals;
  state.counters["steps/int"] = (after.steps - before.steps) / intervals;
  state.counters["rhs/int"] = (after.rhs_evals - before.rhs_evals) / intervals;
  state.counters["jac/int"] = (after.jac_evals - before.jac_evals) / intervals;
  state.counters["|x(60s)|"] = x.norm();
  state.SetLabel(std::string(bdf_newton ? "BDF+Newton" : "Adams+FP") +
                 (options.initial_step_hint ? " hint" : " no-hint") + (sens ? " sens20" : ""));
}

BENCHMARK(BM_SimulateMinute)
    ->ArgNames({"bdf_newton", "hint", "sens"})
    ->ArgsProduct({{0, 1}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace coaxid

BENCHMARK_MAIN();
