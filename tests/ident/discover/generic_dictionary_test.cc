// Step 7's generic dictionary (ident/discover/generic_dictionary.h): FROLS recovers the
// terms a synthetic residual was built from, with their coefficients, and
// offers nothing on white noise.
#include "ident/discover/generic_dictionary.h"

#include <algorithm>
#include <random>

#include <gtest/gtest.h>

namespace coaxid {
namespace {

// Six independent signals (uniform in [-1, 1]) of n samples, as a joined residual would carry.
JoinedResidual Signals(int n, std::mt19937* rng) {
  JoinedResidual j;
  std::uniform_real_distribution<double> u(-1, 1);
  for (const char* name : {"omega1", "omega2", "delta_cx", "delta_cy", "p", "q"}) {
    std::vector<double>& s = j.signals[name];
    for (int k = 0; k < n; ++k) s.push_back(u(*rng));
  }
  j.residual.assign(n, 0.0);
  j.time.resize(n);
  return j;
}

TEST(GenericDictionary, DegreeTwoDictionaryHasEveryProduct) {
  std::mt19937 rng(1);
  const JoinedResidual j = Signals(10, &rng);
  Eigen::MatrixXd d;
  std::vector<std::string> names;
  BuildDegreeTwoDictionary(j, &d, &names);
  EXPECT_EQ(d.cols(), 1 + 6 + 21);  // constant, 6 signals, 6 * 7 / 2 products
  const auto col = [&](const std::string& n) {
    return std::find(names.begin(), names.end(), n) - names.begin();
  };
  ASSERT_LT(col("delta_cx*p"), d.cols());
  EXPECT_DOUBLE_EQ(d(3, col("delta_cx*p")), j.signals.at("delta_cx")[3] * j.signals.at("p")[3]);
  EXPECT_DOUBLE_EQ(d(4, col("q^2")), j.signals.at("q")[4] * j.signals.at("q")[4]);
}

TEST(GenericDictionary, RecoversTheTermsOfASyntheticResidual) {
  std::mt19937 rng(2);
  const int n = 4000;
  JoinedResidual j = Signals(n, &rng);
  std::normal_distribution<double> noise(0, 0.1);
  for (int k = 0; k < n; ++k) {
    j.residual[k] = 0.5 * j.signals["omega1"][k] * j.signals["delta_cx"][k] -
                    0.3 * j.signals["q"][k] + noise(rng);
  }
  Eigen::MatrixXd d;
  std::vector<std::string> names;
  BuildDegreeTwoDictionary(j, &d, &names);
  const DictionarySearch s =
      SearchDictionary(Eigen::Map<const Eigen::VectorXd>(j.residual.data(), n), d, names);
  ASSERT_EQ(s.terms.size(), 2u);
    std::vector<std::string> chosen = {s.terms[0].name, s.terms[1].name};
  std::sort(chosen.begin(), chosen.end());
  EXPECT_EQ(chosen, (std::vector<std::string>{"delta_cx*omega1", "q"}));  // signals in name order
  for (const DictionaryTerm& t : s.terms) {
    // Least-squares std: 0.1 / sqrt(n var(term)) = 0.0047 (product, var 1/9) and
    // 0.0027 (q, var 1/3); 5 std.
    EXPECT_NEAR(t.coefficient, t.name == "q" ? -0.3 : 0.5, t.name == "q" ? 0.014 : 0.024) << t.name;
  }
  // The two terms explain all but the noise: 1 - 0.01 / (0.25 / 9 + 0.09 / 3 + 0.01).
  EXPECT_NEAR(s.explained, 1 - 0.01 / (0.25 / 9 + 0.03 + 0.01), 0.03);
  EXPECT_LT(s.criterion, s.criterion_none);
  EXPECT_NEAR(s.effective_samples, n, 0.15 * n);  // white noise left: n_eff ~ n
}

TEST(GenericDictionary, OffersNothingOnWhiteNoise) {
  // A chance term needs chi2(1) > ln n + 2 ln m (14.7 here, p ~ 1e-4 per
  // term, 0.4 % per search over 28 terms) and 1 % of the energy.
  for (unsigned seed = 10; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    const int n = 3000;
    JoinedResidual j = Signals(n, &rng);
    std::normal_distribution<double> noise(0, 1);
    for (double& r : j.residual) r = noise(rng);
    Eigen::MatrixXd d;
    std::vector<std::string> names;
    BuildDegreeTwoDictionary(j, &d, &names);
    const DictionarySearch s =
        SearchDictionary(Eigen::Map<const Eigen::VectorXd>(j.residual.data(), n), d, names);
    EXPECT_TRUE(s.terms.empty()) << "seed " << seed << ": " << s.terms.front().name;
  }
}

}  // namespace
}  // namespace coaxid
