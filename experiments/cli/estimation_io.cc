#include "experiments/cli/estimation_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/atomic_file.h"
#include "core/report_values.h"
#include "ident/baseline/balance_holds.h"

namespace coaxid {

LogSplit SplitEstimationAndValidation(const std::vector<Log>& logs,
                                      const std::vector<Log>& validate, double holdout_fraction) {
  LogSplit s;
  if (!validate.empty()) {
    for (const Log& log : logs) s.estimation.push_back(MakeEstimationLog(log));
    for (const Log& log : validate) s.validation.push_back(MakeEstimationLog(log));
    s.description = "the --validate logs, whole";
    return s;
  }
  if (holdout_fraction <= 0) {
    for (const Log& log : logs) s.estimation.push_back(MakeEstimationLog(log));
    s.description = "none (--holdout_fraction=0 and no --validate)";
    return s;
  }
  s.description = "the contiguous final part of each log (--holdout_fraction=" +
                  std::to_string(holdout_fraction) + "):";
  for (const Log& log : logs) {
    const int cut = log.kind == LogKind::kBalance
                        ? HoldoutStartRow(log, holdout_fraction)
                        : HoldoutStart(log.NumRows(), holdout_fraction, log.source);
    s.estimation.push_back(MakeEstimationLog(log, 0, cut));
    s.validation.push_back(MakeEstimationLog(log, cut));
    s.description += " " + log.source + " rows " + std::to_string(cut + 1) + "-" +
                     std::to_string(log.NumRows());
  }
  return s;
}

void WriteMeasuredVersusModelCsv(const std::string& path, const EstimationLog& log,
                                 const Eigen::MatrixXd& model) {
  WriteFileAtomically(path, [&](const EmitText& emit) {
    TextPieces out(emit);
    std::string& text = out.text;
    text = "t";
    for (const std::string& name : log.channel_names) text += "," + name + "," + name + "_model";
    text += "\n";
    char number[32];
    auto append = [&](double value) {
      if (!std::isfinite(value)) return;
      text.append(number, WriteSignificant(number, value, 10));
    };
    for (int k = 0; k < log.NumRows(); ++k) {
      append(log.inputs.time(k));
      for (int c = 0; c < log.NumChannels(); ++c) {
        text += ',';
        append(log.values(k, c));
        text += ',';
        append(model(k, c));
      }
      text += '\n';
      out.EndOfRow();
    }
  });
}

Figure MeasuredVersusModelsFigure(const std::string& title, const EstimationLog& log,
                                  const std::vector<ModelCurve>& models) {
  Figure f;
  f.title = title;
  f.columns = 3;
  const bool balance = log.kind == LogKind::kBalance;
  // A flight log longer than kMaxPlotPoints samples is drawn from every
  // stride-th sample (an hour at 200 Hz would be 720,000 points a curve, more
  // than a figure shows and 0.3 GB of plot data).
  const int stride =
      balance ? 1 : std::max(1, (log.NumRows() + kMaxPlotPoints - 1) / kMaxPlotPoints);
  for (int c = 0; c < log.NumChannels(); ++c) {
    PlotPanel panel;
    panel.title = log.channel_names[c];
    panel.x_label = balance ? "row" : "t [s]";
    PlotSeries measured{"measured", {}, {},
                        balance ? "points pt 7 ps 0.3 lc rgb '#999999'" : "lines lc rgb '#999999'"};
    for (int k = 0; k < log.NumRows(); k += stride) {
      measured.x.push_back(balance ? k : log.inputs.time(k));
      measured.y.push_back(log.values(k, c));
    }
    panel.series = {measured};
    for (const ModelCurve& model : models) {
      const std::string colour = " lc rgb '" + model.colour + "'";
      PlotSeries s{model.name, measured.x, {},
                   (balance ? "points pt 6 ps 0.4" : "lines") + colour};
      for (int k = 0; k < log.NumRows(); k += stride) s.y.push_back((*model.values)(k, c));
      panel.series.push_back(s);
    }
    f.panels.push_back(panel);
  }
  return f;
}

Figure MeasuredVersusModelFigure(const std::string& title, const EstimationLog& log,
                                 const Eigen::MatrixXd& model) {
  return MeasuredVersusModelsFigure(title, log, {{"model", &model, "red"}});
}

}  // namespace coaxid
