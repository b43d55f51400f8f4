// Residual analysis of a fitted model, per output channel (effects.md, step 2):
// whiteness (autocorrelation and the Ljung-Box test with its p-value),
// cross-correlation with each input and (flight) each measured state, and a
// periodogram. Also the special functions behind the tests' p-values.
//
// Residuals are measured - model: for flight logs, model = the predictions of
// the fit (each segment / window started from its estimated state); for balance
// logs, the static model. A channel's residuals from several logs are joined
// end to end (the few lags that straddle a join are negligible).
#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ident/estimation_log.h"

namespace coaxid {

// Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a)
// (series for x < a + 1, Lentz continued fraction otherwise; Numerical Recipes
// sect. 6.2). Chi-square survival: Q(k / 2, x / 2).
double RegularizedGammaQ(double a, double x);
double ChiSquareSurvival(double x, double dof);
// Regularized incomplete beta I_x(a, b) (continued fraction, NR sect. 6.4).
double RegularizedBeta(double x, double a, double b);
// P(F > f) for F(d1, d2): I_{d2 / (d2 + d1 f)}(d2 / 2, d1 / 2).
double FSurvival(double f, double d1, double d2);

struct Correlation {
  std::string with;  // input or state name
  double r = 0;      // Pearson correlation with the residual
};

struct ChannelResidualTest {
  std::string channel;
  int count = 0;                      // finite residuals used
  double rms = 0;                     // rms of the residual
  double mean = 0;                    // its mean (an offset, which Ljung-Box does not see)
  double noise_std = 0;               // sample-to-sample noise estimate (robust first differences)
  std::vector<double> autocorrelation;  // lags 0..lags
  double ljung_box_q = 0;
  int ljung_box_lags = 0;
  double ljung_box_p = 1;             // chi-square(lags) survival of Q
  std::vector<Correlation> correlations;  // with every input and state, largest |r| first
  std::vector<double> frequency_hz, power;  // periodogram of the (decimated) residual
  double dominant_hz = 0;              // frequency of the periodogram's peak (excluding 0)
  nlohmann::json ToJson() const;
};

struct ResidualAnalysisOptions {
  int lags = 20;              // Ljung-Box lags (and autocorrelation length)
  int max_spectrum_samples = 2048;  // residual decimated to at most this many samples for the DFT
  int spectrum_bins = 64;
};

// residuals[i] = logs[i].values - model[i] (same shape). Channels by name, in
// the order of first appearance.
std::vector<ChannelResidualTest> AnalyseResiduals(const std::vector<EstimationLog>& logs,
                                                  const std::vector<Eigen::MatrixXd>& model,
                                                  const ResidualAnalysisOptions& options = {});

// The joined residual series of one channel (NaN rows dropped) and, aligned
// with it, the named regressors it is correlated against (inputs, states).
struct JoinedResidual {
  std::vector<double> residual, time;
  std::map<std::string, std::vector<double>> signals;
};
JoinedResidual JoinResidual(const std::vector<EstimationLog>& logs,
                            const std::vector<Eigen::MatrixXd>& model, const std::string& channel);

}  // namespace coaxid
