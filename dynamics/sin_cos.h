// The sine and cosine of one angle together. ceres::Jet's sin and cos each
// evaluate both of the scalar part, so a Jet-typed model that takes sin(a)
// and cos(a) separately pays for two sincos per angle: the Jacobian passes
// of the flight model took 13 where its 5 angles need 5 (sincos was 16 % of
// a discover run's CPU time, perf on a 60 s flight-only log).
//
// The scalar pair is also remembered per thread (ScalarSinCos): the model
// meets the same angle again and again. A held swashplate angle is the same
// in every stage of a hold interval's Runge-Kutta step, and every angle is
// the same in the chunked Jet passes of one Jacobian (dynamics/autodiff.h:
// three passes for 12 states and 12 parameters) and again at the step's
// ends (the sensitivity step's Jacobians, dynamics/simulator.cc). Measured:
// sincos was still 14 % of a discover run's CPU time (perf, the 42 s
// flight-only log of bench/discover_speed.sh seed 20356), two thirds of the
// calls repeating an angle. The values are bit for bit those of sin(a) and
// cos(a).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include <ceres/jet.h>

namespace coaxid {

// sin(a), cos(a), from the calling thread's table of recent angles when a
// is there (a direct-mapped table: a miss costs one sincos and replaces the
// slot's angle).
inline void ScalarSinCos(double a, double* s, double* c) {
  struct Slot {
    // Empty: a NaN's pattern, and NaN values should an angle have it.
    std::uint64_t bits = ~std::uint64_t{0};
    double s = std::numeric_limits<double>::quiet_NaN(), c = s;
  };
  constexpr int kSlotBits = 6;
  thread_local Slot table[1 << kSlotBits];
  std::uint64_t bits;
  std::memcpy(&bits, &a, sizeof bits);
  Slot& slot = table[(bits * 0x9E3779B97F4A7C15ull) >> (64 - kSlotBits)];
  if (slot.bits != bits) {
    slot.bits = bits;
    slot.s = std::sin(a);
    slot.c = std::cos(a);
  }
  *s = slot.s;
  *c = slot.c;
}

template <typename T>
void SinCos(const T& a, T* s, T* c) {
  using std::cos;
  using std::sin;
  *s = sin(a);
  *c = cos(a);
}

inline void SinCos(double a, double* s, double* c) { ScalarSinCos(a, s, c); }

template <typename T, int N>
void SinCos(const ceres::Jet<T, N>& a, ceres::Jet<T, N>* s, ceres::Jet<T, N>* c) {
  T sa, ca;
  SinCos(a.a, &sa, &ca);
  *s = ceres::Jet<T, N>(sa, ca * a.v);   // d sin = cos da
  *c = ceres::Jet<T, N>(ca, -sa * a.v);  // d cos = -sin da
}

}  // namespace coaxid
