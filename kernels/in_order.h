/* IN_ORDER, written before a loop that accumulates in floating point, keeps the sum in
 * the loop's order: Intel's CPU compiler otherwise vectorizes such a loop where a work-item
 * runs alone (a work-group's tail), summing in four partial sums -- other bits than the
 * NumPy twin's, which adds in order (tests/test_devices.py). Other compilers read the same
 * hint and lose nothing: they vectorize across work-items, not along these loops. */
#ifndef CLSAMP_IN_ORDER_H
#define CLSAMP_IN_ORDER_H

#define IN_ORDER _Pragma("clang loop vectorize(disable)")

#endif
