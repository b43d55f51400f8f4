// `coaxid demo --out=DIR`: the whole story on the shipped data.
//
//  1. simulate every shipped scenario (configs/scenarios/NAME.yaml) and check
//     that the shipped log data/glmav/NAME.csv is reproduced from its seed;
//  2-5. `coaxid compare` on the shipped flight and balance logs with the
//     simulated truth: the paper's linear_kf, output_error and the EKF, each
//     in DIR/compare/METHOD/, and the comparison in DIR/compare/;
//  6. `coaxid discover` on a simulated balance log with an undeclared effect
//     (DIR/discover_simulated/) and on the measured T-motor test-stand data
//     (DIR/discover_tmotor28/).
// Ends with one report, DIR/report.html (self-contained, opens in a browser)
// and the same as DIR/report.md (experiments/reports/demo_report.h), plus
// DIR/summary.json for programs. Progress on stderr.
#pragma once

namespace coaxid {

int RunDemo();

}  // namespace coaxid
