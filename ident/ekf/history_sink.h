// Where the EKF's per-row records go (issue 15): the filtered and smoothed
// states, the recursive parameter estimates, the innovations. A pass hands
// them over row by row as it runs (the smoothed states block by block from
// the last, each block backward: ekf/pass.h), so that they need not all be
// in memory at once: an hour at 200 Hz is ~1 kB a row, 720 MB.
//
// EkfMemoryHistory keeps them in EkfResult::logs (EkfLogHistory, for library
// users and the tests); ekf/history_files.h streams them to the CSV tables
// and keeps a thinned copy for the plots.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "ident/ekf/ekf.h"
#include "ident/estimation_log.h"

namespace coaxid {

// What a pass records.
struct EkfPassRecord {
  bool states = false;           // filtered states (and smoothed ones when smoothing)
  bool parameters = false;       // the recursive parameter estimates
  bool std_at_estimate = false;  // the covariance pass's parameter std
  bool innovations = false;      // innovations, NIS
};

// A row's values: a matrix row or a contiguous buffer.
using EkfRowValues = Eigen::Ref<const Eigen::VectorXd, 0, Eigen::InnerStride<>>;

class EkfHistorySink {
 public:
  virtual ~EkfHistorySink() = default;
  // A pass recording `what` starts. Several passes may record the same
  // quantity (the noise adaptation passes and the estimation pass): a later
  // pass's values replace the earlier's where it writes.
  virtual void BeginPass(const EkfPassRecord& what) = 0;
  // The filtered states and their std at a row (the model's states, the 12
  // rigid-body ones first), every row in order.
  virtual void FilteredStates(int log, int row, const EkfRowValues& x, const EkfRowValues& std) = 0;
  // The smoothed ones, every row, in reverse blocks.
  virtual void SmoothedStates(int log, int row, const EkfRowValues& x, const EkfRowValues& std) = 0;
  // The recursive parameter estimates and their filter std (physical units), every row in order.
  virtual void Parameters(int log, int row, const EkfRowValues& value, const EkfRowValues& std) = 0;
  // The covariance pass's parameter std at the final estimates, every row in order.
  virtual void ParameterStdAtEstimate(int log, int row, const EkfRowValues& std) = 0;
  // At a row with an update: the innovations nu and sqrt(S_jj) of the log's
  // columns `columns` that took part, the row's NIS and its degrees of freedom.
  virtual void Innovations(int log, int row, const std::vector<int>& columns,
                           const Eigen::VectorXd& nu, const Eigen::VectorXd& std, double nis,
                           int dof) = 0;
  // The recorded parameter estimates again, row by row in order (for
  // EkfResult::settled_after_s).
  virtual void VisitParameters(
      const std::function<void(int log, int row, const EkfRowValues& value)>& visit) = 0;
};

// Sizes h's per-row state and innovation records for `rows` rows, its
// state_names and `m` measured columns (the smoothed states only with
// `smoother`), all NaN.
void SizeStateAndInnovationRecords(int rows, int m, bool smoother, EkfLogHistory* h);

// Stores one row's innovations (EkfHistorySink::Innovations) at `row` of *h.
void StoreInnovations(int row, const std::vector<int>& columns, const Eigen::VectorXd& nu,
                      const Eigen::VectorXd& std, double nis, int dof, EkfLogHistory* h);

// Into EkfLogHistory (EkfResult::logs): sized for the logs by the constructor.
class EkfMemoryHistory : public EkfHistorySink {
 public:
  // state_names: the model's (VehicleModel::StateNames); np: free
  // parameters; smoother, covariance_pass: which matrices there are.
  EkfMemoryHistory(const std::vector<EstimationLog>& logs,
                   const std::vector<std::string>& state_names, int np, bool smoother,
                   bool covariance_pass, std::vector<EkfLogHistory>* histories);

  void BeginPass(const EkfPassRecord&) override {}
  void FilteredStates(int log, int row, const EkfRowValues& x, const EkfRowValues& std) override;
  void SmoothedStates(int log, int row, const EkfRowValues& x, const EkfRowValues& std) override;
  void Parameters(int log, int row, const EkfRowValues& value, const EkfRowValues& std) override;
  void ParameterStdAtEstimate(int log, int row, const EkfRowValues& std) override;
  void Innovations(int log, int row, const std::vector<int>& columns, const Eigen::VectorXd& nu,
                   const Eigen::VectorXd& std, double nis, int dof) override;
  void VisitParameters(const std::function<void(int, int, const EkfRowValues&)>& visit) override;

 private:
  std::vector<EkfLogHistory>& logs_;
};

}  // namespace coaxid
