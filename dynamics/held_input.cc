#include "dynamics/held_input.h"

namespace coaxid {

HeldInput NextHeldInput(const HeldInput& held, const InputVector& lag, const InputVector& u,
                        double t1) {
  HeldInput next;
  next.logged = u;
  next.t0 = t1;
  next.lag = lag;
  const double h = t1 - held.t0;
  for (int i = 0; i < static_cast<int>(u.size()); ++i) {
    const double T = lag[i];
    if (!(T > 0)) {
      next.start[i] = u[i];
      next.start_dlag[i] = 0;
      continue;
    }
    // The previous interval's start at this T (first order in T - held.lag).
    const double a0 = held.start[i] + held.start_dlag[i] * (T - held.lag[i]);
    const double c = held.logged[i];
    const double E = std::exp(-h / T);
    next.start[i] = c + (a0 - c) * E;                                        // (B)
    next.start_dlag[i] = E * held.start_dlag[i] + (a0 - c) * E * h / (T * T);  // (B)
  }
  return next;
}

namespace {
bool AnyLag(const InputVector& lag) {
  for (double T : lag) {
    if (T > 0) return true;
  }
  return false;
}
}  // namespace

HeldInput FirstHeldInput(const InputHold& hold, const InputVector& lag) {
  const std::vector<double>& t = hold.lead_in_times();
  if (!AnyLag(lag) || t.empty()) return HeldInput::Steady(hold.input(0), hold.time(0));
  const std::vector<InputVector>& u = hold.lead_in_inputs();
  HeldInput held = HeldInput::Steady(u[0], t[0]);
  for (size_t j = 1; j < t.size(); ++j) held = NextHeldInput(held, lag, u[j], t[j]);
  return NextHeldInput(held, lag, hold.input(0), hold.time(0));
}

HeldInput HeldInputAt(const InputHold& hold, int k, const InputVector& lag) {
  if (!AnyLag(lag)) return HeldInput::Steady(hold.input(k), hold.time(k));
  HeldInput held = FirstHeldInput(hold, lag);
  for (int j = 1; j <= k; ++j) held = NextHeldInput(held, lag, hold.input(j), hold.time(j));
  return held;
}

HeldInput HeldInputPath::At(int k, const InputVector& lag) const {
  if (!AnyLag(lag)) return HeldInput::Steady(hold_.input(k), hold_.time(k));
  std::lock_guard<std::mutex> lock(mutex_);
  if (lag != lag_) {
    path_ = HeldInputs(hold_, lag);
    lag_ = lag;
  }
  return path_[k];
}

std::vector<HeldInput> HeldInputs(const InputHold& hold, const InputVector& lag) {
  std::vector<HeldInput> out;
  out.reserve(hold.size());
  const bool any = AnyLag(lag);
  for (int k = 0; k < hold.size(); ++k) {
    out.push_back(!any  ? HeldInput::Steady(hold.input(k), hold.time(k))
                  : k == 0 ? FirstHeldInput(hold, lag)
                           : NextHeldInput(out.back(), lag, hold.input(k), hold.time(k)));
  }
  return out;
}

}  // namespace coaxid
