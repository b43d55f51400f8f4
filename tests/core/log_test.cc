// Tests of the CSV log reader/writer (shared/spec/log-format.md) and of the
// atomic file helpers it writes through.
#include "core/log.h"

#include <dirent.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <ostream>
#include <random>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/errors.h"

namespace coaxid {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A fresh, empty folder per test, so tests can list what a write left behind;
// removed with its contents at the end of the test.
class TempDir {
 public:
  TempDir() {
    std::string pattern = ::testing::TempDir() + "coaxid_log_test_XXXXXX";
    std::vector<char> buffer(pattern.begin(), pattern.end());
    buffer.push_back('\0');
    if (::mkdtemp(buffer.data()) == nullptr) {
      ADD_FAILURE() << "mkdtemp failed: " << std::strerror(errno);
      path_ = "/nonexistent";
    } else {
      path_ = buffer.data();
    }
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::vector<std::string> ListDir(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return names;
  while (const dirent* entry = ::readdir(d)) {
    const std::string name = entry->d_name;
    if (name != "." && name != "..") names.push_back(name);
  }
  ::closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

// Bitwise equality: tells -0 from 0 and treats every NaN as equal to NaN, the
// exact meaning of "the log reads back unchanged".
bool SameDouble(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}

// A valid flight log: line 1 kind, line 2 header, rows from line 3.
const char kFlightHeader[] = "t,omega1,omega2,delta_cx,delta_cy,phi,theta,psi,p,q,r,x";

// One valid flight row at time `t`, with some fields replaced by raw text.
std::string FlightRow(const std::string& t, const std::map<std::string, std::string>& raw = {}) {
  const std::vector<std::string> names = {
      "t", "omega1", "omega2", "delta_cx", "delta_cy", "phi", "theta", "psi", "p", "q", "r", "x"};
  const std::vector<std::string> values = {t,         "150.2",  "164.9",  "0.0012",
                                           "-0.0031", "0.0011", "-0.002", "0",
                                           "0.004",   "-0.01",  "0.001",  "1.5"};
  std::string row;
  for (size_t j = 0; j < names.size(); ++j) {
    if (j > 0) row += ',';
    const auto it = raw.find(names[j]);
    row += it != raw.end() ? it->second : values[j];
  }
  return row;
}

std::string FlightLog(const std::vector<std::string>& rows) {
  std::string text = std::string("# kind: flight\n") + kFlightHeader + "\n";
  for (const std::string& row : rows) text += row + "\n";
  return text;
}

// The message of the InputError that parsing `text` throws ("" and a test
// failure if it does not throw).
std::string ParseError(const std::string& text) {
  try {
    ParseLog(text, "bad.csv");
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return "";
}

TEST(LogTest, ParsesSpecExample) {
  const Log log = ParseLog(
      "# kind: flight\n"
      "# vehicle: glmav\n"
      "# rate_hz: 200\n"
      "t,omega1,omega2,delta_cx,delta_cy,phi,theta,psi,p,q,r,x,y,z\n"
      "0.000,150.2,164.9,0.0012,-0.0031,0.0011,-0.0020,0.0000,0.004,-0.010,0.001,0.00,0.00,-1.50\n"
      "0.005,150.4,164.7,0.0015,-0.0029,0.0012,-0.0021,0.0000,0.006,-0.009,0.001,0.00,0.00,-1.50\n",
      "example.csv");
  EXPECT_EQ(log.kind, LogKind::kFlight);
  EXPECT_EQ(log.source, "example.csv");
  EXPECT_EQ(log.metadata,
            (std::map<std::string, std::string>{{"vehicle", "glmav"}, {"rate_hz", "200"}}));
  ASSERT_EQ(log.columns.size(), 14u);
  EXPECT_EQ(log.columns[0], "t");
  EXPECT_EQ(log.columns[13], "z");
  ASSERT_EQ(log.NumRows(), 2);
  // Exact: from_chars is correctly rounded, so "150.4" gives the same double as the literal.
  EXPECT_EQ(log.Column("t")[1], 0.005);
  EXPECT_EQ(log.Column("omega1")[1], 150.4);
  EXPECT_EQ(log.Column("delta_cy")[0], -0.0031);
  EXPECT_EQ(log.Column("z")[1], -1.5);
  EXPECT_EQ(log.ColumnIndex("omega2"), 2);
  EXPECT_EQ(log.ColumnIndex("nope"), -1);
  EXPECT_FALSE(log.Has("ax"));
}

TEST(LogTest, BalanceSteadyPointsWithPerRotorLoadsOnly) {
  // A rig that measures each rotor alone: Z1, Z2, N1, N2 and no X..N.
  const Log log = ParseLog(
      "# kind: balance\n"
      "t,omega1,omega2,delta_cx,delta_cy,Z1,Z2,N1,N2\n"
      "1,100,110,0,0,-0.21,-0.25,0.004,-0.0045\n"
      "2,120,132,0,0,-0.30,-0.36,0.0058,-0.0065\n"
      "3,140,154,0,0,-0.41,-0.49,0.0079,-0.0088\n",
      "rig.csv");
  EXPECT_EQ(log.kind, LogKind::kBalance);
  EXPECT_TRUE(log.metadata.empty());
  ASSERT_EQ(log.NumRows(), 3);
  EXPECT_EQ(log.Column("Z2")[2], -0.49);
  EXPECT_EQ(log.Column("N2")[0], -0.0045);
  EXPECT_FALSE(log.Has("Z"));
}

TEST(LogTest, KeepsUnknownColumnsAndMetadata) {
  const Log log = ParseLog(
      "# kind: balance\n"
      "# source: rig 2: left mount\n"
      "# operator: ann\n"
      "# a free comment without a key\n"
      "temperature_c,t,omega1,omega2,delta_cx,delta_cy,Z\n"
      "21.5,0,100,110,0,0,-0.46\n",
      "rig.csv");
  EXPECT_EQ(log.metadata.at("source"), "rig 2: left mount");  // Split at the first colon.
  EXPECT_EQ(log.metadata.at("operator"), "ann");
  EXPECT_EQ(log.metadata.size(), 2u);
  EXPECT_EQ(log.Column("temperature_c")[0], 21.5);
  EXPECT_EQ(log.ColumnIndex("t"), 1);
}

TEST(LogTest, MissingValuesInOptionalColumnsAreNaN) {
  const Log log = ParseLog(FlightLog({FlightRow("0", {{"x", ""}}), FlightRow("1", {{"x", "nan"}}),
                                      FlightRow("2", {{"x", "NaN"}}), FlightRow("3", {{"x", " "}}),
                                      FlightRow("4", {{"x", "2.5"}})}),
                           "f.csv");
  const std::vector<double>& x = log.Column("x");
  ASSERT_EQ(x.size(), 5u);
  for (int k = 0; k < 4; ++k) EXPECT_TRUE(std::isnan(x[k])) << "row " << k;
  EXPECT_EQ(x[4], 2.5);
}

TEST(LogTest, AcceptsCrLfBomSpacesAndTrailingBlankLines) {
  const Log log = ParseLog(
      "\xEF\xBB\xBF# kind: flight\r\n" + std::string(kFlightHeader) + "\r\n" + FlightRow("0") +
          "\r\n" + FlightRow("0.5", {{"p", " +0.25 "}, {"q", "1e-400"}}) + "\r\n\r\n  \r\n\t\n",
      "crlf.csv");
  ASSERT_EQ(log.NumRows(), 2);
  EXPECT_EQ(log.Column("t")[1], 0.5);
  EXPECT_EQ(log.Column("p")[1], 0.25);
  EXPECT_EQ(log.Column("q")[1], 0.0);  // Underflow rounds to zero, as strtod does.
  EXPECT_EQ(log.Column("x")[1], 1.5);  // Last field: the \r is not part of it.
}

TEST(LogTest, AcceptsLastLineWithoutNewline) {
  const Log log = ParseLog(FlightLog({FlightRow("0")}) + FlightRow("1"), "f.csv");
  EXPECT_EQ(log.NumRows(), 2);
}

TEST(LogTest, NumberForms) {
  const std::vector<std::pair<std::string, double>> forms = {
      {"-0", -0.0},
      {"5.", 5.0},
      {".5", 0.5},
      {"+.5", 0.5},
      {"1E3", 1e3},
      {"1e+3", 1e3},
      {"-2.5e-3", -2.5e-3},
      {"007", 7.0},
      {"1e22", 1e22},
      {"1e23", 1e23},
      {"9007199254740993", 9007199254740993.0},
      {"0.000000000000000000000000000001", 1e-30}};
  std::string text = "# kind: balance\nt,omega1,omega2,delta_cx,delta_cy,Z\n";
  for (size_t k = 0; k < forms.size(); ++k)
    text += std::to_string(k) + ",1,1,0,0," + forms[k].first + "\n";
  const Log log = ParseLog(text, "forms.csv");
  for (size_t k = 0; k < forms.size(); ++k) {
    EXPECT_TRUE(SameDouble(log.Column("Z")[k], forms[k].second)) << forms[k].first;
  }
}

// The reader has a fast path for short decimals and uses from_chars for the
// rest; both must give strtod's correctly rounded double, bit for bit.
TEST(LogTest, NumbersMatchStrtodBitForBit) {
  std::mt19937_64 rng(20240601);  // Seeded: a failure is repeatable.
  std::uniform_int_distribution<int> int_digits(0, 10), fraction_digits(0, 14), digit(0, 9);
  std::uniform_int_distribution<int> exponent(-40, 40), coin(0, 3);
  std::vector<std::string> numbers;
  for (int i = 0; i < 100000; ++i) {
    std::string s = coin(rng) == 0 ? "-" : "";
    const int n_int = int_digits(rng), n_fraction = fraction_digits(rng);
    for (int d = 0; d < n_int; ++d) s += static_cast<char>('0' + digit(rng));
    if (n_int == 0 || n_fraction > 0) {
      s += '.';
      for (int d = 0; d < std::max(n_fraction, n_int == 0 ? 1 : 0); ++d) {
        s += static_cast<char>('0' + digit(rng));
      }
    }
    if (coin(rng) == 0) s += "e" + std::to_string(exponent(rng));
    numbers.push_back(s);
    // And the shortest form of a random finite double of any magnitude, as WriteLog writes.
    double v;
    do {
      const uint64_t bits = rng();
      std::memcpy(&v, &bits, sizeof(v));
    } while (!std::isfinite(v));
    char buffer[32];
    numbers.emplace_back(buffer, std::to_chars(buffer, buffer + sizeof(buffer), v).ptr);
  }
  // Around 2^53, where the fast path must hand over to from_chars.
  for (const char* s :
       {"9007199254740992", "9007199254740993", "9007199254740995e-3", "900719925474099.3",
        "4503599627370497.5", "1.7976931348623157e308", "4.9e-324", "2.2250738585072011e-308"}) {
    numbers.push_back(s);
  }
  std::string text = "# kind: balance\nt,omega1,omega2,delta_cx,delta_cy,Z\n";
  for (size_t k = 0; k < numbers.size(); ++k) {
    text += std::to_string(k) + ",1,1,0,0," + numbers[k] + "\n";
  }
  const Log log = ParseLog(text, "numbers.csv");
  const std::vector<double>& z = log.Column("Z");
  ASSERT_EQ(z.size(), numbers.size());
  int mismatches = 0;
  for (size_t k = 0; k < numbers.size(); ++k) {
    const double expected = std::strtod(numbers[k].c_str(), nullptr);
    if (!SameDouble(z[k], expected) && ++mismatches <= 10) {
      ADD_FAILURE() << numbers[k] << ": read " << z[k] << ", strtod " << expected;
    }
  }
  EXPECT_EQ(mismatches, 0);
}

struct BadCase {
  const char* name;
  std::string text;
  int line;
  std::string column;              // "" where no column applies.
  std::vector<std::string> words;  // What the message must say about the problem.
};

// Names the case in failure output instead of dumping the struct's bytes.
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class BadLogTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadLogTest, RefusesWithFileLineColumnAndProblem) {
  const BadCase& c = GetParam();
  const std::string message = ParseError(c.text);
  EXPECT_THAT(message, StartsWith("bad.csv:" + std::to_string(c.line) + ": "));
  if (c.column.empty()) {
    EXPECT_THAT(message, ::testing::Not(HasSubstr("column '")));
  } else {
    EXPECT_THAT(message, HasSubstr("column '" + c.column + "': "));
  }
  for (const std::string& word : c.words) EXPECT_THAT(message, HasSubstr(word));
}

const std::string kKindWords = "no '# kind: balance|flight' line";

INSTANTIATE_TEST_SUITE_P(
    AllProblems, BadLogTest,
    ::testing::Values(
        BadCase{"EmptyFile", "", 1, "", {"empty file"}},
        BadCase{"OnlyBlankLines", "\n  \n", 1, "", {"empty file"}},
        BadCase{"NoHeader", "# kind: flight\n# vehicle: a\n", 2, "", {"no header"}},
        BadCase{"NoKind",
                std::string(kFlightHeader) + "\n" + FlightRow("0") + "\n",
                1,
                "",
                {kKindWords}},
        BadCase{"UnknownKind",
                "# vehicle: a\n# kind: hover\n" + std::string(kFlightHeader) + "\n",
                2,
                "",
                {kKindWords, "'hover'"}},
        BadCase{"SecondKind", "# kind: flight\n# kind: balance\n", 2, "", {"second", "line 1"}},
        BadCase{"RepeatedMetadataKey",
                "# kind: flight\n# rate_hz: 1\n# rate_hz: 2\n",
                3,
                "",
                {"'rate_hz'", "repeated", "line 2"}},
        BadCase{"MissingRequiredColumn",
                "# kind: flight\nt,omega1,omega2,delta_cx,delta_cy,phi,theta,psi,p,r\n",
                2,
                "q",
                {"missing required column"}},
        BadCase{"MissingRequiredBalanceColumn",
                "# kind: balance\nt,omega1,omega2,delta_cx,Z\n",
                2,
                "delta_cy",
                {"missing required column"}},
        BadCase{"BalanceWithoutLoadColumn",
                "# kind: balance\nt,omega1,omega2,delta_cx,delta_cy,temp\n0,1,1,0,0,20\n",
                2,
                "",
                {"no load column", "Z1", "N2"}},
        BadCase{"DuplicatedColumn",
                "# kind: flight\n" + std::string(kFlightHeader) + ",p\n",
                2,
                "p",
                {"duplicated", "columns 9 and 13"}},
        BadCase{"EmptyColumnName",
                "# kind: flight\n" + std::string(kFlightHeader) + ",\n",
                2,
                "",
                {"empty column name"}},
        BadCase{"HeaderOnly", FlightLog({}), 2, "", {"no data rows"}},
        BadCase{"NonNumericField",
                FlightLog({FlightRow("0"), FlightRow("1", {{"p", "abc"}})}),
                4,
                "p",
                {"'abc'", "not a number"}},
        BadCase{"TwoDecimalPoints",
                FlightLog({FlightRow("0", {{"omega1", "1.5.3"}})}),
                3,
                "omega1",
                {"'1.5.3'", "not a number"}},
        BadCase{"HexNumber",
                FlightLog({FlightRow("0", {{"x", "0x10"}})}),
                3,
                "x",
                {"'0x10'", "not a number"}},
        BadCase{"NumberWithUnit",
                FlightLog({FlightRow("0", {{"x", "1.5 m"}})}),
                3,
                "x",
                {"'1.5 m'", "not a number"}},
        BadCase{"InfinityInOptionalColumn",
                FlightLog({FlightRow("0", {{"x", "inf"}})}),
                3,
                "x",
                {"'inf'", "not finite"}},
        BadCase{"OverflowInOptionalColumn",
                FlightLog({FlightRow("0", {{"x", "-1e999"}})}),
                3,
                "x",
                {"'-1e999'", "not finite"}},
        BadCase{"NaNInRequiredColumn",
                FlightLog({FlightRow("0"), FlightRow("1"), FlightRow("2", {{"theta", "nan"}})}),
                5,
                "theta",
                {"'nan'", "not finite", "required"}},
        BadCase{"NaNTime", FlightLog({FlightRow("nan")}), 3, "t", {"not finite", "required"}},
        BadCase{"EmptyFieldInRequiredColumn",
                FlightLog({FlightRow("0", {{"omega2", ""}})}),
                3,
                "omega2",
                {"missing", "required"}},
        BadCase{"RepeatedTime",
                FlightLog({FlightRow("0"), FlightRow("0.01"), FlightRow("0.01")}),
                5,
                "t",
                {"0.01 is not after the previous time 0.01", "line 4", "increasing"}},
        BadCase{"DecreasingTime",
                FlightLog({FlightRow("0.5"), FlightRow("0.25")}),
                4,
                "t",
                {"time 0.25", "previous time 0.5", "increasing"}},
        BadCase{"TooFewFields",
                FlightLog({FlightRow("0"), "1,150,160"}),
                4,
                "",
                {"row has 3 fields", "header has 12"}},
        BadCase{"TooManyFields",
                FlightLog({FlightRow("0") + ",7"}),
                3,
                "",
                {"row has 13 fields", "header has 12"}},
        BadCase{"DataAfterBlankLine",
                FlightLog({FlightRow("0"), "", FlightRow("1")}),
                5,
                "",
                {"blank line 4"}},
        BadCase{"MetadataAfterHeader",
                FlightLog({FlightRow("0"), "# rate_hz: 200"}),
                4,
                "",
                {"metadata line after the header"}}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

// Seeded random edits of a valid log: the reader either refuses with an
// InputError or returns a log that keeps the format's promises; it never
// crashes, reads out of bounds (run under ASan in the sanitizer build) or
// throws anything else.
TEST(LogTest, RandomEditsAreRefusedOrValid) {
  const std::string valid = "# kind: flight\n# vehicle: v\n" +
                            FlightLog({FlightRow("0"), FlightRow("0.5", {{"x", ""}}),
                                       FlightRow("1", {{"p", "-1e-3"}}), FlightRow("2")})
                                .substr(15);
  const std::string alphabet = "0123456789.,-+eE \t\r\n#:naifx";
  std::mt19937 rng(7);  // Seeded: a failure is repeatable.
  std::uniform_int_distribution<int> edits(1, 4), kind(0, 2);
  std::uniform_int_distribution<size_t> pick(0, alphabet.size() - 1);
  int accepted = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    std::string text = valid;
    for (int e = edits(rng); e > 0; --e) {
      const size_t at = std::uniform_int_distribution<size_t>(0, text.size())(rng);
      switch (kind(rng)) {
        case 0:
          text.insert(at, 1, alphabet[pick(rng)]);
          break;
        case 1:
          if (at < text.size()) text.erase(at, 1);
          break;
        default:
          if (at < text.size()) text[at] = alphabet[pick(rng)];
      }
    }
    Log log;
    try {
      log = ParseLog(text, "fuzz.csv");
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), StartsWith("fuzz.csv:")) << text;
      continue;
    }
    ++accepted;
    ASSERT_EQ(log.values.size(), log.columns.size()) << text;
    for (const auto& column : log.values) ASSERT_EQ(column.size(), log.values[0].size()) << text;
    for (const std::string& name : RequiredColumns(log.kind)) {
      ASSERT_TRUE(log.Has(name)) << text;
      for (const double v : log.Column(name)) ASSERT_TRUE(std::isfinite(v)) << text;
    }
    const std::vector<double>& t = log.Column("t");
    for (size_t k = 1; k < t.size(); ++k) ASSERT_GT(t[k], t[k - 1]) << text;
  }
  // Both outcomes must occur, or the edits test nothing.
  EXPECT_GT(accepted, 100);
  EXPECT_LT(accepted, 4900);
}

TEST(LogTest, ReadLogNamesThePathInMessages) {
  const TempDir temp;
  const std::string& dir = temp.path();
  const std::string path = dir + "/flight 7.csv";
  WriteFileAtomically(path, FlightLog({FlightRow("0"), FlightRow("1", {{"r", "x"}})}));
  try {
    ReadLog(path);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith(path + ":4: column 'r': "));
  }
  try {
    ReadLog(dir + "/missing.csv");
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith(dir + "/missing.csv: "));
    EXPECT_THAT(e.what(), HasSubstr(std::strerror(ENOENT)));
  }
}

// ReadLog reads files in 1 MB pieces: a log of several pieces, with \r\n
// endings and no final newline, reads as ParseLog reads the same text, and
// an error in the last piece names its line.
TEST(LogTest, ReadLogAcrossPiecesEqualsParseLog) {
  const TempDir temp;
  const int rows = 60000;  // about 4 MB
  std::string text = "\xEF\xBB\xBF# kind: flight\r\n" + std::string(kFlightHeader) + "\r\n";
  for (int k = 0; k < rows; ++k) {
    text += FlightRow(std::to_string(0.005 * (k + 1)), {{"x", std::to_string(k % 977)}});
    if (k + 1 < rows) text += "\r\n";
  }
  const std::string path = temp.path() + "/long.csv";
  WriteFileAtomically(path, text);
  const Log read = ReadLog(path);
  const Log parsed = ParseLog(text, path);
  ASSERT_EQ(read.NumRows(), rows);
  EXPECT_EQ(read.columns, parsed.columns);
  EXPECT_EQ(read.metadata, parsed.metadata);
  for (size_t j = 0; j < read.columns.size(); ++j) {
    EXPECT_EQ(read.values[j], parsed.values[j]) << read.columns[j];
  }
  EXPECT_EQ(read.Column("x")[rows - 1], (rows - 1) % 977);

  const std::string bad = temp.path() + "/bad.csv";
  const size_t last = text.rfind("\r\n");
  WriteFileAtomically(bad, text.substr(0, last) + "\r\n" + FlightRow("1e9", {{"q", "nope"}}));
  try {
    ReadLog(bad);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith(bad + ":" + std::to_string(rows + 2) + ": column 'q': "));
  }
}

