#include "ident/ekf/states_at_rows.h"

#include <limits>

namespace coaxid {

EkfStatesAtRows::EkfStatesAtRows(const std::vector<std::vector<int>>& rows) : rows_(rows) {
  // Sized by the first state recorded (the model's states).
  const Eigen::VectorXd nan = Eigen::VectorXd::Constant(1, std::numeric_limits<double>::quiet_NaN());
  for (size_t L = 0; L < rows_.size(); ++L) {
    for (const int row : rows_[L]) kept_[{static_cast<int>(L), row}] = {nan, nan};
  }
}

std::vector<Eigen::VectorXd> EkfStatesAtRows::Reported(int log, bool smoothed) const {
  std::vector<Eigen::VectorXd> out;
  out.reserve(rows_[log].size());
  for (const int row : rows_[log]) {
    const auto& [filtered, smoothed_state] = kept_.at({log, row});
    out.push_back(smoothed ? smoothed_state : filtered);
  }
  return out;
}

void EkfStatesAtRows::FilteredStates(int log, int row, const EkfRowValues& x, const EkfRowValues&) {
  auto it = kept_.find({log, row});
  if (it != kept_.end()) it->second.first = x;
}

void EkfStatesAtRows::SmoothedStates(int log, int row, const EkfRowValues& x, const EkfRowValues&) {
  auto it = kept_.find({log, row});
  if (it != kept_.end()) it->second.second = x;
}

}  // namespace coaxid
