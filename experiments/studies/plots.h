// The figures of a study (rendered by core/plot.h RenderFigures into
// DIR/plots/), whichever apply:
//   estimates.png        estimate / truth with error bars per method: every run
//                        (+- its reported std) for a plain Monte Carlo, the
//                        mean +- spread per point for a sweep;
//   coverage.png         coverage of the 95 % intervals per parameter against
//                        the nominal 95 % and its binomial band;
//   detection.png        discover's detection probability vs effect strength;
//   error_vs_length.png  rms error / |truth| vs flight log length.
#pragma once

#include <vector>

#include <nlohmann/json.hpp>

#include "core/plot.h"
#include "experiments/studies/spec.h"

namespace coaxid {

std::vector<NamedFigure> StudyFigures(const StudySpec& spec, const nlohmann::json& summary,
                                      const std::vector<nlohmann::json>& records);

}  // namespace coaxid
