// Persistent excitation of the linear balance model (paper, Lemma 1 and
// eqs. 71-79, 73-74), checked before the Kalman filter runs.
//
// Lemma 1. With w = omega^2 and c = cos(delta_cx) cos(delta_cy), the model is
// identifiable if there are samples xi != zeta and lambda != nu with
//     w1(xi) w2(zeta) c(zeta) != w1(zeta) w2(xi) c(xi)         (71, 77)
//     w1(lambda) w2(nu)       != w1(nu) w2(lambda)              (72, 79)
// i.e. the vectors (w1, w2 c) of the samples with Z measured are not all
// parallel (then X32 and X33 are independent: Cz_alpha and Cz_beta separate),
// and the vectors (w1, w2) of the samples with N are not all parallel
// (X64, X65: gamma1 and gamma2 separate). The search is O(N): take the
// longest vector as reference; the condition holds if and only if some vector
// is not parallel to it, and that pair is the witness. "Not parallel" means
// |sin(angle)| > relative_tolerance, so that round-off and sensor noise on a
// fixed speed ratio do not pass for excitation; samples with both rotors
// stopped (below stopped_speed) take no part.
//
// The paper's proof takes the beta row of Y^T as independent of the others.
// Because X31 and X33 are exactly collinear, it is so only through L and M:
// the swashplate condition requires X41 = -d sin(delta_cx) w2 or
// X51 = d sin(delta_cy) cos(delta_cx) w2 to be nonzero at a sample where L
// (resp. M) is measured: |delta| above min_swashplate_angle with the lower
// rotor turning.
//
// Eq. 73-74: eps I <= sum_k X_k^T X_k <= mu I. Reported as the paper writes
// it (the rows Z_bar, L, M, N of X_k, unweighted: epsilon, mu and mu/epsilon,
// whose size mixes the units of the parameters), and as the scaled,
// noise-weighted information matrix sum_k S X_k^T R^-1 X_k S (S = diag of the
// parameter scales), whose condition number decides numerical identifiability.
#pragma once

#include <string>
#include <vector>

#include "ident/baseline/balance_holds.h"
#include "ident/baseline/linear_balance_model.h"

namespace coaxid {

struct ExcitationOptions {
  double relative_tolerance = 1e-3;    // |sin(angle)| above which two samples differ (71-72)
  double min_swashplate_angle = 1e-3;  // rad: smaller angles count as no swashplate motion
  double stopped_speed = 1.0;          // rad/s: a slower rotor is stopped
  double max_condition_number = 1e10;  // of the scaled, noise-weighted information matrix
  bool IsValid(std::string* why) const;
};

// Two samples that satisfy a condition: (data set, row) each.
struct WitnessPair {
  bool found = false;
  int data_a = -1, row_a = -1, data_b = -1, row_b = -1;
  double sine = 0;  // |sin(angle)| between their vectors (the largest found)
};

struct ExcitationReport {
  // Lemma 1 (eqs. 71/77 and 72/79) and the swashplate condition.
  bool condition71 = false, condition72 = false, swashplate = false;
  WitnessPair witness71, witness72;
  int samples71 = 0, samples72 = 0;  // samples with Z (resp. N) and a nonzero vector
  int swashplate_samples = 0;        // samples where X41 or X51 is nonzero and measured
  double max_abs_delta_cx = 0,
         max_abs_delta_cy = 0;  // over samples with L / M and the lower rotor turning

  // Eqs. 73-74 (when computed).
  bool information_computed = false;
  ThetaVector eigenvalues = ThetaVector::Zero();  // of sum X_k^T X_k, ascending
  double epsilon = 0, mu = 0, condition_number = 0;
  ThetaVector scaled_eigenvalues = ThetaVector::Zero();  // scaled, noise-weighted, ascending
  ThetaVector weakest_direction = ThetaVector::Zero();   // its eigenvector (scaled parameters)
  double scaled_condition_number = 0;
  bool well_conditioned = false;

  bool Exciting() const {
    return condition71 && condition72 && swashplate && (!information_computed || well_conditioned);
  }
  // One paragraph: the verdict, and for each failing condition what it means
  // and which inputs must vary.
  std::string message;
};

// Lemma 1 and the swashplate condition over the data sets (no model needed:
// sigma and d cancel from the conditions).
ExcitationReport CheckLemma1(const std::vector<const BalanceData*>& data,
                             const ExcitationOptions& options = {});

// Adds eqs. 73-74 (needs the model for X_k, the noise variances and the
// parameter scales for the weighted condition number) and recomposes the message.
void AddInformationMatrix(const LinearBalanceModel& model,
                          const std::vector<WeightedBalanceData>& data, const ThetaVector& scale,
                          const ExcitationOptions& options, ExcitationReport* report);

// A few lines for people (coaxid check): each condition with its witness, the
// eigenvalues, the verdict.
std::string ExcitationText(const ExcitationReport& report,
                           const std::vector<const BalanceData*>& data);

}  // namespace coaxid
