// The MPI side of `coaxid study` (built with -DCOAXID_MPI=ON, Debian's
// OpenMPI): `mpirun -n K coaxid study --spec=F --out=DIR` gives rank r the
// runs i with i mod K = r (the shards of `--export=K`); each rank appends its
// records to DIR/parts/rank_r.jsonl, and after a barrier rank 0 merges them
// into DIR/runs.jsonl and writes the summary. Without COAXID_MPI, or when
// not started by mpirun, the world is one process and nothing here calls MPI.
#pragma once

namespace coaxid {

struct MpiWorld {
  int rank = 0, size = 1;
  bool active = false;  // MPI_Init was called
};

// Initialises MPI when built with it and started by mpirun (OMPI_COMM_WORLD_SIZE
// or PMI_SIZE in the environment).
MpiWorld StartMpiIfLaunched();
// The largest of every rank's value (a collective; each rank's own value
// without MPI).
int MpiMax(const MpiWorld& world, int value);
void FinishMpi(const MpiWorld& world);

// Whether this binary was built with MPI.
bool BuiltWithMpi();

}  // namespace coaxid
