#include "dynamics/integrator.h"
#include "dynamics/serial_vector_ops.h"
#include "dynamics/sundials_callbacks.h"

#include <cvodes/cvodes.h>
#include <glog/logging.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

#include "core/errors.h"
#include "dynamics/explicit_runge_kutta.h"

namespace coaxid {

namespace {

// Initial-step hint as a fraction of the order-1 step CVODE chose after the first step of the
// previous interval (see AdvanceTo).
constexpr double kHintFraction = 0.1;

std::string FlagName(int flag) {
  // CVodeGetReturnFlagName returns a malloc'ed string.
  char* name = CVodeGetReturnFlagName(flag);
  std::string result = name != nullptr ? name : "CV_UNKNOWN";
  std::free(name);
  return result;
}

}  // namespace

bool IntegratorOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(std::isfinite(relative_tolerance) && relative_tolerance > 0.0)) {
    return fail("relative_tolerance must be finite and > 0");
  }
  if (!(std::isfinite(absolute_tolerance) && absolute_tolerance > 0.0)) {
    return fail("absolute_tolerance must be finite and > 0");
  }
  if (relative_tolerance >= 1.0) return fail("relative_tolerance must be < 1");
  if (max_steps_per_interval <= 0) return fail("max_steps_per_interval must be > 0");
  if (error_controlled_states < 0) return fail("error_controlled_states must be >= 0");
  if (method == Method::kExplicitRungeKutta) {
    if (newton) return fail("newton must be false for the explicit Runge-Kutta method");
    if (max_order != 0) return fail("max_order must be 0 for the explicit Runge-Kutta method");
    return true;
  }
  const int order_limit = method == Method::kAdams ? 12 : 5;
  if (max_order < 0 || max_order > order_limit) {
    return fail("max_order must be in [0, " + std::to_string(order_limit) + "] for " +
                (method == Method::kAdams ? "Adams" : "BDF") + " (0 = CVODE default)");
  }
  return true;
}

struct Integrator::Impl {
  Impl(const OdeSystem& system_in, const IntegratorOptions& options_in,
       const SensitivityOptions& sens_in);
  ~Impl();
  void Release();  // Frees all SUNDIALS memory; idempotent.

  bool Reset(double t0, const Eigen::VectorXd& x0, const Eigen::MatrixXd* S0);
  // Reset()'s CVODES part: CVodeReInit and CVodeSensReInit; false via Fail().
  bool ReInitCvodes(double t0, const Eigen::VectorXd& x0, const Eigen::MatrixXd* S0);
  bool AdvanceTo(double t1, Eigen::VectorXd* x, Eigen::MatrixXd* S);
  bool Fail(const std::string& message);

  // CVODE callbacks; user_data is the Impl.
  static int RhsCallback(double t, N_Vector y, N_Vector ydot, void* user_data);
  static int SensRhsCallback(int ns, double t, N_Vector y, N_Vector ydot, N_Vector* yS,
                             N_Vector* ySdot, void* user_data, N_Vector tmp1, N_Vector tmp2);
  static int JacCallback(double t, N_Vector y, N_Vector fy, SUNMatrix J, void* user_data,
                         N_Vector tmp1, N_Vector tmp2, N_Vector tmp3);
  static void ErrorCallback(int error_code, const char* module, const char* function, char* msg,
                            void* user_data);

  // Evaluates df/dx and (with parameter sensitivities) df/dp at (t, y) into dfdx, dfdp unless
  // they are already there. CVODES's staggered corrector evaluates the sensitivity RHS several
  // times at the same converged state (once per corrector iteration), so this keeps it to one
  // OdeSystem::Jacobians call per step.
  bool SensitivityJacobians(double t, const double* y);

  const OdeSystem& system;
  const IntegratorOptions options;
  const int n;
  const int p;           // Parameter columns carried (0 unless wrt_parameters).
  const int state_cols;  // Initial-state columns carried (0 or n).
  const int ns;          // state_cols + p.

  // Set for Method::kExplicitRungeKutta, which uses it instead of CVODES.
  std::unique_ptr<ExplicitRungeKutta> erk;

