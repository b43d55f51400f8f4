#include "ident/kinematic/flight_path_reconstruction.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include <Eigen/Sparse>
#include <ceres/ceres.h>
#include <glog/logging.h>

#include "core/errors.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "dynamics/autodiff.h"
#include "dynamics/outputs.h"
#include "dynamics/rigid_body.h"
#include "dynamics/state.h"
#include "ident/output_error/output_error.h"

namespace coaxid {
namespace {

using Clock = std::chrono::steady_clock;

// x, y, z, u, v, w, phi, theta, psi: the first 9 states in StateIndex order.
constexpr int kNumKinematicStates = kPhi + 3;
enum SensorError : int { kBp, kBq, kBr, kBax, kBay, kBaz, kSp, kSq, kSr, kSax, kSay, kSaz, kTau,
                         kNumSensorErrors };
constexpr int kImuChannels[6] = {kP, kQ, kR, kAx, kAy, kAz};

inline double ValueOf(double x) { return x; }
template <typename J>
double ValueOf(const J& x) {
  return x.a;
}

// Eqs. 34-42 with the IMU as the input: the rigid body's kinematic rows,
// with the force per unit mass = the measured specific force (model.md,
// decision 7) + gravity in body axes.
template <typename T>
void KinematicDerivative(const T* z, const T* rates, const T* specific_force, const T& g,
                         T* zdot) {
  T x[kNumStates];
  for (int i = 0; i < kNumKinematicStates; ++i) x[i] = z[i];
  for (int i = 0; i < 3; ++i) x[kP + i] = rates[i];
  const EulerSines<T> e = EulerSinesOf(x[kPhi], x[kTheta], x[kPsi]);
  const Mat3<T> R_EB = BodyToEarth(e);
  const Vec3<T> f = Vec3<T>(specific_force[0], specific_force[1], specific_force[2]) +
                    R_EB.transpose() * Vec3<T>(T(0), T(0), g);
  T xdot[kNumStates];
  const T one(1);
  RigidBodyDerivative(x, e, R_EB, f, Vec3<T>(T(0), T(0), T(0)), one, one, one, one, xdot);
  for (int i = 0; i < kNumKinematicStates; ++i) zdot[i] = xdot[i];
}

struct Term {
  int row, column, state;
  double weight;
};

// One multiple-shooting segment: rows first..last of a log (last: the next
// segment's first row, or the log's last row).
struct Segment {
  const EstimationLog* log = nullptr;
  int first = 0, last = 0;
  bool has_next = false;
  std::array<int, 6> imu{};  // the log's columns of p, q, r, ax, ay, az
  std::vector<Term> terms;   // measured kinematic samples of rows first..last-1 (..last at the end)
  std::array<double, kNumKinematicStates> continuity_weight{};
  double g = 9.81;
  double time(int k) const { return log->inputs.time(k); }

  // The corrected IMU of row k: (measured - b) / (1 + s).
  template <typename T>
  void Imu(int k, const T* e, T* rates, T* accel) const {
    for (int i = 0; i < 3; ++i) {
      rates[i] = (T(log->values(k, imu[i])) - e[kBp + i]) / (T(1) + e[kSp + i]);
      accel[i] = (T(log->values(k, imu[3 + i])) - e[kBax + i]) / (T(1) + e[kSax + i]);
    }
  }

