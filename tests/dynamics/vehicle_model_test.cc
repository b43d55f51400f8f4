// Tests of the templated vehicle model (dynamics/vehicle_model.h), the
// interference loss (dynamics/interference_loss.h) and every effect of the
// library (dynamics/effects/), against closed forms of the paper
// (../shared/seed/glmav-paper.txt, eqs. 6-63) with the decisions of
// ../shared/spec/model.md and the effect table of ../shared/spec/effects.md.
//
// Every property test is a typed test run for double and for
// ceres::Jet<double, 4> (STYLE.md, 10(b)): the Jet run seeds the four
// derivative directions on the four inputs and compares the value parts.
//
// Tolerances (each comparison says which one it uses and why):
// - kClosedFormRel = 1e-10 relative. The model evaluates the same closed forms
//   in a different order (rounding ~1e-15 relative); its only approximations
//   are the smoothings of eq. 46's radicand (sqrt(0.5 (r + sqrt(r^2 + 1e-12))),
//   which differs from sqrt(r) by ~1e-12 / (8 r^1.5), r ~ 3..60 m^2/s^2 here)
//   and of eq. 25's airspeed norm (+1e-12 m^2/s^2 under the root, ~1e-14
//   relative at the ~7 m/s wake speeds here). 1e-10 is far above both and far
//   below any modelling error (a wrong sign or factor changes a load by >1%).
// - Where the closed form is exactly 0 because both rotors are stopped the
//   smoothing leaves a tiny wake V_prop = sqrt(1e-6 / 2) m/s, whose body force
//   is at most 0.5 rho S_s Cz (1e-6 / 2 + 1e-12 / 2) ~ 5e-10 N: twice that
//   bound is the absolute tolerance on Z (kSmoothingForceBound below).
#include "dynamics/vehicle_model.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "core/parameters.h"
#include "core/vehicle_config.h"
#include "dynamics/effects/effect_library.h"
#include "dynamics/interference_loss.h"
#include "dynamics/outputs.h"
#include "dynamics/state.h"
#include "dynamics/vehicle.h"

