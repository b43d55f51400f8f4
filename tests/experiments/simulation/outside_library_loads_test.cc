// Loads outside the effect library (experiments/simulation/outside_library_loads.h)
// change the simulated truth by exactly their documented terms, and only the
// double-valued model: an estimator's Jet model of the same vehicle cannot
// see them, so they stay outside anything discover could add.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "core/errors.h"
#include "experiments/simulation/excitation.h"
#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {
namespace {

struct Point {
  State x{};
  InputVector u{};
};

Point NearHover() {
  Point p;
  p.x.fill(0.0);
  p.x[kZ] = -1.5;
  p.x[kU] = 0.3;
  p.x[kV] = -0.2;
  p.x[kW] = -0.4;  // climbing at 0.4 m/s
  p.x[kP] = 0.1;
  p.x[kPhi] = 0.05;
  p.u = {150.0, 140.0, 0.05, -0.03};
  return p;
}

Vehicle Truth(const std::map<std::string, double>& outside) {
  Scenario s;
  s.truth_outside_library = outside;
  return MakeTruthVehicle(
      LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml").config, s);
}

AeroLoads<double> LoadsAt(const Vehicle& v, const Point& p) {
  const Eigen::VectorXd theta = v.parameters.Values();
  return v.model.Loads(theta.data(), p.u.data(), Setting::kFlight, p.x.data());
}

TEST(OutsideLibraryLoads, AddExactlyTheirDocumentedTerms) {
  const Point p = NearHover();
  const AeroLoads<double> base = LoadsAt(Truth({}), p);
  const AeroLoads<double> yaw = LoadsAt(Truth({{"yaw_from_swashplate", 2e-3}}), p);
  const AeroLoads<double> climb = LoadsAt(Truth({{"thrust_from_climb_rate", 0.3}}), p);
  // N += k delta_cx.
  EXPECT_NEAR(yaw.moment_B[2] - base.moment_B[2], 2e-3 * 0.05, 1e-15);
  EXPECT_TRUE(yaw.force_B == base.force_B);
  // Z += k w Z_T: climbing (w < 0) with Z_T < 0 makes Z less negative.
  const double rotor_z = base.Z1 + base.Z2;
  ASSERT_LT(rotor_z, 0);
  EXPECT_NEAR(climb.force_B[2] - base.force_B[2], 0.3 * (-0.4) * rotor_z, 1e-12);
  EXPECT_GT(climb.force_B[2], base.force_B[2]);
  EXPECT_TRUE(climb.moment_B == base.moment_B);
}

TEST(OutsideLibraryLoads, AJetModelOfTheSameVehicleCannotSeeThem) {
  using Jet = ceres::Jet<double, 1>;
  const Point p = NearHover();
  const Vehicle truth = Truth({{"yaw_from_swashplate", 2e-3}, {"thrust_from_climb_rate", 0.3}});
  const AeroLoads<double> base = LoadsAt(Truth({}), p);
  const Eigen::VectorXd theta = truth.parameters.Values();
  std::vector<Jet> theta_j(theta.size()), x_j(kNumStates), u_j(kNumInputs);
  for (int i = 0; i < theta.size(); ++i) theta_j[i] = Jet(theta[i]);
  for (int i = 0; i < kNumStates; ++i) x_j[i] = Jet(p.x[i]);
  for (int i = 0; i < kNumInputs; ++i) u_j[i] = Jet(p.u[i]);
  const AeroLoads<Jet> jet = truth.model.Loads(theta_j.data(), u_j.data(), Setting::kFlight, x_j.data());
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(jet.force_B[k].a, base.force_B[k], 1e-12 * (1 + std::fabs(base.force_B[k])));
    EXPECT_NEAR(jet.moment_B[k].a, base.moment_B[k], 1e-15);
  }
  EXPECT_TRUE(truth.model.HasTruthOnlyLoads());
}

TEST(OutsideLibraryLoads, AnUnknownNameIsAnInputError) {
  const std::string yaml =
      "scenario: flight\ntruth:\n  outside_library: {yaw_from_swashplate: 1e-3, tail_rotor: 2}\n";
  try {
    ParseScenario(yaml, "bad.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("truth.outside_library: unknown outside-library load "
                                         "'tail_rotor'"),
              std::string::npos)
        << e.what();
  }
}

// Doublets: +A for 2 pulse units, -A for 2, 4 units of rest, channels in turn.
TEST(Excitation, DoubletsTakeTurnsOnTheChannels) {
  Excitation e;
  e.type = Excitation::Type::kDoublet;
  e.start_s = 1.0;
  e.pulse_s = 0.25;
  e.amplitude = {{"omega1", 4.0}, {"omega2", 5.0}, {"delta_cx", 0.02}, {"delta_cy", 0.03}};
  const ExcitationSignal signal(e);
  const double slot = 8 * e.pulse_s;
  const double amplitude[4] = {4.0, 5.0, 0.02, 0.03};
  EXPECT_EQ(signal.At(0.9), (InputVector{0, 0, 0, 0}));
  for (int c = 0; c < 4; ++c) {
    for (double units : {0.5, 1.9, 2.1, 3.9, 4.1, 7.9}) {
      const InputVector v = signal.At(1.0 + (c + 4) * slot + units * e.pulse_s);  // 2nd cycle
      const double want = units < 2 ? amplitude[c] : units < 4 ? -amplitude[c] : 0.0;
      for (int k = 0; k < 4; ++k) {
        EXPECT_DOUBLE_EQ(v[k], k == c ? want : 0.0) << "channel " << c << " at unit " << units;
      }
    }
  }
}

}  // namespace
}  // namespace coaxid
