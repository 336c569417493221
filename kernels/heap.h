/* HEAP_SIFT(name, first) defines name(key, idx, size, at): restores the binary heap of
 * (key, idx) pairs below entry at (the heap's first `size` entries), where the root is
 * the pair that first(ka, ia, kb, ib) puts before every other. Sliced optimal transport's
 * heapsort (the largest pair first) is this. */
#ifndef CLSAMP_HEAP_H
#define CLSAMP_HEAP_H

#define HEAP_SIFT(name, first)                                                             \
    static inline void name(__global double *key, __global uint *idx, const uint size,    \
                            uint at)                                                        \
    {                                                                                       \
        const double k = key[at];                                                           \
        const uint i = idx[at];                                                             \
        for (;;) {                                                                          \
            uint child = 2 * at + 1;                                                        \
            if (child >= size)                                                              \
                break;                                                                      \
            if (child + 1 < size && first(key[child + 1], idx[child + 1], key[child],      \
                                          idx[child]))                                      \
                child += 1;                                                                 \
            if (!first(key[child], idx[child], k, i))                                       \
                break;                                                                      \
            key[at] = key[child];                                                           \
            idx[at] = idx[child];                                                           \
            at = child;                                                                     \
        }                                                                                   \
        key[at] = k;                                                                        \
        idx[at] = i;                                                                        \
    }

#endif
