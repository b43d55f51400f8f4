#include "experiments/cli/flag_checks.h"

#include <filesystem>

#include "core/errors.h"
#include "core/report_values.h"

namespace coaxid {

void RequireFlag(const std::string& value, const char* flag, const std::string& usage) {
  if (value.empty()) throw InputError(std::string("missing --") + flag + "\n" + usage);
}

void CheckHoldoutFraction(double fraction) {
  if (!(fraction >= 0 && fraction < 1)) {
    throw InputError("--holdout_fraction must lie in [0, 1), got " + NumberText(fraction, "%g"));
  }
}

void CheckOutputFolder(const std::string& out) {
  std::error_code ec;
  if (std::filesystem::exists(out, ec) && !std::filesystem::is_directory(out, ec)) {
    throw InputError("--out=" + out + " exists and is not a folder");
  }
}

}  // namespace coaxid
