// `coaxid import` (experiments/cli/import.h): unit conversion and sign
// conventions of the tmotor28 format, error messages on malformed input, and
// that the shipped logs in data/real/tmotor28-coaxial/ are a fresh conversion
// of the upstream files.
#include "experiments/cli/import.h"

#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "core/errors.h"
#include "core/log.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

const ImportTable& Table(const std::string& input_file) {
  for (const ImportTable& t : ImportFormat("tmotor28")) {
    if (t.input_file == input_file) return t;
  }
  ADD_FAILURE() << "no table for " << input_file;
  return ImportFormat("tmotor28").front();
}

constexpr double kRpm = 2.0 * M_PI / 60.0;

TEST(ImportTest, CoaxialSampleHasSignsAndUnitsOfTheModel) {
  const std::string text =
      "RPM,T_A(N),Q_A(Nm),P_A(W),T_B(N),Q_B(Nm),P_B(W),RPM_B\n"
      "1000,3.5,0.18,19.3,5.4,0.2,22.4,1010\n"
      "2000,14,0.7,150,21,0.8,170,2020\r\n";
  const Log log = ConvertTable(Table("coaxial.csv"), text, "sample.csv");
  ASSERT_EQ(log.NumRows(), 2);
  EXPECT_EQ(log.kind, LogKind::kBalance);
  EXPECT_EQ(log.metadata.at("layout"), "steady_points");
  EXPECT_EQ(log.metadata.at("vehicle"), "tmotor28");
  EXPECT_NE(log.metadata.at("source").find("pyBEMT"), std::string::npos);
  EXPECT_EQ(log.Column("t")[0], 0.0);
  EXPECT_EQ(log.Column("t")[1], 1.0);
  // omega1 is the UPPER rotor B, omega2 the LOWER rotor A; rad/s.
  EXPECT_NEAR(log.Column("omega1")[0], 1010 * kRpm, 1e-12);
  EXPECT_NEAR(log.Column("omega2")[0], 1000 * kRpm, 1e-12);
  EXPECT_NEAR(log.Column("omega1")[1], 2020 * kRpm, 1e-12);
  EXPECT_EQ(log.Column("delta_cx")[1], 0.0);
  EXPECT_EQ(log.Column("delta_cy")[1], 0.0);
  // Thrust up is negative Z (z down).
  EXPECT_EQ(log.Column("Z1")[0], -5.4);
  EXPECT_EQ(log.Column("Z2")[0], -3.5);
  EXPECT_EQ(log.Column("Z")[0], log.Column("Z1")[0] + log.Column("Z2")[0]);
  // Counter-rotating reaction torques: upper positive, lower negative.
  EXPECT_EQ(log.Column("N1")[1], 0.8);
  EXPECT_EQ(log.Column("N2")[1], -0.7);
  EXPECT_EQ(log.Column("N")[1], log.Column("N1")[1] + log.Column("N2")[1]);
  EXPECT_FALSE(log.Has("P_A(W)"));
}

TEST(ImportTest, IsolatedSampleIsTheUpperRotorAlone) {
  const std::string text =
      "RPM;omega;T(gf);T(N);Q(Nm);P(W);\n"
      "1006.000;105.348;539.999;5.296;0.187;19.68616467;\n"
      "1172.000;122.732;747.492;7.330;0.258;31.60583297;\n";
  const Log log = ConvertTable(Table("isolated.csv"), text, "iso.csv");
  ASSERT_EQ(log.NumRows(), 2);
  EXPECT_EQ(log.Column("omega1")[1], 122.732);
  EXPECT_EQ(log.Column("omega2")[1], 0.0);
  EXPECT_EQ(log.Column("Z1")[0], -5.296);
  EXPECT_EQ(log.Column("Z")[0], -5.296);
  EXPECT_EQ(log.Column("N1")[0], 0.187);
  EXPECT_EQ(log.Column("N")[0], 0.187);
  // No lower rotor: missing values, not measured zeros.
  EXPECT_TRUE(std::isnan(log.Column("Z2")[0]));
  EXPECT_TRUE(std::isnan(log.Column("N2")[1]));
}

void ExpectError(const std::string& text, const std::string& input_file,
                 const std::vector<std::string>& parts) {
  try {
    ConvertTable(Table(input_file), text, "/in/" + input_file);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const std::string& part : parts) {
      EXPECT_NE(what.find(part), std::string::npos) << "'" << part << "' not in: " << what;
    }
  }
}

