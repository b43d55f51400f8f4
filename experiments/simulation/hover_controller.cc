#include "experiments/simulation/hover_controller.h"

#include <algorithm>
#include <cmath>

namespace coaxid {

HoverController::HoverController(const ControllerGains& gains, const InputVector& trim,
                                 double dt_s)
    : gains_(gains), trim_(trim), dt_(dt_s) {}

InputVector HoverController::Update(const Measurement& y, const Waypoint& target) {
  const double cf = std::cos(y.phi), sf = std::sin(y.phi);
  const double ct = std::cos(y.theta), st = std::sin(y.theta);
  const double cp = std::cos(y.psi), sp = std::sin(y.psi);
  // Earth-frame velocity from the body velocity (eq. 1).
  const double vn = ct * cp * y.u + (sf * st * cp - cf * sp) * y.v + (cf * st * cp + sf * sp) * y.w;
  const double ve = ct * sp * y.u + (sf * st * sp + cf * cp) * y.v + (cf * st * sp - sf * cp) * y.w;
  const double vd = -st * y.u + sf * ct * y.v + cf * ct * y.w;

  // Position loop: desired horizontal acceleration, turned into tilt in the
  // heading frame. Pitch up (theta > 0) accelerates backwards, roll right
  // (phi > 0) accelerates right.
  const double an = gains_.pos_kp * (target.north - y.x) - gains_.pos_kd * vn;
  const double ae = gains_.pos_kp * (target.east - y.y) - gains_.pos_kd * ve;
  const double a_fwd = cp * an + sp * ae;
  const double a_right = -sp * an + cp * ae;
  const double g = 9.81;
  const double theta_ref = std::clamp(-a_fwd / g, -gains_.max_tilt, gains_.max_tilt);
  const double phi_ref = std::clamp(a_right / g, -gains_.max_tilt, gains_.max_tilt);

  // Attitude loop on the swashplate.
  const double delta_cx = trim_[2] + gains_.att_kp * (phi_ref - y.phi) - gains_.att_kd * y.p;
  const double delta_cy =
      trim_[3] - (gains_.att_kp * (theta_ref - y.theta) - gains_.att_kd * y.q);

  // Altitude by collective speed (height h = -z; descending, vd > 0, needs more thrust).
  const double h_error = target.height - (-y.z);
  altitude_integral_ = std::clamp(altitude_integral_ + h_error * dt_, -2.0, 2.0);
  const double collective =
      gains_.alt_kp * h_error + gains_.alt_kd * vd + gains_.alt_ki * altitude_integral_;

  // Yaw by differential speed: speeding the upper rotor (gamma1 > 0) yaws right.
  const double heading_error = std::remainder(target.heading - y.psi, 2 * M_PI);
  const double differential = gains_.yaw_kp * heading_error - gains_.yaw_kd * y.r;

  const double ratio = trim_[1] / std::max(trim_[0], 1e-9);
  return {trim_[0] + collective + differential, trim_[1] + ratio * collective - differential,
          delta_cx, delta_cy};
}

}  // namespace coaxid
