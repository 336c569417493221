/* Inline forms of OpenCL built-ins that PoCL 3.0 calls as functions, for code that runs
 * once a point or more (the call, its argument moves and the spills around it cost more
 * than the work): min, max, any, select of 0 and 1, and the vload/vstore of a few words, which plain element
 * accesses replace and the compiler merges into vector moves (docs/performance.md, "PoCL's
 * built-ins as calls"). Other devices compile both forms to the same code.
 */
#ifndef CLSAMP_INLINE_BUILTINS_H
#define CLSAMP_INLINE_BUILTINS_H

#include "f64bits.h"

CLSAMP_ALWAYS_INLINE uint clsamp_min(uint a, uint b) { return a < b ? a : b; }
CLSAMP_ALWAYS_INLINE uint clsamp_max(uint a, uint b) { return a > b ? a : b; }

/* any(x) of a comparison's result (lanes 0 or -1) */
CLSAMP_ALWAYS_INLINE bool clsamp_any4(int4 x) { return ((x.s0 | x.s1) | (x.s2 | x.s3)) < 0; }
CLSAMP_ALWAYS_INLINE bool clsamp_any4l(long4 x) { return ((x.s0 | x.s1) | (x.s2 | x.s3)) < 0; }

#if CLSAMP_FP64
/* select((double4)(0.0), (double4)(1.0), holds): 1.0 where a comparison holds (lane -1) */
CLSAMP_ALWAYS_INLINE double4 clsamp_indicator4(long4 holds) { return holds ? (double4)(1.0) : (double4)(0.0); }
#endif

#endif
