#include "core/log.h"

#include <glog/logging.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/report_values.h"

namespace coaxid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr char kKindHelp[] = "no '# kind: balance|flight' line";

bool IsSpace(char c) { return c == ' ' || c == '\t'; }

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsSpace(s.back())) s.remove_suffix(1);
  return s;
}

bool IsBlank(std::string_view line) { return Trim(line).empty(); }

// Shortest text that reads back to the same double (C++17 to_chars without a
// precision); used both for writing logs and for numbers quoted in messages.
std::string FormatDouble(double v) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), v);
  return std::string(buffer, result.ptr);
}

// Clinger's fast path for the numbers loggers write ("150.2345", "-0.0031",
// "1e-05"): at most 19 digits whose integer value w <= 2^53 and a decimal
// exponent |e| <= 22. Then w and 10^|e| are exact doubles and one IEEE multiply
// or divide gives the correctly rounded result, the same double from_chars
// gives, at a few times its speed. Returns the end of the number, or nullptr
// for anything else (empty, '+', more digits, nan, inf, malformed): the caller
// then uses from_chars, which also decides what is an error.
//
// No end pointer: the text must be followed by a character that is none of
// digit, '.', 'e', 'E', '+', '-' (the line reader guarantees '\r', '\n' or the
// string's terminating '\0'), which saves a bounds check per character.
const char* ParseSimpleDecimal(const char* p, double* value) {
  static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                      1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                      1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  auto digit = [](char c) { return static_cast<unsigned>(c - '0'); };
  const bool negative = *p == '-';
  if (negative) ++p;
  const char* const start = p;
  uint64_t w = 0;  // Wraps silently past 19 digits; the digit count then rejects it.
  for (; digit(*p) < 10; ++p) w = 10 * w + digit(*p);
  int digits = static_cast<int>(p - start);
  int exponent = 0;
  if (*p == '.') {
    const char* const fraction = ++p;
    for (; digit(*p) < 10; ++p) w = 10 * w + digit(*p);
    exponent = -static_cast<int>(p - fraction);
    digits -= exponent;
  }
  if (digits == 0 || digits > 19) return nullptr;
  if (*p == 'e' || *p == 'E') {
    ++p;
    const bool exponent_negative = *p == '-';
    if (*p == '-' || *p == '+') ++p;
    if (digit(*p) >= 10) return nullptr;
    int e = 0;
    for (; digit(*p) < 10; ++p) e = std::min(10 * e + static_cast<int>(digit(*p)), 100000);
    exponent += exponent_negative ? -e : e;
  }
  if (w > (uint64_t{1} << 53) || exponent < -22 || exponent > 22) return nullptr;
  double v = static_cast<double>(w);
  v = exponent < 0 ? v / kPow10[-exponent] : v * kPow10[exponent];
  *value = negative ? -v : v;
  return p;
}

// Quotes a field for a message, cut short so a runaway line does not flood the terminal.
std::string Quote(std::string_view field) {
  constexpr size_t kMax = 40;
  std::string out = "'";
  out += field.substr(0, kMax);
  if (field.size() > kMax) out += "...";
  out += "'";
  return out;
}

// The one error format of the log reader: FILE:LINE: column 'NAME': PROBLEM.
[[noreturn]] void Fail(const std::string& source, int line, std::string_view column,
                       const std::string& problem) {
  std::string message = source.empty() ? "<log>" : source;
  message += ':';
  message += std::to_string(line);
  message += ": ";
  if (!column.empty()) {
    message += "column '";
    message += column;
    message += "': ";
  }
  message += problem;
  throw InputError(message);
}

// Splits text into lines, 1-based numbering, accepting \n and \r\n endings:
// from text in memory, or from a file read in pieces (a line's view holds
// until the next call). Every line returned is followed in memory by '\r',
// '\n' or '\0' (ParseRow's fast path stops there).
class LineReader {
 public:
  explicit LineReader(std::string_view text) : p_(text.data()), end_(text.data() + text.size()) {
    SkipByteOrderMark();
  }
  explicit LineReader(FileReader* file) : file_(file) {
    Refill();
    SkipByteOrderMark();
  }

  bool Next(std::string_view* line) {
    const char* newline = FindNewline();
    while (newline == nullptr && Refill()) newline = FindNewline();
    if (p_ == end_) return false;
    const char* stop = newline != nullptr ? newline : end_;
    const char* line_end = (stop > p_ && stop[-1] == '\r') ? stop - 1 : stop;
    *line = std::string_view(p_, line_end - p_);
    p_ = newline != nullptr ? newline + 1 : end_;
    ++number_;
    return true;
  }

