#include "ident/baseline/plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace coaxid {
namespace {

std::string Label(const char* format, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
}

const char* Unit(int channel) { return channel <= kLoadZ ? "N" : "N m"; }

// Measured (solid) and model (dashed) of one channel against t.
PlotPanel ChannelPanel(const Reconstruction& r, int c, const std::string& title) {
  PlotPanel panel;
  panel.title = title;
  panel.x_label = "t [s]";
  panel.y_label = std::string(LoadChannelName(c)) + " [" + Unit(c) + "]";
  const BalanceData& d = *r.data;
  panel.series.push_back({"measured", d.t, d.loads[c], "lines lw 1 lc rgb '#1f77b4'"});
  panel.series.push_back({"model", d.t, r.model[c], "lines lw 2 dt 2 lc rgb '#d62728'"});
  panel.key = "below horizontal";
  return panel;
}

Figure ChannelsFigure(const Reconstruction& r, const std::vector<int>& channels,
                      const std::string& title, const std::string& subtitle) {
  Figure f;
  f.title = title;
  f.columns = channels.size() > 2 ? 2 : 1;
  for (const int c : channels) {
    if (!r.data->has_channel[c]) continue;
    f.panels.push_back(ChannelPanel(r, c, std::string(LoadChannelName(c)) + " " + subtitle));
  }
  return f;
}

Figure ThrustMapFigure(const ThrustMap& m) {
  Figure f;
  f.title = "Thrust map (paper Fig. 8): mean Z of the holds with delta = 0";
  f.columns = 2;
  PlotPanel by2, by1;
  by2.title = "Z against omega2, per omega1";
  by2.x_label = "omega2 [rad/s]";
  by2.y_label = "Z [N]";
  by1.title = "Z against omega1, per omega2";
  by1.x_label = "omega1 [rad/s]";
  by1.y_label = "Z [N]";
  std::map<double, PlotSeries> per1, per2;
  for (const ThrustMapPoint& p : m.points) {
    PlotSeries& a = per1[p.omega1];
    a.title = "omega1 = " + Label("%.0f", p.omega1);
    a.style = "linespoints pt 7";
    a.x.push_back(p.omega2);
    a.y.push_back(p.Z);
    PlotSeries& b = per2[p.omega2];
    b.title = "omega2 = " + Label("%.0f", p.omega2);
    b.style = "linespoints pt 7";
    b.x.push_back(p.omega1);
    b.y.push_back(p.Z);
  }
  for (auto& [w, s] : per1) by2.series.push_back(s);
  for (auto& [w, s] : per2) by1.series.push_back(s);
  // The single-rotor fits: Z = alpha (1 - Cz k) omega1^2 and beta (1 - Cz k) omega2^2.
  PlotSeries fit_beta{"fit beta (lower alone)", {}, {}, "lines dt 2 lw 2 lc rgb 'black'"};
  PlotSeries fit_alpha{"fit alpha (upper alone)", {}, {}, "lines dt 2 lw 2 lc rgb 'black'"};
  const double top1 = m.table.omega1.back(), top2 = m.table.omega2.back();
  for (int k = 0; k <= 50; ++k) {
    const double w2 = top2 * k / 50.0, w1 = top1 * k / 50.0;
    fit_beta.x.push_back(w2);
    fit_beta.y.push_back(m.beta * m.thrust_factor * w2 * w2);
    fit_alpha.x.push_back(w1);
    fit_alpha.y.push_back(m.alpha * m.thrust_factor * w1 * w1);
  }
  by2.series.push_back(fit_beta);
  by1.series.push_back(fit_alpha);
  f.panels = {by2, by1};
  return f;
}

Figure SigmaFigure(const ThrustMap& m) {
  Figure f;
  f.title =
      "Interference loss sigma (paper Fig. 9): map at the coaxial holds (delta = 0), "
      "parametric fit sigma0 = " +
      Label("%.4f", m.sigma0);
  f.columns = 2;
  PlotPanel by2, ratio;
  by2.title = "sigma against omega2 (points: map, lines: fit)";
  by2.x_label = "omega2 [rad/s]";
  by2.y_label = "sigma [-]";
  ratio.title = "sigma against omega1/omega2 (the fit depends on it only)";
  ratio.x_label = "omega1 / omega2 [-]";
  ratio.y_label = "sigma [-]";
  std::map<double, PlotSeries> measured;
  PlotSeries by_ratio{"map (coaxial holds)", {}, {}, "points pt 7 ps 1.2"};
  for (const MapHold& h : m.holds) {
    if (h.role != MapHoldRole::kCoaxial) continue;
    PlotSeries& s = measured[m.table.omega1[h.cell / m.table.omega2.size()]];
    s.x.push_back(h.omega2);
    s.y.push_back(h.sigma);
    by_ratio.x.push_back(h.omega1 / h.omega2);
    by_ratio.y.push_back(h.sigma);
  }
  const double top2 = m.table.omega2.back();
  int color = 1;
  for (auto& [w1, s] : measured) {
    s.title = "map, omega1 = " + Label("%.0f", w1);
    s.style = "points pt 7 ps 1.2 lc " + std::to_string(color);
    PlotSeries fit{
        "fit, omega1 = " + Label("%.0f", w1), {}, {}, "lines lw 1.5 lc " + std::to_string(color)};
    for (int k = 1; k <= 60; ++k) {
      const double w2 = top2 * k / 60.0;
      fit.x.push_back(w2);
      fit.y.push_back(1 - m.sigma0 * InterferenceShape(w1, w2));
    }
    by2.series.push_back(s);
    by2.series.push_back(fit);
    ++color;
  }
  PlotSeries fit_ratio{"fit 1 - sigma0 * 4 r^2/(1 + r^2)^2", {}, {}, "lines lw 2 lc rgb 'black'"};
  double top_ratio = 2;
  for (const double x : by_ratio.x) top_ratio = std::max(top_ratio, 1.1 * x);
  for (int k = 0; k <= 100; ++k) {
    const double r = top_ratio * k / 100.0;
    fit_ratio.x.push_back(r);
    fit_ratio.y.push_back(1 - m.sigma0 * InterferenceShape(r, 1.0));
  }
  ratio.series = {by_ratio, fit_ratio};
  f.panels = {by2, ratio};
  return f;
}

Figure KalmanFigure(const LinearBaselineResult& r) {
  const LinearKfHistory& h = r.kf.history;
  Figure f;
  f.title = "Kalman filter (paper Fig. 11): trace(P) and the estimates along the updates";
  f.columns = 1;
  PlotPanel trace;
  trace.title = "trace(P) in parameter scales (sum P_ii / scale_i^2)";
  trace.x_label = "update";
  trace.y_label = "trace(P) [-]";
  trace.log_y = true;
  trace.key = "below horizontal";
  PlotSeries t{"trace(P)", {}, {}, "lines lw 2"};
  PlotPanel estimates;
  estimates.title = "estimate / final estimate";
  estimates.x_label = "update";
  estimates.y_label = "[-]";
  estimates.y_min = 0.5;
  estimates.y_max = 1.5;
  estimates.key = "below horizontal";
  std::vector<PlotSeries> series(kNumTheta);
  // Thin long histories to about 5000 points per curve: the plot cannot show more.
  const size_t stride = std::max<size_t>(1, h.t.size() / 5000);
  for (size_t k = 0; k < h.t.size(); k += stride) {
    const double update = static_cast<double>(k + 1);
    t.x.push_back(update);
    t.y.push_back(h.trace_scaled[k]);
    for (int i = 0; i < kNumTheta; ++i) {
      series[i].x.push_back(update);
      series[i].y.push_back(h.estimate[k][i] / r.kf.estimate[i]);
    }
  }
  trace.series = {t};
  for (int i = 0; i < kNumTheta; ++i) {
    series[i].title = ThetaName(i);
    estimates.series.push_back(series[i]);
  }
  f.panels = {trace, estimates};
  return f;
}

}  // namespace

