#include "experiments/studies/mpi.h"

#include <cstdlib>

#ifdef COAXID_MPI
#include <mpi.h>
#endif

namespace coaxid {

bool BuiltWithMpi() {
#ifdef COAXID_MPI
  return true;
#else
  return false;
#endif
}

MpiWorld StartMpiIfLaunched() {
  MpiWorld world;
#ifdef COAXID_MPI
  if (!std::getenv("OMPI_COMM_WORLD_SIZE") && !std::getenv("PMI_SIZE")) return world;
  MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, &world.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &world.size);
  world.active = true;
#endif
  return world;
}

int MpiMax(const MpiWorld& world, int value) {
#ifdef COAXID_MPI
  if (world.active) {
    int out = value;
    MPI_Allreduce(&value, &out, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return out;
  }
#endif
  return value;
}

void FinishMpi(const MpiWorld& world) {
#ifdef COAXID_MPI
  if (world.active) MPI_Finalize();
#endif
}

}  // namespace coaxid
