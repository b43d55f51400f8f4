// Tests of the integrator (dynamics/integrator.h: CVODES, and ARKODE's explicit Runge-Kutta)
// and the RK4 reference (dynamics/rk4.h)
// on systems with closed-form solutions and sensitivities.
//
// Tolerances. CVODE keeps the estimated local error of every step below the local tolerance
// tol = rtol*|x| + atol. Over one uninterrupted run of a stable, non-stiff problem across a few
// time constants the global error is a small multiple of that: we allow kGlobalErrorFactor = 20
// tol (observed 0.02-3.5 tol over the four method/iteration combinations, so the bound keeps a
// margin of about 6 and still catches an error off by an order of magnitude).
// Restarting costs accuracy: each restart begins again with low-order steps, each of whose local
// errors may reach tol, and for a smooth system they have a consistent sign, so they add up
// linearly with the number of restarts. For restarted runs we therefore allow one more tol per
// restart (observed 0.02-0.3 tol per restart with 5-10 ms intervals).
// Every bound states the scale |x| (or |S|) it uses. Sensitivities are in the error test
// (CVodeSetSensErrCon) with the state's tolerances (CVodeSensEEtolerances), so the same rules
// apply to them with |S| as the scale.

#include "dynamics/integrator.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>
#include <utility>
#include <vector>

#include "core/errors.h"
#include "dynamics/ode_system.h"
#include "dynamics/rk4.h"
#include "dynamics/variational_system.h"

namespace coaxid {
namespace {

constexpr double kGlobalErrorFactor = 20.0;

// Bound on the global error of a run restarted `restarts` times, for local tolerance `tol`.
double RestartedBound(int restarts, double tol) { return (kGlobalErrorFactor + restarts) * tol; }

// Damped oscillator x'' + c x' + k x = 0, state (x, v), parameters (k, c).
class DampedOscillator : public OdeSystem {
 public:
  DampedOscillator(double k, double c) : k_(k), c_(c) {}
  int NumStates() const override { return 2; }
  int NumSensitivityParameters() const override { return 2; }
  bool Rhs(double t, const double* x, double* xdot) const override {
    xdot[0] = x[1];
    xdot[1] = -k_ * x[0] - c_ * x[1];
    return true;
  }
  bool Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                 Eigen::MatrixXd* dfdp) const override {
    *dfdx << 0.0, 1.0, -k_, -c_;
    if (dfdp != nullptr) *dfdp << 0.0, 0.0, -x[0], -x[1];
    return true;
  }
  Eigen::Matrix2d A() const { return (Eigen::Matrix2d() << 0.0, 1.0, -k_, -c_).finished(); }

  // Closed form (underdamped, c^2 < 4k) with a = c/2, wd = sqrt(k - a^2):
  //   x(t) = e^{-at} [x0 cos wd t + (v0 + a x0)/wd sin wd t]
  //   v(t) = e^{-at} [v0 cos wd t - (a v0 + k x0)/wd sin wd t]
  // Linear in (x0, v0), so its transition matrix is dx(t)/dx0.
  Eigen::Matrix2d TransitionMatrix(double t) const {
    const double a = 0.5 * c_, wd = std::sqrt(k_ - a * a);
    const double e = std::exp(-a * t), co = std::cos(wd * t), si = std::sin(wd * t);
    Eigen::Matrix2d phi;
    phi << e * (co + a / wd * si), e * si / wd,  //
        -e * k_ / wd * si, e * (co - a / wd * si);
    return phi;
  }
  // d/dtheta_j of expm(A t) x0 from Van Loan's block exponential:
  //   expm([[A, dA/dtheta_j], [0, A]] t) has d expm(A t)/dtheta_j in its upper-right block.
  Eigen::Matrix2d ParameterSensitivity(double t, const Eigen::Vector2d& x0) const {
    Eigen::Matrix2d result;
    for (int j = 0; j < 2; ++j) {
      Eigen::Matrix2d dA = Eigen::Matrix2d::Zero();
      dA(1, j) = -1.0;  // dA/dk = [[0,0],[-1,0]], dA/dc = [[0,0],[0,-1]].
      Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
      M.topLeftCorner<2, 2>() = A();
      M.bottomRightCorner<2, 2>() = A();
      M.topRightCorner<2, 2>() = dA;
      const Eigen::Matrix4d E = (M * t).exp();
      result.col(j) = E.topRightCorner<2, 2>() * x0;
    }
    return result;
  }