  SUNContext context = nullptr;
  void* cvode = nullptr;
  N_Vector y = nullptr;
  N_Vector* yS = nullptr;
  SUNMatrix matrix = nullptr;
  SUNLinearSolver linear_solver = nullptr;
  SUNNonlinearSolver nonlinear_solver = nullptr;       // Fixed point for the state, if used.
  SUNNonlinearSolver sens_nonlinear_solver = nullptr;  // Fixed point for sensitivities, if used.

  Eigen::MatrixXd jac_dfdx;  // Newton Jacobian scratch, n x n.
  Eigen::MatrixXd dfdx;      // Sensitivity Jacobians at (cache_t, cache_y).
  Eigen::MatrixXd dfdp;
  Eigen::VectorXd cache_y;
  double cache_t = 0.0;
  bool cache_valid = false;

  bool ready = false;        // Reset() succeeded and no AdvanceTo() failed since.
  bool fresh_start = false;  // No step taken since the last Reset().
  double t = 0.0;
  double step_hint = 0.0;  // 0 = none yet.

  std::string error;           // last_error().
  std::string failure;         // Why the integrator became unusable (until the next Reset()).
  std::string cvode_message;   // Last message CVODE passed to the error handler.
  std::string callback_error;  // Why a callback failed (more specific than CVODE's message).

  long completed_steps = 0;  // Steps of runs before the last ReInit.
  long rhs_evals = 0;
  long jac_evals = 0;
  long restarts = 0;
};

