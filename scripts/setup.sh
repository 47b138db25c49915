#!/usr/bin/env bash
# Installs every Debian 12 package vpm needs, and the npm packages of the browser view (web/,
# from its lockfile). Idempotent, non-interactive.
set -euo pipefail
PKGS=(
  cmake g++ make ninja-build pkg-config git python3  # ninja: the sanitizer tree builds its targets in parallel
  pocl-opencl-icd ocl-icd-opencl-dev opencl-headers opencl-clhpp-headers clinfo
  libeigen3-dev libboost-dev catch2
  libtet1.5-dev tetgen libnifti2-dev zlib1g-dev mricron-data
  libexpat1-dev  # GIfTI surfaces (.gii) are XML, read with expat
  libcgal-dev libgmp-dev libmpfr-dev
  libhdf5-dev python3-h5py  # element tables and reference sums (HDF5); h5py reads them in Python without vpm
  libsuitesparse-dev libopenblas0-pthread  # CHOLMOD's supernodal Cholesky for the sphere map, on OpenBLAS
  libcgal-demo  # the public surface models of bench/shapes (--models; its quick form in the tests)
  libviennacl-dev python3-vtk9 python3-numpy
  libhypre-dev openmpi-bin  # bench only: hypre BoomerAMG, the solver benchmark's peer, and its mpirun
  elastix  # bench only: the image registration a user would otherwise pick, bench/register_peers' peer
  snakemake python3-nibabel python3-scipy
  pybind11-dev python3-dev python3-pytest  # the Python package vpm (python/) and its tests (ctest python:*)
  python3-matplotlib python3-nbformat  # the worked example (examples/): plots, and its notebook made from the script
  python3-tqdm  # optional: progress bars of vpm.map_to_ball(progress=True)
  chromium
  linux-perf valgrind  # bench only: bench/ab/compare_builds.py --profile and --instructions
  clang-14 libclang-rt-14-dev llvm-14  # the ASan + UBSan build and libFuzzer (scripts/sanitize.sh, scripts/fuzz.sh); llvm-symbolizer for their stacks
  # tests only: the one-node Slurm cluster of tests/workflow/slurm.sh (ctest workflow:slurm), whose
  # daemons that test configures, starts and stops itself; slurmdbd keeps its accounts in a private
  # MariaDB (its server and my_print_defaults alone: these two packages have no service). The Slurm
  # packages' start scripts start nothing without /etc/slurm/slurm.conf and slurmdbd.conf
  slurmctld slurmd slurm-client slurmdbd munge mariadb-server-core mariadb-client-core
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  SUDO=""; [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
# Node.js and npm: Debian's, unless a node (>= 18) is on PATH already
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  SUDO=""; [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends nodejs npm
fi
# web/: three.js, esbuild and playwright-core, exactly as the lockfile says; skipped when
# node_modules already matches it
web="$(dirname "$0")/../web"
if ! cmp -s "$web/package-lock.json" "$web/node_modules/.package-lock.json.installed" 2>/dev/null; then
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
  cp "$web/package-lock.json" "$web/node_modules/.package-lock.json.installed"
fi
echo "setup: all ${#PKGS[@]} packages present, web/ npm packages installed"