  int number() const { return number_; }
  // About how many lines are left, to reserve the column vectors once: the
  // lines in memory, or the bytes left over the mean line length so far.
  size_t LinesLeft() const {
    size_t count = 0;
    for (const char* p = p_; p < end_; ++count) {
      const char* newline = static_cast<const char*>(std::memchr(p, '\n', end_ - p));
      if (newline == nullptr) {
        ++count;
        break;
      }
      p = newline + 1;
    }
    if (file_ == nullptr || count == 0) return count;
    const size_t in_memory = static_cast<size_t>(end_ - p_);
    const size_t unread = file_->size_hint() > read_ ? file_->size_hint() - read_ : 0;
    return count + unread * count / std::max<size_t>(in_memory, 1) + 1;
  }

 private:
  static constexpr size_t kPiece = 1 << 20;

  // The next '\n' from p_, nullptr if none (or nothing read yet).
  const char* FindNewline() const {
    return p_ < end_ ? static_cast<const char*>(std::memchr(p_, '\n', end_ - p_)) : nullptr;
  }

  void SkipByteOrderMark() {
    // A UTF-8 byte order mark, as some spreadsheets write, is not part of the first line.
    if (end_ - p_ >= 3 && std::memcmp(p_, "\xEF\xBB\xBF", 3) == 0) p_ += 3;
  }

  // Keeps the unread part and appends the next piece of the file; false at
  // its end (or for text in memory).
  bool Refill() {
    if (file_ == nullptr || at_end_) return false;
    const size_t kept = static_cast<size_t>(end_ - p_);
    if (kept > 0) std::memmove(buffer_.data(), p_, kept);
    buffer_.resize(kept + kPiece);
    const size_t n = file_->Read(buffer_.data() + kept, kPiece);
    read_ += n;
    at_end_ = n == 0;
    buffer_.resize(kept + n);  // std::string: buffer_[size()] is '\0'
    p_ = buffer_.data();
    end_ = p_ + buffer_.size();
    return n > 0;
  }

  const char* p_ = nullptr;
  const char* end_ = nullptr;
  int number_ = 0;
  FileReader* file_ = nullptr;
  std::string buffer_;
  size_t read_ = 0;
  bool at_end_ = false;
};

// Parses the text of one log; `source` names it in messages.
class Parser {
 public:
  // A std::string, not a view: its terminating '\0' ends the last line for ParseRow.
  Parser(const std::string& text, const std::string& source) : reader_(text), source_(source) {}
  Parser(FileReader* file, const std::string& source) : reader_(file), source_(source) {}

  Log Parse() {
    log_.source = source_;
    std::string_view header;
    int header_line = 0;
    bool any_line = false;
    std::string_view line;
    while (reader_.Next(&line)) {
      if (IsBlank(line)) continue;
      any_line = true;
      if (Trim(line).front() == '#') {
        ParseMetadata(Trim(line));
        continue;
      }
      header = line;
      header_line = reader_.number();
      break;
    }
    if (!any_line) Fail(source_, 1, "", "empty file");
    if (header_line == 0) Fail(source_, reader_.number(), "", "no header line after the metadata");
    if (kind_line_ == 0) Fail(source_, header_line, "", kKindHelp);
    ParseHeader(header, header_line);
    ParseRows();
    return std::move(log_);
  }

 private:
  // `# key: value`; a `#` line without a key and colon is a free comment.
  void ParseMetadata(std::string_view line) {
    line.remove_prefix(1);
    const size_t colon = line.find(':');
    if (colon == std::string_view::npos) return;
    const std::string key(Trim(line.substr(0, colon)));
    const std::string value(Trim(line.substr(colon + 1)));
    if (key.empty()) return;
    const int number = reader_.number();
    if (key == "kind") {
      if (kind_line_ != 0) {
        Fail(source_, number, "",
             "second '# kind:' line (first on line " + std::to_string(kind_line_) + ")");
      }
      if (value == "balance") {
        log_.kind = LogKind::kBalance;
      } else if (value == "flight") {
        log_.kind = LogKind::kFlight;
      } else {
        Fail(source_, number, "", "kind " + Quote(value) + " is unknown (" + kKindHelp + ")");
      }
      kind_line_ = number;
      return;
    }
    // A repeated key would silently lose one value; the reader never picks one.
    for (const auto& [seen_key, seen_line] : metadata_lines_) {
      if (seen_key == key) {
        Fail(source_, number, "",
             "metadata key " + Quote(key) + " repeated (first on line " +
                 std::to_string(seen_line) + ")");
      }
    }
    metadata_lines_.emplace_back(key, number);
    log_.metadata[key] = value;
  }