Integrator::Impl::Impl(const OdeSystem& system_in, const IntegratorOptions& options_in,
                       const SensitivityOptions& sens_in)
    : system(system_in),
      options(options_in),
      n(system_in.NumStates()),
      p(sens_in.wrt_parameters ? system_in.NumSensitivityParameters() : 0),
      state_cols(sens_in.wrt_initial_state ? system_in.NumStates() : 0),
      ns(state_cols + p) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("IntegratorOptions: " + why);
  if (n <= 0) throw InputError("Integrator: the OdeSystem has no states");
  if (p < 0) throw InputError("Integrator: negative NumSensitivityParameters()");

  auto check = [this](int flag, const char* what) {
    if (flag != 0) {
      throw ComputationError(std::string("Integrator: ") + what + " failed (" + FlagName(flag) +
                             "): " + cvode_message);
    }
  };
  auto check_ptr = [](const void* ptr, const char* what) {
    if (ptr == nullptr) throw ComputationError(std::string("Integrator: ") + what + " failed");
  };
  if (options.method == IntegratorOptions::Method::kExplicitRungeKutta) {
    if (ns > 0) {
      throw InputError(
          "Integrator: the explicit Runge-Kutta method carries no CVODES sensitivities; "
          "integrate the variational equations as states (SensitivityMethod::"
          "kVariationalEquations) or use Adams/BDF");
    }
    erk = std::make_unique<ExplicitRungeKutta>(system, options);
    return;
  }
  try {
    check(SUNContext_Create(nullptr, &context), "SUNContext_Create");
    cvode = CVodeCreate(options.method == IntegratorOptions::Method::kAdams ? CV_ADAMS : CV_BDF,
                        context);
    check_ptr(cvode, "CVodeCreate");
    // First thing: route CVODE's messages to last_error() instead of stderr.
    check(CVodeSetErrHandlerFn(cvode, &Impl::ErrorCallback, this), "CVodeSetErrHandlerFn");
    y = N_VNew_Serial(n, context);
    check_ptr(y, "N_VNew_Serial");
    N_VConst(0.0, y);
    // Fused vector kernels (one call per vector array instead of one per vector): CVODE's own
    // vectors and the sensitivity vectors are cloned from y and inherit this. Measured: -15%
    // time with 20 sensitivities, neutral without (bench/dynamics/integrator_bench.cc).
    check(N_VEnableFusedOps_Serial(y, SUNTRUE), "N_VEnableFusedOps_Serial");
    // Optimised kernels in place of the distribution's unoptimised ones (serial_vector_ops.h).
    if (options.optimized_vector_ops) UseOptimizedSerialOps(y);
    // All allocation happens here, once; Reset() only re-initialises.
    check(CVodeInit(cvode, &Impl::RhsCallback, 0.0, y), "CVodeInit");
    check(CVodeSetUserData(cvode, this), "CVodeSetUserData");
    if (N_Vector atol = PartialAbsoluteTolerances(y, options)) {
      const int flag = CVodeSVtolerances(cvode, options.relative_tolerance, atol);
      N_VDestroy(atol);  // CVODE keeps its own copy
      check(flag, "CVodeSVtolerances");
    } else {
      check(CVodeSStolerances(cvode, options.relative_tolerance, options.absolute_tolerance),
            "CVodeSStolerances");
    }
    check(CVodeSetMaxNumSteps(cvode, options.max_steps_per_interval), "CVodeSetMaxNumSteps");
    if (options.max_order > 0) check(CVodeSetMaxOrd(cvode, options.max_order), "CVodeSetMaxOrd");
    // "t + h = t" warnings would only fill the error handler; a step that small fails anyway.
    check(CVodeSetMaxHnilWarns(cvode, -1), "CVodeSetMaxHnilWarns");

    if (options.newton) {
      matrix = SUNDenseMatrix(n, n, context);
      check_ptr(matrix, "SUNDenseMatrix");
      linear_solver = SUNLinSol_Dense(y, matrix, context);
      check_ptr(linear_solver, "SUNLinSol_Dense");
      check(CVodeSetLinearSolver(cvode, linear_solver, matrix), "CVodeSetLinearSolver");
      check(CVodeSetJacFn(cvode, &Impl::JacCallback), "CVodeSetJacFn");
      jac_dfdx.setZero(n, n);
      // CVodeInit's default nonlinear solver is already Newton.
    } else {
      nonlinear_solver = SUNNonlinSol_FixedPoint(y, 0, context);  // m = 0: no Anderson mixing.
      check_ptr(nonlinear_solver, "SUNNonlinSol_FixedPoint");
      check(CVodeSetNonlinearSolver(cvode, nonlinear_solver), "CVodeSetNonlinearSolver");
    }

    if (ns > 0) {
      yS = N_VCloneVectorArray(ns, y);
      check_ptr(yS, "N_VCloneVectorArray");
      for (int j = 0; j < ns; ++j) N_VConst(0.0, yS[j]);
      dfdx.setZero(n, n);
      dfdp.setZero(n, p);
      cache_y.setZero(n);
      // Staggered corrector: the state is corrected (and passes its own error test) before any
      // sensitivity work is done for the step, and all sensitivity iterations of the step then
      // see the same converged state, so with the cache in SensitivityJacobians() a step costs
      // one OdeSystem::Jacobians call. CV_SIMULTANEOUS would re-evaluate the Jacobians at every
      // corrector iterate (2-3 per step with fixed point) and redo sensitivity work for steps
      // the state error test rejects. The sensitivity equations are linear in S, so the
      // staggered sensitivity corrector converges in about one iteration.
      // User data must be set before CVodeSensInit, which copies it for the sensitivity RHS.
      check(CVodeSensInit(cvode, ns, CV_STAGGERED, &Impl::SensRhsCallback, yS), "CVodeSensInit");
      // Tolerances for S from those of x (scaled by pbar = 1), and S in the error test, so the
      // sensitivities are as accurate as the state instead of merely consistent with it.
      check(CVodeSensEEtolerances(cvode), "CVodeSensEEtolerances");
      check(CVodeSetSensErrCon(cvode, options.sensitivity_error_control ? SUNTRUE : SUNFALSE),
            "CVodeSetSensErrCon");
      if (!options.newton) {
        // CVodeSensInit attached (and owns) a Newton sensitivity solver; replace it.
        sens_nonlinear_solver = SUNNonlinSol_FixedPointSens(ns, y, 0, context);
        check_ptr(sens_nonlinear_solver, "SUNNonlinSol_FixedPointSens");
        check(CVodeSetNonlinearSolverSensStg(cvode, sens_nonlinear_solver),
              "CVodeSetNonlinearSolverSensStg");
      }
    }
  } catch (...) {
    Release();  // The destructor does not run for an object whose constructor threw.
    throw;
  }
}

Integrator::Impl::~Impl() { Release(); }