 private:
  double k_, c_;
};

// Logistic growth x' = r x (1 - x/K), parameters (r, K). With E = e^{rt} and
// D = K + x0 (E - 1):
//   x(t)   = K x0 E / D
//   dx/dx0 = K^2 E / D^2
//   dx/dr  = K x0 t E (K - x0) / D^2
//   dx/dK  = x0^2 E (E - 1) / D^2
class Logistic : public OdeSystem {
 public:
  Logistic(double r, double K) : r_(r), K_(K) {}
  int NumStates() const override { return 1; }
  int NumSensitivityParameters() const override { return 2; }
  bool Rhs(double t, const double* x, double* xdot) const override {
    xdot[0] = r_ * x[0] * (1.0 - x[0] / K_);
    return true;
  }
  bool Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                 Eigen::MatrixXd* dfdp) const override {
    (*dfdx)(0, 0) = r_ * (1.0 - 2.0 * x[0] / K_);
    if (dfdp != nullptr) {
      (*dfdp)(0, 0) = x[0] * (1.0 - x[0] / K_);
      (*dfdp)(0, 1) = r_ * x[0] * x[0] / (K_ * K_);
    }
    return true;
  }
  double Solution(double t, double x0) const {
    const double E = std::exp(r_ * t), D = K_ + x0 * (E - 1.0);
    return K_ * x0 * E / D;
  }
  // [dx/dx0, dx/dr, dx/dK].
  Eigen::RowVector3d Sensitivities(double t, double x0) const {
    const double E = std::exp(r_ * t), D = K_ + x0 * (E - 1.0), D2 = D * D;
    return Eigen::RowVector3d(K_ * K_ * E / D2, K_ * x0 * t * E * (K_ - x0) / D2,
                              x0 * x0 * E * (E - 1.0) / D2);
  }

 private:
  double r_, K_;
};

// Prothero-Robinson: x' = lambda (x - cos t) - sin t, x(0) = 1 has x = cos t; stiff for
// lambda << -1.
class ProtheroRobinson : public OdeSystem {
 public:
  explicit ProtheroRobinson(double lambda) : lambda_(lambda) {}
  int NumStates() const override { return 1; }
  int NumSensitivityParameters() const override { return 0; }
  bool Rhs(double t, const double* x, double* xdot) const override {
    xdot[0] = lambda_ * (x[0] - std::cos(t)) - std::sin(t);
    return true;
  }
  bool Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                 Eigen::MatrixXd* dfdp) const override {
    (*dfdx)(0, 0) = lambda_;
    return true;
  }

 private:
  double lambda_;
};

// The oscillator, failing (returning false, or NaN derivatives) after t_fail.
class FailingOscillator : public DampedOscillator {
 public:
  enum class Mode { kRhsFalse, kRhsNan, kJacobiansFalse };
  FailingOscillator(double t_fail, Mode mode)
      : DampedOscillator(4.0, 0.4), t_fail_(t_fail), mode_(mode) {}
  bool Rhs(double t, const double* x, double* xdot) const override {
    DampedOscillator::Rhs(t, x, xdot);
    if (t <= t_fail_) return true;
    if (mode_ == Mode::kRhsFalse) return false;
    if (mode_ == Mode::kRhsNan) xdot[1] = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  bool Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                 Eigen::MatrixXd* dfdp) const override {
    if (mode_ == Mode::kJacobiansFalse && t > t_fail_) return false;
    return DampedOscillator::Jacobians(t, x, dfdx, dfdp);
  }

 private:
  double t_fail_;
  Mode mode_;
};

// x' = u with u = 1 on [0, 1) and 1000 after: records the latest time the integrator asked
// for, to check that the stop time keeps it from stepping past an input change.
class StopTimeProbe : public OdeSystem {
 public:
  int NumStates() const override { return 1; }
  int NumSensitivityParameters() const override { return 0; }
  bool Rhs(double t, const double* x, double* xdot) const override {
    max_t_ = std::max(max_t_, t);
    xdot[0] = t < 1.0 ? 1.0 : 1000.0;
    return true;
  }
  bool Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                 Eigen::MatrixXd* dfdp) const override {
    (*dfdx)(0, 0) = 0.0;
    return true;
  }
  double max_t() const { return max_t_; }

 private:
  mutable double max_t_ = -1.0;
};

struct Config {
  const char* name;
  IntegratorOptions::Method method;
  bool newton;
};

IntegratorOptions MakeOptions(const Config& config, double rtol = 1e-7, double atol = 1e-9) {
  IntegratorOptions options;
  options.method = config.method;
  options.newton = config.newton;
  options.relative_tolerance = rtol;
  options.absolute_tolerance = atol;
  return options;
}

class IntegratorMethodTest : public ::testing::TestWithParam<Config> {};

const Config kConfigs[] = {
    {"AdamsFixedPoint", IntegratorOptions::Method::kAdams, false},
    {"BdfNewton", IntegratorOptions::Method::kBdf, true},
    {"AdamsNewton", IntegratorOptions::Method::kAdams, true},
    {"BdfFixedPoint", IntegratorOptions::Method::kBdf, false},
};
INSTANTIATE_TEST_SUITE_P(Methods, IntegratorMethodTest, ::testing::ValuesIn(kConfigs),
                         [](const ::testing::TestParamInfo<Config>& info) {
                           return std::string(info.param.name);
                         });

