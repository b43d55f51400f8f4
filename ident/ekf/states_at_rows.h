// A history sink that keeps only the filtered and smoothed states at chosen
// rows (the first rows of the fit windows, report.h WindowStartRows): what
// the window predictions need, without the full-rate histories (issue 15).
#pragma once

#include <map>
#include <utility>
#include <vector>

#include "dynamics/state.h"
#include "ident/ekf/history_sink.h"

namespace coaxid {

class EkfStatesAtRows : public EkfHistorySink {
 public:
  // rows[L]: the rows of log L to keep.
  explicit EkfStatesAtRows(const std::vector<std::vector<int>>& rows);

  // The reported states at the kept rows of log L, in the order given:
  // smoothed (when the smoother ran) or filtered.
  std::vector<Eigen::VectorXd> Reported(int log, bool smoothed) const;

  void BeginPass(const EkfPassRecord&) override {}
  void FilteredStates(int log, int row, const EkfRowValues& x, const EkfRowValues&) override;
  void SmoothedStates(int log, int row, const EkfRowValues& x, const EkfRowValues&) override;
  void Parameters(int, int, const EkfRowValues&, const EkfRowValues&) override {}
  void ParameterStdAtEstimate(int, int, const EkfRowValues&) override {}
  void Innovations(int, int, const std::vector<int>&, const Eigen::VectorXd&,
                   const Eigen::VectorXd&, double, int) override {}
  // No parameters are kept: EkfResult::settled_after_s needs a sink that keeps them.
  void VisitParameters(const std::function<void(int, int, const EkfRowValues&)>&) override {}

 private:
  std::vector<std::vector<int>> rows_;
  // (log, row) -> (filtered, smoothed)
  std::map<std::pair<int, int>, std::pair<Eigen::VectorXd, Eigen::VectorXd>> kept_;
};

}  // namespace coaxid
