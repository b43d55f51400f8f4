// `coaxid study` (docs/study.md): Monte Carlo and sensitivity studies.
//
//   coaxid study --spec=FILE --out=DIR [--jobs=N] [--restart] [--max_runs=N]
//   coaxid study --spec=FILE --out=DIR --export=N      N job specs and scripts in DIR/jobs/
//   coaxid study --job=DIR/jobs/job_K.yaml [--jobs=N]  one exported job (DIR/parts/job_K.jsonl)
//   coaxid study --merge --out=DIR                     merge the parts, write the summary
//   coaxid study --spec=FILE --run=KEY --out=DIR       one run: its logs, record and progress
//   mpirun -n K coaxid study --spec=FILE --out=DIR     (built with -DCOAXID_MPI=ON)
//
// The spec is read and checked before anything is written (bad spec: exit 2,
// DIR untouched). Runs go to DIR/runs.jsonl as they finish; rerunning the same
// command resumes (a different spec with the same DIR is an error unless
// --restart). At the end (also after an interrupt, with the runs done so far)
// DIR/summary.json, DIR/summary.md and DIR/plots/ are written atomically.
#pragma once

namespace coaxid {

int RunStudy();

}  // namespace coaxid