  // RK4 from row to row. The rates are states, sampled: linear between rows.
  // The accelerometer of row k is the specific force with row k's inputs
  // (model.md, decision 7), which hold on [t_k, t_{k+1}): it holds too.
  template <typename T>
  void Integrate(const T* z0, const T* e, std::vector<std::array<T, kNumKinematicStates>>* z) const {
    const int n = last - first + 1;
    z->resize(n);
    for (int i = 0; i < kNumKinematicStates; ++i) (*z)[0][i] = z0[i];
    T r0[3], a0[3], r1[3], a1[3], rm[3];
    Imu(first, e, r0, a0);
    const T gravity(g);
    T k1[kNumKinematicStates], k2[kNumKinematicStates], k3[kNumKinematicStates],
        k4[kNumKinematicStates], tmp[kNumKinematicStates];
    for (int j = 0; j + 1 < n; ++j) {
      Imu(first + j + 1, e, r1, a1);
      for (int i = 0; i < 3; ++i) rm[i] = T(0.5) * (r0[i] + r1[i]);
      const T h(time(first + j + 1) - time(first + j));
      const std::array<T, kNumKinematicStates>& s = (*z)[j];
      KinematicDerivative(s.data(), r0, a0, gravity, k1);
      for (int i = 0; i < kNumKinematicStates; ++i) tmp[i] = s[i] + T(0.5) * h * k1[i];
      KinematicDerivative(tmp, rm, a0, gravity, k2);
      for (int i = 0; i < kNumKinematicStates; ++i) tmp[i] = s[i] + T(0.5) * h * k2[i];
      KinematicDerivative(tmp, rm, a0, gravity, k3);
      for (int i = 0; i < kNumKinematicStates; ++i) tmp[i] = s[i] + h * k3[i];
      KinematicDerivative(tmp, r1, a0, gravity, k4);
      for (int i = 0; i < kNumKinematicStates; ++i) {
        (*z)[j + 1][i] = s[i] + h / T(6) * (k1[i] + T(2) * k2[i] + T(2) * k3[i] + k4[i]);
      }
      for (int i = 0; i < 3; ++i) {
        r0[i] = r1[i];
        a0[i] = a1[i];
      }
    }
  }

  // The state `term.state` at t_row - tau, linear between the segment's rows
  // (extrapolated from its first or last interval beyond them).
  template <typename T>
  T Late(const std::vector<std::array<T, kNumKinematicStates>>& z, const T* e, int row,
         int state) const {
    const T t = T(time(row)) - e[kTau];
    const double tv = ValueOf(t);
    int j = std::min(row, last - 1);  // the interval [t_j, t_j+1] holding t, first <= j < last
    while (j > first && time(j) > tv) --j;
    while (j + 1 < last && time(j + 1) <= tv) ++j;
    const T w = (t - T(time(j))) / T(time(j + 1) - time(j));
    const T& a = z[j - first][state];
    const T& b = z[j + 1 - first][state];
    return a + w * (b - a);
  }

  int NumResiduals() const {
    return static_cast<int>(terms.size()) + (has_next ? kNumKinematicStates : 0);
  }
};

struct SegmentResidual {
  explicit SegmentResidual(const Segment* s) : s_(s) {}
  template <typename T>
  bool operator()(T const* const* p, T* residuals) const {
    const Segment& s = *s_;
    std::vector<std::array<T, kNumKinematicStates>> z;
    s.Integrate(p[0], p[1], &z);
    int out = 0;
    for (const Term& term : s.terms) {
      T nu = T(s.log->values(term.row, term.column)) - s.Late(z, p[1], term.row, term.state);
      if (term.state == kPsi) nu -= T(2 * M_PI * std::round(ValueOf(nu) / (2 * M_PI)));
      residuals[out++] = term.weight * nu;
    }
    if (s.has_next) {
      for (int i = 0; i < kNumKinematicStates; ++i) {
        residuals[out++] = s.continuity_weight[i] * (z.back()[i] - p[2][i]);
      }
    }
    CHECK_EQ(out, s.NumResiduals());
    for (int r = 0; r < out; ++r) {
      if (!std::isfinite(ValueOf(residuals[r]))) return false;
    }
    return true;
  }

