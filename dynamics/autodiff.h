// Forward-mode automatic differentiation of the one templated model with
// ceres::Jet, a chunk of derivative directions at a time (like Ceres'
// DynamicAutoDiffCostFunction): the only way Jacobians are made in coaxid
// (STYLE.md, item 3). Used for the state derivative (model_jacobian.h) and
// the output models (outputs.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <ceres/jet.h>

namespace coaxid {

// Directions per pass, measured with bench/dynamics/model_bench.cc (Jacobians with 12
// unknowns): with AVX (the default -march=native build) Eigen vectorises a
// Jet<double, 8> fully and 8-wide passes win (1.1 us against 1.6 us for
// 16-wide); without it a Jet evaluation costs about the same for 8 and 16
// directions, so 16-wide passes win (4.5 us against 8.2 us).
#ifdef __AVX__
inline constexpr int kAutodiffChunk = 8;
#else
inline constexpr int kAutodiffChunk = 16;
#endif

// f(theta, x, y) is a generic callable (templated on the scalar) computing ny
// outputs y from the full parameter vector theta and nx variables x. Returns
// y (optional), dy/dx (ny x nx, optional) and dy/dtheta[k] for k in
// parameter_indices (ny x P, optional). Returns false if any value is not
// finite.
template <typename F>
bool AutodiffJacobian(const F& f, const Eigen::VectorXd& theta, const double* x, int nx, int ny,
                      const std::vector<int>& parameter_indices, double* y, Eigen::MatrixXd* dydx,
                      Eigen::MatrixXd* dydp) {
  using Jet = ceres::Jet<double, kAutodiffChunk>;
  const int nx_dirs = dydx ? nx : 0;
  const int np_dirs = dydp ? static_cast<int>(parameter_indices.size()) : 0;
  const int num_directions = nx_dirs + np_dirs;
  if (dydx) dydx->resize(ny, nx);
  if (dydp) dydp->resize(ny, np_dirs);

  // Per-thread scratch (this runs inside integrator right-hand sides, several
  // times per step: allocating here was ~5 % of an output-error fit). Every
  // jet is set once; each pass seeds its directions and clears them after.
  thread_local std::vector<Jet> theta_jet, x_jet, y_jet;
  theta_jet.resize(theta.size());
  x_jet.resize(nx);
  y_jet.resize(ny);
  for (int i = 0; i < theta.size(); ++i) theta_jet[i] = Jet(theta[i]);
  for (int i = 0; i < nx; ++i) x_jet[i] = Jet(x[i]);
  auto seed = [&](int dir, int first, double value) {
    if (dir < nx_dirs) {
      x_jet[dir].v[dir - first] = value;
    } else {
      theta_jet[parameter_indices[dir - nx_dirs]].v[dir - first] = value;
    }
  };
  int first = 0;
  do {  // at least one pass, also to compute y when no derivative is asked
    const int last = std::min(first + kAutodiffChunk, num_directions);
    for (int dir = first; dir < last; ++dir) seed(dir, first, 1.0);
    f(theta_jet.data(), x_jet.data(), y_jet.data());
    for (int dir = first; dir < last; ++dir) seed(dir, first, 0.0);
    for (int row = 0; row < ny; ++row) {
      if (!std::isfinite(y_jet[row].a)) return false;
      if (y && first == 0) y[row] = y_jet[row].a;
    }
    // Column by column (each column of dy/dx and dy/dp is contiguous),
    // checked once at the end.
    for (int dir = first; dir < last; ++dir) {
      double* column = dir < nx_dirs ? dydx->data() + static_cast<size_t>(dir) * ny
                                     : dydp->data() + static_cast<size_t>(dir - nx_dirs) * ny;
      for (int row = 0; row < ny; ++row) column[row] = y_jet[row].v[dir - first];
    }
    first = last;
  } while (first < num_directions);
  // value * 0 is NaN exactly for a value that is not finite, and a NaN
  // survives the (vectorised) sum. A test per value (or Eigen's allFinite,
  // one value at a time) was a third of the call's own time: a state
  // Jacobian with 12 unknowns 1080 -> 950 ns (bench/dynamics/model_bench.cc).
  auto all_finite = [](const Eigen::MatrixXd* m) {
    return m == nullptr || (m->array() * 0.0).sum() == 0;
  };
  return all_finite(dydx) && all_finite(dydp);
}

// y and its tangents along m directions (ny x m): direction j moves x by
// x_tangents.col(j) (nx x m) and theta[parameter_indices[k]] by
// theta_tangents(k, j) (P x m; may be empty when P = 0), so
//   dy = dy/dx x_tangents + dy/dtheta[parameter_indices] theta_tangents,
// the chain rule carried inside the jets, in the passes the Jacobians alone
// would take (ceil(m / kAutodiffChunk)). An output's sensitivities from its
// state's (x_tangents = S, theta_tangents = [0 | I]) without forming dy/dx
// and multiplying it out row by row (that product was 8 % of a discover
// run's CPU time, perf on confusion seed 22296). False if any value is not
// finite.
template <typename F>
bool AutodiffTangents(const F& f, const Eigen::VectorXd& theta, const double* x, int nx, int ny,
                      const std::vector<int>& parameter_indices,
                      const Eigen::MatrixXd& x_tangents, const Eigen::MatrixXd& theta_tangents,
                      double* y, Eigen::MatrixXd* dy) {
  using Jet = ceres::Jet<double, kAutodiffChunk>;
  const int m = static_cast<int>(x_tangents.cols());
  const int np = static_cast<int>(parameter_indices.size());
  dy->resize(ny, m);
  thread_local std::vector<Jet> theta_jet, x_jet, y_jet;
  theta_jet.resize(theta.size());
  x_jet.resize(nx);
  y_jet.resize(ny);
  for (int i = 0; i < theta.size(); ++i) theta_jet[i] = Jet(theta[i]);
  for (int i = 0; i < nx; ++i) x_jet[i] = Jet(x[i]);
  int first = 0;
  do {  // at least one pass, also to compute y when no direction is asked
    const int width = std::min(kAutodiffChunk, m - first);
    for (int i = 0; i < nx; ++i) {
      x_jet[i].v.setZero();
      x_jet[i].v.head(width) = x_tangents.row(i).segment(first, width).transpose();
    }
    for (int k = 0; k < np && m > 0; ++k) {
      Jet& p = theta_jet[parameter_indices[k]];
      p.v.setZero();
      p.v.head(width) = theta_tangents.row(k).segment(first, width).transpose();
    }
    f(theta_jet.data(), x_jet.data(), y_jet.data());
    for (int row = 0; row < ny; ++row) {
      if (!std::isfinite(y_jet[row].a)) return false;
      if (y && first == 0) y[row] = y_jet[row].a;
    }
    for (int j = 0; j < width; ++j) {
      double* column = dy->data() + static_cast<size_t>(first + j) * ny;
      for (int row = 0; row < ny; ++row) column[row] = y_jet[row].v[j];
    }
    first += width;
  } while (first < m);
  return (dy->array() * 0.0).sum() == 0;  // as AutodiffJacobian's all_finite
}

}  // namespace coaxid
