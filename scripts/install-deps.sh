#!/usr/bin/env bash
# Installs coaxid's build dependencies from Debian 12 packages when missing.
# Idempotent: does nothing (and needs no network) when everything is there.
#   scripts/install-deps.sh         what the default build needs
#   scripts/install-deps.sh --mpi   also OpenMPI, for the -DCOAXID_MPI=ON build
set -euo pipefail

packages=(
  build-essential cmake
  libceres-dev libeigen3-dev libsundials-dev
  libgflags-dev libgoogle-glog-dev libgtest-dev
  libyaml-cpp-dev nlohmann-json3-dev libbenchmark-dev
  gnuplot-nox
)
if [ "${1:-}" = "--mpi" ]; then packages+=(libopenmpi-dev openmpi-bin); fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all dependencies present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
