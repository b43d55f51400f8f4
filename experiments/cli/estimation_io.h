// Pieces every estimation command (identify, discover) shares: cutting the
// logs into estimation and held-out parts (cli-and-reports.md: --validate
// logs, or a contiguous final part of each log), and measured-vs-model
// tables and plots.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/log.h"
#include "core/plot.h"
#include "ident/estimation_log.h"

namespace coaxid {

struct LogSplit {
  std::vector<EstimationLog> estimation, validation;
  std::string description;  // which rows are held out, for reports
};

// With validate logs: all of logs for estimation, validate for validation.
// Otherwise the final holdout_fraction of each log is held out (balance logs
// cut at a hold boundary); 0 holds out nothing.
LogSplit SplitEstimationAndValidation(const std::vector<Log>& logs,
                                      const std::vector<Log>& validate, double holdout_fraction);

// CSV at path (atomically, in pieces): t, then for each channel its
// measured value and the model's.
void WriteMeasuredVersusModelCsv(const std::string& path, const EstimationLog& log,
                                 const Eigen::MatrixXd& model);
// A model's outputs on a log (same shape as its values) and how to draw them.
struct ModelCurve {
  std::string name;              // legend entry
  const Eigen::MatrixXd* values;
  std::string colour;            // gnuplot colour, e.g. "red"
};
// One panel per channel: measured (grey) and each model; a flight log's
// curves at most kMaxPlotPoints points each (every stride-th sample).
constexpr int kMaxPlotPoints = 20000;
Figure MeasuredVersusModelsFigure(const std::string& title, const EstimationLog& log,
                                  const std::vector<ModelCurve>& models);
// One panel per channel, measured (grey) and model (red).
Figure MeasuredVersusModelFigure(const std::string& title, const EstimationLog& log,
                                 const Eigen::MatrixXd& model);

}  // namespace coaxid
