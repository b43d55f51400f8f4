// Error types shared by every layer (STYLE.md, item 9).
//
// - A bug (broken internal invariant) is a CHECK failure (glog).
// - Bad input or configuration, the user's problem, is an InputError; the CLI
//   prints its message and exits with status 2.
// - A computation that could not complete (solver diverged, integrator
//   failure) is a ComputationError; the CLI exits with status 1.
// Hot numeric code returns bool instead of throwing.
#pragma once

#include <stdexcept>
#include <string>

namespace coaxid {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ComputationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace coaxid
