/* The dimensions [CLSAMP_DIM0, CLSAMP_DIM_END(d)) one work-item makes: all d of them, or,
 * with -DDIMS_PER_ITEM=k, chunk get_global_id(2) of k. The runtime splits dimensions only
 * on devices that stop long loops (runtime.loop_limit: Mesa's llvmpipe ends a work-item's
 * loops after 65535 iterations in all, silently); any split gives the same bits. */
#ifndef CLSAMP_DIMS_H
#define CLSAMP_DIMS_H

#ifdef DIMS_PER_ITEM
#define CLSAMP_DIM0 ((uint)get_global_id(2) * (uint)DIMS_PER_ITEM)
#define CLSAMP_DIM_END(d) min((uint)(d), CLSAMP_DIM0 + (uint)DIMS_PER_ITEM)
#else
#define CLSAMP_DIM0 0u
#define CLSAMP_DIM_END(d) (d)
#endif

#endif