 private:
  const Segment* s_;
};

double NoiseOf(const NoiseWeights& noise, const std::string& channel) {
  const auto it = noise.std.find(channel);
  return it == noise.std.end() ? 1.0 : it->second;
}

class Progress : public ceres::IterationCallback {
 public:
  Progress(const KinematicOptions& o, Clock::time_point start) : o_(o), start_(start) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (o_.progress) {
      char line[160];
      std::snprintf(line, sizeof line, "kinematic: iteration %2d  cost %.6e  elapsed %.1f s",
                    s.iteration, s.cost, SecondsSince(start_));
      o_.progress(line);
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const KinematicOptions& o_;
  Clock::time_point start_;
};

// Solves for the segment states and the sensor errors not held (held ones
// at 0), and fills result's estimates, std, fit and predictions.
void SolveSensorErrors(const std::vector<Segment>& segments, const std::vector<EstimationLog>& logs,
                       const std::array<bool, kNumSensorErrors>& held_mask,
                       const KinematicOptions& options, Clock::time_point start,
                       KinematicResult* out) {
  KinematicResult& result = *out;

  // Unknowns: each segment's start state (from the log's measurements) and
  // the sensor errors (from 0).
  std::vector<std::array<double, kNumKinematicStates>> states(segments.size());
  for (size_t j = 0; j < segments.size(); ++j) {
    const Eigen::VectorXd x = InitialStateFromLog(*segments[j].log, segments[j].first);
    for (int i = 0; i < kNumKinematicStates; ++i) states[j][i] = x[i];
  }
  std::array<double, kNumSensorErrors> e{};
  ceres::Problem problem;
  int num_residuals = 0;
  for (size_t j = 0; j < segments.size(); ++j) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<SegmentResidual, kAutodiffChunk>(
        new SegmentResidual(&segments[j]));
    cost->AddParameterBlock(kNumKinematicStates);
    cost->AddParameterBlock(kNumSensorErrors);
    std::vector<double*> blocks = {states[j].data(), e.data()};
    if (segments[j].has_next) {
      cost->AddParameterBlock(kNumKinematicStates);
      blocks.push_back(states[j + 1].data());
    }
    cost->SetNumResiduals(segments[j].NumResiduals());
    num_residuals += segments[j].NumResiduals();
    problem.AddResidualBlock(cost, nullptr, blocks);
  }
  result.estimated.assign(kNumSensorErrors, true);
  std::vector<int> held;
  for (int i = 0; i < kNumSensorErrors; ++i) {
    if (held_mask[i]) {
      held.push_back(i);
      result.estimated[i] = false;
    }
  }
  if (!held.empty()) {
    problem.SetManifold(e.data(), new ceres::SubsetManifold(kNumSensorErrors, held));
  }
  problem.SetParameterLowerBound(e.data(), kTau, -0.5);
  problem.SetParameterUpperBound(e.data(), kTau, 0.5);
  for (int i = kSp; i <= kSaz; ++i) {
    problem.SetParameterLowerBound(e.data(), i, -0.5);
    problem.SetParameterUpperBound(e.data(), i, 0.5);
  }

  ceres::Solver::Options so;
  so.linear_solver_type = ceres::SPARSE_SCHUR;
  so.max_num_iterations = options.max_iterations;
  so.num_threads = options.num_threads;
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-12;
  Progress progress(options, start);
  so.callbacks.push_back(&progress);
  so.update_state_every_iteration = false;
  if (options.progress) {
    options.progress("kinematic: " + std::to_string(segments.size()) + " segments of " +
                     std::to_string(options.segment_s) + " s, " + std::to_string(num_residuals) +
                     " residuals, " + std::to_string(kNumSensorErrors - held.size()) +
                     " sensor errors");
  }
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    throw ComputationError("kinematic reconstruction: the solve failed: " + summary.message);
  }
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.termination = summary.message;
  const int unknowns = static_cast<int>(segments.size()) * kNumKinematicStates +
                       kNumSensorErrors - static_cast<int>(held.size());
  result.residual_variance_factor =
      num_residuals > unknowns ? 2 * summary.final_cost / (num_residuals - unknowns) : 1.0;

