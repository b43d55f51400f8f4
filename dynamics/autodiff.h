// Forward-mode automatic differentiation of the one templated model with
// ceres::Jet, a chunk of derivative directions at a time (like Ceres'
// DynamicAutoDiffCostFunction): the only way Jacobians are made in coaxid
// (STYLE.md, item 3). Used for the state derivative (model_jacobian.h) and
// the output models (outputs.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <vector>

#include <Eigen/Core>
#include <ceres/jet.h>

namespace coaxid {

// Directions per pass, measured with bench/dynamics/model_bench.cc. With AVX
// (the default -march=native build) Eigen vectorises a Jet<double, 8>
// fully: passes are 16 wide while more than 8 directions are left, then 8
// wide. BM_DerivativeJacobiansWithParameters (every effect, 12 states + P
// parameters, the AVX-512 machine of 2026-12-07): 16 directions 627 ns in
// one 16-wide pass against 717 ns in two 8-wide ones, 28 directions 1142
// against 1384, 32 directions 1172 against 1392; 20 and 24 directions (a
// 16- and an 8-wide pass against three 8-wide) 1059 against 1017 and 1058
// against 1052. Wider jets cost more per direction (BM_DerivativeJet, no
// effect: 153 ns 8-wide, 271 16-wide, 498 24-wide, 638 32-wide). Without
// AVX a Jet evaluation costs about the same for 8 and 16 directions, so
// every pass is 16 wide (4.5 us against 8.2 us, 12 unknowns). The values
// are the same to the last bit whatever the widths (each direction's
// arithmetic does not depend on them): on confusion seed 22296 discover's
// 5068 reported values were identical with 8-wide passes alone, its CPU
// time 35.4 -> 33.6 s.
#ifdef __AVX__
inline constexpr int kAutodiffChunk = 8;
inline constexpr int kAutodiffWideChunk = 16;
#else
inline constexpr int kAutodiffChunk = 16;
inline constexpr int kAutodiffWideChunk = 16;
#endif

namespace autodiff_internal {

// Jets of width N for the parameters, the variables and the outputs, one set
// per thread, reused from call to call (these run inside integrator
// right-hand sides, several times per step: allocating them per call was
// ~5 % of an output-error fit).
template <int N>
struct JetScratch {
  std::vector<ceres::Jet<double, N>> theta, x, y;
};
template <int N>
JetScratch<N>& ThreadJetScratch() {
  thread_local JetScratch<N> scratch;
  return scratch;
}

// Calls pass(std::integral_constant<int, N>(), first, width) over the
// directions [0, num_directions), at least once (width 0 when there are
// none): kAutodiffWideChunk-wide passes while more than kAutodiffChunk
// directions are left, then one kAutodiffChunk-wide pass. False as soon as
// a pass returns false.
template <typename Pass>
bool ForEachPass(int num_directions, const Pass& pass) {
  int first = 0;
  do {
    const int left = num_directions - first;
    const bool wide = left > kAutodiffChunk;
    const int width = std::min(wide ? kAutodiffWideChunk : kAutodiffChunk, left);
    const bool ok = wide ? pass(std::integral_constant<int, kAutodiffWideChunk>(), first, width)
                         : pass(std::integral_constant<int, kAutodiffChunk>(), first, width);
    if (!ok) return false;
    first += width;
  } while (first < num_directions);
  return true;
}

// The scratch of width N with theta's and x's values (no direction seeded),
// set at its first use in a call (`ready`, one flag per width).
template <int N>
JetScratch<N>& ScratchAt(const Eigen::VectorXd& theta, const double* x, int nx, int ny,
                         bool ready[2]) {
  using Jet = ceres::Jet<double, N>;
  JetScratch<N>& s = ThreadJetScratch<N>();
  bool& set = ready[N == kAutodiffWideChunk ? 1 : 0];
  if (!set) {
    s.theta.resize(theta.size());
    s.x.resize(nx);
    s.y.resize(ny);
    for (int i = 0; i < theta.size(); ++i) s.theta[i] = Jet(theta[i]);
    for (int i = 0; i < nx; ++i) s.x[i] = Jet(x[i]);
    set = true;
  }
  return s;
}

}  // namespace autodiff_internal

// f(theta, x, y) is a generic callable (templated on the scalar) computing ny
// outputs y from the full parameter vector theta and nx variables x. Returns
// y (optional), dy/dx (ny x nx, optional) and dy/dtheta[k] for k in
// parameter_indices (ny x P, optional). Returns false if any value is not
// finite.
template <typename F>
bool AutodiffJacobian(const F& f, const Eigen::VectorXd& theta, const double* x, int nx, int ny,
                      const std::vector<int>& parameter_indices, double* y, Eigen::MatrixXd* dydx,
                      Eigen::MatrixXd* dydp) {
  const int nx_dirs = dydx ? nx : 0;
  const int np_dirs = dydp ? static_cast<int>(parameter_indices.size()) : 0;
  const int num_directions = nx_dirs + np_dirs;
  if (dydx) dydx->resize(ny, nx);
  if (dydp) dydp->resize(ny, np_dirs);
  bool ready[2] = {false, false};
  // Each pass seeds its directions and clears them after.
  auto pass = [&](auto chunk, int first, int width) {
    auto& s = autodiff_internal::ScratchAt<decltype(chunk)::value>(theta, x, nx, ny, ready);
    auto seed = [&](int dir, double value) {
      if (dir < nx_dirs) {
        s.x[dir].v[dir - first] = value;
      } else {
        s.theta[parameter_indices[dir - nx_dirs]].v[dir - first] = value;
      }
    };
    for (int dir = first; dir < first + width; ++dir) seed(dir, 1.0);
    f(s.theta.data(), s.x.data(), s.y.data());
    for (int dir = first; dir < first + width; ++dir) seed(dir, 0.0);
    for (int row = 0; row < ny; ++row) {
      if (!std::isfinite(s.y[row].a)) return false;
      if (y && first == 0) y[row] = s.y[row].a;
    }
    // Column by column (each column of dy/dx and dy/dp is contiguous),
    // checked once at the end.
    for (int dir = first; dir < first + width; ++dir) {
      double* column = dir < nx_dirs ? dydx->data() + static_cast<size_t>(dir) * ny
                                     : dydp->data() + static_cast<size_t>(dir - nx_dirs) * ny;
      for (int row = 0; row < ny; ++row) column[row] = s.y[row].v[dir - first];
    }
    return true;
  };
  if (!autodiff_internal::ForEachPass(num_directions, pass)) return false;
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
// would take (autodiff_internal::ForEachPass). An output's sensitivities from its
// state's (x_tangents = S, theta_tangents = [0 | I]) without forming dy/dx
// and multiplying it out row by row (that product was 8 % of a discover
// run's CPU time, perf on confusion seed 22296). False if any value is not
// finite.
template <typename F>
bool AutodiffTangents(const F& f, const Eigen::VectorXd& theta, const double* x, int nx, int ny,
                      const std::vector<int>& parameter_indices,
                      const Eigen::MatrixXd& x_tangents, const Eigen::MatrixXd& theta_tangents,
                      double* y, Eigen::MatrixXd* dy) {
  const int m = static_cast<int>(x_tangents.cols());
  const int np = static_cast<int>(parameter_indices.size());
  dy->resize(ny, m);
  bool ready[2] = {false, false};
  auto pass = [&](auto chunk, int first, int width) {
    auto& s = autodiff_internal::ScratchAt<decltype(chunk)::value>(theta, x, nx, ny, ready);
    for (int i = 0; i < nx; ++i) {
      s.x[i].v.setZero();
      s.x[i].v.head(width) = x_tangents.row(i).segment(first, width).transpose();
    }
    for (int k = 0; k < np && m > 0; ++k) {
      auto& p = s.theta[parameter_indices[k]];
      p.v.setZero();
      p.v.head(width) = theta_tangents.row(k).segment(first, width).transpose();
    }
    f(s.theta.data(), s.x.data(), s.y.data());
    for (int row = 0; row < ny; ++row) {
      if (!std::isfinite(s.y[row].a)) return false;
      if (y && first == 0) y[row] = s.y[row].a;
    }
    for (int j = 0; j < width; ++j) {
      double* column = dy->data() + static_cast<size_t>(first + j) * ny;
      for (int row = 0; row < ny; ++row) column[row] = s.y[row].v[j];
    }
    return true;
  };
  if (!autodiff_internal::ForEachPass(m, pass)) return false;
  return (dy->array() * 0.0).sum() == 0;  // as AutodiffJacobian's all_finite
}

}  // namespace coaxid
