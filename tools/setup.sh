#!/usr/bin/env bash
# Installs what lsqt-cl needs to build and test on Debian 12 (as root, or through sudo):
# a C compiler, CMake, the OpenCL headers and ICD loader, PoCL's CPU device, and clang
# with its sanitizer/fuzzer runtimes, and SLURM with munge (test_slurm starts a single-node
# SLURM of its own; no daemon of these packages needs to run). Installs nothing when
# everything is present. OpenImageIO and GLM are for lssview (C++17, tools/lssview),
# Debian's matplotlib for tools/lssplot. clang-15, lld-15, rocm-device-libs, libclc-15 and
# oclgrind check the GPU code path without a GPU (test_gpu_build, test_oclgrind).
# libnetcdf-dev writes `lsqt-cl export`'s NetCDF; Debian's xarray and netCDF4 read it back
# in test_export, as a Python user would; python3-venv makes the venv into which test_rgl
# installs Mitsuba 3 from PyPI (CI's "clients" tests).
set -euo pipefail
PKGS=(build-essential cmake pkg-config ocl-icd-opencl-dev opencl-headers opencl-c-headers
      ocl-icd-libopencl1 pocl-opencl-icd clinfo clang libclang-rt-14-dev python3
      slurm-wlm munge libopenimageio-dev libglm-dev python3-matplotlib
      clang-15 lld-15 rocm-device-libs libclc-15 oclgrind
      libnetcdf-dev python3-xarray python3-netcdf4 python3-venv)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" != 0 ]; then
  command -v sudo >/dev/null || { echo "setup: run as root (apt-get needs it)" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
