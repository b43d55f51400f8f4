// The parameter set: every parameter of ../shared/spec/model.md by its
// canonical name, plus the parameters of enabled effects ("effect.name").
// Parameters are a named, indexed vector that estimators read and write; the
// model never holds a parameter value itself (STYLE.md, item 2).
//
// The base parameters always come first, in the order of BaseParameter, so
// the templated model reads theta[kAlpha] with a compile-time index. Effect
// parameters follow, each effect's as one contiguous block.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace coaxid {

enum BaseParameter : int {
  // Known constants (measured; not estimated unless asked).
  kMass,         // m [kg]
  kGravity,      // g [m/s^2]
  kAirDensity,   // rho [kg/m^3]
  kRotorRadius,  // R [m], S_prop = pi R^2
  kBodyRadius,   // D [m], S_s = pi D^2 (eq. 26)
  kBodyLength,   // l [m], S_c = 2 D l (eq. 26)
  // Unknowns (model.md, Parameters table).
  kAlpha,        // upper-rotor thrust coefficient [N s^2], eq. 6, < 0
  kBeta,         // lower-rotor thrust coefficient [N s^2], eq. 7, < 0
  kSigma0,       // coaxial interference loss at omega1 = omega2 [-]
  kCx,           // body-shape coefficients, eq. 24 [-]
  kCy,
  kCz,
  kGamma1,       // yaw-torque coefficients [N m s^2], eq. 33
  kGamma2,
  kHubDistance,  // d [m], G to lower-rotor hub O2, eqs. 31-32
  kIxx,          // principal inertias [kg m^2], eq. 5
  kIyy,
  kIzz,
  kNumBaseParameters
};

// Canonical names, indexed by BaseParameter.
const char* BaseParameterName(int index);
// Names of the unknown base parameters (alpha .. Izz), in index order.
std::vector<std::string> UnknownBaseParameterNames();

struct Parameter {
  std::string name;
  double value = 0;
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  // Typical magnitude: estimators work with value / scale, so that every
  // free coordinate is of order one.
  double scale = 1;
  bool estimated = false;
  std::string unit;
};

class ParameterSet {
 public:
  // Appends a parameter. Throws InputError on a duplicate name, a non-finite
  // value or scale, lower > upper, or a value outside its bounds.
  int Add(const Parameter& p);

  int size() const { return static_cast<int>(parameters_.size()); }
  // -1 if absent.
  int Index(const std::string& name) const;
  // Throws InputError naming the parameter if absent.
  int IndexOrThrow(const std::string& name) const;
  bool Has(const std::string& name) const { return Index(name) >= 0; }

  const Parameter& operator[](int i) const { return parameters_[i]; }
  Parameter& mutable_parameter(int i) { return parameters_[i]; }
  const Parameter& Get(const std::string& name) const { return parameters_[IndexOrThrow(name)]; }
  double Value(const std::string& name) const { return Get(name).value; }
  void SetValue(const std::string& name, double value);
  void SetEstimated(const std::string& name, bool estimated);

  // Every value in index order: the theta vector the model reads.
  Eigen::VectorXd Values() const;
  void SetValues(const Eigen::VectorXd& values);

  // The estimated (free) parameters: their indices, values, and values divided
  // by scale, in index order.
  std::vector<int> FreeIndices() const;
  std::vector<std::string> FreeNames() const;
  Eigen::VectorXd FreeVector() const;
  void SetFreeVector(const Eigen::VectorXd& free_values);
  Eigen::VectorXd ScaledFreeVector() const;
  void SetScaledFreeVector(const Eigen::VectorXd& scaled);

 private:
  std::vector<Parameter> parameters_;
};

// Free parameters within 1e-6 of their range from a bound.
std::vector<std::string> ParametersAtBounds(const ParameterSet& parameters);

}  // namespace coaxid