  // Covariance of the sensor errors, all segment states marginalised:
  // H = J^T J (sparse; the states are block tridiagonal), and the rows of
  // H^-1 of the free sensor errors (ordered first) from k sparse solves.
  std::vector<double*> order = {e.data()};
  for (auto& x : states) order.push_back(x.data());
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = order;
  eo.num_threads = options.num_threads;
  ceres::CRSMatrix crs;
  if (!problem.Evaluate(eo, nullptr, nullptr, nullptr, &crs)) {
    throw ComputationError("kinematic reconstruction: the Jacobian at the solution cannot be "
                           "evaluated");
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> J(crs.num_rows, crs.num_cols);
  {
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(crs.values.size());
    for (int r = 0; r < crs.num_rows; ++r) {
      for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) {
        triplets.emplace_back(r, crs.cols[k], crs.values[k]);
      }
    }
    J.setFromTriplets(triplets.begin(), triplets.end());
  }
  const Eigen::SparseMatrix<double> H = (J.transpose() * J).pruned();
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(H);
  const int free_count = kNumSensorErrors - static_cast<int>(held.size());
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(H.rows(), free_count);
  for (int k = 0; k < free_count; ++k) unit(k, k) = 1;
  const Eigen::MatrixXd columns = ldlt.info() == Eigen::Success ? ldlt.solve(unit)
                                                                : Eigen::MatrixXd();
  bool separable = ldlt.info() == Eigen::Success && columns.allFinite();
  for (int k = 0; separable && k < free_count; ++k) separable = columns(k, k) > 0;
  if (!separable) {
    throw ComputationError(
        "kinematic reconstruction: the sensor errors are not separable from these logs (the "
        "information matrix is singular); hold the scale factors (--kinematic_scale_factors="
        "false) or fly with more varied rates and accelerations");
  }
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(kNumSensorErrors, kNumSensorErrors);
  std::vector<int> free_index;
  for (int i = 0; i < kNumSensorErrors; ++i) {
    if (!held_mask[i]) free_index.push_back(i);
  }
  for (int a = 0; a < free_count; ++a) {
    for (int b = 0; b < free_count; ++b) cov(free_index[a], free_index[b]) = columns(a, b);
  }
  cov *= result.residual_variance_factor;
  result.estimate = Eigen::Map<const Eigen::VectorXd>(e.data(), kNumSensorErrors);
  result.std = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  result.correlation = Eigen::MatrixXd::Zero(kNumSensorErrors, kNumSensorErrors);
  for (int a = 0; a < kNumSensorErrors; ++a) {
    for (int b = 0; b < kNumSensorErrors; ++b) {
      if (result.std[a] > 0 && result.std[b] > 0) {
        result.correlation(a, b) = cov(a, b) / (result.std[a] * result.std[b]);
      }
    }
  }

  // The reconstruction on the logs' rows, and its fit.
  std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> pooled;
  size_t j = 0;
  for (const EstimationLog& log : logs) {
    Eigen::MatrixXd prediction =
        Eigen::MatrixXd::Constant(log.NumRows(), log.NumChannels(), std::nan(""));
    for (; j < segments.size() && segments[j].log == &log; ++j) {
      const Segment& s = segments[j];
      std::vector<std::array<double, kNumKinematicStates>> z;
      s.Integrate(states[j].data(), e.data(), &z);
      for (const Term& term : s.terms) {
        const double y = s.Late(z, e.data(), term.row, term.state);
        prediction(term.row, term.column) = y;
        auto& [measured, model] = pooled[log.channel_names[term.column]];
        measured.push_back(log.values(term.row, term.column));
        model.push_back(y);
      }
    }
    result.predictions.push_back(std::move(prediction));
  }
  for (const auto& [name, mm] : pooled) result.fit[name] = ComputeFitError(mm.first, mm.second);
}

}  // namespace

bool KinematicOptions::IsValid(std::string* why) const {
  if (!(segment_s > 0 && std::isfinite(segment_s))) {
    *why = "segment_s must be > 0";
    return false;
  }
  if (!(gravity > 0 && std::isfinite(gravity))) {
    *why = "gravity must be > 0";
    return false;
  }
  if (!(scale_factor_std_limit > 0)) {
    *why = "scale_factor_std_limit must be > 0";
    return false;
  }
  if (max_iterations < 1 || num_threads < 1) {
    *why = "max_iterations and num_threads must be >= 1";
    return false;
  }
  return true;
}

