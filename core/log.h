// Experiment logs in the CSV format of ../shared/spec/log-format.md: one
// experiment (balance or flight) per file, metadata lines `# key: value`, one
// header line, one row per sample. Missing values (empty field or `nan`) are
// stored as NaN. Columns are stored column-major (one std::vector per column)
// so estimators can take a whole channel at once.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace coaxid {

enum class LogKind { kBalance, kFlight };

// "balance" / "flight".
const char* LogKindName(LogKind kind);

struct Log {
  LogKind kind = LogKind::kFlight;
  // Every metadata line except `kind`, in file order of keys (std::map sorts;
  // order is not significant in the format).
  std::map<std::string, std::string> metadata;
  // Column names as in the header, and the values, one vector per column, all
  // of the same length. NaN is a missing value.
  std::vector<std::string> columns;
  std::vector<std::vector<double>> values;
  // Where the log came from (file path), for messages. Empty if built in memory.
  std::string source;

  int NumRows() const { return values.empty() ? 0 : static_cast<int>(values[0].size()); }
  bool Has(const std::string& column) const { return ColumnIndex(column) >= 0; }
  // -1 if absent.
  int ColumnIndex(const std::string& column) const;
  // The column's values; CHECK-fails if absent (call Has() first).
  const std::vector<double>& Column(const std::string& column) const;
  // Adds a column (or replaces an existing one of the same name). CHECKs the length.
  void SetColumn(const std::string& column, std::vector<double> data);
};

// The columns every log must have (log-format.md, Columns table).
const std::vector<std::string>& RequiredColumns(LogKind kind);
// Load columns of a balance log: X, Y, Z, L, M, N, Z1, Z2, N1, N2.
const std::vector<std::string>& BalanceLoadColumns();
// Output columns of a flight log: x..z, u..w, phi..psi, p..r, ax..az.
const std::vector<std::string>& FlightOutputColumns();
// Input columns: omega1, omega2, delta_cx, delta_cy (in this order everywhere).
const std::vector<std::string>& InputColumns();

// Reads and validates a log. Throws InputError with one message naming the
// file, the line (1-based), the column and what is wrong:
//   missing `# kind:` line or unknown kind, missing required column, a field
//   that is not a number, a non-finite value in a required column (inputs, t,
//   and for flight the attitude and rates), time not strictly increasing, a
//   row with the wrong number of fields, a balance log without any load column.
// Unknown columns are kept; unknown metadata keys are kept.
Log ReadLog(const std::string& path);
// Same, from text already in memory (`source` names it in messages).
Log ParseLog(const std::string& text, const std::string& source);

// Writes the log atomically (temporary file in the same folder, then rename):
// a reader never sees a half-written file. Numbers are written with enough
// digits (%.17g or shortest round-trip) that ReadLog(WriteLog(log)) == log
// exactly; NaN is written as an empty field. Throws InputError if the folder
// cannot be written.
void WriteLog(const std::string& path, const Log& log);

}  // namespace coaxid