namespace coaxid {
namespace {

constexpr double kClosedFormRel = 1e-10;

using Input = std::array<double, kNumInputs>;
using Jet4 = ceres::Jet<double, 4>;

// ---------------------------------------------------------------------------
// Scalar helpers: the same test body runs for double and Jet.

double Value(double t) { return t; }
template <typename S, int N>
double Value(const ceres::Jet<S, N>& t) {
  return t.a;
}

// A scalar with value v; for a Jet, derivative direction `dir` set to 1 (if
// in range), so the Jet run really carries derivatives through the model.
template <typename T>
T Lift(double v, int dir) {
  if constexpr (std::is_same_v<T, double>) {
    return v;
  } else {
    T t(v);
    if (dir >= 0 && dir < T::DIMENSION) t.v[dir] = 1.0;
    return t;
  }
}

// Loads with the value parts only.
struct Loads {
  Eigen::Vector3d F;  // X, Y, Z [N]
  Eigen::Vector3d M;  // L, M, N [N m]
  double Z1, Z2, N1, N2;
};

template <typename T>
Loads EvalLoads(const VehicleModel& model, const Eigen::VectorXd& theta, const Input& input,
                Setting setting, const double* x) {
  std::vector<T> th(theta.size());
  for (int i = 0; i < theta.size(); ++i) th[i] = T(theta[i]);
  T in[kNumInputs];
  for (int k = 0; k < kNumInputs; ++k) in[k] = Lift<T>(input[k], k);
  T xs[kNumStates];
  const T* xp = nullptr;
  if (x != nullptr) {
    for (int i = 0; i < kNumStates; ++i) xs[i] = T(x[i]);
    xp = xs;
  }
  const AeroLoads<T> l = model.Loads(th.data(), in, setting, xp);
  Loads out;
  for (int i = 0; i < 3; ++i) {
    out.F[i] = Value(l.force_B[i]);
    out.M[i] = Value(l.moment_B[i]);
  }
  out.Z1 = Value(l.Z1);
  out.Z2 = Value(l.Z2);
  out.N1 = Value(l.N1);
  out.N2 = Value(l.N2);
  return out;
}

template <typename T>
State EvalDerivative(const VehicleModel& model, const Eigen::VectorXd& theta, const State& x,
                     const Input& input) {
  std::vector<T> th(theta.size());
  for (int i = 0; i < theta.size(); ++i) th[i] = T(theta[i]);
  T in[kNumInputs], xs[kNumStates], xdot[kNumStates];
  for (int k = 0; k < kNumInputs; ++k) in[k] = Lift<T>(input[k], k);
  for (int i = 0; i < kNumStates; ++i) xs[i] = T(x[i]);
  model.Derivative(th.data(), xs, in, xdot);
  State out;
  for (int i = 0; i < kNumStates; ++i) out[i] = Value(xdot[i]);
  return out;
}

template <typename T>
Eigen::Vector3d EvalSpecificForce(const VehicleModel& model, const Eigen::VectorXd& theta,
                                  const State& x, const Input& input) {
  std::vector<T> th(theta.size());
  for (int i = 0; i < theta.size(); ++i) th[i] = T(theta[i]);
  T in[kNumInputs], xs[kNumStates];
  for (int k = 0; k < kNumInputs; ++k) in[k] = Lift<T>(input[k], k);
  for (int i = 0; i < kNumStates; ++i) xs[i] = T(x[i]);
  const Vec3<T> a = model.SpecificForce(th.data(), xs, in);
  return Eigen::Vector3d(Value(a[0]), Value(a[1]), Value(a[2]));
}

// ---------------------------------------------------------------------------
// Vehicles and parameters.

Vehicle ReferenceVehicle() {
  return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
}

// Base parameters with every unknown distinct (the nominal config has
// alpha = beta, Cx = Cy = Cz, Ixx = Iyy, which would hide a swapped index).
void SetDistinctBaseParameters(ParameterSet* p) {
  p->SetValue("alpha", -5.0e-5);
  p->SetValue("beta", -6.1e-5);
  p->SetValue("sigma0", 0.13);
  p->SetValue("Cx", 0.9);
  p->SetValue("Cy", 1.3);
  p->SetValue("Cz", 1.7);
  p->SetValue("gamma1", 1.3e-6);
  p->SetValue("gamma2", -0.9e-6);
  p->SetValue("d", 0.11);
  p->SetValue("Ixx", 1.8e-3);
  p->SetValue("Iyy", 2.1e-3);
  p->SetValue("Izz", 3.3e-4);
}

Vehicle DistinctVehicle() {
  Vehicle v = ReferenceVehicle();
  SetDistinctBaseParameters(&v.parameters);
  return v;
}

// The vehicle with one more effect whose parameters take their `typical`
// values from the library.
Vehicle WithTypicalEffect(const Vehicle& base, const std::string& name) {
  const int index = EffectIndex(name);
  EXPECT_GE(index, 0) << name;
  std::map<std::string, ParameterOverride> overrides;
  for (const auto& spec : EffectLibrary()[index].parameters) {
    overrides[spec.name].value = spec.typical;
  }
  return WithEffect(base, name, overrides);
}

double Param(const Vehicle& v, const std::string& name) { return v.parameters.Value(name); }

// Reference closed forms, independent of the model code.
double Sigma(double sigma0, double omega1, double omega2) {
  const double w1 = omega1 * omega1, w2 = omega2 * omega2;
  if (w1 + w2 == 0) return 1.0;
  return 1.0 - sigma0 * 4.0 * w1 * w2 / ((w1 + w2) * (w1 + w2));
}

// A flight state away from every special case: moving, rotating, tilted,
// 0.3 m above the floor (ground effect visible: (R / 4h)^2 = 0.02).
State FlightState() {
  State x;
  x << 0.4, -0.7, -0.3,   // x, y, z [m]
      1.3, -0.8, 0.45,    // u, v, w [m/s]
      0.12, -0.09, 0.8,   // phi, theta, psi [rad]
      0.35, -0.55, 0.25;  // p, q, r [rad/s]
  return x;
}
const Input kFlightInput = {150.0, 163.0, 0.11, -0.07};

// ---------------------------------------------------------------------------
// Comparison helpers.

void ExpectClose(double got, double want, double tol, const std::string& what) {
  EXPECT_NEAR(got, want, tol) << what << ": got " << got << ", want " << want;
}

void ExpectRel(double got, double want, double rel, double abs_floor, const std::string& what) {
  ExpectClose(got, want, rel * std::fabs(want) + abs_floor, what);
}

// Channel scales for "unchanged" checks: a weight and a weight times the hub
// distance. An unchanged channel must agree to 1e-12 of that scale: the two
// evaluations run the same base code (rounding ~1e-16); any physical
// contribution of an effect is >1e-6 of the scale at the states used.
constexpr double kForceScale = 2.5;    // ~ m g [N]
constexpr double kMomentScale = 0.25;  // ~ m g d [N m]
constexpr double kUnchangedRel = 1e-12;

enum Channel { cX, cY, cZ, cL, cM, cN, cZ1, cZ2, cN1, cN2, kNumChannels };
const char* kChannelNames[kNumChannels] = {"X", "Y", "Z", "L", "M", "N", "Z1", "Z2", "N1", "N2"};

double Get(const Loads& l, int c) {
  switch (c) {
    case cX:
    case cY:
    case cZ:
      return l.F[c];
    case cL:
    case cM:
    case cN:
      return l.M[c - cL];
    case cZ1:
      return l.Z1;
    case cZ2:
      return l.Z2;
    case cN1:
      return l.N1;
    default:
      return l.N2;
  }
}
bool IsForce(int c) { return c <= cZ || c == cZ1 || c == cZ2; }

// Checks with - without == expected_delta on every channel listed in
// `deltas`, and with == without on every other channel.
void ExpectDeltas(const Loads& with, const Loads& without, const std::map<int, double>& deltas,
                  const std::string& what) {
  for (int c = 0; c < kNumChannels; ++c) {
    const double scale = IsForce(c) ? kForceScale : kMomentScale;
    const double got = Get(with, c) - Get(without, c);
    auto it = deltas.find(c);
    const double want = it == deltas.end() ? 0.0 : it->second;
    // Changed channels: the delta's closed form to kClosedFormRel, plus the
    // rounding of the subtraction (kUnchangedRel of the channel scale).
    const double tol = kClosedFormRel * std::fabs(want) + kUnchangedRel * scale;
    EXPECT_NEAR(got, want, tol) << what << ": channel " << kChannelNames[c];
  }
}

void ExpectLoadsEqual(const Loads& a, const Loads& b, const std::string& what) {
  ExpectDeltas(a, b, {}, what);
}

// ---------------------------------------------------------------------------
// An independent transcription of the paper's complete model, eqs. 34-49,
// straight from the printed equations, with model.md decision 2 (plus sign on
// the x and y body-force terms of eqs. 40-41, as in eq. 24) and decision 3
// (V_prop = 0 when the radicand of eq. 46 is negative). wind_B is
// [V_wind]_b of eqs. 43-45 (zero in the paper's model). Also returns the
// aerodynamic force T + f_body (eq. 28 without f_p) for the accelerometer.
struct PaperResult {
  State xdot;
  Eigen::Vector3d aero_force;
};

PaperResult PaperModel(const Eigen::VectorXd& th, const State& s, const Input& in,
                       const Eigen::Vector3d& wind_B = Eigen::Vector3d::Zero()) {
  const double m = th[kMass], g = th[kGravity], rho = th[kAirDensity];
  const double alpha = th[kAlpha], beta = th[kBeta], Cx = th[kCx], Cy = th[kCy], Cz = th[kCz];
  const double gamma1 = th[kGamma1], gamma2 = th[kGamma2], d = th[kHubDistance];
  const double Ixx = th[kIxx], Iyy = th[kIyy], Izz = th[kIzz];
  const double S_prop = M_PI * th[kRotorRadius] * th[kRotorRadius];
  const double S_c = 2.0 * th[kBodyRadius] * th[kBodyLength];   // eq. 26
  const double S_s = M_PI * th[kBodyRadius] * th[kBodyRadius];  // eq. 26
  const double u = s[kU], v = s[kV], w = s[kW];
  const double phi = s[kPhi], theta = s[kTheta], psi = s[kPsi];
  const double p = s[kP], q = s[kQ], r = s[kR];
  const double O1 = in[kOmega1], O2 = in[kOmega2], dcx = in[kDeltaCx], dcy = in[kDeltaCy];
  const double sigma = Sigma(th[kSigma0], O1, O2);
  using std::cos;
  using std::sin;
  using std::tan;

  PaperResult out;
  State& f = out.xdot;
  // Eq. 34-36.
  f[kX] = (cos(theta) * cos(psi)) * u +
          (sin(phi) * sin(theta) * cos(psi) - cos(phi) * sin(psi)) * v +
          (cos(phi) * sin(theta) * cos(psi) + sin(phi) * sin(psi)) * w;
  f[kY] = (cos(theta) * sin(psi)) * u +
          (sin(phi) * sin(theta) * sin(psi) + cos(phi) * cos(psi)) * v +
          (cos(phi) * sin(theta) * sin(psi) - sin(phi) * cos(psi)) * w;
  f[kZ] = (-sin(theta)) * u + (sin(phi) * cos(theta)) * v + (cos(phi) * cos(theta)) * w;
  // Eq. 37-39.
  f[kPhi] = p + (tan(theta) * sin(phi)) * q + (tan(theta) * cos(phi)) * r;
  f[kTheta] = cos(phi) * q - sin(phi) * r;
  f[kPsi] = (sin(phi) / cos(theta)) * q + (cos(phi) / cos(theta)) * r;
  // Eq. 46 (decision 3) and eqs. 43-45.
  const double radicand =
      -2.0 * sigma * (alpha * O1 * O1 + beta * cos(dcx) * cos(dcy) * O2 * O2) / (rho * S_prop);
  const double V_prop = radicand > 0 ? std::sqrt(radicand) : 0.0;
  const double V_ux = -u + wind_B[0];
  const double V_vy = -v + wind_B[1];
  const double V_wz = V_prop - w + wind_B[2];
  const double V = std::sqrt(V_ux * V_ux + V_vy * V_vy + V_wz * V_wz);
  // Eq. 40-42 (decision 2: + on the body-force terms of all three).
  const double T_x = -beta * sin(dcy) * cos(dcx) * O2 * O2;
  const double T_y = -beta * sin(dcx) * O2 * O2;
  const double T_z = sigma * alpha * O1 * O1 + sigma * beta * cos(dcx) * cos(dcy) * O2 * O2;
  const double fb_x = 0.5 * rho * S_c * Cx * V_ux * V;
  const double fb_y = 0.5 * rho * S_c * Cy * V_vy * V;
  const double fb_z = 0.5 * rho * S_s * Cz * V_wz * V;
  f[kU] = r * v - q * w + T_x / m + fb_x / m - g * sin(theta);
  f[kV] = p * w - r * u + T_y / m + fb_y / m + g * cos(theta) * sin(phi);
  f[kW] = q * u - p * v + T_z / m + fb_z / m + g * cos(theta) * cos(phi);
  // Eq. 47-49.
  f[kP] = ((Iyy - Izz) / Ixx) * r * q - (1.0 / Ixx) * (d * beta * sin(dcx) * O2 * O2);
  f[kQ] = ((Izz - Ixx) / Iyy) * r * p + (1.0 / Iyy) * (d * beta * sin(dcy) * cos(dcx) * O2 * O2);
  f[kR] = ((Ixx - Iyy) / Izz) * p * q + (1.0 / Izz) * (gamma1 * O1 * O1 + gamma2 * O2 * O2);
  out.aero_force = Eigen::Vector3d(T_x + fb_x, T_y + fb_y, T_z + fb_z);
  return out;
}

// Random near-hover-to-manoeuvring states and inputs, seeded.
struct RandomCase {
  State x;
  Input input;
};
std::vector<RandomCase> RandomCases(unsigned seed, int n) {
  std::mt19937 rng(seed);
  auto U = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  std::vector<RandomCase> cases;
  for (int k = 0; k < n; ++k) {
    RandomCase c;
    c.x << U(-5, 5), U(-5, 5), U(-3, -0.5),  //
        U(-3, 3), U(-3, 3), U(-2, 2),        //
        U(-0.4, 0.4), U(-0.4, 0.4), U(-M_PI, M_PI), U(-2, 2), U(-2, 2), U(-2, 2);
    c.input = {U(100, 200), U(100, 200), U(-0.2, 0.2), U(-0.2, 0.2)};
    // Every fourth case with one rotor stopped (sigma = 1 there).
    if (k % 4 == 1) c.input[kOmega1] = 0.0;
    if (k % 4 == 2) c.input[kOmega2] = 0.0;
    cases.push_back(c);
  }
  return cases;
}

// Derivative tolerance against the transcription: every derivative is a sum
// of O(0.1..100) SI terms at these states, rounded at ~1e-15 relative, and the
// model's smoothings move it by <1e-13; 1e-10 * (1 + |f|) is far above both
// and far below any modelling error (e.g. a flipped body-force sign moves
// u_dot by ~0.1 m/s^2).
void ExpectStateNear(const State& got, const State& want, const std::string& what) {
  for (int i = 0; i < kNumStates; ++i) {
    EXPECT_NEAR(got[i], want[i], 1e-10 * (1.0 + std::fabs(want[i])))
        << what << ": d" << StateName(i) << "/dt";
  }
}

// ===========================================================================
// Typed test suite: double and Jet<double, 4>.

template <typename T>
class VehicleModelTest : public ::testing::Test {};
using ScalarTypes = ::testing::Types<double, Jet4>;
TYPED_TEST_SUITE(VehicleModelTest, ScalarTypes);

// Balance loads (model.md decision 5) against the closed forms of eqs. 61-63
// and 57-59 with model.md's sigma (decision 1), including single-rotor runs
// (sigma = 1), both rotors stopped and swashplate angles.
TYPED_TEST(VehicleModelTest, BalanceLoadsMatchClosedFormsOfEqs57To63) {
  using T = TypeParam;
  const Vehicle v = DistinctVehicle();
  const Eigen::VectorXd th = v.parameters.Values();
  const double alpha = th[kAlpha], beta = th[kBeta], Cz = th[kCz], d = th[kHubDistance];
  const double S_prop = M_PI * th[kRotorRadius] * th[kRotorRadius];
  const double S_s = M_PI * th[kBodyRadius] * th[kBodyRadius];
  // Both rotors stopped: V_prop^2 = eps_r / 2 and V_prop V_tot <= V_prop^2 +
  // eps_a^2 / 2, so the smoothed wake force is at most this; the model sits
  // right at it, so allow twice the bound for rounding.
  const double kSmoothingForceBound =
      2.0 * 0.5 * th[kAirDensity] * S_s * Cz *
      (0.5 * kWakeRadicandSmoothing + 0.5 * kAirspeedSmoothing * kAirspeedSmoothing);
  const std::vector<Input> inputs = {
      {150.0, 164.0, 0.0, 0.0},     {150.0, 0.0, 0.0, 0.0},      // single upper rotor
      {0.0, 160.0, 0.0, 0.0},       {0.0, 160.0, 0.1, -0.15},    // single lower rotor
      {0.0, 0.0, 0.0, 0.0},         {0.0, 0.0, 0.2, 0.1},        // both stopped
      {140.0, 170.0, 0.15, 0.1},    {160.0, 150.0, -0.2, 0.2},   //
      {120.0, 190.0, -0.05, -0.18}, {80.0, 60.0, 0.19, -0.01}};  // low speeds
  for (const Input& in : inputs) {
    const std::string what = "input (" + std::to_string(in[0]) + ", " + std::to_string(in[1]) +
                             ", " + std::to_string(in[2]) + ", " + std::to_string(in[3]) + ")";
    const double w1 = in[0] * in[0], w2 = in[1] * in[1];
    const double cx = std::cos(in[2]), sx = std::sin(in[2]);
    const double cy = std::cos(in[3]), sy = std::sin(in[3]);
    const double sigma = Sigma(th[kSigma0], in[0], in[1]);
    const double A = alpha * w1 + beta * cx * cy * w2;
    const Loads l = EvalLoads<T>(v.model, th, in, Setting::kBalance, nullptr);
    ExpectRel(l.F[0], -beta * sy * cx * w2, kClosedFormRel, 0, what + " X (eq. 61)");
    ExpectRel(l.F[1], -beta * sx * w2, kClosedFormRel, 0, what + " Y (eq. 62)");
    ExpectRel(l.F[2], sigma * A - sigma * S_s * Cz * A / S_prop, kClosedFormRel,
              kSmoothingForceBound, what + " Z (eq. 63)");
    ExpectRel(l.M[0], -d * beta * sx * w2, kClosedFormRel, 0, what + " L (eq. 57)");
    ExpectRel(l.M[1], d * beta * sy * cx * w2, kClosedFormRel, 0, what + " M (eq. 58)");
    ExpectRel(l.M[2], th[kGamma1] * w1 + th[kGamma2] * w2, kClosedFormRel, 0, what + " N (eq. 59)");
    ExpectRel(l.Z1, sigma * alpha * w1, kClosedFormRel, 0, what + " Z1 (decision 5)");
    ExpectRel(l.Z2, sigma * beta * cx * cy * w2, kClosedFormRel, 0, what + " Z2 (decision 5)");
    ExpectRel(l.N1, th[kGamma1] * w1, kClosedFormRel, 0, what + " N1 (decision 5)");
    ExpectRel(l.N2, th[kGamma2] * w2, kClosedFormRel, 0, what + " N2 (decision 5)");
  }
}

// The balance setting ignores the state (u = v = w = 0, level, no rotation).
TYPED_TEST(VehicleModelTest, BalanceLoadsIgnoreTheState) {
  using T = TypeParam;
  const Vehicle v = DistinctVehicle();
  const Eigen::VectorXd th = v.parameters.Values();
  const State x = FlightState();
  const Loads a = EvalLoads<T>(v.model, th, kFlightInput, Setting::kBalance, nullptr);
  const Loads b = EvalLoads<T>(v.model, th, kFlightInput, Setting::kBalance, x.data());
  ExpectLoadsEqual(b, a, "balance with and without a state");
}

// With no effect the model is exactly the paper's eqs. 34-49 (with model.md
// decisions 2 and 3), at random states and inputs.
TYPED_TEST(VehicleModelTest, NoEffectDerivativeIsThePapersEqs34To49) {
  using T = TypeParam;
  for (const Vehicle& v : {ReferenceVehicle(), DistinctVehicle()}) {
    const Eigen::VectorXd th = v.parameters.Values();
    int k = 0;
    for (const RandomCase& c : RandomCases(20240611u, 24)) {
      const State got = EvalDerivative<T>(v.model, th, c.x, c.input);
      const State want = PaperModel(th, c.x, c.input).xdot;
      ExpectStateNear(got, want, "random case " + std::to_string(k++));
    }
  }
}

// Accelerometer (model.md decision 7): (X, Y, Z) / m, gravity excluded.
TYPED_TEST(VehicleModelTest, SpecificForceIsAeroForceOverMass) {
  using T = TypeParam;
  const Vehicle v = DistinctVehicle();
  const Eigen::VectorXd th = v.parameters.Values();
  int k = 0;
  for (const RandomCase& c : RandomCases(777u, 8)) {
    const Eigen::Vector3d a = EvalSpecificForce<T>(v.model, th, c.x, c.input);
    const Loads l = EvalLoads<T>(v.model, th, c.input, Setting::kFlight, c.x.data());
    const Eigen::Vector3d paper = PaperModel(th, c.x, c.input).aero_force / th[kMass];
    for (int i = 0; i < 3; ++i) {
      // Same division of the same loads: equal to rounding.
      EXPECT_NEAR(a[i], l.F[i] / th[kMass], 1e-14 * (1 + std::fabs(a[i]))) << k;
      // Against the transcription: kClosedFormRel-type bound (see top).
      EXPECT_NEAR(a[i], paper[i], 1e-10 * (1 + std::fabs(paper[i]))) << k;
    }
    ++k;
  }
}

// With every effect enabled, the accelerometer still is the total
// non-gravitational force over m: a = v_dot + w x v - g_B (eq. 3), which ties
// SpecificForce to Derivative whatever the effects add.
TYPED_TEST(VehicleModelTest, SpecificForceIncludesEffectForces) {
  using T = TypeParam;
  Vehicle v = DistinctVehicle();
  for (const auto& info : EffectLibrary()) {
    // These cases hold the 12 rigid-body states; an effect's own states
    // (stabilizer_bar) have their tests in stabilizer_bar_test.cc.
    if (info.num_own_states == 0) v = WithTypicalEffect(v, info.name);
  }
  const Eigen::VectorXd th = v.parameters.Values();
  int k = 0;
  for (const RandomCase& c : RandomCases(4242u, 8)) {
    const Eigen::Vector3d a = EvalSpecificForce<T>(v.model, th, c.x, c.input);
    const State f = EvalDerivative<T>(v.model, th, c.x, c.input);
    const double u = c.x[kU], vv = c.x[kV], w = c.x[kW], p = c.x[kP], q = c.x[kQ], r = c.x[kR];
    const double phi = c.x[kPhi], theta = c.x[kTheta], g = th[kGravity];
    const Eigen::Vector3d expected(f[kU] - (r * vv - q * w) + g * std::sin(theta),
                                   f[kV] - (p * w - r * u) - g * std::cos(theta) * std::sin(phi),
                                   f[kW] - (q * u - p * vv) - g * std::cos(theta) * std::cos(phi));
    for (int i = 0; i < 3; ++i) {
      // Terms O(10 m/s^2) recombined: rounding ~1e-14; 1e-11 leaves margin.
      EXPECT_NEAR(a[i], expected[i], 1e-11 * (1 + std::fabs(expected[i]))) << "case " << k;
    }
    ++k;
  }
}

// --- Interference loss (model.md decision 1) --------------------------------

TYPED_TEST(VehicleModelTest, ParametricInterferenceLossLimits) {
  using T = TypeParam;
  const double sigma0 = 0.13;
  for (double omega : {1.0, 50.0, 150.0, 300.0}) {
    // Either rotor stopped: sigma = 1 exactly (w1 w2 = 0).
    EXPECT_EQ(Value(InterferenceLoss(T(sigma0), Lift<T>(omega, 0), Lift<T>(0.0, 1))), 1.0);
    EXPECT_EQ(Value(InterferenceLoss(T(sigma0), Lift<T>(0.0, 0), Lift<T>(omega, 1))), 1.0);
    // Equal speeds: 4 w^2 / (2 w)^2 = 1, so sigma = 1 - sigma0 (rounding only).
    EXPECT_NEAR(Value(InterferenceLoss(T(sigma0), Lift<T>(omega, 0), Lift<T>(omega, 1))),
                1.0 - sigma0, 1e-15);
  }
  // Both stopped: no interference.
  EXPECT_EQ(Value(InterferenceLoss(T(sigma0), Lift<T>(0.0, 0), Lift<T>(0.0, 1))), 1.0);
  // In between: the formula, symmetric in the two speeds, between 1 - sigma0 and 1.
  for (const auto& [o1, o2] :
       std::vector<std::pair<double, double>>{{150, 164}, {100, 200}, {30, 180}, {190, 12}}) {
    const double s = Value(InterferenceLoss(T(sigma0), Lift<T>(o1, 0), Lift<T>(o2, 1)));
    const double s_swapped = Value(InterferenceLoss(T(sigma0), Lift<T>(o2, 0), Lift<T>(o1, 1)));
    EXPECT_NEAR(s, Sigma(sigma0, o1, o2), 1e-15);
    EXPECT_NEAR(s, s_swapped, 1e-15);
    EXPECT_GT(s, 1.0 - sigma0);
    EXPECT_LT(s, 1.0);
  }
}

// A table on a non-uniform grid (rows over omega1, columns over omega2).
SigmaTable TestTable(const std::function<double(double, double)>& f) {
  SigmaTable t;
  t.omega1 = {0.0, 100.0, 160.0, 250.0};
  t.omega2 = {0.0, 120.0, 200.0};
  for (double o1 : t.omega1) {
    for (double o2 : t.omega2) t.sigma.push_back(f(o1, o2));
  }
  return t;
}

// Bilinear interpolation reproduces the grid points, reproduces any bilinear
// function exactly inside the grid, gives the corner average at a cell's
// centre and clamps to the edges outside.
TYPED_TEST(VehicleModelTest, TabulatedInterferenceLossIsBilinear) {
  using T = TypeParam;
  auto sigma_of = [](const SigmaTable& t, double o1, double o2) {
    return Value(InterferenceLossFromTable(t, Lift<T>(o1, 0), Lift<T>(o2, 1)));
  };
  // A non-bilinear table (the paper's Fig. 9 shape).
  const SigmaTable table = TestTable([](double o1, double o2) { return Sigma(0.1, o1, o2); });
  ASSERT_NO_THROW(table.Validate("test table"));
  const size_t n2 = table.omega2.size();
  for (size_t i = 0; i < table.omega1.size(); ++i) {
    for (size_t j = 0; j < n2; ++j) {
      // A grid point: one corner weight is 1, the others 0: exact.
      EXPECT_EQ(sigma_of(table, table.omega1[i], table.omega2[j]), table.sigma[i * n2 + j])
          << i << ", " << j;
    }
  }
  // Cell centre: the average of the four corners (rounding only: 1e-15).
  for (size_t i = 0; i + 1 < table.omega1.size(); ++i) {
    for (size_t j = 0; j + 1 < n2; ++j) {
      const double o1 = 0.5 * (table.omega1[i] + table.omega1[i + 1]);
      const double o2 = 0.5 * (table.omega2[j] + table.omega2[j + 1]);
      const double avg = 0.25 * (table.sigma[i * n2 + j] + table.sigma[i * n2 + j + 1] +
                                 table.sigma[(i + 1) * n2 + j] + table.sigma[(i + 1) * n2 + j + 1]);
      EXPECT_NEAR(sigma_of(table, o1, o2), avg, 1e-15) << "cell " << i << ", " << j;
    }
  }
  // Clamped outside the grid: the value at the nearest edge point.
  EXPECT_EQ(sigma_of(table, 400.0, 250.0), table.sigma.back());
  EXPECT_NEAR(sigma_of(table, -5.0, 160.0), sigma_of(table, 0.0, 160.0), 1e-15);
  EXPECT_NEAR(sigma_of(table, 130.0, 999.0), sigma_of(table, 130.0, 200.0), 1e-15);

  // A bilinear function is reproduced exactly (to rounding, 1e-14 on values
  // ~1) at random points inside the grid: this pins the weights, not just
  // the corners.
  auto bilinear = [](double o1, double o2) {
    return 0.95 - 1.1e-4 * o1 + 0.7e-4 * o2 - 2.3e-7 * o1 * o2;
  };
  const SigmaTable lin = TestTable(bilinear);
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u1(0.0, 250.0), u2(0.0, 200.0);
  for (int k = 0; k < 50; ++k) {
    const double o1 = u1(rng), o2 = u2(rng);
    EXPECT_NEAR(sigma_of(lin, o1, o2), bilinear(o1, o2), 1e-14) << o1 << ", " << o2;
  }
}

// The model uses the table when configured so: balance Z1, Z2 carry the
// table's sigma.
TYPED_TEST(VehicleModelTest, TableModelUsesTheTable) {
  using T = TypeParam;
  VehicleConfig config = ReferenceVehicle().config;
  config.interference = InterferenceModel::kTable;
  // A table clearly different from the parametric sigma.
  config.sigma_table = TestTable([](double o1, double o2) { return 0.8 + 1e-4 * (o1 + o2) / 2; });
  const Vehicle v = MakeVehicle(config);
  const Eigen::VectorXd th = v.parameters.Values();
  const Input in = {130.0, 170.0, 0.05, -0.1};
  // Bilinear by hand: cell (100..160) x (120..200).
  const double a = (130.0 - 100.0) / 60.0, b = (170.0 - 120.0) / 80.0;
  auto s = [&](double o1, double o2) { return 0.8 + 1e-4 * (o1 + o2) / 2; };
  const double sigma = (1 - a) * ((1 - b) * s(100, 120) + b * s(100, 200)) +
                       a * ((1 - b) * s(160, 120) + b * s(160, 200));
  const Loads l = EvalLoads<T>(v.model, th, in, Setting::kBalance, nullptr);
  ExpectRel(l.Z1, sigma * th[kAlpha] * in[0] * in[0], kClosedFormRel, 0, "Z1 with table");
  ExpectRel(l.Z2, sigma * th[kBeta] * std::cos(in[2]) * std::cos(in[3]) * in[1] * in[1],
            kClosedFormRel, 0, "Z2 with table");
}

// --- Effects (effects.md table) ----------------------------------------------

struct EffectCase {
  Vehicle base, with;
  Eigen::VectorXd th_base, th_with;
};

EffectCase MakeEffectCase(const std::string& name) {
  EffectCase c;
  c.base = DistinctVehicle();
  c.with = WithTypicalEffect(c.base, name);
  c.th_base = c.base.parameters.Values();
  c.th_with = c.with.parameters.Values();
  return c;
}

TYPED_TEST(VehicleModelTest, GyroscopicChangesOnlyLAndM) {
  using T = TypeParam;
  const EffectCase c = MakeEffectCase("gyroscopic");
  const double J_r = Param(c.with, "gyroscopic.J_r");
  ASSERT_GT(J_r, 0);
  const State x = FlightState();
  const Input& in = kFlightInput;
  const Loads with = EvalLoads<T>(c.with.model, c.th_with, in, Setting::kFlight, x.data());
  const Loads without = EvalLoads<T>(c.base.model, c.th_base, in, Setting::kFlight, x.data());
  const double h = J_r * (in[kOmega1] - in[kOmega2]);
  ExpectDeltas(with, without, {{cL, -x[kQ] * h}, {cM, x[kP] * h}}, "gyroscopic, flight");
  // Balance: no rotation, no gyroscopic moment.
  ExpectLoadsEqual(EvalLoads<T>(c.with.model, c.th_with, in, Setting::kBalance, nullptr),
                   EvalLoads<T>(c.base.model, c.th_base, in, Setting::kBalance, nullptr),
                   "gyroscopic, balance");
}

TYPED_TEST(VehicleModelTest, RotorDampingChangesOnlyLAndM) {
  using T = TypeParam;
  const EffectCase c = MakeEffectCase("rotor_damping");
  const double k = Param(c.with, "rotor_damping.k_pq");
  ASSERT_GT(k, 0);
  const State x = FlightState();
  const Loads with =
      EvalLoads<T>(c.with.model, c.th_with, kFlightInput, Setting::kFlight, x.data());
  const Loads without =
      EvalLoads<T>(c.base.model, c.th_base, kFlightInput, Setting::kFlight, x.data());
  // Damping opposes the rates: L = -k p, M = -k q.
  ExpectDeltas(with, without, {{cL, -k * x[kP]}, {cM, -k * x[kQ]}}, "rotor_damping");
}

TYPED_TEST(VehicleModelTest, GroundEffectScalesRotorThrustInFlightOnly) {
  using T = TypeParam;
  const EffectCase c = MakeEffectCase("ground_effect");
  const double k_ge = Param(c.with, "ground_effect.k_ge");
  const double R = c.th_base[kRotorRadius];
  ASSERT_GT(k_ge, 0);
  State x = FlightState();
  for (double h : {0.15, 0.3, 1.0}) {
    x[kZ] = -h;  // height above ground h = -z (NED)
    const Loads with =
        EvalLoads<T>(c.with.model, c.th_with, kFlightInput, Setting::kFlight, x.data());
    const Loads without =
        EvalLoads<T>(c.base.model, c.th_base, kFlightInput, Setting::kFlight, x.data());
    const double q = R / (4 * h);
    const double gain = 1.0 / (1.0 - k_ge * q * q) - 1.0;
    const double Z_T = without.Z1 + without.Z2;  // the rotor z-force of eq. 13
    ExpectDeltas(with, without,
                 {{cZ, gain * Z_T}, {cZ1, gain * without.Z1}, {cZ2, gain * without.Z2}},
                 "ground_effect at h = " + std::to_string(h));
    // More thrust near the floor: Z more negative (z down).
    EXPECT_LT(with.F[2], without.F[2]);
  }
  // On the floor or below R / 4 the factor is capped at 1 / (1 - 0.95) = 20.
  x[kZ] = -0.03;
  const Loads capped =
      EvalLoads<T>(c.with.model, c.th_with, kFlightInput, Setting::kFlight, x.data());
  const Loads base =
      EvalLoads<T>(c.base.model, c.th_base, kFlightInput, Setting::kFlight, x.data());
  // 1 / (1 - 0.95) = 20 to rounding (~1e-15); 1e-12 relative leaves margin.
  ExpectRel(capped.Z1, 20.0 * base.Z1, 1e-12, 0, "capped ground effect Z1");
  // At or below the floor's datum (h <= 0): the same cap, the limit h -> 0+.
  for (double z : {0.0, 0.02}) {
    x[kZ] = z;
    const Loads on_floor =
        EvalLoads<T>(c.with.model, c.th_with, kFlightInput, Setting::kFlight, x.data());
    const Loads none =
        EvalLoads<T>(c.base.model, c.th_base, kFlightInput, Setting::kFlight, x.data());
    ExpectRel(on_floor.Z1, 20.0 * none.Z1, 1e-12, 0,
              "ground effect Z1 at z = " + std::to_string(z));
  }
  // A balance is far from the floor: nothing changes.
  ExpectLoadsEqual(EvalLoads<T>(c.with.model, c.th_with, kFlightInput, Setting::kBalance, nullptr),
                   EvalLoads<T>(c.base.model, c.th_base, kFlightInput, Setting::kBalance, nullptr),
                   "ground_effect, balance");
}

TYPED_TEST(VehicleModelTest, RotorDragChangesOnlyXAndYAgainstGroundVelocity) {
  using T = TypeParam;
  const EffectCase c = MakeEffectCase("rotor_drag");
  const double k_h = Param(c.with, "rotor_drag.k_h");
  ASSERT_GT(k_h, 0);
  const State x = FlightState();
  const Input& in = kFlightInput;
  const Loads with = EvalLoads<T>(c.with.model, c.th_with, in, Setting::kFlight, x.data());
  const Loads without = EvalLoads<T>(c.base.model, c.th_base, in, Setting::kFlight, x.data());
  const double k = k_h * (in[kOmega1] + in[kOmega2]);
  ExpectDeltas(with, without, {{cX, -k * x[kU]}, {cY, -k * x[kV]}}, "rotor_drag");
  // Against the motion: u > 0 gives a negative X change, v < 0 a positive Y.
  ASSERT_GT(x[kU], 0);
  ASSERT_LT(x[kV], 0);
  EXPECT_LT(with.F[0] - without.F[0], 0);
  EXPECT_GT(with.F[1] - without.F[1], 0);
  // Ground-relative u, v: the same change with a wind blowing.
  const Vehicle windy = WithTypicalEffect(c.base, "wind");
  const Vehicle windy_drag = WithTypicalEffect(windy, "rotor_drag");
  const Loads wd = EvalLoads<T>(windy_drag.model, windy_drag.parameters.Values(), in,
                                Setting::kFlight, x.data());
  const Loads w =
      EvalLoads<T>(windy.model, windy.parameters.Values(), in, Setting::kFlight, x.data());
  ExpectDeltas(wd, w, {{cX, -k * x[kU]}, {cY, -k * x[kV]}}, "rotor_drag with wind");
  // Balance: u = v = 0, no drag.
  ExpectLoadsEqual(EvalLoads<T>(c.with.model, c.th_with, in, Setting::kBalance, nullptr),
                   EvalLoads<T>(c.base.model, c.th_base, in, Setting::kBalance, nullptr),
                   "rotor_drag, balance");
}

TYPED_TEST(VehicleModelTest, CgOffsetChangesOnlyLAndMByTheRotorForce) {
  using T = TypeParam;
  const EffectCase c = MakeEffectCase("cg_offset");
  const double x_g = Param(c.with, "cg_offset.x_g"), y_g = Param(c.with, "cg_offset.y_g");
  ASSERT_NE(x_g, 0);
  ASSERT_NE(y_g, 0);
  const State x = FlightState();
  for (Setting setting : {Setting::kFlight, Setting::kBalance}) {
    const double* xp = setting == Setting::kFlight ? x.data() : nullptr;
    const Loads with = EvalLoads<T>(c.with.model, c.th_with, kFlightInput, setting, xp);
    const Loads without = EvalLoads<T>(c.base.model, c.th_base, kFlightInput, setting, xp);
    const double Z_T = without.Z1 + without.Z2;  // eq. 13's z-force, sigma included
    // Shaft at (x_g, y_g): (x_g, y_g, .) x (0, 0, Z_T) = (y_g Z_T, -x_g Z_T, 0).
    ExpectDeltas(with, without, {{cL, y_g * Z_T}, {cM, -x_g * Z_T}},
                 setting == Setting::kFlight ? "cg_offset, flight" : "cg_offset, balance");
    // Upward thrust (Z_T < 0) ahead of G (x_g > 0) pitches the nose up.
    ASSERT_LT(Z_T, 0);
    if (x_g > 0) {
      EXPECT_GT(with.M[1] - without.M[1], 0);
    }
  }
}

TYPED_TEST(VehicleModelTest, SwashplateBiasIsTheBaseModelAtBiasedAngles) {
  using T = TypeParam;
  const EffectCase c = MakeEffectCase("swashplate_bias");
  const double b_x = Param(c.with, "swashplate_bias.b_x");
  const double b_y = Param(c.with, "swashplate_bias.b_y");
  ASSERT_NE(b_x, 0);
  ASSERT_NE(b_y, 0);
  const State x = FlightState();
  Input biased = kFlightInput;
  biased[kDeltaCx] += b_x;
  biased[kDeltaCy] += b_y;
  for (Setting setting : {Setting::kFlight, Setting::kBalance}) {
    const double* xp = setting == Setting::kFlight ? x.data() : nullptr;
    // Everything (thrust, moments, wake speed) sees the biased angles.
    ExpectLoadsEqual(EvalLoads<T>(c.with.model, c.th_with, kFlightInput, setting, xp),
                     EvalLoads<T>(c.base.model, c.th_base, biased, setting, xp), "swashplate_bias");
  }
  // And the derivative too.
  const State f_with = EvalDerivative<T>(c.with.model, c.th_with, x, kFlightInput);
  const State f_base = EvalDerivative<T>(c.base.model, c.th_base, x, biased);
  for (int i = 0; i < kNumStates; ++i) {
    EXPECT_NEAR(f_with[i], f_base[i], 1e-12 * (1 + std::fabs(f_base[i]))) << StateName(i);
  }
}

TYPED_TEST(VehicleModelTest, WindChangesOnlyTheBodyForceAsARelativeVelocity) {
  using T = TypeParam;
  const EffectCase c = MakeEffectCase("wind");
  const Eigen::Vector3d wind_E(Param(c.with, "wind.wn"), Param(c.with, "wind.we"),
                               Param(c.with, "wind.wd"));
  ASSERT_GT(wind_E.norm(), 0);
  const State x = FlightState();
  const Eigen::Matrix3d R_EB = BodyToEarth(x[kPhi], x[kTheta], x[kPsi]);
  const Eigen::Vector3d wind_B = R_EB.transpose() * wind_E;
  const Loads with =
      EvalLoads<T>(c.with.model, c.th_with, kFlightInput, Setting::kFlight, x.data());
  const Loads without =
      EvalLoads<T>(c.base.model, c.th_base, kFlightInput, Setting::kFlight, x.data());
  // Only X, Y, Z may change; moments and per-rotor loads stay.
  for (int ch : {cL, cM, cN, cZ1, cZ2, cN1, cN2}) {
    EXPECT_NEAR(Get(with, ch), Get(without, ch),
                kUnchangedRel * (IsForce(ch) ? kForceScale : kMomentScale))
        << kChannelNames[ch];
  }
  // The body force changes: the wind is felt.
  EXPECT_GT((with.F - without.F).norm(), 1e-3);
  // Equals the base model with V_body replaced by V_body - V_wind (eqs. 43-45).
  State x_rel = x;
  for (int i = 0; i < 3; ++i) x_rel[kU + i] -= wind_B[i];
  const Loads relative =
      EvalLoads<T>(c.base.model, c.th_base, kFlightInput, Setting::kFlight, x_rel.data());
  ExpectLoadsEqual(with, relative, "wind == base at relative velocity");
  // And the full derivative equals the paper's eqs. 34-49 with [V_wind]_b.
  const State f = EvalDerivative<T>(c.with.model, c.th_with, x, kFlightInput);
  ExpectStateNear(f, PaperModel(c.th_base, x, kFlightInput, wind_B).xdot, "wind vs paper");
}

TYPED_TEST(VehicleModelTest, WakeInterferenceLowersLowerRotorThrustAndTorque) {
  using T = TypeParam;
  const EffectCase c = MakeEffectCase("wake_interference");
  const double k_T = Param(c.with, "wake_interference.k_T");
  const double k_Q = Param(c.with, "wake_interference.k_Q");
  ASSERT_GT(k_T, 0);
  ASSERT_GT(k_Q, 0);
  const State x = FlightState();
  const Input& in = kFlightInput;
  const double w12 = in[kOmega1] * in[kOmega2];
  const double cx = std::cos(in[kDeltaCx]), sx = std::sin(in[kDeltaCx]);
  const double cy = std::cos(in[kDeltaCy]), sy = std::sin(in[kDeltaCy]);
  const double d = c.th_base[kHubDistance];
  for (Setting setting : {Setting::kFlight, Setting::kBalance}) {
    const double* xp = setting == Setting::kFlight ? x.data() : nullptr;
    const Loads with = EvalLoads<T>(c.with.model, c.th_with, in, setting, xp);
    const Loads without = EvalLoads<T>(c.base.model, c.th_base, in, setting, xp);
    // |Z2| falls by k_T w1 w2 cx cy and |N2| by k_Q w1 w2 ...
    EXPECT_NEAR(std::fabs(without.Z2) - std::fabs(with.Z2), k_T * w12 * cx * cy,
                kClosedFormRel * k_T * w12 + kUnchangedRel * kForceScale);
    EXPECT_NEAR(std::fabs(without.N2) - std::fabs(with.N2), k_Q * w12,
                kClosedFormRel * k_Q * w12 + kUnchangedRel * kMomentScale);
    // ... along the lower rotor's own axis (eq. 9), so its lateral force and
    // the moments GO2 ^ T2 (eqs. 31-32) shrink with it; V_prop and the body
    // force keep the base thrust (effects.md), so Z changes by dZ2 alone.
    const double dk = k_T * w12;  // the magnitude lost; beta < 0 so T2 = beta w2^2 n
    const Eigen::Vector3d dT2 = dk * Eigen::Vector3d(-sy * cx, -sx, cx * cy);
    ExpectDeltas(
        with, without,
        {{cX, dT2[0]},
         {cY, dT2[1]},
         {cZ, dT2[2]},
         {cZ2, dT2[2]},
         {cL, d * dT2[1]},
         {cM, -d * dT2[0]},
         {cN, k_Q * w12},
         {cN2, k_Q * w12}},
        setting == Setting::kFlight ? "wake_interference, flight" : "wake_interference, balance");
  }
}

// Every effect with every parameter at 0 is the base model, and with its
// library defaults too, except ground_effect whose default k_ge = 1 is the
// physical Cheeseman-Bennett gain, not "absent" (effects.md): at its default
// it is checked on a balance, which never sees it (its flight closed form is
// GroundEffectScalesRotorThrustInFlightOnly).
TYPED_TEST(VehicleModelTest, EffectsWithZeroOrDefaultParametersAreTheBaseModel) {
  using T = TypeParam;
  const Vehicle base = DistinctVehicle();
  const Eigen::VectorXd th_base = base.parameters.Values();
  const State x = FlightState();
  for (const auto& info : EffectLibrary()) {
    if (info.num_own_states > 0) continue;  // 12-state x here; see stabilizer_bar_test.cc
    for (bool zero : {true, false}) {
      if (!zero && info.name == "ground_effect") continue;  // default is physical, see above
      std::map<std::string, ParameterOverride> overrides;
      for (const auto& spec : info.parameters) {
        overrides[spec.name].value = zero ? 0.0 : spec.value;
      }
      const Vehicle v = WithEffect(base, info.name, overrides);
      ASSERT_TRUE(v.model.EffectEnabled(EffectIndex(info.name))) << info.name;
      const Eigen::VectorXd th = v.parameters.Values();
      const std::string what = info.name + (zero ? " at zero" : " at defaults");
      // Absent at any logged height: on the floor and below it too (h = -z
      // <= 0, a height datum a few cm off), where ground_effect's factor is
      // capped for any k_ge > 0.
      for (double z : {x[kZ], 0.0, 0.03}) {
        State at = x;
        at[kZ] = z;
        const Loads with = EvalLoads<T>(v.model, th, kFlightInput, Setting::kFlight, at.data());
        const Loads without =
            EvalLoads<T>(base.model, th_base, kFlightInput, Setting::kFlight, at.data());
        ExpectLoadsEqual(with, without, what + ", flight at z = " + std::to_string(z));
      }
      ExpectLoadsEqual(EvalLoads<T>(v.model, th, kFlightInput, Setting::kBalance, nullptr),
                       EvalLoads<T>(base.model, th_base, kFlightInput, Setting::kBalance, nullptr),
                       what + ", balance");
      ExpectStateNear(EvalDerivative<T>(v.model, th, x, kFlightInput),
                      EvalDerivative<T>(base.model, th_base, x, kFlightInput), what);
    }
  }
  // ground_effect at its default k_ge = 1: nothing on a balance.
  const Vehicle ge = WithEffect(base, "ground_effect");
  ExpectLoadsEqual(
      EvalLoads<T>(ge.model, ge.parameters.Values(), kFlightInput, Setting::kBalance, nullptr),
      EvalLoads<T>(base.model, th_base, kFlightInput, Setting::kBalance, nullptr),
      "ground_effect at defaults, balance");
}

// ===========================================================================
// Non-typed: the Jet value parts are the double evaluation (same operations
// on the value part; 1e-14 relative allows for a different contraction order).

TEST(VehicleModelJetTest, JetValuePartsEqualDoubleWithAllEffects) {
  Vehicle v = DistinctVehicle();
  for (const auto& info : EffectLibrary()) {
    // These cases hold the 12 rigid-body states; an effect's own states
    // (stabilizer_bar) have their tests in stabilizer_bar_test.cc.
    if (info.num_own_states == 0) v = WithTypicalEffect(v, info.name);
  }
  const Eigen::VectorXd th = v.parameters.Values();
  for (const RandomCase& c : RandomCases(31337u, 12)) {
    const State fd = EvalDerivative<double>(v.model, th, c.x, c.input);
    const State fj = EvalDerivative<Jet4>(v.model, th, c.x, c.input);
    const State fj12 = EvalDerivative<ceres::Jet<double, 12>>(v.model, th, c.x, c.input);
    for (int i = 0; i < kNumStates; ++i) {
      EXPECT_NEAR(fj[i], fd[i], 1e-14 * (1 + std::fabs(fd[i]))) << StateName(i);
      EXPECT_NEAR(fj12[i], fd[i], 1e-14 * (1 + std::fabs(fd[i]))) << StateName(i);
    }
  }
}

// Every effect named in effects.md is in the library, each with a typical
// value inside its bounds.
TEST(VehicleModelJetTest, LibraryHoldsTheEffectsOfTheSpec) {
  for (const char* name : {"gyroscopic", "rotor_damping", "ground_effect", "rotor_drag",
                           "cg_offset", "swashplate_bias", "wind", "wake_interference",
                           "gyro_bias", "accel_bias", "servo_lag", "motor_lag",
                           "stabilizer_bar"}) {
    const int i = EffectIndex(name);
    ASSERT_GE(i, 0) << name;
    bool any_visible = false;
    for (const auto& spec : EffectLibrary()[i].parameters) {
      EXPECT_GE(spec.typical, spec.lower) << name << "." << spec.name;
      EXPECT_LE(spec.typical, spec.upper) << name << "." << spec.name;
      if (std::isfinite(spec.linearise_at)) {  // beside absence, inside the bounds
        EXPECT_GT(spec.linearise_at, spec.lower) << name << "." << spec.name;
        EXPECT_LT(spec.linearise_at, spec.typical) << name << "." << spec.name;
      }
      any_visible = any_visible || spec.typical != 0.0;
    }
    EXPECT_TRUE(any_visible) << name << ": typical values must make the effect visible";
  }
}

// The actuator effects lag exactly the inputs effects.md names: servo_lag
// the swashplate angles (with T_s), motor_lag the rotor speeds (omega1 with
// T_m1, omega2 with T_m2); the others are applied as logged.
TEST(VehicleModelJetTest, ActuatorLagsActOnTheirOwnInputs) {
  const Vehicle base = DistinctVehicle();
  ASSERT_FALSE(base.model.LagsInputs());
  HeldInput held = HeldInput::Steady({300.0, 320.0, 0.02, -0.01}, 1.0);
  held.start = {280.0, 330.0, 0.0, 0.01};  // where the lags left the actuators at t0
  const double t = 1.0 + 0.03;
  for (const char* name : {"servo_lag", "motor_lag"}) {
    const Vehicle v = WithTypicalEffect(base, name);
    ASSERT_TRUE(v.model.LagsInputs()) << name;
    const Eigen::VectorXd theta = v.parameters.Values();
    const InputVector lag = v.model.InputLags(theta.data());
    double u[kNumInputs];
    v.model.AppliedInput(theta.data(), held, t, u);
    const bool swash = std::string(name) == "servo_lag";
    for (int i = 0; i < kNumInputs; ++i) {
      const bool lagged = (i >= kDeltaCx) == swash;
      if (!lagged) {
        EXPECT_EQ(lag[i], 0.0) << name << " input " << i;
        EXPECT_EQ(u[i], held.logged[i]) << name << " input " << i;
        continue;
      }
      const char* parameter = swash ? "servo_lag.T_s" : i == kOmega1 ? "motor_lag.T_m1"
                                                                     : "motor_lag.T_m2";
      const double T = v.parameters.Value(parameter);
      EXPECT_EQ(lag[i], T) << name << " input " << i;
      EXPECT_NEAR(u[i], held.logged[i] + (held.start[i] - held.logged[i]) * std::exp(-0.03 / T),
                  1e-12 * (1 + std::fabs(u[i])))
          << name << " input " << i;
    }
  }
}

// The measurement effects (effects.md) change what the sensors log and
// nothing else: logged p, q, r move by exactly (b_p, b_q, b_r) and ax, ay, az
// by (b_ax, b_ay, b_az), every other channel and the dynamics not at all, in
// double and in Jet (whose derivative along each bias is 1 on its channel).
TEST(VehicleModelJetTest, MeasurementBiasesMoveOnlyTheirChannels) {
  const Vehicle base = DistinctVehicle();
  const Vehicle v = WithTypicalEffect(WithTypicalEffect(base, "gyro_bias"), "accel_bias");
  ASSERT_FALSE(base.model.ChangesFlightMeasurements());
  ASSERT_TRUE(v.model.ChangesFlightMeasurements());
  ASSERT_FALSE(WithTypicalEffect(base, "wind").model.ChangesFlightMeasurements());
  const Eigen::VectorXd th_base = base.parameters.Values(), th = v.parameters.Values();
  const State x = FlightState();
  double y_base[kNumFlightChannels], y[kNumFlightChannels];
  FlightOutputs(base.model, th_base.data(), x.data(), kFlightInput.data(), y_base);
  FlightOutputs(v.model, th.data(), x.data(), kFlightInput.data(), y);
  const std::map<int, std::string> bias = {{kP, "gyro_bias.b_p"},   {kQ, "gyro_bias.b_q"},
                                           {kR, "gyro_bias.b_r"},   {kAx, "accel_bias.b_ax"},
                                           {kAy, "accel_bias.b_ay"}, {kAz, "accel_bias.b_az"}};
  for (int c = 0; c < kNumFlightChannels; ++c) {
    const auto it = bias.find(c);
    const double b = it == bias.end() ? 0.0 : Param(v, it->second);
    if (it != bias.end()) ASSERT_NE(b, 0.0) << it->second;
    EXPECT_NEAR(y[c] - y_base[c], b, 1e-15 * (1 + std::fabs(y_base[c]))) << c;
  }
  ExpectStateNear(EvalDerivative<double>(v.model, th, x, kFlightInput),
                  EvalDerivative<double>(base.model, th_base, x, kFlightInput), "biases");
  // Jet: seed each bias in turn.
  using J = ceres::Jet<double, 1>;
  for (const auto& [channel, name] : bias) {
    std::vector<J> th_jet(th.size());
    for (int i = 0; i < th.size(); ++i) th_jet[i] = J(th[i]);
    th_jet[v.parameters.IndexOrThrow(name)].v[0] = 1.0;
    J xs[kNumStates], in[kNumInputs], out[kNumFlightChannels];
    for (int i = 0; i < kNumStates; ++i) xs[i] = J(x[i]);
    for (int k = 0; k < kNumInputs; ++k) in[k] = J(kFlightInput[k]);
    FlightOutputs(v.model, th_jet.data(), xs, in, out);
    for (int c = 0; c < kNumFlightChannels; ++c) {
      EXPECT_EQ(out[c].v[0], c == channel ? 1.0 : 0.0) << name << " on channel " << c;
      EXPECT_NEAR(out[c].a, y[c], 1e-14 * (1 + std::fabs(y[c]))) << c;
    }
  }
}

}  // namespace
}  // namespace coaxid

