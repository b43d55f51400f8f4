#include "experiments/cli/cli.h"

#include <iostream>

#include "core/errors.h"
#include "experiments/cli/check.h"
#include "experiments/cli/compare.h"
#include "experiments/cli/demo.h"
#include "experiments/cli/design.h"
#include "experiments/cli/discover.h"
#include "experiments/cli/identify.h"
#include "experiments/cli/import.h"
#include "experiments/cli/simulate.h"
#include "experiments/cli/study.h"

namespace coaxid {

const char* const kCliUsage =
    "usage: coaxid <subcommand> [--flags]\n"
    "  simulate --config=F --scenario=S --out=FILE.csv [--truth=T.json] [--seed=N]\n"
    "  check    --logs=A.csv[,B.csv...] [--config=F]\n"
    "  identify --method=linear_kf|output_error|ekf --logs=A.csv[,B.csv...] --config=F --out=DIR\n"
    "           [--validate=C.csv,...] [--holdout_fraction=0.2]\n"
    "           linear_kf: [--process_noise=0]\n"
    "           output_error: [--segment_s=1] [--start=config|linear_kf] [--huber=0] [--coloured_residuals]\n"
    "  identify --method=kinematic --logs=A.csv[,B.csv...] --out=DIR [--config=F]\n"
    "           (sensor biases, scale factors, time offset; writes corrected logs)\n"
    "  discover --logs=A.csv[,B.csv...] --config=F --out=DIR [--validate=C.csv,...]\n"
    "           [--alpha=0.01] [--max_added=4] [--segment_s=1]\n"
    "  compare  --logs=A.csv[,B.csv...] --config=F --out=DIR [--validate=C.csv,...]\n"
    "           [--holdout_fraction=0.2] [--truth=T.json]\n"
    "           linear_kf (balance logs), output_error (all), ekf (flight logs); one table\n"
    "  import   --format=tmotor28 --in=DIR --out=DIR2\n"
    "  study    --spec=FILE --out=DIR [--jobs=N] [--restart] [--max_runs=N]\n"
    "           --spec=FILE --out=DIR --export=N | --job=DIR/jobs/job_K.yaml | --merge --out=DIR\n"
    "           (mpirun -n K coaxid study ... in a -DCOAXID_MPI=ON build; docs/study.md)\n"
    "  design   --config=F --scenario=S[,S2...] --out=DIR [--design_parameters=Cz,sigma0]\n"
    "           [--criterion=D|A] [--max_attitude_rad=R] [--add_holds=N] (predicted std of a\n"
    "           planned experiment; a designed excitation and balance holds)\n"
    "  demo     --out=DIR   (the whole story on the shipped data -> DIR/report.html)\n"
    "Run `coaxid --help` for every flag.\n";

std::vector<std::string> SplitList(const std::string& list) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = list.find(',', start);
    const std::string part =
        list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!part.empty()) out.push_back(part);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

int RunCli(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << kCliUsage;
    return 2;
  }
  const std::string command = argv[1];
  if (argc > 2) {
    std::cerr << "coaxid: unexpected argument '" << argv[2] << "'\n" << kCliUsage;
    return 2;
  }
  try {
    if (command == "simulate") return RunSimulate();
    if (command == "check") return RunCheck();
    if (command == "demo") return RunDemo();
    if (command == "compare") return RunCompare();
    if (command == "identify") return RunIdentify();
    if (command == "discover") return RunDiscover();
    if (command == "import") return RunImport();
    if (command == "study") return RunStudy();
    if (command == "design") return RunDesign();
    std::cerr << "coaxid: unknown subcommand '" << command << "'\n" << kCliUsage;
    return 2;
  } catch (const InputError& e) {
    std::cerr << "coaxid " << command << ": " << e.what() << "\n";
    return 2;
  } catch (const ComputationError& e) {
    std::cerr << "coaxid " << command << ": failed: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "coaxid " << command << ": internal error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace coaxid
