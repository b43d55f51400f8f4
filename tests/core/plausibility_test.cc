// The plausibility verdict (core/plausibility.h): the published constants of
// two real coaxial vehicles pass; each kind of implausible fit is named.
#include "core/plausibility.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "core/vehicle_config.h"

namespace coaxid {
namespace {

ParameterSet Config(const std::string& name) {
  return LoadVehicleConfig(std::string(COAXID_SOURCE_DIR) + "/configs/" + name + ".yaml")
      .parameters;
}

// The config's unknowns as estimates at their config values.
std::map<std::string, double> AtConfig(const ParameterSet& p) {
  std::map<std::string, double> out;
  for (int i : p.FreeIndices()) out[p[i].name] = p[i].value;
  return out;
}

nlohmann::json Fit(double p_nrmse, double p_rms) {
  return {{"u", {{"rms", 0.01}, {"nrmse", 0.2}}},
          {"p", {{"rms", p_rms}, {"nrmse", p_nrmse}}},
          {"overall_nrmse", 0.5}};
}

std::vector<std::string> Subjects(const PlausibilityVerdict& v, PlausibilityFinding::Kind kind) {
  std::vector<std::string> out;
  for (const PlausibilityFinding& f : v.findings) {
    if (f.kind == kind) out.push_back(f.subject);
  }
  return out;
}

using Kind = PlausibilityFinding::Kind;

TEST(Plausibility, PublishedConstantsOfTheGlmavAndTheCoaxPass) {
  for (const char* vehicle : {"glmav", "coax"}) {
    const ParameterSet p = Config(vehicle);
    const PlausibilityVerdict v = JudgePlausibility(p, AtConfig(p), Fit(0.3, 0.05), nullptr);
    EXPECT_TRUE(v.DescribesVehicle()) << vehicle << ": " << v.Summary();
    EXPECT_TRUE(v.ToJson()["describes_vehicle"].get<bool>());
  }
}

// What the fit of issue 17 looked like: d at its lower bound, inertias 10-100x
// above physical values, p not explained.
TEST(Plausibility, TheCoaxFitWithoutItsBarIsNamedForWhatItIs) {
  const ParameterSet p = Config("coax");
  std::map<std::string, double> e = AtConfig(p);
  e["d"] = 0.005;       // the lower bound
  e["Ixx"] = 0.03;      // 16x the published value
  e["Iyy"] = 0.0035;    // 1.9x: large but possible
  e["Izz"] = 0.0400;    // > Ixx + Iyy and > m r^2
  const double noise = 0.01;
  const PlausibilityVerdict v =
      JudgePlausibility(p, e, Fit(1.0, 20 * noise), Fit(0.95, 20 * noise), {{"p", noise}});
  EXPECT_FALSE(v.DescribesVehicle());
  EXPECT_EQ(Subjects(v, Kind::kAtBound), std::vector<std::string>{"d"});
  const std::vector<std::string> outside = Subjects(v, Kind::kOutsidePhysicalRange);
  // m r^2 = 0.302 (0.171^2 + 0.135^2) = 0.01433 kg m^2.
  EXPECT_NE(std::find(outside.begin(), outside.end(), "Ixx"), outside.end());
  EXPECT_EQ(std::find(outside.begin(), outside.end(), "Iyy"), outside.end());
  EXPECT_NE(std::find(outside.begin(), outside.end(), "Izz"), outside.end());
  EXPECT_NE(std::find(outside.begin(), outside.end(), "Ixx + Iyy - Izz"), outside.end());
  EXPECT_EQ(Subjects(v, Kind::kUnexplainedChannel), (std::vector<std::string>{"p", "p"}));
  const nlohmann::json j = v.ToJson();
  EXPECT_FALSE(j["describes_vehicle"].get<bool>());
  EXPECT_NE(j["verdict"].get<std::string>().find("does not describe this vehicle"),
            std::string::npos);
  EXPECT_NE(v.Summary().find("p (nrmse 1, estimation)"), std::string::npos) << v.Summary();
}

TEST(Plausibility, APhysicalLimitIsJudgedAtItsEdge) {
  const ParameterSet p = Config("glmav");
  const double m = 0.25, r2 = 0.17 * 0.17 + 0.15 * 0.15;
  std::map<std::string, double> e = AtConfig(p);
  e["Ixx"] = e["Iyy"] = 0.999 * m * r2;
  e["Izz"] = 1e-4;
  EXPECT_TRUE(JudgePlausibility(p, e, nullptr, nullptr).DescribesVehicle());
  e["Ixx"] = 1.001 * m * r2;
  EXPECT_EQ(Subjects(JudgePlausibility(p, e, nullptr, nullptr), Kind::kOutsidePhysicalRange),
            std::vector<std::string>{"Ixx"});
  // The torque-to-thrust ratio: 0.5 R at most.
  e = AtConfig(p);
  e["gamma1"] = 0.51 * 0.17 * 5.6e-5;
  EXPECT_EQ(Subjects(JudgePlausibility(p, e, nullptr, nullptr), Kind::kOutsidePhysicalRange),
            std::vector<std::string>{"|gamma1 / alpha|"});
  // Beyond a bound (linear_kf and ekf have none) counts as at it.
  e = AtConfig(p);
  e["Cz"] = -0.5;
  const PlausibilityVerdict v = JudgePlausibility(p, e, nullptr, nullptr);
  EXPECT_EQ(Subjects(v, Kind::kAtBound), std::vector<std::string>{"Cz"});
  EXPECT_NE(v.findings[0].text.find("beyond its lower bound"), std::string::npos);
}

TEST(Plausibility, AChannelHoldingOnlyNoiseIsNotUnexplained) {
  const ParameterSet p = Config("glmav");
  // nrmse 11 on a channel that barely moves: variation 0.05 / 11 against a
  // noise std of 0.01: nothing there to explain.
  EXPECT_TRUE(JudgePlausibility(p, AtConfig(p), Fit(11.0, 0.05), nullptr, {{"p", 0.01}})
                  .DescribesVehicle());
  // Variation 0.021, twice and a bit its noise: judged.
  EXPECT_FALSE(JudgePlausibility(p, AtConfig(p), Fit(1.0, 0.021), nullptr, {{"p", 0.01}})
                   .DescribesVehicle());
  // Without the noise std, nrmse alone decides.
  EXPECT_FALSE(JudgePlausibility(p, AtConfig(p), Fit(11.0, 0.05), nullptr).DescribesVehicle());
  // A parameter the report calls undetermined (std null) is not judged
  // (Izz drifting in a short flight without yaw), unless the fit pushed it
  // to a bound (Iyy at 0.1 kg m^2 with the scale held).
  nlohmann::json parameters = {{"Izz", {{"value", 0.0135}, {"std", nullptr}, {"estimated", true}}},
                               {"Ixx", {{"value", 0.0019}, {"std", 5e-5}, {"estimated", true}}},
                               {"d", {{"value", 0.1}, {"std", nullptr}, {"estimated", false}}}};
  std::map<std::string, double> from_report = EstimatesOfReport(parameters, p);
  EXPECT_EQ(from_report.size(), 1u);
  EXPECT_EQ(from_report.count("Ixx"), 1u);
  EXPECT_TRUE(JudgePlausibility(p, from_report, nullptr, nullptr).DescribesVehicle());
  // Pressed to a bound: judged against the physical ranges (Iyy at 0.1 kg
  // m^2 is 8x what 0.25 kg of this size can have); the bound itself is no
  // finding for an undetermined parameter (sigma0 at 0 in a flight-only fit).
  parameters["Iyy"] = {{"value", 0.1}, {"std", nullptr}, {"estimated", true}};
  parameters["sigma0"] = {{"value", 0.0}, {"std", nullptr}, {"estimated", true}};
  std::set<std::string> undetermined;
  from_report = EstimatesOfReport(parameters, p, &undetermined);
  EXPECT_EQ(undetermined, (std::set<std::string>{"Iyy", "sigma0"}));
  const PlausibilityVerdict v =
      JudgePlausibility(p, from_report, nullptr, nullptr, {}, undetermined);
  EXPECT_TRUE(Subjects(v, Kind::kAtBound).empty());
  const std::vector<std::string> outside = Subjects(v, Kind::kOutsidePhysicalRange);
  EXPECT_NE(std::find(outside.begin(), outside.end(), "Iyy"), outside.end());
  EXPECT_EQ(std::find(outside.begin(), outside.end(), "sigma0"), outside.end());
  // Parameters the fit did not estimate are the user's: not judged.
  std::map<std::string, double> e = AtConfig(p);
  e.erase("d");
  ParameterSet held = p;
  held.SetValue("d", 0.005);
  EXPECT_TRUE(JudgePlausibility(held, e, nullptr, nullptr).DescribesVehicle());
}

}  // namespace
}  // namespace coaxid
