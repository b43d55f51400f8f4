#include "core/input_hold.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.h"

namespace coaxid {

InputHold::InputHold(std::vector<double> times, std::vector<InputVector> inputs)
    : times_(std::move(times)), inputs_(std::move(inputs)) {
  if (times_.size() != inputs_.size()) {
    throw InputError("input hold: " + std::to_string(times_.size()) + " times but " +
                     std::to_string(inputs_.size()) + " input samples");
  }
  // An empty hold has no input to return for any time.
  if (times_.empty()) throw InputError("input hold: no samples");
  for (size_t k = 0; k < times_.size(); ++k) {
    if (!std::isfinite(times_[k])) {
      throw InputError("input hold: time of sample " + std::to_string(k) + " is not finite");
    }
    if (k > 0 && !(times_[k] > times_[k - 1])) {
      throw InputError("input hold: time of sample " + std::to_string(k) +
                       " is not after the previous one (times must be strictly increasing)");
    }
    for (const double u : inputs_[k]) {
      if (!std::isfinite(u)) {
        throw InputError("input hold: input of sample " + std::to_string(k) + " is not finite");
      }
    }
  }
}

void InputHold::SetLeadIn(std::vector<double> times, std::vector<InputVector> inputs) {
  if (times.size() != inputs.size()) throw InputError("input hold: lead-in sizes differ");
  for (size_t k = 0; k < times.size(); ++k) {
    const double next = k + 1 < times.size() ? times[k + 1] : times_.front();
    if (!(times[k] < next)) {
      throw InputError("input hold: the lead-in's times must increase to before the first row");
    }
  }
  lead_in_times_ = std::move(times);
  lead_in_inputs_ = std::move(inputs);
}

InputHold InputHold::FromLog(const Log& log) {
  const std::string source = log.source.empty() ? "<log>" : log.source;
  // A log that ReadLog accepted has these; one built in memory might not.
  std::vector<std::string> needed = {"t"};
  needed.insert(needed.end(), InputColumns().begin(), InputColumns().end());
  for (const std::string& name : needed) {
    if (!log.Has(name)) throw InputError(source + ": column '" + name + "': missing");
  }
  const std::vector<double>& t = log.Column("t");
  std::vector<const std::vector<double>*> columns;
  for (const std::string& name : InputColumns()) columns.push_back(&log.Column(name));
  std::vector<InputVector> inputs(t.size());
  for (size_t k = 0; k < t.size(); ++k) {
    for (size_t i = 0; i < inputs[k].size(); ++i) inputs[k][i] = (*columns[i])[k];
  }
  try {
    return InputHold(t, std::move(inputs));
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  }
}

int InputHold::IntervalAt(double t) const {
  CHECK(!times_.empty()) << "IntervalAt on an empty InputHold";
  // No cached "last index": a cache would make concurrent reads (parallel
  // simulations sharing one hold) a data race, and the search is only ~20 compares.
  const auto after = std::upper_bound(times_.begin(), times_.end(), t);
  if (after == times_.begin()) return 0;  // Before the first sample: its input holds.
  return static_cast<int>(after - times_.begin()) - 1;
}

}  // namespace coaxid
