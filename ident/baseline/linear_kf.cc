#include "ident/baseline/linear_kf.h"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <cmath>
#include <string>
#include <vector>

namespace coaxid {
namespace {

constexpr int kM = kNumEstimationChannels;
using OutputMatrix = Eigen::Matrix<double, kM, kNumTheta>;  // whitened, scaled X_k rows
using OutputVector = Eigen::Matrix<double, kM, 1>;

// Checks the noise std of every estimation channel that has samples.
bool NoiseStds(const WeightedBalanceData& d, OutputVector* std_dev, std::string* why) {
  for (int r = 0; r < kM; ++r) {
    const int c = kEstimationChannels[r];
    const double v = d.variance[c];
    bool has_samples = false;
    for (const BalanceHold& hold : d.data->holds) has_samples = has_samples || hold.count[c] > 0;
    if (has_samples && !(v > 0 && std::isfinite(v))) {
      *why = d.data->source + ": channel " + LoadChannelName(c) +
             " has samples but noise variance " + std::to_string(v) +
             " (must be positive and finite)";
      return false;
    }
    (*std_dev)[r] = has_samples ? std::sqrt(v) : 1.0;
  }
  return true;
}

// The whitened, scaled model at a hold: H row r = X_k(channel r) .* scale / std_r,
// and the offsets of eq. 69 (Z_bar = Z - sigma alpha w1).
void HoldModel(const LinearBalanceModel& model, const InputVector& input, const ThetaVector& scale,
               const OutputVector& std_dev, OutputMatrix* H, OutputVector* offset) {
  const LinearizedLoads lin = model.Linearize(input);
  for (int r = 0; r < kM; ++r) {
    const int c = kEstimationChannels[r];
    H->row(r) = lin.X.row(c).cwiseProduct(scale.transpose()) / std_dev[r];
    (*offset)[r] = lin.offset[c];
  }
}

// Row k's whitened outputs; a missing output gets a zero row of H and z = 0,
// which removes it from the update exactly. Returns false if every output is missing.
bool RowOutputs(const BalanceData& data, int k, const OutputMatrix& H_hold,
                const OutputVector& offset, const OutputVector& std_dev, OutputMatrix* H,
                OutputVector* z) {
  bool any = false;
  *H = H_hold;
  for (int r = 0; r < kM; ++r) {
    const double v = data.loads[kEstimationChannels[r]][k];
    if (std::isnan(v)) {
      H->row(r).setZero();
      (*z)[r] = 0;
    } else {
      (*z)[r] = (v - offset[r]) / std_dev[r];
      any = true;
    }
  }
  return any;
}

}  // namespace

bool LinearKfOptions::IsValid(std::string* why) const {
  for (int i = 0; i < kNumTheta; ++i) {
    if (!(scale[i] > 0 && std::isfinite(scale[i]))) {
      return *why = std::string("scale of ") + ThetaName(i) + " must be positive", false;
    }
    if (!std::isfinite(initial[i])) {
      return *why = std::string("initial value of ") + ThetaName(i) + " is not finite", false;
    }
  }
  if (!(prior_std > 0)) return *why = "prior_std must be > 0", false;
  if (!(process_noise >= 0 && std::isfinite(process_noise))) {
    return *why = "process_noise must be finite and >= 0", false;
  }
  if (history_stride < 1) return *why = "history_stride must be >= 1", false;
  return true;
}

LinearKfSummary RunLinearKf(const LinearBalanceModel& model,
                            const std::vector<WeightedBalanceData>& data,
                            const LinearKfOptions& options) {
  LinearKfSummary summary;
  std::string why;
  if (!options.IsValid(&why) || !std::isfinite(options.prior_std)) {
    summary.message = why.empty() ? "the filter needs a finite prior_std" : why;
    return summary;
  }
  const ThetaVector& scale = options.scale;
  ThetaVector phi = options.initial.cwiseQuotient(scale);  // Theta / scale
  ThetaMatrix P = ThetaMatrix::Identity() * (options.prior_std * options.prior_std);
  const ThetaMatrix Q = ThetaMatrix::Identity() * options.process_noise;
  const ThetaMatrix I = ThetaMatrix::Identity();

  auto record = [&](int i, int k) {
    LinearKfHistory& h = summary.history;
    h.data_index.push_back(i);
    h.row.push_back(k);
    h.t.push_back(data[i].data->t[k]);
    h.estimate.push_back(phi.cwiseProduct(scale));
    h.trace_scaled.push_back(P.trace());
  };

  int last_i = -1, last_k = -1;
  bool last_recorded = false;
  for (int i = 0; i < static_cast<int>(data.size()); ++i) {
    const BalanceData& d = *data[i].data;
    OutputVector std_dev;
    if (!NoiseStds(data[i], &std_dev, &summary.message)) return summary;
    for (const BalanceHold& hold : d.holds) {
      OutputMatrix H_hold, H;
      OutputVector offset, z;
      HoldModel(model, hold.input, scale, std_dev, &H_hold, &offset);
      for (int k = hold.first_row; k < hold.first_row + hold.num_rows; ++k) {
        if (!RowOutputs(d, k, H_hold, offset, std_dev, &H, &z)) {
          ++summary.skipped_rows;
          continue;
        }
        // Eq. 80: K = P H^T S^-1 with S = H P H^T + R (R = I after whitening);
        // K^T = S^-1 (H P) by a Cholesky solve.
        const Eigen::Matrix<double, kM, kNumTheta> HP = H * P;
        const Eigen::Matrix<double, kM, kM> S =
            HP * H.transpose() + Eigen::Matrix<double, kM, kM>::Identity();
        const Eigen::LLT<Eigen::Matrix<double, kM, kM>> llt(S);
        if (llt.info() != Eigen::Success) {
          summary.message = "innovation covariance not positive definite at " + d.source + " row " +
                            std::to_string(k + 1);
          return summary;
        }
        const Eigen::Matrix<double, kNumTheta, kM> K = llt.solve(HP).transpose();
        phi += K * (z - H * phi);           // eq. 81
        const ThetaMatrix IKH = I - K * H;  // eq. 82, Joseph form
        P = IKH * P * IKH.transpose() + K * K.transpose() + Q;
        P = 0.5 * (P + P.transpose());
        ++summary.updates;
        last_i = i;
        last_k = k;
        last_recorded = summary.updates % options.history_stride == 0;
        if (last_recorded) record(i, k);
      }
    }
  }
  if (summary.updates == 0) {
    summary.message = "no sample with any of the outputs Z, L, M, N";
    return summary;
  }
  if (!last_recorded) record(last_i, last_k);
  summary.estimate = phi.cwiseProduct(scale);
  summary.covariance = scale.asDiagonal() * P * scale.asDiagonal();
  summary.covariance = 0.5 * (summary.covariance + summary.covariance.transpose()).eval();
  summary.usable = summary.estimate.allFinite() && summary.covariance.allFinite() &&
                   (summary.covariance.diagonal().array() > 0).all();
  if (!summary.usable) summary.message = "the filter's estimate or covariance is not finite";
  return summary;
}

BatchLeastSquaresSummary SolveBatchLeastSquares(const LinearBalanceModel& model,
                                                const std::vector<WeightedBalanceData>& data,
                                                const LinearKfOptions& options) {
  BatchLeastSquaresSummary summary;
  std::string why;
  if (!options.IsValid(&why)) {
    summary.message = why;
    return summary;
  }
  const ThetaVector& scale = options.scale;
  constexpr int kCols = kNumTheta + 1;  // [H | z]
  constexpr int kBlockRows = 1024;
  using Augmented = Eigen::Matrix<double, Eigen::Dynamic, kCols>;
  // Rows kept between blocks: the triangular factor of everything so far.
  Eigen::Matrix<double, kCols, kCols> R_aug = Eigen::Matrix<double, kCols, kCols>::Zero();
  if (std::isfinite(options.prior_std)) {
    // Prior rows (Theta_i/scale_i - Theta0_i/scale_i) / prior_std.
    for (int i = 0; i < kNumTheta; ++i) {
      R_aug(i, i) = 1.0 / options.prior_std;
      R_aug(i, kNumTheta) = options.initial[i] / scale[i] / options.prior_std;
    }
  }
  Augmented block(kCols + kBlockRows * kM, kCols);
  int used = kCols;
  auto flush = [&]() {
    block.topRows(kCols) = R_aug;
    const Eigen::HouseholderQR<Augmented> qr(block.topRows(used));
    R_aug = qr.matrixQR().topRows(kCols).triangularView<Eigen::Upper>();
    used = kCols;
  };
  for (const WeightedBalanceData& wd : data) {
    OutputVector std_dev;
    if (!NoiseStds(wd, &std_dev, &summary.message)) return summary;
    const BalanceData& d = *wd.data;
    for (const BalanceHold& hold : d.holds) {
      OutputMatrix H_hold, H;
      OutputVector offset, z;
      HoldModel(model, hold.input, scale, std_dev, &H_hold, &offset);
      for (int k = hold.first_row; k < hold.first_row + hold.num_rows; ++k) {
        for (int r = 0; r < kM; ++r) {
          const double v = d.loads[kEstimationChannels[r]][k];
          if (std::isnan(v)) continue;
          block.row(used).head<kNumTheta>() = H_hold.row(r);
          block(used, kNumTheta) = (v - offset[r]) / std_dev[r];
          ++used;
          ++summary.observations;
        }
        if (used > kCols + (kBlockRows - 1) * kM) flush();
      }
    }
  }
  if (used > kCols) flush();
  const Eigen::Matrix<double, kNumTheta, kNumTheta> R = R_aug.topLeftCorner<kNumTheta, kNumTheta>();
  // Rank: Householder QR of a rank-deficient matrix leaves a (near) zero on
  // R's diagonal.
  const ThetaVector diagonal = R.diagonal().cwiseAbs();
  if (!(diagonal.minCoeff() > 1e-13 * diagonal.maxCoeff())) {
    summary.message = "the least-squares problem is rank deficient (|R_ii| from " +
                      std::to_string(diagonal.minCoeff()) + " to " +
                      std::to_string(diagonal.maxCoeff()) + ")";
    return summary;
  }
  const auto upper = R.triangularView<Eigen::Upper>();
  const ThetaVector phi = upper.solve(R_aug.topRightCorner<kNumTheta, 1>());
  // Covariance (R^T R)^-1 = R^-1 R^-T, from triangular solves.
  const ThetaMatrix R_inv = upper.solve(ThetaMatrix::Identity());
  const ThetaMatrix cov_scaled = R_inv * R_inv.transpose();
  summary.estimate = phi.cwiseProduct(scale);
  summary.covariance = scale.asDiagonal() * cov_scaled * scale.asDiagonal();
  summary.covariance = 0.5 * (summary.covariance + summary.covariance.transpose()).eval();
  summary.weighted_rss = R_aug(kNumTheta, kNumTheta) * R_aug(kNumTheta, kNumTheta);
  summary.usable = summary.estimate.allFinite() && summary.covariance.allFinite();
  if (!summary.usable) summary.message = "the least-squares solution is not finite";
  return summary;
}

}  // namespace coaxid
