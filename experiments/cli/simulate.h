// `coaxid simulate` (cli-and-reports.md): a truth vehicle (the config's, with
// the scenario's overrides and effects) run through a scenario file, written
// as a log and, with --truth, the truth parameters as JSON.
//
//   coaxid simulate --config=F --scenario=S --out=FILE.csv [--truth=T.json] [--seed=N]
#pragma once

namespace coaxid {

int RunSimulate();

}  // namespace coaxid
