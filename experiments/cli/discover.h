// `coaxid discover` (cli-and-reports.md, effects.md):
//
//   coaxid discover --logs=A.csv[,B.csv] --config=F --out=DIR [--validate=C.csv,...]
//       [--holdout_fraction=0.2] [--alpha=0.01] [--max_added=4] [--segment_s=1]
//
// Fits the declared model, scores every library effect it lacks, adds the
// best passing one and refits until none passes (ident/discover/discovery.h). Writes
// DIR/discovery.json, DIR/report.md (a Markdown report with the plots),
// DIR/config.yaml (the final model, resolved) and DIR/plots/*.png. Progress
// on stderr. Bad input exits 2 and writes nothing; a failed fit exits 1.
#pragma once

namespace coaxid {

int RunDiscover();

}  // namespace coaxid
