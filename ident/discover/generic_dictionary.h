// Step 7 of the closing loop (issue 6): when no named effect explains a
// structured residual, search a generic dictionary, every product of the
// inputs and measured states up to degree 2 (with the constant), by forward
// orthogonal least squares (FROLS; Billings, "Nonlinear System
// Identification", 2013, sect. 3.3), and offer the best terms as an unnamed
// candidate for the engineer to interpret. Never added to the model.
//
// FROLS: at step k every remaining term p_j is orthogonalised against the
// terms already chosen (Gram-Schmidt), w_j = p_j - sum_i (w_i^T p_j / w_i^T w_i) w_i,
// and the one with the largest error reduction ratio
//   ERR_j = (w_j^T y)^2 / ((w_j^T w_j) (y^T y))
// (the fraction of the residual's energy it explains) is taken. Terms are
// chosen greedily up to max_terms; the model size k is the one that
// minimises the extended BIC (Chen and Chen, Biometrika 2008, gamma = 1),
//   EBIC(k) = n_eff ln(RSS_k / n) + k (ln n_eff + 2 ln m),
// m the dictionary size (the 2 ln m pays for choosing among m terms, so
// white noise gives nothing: a chance term needs chi2(1) > ln n + 2 ln m),
// n_eff = n / (1 + 2 sum_l (1 - l / L) rho_l) the effective sample size of the
// largest model's residual (autocorrelation rho_l, Bartlett weights, L lags),
// so that a coloured residual is not counted as n independent samples. A
// term must also explain at least min_err of the residual's energy.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ident/discover/residual_analysis.h"

namespace coaxid {

struct DictionaryOptions {
  int max_terms = 6;        // greedy FROLS steps
  double min_err = 0.01;    // a term must explain >= this fraction of the residual energy
  int correlation_lags = 50;  // L of the effective sample size
  bool IsValid(std::string* why) const;
};

struct DictionaryTerm {
  std::string name;      // "1", "omega1", "omega1*delta_cx", "p^2", ...
  double coefficient = 0;  // in the residual's units per the term's units (least squares on the chosen terms)
  double err = 0;          // error reduction ratio when it was taken
};

struct DictionarySearch {
  std::string channel;
  int dictionary_size = 0;
  int samples = 0;
  double effective_samples = 0;
  std::vector<DictionaryTerm> terms;  // the chosen model (empty: nothing offered)
  double explained = 0;               // sum of the chosen terms' ERR
  double criterion_none = 0, criterion = 0;  // EBIC of the empty and of the chosen model
  nlohmann::json ToJson() const;
};

// FROLS of y on the columns of `dictionary` (named by `names`).
DictionarySearch SearchDictionary(const Eigen::VectorXd& y, const Eigen::MatrixXd& dictionary,
                                  const std::vector<std::string>& names,
                                  const DictionaryOptions& options = {});

// The degree-2 dictionary of a channel's joined residual (its inputs and
// states, residual_analysis.h): 1, every signal, every product of two
// signals (squares included).
void BuildDegreeTwoDictionary(const JoinedResidual& joined, Eigen::MatrixXd* dictionary,
                              std::vector<std::string>* names);

// Both, for one channel of a fit.
DictionarySearch SearchChannelDictionary(const std::vector<EstimationLog>& logs,
                                         const std::vector<Eigen::MatrixXd>& model,
                                         const std::string& channel,
                                         const DictionaryOptions& options = {});

}  // namespace coaxid
