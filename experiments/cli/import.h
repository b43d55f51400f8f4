// `coaxid import`: converts a test rig's own CSV files into logs of
// ../shared/spec/log-format.md.
//
//   coaxid import --format=tmotor28 --in=DIR --out=DIR2
//
// A format is a list of tables, one per source file: the file name, its field
// separator, the log it becomes, the metadata written with it, and one rule per
// log column (a sum of source columns times factors, plus a constant; the row
// index for t). Another rig is one more entry in the table of formats
// (import.cc, Formats()); the conventions of each mapping are
// documented there and in data/real/<rig>/README.md.
//
// Every source file is read and converted before anything is written; the
// logs are then written with WriteLog (atomic). Malformed input is an
// InputError naming the file, the line (1-based), the column and the problem.
#pragma once

#include <string>
#include <vector>

#include "core/log.h"

namespace coaxid {

// One term of a column rule: factor * (value of the source column). An empty
// source column name means the row index (0, 1, 2, ...).
struct ImportTerm {
  std::string column;
  double factor = 1.0;
};

// A log column = constant + sum of terms. No terms: the constant (NaN: the
// column is written empty, a missing value).
struct ImportColumnRule {
  std::string log_column;
  std::vector<ImportTerm> terms;
  double constant = 0.0;
};

struct ImportTable {
  std::string input_file;   // in --in, e.g. "coaxial.csv"
  char separator = ',';
  std::string output_file;  // in --out, e.g. "tmotor28_coaxial.csv"
  LogKind kind = LogKind::kBalance;
  std::vector<std::pair<std::string, std::string>> metadata;  // `# key: value` lines
  std::vector<ImportColumnRule> columns;                     // in output order
};

// The tables of a format; throws InputError for an unknown format.
const std::vector<ImportTable>& ImportFormat(const std::string& format);
// The known format names, comma-separated (for messages).
std::string ImportFormatNames();

// Converts one source file's text. `source` names it in messages (the path).
// Throws InputError "SOURCE:LINE: column 'NAME': problem" on malformed input:
// missing header or column, wrong number of fields, a field that is not a
// finite number, no data rows.
Log ConvertTable(const ImportTable& table, const std::string& text, const std::string& source);

// Converts every table of the format from the files in in_dir; nothing written.
// Returns (output file name, log) pairs.
std::vector<std::pair<std::string, Log>> ConvertFormat(const std::string& format,
                                                       const std::string& in_dir);

// Runs `import` from the parsed flags (--format, --in, --out). Returns the exit
// status; throws InputError on bad input.
int RunImport();

}  // namespace coaxid
