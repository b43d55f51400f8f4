#include "dynamics/explicit_runge_kutta.h"

#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "core/errors.h"
#include "dynamics/integrator.h"
#include "dynamics/serial_vector_ops.h"
#include "dynamics/sundials_callbacks.h"

namespace coaxid {

namespace {

std::string FlagName(int flag) {
  char* name = ERKStepGetReturnFlagName(flag);  // malloc'ed
  std::string result = name != nullptr ? name : "ARK_UNKNOWN";
  std::free(name);
  return result;
}

}  // namespace

struct ExplicitRungeKutta::Impl {
  Impl(const OdeSystem& system_in, const IntegratorOptions& options);
  ~Impl() { Release(); }
  void Release();  // Frees all SUNDIALS memory; idempotent.

  static int RhsCallback(double t, N_Vector y, N_Vector ydot, void* user_data);
  static void ErrorCallback(int error_code, const char* module, const char* function, char* msg,
                            void* user_data);
  std::string Why(const std::string& what, int flag) const;
  // Throw ComputationError when a SUNDIALS call fails (flag != 0) or returns null.
  void Check(int flag, const char* what) const;
  static void CheckNotNull(const void* pointer, const char* what);

  const OdeSystem& system;
  const int n;
  SUNContext context = nullptr;
  void* arkode = nullptr;
  N_Vector y = nullptr;
  std::string arkode_message;   // Last message ARKODE passed to the error handler.
  std::string callback_error;   // Why a callback failed (more specific than ARKODE's message).
  long rhs_evals = 0;
};

ExplicitRungeKutta::Impl::Impl(const OdeSystem& system_in, const IntegratorOptions& options)
    : system(system_in), n(system_in.NumStates()) {
  try {
    Check(SUNContext_Create(nullptr, &context), "SUNContext_Create");
    y = N_VNew_Serial(n, context);
    CheckNotNull(y, "N_VNew_Serial");
    N_VConst(0.0, y);
    Check(N_VEnableFusedOps_Serial(y, SUNTRUE), "N_VEnableFusedOps_Serial");
    if (options.optimized_vector_ops) UseOptimizedSerialOps(y);
    arkode = ERKStepCreate(&Impl::RhsCallback, 0.0, y, context);
    CheckNotNull(arkode, "ERKStepCreate");
    Check(ERKStepSetErrHandlerFn(arkode, &Impl::ErrorCallback, this), "ERKStepSetErrHandlerFn");
    Check(ERKStepSetUserData(arkode, this), "ERKStepSetUserData");
    // Dormand-Prince 5(4): seven stages, first-same-as-last, the classical choice for non-stiff
    // problems at tolerances of 1e-5 to 1e-9.
    Check(ERKStepSetTableNum(arkode, ARKODE_DORMAND_PRINCE_7_4_5), "ERKStepSetTableNum");
    if (N_Vector atol = PartialAbsoluteTolerances(y, options)) {
      const int flag = ERKStepSVtolerances(arkode, options.relative_tolerance, atol);
      N_VDestroy(atol);  // ARKODE keeps its own copy
      Check(flag, "ERKStepSVtolerances");
    } else {
      Check(ERKStepSStolerances(arkode, options.relative_tolerance, options.absolute_tolerance),
            "ERKStepSStolerances");
    }
    Check(ERKStepSetMaxNumSteps(arkode, options.max_steps_per_interval), "ERKStepSetMaxNumSteps");
    Check(ERKStepSetMaxHnilWarns(arkode, -1), "ERKStepSetMaxHnilWarns");
  } catch (...) {
    Release();  // The destructor does not run for an object whose constructor threw.
    throw;
  }
}

void ExplicitRungeKutta::Impl::Check(int flag, const char* what) const {
  if (flag != 0) throw ComputationError("ExplicitRungeKutta: " + Why(what, flag));
}

void ExplicitRungeKutta::Impl::CheckNotNull(const void* pointer, const char* what) {
  if (pointer == nullptr) {
    throw ComputationError(std::string("ExplicitRungeKutta: ") + what + " failed");
  }
}

void ExplicitRungeKutta::Impl::Release() {
  if (arkode != nullptr) ERKStepFree(&arkode);
  if (y != nullptr) N_VDestroy(y);
  if (context != nullptr) SUNContext_Free(&context);
  arkode = nullptr;
  y = nullptr;
  context = nullptr;
}

std::string ExplicitRungeKutta::Impl::Why(const std::string& what, int flag) const {
  std::string message = what + " failed (" + FlagName(flag) + "): " + arkode_message;
  if (!callback_error.empty()) message += " [" + callback_error + "]";
  return message;
}

int ExplicitRungeKutta::Impl::RhsCallback(double t, N_Vector y, N_Vector ydot, void* user_data) {
  Impl* self = static_cast<Impl*>(user_data);
  ++self->rhs_evals;
  return EvaluateRhs(self->system, t, y, ydot, &self->callback_error);
}

void ExplicitRungeKutta::Impl::ErrorCallback(int error_code, const char* module,
                                             const char* function, char* msg, void* user_data) {
  if (error_code == ARK_WARNING) return;
  Impl* self = static_cast<Impl*>(user_data);
  self->arkode_message = SundialsMessage(module, function, msg);
}

ExplicitRungeKutta::ExplicitRungeKutta(const OdeSystem& system, const IntegratorOptions& options)
    : impl_(std::make_unique<Impl>(system, options)) {}

ExplicitRungeKutta::~ExplicitRungeKutta() = default;

bool ExplicitRungeKutta::Reset(double t0, const Eigen::VectorXd& x0, std::string* error) {
  Impl& m = *impl_;
  m.arkode_message.clear();
  m.callback_error.clear();
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(m.y), m.n) = x0;
  const int flag = ERKStepReset(m.arkode, t0, m.y);
  if (flag != ARK_SUCCESS) {
    *error = m.Why("ERKStepReset", flag);
    return false;
  }
  return true;
}