// A log with the values that break naive formatting: not exactly representable
// decimals, extremes of the range, subnormals, -0 and missing values.
Log TrickyLog() {
  Log log;
  log.kind = LogKind::kFlight;
  log.metadata = {{"vehicle", "glmav"}, {"rate_hz", "200"}, {"note", "a: b, c"}};
  const std::vector<double> tricky = {0.1,
                                      1e-300,
                                      -1e-300,
                                      std::numeric_limits<double>::denorm_min(),
                                      DBL_MIN,
                                      DBL_MAX,
                                      -DBL_MAX,
                                      1.0 / 3.0,
                                      -0.0,
                                      std::acos(-1.0),
                                      1e21,
                                      123456789012345678.0,
                                      std::nextafter(1.0, 2.0),
                                      kNaN};
  const int n = static_cast<int>(tricky.size());
  std::vector<double> t(n);
  for (int k = 0; k < n; ++k) t[k] = 0.1 * k + 0.2;  // 0.30000000000000004 etc.
  log.SetColumn("t", t);
  for (const std::string& name : RequiredColumns(LogKind::kFlight)) {
    if (name == "t") continue;
    std::vector<double> column(n);
    // Finite only: these columns are required. Rotate so every column sees every value.
    for (int k = 0; k < n; ++k) {
      const double v = tricky[(k + log.columns.size()) % n];
      column[k] = std::isnan(v) ? 0.7 : v;
    }
    log.SetColumn(name, column);
  }
  log.SetColumn("ax", tricky);
  log.SetColumn("custom", std::vector<double>(n, kNaN));
  return log;
}