const std::vector<std::string>& KinematicParameterNames() {
  static const std::vector<std::string> names = {"b_p",  "b_q",  "b_r",  "b_ax", "b_ay",
                                                 "b_az", "s_p",  "s_q",  "s_r",  "s_ax",
                                                 "s_ay", "s_az", "tau"};
  return names;
}

const std::vector<std::string>& KinematicParameterUnits() {
  static const std::vector<std::string> units = {"rad/s", "rad/s", "rad/s", "m/s^2", "m/s^2",
                                                 "m/s^2", "-",     "-",     "-",     "-",
                                                 "-",     "-",     "s"};
  return units;
}

double KinematicResult::Value(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  CHECK(it != names.end()) << name;
  return estimate[it - names.begin()];
}

KinematicResult ReconstructFlightPath(const std::vector<EstimationLog>& logs,
                                      const KinematicOptions& options) {
  const auto start = Clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw InputError("kinematic options: " + why);
  if (logs.empty()) throw InputError("kinematic: no log");
  KinematicResult result;
  result.names = KinematicParameterNames();
  result.noise = NoiseFromData(logs);

  // Continuity std per state: the IMU's white noise integrated over a
  // segment (velocity sigma_a sqrt(dt T), position sigma_a sqrt(dt) T^1.5 /
  // sqrt(3), attitude sigma_g sqrt(dt T)).
  auto mean_noise = [&](int first) {
    double sum = 0;
    for (int i = 0; i < 3; ++i) sum += NoiseOf(result.noise, FlightChannelName(kImuChannels[first + i]));
    return sum / 3;
  };
  const double sigma_g = mean_noise(0), sigma_a = mean_noise(3);

  std::vector<Segment> segments;
  for (const EstimationLog& log : logs) {
    if (log.kind != LogKind::kFlight) {
      throw InputError(log.source + ": a " + LogKindName(log.kind) +
                       " log; the kinematic reconstruction needs flight logs");
    }
    if (log.NumRows() < 3) throw InputError(log.source + ": fewer than three rows");
    std::array<int, 6> imu{};
    for (int i = 0; i < 6; ++i) {
      imu[i] = log.ChannelColumn(kImuChannels[i]);
      const char* name = FlightChannelName(kImuChannels[i]);
      if (imu[i] < 0) {
        throw InputError(log.source + ": column '" + name +
                         "' missing: the kinematic reconstruction is driven by the rate gyros "
                         "and the accelerometer");
      }
      for (int k = 0; k < log.NumRows(); ++k) {
        if (!std::isfinite(log.values(k, imu[i]))) {
          throw InputError(log.source + ": row " + std::to_string(log.LogRow(k) + 1) +
                           ", column '" + name +
                           "': value missing; the kinematic reconstruction needs the IMU in "
                           "every row");
        }
      }
    }
    std::vector<std::pair<int, int>> measured;  // (column, state)
    for (int s = 0; s < kNumKinematicStates; ++s) {
      const int c = log.ChannelColumn(s);
      if (c >= 0) measured.push_back({c, s});
    }
    if (measured.empty()) {
      throw InputError(log.source + ": no position, velocity or attitude column to reconstruct");
    }
    const double dt = (log.inputs.time(log.NumRows() - 1) - log.inputs.time(0)) / (log.NumRows() - 1);
    int first = 0;
    while (first < log.NumRows() - 1) {
      int last = first + 1;
      while (last < log.NumRows() - 1 &&
             log.inputs.time(last) < log.inputs.time(first) + options.segment_s) {
        ++last;
      }
      // A short remainder joins this segment.
      if (log.inputs.time(log.NumRows() - 1) - log.inputs.time(last) < 0.5 * options.segment_s) {
        last = log.NumRows() - 1;
      }
      Segment s;
      s.log = &log;
      s.first = first;
      s.last = last;
      s.has_next = last < log.NumRows() - 1;
      s.imu = imu;
      s.g = options.gravity;
      const int end = s.has_next ? last - 1 : last;
      for (int k = first; k <= end; ++k) {
        for (const auto& [c, state] : measured) {
          if (std::isfinite(log.values(k, c))) {
            s.terms.push_back({k, c, state, 1.0 / NoiseOf(result.noise, log.channel_names[c])});
          }
        }
      }
      const double T = log.inputs.time(last) - log.inputs.time(first);
      for (int i = 0; i < 3; ++i) {
        s.continuity_weight[kX + i] =
            1.0 / std::max(1e-9, sigma_a * std::sqrt(dt) * std::pow(T, 1.5) / std::sqrt(3.0));
        s.continuity_weight[kU + i] = 1.0 / std::max(1e-9, sigma_a * std::sqrt(dt * T));
        s.continuity_weight[kPhi + i] = 1.0 / std::max(1e-9, sigma_g * std::sqrt(dt * T));
      }
      segments.push_back(std::move(s));
      first = last;
    }
  }
  result.num_segments = static_cast<int>(segments.size());

  std::array<bool, kNumSensorErrors> held{};
  for (int i = kSp; i <= kSaz; ++i) held[i] = !options.scale_factors;
  held[kTau] = !options.time_offset;
  SolveSensorErrors(segments, logs, held, options, start, &result);
  // Scale factors the logs do not fix are held at 0 and the fit repeated.
  if (options.scale_factors) {
    for (int i = kSp; i <= kSaz; ++i) {
      if (result.std[i] > options.scale_factor_std_limit) {
        held[i] = true;
        result.unidentified.push_back(result.names[i]);
      }
    }
    if (!result.unidentified.empty()) {
      if (options.progress) {
        std::string names;
        for (const std::string& n : result.unidentified) names += " " + n;
        options.progress("kinematic: not fixed by these logs (std above " +
                         NumberText(options.scale_factor_std_limit, "%g") + "), held at 0:" +
                         names);
      }
      SolveSensorErrors(segments, logs, held, options, start, &result);
    }
  }
  result.seconds = SecondsSince(start);
  return result;
}

