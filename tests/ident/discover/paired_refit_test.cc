#include "ident/discover/paired_refit.h"

#include <gtest/gtest.h>

namespace coaxid {
namespace {

// A round of three refits (scores 4, 7, 9) in which the bar's refit at its
// bound (shortlist slot 0) held back the best qualifying one (slot 2, score 9).
RoundRefits RoundWithAVeto() {
  RoundRefits r;
  r.shortlist = {4, 7, 9};
  r.refits.resize(3);
  r.choice.dominant = 0;
  r.choice.vetoed = 2;
  return r;
}

// Seed 10117 of the confusion study: gyroscopic, held back in round 1 by the
// bar at T_b = 10 s, qualifies beside the bar, which stays at its bound.
TEST(VetoedRefitOfTheSecond, IsAddedWhenBesideItTheFirstIsNotAnEffect) {
  EXPECT_EQ(VetoedRefitOfTheSecond(RoundWithAVeto(), 9, true), 2);
}

TEST(VetoedRefitOfTheSecond, IsNotAddedWhenTheFirstIsAnEffectBesideIt) {
  // The pair was refused on its share only: the first may still be the
  // dominant physics.
  EXPECT_EQ(VetoedRefitOfTheSecond(RoundWithAVeto(), 9, false), -1);
}

TEST(VetoedRefitOfTheSecond, OnlyTheRefitTheRoundHeldBack) {
  // The second had a refit of the round that did not qualify (slot 1).
  EXPECT_EQ(VetoedRefitOfTheSecond(RoundWithAVeto(), 7, true), -1);
  // No veto in the round.
  RoundRefits r = RoundWithAVeto();
  r.choice.vetoed = -1;
  r.choice.dominant = -1;
  EXPECT_EQ(VetoedRefitOfTheSecond(r, 9, true), -1);
}

}  // namespace
}  // namespace coaxid
