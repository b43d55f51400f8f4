// SinCos (dynamics/sin_cos.h) gives, bit for bit, what ceres::Jet's own sin
// and cos give, value and every derivative direction, so the model's
// equations keep their results when they take both at once; and the Euler
// sines feed the same rotation as the angles themselves (eq. 1).
#include "dynamics/sin_cos.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/LU>
#include <ceres/jet.h>

#include "dynamics/rigid_body.h"

namespace coaxid {
namespace {

using Jet = ceres::Jet<double, 4>;

TEST(SinCos, EqualsTheJetsOwnSinAndCosBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-3.2, 3.2), direction(-5, 5);
  for (int trial = 0; trial < 200; ++trial) {
    Jet a(angle(rng));
    for (int k = 0; k < 4; ++k) a.v[k] = direction(rng);
    Jet s, c;
    SinCos(a, &s, &c);
    const Jet s_ref = sin(a), c_ref = cos(a);
    ASSERT_EQ(s.a, s_ref.a);
    ASSERT_EQ(c.a, c_ref.a);
    for (int k = 0; k < 4; ++k) {
      ASSERT_EQ(s.v[k], s_ref.v[k]) << "direction " << k;
      ASSERT_EQ(c.v[k], c_ref.v[k]) << "direction " << k;
    }
    double sd, cd;
    SinCos(a.a, &sd, &cd);
    ASSERT_EQ(sd, std::sin(a.a));
    ASSERT_EQ(cd, std::cos(a.a));
  }
}

// The per-thread table of recent angles serves an angle met again, and a
// slot another angle took over gives that angle's values: drawn from a small
// pool so that angles repeat and share slots, every value is sin's and cos's.
TEST(SinCos, RecentAnglesServedAgainAreBitForBitTheFunctions) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> angle(-3.2, 3.2);
  std::vector<double> pool(300);
  for (double& a : pool) a = angle(rng);
  pool.push_back(0.0);
  pool.push_back(-0.0);
  std::uniform_int_distribution<size_t> pick(0, pool.size() - 1);
  for (int trial = 0; trial < 20000; ++trial) {
    const double a = pool[pick(rng)];
    double s, c;
    ScalarSinCos(a, &s, &c);
    ASSERT_EQ(std::signbit(s), std::signbit(std::sin(a))) << a;
    ASSERT_EQ(s, std::sin(a)) << a;
    ASSERT_EQ(c, std::cos(a)) << a;
  }
  // Not a number, also the one whose bits mark an empty slot.
  std::uint64_t empty = ~std::uint64_t{0};
  double marked;
  std::memcpy(&marked, &empty, sizeof marked);
  for (double a : {std::numeric_limits<double>::quiet_NaN(), marked}) {
    double s = 0, c = 0;
    ScalarSinCos(a, &s, &c);
    EXPECT_TRUE(std::isnan(s) && std::isnan(c));
  }
}

TEST(SinCos, EulerSinesGiveARotationWhoseColumnsAreOrthonormal) {
  const Eigen::Matrix3d R = BodyToEarth(0.3, -0.2, 2.1);
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-15);
  // Third row (eq. 1): (-sin theta, sin phi cos theta, cos phi cos theta).
  EXPECT_DOUBLE_EQ(R(2, 0), -std::sin(-0.2));
  EXPECT_DOUBLE_EQ(R(2, 1), std::sin(0.3) * std::cos(-0.2));
  EXPECT_DOUBLE_EQ(R(2, 2), std::cos(0.3) * std::cos(-0.2));
}

}  // namespace
}  // namespace coaxid
