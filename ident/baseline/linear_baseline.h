// The paper's method end to end on balance logs (sects. 3-5), the honest
// baseline every later estimator is compared against:
//
//  1. persistent excitation, structural part (Lemma 1, swashplate condition);
//  2. thrust map: alpha, beta from single-rotor holds (Fig. 8), Cz assumed;
//  3. interference map sigma (Fig. 9): table and parametric sigma0;
//  4. noise covariance R from the holds (eqs. 83-84), or from the residuals
//     for steady-point logs;
//  5. persistent excitation, eq. 73-74 (eigenvalues of sum X^T X);
//  6. Kalman estimation of Theta = (beta, Cz_alpha, Cz_beta, gamma1, gamma2)
//     (eqs. 66-70, 80-82), with the map's uncertainty propagated;
//  7. alpha and Cz (Cz_alpha / alpha and Cz_beta / beta, compared);
//  8. reconstruction on the estimation data and validation on held-out data
//     (sect. 5), X and Y included.
//
// d comes from the config and sigma from the map of the same logs (model.md
// decision 6); the result's notes say so, with everything else a reader needs
// to judge the numbers.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "core/parameters.h"
#include "ident/baseline/balance_holds.h"
#include "ident/baseline/linear_kf.h"
#include "ident/baseline/map_uncertainty.h"
#include "ident/baseline/noise_covariance.h"
#include "ident/baseline/persistent_excitation.h"
#include "ident/baseline/reconstruction.h"
#include "ident/baseline/thrust_map.h"

namespace coaxid {

struct LinearBaselineOptions {
  ThrustMapOptions thrust_map;
  NoiseCovarianceOptions noise;
  ExcitationOptions excitation;
  double process_noise = 0;  // Q, see LinearKfOptions (paper: 0)
  double prior_std = 1e3;    // diffuse prior, in parameter scales (LinearKfOptions)
  int history_stride = 1;    // Kalman history: every n-th update
  bool IsValid(std::string* why) const;
};

struct BaselineEstimate {
  double value = std::numeric_limits<double>::quiet_NaN();
  double std = std::numeric_limits<double>::quiet_NaN();
};

struct LinearBaselineResult {
  // What the method takes as known (model.md decision 6).
  double d = 0;           // [m], config
  double Cz_assumed = 0;  // config; alpha and beta of the thrust map assume it
  double area_ratio = 0;  // S_s / S_prop

  ThrustMap thrust_map;
  std::vector<NoiseCovariance> noise;  // per estimation data set
  ExcitationReport excitation;
  LinearBalanceModel model;  // alpha, d, k, sigma map
  LinearKfOptions kf_options;
  LinearKfSummary kf;

  // (Theta, alpha) and their covariance with the thrust map's uncertainty
  // propagated (map_uncertainty.h); std_from_filter is the filter's own P.
  PsiVector estimate = PsiVector::Zero();
  PsiMatrix covariance = PsiMatrix::Zero();
  ThetaVector std_from_filter = ThetaVector::Zero();

  // Cz two ways (eqs. 64-65) and whether they disagree (beyond 3 std of the difference).
  BaselineEstimate Cz_from_alpha, Cz_from_beta;
  double Cz_difference_in_std = 0;
  bool Cz_disagree = false;
  // Diagnostic: beta from X and Y alone (eqs. 61-62, not used in estimation,
  // independent of d), and the d it implies with the filter's beta.
  BaselineEstimate beta_from_xy;
  double implied_d = std::numeric_limits<double>::quiet_NaN();

  // Model outputs against the measured loads. The reconstructions point into
  // the BalanceData given to RunLinearBaseline: keep those alive.
  std::vector<Reconstruction> estimation, validation;
  ChannelFits fit, validation_fit;

  std::vector<std::string> notes;

  BaselineEstimate Parameter(int psi_index) const {
    return {estimate[psi_index], std::sqrt(covariance(psi_index, psi_index))};
  }
};

// config: the vehicle's parameters (d, Cz, D, R, and the scales and nominal
// values of alpha, beta, Cz, gamma1, gamma2 for the filter's scaling and
// prior). Throws InputError when the data cannot support the method (the
// message names what is missing; for too little excitation, which condition
// fails and which inputs must vary) and ComputationError when the filter fails.
LinearBaselineResult RunLinearBaseline(const ParameterSet& config,
                                       const std::vector<BalanceData>& estimation,
                                       const std::vector<BalanceData>& validation,
                                       const LinearBaselineOptions& options = {});

// The excitation check alone, as `coaxid check` runs it on any balance logs:
// Lemma 1 and the swashplate condition, then eqs. 73-74 with sigma = 1 (no
// thrust map needed: sigma only rescales rows by 0.8-1), d and the scales
// from the config, R from the holds (a provisional 1 % of the channel's rms
// where the holds have no spread).
ExcitationReport CheckBalanceExcitation(const ParameterSet& config,
                                        const std::vector<BalanceData>& data,
                                        const LinearBaselineOptions& options = {});

// The filter's scaling and prior from the config: Theta_0 = (beta, Cz alpha,
// Cz beta, gamma1, gamma2) at their nominal values, scales from the
// parameters' scales.
LinearKfOptions KfOptionsFromConfig(const ParameterSet& config,
                                    const LinearBaselineOptions& options);

}  // namespace coaxid