TEST_P(IntegratorMethodTest, OscillatorStateMatchesClosedForm) {
  const DampedOscillator system(4.0, 0.4);
  const IntegratorOptions options = MakeOptions(GetParam());
  Integrator integrator(system, options);
  const Eigen::Vector2d x0(1.0, -0.5);
  ASSERT_TRUE(integrator.Reset(0.0, x0));
  Eigen::VectorXd x;
  for (double t1 : {0.5, 3.0, 10.0}) {
    ASSERT_TRUE(integrator.AdvanceTo(t1, &x)) << integrator.last_error();
    const Eigen::Vector2d expected = system.TransitionMatrix(t1) * x0;
    // Scale |x| <= 2 (the amplitude of (x, v) from x0 = (1, -0.5), omega ~ 2).
    const double tol =
        kGlobalErrorFactor * (options.relative_tolerance * 2.0 + options.absolute_tolerance);
    EXPECT_NEAR(x[0], expected[0], tol) << "t1 = " << t1;
    EXPECT_NEAR(x[1], expected[1], tol) << "t1 = " << t1;
  }
  EXPECT_DOUBLE_EQ(integrator.time(), 10.0);
}

TEST_P(IntegratorMethodTest, LogisticStateAndSensitivitiesMatchClosedForm) {
  const Logistic system(1.5, 2.0);
  const IntegratorOptions options = MakeOptions(GetParam());
  Integrator integrator(system, options, {true, true});
  ASSERT_EQ(integrator.num_sensitivities(), 3);
  const double x0 = 0.1;
  ASSERT_TRUE(integrator.Reset(0.0, Eigen::VectorXd::Constant(1, x0)));
  Eigen::VectorXd x;
  Eigen::MatrixXd S;
  for (double t1 : {1.0, 2.5, 6.0}) {
    ASSERT_TRUE(integrator.AdvanceTo(t1, &x, &S)) << integrator.last_error();
    ASSERT_EQ(S.rows(), 1);
    ASSERT_EQ(S.cols(), 3);
    // Scale: x <= K = 2.
    EXPECT_NEAR(
        x[0], system.Solution(t1, x0),
        kGlobalErrorFactor * (options.relative_tolerance * 2.0 + options.absolute_tolerance))
        << "t1 = " << t1;
    const Eigen::RowVector3d expected = system.Sensitivities(t1, x0);
    for (int j = 0; j < 3; ++j) {
      // Scale: the largest sensitivity over the run, dx/dx0 = K^2 E / D^2 <= 5.3 (at E = 19).
      const double scale = 6.0;
      EXPECT_NEAR(
          S(0, j), expected[j],
          kGlobalErrorFactor * (options.relative_tolerance * scale + options.absolute_tolerance))
          << "t1 = " << t1 << ", column " << j;
    }
  }
}

TEST_P(IntegratorMethodTest, OscillatorSensitivitiesMatchClosedFormAndFiniteDifferences) {
  const double k = 4.0, c = 0.4, t1 = 5.0;
  const Eigen::Vector2d x0(1.0, -0.5);
  const DampedOscillator system(k, c);
  const IntegratorOptions options = MakeOptions(GetParam());
  Integrator integrator(system, options, {true, true});
  ASSERT_EQ(integrator.num_sensitivities(), 4);
  ASSERT_TRUE(integrator.Reset(0.0, x0));
  Eigen::VectorXd x;
  Eigen::MatrixXd S;
  ASSERT_TRUE(integrator.AdvanceTo(t1, &x, &S)) << integrator.last_error();
  ASSERT_EQ(S.rows(), 2);
  ASSERT_EQ(S.cols(), 4);

  Eigen::Matrix<double, 2, 4> expected;
  expected.leftCols<2>() = system.TransitionMatrix(t1);
  expected.rightCols<2>() = system.ParameterSensitivity(t1, x0);
  // Scale: |S| <= 5 (the parameter columns grow like t |x|).
  const double tol_closed =
      kGlobalErrorFactor * (options.relative_tolerance * 5.0 + options.absolute_tolerance);
  EXPECT_LT((S - expected).cwiseAbs().maxCoeff(), tol_closed) << "S =\n"
                                                              << S << "\nexpected\n"
                                                              << expected;

  // Central differences of whole integrations at tight tolerances (rtol 1e-12): the
  // integration error, which is not smooth in the perturbation, contributes about
  // 1e-11 / (2 delta) = 5e-8, and the truncation error delta^2/6 |d^3 x/d theta^3| is 1.4e-8
  // (measured: 1.4e-6 at delta = 1e-3); allow 1e-6.
  const double delta = 1e-4;
  const IntegratorOptions tight = MakeOptions(GetParam(), 1e-12, 1e-14);
  auto solve = [&](double kk, double cc, const Eigen::Vector2d& xx0) {
    const DampedOscillator perturbed(kk, cc);
    Integrator fd_integrator(perturbed, tight);
    Eigen::VectorXd out;
    EXPECT_TRUE(fd_integrator.Reset(0.0, xx0));
    EXPECT_TRUE(fd_integrator.AdvanceTo(t1, &out)) << fd_integrator.last_error();
    return Eigen::Vector2d(out);
  };
  Eigen::Matrix<double, 2, 4> fd;
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector2d e = Eigen::Vector2d::Unit(i) * delta;
    fd.col(i) = (solve(k, c, x0 + e) - solve(k, c, x0 - e)) / (2 * delta);
  }
  fd.col(2) = (solve(k + delta, c, x0) - solve(k - delta, c, x0)) / (2 * delta);
  fd.col(3) = (solve(k, c + delta, x0) - solve(k, c - delta, x0)) / (2 * delta);
  EXPECT_LT((fd - expected).cwiseAbs().maxCoeff(), 1e-6) << "fd =\n" << fd;
  EXPECT_LT((S - fd).cwiseAbs().maxCoeff(), tol_closed + 1e-6);
}

