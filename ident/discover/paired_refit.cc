#include "ident/discover/paired_refit.h"

#include <algorithm>
#include <cmath>

#include "core/report_values.h"
#include "ident/discover/practical_significance.h"

namespace coaxid {
namespace {

// The refit of the round at its own bound that is significant and removes
// at least min_share_to_pair of its channels' excess (estimation data), the
// one removing the most excess error over all channels; or the round's
// dominant refit that held back a qualifying one without being significant
// (round_choice.h), when it removes the most. -1: none.
int FirstOfAPair(const RoundRefits& round, const std::vector<CandidateScore>& scores,
                 const DiscoveryOptions& o) {
  const double level = WaldLevel(o, round.shortlist.size());
  const double min_share = std::min(o.min_share_to_pair, o.min_share_of_excess);
  int first = -1;
  for (size_t k = 0; k < round.refits.size(); ++k) {
    const CandidateScore& s = scores[round.shortlist[k]];
    const bool at_its_bound = !s.plausible && s.wald_p_value < level;
    const bool dominant = static_cast<int>(k) == round.choice.dominant;
    if (!round.refits[k].ok || !(at_its_bound || dominant) ||
        !(s.channels_excess >= o.min_channels_excess) || !(s.share_of_excess >= min_share)) {
      continue;
    }
    if (first < 0 || round.refits[k].share_of_all_excess > round.refits[first].share_of_all_excess) {
      first = static_cast<int>(k);
    }
  }
  return first;
}

}  // namespace

int VetoedRefitOfTheSecond(const RoundRefits& round, int second, bool first_not_an_effect) {
  const int vetoed = round.choice.vetoed;
  if (!first_not_an_effect || vetoed < 0 || round.shortlist[vetoed] != second) return -1;
  return vetoed;
}

PairedRefit RefitBesideABound(const CandidatePass& pass, const ModelSnapshot& now,
                              const RoundRefits& round,
                              std::vector<CandidateScore>* scores, const Vehicle& declared,
                              const std::vector<std::string>& excluded,
                              const std::vector<EstimationLog>& estimation,
                              const std::vector<EstimationLog>& validation,
                              const DiscoveryOptions& o, int round_number,
                              DiscoveryClock::time_point start) {
  PairedRefit pair;
  const int k = FirstOfAPair(round, *scores, o);
  if (k < 0) return pair;
  CandidateScore& first = (*scores)[round.shortlist[k]];
  const CandidateRefit& with_first = round.refits[k];
  pair.first = first.effect;
  const bool significant = first.wald_p_value < WaldLevel(o, round.shortlist.size());
  Say(o, "discover: " + first.effect + "'s refit " + (significant ? "is significant and " : "") +
             "removes " + NumberText(100 * first.share_of_excess, "%.0f") +
             " % of its channels' excess error (" +
             NumberText(100 * with_first.share_of_all_excess, "%.0f") +
             " % over all channels), but " +
             (significant ? first.why_implausible
                          : "it is not significant (cluster-robust Wald p = " +
                                NumberText(first.wald_p_value, "%.3g") + ")") +
             ": refitting the round with it in the model, for an effect beside it");
  ModelSnapshot at_first = with_first.snapshot;
  const std::string failed = TryAddValidation(validation, o, &at_first);
  if (!failed.empty()) {
    pair.why_not = "the model with it fails on the held-out data: " + failed;
    Say(o, "discover: nothing added beside " + first.effect + ": " + pair.why_not);
    return pair;
  }
  pair.beside = ScoreRound(with_first.next, at_first, estimation, o, round_number);
  for (CandidateScore& s : pair.beside) s.beside = first.effect;
  std::vector<std::string> not_beside = excluded;
  not_beside.push_back(first.effect);
  RoundRefits refits = RefitShortlisted(with_first.next, at_first, declared, not_beside, estimation,
                                        validation, &pair.beside, o, start);
  if (refits.choice.added < 0) {
    pair.why_not = "no candidate qualifies beside it";
    Say(o, "discover: nothing added beside " + first.effect + ": " + pair.why_not);
    return pair;
  }
  CandidateScore& second = pair.beside[refits.shortlist[refits.choice.added]];
  pair.second = second.effect;
  pair.joint = std::move(refits.refits[refits.choice.added]);
  const ParameterSet& joint = pair.joint.snapshot.result.parameters;
  // The first at the joint refit: inside its bounds and significantly away
  // from absence.
  std::string why;
  bool first_not_an_effect = true;  // beside the second: at its bound, or not significant
  if (OwnParameterAtBound(first.effect, joint)) {
    why = first.effect + " stays at its bound beside " + second.effect;
  } else {
    std::string why_not_tested;
    const ColumnTest t = EffectWaldTest(pair.joint.next, first.effect, &why_not_tested);
    pair.first_wald_p_value = t.ok ? t.p_value : 1;
    if (!t.ok) {
      why = first.effect + " at the joint refit: " + why_not_tested;
    } else if (!(t.p_value < WaldLevel(o, round.shortlist.size()))) {
      why = first.effect + " is not significantly away from absence beside " + second.effect +
            " (cluster-robust Wald p = " + NumberText(t.p_value, "%.3g") + ")";
    }
  }
  // The pair against the model with neither, on both members' channels.
  std::vector<std::string> channels = first.channels;
  for (const std::string& c : second.channels) {
    if (std::find(channels.begin(), channels.end(), c) == channels.end()) channels.push_back(c);
  }
  const ExcessShare estimation_share =
      ShareOfExcessRemoved(now.fit, pair.joint.snapshot.fit, now.residual_tests, channels);
  pair.share_of_excess = estimation_share.share;
  if (!validation.empty() && !pair.joint.snapshot.validation.empty()) {
    pair.share_of_excess_held_out = HeldOutShareOfExcessRemoved(
        estimation_share, now.validation, pair.joint.snapshot.validation,
        now.validation_residual_tests, channels);
  }
  const double held_out = std::isfinite(pair.share_of_excess_held_out)
                              ? pair.share_of_excess_held_out
                              : pair.share_of_excess;
  if (why.empty()) first_not_an_effect = false;
  if (why.empty() &&
      !(pair.share_of_excess >= o.min_share_of_excess && held_out >= o.min_share_of_excess)) {
    why = "the pair removes " + ShareText(pair.share_of_excess, pair.share_of_excess_held_out) +
          ", below " +
          NumberText(100 * o.min_share_of_excess, "%.0f") + " %";
  }
  if (!why.empty()) {
    pair.why_not = why;
    Say(o, "discover: " + first.effect + " and " + second.effect + " are not added: " + why);
    // The second may be the whole answer, kept off the round's shortlist by
    // the first (measured, controllers' study seed 9092: a swashplate bias
    // alone, the bar's refit at T_b = 10 s took a slot, the bias none).
    const auto it = std::find_if(scores->begin(), scores->end(), [&](const CandidateScore& s) {
      return s.effect == second.effect;
    });
    if (it == scores->end()) return pair;
    if (it->refitted) {
      // The second qualified alone in the round and was held back only by
      // the first's dominance (round_choice.h); beside it the first is not
      // an effect: the second is added from its own refit of the round
      // (measured, confusion study seed 10117, gyroscopic + wind with the
      // balance log: the bar's refit at T_b = 10 s and d_u = 0 removed 92 %
      // of all channels' excess and held back gyroscopic, which removed
      // 100 % of its channels'; beside gyroscopic the bar stayed at its
      // bounds and nothing was added).
      const int vetoed =
          VetoedRefitOfTheSecond(round, static_cast<int>(it - scores->begin()), first_not_an_effect);
      if (vetoed < 0) return pair;
      pair.second_alone = true;
      pair.joint = round.refits[vetoed];
      it->confirmed = true;
      it->why_not_confirmed.clear();
      Say(o, "discover: added " + second.effect + " from its own refit of the round (removes " +
                 ShareText(it->share_of_excess, it->share_of_excess_held_out) + "): " +
                 first.effect + ", which held it back, is not an effect beside it");
      return pair;
    }
    Say(o, "discover: refitting " + second.effect + " alone, against the model without " +
               first.effect);
    RoundRefits alone = RefitListed(pass, now, declared, {static_cast<int>(it - scores->begin())},
                                    round.shortlist.size() + 1, estimation, validation, scores, o,
                                    start);
    if (alone.choice.added != 0) return pair;
    pair.second_alone = true;
    pair.joint = std::move(alone.refits[0]);
    Say(o, "discover: added " + second.effect + " (Wald p = " +
               NumberText(it->wald_p_value, "%.3g") + ", removes " +
               ShareText(it->share_of_excess, it->share_of_excess_held_out) + ")");
    return pair;
  }
  pair.added = true;
  first.confirmed = true;
  first.added_with = second.effect;
  first.why_not_confirmed.clear();
  Say(o, "discover: added " + first.effect + " and " + second.effect + " together (" +
             first.effect + " Wald p = " + NumberText(pair.first_wald_p_value, "%.3g") +
             " beside it; the pair removes " +
             ShareText(pair.share_of_excess, pair.share_of_excess_held_out) + ")");
  return pair;
}

}  // namespace coaxid
