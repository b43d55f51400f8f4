// The EKF's per-row records streamed to scratch files (issue 15), for the
// CSV tables of long logs: memory independent of the log length.
//
// Each quantity goes to its own binary scratch file in a given folder (the
// CLI: the temporary folder, $TMPDIR or /tmp), unlinked as soon as it is
// opened (nothing is left behind if the run fails): the filtered states,
// the parameters and their std, the std at the estimate, row by row in
// order; the smoothed states block by block at their rows' places; the innovations one file per
// recording pass (a noise adaptation pass and the estimation pass), merged as the in-memory history
// merges them (a later pass's value where it wrote one). The CSV tables are
// written from them at the end (history_csv.h: the same bytes as report.h's
// writers over EkfResult::logs), each through WriteFileAtomically.
//
// A thinned copy (every EkfPlotStride-th row and each log's last row, as
// EkfLogHistory with `rows` set) stays in memory for the plots, and the
// states at chosen rows (states_at_rows.h) for the window predictions.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "ident/ekf/history_sink.h"
#include "ident/ekf/states_at_rows.h"

namespace coaxid {

class EkfHistoryFiles : public EkfHistorySink {
 public:
  // logs: as given to RunEkf (they must outlive this); state_names: the
  // model's (VehicleModel::StateNames); smoother: whether RunEkf smooths
  // (EkfOptions::smoother); folder: where the scratch files go;
  // keep_states_at[L]: rows of log L whose states to keep (EkfStatesAtRows).
  // Throws InputError if the scratch files cannot be made.
  EkfHistoryFiles(const std::vector<EstimationLog>& logs,
                  const std::vector<std::string>& state_names, bool smoother,
                  const std::string& folder, const std::vector<std::vector<int>>& keep_states_at);
  ~EkfHistoryFiles() override;

  // The tables (history_csv.h), after a usable RunEkf; the parameters'
  // names and whether there was a covariance pass from its EkfResult.
  void StatesCsv(const EmitText& emit);
  void ParametersCsv(const std::vector<std::string>& free_names, bool covariance_pass,
                     const EmitText& emit);
  void InnovationsCsv(const EmitText& emit);
  // The thinned copy per log; `rows` holds the log rows kept.
  const std::vector<EkfLogHistory>& thinned() const { return thinned_; }
  const EkfStatesAtRows& states_at_rows() const { return states_at_rows_; }

  void BeginPass(const EkfPassRecord& what) override;
  void FilteredStates(int log, int row, const EkfRowValues& x, const EkfRowValues& std) override;
  void SmoothedStates(int log, int row, const EkfRowValues& x, const EkfRowValues& std) override;
  void Parameters(int log, int row, const EkfRowValues& value, const EkfRowValues& std) override;
  void ParameterStdAtEstimate(int log, int row, const EkfRowValues& std) override;
  void Innovations(int log, int row, const std::vector<int>& columns, const Eigen::VectorXd& nu,
                   const Eigen::VectorXd& std, double nis, int dof) override;
  void VisitParameters(const std::function<void(int, int, const EkfRowValues&)>& visit) override;

 private:
  // A binary scratch file of doubles, unlinked once open.
  class Scratch;

  long GlobalRow(int log, int row) const { return offsets_[log] + row; }
  // The thinned copy's index of a row (-1: not kept).
  int ThinnedIndex(int log, int row) const;
  // Innovation records (2 m + 2 doubles: nu, sqrt(S), nis, dof) of the
  // current pass's file up to (not including) global row `end`, NaN.
  void PadInnovations(long end);
  void FlushSmoothed();

  // The thinned copy's parameter matrices, once the number of parameters is known.
  void SizeThinnedParameters(int np);

  const std::vector<EstimationLog>& logs_;
  const std::vector<std::string> state_names_;
  const int nx_;               // states
  const int state_columns_;    // a row's record: x and std, 2 nx doubles
  const bool smoother_;
  const std::string folder_;
  int np_ = -1;                // from the first parameter rows
  std::vector<long> offsets_;  // global row of each log's row 0
  long rows_ = 0;
  std::unique_ptr<Scratch> filtered_, smoothed_, parameters_, std_at_estimate_;
  std::vector<std::unique_ptr<Scratch>> innovations_;  // one per recording pass
  long innovations_written_ = 0;                       // rows of the current pass's innovation file
  // Smoothed rows arriving backward: the run being collected (rows
  // smoothed_low_ .. smoothed_low_ + n - 1, stored last first).
  std::vector<double> smoothed_buffer_;
  long smoothed_low_ = -1;
  std::vector<int> stride_;
  std::vector<EkfLogHistory> thinned_;
  EkfStatesAtRows states_at_rows_;
};

}  // namespace coaxid
