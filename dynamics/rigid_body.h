// The generic 6-DoF rigid body (sect. 2.1): kinematics and dynamics of eqs.
// 1-5, developed as eqs. 34-39 and the inertial parts of eqs. 40-42, 47-49.
// Templated on the scalar so the simulator, the EKF and Ceres run one code.
#pragma once

#include <cmath>

#include "dynamics/sin_cos.h"
#include "dynamics/state.h"

namespace coaxid {

// The sines and cosines of the ZYX Euler angles (phi, theta, psi), each
// taken once: the rotation (eq. 1) and the Euler angle rates (eq. 2) share
// them.
template <typename T>
struct EulerSines {
  T sf, cf, st, ct, sp, cp;
};

template <typename T>
EulerSines<T> EulerSinesOf(const T& phi, const T& theta, const T& psi) {
  EulerSines<T> e;
  SinCos(phi, &e.sf, &e.cf);
  SinCos(theta, &e.st, &e.ct);
  SinCos(psi, &e.sp, &e.cp);
  return e;
}

// Rotation body -> earth for ZYX Euler angles (eq. 1).
template <typename T>
Mat3<T> BodyToEarth(const EulerSines<T>& e) {
  const T &sf = e.sf, &cf = e.cf, &st = e.st, &ct = e.ct, &sp = e.sp, &cp = e.cp;
  Mat3<T> R_EB;
  R_EB << ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp,  //
      ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp,      //
      -st, sf * ct, cf * ct;
  return R_EB;
}

template <typename T>
Mat3<T> BodyToEarth(const T& phi, const T& theta, const T& psi) {
  return BodyToEarth(EulerSinesOf(phi, theta, psi));
}

// State derivative of a rigid body of mass m and principal inertias
// (Ixx, Iyy, Izz) (eq. 5) under the total force F_B (aerodynamic + gravity)
// and moment M_B in body axes. Euler angles ZYX, x[kTheta] away from +-pi/2;
// e their sines and cosines, R_EB = BodyToEarth(e).
template <typename T>
void RigidBodyDerivative(const T* x, const EulerSines<T>& e, const Mat3<T>& R_EB,
                         const Vec3<T>& F_B, const Vec3<T>& M_B, const T& m, const T& Ixx,
                         const T& Iyy, const T& Izz, T* xdot) {
  const T u = x[kU], v = x[kV], w = x[kW];
  const T p = x[kP], q = x[kQ], r = x[kR];
  // Eqs. 34-36 (eq. 1): position rate in earth axes.
  const Vec3<T> v_B(u, v, w);
  const Vec3<T> pos_dot = R_EB * v_B;
  xdot[kX] = pos_dot[0];
  xdot[kY] = pos_dot[1];
  xdot[kZ] = pos_dot[2];
  // Eqs. 40-42 (eq. 3): m v_dot = F - m w x v.
  xdot[kU] = r * v - q * w + F_B[0] / m;
  xdot[kV] = p * w - r * u + F_B[1] / m;
  xdot[kW] = q * u - p * v + F_B[2] / m;
  // Eqs. 37-39 (eq. 2): Euler angle rates.
  const T &cos_theta = e.ct, &sf = e.sf, &cf = e.cf;
  const T tan_theta = e.st / cos_theta;
  xdot[kPhi] = p + tan_theta * (sf * q + cf * r);
  xdot[kTheta] = cf * q - sf * r;
  xdot[kPsi] = (sf * q + cf * r) / cos_theta;
  // Eqs. 47-49 (eq. 4): I w_dot = M - w x I w.
  xdot[kP] = ((Iyy - Izz) * r * q + M_B[0]) / Ixx;
  xdot[kQ] = ((Izz - Ixx) * r * p + M_B[1]) / Iyy;
  xdot[kR] = ((Ixx - Iyy) * p * q + M_B[2]) / Izz;
}

}  // namespace coaxid
