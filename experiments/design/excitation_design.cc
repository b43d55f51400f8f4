#include "experiments/design/excitation_design.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "core/errors.h"
#include "core/stopwatch.h"
#include "dynamics/trim.h"
#include "experiments/simulation/excitation.h"

namespace coaxid {

nlohmann::json DesignLimits::ToJson() const {
  return {{"max_attitude_rad", max_attitude_rad},
          {"max_rotor_speed_deviation_rad_s", max_rotor_speed_deviation_rad_s},
          {"max_swashplate_rad", max_swashplate_rad},
          {"max_height_deviation_m", max_height_deviation_m}};
}

namespace {

constexpr const char* kInputs[4] = {"omega1", "omega2", "delta_cx", "delta_cy"};
constexpr int kNumLimits = 4;  // attitude, rotor speed, swashplate, height

std::array<double, kNumLimits> Peaks(const FlightEnvelope& e) {
  return {e.max_attitude_rad, e.max_rotor_speed_deviation_rad_s, e.max_swashplate_rad,
          e.max_height_deviation_m};
}
std::array<double, kNumLimits> MeanSquares(const FlightEnvelope& e) {
  return {e.ms_attitude, e.ms_rotor_speed, e.ms_swashplate, e.ms_height};
}
std::array<double, kNumLimits> LimitValues(const DesignLimits& l) {
  return {l.max_attitude_rad, l.max_rotor_speed_deviation_rad_s, l.max_swashplate_rad,
          l.max_height_deviation_m};
}
constexpr const char* kLimitNames[kNumLimits] = {"attitude", "rotor-speed deviation",
                                                 "swashplate angle", "height deviation"};
constexpr const char* kLimitFlags[kNumLimits] = {"--max_attitude_rad",
                                                 "--max_rotor_speed_deviation_rad_s",
                                                 "--max_swashplate_rad",
                                                 "--max_height_deviation_m"};

// The plan with the designed flight's excitation replaced.
std::vector<Scenario> WithExcitation(const std::vector<Scenario>& plan, int flight,
                                     const Excitation& excitation) {
  std::vector<Scenario> out = plan;
  out[flight].flight.excitation = excitation;
  return out;
}

// A multisine of the given bands and rms (per component: channel-major).
Excitation BandExcitation(const Excitation& reference, const std::vector<FrequencyBand>& bands,
                          const std::vector<double>& rms,
                          const std::vector<std::array<double, 2>>& quiet) {
  Excitation e;
  e.quiet = quiet;
  e.type = Excitation::Type::kMultisine;
  e.start_s = reference.start_s;
  e.period_s = reference.period_s;
  e.amplitude.clear();
  const int B = static_cast<int>(bands.size());
  for (int b = 0; b < B; ++b) {
    Excitation::Band band;
    band.min_hz = bands[b].min_hz;
    band.max_hz = bands[b].max_hz;
    for (int c = 0; c < 4; ++c) {
      if (rms[c * B + b] > 0) band.rms[kInputs[c]] = rms[c * B + b];
    }
    e.bands.push_back(band);
  }
  return e;
}

struct Evaluation {
  SimulatedExperiment run;
  PredictedPrecision precision;
};

Evaluation Evaluate(const Vehicle& vehicle, const std::vector<Scenario>& plan,
                    const OutputErrorOptions& options) {
  Evaluation e;
  e.run = SimulatePlannedExperiment(vehicle, plan);
  e.precision = PredictPrecision(vehicle, e.run, options);
  return e;
}

// The positive semi-definite part of a symmetric matrix (a difference of two
// informations carries the integration's noise in its small eigenvalues).
Eigen::MatrixXd PositivePart(const Eigen::MatrixXd& A) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (A + A.transpose()));
  const Eigen::VectorXd d = eig.eigenvalues().cwiseMax(0.0);
  return eig.eigenvectors() * d.asDiagonal() * eig.eigenvectors().transpose();
}

