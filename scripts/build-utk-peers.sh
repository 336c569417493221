#!/usr/bin/env bash
# Build UTK's SOT, PeriodicBNOT, Faure and Niederreiter samplers (utk-team/utk) as the
# timing drivers benchmarks/bench_utk.py runs (scripts/utk/utk_peer.cpp: one call of the
# sampler's generateSamples, timed, points to a file).
#
#     scripts/build-utk-peers.sh UTK_SRC SOT_SRC OUT_DIR
#     CLSAMP_UTK_BIN=OUT_DIR python benchmarks/bench_utk.py
#
# UTK_SRC: a tree of utk-team/utk (include/, externals/ and data/niederreiter/ are read);
# SOT_SRC: Paulin et al.'s Sliced-Optimal-Transport-Sampling at the commit UTK's
# cmake/externals/sot.cmake pins (e1a9aadabd0594291c0aa6131efc930c1f855102; UTK's
# sot.patch only edits that project's CMakeLists.txt, which this script does not use);
# OUT_DIR: where utk_sot, utk_periodic_bnot, utk_periodic_bnot_uniform (UTK's PeriodicBNOT
# code from a uniform start; see utk_peer.cpp), utk_faure and utk_niederreiter go.
#
# The flags are UTK's Release build's (CMAKE_BUILD_TYPE Release: -O3 -DNDEBUG, C++17,
# -Wall; SOT with OpenMP as UTK links it), without UTK_LOG (spdlog), which none of these
# samplers needs to run. Debian/Ubuntu packages:
#     apt-get install g++ libgsl-dev libcgal-dev libsuitesparse-dev libeigen3-dev
# A sampler whose libraries are missing is skipped with a message; the others still build.
# CXX and CXXFLAGS override the compiler and flags.
set -euo pipefail

if [ $# -ne 3 ]; then
    sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
UTK_SRC=$(cd "$1" && pwd)
SOT_SRC=$(cd "$2" && pwd)
mkdir -p "$3"
OUT=$(cd "$3" && pwd)
DRIVER="$(cd "$(dirname "$0")" && pwd)/utk/utk_peer.cpp"
CXX=${CXX:-g++}
CXXFLAGS=${CXXFLAGS:--O3 -DNDEBUG -std=c++17 -Wall -Wno-unused-variable -Wno-sign-compare}
# UTK_DATA_PATH as UTK's CMakeLists.txt sets it: Niederreiter reads its tables from
# data/niederreiter/ (gfarit.txt, gfplys.txt) at run time.
COMMON=(-D_USE_MATH_DEFINES -DUTK_DATA_PATH="\"$UTK_SRC/data\"" -I"$UTK_SRC/include" -I"$UTK_SRC/externals")

for f in include/utk/samplers/SamplerSOT.hpp include/utk/samplers/SamplerPeriodicBNOT.hpp \
         externals/PeriodicBNOT/BNOT.hpp data/niederreiter/gfplys.txt; do
    [ -f "$UTK_SRC/$f" ] || { echo "no $f under $UTK_SRC: not a UTK tree" >&2; exit 2; }
done
[ -f "$SOT_SRC/Transport/slicedOptimalTransportNBall.h" ] \
    || { echo "no Transport/slicedOptimalTransportNBall.h under $SOT_SRC" >&2; exit 2; }

build() {   # name, then the compiler's arguments
    local name=$1
    shift
    echo "+ $CXX $CXXFLAGS $*" >&2
    # shellcheck disable=SC2086
    if $CXX $CXXFLAGS "$@"; then
        echo "built $OUT/$name" >&2
    else
        echo "skipped $name: the build failed (missing libraries? see above)" >&2
    fi
}

build utk_faure "${COMMON[@]}" -DUTK_PEER_FAURE "$DRIVER" -o "$OUT/utk_faure"
build utk_niederreiter "${COMMON[@]}" -DUTK_PEER_NIEDERREITER "$DRIVER" -o "$OUT/utk_niederreiter"

# SOT: UTK's SOT_LIB is these five files of Paulin's code, linked with GSL; the sampler
# with OpenMP.
build utk_sot "${COMMON[@]}" -I"$SOT_SRC" -fopenmp -DUTK_PEER_SOT "$DRIVER" \
    "$SOT_SRC/Transport/NBallRadonManager.cpp" "$SOT_SRC/Tools/mapping.cpp" \
    "$SOT_SRC/Tools/my_utility.cpp" "$SOT_SRC/Math/myMath.cpp" "$SOT_SRC/Tools/iopointset.cpp" \
    -lgsl -lgslcblas -o "$OUT/utk_sot"

# PeriodicBNOT: header-only CGAL (5.x) with SuiteSparse's CHOLMOD and SPQR, as UTK links
# it (CGAL::CGAL SuiteSparse::AMD SuiteSparse::CHOLMOD SuiteSparse::SPQR).
build utk_periodic_bnot "${COMMON[@]}" -I/usr/include/suitesparse -I/usr/include/eigen3 \
    -DUTK_PEER_PERIODIC_BNOT "$DRIVER" -lspqr -lcholmod -lamd -lgmp -lmpfr \
    -o "$OUT/utk_periodic_bnot"
build utk_periodic_bnot_uniform "${COMMON[@]}" -I/usr/include/suitesparse -I/usr/include/eigen3 \
    -DUTK_PEER_PERIODIC_BNOT_UNIFORM "$DRIVER" -lspqr -lcholmod -lamd -lgmp -lmpfr \
    -o "$OUT/utk_periodic_bnot_uniform"

ls -l "$OUT"
