// TrimHover (dynamics/trim.h) on the reference vehicle (configs/glmav.yaml):
// the trim is an equilibrium of the 12-state derivative, and matches the
// closed forms of the paper's model at hover (model.md, "Reference vehicle":
// hover near 150 rad/s; the yaw balance N = 0 of eq. 33 gives
// omega2 / omega1 = sqrt(gamma1 / -gamma2)); with cg_offset or wind enabled it
// tilts by the closed-form angles and is still an equilibrium.
//
// Tolerances. TrimHover stops when every acceleration is below 1e-10 (its
// default tolerance, m/s^2 and rad/s^2); the equilibrium check allows 1e-9.
// Closed-form inputs and angles follow from the residual through Jacobians of
// order one or more (dZ/domega ~ 0.03 N s, g for an angle), so they hold to
// ~1e-10; we allow 1e-8 relative (angles 1e-9 rad). The model's smoothings
// (wake radicand ~45 m^2/s^2, airspeed ~7 m/s) shift the trim by ~1e-14.
#include "dynamics/trim.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <string>

#include "core/input_hold.h"
#include "core/parameters.h"
#include "dynamics/rigid_body.h"
#include "dynamics/state.h"
#include "dynamics/vehicle.h"

namespace coaxid {
namespace {

constexpr double kEquilibriumTol = 1e-9;
constexpr double kInputRel = 1e-8;
constexpr double kAngleTol = 1e-9;

Vehicle Reference() { return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml"); }

Vehicle With(const Vehicle& base, const std::string& effect,
             const std::map<std::string, double>& values) {
  std::map<std::string, ParameterOverride> overrides;
  for (const auto& [name, value] : values) overrides[name].value = value;
  return WithEffect(base, effect, overrides);
}

void ExpectEquilibrium(const Vehicle& v, const HoverTrim& trim, const std::string& what) {
  const Eigen::VectorXd theta = v.parameters.Values();
  State f;
  v.model.Derivative(theta.data(), trim.state.data(), trim.input.data(), f.data());
  for (int i = 0; i < kNumStates; ++i) {
    EXPECT_NEAR(f[i], 0.0, kEquilibriumTol) << what << ": d" << StateName(i) << "/dt";
  }
  // Still: zero velocity and rates; the position and heading asked for.
  for (int i : {kU, kV, kW, kP, kQ, kR}) EXPECT_EQ(trim.state[i], 0.0) << StateName(i);
  EXPECT_LE(trim.residual, 1e-10) << what;
}

// Paper's model at hover, level, no swashplate: Z_T (1 - S_s Cz / S_prop) =
// -m g cos(theta) cos(phi), because the wake body force of eq. 60 is
// 0.5 rho S_s Cz V_prop^2 = -S_s Cz Z_T / S_prop.
double BodyForceFactor(const Eigen::VectorXd& th) {
  const double S_s = M_PI * th[kBodyRadius] * th[kBodyRadius];
  const double S_prop = M_PI * th[kRotorRadius] * th[kRotorRadius];
  return 1.0 - S_s * th[kCz] / S_prop;
}

double Sigma(double sigma0, double omega1, double omega2) {
  const double w1 = omega1 * omega1, w2 = omega2 * omega2;
  return 1.0 - sigma0 * 4.0 * w1 * w2 / ((w1 + w2) * (w1 + w2));
}

// Closed-form hover speeds of the paper's model (no effect): N = 0 fixes the
// ratio, Z balance the level (sigma depends only on the ratio).
void ClosedFormHover(const Eigen::VectorXd& th, double* omega1, double* omega2) {
  const double ratio = std::sqrt(th[kGamma1] / -th[kGamma2]);  // omega2 / omega1
  const double sigma = Sigma(th[kSigma0], 1.0, ratio);
  const double mg = th[kMass] * th[kGravity];
  const double w1 = -mg / (sigma * BodyForceFactor(th) * (th[kAlpha] + th[kBeta] * ratio * ratio));
  *omega1 = std::sqrt(w1);
  *omega2 = ratio * *omega1;
}

TEST(TrimTest, ReferenceHoverIsAnEquilibriumAtTheClosedFormSpeeds) {
  const Vehicle v = Reference();
  const Eigen::VectorXd th = v.parameters.Values();
  const HoverTrim trim = TrimHover(v.model, th, 1.0);
  ExpectEquilibrium(v, trim, "reference");
  EXPECT_EQ(trim.state[kZ], -1.0);  // height 1 m, NED
  EXPECT_EQ(trim.state[kPsi], 0.0);

  const double omega1 = trim.input[kOmega1], omega2 = trim.input[kOmega2];
  // model.md: hover near 150 rad/s; with gamma1 / -gamma2 = 1.2 the lower
  // rotor turns sqrt(1.2) = 1.095 times faster: ~150 / ~164 rad/s.
  EXPECT_NEAR(omega1, 150.0, 1.0);
  EXPECT_NEAR(omega2, 164.0, 1.0);
  EXPECT_NEAR(omega2 / omega1, std::sqrt(th[kGamma1] / -th[kGamma2]), kInputRel);
  double w1, w2;
  ClosedFormHover(th, &w1, &w2);
  EXPECT_NEAR(omega1, w1, kInputRel * w1);
  EXPECT_NEAR(omega2, w2, kInputRel * w2);
  // No moment needed: swashplate centred, level.
  EXPECT_NEAR(trim.input[kDeltaCx], 0.0, kAngleTol);
  EXPECT_NEAR(trim.input[kDeltaCy], 0.0, kAngleTol);
  EXPECT_NEAR(trim.state[kPhi], 0.0, kAngleTol);
  EXPECT_NEAR(trim.state[kTheta], 0.0, kAngleTol);
}

// Heading and height change nothing without wind or ground effect.
TEST(TrimTest, HeadingAndHeightDoNotChangeTheTrimOfThePapersModel) {
  const Vehicle v = Reference();
  const Eigen::VectorXd th = v.parameters.Values();
  const HoverTrim a = TrimHover(v.model, th, 1.0, 0.0);
  const HoverTrim b = TrimHover(v.model, th, 3.0, 2.1);
  ExpectEquilibrium(v, b, "heading 2.1, 3 m");
  EXPECT_EQ(b.state[kPsi], 2.1);
  EXPECT_EQ(b.state[kZ], -3.0);
  for (int k = 0; k < kNumInputs; ++k) {
    EXPECT_NEAR(a.input[k], b.input[k], kInputRel * (1 + std::fabs(a.input[k]))) << k;
  }
}

// cg_offset: the rotor force Z_T, off G by (x_g, y_g), makes L = y_g Z_T and
// M = -x_g Z_T; the swashplate cancels them (eqs. 31-32) and the lateral
// force this costs (eq. 9) is balanced by tilting the weight (eq. 27):
//   X: -beta sin(dcy) cos(dcx) w2^2 - m g sin(theta) = 0
//   M: d beta sin(dcy) cos(dcx) w2^2 = x_g Z_T
//   Y: -beta sin(dcx) w2^2 + m g cos(theta) sin(phi) = 0
//   L: d beta sin(dcx) w2^2 = y_g Z_T
//   Z: Z_T (1 - S_s Cz / S_prop) = -m g cos(theta) cos(phi)
// so tan(phi) = -y_g / (d k) and tan(theta) = x_g cos(phi) / (d k), k the
// body-force factor.
TEST(TrimTest, CgOffsetTiltsTheTrimByTheClosedFormAngles) {
  const double x_g = 4e-3, y_g = -3e-3;
  const Vehicle v = With(Reference(), "cg_offset", {{"x_g", x_g}, {"y_g", y_g}});
  const Eigen::VectorXd th = v.parameters.Values();
  const HoverTrim trim = TrimHover(v.model, th, 1.0);
  ExpectEquilibrium(v, trim, "cg_offset");
  const double k = BodyForceFactor(th), d = th[kHubDistance], beta = th[kBeta];
  const double phi = std::atan(-y_g / (d * k));
  const double theta = std::atan(x_g * std::cos(phi) / (d * k));
  EXPECT_NEAR(trim.state[kPhi], phi, kAngleTol);
  EXPECT_NEAR(trim.state[kTheta], theta, kAngleTol);
  // Shaft ahead of G (x_g > 0): nose up; shaft left of G (y_g < 0): roll right.
  EXPECT_GT(trim.state[kTheta], 0.01);
  EXPECT_GT(trim.state[kPhi], 0.01);
  // The swashplate angles from the moment balances.
  const double mg = th[kMass] * th[kGravity];
  const double Z_T = -mg * std::cos(theta) * std::cos(phi) / k;
  const double w2 = trim.input[kOmega2] * trim.input[kOmega2];
  const double dcx = std::asin(y_g * Z_T / (d * beta * w2));
  const double dcy = std::asin(x_g * Z_T / (d * beta * std::cos(dcx) * w2));
  EXPECT_NEAR(trim.input[kDeltaCx], dcx, kAngleTol);
  EXPECT_NEAR(trim.input[kDeltaCy], dcy, kAngleTol);
  // Yaw balance unchanged.
  EXPECT_NEAR(trim.input[kOmega2] / trim.input[kOmega1], std::sqrt(th[kGamma1] / -th[kGamma2]),
              kInputRel);
}

// Wind: the body force of eq. 24 with V_tot = V_prop + R_EB^T V_wind (no
// ground speed) is balanced by the tilted weight; no moment is needed
// (eqs. 31-32), so the swashplate stays centred. The vehicle leans into the
// wind, by the signs given for each heading below (wind wn = 2 m/s,
// we = -1.5 m/s: air moving north and west).
void CheckWindTrim(double heading, double expect_theta_sign, double expect_phi_sign) {
  const Eigen::Vector3d wind_E(2.0, -1.5, 0.0);
  const Vehicle v =
      With(Reference(), "wind", {{"wn", wind_E[0]}, {"we", wind_E[1]}, {"wd", wind_E[2]}});
  const Eigen::VectorXd th = v.parameters.Values();
  const std::string what = "wind at heading " + std::to_string(heading);
  const HoverTrim trim = TrimHover(v.model, th, 1.0, heading);
  ExpectEquilibrium(v, trim, what);
  EXPECT_NEAR(trim.input[kDeltaCx], 0.0, kAngleTol) << what;
  EXPECT_NEAR(trim.input[kDeltaCy], 0.0, kAngleTol) << what;
  const double phi = trim.state[kPhi], theta = trim.state[kTheta];
  EXPECT_GT(expect_theta_sign * theta, 0.01) << what;
  EXPECT_GT(expect_phi_sign * phi, 0.01) << what;

  // Independent force balance (eqs. 13, 23-28), from the trim found.
  const double O1 = trim.input[kOmega1], O2 = trim.input[kOmega2];
  const double sigma = Sigma(th[kSigma0], O1, O2);
  const double Z_T = sigma * (th[kAlpha] * O1 * O1 + th[kBeta] * O2 * O2);
  const double rho = th[kAirDensity];
  const double S_prop = M_PI * th[kRotorRadius] * th[kRotorRadius];
  const double S_c = 2 * th[kBodyRadius] * th[kBodyLength];
  const double S_s = M_PI * th[kBodyRadius] * th[kBodyRadius];
  const Eigen::Matrix3d R_EB = BodyToEarth(phi, theta, heading);
  const Eigen::Vector3d wind_B = R_EB.transpose() * wind_E;
  const Eigen::Vector3d V(wind_B[0], wind_B[1], std::sqrt(-2 * Z_T / (rho * S_prop)) + wind_B[2]);
  const Eigen::Vector3d f_body =
      0.5 * rho * V.norm() *
      Eigen::Vector3d(S_c * th[kCx] * V[0], S_c * th[kCy] * V[1], S_s * th[kCz] * V[2]);
  const double mg = th[kMass] * th[kGravity];
  const Eigen::Vector3d weight_B =
      mg * Eigen::Vector3d(-std::sin(theta), std::cos(theta) * std::sin(phi),
                           std::cos(theta) * std::cos(phi));
  const Eigen::Vector3d total = Eigen::Vector3d(0, 0, Z_T) + f_body + weight_B;
  for (int i = 0; i < 3; ++i) {
    // Residual accelerations <= 1e-10 m/s^2 times m = 0.25 kg; 1e-9 N allows
    // for the smoothing (~1e-14 N) and rounding.
    EXPECT_NEAR(total[i], 0.0, 1e-9) << what << ": force " << i;
  }
}

TEST(TrimTest, WindDeflectsTheTrimIntoTheWind) {
  // Heading 0: body x north, y east. North wind pushes the nose side north:
  // nose up (theta > 0) tilts the thrust south. West-going wind (we < 0)
  // pushes west: roll right (phi > 0) tilts the thrust east.
  CheckWindTrim(0.0, +1.0, +1.0);
  // Heading pi/2: body x east, y south. The west push is now along -x: nose
  // down (theta < 0); the north push along -y: roll right (phi > 0) tilts the
  // thrust to +y = south.
  CheckWindTrim(M_PI / 2, -1.0, +1.0);
}

}  // namespace
}  // namespace coaxid
