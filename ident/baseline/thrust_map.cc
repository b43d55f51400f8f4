#include "ident/baseline/thrust_map.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.h"

namespace coaxid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Grid lines from speeds: sorted, runs closer than `merge` averaged into one.
std::vector<double> GridLines(std::vector<double> speeds, double merge) {
  std::sort(speeds.begin(), speeds.end());
  std::vector<double> grid;
  size_t start = 0;
  for (size_t i = 1; i <= speeds.size(); ++i) {
    if (i == speeds.size() || speeds[i] - speeds[i - 1] >= merge) {
      double sum = 0;
      for (size_t j = start; j < i; ++j) sum += speeds[j];
      grid.push_back(sum / static_cast<double>(i - start));
      start = i;
    }
  }
  // The table interpolates between two lines at least; a single speed gets a
  // second line just above it with the same values (the table clamps anyway).
  if (grid.size() == 1) grid.push_back(grid[0] + std::max(1.0, 0.1 * std::fabs(grid[0])));
  return grid;
}

int Nearest(const std::vector<double>& grid, double w) {
  int best = 0;
  for (int i = 1; i < static_cast<int>(grid.size()); ++i) {
    if (std::fabs(grid[i] - w) < std::fabs(grid[best] - w)) best = i;
  }
  return best;
}

// Least squares through the origin on hold means, row level: Z_k = coef * a_h
// for every sample k of hold h. Returns coef; *variance is the residual
// variance per sample, *coef_variance the coefficient's.
struct OriginFit {
  double coef = kNaN, coef_variance = kNaN, residual_variance = kNaN, sum_weight = 0;
  double sum_squares = 0;
  int samples = 0, holds = 0;
};

OriginFit FitThroughOrigin(const std::vector<const MapHold*>& holds,
                           const std::vector<double>& regressor,
                           const std::vector<double>& within_squares) {
  OriginFit fit;
  double saz = 0, saa = 0;
  for (size_t i = 0; i < holds.size(); ++i) {
    saz += holds[i]->count * regressor[i] * holds[i]->Z;
    saa += holds[i]->count * regressor[i] * regressor[i];
    fit.samples += holds[i]->count;
  }
  fit.holds = static_cast<int>(holds.size());
  fit.sum_weight = saa;
  if (!(saa > 0)) return fit;
  fit.coef = saz / saa;
  double ss = 0;
  for (size_t i = 0; i < holds.size(); ++i) {
    const double r = holds[i]->Z - fit.coef * regressor[i];
    ss += within_squares[i] + holds[i]->count * r * r;
  }
  fit.sum_squares = ss;
  if (fit.samples >= 2) {
    fit.residual_variance = ss / (fit.samples - 1);
    fit.coef_variance = fit.residual_variance / saa;
  }
  return fit;
}

// sigma0 by least squares on the Z scale: Z_h - A_h = -sigma0 A_h g_h over the
// coaxial holds (A_h = (alpha w1 + beta w2)(1 - Cz k), g the shape), weighted
// by sample counts.
double FitSigma0(const std::vector<const MapHold*>& coaxial, double alpha, double beta,
                 double factor) {
  double num = 0, den = 0;
  for (const MapHold* h : coaxial) {
    const double w1 = h->omega1 * h->omega1, w2 = h->omega2 * h->omega2;
    const double A = (alpha * w1 + beta * w2) * factor;
    const double Ag = A * InterferenceShape(h->omega1, h->omega2);
    num += -h->count * Ag * (h->Z - A);
    den += h->count * Ag * Ag;
  }
  return num / den;
}

}  // namespace

bool ThrustMapOptions::IsValid(std::string* why) const {
  if (!(zero_angle >= 0)) return *why = "zero_angle must be >= 0", false;
  if (!(stopped_speed > 0)) return *why = "stopped_speed must be > 0", false;
  if (!(grid_merge >= 0)) return *why = "grid_merge must be >= 0", false;
  return true;
}

const char* MapHoldRoleName(MapHoldRole role) {
  switch (role) {
    case MapHoldRole::kStopped:
      return "stopped";
    case MapHoldRole::kUpperOnly:
      return "upper_only";
    case MapHoldRole::kLowerOnly:
      return "lower_only";
    case MapHoldRole::kCoaxial:
      return "coaxial";
  }
  return "";
}

const char* SigmaCellSourceName(SigmaCellSource source) {
  switch (source) {
    case SigmaCellSource::kStopped:
      return "stopped";
    case SigmaCellSource::kMeasured:
      return "measured";
    case SigmaCellSource::kParametric:
      return "parametric_fill";
  }
  return "";
}