  void ParseHeader(std::string_view header, int line) {
    header_line_ = line;
    size_t start = 0;
    while (true) {
      const size_t comma = header.find(',', start);
      const std::string_view name =
          Trim(header.substr(start, comma == std::string_view::npos ? comma : comma - start));
      if (name.empty()) {
        Fail(source_, line, "",
             "empty column name in the header (column " + std::to_string(log_.columns.size() + 1) +
                 ")");
      }
      const int previous = log_.ColumnIndex(std::string(name));
      if (previous >= 0) {
        Fail(source_, line, name,
             "duplicated column name (columns " + std::to_string(previous + 1) + " and " +
                 std::to_string(log_.columns.size() + 1) + ")");
      }
      log_.columns.emplace_back(name);
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    for (const std::string& name : RequiredColumns(log_.kind)) {
      if (!log_.Has(name)) Fail(source_, line, name, "missing required column");
    }
    if (log_.kind == LogKind::kBalance) {
      const auto& loads = BalanceLoadColumns();
      if (std::none_of(loads.begin(), loads.end(),
                       [&](const std::string& name) { return log_.Has(name); })) {
        Fail(source_, line, "", "balance log has no load column (needs one of " + Joined(loads) + ")");
      }
    }
    required_.assign(log_.columns.size(), false);
    for (const std::string& name : RequiredColumns(log_.kind)) {
      required_[log_.ColumnIndex(name)] = true;
    }
    time_column_ = log_.ColumnIndex("t");
    log_.values.resize(log_.columns.size());
  }

  void ParseRows() {
    const size_t capacity = reader_.LinesLeft();
    for (auto& column : log_.values) column.reserve(capacity);
    int first_blank_line = 0;
    int previous_line = 0;
    std::string_view line;
    while (reader_.Next(&line)) {
      // Only the first character is tested on the fast path; whole-line checks
      // run when it is a space, a tab or '#'.
      const char first = line.empty() ? ' ' : line.front();
      if (IsSpace(first) || first == '#') {
        const std::string_view trimmed = Trim(line);
        if (trimmed.empty()) {
          if (first_blank_line == 0) first_blank_line = reader_.number();
          continue;
        }
        if (trimmed.front() == '#') {
          Fail(source_, reader_.number(), "", "metadata line after the header");
        }
      }
      if (first_blank_line != 0) {
        Fail(source_, reader_.number(), "",
             "data after the blank line " + std::to_string(first_blank_line) +
                 " (blank lines are only allowed at the end)");
      }
      ParseRow(line);
      const std::vector<double>& t = log_.values[time_column_];
      const size_t n = t.size();
      if (n >= 2 && !(t[n - 1] > t[n - 2])) {
        Fail(source_, reader_.number(), "t",
             "time " + FormatDouble(t[n - 1]) + " is not after the previous time " +
                 FormatDouble(t[n - 2]) + " (line " + std::to_string(previous_line) +
                 "); time must be strictly increasing");
      }
      previous_line = reader_.number();
    }
    if (log_.NumRows() == 0) Fail(source_, header_line_, "", "no data rows after the header");
  }

  // One data line; `line` is followed by '\r', '\n' or '\0' (see ParseSimpleDecimal).
  void ParseRow(std::string_view line) {
    const char* p = line.data();
    const char* const end = p + line.size();
    const size_t num_columns = log_.columns.size();
    for (size_t j = 0; j < num_columns; ++j) {
      const char* const field = p;
      while (IsSpace(*p)) ++p;
      double value;
      const char* const number_end = ParseSimpleDecimal(p, &value);
      // The fast path gives finite numbers only; everything else is checked in ParseField.
      p = number_end != nullptr ? number_end : ParseField(field, p, end, j, &value);
      while (IsSpace(*p)) ++p;
      log_.values[j].push_back(value);
      if (*p == ',') {
        if (j + 1 == num_columns) FailFieldCount(line);
        ++p;
      } else if (p == end) {
        if (j + 1 < num_columns) FailFieldCount(line);
      } else {
        FailNotNumber(field, end, j);
      }
    }
  }

  // The slow path of a field starting at `p` (spaces skipped): empty, '+',
  // nan, inf, long mantissas, or not a number. Returns the end of what was read.
  const char* ParseField(const char* field, const char* p, const char* end, size_t column,
                         double* value) {
    if (p == end || *p == ',') {
      *value = kNaN;  // An empty field is a missing value.
    } else {
      // from_chars refuses a leading '+', which other tools may write.
      if (*p == '+' && ((p[1] >= '0' && p[1] <= '9') || p[1] == '.')) ++p;
      const auto result = std::from_chars(p, end, *value);
      if (result.ec == std::errc::result_out_of_range) {
        *value = ParseOutOfRange(field, end, column);
      } else if (result.ec != std::errc()) {
        FailNotNumber(field, end, column);
      }
      p = result.ptr;
    }
    // from_chars also reads "nan" and "inf"; NaN is a missing value, infinity never valid.
    if (!std::isfinite(*value)) CheckNotFinite(*value, field, end, column);
    return p;
  }

  // from_chars reports both overflow and underflow as out of range; underflow
  // is an ordinary rounding to a tiny number (strtod gives it), overflow is infinity.
  double ParseOutOfRange(const char* field, const char* end, size_t column) {
    const std::string text(Trim(FieldText(field, end)));
    const double value = std::strtod(text.c_str(), nullptr);
    if (std::isinf(value)) {
      Fail(source_, reader_.number(), log_.columns[column],
           "value " + Quote(text) + " is out of range (not finite)");
    }
    return value;
  }

  void CheckNotFinite(double value, const char* field, const char* end, size_t column) {
    const std::string_view text = Trim(FieldText(field, end));
    if (std::isinf(value)) {
      Fail(source_, reader_.number(), log_.columns[column],
           "value " + Quote(text) + " is not finite");
    }
    if (!required_[column]) return;
    if (text.empty()) {
      Fail(source_, reader_.number(), log_.columns[column],
           "value is missing (empty field) in a required column");
    }
    Fail(source_, reader_.number(), log_.columns[column],
         "value " + Quote(text) + " is not finite (missing) in a required column");
  }

  [[noreturn]] void FailNotNumber(const char* field, const char* end, size_t column) {
    Fail(source_, reader_.number(), log_.columns[column],
         "field " + Quote(Trim(FieldText(field, end))) + " is not a number");
  }

  [[noreturn]] void FailFieldCount(std::string_view line) {
    const size_t fields = std::count(line.begin(), line.end(), ',') + 1;
    Fail(source_, reader_.number(), "",
         "row has " + std::to_string(fields) + " fields but the header has " +
             std::to_string(log_.columns.size()));
  }

  // The field starting at `field`, up to the next comma or the end of the line.
  static std::string_view FieldText(const char* field, const char* end) {
    const char* comma = static_cast<const char*>(std::memchr(field, ',', end - field));
    return std::string_view(field, (comma != nullptr ? comma : end) - field);
  }

  LineReader reader_;
  const std::string& source_;
  Log log_;
  int kind_line_ = 0;
  int header_line_ = 0;
  std::vector<std::pair<std::string, int>> metadata_lines_;
  std::vector<bool> required_;
  int time_column_ = -1;
};

// Names the writer refuses because they would not read back the same.
void CheckWritableName(const std::string& path, const std::string& what, const std::string& name,
                       const char* forbidden) {
  if (name.empty() || Trim(name).size() != name.size() ||
      name.find_first_of(forbidden) != std::string::npos) {
    throw InputError(path + ": " + what + " " + Quote(name) +
                     " cannot be written (empty, surrounding spaces or a reserved character)");
  }
}

}  // namespace

