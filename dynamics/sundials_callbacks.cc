#include "dynamics/sundials_callbacks.h"

#include <cmath>
#include <sstream>

#include "core/errors.h"
#include "dynamics/integrator.h"

namespace coaxid {

std::string FullPrecision(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

int EvaluateRhs(const OdeSystem& system, double t, N_Vector y, N_Vector ydot, std::string* why) {
  double* xdot = N_VGetArrayPointer(ydot);
  if (!system.Rhs(t, N_VGetArrayPointer(y), xdot)) {
    *why = "OdeSystem::Rhs returned false at t = " + FullPrecision(t);
    return kCallbackFatal;
  }
  const sunindextype n = N_VGetLength_Serial(ydot);
  for (sunindextype i = 0; i < n; ++i) {
    if (!std::isfinite(xdot[i])) {
      *why = "OdeSystem::Rhs returned a non-finite derivative at t = " + FullPrecision(t);
      return kCallbackRecoverable;
    }
  }
  return kCallbackOk;
}

N_Vector PartialAbsoluteTolerances(N_Vector like, const IntegratorOptions& options) {
  const sunindextype n = N_VGetLength_Serial(like);
  if (options.error_controlled_states <= 0 || options.error_controlled_states >= n) return nullptr;
  N_Vector atol = N_VClone(like);
  if (atol == nullptr) throw ComputationError("Integrator: N_VClone failed");
  double* a = N_VGetArrayPointer(atol);
  for (sunindextype i = 0; i < n; ++i) {
    a[i] = i < options.error_controlled_states ? options.absolute_tolerance : 1e100;
  }
  return atol;
}

std::string SundialsMessage(const char* module, const char* function, const char* message) {
  return std::string(module != nullptr ? module : "") + "::" +
         (function != nullptr ? function : "") + ": " + (message != nullptr ? message : "");
}

}  // namespace coaxid