TEST_P(IntegratorMethodTest, LogisticSensitivitiesMatchFiniteDifferences) {
  const double r = 1.5, K = 2.0, x0 = 0.1, t1 = 4.0;
  const IntegratorOptions options = MakeOptions(GetParam());
  const Logistic system(r, K);
  Integrator integrator(system, options, {true, true});
  Eigen::VectorXd x;
  Eigen::MatrixXd S;
  ASSERT_TRUE(integrator.Reset(0.0, Eigen::VectorXd::Constant(1, x0)));
  ASSERT_TRUE(integrator.AdvanceTo(t1, &x, &S)) << integrator.last_error();

  // Same error budget as the oscillator: integration noise ~1e-11 / (2 delta), truncation
  // delta^2/6 |d^3x/dtheta^3|; with delta = 1e-4 relative to each quantity both stay < 1e-6.
  const IntegratorOptions tight = MakeOptions(GetParam(), 1e-12, 1e-14);
  auto solve = [&](double rr, double KK, double xx0) {
    const Logistic perturbed(rr, KK);
    Integrator fd_integrator(perturbed, tight);
    Eigen::VectorXd out;
    EXPECT_TRUE(fd_integrator.Reset(0.0, Eigen::VectorXd::Constant(1, xx0)));
    EXPECT_TRUE(fd_integrator.AdvanceTo(t1, &out)) << fd_integrator.last_error();
    return out[0];
  };
  const double d0 = 1e-4 * x0, dr = 1e-4 * r, dK = 1e-4 * K;
  const Eigen::RowVector3d fd((solve(r, K, x0 + d0) - solve(r, K, x0 - d0)) / (2 * d0),
                              (solve(r + dr, K, x0) - solve(r - dr, K, x0)) / (2 * dr),
                              (solve(r, K + dK, x0) - solve(r, K - dK, x0)) / (2 * dK));
  const Eigen::RowVector3d exact = system.Sensitivities(t1, x0);
  EXPECT_LT((fd - exact).cwiseAbs().maxCoeff(), 1e-5 * exact.cwiseAbs().maxCoeff());
  const double scale = std::max(1.0, exact.cwiseAbs().maxCoeff());
  EXPECT_LT(
      (S - fd).cwiseAbs().maxCoeff(),
      kGlobalErrorFactor * options.relative_tolerance * scale + 1e-5 * exact.cwiseAbs().maxCoeff());
}

TEST_P(IntegratorMethodTest, ThousandRestartsMatchOneUninterruptedRun) {
  const double k = 4.0, c = 0.4, t_end = 10.0;
  const int kRestarts = 1000;
  const DampedOscillator system(k, c);
  const Eigen::Vector2d x0(1.0, -0.5);
  const IntegratorOptions options = MakeOptions(GetParam());

  Integrator once(system, options, {true, true});
  Eigen::VectorXd x_once;
  Eigen::MatrixXd S_once;
  ASSERT_TRUE(once.Reset(0.0, x0));
  ASSERT_TRUE(once.AdvanceTo(t_end, &x_once, &S_once)) << once.last_error();

  Integrator restarted(system, options, {true, true});
  Eigen::VectorXd x = x0;
  Eigen::MatrixXd S;  // Empty: the natural S0 for the first interval.
  for (int i = 0; i < kRestarts; ++i) {
    // Interval ends from the index, so the last one lands exactly on t_end.
    const double t0 = t_end * i / kRestarts, t1 = t_end * (i + 1) / kRestarts;
    ASSERT_TRUE(restarted.Reset(t0, x, i == 0 ? nullptr : &S)) << restarted.last_error();
    ASSERT_TRUE(restarted.AdvanceTo(t1, &x, &S))
        << "interval " << i << ": " << restarted.last_error();
  }
  // Scale |x| <= 2, |S| <= 5. The uninterrupted run is within kGlobalErrorFactor tol of the
  // truth, the restarted one within RestartedBound(); they differ by at most the sum.
  const double local_x = options.relative_tolerance * 2.0 + options.absolute_tolerance;
  const double local_S = options.relative_tolerance * 5.0 + options.absolute_tolerance;
  const Eigen::Vector2d exact = system.TransitionMatrix(t_end) * x0;
  Eigen::Matrix<double, 2, 4> exact_S;
  exact_S << system.TransitionMatrix(t_end), system.ParameterSensitivity(t_end, x0);
  EXPECT_LT((x_once - exact).cwiseAbs().maxCoeff(), kGlobalErrorFactor * local_x);
  EXPECT_LT((S_once - exact_S).cwiseAbs().maxCoeff(), kGlobalErrorFactor * local_S);
  EXPECT_LT((x - exact).cwiseAbs().maxCoeff(), RestartedBound(kRestarts, local_x));
  EXPECT_LT((S - exact_S).cwiseAbs().maxCoeff(), RestartedBound(kRestarts, local_S));
  EXPECT_LT((x - x_once).cwiseAbs().maxCoeff(),
            RestartedBound(kRestarts, local_x) + kGlobalErrorFactor * local_x);
  EXPECT_LT((S - S_once).cwiseAbs().maxCoeff(),
            RestartedBound(kRestarts, local_S) + kGlobalErrorFactor * local_S);

  const Integrator::Stats stats = restarted.stats();
  EXPECT_EQ(stats.restarts, kRestarts);
  EXPECT_GE(stats.steps, kRestarts);  // At least one step per interval, summed over ReInits.
  EXPECT_GT(stats.rhs_evals, stats.steps);
  EXPECT_GE(stats.jac_evals, kRestarts);  // Sensitivities need >= 1 Jacobian per interval.
}

