#include "ident/baseline/map_uncertainty.h"

#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <vector>

namespace coaxid {

PsiMatrix PropagateMapUncertainty(const LinearBalanceModel& model,
                                  const std::vector<WeightedBalanceData>& data,
                                  const ThrustMap& map, const ThetaVector& theta,
                                  const ThetaMatrix& filter_covariance,
                                  const LinearKfOptions& options) {
  const ThetaVector& s = options.scale;
  const int cells = static_cast<int>(map.table.sigma.size());
  CHECK(!model.sigma.empty()) << "the propagation needs the sigma map";
  CHECK_EQ(static_cast<int>(model.sigma.sigma.size()), cells);

  // One pass over the holds: the scaled information matrix A~ = S A S, the
  // sigma sensitivities G (S times db/ds - dA/ds Theta, per table cell) and
  // alpha's direct one (Z_bar = Z - sigma alpha w1).
  ThetaMatrix A = ThetaMatrix::Zero();
  if (std::isfinite(options.prior_std)) {
    A.diagonal().setConstant(1.0 / (options.prior_std * options.prior_std));
  }
  Eigen::Matrix<double, kNumTheta, Eigen::Dynamic> G =
      Eigen::Matrix<double, kNumTheta, Eigen::Dynamic>::Zero(kNumTheta, cells);
  ThetaVector v_alpha = ThetaVector::Zero();
  for (const WeightedBalanceData& wd : data) {
    for (const BalanceHold& hold : wd.data->holds) {
      const LinearizedLoads lin = model.Linearize(hold.input);
      for (const int c : kEstimationChannels) {
        const int n = hold.count[c];
        if (n == 0) continue;
        const ThetaVector xs = lin.X.row(c).transpose().cwiseProduct(s);
        A += (n / wd.variance[c]) * xs * xs.transpose();
      }
      const int n = hold.count[kLoadZ];
      if (n == 0) continue;
      const double R = wd.variance[kLoadZ];
      const double w1 = hold.input[0] * hold.input[0];
      const ThetaVector x = lin.X.row(kLoadZ).transpose();  // sigma h
      // Sum over the hold's samples of the derivative with respect to this
      // sample's sigma (see the header); r_bar the mean residual of Z_bar.
      const double r_bar = hold.mean[kLoadZ] - lin.offset[kLoadZ] - x.dot(theta);
      if (lin.sigma != 0) {
        const ThetaVector h = x / lin.sigma;
        const ThetaVector g = (n / R) * h * (r_bar - lin.sigma * (model.alpha * w1 + h.dot(theta)));
        const SigmaCellWeights w = SigmaWeights(model.sigma, hold.input[0], hold.input[1]);
        for (int j = 0; j < 4; ++j) {
          if (w.weight[j] != 0) G.col(w.cell[j]) += w.weight[j] * g.cwiseProduct(s);
        }
      }
      v_alpha += (n / R) * x * (-lin.sigma * w1);
    }
  }
  const Eigen::LLT<ThetaMatrix> llt(A);
  CHECK(llt.info() == Eigen::Success) << "information matrix not positive definite";
  // Physical dTheta/dq = S A~^-1 (scaled vector).
  auto solve = [&](const ThetaVector& scaled) -> ThetaVector {
    return llt.solve(scaled).cwiseProduct(s);
  };
  const Eigen::Matrix<double, kNumTheta, Eigen::Dynamic> dtheta_dcell =
      s.asDiagonal() * llt.solve(G);

  // Total derivatives through the map (filled cells depend on sigma0).
  ThetaVector dtheta_dsigma0 = ThetaVector::Zero();
  for (int c = 0; c < cells; ++c) dtheta_dsigma0 += dtheta_dcell.col(c) * map.dcell_dsigma0[c];
  ThetaVector dtheta_dalpha = solve(v_alpha.cwiseProduct(s));
  ThetaVector dtheta_dbeta = ThetaVector::Zero();
  for (int c = 0; c < cells; ++c) {
    dtheta_dalpha += dtheta_dcell.col(c) * map.dcell_dalpha[c];
    dtheta_dbeta += dtheta_dcell.col(c) * map.dcell_dbeta[c];
  }
  dtheta_dalpha += dtheta_dsigma0 * map.dsigma0_dalpha;
  dtheta_dbeta += dtheta_dsigma0 * map.dsigma0_dbeta;

  PsiMatrix cov = PsiMatrix::Zero();
  cov.topLeftCorner<kNumTheta, kNumTheta>() = filter_covariance;
  for (const MapHold& m : map.holds) {
    if (m.role == MapHoldRole::kStopped || m.count == 0) continue;
    PsiVector dm = PsiVector::Zero();
    switch (m.role) {
      case MapHoldRole::kUpperOnly:
        dm.head<kNumTheta>() = dtheta_dalpha * m.d_dZ;
        dm[kPsiAlpha] = m.d_dZ;
        break;
      case MapHoldRole::kLowerOnly:
        dm.head<kNumTheta>() = dtheta_dbeta * m.d_dZ;
        break;
      case MapHoldRole::kCoaxial:
        dm.head<kNumTheta>() = dtheta_dcell.col(m.cell) * m.d_dZ + dtheta_dsigma0 * m.dsigma0_dZ;
        break;
      case MapHoldRole::kStopped:
        break;
    }
    const WeightedBalanceData& wd = data[m.data_index];
    const BalanceHold& hold = wd.data->holds[m.hold_index];
    const LinearizedLoads lin = model.Linearize(hold.input);
    PsiVector u = PsiVector::Zero();
    u.head<kNumTheta>() = solve(lin.X.row(kLoadZ).transpose().cwiseProduct(s));
    cov += u * dm.transpose() + dm * u.transpose() +
           (wd.variance[kLoadZ] / m.count) * dm * dm.transpose();
  }
  return 0.5 * (cov + cov.transpose());
}

}  // namespace coaxid
