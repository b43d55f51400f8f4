// Practical significance of a candidate effect (effects.md, step 5): with
// thousands of samples a candidate can pass a test while explaining almost
// nothing. What matters is how much of its channels' structured misfit it
// removes. A channel's excess error is what its residual holds beyond sensor
// noise, rms^2 - noise^2, the noise variance being the residual's
// sample-to-sample estimate (ChannelResidualTest::noise_std: robust first
// differences, which a misfit smooth on the scale of a sample does not
// reach). Channels are summed in units of their own noise variance.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/statistics.h"
#include "ident/discover/residual_analysis.h"
#include "ident/noise_weights.h"

namespace coaxid {

// Sum over channels of count * max(0, rms^2 - noise^2) / weight^2: the
// excess in the units of the fit's weighted RSS.
double WeightedExcess(const std::vector<ChannelResidualTest>& tests, const NoiseWeights& weights);

struct ExcessShare {
  double share = 0;  // sum of (ms_before - ms_after) / noise^2 over sum of excess / noise^2
  std::map<std::string, double> per_channel;  // (ms_before - ms_after) / excess_before
  double excess = 0;  // sum of max(0, ms_before - noise^2) / noise^2 over the channels
};

// The share of the excess of `channels` removed from `before` to `after`
// (fit errors of the same logs), the noise from `tests` (the residual tests
// of `before`). Channels absent from any of the three are skipped; a share
// is 0 when the channels hold no excess.
ExcessShare ShareOfExcessRemoved(const std::map<std::string, FitError>& before,
                                 const std::map<std::string, FitError>& after,
                                 const std::vector<ChannelResidualTest>& tests,
                                 const std::vector<std::string>& channels);

// "12.3 % of its channels' excess error (4.5 % held out)": a share and its
// held-out share (NaN: none), in words.
std::string ShareText(double share, double share_held_out);

}  // namespace coaxid