TEST_P(IntegratorMethodTest, RestartsWithoutInitialStepHintAgree) {
  const DampedOscillator system(4.0, 0.4);
  const Eigen::Vector2d x0(1.0, -0.5);
  IntegratorOptions options = MakeOptions(GetParam());
  Eigen::Vector2d result[2];
  for (int hint = 0; hint < 2; ++hint) {
    options.initial_step_hint = hint == 1;
    Integrator integrator(system, options);
    Eigen::VectorXd x = x0;
    for (int i = 0; i < 200; ++i) {
      ASSERT_TRUE(integrator.Reset(0.005 * i, x));
      ASSERT_TRUE(integrator.AdvanceTo(0.005 * (i + 1), &x)) << integrator.last_error();
    }
    result[hint] = x;
  }
  // Scale |x| <= 2; 200 restarts each.
  const double bound =
      RestartedBound(200, options.relative_tolerance * 2.0 + options.absolute_tolerance);
  const Eigen::Vector2d exact = system.TransitionMatrix(1.0) * x0;
  EXPECT_LT((result[0] - exact).cwiseAbs().maxCoeff(), bound);
  EXPECT_LT((result[1] - exact).cwiseAbs().maxCoeff(), bound);
}

// Tolerance proportionality: 1000x tighter tolerances (rtol 1e-5 -> 1e-8, atol rtol / 100)
// give a much smaller error on the oscillator over 10 s, one uninterrupted run each.
void ExpectErrorShrinksWithTolerance(IntegratorOptions options) {
  const DampedOscillator system(4.0, 0.4);
  const Eigen::Vector2d x0(1.0, -0.5);
  const Eigen::Vector2d exact = system.TransitionMatrix(10.0) * x0;
  double errors[2];
  const double rtols[2] = {1e-5, 1e-8};
  for (int i = 0; i < 2; ++i) {
    options.relative_tolerance = rtols[i];
    options.absolute_tolerance = rtols[i] * 1e-2;
    Integrator integrator(system, options);
    Eigen::VectorXd x;
    ASSERT_TRUE(integrator.Reset(0.0, x0));
    ASSERT_TRUE(integrator.AdvanceTo(10.0, &x));
    errors[i] = (x - exact).cwiseAbs().maxCoeff();
  }
  EXPECT_LT(errors[1], errors[0] / 30.0) << errors[0] << " " << errors[1];
}

TEST_P(IntegratorMethodTest, ErrorShrinksWithTolerance) {
  ExpectErrorShrinksWithTolerance(MakeOptions(GetParam()));
}

TEST_P(IntegratorMethodTest, StopTimeKeepsStepsBeforeInputChange) {
  const StopTimeProbe system;
  Integrator integrator(system, MakeOptions(GetParam()));
  Eigen::VectorXd x;
  ASSERT_TRUE(integrator.Reset(0.0, Eigen::VectorXd::Zero(1)));
  ASSERT_TRUE(integrator.AdvanceTo(1.0, &x)) << integrator.last_error();
  EXPECT_LE(system.max_t(), 1.0);
  // x' = 1 exactly (the order-1 method is exact for it): x(1) = 1 up to round-off.
  EXPECT_NEAR(x[0], 1.0, 1e-12);
}

TEST_P(IntegratorMethodTest, RhsReturningFalseFailsWithMessage) {
  for (bool with_sens : {false, true}) {
    const FailingOscillator system(0.3, FailingOscillator::Mode::kRhsFalse);
    Integrator integrator(system, MakeOptions(GetParam()), {with_sens, with_sens});
    Eigen::VectorXd x;
    Eigen::MatrixXd S;
    ASSERT_TRUE(integrator.Reset(0.0, Eigen::Vector2d(1.0, 0.0)));
    ASSERT_TRUE(integrator.AdvanceTo(0.2, &x, &S)) << integrator.last_error();
    EXPECT_FALSE(integrator.AdvanceTo(1.0, &x, &S));
    EXPECT_NE(integrator.last_error().find("Rhs returned false"), std::string::npos)
        << integrator.last_error();
    // Unusable until Reset.
    EXPECT_FALSE(integrator.AdvanceTo(2.0, &x, &S));
    EXPECT_NE(integrator.last_error().find("without Reset"), std::string::npos)
        << integrator.last_error();
    // Failing at the very first RHS call too.
    ASSERT_TRUE(integrator.Reset(0.5, Eigen::Vector2d(1.0, 0.0)));
    EXPECT_FALSE(integrator.AdvanceTo(1.0, &x, &S));
    EXPECT_FALSE(integrator.last_error().empty());
    // And usable again after a Reset where the RHS works.
    ASSERT_TRUE(integrator.Reset(0.0, Eigen::Vector2d(1.0, 0.0)));
    EXPECT_TRUE(integrator.AdvanceTo(0.25, &x, &S)) << integrator.last_error();
  }
}

