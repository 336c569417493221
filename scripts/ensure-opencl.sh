#!/usr/bin/env bash
# Make sure clsamp has an OpenCL device that compiles kernels, installing Debian's PoCL
# where the one from PyPI cannot (run it in the virtualenv clsamp is installed in).
#
# PoCL 3.0 from PyPI (pocl-binary-distribution) links LLVM 14, which calls CPUs newer than
# itself (AMD Zen 5 and later) 'generic' and then refuses that target: every kernel build
# fails there. Debian's pocl-opencl-icd (PoCL 3.1) picks its code target from the CPU's
# features and works; pyopencl's loader finds it in /etc/OpenCL/vendors, and clsamp uses the
# first CPU device that compiles. Where a device already compiles, this installs nothing.
# Where Intel's CPU runtime is pip-installed (intel-opencl-rt), it registers it with
# pyopencl's loader first (scripts/register-intel-opencl.sh).
set -uo pipefail

check() { python -c "import clsamp; print('clsamp uses', clsamp.current_device())"; }

# Intel's CPU runtime, where it is pip-installed here (CI installs it; clsamp does not need it)
bash "$(dirname "$0")/register-intel-opencl.sh"

check 2>/dev/null && exit 0
echo "ensure-opencl: no OpenCL device here compiles a kernel; installing Debian's PoCL" >&2
if ! command -v apt-get >/dev/null; then
  echo "ensure-opencl: no apt-get; install an OpenCL driver for this CPU (a PoCL built with" \
       "an LLVM that knows it) and run this again" >&2
  check
  exit 1
fi
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get install -y -q pocl-opencl-icd >/dev/null \
  || { $sudo apt-get update -q >/dev/null && $sudo apt-get install -y -q pocl-opencl-icd >/dev/null; } \
  || { echo "ensure-opencl: apt-get install pocl-opencl-icd failed" >&2; exit 1; }
check
