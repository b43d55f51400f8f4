#include <gtest/gtest.h>
#include <cstdio>
#include "core/log.h"
#include "dynamics/vehicle.h"
#include "ident/linear_baseline.h"
namespace coaxid {
TEST(Scratch, Shipped) {
  const Vehicle v = LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  const Log log = ReadLog(std::string(COAXID_SOURCE_DIR) + "/data/glmav/balance.csv");
  const int cut = HoldoutStartRow(log, 0.2);
  std::vector<BalanceData> est{MakeBalanceData(log, 0, cut)}, val{MakeBalanceData(log, cut)};
  LinearBaselineResult r = RunLinearBaseline(v.parameters, est, val);
  printf("alpha %g +- %g beta_map %g sigma0 %g +- %g\n", r.thrust_map.alpha, r.thrust_map.alpha_std, r.thrust_map.beta, r.thrust_map.sigma0, r.thrust_map.sigma0_std);
  for (int i = 0; i < kNumPsi; ++i) printf("%d %g +- %g (filter %g)\n", i, r.estimate[i], std::sqrt(r.covariance(i,i)), i < 5 ? r.std_from_filter[i] : 0.0);
  printf("%s\n", r.excitation.message.c_str());
  for (auto& n : r.notes) printf("- %s\n", n.c_str());
  for (int c = 0; c < 6; ++c) printf("%s fit nrmse %g rel %g max %g hold %g | val nrmse %g rel %g\n", LoadChannelName(c), r.fit[c].error.nrmse, r.fit[c].mean_relative_error, r.fit[c].max_relative_error, r.fit[c].hold_mean_relative_error, r.validation_fit[c].error.nrmse, r.validation_fit[c].mean_relative_error);
  for (int c = 0; c < 6; ++c) printf("R %s %g src %d\n", LoadChannelName(c), r.noise[0].channel[c].variance, (int)r.noise[0].channel[c].source);
}
}
