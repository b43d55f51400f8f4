// Optimised kernels for the SUNDIALS serial N_Vector operations that CVODE
// calls in its inner loop. Debian's libsundials 6.4.1 is built without
// optimisation (`objdump -d` of N_VWSqrSumLocal_Serial shows every loop
// variable stored to the stack), and with a restart every 5 ms those vector
// kernels were the largest single cost (perf: N_VWSqrSumLocal_Serial alone
// 26-37 % of a sensitivity simulation). Same results as SUNDIALS' own
// kernels up to round-off order of summation.
#pragma once

#include <nvector/nvector_serial.h>

namespace coaxid {

// Replaces the hot operations of a serial vector's ops table; vectors cloned
// from it afterwards inherit them.
void UseOptimizedSerialOps(N_Vector v);

}  // namespace coaxid
