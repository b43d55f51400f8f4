// What the two SUNDIALS back ends of Integrator (CVODES in integrator.cc,
// ARKODE in explicit_runge_kutta.cc) share: the right-hand-side callback's
// checks, the error-weight vector, messages. Internal to dynamics/.
#pragma once

#include <nvector/nvector_serial.h>

#include <string>

#include "dynamics/ode_system.h"

namespace coaxid {

struct IntegratorOptions;

// SUNDIALS return codes for user callbacks: 0 success, > 0 recoverable (the
// integrator retries with a smaller step), < 0 unrecoverable (it stops).
constexpr int kCallbackOk = 0;
constexpr int kCallbackRecoverable = 1;
constexpr int kCallbackFatal = -1;

// A time or value in messages, with all 17 digits.
std::string FullPrecision(double value);

// system.Rhs(t, y) into ydot. Rhs returning false is fatal (the model cannot
// be evaluated there: a smaller step will not help); a non-finite derivative
// is recoverable (typically the trial point of an oversized step). Either way
// *why says what and when.
int EvaluateRhs(const OdeSystem& system, double t, N_Vector y, N_Vector ydot, std::string* why);

// The absolute tolerances as a vector shaped like `like` when only the first
// options.error_controlled_states states are in the error test: a huge
// tolerance gives the others a negligible error weight (not 1e300: squared
// weighted values would be subnormal, 100x slower per flop). Null when every
// state is in the test (use the scalar tolerance). The caller destroys it
// (the integrators copy it). Throws ComputationError if it cannot be allocated.
N_Vector PartialAbsoluteTolerances(N_Vector like, const IntegratorOptions& options);

// "module::function: message", what the error handlers keep for last_error().
std::string SundialsMessage(const char* module, const char* function, const char* message);

}  // namespace coaxid