TEST(LogTest, WriteThenReadIsExact) {
  const TempDir temp;
  const std::string& dir = temp.path();
  const std::string path = dir + "/log.csv";
  const Log written = TrickyLog();
  WriteLog(path, written);
  const Log read = ReadLog(path);
  EXPECT_EQ(read.kind, written.kind);
  EXPECT_EQ(read.metadata, written.metadata);
  EXPECT_EQ(read.columns, written.columns);
  EXPECT_EQ(read.source, path);
  ASSERT_EQ(read.values.size(), written.values.size());
  for (size_t j = 0; j < read.values.size(); ++j) {
    ASSERT_EQ(read.values[j].size(), written.values[j].size());
    for (size_t k = 0; k < read.values[j].size(); ++k) {
      EXPECT_TRUE(SameDouble(read.values[j][k], written.values[j][k]))
          << read.columns[j] << "[" << k << "]: wrote " << written.values[j][k] << ", read "
          << read.values[j][k];
    }
  }
  // The text is stable: writing what was read gives the same bytes.
  WriteLog(dir + "/again.csv", read);
  EXPECT_EQ(ReadFile(dir + "/again.csv"), ReadFile(path));
  EXPECT_EQ(ListDir(dir), (std::vector<std::string>{"again.csv", "log.csv"}));  // No temp files.
}