TEST_P(IntegratorMethodTest, NonFiniteRhsFailsWithMessage) {
  const FailingOscillator system(0.3, FailingOscillator::Mode::kRhsNan);
  Integrator integrator(system, MakeOptions(GetParam()));
  Eigen::VectorXd x;
  ASSERT_TRUE(integrator.Reset(0.0, Eigen::Vector2d(1.0, 0.0)));
  EXPECT_FALSE(integrator.AdvanceTo(1.0, &x));
  EXPECT_FALSE(integrator.last_error().empty());
}

TEST_P(IntegratorMethodTest, JacobiansReturningFalseFailsWithMessage) {
  const FailingOscillator system(0.3, FailingOscillator::Mode::kJacobiansFalse);
  Integrator integrator(system, MakeOptions(GetParam()), {false, true});
  Eigen::VectorXd x;
  Eigen::MatrixXd S;
  ASSERT_TRUE(integrator.Reset(0.0, Eigen::Vector2d(1.0, 0.0)));
  EXPECT_FALSE(integrator.AdvanceTo(1.0, &x, &S));
  EXPECT_NE(integrator.last_error().find("Jacobians returned false"), std::string::npos)
      << integrator.last_error();
}

TEST(IntegratorTest, BdfNewtonHandlesStiffProblemInFewSteps) {
  const ProtheroRobinson system(-1e4);
  long steps[2];
  for (int newton = 0; newton < 2; ++newton) {
    IntegratorOptions options;
    options.method = newton ? IntegratorOptions::Method::kBdf : IntegratorOptions::Method::kAdams;
    options.newton = newton == 1;
    options.max_steps_per_interval = 100000;
    Integrator integrator(system, options);
    Eigen::VectorXd x;
    ASSERT_TRUE(integrator.Reset(0.0, Eigen::VectorXd::Ones(1)));
    ASSERT_TRUE(integrator.AdvanceTo(2.0, &x)) << integrator.last_error();
    // Scale |x| <= 1.
    EXPECT_NEAR(x[0], std::cos(2.0),
                kGlobalErrorFactor * (options.relative_tolerance + options.absolute_tolerance));
    steps[newton] = integrator.stats().steps;
    if (newton) {
      EXPECT_GT(integrator.stats().jac_evals, 0);
    }
  }
  // Explicit-like Adams/fixed-point is stability-limited (h ~ 1/|lambda|): thousands of steps.
  EXPECT_LT(10 * steps[1], steps[0]) << steps[1] << " vs " << steps[0];
}

TEST(IntegratorTest, UsageErrors) {
  const DampedOscillator system(4.0, 0.4);
  Integrator integrator(system, IntegratorOptions{});
  Eigen::VectorXd x;
  EXPECT_FALSE(integrator.AdvanceTo(1.0, &x));
  EXPECT_NE(integrator.last_error().find("before Reset"), std::string::npos);
  ASSERT_TRUE(integrator.Reset(1.0, Eigen::Vector2d(1.0, 0.0)));
  EXPECT_TRUE(integrator.last_error().empty());
  EXPECT_FALSE(integrator.AdvanceTo(1.0, &x));  // Not after the current time.
  EXPECT_FALSE(integrator.AdvanceTo(0.5, &x));
  EXPECT_FALSE(integrator.last_error().empty());
  EXPECT_TRUE(integrator.AdvanceTo(1.5, &x)) << integrator.last_error();  // Still usable.
  EXPECT_EQ(integrator.num_sensitivities(), 0);
  Eigen::MatrixXd S;
  EXPECT_TRUE(integrator.AdvanceTo(2.0, &x, &S));
  EXPECT_EQ(S.cols(), 0);
  EXPECT_FALSE(integrator.Reset(0.0, Eigen::Vector2d(std::nan(""), 0.0)));
}

TEST(IntegratorTest, ExplicitInitialSensitivityAndContinuation) {
  // S0 supplied by the caller propagates linearly: S(t) = Phi(t) S0 for the state columns.
  const DampedOscillator system(4.0, 0.4);
  IntegratorOptions options;
  Integrator integrator(system, options, {true, false});
  const Eigen::Vector2d x0(0.3, 0.7);
  Eigen::MatrixXd S0(2, 2);
  S0 << 2.0, -1.0, 0.5, 3.0;
  ASSERT_TRUE(integrator.Reset(0.0, x0, &S0));
  Eigen::VectorXd x;
  Eigen::MatrixXd S;
  // Several AdvanceTo calls without Reset continue the same run.
  for (double t1 : {0.7, 1.9, 4.0}) ASSERT_TRUE(integrator.AdvanceTo(t1, &x, &S));
  const Eigen::Matrix2d expected = system.TransitionMatrix(4.0) * S0;
  EXPECT_LT((S - expected).cwiseAbs().maxCoeff(),
            kGlobalErrorFactor * (options.relative_tolerance * 3.0 + options.absolute_tolerance));
}

