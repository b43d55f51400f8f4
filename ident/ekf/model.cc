#include "ident/ekf/model.h"

#include <algorithm>
#include <cmath>

#include <ceres/jet.h>
#include <glog/logging.h>

#include "dynamics/model_jacobian.h"

namespace coaxid {
namespace {

// After scaling, |F h|_1 <= this; the 5th-order Taylor series of exp and of
// phi1(X) = (exp(X) - I) / X then truncates at X^6 / 720 < 4e-7.
constexpr double kMaxScaledNorm = 0.25;

// Composes the accumulated transition (A, B, Qxx, Qxp) with one more sub-step
// (a, b, qxx, qxp): Phi <- Phi_j Phi, Qd <- Phi_j Qd Phi_j^T + Qd_j, where the
// accumulated Qpp (diagonal, qpp_acc) is needed for the cross terms.
template <int N>
void Compose(const typename TransitionBlocks<N>::Square& a,
             const typename TransitionBlocks<N>::ByParameter& b,
             const typename TransitionBlocks<N>::Square& qxx,
             const typename TransitionBlocks<N>::ByParameter& qxp, const Eigen::VectorXd& qpp_acc,
             TransitionBlocks<N>* acc) {
  using Square = typename TransitionBlocks<N>::Square;
  using ByParameter = typename TransitionBlocks<N>::ByParameter;
  // Qd first (it needs the old blocks).
  const ByParameter AQxp = a.lazyProduct(acc->Qxp);  // nx x np
  Square Qxx = a * acc->Qxx * a.transpose();
  if (b.cols() > 0) {
    const Square cross = AQxp.lazyProduct(b.transpose());
    Qxx += cross + cross.transpose();
    Qxx.noalias() += (b * qpp_acc.asDiagonal()).lazyProduct(b.transpose());
  }
  acc->Qxx = Qxx + qxx;
  acc->Qxp = AQxp + b * qpp_acc.asDiagonal();
  acc->Qxp += qxp;
  acc->B = (a.lazyProduct(acc->B) + b).eval();  // lazy products do not guard aliasing
  acc->A = a * acc->A;
}

}  // namespace

template <int N>
void ZeroOrderTransition(const typename TransitionBlocks<N>::Square& F,
                         const typename TransitionBlocks<N>::ByParameter& G,
                         const typename TransitionBlocks<N>::Vector& qx, const Eigen::VectorXd& qp,
                         double h, TransitionBlocks<N>* out) {
  using StateMatrix = typename TransitionBlocks<N>::Square;
  using StateByParameter = typename TransitionBlocks<N>::ByParameter;
  const int nx = static_cast<int>(F.rows());
  const int np = static_cast<int>(G.cols());
  const double norm = (F * h).cwiseAbs().colwise().sum().maxCoeff();
  int squarings = 0;
  if (norm > kMaxScaledNorm) squarings = static_cast<int>(std::ceil(std::log2(norm / kMaxScaledNorm)));
  const double hs = std::ldexp(h, -squarings);
  // exp([[F, G], [0, 0]] hs) = [[exp(X), hs phi1(X) G], [0, I]], X = F hs,
  // phi1(X) = I + X/2! + X^2/3! + ... (Horner, to X^5).
  const StateMatrix X = F * hs;
  const StateMatrix I = StateMatrix::Identity(nx, nx);
  const StateMatrix phi1 = I + X / 2 * (I + X / 3 * (I + X / 4 * (I + X / 5 * (I + X / 6))));
  StateMatrix A = I + X * phi1;
  StateByParameter B = hs * phi1.lazyProduct(G);
  // Qd over hs (series in the header comment): with X = F,
  //   Qx part: sum_k hs^(k+1)/(k+1)! sum_{i+j=k} C(k,i) F^i qx F^T^j,  k = 0..3,
  //   M part:  sum_{i,j} hs^(i+j+3) / ((i+j+3) (i+1)! (j+1)!) F^i M F^T^j,  i+j <= 2,
  //   Qxp:     sum_i hs^(i+2)/(i+2)! F^i G qp,  i = 0..3.
  const double h2 = hs * hs, h3 = h2 * hs, h4 = h3 * hs, h5 = h4 * hs;
  const StateMatrix FQ = F * qx.asDiagonal();
  const StateMatrix F2Q = F * FQ, F3Q = F * F2Q;
  const StateMatrix FQFt = FQ * F.transpose(), F2QFt = F2Q * F.transpose();
  StateMatrix Qxx = StateMatrix(qx.asDiagonal()) * hs;
  Qxx += (FQ + FQ.transpose()) * (h2 / 2);
  Qxx += (F2Q + F2Q.transpose() + 2 * FQFt) * (h3 / 6);
  Qxx += (F3Q + F3Q.transpose() + 3 * (F2QFt + F2QFt.transpose())) * (h4 / 24);
  StateByParameter Qxp(nx, np);
  if (np > 0) {
    const StateByParameter Gq = G * qp.asDiagonal();
    const StateMatrix M = Gq.lazyProduct(G.transpose());
    const StateMatrix FM = F * M;
    const StateMatrix F2M = F * FM;
    Qxx += M * (h3 / 3) + (FM + FM.transpose()) * (h4 / 8);
    Qxx += FM * F.transpose() * (h5 / 20) + (F2M + F2M.transpose()) * (h5 / 30);
    const StateByParameter FGq = F.lazyProduct(Gq), F2Gq = F.lazyProduct(FGq);
    Qxp = (h2 / 2) * Gq + (h3 / 6) * FGq + (h4 / 24) * F2Gq + (h5 / 120) * F.lazyProduct(F2Gq);
  }
  out->A = A;
  out->B = B;
  out->Qxx = 0.5 * (Qxx + Qxx.transpose());
  out->Qxp = Qxp;
  // Squaring: the transition over 2 hs is this one twice.
  Eigen::VectorXd qpp = hs * qp;
  for (int s = 0; s < squarings; ++s) {
    const TransitionBlocks<N> half = *out;
    Compose<N>(half.A, half.B, half.Qxx, half.Qxp, qpp, out);
    qpp *= 2;
  }
}
template void ZeroOrderTransition<kNumStates>(const TransitionBlocks<kNumStates>::Square&,
                                              const TransitionBlocks<kNumStates>::ByParameter&,
                                              const TransitionBlocks<kNumStates>::Vector&,
                                              const Eigen::VectorXd&, double,
                                              TransitionBlocks<kNumStates>*);
template void ZeroOrderTransition<Eigen::Dynamic>(const StateMatrix&, const StateByParameter&,
                                                  const EkfState&, const Eigen::VectorXd&, double,
                                                  EkfTransition*);

const char* EkfTransitionMethodName(EkfTransitionMethod method) {
  return method == EkfTransitionMethod::kLinearised ? "linearised" : "sensitivities";
}

EkfPropagator::EkfPropagator(const VehicleModel& model, const Eigen::VectorXd& theta,
                             std::vector<int> free_indices, Eigen::VectorXd dtheta_dp,
                             const EkfState& state_psd,
                             Eigen::VectorXd parameter_psd, EkfTransitionMethod method,
                             const IntegratorOptions& integrator, double max_substep_s)
    : model_(model),
      theta_(theta),
      free_indices_(std::move(free_indices)),
      dtheta_dp_(std::move(dtheta_dp)),
      nx_(model.NumStates()),
      state_psd_(state_psd),
      parameter_psd_(std::move(parameter_psd)),
      method_(method),
      max_substep_(max_substep_s),
      ode_(model, theta, free_indices_) {
  CHECK_EQ(static_cast<int>(free_indices_.size()), dtheta_dp_.size());
  CHECK_EQ(dtheta_dp_.size(), parameter_psd_.size());
  CHECK_GT(max_substep_, 0.0);
  CHECK_EQ(state_psd_.size(), nx_);
  if (method_ == EkfTransitionMethod::kSensitivities) {
    variational_ = std::make_unique<VariationalSystem>(ode_, true, num_parameters() > 0);
    IntegratorOptions options = integrator;
    options.newton = false;  // fixed-point iteration on the augmented system
    if (!options.sensitivity_error_control) options.error_controlled_states = nx_;
    integrator_ = std::make_unique<Integrator>(*variational_, options);
    z_.resize(variational_->NumStates());
  } else {
    integrator_ = std::make_unique<Integrator>(ode_, integrator);
    z_.resize(nx_);
  }
}

void EkfPropagator::SetParameters(const Eigen::VectorXd& free_values,
                                  const Eigen::VectorXd& dtheta_dp) {
  CHECK_EQ(free_values.size(), num_parameters());
  CHECK_EQ(dtheta_dp.size(), num_parameters());
  for (int k = 0; k < num_parameters(); ++k) theta_[free_indices_[k]] = free_values[k];
  dtheta_dp_ = dtheta_dp;
  ode_.SetTheta(theta_);
}

bool EkfPropagator::Fail(const std::string& why) {
  error_ = why;
  return false;
}

template <typename Vector, typename Square, typename ByParameter>
bool EkfPropagator::MidpointJacobian(const Vector& x_a, const Vector& x_b, const HeldInput& u,
                                     double t_mid, Square* F, ByParameter* G) {
  const Vector x_mid = 0.5 * (x_a + x_b);
  ++counters_.jacobians;
  const int np = num_parameters();
  if (!DerivativeJacobians(model_, theta_, x_mid.data(), u, t_mid, free_indices_, &dfdx_,
                           np > 0 ? &dfdp_ : nullptr)) {
    return Fail("model Jacobian not finite");
  }
  *F = dfdx_;
  G->resize(nx_, np);
  if (np > 0) *G = dfdp_ * dtheta_dp_.asDiagonal();
  return true;
}

bool EkfPropagator::Propagate(double t0, double t1, const HeldInput& u, const EkfState& x0,
                              EkfTransition* out) {
  return nx_ == kNumStates ? PropagateBlocks<kNumStates>(t0, t1, u, x0, out)
                           : PropagateBlocks<Eigen::Dynamic>(t0, t1, u, x0, out);
}

template <int N>
bool EkfPropagator::PropagateBlocks(double t0, double t1, const HeldInput& u,
                                    const EkfState& x0_in, EkfTransition* result) {
  using Blocks = TransitionBlocks<N>;
  CHECK(t1 > t0);
  // Fixed-size arithmetic for the 12 states (a copy in and out); with effect
  // states the blocks are the result's own.
  Blocks fixed;
  Blocks* out = &fixed;
  if constexpr (N == Eigen::Dynamic) out = result;
  const typename Blocks::Vector& x0 = x0_in;             // a converted copy only for N = 12
  const typename Blocks::Vector& state_psd = state_psd_;
  ++counters_.intervals;
  const int np = num_parameters();
  const int substeps = std::max(1, static_cast<int>(std::ceil((t1 - t0) / max_substep_ - 1e-9)));
  ode_.SetInput(u);
  out->A.setIdentity(nx_, nx_);
  out->B.setZero(nx_, np);
  out->Qxx.setZero(nx_, nx_);
  out->Qxp.setZero(nx_, np);
  Eigen::VectorXd qpp_acc = Eigen::VectorXd::Zero(np);

  typename Blocks::Vector x_a = x0;
  typename Blocks::Square F(nx_, nx_);
  typename Blocks::ByParameter G(nx_, np);
  Blocks step;
  if (method_ == EkfTransitionMethod::kLinearised) {
    z_ = x0;
    if (!integrator_->Reset(t0, z_)) return Fail(integrator_->last_error());
  }
  for (int j = 0; j < substeps; ++j) {
    const double ta = t0 + (t1 - t0) * j / substeps;
    const double tb = j + 1 == substeps ? t1 : t0 + (t1 - t0) * (j + 1) / substeps;
    const double h = tb - ta;
    ++counters_.substeps;
    typename Blocks::Vector x_b;
    if (method_ == EkfTransitionMethod::kLinearised) {
      if (!integrator_->AdvanceTo(tb, &z_)) return Fail(integrator_->last_error());
      x_b = z_;
      if (!x_b.allFinite()) return Fail("state not finite");
      if (!MidpointJacobian(x_a, x_b, u, 0.5 * (ta + tb), &F, &G)) return false;
      ZeroOrderTransition<N>(F, G, state_psd, parameter_psd_, h, &step);
    } else {
      // [x; vec([I | 0])], restarted at every sub-step so that each gives its own Phi_j.
      z_.setZero();
      z_.head(nx_) = x_a;
      for (int i = 0; i < nx_; ++i) z_[nx_ + i * nx_ + i] = 1.0;
      if (!integrator_->Reset(ta, z_) || !integrator_->AdvanceTo(tb, &z_)) {
        return Fail(integrator_->last_error());
      }
      x_b = z_.head(nx_);
      if (!z_.allFinite()) return Fail("state or sensitivities not finite");
      if (!MidpointJacobian(x_a, x_b, u, 0.5 * (ta + tb), &F, &G)) return false;
      ZeroOrderTransition<N>(F, G, state_psd, parameter_psd_, h, &step);  // for Qd
      const Eigen::Map<const Eigen::MatrixXd> S(z_.data() + nx_, nx_, nx_ + np);
      step.A = S.leftCols(nx_);
      if (np > 0) step.B = S.rightCols(np) * dtheta_dp_.asDiagonal();
    }
    Compose<N>(step.A, step.B, step.Qxx, step.Qxp, qpp_acc, out);
    qpp_acc += h * parameter_psd_;
    x_a = x_b;
  }
  out->x = x_a;
  if (!out->A.allFinite() || !out->B.allFinite() || !out->Qxx.allFinite()) {
    return Fail("state transition matrix not finite");
  }
  if constexpr (N != Eigen::Dynamic) {
    result->x = out->x;
    result->A = out->A;
    result->B = out->B;
    result->Qxx = out->Qxx;
    result->Qxp = out->Qxp;
  }
  return true;
}

bool FlightOutputsAndJacobian(const VehicleModel& model, const Eigen::VectorXd& theta,
                              const std::vector<int>& free_indices,
                              const Eigen::VectorXd& dtheta_dp, const EkfState& x,
                              const HeldInput& u,
                              Eigen::Matrix<double, kNumFlightChannels, 1>* y,
                              Eigen::Matrix<double, kNumFlightChannels, Eigen::Dynamic>* H) {
  FlightOutputsAt(model, theta.data(), x.data(), u, y->data());
  if (!y->allFinite()) return false;
  if (H == nullptr) return true;
  // Derivative directions kChunk at a time (as dynamics/model_jacobian.cc).
  constexpr int kChunk = 16;
  using Jet = ceres::Jet<double, kChunk>;
  const int np = static_cast<int>(free_indices.size());
  const int nx = static_cast<int>(x.size());
  const int directions = nx + np;
  H->resize(kNumFlightChannels, directions);
  std::vector<Jet> theta_jet(theta.size());
  std::vector<Jet> x_jet(nx);
  Jet y_jet[kNumFlightChannels];
  for (int first = 0; first < directions; first += kChunk) {
    for (int i = 0; i < theta.size(); ++i) theta_jet[i] = Jet(theta[i]);
    for (int i = 0; i < nx; ++i) x_jet[i] = Jet(x[i]);
    const int last = std::min(first + kChunk, directions);
    for (int dir = first; dir < last; ++dir) {
      if (dir < nx) {
        x_jet[dir].v[dir - first] = 1.0;
      } else {
        theta_jet[free_indices[dir - nx]].v[dir - first] = dtheta_dp[dir - nx];
      }
    }
    FlightOutputsAt(model, theta_jet.data(), x_jet.data(), u, y_jet);
    for (int row = 0; row < kNumFlightChannels; ++row) {
      for (int dir = first; dir < last; ++dir) (*H)(row, dir) = y_jet[row].v[dir - first];
    }
  }
  return H->allFinite();
}

}  // namespace coaxid
