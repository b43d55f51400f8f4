#include "ident/discover/practical_significance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/report_values.h"

namespace coaxid {

double WeightedExcess(const std::vector<ChannelResidualTest>& tests, const NoiseWeights& weights) {
  double excess = 0;
  for (const ChannelResidualTest& t : tests) {
    const double w = weights.For(t.channel);
    excess += t.count * std::max(0.0, t.rms * t.rms - t.noise_std * t.noise_std) / (w * w);
  }
  return excess;
}

ExcessShare ShareOfExcessRemoved(const std::map<std::string, FitError>& before,
                                 const std::map<std::string, FitError>& after,
                                 const std::vector<ChannelResidualTest>& tests,
                                 const std::vector<std::string>& channels) {
  ExcessShare out;
  double removed = 0;
  for (const std::string& c : channels) {
    const auto b = before.find(c), a = after.find(c);
    const auto t = std::find_if(tests.begin(), tests.end(),
                                [&](const ChannelResidualTest& x) { return x.channel == c; });
    if (b == before.end() || a == after.end() || t == tests.end() || !(t->noise_std > 0)) continue;
    const double noise2 = t->noise_std * t->noise_std;
    const double ms_before = b->second.rms * b->second.rms, ms_after = a->second.rms * a->second.rms;
    const double excess = std::max(0.0, ms_before - noise2);
    out.excess += excess / noise2;
    removed += (ms_before - ms_after) / noise2;
    out.per_channel[c] = excess > 0 ? (ms_before - ms_after) / excess : 0.0;
    out.removed[c] = (ms_before - ms_after) / noise2;
  }
  out.share = out.excess > 0 ? removed / out.excess : 0.0;
  return out;
}

double ChannelsExcess(const std::map<std::string, FitError>& fit,
                      const std::vector<ChannelResidualTest>& tests,
                      const std::vector<std::string>& channels) {
  return ShareOfExcessRemoved(fit, fit, tests, channels).excess;
}

double HeldOutShareOfExcessRemoved(const ExcessShare& estimation,
                                   const std::map<std::string, FitError>& before,
                                   const std::map<std::string, FitError>& after,
                                   const std::vector<ChannelResidualTest>& tests,
                                   const std::vector<std::string>& channels) {
  double gain = 0, gain_held_out = 0;
  for (const auto& [channel, removed] : estimation.removed) {
    if (!(removed > 0)) continue;
    gain += removed;
    const bool measured = std::any_of(tests.begin(), tests.end(), [&](const ChannelResidualTest& t) {
      return t.channel == channel;
    });
    if (measured) gain_held_out += removed;
  }
  if (gain > 0 && gain_held_out < 0.5 * gain) return std::numeric_limits<double>::quiet_NaN();
  return ShareOfExcessRemoved(before, after, tests, channels).share;
}

std::string ShareText(double share, double share_held_out) {
  return NumberText(100 * share, "%.1f") + " % of its channels' excess error" +
         (std::isfinite(share_held_out)
              ? " (" + NumberText(100 * share_held_out, "%.1f") + " % held out)"
              : std::string());
}

}  // namespace coaxid
