// Numbers written into tables: the fast writer prints exactly what printf's
// "%.<digits>g" prints, so switching to it changed no output byte.
#include "core/report_values.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

namespace coaxid {
namespace {

std::string Printf(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return text;
}

TEST(Significant, PrintsWhatPrintfPrints) {
  std::mt19937_64 rng(20261126);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-320, 308);
  std::uniform_int_distribution<int> digits(1, 17);
  int checked = 0;
  for (int i = 0; i < 200000; ++i) {
    const double v = mantissa(rng) * std::pow(10.0, exponent(rng));
    if (!std::isfinite(v)) continue;
    const int d = digits(rng);
    ASSERT_EQ(Significant(v, d), Printf(v, d)) << "digits " << d;
    ++checked;
  }
  EXPECT_GT(checked, 190000);
  // Edge cases: zeros, ties at the last digit, powers of ten, the extremes.
  for (double v : {0.0, -0.0, 0.5, 1.5, 2.5, 1e-5, 1e-4, 123456.5, 1e16, 9.9999999995,
                   std::numeric_limits<double>::min(), std::numeric_limits<double>::denorm_min(),
                   std::numeric_limits<double>::max(), -std::numeric_limits<double>::max()}) {
    for (int d : {1, 6, 9, 10, 17}) EXPECT_EQ(Significant(v, d), Printf(v, d)) << v;
  }
  char buffer[32];
  const char* end = WriteSignificant(buffer, -1.0 / 3.0, 10);
  EXPECT_EQ(std::string(static_cast<const char*>(buffer), end), "-0.3333333333");
}

}  // namespace
}  // namespace coaxid