double InterferenceShape(double omega1, double omega2) {
  const double w1 = omega1 * omega1, w2 = omega2 * omega2;
  const double sum = w1 + w2;
  return sum > 0 ? 4 * w1 * w2 / (sum * sum) : 0.0;
}

ThrustMap FitThrustMap(const std::vector<BalanceData>& data, double Cz, double area_ratio,
                       const ThrustMapOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("thrust map options: " + why);
  ThrustMap map;
  map.Cz = Cz;
  map.area_ratio = area_ratio;
  map.thrust_factor = 1 - Cz * area_ratio;
  const double f = map.thrust_factor;
  if (!(f > 0)) {
    throw InputError("thrust map: 1 - Cz S_s / S_prop = " + std::to_string(f) +
                     " is not positive (Cz or the body/rotor radii in the config are wrong)");
  }

  // 1. The delta = 0 holds with a measured Z, by role.
  for (int i = 0; i < static_cast<int>(data.size()); ++i) {
    for (int h = 0; h < data[i].NumHolds(); ++h) {
      const BalanceHold& hold = data[i].holds[h];
      if (std::fabs(hold.input[2]) > options.zero_angle ||
          std::fabs(hold.input[3]) > options.zero_angle || hold.count[kLoadZ] == 0) {
        continue;
      }
      MapHold m;
      m.data_index = i;
      m.hold_index = h;
      m.omega1 = hold.input[0];
      m.omega2 = hold.input[1];
      m.Z = hold.mean[kLoadZ];
      m.count = hold.count[kLoadZ];
      m.Z_std = m.count >= 2 ? std::sqrt(hold.sum_squares[kLoadZ] / (m.count - 1)) : kNaN;
      const bool upper = std::fabs(m.omega1) >= options.stopped_speed;
      const bool lower = std::fabs(m.omega2) >= options.stopped_speed;
      m.role = upper && lower ? MapHoldRole::kCoaxial
               : upper        ? MapHoldRole::kUpperOnly
               : lower        ? MapHoldRole::kLowerOnly
                              : MapHoldRole::kStopped;
      m.sigma = m.sigma_std = kNaN;
      map.holds.push_back(m);
    }
  }
  auto within = [&](const MapHold& m) {
    return data[m.data_index].holds[m.hold_index].sum_squares[kLoadZ];
  };
  // Indices into map.holds by role (map.holds does not grow from here on).
  std::vector<int> upper_index, lower_index, coaxial_index;
  for (int i = 0; i < static_cast<int>(map.holds.size()); ++i) {
    const MapHoldRole role = map.holds[i].role;
    if (role == MapHoldRole::kUpperOnly) upper_index.push_back(i);
    if (role == MapHoldRole::kLowerOnly) lower_index.push_back(i);
    if (role == MapHoldRole::kCoaxial) coaxial_index.push_back(i);
  }
  auto pointers = [&](const std::vector<int>& index) {
    std::vector<const MapHold*> out;
    for (int i : index) out.push_back(&map.holds[i]);
    return out;
  };
  const std::vector<const MapHold*> upper = pointers(upper_index);
  const std::vector<const MapHold*> lower = pointers(lower_index);
  const std::vector<const MapHold*> coaxial = pointers(coaxial_index);
  if (upper.empty() || lower.empty()) {
    throw InputError(std::string("thrust map (paper, Fig. 8): no hold with delta_cx = delta_cy = 0 "
                                 "and only the ") +
                     (upper.empty() ? "upper rotor (omega1)" : "lower rotor (omega2)") +
                     " turning: alpha and beta come from single-rotor runs (sigma = 1); the logs "
                     "need such holds");
  }
  if (coaxial.empty()) {
    throw InputError(
        "sigma map (paper, Fig. 9): no hold with delta_cx = delta_cy = 0 and both rotors "
        "turning: the interference loss sigma cannot be mapped");
  }

  // 2. alpha and beta from the single-rotor holds.
  auto fit_single = [&](const std::vector<const MapHold*>& holds, bool is_upper) {
    std::vector<double> a, ss;
    for (const MapHold* m : holds) {
      const double omega = is_upper ? m->omega1 : m->omega2;
      a.push_back(omega * omega * f);
      ss.push_back(within(*m));
    }
    return FitThroughOrigin(holds, a, ss);
  };
  const OriginFit alpha_fit = fit_single(upper, true);
  const OriginFit beta_fit = fit_single(lower, false);
  map.alpha = alpha_fit.coef;
  map.alpha_std = std::sqrt(alpha_fit.coef_variance);
  map.alpha_holds = alpha_fit.holds;
  map.alpha_samples = alpha_fit.samples;
  map.beta = beta_fit.coef;
  map.beta_std = std::sqrt(beta_fit.coef_variance);
  map.beta_holds = beta_fit.holds;
  map.beta_samples = beta_fit.samples;
  for (const auto& [name, value] : {std::pair<const char*, double>{"alpha", map.alpha},
                                    std::pair<const char*, double>{"beta", map.beta}}) {
    if (!(value < 0)) {
      throw InputError(std::string("thrust map: ") + name + " = " + std::to_string(value) +
                       " from the single-rotor holds is not negative: thrust is along -z_b, so Z "
                       "must be negative (check the sign convention of the Z column)");
    }
  }
  const int single_samples = alpha_fit.samples + beta_fit.samples;
  map.z_residual_variance =
      single_samples > 2 ? (alpha_fit.sum_squares + beta_fit.sum_squares) / (single_samples - 2)
                         : kNaN;
  const double var_alpha = alpha_fit.coef_variance, var_beta = beta_fit.coef_variance;
  for (int i : upper_index) {
    MapHold& m = map.holds[i];
    m.d_dZ = m.count * m.omega1 * m.omega1 * f / alpha_fit.sum_weight;
  }
  for (int i : lower_index) {
    MapHold& m = map.holds[i];
    m.d_dZ = m.count * m.omega2 * m.omega2 * f / beta_fit.sum_weight;
  }

  // 3. sigma at each coaxial hold, with its standard deviation (noise of the
  // hold mean, plus alpha's and beta's uncertainty to first order).
  const double noise_var = std::isfinite(map.z_residual_variance) ? map.z_residual_variance : 0.0;
  for (int i : coaxial_index) {
    MapHold& m = map.holds[i];
    const double w1 = m.omega1 * m.omega1, w2 = m.omega2 * m.omega2;
    const double A = (map.alpha * w1 + map.beta * w2) * f;
    m.sigma = m.Z / A;
    const double ds_da = -m.sigma * w1 * f / A, ds_db = -m.sigma * w2 * f / A;
    double var = noise_var / (m.count * A * A);
    if (std::isfinite(var_alpha)) var += ds_da * ds_da * var_alpha;
    if (std::isfinite(var_beta)) var += ds_db * ds_db * var_beta;
    m.sigma_std = std::sqrt(var);
  }

  // 4. Parametric fit of sigma0 (Z scale); std from the residual variance
  // plus alpha's and beta's uncertainty (central differences of the closed form).
  map.sigma0 = FitSigma0(coaxial, map.alpha, map.beta, f);
  {
    double ss = 0, den = 0, sum_sq_sigma = 0;
    int samples = 0;
    for (int i : coaxial_index) {
      MapHold& m = map.holds[i];
      const double w1 = m.omega1 * m.omega1, w2 = m.omega2 * m.omega2;
      const double A = (map.alpha * w1 + map.beta * w2) * f;
      const double g = InterferenceShape(m.omega1, m.omega2);
      const double r = m.Z - A * (1 - map.sigma0 * g);
      ss += within(m) + m.count * r * r;
      den += m.count * A * A * g * g;
      samples += m.count;
      const double ds = m.sigma - (1 - map.sigma0 * g);
      sum_sq_sigma += ds * ds;
      m.dsigma0_dZ = -m.count * A * g;  // divided by den below
    }
    for (int i : coaxial_index) map.holds[i].dsigma0_dZ /= den;
    map.sigma_fit_rms = std::sqrt(sum_sq_sigma / coaxial.size());
    const double h_alpha = 1e-6 * std::fabs(map.alpha), h_beta = 1e-6 * std::fabs(map.beta);
    map.dsigma0_dalpha = (FitSigma0(coaxial, map.alpha + h_alpha, map.beta, f) -
                          FitSigma0(coaxial, map.alpha - h_alpha, map.beta, f)) /
                         (2 * h_alpha);
    map.dsigma0_dbeta = (FitSigma0(coaxial, map.alpha, map.beta + h_beta, f) -
                         FitSigma0(coaxial, map.alpha, map.beta - h_beta, f)) /
                        (2 * h_beta);
    double var = samples >= 2 ? ss / (samples - 1) / den : kNaN;
    if (std::isfinite(var_alpha)) var += map.dsigma0_dalpha * map.dsigma0_dalpha * var_alpha;
    if (std::isfinite(var_beta)) var += map.dsigma0_dbeta * map.dsigma0_dbeta * var_beta;
    map.sigma0_std = std::sqrt(var);
  }

  // 5. The table over the distinct speeds of the delta = 0 holds.
  std::vector<double> speeds1, speeds2;
  for (const MapHold& m : map.holds) {
    speeds1.push_back(m.omega1);
    speeds2.push_back(m.omega2);
  }
  SigmaTable& table = map.table;
  table.omega1 = GridLines(speeds1, options.grid_merge);
  table.omega2 = GridLines(speeds2, options.grid_merge);
  const int n1 = static_cast<int>(table.omega1.size()), n2 = static_cast<int>(table.omega2.size());
  const int cells = n1 * n2;
  table.sigma.assign(cells, 0.0);
  map.cell_source.assign(cells, SigmaCellSource::kParametric);
  map.cell_std.assign(cells, 0.0);
  map.dcell_dalpha.assign(cells, 0.0);
  map.dcell_dbeta.assign(cells, 0.0);
  map.dcell_dsigma0.assign(cells, 0.0);
  std::vector<double> cell_count(cells, 0.0), cell_var(cells, 0.0);
  for (int i : coaxial_index) {
    MapHold& m = map.holds[i];
    m.cell = Nearest(table.omega1, m.omega1) * n2 + Nearest(table.omega2, m.omega2);
    cell_count[m.cell] += m.count;
  }
  for (int i : coaxial_index) {
    MapHold& m = map.holds[i];
    const double w1 = m.omega1 * m.omega1, w2 = m.omega2 * m.omega2;
    const double A = (map.alpha * w1 + map.beta * w2) * f;
    const double share = m.count / cell_count[m.cell];
    table.sigma[m.cell] += share * m.sigma;
    // Hold sigmas share alpha's and beta's errors, so this variance (noise
    // parts only add independently) is approximate; the sensitivities below
    // are exact to first order.
    cell_var[m.cell] += share * share * m.sigma_std * m.sigma_std;
    map.dcell_dalpha[m.cell] += share * (-m.sigma * w1 * f / A);
    map.dcell_dbeta[m.cell] += share * (-m.sigma * w2 * f / A);
    m.d_dZ = share / A;
    map.cell_source[m.cell] = SigmaCellSource::kMeasured;
  }
  for (int i = 0; i < n1; ++i) {
    for (int j = 0; j < n2; ++j) {
      const int c = i * n2 + j;
      if (std::fabs(table.omega1[i]) < options.stopped_speed ||
          std::fabs(table.omega2[j]) < options.stopped_speed) {
        // sigma = 1 where a rotor is stopped (paper, sect. 4).
        map.cell_source[c] = SigmaCellSource::kStopped;
        table.sigma[c] = 1.0;
        map.dcell_dalpha[c] = map.dcell_dbeta[c] = 0;
      } else if (map.cell_source[c] == SigmaCellSource::kMeasured) {
        ++map.measured_cells;
        map.cell_std[c] = std::sqrt(cell_var[c]);
      } else {
        const double g = InterferenceShape(table.omega1[i], table.omega2[j]);
        table.sigma[c] = 1 - map.sigma0 * g;
        map.cell_std[c] = g * map.sigma0_std;
        map.dcell_dsigma0[c] = -g;
        ++map.filled_cells;
      }
    }
  }

  // 6. Where the loss is largest (measured holds).
  map.max_loss = -std::numeric_limits<double>::infinity();
  for (const MapHold* m : coaxial) {
    if (1 - m->sigma > map.max_loss) {
      map.max_loss = 1 - m->sigma;
      map.max_loss_omega1 = m->omega1;
      map.max_loss_omega2 = m->omega2;
    }
  }

  // 7. The thrust map points (Fig. 8): holds pooled per grid speed pair.
  std::map<std::pair<int, int>, ThrustMapPoint> points;
  for (const MapHold& m : map.holds) {
    const std::pair<int, int> key(Nearest(table.omega1, m.omega1), Nearest(table.omega2, m.omega2));
    ThrustMapPoint& p = points[key];
    p.omega1 = table.omega1[key.first];
    p.omega2 = table.omega2[key.second];
    p.Z = (p.Z * p.samples + m.Z * m.count) / (p.samples + m.count);
    p.samples += m.count;
    ++p.holds;
    p.role = m.role;
  }
  for (const auto& [key, p] : points) map.points.push_back(p);
  return map;
}

}  // namespace coaxid
