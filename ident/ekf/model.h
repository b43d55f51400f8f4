// The EKF's process and measurement models (ident/ekf/ekf.h): one hold interval's
// transition of the augmented state and the flight outputs with their
// Jacobian, all from the one templated model (STYLE.md, items 1 and 3).
//
// Augmented state z = [x; p]: the model's states (the 12 of dynamics/state.h,
// then any effect's own, e.g. the stabilizer bar's tilt) and the np free
// parameters in scaled coordinates (p_k = theta_k / scale_k,
// ident/free_parameters.h), modelled as random walks (the paper's eq. 66, here
// with the nonlinear 6-DoF model):
//
//   xdot = f(x, theta(p), u_k) + w_x,   pdot = w_p,
//   E[w w^T] = Qc delta(t - s),   Qc = diag(q_x (nx), q_p (np)).
//
// Over one hold interval [t0, t1) (input u_k constant, model.md) the mean is
// integrated with CVODE and the covariance is carried by
//
//   Phi = dz(t1)/dz(t0) = [[A, B], [0, I]],  A = dx1/dx0 (nx x nx), B = dx1/dp (nx x np),
//   Qd  = int_t0^t1 Phi(t1, s) Qc Phi(t1, s)^T ds.
//
// Two ways to get Phi (EkfTransitionMethod):
//  - kSensitivities: CVODE on the state augmented with its variational
//    equations (dynamics/variational_system.h, Jacobians by autodiff): A and
//    B to the integrator's tolerance. Every right-hand side needs a Jacobian
//    (~16 per 5 ms interval): 35 us per interval (bench/ident/ekf/ekf_bench.cc).
//  - kLinearised (default): CVODE integrates the state alone; A and B are
//    exp(Abar h) of the augmented Jacobian Abar = [[F, G], [0, 0]] taken once
//    per sub-step at the midpoint state x_mid = (x(t0) + x(t1)) / 2 (one
//    autodiff evaluation): 12 us per interval. By the Magnus expansion,
//    exp(h Abar(t_mid)) differs from the exact transition by
//    O(h^3 |dAbar/dt| |Abar|) (the midpoint rule is second order): below
//    1e-5 of Phi's entries at h = 5 ms on the simulated flight, and the
//    filter's estimates agree with kSensitivities' to 0.05 std
//    (tests/ident/ekf/ekf_test.cc). The mean is CVODE's in both methods, so the
//    cheaper Phi only changes the gain, to second order in h. The exponential is a Taylor series to 5th order with
//    scaling and squaring (|F h| <= 1/4 after scaling: truncation < 1e-6 of a
//    term that is itself a first-order-accurate linearisation).
// Intervals longer than max_substep are split into equal sub-steps (one
// Jacobian each; CVODE is not restarted between them) so that irregular rows
// and gaps keep the linearisation accurate.
//
// Qd of a sub-step of length h (ZeroOrderTransition): the integral for the
// constant Jacobian at the midpoint, by its Taylor series in h,
//   Qxx = sum_k h^(k+1)/(k+1)! sum_{i+j=k} C(k,i) F^i qx F^T^j        (k <= 3)
//       + sum_{i+j<=2} h^(i+j+3) / ((i+j+3) (i+1)! (j+1)!) F^i M F^T^j,  M = G qp G^T,
//   Qxp = sum_{i<=3} h^(i+2)/(i+2)! F^i G qp,   Qpp = qp h,
// (the M terms: parameter random walk seen through the states, to the
// angles via the rates), truncated at relative order (|F| h)^3 / 24 < 1e-3
// (|F| h <= 1/4 after the same scaling and squaring, Qd(2h) = Phi(h) Qd(h)
// Phi(h)^T + Qd(h)); checked against Van Loan's matrix exponential in
// tests/ident/ekf/ekf_test.cc. A plain trapezoidal rule, h/2 (Phi Qc Phi^T + Qc),
// was tried first: it gets the parameter-driven term M h^3/3 wrong by half
// (the yaw rate's process noise, driven by gamma1 / Izz, by 12 % at 30 ms).
// With kSensitivities, Phi comes from CVODE and Qd from the same series at
// the midpoint Jacobian.
// Sub-steps are composed: Qd <- Phi_j Qd Phi_j^T + Qd_j.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/input_hold.h"
#include "dynamics/integrator.h"
#include "dynamics/outputs.h"
#include "dynamics/state.h"
#include "dynamics/variational_system.h"
#include "dynamics/vehicle_model.h"
#include "dynamics/vehicle_ode.h"

namespace coaxid {

enum class EkfTransitionMethod { kLinearised, kSensitivities };
// "linearised" / "sensitivities".
const char* EkfTransitionMethodName(EkfTransitionMethod method);

// The blocks of one interval's transition of z = [x; p] (the parameters'
// mean is constant), for N states: kNumStates (a model without effect
// states: fixed-size arithmetic) or Eigen::Dynamic (the model's NumStates(),
// in storage of fixed capacity kMaxModelStates: no allocation per interval).
// The equations are written once, templated on N.
template <int N>
struct TransitionBlocks {
  static constexpr int kCapacity = N == Eigen::Dynamic ? kMaxModelStates : N;
  using Vector = Eigen::Matrix<double, N, 1, 0, kCapacity, 1>;
  using Square = Eigen::Matrix<double, N, N, 0, kCapacity, kCapacity>;
  using ByParameter = Eigen::Matrix<double, N, Eigen::Dynamic, 0, kCapacity, Eigen::Dynamic>;
  Vector x;        // x(t1)
  Square A;        // dx(t1)/dx(t0)
  ByParameter B;   // dx(t1)/dp (nx x np), p scaled
  Square Qxx;      // blocks of Qd; Qpp = q_p (t1 - t0), diagonal, not stored
  ByParameter Qxp;
};
using EkfTransition = TransitionBlocks<Eigen::Dynamic>;
using EkfState = EkfTransition::Vector;
using StateMatrix = EkfTransition::Square;
using StateByParameter = EkfTransition::ByParameter;

class EkfPropagator {
 public:
  // theta: the full parameter vector (the free entries are overwritten by
  // SetParameters). free_indices: FreeParameters's; dtheta_dp: the initial
  // d theta_k / d p_k.
  // state_psd (nx) and parameter_psd (np): the diagonal of Qc.
  EkfPropagator(const VehicleModel& model, const Eigen::VectorXd& theta,
                std::vector<int> free_indices, Eigen::VectorXd dtheta_dp,
                const EkfState& state_psd,
                Eigen::VectorXd parameter_psd, EkfTransitionMethod method,
                const IntegratorOptions& integrator, double max_substep_s);