void Integrator::Impl::Release() {
  // CVodeFree first: it may still reference the solvers, matrix and vectors.
  if (cvode != nullptr) CVodeFree(&cvode);
  if (sens_nonlinear_solver != nullptr) SUNNonlinSolFree(sens_nonlinear_solver);
  if (nonlinear_solver != nullptr) SUNNonlinSolFree(nonlinear_solver);
  if (linear_solver != nullptr) SUNLinSolFree(linear_solver);
  if (matrix != nullptr) SUNMatDestroy(matrix);
  if (yS != nullptr) N_VDestroyVectorArray(yS, ns);
  if (y != nullptr) N_VDestroy(y);
  if (context != nullptr) SUNContext_Free(&context);
  cvode = nullptr;
  sens_nonlinear_solver = nonlinear_solver = nullptr;
  linear_solver = nullptr;
  matrix = nullptr;
  yS = nullptr;
  y = nullptr;
}

bool Integrator::Impl::Fail(const std::string& message) {
  error = failure = message;
  ready = false;
  return false;
}

bool Integrator::Impl::Reset(double t0, const Eigen::VectorXd& x0, const Eigen::MatrixXd* S0) {
  CHECK_EQ(x0.size(), n) << "Integrator::Reset: x0 has the wrong size";
  ++restarts;
  cvode_message.clear();
  callback_error.clear();
  if (!std::isfinite(t0) || !x0.allFinite()) {
    return Fail("Integrator::Reset: non-finite t0 or x0");
  }
  if (erk) {
    std::string why;
    if (!erk->Reset(t0, x0, &why)) return Fail(why);
  } else if (!ReInitCvodes(t0, x0, S0)) {
    return false;
  }
  t = t0;
  cache_valid = false;
  fresh_start = true;
  ready = true;
  error.clear();
  failure.clear();
  return true;
}

bool Integrator::Impl::ReInitCvodes(double t0, const Eigen::VectorXd& x0,
                                    const Eigen::MatrixXd* S0) {
  long steps = 0;
  CVodeGetNumSteps(cvode, &steps);
  completed_steps += steps;

  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), n) = x0;
  int flag = CVodeReInit(cvode, t0, y);
  if (flag != CV_SUCCESS) {
    return Fail("CVodeReInit failed (" + FlagName(flag) + "): " + cvode_message);
  }
  if (ns > 0) {
    if (S0 != nullptr) {
      CHECK(S0->rows() == n && S0->cols() == ns)
          << "Integrator::Reset: S0 is " << S0->rows() << " x " << S0->cols() << ", expected " << n
          << " x " << ns;
      if (!S0->allFinite()) return Fail("Integrator::Reset: non-finite S0");
      for (int j = 0; j < ns; ++j) {
        Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(yS[j]), n) = S0->col(j);
      }
    } else {
      for (int j = 0; j < ns; ++j) {
        N_VConst(0.0, yS[j]);
        if (j < state_cols) N_VGetArrayPointer(yS[j])[j] = 1.0;
      }
    }
    flag = CVodeSensReInit(cvode, CV_STAGGERED, yS);
    if (flag != CV_SUCCESS) {
      return Fail("CVodeSensReInit failed (" + FlagName(flag) + "): " + cvode_message);
    }
  }
  return true;
}

