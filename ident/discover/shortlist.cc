#include "ident/discover/shortlist.h"

#include <algorithm>
#include <utility>

namespace coaxid {

std::vector<int> RoundShortlist::All() const {
  std::vector<int> all = first;
  all.insert(all.end(), after_passing.begin(), after_passing.end());
  all.insert(all.end(), on_lost_channels.begin(), on_lost_channels.end());
  return all;
}

RoundShortlist Shortlist(const std::vector<CandidateScore>& scores,
                         const std::vector<std::string>& symptom_channels,
                         const std::vector<std::string>& excluded, int max_refits,
                         double min_share_of_excess, double alpha,
                         const std::vector<std::string>& lost_channels) {
  std::vector<int> passing, blind, symptomatic, promising;
  int most_significant = -1;  // by the score test, of the testable ones that do not pass
  for (size_t k = 0; k < scores.size(); ++k) {
    const CandidateScore& s = scores[k];
    if (std::find(excluded.begin(), excluded.end(), s.effect) != excluded.end()) continue;
    if (s.testable && !s.passes && !s.blind_at_bounds &&
        (most_significant < 0 || s.p_value < scores[most_significant].p_value)) {
      most_significant = static_cast<int>(k);
    }
    if (s.passes) {
      passing.push_back(static_cast<int>(k));
    } else if (s.blind_at_bounds) {
      blind.push_back(static_cast<int>(k));
    } else if (s.testable && ReachesAny(s.channels, symptom_channels)) {
      symptomatic.push_back(static_cast<int>(k));
    } else if (s.testable && s.predicted_share >= 0.5 * min_share_of_excess) {
      promising.push_back(static_cast<int>(k));
    }
  }
  // A share above 1 from a step that left the candidate's bounds: the
  // linearisation failed (shortlist.h).
  auto ranking_share = [&](int k) {
    const CandidateScore& s = scores[k];
    return s.predicted_share > 1 && s.beyond_linear_range ? -1.0 : s.predicted_share;
  };
  auto by_share = [&](int a, int b) { return ranking_share(a) > ranking_share(b); };
  std::stable_sort(symptomatic.begin(), symptomatic.end(), by_share);
  std::stable_sort(promising.begin(), promising.end(), by_share);
  const size_t at_most = static_cast<size_t>(std::max(0, max_refits));
  auto take = [&](const std::vector<int>& group, size_t n, std::vector<int>* out) {
    for (size_t i = 0; i < group.size() && i < n; ++i) out->push_back(group[i]);
  };
  std::vector<int> out;
  take(passing, at_most, &out);
  // At the bounds: those blind there, then the passing ones the slots left
  // out that act on a distorted channel (in their rank), then the
  // symptomatic ones that fail (shortlist.h).
  std::vector<int> at_bounds = blind, passing_beyond;
  for (size_t i = at_most; i < passing.size(); ++i) {
    if (ReachesAny(scores[passing[i]].channels, symptom_channels)) {
      passing_beyond.push_back(passing[i]);
    }
  }
  at_bounds.insert(at_bounds.end(), passing_beyond.begin(), passing_beyond.end());
  at_bounds.insert(at_bounds.end(), symptomatic.begin(), symptomatic.end());
  take(at_bounds, at_most, &out);
  take(promising, at_most > out.size() ? at_most - out.size() : 0, &out);
  // The most significant by its score test (uncorrected), when the shares
  // left it out.
  const bool significant = most_significant >= 0 && scores[most_significant].p_value < alpha;
  if (significant &&
      std::find(out.begin(), out.end(), most_significant) == out.end()) {
    out.push_back(most_significant);
  }
  RoundShortlist list;
  // Beyond the slots: every one acting on a channel the fit has lost.
  for (int k : symptomatic) {
    if (ReachesAny(scores[k].channels, lost_channels) &&
        std::find(out.begin(), out.end(), k) == out.end()) {
      list.on_lost_channels.push_back(k);
    }
  }
  // The at-bounds slots' symptomatic and passing ones wait for the passing
  // slots' refits, when there are any.
  auto in = [](const std::vector<int>& group, int k) {
    return std::find(group.begin(), group.end(), k) != group.end();
  };
  for (int k : out) {
    const bool waits = !passing.empty() && (in(symptomatic, k) || in(passing_beyond, k)) &&
                       !(significant && k == most_significant);
    (waits ? list.after_passing : list.first).push_back(k);
  }
  return list;
}

std::vector<std::string> LostChannels(const std::map<std::string, FitError>& fit,
                                      const std::vector<ChannelResidualTest>& residual_tests,
                                      const std::vector<std::string>& symptom_channels) {
  std::vector<std::string> lost;
  for (const ChannelResidualTest& t : residual_tests) {
    const auto error = fit.find(t.channel);
    if (error != fit.end() && error->second.nrmse >= kUnexplainedNrmse &&
        t.rms >= kLostChannelRms * t.noise_std && ReachesAny({t.channel}, symptom_channels)) {
      lost.push_back(t.channel);
    }
  }
  return lost;
}

}  // namespace coaxid
