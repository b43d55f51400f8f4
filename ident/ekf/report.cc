#include "ident/ekf/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <glog/logging.h>

#include "core/report.h"
#include "dynamics/outputs.h"
#include "dynamics/simulator.h"
#include "ident/ekf/history_csv.h"

namespace coaxid {
namespace {

using nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// NaN and infinity have no JSON form: null.
json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace

// Every k-th index so that at most 3000 remain.
int EkfPlotStride(size_t n) {
  constexpr size_t kMaxPoints = 3000;
  return static_cast<int>(std::max<size_t>(1, (n + kMaxPoints - 1) / kMaxPoints));
}

std::vector<int> WindowStartRows(const EstimationLog& log, double window_s) {
  std::vector<int> starts;
  const int N = log.NumRows();
  int a = 0;
  while (a < N) {
    starts.push_back(a);
    int b = a + 1;
    while (b < N && log.inputs.time(b) < log.inputs.time(a) + window_s - 1e-9) ++b;
    a = b;
  }
  return starts;
}

Eigen::MatrixXd WindowPredictions(const Vehicle& vehicle, const EstimationLog& log,
                                  const Eigen::MatrixXd& start_states, double window_s,
                                  const IntegratorOptions& integrator, int* failed_windows) {
  std::vector<Eigen::VectorXd> starts;
  for (const int row : WindowStartRows(log, window_s)) {
    starts.push_back(start_states.row(row).transpose());
  }
  return WindowPredictions(vehicle, log, starts, window_s, integrator, failed_windows);
}

Eigen::MatrixXd WindowPredictions(const Vehicle& vehicle, const EstimationLog& log,
                                  const std::vector<Eigen::VectorXd>& window_start_states,
                                  double window_s, const IntegratorOptions& integrator,
                                  int* failed_windows) {
  const int N = log.NumRows();
  const std::vector<int> starts = WindowStartRows(log, window_s);
  CHECK_EQ(starts.size(), window_start_states.size());
  const Eigen::VectorXd theta = vehicle.parameters.Values();
  Simulator simulator(vehicle.model, theta, integrator);
  Eigen::MatrixXd out = Eigen::MatrixXd::Constant(N, log.NumChannels(), kNaN);
  Trajectory trajectory;
  const HeldInputPath path(log.inputs);
  const InputVector lag = vehicle.model.InputLags(theta.data());
  double y[kNumFlightChannels];
  for (size_t w = 0; w < starts.size(); ++w) {
    // Window rows [a, b), from the state at row a.
    const int a = starts[w];
    const int b = w + 1 < starts.size() ? starts[w + 1] : N;
    // A start without the model's effect states (a 12-state table): at rest.
    const Eigen::VectorXd x0 = vehicle.model.StateOf(window_start_states[w]);
    bool ok = x0.allFinite();
    const HeldInput start = path.At(a, lag);
    if (ok && b - 1 > a) {
      ok = simulator.Run(log.inputs, a, b - 1, x0, &trajectory, &start);
    } else if (ok) {
      trajectory.states.assign(1, x0);
      trajectory.inputs.assign(1, start);
    }
    if (!ok) {
      if (failed_windows) ++*failed_windows;
      continue;
    }
    for (int k = a; k < b; ++k) {
      const Eigen::VectorXd& x = trajectory.states[k - a];
      FlightOutputsAt(vehicle.model, theta.data(), x.data(), trajectory.inputs[k - a], y);
      for (int c = 0; c < log.NumChannels(); ++c) out(k, c) = y[log.channels[c]];
    }
  }
  return out;
}

json EkfReportJson(const EkfResult& r, const EkfOptions& options, const ParameterSet& initial,
                   const EkfReportContext& context) {
  json report;
  report["method"] = "ekf";
  report["logs"] = context.logs;
  if (!context.validation_logs.empty()) report["validation_logs"] = context.validation_logs;

  // Parameters: every parameter of the set.
  json parameters = json::object();
  auto free_position = [&](const std::string& name) {
    for (size_t k = 0; k < r.free_names.size(); ++k) {
      if (r.free_names[k] == name) return static_cast<int>(k);
    }
    return -1;
  };
  for (int i = 0; i < r.parameters.size(); ++i) {
    const Parameter& p = r.parameters[i];
    json entry;
    entry["value"] = Number(p.value);
    const int k = free_position(p.name);
    if (k >= 0) {
      const bool identifiable = r.identifiable[k];
      entry["std"] = identifiable ? Number(r.estimate_std[k]) : json(nullptr);
      entry["estimated"] = true;
      entry["identifiable"] = identifiable;
      entry["filter_std"] = Number(r.filter_std[k]);
      entry["initial"] = Number(initial[i].value);
      entry["initial_std"] = Number(std::sqrt(r.prior_covariance(k, k)) * r.scales[k]);
      entry["settled_after_s"] = Number(r.settled_after_s[k]);
      if (!identifiable) {
        entry["note"] = "not separately identifiable from these logs: they reduce the prior "
                        "variance by less than half along a direction that loads on it (see "
                        "ekf.undetermined_directions; for the scale of model.md decision 8, "
                        "the scale-free ratios)";
      }
    } else {
      entry["std"] = nullptr;
      entry["estimated"] = false;
      std::string source = "config";
      if (i < kAlpha) source = "config: known constant";
      if (i >= kAlpha) {
        source = "config: estimated: false";
      }
      entry["source"] = source;
    }
    if (!p.unit.empty()) entry["unit"] = p.unit;
    parameters[p.name] = entry;
  }
  MarkHeldForTheScale(r.gauge, &parameters);
  report["parameters"] = parameters;
  report["scale"] = r.gauge.ToJson();
  report["scale"]["anchor_option"] =
      options.scale_anchor == ScaleAnchor::kHubDistance
          ? "d (hold d when nothing else fixes the scale)"
          : "none (augment all; report the undetermined direction)";
  report["ratios"] = RatiosJson(r.ratios);

  const std::string fit_definition =
      "model = open-loop prediction over consecutive windows of window_s, each started from "
      "the state estimated at its first row with the final parameters (" + context.fit_states +
      "); accelerometer with each row's inputs";
  report["fit"] = FitJson(context.fit);
  report["fit"]["overall_nrmse"] = Number(report["fit"]["overall_nrmse"].get<double>());
  report["fit"]["definition"] = fit_definition;
  report["fit"]["window_s"] = context.window_s;
  if (context.failed_fit_windows > 0) report["fit"]["failed_windows"] = context.failed_fit_windows;
  report["validation"] = FitJson(context.validation);
  report["validation"]["overall_nrmse"] =
      Number(report["validation"]["overall_nrmse"].get<double>());
  report["validation"]["data"] = context.validation_description;
  report["validation"]["definition"] =
      "as fit, with window states from the same filter run on the validation data with every "
      "parameter held at the estimates";
  report["validation"]["window_s"] = context.window_s;
  if (context.failed_validation_windows > 0) {
    report["validation"]["failed_windows"] = context.failed_validation_windows;
  }

  // The filter.
  json ekf;
  ekf["estimates_from"] = r.estimates_from;
  ekf["passes"] = r.covariance_pass ? 2 : 1;
  ekf["transition"] = EkfTransitionMethodName(options.transition);
  ekf["smoother"] = options.smoother;
  ekf["augmented"] = r.free_names;
  ekf["parameter_coordinates"] = "value / scale (the config's scale)";
  json psd = json::object();
  for (int i = 0; i < kNumStates; ++i) psd[StateName(i)] = options.state_psd[i];
  ekf["process_noise"] = {
      {"state_psd", psd},
      {"state_psd_units", "(state unit)^2 / s"},
      {"effect_state_psd", options.effect_state_psd},
      {"parameter_psd_scaled", options.parameter_psd},
      {"parameter_psd_by_name", options.parameter_psd_by_name}};
  ekf["initial_parameter_std_scaled"] = options.initial_parameter_std;
  json noise = json::object(), noise_initial = json::object();
  for (const auto& [name, s] : r.noise.std) noise[name] = Number(s);
  for (const auto& [name, s] : r.noise_initial.std) noise_initial[name] = Number(s);
  ekf["measurement_noise"] = {
      {"std", noise},
      {"initial_std", noise_initial},
      {"initial_source", context.noise_source},
      {"adaptations", options.noise_adaptations},
      {"adaptation_rows", options.noise_adaptation_rows},
      {"adaptation", "R_ii = mean(nu_i^2 - (H P H^T)_ii) over the estimation pass's updates "
                     "after the burn-in (Mehra 1970), then the estimation is run again"}};
  ekf["integrator"] = {{"relative_tolerance", options.integrator.relative_tolerance},
                       {"absolute_tolerance", options.integrator.absolute_tolerance}};

  json nis_channels = json::object();
  bool all_consistent = r.total_nis.consistent();
  for (const NisStatistic& s : r.channel_nis) {
    nis_channels[s.channel] = {{"mean", Number(s.mean)},
                               {"band_95", {Number(s.lower), Number(s.upper)}},
                               {"consistent", s.consistent()},
                               {"samples", s.dof},
                               {"innovation_rms", Number(s.innovation_rms)}};
  }
  ekf["nis"] = {
      {"definition", "normalised innovation squared per degree of freedom of the estimation "
                     "pass (nu_i^2 / S_ii per channel; nu^T S^-1 nu / m for all), mean over "
                     "the updates after the burn-in; band_95: the two-sided 95 % band of that "
                     "mean for a consistent filter (chi-square); expected 1"},
      {"burn_in_s", options.nis_burn_in_s},
      {"channels", nis_channels},
      {"all", {{"mean", Number(r.total_nis.mean)},
               {"band_95", {Number(r.total_nis.lower), Number(r.total_nis.upper)}},
               {"consistent", r.total_nis.consistent()},
               {"degrees_of_freedom", r.total_nis.dof}}},
      {"consistent", all_consistent}};
  ekf["log_likelihood"] = Number(r.log_likelihood);
  if (r.covariance_pass) {
    ekf["refinement"] = {
        {"definition", "Gauss-Newton steps of the filter's likelihood (parameters held in the "
                       "mean) from the estimation pass's estimate, until no parameter's step "
                       "exceeds tolerance_std of its std or the likelihood stops rising along "
                       "the step; largest_step_std: the largest step in std at that estimate "
                       "and at the reported one; converged: false when max_steps stopped it, "
                       "or a step above unconverged_step_std that does not raise the "
                       "likelihood (short_of_maximum: the parameters it would move)"},
        {"steps", r.refinements},
        {"max_steps", options.max_refinements},
        {"tolerance_std", options.refine_tolerance_std},
        {"unconverged_step_std", options.unconverged_step_std},
        {"short_of_maximum", r.short_of_maximum},
        {"largest_step_std", {{"estimation_pass", Number(r.step_std_at_pass1)},
                              {"reported", Number(r.step_std_at_estimate)}}},
        {"log_likelihood", {{"estimation_pass", Number(r.frozen_log_likelihood_at_pass1)},
                            {"reported", Number(r.frozen_log_likelihood)}}},
        {"converged", r.refinement_converged},
        {"stopped_because", r.refinement_stop}};
  }

  json undetermined = json::array();
  for (const UndeterminedDirection& d : r.undetermined) {
    json components = json::object();
    for (size_t k = 0; k < r.free_names.size(); ++k) {
      components[r.free_names[k]] = Number(d.direction[k]);
    }
    undetermined.push_back({{"variance_ratio", Number(d.variance_ratio)},
                            {"cos_to_scale_direction", Number(d.cos_to_scale)},
                            {"components_scaled", components}});
  }
  ekf["undetermined_directions"] = undetermined;
  ekf["undetermined_threshold"] = options.undetermined_variance_ratio;
  ekf["clamped_to_bounds"] = r.clamped;
  json rejected = json::object();
  for (const auto& [channel, count] : r.rejected) rejected[channel] = count;
  ekf["innovation_gate"] = {
      {"probability", options.gate_probability},
      {"threshold_nis", options.gate_probability > 0
                            ? json(Number(InnovationGateThreshold(options.gate_probability)))
                            : json(nullptr)},
      {"max_s", options.gate_max_s},
      {"definition", "a sample whose nu^2 / S of its own channel exceeds the chi-square(1) "
                     "quantile at 1 - probability is rejected as a glitch (estimation pass); "
                     "a channel rejected for longer than max_s without a break stops the "
                     "filter with an error naming it"},
      {"rejected_samples", rejected}};
  ekf["effort"] = {
      {"rows_per_pass", r.rows},
      {"updates", r.updates},
      {"seconds", {{"total", r.total_s},
                   {"estimation_pass", r.estimation_pass_s},
                   {"covariance_pass", r.covariance_pass_s},
                   {"propagation", r.propagation_s},
                   {"update", r.update_s},
                   {"smoother", r.smoother_s}}},
      {"cvode_steps", r.integrator.steps},
      {"rhs_evaluations", r.integrator.rhs_evals},
      {"model_jacobians", r.propagation.jacobians}};
  report["ekf"] = ekf;
  report["outputs"] = context.outputs;
  std::vector<std::string> notes = r.notes;
  notes.insert(notes.end(), context.notes.begin(), context.notes.end());
  report["notes"] = notes;
  return report;
}

void EkfStatesCsv(const EkfResult& r, const EmitText& emit) {
  TextPieces pieces(emit);
  const bool smoothed = !r.logs.empty() && r.logs[0].smoothed_states.size() > 0;
  const std::vector<std::string> names =
      r.logs.empty() ? std::vector<std::string>() : r.logs[0].state_names;
  const int nx = static_cast<int>(names.size());
  pieces.text = EkfStatesCsvHeader(names, smoothed);
  Eigen::MatrixXd row(nx, 4);  // x, std, smoothed x, smoothed std
  for (const EkfLogHistory& h : r.logs) {
    const std::string name = EkfCsvLogName(h.name);
    for (size_t k = 0; k < h.times.size(); ++k) {
      row.col(0) = h.states.row(k).transpose();
      row.col(1) = h.state_std.row(k).transpose();
      if (smoothed) {
        row.col(2) = h.smoothed_states.row(k).transpose();
        row.col(3) = h.smoothed_state_std.row(k).transpose();
      }
      AppendEkfStatesCsvRow(name, h.times[k], nx, row.col(0).data(), row.col(1).data(),
                            smoothed ? row.col(2).data() : nullptr,
                            smoothed ? row.col(3).data() : nullptr, &pieces.text);
      pieces.EndOfRow();
    }
  }
}

void EkfParametersCsv(const EkfResult& r, const EmitText& emit) {
  TextPieces pieces(emit);
  const bool at_estimate = r.covariance_pass;
  const int np = static_cast<int>(r.free_names.size());
  pieces.text = EkfParametersCsvHeader(r.free_names, at_estimate);
  Eigen::MatrixXd row(np, 3);  // value, std, std at the estimate
  for (const EkfLogHistory& h : r.logs) {
    const std::string name = EkfCsvLogName(h.name);
    for (size_t k = 0; k < h.times.size(); ++k) {
      row.col(0) = h.parameters.row(k).transpose();
      row.col(1) = h.parameter_std.row(k).transpose();
      if (at_estimate) row.col(2) = h.parameter_std_at_estimate.row(k).transpose();
      AppendEkfParametersCsvRow(name, h.times[k], np, row.col(0).data(), row.col(1).data(),
                                at_estimate ? row.col(2).data() : nullptr, &pieces.text);
      pieces.EndOfRow();
    }
  }
}

void EkfInnovationsCsv(const EkfResult& r, const EmitText& emit) {
  TextPieces pieces(emit);
  std::vector<std::vector<std::string>> names;
  for (const EkfLogHistory& h : r.logs) names.push_back(h.channel_names);
  const std::vector<std::string> channels = EkfInnovationChannels(names);
  pieces.text = EkfInnovationsCsvHeader(channels);
  for (const EkfLogHistory& h : r.logs) {
    const std::vector<int> column = EkfInnovationColumns(channels, h.channel_names);
    const std::string name = EkfCsvLogName(h.name);
    Eigen::MatrixXd row(h.channel_names.size(), 2);  // nu, sqrt(S_ii) per column of the log
    for (size_t k = 0; k < h.times.size(); ++k) {
      row.col(0) = h.innovations.row(k).transpose();
      row.col(1) = h.innovation_std.row(k).transpose();
      AppendEkfInnovationsCsvRow(name, h.times[k], column, row.col(0).data(), row.col(1).data(),
                                 h.nis[k], h.nis_dof[k], &pieces.text);
      pieces.EndOfRow();
    }
  }
}

std::vector<EkfFigure> EkfFigures(const EkfResult& r,
                                  const std::vector<Eigen::MatrixXd>& fit_predictions) {
  std::vector<EkfFigure> figures;
  // Parameters along the chained logs.
  if (!r.free_names.empty()) {
    Figure f;
    f.title = "EKF parameter estimates with their 3-sigma band (estimation pass); dotted: final "
              "estimate +- 3 reported std";
    f.columns = 3;
    for (size_t j = 0; j < r.free_names.size(); ++j) {
      PlotPanel panel;
      panel.title = r.free_names[j];
      panel.x_label = "t [s] (logs chained)";
      const bool legend = j == 0;  // one legend for the figure
      PlotSeries estimate{legend ? "estimate" : "", {}, {}, "lines lw 2"};
      PlotSeries upper{legend ? "+-3 sigma" : "", {}, {}, "lines dt 2 lc rgb 'gray40'"};
      PlotSeries lower{"", {}, {}, "lines dt 2 lc rgb 'gray40'"};
      double offset = 0;
      for (const EkfLogHistory& h : r.logs) {
        const int stride = h.rows.empty() ? EkfPlotStride(h.times.size() * r.logs.size()) : 1;
        for (size_t k = 0; k < h.times.size(); k += stride) {
          const double t = offset + h.times[k] - h.times[0];
          const double v = h.parameters(k, j), s = h.parameter_std(k, j);
          estimate.x.push_back(t);
          estimate.y.push_back(v);
          upper.x.push_back(t);
          upper.y.push_back(v + 3 * s);
          lower.x.push_back(t);
          lower.y.push_back(v - 3 * s);
        }
        offset += h.times.back() - h.times.front();
      }
      panel.series = {estimate, upper, lower};
      const double final_std = r.identifiable[j] ? r.estimate_std[j] : kNaN;
      if (std::isfinite(final_std)) {
        for (double sign : {-1.0, 1.0}) {
          panel.series.push_back({sign > 0 && legend ? "final +-3 std" : "",
                                  {0.0, offset},
                                  {r.estimate[j] + sign * 3 * final_std,
                                   r.estimate[j] + sign * 3 * final_std},
                                  "lines dt 3 lc rgb 'red'"});
        }
        // Keep the axis on the converged part: the prior band is wide.
        panel.y_min = r.estimate[j] - 12 * final_std;
        panel.y_max = r.estimate[j] + 12 * final_std;
      }
      f.panels.push_back(panel);
    }
    figures.push_back({"parameters.png", f});
  }
  for (size_t L = 0; L < r.logs.size(); ++L) {
    const EkfLogHistory& h = r.logs[L];
    const int stride = h.rows.empty() ? EkfPlotStride(h.times.size()) : 1;
    // Innovations.
    Figure innovations;
    innovations.title = "EKF innovations (estimation pass), " + h.source + ": points; +-3 sqrt(S_ii)";
    innovations.columns = 3;
    for (size_t c = 0; c < h.channel_names.size(); ++c) {
      PlotPanel panel;
      panel.title = h.channel_names[c];
      panel.x_label = "t [s]";
      PlotSeries nu{"", {}, {}, "points pt 7 ps 0.3"};
      PlotSeries up{"", {}, {}, "lines lc rgb 'red'"}, down{"", {}, {}, "lines lc rgb 'red'"};
      for (size_t k = 0; k < h.times.size(); k += stride) {
        nu.x.push_back(h.times[k]);
        nu.y.push_back(h.innovations(k, c));
        up.x.push_back(h.times[k]);
        up.y.push_back(3 * h.innovation_std(k, c));
        down.x.push_back(h.times[k]);
        down.y.push_back(-3 * h.innovation_std(k, c));
      }
      panel.series = {nu, up, down};
      innovations.panels.push_back(panel);
    }
    figures.push_back({"innovations_" + h.name + ".png", innovations});

    // States: measured and estimated.
    const bool smoothed = h.smoothed_states.size() > 0;
    const Eigen::MatrixXd& estimate = smoothed ? h.smoothed_states : h.states;
    Figure states;
    states.title = std::string("EKF states, ") + h.source + ": measured (points), " +
                   (smoothed ? "smoothed" : "filtered") + " (line)";
    states.columns = 3;
    for (int i = 0; i < kNumStates; ++i) {
      PlotPanel panel;
      panel.title = StateName(i);
      panel.x_label = "t [s]";
      PlotSeries measured{"", {}, {}, "points pt 7 ps 0.3 lc rgb 'gray50'"};
      PlotSeries line{"", {}, {}, "lines lw 2"};
      int col = -1;
      for (size_t c = 0; c < h.channels.size(); ++c) {
        if (h.channels[c] == i) col = static_cast<int>(c);
      }
      for (size_t k = 0; k < h.times.size(); k += stride) {
        if (col >= 0) {
          measured.x.push_back(h.times[k]);
          measured.y.push_back(h.measured(k, col));
        }
        line.x.push_back(h.times[k]);
        line.y.push_back(estimate(k, i));
      }
      if (col >= 0) panel.series.push_back(measured);
      panel.series.push_back(line);
      states.panels.push_back(panel);
    }
    figures.push_back({"states_" + h.name + ".png", states});

    // Fit windows.
    if (L < fit_predictions.size()) {
      Figure fit;
      fit.title = "Fit, " + h.source + ": measured (points) and window predictions (line)";
      fit.columns = 3;
      for (size_t c = 0; c < h.channel_names.size(); ++c) {
        PlotPanel panel;
        panel.title = h.channel_names[c];
        panel.x_label = "t [s]";
        PlotSeries measured{"", {}, {}, "points pt 7 ps 0.3 lc rgb 'gray50'"};
        PlotSeries model{"", {}, {}, "lines lw 2"};
        for (size_t k = 0; k < h.times.size(); k += stride) {
          measured.x.push_back(h.times[k]);
          measured.y.push_back(h.measured(k, c));
          model.x.push_back(h.times[k]);
          model.y.push_back(fit_predictions[L](k, c));
        }
        panel.series = {measured, model};
        fit.panels.push_back(panel);
      }
      figures.push_back({"fit_" + h.name + ".png", fit});
    }
  }
  return figures;
}

}  // namespace coaxid