Log CorrectedLog(const Log& log, const KinematicResult& r) {
  Log out = log;
  const std::vector<double>& t = log.Column("t");
  const double tau = r.Value("tau");
  for (size_t c = 0; c < out.columns.size(); ++c) {
    const std::string& name = out.columns[c];
    const int channel = FlightChannelIndex(name);
    std::vector<double>& v = out.values[c];
    for (int i = 0; i < 6; ++i) {
      if (channel != kImuChannels[i]) continue;
      const double b = r.estimate[kBp + i], s = r.estimate[kSp + i];
      for (double& x : v) x = (x - b) / (1 + s);
    }
    if (channel < 0 || channel >= kNumKinematicStates || tau == 0) continue;
    // y(t_k) = y_m(t_k + tau), between the column's own samples.
    std::vector<int> rows;
    for (size_t k = 0; k < v.size(); ++k) {
      if (std::isfinite(log.values[c][k])) rows.push_back(static_cast<int>(k));
    }
    if (rows.size() < 2) continue;
    for (int k : rows) {
      const double tq = t[k] + tau;
      const auto it = std::upper_bound(rows.begin(), rows.end(), tq,
                                       [&](double a, int row) { return a < t[row]; });
      if (it == rows.begin()) {
        v[k] = log.values[c][rows.front()];
      } else if (it == rows.end()) {
        v[k] = log.values[c][rows.back()];
      } else {
        const int a = *(it - 1), b = *it;
        const double w = (tq - t[a]) / (t[b] - t[a]);
        double ya = log.values[c][a], yb = log.values[c][b];
        if (channel == kPsi) yb = ya + std::remainder(yb - ya, 2 * M_PI);
        v[k] = ya + w * (yb - ya);
      }
    }
  }
  out.metadata["corrected"] = "coaxid identify --method=kinematic (sensor errors removed)";
  return out;
}

}  // namespace coaxid
