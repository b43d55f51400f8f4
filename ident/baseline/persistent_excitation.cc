#include "ident/baseline/persistent_excitation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace coaxid {
namespace {

std::string Format(const char* format, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
}

// The O(N) witness search of Lemma 1 over holds (rows of a hold share their
// inputs): the longest vector is the reference, the vector least parallel to
// it the other witness.
// A sample with both rotors stopped (below stopped_speed) carries no
// information, and the sensor noise of a stopped rotor's speed would pass for
// a speed ratio: it takes no part in the conditions.
bool Turning(const InputVector& u, double stopped_speed) {
  return std::fabs(u[0]) >= stopped_speed || std::fabs(u[1]) >= stopped_speed;
}

WitnessPair FindWitness(const std::vector<const BalanceData*>& data, int channel,
                        double stopped_speed,
                        const std::function<std::array<double, 2>(const InputVector&)>& vec,
                        int* samples) {
  WitnessPair w;
  *samples = 0;
  int ref_i = -1, ref_h = -1;
  double ref_norm = 0;
  std::array<double, 2> ref{};
  for (int i = 0; i < static_cast<int>(data.size()); ++i) {
    for (int h = 0; h < data[i]->NumHolds(); ++h) {
      const BalanceHold& hold = data[i]->holds[h];
      if (hold.count[channel] == 0 || !Turning(hold.input, stopped_speed)) continue;
      const std::array<double, 2> v = vec(hold.input);
      const double norm = std::hypot(v[0], v[1]);
      if (!(norm > 0)) continue;
      *samples += hold.count[channel];
      if (norm > ref_norm) {
        ref_norm = norm;
        ref = v;
        ref_i = i;
        ref_h = h;
      }
    }
  }
  if (ref_i < 0) return w;
  for (int i = 0; i < static_cast<int>(data.size()); ++i) {
    for (int h = 0; h < data[i]->NumHolds(); ++h) {
      const BalanceHold& hold = data[i]->holds[h];
      if (hold.count[channel] == 0 || !Turning(hold.input, stopped_speed)) continue;
      const std::array<double, 2> v = vec(hold.input);
      const double norm = std::hypot(v[0], v[1]);
      if (!(norm > 0)) continue;
      const double sine = std::fabs(ref[0] * v[1] - ref[1] * v[0]) / (ref_norm * norm);
      if (sine > w.sine) {
        w.sine = sine;
        w.data_a = ref_i;
        w.row_a = data[ref_i]->holds[ref_h].first_row;
        w.data_b = i;
        w.row_b = hold.first_row;
      }
    }
  }
  return w;
}

void ComposeMessage(const ExcitationOptions& options, ExcitationReport* r) {
  std::vector<std::string> failures;
  if (!r->condition71) {
    failures.push_back(
        r->samples71 == 0
            ? "Lemma 1, condition (71)/(77) fails: no sample with Z measured and a rotor "
              "turning, so Cz_alpha and Cz_beta are not observed; log Z with the rotors turning"
            : "Lemma 1, condition (71)/(77) fails: omega1^2 and omega2^2 cos(delta_cx) "
              "cos(delta_cy) keep one ratio at every sample with Z (largest |sin| between "
              "samples " +
                  Format("%.2g", r->witness71.sine) +
                  " <= " + Format("%.2g", options.relative_tolerance) +
                  "), so X32 and X33 are proportional and Cz_alpha and Cz_beta cannot be told "
                  "apart; omega1 and omega2 must vary independently (their ratio must change)");
  }
  if (!r->condition72) {
    failures.push_back(
        r->samples72 == 0
            ? "Lemma 1, condition (72)/(79) fails: no sample with N measured and a rotor "
              "turning, so gamma1 and gamma2 are not observed; log N with the rotors turning"
            : "Lemma 1, condition (72)/(79) fails: omega1^2 / omega2^2 is the same at every "
              "sample with N (largest |sin| between samples " +
                  Format("%.2g", r->witness72.sine) +
                  " <= " + Format("%.2g", options.relative_tolerance) +
                  "), so X64 and X65 are proportional and gamma1 and gamma2 cannot be told "
                  "apart; omega1 and omega2 must vary independently (the ratio omega1/omega2 "
                  "must change)");
  }
  if (!r->swashplate) {
    failures.push_back(
        "the swashplate condition fails: at every sample with L or M measured and the lower "
        "rotor turning, |delta_cx| <= " +
        Format("%.3g", r->max_abs_delta_cx) +
        " rad and "
        "|delta_cy| <= " +
        Format("%.3g", r->max_abs_delta_cy) + " rad (threshold " +
        Format("%.3g", options.min_swashplate_angle) +
        " rad), so X41 = X51 = 0 and beta is seen only through Z, where X31 and X33 are "
        "collinear: beta and Cz_beta cannot be separated; delta_cx or delta_cy must vary with "
        "the lower rotor turning (and L, M be logged)");
  }
  if (r->information_computed && !r->well_conditioned) {
    std::string direction;
    for (int i = 0; i < kNumTheta; ++i) {
      if (std::fabs(r->weakest_direction[i]) < 0.05) continue;
      direction += (direction.empty() ? "" : " ") + Format("%+.2f", r->weakest_direction[i]) + " " +
                   ThetaName(i);
    }
    failures.push_back(
        "eq. (73) fails numerically: the scaled, noise-weighted sum X_k^T R^-1 X_k "
        "has condition number " +
        Format("%.3g", r->scaled_condition_number) + " > " +
        Format("%.3g", options.max_condition_number) +
        "; the weakest direction (in parameter scales) is " + direction +
        "; the inputs must vary more (longer holds or wider speed and angle "
        "ranges)");
  }
  if (failures.empty()) {
    r->message =
        "persistently exciting: Lemma 1 conditions (71) and (72) and the swashplate "
        "condition hold";
    if (r->information_computed) {
      r->message += ", and eq. (73) with epsilon = " + Format("%.4g", r->epsilon) +
                    ", mu = " + Format("%.4g", r->mu) +
                    " (scaled, noise-weighted condition "
                    "number " +
                    Format("%.3g", r->scaled_condition_number) + ")";
    }
    return;
  }
  r->message = "not exciting enough for the linear Kalman estimation: ";
  for (size_t i = 0; i < failures.size(); ++i) {
    r->message += (i == 0 ? "" : "; ") + failures[i];
  }
}

std::string Where(const std::vector<const BalanceData*>& data, int i, int row) {
  return data[i]->source + " row " + std::to_string(data[i]->first_log_row + row + 1);
}

}  // namespace

