// The stabilizer bar (effects.md, stabilizer_bar), the first effect with
// states of its own: its states' derivative and loads against the formulas
// of effects.md, its Jacobian against central differences, and the damping
// it gives at hover. The simulator with the bar against an independent RK4
// and its sensitivities (bar states and parameters included) against finite
// differences of whole simulations: simulator_test.cc.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "core/errors.h"
#include "dynamics/model_jacobian.h"
#include "dynamics/trim.h"
#include "dynamics/vehicle.h"

namespace coaxid {
namespace {

constexpr double kTb = 1.8, kKb = 0.6, kDu = 0.165;

Vehicle WithBar(double k_b = kKb) {
  const Vehicle base = LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  std::map<std::string, ParameterOverride> o;
  o["T_b"].value = kTb;
  o["k_b"].value = k_b;
  o["d_u"].value = kDu;
  return WithEffect(base, "stabilizer_bar", o);
}

// A flight state away from hover, the bar tilted.
Eigen::VectorXd FlightState(int n) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  x[kZ] = -1.5;
  x[kU] = 0.4;
  x[kV] = -0.2;
  x[kW] = 0.1;
  x[kPhi] = 0.05;
  x[kTheta] = -0.03;
  x[kP] = 0.3;
  x[kQ] = -0.2;
  x[kR] = 0.1;
  x[kNumStates] = 0.04;       // b_x
  x[kNumStates + 1] = -0.07;  // b_y
  return x;
}

const double kInput[kNumInputs] = {150.0, 164.0, 0.02, -0.01};

TEST(StabilizerBar, OwnsTwoStatesAfterTheTwelve) {
  const Vehicle v = WithBar();
  EXPECT_EQ(v.model.NumStates(), kNumStates + 2);
  EXPECT_EQ(v.model.EffectStateOffset(EffectIndex("stabilizer_bar")), kNumStates);
  EXPECT_EQ(EffectLibrary()[EffectIndex("stabilizer_bar")].num_own_states, 2);
  const Vehicle base = LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  EXPECT_EQ(base.model.NumStates(), kNumStates);
  EXPECT_EQ(v.model.NameOfState(kR), "r");
  EXPECT_EQ(v.model.NameOfState(kNumStates), "stabilizer_bar.b_x");
  EXPECT_EQ(v.model.NameOfState(kNumStates + 1), "stabilizer_bar.b_y");
}

// db/dt = -(p, q) - b / T_b; X = -k_b b_y T1, Y = k_b b_x T1, L = d_u Y,
// M = -d_u X on top of the base model's loads; nothing else changes.
TEST(StabilizerBar, StatesAndLoadsFollowEffectsMd) {
  const Vehicle v = WithBar();
  const Vehicle base = LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  const Eigen::VectorXd th = v.parameters.Values(), th0 = base.parameters.Values();
  const Eigen::VectorXd x = FlightState(v.model.NumStates());
  const AeroLoads<double> with = v.model.Loads(th.data(), kInput, Setting::kFlight, x.data());
  const AeroLoads<double> without =
      base.model.Loads(th0.data(), kInput, Setting::kFlight, x.data());
  const double T1 = -without.Z1;
  ASSERT_GT(T1, 0);
  const double b_x = x[kNumStates], b_y = x[kNumStates + 1];
  const double X = -kKb * b_y * T1, Y = kKb * b_x * T1;
  const double tol = 1e-12 * T1;
  EXPECT_NEAR(with.force_B[0] - without.force_B[0], X, tol);
  EXPECT_NEAR(with.force_B[1] - without.force_B[1], Y, tol);
  EXPECT_NEAR(with.force_B[2], without.force_B[2], tol);
  EXPECT_NEAR(with.moment_B[0] - without.moment_B[0], kDu * Y, tol);
  EXPECT_NEAR(with.moment_B[1] - without.moment_B[1], -kDu * X, tol);
  EXPECT_NEAR(with.moment_B[2], without.moment_B[2], tol);
  // A balance holds the body: the bar rests on the shaft, no load.
  const AeroLoads<double> bal = v.model.Loads(th.data(), kInput, Setting::kBalance, static_cast<const double*>(nullptr));
  const AeroLoads<double> bal0 = base.model.Loads(th0.data(), kInput, Setting::kBalance, static_cast<const double*>(nullptr));
  EXPECT_EQ((bal.force_B - bal0.force_B).norm(), 0.0);
  EXPECT_EQ((bal.moment_B - bal0.moment_B).norm(), 0.0);

  Eigen::VectorXd f(v.model.NumStates()), f0(kNumStates);
  v.model.Derivative(th.data(), x.data(), kInput, f.data());
  EXPECT_NEAR(f[kNumStates], -x[kP] - b_x / kTb, 1e-15);
  EXPECT_NEAR(f[kNumStates + 1], -x[kQ] - b_y / kTb, 1e-15);
  // With k_b = 0 the rigid body moves as without the bar.
  const Vehicle off = WithBar(0.0);
  const Eigen::VectorXd th_off = off.parameters.Values();
  off.model.Derivative(th_off.data(), x.data(), kInput, f.data());
  base.model.Derivative(th0.data(), x.data(), kInput, f0.data());
  for (int i = 0; i < kNumStates; ++i) EXPECT_EQ(f[i], f0[i]) << StateName(i);
}

// The state Jacobian (14 x 14) and the parameter Jacobian by automatic
// differentiation against central differences of Derivative.
TEST(StabilizerBar, JacobiansMatchCentralDifferences) {
  const Vehicle v = WithBar();
  const int n = v.model.NumStates();
  const Eigen::VectorXd th = v.parameters.Values();
  const Eigen::VectorXd x = FlightState(n);
  std::vector<int> all(th.size());
  for (int i = 0; i < th.size(); ++i) all[i] = i;
  const HeldInput held = HeldInput::Steady({kInput[0], kInput[1], kInput[2], kInput[3]}, 0);
  Eigen::MatrixXd dfdx, dfdp;
  ASSERT_TRUE(DerivativeJacobians(v.model, th, x.data(), held, 0, all, &dfdx, &dfdp));
  ASSERT_EQ(dfdx.rows(), n);
  ASSERT_EQ(dfdx.cols(), n);
  auto f = [&](const Eigen::VectorXd& t, const Eigen::VectorXd& s) {
    Eigen::VectorXd out(n);
    v.model.Derivative(t.data(), s.data(), kInput, out.data());
    return out;
  };
  // Steps of 1e-6 of each coordinate's scale: truncation ~1e-12, round-off
  // ~1e-16 |f| / 1e-6; 1e-6 of the column's size covers both.
  for (int j = 0; j < n + th.size(); ++j) {
    Eigen::VectorXd t = th, s = x;
    double* c = j < n ? &s[j] : &t[j - n];
    const double h = 1e-6 * (j < n ? 1.0 : v.parameters[j - n].scale);
    const double saved = *c;
    *c = saved + h;
    const Eigen::VectorXd plus = f(t, s);
    *c = saved - h;
    const Eigen::VectorXd fd = (plus - f(t, s)) / (2 * h);
    const Eigen::VectorXd ad = j < n ? Eigen::VectorXd(dfdx.col(j)) : Eigen::VectorXd(dfdp.col(j - n));
    EXPECT_LT((fd - ad).norm(), 1e-6 * std::max(1.0, ad.norm()))
        << (j < n ? "state " + std::to_string(j) : v.parameters[j - n].name) << "\nFD " << fd.transpose()
        << "\nAD " << ad.transpose();
  }
}

// At hover trim the bar is a lagged rate damper: a pitch rate tilts the bar
// back (d(b_y)/dt = -q), the tilted bar tilts the upper thrust forward and
// pitches the nose down, dq/dt per b_y = d_u k_b T1 / Iyy > 0 (and du/dt per
// b_y = -k_b T1 / m): q > 0 drives b_y < 0, which drives q back.
TEST(StabilizerBar, DampsThePitchRateAtHover) {
  const Vehicle v = WithBar();
  const Eigen::VectorXd th = v.parameters.Values();
  const HoverTrim trim = TrimHover(v.model, th, 1.5);
  ASSERT_EQ(trim.state.size(), v.model.NumStates());
  EXPECT_EQ(trim.state[kNumStates], 0.0);
  Eigen::MatrixXd A;
  ASSERT_TRUE(DerivativeJacobians(v.model, th, trim.state.data(), HeldInput::Steady(trim.input, 0), 0,
                                  {}, &A, nullptr));
  const double T1 = -v.model.Loads(th.data(), trim.input.data(), Setting::kFlight,
                                   trim.state.data()).Z1;
  const int bx = kNumStates, by = kNumStates + 1;
  EXPECT_NEAR(A(kQ, by), kDu * kKb * T1 / th[kIyy], 1e-9 * A(kQ, by));
  EXPECT_NEAR(A(kP, bx), kDu * kKb * T1 / th[kIxx], 1e-9 * A(kP, bx));
  EXPECT_NEAR(A(kU, by), -kKb * T1 / th[kMass], 1e-9 * std::fabs(A(kU, by)));
  EXPECT_DOUBLE_EQ(A(by, kQ), -1.0);
  EXPECT_DOUBLE_EQ(A(by, by), -1.0 / kTb);
  // The loop q -> b_y -> q: the product of the two couplings is negative
  // (a negative feedback on the pitch rate).
  EXPECT_LT(A(by, kQ) * A(kQ, by), 0.0);
}

}  // namespace
}  // namespace coaxid
