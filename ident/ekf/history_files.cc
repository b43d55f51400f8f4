#include "ident/ekf/history_files.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "core/errors.h"
#include "dynamics/effects/effect_library.h"
#include "ident/ekf/history_csv.h"
#include "ident/ekf/report.h"

namespace coaxid {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

class EkfHistoryFiles::Scratch {
 public:
  Scratch(const std::string& folder, const std::string& what) : what_(what) {
    std::string pattern = folder + "/.ekf_" + what + "_XXXXXX";
    std::vector<char> path(pattern.begin(), pattern.end());
    path.push_back('\0');
    const int fd = mkstemp(path.data());
    if (fd < 0) {
      throw InputError("cannot make a scratch file in " + folder + " for the EKF's " + what + ": " +
                       std::strerror(errno));
    }
    unlink(path.data());  // gone with the process, whatever happens
    file_ = fdopen(fd, "w+b");
    if (file_ == nullptr) {
      close(fd);
      throw InputError("cannot open the scratch file for the EKF's " + what);
    }
  }
  ~Scratch() { std::fclose(file_); }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;

  void Append(const double* v, size_t n) {
    if (std::fwrite(v, sizeof(double), n, file_) != n) Fail("writing");
  }
  // At index (in doubles) from the start.
  void WriteAt(long index, const double* v, size_t n) {
    if (fseeko(file_, static_cast<off_t>(index) * sizeof(double), SEEK_SET) != 0) Fail("seeking");
    Append(v, n);
  }
  // Empty again, for a later pass's rows.
  void Truncate() {
    if (std::fflush(file_) != 0 || ftruncate(fileno(file_), 0) != 0) Fail("truncating");
    std::rewind(file_);
  }
  // Reading from the start.
  void Rewind() {
    if (std::fflush(file_) != 0) Fail("writing");
    std::rewind(file_);
  }
  void Read(double* v, size_t n) {
    if (std::fread(v, sizeof(double), n, file_) != n) Fail("reading");
  }
  // Back to the end, for appending after a Rewind() and reads.
  void SeekEnd() {
    if (fseeko(file_, 0, SEEK_END) != 0) Fail("seeking");
  }