bool ExcitationOptions::IsValid(std::string* why) const {
  if (!(relative_tolerance >= 0 && relative_tolerance < 1)) {
    return *why = "relative_tolerance must lie in [0, 1)", false;
  }
  if (!(min_swashplate_angle >= 0)) return *why = "min_swashplate_angle must be >= 0", false;
  if (!(stopped_speed > 0)) return *why = "stopped_speed must be > 0", false;
  if (!(max_condition_number > 1)) return *why = "max_condition_number must be > 1", false;
  return true;
}

ExcitationReport CheckLemma1(const std::vector<const BalanceData*>& data,
                             const ExcitationOptions& options) {
  ExcitationReport r;
  r.witness71 = FindWitness(
      data, kLoadZ, options.stopped_speed,
      [](const InputVector& u) {
        return std::array<double, 2>{u[0] * u[0], u[1] * u[1] * std::cos(u[2]) * std::cos(u[3])};
      },
      &r.samples71);
  r.witness72 = FindWitness(
      data, kLoadN, options.stopped_speed,
      [](const InputVector& u) {
        return std::array<double, 2>{u[0] * u[0], u[1] * u[1]};
      },
      &r.samples72);
  r.witness71.found = r.witness71.sine > options.relative_tolerance;
  r.witness72.found = r.witness72.sine > options.relative_tolerance;
  r.condition71 = r.witness71.found;
  r.condition72 = r.witness72.found;

  for (const BalanceData* d : data) {
    for (const BalanceHold& hold : d->holds) {
      if (std::fabs(hold.input[1]) < options.stopped_speed) continue;
      int samples = 0;  // rows of this hold where X41 or X51 is nonzero and measured
      if (hold.count[kLoadL] > 0) {
        r.max_abs_delta_cx = std::max(r.max_abs_delta_cx, std::fabs(hold.input[2]));
        if (std::fabs(hold.input[2]) > options.min_swashplate_angle) samples = hold.count[kLoadL];
      }
      if (hold.count[kLoadM] > 0) {
        r.max_abs_delta_cy = std::max(r.max_abs_delta_cy, std::fabs(hold.input[3]));
        if (std::fabs(hold.input[3]) > options.min_swashplate_angle) {
          samples = std::max(samples, hold.count[kLoadM]);
        }
      }
      r.swashplate_samples += samples;
    }
  }
  r.swashplate = r.swashplate_samples > 0;
  ComposeMessage(options, &r);
  return r;
}

