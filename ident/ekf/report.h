// The EKF's outputs (`coaxid identify --method=ekf`): fit and validation
// predictions, report.json (cli-and-reports.md, with an "ekf" section), the
// CSV histories and the figures. Pure functions from results to data and
// text; the caller writes the files.
//
// Fit (cli-and-reports.md, flight logs): the open-loop model diverges, so the
// model output is a prediction over consecutive windows of window_s (1 s by
// default), each started from the state estimated at the window's first row
// with the final parameters: on the estimation logs the smoothed states of
// the covariance pass (filtered ones without the smoother); on held-out data
// the states of the same filter run with every parameter held at the
// estimates. The accelerometer uses each row's inputs (model.md decision 7).
#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/parameters.h"
#include "core/plot.h"
#include "core/statistics.h"
#include "dynamics/integrator.h"
#include "dynamics/vehicle.h"
#include "ident/ekf/ekf.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"

namespace coaxid {

// Model outputs of `log`'s channels (rows x channels) over consecutive
// windows of window_s, window k started at its first row from start_states
// (rows x 12). A window whose simulation fails is left NaN and counted in
// *failed_windows.
Eigen::MatrixXd WindowPredictions(const Vehicle& vehicle, const EstimationLog& log,
                                  const Eigen::MatrixXd& start_states, double window_s,
                                  const IntegratorOptions& integrator, int* failed_windows);
// The first rows of those windows.
std::vector<int> WindowStartRows(const EstimationLog& log, double window_s);
// The same from the states at the windows' first rows only (one per
// WindowStartRows entry): a long log's states need not all be kept.
Eigen::MatrixXd WindowPredictions(const Vehicle& vehicle, const EstimationLog& log,
                                  const std::vector<Eigen::VectorXd>& window_start_states,
                                  double window_s, const IntegratorOptions& integrator,
                                  int* failed_windows);

// The plots' stride over n rows: every k-th row so that at most 3000 remain.
int EkfPlotStride(size_t n);

// Per-channel fit errors of predictions: ChannelFitErrors of ident/output_error/output_error.h.

struct EkfReportContext {
  std::vector<std::string> logs;             // estimation logs as given
  std::vector<std::string> validation_logs;  // --validate logs (empty: held-out parts)
  std::string validation_description;
  double window_s = 1.0;
  std::string fit_states;                    // which states start the fit windows
  NoiseWeights noise;
  std::string noise_source;
  std::map<std::string, FitError> fit, validation;
  int failed_fit_windows = 0, failed_validation_windows = 0;
  nlohmann::json outputs = nlohmann::json::object();  // files written, plots (or why skipped)
  std::vector<std::string> notes;
};

// report.json. initial: the parameters the run started from (config or an
// earlier report), for the "initial" entries.
nlohmann::json EkfReportJson(const EkfResult& result, const EkfOptions& options,
                             const ParameterSet& initial, const EkfReportContext& context);

// The CSV tables, emitted in pieces (core/atomic_file.h).
// states.csv: log, t, then per state its estimate and std (reported pass),
// and the smoothed estimate and std when smoothed.
void EkfStatesCsv(const EkfResult& result, const EmitText& emit);
// parameters.csv: log, t, then per free parameter the recursive estimate, its
// filter std, and the covariance pass's std at the final estimate.
void EkfParametersCsv(const EkfResult& result, const EmitText& emit);
// innovations.csv: log, t, per channel the innovation and sqrt(S_ii), then
// the row's NIS and its degrees of freedom.
void EkfInnovationsCsv(const EkfResult& result, const EmitText& emit);

using EkfFigure = NamedFigure;
// parameters.png (estimates vs time with their 3-sigma band), innovations_NAME.png
// (innovations with +-3 sqrt(S_ii)), states_NAME.png (measured and estimated),
// fit_NAME.png (measured and window predictions).
std::vector<EkfFigure> EkfFigures(const EkfResult& result,
                                  const std::vector<Eigen::MatrixXd>& fit_predictions);

}  // namespace coaxid
