#include "experiments/cli/import.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

constexpr double kRpmToRadPerSecond = 2.0 * M_PI / 60.0;

// The T-motor 28" coaxial test stand (pyBEMT, University of Stavanger;
// data/real/tmotor28-coaxial/README.md). Rotor A is the LOWER rotor, B the
// UPPER one. Body axes z down (model.md): an upward thrust T is Z = -T. The
// source gives torque magnitudes Q; the rotors counter-rotate, so their
// reaction torques have opposite signs: the upper rotor's is positive
// (N1 = gamma1 omega1^2, gamma1 > 0), the lower rotor's negative
// (N2 = gamma2 omega2^2, gamma2 < 0): N1 = +Q_B, N2 = -Q_A.
std::vector<ImportTable> Tmotor28() {
  const std::string origin =
      "(github.com/kegiljarhus/pyBEMT, MIT licence), T-motor 28-inch two-blade propellers "
      "measured at the University of Stavanger; unchanged data converted by coaxid import "
      "--format=tmotor28";
  ImportTable coaxial;
  coaxial.input_file = "coaxial.csv";
  coaxial.separator = ',';
  coaxial.output_file = "tmotor28_coaxial.csv";
  coaxial.metadata = {
      {"layout", "steady_points"},
      {"vehicle", "tmotor28"},
      {"source", "pyBEMT examples/tmotor28_coaxial_data.csv " + origin},
      {"conventions",
       "upper rotor = B, lower rotor = A; omega1 = RPM_B 2pi/60, omega2 = RPM 2pi/60; "
       "Z1 = -T_B, Z2 = -T_A (z down); N1 = +Q_B, N2 = -Q_A (counter-rotating reaction "
       "torques); Z = Z1 + Z2, N = N1 + N2; t = row index"}};
  coaxial.columns = {
      {"t", {{"", 1.0}}},
      {"omega1", {{"RPM_B", kRpmToRadPerSecond}}},
      {"omega2", {{"RPM", kRpmToRadPerSecond}}},
      {"delta_cx", {}, 0.0},
      {"delta_cy", {}, 0.0},
      {"Z1", {{"T_B(N)", -1.0}}},
      {"Z2", {{"T_A(N)", -1.0}}},
      {"N1", {{"Q_B(Nm)", 1.0}}},
      {"N2", {{"Q_A(Nm)", -1.0}}},
      // Same terms in the same order as Z1 + Z2 and N1 + N2: exactly their sums.
      {"Z", {{"T_B(N)", -1.0}, {"T_A(N)", -1.0}}},
      {"N", {{"Q_B(Nm)", 1.0}, {"Q_A(Nm)", -1.0}}},
  };

  // The isolated rotor, logged as the upper rotor alone (omega2 = 0). The
  // lower rotor is absent, not measured: Z2 and N2 are left empty (missing
  // values, skipped by the estimators) rather than written as measured zeros.
  ImportTable isolated;
  isolated.input_file = "isolated.csv";
  isolated.separator = ';';
  isolated.output_file = "tmotor28_isolated.csv";
  isolated.metadata = {
      {"layout", "steady_points"},
      {"vehicle", "tmotor28"},
      {"source", "pyBEMT examples/tmotor28_data.csv " + origin},
      {"conventions",
       "one rotor alone, logged as the upper rotor: omega1 = omega, omega2 = 0; Z1 = Z = -T(N) "
       "(z down); N1 = N = +Q(Nm); Z2, N2 empty (no lower rotor); t = row index"}};
  isolated.columns = {
      {"t", {{"", 1.0}}},
      {"omega1", {{"omega", 1.0}}},
      {"omega2", {}, 0.0},
      {"delta_cx", {}, 0.0},
      {"delta_cy", {}, 0.0},
      {"Z1", {{"T(N)", -1.0}}},
      {"Z2", {}, NAN},
      {"N1", {{"Q(Nm)", 1.0}}},
      {"N2", {}, NAN},
      {"Z", {{"T(N)", -1.0}}},
      {"N", {{"Q(Nm)", 1.0}}},
  };
  return {coaxial, isolated};
}

const std::map<std::string, std::vector<ImportTable>>& Formats() {
  static const auto* formats =
      new std::map<std::string, std::vector<ImportTable>>{{"tmotor28", Tmotor28()}};
  return *formats;
}

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> SplitFields(const std::string& line, char separator) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t at = line.find(separator, start);
    fields.push_back(Trim(line.substr(start, at == std::string::npos ? std::string::npos
                                                                     : at - start)));
    if (at == std::string::npos) break;
    start = at + 1;
  }
  return fields;
}

[[noreturn]] void Fail(const std::string& source, int line, const std::string& column,
                       const std::string& problem) {
  std::string message = source + ":" + std::to_string(line) + ": ";
  if (!column.empty()) message += "column '" + column + "': ";
  throw InputError(message + problem);
}

std::string SeparatorName(char separator) {
  return separator == ',' ? "','" : separator == ';' ? "';'" : std::string("'") + separator + "'";
}

}  // namespace

const std::vector<ImportTable>& ImportFormat(const std::string& format) {
  const auto it = Formats().find(format);
  if (it == Formats().end()) {
    throw InputError("unknown import format '" + format + "' (known: " + ImportFormatNames() +
                     ")");
  }
  return it->second;
}

std::string ImportFormatNames() {
  std::string names;
  for (const auto& kv : Formats()) names += (names.empty() ? "" : ", ") + kv.first;
  return names;
}

