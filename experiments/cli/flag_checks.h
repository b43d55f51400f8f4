// Flag checks shared by the subcommands: each bad flag gets one message
// naming it (InputError, exit 2) before anything is read or written.
#pragma once

#include <string>

namespace coaxid {

// Throws "missing --FLAG" followed by the subcommand's usage when value is empty.
void RequireFlag(const std::string& value, const char* flag, const std::string& usage);

// --holdout_fraction must lie in [0, 1).
void CheckHoldoutFraction(double fraction);

// --out may be missing or a folder, not an existing file.
void CheckOutputFolder(const std::string& out);

}  // namespace coaxid