  int num_states() const { return nx_; }
  int num_parameters() const { return static_cast<int>(free_indices_.size()); }
  // The free parameters' values theta_k and d theta_k / d p_k (the filter's
  // coordinates p: scale_k for scaled coordinates, theta_k for logarithmic ones).
  void SetParameters(const Eigen::VectorXd& free_values, const Eigen::VectorXd& dtheta_dp);
  const Eigen::VectorXd& theta() const { return theta_; }

  // x(t1) and Phi, Qd for the interval [t0, t1) with input u (held, lagged
  // inputs as applied). Returns false (never throws) if CVODE fails or a
  // value stops being finite; then last_error() says why.
  bool Propagate(double t0, double t1, const HeldInput& u, const EkfState& x0,
                 EkfTransition* out);
  const std::string& last_error() const { return error_; }

  struct Counters {
    long intervals = 0, substeps = 0, jacobians = 0;
    Counters& operator+=(const Counters& o) {
      intervals += o.intervals;
      substeps += o.substeps;
      jacobians += o.jacobians;
      return *this;
    }
  };
  const Counters& counters() const { return counters_; }
  Integrator::Stats integrator_stats() const { return integrator_->stats(); }
  // CVODE's first-step hint carried from interval to interval (dynamics/integrator.h):
  // with the filter state, what makes the next Propagate() repeat exactly.
  double step_hint() const { return integrator_->step_hint(); }
  void RestoreStepHint(double hint) { integrator_->RestoreStepHint(hint); }

 private:
  // Propagate() with N = kNumStates or Eigen::Dynamic (TransitionBlocks).
  template <int N>
  bool PropagateBlocks(double t0, double t1, const HeldInput& u, const EkfState& x0,
                       EkfTransition* out);
  // F, G at the midpoint of a sub-step (G with respect to the filter's p).
  template <typename Vector, typename Square, typename ByParameter>
  bool MidpointJacobian(const Vector& x_a, const Vector& x_b, const HeldInput& u, double t_mid,
                        Square* F, ByParameter* G);
  bool Fail(const std::string& why);

  const VehicleModel& model_;
  Eigen::VectorXd theta_;
  std::vector<int> free_indices_;
  Eigen::VectorXd dtheta_dp_;  // d theta_k / d p_k at the current parameters
  const int nx_;  // the model's states
  EkfState state_psd_;
  Eigen::VectorXd parameter_psd_;
  EkfTransitionMethod method_;
  double max_substep_;
  VehicleOde ode_;
  std::unique_ptr<VariationalSystem> variational_;
  std::unique_ptr<Integrator> integrator_;
  // Workspace.
  Eigen::MatrixXd dfdx_, dfdp_;
  Eigen::VectorXd z_;
  Counters counters_;
  std::string error_;
};

// The zero-order-hold transition of the linear system
//   d/dt [x; p] = [[F, G], [0, 0]] [x; p] + w,  E[w w^T] = diag(qx, qp) delta,
// over h: A = exp(F h), B = (int_0^h exp(F s) ds) G and the blocks of Qd
// (series above, with scaling and squaring).
template <int N>
void ZeroOrderTransition(const typename TransitionBlocks<N>::Square& F,
                         const typename TransitionBlocks<N>::ByParameter& G,
                         const typename TransitionBlocks<N>::Vector& qx, const Eigen::VectorXd& qp,
                         double h, TransitionBlocks<N>* out);
inline void ZeroOrderTransition(const StateMatrix& F, const StateByParameter& G,
                                const EkfState& qx, const Eigen::VectorXd& qp, double h,
                                EkfTransition* out) {
  ZeroOrderTransition<Eigen::Dynamic>(F, G, qx, qp, h, out);
}

// The 15 flight outputs (dynamics/outputs.h) at (x, u at its row's time) and, if H is not
// null, their Jacobian with respect to z = [x; p] (15 x (nx + np);
// dtheta_dp: d theta_k / d p_k), by autodiff of FlightOutputs. Without a
// measurement effect (VehicleModel::ChangesFlightMeasurements) the state
// channels' rows are unit vectors, and the filter uses them as such. Returns
// false if a value is not finite.
bool FlightOutputsAndJacobian(const VehicleModel& model, const Eigen::VectorXd& theta,
                              const std::vector<int>& free_indices,
                              const Eigen::VectorXd& dtheta_dp, const EkfState& x,
                              const HeldInput& u,
                              Eigen::Matrix<double, kNumFlightChannels, 1>* y,
                              Eigen::Matrix<double, kNumFlightChannels, Eigen::Dynamic>* H);

}  // namespace coaxid