// min f(t) subject to A t <= b, t >= 0, by a log barrier and damped Newton
// steps (the Hessian by differences of the analytic gradient: a few dozen
// variables at most). t0 must be strictly feasible.
Eigen::VectorXd MinimiseOnPolytope(const std::function<double(const Eigen::VectorXd&)>& f,
                                   const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& grad,
                                   const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                                   Eigen::VectorXd t) {
  const int K = static_cast<int>(t.size());
  auto feasible = [&](const Eigen::VectorXd& x) {
    return (x.array() > 0).all() && ((b - A * x).array() > 0).all() && std::isfinite(f(x));
  };
  for (double mu = 1.0; mu > 1e-7; mu *= 0.2) {
    auto F = [&](const Eigen::VectorXd& x) {
      return f(x) - mu * ((b - A * x).array().log().sum() + x.array().log().sum());
    };
    auto G = [&](const Eigen::VectorXd& x) {
      Eigen::VectorXd g = grad(x);
      g += mu * A.transpose() * (b - A * x).cwiseInverse();
      g -= mu * x.cwiseInverse();
      return g;
    };
    for (int iteration = 0; iteration < 50; ++iteration) {
      const Eigen::VectorXd g = G(t);
      Eigen::MatrixXd H(K, K);
      for (int k = 0; k < K; ++k) {
        const double h = 1e-6 * std::max(t[k], 1e-3);
        Eigen::VectorXd tp = t;
        tp[k] += h;
        if (!feasible(tp)) {
          tp[k] = t[k] - h;
          H.col(k) = (g - G(tp)) / h;
        } else {
          H.col(k) = (G(tp) - g) / h;
        }
      }
      H = 0.5 * (H + H.transpose());
      Eigen::VectorXd step;
      for (double lambda = 0;; lambda = std::max(1e-10, 10 * lambda)) {
        const Eigen::MatrixXd Hl =
            H + lambda * H.diagonal().cwiseAbs().asDiagonal().toDenseMatrix() +
            lambda * Eigen::MatrixXd::Identity(K, K);
        const Eigen::LLT<Eigen::MatrixXd> llt(Hl);
        if (llt.info() == Eigen::Success) {
          step = -llt.solve(g);
          break;
        }
        if (lambda > 1e10) {
          step = -g;
          break;
        }
      }
      const double decrement = -g.dot(step);
      if (decrement < 1e-10) break;
      double s = 1.0;
      const double F0 = F(t);
      while (s > 1e-12 && (!feasible(t + s * step) || F(t + s * step) > F0 - 0.25 * s * decrement)) {
        s *= 0.5;
      }
      if (s <= 1e-12) break;
      t += s * step;
    }
  }
  return t;
}

std::string Format(const char* format, double a, double b = 0, double c = 0, double d = 0) {
  char line[256];
  std::snprintf(line, sizeof line, format, a, b, c, d);
  return line;
}

}  // namespace

Log ExcitationTimeSeries(const FlightScenario& flight) {
  const ExcitationSignal signal(flight.excitation);
  const int steps = static_cast<int>(std::floor(flight.duration_s * flight.rate_hz + 1e-9)) + 1;
  Log log;
  log.kind = LogKind::kFlight;
  log.columns = {"t", "omega1", "omega2", "delta_cx", "delta_cy"};
  log.values.assign(5, {});
  for (int k = 0; k < steps; ++k) {
    const double t = k / flight.rate_hz;
    const InputVector e = signal.At(t);
    log.values[0].push_back(t);
    for (int c = 0; c < 4; ++c) log.values[1 + c].push_back(e[c]);
  }
  return log;
}

