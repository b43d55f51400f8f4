#include "ident/identifiability.h"

#include <algorithm>
#include <cmath>
#include <set>

#include <Eigen/Eigenvalues>
#include <glog/logging.h>

namespace coaxid {
namespace {

// Parameters that scale together with one common factor leave every flight
// output unchanged (model.md, decision 8).
bool IsMomentScaleParameter(const std::string& name) {
  static const std::set<std::string> base = {"d", "gamma1", "gamma2", "Ixx", "Iyy", "Izz"};
  if (base.count(name)) return true;
  // Moment-type effect parameters scale with them.
  static const std::set<std::string> effects = {"gyroscopic.J_r", "rotor_damping.k_pq",
                                                "cg_offset.x_g", "cg_offset.y_g",
                                                "wake_interference.k_Q"};
  return effects.count(name) > 0;
}

std::string Explain(const std::vector<std::string>& group) {
  std::string list;
  for (const auto& n : group) list += (list.empty() ? "" : ", ") + n;
  const bool moment_scale =
      std::all_of(group.begin(), group.end(), IsMomentScaleParameter) && group.size() >= 2;
  if (moment_scale) {
    return list + ": only their ratios (such as d*beta/Ixx, gamma1/Izz, Iyy/Ixx) are determined "
                  "by these logs: scaling them together leaves every flight output unchanged "
                  "(model.md, decision 8). A balance log of the same vehicle fixes the scale.";
  }
  if (group.size() == 1) {
    return list + ": these logs carry no information on it (its effect on the outputs is nil or "
                  "exactly absorbed by other parameters).";
  }
  return list + ": these parameters move together along a direction the logs do not see; only "
                "combinations independent of it are identifiable.";
}

}  // namespace

IdentifiabilityReport AnalyzeIdentifiability(const Eigen::MatrixXd& information_scaled,
                                             const std::vector<std::string>& names,
                                             const Eigen::VectorXd& scales,
                                             double relative_threshold) {
  const int P = static_cast<int>(names.size());
  CHECK_EQ(information_scaled.rows(), P);
  CHECK_EQ(scales.size(), P);
  IdentifiabilityReport report;
  report.names = names;
  const Eigen::MatrixXd sym = 0.5 * (information_scaled + information_scaled.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(sym);
  // Descending order.
  const Eigen::VectorXd values = eig.eigenvalues().reverse();
  const Eigen::MatrixXd vectors = eig.eigenvectors().rowwise().reverse();
  report.eigenvalues = values;
  const double largest = std::max(values.size() > 0 ? values[0] : 0.0, 0.0);

  report.identifiable.assign(P, true);
  Eigen::MatrixXd cov_scaled = Eigen::MatrixXd::Zero(P, P);
  double smallest_kept = largest;
  for (int i = 0; i < P; ++i) {
    const double rel = largest > 0 ? values[i] / largest : 0.0;
    if (rel > relative_threshold) {
      cov_scaled += vectors.col(i) * vectors.col(i).transpose() / values[i];
      smallest_kept = values[i];
      continue;
    }
    NullDirection null;
    null.relative_eigenvalue = rel;
    const Eigen::VectorXd v = vectors.col(i);
    for (int k = 0; k < P; ++k) {
      // A share above 5 % of the unit direction marks a parameter as involved.
      if (std::fabs(v[k]) > 0.05) {
        null.parameters.push_back(names[k]);
        null.components.push_back(v[k]);
        report.identifiable[k] = false;
      }
    }
    null.explanation = Explain(null.parameters);
    report.null_directions.push_back(null);
  }
  report.condition_number = smallest_kept > 0 ? largest / smallest_kept : INFINITY;
  const Eigen::MatrixXd S = scales.asDiagonal();
  report.SetCovariance(S * cov_scaled * S);
  return report;
}

void IdentifiabilityReport::SetCovariance(const Eigen::MatrixXd& new_covariance) {
  const int P = static_cast<int>(names.size());
  CHECK(new_covariance.rows() == P && new_covariance.cols() == P);
  covariance = new_covariance;
  std.resize(P);
  correlation = Eigen::MatrixXd::Constant(P, P, NAN);
  for (int k = 0; k < P; ++k) {
    std[k] = identifiable[k] ? std::sqrt(std::max(covariance(k, k), 0.0)) : NAN;
  }
  for (int a = 0; a < P; ++a) {
    for (int b = 0; b < P; ++b) {
      if (identifiable[a] && identifiable[b] && std[a] > 0 && std[b] > 0) {
        correlation(a, b) = covariance(a, b) / (std[a] * std[b]);
      }
    }
  }
}

nlohmann::json IdentifiabilityReport::ToJson() const {
  nlohmann::json out;
  out["eigenvalues_scaled_information"] = std::vector<double>(eigenvalues.data(),
                                                              eigenvalues.data() + eigenvalues.size());
  out["condition_number"] = condition_number;
  nlohmann::json nulls = nlohmann::json::array();
  for (const NullDirection& n : null_directions) {
    nulls.push_back({{"relative_eigenvalue", n.relative_eigenvalue},
                     {"parameters", n.parameters},
                     {"components", n.components},
                     {"explanation", n.explanation}});
  }
  out["not_identifiable"] = nulls;
  out["verdict"] = null_directions.empty()
                       ? "every estimated parameter is identifiable from these logs"
                       : "some parameters are not separately identifiable from these logs";
  nlohmann::json corr = nlohmann::json::object();
  for (size_t a = 0; a < names.size(); ++a) {
    nlohmann::json row = nlohmann::json::object();
    for (size_t b = 0; b < names.size(); ++b) {
      const double c = correlation(a, b);
      row[names[b]] = std::isfinite(c) ? nlohmann::json(c) : nlohmann::json(nullptr);
    }
    corr[names[a]] = row;
  }
  out["correlation"] = corr;
  return out;
}

}  // namespace coaxid
