// coaxid: identify the flight-dynamics model of a coaxial-rotor MAV.
#include <gflags/gflags.h>
#include <glog/logging.h>

#include "experiments/cli/cli.h"

int main(int argc, char** argv) {
  gflags::SetUsageMessage("coaxid <simulate|check|identify|demo> [--flags]");
  gflags::ParseCommandLineFlags(&argc, &argv, /*remove_flags=*/true);
  FLAGS_logtostderr = true;
  // Ceres' own ERROR and WARNING lines ("Terminating: Residual and Jacobian
  // evaluation failed.") repeat what coaxid reports itself, in its words and
  // with where the model fails: shown only with -v or --minloglevel.
  if (FLAGS_v == 0 && gflags::GetCommandLineFlagInfoOrDie("minloglevel").is_default) {
    FLAGS_minloglevel = google::GLOG_FATAL;
  }
  google::InitGoogleLogging(argv[0]);
  return coaxid::RunCli(argc, argv);
}
