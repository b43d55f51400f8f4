// The output-error residual blocks' simulation cache and the block-wise
// marginal information, against plain recomputation.
#include "ident/output_error/information.h"

#include <cmath>
#include <memory>

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include "experiments/simulation/simulate_experiment.h"
#include "ident/free_parameters.h"
#include "ident/output_error/compressed_segment_cost.h"
#include "ident/output_error/costs.h"
#include "ident/output_error/output_error.h"

namespace coaxid {
namespace {

struct Fixture {
  Vehicle vehicle = LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  FreeParameters free{vehicle.parameters};
  EstimationLog flight, balance;
  std::vector<double> flight_std, balance_std;
  Fixture() {
    FlightScenario f;
    f.duration_s = 1.0;
    f.excitation.start_s = 0.0;
    flight = MakeEstimationLog(SimulateFlight(vehicle, f, 7));
    BalanceScenario b;
    b.hold_s = 0.2;
    balance = MakeEstimationLog(SimulateBalance(vehicle, b, 8));
    flight_std.assign(flight.NumChannels(), 0.01);
    balance_std.assign(balance.NumChannels(), 0.05);
  }
};

// Residuals at a point evaluated again are served from the segment's last
// run (no CVODE), also after a run with sensitivities there; Jacobians are
// recomputed (sensitivities are not kept) and equal; a new point is
// simulated afresh.
TEST(FlightSegmentCost, ReusesItsLastSimulationOnlyAtTheSamePoint) {
  const Fixture f;
  FlightSegmentCost cost(f.vehicle.model, f.free, f.flight, 0, 100, true, f.flight_std, 1e-2,
                         OutputErrorOptions::DefaultIntegrator());
  SegmentCostTimes times;
  cost.set_times(&times);
  Eigen::VectorXd s0 = InitialStateFromLog(f.flight, 0), s1 = InitialStateFromLog(f.flight, 100);
  Eigen::VectorXd theta = f.free.ScaledValues();
  const int m = cost.num_residuals(), P = f.free.size();
  std::vector<double> r1(m), r2(m), r3(m), j1(m * P), j2(m * P), js(m * kNumStates),
      jn(m * kNumStates);
  const double* blocks[] = {s0.data(), theta.data(), s1.data()};
  double* jacobians1[] = {js.data(), j1.data(), jn.data()};
  double* jacobians2[] = {js.data(), j2.data(), jn.data()};
  ASSERT_TRUE(cost.Evaluate(blocks, r1.data(), jacobians1));
  ASSERT_TRUE(cost.Evaluate(blocks, r2.data(), nullptr));  // served by the run above
  EXPECT_EQ(times.state_runs.load(), 0);
  EXPECT_EQ(r1, r2);
  ASSERT_TRUE(cost.Evaluate(blocks, r2.data(), jacobians2));  // run again, same numbers
  EXPECT_EQ(times.sensitivity_runs.load(), 2);
  EXPECT_EQ(r1, r2);
  EXPECT_EQ(j1, j2);
  theta[0] *= 1.001;
  ASSERT_TRUE(cost.Evaluate(blocks, r3.data(), nullptr));
  EXPECT_EQ(times.state_runs.load(), 1);
  EXPECT_NE(r1, r3);
  theta[0] /= 1.001;  // back: a new run, without the sensitivities in its error control
  ASSERT_TRUE(cost.Evaluate(blocks, r3.data(), nullptr));
  EXPECT_EQ(times.state_runs.load(), 2);
  // Two integrations to rtol 1e-7, atol 1e-9 over 100 intervals of states
  // of order 1, weighted by 1 / 0.01: within 1e-4 of each other.
  for (int r = 0; r < m; ++r) EXPECT_NEAR(r1[r], r3[r], 1e-4) << "residual " << r;
}

// The block-wise Schur complement equals H_tt - H_ts H_ss^-1 H_st from the
// whole Jacobian as Ceres evaluates it (held coordinates held by a manifold),
// from the full segments and from the compressed ones.
TEST(OutputErrorInformation, EqualsTheDenseSchurComplement) {
  const Fixture f;
  const std::vector<int> starts = {0, 60, 130, 200};  // three segments
  const std::vector<int> held = {kX, kY};
  std::vector<std::unique_ptr<FlightSegmentCost>> segments;
  std::vector<Eigen::VectorXd> states;
  for (size_t j = 0; j + 1 < starts.size(); ++j) {
    const bool next = j + 2 < starts.size();
    segments.push_back(std::make_unique<FlightSegmentCost>(
        f.vehicle.model, f.free, f.flight, starts[j], starts[j + 1], next, f.flight_std, 1e-2,
        OutputErrorOptions::DefaultIntegrator()));
    states.push_back(InitialStateFromLog(f.flight, starts[j]));
  }
  BalanceRowsCost balance(f.vehicle.model, f.free, f.balance, 0, f.balance.NumRows(),
                          f.balance_std);
  Eigen::VectorXd theta = f.free.ScaledValues();
  const int P = f.free.size();

  LogResidualBlocks flight_blocks, balance_blocks;
  flight_blocks.log = &f.flight;
  for (size_t j = 0; j < segments.size(); ++j) {
    flight_blocks.segments.push_back(segments[j].get());
    flight_blocks.segment_states.push_back(states[j].data());
  }
  flight_blocks.held_states = held;
  balance_blocks.log = &f.balance;
  balance_blocks.balance.push_back(&balance);
  const OutputErrorInformation info =
      ComputeOutputErrorInformation({flight_blocks, balance_blocks}, theta.data(), P, false);
  // The same through the segments as Ceres sees them (compressed).
  std::vector<std::unique_ptr<CompressedSegmentCost>> compressed;
  LogResidualBlocks compressed_blocks = flight_blocks;
  for (size_t j = 0; j + 1 < starts.size(); ++j) {
    compressed.push_back(std::make_unique<CompressedSegmentCost>(
        std::make_unique<FlightSegmentCost>(f.vehicle.model, f.free, f.flight, starts[j],
                                            starts[j + 1], j + 2 < starts.size(), f.flight_std,
                                            1e-2, OutputErrorOptions::DefaultIntegrator())));
    ASSERT_TRUE(compressed.back()->compressed());
    compressed_blocks.compressed.push_back(compressed.back().get());
  }
  const OutputErrorInformation via_compressed = ComputeOutputErrorInformation(
      {compressed_blocks, balance_blocks}, theta.data(), P, false);

  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(options);
  problem.AddParameterBlock(theta.data(), P);
  for (Eigen::VectorXd& s : states) problem.AddParameterBlock(s.data(), kNumStates);
  problem.SetManifold(states[0].data(), new ceres::SubsetManifold(kNumStates, held));
  for (size_t j = 0; j < segments.size(); ++j) {
    std::vector<double*> blocks = {states[j].data(), theta.data()};
    if (segments[j]->has_next()) blocks.push_back(states[j + 1].data());
    problem.AddResidualBlock(segments[j].get(), nullptr, blocks);
  }
  problem.AddResidualBlock(&balance, nullptr, theta.data());
  ceres::Problem::EvaluateOptions eval;
  eval.parameter_blocks.push_back(theta.data());  // theta's columns first
  for (Eigen::VectorXd& s : states) eval.parameter_blocks.push_back(s.data());
  ceres::CRSMatrix crs;
  ASSERT_TRUE(problem.Evaluate(eval, nullptr, nullptr, nullptr, &crs));
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) J(r, crs.cols[k]) = crs.values[k];
  }
  const Eigen::MatrixXd H = J.transpose() * J;
  const int n = crs.num_cols - P;
  const Eigen::MatrixXd expected =
      H.topLeftCorner(P, P) -
      H.topRightCorner(P, n) * H.bottomRightCorner(n, n).ldlt().solve(H.bottomLeftCorner(n, P));
  ASSERT_EQ(info.information.rows(), P);
  // Same sums in another order: agreement to round-off of the largest entries.
  EXPECT_LT((info.information - expected).cwiseAbs().maxCoeff(),
            1e-9 * expected.cwiseAbs().maxCoeff());
  EXPECT_LT((via_compressed.information - expected).cwiseAbs().maxCoeff(),
            1e-9 * expected.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace coaxid