bool ExplicitRungeKutta::AdvanceTo(double t, double t1, double first_step, double* x,
                                   double* next_first_step, std::string* error) {
  Impl& m = *impl_;
  m.arkode_message.clear();
  m.callback_error.clear();
  int flag = ERKStepSetStopTime(m.arkode, t1);
  if (flag != ARK_SUCCESS) {
    *error = m.Why("ERKStepSetStopTime", flag);
    return false;
  }
  if (first_step >= 0.0) {
    double h0 = std::min(first_step, t1 - t);
    // A step below round-off level of t would only fail: let ARKODE estimate instead.
    if (h0 < 1e3 * std::numeric_limits<double>::epsilon() * std::max(std::abs(t), t1 - t)) {
      h0 = 0.0;
    }
    flag = ERKStepSetInitStep(m.arkode, h0);
    if (flag != ARK_SUCCESS) {
      *error = m.Why("ERKStepSetInitStep", flag);
      return false;
    }
  }
  double tret = t;
  flag = ERKStepEvolve(m.arkode, t1, m.y, &tret, ARK_NORMAL);
  if (flag < 0) {
    *error = m.Why("ARKODE ERKStep integrating from " + FullPrecision(t) + " to " +
                       FullPrecision(t1),
                   flag);
    return false;
  }
  const double* y = N_VGetArrayPointer(m.y);
  std::copy(y, y + m.n, x);
  double h_next = 0.0;
  if (next_first_step != nullptr && ERKStepGetCurrentStep(m.arkode, &h_next) == ARK_SUCCESS) {
    *next_first_step = std::max(h_next, 0.0);
  }
  return true;
}

long ExplicitRungeKutta::steps() const {
  long steps = 0;  // ARKODE's counter runs on across ERKStepReset.
  ERKStepGetNumSteps(impl_->arkode, &steps);
  return steps;
}

long ExplicitRungeKutta::rhs_evals() const { return impl_->rhs_evals; }

}  // namespace coaxid
