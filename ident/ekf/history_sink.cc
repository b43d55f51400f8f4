#include "ident/ekf/history_sink.h"

#include <limits>

namespace coaxid {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

EkfMemoryHistory::EkfMemoryHistory(const std::vector<EstimationLog>& logs,
                                   const std::vector<std::string>& state_names, int np,
                                   bool smoother, bool covariance_pass,
                                   std::vector<EkfLogHistory>* histories)
    : logs_(*histories) {
  logs_.resize(logs.size());
  for (size_t L = 0; L < logs.size(); ++L) {
    const EstimationLog& log = logs[L];
    EkfLogHistory& h = logs_[L];
    const int N = log.NumRows(), m = log.NumChannels();
    h.source = log.source;
    h.name = log.name;
    h.times = log.inputs.times();
    h.channels = log.channels;
    h.channel_names = log.channel_names;
    h.measured = log.values;
    h.state_names = state_names;
    SizeStateAndInnovationRecords(N, m, smoother, &h);
    h.parameters.setConstant(N, np, kNaN);
    h.parameter_std.setConstant(N, np, kNaN);
    if (covariance_pass) h.parameter_std_at_estimate.setConstant(N, np, kNaN);
  }
}

void SizeStateAndInnovationRecords(int rows, int m, bool smoother, EkfLogHistory* h) {
  const int nx = static_cast<int>(h->state_names.size());
  h->states.setConstant(rows, nx, kNaN);
  h->state_std.setConstant(rows, nx, kNaN);
  if (smoother) {
    h->smoothed_states.setConstant(rows, nx, kNaN);
    h->smoothed_state_std.setConstant(rows, nx, kNaN);
  }
  h->innovations.setConstant(rows, m, kNaN);
  h->innovation_std.setConstant(rows, m, kNaN);
  h->nis.assign(rows, kNaN);
  h->nis_dof.assign(rows, 0);
}

void EkfMemoryHistory::FilteredStates(int log, int row, const EkfRowValues& x,
                                      const EkfRowValues& std) {
  logs_[log].states.row(row) = x.transpose();
  logs_[log].state_std.row(row) = std.transpose();
}

void EkfMemoryHistory::SmoothedStates(int log, int row, const EkfRowValues& x,
                                      const EkfRowValues& std) {
  logs_[log].smoothed_states.row(row) = x.transpose();
  logs_[log].smoothed_state_std.row(row) = std.transpose();
}

void EkfMemoryHistory::Parameters(int log, int row, const EkfRowValues& value,
                                  const EkfRowValues& std) {
  logs_[log].parameters.row(row) = value.transpose();
  logs_[log].parameter_std.row(row) = std.transpose();
}

void EkfMemoryHistory::ParameterStdAtEstimate(int log, int row, const EkfRowValues& std) {
  logs_[log].parameter_std_at_estimate.row(row) = std.transpose();
}

void StoreInnovations(int row, const std::vector<int>& columns, const Eigen::VectorXd& nu,
                      const Eigen::VectorXd& std, double nis, int dof, EkfLogHistory* h) {
  h->nis[row] = nis;
  h->nis_dof[row] = dof;
  for (size_t j = 0; j < columns.size(); ++j) {
    h->innovations(row, columns[j]) = nu[j];
    h->innovation_std(row, columns[j]) = std[j];
  }
}

void EkfMemoryHistory::Innovations(int log, int row, const std::vector<int>& columns,
                                   const Eigen::VectorXd& nu, const Eigen::VectorXd& std,
                                   double nis, int dof) {
  StoreInnovations(row, columns, nu, std, nis, dof, &logs_[log]);
}

void EkfMemoryHistory::VisitParameters(
    const std::function<void(int, int, const EkfRowValues&)>& visit) {
  for (size_t L = 0; L < logs_.size(); ++L) {
    const EkfLogHistory& h = logs_[L];
    for (int row = 0; row < h.parameters.rows(); ++row) {
      visit(static_cast<int>(L), row, h.parameters.row(row).transpose());
    }
  }
}

}  // namespace coaxid
