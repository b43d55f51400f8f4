// Study spec files (docs/study.md, configs/studies/*.yaml): a Monte Carlo or
// sensitivity study of the estimators on simulated logs. A study is a list of
// runs, one per (sweep point, seed); each run is a pure function of the spec,
// the point and the seed (experiments/studies/run.h), so runs can be done in any
// order, on any number of threads, processes or machines.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/vehicle_config.h"
#include "experiments/simulation/scenario.h"

namespace coaxid {

enum class StudyMethod { kLinearKf, kOutputError, kEkf, kDiscover };
const char* StudyMethodName(StudyMethod method);

// What the sweep varies (one setting per study).
enum class SweepSetting {
  kNone,             // plain Monte Carlo: one point
  kNoiseScale,       // factor on every noise std of every scenario
  kExcitationScale,  // factor on the flight excitation amplitudes and the balance swashplate grid
  kExcitationType,   // flight excitation: multisine, 3211, doublet, none
  kLogLength,        // flight duration [s]
  kSampleRate,       // flight and balance sampling rate [Hz]
  kInitialError,     // relative perturbation of the start values (uniform in +-value, per seed)
  kEffectStrength,   // a truth effect parameter ("effect.param"); 0: the effect is absent
};
const char* SweepSettingName(SweepSetting setting);

struct StudySweep {
  SweepSetting setting = SweepSetting::kNone;
  std::string parameter;           // kEffectStrength: "effect.param"
  std::vector<double> values;      // numeric settings
  std::vector<std::string> types;  // kExcitationType
  int NumPoints() const;
  // The point's value as text ("0.5", "3211"; "-" for kNone).
  std::string Label(int point) const;
  // The point's numeric value (NaN for kNone and kExcitationType).
  double Value(int point) const;
};

// A randomised study (key `randomise`, docs/study.md): every seed draws its
// own truth vehicle, truth effects and flight, as a user's vehicles and
// flights differ; used by the discover confusion study (issue 13). Ranges
// are [lo, hi], drawn uniformly.
struct StudyRandomisation {
  bool enabled = false;
  std::array<double, 2> truth_offset{0.10, 0.30};  // |truth / config - 1| per free parameter, random sign
  // Ixx, Iyy, Izz drawn again (from a stream of their own) until they obey
  // the triangle inequality of principal moments, as a rigid body's do.
  // false: each as drawn, what the studies drew before 2026-12-01 (replays of
  // the seeds judged then).
  bool rigid_body_inertias = true;
  // Relative weights of the truth classes: no effect, one library effect,
  // two, one load outside the library (experiments/simulation/outside_library_loads.h).
  std::map<std::string, double> truth_weights{
      {"none", 3}, {"single", 8}, {"pair", 2}, {"outside", 2}};
  std::vector<std::string> effects;                   // library effects drawn (default: all)
  std::array<double, 2> effect_strength{0.7, 1.4};    // x the effect's typical strength
  std::map<std::string, std::array<double, 2>> outside_strength{
      {"yaw_from_swashplate", {1.5e-3, 4e-3}}, {"thrust_from_climb_rate", {0.2, 0.5}}};
  std::vector<std::string> excitations{"multisine", "3211", "doublet"};
  std::array<double, 2> swashplate_rms_rad{0.02, 0.06};
  std::array<double, 2> omega_difference_rad_s{0, 50};          // hover trim |omega1 - omega2|
  std::array<double, 2> gyroscopic_omega_difference_rad_s{20, 50};  // when gyroscopic is in the truth
  std::array<double, 2> duration_s{30, 60};
  std::array<double, 2> hover_height_m{1.5, 2.5};
  std::array<double, 2> low_height_m{0.13, 0.9};  // always when ground_effect is in the truth
  double low_share = 0.5;      // share of the other flights flown low
  double balance_share = 0.5;  // share of runs that add the spec's balance scenario
  double held_out_s = 30;      // a 3211 flight held out for discover (0: none)
  // Flights by other controllers and sensors than the template's: each
  // controller gain, and each logged channel's noise std, times its own
  // factor drawn log-uniformly in the range ([1, 1]: the template's).
  std::array<double, 2> controller_gain_factor{1, 1};
  std::array<double, 2> sensor_noise_factor{1, 1};
};

struct StudySpec {
  std::string source;       // the spec file
  std::string name;         // file stem unless given
  std::string config_path;  // resolved against the spec file's folder
  VehicleConfig config;
  std::vector<std::string> scenario_paths;
  std::vector<Scenario> scenarios;
  std::vector<std::string> estimate;  // empty: the config's free parameters
  std::vector<StudyMethod> methods;
  int seed_count = 0;
  uint64_t base_seed = 1;
  StudySweep sweep;
  StudyRandomisation randomise;
  // output_error (and discover's fits).
  double segment_s = 1.0;
  int noise_relaxations = 2;
  // discover.
  double discover_alpha = 0.01;
  int discover_max_added = 4;
  // FNV-1a of the spec text and of every file it names (config, scenarios):
  // a finished run belongs to this study only if the hashes agree.
  std::string hash;

  int NumRuns() const { return sweep.NumPoints() * seed_count; }
  bool HasFlight() const;
  bool HasBalance() const;
};

// One run of the study: run index = point * seed_count + seed_index.
struct StudyRunId {
  int point = 0, seed_index = 0;
  uint64_t seed = 0;  // base_seed + seed_index
};
StudyRunId RunIdAt(const StudySpec& spec, int run_index);
std::string RunKey(int point, int seed_index);  // "p3_s12"

// Reads and checks a spec strictly: unknown keys, missing entries, bad values,
// methods that cannot use the scenarios' logs and sweeps that do not apply
// throw InputError naming the file and key. Builds every point's scenarios
// and truth once, so a spec that parses runs.
StudySpec LoadStudySpec(const std::string& path);
StudySpec ParseStudySpec(const std::string& yaml_text, const std::string& source);

// 64-bit FNV-1a as 16 hex digits.
std::string Fnv1aHex(const std::string& text, uint64_t hash = 14695981039346656037ull);

}  // namespace coaxid
