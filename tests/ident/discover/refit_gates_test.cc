// The gates a refitted candidate must pass (round_refits.h, WhyNotConfirmed):
// each one, on a refit that passes every other.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "ident/discover/round_refits.h"

namespace coaxid {
namespace {

// A refit that passes every gate at level 0.01.
CandidateScore Qualifying() {
  CandidateScore s;
  s.effect = "wake_interference";
  s.wald_p_value = 1e-10;
  s.plausible = true;
  s.channels_excess = 50;
  s.share_of_excess = 0.9;
  s.share_of_excess_held_out = 0.8;
  return s;
}

TEST(RefitGates, AQualifyingRefitPassesEveryGate) {
  EXPECT_EQ(WhyNotConfirmed(Qualifying(), 0.01, DiscoveryOptions()), "");
}

// A held-out share judges when there is one; NaN (no held-out logs, or none
// whose channels hold a misfit) leaves the estimation share to decide.
TEST(RefitGates, TheHeldOutShareJudgesOnlyWhenThereIsOne) {
  CandidateScore s = Qualifying();
  s.share_of_excess_held_out = 0.15;
  const std::string why = WhyNotConfirmed(s, 0.01, DiscoveryOptions());
  EXPECT_NE(why.find("practically insignificant"), std::string::npos) << why;
  s.share_of_excess_held_out = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(WhyNotConfirmed(s, 0.01, DiscoveryOptions()), "");
  s.share_of_excess = 0.2;
  EXPECT_NE(WhyNotConfirmed(s, 0.01, DiscoveryOptions()).find("practically insignificant"),
            std::string::npos);
}

TEST(RefitGates, SignificanceAndPhysicalMeaningComeFirst) {
  CandidateScore s = Qualifying();
  s.wald_p_value = 0.02;
  EXPECT_NE(WhyNotConfirmed(s, 0.01, DiscoveryOptions()).find("not significantly away"),
            std::string::npos);
  s = Qualifying();
  s.plausible = false;
  s.why_implausible = "k_T at its bound";
  EXPECT_NE(WhyNotConfirmed(s, 0.01, DiscoveryOptions()).find("not physically meaningful"),
            std::string::npos);
}

}  // namespace
}  // namespace coaxid
