#include "ident/ekf/identifiability.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <glog/logging.h>

#include "dynamics/model_jacobian.h"
#include "ident/ekf/model.h"

namespace coaxid {
namespace {

// The invariance is exact algebra (moments and inertias scale together), so
// its residual is at round-off level; anything above this is a real change.
constexpr double kInvarianceTolerance = 1e-9;

}  // namespace

ScaleDirection FindScaleDirection(const VehicleModel& model, const ParameterSet& parameters,
                                  const std::vector<ModelSample>& samples) {
  CHECK(!samples.empty());
  const Eigen::VectorXd theta = parameters.Values();
  std::vector<int> candidates;
  for (int i = kAlpha; i < parameters.size(); ++i) candidates.push_back(i);
  const int nc = static_cast<int>(candidates.size());
  const int rows_per_sample = kNumStates + 3;
  Eigen::MatrixXd J(rows_per_sample * samples.size(), nc);
  Eigen::MatrixXd dfdx, dfdp;
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(nc);
  for (size_t s = 0; s < samples.size(); ++s) {
    ScaleDirection none;
    none.direction = Eigen::VectorXd::Zero(theta.size());
    if (!DerivativeJacobians(model, theta, samples[s].x.data(), samples[s].u, candidates, &dfdx,
                             &dfdp)) {
      return none;
    }
    Eigen::Matrix<double, kNumFlightChannels, 1> y;
    Eigen::Matrix<double, 3, Eigen::Dynamic> H;
    if (!FlightOutputsAndJacobian(model, theta, candidates, ones, samples[s].x, samples[s].u, &y,
                                  &H)) {
      return none;
    }
    J.block(s * rows_per_sample, 0, kNumStates, nc) = dfdp;
    J.block(s * rows_per_sample + kNumStates, 0, 3, nc) = H.rightCols(nc);
  }
  ScaleDirection out;
  out.direction = Eigen::VectorXd::Zero(theta.size());
  const int base_group[] = {kGamma1, kGamma2, kHubDistance, kIxx, kIyy, kIzz};
  Eigen::VectorXd r = Eigen::VectorXd::Zero(J.rows());
  double size = 0;
  for (int i : base_group) {
    const Eigen::VectorXd term = theta[i] * J.col(i - kAlpha);
    r += term;
    size += term.norm();
    out.direction[i] = theta[i];
  }
  // Effect parameters: min |r + E b|.
  const int ne = parameters.size() - kNumBaseParameters;
  if (ne > 0) {
    const Eigen::MatrixXd E = J.rightCols(ne);
    const Eigen::VectorXd b = E.completeOrthogonalDecomposition().solve(-r);
    r += E * b;
    for (int e = 0; e < ne; ++e) {
      // Keep only coefficients that change something.
      if (std::fabs(b[e]) * E.col(e).norm() > kInvarianceTolerance * size) {
        out.direction[kNumBaseParameters + e] = b[e];
      }
    }
  }
  out.residual = size > 0 ? r.norm() / size : 1.0;
  out.exists = out.residual < kInvarianceTolerance;
  if (!out.exists) out.direction.setZero();
  for (int i = 0; i < theta.size(); ++i) {
    if (out.direction[i] != 0) out.group.push_back(i);
  }
  return out;
}

std::vector<UndeterminedDirection> FindUndeterminedDirections(
    const Eigen::MatrixXd& prior, const Eigen::MatrixXd& posterior, double threshold,
    const Eigen::VectorXd& scale_scaled) {
  std::vector<UndeterminedDirection> out;
  const int np = static_cast<int>(prior.rows());
  if (np == 0) return out;
  const Eigen::LLT<Eigen::MatrixXd> llt(prior);
  CHECK(llt.info() == Eigen::Success) << "prior parameter covariance not positive definite";
  const Eigen::MatrixXd L = llt.matrixL();
  // M = L^{-1} P L^{-T}: symmetric, eigenvalues = the generalised ones.
  Eigen::MatrixXd M = L.triangularView<Eigen::Lower>().solve(posterior);
  M = L.triangularView<Eigen::Lower>().solve(M.transpose().eval());
  M = 0.5 * (M + M.transpose()).eval();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
  for (int j = np - 1; j >= 0; --j) {
    const double lambda = eig.eigenvalues()[j];
    if (!(lambda > threshold)) break;
    UndeterminedDirection d;
    d.variance_ratio = lambda;
    d.direction = L * eig.eigenvectors().col(j);
    d.direction.normalize();
    int largest;
    d.direction.cwiseAbs().maxCoeff(&largest);
    if (d.direction[largest] < 0) d.direction = -d.direction;
    d.cos_to_scale = std::numeric_limits<double>::quiet_NaN();
    if (scale_scaled.size() == np && scale_scaled.norm() > 0) {
      d.cos_to_scale = std::fabs(d.direction.dot(scale_scaled)) / scale_scaled.norm();
    }
    out.push_back(d);
  }
  return out;
}

std::vector<ScaleRatio> ScaleRatios(const ScaleDirection& scale, const ParameterSet& parameters,
                                    const std::vector<int>& free_indices,
                                    const Eigen::VectorXd& scales,
                                    const Eigen::MatrixXd& covariance) {
  std::vector<ScaleRatio> out;
  if (!scale.exists || scale.group.size() < 2) return out;
  int ref = scale.group.front();
  for (int i : scale.group) {
    if (i == kHubDistance) ref = i;
  }
  auto free_position = [&](int theta_index) {
    for (size_t k = 0; k < free_indices.size(); ++k) {
      if (free_indices[k] == theta_index) return static_cast<int>(k);
    }
    return -1;
  };
  const double ref_value = parameters[ref].value;
  if (ref_value == 0) return out;
  for (int i : scale.group) {
    if (i == ref) continue;
    ScaleRatio r;
    r.name = parameters[i].name + "/" + parameters[ref].name;
    r.numerator = i;
    r.denominator = ref;
    r.value = parameters[i].value / ref_value;
    // Gradient with respect to the scaled free parameters.
    Eigen::VectorXd g = Eigen::VectorXd::Zero(free_indices.size());
    const int ki = free_position(i), kr = free_position(ref);
    if (ki >= 0) g[ki] = scales[ki] / ref_value;
    if (kr >= 0) g[kr] = -parameters[i].value * scales[kr] / (ref_value * ref_value);
    r.std = g.size() > 0 ? std::sqrt(std::max(0.0, g.dot(covariance * g))) : 0.0;
    out.push_back(r);
  }
  return out;
}

}  // namespace coaxid
