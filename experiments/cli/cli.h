// The `coaxid` command line (../shared/spec/cli-and-reports.md). Each
// subcommand is a function from parsed flags to an exit status: 0 success,
// 2 bad input (one clear message on stderr), 1 any other failure.
#pragma once

#include <string>
#include <vector>

namespace coaxid {

// Every subcommand's flags on one screen, printed after a call it cannot run.
extern const char* const kCliUsage;

// argv[0] is the program, argv[1] the subcommand; flags already parsed by gflags.
int RunCli(int argc, char** argv);

// Splits "a.csv,b.csv" into its parts (empty parts dropped).
std::vector<std::string> SplitList(const std::string& list);

}  // namespace coaxid