std::vector<NamedFigure> BaselineFigures(const LinearBaselineResult& r,
                                         const std::vector<std::string>& names,
                                         const std::vector<std::string>& validation_names) {
  std::vector<NamedFigure> figures;
  figures.push_back({"fig08_thrust_map.png", ThrustMapFigure(r.thrust_map)});
  figures.push_back({"fig09_sigma_map.png", SigmaFigure(r.thrust_map)});
  for (size_t i = 0; i < r.estimation.size(); ++i) {
    const std::string& source = r.estimation[i].data->source;
    figures.push_back({"fig10_estimation_" + names[i] + ".png",
                       ChannelsFigure(r.estimation[i], {kLoadZ, kLoadL, kLoadM, kLoadN},
                                      "Estimation (paper Fig. 10): " + source,
                                      "(solid measured, dashed model)")});
  }
  figures.push_back({"fig11_kalman.png", KalmanFigure(r)});
  for (size_t i = 0; i < r.validation.size(); ++i) {
    const std::string& source = r.validation[i].data->source;
    figures.push_back(
        {"fig12_validation_" + validation_names[i] + ".png",
         ChannelsFigure(r.validation[i], {kLoadX, kLoadY, kLoadZ, kLoadL, kLoadM, kLoadN},
                        "Validation (paper Fig. 12): held-out " + source,
                        "(solid measured, dashed model)")});
  }
  for (size_t i = 0; i < r.estimation.size(); ++i) {
    const std::string& source = r.estimation[i].data->source;
    figures.push_back({"fig13_reconstruction_" + names[i] + ".png",
                       ChannelsFigure(r.estimation[i], {kLoadX, kLoadY},
                                      "Reconstruction (paper Fig. 13): X and Y, not used in the "
                                      "estimation: " +
                                          source,
                                      "(solid measured, dashed model)")});
  }
  return figures;
}

}  // namespace coaxid
