#include "dynamics/variational_system.h"

namespace coaxid {

VariationalSystem::VariationalSystem(const OdeSystem& base, bool wrt_initial_state,
                                     bool wrt_parameters)
    : base_(base),
      n_(base.NumStates()),
      p_(wrt_parameters ? base.NumSensitivityParameters() : 0),
      state_columns_(wrt_initial_state ? base.NumStates() : 0),
      columns_(state_columns_ + p_),
      dfdx_(Eigen::MatrixXd::Zero(n_, n_)),
      dfdp_(Eigen::MatrixXd::Zero(n_, p_)) {}

bool VariationalSystem::Rhs(double t, const double* z, double* zdot) const {
  if (!base_.Rhs(t, z, zdot)) return false;
  if (!base_.Jacobians(t, z, &dfdx_, p_ > 0 ? &dfdp_ : nullptr)) return false;
  const Eigen::Map<const Eigen::MatrixXd> S(z + n_, n_, columns_);
  Eigen::Map<Eigen::MatrixXd> Sdot(zdot + n_, n_, columns_);
  Sdot.noalias() = dfdx_ * S;
  if (p_ > 0) Sdot.rightCols(p_) += dfdp_;
  return true;
}

}  // namespace coaxid