TEST(LogTest, WritesKindFirstShortestNumbersAndEmptyNaN) {
  const TempDir temp;
  const std::string& dir = temp.path();
  Log log;
  log.kind = LogKind::kBalance;
  log.metadata = {{"vehicle", "glmav"}};
  log.SetColumn("t", {0.1, 0.30000000000000004});
  log.SetColumn("Z", {kNaN, -2.5});
  WriteLog(dir + "/b.csv", log);
  EXPECT_EQ(ReadFile(dir + "/b.csv"),
            "# kind: balance\n# vehicle: glmav\nt,Z\n0.1,\n0.30000000000000004,-2.5\n");
}

TEST(LogTest, WriteRefusesWhatWouldNotReadBack) {
  const TempDir temp;
  const std::string& dir = temp.path();
  const std::string path = dir + "/w.csv";
  Log log;
  log.SetColumn("t", {0, 1});
  log.SetColumn("x", {1, std::numeric_limits<double>::infinity()});
  try {
    WriteLog(path, log);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith(path + ": column 'x': row 2: "));
    EXPECT_THAT(e.what(), HasSubstr("not finite"));
  }
  Log bad_name;
  bad_name.SetColumn("a,b", {1});
  EXPECT_THROW(WriteLog(path, bad_name), InputError);
  Log twice;
  twice.columns = {"t", "t"};
  twice.values = {{1}, {2}};
  EXPECT_THROW(WriteLog(path, twice), InputError);
  Log bad_key;
  bad_key.SetColumn("t", {1});
  bad_key.metadata["kind"] = "flight";
  EXPECT_THROW(WriteLog(path, bad_key), InputError);
  Log bad_value;
  bad_value.SetColumn("t", {1});
  bad_value.metadata["note"] = "two\nlines";
  EXPECT_THROW(WriteLog(path, bad_value), InputError);
  EXPECT_TRUE(ListDir(dir).empty());  // Nothing written from a refused log.
}

