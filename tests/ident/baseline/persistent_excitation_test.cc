// Persistent excitation (paper Lemma 1, eqs. 71-79, and eq. 73-74): the check
// accepts the paper's experiment and refuses, naming the condition and the
// inputs, logs with the rotors always at equal speed or without swashplate
// motion.
#include "ident/baseline/persistent_excitation.h"

#include <gtest/gtest.h>

#include <string>

#include "core/errors.h"
#include "tests/ident/baseline/balance_test_util.h"

namespace coaxid {
namespace {

using testing_util::ReferenceVehicle;
using testing_util::SimulatedBalance;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Keeps the rows of a log where keep(omega1, omega2) holds.
Log Filter(const Log& log, bool (*keep)(double, double)) {
  Log out = log;
  for (auto& column : out.values) column.clear();
  for (int k = 0; k < log.NumRows(); ++k) {
    if (!keep(log.Column("omega1")[k], log.Column("omega2")[k])) continue;
    for (size_t c = 0; c < log.columns.size(); ++c) out.values[c].push_back(log.values[c][k]);
  }
  return out;
}

ExcitationReport Check(const Log& log) {
  const std::vector<BalanceData> data = {MakeBalanceData(log)};
  return CheckBalanceExcitation(ReferenceVehicle().parameters, data);
}

TEST(Excitation, ThePapersExperimentIsExciting) {
  BalanceScenario s;
  s.hold_s = 0.2;
  const ExcitationReport r = Check(SimulatedBalance(s, 1));
  EXPECT_TRUE(r.condition71);
  EXPECT_TRUE(r.condition72);
  EXPECT_TRUE(r.swashplate);
  EXPECT_TRUE(r.information_computed);
  EXPECT_TRUE(r.well_conditioned);
  EXPECT_TRUE(r.Exciting()) << r.message;
  // The witnesses really satisfy eqs. 71-72 (checked on the inputs directly).
  const std::vector<BalanceData> data = {MakeBalanceData(SimulatedBalance(s, 1))};
  const InputVector& a = data[0].inputs[r.witness72.row_a];
  const InputVector& b = data[0].inputs[r.witness72.row_b];
  EXPECT_NE(a[0] * a[0] * b[1] * b[1], b[0] * b[0] * a[1] * a[1]);
  // eps I <= sum X^T X <= mu I with eps > 0 (eq. 73).
  EXPECT_GT(r.epsilon, 0);
  EXPECT_GE(r.mu, r.epsilon);
  EXPECT_NEAR(r.condition_number, r.mu / r.epsilon, 1e-9 * r.condition_number);
  EXPECT_TRUE(Contains(r.message, "persistently exciting")) << r.message;
}

TEST(Excitation, EqualRotorSpeedsFailCondition72) {
  BalanceScenario s;
  s.hold_s = 0.2;
  // Both rotors always at the same speed (the swashplate still moves, so the
  // ratio of w1 to w2 cos cos changes and (71) holds).
  const Log log = Filter(SimulatedBalance(s, 1), [](double w1, double w2) { return w1 == w2; });
  const ExcitationReport r = Check(log);
  EXPECT_TRUE(r.condition71);
  EXPECT_FALSE(r.condition72);
  EXPECT_TRUE(r.swashplate);
  EXPECT_FALSE(r.Exciting());
  EXPECT_TRUE(Contains(r.message, "(72)")) << r.message;
  EXPECT_TRUE(Contains(r.message, "gamma1 and gamma2")) << r.message;
  EXPECT_TRUE(Contains(r.message, "omega1 and omega2 must vary independently")) << r.message;
  EXPECT_FALSE(Contains(r.message, "(71)")) << r.message;
  EXPECT_FALSE(r.well_conditioned);  // the information matrix is singular too
}

TEST(Excitation, NoSwashplateMotionFailsTheSwashplateCondition) {
  BalanceScenario s;
  s.hold_s = 0.2;
  s.delta_cx = {0.0};
  s.delta_cy = {0.0};
  const ExcitationReport r = Check(SimulatedBalance(s, 1));
  EXPECT_TRUE(r.condition71);
  EXPECT_TRUE(r.condition72);
  EXPECT_FALSE(r.swashplate);
  EXPECT_FALSE(r.Exciting());
  EXPECT_TRUE(Contains(r.message, "swashplate condition fails")) << r.message;
  EXPECT_TRUE(Contains(r.message, "beta and Cz_beta cannot be separated")) << r.message;
  EXPECT_TRUE(Contains(r.message, "delta_cx or delta_cy must vary")) << r.message;
}

TEST(Excitation, EqualSpeedsWithoutSwashplateFailEverything) {
  BalanceScenario s;
  s.hold_s = 0.2;
  s.delta_cx = {0.0};
  s.delta_cy = {0.0};
  const Log log = Filter(SimulatedBalance(s, 1), [](double w1, double w2) { return w1 == w2; });
  const ExcitationReport r = Check(log);
  EXPECT_FALSE(r.condition71);
  EXPECT_FALSE(r.condition72);
  EXPECT_FALSE(r.swashplate);
  for (const char* part : {"(71)", "(72)", "swashplate"}) {
    EXPECT_TRUE(Contains(r.message, part)) << part << " in " << r.message;
  }
}

TEST(Excitation, TheBaselineRefusesUnexcitingLogs) {
  BalanceScenario s;
  s.hold_s = 0.2;
  s.delta_cx = {0.0};
  s.delta_cy = {0.0};
  const std::vector<BalanceData> data = {MakeBalanceData(SimulatedBalance(s, 1))};
  try {
    RunLinearBaseline(ReferenceVehicle().parameters, data, {});
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_TRUE(Contains(e.what(), "swashplate condition fails")) << e.what();
  }
}

TEST(Excitation, NoiseOnAFixedRatioIsNotExcitation) {
  // Equal commanded speeds measured with 0.01 rad/s of noise differ in ratio
  // by ~2e-4: below the tolerance (|sin| 1e-3), still a failure of (72).
  BalanceScenario s;
  s.hold_s = 0.2;
  Log log = Filter(SimulatedBalance(s, 1), [](double w1, double w2) { return w1 == w2; });
  std::vector<double>& omega1 = log.values[log.ColumnIndex("omega1")];
  for (size_t k = 0; k < omega1.size(); ++k) {
    omega1[k] += 0.01 * (static_cast<int>((k * 7919) % 13) - 6) / 6.0;  // within +-0.01 rad/s
  }
  const ExcitationReport r = Check(log);
  EXPECT_FALSE(r.condition72) << r.message;
  EXPECT_LT(r.witness72.sine, 3e-4);  // ~ 2 * 0.01 / 110 between two perturbed holds
  EXPECT_GT(r.witness72.sine, 0);
}

}  // namespace
}  // namespace coaxid
