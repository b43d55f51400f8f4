// DerivativeJacobians (dynamics/model_jacobian.h) against central finite
// differences of VehicleModel::Derivative (STYLE.md, 10(a)), for df/dx and
// df/dtheta over every parameter (known, unknown and effect parameters), at
// seeded random near-hover states, with no effect and with every effect of
// the library enabled at its typical strength.
//
// Step and tolerance. Column j is differenced with h_j = 1e-6 * max(|p_j|, s_j),
// s_j = 1 (SI unit) for a state and the parameter's own scale (its typical
// magnitude, configs/glmav.yaml) for a parameter. The central difference's
// truncation error is h^2 f''' / 6 ~ 1e-12 of the column's scale (f is smooth
// on the scale s_j near hover: trigonometric in the angles, quadratic-ish in
// the speeds; the two kinks of the model are smoothed and far away: the wake
// radicand is ~45 m^2/s^2 and the airspeed ~7 m/s). Its rounding error is
// ~eps * S_i / h_j, with S_i the size of the terms that make up row i (they
// cancel at hover, so |f_i| itself is no guide): 1 for position and angle
// rates, 10 m/s^2 (g) for velocity rates, 1e3 rad/s^2 for body-rate rates
// (moments of ~0.1 N m over inertias of ~3e-4 kg m^2). The check is
//   |AD - FD| <= 1e-6 * max_i |FD_ij| + 100 eps S_i / h_j,
// a million times the truncation error and 100 times the rounding bound, and
// far below any real Jacobian error (a wrong or swapped column is O(1) wrong).
#include "dynamics/autodiff.h"
#include "dynamics/model_jacobian.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "core/input_hold.h"
#include "core/parameters.h"
#include "dynamics/effects/effect_library.h"
#include "dynamics/outputs.h"
#include "dynamics/state.h"
#include "dynamics/vehicle.h"
#include "dynamics/vehicle_model.h"

