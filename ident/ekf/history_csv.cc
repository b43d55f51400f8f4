#include "ident/ekf/history_csv.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/report_values.h"
#include "dynamics/state.h"

namespace coaxid {
namespace {

std::string Csv(double v) {
  if (!std::isfinite(v)) return "";
  return Significant(v, 10);
}

}  // namespace

std::string EkfCsvLogName(const std::string& name) {
  // Log names may hold commas in principle; keep the CSV well formed.
  std::string out = name;
  std::replace(out.begin(), out.end(), ',', '_');
  return out;
}

std::string EkfStatesCsvHeader(const std::vector<std::string>& state_names, bool smoothed) {
  std::string out = "log,t";
  for (const std::string& name : state_names) out += "," + name + "," + name + "_std";
  if (smoothed) {
    for (const std::string& name : state_names) {
      out += "," + name + "_smoothed," + name + "_smoothed_std";
    }
  }
  return out + "\n";
}

void AppendEkfStatesCsvRow(const std::string& log, double t, int nx, const double* x,
                           const double* std, const double* smoothed_x, const double* smoothed_std,
                           std::string* out) {
  *out += log + "," + Csv(t);
  for (int i = 0; i < nx; ++i) *out += "," + Csv(x[i]) + "," + Csv(std[i]);
  if (smoothed_x != nullptr) {
    for (int i = 0; i < nx; ++i) {
      *out += "," + Csv(smoothed_x[i]) + "," + Csv(smoothed_std[i]);
    }
  }
  *out += "\n";
}

std::string EkfParametersCsvHeader(const std::vector<std::string>& free_names, bool at_estimate) {
  std::string out = "log,t";
  for (const std::string& p : free_names) {
    out += "," + p + "," + p + "_std";
    if (at_estimate) out += "," + p + "_std_at_estimate";
  }
  return out + "\n";
}

void AppendEkfParametersCsvRow(const std::string& log, double t, int np, const double* value,
                               const double* std, const double* std_at_estimate, std::string* out) {
  *out += log + "," + Csv(t);
  for (int j = 0; j < np; ++j) {
    *out += "," + Csv(value[j]) + "," + Csv(std[j]);
    if (std_at_estimate != nullptr) *out += "," + Csv(std_at_estimate[j]);
  }
  *out += "\n";
}

std::vector<std::string> EkfInnovationChannels(
    const std::vector<std::vector<std::string>>& channels_of_logs) {
  std::vector<std::string> channels;
  for (const std::vector<std::string>& names : channels_of_logs) {
    for (const std::string& c : names) {
      if (std::find(channels.begin(), channels.end(), c) == channels.end()) channels.push_back(c);
    }
  }
  return channels;
}

std::string EkfInnovationsCsvHeader(const std::vector<std::string>& channels) {
  std::string out = "log,t";
  for (const std::string& c : channels) out += "," + c + "," + c + "_std";
  return out + ",nis,nis_dof\n";
}

std::vector<int> EkfInnovationColumns(const std::vector<std::string>& channels,
                                      const std::vector<std::string>& channel_names) {
  std::vector<int> column(channels.size(), -1);
  for (size_t j = 0; j < channels.size(); ++j) {
    for (size_t c = 0; c < channel_names.size(); ++c) {
      if (channel_names[c] == channels[j]) column[j] = static_cast<int>(c);
    }
  }
  return column;
}

void AppendEkfInnovationsCsvRow(const std::string& log, double t, const std::vector<int>& column,
                                const double* nu, const double* std, double nis, int dof,
                                std::string* out) {
  *out += log + "," + Csv(t);
  for (const int c : column) {
    if (c < 0) {
      *out += ",,";
    } else {
      *out += "," + Csv(nu[c]) + "," + Csv(std[c]);
    }
  }
  *out += "," + Csv(nis) + "," + std::to_string(dof) + "\n";
}

}  // namespace coaxid