bool Integrator::Impl::AdvanceTo(double t1, Eigen::VectorXd* x, Eigen::MatrixXd* S) {
  CHECK(x != nullptr);
  if (!ready) {
    error = failure.empty() ? "Integrator::AdvanceTo called before Reset()"
                            : "Integrator::AdvanceTo after a failure without Reset(): " + failure;
    return false;
  }
  if (!(t1 > t)) {  // Also rejects NaN.
    error = "Integrator::AdvanceTo: t1 = " + FullPrecision(t1) +
            " is not after the current time " + FullPrecision(t);
    return false;  // Nothing was done; the integrator stays usable.
  }
  cvode_message.clear();
  callback_error.clear();
  // The concrete system may have changed its held input since the last call.
  cache_valid = false;
  if (erk) {
    // A one-step method needs no order ramp: the first step of an interval is the step the
    // error controller proposed at the end of the previous one.
    x->resize(n);
    std::string why;
    double next_step = 0.0;
    const double first_step = fresh_start ? (options.initial_step_hint ? step_hint : 0.0) : -1.0;
    if (!erk->AdvanceTo(t, t1, first_step, x->data(), &next_step, &why)) {
      step_hint = 0.0;
      return Fail(why);
    }
    if (options.initial_step_hint && next_step > 0.0) step_hint = next_step;
    fresh_start = false;
    t = t1;
    if (S != nullptr) S->resize(n, 0);
    return true;
  }

  int flag = CVodeSetStopTime(cvode, t1);
  if (flag != CV_SUCCESS) {
    return Fail("CVodeSetStopTime failed (" + FlagName(flag) + "): " + cvode_message);
  }
  double tret = t;
  const bool learn_hint = fresh_start && options.initial_step_hint;
  if (fresh_start) {
    // 0 = let CVODE estimate the first step (cvHin: 2-5 extra RHS and, with sensitivities,
    // sensitivity-RHS evaluations at every restart). A hint below round-off level of t would
    // only trigger "t + h = t" failures, so it falls back to the estimate too.
    double h0 = learn_hint ? std::min(step_hint, t1 - t) : 0.0;
    if (h0 < 1e3 * std::numeric_limits<double>::epsilon() * std::max(std::abs(t), t1 - t)) {
      h0 = 0.0;
    }
    flag = CVodeSetInitStep(cvode, h0);
    if (flag != CV_SUCCESS) {
      return Fail("CVodeSetInitStep failed (" + FlagName(flag) + "): " + cvode_message);
    }
  }
  if (learn_hint) {
    // Take the first step alone to learn the next hint. After one step CVODE knows the local
    // error constant and sizes the next (still order-1) step from it: CVodeGetCurrentStep.
    // The hint is a tenth of that. Such a first step is accepted with error ~1/100 of the
    // tolerance after one fixed-point iteration, and CVODE then grows the step (by up to
    // 10^4 after the first step) straight to the error-optimal size; measured, this is
    // cheaper than starting at the full order-1 step, which sometimes needs a second
    // corrector iteration (bench: 12.0 vs 12.8 RHS calls per 5 ms interval; 15.1 without
    // any hint). The hint adapts every interval, so it follows the dynamics.
    flag = CVode(cvode, t1, y, &tret, CV_ONE_STEP);
    if (flag == CV_SUCCESS) {
      double h_next = 0.0;
      if (CVodeGetCurrentStep(cvode, &h_next) == CV_SUCCESS && h_next > 0.0) {
        step_hint = kHintFraction * h_next;
      }
      if (tret < t1) flag = CVode(cvode, t1, y, &tret, CV_NORMAL);
    }
  } else {
    flag = CVode(cvode, t1, y, &tret, CV_NORMAL);
  }
  fresh_start = false;
  if (flag < 0) {
    step_hint = 0.0;  // Back to CVODE's estimate after the next Reset().
    std::string message = "CVODES failed (" + FlagName(flag) + ") integrating from " +
                          FullPrecision(t) + " to " + FullPrecision(t1) + ": " + cvode_message;
    if (!callback_error.empty()) message += " [" + callback_error + "]";
    return Fail(message);
  }
  t = t1;
  x->resize(n);
  *x = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(y), n);
  if (S != nullptr) {
    S->resize(n, ns);
    if (ns > 0) {
      flag = CVodeGetSens(cvode, &tret, yS);
      if (flag != CV_SUCCESS) {
        return Fail("CVodeGetSens failed (" + FlagName(flag) + "): " + cvode_message);
      }
      for (int j = 0; j < ns; ++j) {
        S->col(j) = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(yS[j]), n);
      }
    }
  }
  return true;
}

int Integrator::Impl::RhsCallback(double t, N_Vector y, N_Vector ydot, void* user_data) {
  Impl* self = static_cast<Impl*>(user_data);
  ++self->rhs_evals;
  return EvaluateRhs(self->system, t, y, ydot, &self->callback_error);
}

bool Integrator::Impl::SensitivityJacobians(double t_eval, const double* y_eval) {
  const Eigen::Map<const Eigen::VectorXd> y_map(y_eval, n);
  if (cache_valid && t_eval == cache_t && y_map == cache_y) return true;
  ++jac_evals;
  cache_valid = false;
  if (!system.Jacobians(t_eval, y_eval, &dfdx, p > 0 ? &dfdp : nullptr)) {
    callback_error = "OdeSystem::Jacobians returned false at t = " + FullPrecision(t_eval);
    return false;
  }
  CHECK(dfdx.rows() == n && dfdx.cols() == n) << "OdeSystem::Jacobians: df/dx has a wrong size";
  CHECK(p == 0 || (dfdp.rows() == n && dfdp.cols() == p))
      << "OdeSystem::Jacobians: df/dp has a wrong size";
  cache_t = t_eval;
  cache_y = y_map;
  cache_valid = true;
  return true;
}