namespace coaxid {
namespace {

constexpr double kRelStep = 1e-6;
constexpr double kRelTol = 1e-6;
constexpr double kEps = std::numeric_limits<double>::epsilon();

Vehicle Reference() { return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml"); }

Vehicle AllEffects() {
  Vehicle v = Reference();
  for (const auto& info : EffectLibrary()) {
    // The 12-state cases below; an effect's own states: stabilizer_bar_test.cc.
    if (info.num_own_states > 0) continue;
    std::map<std::string, ParameterOverride> overrides;
    for (const auto& spec : info.parameters) overrides[spec.name].value = spec.typical;
    v = WithEffect(v, info.name, overrides);
  }
  return v;
}

// Size of the terms of each row of f (see the header comment).
double RowTermScale(int row) {
  if (row >= kU && row <= kW) return 10.0;
  if (row >= kP) return 1e3;
  return 1.0;
}

struct Case {
  State x;
  InputVector input;
};

// Near hover: 0.5 .. 2 m up, slow, nearly level, slowly rotating, inputs
// around the hover trim (150 / 164 rad/s).
std::vector<Case> NearHoverCases(unsigned seed, int n) {
  std::mt19937 rng(seed);
  auto U = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  std::vector<Case> cases;
  for (int k = 0; k < n; ++k) {
    Case c;
    c.x << U(-2, 2), U(-2, 2), U(-2, -0.5), U(-0.5, 0.5), U(-0.5, 0.5), U(-0.5, 0.5), U(-0.1, 0.1),
        U(-0.1, 0.1), U(-M_PI, M_PI), U(-0.3, 0.3), U(-0.3, 0.3), U(-0.3, 0.3);
    c.input = {150.0 + U(-10, 10), 164.0 + U(-10, 10), U(-0.05, 0.05), U(-0.05, 0.05)};
    cases.push_back(c);
  }
  return cases;
}

State F(const VehicleModel& model, const Eigen::VectorXd& theta, const State& x,
        const InputVector& input) {
  State f;
  model.Derivative(theta.data(), x.data(), input.data(), f.data());
  return f;
}

// Central differences: columns over the states, then over `indices`.
void FiniteDifferences(const Vehicle& v, const Eigen::VectorXd& theta, const State& x,
                       const InputVector& input, const std::vector<int>& indices,
                       Eigen::MatrixXd* dfdx, Eigen::MatrixXd* dfdp, std::vector<double>* hx,
                       std::vector<double>* hp) {
  dfdx->resize(kNumStates, kNumStates);
  dfdp->resize(kNumStates, static_cast<int>(indices.size()));
  hx->clear();
  hp->clear();
  for (int j = 0; j < kNumStates; ++j) {
    const double h = kRelStep * std::max(std::fabs(x[j]), 1.0);
    State xp = x, xm = x;
    xp[j] += h;
    xm[j] -= h;
    dfdx->col(j) = (F(v.model, theta, xp, input) - F(v.model, theta, xm, input)) / (2 * h);
    hx->push_back(h);
  }
  for (size_t k = 0; k < indices.size(); ++k) {
    const int j = indices[k];
    const double h = kRelStep * std::max(std::fabs(theta[j]), v.parameters[j].scale);
    Eigen::VectorXd tp = theta, tm = theta;
    tp[j] += h;
    tm[j] -= h;
    dfdp->col(k) = (F(v.model, tp, x, input) - F(v.model, tm, x, input)) / (2 * h);
    hp->push_back(h);
  }
}

void ExpectJacobianNear(const Eigen::MatrixXd& ad, const Eigen::MatrixXd& fd,
                        const std::vector<double>& steps, const std::vector<std::string>& names,
                        const std::string& what) {
  ASSERT_EQ(ad.rows(), fd.rows());
  ASSERT_EQ(ad.cols(), fd.cols());
  for (int j = 0; j < ad.cols(); ++j) {
    const double col_scale = fd.col(j).cwiseAbs().maxCoeff();
    for (int i = 0; i < ad.rows(); ++i) {
      const double tol = kRelTol * col_scale + 100 * kEps * RowTermScale(i) / steps[j];
      EXPECT_NEAR(ad(i, j), fd(i, j), tol)
          << what << ": d(" << StateName(i) << "_dot)/d(" << names[j] << ")";
    }
  }
}

void CheckVehicle(const Vehicle& v, unsigned seed, const std::string& what) {
  const Eigen::VectorXd theta = v.parameters.Values();
  std::vector<int> all(v.parameters.size());
  std::vector<std::string> param_names, state_names;
  for (int i = 0; i < v.parameters.size(); ++i) {
    all[i] = i;
    param_names.push_back(v.parameters[i].name);
  }
  for (int i = 0; i < kNumStates; ++i) state_names.push_back(StateName(i));
  int k = 0;
  for (const Case& c : NearHoverCases(seed, 6)) {
    const std::string where = what + ", case " + std::to_string(k++);
    Eigen::MatrixXd dfdx, dfdp;
    ASSERT_TRUE(DerivativeJacobians(v.model, theta, c.x.data(), HeldInput::Steady(c.input, 0), 0, all, &dfdx, &dfdp));
    Eigen::MatrixXd fdx, fdp;
    std::vector<double> hx, hp;
    FiniteDifferences(v, theta, c.x, c.input, all, &fdx, &fdp, &hx, &hp);
    ExpectJacobianNear(dfdx, fdx, hx, state_names, where + ", dfdx");
    ExpectJacobianNear(dfdp, fdp, hp, param_names, where + ", dfdp");
    // Without dfdp the same dfdx (same Jet evaluation of the state columns).
    Eigen::MatrixXd dfdx_only;
    ASSERT_TRUE(DerivativeJacobians(v.model, theta, c.x.data(), HeldInput::Steady(c.input, 0), 0, {}, &dfdx_only, nullptr));
    EXPECT_EQ((dfdx_only - dfdx).cwiseAbs().maxCoeff(), 0.0) << where;
  }
}

TEST(ModelJacobianTest, NoEffectMatchesCentralDifferences) {
  CheckVehicle(Reference(), 1001u, "no effect");
}

TEST(ModelJacobianTest, AllEffectsMatchCentralDifferences) {
  const Vehicle v = AllEffects();
  size_t stateless = 0;
  for (const auto& info : EffectLibrary()) stateless += info.num_own_states == 0;
  ASSERT_EQ(v.EffectNames().size(), stateless);
  CheckVehicle(v, 2002u, "all effects");
}

// FlightOutputJacobians against central differences of FlightOutputs, every
// effect on (the measurement effects put unit columns on their channels; the
// output model's Jacobians feed output-error, the EKF and discover). Same
// steps and tolerances as the derivative: the accelerometer's terms are of
// the size of g (RowTermScale 10), the state channels' of 1.
TEST(ModelJacobianTest, FlightOutputsMatchCentralDifferencesWithAllEffects) {
  const Vehicle v = AllEffects();
  ASSERT_TRUE(v.model.ChangesFlightMeasurements());
  const Eigen::VectorXd theta = v.parameters.Values();
  std::vector<int> all(v.parameters.size());
  for (int i = 0; i < v.parameters.size(); ++i) all[i] = i;
  using Outputs = Eigen::Matrix<double, kNumFlightChannels, 1>;
  auto outputs = [&](const Eigen::VectorXd& th, const State& x, const InputVector& u) {
    Outputs y;
    FlightOutputs(v.model, th.data(), x.data(), u.data(), y.data());
    return y;
  };
  auto row_scale = [](int i) { return i >= kAx ? 10.0 : 1.0; };
  for (const Case& c : NearHoverCases(4004u, 4)) {
    double y[kNumFlightChannels];
    Eigen::MatrixXd dydx, dydp;
    ASSERT_TRUE(FlightOutputJacobians(v.model, theta, c.x.data(), HeldInput::Steady(c.input, 0), all, y, &dydx, &dydp));
    ASSERT_EQ(dydx.rows(), kNumFlightChannels);
    ASSERT_EQ(dydp.cols(), v.parameters.size());
    auto check = [&](const Eigen::VectorXd& ad, const Outputs& fd, double h, const std::string& w) {
      const double col_scale = fd.cwiseAbs().maxCoeff();
      for (int i = 0; i < kNumFlightChannels; ++i) {
        EXPECT_NEAR(ad[i], fd[i], kRelTol * col_scale + 100 * kEps * row_scale(i) / h)
            << "d(" << FlightChannelName(i) << ")/d(" << w << ")";
      }
    };
    for (int j = 0; j < kNumStates; ++j) {
      const double h = kRelStep * std::max(std::fabs(c.x[j]), 1.0);
      State xp = c.x, xm = c.x;
      xp[j] += h;
      xm[j] -= h;
      check(dydx.col(j), (outputs(theta, xp, c.input) - outputs(theta, xm, c.input)) / (2 * h), h,
            StateName(j));
    }
    for (int j = 0; j < v.parameters.size(); ++j) {
      const double h = kRelStep * std::max(std::fabs(theta[j]), v.parameters[j].scale);
      Eigen::VectorXd tp = theta, tm = theta;
      tp[j] += h;
      tm[j] -= h;
      check(dydp.col(j), (outputs(tp, c.x, c.input) - outputs(tm, c.x, c.input)) / (2 * h), h,
            v.parameters[j].name);
    }
  }
}

// FlightOutputTangents is dy/dx X + dy/dtheta[subset] T for any tangents:
// 21 directions (two full chunks of jets and a partial one), random, every
// effect on, parameters in any order. The two sides are the same sums in
// another order: equal to rounding, 1e-12 of the terms' magnitudes.
TEST(ModelJacobianTest, FlightOutputTangentsAreTheJacobiansTimesTheTangents) {
  const Vehicle v = AllEffects();
  const Eigen::VectorXd theta = v.parameters.Values();
  const std::vector<int> indices = {kIzz, v.parameters.IndexOrThrow("cg_offset.y_g"), kAlpha,
                                    v.parameters.IndexOrThrow("gyro_bias.b_q"), kCx, kGamma2};
  const int nx = v.model.NumStates(), np = static_cast<int>(indices.size()), m = 21;
  std::mt19937 rng(5005u);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd X(nx, m), T(np, m);
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < nx; ++i) X(i, j) = normal(rng);
    for (int k = 0; k < np; ++k) T(k, j) = normal(rng);
  }
  for (const Case& c : NearHoverCases(6006u, 3)) {
    const HeldInput u = HeldInput::Steady(c.input, 0);
    double y[kNumFlightChannels], y_tangents[kNumFlightChannels];
    Eigen::MatrixXd dydx, dydp, dy;
    ASSERT_TRUE(FlightOutputJacobians(v.model, theta, c.x.data(), u, indices, y, &dydx, &dydp));
    ASSERT_TRUE(FlightOutputTangents(v.model, theta, c.x.data(), u, indices, X, T, y_tangents, &dy));
    ASSERT_EQ(dy.rows(), kNumFlightChannels);
    ASSERT_EQ(dy.cols(), m);
    const Eigen::MatrixXd expected = dydx * X + dydp * T;
    const Eigen::MatrixXd size = dydx.cwiseAbs() * X.cwiseAbs() + dydp.cwiseAbs() * T.cwiseAbs();
    for (int i = 0; i < kNumFlightChannels; ++i) {
      EXPECT_EQ(y_tangents[i], y[i]) << FlightChannelName(i);
      for (int j = 0; j < m; ++j) {
        EXPECT_NEAR(dy(i, j), expected(i, j), 1e-12 * size(i, j))
            << FlightChannelName(i) << ", direction " << j;
      }
    }
    // Not void: every output channel moves along some direction.
    for (int i = 0; i < kNumFlightChannels; ++i) {
      EXPECT_GT(dy.row(i).cwiseAbs().maxCoeff(), 0.0) << FlightChannelName(i);
    }
  }
}

// A subset of parameters in arbitrary order: column k is the derivative with
// respect to parameter_indices[k], whatever the order (the chunking of the
// Jet directions must not mix them up).
TEST(ModelJacobianTest, ParameterSubsetInAnyOrder) {
  const Vehicle v = AllEffects();
  const Eigen::VectorXd theta = v.parameters.Values();
  const std::vector<int> indices = {
      kIzz,         v.parameters.IndexOrThrow("cg_offset.y_g"),
      kAlpha,       v.parameters.IndexOrThrow("wind.wn"),
      kHubDistance, v.parameters.IndexOrThrow("gyroscopic.J_r"),
      kCx,          v.parameters.IndexOrThrow("wake_interference.k_Q"),
      kGamma2};
  std::vector<std::string> names;
  for (int i : indices) names.push_back(v.parameters[i].name);
  const Case c = NearHoverCases(3003u, 1)[0];
  Eigen::MatrixXd dfdx, dfdp, fdx, fdp;
  std::vector<double> hx, hp;
  ASSERT_TRUE(DerivativeJacobians(v.model, theta, c.x.data(), HeldInput::Steady(c.input, 0), 0, indices, &dfdx, &dfdp));
  ASSERT_EQ(dfdp.cols(), static_cast<int>(indices.size()));
  FiniteDifferences(v, theta, c.x, c.input, indices, &fdx, &fdp, &hx, &hp);
  ExpectJacobianNear(dfdp, fdp, hp, names, "subset");
  // Every chosen column is really non-zero somewhere (else the test is void).
  for (int k = 0; k < dfdp.cols(); ++k) {
    EXPECT_GT(dfdp.col(k).cwiseAbs().maxCoeff(), 0.0) << names[k];
  }
}

// The 12 unknown base parameters alone (the usual estimation set).
TEST(ModelJacobianTest, UnknownBaseParametersMatchCentralDifferences) {
  const Vehicle v = Reference();
  const Eigen::VectorXd theta = v.parameters.Values();
  std::vector<int> indices;
  std::vector<std::string> names;
  for (int i = kAlpha; i < kNumBaseParameters; ++i) {
    indices.push_back(i);
    names.push_back(BaseParameterName(i));
  }
  for (const Case& c : NearHoverCases(4004u, 3)) {
    Eigen::MatrixXd dfdx, dfdp, fdx, fdp;
    std::vector<double> hx, hp;
    ASSERT_TRUE(DerivativeJacobians(v.model, theta, c.x.data(), HeldInput::Steady(c.input, 0), 0, indices, &dfdx, &dfdp));
    FiniteDifferences(v, theta, c.x, c.input, indices, &fdx, &fdp, &hx, &hp);
    ExpectJacobianNear(dfdp, fdp, hp, names, "unknowns");
  }
}

// A non-finite derivative (zero inertia) is reported, not returned.
TEST(ModelJacobianTest, ReportsNonFiniteDerivatives) {
  const Vehicle v = Reference();
  Eigen::VectorXd theta = v.parameters.Values();
  theta[kIxx] = 0.0;
  const Case c = NearHoverCases(5005u, 1)[0];
  Eigen::MatrixXd dfdx, dfdp;
  EXPECT_FALSE(DerivativeJacobians(v.model, theta, c.x.data(), HeldInput::Steady(c.input, 0), 0, {kAlpha}, &dfdx, &dfdp));
}

// A finite value with a derivative that is not (sqrt at 0), in either block
// and in any pass, is reported: the derivatives' check is a separate one
// from the values' (dynamics/autodiff.h).
TEST(ModelJacobianTest, ReportsANonFiniteDerivativeOfAFiniteValue) {
  // y0 = theta_k * x0, y1 = sqrt(x_j) + sqrt(theta_m): at x_j = 0 (theta_m =
  // 0) the value is 0 and dy1/dx_j (dy1/dtheta_m) infinite.
  const int nx = 19;  // 21 directions: a kAutodiffWideChunk pass, then a kAutodiffChunk one
  auto f = [](const auto* th, const auto* x, auto* y) {
    using std::sqrt;
    y[0] = th[0] * x[0];
    y[1] = sqrt(x[nx - 1]) + sqrt(th[2]);
  };
  const Eigen::VectorXd theta = (Eigen::VectorXd(3) << 2.0, 3.0, 1.0).finished();
  std::vector<double> x(nx, 1.0);
  double y[2];
  Eigen::MatrixXd dydx, dydp;
  ASSERT_TRUE(AutodiffJacobian(f, theta, x.data(), nx, 2, {0, 2}, y, &dydx, &dydp));
  EXPECT_DOUBLE_EQ(dydx(0, 0), 2.0);
  EXPECT_DOUBLE_EQ(dydx(1, nx - 1), 0.5);
  EXPECT_DOUBLE_EQ(dydp(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(dydp(1, 1), 0.5);
  x[nx - 1] = 0.0;  // in the second pass's directions (direction 18)
  EXPECT_FALSE(AutodiffJacobian(f, theta, x.data(), nx, 2, {0, 2}, y, &dydx, &dydp));
  x[nx - 1] = 1.0;
  Eigen::VectorXd at_zero = theta;
  at_zero[2] = 0.0;
  EXPECT_FALSE(AutodiffJacobian(f, at_zero, x.data(), nx, 2, {0, 2}, nullptr, nullptr, &dydp));
}

// Every direction lands in its own column whatever the number of directions,
// and so whatever the mix of pass widths (autodiff_internal::ForEachPass:
// kAutodiffWideChunk-wide passes, then a kAutodiffChunk-wide one): a
// function whose Jacobian is known in closed form, 1 to 40 directions split
// between x and theta (the parameters taken in reverse order), and the
// tangents along random directions against that Jacobian times them. A
// direction seeded in the wrong lane, skipped or seeded twice moves a
// column by O(1).
TEST(AutodiffTest, EveryDirectionInItsColumnWhateverTheirNumber) {
  std::mt19937 rng(7007u);
  std::normal_distribution<double> normal;
  for (int directions = 1; directions <= 40; ++directions) {
    const int nx = (directions + 1) / 2, np = directions - nx, ny = 3;
    const int nth = np + 2;
    Eigen::VectorXd theta(nth);
    for (int k = 0; k < nth; ++k) theta[k] = 0.5 + 0.25 * k;
    std::vector<int> indices(np);
    for (int k = 0; k < np; ++k) indices[k] = np - k;  // theta[np], ..., theta[1]
    std::vector<double> x(nx);
    for (int i = 0; i < nx; ++i) x[i] = 1.0 + 0.125 * i;
    // y0 = sum_i (i + 1) x_i^2 + sum_k (k + 1) theta_k, y1 = x_0 sum_k theta_k^2,
    // y2 = sum_i x_i theta_(i mod nth).
    auto f = [nx, nth](const auto* th, const auto* xx, auto* y) {
      using T = std::remove_cv_t<std::remove_pointer_t<decltype(th)>>;
      T sum_sq(0.0);
      y[0] = T(0.0);
      y[2] = T(0.0);
      for (int i = 0; i < nx; ++i) {
        y[0] += double(i + 1) * xx[i] * xx[i];
        y[2] += xx[i] * th[i % nth];
      }
      for (int k = 0; k < nth; ++k) {
        y[0] += double(k + 1) * th[k];
        sum_sq += th[k] * th[k];
      }
      y[1] = xx[0] * sum_sq;
    };
    Eigen::MatrixXd dydx_expected = Eigen::MatrixXd::Zero(ny, nx);
    Eigen::MatrixXd dydtheta = Eigen::MatrixXd::Zero(ny, nth);  // every theta
    double sum_sq = 0;
    for (int k = 0; k < nth; ++k) sum_sq += theta[k] * theta[k];
    for (int i = 0; i < nx; ++i) {
      dydx_expected(0, i) = 2.0 * (i + 1) * x[i];
      dydx_expected(2, i) = theta[i % nth];
      dydtheta(2, i % nth) += x[i];
    }
    dydx_expected(1, 0) = sum_sq;
    for (int k = 0; k < nth; ++k) {
      dydtheta(0, k) = k + 1;
      dydtheta(1, k) = 2.0 * x[0] * theta[k];
    }
    Eigen::MatrixXd dydp_expected(ny, np);
    for (int k = 0; k < np; ++k) dydp_expected.col(k) = dydtheta.col(indices[k]);

    Eigen::MatrixXd dydx, dydp;
    double y[3];
    ASSERT_TRUE(AutodiffJacobian(f, theta, x.data(), nx, ny, indices, y, &dydx, &dydp));
    ASSERT_EQ(dydx.cols(), nx);
    ASSERT_EQ(dydp.cols(), np);
    const double tol = 1e-13 * (1.0 + dydx_expected.cwiseAbs().maxCoeff() +
                                (np > 0 ? dydp_expected.cwiseAbs().maxCoeff() : 0.0));
    for (int r = 0; r < ny; ++r) {
      for (int i = 0; i < nx; ++i) {
        EXPECT_NEAR(dydx(r, i), dydx_expected(r, i), tol)
            << directions << " directions: dy" << r << "/dx" << i;
      }
      for (int k = 0; k < np; ++k) {
        EXPECT_NEAR(dydp(r, k), dydp_expected(r, k), tol)
            << directions << " directions: dy" << r << "/dtheta" << indices[k];
      }
    }
    // The tangents along m random directions: m runs over the pass widths too.
    const int m = directions;
    Eigen::MatrixXd X(nx, m), Th(np, m);
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < nx; ++i) X(i, j) = normal(rng);
      for (int k = 0; k < np; ++k) Th(k, j) = normal(rng);
    }
    Eigen::MatrixXd dy;
    double y_tangents[3];
    ASSERT_TRUE(AutodiffTangents(f, theta, x.data(), nx, ny, indices, X, Th, y_tangents, &dy));
    const Eigen::MatrixXd expected = dydx_expected * X + dydp_expected * Th;
    const Eigen::MatrixXd size =
        dydx_expected.cwiseAbs() * X.cwiseAbs() + dydp_expected.cwiseAbs() * Th.cwiseAbs();
    for (int r = 0; r < ny; ++r) {
      EXPECT_EQ(y_tangents[r], y[r]);
      for (int j = 0; j < m; ++j) {
        EXPECT_NEAR(dy(r, j), expected(r, j), 1e-13 * (1.0 + size(r, j)))
            << directions << " directions: tangent " << j << " of y" << r;
      }
    }
  }
}

// A rotor pushing down (a trial point of a refit far from the truth) makes eq. 46's radicand negative and large; written as radicand +
// sqrt(radicand^2 + eps^2) the smoothed positive part cancelled to exactly 0
// there, and the wake speed's derivative was NaN (study run p0_s33). The
// derivative is finite and tiny: v_prop ~ eps / (2 sqrt(-radicand)).
TEST(ModelJacobianTest, FiniteWhenTheRotorPushesDown) {
  const Vehicle v = Reference();
  Eigen::VectorXd theta = v.parameters.Values();
  // Ten times the thrust, downwards: radicand ~ -450 m^2/s^2 (hover: +45),
  // well past where the old sum cancelled (~-70).
  theta[kAlpha] = -10 * theta[kAlpha];
  theta[kBeta] = -10 * theta[kBeta];
  const Case c = NearHoverCases(5005u, 1)[0];
  Eigen::MatrixXd dfdx, dfdp;
  EXPECT_TRUE(DerivativeJacobians(v.model, theta, c.x.data(), HeldInput::Steady(c.input, 0), 0,
                                  {kAlpha, kBeta, kCz}, &dfdx, &dfdp));
  EXPECT_TRUE(dfdx.allFinite() && dfdp.allFinite());
}

}  // namespace
}  // namespace coaxid
