#include "ident/baseline/report.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/report.h"
#include "core/report_values.h"

namespace coaxid {
namespace {

using nlohmann::json;

// NaN and infinity have no JSON form: null.
json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

std::string Csv(double v) {
  if (std::isnan(v)) return "";
  return Significant(v, 10);
}

json ValueStd(double value, double std) { return {{"value", Number(value)}, {"std", Number(std)}}; }

json FitSection(const ChannelFits& fits) {
  std::map<std::string, FitError> errors;
  for (int c = 0; c < kNumLoadChannels; ++c) {
    if (fits[c].error.count > 0) errors[LoadChannelName(c)] = fits[c].error;
  }
  json out = FitJson(errors);
  for (int c = 0; c < kNumLoadChannels; ++c) {
    if (fits[c].error.count == 0) continue;
    json& channel = out[LoadChannelName(c)];
    channel["rms"] = Number(fits[c].error.rms);
    channel["nrmse"] = Number(fits[c].error.nrmse);
    channel["peak"] = Number(fits[c].peak);
    channel["mean_relative_error"] = Number(fits[c].mean_relative_error);
    channel["max_relative_error"] = Number(fits[c].max_relative_error);
    channel["hold_mean_relative_error"] = Number(fits[c].hold_mean_relative_error);
    channel["hold_max_relative_error"] = Number(fits[c].hold_max_relative_error);
    channel["used_in_estimation"] = c != kLoadX && c != kLoadY;
  }
  out["overall_nrmse"] = Number(out["overall_nrmse"].get<double>());  // NaN -> null
  out["relative_error_definition"] =
      "|measured - model| / max|measured| of the channel over these data; mean and max over "
      "samples, and over hold means (hold_*)";
  return out;
}

json Witness(const WitnessPair& w, const std::vector<Reconstruction>& parts) {
  auto where = [&](int i, int row) -> json {
    if (i < 0 || i >= static_cast<int>(parts.size())) return nullptr;
    const BalanceData& d = *parts[i].data;
    return {{"data", d.source}, {"row", d.first_log_row + row + 1}};
  };
  return {{"found", w.found},
          {"sine", Number(w.sine)},
          {"a", where(w.data_a, w.row_a)},
          {"b", where(w.data_b, w.row_b)}};
}

std::vector<double> ToVector(const ThetaVector& v) { return {v.data(), v.data() + v.size()}; }

}  // namespace

json LinearBaselineReportJson(const LinearBaselineResult& r, const ParameterSet& config,
                              const BaselineReportContext& context) {
  json report;
  report["method"] = "linear_kf";
  report["logs"] = context.logs;
  if (!context.validation_logs.empty()) report["validation_logs"] = context.validation_logs;

  // Parameters: the paper's Theta, alpha, Cz, sigma0; then the config's.
  json parameters = json::object();
  const char* units[kNumTheta] = {"N s^2", "N s^2", "N s^2", "N m s^2", "N m s^2"};
  const char* sources[kNumTheta] = {
      "Kalman filter (eqs. 69-70, 80-82); through L and M with d from the config",
      "Kalman filter (Z_bar)", "Kalman filter (Z_bar, separated from beta through L and M)",
      "Kalman filter (N)", "Kalman filter (N)"};
  for (int i = 0; i < kNumTheta; ++i) {
    const BaselineEstimate e = r.Parameter(i);
    parameters[ThetaName(i)] = {
        {"value", Number(e.value)}, {"std", Number(e.std)},
        {"estimated", true},        {"std_from_filter", Number(r.std_from_filter[i])},
        {"unit", units[i]},         {"source", sources[i]}};
  }
  const BaselineEstimate alpha = r.Parameter(kPsiAlpha);
  parameters["alpha"] = {{"value", Number(alpha.value)},
                         {"std", Number(alpha.std)},
                         {"estimated", true},
                         {"unit", "N s^2"},
                         {"source",
                          "thrust map: upper rotor alone, delta = 0 (paper Fig. 8), "
                          "with Cz assumed from the config"}};
  parameters["Cz"] = {{"value", Number(r.Cz_from_beta.value)},
                      {"std", Number(r.Cz_from_beta.std)},
                      {"estimated", true},
                      {"source", "Cz_beta / beta (eq. 65)"},
                      {"from_Cz_alpha", ValueStd(r.Cz_from_alpha.value, r.Cz_from_alpha.std)},
                      {"from_Cz_beta", ValueStd(r.Cz_from_beta.value, r.Cz_from_beta.std)},
                      {"difference_in_std", Number(r.Cz_difference_in_std)},
                      {"disagree", r.Cz_disagree},
                      {"assumed_for_thrust_map", Number(r.Cz_assumed)}};
  parameters["sigma0"] = {{"value", Number(r.thrust_map.sigma0)},
                          {"std", Number(r.thrust_map.sigma0_std)},
                          {"estimated", true},
                          {"source",
                           "least-squares fit of the sigma map (paper Fig. 9) to "
                           "model.md's parametric form"}};
  for (int i = 0; i < config.size(); ++i) {
    const Parameter& p = config[i];
    if (parameters.contains(p.name)) continue;
    std::string source = "config: not determined by a balance experiment";
    if (i < kAlpha) source = "config: known constant";
    if (p.name == "d") source = "config: a measured length (model.md decision 6), not estimated";
    if (p.name.find('.') != std::string::npos) {
      source = "config: effect parameter, not in the paper's linear model";
    }
    parameters[p.name] = {
        {"value", Number(p.value)}, {"std", nullptr}, {"estimated", false}, {"source", source}};
    if (!p.unit.empty()) parameters[p.name]["unit"] = p.unit;
  }
  report["parameters"] = parameters;

  report["fit"] = FitSection(r.fit);
  report["validation"] = FitSection(r.validation_fit);
  report["validation"]["data"] = context.validation_description;

  // Noise covariance (eqs. 83-84).
  json noise = json::array();
  for (size_t i = 0; i < r.noise.size(); ++i) {
    json channels = json::object();
    for (int c = 0; c < kNumLoadChannels; ++c) {
      const ChannelNoise& n = r.noise[i].channel[c];
      if (n.source == NoiseSource::kAbsent) continue;
      channels[LoadChannelName(c)] = {
          {"variance", Number(n.variance)}, {"std", Number(std::sqrt(n.variance))},
          {"dof", Number(n.dof)},           {"source", NoiseSourceName(n.source)},
          {"floored", n.floored},           {"used_in_estimation", c != kLoadX && c != kLoadY}};
    }
    noise.push_back({{"data", r.estimation[i].data->source}, {"channels", channels}});
  }
  report["noise_covariance"] = {
      {"method",
       "pooled within-hold variance of each load about its hold mean (paper eqs. "
       "83-84); residual variance of the fitted model where the holds have no spread "
       "(steady points)"},
      {"data_sets", noise}};

  // Persistent excitation (Lemma 1, eqs. 71-79, 73-74).
  const ExcitationReport& e = r.excitation;
  report["excitation"] = {{"exciting", e.Exciting()},
                          {"message", e.message},
                          {"condition_71",
                           {{"holds", e.condition71},
                            {"samples", e.samples71},
                            {"witness", Witness(e.witness71, r.estimation)}}},
                          {"condition_72",
                           {{"holds", e.condition72},
                            {"samples", e.samples72},
                            {"witness", Witness(e.witness72, r.estimation)}}},
                          {"swashplate",
                           {{"holds", e.swashplate},
                            {"samples", e.swashplate_samples},
                            {"max_abs_delta_cx", Number(e.max_abs_delta_cx)},
                            {"max_abs_delta_cy", Number(e.max_abs_delta_cy)}}},
                          {"sum_XtX",
                           {{"eigenvalues", ToVector(e.eigenvalues)},
                            {"epsilon", Number(e.epsilon)},
                            {"mu", Number(e.mu)},
                            {"condition_number", Number(e.condition_number)},
                            {"note", "unweighted, rows Z_bar, L, M, N of X_k, as eq. 74"}}},
                          {"scaled_information",
                           {{"eigenvalues", ToVector(e.scaled_eigenvalues)},
                            {"condition_number", Number(e.scaled_condition_number)},
                            {"well_conditioned", e.well_conditioned},
                            {"note", "sum S X_k^T R^-1 X_k S, S = parameter scales"}}}};

  // Thrust map and interference (Figs. 8-9).
  const ThrustMap& m = r.thrust_map;
  json points = json::array();
  for (const ThrustMapPoint& p : m.points) {
    points.push_back({{"omega1", p.omega1},
                      {"omega2", p.omega2},
                      {"Z", Number(p.Z)},
                      {"samples", p.samples},
                      {"holds", p.holds},
                      {"role", MapHoldRoleName(p.role)}});
  }
  report["thrust_map"] = {{"Cz_assumed", Number(m.Cz)},
                          {"area_ratio_Ss_over_Sprop", Number(m.area_ratio)},
                          {"alpha",
                           {{"value", Number(m.alpha)},
                            {"std", Number(m.alpha_std)},
                            {"holds", m.alpha_holds},
                            {"samples", m.alpha_samples}}},
                          {"beta_single_rotor",
                           {{"value", Number(m.beta)},
                            {"std", Number(m.beta_std)},
                            {"holds", m.beta_holds},
                            {"samples", m.beta_samples},
                            {"note",
                             "lower rotor alone, delta = 0; the Kalman beta is the "
                             "reported one"}}},
                          {"z_residual_variance", Number(m.z_residual_variance)},
                          {"points", points}};
  std::vector<std::string> cell_sources;
  for (const SigmaCellSource s : m.cell_source) cell_sources.push_back(SigmaCellSourceName(s));
  report["interference"] = {
      {"sigma0", ValueStd(m.sigma0, m.sigma0_std)},
      {"map_minus_parametric_rms", Number(m.sigma_fit_rms)},
      {"largest_loss",
       {{"loss", Number(m.max_loss)},
        {"sigma", Number(1 - m.max_loss)},
        {"omega1", Number(m.max_loss_omega1)},
        {"omega2", Number(m.max_loss_omega2)},
        {"omega1_over_omega2", Number(m.max_loss_omega1 / m.max_loss_omega2)}}},
      {"measured_cells", m.measured_cells},
      {"filled_cells", m.filled_cells},
      {"table",
       {{"omega1", m.table.omega1},
        {"omega2", m.table.omega2},
        {"sigma", m.table.sigma},
        {"source", cell_sources},
        {"layout", "row-major over omega1: sigma[i * len(omega2) + j]"}}}};

  // The filter.
  const LinearKfOptions& o = r.kf_options;
  ThetaMatrix correlation = r.kf.covariance;
  for (int i = 0; i < kNumTheta; ++i) {
    for (int j = 0; j < kNumTheta; ++j) {
      correlation(i, j) /= std::sqrt(r.kf.covariance(i, i) * r.kf.covariance(j, j));
    }
  }
  json corr = json::array();
  for (int i = 0; i < kNumTheta; ++i) {
    corr.push_back(ToVector(correlation.row(i).transpose()));
  }
  report["kalman"] = {
      {"parameters", {"beta", "Cz_alpha", "Cz_beta", "gamma1", "gamma2"}},
      {"outputs", {"Z_bar", "L", "M", "N"}},
      {"process_noise_Q", Number(o.process_noise)},
      {"Q_definition", "Q = process_noise * diag(scale^2) per sample"},
      {"initial", ToVector(o.initial)},
      {"scale", ToVector(o.scale)},
      {"prior_std_in_scales", Number(o.prior_std)},
      {"updates", r.kf.updates},
      {"skipped_rows", r.kf.skipped_rows},
      {"final_trace_P_scaled",
       Number(r.kf.history.trace_scaled.empty() ? NAN : r.kf.history.trace_scaled.back())},
      {"filter_correlation", corr}};
  report["diagnostics"] = {
      {"beta_from_X_Y", ValueStd(r.beta_from_xy.value, r.beta_from_xy.std)},
      {"implied_d", Number(r.implied_d)},
      {"note",
       "beta from X and Y alone (eqs. 61-62), independent of d; implied_d = d * "
       "beta_kalman / beta_from_X_Y"}};
  report["outputs"] = context.outputs;
  std::vector<std::string> notes = r.notes;
  notes.insert(notes.end(), context.notes.begin(), context.notes.end());
  report["notes"] = notes;
  return report;
}

std::string ThrustMapCsv(const LinearBaselineResult& r) {
  std::string s = "data,first_row,omega1,omega2,role,Z_mean,Z_std,samples,sigma,sigma_std\n";
  for (const MapHold& m : r.thrust_map.holds) {
    const BalanceData& d = *r.estimation[m.data_index].data;
    const BalanceHold& hold = d.holds[m.hold_index];
    s += d.name + "," + std::to_string(d.first_log_row + hold.first_row + 1) + "," + Csv(m.omega1) +
         "," + Csv(m.omega2) + "," + MapHoldRoleName(m.role) + "," + Csv(m.Z) + "," + Csv(m.Z_std) +
         "," + std::to_string(m.count) + "," + Csv(m.sigma) + "," + Csv(m.sigma_std) + "\n";
  }
  return s;
}

std::string SigmaMapCsv(const LinearBaselineResult& r) {
  const ThrustMap& m = r.thrust_map;
  std::string s = "omega1,omega2,sigma,sigma_std,source,sigma_parametric\n";
  const size_t n2 = m.table.omega2.size();
  for (size_t i = 0; i < m.table.omega1.size(); ++i) {
    for (size_t j = 0; j < n2; ++j) {
      const size_t c = i * n2 + j;
      const double w1 = m.table.omega1[i], w2 = m.table.omega2[j];
      const double parametric = m.cell_source[c] == SigmaCellSource::kStopped
                                    ? 1.0
                                    : 1 - m.sigma0 * InterferenceShape(w1, w2);
      s += Csv(w1) + "," + Csv(w2) + "," + Csv(m.table.sigma[c]) + "," + Csv(m.cell_std[c]) + "," +
           SigmaCellSourceName(m.cell_source[c]) + "," + Csv(parametric) + "\n";
    }
  }
  return s;
}

std::string KfHistoryCsv(const LinearBaselineResult& r) {
  const LinearKfHistory& h = r.kf.history;
  std::string s = "update,data,row,t,beta,Cz_alpha,Cz_beta,gamma1,gamma2,trace_P_scaled\n";
  s.reserve(h.t.size() * 140);
  for (size_t k = 0; k < h.t.size(); ++k) {
    const BalanceData& d = *r.estimation[h.data_index[k]].data;
    s += std::to_string(k + 1) + "," + d.name + "," +
         std::to_string(d.first_log_row + h.row[k] + 1) + "," + Csv(h.t[k]);
    for (int i = 0; i < kNumTheta; ++i) s += "," + Csv(h.estimate[k][i]);
    s += "," + Csv(h.trace_scaled[k]) + "\n";
  }
  return s;
}

std::string ReconstructionCsv(const std::vector<const Reconstruction*>& parts,
                              const std::vector<std::string>& part_labels) {
  std::string s = "t,row,part";
  for (int c = 0; c < kNumLoadChannels; ++c) {
    s += std::string(",") + LoadChannelName(c) + "_measured," + LoadChannelName(c) + "_model";
  }
  s += "\n";
  for (size_t p = 0; p < parts.size(); ++p) {
    const Reconstruction& r = *parts[p];
    const BalanceData& d = *r.data;
    for (int k = 0; k < d.NumRows(); ++k) {
      s += Csv(d.t[k]) + "," + std::to_string(d.first_log_row + k + 1) + "," + part_labels[p];
      for (int c = 0; c < kNumLoadChannels; ++c) {
        s += "," + Csv(d.loads[c][k]) + "," + (d.has_channel[c] ? Csv(r.model[c][k]) : "");
      }
      s += "\n";
    }
  }
  return s;
}

}  // namespace coaxid