 private:
  [[noreturn]] void Fail(const char* doing) {
    throw ComputationError(std::string(doing) + " the scratch file of the EKF's " + what_ +
                           " failed: " + std::strerror(errno) + " (disk full?)");
  }
  std::string what_;
  std::FILE* file_ = nullptr;
};

EkfHistoryFiles::EkfHistoryFiles(const std::vector<EstimationLog>& logs,
                                 const std::vector<std::string>& state_names, bool smoother,
                                 const std::string& folder,
                                 const std::vector<std::vector<int>>& keep_states_at)
    : logs_(logs),
      state_names_(state_names),
      nx_(static_cast<int>(state_names.size())),
      state_columns_(2 * nx_),
      smoother_(smoother),
      folder_(folder),
      states_at_rows_(keep_states_at) {
  for (const EstimationLog& log : logs_) {
    offsets_.push_back(rows_);
    rows_ += log.NumRows();
  }
  filtered_ = std::make_unique<Scratch>(folder_, "states");
  if (smoother_) smoothed_ = std::make_unique<Scratch>(folder_, "smoothed_states");
  parameters_ = std::make_unique<Scratch>(folder_, "parameters");
  std_at_estimate_ = std::make_unique<Scratch>(folder_, "std_at_estimate");

  for (const EstimationLog& log : logs_) {
    const int N = log.NumRows(), m = log.NumChannels();
    const int stride = EkfPlotStride(N);
    stride_.push_back(stride);
    EkfLogHistory h;
    h.source = log.source;
    h.name = log.name;
    h.channels = log.channels;
    h.channel_names = log.channel_names;
    h.state_names = state_names_;
    for (int row = 0; row < N; row += stride) h.rows.push_back(row);
    if (h.rows.back() != N - 1) h.rows.push_back(N - 1);  // the log's end, for the time axis
    const int n = static_cast<int>(h.rows.size());
    h.measured.resize(n, m);
    for (int i = 0; i < n; ++i) {
      h.times.push_back(log.inputs.time(h.rows[i]));
      h.measured.row(i) = log.values.row(h.rows[i]);
    }
    SizeStateAndInnovationRecords(n, m, smoother_, &h);
    thinned_.push_back(std::move(h));
  }
}

EkfHistoryFiles::~EkfHistoryFiles() = default;

void EkfHistoryFiles::SizeThinnedParameters(int np) {
  if (np_ == np) return;
  np_ = np;
  for (EkfLogHistory& h : thinned_) {
    const int n = static_cast<int>(h.rows.size());
    h.parameters.setConstant(n, np, kNaN);
    h.parameter_std.setConstant(n, np, kNaN);
    h.parameter_std_at_estimate.setConstant(n, np, kNaN);
  }
}

int EkfHistoryFiles::ThinnedIndex(int log, int row) const {
  if (row % stride_[log] == 0) return row / stride_[log];
  if (row == logs_[log].NumRows() - 1) return static_cast<int>(thinned_[log].rows.size()) - 1;
  return -1;
}

void EkfHistoryFiles::BeginPass(const EkfPassRecord& what) {
  if (what.states) {
    filtered_->Truncate();
    if (smoothed_) {
      FlushSmoothed();
      smoothed_->Truncate();
    }
  }
  if (what.parameters) parameters_->Truncate();
  if (what.std_at_estimate) std_at_estimate_->Truncate();
  if (what.innovations) {
    if (!innovations_.empty()) PadInnovations(rows_);
    innovations_.push_back(
        std::make_unique<Scratch>(folder_, "innovations_" + std::to_string(innovations_.size())));
    innovations_written_ = 0;
  }
}

void EkfHistoryFiles::FilteredStates(int log, int row, const EkfRowValues& x,
                                     const EkfRowValues& std) {
  double record[2 * kMaxModelStates];
  Eigen::Map<Eigen::VectorXd>(record, nx_) = x;
  Eigen::Map<Eigen::VectorXd>(record + nx_, nx_) = std;
  filtered_->Append(record, state_columns_);
  states_at_rows_.FilteredStates(log, row, x, std);
  const int i = ThinnedIndex(log, row);
  if (i >= 0) {
    thinned_[log].states.row(i) = x.transpose();
    thinned_[log].state_std.row(i) = std.transpose();
  }
}

void EkfHistoryFiles::SmoothedStates(int log, int row, const EkfRowValues& x,
                                     const EkfRowValues& std) {
  const long global = GlobalRow(log, row);
  // Rows come backward within a block: collect a run of consecutive rows and
  // write it at its place in one piece.
  if (smoothed_low_ >= 0 && global != smoothed_low_ - 1) FlushSmoothed();
  smoothed_low_ = global;
  const size_t at = smoothed_buffer_.size();
  smoothed_buffer_.resize(at + state_columns_);
  Eigen::Map<Eigen::VectorXd>(smoothed_buffer_.data() + at, nx_) = x;
  Eigen::Map<Eigen::VectorXd>(smoothed_buffer_.data() + at + nx_, nx_) = std;
  states_at_rows_.SmoothedStates(log, row, x, std);
  const int i = ThinnedIndex(log, row);
  if (i >= 0) {
    thinned_[log].smoothed_states.row(i) = x.transpose();
    thinned_[log].smoothed_state_std.row(i) = std.transpose();
  }
}

void EkfHistoryFiles::FlushSmoothed() {
  if (smoothed_low_ < 0) return;
  // The buffer holds rows high .. low (last first): reverse the records.
  const size_t n = smoothed_buffer_.size() / state_columns_;
  std::vector<double> forward(smoothed_buffer_.size());
  for (size_t j = 0; j < n; ++j) {
    std::copy_n(smoothed_buffer_.data() + (n - 1 - j) * state_columns_, state_columns_,
                forward.data() + j * state_columns_);
  }
  smoothed_->WriteAt(smoothed_low_ * state_columns_, forward.data(), forward.size());
  smoothed_buffer_.clear();
  smoothed_low_ = -1;
}

void EkfHistoryFiles::Parameters(int log, int row, const EkfRowValues& value,
                                 const EkfRowValues& std) {
  SizeThinnedParameters(static_cast<int>(value.size()));
  std::vector<double> record(2 * np_);
  Eigen::Map<Eigen::VectorXd>(record.data(), np_) = value;
  Eigen::Map<Eigen::VectorXd>(record.data() + np_, np_) = std;
  parameters_->Append(record.data(), record.size());
  const int i = ThinnedIndex(log, row);
  if (i >= 0) {
    thinned_[log].parameters.row(i) = value.transpose();
    thinned_[log].parameter_std.row(i) = std.transpose();
  }
}

void EkfHistoryFiles::ParameterStdAtEstimate(int log, int row, const EkfRowValues& std) {
  SizeThinnedParameters(static_cast<int>(std.size()));
  std::vector<double> record(np_);
  Eigen::Map<Eigen::VectorXd>(record.data(), np_) = std;
  std_at_estimate_->Append(record.data(), record.size());
  const int i = ThinnedIndex(log, row);
  if (i >= 0) thinned_[log].parameter_std_at_estimate.row(i) = std.transpose();
}

void EkfHistoryFiles::PadInnovations(long end) {
  std::vector<double> nan;
  for (; innovations_written_ < end; ++innovations_written_) {
    int L = static_cast<int>(logs_.size()) - 1;
    while (offsets_[L] > innovations_written_) --L;
    nan.assign(2 * logs_[L].NumChannels() + 2, kNaN);
    innovations_.back()->Append(nan.data(), nan.size());
  }
}

void EkfHistoryFiles::Innovations(int log, int row, const std::vector<int>& columns,
                                  const Eigen::VectorXd& nu, const Eigen::VectorXd& std, double nis,
                                  int dof) {
  PadInnovations(GlobalRow(log, row));
  const int m = logs_[log].NumChannels();
  std::vector<double> record(2 * m + 2, kNaN);
  for (size_t j = 0; j < columns.size(); ++j) {
    record[columns[j]] = nu[j];
    record[m + columns[j]] = std[j];
  }
  record[2 * m] = nis;
  record[2 * m + 1] = dof;
  innovations_.back()->Append(record.data(), record.size());
  ++innovations_written_;
  const int i = ThinnedIndex(log, row);
  if (i >= 0) StoreInnovations(i, columns, nu, std, nis, dof, &thinned_[log]);
}

void EkfHistoryFiles::VisitParameters(
    const std::function<void(int, int, const EkfRowValues&)>& visit) {
  parameters_->Rewind();
  std::vector<double> record(2 * np_);
  for (size_t L = 0; L < logs_.size(); ++L) {
    for (int row = 0; row < logs_[L].NumRows(); ++row) {
      parameters_->Read(record.data(), record.size());
      visit(static_cast<int>(L), row, Eigen::Map<const Eigen::VectorXd>(record.data(), np_));
    }
  }
  parameters_->SeekEnd();
}

void EkfHistoryFiles::StatesCsv(const EmitText& emit) {
  FlushSmoothed();
  filtered_->Rewind();
  if (smoother_) smoothed_->Rewind();
  TextPieces pieces(emit);
  pieces.text = EkfStatesCsvHeader(state_names_, smoother_);
  double filtered[2 * kMaxModelStates], smoothed[2 * kMaxModelStates];
  for (const EstimationLog& log : logs_) {
    const std::string name = EkfCsvLogName(log.name);
    for (int row = 0; row < log.NumRows(); ++row) {
      filtered_->Read(filtered, state_columns_);
      if (smoother_) smoothed_->Read(smoothed, state_columns_);
      AppendEkfStatesCsvRow(name, log.inputs.time(row), nx_, filtered, filtered + nx_,
                            smoother_ ? smoothed : nullptr,
                            smoother_ ? smoothed + nx_ : nullptr, &pieces.text);
      pieces.EndOfRow();
    }
  }
}

void EkfHistoryFiles::ParametersCsv(const std::vector<std::string>& free_names,
                                    bool covariance_pass, const EmitText& emit) {
  SizeThinnedParameters(static_cast<int>(free_names.size()));
  parameters_->Rewind();
  std_at_estimate_->Rewind();
  TextPieces pieces(emit);
  pieces.text = EkfParametersCsvHeader(free_names, covariance_pass);
  std::vector<double> record(2 * np_), at_estimate(np_);
  for (const EstimationLog& log : logs_) {
    const std::string name = EkfCsvLogName(log.name);
    for (int row = 0; row < log.NumRows(); ++row) {
      parameters_->Read(record.data(), record.size());
      if (covariance_pass) std_at_estimate_->Read(at_estimate.data(), at_estimate.size());
      AppendEkfParametersCsvRow(name, log.inputs.time(row), np_, record.data(), record.data() + np_,
                                covariance_pass ? at_estimate.data() : nullptr, &pieces.text);
      pieces.EndOfRow();
    }
  }
}

void EkfHistoryFiles::InnovationsCsv(const EmitText& emit) {
  PadInnovations(rows_);
  for (auto& file : innovations_) file->Rewind();
  std::vector<std::vector<std::string>> names;
  for (const EstimationLog& log : logs_) names.push_back(log.channel_names);
  const std::vector<std::string> channels = EkfInnovationChannels(names);
  TextPieces pieces(emit);
  pieces.text = EkfInnovationsCsvHeader(channels);
  std::vector<double> merged, record;
  for (const EstimationLog& log : logs_) {
    const std::vector<int> column = EkfInnovationColumns(channels, log.channel_names);
    const std::string name = EkfCsvLogName(log.name);
    const int m = log.NumChannels();
    for (int row = 0; row < log.NumRows(); ++row) {
      // A later pass's values where it wrote (EkfMemoryHistory writes over the earlier's).
      merged.assign(2 * m + 2, kNaN);
      record.resize(2 * m + 2);
      for (auto& file : innovations_) {
        file->Read(record.data(), record.size());
        for (int c = 0; c < m; ++c) {
          if (std::isfinite(record[c])) {
            merged[c] = record[c];
            merged[m + c] = record[m + c];
          }
        }
        if (std::isfinite(record[2 * m])) {
          merged[2 * m] = record[2 * m];
          merged[2 * m + 1] = record[2 * m + 1];
        }
      }
      const int dof = std::isfinite(merged[2 * m + 1]) ? static_cast<int>(merged[2 * m + 1]) : 0;
      AppendEkfInnovationsCsvRow(name, log.inputs.time(row), column, merged.data(),
                                 merged.data() + m, merged[2 * m], dof, &pieces.text);
      pieces.EndOfRow();
    }
  }
}

}  // namespace coaxid