TEST(LogTest, WriteIntoMissingFolderNamesThePath) {
  const TempDir temp;
  const std::string path = temp.path() + "/no/such/folder/log.csv";
  try {
    WriteLog(path, TrickyLog());
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith(path + ": "));
    EXPECT_THAT(e.what(), HasSubstr(std::strerror(ENOENT)));
  }
}

TEST(LogTest, SetColumnAddsAndReplaces) {
  Log log;
  log.SetColumn("t", {0, 1, 2});
  log.SetColumn("x", {5, 6, 7});
  log.SetColumn("t", {0, 1, 3});
  EXPECT_EQ(log.columns, (std::vector<std::string>{"t", "x"}));
  EXPECT_EQ(log.Column("t"), (std::vector<double>{0, 1, 3}));
  EXPECT_EQ(log.NumRows(), 3);
}

TEST(LogDeathTest, BugsAreCheckFailures) {
  Log log;
  log.SetColumn("t", {0, 1, 2});
  EXPECT_DEATH(log.Column("x"), "column 'x'");
  EXPECT_DEATH(log.SetColumn("x", {1, 2}), "wrong length");
}

TEST(LogTest, NamesOfKindsAndColumnSets) {
  EXPECT_STREQ(LogKindName(LogKind::kBalance), "balance");
  EXPECT_STREQ(LogKindName(LogKind::kFlight), "flight");
  EXPECT_EQ(InputColumns(), (std::vector<std::string>{"omega1", "omega2", "delta_cx", "delta_cy"}));
  EXPECT_EQ(RequiredColumns(LogKind::kBalance).size(), 5u);
  EXPECT_EQ(RequiredColumns(LogKind::kFlight).size(), 11u);
  EXPECT_EQ(BalanceLoadColumns().size(), 10u);
  EXPECT_EQ(FlightOutputColumns().size(), 15u);
}