ExcitationDesign DesignExcitation(const Vehicle& vehicle, const std::vector<Scenario>& plan,
                                  const DesignCriterion& criterion,
                                  const ExcitationDesignOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(Format("design %6.1f s: ", SecondsSince(start)) + line);
  };
  ExcitationDesign out;
  out.flight_index = -1;
  for (size_t i = 0; i < plan.size() && out.flight_index < 0; ++i) {
    if (plan[i].kind == Scenario::Kind::kFlight) out.flight_index = static_cast<int>(i);
  }
  if (out.flight_index < 0) {
    throw InputError("an excitation is designed for a flight: the plan has no flight scenario");
  }
  const bool multisine = options.excitation == Excitation::Type::kMultisine;
  if (!multisine && options.excitation != Excitation::Type::k3211) {
    throw InputError("the excitation design makes a multisine or a 3211");
  }
  out.type = options.excitation;
  if (multisine && options.bands.empty()) {
    throw InputError("the excitation design needs at least one band");
  }
  const int fi = out.flight_index;
  const Excitation& reference_excitation = plan[fi].flight.excitation;
  const double df = 1.0 / reference_excitation.period_s;
  for (const FrequencyBand& band : multisine ? options.bands : std::vector<FrequencyBand>{}) {
    if (!(band.min_hz > 0 && band.max_hz > band.min_hz)) {
      throw InputError("design band: need 0 < min_hz < max_hz");
    }
    const int harmonics = static_cast<int>(std::floor(band.max_hz / df + 1e-9)) -
                          static_cast<int>(std::ceil(band.min_hz / df - 1e-9));
    if (harmonics < 4) {  // the lowest may belong to the band below
      throw InputError(Format("design band %g-%g Hz holds %g harmonics of 1/period_s (%g Hz): "
                              "each of the four inputs needs one; widen it or lengthen the "
                              "scenario's excitation period_s",
                              band.min_hz, band.max_hz, std::max(harmonics, 0), df));
    }
  }

  // The reference: the plan as given.
  out.reference = plan;
  say("the planned experiment as given");
  Evaluation reference = Evaluate(vehicle, plan, options.output_error);
  const CriterionOnInformation objective(criterion, reference.precision);
  out.before = reference.precision;
  out.criterion_before = objective.Value(reference.precision.information_scaled);
  const FlightEnvelope ref_envelope = reference.run.envelopes[fi];
  out.reference_run = std::move(reference.run);

  // Limits: given, or the reference's own peaks.
  out.limits = options.limits;
  {
    std::array<double, kNumLimits> given = LimitValues(options.limits);
    const std::array<double, kNumLimits> ref_peaks = Peaks(ref_envelope);
    const Waypoint& first = plan[fi].flight.waypoints.front();
    const HoverTrim trim =
        TrimHover(vehicle.model, vehicle.parameters.Values(), first.height, first.heading);
    const std::array<double, kNumLimits> defaults = {
        ref_peaks[0], std::max(ref_peaks[1], 0.1 * (trim.input[0] + trim.input[1])),
        std::max(ref_peaks[2], 0.1), std::max(ref_peaks[3], 0.5)};
    for (int j = 0; j < kNumLimits; ++j) {
      if (std::isnan(given[j])) given[j] = defaults[j];
      if (!(given[j] > 0)) {
        throw InputError(std::string("the ") + kLimitNames[j] + " limit must be positive (" +
                         kLimitFlags[j] + ")");
      }
    }
    out.limits.max_attitude_rad = given[0];
    out.limits.max_rotor_speed_deviation_rad_s = given[1];
    out.limits.max_swashplate_rad = given[2];
    out.limits.max_height_deviation_m = given[3];
  }
  const std::array<double, kNumLimits> limit = LimitValues(out.limits);

  // M_0: no excitation.
  Excitation none = reference_excitation;
  none.type = Excitation::Type::kNone;
  say("the flight without excitation");
  // Only its envelope is needed: where the limits stand without excitation.
  const FlightEnvelope base_envelope =
      SimulatePlannedExperiment(vehicle, WithExcitation(plan, fi, none)).envelopes[fi];
  const std::array<double, kNumLimits> base_peak = Peaks(base_envelope);
  const std::array<double, kNumLimits> base_ms = MeanSquares(base_envelope);
  say(Format("without excitation: attitude %.3g rad, rotor speed %.3g rad/s, swashplate %.3g rad, "
             "height %.3g m",
             base_peak[0], base_peak[1], base_peak[2], base_peak[3]));
  // What the design aims at: a share of each limit (the sensor noise the
  // controller feeds back moves the peaks from flight to flight).
  std::array<double, kNumLimits> target;
  for (int j = 0; j < kNumLimits; ++j) {
    target[j] = options.margin * limit[j];
    if (base_peak[j] >= limit[j]) {
      throw InputError(std::string("the flight without excitation already reaches its ") +
                       kLimitNames[j] + Format(" (%.4g against the limit %.4g): ", base_peak[j],
                                               limit[j]) +
                       "raise " + kLimitFlags[j] + " or plan gentler waypoints");
    }
  }

  // The start: the planned excitation's power per input, spread over the
  // bands in proportion to the harmonics each input gets there (a flat
  // spectrum like the planned multisine's).
  const int B = multisine ? static_cast<int>(options.bands.size()) : 0, K = 4 * B;
  std::vector<double> unit_rms(K);  // t_k = (rms_k / unit_rms_k)^2
  if (multisine) {
    const ExcitationSignal planned_signal(reference_excitation);
    const double default_rms[4] = {2.0, 2.0, 0.01, 0.01};
    const int samples = 4000;
    const double span = reference_excitation.type == Excitation::Type::kMultisine
                            ? reference_excitation.period_s
                            : plan[fi].flight.duration_s - reference_excitation.start_s;
    std::array<double, 4> power{};
    for (int i = 0; i < samples; ++i) {
      const InputVector e =
          planned_signal.At(reference_excitation.start_s + span * (i + 0.5) / samples);
      for (int c = 0; c < 4; ++c) power[c] += e[c] * e[c] / samples;
    }
    // Harmonics per input and band, dealt as ExcitationSignal deals them.
    std::vector<int> harmonics(K, 0);
    const std::vector<std::array<std::vector<int>, 4>> dealt = BandHarmonics(
        BandExcitation(reference_excitation, options.bands, std::vector<double>(K, 1.0), {}));
    for (int b = 0; b < B; ++b) {
      for (int c = 0; c < 4; ++c) harmonics[c * B + b] = static_cast<int>(dealt[b][c].size());
    }
    for (int c = 0; c < 4; ++c) {
      int total = 0;
      for (int b = 0; b < B; ++b) total += harmonics[c * B + b];
      const double channel_power = power[c] > 0 ? power[c] : default_rms[c] * default_rms[c];
      for (int b = 0; b < B; ++b) {
        unit_rms[c * B + b] = std::sqrt(channel_power * harmonics[c * B + b] / std::max(total, 1));
      }
    }
  }
  std::vector<std::array<double, 2>> quiet;
  if (options.quiet_after_waypoint_s > 0) {
    for (const Waypoint& w : plan[fi].flight.waypoints) {
      if (w.t_s > reference_excitation.start_s) {
        quiet.push_back({w.t_s - 0.5, w.t_s + options.quiet_after_waypoint_s});
      }
    }
  }
  // The plan flown with the design of variables t (powers: every peak grows
  // about as sqrt(t)); the 3211 search replaces it for each pulse width.
  std::function<std::vector<Scenario>(const Eigen::VectorXd&)> design_of =
      [&](const Eigen::VectorXd& t) {
        std::vector<double> rms(K);
        for (int k = 0; k < K; ++k) rms[k] = unit_rms[k] * std::sqrt(std::max(t[k], 0.0));
        return WithExcitation(plan, fi,
                              BandExcitation(reference_excitation, options.bands, rms, quiet));
      };
  struct Point {
    Eigen::VectorXd t;
    Evaluation flown;
    bool flew = false;
    double criterion = std::numeric_limits<double>::infinity();
    std::array<double, kNumLimits> peak{}, ms{};
    bool within = false;
  };
  auto fly = [&](const Eigen::VectorXd& t) {
    Point p;
    p.t = t;
    try {
      p.flown = Evaluate(vehicle, design_of(t), options.output_error);
      p.flew = true;
      p.criterion = objective.Value(p.flown.precision.information_scaled);
      p.peak = Peaks(p.flown.run.envelopes[fi]);
      p.ms = MeanSquares(p.flown.run.envelopes[fi]);
      p.within = true;
      for (int j = 0; j < kNumLimits; ++j) p.within &= p.peak[j] <= limit[j];
    } catch (const ComputationError&) {
      p.flew = false;  // the closed loop lost the vehicle: outside every limit
    }
    return p;
  };
  auto record = [&](const Point& p, double predicted) {
    ExcitationDesign::Round r;
    r.predicted_criterion = predicted;
    r.flown_criterion = p.criterion;
    if (p.flew) r.envelope = p.flown.run.envelopes[fi];
    r.within_limits = p.flew && p.within;
    out.rounds.push_back(r);
    say(Format("round %g: criterion %.4g (predicted %.4g, as planned %.4g)", out.rounds.size(),
               p.criterion, predicted, out.criterion_before) +
        (p.flew ? Format(", attitude %.3g rad (limit %.3g), rotor speed %.3g rad/s (%.3g)",
                         p.peak[0], limit[0], p.peak[1], limit[1]) +
                      Format(", swashplate %.3g rad (%.3g), height %.3g m (%.3g)", p.peak[2],
                             limit[2], p.peak[3], limit[3])
                : std::string(", the closed loop lost the vehicle")));
  };

  // A design's shape (how its power is shared among the components) is what
  // the search decides; its size is then the largest the limits allow. Peaks
  // the excitation makes grow about as the square root of its power: a
  // design is flown, scaled by (target / peak)^2 of the tightest limit, and
  // flown again (down when it leaves a limit, up when every peak has room),
  // keeping the best flight within the limits.
  auto fly_to_limits = [&](const Eigen::VectorXd& t, double predicted) {
    Point best, p = fly(t);
    record(p, predicted);
    for (int attempt = 0; attempt < 4; ++attempt) {
      if (p.flew && p.within && p.criterion < best.criterion) best = p;
      double scale = p.flew ? std::numeric_limits<double>::infinity() : 0.25;
      for (int j = 0; j < kNumLimits && p.flew; ++j) {
        if (p.peak[j] > 0) scale = std::min(scale, std::pow(target[j] / p.peak[j], 2));
      }
      const bool over = !(p.flew && p.within);
      if (over) {
        scale = std::clamp(scale, 0.05, 0.95);
      } else if (scale > 1.3 && attempt == 0) {
        scale = std::min(scale, 4.0);  // room left on every limit: larger
      } else {
        break;
      }
      p = fly(p.t * scale);
      record(p, NAN);
    }
    if (p.flew && p.within && p.criterion < best.criterion) best = p;
    return best.flew ? best : p;
  };
  if (!multisine) {
    // A 3211 train: each pulse width of the grid whose four-input cycle (40
    // units) fits the excitation time, flown at the planned levels scaled to
    // the limits; then, at the best width, each input's share of the power
    // doubled or halved (and flown to the limits again) while that helps.
    std::array<double, 4> planned_level;
    const double default_level[4] = {4.0, 4.0, 0.02, 0.02};
    for (int c = 0; c < 4; ++c) {
      const auto it = reference_excitation.amplitude.find(kInputs[c]);
      planned_level[c] = it != reference_excitation.amplitude.end() && it->second > 0
                             ? it->second
                             : default_level[c];
    }
    auto train = [&](double width) {
      return [&, width](const Eigen::VectorXd& t) {
        Excitation e;
        e.type = Excitation::Type::k3211;
        e.start_s = reference_excitation.start_s;
        e.pulse_s = width;
        e.quiet = quiet;
        for (int c = 0; c < 4; ++c) e.amplitude[kInputs[c]] = planned_level[c] * std::sqrt(std::max(t[c], 0.0));
        return WithExcitation(plan, fi, e);
      };
    };
    const double room_s = plan[fi].flight.duration_s - reference_excitation.start_s;
    Point best;
    double best_width = 0;
    for (double width : options.pulse_widths_s) {
      if (!(width > 0) || 40 * width > room_s) continue;
      say(Format("3211 with %.3g s pulses", width));
      design_of = train(width);
      const Point p = fly_to_limits(Eigen::VectorXd::Ones(4), NAN);
      if (p.flew && p.within && p.criterion < best.criterion) {
        best = p;
        best_width = width;
      }
    }
    if (!(best_width > 0)) {
      throw ComputationError(Format("no 3211 of the pulse widths given both fits the %.3g s of "
                                    "excitation (a cycle of the four inputs is 40 pulse widths) "
                                    "and stays within the limits",
                                    room_s));
    }
    design_of = train(best_width);
    for (int pass = 0, improved = 1; improved && pass < options.max_rounds; ++pass) {
      improved = 0;
      for (int c = 0; c < 4; ++c) {
        for (double factor : {2.0, 0.5}) {
          Eigen::VectorXd t = best.t;
          t[c] *= factor;
          say(Format("3211 with %.3g s pulses: input %g's share x %g", best_width, c + 1, factor));
          const Point p = fly_to_limits(t, NAN);
          if (p.flew && p.within && p.criterion < best.criterion) {
            best = p;
            improved = 1;
            break;
          }
        }
      }
    }
    out.pulse_s = best_width;
    out.designed = design_of(best.t);
    out.designed_run = std::move(best.flown.run);
    out.after = std::move(best.flown.precision);
    out.criterion_after = best.criterion;
    for (int c = 0; c < 4; ++c) {
      ExcitationDesign::Component component;
      component.channel = kInputs[c];
      component.planned_level = planned_level[c];
      component.designed_level = planned_level[c] * std::sqrt(std::max(best.t[c], 0.0));
      out.components.push_back(component);
    }
    out.seconds = SecondsSince(start);
    say(Format("done: 3211 with %.3g s pulses, criterion %.4g -> %.4g", best_width,
               out.criterion_before, out.criterion_after));
    return out;
  }

  Point current = fly_to_limits(Eigen::VectorXd::Ones(K), NAN);
  if (!(current.flew && current.within)) {
    throw ComputationError("even a weak multisine leaves the limits: the limits leave the "
                           "excitation almost no room (raise them, or plan gentler waypoints)");
  }

  // Sequential local models: around the current design, the information
  // and the flight's mean squares as linear in each component's power
  // (one flight more per component), a convex step inside a trust region,
  // flown; kept when it is better and within the limits.
  double rho = 16.0;  // each power may grow or shrink by this factor in a step
  std::array<double, kNumLimits> crest;
  crest.fill(3.0);  // a multisine's peak over its rms, before one is measured
  for (int iteration = 0; iteration < options.max_rounds && rho > 1.2; ++iteration) {
    const Eigen::MatrixXd& Mc = current.flown.precision.information_scaled;
    const Eigen::LLT<Eigen::MatrixXd> llt(Mc + 1e-12 * Mc.trace() *
                                                   Eigen::MatrixXd::Identity(Mc.rows(), Mc.rows()));
    const Eigen::MatrixXd L = llt.matrixL();
    const Eigen::MatrixXd L_inverse = L.triangularView<Eigen::Lower>().solve(
        Eigen::MatrixXd::Identity(Mc.rows(), Mc.rows()));
    std::vector<Eigen::MatrixXd> G(K);
    Eigen::MatrixXd V(kNumLimits, K);  // d ms_j / d t_k: mean squares add up over components
    const double t_scale = std::max(current.t.maxCoeff(), 1e-6);
    for (int k = 0; k < K; ++k) {
      const double delta = std::max(0.5 * current.t[k], 0.05 * t_scale);
      Eigen::VectorXd t = current.t;
      t[k] += delta;
      say(Format("round %g, local model %g of %g", out.rounds.size() + 1, k + 1, K));
      const Point probe = fly(t);
      if (!probe.flew) {
        G[k] = Eigen::MatrixXd::Zero(Mc.rows(), Mc.cols());
        V.col(k).setConstant(1e6);  // the loop cannot take more of this component
        continue;
      }
      // Whitened by the current information, where the integration's error
      // is relative, then back.
      G[k] = L * PositivePart(L_inverse * (probe.flown.precision.information_scaled - Mc) *
                              L_inverse.transpose()) *
             L.transpose() / delta;
      for (int j = 0; j < kNumLimits; ++j) V(j, k) = std::max(0.0, probe.ms[j] - current.ms[j]) / delta;
    }
    // Limits: outside the quiet windows a peak is the excitation's, its crest
    // factor times the rms the excitation adds, crest_j^2 (ms_j - ms_j(0)) <=
    // target_j^2 with ms_j = ms_j(t_c) + V (t - t_c), the crest factor from
    // the current flight when the excitation makes its peak; the trust
    // region as rows of the same polytope.
    for (int j = 0; j < kNumLimits; ++j) {
      const double excited = current.ms[j] - base_ms[j];
      if (current.peak[j] > base_peak[j] && excited > 0) crest[j] = current.peak[j] / std::sqrt(excited);
    }
    Eigen::MatrixXd A(kNumLimits + 2 * K, K);
    Eigen::VectorXd b(kNumLimits + 2 * K);
    A.setZero();
    for (int j = 0; j < kNumLimits; ++j) {
      A.row(j) = V.row(j);
      const double room = std::pow(target[j] / crest[j], 2) + base_ms[j] - current.ms[j];
      b[j] = std::max(room, 1e-9 * std::max(current.ms[j], 1e-300)) + V.row(j).dot(current.t);
    }
    const double floor = 1e-4 * t_scale;
    for (int k = 0; k < K; ++k) {
      A(kNumLimits + k, k) = 1;  // t_k <= rho max(t_k, floor)
      b[kNumLimits + k] = rho * std::max(current.t[k], floor);
      A(kNumLimits + K + k, k) = -1;  // t_k >= max(t_k, floor) / rho... as -t_k <= -lower
      b[kNumLimits + K + k] = -std::max(current.t[k], floor) / rho;
    }
    auto information = [&](const Eigen::VectorXd& t) {
      Eigen::MatrixXd M = Mc;
      for (int k = 0; k < K; ++k) M += (t[k] - current.t[k]) * G[k];
      return M;
    };
    auto f = [&](const Eigen::VectorXd& t) { return objective.Value(information(t)); };
    auto grad = [&](const Eigen::VectorXd& t) { return objective.Gradient(information(t), G); };
    Eigen::VectorXd t0 = current.t.cwiseMax(floor);
    // A strictly feasible start inside the polytope: shrink towards the lower trust bound.
    for (int i = 0; i < 60 && !((b - A * t0).array() > 0).all(); ++i) {
      t0 = 0.9 * t0 + 0.1 * (current.t.cwiseMax(floor) / (rho * 0.99));
    }
    if (!((b - A * t0).array() > 0).all() || !std::isfinite(f(t0))) {
      rho = std::sqrt(rho);
      continue;
    }
    const Eigen::VectorXd t_new = MinimiseOnPolytope(f, grad, A, b, t0);
    const double predicted = f(t_new);
    const Point next = fly_to_limits(t_new, predicted);
    if (next.flew && next.within && next.criterion < current.criterion) {
      const bool good = current.criterion - next.criterion > 0.5 * (current.criterion - predicted);
      current = next;
      if (good) rho = std::min(2 * rho, 64.0);
    } else {
      rho = std::sqrt(rho);
    }
  }
  out.designed = design_of(current.t);
  out.designed_run = std::move(current.flown.run);
  out.after = std::move(current.flown.precision);
  out.criterion_after = current.criterion;
  for (int c = 0; c < 4; ++c) {
    for (int b2 = 0; b2 < B; ++b2) {
      const int k = c * B + b2;
      ExcitationDesign::Component component;
      component.channel = kInputs[c];
      component.band = options.bands[b2];
      component.planned_rms = unit_rms[k];
      component.designed_rms = unit_rms[k] * std::sqrt(std::max(current.t[k], 0.0));
      out.components.push_back(component);
    }
  }
  out.seconds = SecondsSince(start);
  say(Format("done: criterion %.4g -> %.4g", out.criterion_before, out.criterion_after));
  return out;
}

}  // namespace coaxid
