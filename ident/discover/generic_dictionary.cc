#include "ident/discover/generic_dictionary.h"

#include <algorithm>
#include <cmath>

#include <Eigen/QR>
#include <glog/logging.h>

namespace coaxid {
namespace {

// n / (1 + 2 sum_{l=1..L} (1 - l / L) rho_l), within [1, n].
double EffectiveSamples(const Eigen::VectorXd& e, int lags) {
  const int n = static_cast<int>(e.size());
  const Eigen::VectorXd c = e.array() - e.mean();
  const double c0 = c.squaredNorm();
  if (!(c0 > 0)) return n;
  const int L = std::min(lags, n / 4);
  double sum = 0;
  for (int l = 1; l <= L; ++l) {
    const double rho = c.head(n - l).dot(c.tail(n - l)) / c0;
    sum += (1.0 - static_cast<double>(l) / (L + 1)) * rho;
  }
  return std::clamp(n / (1 + 2 * sum), 1.0, static_cast<double>(n));
}

}  // namespace

bool DictionaryOptions::IsValid(std::string* why) const {
  if (max_terms < 1) {
    *why = "max_terms must be >= 1";
    return false;
  }
  if (!(min_err >= 0 && min_err < 1)) {
    *why = "min_err must be in [0, 1)";
    return false;
  }
  if (correlation_lags < 0) {
    *why = "correlation_lags must be >= 0";
    return false;
  }
  return true;
}

nlohmann::json DictionarySearch::ToJson() const {
  nlohmann::json terms_json = nlohmann::json::array();
  for (const DictionaryTerm& t : terms) {
    terms_json.push_back({{"term", t.name}, {"coefficient", t.coefficient}, {"err", t.err}});
  }
  return {{"channel", channel},
          {"what", "unnamed candidate for the engineer to interpret (never added to the model)"},
          {"method",
           "FROLS over products of inputs and states up to degree 2, extended BIC with the "
           "effective sample size"},
          {"dictionary_size", dictionary_size},
          {"samples", samples},
          {"effective_samples", effective_samples},
          {"terms", terms_json},
          {"explained_fraction", explained},
          {"criterion_without", criterion_none},
          {"criterion_with", criterion}};
}

DictionarySearch SearchDictionary(const Eigen::VectorXd& y, const Eigen::MatrixXd& dictionary,
                                  const std::vector<std::string>& names,
                                  const DictionaryOptions& options) {
  CHECK_EQ(dictionary.rows(), y.size());
  CHECK_EQ(static_cast<size_t>(dictionary.cols()), names.size());
  DictionarySearch out;
  const int n = static_cast<int>(y.size());
  const int m = static_cast<int>(dictionary.cols());
  out.dictionary_size = m;
  out.samples = n;
  const double yy = y.squaredNorm();
  if (n < 4 || m == 0 || !(yy > 0)) return out;

  // Greedy FROLS: W holds the remaining terms, orthogonalised against the chosen ones.
  Eigen::MatrixXd W = dictionary;
  std::vector<bool> taken(m, false);
  std::vector<int> chosen;
  std::vector<double> errs;
  Eigen::VectorXd e = y;
  std::vector<double> rss = {yy};
  const int steps = std::min({options.max_terms, m, n - 2});
  for (int step = 0; step < steps; ++step) {
    int best = -1;
    double best_err = 0;
    for (int j = 0; j < m; ++j) {
      if (taken[j]) continue;
      const double ww = W.col(j).squaredNorm();
      // A term (nearly) in the span of the chosen ones adds nothing.
      if (!(ww > 1e-10 * dictionary.col(j).squaredNorm()) || !(ww > 0)) continue;
      const double wy = W.col(j).dot(y);
      const double err = wy * wy / (ww * yy);
      if (err > best_err) {
        best_err = err;
        best = j;
      }
    }
    if (best < 0 || best_err < options.min_err) break;
    taken[best] = true;
    chosen.push_back(best);
    errs.push_back(best_err);
    const Eigen::VectorXd w = W.col(best);
    const double ww = w.squaredNorm();
    e -= (w.dot(y) / ww) * w;
    rss.push_back(std::max(e.squaredNorm(), 1e-300));
    for (int j = 0; j < m; ++j) {
      if (!taken[j]) W.col(j) -= (w.dot(W.col(j)) / ww) * w;
    }
  }
  // The model size by the extended BIC, with the largest model's effective samples.
  out.effective_samples = EffectiveSamples(e, options.correlation_lags);
  const double n_eff = out.effective_samples;
  auto criterion = [&](int k) {
    return n_eff * std::log(rss[k] / n) + k * (std::log(n_eff) + 2 * std::log(m));
  };
  int k_best = 0;
  for (int k = 1; k < static_cast<int>(rss.size()); ++k) {
    if (criterion(k) < criterion(k_best)) k_best = k;
  }
  out.criterion_none = criterion(0);
  out.criterion = criterion(k_best);
  if (k_best == 0) return out;
  // Coefficients of the chosen terms: least squares in the original terms.
  Eigen::MatrixXd P(n, k_best);
  for (int k = 0; k < k_best; ++k) P.col(k) = dictionary.col(chosen[k]);
  const Eigen::VectorXd coefficients = P.colPivHouseholderQr().solve(y);
  for (int k = 0; k < k_best; ++k) {
    out.terms.push_back({names[chosen[k]], coefficients[k], errs[k]});
    out.explained += errs[k];
  }
  return out;
}

void BuildDegreeTwoDictionary(const JoinedResidual& joined, Eigen::MatrixXd* dictionary,
                              std::vector<std::string>* names) {
  const int n = static_cast<int>(joined.residual.size());
  std::vector<std::string> signal_names;
  std::vector<const std::vector<double>*> signals;
  for (const auto& [name, values] : joined.signals) {
    signal_names.push_back(name);
    signals.push_back(&values);
  }
  const int s = static_cast<int>(signals.size());
  const int m = 1 + s + s * (s + 1) / 2;
  dictionary->resize(n, m);
  names->clear();
  dictionary->col(0).setOnes();
  names->push_back("1");
  for (int a = 0; a < s; ++a) {
    dictionary->col(names->size()) = Eigen::Map<const Eigen::VectorXd>(signals[a]->data(), n);
    names->push_back(signal_names[a]);
  }
  for (int a = 0; a < s; ++a) {
    for (int b = a; b < s; ++b) {
      const Eigen::Map<const Eigen::VectorXd> x(signals[a]->data(), n), z(signals[b]->data(), n);
      dictionary->col(names->size()) = x.cwiseProduct(z);
      names->push_back(a == b ? signal_names[a] + "^2" : signal_names[a] + "*" + signal_names[b]);
    }
  }
}

DictionarySearch SearchChannelDictionary(const std::vector<EstimationLog>& logs,
                                         const std::vector<Eigen::MatrixXd>& model,
                                         const std::string& channel,
                                         const DictionaryOptions& options) {
  const JoinedResidual joined = JoinResidual(logs, model, channel);
  Eigen::MatrixXd dictionary;
  std::vector<std::string> names;
  BuildDegreeTwoDictionary(joined, &dictionary, &names);
  const Eigen::VectorXd y =
      Eigen::Map<const Eigen::VectorXd>(joined.residual.data(), joined.residual.size());
  DictionarySearch out = SearchDictionary(y, dictionary, names, options);
  out.channel = channel;
  return out;
}

}  // namespace coaxid