int Integrator::Impl::SensRhsCallback(int ns, double t, N_Vector y, N_Vector /*ydot*/, N_Vector* yS,
                                      N_Vector* ySdot, void* user_data, N_Vector /*tmp1*/,
                                      N_Vector /*tmp2*/) {
  Impl* self = static_cast<Impl*>(user_data);
  if (!self->SensitivityJacobians(t, N_VGetArrayPointer(y))) return kCallbackFatal;
  const int n = self->n;
  for (int j = 0; j < ns; ++j) {
    Eigen::Map<Eigen::VectorXd> sdot(N_VGetArrayPointer(ySdot[j]), n);
    sdot.noalias() = self->dfdx * Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(yS[j]), n);
    if (j >= self->state_cols) sdot += self->dfdp.col(j - self->state_cols);
  }
  return kCallbackOk;
}

int Integrator::Impl::JacCallback(double t, N_Vector y, N_Vector /*fy*/, SUNMatrix J,
                                  void* user_data, N_Vector /*tmp1*/, N_Vector /*tmp2*/,
                                  N_Vector /*tmp3*/) {
  Impl* self = static_cast<Impl*>(user_data);
  ++self->jac_evals;
  if (!self->system.Jacobians(t, N_VGetArrayPointer(y), &self->jac_dfdx, nullptr)) {
    self->callback_error = "OdeSystem::Jacobians returned false at t = " + FullPrecision(t);
    return kCallbackFatal;
  }
  const int n = self->n;
  CHECK(self->jac_dfdx.rows() == n && self->jac_dfdx.cols() == n)
      << "OdeSystem::Jacobians: df/dx has a wrong size";
  // Dense SUNMatrix storage is column-major with leading dimension n, like Eigen's default.
  Eigen::Map<Eigen::MatrixXd>(SUNDenseMatrix_Data(J), n, n) = self->jac_dfdx;
  return kCallbackOk;
}

void Integrator::Impl::ErrorCallback(int error_code, const char* module, const char* function,
                                     char* msg, void* user_data) {
  if (error_code == CV_WARNING) return;  // Warnings do not make a call fail.
  Impl* self = static_cast<Impl*>(user_data);
  self->cvode_message = SundialsMessage(module, function, msg);
}

Integrator::Integrator(const OdeSystem& system, const IntegratorOptions& options,
                       const SensitivityOptions& sens)
    : impl_(std::make_unique<Impl>(system, options, sens)) {}

Integrator::~Integrator() = default;
Integrator::Integrator(Integrator&&) noexcept = default;
Integrator& Integrator::operator=(Integrator&&) noexcept = default;

bool Integrator::Reset(double t0, const Eigen::VectorXd& x0, const Eigen::MatrixXd* S0) {
  return impl_->Reset(t0, x0, S0);
}

void Integrator::ForgetStepHint() { impl_->step_hint = 0.0; }
double Integrator::step_hint() const { return impl_->step_hint; }
void Integrator::RestoreStepHint(double hint) { impl_->step_hint = hint; }

bool Integrator::AdvanceTo(double t1, Eigen::VectorXd* x, Eigen::MatrixXd* S) {
  return impl_->AdvanceTo(t1, x, S);
}

const std::string& Integrator::last_error() const { return impl_->error; }

int Integrator::num_sensitivities() const { return impl_->ns; }

double Integrator::time() const { return impl_->t; }

Integrator::Stats Integrator::stats() const {
  Stats stats;
  if (impl_->erk) {
    stats.steps = impl_->erk->steps();
    stats.rhs_evals = impl_->erk->rhs_evals();
    stats.restarts = impl_->restarts;
    return stats;
  }
  long steps = 0;
  CVodeGetNumSteps(impl_->cvode, &steps);
  stats.steps = impl_->completed_steps + steps;
  stats.rhs_evals = impl_->rhs_evals;
  stats.jac_evals = impl_->jac_evals;
  stats.restarts = impl_->restarts;
  return stats;
}

}  // namespace coaxid
