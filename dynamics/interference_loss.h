// The coaxial interference loss sigma(omega1, omega2) that multiplies the
// z-component of both rotor thrusts (eqs. 12-13; model.md, decision 1).
#pragma once

#include <algorithm>

#include "core/vehicle_config.h"

namespace coaxid {

// Parametric form (model.md, decision 1), the default and the one the
// nonlinear estimators fit:
//   sigma = 1 - sigma0 * 4 w1 w2 / (w1 + w2)^2,  w1 = omega1^2, w2 = omega2^2,
// sigma = 1 when either rotor (or both) is stopped, 1 - sigma0 at equal speeds.
template <typename T>
T InterferenceLoss(const T& sigma0, const T& omega1, const T& omega2) {
  const T w1 = omega1 * omega1;
  const T w2 = omega2 * omega2;
  const T sum = w1 + w2;
  if (sum <= T(0)) return T(1);  // both stopped: no interference
  return T(1) - sigma0 * T(4) * w1 * w2 / (sum * sum);
}

// The tabulated map (the paper's Fig. 9): bilinear interpolation over an
// omega1 x omega2 grid, clamped to the grid's edges outside it.
template <typename T>
T InterferenceLossFromTable(const SigmaTable& table, const T& omega1, const T& omega2) {
  auto locate = [](const std::vector<double>& grid, const T& w, int* cell, T* frac) {
    const int n = static_cast<int>(grid.size());
    if (w <= T(grid.front())) {
      *cell = 0;
      *frac = T(0);
      return;
    }
    if (w >= T(grid.back())) {
      *cell = n - 2;
      *frac = T(1);
      return;
    }
    int k = static_cast<int>(std::upper_bound(grid.begin(), grid.end(), w) - grid.begin()) - 1;
    k = std::clamp(k, 0, n - 2);
    *cell = k;
    *frac = (w - T(grid[k])) / T(grid[k + 1] - grid[k]);
  };
  int i, j;
  T a, b;
  locate(table.omega1, omega1, &i, &a);
  locate(table.omega2, omega2, &j, &b);
  const size_t n2 = table.omega2.size();
  const double s00 = table.sigma[i * n2 + j], s01 = table.sigma[i * n2 + j + 1];
  const double s10 = table.sigma[(i + 1) * n2 + j], s11 = table.sigma[(i + 1) * n2 + j + 1];
  return (T(1) - a) * ((T(1) - b) * s00 + b * s01) + a * ((T(1) - b) * s10 + b * s11);
}

}  // namespace coaxid
