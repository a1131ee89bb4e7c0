#!/usr/bin/env bash
# Installs the Debian 12 packages scallop builds and runs with (as root, or with sudo).
set -euo pipefail
packages=(build-essential cmake ninja-build ccache pkg-config
  libopenblas0-serial  # UMFPACK (the harmonic solve's coarse system, solver=direct) 3 times faster than with the reference BLAS
  libeigen3-dev libcgal-dev libopenmesh-dev libpcl-dev libsuitesparse-dev libtbb-dev nlohmann-json3-dev
  libnanoflann-dev libspectra-dev libcli11-dev libgtest-dev libbenchmark-dev liblzf-dev libxxhash-dev libpng-dev
  linuxcnc-uspace
  libboost-graph-dev  # mesh.segment: Kruskal's minimum spanning tree
  libembree-dev  # MeshDistance: the nearest point of a mesh (the programs' and the certificate's distances)
  libocct-data-exchange-dev libocct-visualization-dev libocct-modeling-algorithms-dev  # B-spline fit, STEP
  blender  # mesh.quad_remesh runs QuadriFlow inside Blender, headless
  slurm-wlm munge  # batch --executor slurm; tests/cli/slurm_test.cpp starts a one-node cluster
  clang libclang-rt-14-dev  # scripts/fuzz.sh: clang++ and libFuzzer's runtime (libclang_rt.fuzzer-x86_64.a)
  python3-numpy python3-scipy python3-matplotlib)  # bench/*.py and ../shared/tools, the measurements
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
