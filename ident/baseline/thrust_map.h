// The coaxial-rotor thrust map and the interference-loss map (paper, sect. 4
// and Figs. 8-9), from the holds with zero swashplate angles.
//
// Thrust coefficients. With delta = 0 and one rotor stopped, sigma = 1 and
// eq. 63 reduces to
//     Z = alpha (1 - Cz k) omega1^2   (upper rotor alone)
//     Z = beta  (1 - Cz k) omega2^2   (lower rotor alone),   k = S_s / S_prop,
// so alpha and beta follow by least squares through the origin, Cz being
// assumed known: the paper takes it "from the literature" [22], the project
// from the vehicle config. A wrong Cz scales both by (1 - Cz_true k) /
// (1 - Cz k), under 1 % for Cz within +-0.5 here.
//
// Interference loss. At each coaxial hold with delta = 0 (both rotors turning)
//     sigma = Z / ((alpha omega1^2 + beta omega2^2) (1 - Cz k)),
// which is the paper's map (Fig. 9); sigma = 1 where a rotor is stopped. The
// map is kept as a SigmaTable over the distinct speeds (bilinear), and fitted
// by least squares (on the Z scale) to model.md's parametric form
//     sigma = 1 - sigma0 * 4 w1 w2 / (w1 + w2)^2,  w = omega^2.
// Grid cells with no coaxial hold are filled from that fit, and counted.
//
// Standard deviations come from the residual variance of each fit (row level:
// within-hold scatter plus misfit of the hold means); sigma's and sigma0's add
// the propagated uncertainty of alpha and beta. The derivatives of alpha, beta
// and every table cell with respect to each hold's mean Z are kept, so that
// later steps can propagate the map's uncertainty to first order.
#pragma once

#include <string>
#include <vector>

#include "core/vehicle_config.h"
#include "ident/baseline/balance_holds.h"

namespace coaxid {

struct ThrustMapOptions {
  double zero_angle = 1e-6;    // rad: |delta_cx| and |delta_cy| at most this count as delta = 0
  double stopped_speed = 1.0;  // rad/s: a rotor slower than this is stopped
  double grid_merge = 1.0;     // rad/s: hold speeds closer than this share a grid line of the map
  bool IsValid(std::string* why) const;
};

enum class MapHoldRole { kStopped, kUpperOnly, kLowerOnly, kCoaxial };
const char* MapHoldRoleName(MapHoldRole role);  // "stopped", "upper_only", "lower_only", "coaxial"

// One hold with delta = 0 and a measured Z.
struct MapHold {
  int data_index = 0;  // which BalanceData
  int hold_index = 0;  // which hold of it
  MapHoldRole role = MapHoldRole::kStopped;
  double omega1 = 0, omega2 = 0;    // rad/s
  double Z = 0;                     // mean Z over the hold [N]
  int count = 0;                    // samples of Z
  double Z_std = 0;                 // within-hold standard deviation of Z (NaN for one sample)
  double sigma = 0, sigma_std = 0;  // coaxial holds: the map's sigma; NaN otherwise
  int cell = -1;                    // coaxial holds: index in the sigma table
  // Derivative of the quantity this hold determines with respect to its mean
  // Z: d alpha / dZ (upper only), d beta / dZ (lower only), d sigma_cell / dZ
  // (coaxial); 0 for a stopped hold. [1/(rad/s)^2, ..., 1/N]
  double d_dZ = 0;
  double dsigma0_dZ = 0;  // coaxial holds: d sigma0 / dZ [1/N]
};

// A point of the thrust map (Fig. 8): the delta = 0 holds at one grid speed pair, pooled.
struct ThrustMapPoint {
  double omega1 = 0, omega2 = 0;  // grid speeds [rad/s]
  double Z = 0;                   // count-weighted mean of the holds' mean Z [N]
  int samples = 0, holds = 0;
  MapHoldRole role = MapHoldRole::kStopped;
};

enum class SigmaCellSource { kStopped, kMeasured, kParametric };
const char* SigmaCellSourceName(
    SigmaCellSource source);  // "stopped", "measured", "parametric_fill"

struct ThrustMap {
  double Cz = 0;             // assumed body coefficient (config)
  double area_ratio = 0;     // k = S_s / S_prop
  double thrust_factor = 0;  // 1 - Cz k

  double alpha = 0, alpha_std = 0;  // [N s^2]
  int alpha_holds = 0, alpha_samples = 0;
  double beta = 0, beta_std = 0;  // [N s^2], lower rotor alone, delta = 0
  int beta_holds = 0, beta_samples = 0;
  double z_residual_variance = 0;  // per-sample variance of Z about the single-rotor fits [N^2]

  std::vector<MapHold> holds;
  std::vector<ThrustMapPoint> points;  // sorted by omega1, then omega2

  SigmaTable table;                          // the map, bilinear (Fig. 9)
  std::vector<SigmaCellSource> cell_source;  // per table cell
  std::vector<double> cell_std;              // per cell (0 for stopped cells)
  int measured_cells = 0, filled_cells = 0;
  double sigma0 = 0, sigma0_std = 0;  // parametric fit
  double sigma_fit_rms = 0;           // rms of (map sigma - parametric sigma) over coaxial holds
  // Largest loss 1 - sigma over the measured coaxial holds, and where.
  double max_loss = 0, max_loss_omega1 = 0, max_loss_omega2 = 0;

  // First-order sensitivities of the table cells (0 for stopped cells).
  std::vector<double> dcell_dalpha, dcell_dbeta;  // [1/(N s^2)]
  std::vector<double> dcell_dsigma0;              // -4 w1 w2/(w1+w2)^2 for filled cells, else 0
  double dsigma0_dalpha = 0, dsigma0_dbeta = 0;
};

// Fits the thrust and sigma maps to the delta = 0 holds of all data sets.
// Throws InputError naming what is missing: no single-rotor hold with delta = 0
// for the upper (or lower) rotor, no coaxial hold with delta = 0, or a thrust
// coefficient that is not negative (Z must be negative: body z axis down).
ThrustMap FitThrustMap(const std::vector<BalanceData>& data, double Cz, double area_ratio,
                       const ThrustMapOptions& options = {});

// 4 w1 w2 / (w1 + w2)^2 with w = omega^2 (0 if both stopped): the shape of
// model.md's parametric loss, sigma = 1 - sigma0 * shape.
double InterferenceShape(double omega1, double omega2);

}  // namespace coaxid