Log ConvertTable(const ImportTable& table, const std::string& text, const std::string& source) {
  // Lines, 1-based numbers kept for messages; blank lines are skipped.
  std::vector<std::pair<int, std::string>> lines;
  {
    size_t start = 0;
    int number = 0;
    while (start < text.size()) {
      size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      ++number;
      std::string line = text.substr(start, end - start);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (!Trim(line).empty()) lines.emplace_back(number, line);
      start = end + 1;
    }
  }
  if (lines.empty()) Fail(source, 1, "", "empty file: expected a header line");

  // Header. A trailing separator (an empty last name) is allowed, and then an
  // empty trailing field on every row.
  const int header_line = lines[0].first;
  std::vector<std::string> header = SplitFields(lines[0].second, table.separator);
  const bool trailing_separator = header.size() > 1 && header.back().empty();
  if (trailing_separator) header.pop_back();
  std::map<std::string, int> index;
  for (size_t j = 0; j < header.size(); ++j) {
    if (header[j].empty()) {
      Fail(source, header_line, "", "header field " + std::to_string(j + 1) +
                                         " is empty (separator " +
                                         SeparatorName(table.separator) + ")");
    }
    if (!index.emplace(header[j], static_cast<int>(j)).second) {
      Fail(source, header_line, header[j], "appears twice in the header");
    }
  }
  // Every source column the rules use must be in the header.
  std::set<std::string> used;
  for (const ImportColumnRule& rule : table.columns) {
    for (const ImportTerm& term : rule.terms) {
      if (!term.column.empty()) used.insert(term.column);
    }
  }
  for (const std::string& name : used) {
    if (index.count(name) == 0) {
      std::string got;
      for (const std::string& h : header) got += (got.empty() ? "" : ", ") + h;
      Fail(source, header_line, name,
           "missing from the header (separator " + SeparatorName(table.separator) +
               "; header has: " + got + ")");
    }
  }
  if (lines.size() < 2) Fail(source, header_line, "", "no data rows after the header");

  // Rows: parse the used columns only (others, such as power, are not logged).
  const size_t n_rows = lines.size() - 1;
  std::map<std::string, std::vector<double>> values;
  for (const std::string& name : used) values[name].resize(n_rows);
  for (size_t k = 0; k < n_rows; ++k) {
    const int line = lines[k + 1].first;
    std::vector<std::string> fields = SplitFields(lines[k + 1].second, table.separator);
    if (trailing_separator && fields.size() == header.size() + 1 && fields.back().empty()) {
      fields.pop_back();
    }
    if (fields.size() != header.size()) {
      Fail(source, line, "",
           std::to_string(fields.size()) + " fields, the header has " +
               std::to_string(header.size()) + " (separator " + SeparatorName(table.separator) +
               ")");
    }
    for (const std::string& name : used) {
      const std::string& field = fields[index.at(name)];
      if (field.empty()) Fail(source, line, name, "empty field (a value is required)");
      errno = 0;
      char* end = nullptr;
      const double v = std::strtod(field.c_str(), &end);
      if (end != field.c_str() + field.size() || errno == ERANGE) {
        Fail(source, line, name, "'" + field + "' is not a number");
      }
      if (!std::isfinite(v)) Fail(source, line, name, "'" + field + "' is not finite");
      values[name][k] = v;
    }
  }

  Log log;
  log.kind = table.kind;
  for (const auto& [key, value] : table.metadata) log.metadata[key] = value;
  log.source = source;
  for (const ImportColumnRule& rule : table.columns) {
    std::vector<double> column(n_rows);
    for (size_t k = 0; k < n_rows; ++k) {
      if (rule.terms.empty()) {
        column[k] = rule.constant;
        continue;
      }
      double v = 0.0;
      bool first = true;
      for (const ImportTerm& term : rule.terms) {
        const double x = term.column.empty() ? static_cast<double>(k) : values[term.column][k];
        v = first ? term.factor * x : v + term.factor * x;
        first = false;
      }
      column[k] = rule.constant == 0.0 ? v : v + rule.constant;
    }
    log.columns.push_back(rule.log_column);
    log.values.push_back(std::move(column));
  }
  return log;
}

std::vector<std::pair<std::string, Log>> ConvertFormat(const std::string& format,
                                                       const std::string& in_dir) {
  std::vector<std::pair<std::string, Log>> out;
  for (const ImportTable& table : ImportFormat(format)) {
    const std::string path = (fs::path(in_dir) / table.input_file).string();
    out.emplace_back(table.output_file, ConvertTable(table, ReadFile(path), path));
  }
  return out;
}

int RunImport() {
  const char* usage = "\nusage: coaxid import --format=NAME --in=DIR --out=DIR2";
  if (FLAGS_format.empty()) {
    throw InputError("missing --format (known: " + ImportFormatNames() + ")" + usage);
  }
  if (FLAGS_in.empty()) throw InputError(std::string("missing --in") + usage);
  if (FLAGS_out.empty()) throw InputError(std::string("missing --out") + usage);
  if (!fs::is_directory(FLAGS_in)) {
    throw InputError("--in: '" + FLAGS_in + "' is not a folder" + usage);
  }
  // Everything read and converted before anything is written.
  const auto logs = ConvertFormat(FLAGS_format, FLAGS_in);
  MakeOutputFolder(FLAGS_out);
  for (const auto& [name, log] : logs) {
    const std::string path = (fs::path(FLAGS_out) / name).string();
    WriteLog(path, log);
    std::fprintf(stderr, "import: %s (%d rows) -> %s\n", log.source.c_str(), log.NumRows(),
                 path.c_str());
  }
  return 0;
}

}  // namespace coaxid