const char* LogKindName(LogKind kind) {
  switch (kind) {
    case LogKind::kBalance:
      return "balance";
    case LogKind::kFlight:
      return "flight";
  }
  LOG(FATAL) << "unknown LogKind " << static_cast<int>(kind);
  return "";
}

int Log::ColumnIndex(const std::string& column) const {
  // Logs have a few dozen columns at most; a linear scan beats a map here.
  for (size_t j = 0; j < columns.size(); ++j) {
    if (columns[j] == column) return static_cast<int>(j);
  }
  return -1;
}

const std::vector<double>& Log::Column(const std::string& column) const {
  const int index = ColumnIndex(column);
  CHECK_GE(index, 0) << "column '" << column << "' is not in log '" << source << "'";
  return values[index];
}

void Log::SetColumn(const std::string& column, std::vector<double> data) {
  const int index = ColumnIndex(column);
  // Every column has the same length, unless this column is (or replaces) the only one.
  const bool only_column = values.empty() || (values.size() == 1 && index == 0);
  if (!only_column) {
    CHECK_EQ(static_cast<int>(data.size()), NumRows())
        << "column '" << column << "' has the wrong length for log '" << source << "'";
  }
  if (index >= 0) {
    values[index] = std::move(data);
  } else {
    columns.push_back(column);
    values.push_back(std::move(data));
  }
}