TEST(AtomicFileTest, ReplacesContentsAndLeavesNoTemporary) {
  const TempDir temp;
  const std::string& dir = temp.path();
  const std::string path = dir + "/out.txt";
  WriteFileAtomically(path, "first, longer contents\n");
  WriteFileAtomically(path, "second\n");
  EXPECT_EQ(ReadFile(path), "second\n");
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"out.txt"});
  struct stat info;
  ASSERT_EQ(::stat(path.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0644u);  // Not mkstemp's private 0600.
  WriteFileAtomically(path, "");
  EXPECT_EQ(ReadFile(path), "");
}

// A file written in pieces holds them in order; a producer that throws
// leaves neither the target nor a temporary, and an old file stays as it was.
TEST(AtomicFileTest, WrittenInPiecesOrNotAtAll) {
  const TempDir temp;
  const std::string target = temp.path() + "/pieces.csv";
  WriteFileAtomically(target, [](const EmitText& emit) {
    for (int k = 0; k < 1000; ++k) emit(std::to_string(k) + "\n");
  });
  std::string expected;
  for (int k = 0; k < 1000; ++k) expected += std::to_string(k) + "\n";
  EXPECT_EQ(ReadFile(target), expected);
  EXPECT_THROW(WriteFileAtomically(target,
                                   [](const EmitText& emit) {
                                     emit("half");
                                     throw InputError("row 7: not a number");
                                   }),
               InputError);
  EXPECT_EQ(ReadFile(target), expected);
  EXPECT_EQ(ListDir(temp.path()), std::vector<std::string>{"pieces.csv"});
}

TEST(AtomicFileTest, FailedRenameRemovesTemporary) {
  const TempDir temp;
  const std::string& dir = temp.path();
  const std::string target = dir + "/taken";
  ASSERT_EQ(::mkdir(target.c_str(), 0755), 0);  // rename(file, directory) fails.
  try {
    WriteFileAtomically(target, "data");
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith(target + ": "));
  }
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"taken"});
}

TEST(AtomicFileTest, ReadFileErrorsNameThePath) {
  const TempDir temp;
  const std::string& dir = temp.path();
  EXPECT_THROW(ReadFile(dir + "/absent"), InputError);
  try {
    ReadFile(dir);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith(dir + ": "));
    EXPECT_THAT(e.what(), HasSubstr(std::strerror(EISDIR)));
  }
}

}  // namespace
}  // namespace coaxid
