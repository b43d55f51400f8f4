#include "core/input_hold.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/errors.h"
#include "core/log.h"

namespace coaxid {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Samples at t = 0, 1, 2.5 with inputs that name their row.
InputHold ThreeSamples() {
  return InputHold({0.0, 1.0, 2.5}, {InputVector{10, 11, 12, 13}, InputVector{20, 21, 22, 23},
                                     InputVector{30, 31, 32, 33}});
}

TEST(InputHoldTest, IntervalAtBreakpoints) {
  const InputHold hold = ThreeSamples();
  ASSERT_EQ(hold.size(), 3);
  // Zero-order hold: sample k holds on [t_k, t_{k+1}), so a breakpoint belongs
  // to the interval it starts, and the double just below it to the one before.
  EXPECT_EQ(hold.IntervalAt(0.0), 0);
  EXPECT_EQ(hold.IntervalAt(std::nextafter(1.0, -kInf)), 0);
  EXPECT_EQ(hold.IntervalAt(1.0), 1);
  EXPECT_EQ(hold.IntervalAt(std::nextafter(1.0, kInf)), 1);
  EXPECT_EQ(hold.IntervalAt(std::nextafter(2.5, -kInf)), 1);
  EXPECT_EQ(hold.IntervalAt(2.5), 2);
  EXPECT_EQ(hold.IntervalAt(std::nextafter(2.5, kInf)), 2);
}

TEST(InputHoldTest, OutsideTheSamples) {
  const InputHold hold = ThreeSamples();
  EXPECT_EQ(hold.IntervalAt(-1.0), 0);  // Before the first sample: the first input.
  EXPECT_EQ(hold.IntervalAt(std::nextafter(0.0, -kInf)), 0);
  EXPECT_EQ(hold.IntervalAt(1e9), 2);  // The last sample holds for ever.
  EXPECT_EQ(hold.IntervalAt(kInf), 2);
  EXPECT_EQ(hold.IntervalAt(-kInf), 0);
}

TEST(InputHoldTest, AtReturnsTheHeldInput) {
  const InputHold hold = ThreeSamples();
  EXPECT_EQ(hold.At(0.5), (InputVector{10, 11, 12, 13}));
  EXPECT_EQ(hold.At(1.0), (InputVector{20, 21, 22, 23}));
  EXPECT_EQ(hold.At(2.4999), (InputVector{20, 21, 22, 23}));
  EXPECT_EQ(hold.At(3.0), (InputVector{30, 31, 32, 33}));
  EXPECT_EQ(hold.time(2), 2.5);
  EXPECT_EQ(hold.input(1)[3], 23);
}

TEST(InputHoldTest, SingleSampleHoldsEverywhere) {
  const InputHold hold({5.0}, {InputVector{1, 2, 3, 4}});
  EXPECT_EQ(hold.IntervalAt(-10), 0);
  EXPECT_EQ(hold.IntervalAt(5), 0);
  EXPECT_EQ(hold.IntervalAt(50), 0);
}

TEST(InputHoldTest, MatchesLinearSearchOnRandomTimes) {
  // Irregular sampling (jitter) and queries both at and between breakpoints.
  std::mt19937 rng(12345);  // Seeded: the test is repeatable.
  std::uniform_real_distribution<double> step(0.001, 0.01);
  std::vector<double> times = {0.0};
  for (int k = 1; k < 1000; ++k) times.push_back(times.back() + step(rng));
  const InputHold hold(times, std::vector<InputVector>(times.size(), InputVector{}));
  std::uniform_real_distribution<double> query(-0.1, times.back() + 0.1);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(times.size()) - 1);
  for (int i = 0; i < 5000; ++i) {
    const double t = i % 2 == 0 ? query(rng) : times[pick(rng)];
    int expected = 0;
    for (int k = 0; k < static_cast<int>(times.size()); ++k) {
      if (times[k] <= t) expected = k;
    }
    ASSERT_EQ(hold.IntervalAt(t), expected) << "t = " << t;
  }
}

TEST(InputHoldTest, RefusesBadSamples) {
  EXPECT_THROW(InputHold({0.0, 1.0}, {InputVector{}}), InputError);                   // Sizes.
  EXPECT_THROW(InputHold({0.0, 1.0, 1.0}, std::vector<InputVector>(3)), InputError);  // Repeat.
  EXPECT_THROW(InputHold({0.0, 2.0, 1.0}, std::vector<InputVector>(3)), InputError);  // Back.
  EXPECT_THROW(InputHold({}, {}), InputError);                                        // Empty.
  EXPECT_THROW(InputHold({0.0, std::nan("")}, std::vector<InputVector>(2)), InputError);
  EXPECT_THROW(InputHold({0.0}, {InputVector{1, kInf, 0, 0}}), InputError);
}

TEST(InputHoldTest, FromLog) {
  // Column order in the file differs from InputVector order on purpose.
  const Log log = ParseLog(
      "# kind: balance\n"
      "delta_cy,t,omega2,Z,omega1,delta_cx\n"
      "0.04,0.0,110,-1,100,0.03\n"
      "0.08,0.5,220,-2,200,0.07\n",
      "hold.csv");
  const InputHold hold = InputHold::FromLog(log);
  ASSERT_EQ(hold.size(), 2);
  EXPECT_EQ(hold.times(), (std::vector<double>{0.0, 0.5}));
  EXPECT_EQ(hold.At(0.25), (InputVector{100, 110, 0.03, 0.04}));
  EXPECT_EQ(hold.At(0.5), (InputVector{200, 220, 0.07, 0.08}));
}

TEST(InputHoldTest, FromLogWithoutInputsNamesTheColumn) {
  Log log;
  log.source = "mem";
  log.SetColumn("t", {0, 1});
  log.SetColumn("omega1", {1, 1});
  try {
    InputHold::FromLog(log);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "mem: column 'omega2': missing");
  }
}

}  // namespace
}  // namespace coaxid
