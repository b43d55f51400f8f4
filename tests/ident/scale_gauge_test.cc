// The scale gauge (model.md decision 8): what fixes the scale in each case,
// and the ratios' std against the delta method done by finite differences.
#include "ident/scale_gauge.h"

#include <cmath>

#include <gtest/gtest.h>

#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {
namespace {

Vehicle Nominal() { return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml"); }

const std::vector<EstimationLog>& Logs() {
  static const std::vector<EstimationLog> logs = [] {
    const Vehicle v = Nominal();
    FlightScenario f;
    f.duration_s = 1.0;
    BalanceScenario b;
    b.hold_s = 0.2;
    return std::vector<EstimationLog>{MakeEstimationLog(SimulateFlight(v, f, 1)),
                                      MakeEstimationLog(SimulateBalance(v, b, 2))};
  }();
  return logs;
}

ScaleGauge Gauge(const std::vector<EstimationLog>& logs, ParameterSet* parameters,
                 const std::vector<std::string>& priors = {},
                 ScaleAnchor anchor = ScaleAnchor::kHubDistance) {
  return FixScaleGauge(Nominal().model, logs, priors, anchor, parameters);
}

TEST(ScaleGauge, FlightLogsAloneHoldD) {
  ParameterSet p = Nominal().parameters;
  const ScaleGauge g = Gauge({Logs()[0]}, &p);
  EXPECT_EQ(g.held, "d");
  EXPECT_FALSE(p.Get("d").estimated);
  EXPECT_EQ(g.group, (std::vector<std::string>{"gamma1", "gamma2", "d", "Ixx", "Iyy", "Izz"}));
}

TEST(ScaleGauge, BalancePriorOrConfigFixTheScaleInstead) {
  ParameterSet p = Nominal().parameters;
  EXPECT_EQ(Gauge(Logs(), &p).fixed_by, "balance log");
  EXPECT_TRUE(p.Get("d").estimated);
  EXPECT_EQ(Gauge({Logs()[0]}, &p, {"Ixx"}).fixed_by, "prior on Ixx");
  EXPECT_TRUE(p.Get("d").estimated);
  EXPECT_EQ(Gauge({Logs()[0]}, &p, {}, ScaleAnchor::kNone).fixed_by, "nothing");
  EXPECT_TRUE(p.Get("d").estimated);
  p.SetEstimated("Izz", false);
  EXPECT_EQ(Gauge({Logs()[0]}, &p).fixed_by, "config: Izz held");
  EXPECT_TRUE(p.Get("d").estimated);
  // Balance logs alone: no flight output, no gauge to fix.
  ParameterSet q = Nominal().parameters;
  const ScaleGauge balance_only = Gauge({Logs()[1]}, &q);
  EXPECT_FALSE(balance_only.direction.exists);
  EXPECT_TRUE(ScaleFreeRatios(balance_only, q, q.FreeIndices(), Eigen::MatrixXd()).empty());
}

TEST(ScaleGauge, RatiosAreInvariantAndTheirStdIsTheDeltaMethod) {
  ParameterSet p = Nominal().parameters;
  const ScaleGauge g = Gauge({Logs()[0]}, &p);
  const std::vector<int> free = p.FreeIndices();
  const int n = static_cast<int>(free.size());
  // A covariance with correlations: C = B B^T, B scaled to 5 % of each value.
  Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, n);
  for (int k = 0; k < n; ++k) B.row(k) *= 0.05 * std::fabs(p[free[k]].value) / std::sqrt(n);
  const Eigen::MatrixXd C = B * B.transpose();
  const std::vector<ScaleFreeRatio> ratios = ScaleFreeRatios(g, p, free, C);
  ASSERT_EQ(ratios.size(), 6u);
  for (const ScaleFreeRatio& q : ratios) {
    // Invariant under the scale direction (every member times c).
    ParameterSet scaled = p;
    for (int i : g.direction.group) scaled.SetValue(scaled[i].name, 1.7 * scaled[i].value);
    EXPECT_NEAR(q.Evaluate(scaled), q.value, 1e-12 * std::fabs(q.value)) << q.name;
    // std = sqrt(g^T C g), g by central differences.
    Eigen::VectorXd grad(n);
    for (int k = 0; k < n; ++k) {
      const double h = 1e-6 * std::fabs(p[free[k]].value);
      ParameterSet up = p, down = p;
      up.SetValue(p[free[k]].name, p[free[k]].value + h);
      down.SetValue(p[free[k]].name, p[free[k]].value - h);
      grad[k] = (q.Evaluate(up) - q.Evaluate(down)) / (2 * h);
    }
    EXPECT_NEAR(q.std, std::sqrt(grad.dot(C * grad)), 1e-6 * q.std) << q.name;
  }
}

// A covariance that leaves a direction out (a fit's, restricted to what the
// logs determine): a ratio that moves along it by more than its std over a
// move of one scale is not determined (std NaN); one that does not keeps the
// delta method's std. The direction here: Izz, gamma1 and gamma2 together
// (the yaw axis, as in the confusion study's run p0_s59), which leaves
// gamma1/Izz and gamma2/Izz unchanged and moves Izz/Ixx.
TEST(ScaleGauge, ARatioAlongAnUndeterminedDirectionHasNoStd) {
  ParameterSet p = Nominal().parameters;
  const ScaleGauge g = Gauge({Logs()[0]}, &p);
  const std::vector<int> free = p.FreeIndices();
  const int n = static_cast<int>(free.size());
  Eigen::VectorXd scales(n), v = Eigen::VectorXd::Zero(n);  // v: scaled coordinates
  for (int k = 0; k < n; ++k) {
    scales[k] = p[free[k]].scale;
    const std::string& name = p[free[k]].name;
    if (name == "Izz" || name == "gamma1" || name == "gamma2") v[k] = p[free[k]].value / scales[k];
  }
  v.normalize();
  Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, n);
  for (int k = 0; k < n; ++k) B.row(k) *= 0.05 / std::sqrt(n);
  const Eigen::MatrixXd projector = Eigen::MatrixXd::Identity(n, n) - v * v.transpose();
  const Eigen::MatrixXd scaled = projector * B * B.transpose() * projector;
  const Eigen::MatrixXd C = scales.asDiagonal() * scaled * scales.asDiagonal();
  for (const ScaleFreeRatio& q : ScaleFreeRatios(g, p, free, C)) {
    if (q.name == "Izz/Ixx") {
      EXPECT_TRUE(std::isnan(q.std)) << q.std;
    } else {
      EXPECT_TRUE(std::isfinite(q.std) && q.std > 0) << q.name << " " << q.std;
    }
  }
  // The same covariance without the projection: every std finite.
  const Eigen::MatrixXd full = scales.asDiagonal() * B * B.transpose() * scales.asDiagonal();
  for (const ScaleFreeRatio& q : ScaleFreeRatios(g, p, free, full)) {
    EXPECT_TRUE(std::isfinite(q.std)) << q.name;
  }
}

}  // namespace
}  // namespace coaxid
