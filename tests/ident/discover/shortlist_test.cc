// Which candidates a round refits (ident/discover/shortlist.h): passing
// ones first, then those a parameter at its bound may hide (blind ones
// before those acting on the distorted channels), then promising ones, each
// group capped and ranked by the linearised share, where a share above 1
// from a step beyond the candidate's bounds (a failed linearisation) ranks
// last; the most significant by its score test, below alpha before Holm, is
// refitted too. The at-bounds ones (passing beyond the slots, then failing)
// wait for the passing slots' refits.
#include "ident/discover/shortlist.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace coaxid {
namespace {

CandidateScore Score(const std::string& effect, double share, bool passes = false,
                     std::vector<std::string> channels = {"ax"}, bool blind = false,
                     bool beyond_linear_range = false) {
  CandidateScore s;
  s.effect = effect;
  s.testable = true;
  s.passes = passes;
  s.predicted_share = share;
  s.channels = std::move(channels);
  s.blind_at_bounds = blind;
  s.beyond_linear_range = beyond_linear_range;
  return s;
}

std::vector<std::string> Names(const std::vector<CandidateScore>& scores,
                               const std::vector<int>& picked) {
  std::vector<std::string> out;
  for (int k : picked) out.push_back(scores[k].effect);
  return out;
}

// Seed 8000 of discover_controllers.yaml (an undeclared ground effect, Cz at
// its lower bound, distorting az and w), its round-1 shares: wind blind,
// wake_interference at 406 %, accel_bias 1.7 %, ground_effect 0.63 %. The
// 406 % came from a step beyond its bounds (replayed on a766d57, the binary
// of the time: 409 %, k_T and k_Q both clipped to 0) and must not take the
// last slot from ground_effect.
TEST(Shortlist, AShareAboveOneFromAStepBeyondTheBoundsRanksLast) {
  std::vector<CandidateScore> scores = {
      Score("cg_offset", 4e-5, false, {"p", "q"}),
      Score("wake_interference", 4.06, false, {"ax", "az", "w", "p"}, false,
            /*beyond_linear_range=*/true),
      Score("accel_bias", 0.017, false, {"ax", "ay", "az"}),
      Score("wind", 1.7e-4, false, {"u", "v", "az", "w"}, /*blind=*/true),
      Score("ground_effect", 0.0063, false, {"az", "w"}),
      Score("motor_lag", 1.9e-5, false, {"az", "w", "p"})};
  const std::vector<int> picked = Shortlist(scores, {"az", "w"}, {}, 3, 0.3, 0.01).All();
  EXPECT_EQ(Names(scores, picked),
            (std::vector<std::string>{"wind", "accel_bias", "ground_effect"}));
  // With room for all, the 406 % comes after every informative share.
  EXPECT_EQ(Names(scores, Shortlist(scores, {"az", "w"}, {}, 10, 0.3, 0.01).All()),
            (std::vector<std::string>{"wind", "accel_bias", "ground_effect", "motor_lag",
                                      "wake_interference"}));
  // Inside its bounds the same share ranks first after the blind one.
  scores[1].beyond_linear_range = false;
  EXPECT_EQ(Names(scores, Shortlist(scores, {"az", "w"}, {}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"wind", "wake_interference", "accel_bias"}));
}

// Seed 11018 of discover_confusion.yaml (an undeclared ground effect, k_ge
// 1.37, flight only, Cz at its upper bound, distorting az and w), its
// round-1 shares and p-values: ground_effect's linearised step stays inside
// its bounds (k_ge 1.32) and predicts 341 % of the excess, its drop being
// the ties' too (shortlist.h). It takes the first slot; ranked last, wind,
// accel_bias and servo_lag took the three and nothing was added.
TEST(Shortlist, AShareAboveOneFromAStepInsideTheBoundsRanksByItsShare) {
  std::vector<CandidateScore> scores = {
      Score("stabilizer_bar", 0.00375, false, {"ax", "ay", "u", "v", "p", "q"}),
      Score("ground_effect", 3.41, false, {"az", "w"}),
      Score("servo_lag", 1.82e-4, false, {"ax", "ay", "u", "v", "w", "p", "q", "az"}),
      Score("motor_lag", 1.80e-4, false, {"az", "w", "r"}),
      Score("accel_bias", 2.21e-4, false, {"ax", "ay", "az"}),
      Score("wind", 0.00673, false, {"ax", "ay", "az", "u", "v", "w"})};
  const double p_values[] = {0.032, 0.0348, 0.115, 0.469, 0.635, 0.787};
  for (size_t k = 0; k < scores.size(); ++k) scores[k].p_value = p_values[k];
  EXPECT_EQ(Names(scores, Shortlist(scores, {"az", "w"}, {}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"ground_effect", "wind", "accel_bias"}));
  // The same share from a step beyond its bounds: last.
  scores[1].beyond_linear_range = true;
  EXPECT_EQ(Names(scores, Shortlist(scores, {"az", "w"}, {}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"wind", "accel_bias", "servo_lag"}));
}

// Seed 9349 of discover_controllers.yaml (an undeclared ground effect, flight
// only, Cz at its upper bound, distorting az and w), its round-1 scores:
// ground_effect's score test is the round's most significant (p = 0.0012).
// Its step there stays inside its bounds (528 %, first by its share); taken
// here as beyond them, ranked last by the share, it is refitted beside the
// three the shares rank first. A bound that leaves the score no power adds
// nothing.
TEST(Shortlist, TheMostSignificantAtABoundIsRefittedWhenTheSharesLeaveItOut) {
  std::vector<CandidateScore> scores = {
      Score("ground_effect", 5.283, false, {"az", "w"}, false, /*beyond_linear_range=*/true),
      Score("wind", 0.282, false, {"u", "v", "az", "w"}),
      Score("gyro_bias", 0.001, false, {"p", "q", "r"}),
      Score("accel_bias", 0.001, false, {"ax", "ay", "az"}),
      Score("motor_lag", 0.0, false, {"az", "w", "r"}),
      Score("servo_lag", 0.0, false, {"ax", "ay", "az", "w"})};
  const double p_values[] = {0.00116, 0.063, 0.225, 0.635, 0.669, 0.769};
  for (size_t k = 0; k < scores.size(); ++k) scores[k].p_value = p_values[k];
  EXPECT_EQ(Names(scores, Shortlist(scores, {"az", "w"}, {}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"wind", "accel_bias", "motor_lag", "ground_effect"}));
  // Already in the slots: not twice.
  EXPECT_EQ(Names(scores, Shortlist(scores, {"az", "w"}, {}, 10, 0.3, 0.01).All()),
            (std::vector<std::string>{"wind", "accel_bias", "motor_lag", "servo_lag",
                                      "ground_effect"}));
  // No power at the bound (seed 9744: every p-value 0.51-0.99): the shares alone.
  scores[0].p_value = 0.51;
  EXPECT_EQ(Names(scores, Shortlist(scores, {"az", "w"}, {}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"wind", "accel_bias", "motor_lag"}));
  // Excluded (a removed effect not yet allowed back): never.
  scores[0].p_value = 0.00116;
  EXPECT_EQ(Names(scores, Shortlist(scores, {"az", "w"}, {"ground_effect"}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"wind", "accel_bias", "motor_lag"}));
}

// Seed 9379 of discover_controllers.yaml (gyroscopic moments and rotor
// damping with the balance log, no parameter at a bound), its round-1
// scores: none passes Holm, none is predicted to remove half of the
// threshold; gyroscopic, the most significant (p = 0.0011), is refitted.
TEST(Shortlist, TheMostSignificantIsRefittedWhenNothingElseIs) {
  std::vector<CandidateScore> scores = {
      Score("gyroscopic", 0.123, false, {"p", "q", "r"}),
      Score("wind", 0.005, false, {"u", "v", "w"}),
      Score("servo_lag", 0.001, false, {"ax", "ay", "p", "q"}),
      Score("rotor_damping", 0.101, false, {"p", "q"}),
      Score("stabilizer_bar", 0.142, false, {"p", "q"})};
  const double p_values[] = {0.00108, 0.00233, 0.00234, 0.00698, 0.0594};
  for (size_t k = 0; k < scores.size(); ++k) scores[k].p_value = p_values[k];
  EXPECT_EQ(Names(scores, Shortlist(scores, {}, {}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"gyroscopic"}));
  // Not below alpha: nothing.
  scores[0].p_value = 0.014;
  scores[1].p_value = scores[2].p_value = scores[3].p_value = 0.02;
  EXPECT_TRUE(Shortlist(scores, {}, {}, 3, 0.3, 0.01).All().empty());
}

// Seed 9573 of discover_controllers.yaml (a stabilizer bar, flight only, low
// flight): the declared fit pressed Ixx, Iyy to their upper bound (distorting
// p, q, r) and sigma0 to 0 (ax, ay, az, u, v, w), and predicted p, q no better
// than their mean. Its round-1 shares and p-values (the channels written
// short) rank the bar sixth; with p, q lost,
// every candidate acting on them is refitted beyond the slots; one acting
// only on channels the fit still predicts (ground_effect on az, w) is not.
TEST(Shortlist, EveryCandidateOnAChannelTheFitHasLostIsRefitted) {
  std::vector<CandidateScore> scores = {
      Score("wind", 0.00801, false, {"u", "v", "w", "p", "q"}),
      Score("gyroscopic", 0.00606, false, {"p", "q"}),
      Score("rotor_drag", 0.00339, false, {"u", "v", "p", "q"}),
      Score("stabilizer_bar", 0.0029, false, {"p", "q", "phi", "theta"}),
      Score("ground_effect", 1.63e-5, false, {"az", "w"}),
      Score("swashplate_bias", 1.72e-4, false, {"p", "q"})};
  const double p_values[] = {0.0177, 0.0199, 0.0331, 0.144, 0.545, 0.752};
  for (size_t k = 0; k < scores.size(); ++k) scores[k].p_value = p_values[k];
  const std::vector<std::string> distorted = {"p", "q", "r", "ax", "ay", "az", "u", "v", "w"};
  EXPECT_EQ(Names(scores, Shortlist(scores, distorted, {}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"wind", "gyroscopic", "rotor_drag"}));
  EXPECT_EQ(Names(scores, Shortlist(scores, distorted, {}, 3, 0.3, 0.01, {"p", "q"}).All()),
            (std::vector<std::string>{"wind", "gyroscopic", "rotor_drag", "stabilizer_bar",
                                      "swashplate_bias"}));
  // The slots are refitted first; those beyond them only if none of the
  // slots' is added.
  const RoundShortlist split = Shortlist(scores, distorted, {}, 3, 0.3, 0.01, {"p", "q"});
  EXPECT_EQ(Names(scores, split.first),
            (std::vector<std::string>{"wind", "gyroscopic", "rotor_drag"}));
  EXPECT_EQ(Names(scores, split.on_lost_channels),
            (std::vector<std::string>{"stabilizer_bar", "swashplate_bias"}));
  // A lost channel no symptom distorts widens nothing (RefitShortlisted
  // passes only distorted ones); nor does it without a parameter at a bound.
  EXPECT_EQ(Names(scores, Shortlist(scores, {}, {}, 3, 0.3, 0.01, {"p", "q"}).All()),
            (std::vector<std::string>{}));
}

// Seed 9573's declared fit: ax at nrmse 0.95 and 1.0 x its noise holds
// little besides noise; p at nrmse 1.00 and 3.6 x, q at 1.01 and 3.0 x are
// lost; theta at 0.83 and 2.0 x is still followed; r is lost but no symptom
// distorts it.
TEST(LostChannels, PredictedNoBetterThanTheMeanAndWellAboveTheNoise) {
  auto test = [](const std::string& channel, double rms_over_noise) {
    ChannelResidualTest t;
    t.channel = channel;
    t.noise_std = 0.01;
    t.rms = rms_over_noise * t.noise_std;
    return t;
  };
  const std::map<std::string, FitError> fit = {
      {"ax", {0.1, 0.95, 100}}, {"p", {0.1, 1.00, 100}}, {"q", {0.1, 1.01, 100}},
      {"theta", {0.1, 0.83, 100}}, {"r", {0.1, 0.99, 100}}};
  const std::vector<ChannelResidualTest> tests = {test("ax", 1.0), test("p", 3.6), test("q", 3.0),
                                                  test("theta", 2.0), test("r", 5.0)};
  EXPECT_EQ(LostChannels(fit, tests, {"ax", "p", "q", "theta"}),
            (std::vector<std::string>{"p", "q"}));
  EXPECT_TRUE(LostChannels(fit, tests, {}).empty());  // no parameter at a bound
}

TEST(Shortlist, PassingFirstThenAtBoundsThenPromisingEachCapped) {
  const std::vector<CandidateScore> scores = {
      Score("a", 0.5, true),  Score("b", 0.9, true),    Score("c", 0.2, true),
      Score("d", 0.8, true),  Score("e", 0.4, false, {"w"}), Score("f", 0.6),
      Score("g", 0.1),        Score("h", 0.7, false, {"u"}, true)};
  // Passing: capped at 3 in the scores' order; at bounds: blind h, then e;
  // promising (share >= 0.15): none left under the cap of 3 in all.
  EXPECT_EQ(Names(scores, Shortlist(scores, {"w"}, {}, 3, 0.3, 0.01).All()),
            (std::vector<std::string>{"a", "b", "c", "h", "e"}));
  // e, failing and shortlisted for acting on the distorted w, waits for the
  // passing ones' refits; the blind h does not.
  const RoundShortlist split = Shortlist(scores, {"w"}, {}, 3, 0.3, 0.01);
  EXPECT_EQ(Names(scores, split.first), (std::vector<std::string>{"a", "b", "c", "h"}));
  EXPECT_EQ(Names(scores, split.after_passing), (std::vector<std::string>{"e"}));
  // The most significant by its score test, below alpha, does not wait.
  std::vector<CandidateScore> significant = scores;
  significant[4].p_value = 0.001;
  const RoundShortlist e_first = Shortlist(significant, {"w"}, {}, 3, 0.3, 0.01);
  EXPECT_EQ(Names(significant, e_first.first),
            (std::vector<std::string>{"a", "b", "c", "h", "e"}));
  EXPECT_TRUE(e_first.after_passing.empty());
  // With none passing, nothing waits.
  const std::vector<CandidateScore> failing = {Score("e", 0.4, false, {"w"}), Score("f", 0.6),
                                               Score("h", 0.7, false, {"u"}, true)};
  const RoundShortlist none_pass = Shortlist(failing, {"w"}, {}, 3, 0.3, 0.01);
  EXPECT_EQ(Names(failing, none_pass.first), (std::vector<std::string>{"h", "e", "f"}));
  EXPECT_TRUE(none_pass.after_passing.empty());
  // No parameter at a bound: f (0.6) is promising, g (0.1) is not; removed
  // effects never come back.
  const std::vector<CandidateScore> few = {Score("a", 0.5, true), Score("f", 0.6),
                                           Score("g", 0.1), Score("x", 0.9)};
  EXPECT_EQ(Names(few, Shortlist(few, {}, {"x"}, 3, 0.3, 0.01).All()), (std::vector<std::string>{"a", "f"}));
}

// Confusion seed 21387 (a swashplate bias and wind, low flight, flight
// only), round 1: Cx, Cy, Ixx, Iyy and sigma0 at bounds, six candidates
// passing. The three slots took the bar, wake and an accelerometer bias,
// the at-bounds slots three that failed their score test (rotor drag, servo
// lag, gyroscopic), and the bias and the wind, passing at p 1e-15 and 2e-6,
// were never refitted: nothing was added. The passing ones the slots leave
// out and that act on a distorted channel now take the at-bounds slots
// first, waiting for the slots' refits as the failing ones did; those go to
// the lost channels' list.
TEST(Shortlist, PassingOnesTheSlotsLeaveOutComeBeforeFailingOnesAtTheBounds) {
  const std::vector<std::string> p = {"p"};
  const std::vector<CandidateScore> scores = {
      Score("stabilizer_bar", 0.211, true, p), Score("wake_interference", 0.122, true, p),
      Score("accel_bias", 0.0845, true, p),    Score("cg_offset", 0.0764, true, p),
      Score("swashplate_bias", 0.0636, true, p), Score("wind", 0.0075, true, p),
      Score("rotor_drag", 0.0163, false, p),   Score("servo_lag", 0.002, false, p),
      Score("gyroscopic", 0.0016, false, p)};
  const RoundShortlist list = Shortlist(scores, p, {}, 3, 0.3, 0.01, p);
  EXPECT_EQ(Names(scores, list.first),
            (std::vector<std::string>{"stabilizer_bar", "wake_interference", "accel_bias"}));
  EXPECT_EQ(Names(scores, list.after_passing),
            (std::vector<std::string>{"cg_offset", "swashplate_bias", "wind"}));
  EXPECT_EQ(Names(scores, list.on_lost_channels),
            (std::vector<std::string>{"rotor_drag", "servo_lag", "gyroscopic"}));
  // A passing one that acts on no distorted channel stays out.
  std::vector<CandidateScore> elsewhere = scores;
  elsewhere[4].channels = {"r"};
  EXPECT_EQ(Names(elsewhere, Shortlist(elsewhere, p, {}, 3, 0.3, 0.01, p).after_passing),
            (std::vector<std::string>{"cg_offset", "wind", "rotor_drag"}));
}

}  // namespace
}  // namespace coaxid
