# Precompiled headers (option COAXID_PCH). The headers most sources include
# are precompiled once per build tree, in coaxid_core, and every other target
# loads that .gch (REUSE_FROM): a .gch per target would cost its ~7 s build
# again in each of the ~25 targets. The test programs share a second one that
# adds gtest, built once in the first of them.
#
# GCC uses a .gch only for a compile with the flags that built it. Every
# target links coaxid_core and has its flags; the definitions some add
# (COAXID_DEFAULT_DATA_DIR, COAXID_SOURCE_DIR, COAXID_BINARY, COAXID_MPI,
# COAXID_MPIEXEC) are names these headers never use, which GCC allows. Were a
# .gch refused, -Winvalid-pch (added by CMake) would say so and the headers
# would be read as text: the same program, compiled more slowly.
#
# Loading a .gch costs every object 0.5-2 s of CPU whether it needs the headers
# or not, so only headers most objects include are listed (<Eigen/Core> is in
# 155 of 193 objects, gtest in the 63 tests; nlohmann/json, ceres and glog cost
# more to load than they saved on a sample of 11 objects). Measured with g++ 12
# on the shared 2-core machine, 2026-11-29: a fresh Release build 1798 -> 1551 s
# of CPU (user+sys), about 2 min less on 2 cores.
function(coaxid_precompile_headers)
  set(headers <algorithm> <array> <cmath> <functional> <limits> <map> <memory>
      <mutex> <optional> <string> <utility> <vector> <Eigen/Core>)
  target_precompile_headers(coaxid_core PRIVATE ${headers})
  set(tests_pch "")
  set(dirs ${PROJECT_SOURCE_DIR})
  while(dirs)
    list(POP_FRONT dirs dir)
    get_directory_property(subdirs DIRECTORY ${dir} SUBDIRECTORIES)
    get_directory_property(targets DIRECTORY ${dir} BUILDSYSTEM_TARGETS)
    list(APPEND dirs ${subdirs})
    foreach(target ${targets})
      get_target_property(type ${target} TYPE)
      if(target MATCHES "_tests$" AND NOT tests_pch)
        set(tests_pch ${target})
        target_precompile_headers(${target} PRIVATE ${headers} <gtest/gtest.h>)
      elseif(target MATCHES "_tests$")
        target_precompile_headers(${target} REUSE_FROM ${tests_pch})
      elseif(NOT target STREQUAL coaxid_core AND type MATCHES "^(STATIC_LIBRARY|EXECUTABLE)$")
        target_precompile_headers(${target} REUSE_FROM coaxid_core)
      endif()
    endforeach()
  endwhile()
endfunction()
