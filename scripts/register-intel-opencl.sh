#!/usr/bin/env bash
# Register Intel's CPU OpenCL runtime from PyPI (intel-opencl-rt) with pyopencl's ICD loader,
# where it is installed in this Python environment; where it is not, do nothing.
#
# The wheel ships etc/OpenCL/vendors/intel-cpu.icd naming a placeholder path
# (/opt/anaconda1anaconda2anaconda3/lib/libintelocl.so), so no loader finds the runtime. The
# loader inside pyopencl's wheel (ocl-icd) reads the .icd files in pyopencl/.libs besides
# /etc/OpenCL/vendors (the PoCL and Oclgrind wheels put theirs there), and libintelocl.so
# finds its companions through its RUNPATH ($ORIGIN): one file, intel-cpu.icd in
# pyopencl/.libs holding the library's absolute path, makes the device visible to every
# later process of this environment, with no environment variable. (Where OCL_ICD_VENDORS
# is set, the loader reads only that folder: add the file there too.) Reinstalling pyopencl
# removes the file: run this again. scripts/ensure-opencl.sh runs it.
set -uo pipefail

found=$(python - <<'PY'
import importlib.metadata as md, importlib.util, os
try:
    files = md.distribution("intel-opencl-rt").files or []
except md.PackageNotFoundError:
    raise SystemExit(0)
libs = [f for f in files if f.name == "libintelocl.so"]
spec = importlib.util.find_spec("pyopencl")
if libs and spec is not None:
    lib = os.path.realpath(libs[0].locate())
    print(lib, os.path.join(os.path.dirname(spec.origin), ".libs"), sep="\n")
PY
)
[ -n "$found" ] || exit 0
lib=$(sed -n 1p <<<"$found")
folder=$(sed -n 2p <<<"$found")
if [ ! -f "$lib" ]; then
  echo "register-intel-opencl: intel-opencl-rt lists $lib but it is not there" >&2
  exit 1
fi
if [ ! -d "$folder" ]; then
  echo "register-intel-opencl: this pyopencl has no bundled ICD loader ($folder); put a file" \
       "holding '$lib' into /etc/OpenCL/vendors/intel-cpu.icd to use Intel's runtime" >&2
  exit 1
fi
echo "$lib" > "$folder/intel-cpu.icd"
echo "register-intel-opencl: $folder/intel-cpu.icd -> $lib" >&2