TEST(IntegratorTest, MovedIntegratorKeepsWorking) {
  const Logistic system(1.5, 2.0);
  Integrator a(system, IntegratorOptions{}, {true, true});
  ASSERT_TRUE(a.Reset(0.0, Eigen::VectorXd::Constant(1, 0.1)));
  Integrator b = std::move(a);
  Eigen::VectorXd x;
  Eigen::MatrixXd S;
  ASSERT_TRUE(b.AdvanceTo(1.0, &x, &S)) << b.last_error();
  EXPECT_NEAR(x[0], system.Solution(1.0, 0.1), 1e-5);
}

TEST(IntegratorOptionsTest, Validation) {
  std::string why;
  EXPECT_TRUE(IntegratorOptions{}.IsValid(&why));
  IntegratorOptions bad;
  bad.relative_tolerance = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("relative_tolerance"), std::string::npos);
  bad = IntegratorOptions{};
  bad.absolute_tolerance = -1.0;
  EXPECT_FALSE(bad.IsValid(&why));
  bad = IntegratorOptions{};
  bad.method = IntegratorOptions::Method::kBdf;
  bad.max_order = 6;
  EXPECT_FALSE(bad.IsValid(&why));
  bad.method = IntegratorOptions::Method::kAdams;
  EXPECT_TRUE(bad.IsValid(&why));
  bad.max_steps_per_interval = 0;
  EXPECT_FALSE(bad.IsValid(&why));
  const DampedOscillator system(4.0, 0.4);
  EXPECT_THROW(Integrator(system, bad), InputError);
}

// The explicit Runge-Kutta back end (ARKODE ERKStep, Dormand-Prince 5(4)). Its error control is
// the same local test as CVODE's, so the same kGlobalErrorFactor applies to uninterrupted runs.
// Unlike a multistep method it keeps no history, so a restart costs no accuracy: restarted runs
// are held to the uninterrupted bound, with no allowance per restart.
IntegratorOptions ExplicitRungeKuttaOptions(double rtol = 1e-7, double atol = 1e-9) {
  IntegratorOptions options;
  options.method = IntegratorOptions::Method::kExplicitRungeKutta;
  options.relative_tolerance = rtol;
  options.absolute_tolerance = atol;
  return options;
}

TEST(ExplicitRungeKuttaTest, OscillatorMatchesClosedFormWithoutARestartAllowance) {
  const DampedOscillator system(4.0, 0.4);
  const IntegratorOptions options = ExplicitRungeKuttaOptions();
  const Eigen::Vector2d x0(1.0, -0.5);
  // Scale |x| <= 2.
  const double bound =
      kGlobalErrorFactor * (options.relative_tolerance * 2.0 + options.absolute_tolerance);
  Integrator once(system, options);
  Eigen::VectorXd x;
  ASSERT_TRUE(once.Reset(0.0, x0));
  for (double t1 : {0.5, 3.0, 10.0}) {
    ASSERT_TRUE(once.AdvanceTo(t1, &x)) << once.last_error();
    EXPECT_LT((x - system.TransitionMatrix(t1) * x0).cwiseAbs().maxCoeff(), bound);
  }
  const int kRestarts = 2000;  // 5 ms intervals, as the logs' inputs
  Integrator restarted(system, options);
  x = x0;
  for (int i = 0; i < kRestarts; ++i) {
    ASSERT_TRUE(restarted.Reset(0.005 * i, x));
    ASSERT_TRUE(restarted.AdvanceTo(0.005 * (i + 1), &x)) << restarted.last_error();
  }
  EXPECT_LT((x - system.TransitionMatrix(10.0) * x0).cwiseAbs().maxCoeff(), bound);
  const Integrator::Stats stats = restarted.stats();
  EXPECT_EQ(stats.restarts, kRestarts);
  EXPECT_GE(stats.steps, kRestarts);
  // The step learnt on one interval starts the next: one 7-stage step covers a 5 ms interval
  // of this slow oscillator, so about 7-8 RHS calls per interval (a multistep restart at
  // order 1 needs about twice that, bench/experiments/simulation/flight_bench.cc).
  EXPECT_LE(stats.steps, kRestarts + 10);
  EXPECT_LE(stats.rhs_evals, 9 * kRestarts);
  EXPECT_EQ(stats.jac_evals, 0);
}

TEST(ExplicitRungeKuttaTest, VariationalSensitivitiesMatchClosedForm) {
  // Sensitivities ride along as states (the error test on the first two only, as the output
  // error and EKF propagators use it).
  const DampedOscillator system(4.0, 0.4);
  const VariationalSystem augmented(system, true, true);
  IntegratorOptions options = ExplicitRungeKuttaOptions();
  options.error_controlled_states = 2;
  Integrator integrator(augmented, options);
  const Eigen::Vector2d x0(1.0, -0.5);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(augmented.NumStates());
  z.head(2) = x0;
  z[2] = 1.0;  // S0 = [I | 0], column-major after x
  z[5] = 1.0;
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(integrator.Reset(0.005 * i, z));
    ASSERT_TRUE(integrator.AdvanceTo(0.005 * (i + 1), &z)) << integrator.last_error();
  }
  Eigen::Matrix<double, 2, 4> expected;
  expected << system.TransitionMatrix(5.0), system.ParameterSensitivity(5.0, x0);
  const Eigen::Map<const Eigen::Matrix<double, 2, 4>> S(z.data() + 2);
  // Scale |S| <= 5; the sensitivities are not in the error test, but they follow the state's
  // steps and solve a linear system of the same time scales, so the state's bound holds.
  EXPECT_LT((S - expected).cwiseAbs().maxCoeff(),
            kGlobalErrorFactor * (options.relative_tolerance * 5.0 + options.absolute_tolerance));
}

