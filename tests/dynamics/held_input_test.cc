// The first-order actuator lag over zero-order-hold rows
// (dynamics/held_input.h): the row-to-row recursion against the closed-form
// response of the lag ODE, its derivative in the time constant against
// central differences, and the Jet evaluation inside an interval.
#include "dynamics/held_input.h"

#include <random>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "core/errors.h"
#include "dynamics/state.h"

namespace coaxid {
namespace {

InputHold RandomRows(int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-0.05, 0.05), gap(0.002, 0.02);
  std::vector<double> t{0.0};
  std::vector<InputVector> u;
  for (int k = 0; k < n; ++k) {
    if (k > 0) t.push_back(t.back() + gap(rng));  // irregular rows
    u.push_back({300.0, 310.0, angle(rng), angle(rng)});
  }
  return InputHold(t, u);
}

// The lag ODE d(a)/dt = (c - a) / T integrated by 2000 RK4 steps per row:
// independent of the exponential.
double Rk4Lag(const InputHold& hold, int input, double T, double t_end) {
  double a = hold.input(0)[input];
  for (int k = 0; hold.time(k) < t_end; ++k) {
    const double c = hold.input(k)[input];
    const double t1 = k + 1 < hold.size() ? std::min(hold.time(k + 1), t_end) : t_end;
    const double h = (t1 - hold.time(k)) / 2000;
    for (int s = 0; s < 2000; ++s) {
      const double k1 = (c - a) / T, k2 = (c - (a + 0.5 * h * k1)) / T,
                   k3 = (c - (a + 0.5 * h * k2)) / T, k4 = (c - (a + h * k3)) / T;
      a += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    if (k + 1 >= hold.size()) break;
  }
  return a;
}

TEST(HeldInput, LagPathMatchesTheIntegratedLagOde) {
  const InputHold hold = RandomRows(60, 1);
  const double T = 0.03;
  const std::vector<HeldInput> path = HeldInputs(hold, {0, 0, T, T});
  for (int k : {1, 7, 30, 59}) {
    for (int i : {kDeltaCx, kDeltaCy}) {
      // RK4 with h/T <= 3e-4: error ~ (h/T)^4 ~ 1e-14 of the step sizes.
      EXPECT_NEAR(path[k].start[i], Rk4Lag(hold, i, T, hold.time(k)), 1e-12) << k;
      // Unlagged inputs are the logged ones.
      EXPECT_EQ(path[k].start[kOmega1], hold.input(k)[kOmega1]);
    }
    // HeldInputAt walks the same recursion.
    EXPECT_EQ(HeldInputAt(hold, k, {0, 0, T, T}).start[kDeltaCx], path[k].start[kDeltaCx]);
  }
  // Inside an interval: the exponential, evaluated at 40 % of row 30's interval.
  const double t = hold.time(30) + 0.4 * (hold.time(31) - hold.time(30));
  EXPECT_NEAR(LaggedInput(path[30], kDeltaCx, T, t), Rk4Lag(hold, kDeltaCx, T, t), 1e-12);
}

TEST(HeldInput, DerivativeInTheTimeConstantMatchesCentralDifferences) {
  const InputHold hold = RandomRows(200, 2);
  const double T = 0.04, h = 1e-6;
  const std::vector<HeldInput> path = HeldInputs(hold, {0, 0, T, T});
  const std::vector<HeldInput> plus = HeldInputs(hold, {0, 0, T + h, T + h});
  const std::vector<HeldInput> minus = HeldInputs(hold, {0, 0, T - h, T - h});
  using Jet = ceres::Jet<double, 1>;
  for (int k : {3, 50, 199}) {
    const double fd = (plus[k].start[kDeltaCy] - minus[k].start[kDeltaCy]) / (2 * h);
    // Central differences: truncation ~h^2 |a'''| ~1e-9, round-off ~1e-16 / h.
    EXPECT_NEAR(path[k].start_dlag[kDeltaCy], fd, 1e-7 + 1e-6 * std::fabs(fd)) << k;
    if (k + 1 >= hold.size()) continue;
    // The Jet through (A) inside the interval.
    const double t = hold.time(k) + 0.7 * (hold.time(k + 1) - hold.time(k));
    const Jet applied = LaggedInput(path[k], kDeltaCy, Jet(T, 0), t);
    const double fd_t = (LaggedInput(plus[k], kDeltaCy, T + h, t) -
                         LaggedInput(minus[k], kDeltaCy, T - h, t)) / (2 * h);
    EXPECT_NEAR(applied.v[0], fd_t, 1e-7 + 1e-6 * std::fabs(fd_t)) << k;
    EXPECT_DOUBLE_EQ(applied.a, LaggedInput(path[k], kDeltaCy, T, t));
  }
}

TEST(HeldInput, NoLagIsTheLoggedRow) {
  const InputHold hold = RandomRows(20, 3);
  const std::vector<HeldInput> path = HeldInputs(hold, {0, 0, 0, 0});
  for (int k = 0; k < hold.size(); ++k) {
    for (int i = 0; i < kNumInputs; ++i) {
      EXPECT_EQ(LaggedInput(path[k], i, 0.0, hold.time(k) + 1e-3), hold.input(k)[i]);
    }
  }
}

// A hold cut from a longer one (a held-out tail) starts its lagged inputs
// where the source's rows before the cut left them (the lead-in), with the
// derivative in the time constant carried through: the tail's rows equal the
// whole hold's rows, bit for bit, when the lead-in holds every earlier row,
// and to e^(-lead-in / T) of the step otherwise. Without the lead-in the tail
// starts settled at its first command (the logged row).
TEST(HeldInput, ATailStartsWhereTheLeadInLeftTheLag) {
  const InputHold whole = RandomRows(400, 4);
  const InputVector lag = {0.19, 0.11, 0.03, 0.03};
  const std::vector<HeldInput> path = HeldInputs(whole, lag);
  auto tail = [&](int begin, int lead_in_first) {
    std::vector<double> t(whole.times().begin() + begin, whole.times().end());
    std::vector<InputVector> u, lead_u;
    for (int k = begin; k < whole.size(); ++k) u.push_back(whole.input(k));
    for (int k = lead_in_first; k < begin; ++k) lead_u.push_back(whole.input(k));
    InputHold h(t, u);
    h.SetLeadIn(std::vector<double>(whole.times().begin() + lead_in_first,
                                    whole.times().begin() + begin),
                lead_u);
    return h;
  };
  const int begin = 300;
  const InputHold full_lead_in = tail(begin, 0);
  const std::vector<HeldInput> tail_path = HeldInputs(full_lead_in, lag);
  for (int k : {0, 1, 50}) {
    for (int i = 0; i < kNumInputs; ++i) {
      EXPECT_EQ(tail_path[k].start[i], path[begin + k].start[i]) << k << " " << i;
      EXPECT_EQ(tail_path[k].start_dlag[i], path[begin + k].start_dlag[i]) << k << " " << i;
    }
  }
  EXPECT_EQ(FirstHeldInput(full_lead_in, lag).start[kOmega1], path[begin].start[kOmega1]);
  // A lead-in of the last 100 rows only: the rotor commands of RandomRows are
  // constant, so only the swashplate's history is cut off, and it weighs
  // e^(-lead-in / 0.03) of the commands' 0.1 rad spread.
  const double lead_s = whole.time(begin) - whole.time(begin - 100);
  const HeldInput short_lead_in = FirstHeldInput(tail(begin, begin - 100), lag);
  for (int i : {kDeltaCx, kDeltaCy}) {
    EXPECT_NEAR(short_lead_in.start[i], path[begin].start[i], 0.1 * std::exp(-lead_s / 0.03));
  }
  // No lead-in: settled at the first command.
  const InputHold no_lead_in = tail(begin, begin);
  EXPECT_EQ(FirstHeldInput(no_lead_in, lag).start, whole.input(begin));
  EXPECT_NE(path[begin].start[kDeltaCx], whole.input(begin)[kDeltaCx]);
  // Lead-in times must end before the first row.
  InputHold bad = no_lead_in;
  EXPECT_THROW(bad.SetLeadIn({whole.time(begin)}, {whole.input(begin)}), InputError);
}

}  // namespace
}  // namespace coaxid
