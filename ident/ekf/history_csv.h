// The EKF's CSV tables (states.csv, parameters.csv, innovations.csv) a row
// at a time: the one formatting of those tables, used by the writers over
// EkfResult::logs (report.h) and over the streamed histories
// (history_files.h), so both write the same bytes.
#pragma once

#include <string>
#include <vector>

namespace coaxid {

// The log's name as the tables print it (commas replaced).
std::string EkfCsvLogName(const std::string& name);

// states.csv: log, t, then per state its estimate and std (reported pass),
// and the smoothed estimate and std when smoothed.
// state_names: the model's (VehicleModel::StateNames).
std::string EkfStatesCsvHeader(const std::vector<std::string>& state_names, bool smoothed);
// x, std: nx each; smoothed_x, smoothed_std: nx each, or null (no smoother).
void AppendEkfStatesCsvRow(const std::string& log, double t, int nx, const double* x,
                           const double* std, const double* smoothed_x, const double* smoothed_std,
                           std::string* out);

// parameters.csv: log, t, then per free parameter the recursive estimate, its
// filter std, and the covariance pass's std at the final estimate.
std::string EkfParametersCsvHeader(const std::vector<std::string>& free_names, bool at_estimate);
// value, std, std_at_estimate: np each (std_at_estimate null without the covariance pass).
void AppendEkfParametersCsvRow(const std::string& log, double t, int np, const double* value,
                               const double* std, const double* std_at_estimate, std::string* out);

// innovations.csv: log, t, per channel the innovation and sqrt(S_ii), then
// the row's NIS and its degrees of freedom. The channels: those of every log,
// in first-seen order.
std::vector<std::string> EkfInnovationChannels(
    const std::vector<std::vector<std::string>>& channels_of_logs);
std::string EkfInnovationsCsvHeader(const std::vector<std::string>& channels);
// column[j]: the log's column of the table's channel j (-1: the log has none);
// nu, std: per column of the log (NaN where no update).
void AppendEkfInnovationsCsvRow(const std::string& log, double t, const std::vector<int>& column,
                                const double* nu, const double* std, double nis, int dof,
                                std::string* out);
// The columns of a log (channel_names) for the table's channels.
std::vector<int> EkfInnovationColumns(const std::vector<std::string>& channels,
                                      const std::vector<std::string>& channel_names);

}  // namespace coaxid
