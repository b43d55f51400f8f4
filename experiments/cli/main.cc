// coaxid: identify the flight-dynamics model of a coaxial-rotor MAV.
#include <gflags/gflags.h>
#include <glog/logging.h>

#include "experiments/cli/cli.h"

int main(int argc, char** argv) {
  gflags::SetUsageMessage("coaxid <simulate|check|identify|demo> [--flags]");
  gflags::ParseCommandLineFlags(&argc, &argv, /*remove_flags=*/true);
  FLAGS_logtostderr = true;
  google::InitGoogleLogging(argv[0]);
  return coaxid::RunCli(argc, argv);
}