TEST(ImportTest, MalformedInputNamesFileLineAndColumn) {
  const std::string header = "RPM,T_A(N),Q_A(Nm),P_A(W),T_B(N),Q_B(Nm),P_B(W),RPM_B\n";
  ExpectError(header + "1000,3.5,0.18,19.3,5.4,0.2,22.4,1010\n1000,3.5,abc,19.3,5.4,0.2,22.4,1010\n",
              "coaxial.csv", {"/in/coaxial.csv:3:", "column 'Q_A(Nm)'", "'abc' is not a number"});
  ExpectError(header + "1000,3.5,0.18,19.3,5.4,0.2,22.4\n", "coaxial.csv",
              {"/in/coaxial.csv:2:", "7 fields", "8"});
  ExpectError("RPM,T_A(N),Q_A(Nm),P_A(W),T_B(N),Q_B(Nm),P_B(W)\n1,2,3,4,5,6,7\n", "coaxial.csv",
              {"/in/coaxial.csv:1:", "column 'RPM_B'", "missing"});
  ExpectError(header + "1000,3.5,0.18,19.3,,0.2,22.4,1010\n", "coaxial.csv",
              {"/in/coaxial.csv:2:", "column 'T_B(N)'", "empty"});
  ExpectError(header + "1000,3.5,0.18,19.3,inf,0.2,22.4,1010\n", "coaxial.csv",
              {"/in/coaxial.csv:2:", "column 'T_B(N)'", "not finite"});
  ExpectError(header, "coaxial.csv", {"/in/coaxial.csv:1:", "no data rows"});
  // A comma-separated file where `;` is expected: the header is one field.
  ExpectError("RPM,omega,T(gf),T(N),Q(Nm),P(W)\n1,2,3,4,5,6\n", "isolated.csv",
              {"/in/isolated.csv:1:", "missing", "';'"});
  EXPECT_THROW(ImportFormat("nope"), InputError);
}

// The upstream files are beside the repository on a developer's and the CI
// machine (../shared), but the repository does not depend on them.
TEST(ImportTest, ShippedLogsAreAFreshConversionOfTheUpstreamFiles) {
  const fs::path upstream =
      fs::path(COAXID_SOURCE_DIR) / ".." / "shared" / "data" / "real" / "tmotor28-coaxial";
  if (!fs::exists(upstream / "coaxial.csv") || !fs::exists(upstream / "isolated.csv")) {
    GTEST_SKIP() << "upstream data not present at " << upstream;
  }
  const fs::path shipped = fs::path(COAXID_SOURCE_DIR) / "data" / "real" / "tmotor28-coaxial";
  const auto fresh = ConvertFormat("tmotor28", upstream.string());
  ASSERT_EQ(fresh.size(), 2u);
  for (const auto& [name, log] : fresh) {
    SCOPED_TRACE(name);
    const Log ship = ReadLog((shipped / name).string());
    EXPECT_EQ(ship.kind, log.kind);
    EXPECT_EQ(ship.metadata, log.metadata);
    ASSERT_EQ(ship.columns, log.columns);
    for (size_t c = 0; c < log.columns.size(); ++c) {
      ASSERT_EQ(ship.values[c].size(), log.values[c].size());
      for (size_t k = 0; k < log.values[c].size(); ++k) {
        const double a = log.values[c][k], b = ship.values[c][k];
        if (std::isnan(a)) {
          EXPECT_TRUE(std::isnan(b)) << log.columns[c] << " row " << k;
        } else {
          EXPECT_EQ(a, b) << log.columns[c] << " row " << k;  // bit-exact round trip
        }
      }
    }
  }
}

TEST(ImportTest, ShippedLogsAreValidBalanceLogs) {
  const fs::path shipped = fs::path(COAXID_SOURCE_DIR) / "data" / "real" / "tmotor28-coaxial";
  const Log coaxial = ReadLog((shipped / "tmotor28_coaxial.csv").string());
  EXPECT_EQ(coaxial.kind, LogKind::kBalance);
  EXPECT_EQ(coaxial.NumRows(), 19);
  const Log isolated = ReadLog((shipped / "tmotor28_isolated.csv").string());
  EXPECT_EQ(isolated.NumRows(), 30);
  for (int k = 0; k < coaxial.NumRows(); ++k) {
    EXPECT_LT(coaxial.Column("Z1")[k], 0);
    EXPECT_LT(coaxial.Column("Z2")[k], 0);
    EXPECT_GT(coaxial.Column("N1")[k], 0);
    EXPECT_LT(coaxial.Column("N2")[k], 0);
  }
}

}  // namespace
}  // namespace coaxid