namespace coaxid {
namespace {

// WithoutEffect undoes WithEffect: the same effects and parameters (values,
// bounds, estimated flags) as before, whichever effect of two is taken out.
TEST(VehicleTest, WithoutEffectUndoesWithEffect) {
  const Vehicle base = WithTypicalEffect(DistinctVehicle(), "cg_offset");
  const Vehicle both = WithTypicalEffect(base, "wind");
  auto expect_same = [](const Vehicle& a, const Vehicle& b, const std::string& what) {
    EXPECT_EQ(a.EffectNames(), b.EffectNames()) << what;
    ASSERT_EQ(a.parameters.size(), b.parameters.size()) << what;
    for (int i = 0; i < a.parameters.size(); ++i) {
      EXPECT_EQ(a.parameters[i].name, b.parameters[i].name) << what;
      EXPECT_EQ(a.parameters[i].value, b.parameters[i].value) << what << " " << a.parameters[i].name;
      EXPECT_EQ(a.parameters[i].lower, b.parameters[i].lower) << what;
      EXPECT_EQ(a.parameters[i].upper, b.parameters[i].upper) << what;
      EXPECT_EQ(a.parameters[i].estimated, b.parameters[i].estimated) << what;
    }
  };
  expect_same(WithoutEffect(both, "wind"), base, "without wind");
  expect_same(WithoutEffect(both, "cg_offset"), WithTypicalEffect(DistinctVehicle(), "wind"),
              "without cg_offset");
  expect_same(WithoutEffect(base, "wind"), base, "without an effect it does not have");
}

}  // namespace
}  // namespace coaxid
