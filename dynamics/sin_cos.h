// The sine and cosine of one angle together. ceres::Jet's sin and cos each
// evaluate both of the scalar part, so a Jet-typed model that takes sin(a)
// and cos(a) separately pays for two sincos per angle: the Jacobian passes
// of the flight model took 13 where its 5 angles need 5 (sincos was 16 % of
// a discover run's CPU time, perf on a 60 s flight-only log). The values are
// bit for bit those of sin(a) and cos(a).
#pragma once

#include <cmath>

#include <ceres/jet.h>

namespace coaxid {

template <typename T>
void SinCos(const T& a, T* s, T* c) {
  using std::cos;
  using std::sin;
  *s = sin(a);
  *c = cos(a);
}

template <typename T, int N>
void SinCos(const ceres::Jet<T, N>& a, ceres::Jet<T, N>* s, ceres::Jet<T, N>* c) {
  using std::cos;
  using std::sin;
  const T sa = sin(a.a), ca = cos(a.a);
  *s = ceres::Jet<T, N>(sa, ca * a.v);   // d sin = cos da
  *c = ceres::Jet<T, N>(ca, -sa * a.v);  // d cos = -sin da
}

}  // namespace coaxid
