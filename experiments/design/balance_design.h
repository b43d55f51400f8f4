// Balance campaigns (issue 16, item 3): which holds to add to a planned
// strain-gauge balance campaign so that the parameters a user names are
// fixed best, and whether the paper's method can separate beta from
// Cz_beta (Lemma 1 and the swashplate condition, ident/baseline).
//
// Candidate holds: every rotor-speed pair of a grid over the planned speeds
// (single-rotor runs included) with swashplate angles from a grid within the
// limit. A hold's information is that of its steady load (the mean of its
// samples, weight sqrt(rows) / std, as the output-error fit weighs it), so
// holds add information; the design adds, one at a time, the hold that
// improves the criterion most with everything else planned (greedy
// D- or A-optimal selection), then predicts the joint precision of the
// campaign with them.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/input_hold.h"
#include "dynamics/vehicle.h"
#include "experiments/design/design_criterion.h"
#include "experiments/design/planned_experiment.h"
#include "experiments/simulation/scenario.h"
#include "ident/baseline/persistent_excitation.h"

namespace coaxid {

struct BalanceDesignOptions {
  int add_holds = 4;
  // The largest swashplate angle a hold may use [rad]; NaN: the planned
  // campaign's largest (0.15 rad without one).
  double max_swashplate_rad = std::numeric_limits<double>::quiet_NaN();
  OutputErrorOptions output_error;
  std::function<void(const std::string&)> progress;
};

struct BalanceDesign {
  int balance_index = -1;            // the campaign among the plan's scenarios
  bool new_campaign = false;         // the plan had none: one of the added holds alone
  std::vector<Scenario> designed;    // the plan with the holds added
  std::vector<InputVector> added;    // in the order chosen
  std::vector<double> criterion_path;  // the criterion after each addition (holds add information)
  int candidates = 0;
  PredictedPrecision before, after;
  double criterion_before = 0, criterion_after = 0;
  bool has_lemma_before = false;
  ExcitationReport lemma_before, lemma_after;  // the paper's excitation check
};

// Throws InputError for add_holds < 1 or a named parameter the plan does
// not estimate.
BalanceDesign DesignBalanceHolds(const Vehicle& vehicle, const std::vector<Scenario>& plan,
                                 const DesignCriterion& criterion,
                                 const BalanceDesignOptions& options);

}  // namespace coaxid