const std::vector<std::string>& RequiredColumns(LogKind kind) {
  static const std::vector<std::string> balance = {"t", "omega1", "omega2", "delta_cx", "delta_cy"};
  static const std::vector<std::string> flight = {
      "t", "omega1", "omega2", "delta_cx", "delta_cy", "phi", "theta", "psi", "p", "q", "r"};
  return kind == LogKind::kBalance ? balance : flight;
}

const std::vector<std::string>& BalanceLoadColumns() {
  static const std::vector<std::string> columns = {"X", "Y",  "Z",  "L",  "M",
                                                   "N", "Z1", "Z2", "N1", "N2"};
  return columns;
}

const std::vector<std::string>& FlightOutputColumns() {
  static const std::vector<std::string> columns = {"x",   "y", "z", "u", "v",  "w",  "phi", "theta",
                                                   "psi", "p", "q", "r", "ax", "ay", "az"};
  return columns;
}

const std::vector<std::string>& InputColumns() {
  static const std::vector<std::string> columns = {"omega1", "omega2", "delta_cx", "delta_cy"};
  return columns;
}

Log ReadLog(const std::string& path) {
  FileReader file(path);
  return Parser(&file, path).Parse();
}

Log ParseLog(const std::string& text, const std::string& source) {
  return Parser(text, source).Parse();
}

void WriteLog(const std::string& path, const Log& log) {
  CHECK_EQ(log.columns.size(), log.values.size()) << "log '" << log.source << "'";
  const size_t rows = log.values.empty() ? 0 : log.values[0].size();
  for (size_t j = 0; j < log.values.size(); ++j) {
    CHECK_EQ(log.values[j].size(), rows)
        << "column '" << log.columns[j] << "' of log '" << log.source << "'";
  }
  if (log.columns.empty()) throw InputError(path + ": log has no columns to write");

  std::string out;
  out.reserve(64 * (log.metadata.size() + 2) + rows * log.columns.size() * 12);
  out += "# kind: ";
  out += LogKindName(log.kind);
  out += '\n';
  for (const auto& [key, value] : log.metadata) {
    CheckWritableName(path, "metadata key", key, ":\r\n");
    if (key == "kind") throw InputError(path + ": metadata key 'kind' is reserved for Log::kind");
    if (Trim(value).size() != value.size() || value.find_first_of("\r\n") != std::string::npos) {
      throw InputError(path + ": metadata value " + Quote(value) + " of key " + Quote(key) +
                       " cannot be written (surrounding spaces or a line break)");
    }
    out += "# ";
    out += key;
    out += ": ";
    out += value;
    out += '\n';
  }
  for (size_t j = 0; j < log.columns.size(); ++j) {
    // A header starting with '#' would read back as a metadata line.
    CheckWritableName(path, "column name", log.columns[j], ",\r\n");
    if (log.columns[j][0] == '#') {
      throw InputError(path + ": column name " + Quote(log.columns[j]) +
                       " cannot be written (starts with '#')");
    }
    for (size_t i = 0; i < j; ++i) {
      if (log.columns[i] == log.columns[j]) {
        throw InputError(path + ": column name " + Quote(log.columns[j]) + " appears twice");
      }
    }
    if (j > 0) out += ',';
    out += log.columns[j];
  }
  out += '\n';

  char buffer[32];
  for (size_t k = 0; k < rows; ++k) {
    for (size_t j = 0; j < log.values.size(); ++j) {
      if (j > 0) out += ',';
      const double v = log.values[j][k];
      if (std::isnan(v)) continue;  // NaN is written as an empty field.
      if (std::isinf(v)) {
        throw InputError(path + ": column '" + log.columns[j] + "': row " + std::to_string(k + 1) +
                         ": value " + FormatDouble(v) + " cannot be written (not finite)");
      }
      // Shortest representation that reads back to the same double.
      const auto result = std::to_chars(buffer, buffer + sizeof(buffer), v);
      out.append(buffer, result.ptr);
    }
    out += '\n';
  }
  WriteFileAtomically(path, out);
}

}  // namespace coaxid