void AddInformationMatrix(const LinearBalanceModel& model,
                          const std::vector<WeightedBalanceData>& data, const ThetaVector& scale,
                          const ExcitationOptions& options, ExcitationReport* report) {
  ThetaMatrix raw = ThetaMatrix::Zero(), weighted = ThetaMatrix::Zero();
  for (const WeightedBalanceData& wd : data) {
    for (const BalanceHold& hold : wd.data->holds) {
      const LinearizedLoads lin = model.Linearize(hold.input);
      for (const int c : kEstimationChannels) {
        const int n = hold.count[c];
        if (n == 0) continue;
        const Eigen::Matrix<double, 1, kNumTheta> x = lin.X.row(c);
        raw += n * x.transpose() * x;
        if (wd.variance[c] > 0) {
          const Eigen::Matrix<double, 1, kNumTheta> xs = x.cwiseProduct(scale.transpose());
          weighted += (n / wd.variance[c]) * xs.transpose() * xs;
        }
      }
    }
  }
  const Eigen::SelfAdjointEigenSolver<ThetaMatrix> raw_eigen(raw, Eigen::EigenvaluesOnly);
  const Eigen::SelfAdjointEigenSolver<ThetaMatrix> weighted_eigen(weighted);
  report->information_computed = true;
  report->eigenvalues = raw_eigen.eigenvalues();
  report->epsilon = report->eigenvalues[0];
  report->mu = report->eigenvalues[kNumTheta - 1];
  report->condition_number =
      report->epsilon > 0 ? report->mu / report->epsilon : std::numeric_limits<double>::infinity();
  report->scaled_eigenvalues = weighted_eigen.eigenvalues();
  report->weakest_direction = weighted_eigen.eigenvectors().col(0);
  const double lo = report->scaled_eigenvalues[0], hi = report->scaled_eigenvalues[kNumTheta - 1];
  report->scaled_condition_number = lo > 0 ? hi / lo : std::numeric_limits<double>::infinity();
  report->well_conditioned =
      lo > 0 && report->scaled_condition_number <= options.max_condition_number;
  ComposeMessage(options, report);
}

std::string ExcitationText(const ExcitationReport& r, const std::vector<const BalanceData*>& data) {
  std::string s = "linear_kf excitation (paper, Lemma 1 and eqs. 73-74):\n";
  auto condition = [&](const char* name, bool ok, const WitnessPair& w, int samples) {
    s += std::string("  condition ") + name + ": " + (ok ? "holds" : "FAILS");
    if (samples == 0) {
      s += " (no sample with the output measured and a rotor turning)\n";
    } else if (w.data_a >= 0) {
      s += " (" + std::to_string(samples) + " samples; " + (ok ? "witness " : "most different ") +
           Where(data, w.data_a, w.row_a) + " and " + Where(data, w.data_b, w.row_b) +
           ", |sin| = " + Format("%.3g", w.sine) + ")\n";
    } else {
      s += "\n";
    }
  };
  condition("(71) Cz_alpha vs Cz_beta", r.condition71, r.witness71, r.samples71);
  condition("(72) gamma1 vs gamma2", r.condition72, r.witness72, r.samples72);
  s += std::string("  swashplate (X41, X51 nonzero: beta vs Cz_beta): ") +
       (r.swashplate ? "holds" : "FAILS") + " (" + std::to_string(r.swashplate_samples) +
       " samples; max |delta_cx| = " + Format("%.3g", r.max_abs_delta_cx) +
       " rad, max |delta_cy| = " + Format("%.3g", r.max_abs_delta_cy) + " rad)\n";
  if (r.information_computed) {
    s += "  sum X_k^T X_k (eq. 74): epsilon = " + Format("%.4g", r.epsilon) +
         ", mu = " + Format("%.4g", r.mu) +
         ", condition number = " + Format("%.4g", r.condition_number) + "\n";
    s += "  scaled, noise-weighted: eigenvalues " + Format("%.3g", r.scaled_eigenvalues[0]) +
         " .. " + Format("%.3g", r.scaled_eigenvalues[kNumTheta - 1]) +
         ", condition number = " + Format("%.4g", r.scaled_condition_number) + "\n";
  }
  s += "  verdict: " + r.message + "\n";
  return s;
}

}  // namespace coaxid