TEST(ExplicitRungeKuttaTest, ErrorShrinksWithToleranceAndStopTimeHolds) {
  ExpectErrorShrinksWithTolerance(ExplicitRungeKuttaOptions());

  const StopTimeProbe probe;
  Integrator integrator(probe, ExplicitRungeKuttaOptions());
  Eigen::VectorXd x;
  ASSERT_TRUE(integrator.Reset(0.0, Eigen::VectorXd::Zero(1)));
  ASSERT_TRUE(integrator.AdvanceTo(1.0, &x)) << integrator.last_error();
  EXPECT_LE(probe.max_t(), 1.0);
  EXPECT_NEAR(x[0], 1.0, 1e-12);  // x' = 1 is integrated exactly
}

TEST(ExplicitRungeKuttaTest, FailuresSayWhyAndAResetRecovers) {
  for (auto mode : {FailingOscillator::Mode::kRhsFalse, FailingOscillator::Mode::kRhsNan}) {
    const FailingOscillator system(0.3, mode);
    Integrator integrator(system, ExplicitRungeKuttaOptions());
    Eigen::VectorXd x;
    ASSERT_TRUE(integrator.Reset(0.0, Eigen::Vector2d(1.0, 0.0)));
    ASSERT_TRUE(integrator.AdvanceTo(0.2, &x)) << integrator.last_error();
    EXPECT_FALSE(integrator.AdvanceTo(1.0, &x));
    const std::string expected =
        mode == FailingOscillator::Mode::kRhsFalse ? "Rhs returned false" : "non-finite";
    EXPECT_NE(integrator.last_error().find(expected), std::string::npos)
        << integrator.last_error();
    EXPECT_FALSE(integrator.AdvanceTo(2.0, &x));
    EXPECT_NE(integrator.last_error().find("without Reset"), std::string::npos);
    ASSERT_TRUE(integrator.Reset(0.0, Eigen::Vector2d(1.0, 0.0)));
    EXPECT_TRUE(integrator.AdvanceTo(0.25, &x)) << integrator.last_error();
  }
}

TEST(ExplicitRungeKuttaTest, CarriesNoCvodesSensitivitiesAndTakesNoNewtonOptions) {
  const DampedOscillator system(4.0, 0.4);
  EXPECT_THROW(Integrator(system, ExplicitRungeKuttaOptions(), {true, false}), InputError);
  std::string why;
  IntegratorOptions bad = ExplicitRungeKuttaOptions();
  EXPECT_TRUE(bad.IsValid(&why));
  bad.newton = true;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("newton"), std::string::npos);
  bad = ExplicitRungeKuttaOptions();
  bad.max_order = 5;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_THROW(Integrator(system, bad), InputError);
}

TEST(Rk4Test, MatchesClosedFormWithFourthOrderConvergence) {
  const DampedOscillator system(4.0, 0.4);
  const Eigen::Vector2d x0(1.0, -0.5);
  const Eigen::Vector2d exact = system.TransitionMatrix(10.0) * x0;
  double errors[2];
  const int steps[2] = {1000, 2000};
  for (int i = 0; i < 2; ++i) {
    Eigen::VectorXd x = x0;
    ASSERT_TRUE(IntegrateRk4(system, 0.0, 10.0, steps[i], &x));
    errors[i] = (x - exact).cwiseAbs().maxCoeff();
  }
  // h = 0.01, omega ~ 2: the global error ~ t omega^5 h^4 / 120 ~ 3e-8.
  EXPECT_LT(errors[0], 1e-7);
  // Halving h divides the error by 2^4 = 16 (asymptotic regime; allow 13-19).
  EXPECT_GT(errors[0] / errors[1], 13.0);
  EXPECT_LT(errors[0] / errors[1], 19.0);

  const Logistic logistic(1.5, 2.0);
  Eigen::VectorXd x = Eigen::VectorXd::Constant(1, 0.1);
  ASSERT_TRUE(IntegrateRk4(logistic, 0.0, 6.0, 6000, &x));
  EXPECT_NEAR(x[0], logistic.Solution(6.0, 0.1), 1e-10);
}

TEST(Rk4Test, RhsFailureReturnsFalse) {
  const FailingOscillator system(0.3, FailingOscillator::Mode::kRhsFalse);
  Eigen::VectorXd x = Eigen::Vector2d(1.0, 0.0);
  EXPECT_FALSE(IntegrateRk4(system, 0.0, 1.0, 100, &x));
}

}  // namespace
}  // namespace coaxid
