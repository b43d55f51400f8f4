// Randomised studies (spec key `randomise`, experiments/studies/random_draw.h):
// each seed's draw is a pure function of (spec, seed), stays in the spec's
// ranges, sets the hover trim's |omega1 - omega2| it reports, flies low when
// the truth has a ground effect, and draws the truth classes at their
// weights; specs that cannot be randomised are refused. The confusion table
// counts what discover added against the truth.
#include <cmath>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "core/errors.h"
#include "dynamics/trim.h"
#include "experiments/simulation/simulate_experiment.h"
#include "experiments/studies/confusion.h"
#include "experiments/studies/random_draw.h"
#include "experiments/studies/summary.h"
#include "ident/discover/discovery.h"

namespace coaxid {
namespace {

const std::string kSpecPath = std::string(COAXID_SOURCE_DIR) + "/configs/studies/test_random.yaml";

std::string SpecText(const std::string& extra = "") {
  return "study: random\nconfig: ../glmav.yaml\n"
         "scenarios: [../scenarios/flight.yaml, ../scenarios/balance_short.yaml]\n"
         "methods: [discover]\nseeds: {count: 10, base: 5}\n" +
         (extra.empty() ? std::string("randomise: {}\n") : extra);
}

TEST(RandomDraw, IsAPureFunctionOfTheSeedAndStaysInItsRanges) {
  const StudySpec spec = ParseStudySpec(SpecText(), kSpecPath);
  const Vehicle nominal = MakeVehicle(spec.config);
  const StudyRandomisation& r = spec.randomise;
  for (uint64_t seed = 100; seed < 130; ++seed) {
    const RandomDraw draw = DrawRun(spec, seed);
    EXPECT_EQ(draw.description, DrawRun(spec, seed).description) << seed;
    const nlohmann::json& d = draw.description;
    // Every unknown but gamma2 (set by the trim) 10-30 % off its config value.
    for (const std::string& name : nominal.parameters.FreeNames()) {
      if (name == "gamma2") continue;
      const double ratio =
          d["truth_parameters"][name].get<double>() / nominal.parameters.Value(name);
      EXPECT_GE(std::fabs(ratio - 1), r.truth_offset[0] - 1e-12) << name << " seed " << seed;
      EXPECT_LE(std::fabs(ratio - 1), r.truth_offset[1] + 1e-12) << name << " seed " << seed;
    }
    const nlohmann::json& f = d["flight"];
    const double duration = f["duration_s"].get<double>();
    EXPECT_TRUE(duration >= 30 && duration <= 60) << duration;
    const double rms = f["swashplate_rms_rad"].get<double>();
    EXPECT_TRUE(rms >= 0.02 && rms <= 0.06) << rms;
    const bool low = f["band"] == "low";
    for (const auto& h : f["heights_m"]) {
      const std::array<double, 2> band = low ? r.low_height_m : r.hover_height_m;
      EXPECT_TRUE(h.get<double>() >= band[0] && h.get<double>() <= band[1]) << h;
    }
    const bool ground = draw.truth_label.find("ground_effect") != std::string::npos;
    if (ground) {
      EXPECT_TRUE(low) << seed;
    }
    // The reported trim difference is the truth's, at the first waypoint.
    const Scenario& flight = draw.scenarios.front();
    const Vehicle truth = MakeTruthVehicle(spec.config, flight);
    const HoverTrim trim = TrimHover(truth.model, truth.parameters.Values(),
                                     flight.flight.waypoints.front().height);
    const double difference = trim.input[kOmega1] - trim.input[kOmega2];
    EXPECT_NEAR(difference, f["omega_difference_rad_s"].get<double>(), 1e-9);
    const bool gyroscopic = draw.truth_label.find("gyroscopic") != std::string::npos;
    const std::array<double, 2> range =
        gyroscopic ? r.gyroscopic_omega_difference_rad_s : r.omega_difference_rad_s;
    EXPECT_GE(std::fabs(difference), range[0] - 0.01) << seed;
    EXPECT_LE(std::fabs(difference), range[1] + 0.01) << seed;
    // Thrust falls with the climb rate (k > 0); the yaw load takes either sign.
    const auto thrust = flight.truth_outside_library.find("thrust_from_climb_rate");
    if (thrust != flight.truth_outside_library.end()) {
      EXPECT_GE(thrust->second, r.outside_strength.at("thrust_from_climb_rate")[0]);
    }
    // The held-out flight and the balance log (if drawn) share the truth.
    ASSERT_TRUE(draw.has_held_out);
    EXPECT_EQ(draw.held_out.truth_parameters, flight.truth_parameters);
    EXPECT_EQ(draw.held_out.flight.excitation.type, Excitation::Type::k3211);
    EXPECT_EQ(draw.scenarios.size(), d["balance"].get<bool>() ? 2u : 1u);
    for (const Scenario& s : draw.scenarios) {
      EXPECT_EQ(s.truth_parameters, flight.truth_parameters);
      EXPECT_EQ(s.truth_outside_library, flight.truth_outside_library);
    }
  }
}

// The truth vehicle is a rigid body: its principal moments obey the triangle
// inequality. Drawn each on its own, about half of the draws would not (Ixx
// and Iyy, 1.9e-3 nominal, 10-30 % off with random signs, differ by more
// than Izz, 3e-4); those, and only those, get inertias of their own stream,
// and every other draw of the seed stays as it was.
TEST(RandomDraw, TruthInertiasObeyTheTriangleInequalityAndNothingElseMoves) {
  const StudySpec rigid = ParseStudySpec(SpecText(), kSpecPath);
  const StudySpec independent =
      ParseStudySpec(SpecText("randomise: {rigid_body_inertias: false}\n"), kSpecPath);
  ASSERT_TRUE(rigid.randomise.rigid_body_inertias);
  int redrawn = 0;
  for (uint64_t seed = 300; seed < 340; ++seed) {
    const nlohmann::json a = DrawRun(rigid, seed).description;
    const nlohmann::json b = DrawRun(independent, seed).description;
    auto inertia = [](const nlohmann::json& d, const char* name) {
      return d["truth_parameters"][name].get<double>();
    };
    auto obeys_triangle = [&](const nlohmann::json& d) {
      const double x = inertia(d, "Ixx"), y = inertia(d, "Iyy"), z = inertia(d, "Izz");
      return x <= y + z && y <= x + z && z <= x + y;
    };
    EXPECT_TRUE(obeys_triangle(a)) << seed << ": " << a["truth_parameters"].dump();
    const bool obeyed = obeys_triangle(b);
    if (!obeyed) ++redrawn;
    nlohmann::json rest_a = a, rest_b = b;
    for (const char* name : {"Ixx", "Iyy", "Izz"}) {
      rest_a["truth_parameters"].erase(name);
      rest_b["truth_parameters"].erase(name);
      if (obeyed) {
        EXPECT_EQ(inertia(a, name), inertia(b, name)) << name << " seed " << seed;
      }
    }
    // The hover trim that sets gamma2 for the drawn |omega1 - omega2| is a
    // Newton solve of the whole model: other inertias move its last digits.
    for (const char* path : {"/truth_parameters/gamma2", "/flight/omega_difference_rad_s"}) {
      const nlohmann::json::json_pointer where(path);
      const double va = rest_a[where].get<double>(), vb = rest_b[where].get<double>();
      EXPECT_NEAR(va, vb, 1e-9 * std::fabs(vb)) << path << " seed " << seed;
      rest_a[where] = rest_b[where];
    }
    EXPECT_EQ(rest_a, rest_b) << seed;
  }
  // Measured: 21 of these 40 seeds break it as drawn one by one.
  EXPECT_GE(redrawn, 10);
  EXPECT_LE(redrawn, 30);
}

// Another controller and other sensors: each gain and each logged channel's
// noise std takes its own factor in the range, the same on the held-out
// flight, and every other draw of the seed stays as it was (their own
// stream), so a spec that turns them on flies the same truths and flights.
TEST(RandomDraw, OtherControllersAndSensorsChangeOnlyGainsAndNoise) {
  const StudySpec plain = ParseStudySpec(SpecText(), kSpecPath);
  const StudySpec other = ParseStudySpec(
      SpecText("randomise: {controller_gain_factor: [0.7, 1.5], sensor_noise_factor: [0.5, 2]}\n"),
      kSpecPath);
  const FlightScenario& t = plain.scenarios.front().flight;
  int gains_changed = 0;
  for (uint64_t seed = 200; seed < 215; ++seed) {
    const RandomDraw a = DrawRun(plain, seed), b = DrawRun(other, seed);
    nlohmann::json rest = b.description;
    rest.erase("controller_gain_factors");
    rest.erase("sensor_noise_factors");
    EXPECT_EQ(rest, a.description) << seed;
    const FlightScenario& fa = a.scenarios.front().flight;
    const FlightScenario& fb = b.scenarios.front().flight;
    EXPECT_EQ(fb.excitation.amplitude, fa.excitation.amplitude);
    EXPECT_EQ(fb.waypoints.size(), fa.waypoints.size());
    const auto& g = b.description["controller_gain_factors"];
    ASSERT_EQ(g.size(), 9u);
    for (const auto& [name, factor] : g.items()) {
      EXPECT_GE(factor.get<double>(), 0.7 - 1e-12) << name;
      EXPECT_LE(factor.get<double>(), 1.5 + 1e-12) << name;
    }
    EXPECT_DOUBLE_EQ(fb.gains.att_kd, t.gains.att_kd * g["att_kd"].get<double>());
    EXPECT_DOUBLE_EQ(fb.gains.alt_ki, t.gains.alt_ki * g["alt_ki"].get<double>());
    EXPECT_DOUBLE_EQ(fb.gains.max_tilt, t.gains.max_tilt);
    gains_changed += fb.gains.att_kp != fa.gains.att_kp;
    const auto& n = b.description["sensor_noise_factors"];
    for (const auto& [column, std] : t.noise_std) {
      if (std == 0) {
        EXPECT_FALSE(n.contains(column)) << column;
        continue;
      }
      const double factor = n[column].get<double>();
      EXPECT_TRUE(factor >= 0.5 - 1e-12 && factor <= 2 + 1e-12) << column << " " << factor;
      EXPECT_DOUBLE_EQ(fb.noise_std.at(column), std * factor) << column;
      EXPECT_DOUBLE_EQ(b.held_out.flight.noise_std.at(column), std * factor) << column;
    }
    EXPECT_DOUBLE_EQ(b.held_out.flight.gains.yaw_kp, fb.gains.yaw_kp);
  }
  EXPECT_EQ(gains_changed, 15);
}

// The judged set of discover_controllers.yaml can be rerun: seed 8300 draws
// the factors its record holds (runs.jsonl of the study, binary f7ec410).
TEST(RandomDraw, TheControllersJudgedSetDrawsWhatItsRecordsHold) {
  const StudySpec spec = LoadStudySpec(std::string(COAXID_SOURCE_DIR) +
                                       "/configs/studies/discover_controllers.yaml");
  const nlohmann::json& d = DrawRun(spec, 8300).description;
  EXPECT_DOUBLE_EQ(d["controller_gain_factors"]["att_kp"].get<double>(), 1.0219135239372272);
  EXPECT_DOUBLE_EQ(d["controller_gain_factors"]["pos_kd"].get<double>(), 1.2669240966382362);
  EXPECT_DOUBLE_EQ(d["sensor_noise_factors"]["az"].get<double>(), 0.951319203462854);
}

// Weights none 3, single 8, pair 2, outside 2 (of 15): over 300 seeds each
// class's count lies within 4 binomial std of its expectation.
TEST(RandomDraw, DrawsTheTruthClassesAtTheirWeights) {
  const StudySpec spec = ParseStudySpec(SpecText(), kSpecPath);
  std::map<std::string, int> count;
  const int n = 300;
  for (uint64_t seed = 0; seed < n; ++seed) {
    ++count[DrawRun(spec, 7000 + seed).description["truth_class"].get<std::string>()];
  }
  for (const auto& [name, weight] : spec.randomise.truth_weights) {
    const double p = weight / 15.0;
    EXPECT_NEAR(count[name], n * p, 4 * std::sqrt(n * p * (1 - p))) << name;
  }
}

TEST(RandomDraw, SpecsThatCannotBeRandomisedAreRefused) {
  auto refused = [&](const std::string& text, const std::string& what) {
    try {
      ParseStudySpec(text, kSpecPath);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused(SpecText("sweep: {setting: noise_scale, values: [1, 2]}\nrandomise: {}\n"),
          "takes no sweep");
  refused(SpecText("randomise: {truth_offset: [0.3, 0.1]}\n"), "randomise.truth_offset");
  refused(SpecText("randomise: {effects: [tail_rotor]}\n"), "'tail_rotor' is not an effect");
  refused(SpecText("randomise: {truths: {some: 1}}\n"), "unknown key 'some'");
  refused(SpecText("randomise: {excitation: [chirp]}\n"), "'chirp' is not multisine");
  refused(SpecText("randomise: {controller_gain_factor: [0, 2]}\n"),
          "randomise.controller_gain_factor");
  refused(SpecText("randomise: {sensor_noise_factor: [2, 0.5]}\n"), "randomise.sensor_noise_factor");
  refused("study: random\nconfig: ../glmav.yaml\nscenarios: [../scenarios/flight.yaml, "
          "../scenarios/flight_3211.yaml]\nmethods: [discover]\nseeds: {count: 2}\nrandomise: {}\n",
          "exactly one flight scenario");
}

nlohmann::json Record(const std::string& truth, const std::string& truth_class, bool balance,
                      const std::vector<std::string>& added, bool unexplained,
                      double rms_over_noise = 1.0) {
  nlohmann::json u = nlohmann::json::array();
  if (unexplained) u.push_back("r");
  return {{"draw", {{"truth", truth}, {"truth_class", truth_class}, {"balance", balance}}},
          {"methods",
           {{"discover",
             {{"ok", true},
              {"added", added},
              {"unexplained", u},
              {"declared_rms_over_noise", rms_over_noise}}}}}};
}

TEST(Confusion, CountsWhatWasAddedAgainstTheTruth) {
  const std::vector<nlohmann::json> records = {
      Record("none", "none", false, {}, false),
      Record("none", "none", true, {"wind"}, false),
      Record("gyroscopic", "single", false, {"gyroscopic"}, false, 1.5),
      Record("gyroscopic", "single", true, {"gyroscopic", "wind"}, false, 1.05),
      Record("gyroscopic+wind", "pair", false, {"wind", "gyroscopic"}, false),
      Record("outside:yaw_from_swashplate", "outside", false, {}, true, 1.2),
      Record("outside:yaw_from_swashplate", "outside", false, {"cg_offset"}, true),
      {{"key", "p0_s9"}, {"methods", {{"discover", {{"ok", false}, {"error", "x"}}}}}}};
  const nlohmann::json c = ConfusionSummary(records);
  EXPECT_EQ(c["runs_judged"], 7);
  EXPECT_EQ(c["runs_failed"], 1);
  const nlohmann::json& all = c["all"];
  EXPECT_EQ(all["single_found_alone"]["gyroscopic"]["count"], 1);
  EXPECT_EQ(all["single_found_alone"]["gyroscopic"]["runs"], 2);
  // Visible: the declared fit left rms >= 1.1 x noise (the first only).
  EXPECT_EQ(all["single_found_alone_visible"]["gyroscopic"]["count"], 1);
  EXPECT_EQ(all["single_found_alone_visible"]["gyroscopic"]["runs"], 1);
  EXPECT_EQ(all["outside_nothing_added"]["count"], 1);
  EXPECT_EQ(all["pair_both_found"]["count"], 1);
  EXPECT_EQ(all["outside_unexplained"]["count"], 1);
  EXPECT_EQ(all["outside_unexplained"]["runs"], 2);
  EXPECT_EQ(all["outside_unexplained_visible"]["count"], 1);
  EXPECT_EQ(all["outside_unexplained_visible"]["runs"], 1);
  EXPECT_EQ(all["none_false_alarm"]["count"], 1);
  // Wrong additions: wind (none), wind (gyroscopic), cg_offset (outside).
  EXPECT_EQ(all["nothing_wrong_added"]["count"], 4);
  EXPECT_EQ(all["nothing_wrong_added"]["runs"], 7);
  EXPECT_EQ(c["flight_and_balance"]["nothing_wrong_added"]["runs"], 2);
  EXPECT_EQ(c["flight_and_balance"]["nothing_wrong_added"]["count"], 0);
  bool seen = false;
  for (const auto& row : c["matrix"]) {
    if (row["truth"] == "gyroscopic") {
      seen = true;
      EXPECT_EQ(row["added"]["gyroscopic"], 1);
      EXPECT_EQ(row["added"]["gyroscopic+wind"], 1);
    }
  }
  EXPECT_TRUE(seen);
  EXPECT_NE(ConfusionMarkdown(c).find("| gyroscopic alone: found, nothing else | 1/2 = 50 %"),
            std::string::npos)
      << ConfusionMarkdown(c);
}

TEST(Confusion, ReportsDiscoversWallTimePerRun) {
  std::vector<nlohmann::json> records;
  for (int k = 1; k <= 11; ++k) {
    nlohmann::json r = Record("none", "none", k % 2 == 0, {}, false);
    r["methods"]["discover"]["seconds"] = k;
    records.push_back(r);
  }
  const nlohmann::json c = ConfusionSummary(records);
  const nlohmann::json& all = c["seconds"]["all"];
  EXPECT_EQ(all["runs"], 11);
  EXPECT_EQ(all["median"], 6);
  EXPECT_EQ(all["p90"], 10);
  EXPECT_EQ(all["max"], 11);
  EXPECT_EQ(c["seconds"]["flight_only"]["runs"], 6);  // 1, 3, ..., 11
  EXPECT_EQ(c["seconds"]["flight_only"]["max"], 11);
  EXPECT_NE(ConfusionMarkdown(c).find("median 6.0 s, 90th percentile 10.0 s, largest 11.0 s"),
            std::string::npos)
      << ConfusionMarkdown(c);
}

// The per-method discover line of a randomised study judges each run
// against its own draw: before, it judged every run against the spec's
// truth (none), and called 48 of the 60 runs of
// discover_sensors_actuators.yaml false alarms where none was wrong.
TEST(Confusion, TheMethodSummaryJudgesEachRunAgainstItsOwnDraw) {
  const StudySpec spec = LoadStudySpec(std::string(COAXID_SOURCE_DIR) +
                                       "/configs/studies/discover_sensors_actuators.yaml");
  std::vector<nlohmann::json> records = {
      Record("servo_lag", "single", false, {"servo_lag"}, false),
      Record("none", "none", false, {}, false),
      Record("gyro_bias", "single", true, {"gyro_bias", "wind"}, false),
      Record("outside:yaw_from_swashplate", "outside", false, {"cg_offset"}, true)};
  for (nlohmann::json& r : records) {
    r["point"] = 0;
    r["simulation"] = "ok";
    r["methods"]["discover"]["parameters"] = nlohmann::json::object();
  }
  const nlohmann::json summary = SummarizeStudy(spec, records);
  const nlohmann::json& f = summary["points"][0]["methods"]["discover"]["false_alarm"];
  EXPECT_EQ(f["runs"], 4);
  EXPECT_EQ(f["count"], 2);  // the wind and the cg_offset
}

}  // namespace
// "Visible" in the study is what discover calls unexplained: one ratio.
TEST(Confusion, VisibleIsDiscoversUnexplainedRatio) {
  EXPECT_EQ(kVisibleRmsOverNoise, DiscoveryOptions().unexplained_rms_ratio);
}

}  // namespace coaxid
