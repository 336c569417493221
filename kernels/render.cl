/* The renderer: ray casting of spheres (optionally moving), planes and axis-aligned boxes,
 * shaded with ambient occlusion and a quad area light (shading model: clsamp/scene.py).
 *
 * Effects are compiled in only when the scene lists them (docs/design.md, "Rendering"):
 *   EFFECT_AA      pixel area sampling (2 dimensions), else pixel centres
 *   EFFECT_DOF     thin lens (2 dimensions), else a pinhole
 *   EFFECT_MB      motion blur: a time in the shutter interval (1 dimension), else time 0
 *   AO_RAYS=n      n ambient-occlusion rays (2 dimensions each), else unoccluded ambient
 *   HAS_LIGHT      a quad light: EFFECT_SOFT samples its area (2 dimensions), else its centre
 * in that order: the dimension offsets below are the only place that order is written.
 * SAMPLES_PHILOX makes the samples here (the `random` sampler's Philox doubles) instead
 * of reading them from the buffer the renderer filled.
 *
 * NumPy reference: clsamp.render.render_reference (float64, same steps).
 *
 * Ray math is float (fp32): one work-item renders one pixel, VW of its samples at a
 * time in explicit vector lanes (PoCL vectorizes explicit vector types, not loops across
 * work-items: docs/performance.md, "PoCL"). The per-pixel sum is double: each lane
 * group's radiance is summed in float (VW terms of at most a few units) and added to a
 * double accumulator, so the mean of any number of samples carries no growing rounding
 * error.
 */
#include "philox.h"

#ifndef VW
#define VW 8
#endif

#if VW == 1
typedef float vfloat;
typedef int vint;
typedef uint vuint;
typedef ulong vulong;
typedef double vdouble;
#define TO_ULONG convert_ulong
#define TO_UINT convert_uint
#define TO_DOUBLE convert_double
#define TO_FLOAT_RTZ convert_float_rtz
#define LANE_INDEX 0u
#define VLOAD(p) (*(p))
#define LANES 0.0f
#define HSUM(v) (v)
#elif VW == 4
typedef float4 vfloat;
typedef int4 vint;
typedef uint4 vuint;
typedef ulong4 vulong;
typedef double4 vdouble;
#define TO_ULONG convert_ulong4
#define TO_UINT convert_uint4
#define TO_DOUBLE convert_double4
#define TO_FLOAT_RTZ convert_float4_rtz
#define LANE_INDEX ((vuint)(0u, 1u, 2u, 3u))
#define VLOAD(p) vload4(0, p)
#define LANES ((vfloat)(0.0f, 1.0f, 2.0f, 3.0f))
#define HSUM(v) (((v).s0 + (v).s1) + ((v).s2 + (v).s3))
#elif VW == 8
typedef float8 vfloat;
typedef int8 vint;
typedef uint8 vuint;
#define LANE_INDEX ((vuint)(0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u))
#define VLOAD(p) vload8(0, p)
#define LANES ((vfloat)(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f))
#define HSUM(v) ((((v).s0 + (v).s1) + ((v).s2 + (v).s3)) + (((v).s4 + (v).s5) + ((v).s6 + (v).s7)))
#else
#error "VW must be 1, 4 or 8"
#endif

/* Comparisons give 1 (scalar) or -1 (vector) for true; select() reads both right, and
 * (m == 0) negates both right (~m would not for scalars). */
#define NOT(m) ((m) == 0)

/* Dimension offsets of one pixel sample, in the fixed order. */
#ifdef EFFECT_AA
#define DIM_PIXEL 0
#define END_PIXEL 2
#else
#define END_PIXEL 0
#endif
#ifdef EFFECT_DOF
#define DIM_LENS END_PIXEL
#define END_LENS (END_PIXEL + 2)
#else
#define END_LENS END_PIXEL
#endif
#ifdef EFFECT_MB
#define DIM_TIME END_LENS
#define END_TIME (END_LENS + 1)
#else
#define END_TIME END_LENS
#endif
#if defined(AO_RAYS) && AO_RAYS > 0
#define DIM_AO END_TIME
#define END_AO (END_TIME + 2 * AO_RAYS)
#else
#define END_AO END_TIME
#endif
#if defined(HAS_LIGHT) && defined(EFFECT_SOFT)
#define DIM_LIGHT END_AO
#define SAMPLE_DIMS (END_AO + 2)
#else
#define SAMPLE_DIMS END_AO
#endif

/* Where sample dimension `dim` of samples s .. s+VW-1 comes from: the buffer the
 * sampler filled, or (SAMPLES_PHILOX: the `random` sampler with all dimensions at once)
 * Philox draws made here, the same doubles `random_points` makes for realization
 * `pixel % block` under the seed of block `pixel / block`, rounded toward zero. */
#ifdef SAMPLES_PHILOX
#define LOAD(dim) drawn[dim]

/* The 64-bit products a * m of VW lanes: the low words returned, the high words in *hi.
 * With VW = 8 in ulong4 halves: no 512-bit vector (ulong8, double8) may reach a built-in
 * (docs/design.md, "Kernels and the runtime"). */
#if VW == 8
inline vuint mul_wide(const vuint a, const ulong m, vuint *hi)
{
    const ulong4 p = convert_ulong4(a.lo) * m;
    const ulong4 q = convert_ulong4(a.hi) * m;
    *hi = (vuint)(convert_uint4(p >> 32), convert_uint4(q >> 32));
    return (vuint)(convert_uint4(p), convert_uint4(q));
}
#else
inline vuint mul_wide(const vuint a, const ulong m, vuint *hi)
{
    const vulong p = TO_ULONG(a) * m;
    *hi = TO_UINT(p >> 32);
    return TO_UINT(p);
}
#endif

/* philox4x32_10 of philox.h on VW counters at once (the index differs per lane): the
 * same words, computed in vector lanes (PoCL does not vectorize a loop over lanes). */
inline void philox_lanes(const uint2 key, const uint stream, const uint realization,
                         const vuint index, const uint pair, vuint *w0, vuint *w1, vuint *w2,
                         vuint *w3)
{
    vuint c0 = index, c1 = (vuint)realization, c2 = (vuint)pair, c3 = (vuint)stream;
    CLSAMP_PHILOX_ROUNDS(vuint, mul_wide, c0, c1, c2, c3, key);
    *w0 = c0;
    *w1 = c1;
    *w2 = c2;
    *w3 = c3;
}

/* clsamp_unit (53 bits) rounded toward zero to float, lane by lane */
#if VW == 8
inline vfloat unit_lanes(const vuint hi, const vuint lo)
{
    return (vfloat)(convert_float4_rtz(CLSAMP_UNIT53(convert_double4, hi.lo, lo.lo)),
                    convert_float4_rtz(CLSAMP_UNIT53(convert_double4, hi.hi, lo.hi)));
}
#else
inline vfloat unit_lanes(const vuint hi, const vuint lo)
{
    return TO_FLOAT_RTZ(CLSAMP_UNIT53(TO_DOUBLE, hi, lo));
}
#endif
#else
#define LOAD(dim) VLOAD(mine + (dim) * spp_pad + s)
#endif

#define PI_F 3.14159265358979f
#define SPHERE_STRIDE 8   /* cx cy cz r vx vy vz albedo */
#define PLANE_STRIDE 7    /* px py pz nx ny nz albedo */
#define BOX_STRIDE 7      /* min xyz, max xyz, albedo */

typedef struct {
    vfloat x, y, z;
} vec3;

inline vec3 v3(vfloat x, vfloat y, vfloat z)
{
    vec3 r = {x, y, z};
    return r;
}

inline vfloat dot3(vec3 a, vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

inline vec3 normalize3(vec3 a)
{
    const vfloat s = rsqrt(dot3(a, a));
    return v3(a.x * s, a.y * s, a.z * s);
}

/* Shirley and Chiu's concentric map of the square to the disk (pbrt's
 * SampleUniformDiskConcentric): keeps strata compact, so stratified points stay
 * stratified on the disk and on the hemisphere above it. */
inline void concentric_disk(vfloat u1, vfloat u2, vfloat *x, vfloat *y)
{
    const vfloat a = 2.0f * u1 - 1.0f;
    const vfloat b = 2.0f * u2 - 1.0f;
    const vint wide = fabs(a) > fabs(b);
    const vfloat r = select(b, a, wide);
    const vfloat num = select(a, b, wide);
    const vfloat den = select(select(b, (vfloat)1.0f, b == 0.0f), a, wide);
    const vfloat phi = select(PI_F * 0.5f - PI_F * 0.25f * (num / den), PI_F * 0.25f * (num / den), wide);
    const vint zero = (a == 0.0f) & (b == 0.0f);
    *x = select(r * cos(phi), (vfloat)0.0f, zero);
    *y = select(r * sin(phi), (vfloat)0.0f, zero);
}

/* The shapes' intersections, shared by nearest_hit and occluded so that a shadow ray and a
 * camera ray can never disagree about a surface. Each returns the lanes that hit in
 * (eps, inf) and writes the ray parameter t of the hit. */

/* Sphere s (centre moving with velocity s[4..6]); *oc is the origin relative to the
 * centre at `time` (the normal at the hit is (oc + t d) / radius). */
inline vint sphere_hit(vec3 o, vec3 d, vfloat time, const float eps, __global const float *s,
                       vfloat *t, vec3 *oc)
{
    const vfloat ox = o.x - (s[0] + s[4] * time), oy = o.y - (s[1] + s[5] * time);
    const vfloat oz = o.z - (s[2] + s[6] * time);
    const vfloat b = ox * d.x + oy * d.y + oz * d.z;
    const vfloat c = ox * ox + oy * oy + oz * oz - s[3] * s[3];
    const vfloat disc = b * b - c;
    const vfloat root = sqrt(fmax(disc, 0.0f));
    const vfloat t0 = -b - root;
    *t = select(-b + root, t0, t0 > eps);
    *oc = v3(ox, oy, oz);
    return (disc >= 0.0f) & (*t > eps);
}

/* Plane through p[0..2] with normal p[3..5]. */
inline vint plane_hit(vec3 o, vec3 d, const float eps, __global const float *p, vfloat *t)
{
    const vfloat den = d.x * p[3] + d.y * p[4] + d.z * p[5];
    const vfloat num = (p[0] - o.x) * p[3] + (p[1] - o.y) * p[4] + (p[2] - o.z) * p[5];
    *t = num / den;
    return (den != 0.0f) & (*t > eps);
}

/* Axis-aligned box q[0..2]..q[3..5] (slabs); *lx, *ly are the entry parameters of the x and
 * y slabs, which tell the face that was hit. */
inline vint box_hit(vec3 o, vec3 d, const float eps, __global const float *q, vfloat *t,
                    vfloat *lx, vfloat *ly)
{
    const vfloat ix = 1.0f / d.x, iy = 1.0f / d.y, iz = 1.0f / d.z;
    const vfloat ax = (q[0] - o.x) * ix, bx = (q[3] - o.x) * ix;
    const vfloat ay = (q[1] - o.y) * iy, by = (q[4] - o.y) * iy;
    const vfloat az = (q[2] - o.z) * iz, bz = (q[5] - o.z) * iz;
    *lx = fmin(ax, bx);
    *ly = fmin(ay, by);
    const vfloat tnear = fmax(fmax(*lx, *ly), fmin(az, bz));
    const vfloat tfar = fmin(fmin(fmax(ax, bx), fmax(ay, by)), fmax(az, bz));
    *t = tnear;
    return (tnear <= tfar) & (tnear > eps);
}

/* Nearest hit along o + t d, t in (eps, tmax): returns t (tmax when nothing is hit) and
 * the shading normal (facing the ray) and albedo of the hit. */
inline vfloat nearest_hit(vec3 o, vec3 d, vfloat time, vfloat tmax, const float eps,
                          __global const float *spheres, const uint nspheres,
                          __global const float *planes, const uint nplanes,
                          __global const float *boxes, const uint nboxes,
                          vec3 *n, vfloat *albedo)
{
    vfloat best = tmax;
    vfloat nx = 0.0f, ny = 0.0f, nz = 0.0f, alb = 0.0f;
    vfloat t, lx, ly;
    vec3 oc;
    for (uint k = 0; k < nspheres; ++k) {
        __global const float *s = spheres + k * SPHERE_STRIDE;
        const vint hit = sphere_hit(o, d, time, eps, s, &t, &oc) & (t < best);
        best = select(best, t, hit);
        const vfloat inv = 1.0f / s[3];
        nx = select(nx, (oc.x + t * d.x) * inv, hit);
        ny = select(ny, (oc.y + t * d.y) * inv, hit);
        nz = select(nz, (oc.z + t * d.z) * inv, hit);
        alb = select(alb, (vfloat)s[7], hit);
    }
    for (uint k = 0; k < nplanes; ++k) {
        __global const float *p = planes + k * PLANE_STRIDE;
        const vint hit = plane_hit(o, d, eps, p, &t) & (t < best);
        best = select(best, t, hit);
        nx = select(nx, (vfloat)p[3], hit);
        ny = select(ny, (vfloat)p[4], hit);
        nz = select(nz, (vfloat)p[5], hit);
        alb = select(alb, (vfloat)p[6], hit);
    }
    for (uint k = 0; k < nboxes; ++k) {
        __global const float *q = boxes + k * BOX_STRIDE;
        const vint hit = box_hit(o, d, eps, q, &t, &lx, &ly) & (t < best);
        best = select(best, t, hit);
        const vint onx = t == lx, ony = NOT(onx) & (t == ly);
        const vint onz = NOT(onx) & NOT(ony);
        nx = select(nx, select((vfloat)0.0f, (vfloat)1.0f, onx), hit);
        ny = select(ny, select((vfloat)0.0f, (vfloat)1.0f, ony), hit);
        nz = select(nz, select((vfloat)0.0f, (vfloat)1.0f, onz), hit);
        alb = select(alb, (vfloat)q[6], hit);
    }
    /* Shading normals face the incoming ray (surfaces are two-sided). */
    const vfloat flip = select((vfloat)1.0f, (vfloat)-1.0f, nx * d.x + ny * d.y + nz * d.z > 0.0f);
    *n = v3(nx * flip, ny * flip, nz * flip);
    *albedo = alb;
    return best;
}

/* Whether anything lies along o + t d for t in (eps, tmax). */
inline vint occluded(vec3 o, vec3 d, vfloat time, vfloat tmax, const float eps,
                     __global const float *spheres, const uint nspheres,
                     __global const float *planes, const uint nplanes,
                     __global const float *boxes, const uint nboxes)
{
    vint blocked = (vint)0;
    vfloat t, lx, ly;
    vec3 oc;
    for (uint k = 0; k < nspheres; ++k)
        blocked |= sphere_hit(o, d, time, eps, spheres + k * SPHERE_STRIDE, &t, &oc) & (t < tmax);
    for (uint k = 0; k < nplanes; ++k)
        blocked |= plane_hit(o, d, eps, planes + k * PLANE_STRIDE, &t) & (t < tmax);
    for (uint k = 0; k < nboxes; ++k)
        blocked |= box_hit(o, d, eps, boxes + k * BOX_STRIDE, &t, &lx, &ly) & (t < tmax);
    return blocked;
}

/* Grid: one work-item per pixel of the tile [pixel0, pixel0 + npix).
 * samples: (npix, SAMPLE_DIMS, spp_pad) float in [0, 1); spp_pad = spp rounded up to VW
 *   (unused with SAMPLES_PHILOX, which reads the seed of each block of `block` pixels
 *   from block_keys as (low, high) words instead).
 * camera: eye(3) forward(3) right(3) up(3) tan(fov/2) aperture focus shutter0 shutter1
 *   half-width half-height (of the screen window at distance 1: tan(fov/2) times the
 *   aspect ratio along the longer side, as pbrt's film).
 * shading: ambient background ao_distance epsilon.
 * light: corner(3) edge1(3) edge2(3) emission. */
__kernel void render_pixels(__global float *out, __global const float *samples,
                            const uint pixel0, const uint npix, const uint width,
                            const uint height,
                            const uint spp, const uint spp_pad,
                            __global const float *camera, __global const float *shading,
                            __global const float *spheres, const uint nspheres,
                            __global const float *planes, const uint nplanes,
                            __global const float *boxes, const uint nboxes,
                            __global const float *light, __global const uint *block_keys,
                            const uint block)
{
    const uint i = get_global_id(0);
    if (i >= npix)
        return;
    const uint pixel = pixel0 + i;
    const float col = (float)(pixel % width), row = (float)(pixel / width);
    const float inv_w = 1.0f / (float)width, inv_h = 1.0f / (float)height;
    const float eps = shading[3];
    __global const float *mine = samples + (size_t)i * SAMPLE_DIMS * spp_pad;
    double sum = 0.0;
#ifdef SAMPLES_PHILOX
    const uint2 key = vload2(pixel / block, block_keys);
    const uint realization = pixel % block;
    vfloat drawn[SAMPLE_DIMS > 0 ? SAMPLE_DIMS : 1];
    (void)mine;
#else
    (void)block_keys;
    (void)block;
#endif
    for (uint s = 0; s < spp; s += VW) {
#ifdef SAMPLES_PHILOX
#pragma unroll
        for (uint pair = 0; 2 * pair < SAMPLE_DIMS; ++pair) {
            vuint w0, w1, w2, w3;
            philox_lanes(key, SAMPLES_PHILOX_STREAM, realization, s + LANE_INDEX, pair, &w0, &w1,
                         &w2, &w3);
            drawn[2 * pair] = unit_lanes(w0, w1);
            if (2 * pair + 1 < SAMPLE_DIMS)
                drawn[2 * pair + 1] = unit_lanes(w2, w3);
        }
#endif
#ifdef EFFECT_AA
        const vfloat px = LOAD(DIM_PIXEL + 0);
        const vfloat py = LOAD(DIM_PIXEL + 1);
#else
        const vfloat px = 0.5f, py = 0.5f;
#endif
        const vfloat sx = (2.0f * (col + px) * inv_w - 1.0f) * camera[17];
        const vfloat sy = (1.0f - 2.0f * (row + py) * inv_h) * camera[18];
        /* direction through the pixel, unnormalized: forward + sx right + sy up */
        vec3 d = v3(camera[3] + sx * camera[6] + sy * camera[9],
                    camera[4] + sx * camera[7] + sy * camera[10],
                    camera[5] + sx * camera[8] + sy * camera[11]);
        vec3 o = v3((vfloat)camera[0], (vfloat)camera[1], (vfloat)camera[2]);
#ifdef EFFECT_DOF
        {
            vfloat lx, ly;
            concentric_disk(LOAD(DIM_LENS + 0),
                            LOAD(DIM_LENS + 1), &lx, &ly);
            lx *= camera[13];
            ly *= camera[13];
            /* the point this pixel sees in focus: on the plane at the focus distance
             * along forward (d . forward = 1) */
            const vec3 f = v3(o.x + d.x * camera[14], o.y + d.y * camera[14], o.z + d.z * camera[14]);
            o = v3(o.x + lx * camera[6] + ly * camera[9], o.y + lx * camera[7] + ly * camera[10],
                   o.z + lx * camera[8] + ly * camera[11]);
            d = v3(f.x - o.x, f.y - o.y, f.z - o.z);
        }
#endif
        d = normalize3(d);
#ifdef EFFECT_MB
        const vfloat time = camera[15] + (camera[16] - camera[15]) * LOAD(DIM_TIME);
#else
        const vfloat time = 0.0f;
#endif
        vec3 n;
        vfloat albedo;
        const vfloat far = INFINITY;
        const vfloat t = nearest_hit(o, d, time, far, 0.0f, spheres, nspheres, planes, nplanes,
                                     boxes, nboxes, &n, &albedo);
        const vint hit = t < far;
        /* secondary rays leave from just above the surface, on the side it is seen from */
        const vec3 x = v3(o.x + t * d.x + eps * n.x, o.y + t * d.y + eps * n.y,
                          o.z + t * d.z + eps * n.z);
#if defined(AO_RAYS) && AO_RAYS > 0
        /* Duff et al. 2017: an orthonormal basis (b1, b2, n) without branches */
        const vfloat sign = copysign((vfloat)1.0f, n.z);
        const vfloat ia = -1.0f / (sign + n.z);
        const vfloat bb = n.x * n.y * ia;
        const vec3 b1 = v3(1.0f + sign * n.x * n.x * ia, sign * bb, -sign * n.x);
        const vec3 b2 = v3(bb, sign + n.y * n.y * ia, -n.y);
        vfloat open = 0.0f;
        for (uint a = 0; a < AO_RAYS; ++a) {
            /* Malley's method: cosine-weighted directions are disk points lifted to
             * the hemisphere */
            vfloat hx, hy;
            concentric_disk(LOAD(DIM_AO + 2 * a),
                            LOAD(DIM_AO + 2 * a + 1), &hx, &hy);
            const vfloat hz = sqrt(fmax(1.0f - hx * hx - hy * hy, 0.0f));
            const vec3 w = v3(hx * b1.x + hy * b2.x + hz * n.x, hx * b1.y + hy * b2.y + hz * n.y,
                              hx * b1.z + hy * b2.z + hz * n.z);
            const vint blocked = occluded(x, w, time, (vfloat)shading[2], 0.0f, spheres, nspheres,
                                          planes, nplanes, boxes, nboxes);
            open += select((vfloat)1.0f, (vfloat)0.0f, blocked);
        }
        const vfloat ambient = shading[0] * open * (1.0f / (float)AO_RAYS);
#else
        const vfloat ambient = shading[0];
#endif
#ifdef HAS_LIGHT
        const vec3 e1 = v3((vfloat)light[3], (vfloat)light[4], (vfloat)light[5]);
        const vec3 e2 = v3((vfloat)light[6], (vfloat)light[7], (vfloat)light[8]);
#ifdef EFFECT_SOFT
        const vfloat lu = LOAD(DIM_LIGHT + 0);
        const vfloat lv = LOAD(DIM_LIGHT + 1);
#else
        const vfloat lu = 0.5f, lv = 0.5f;
#endif
        const vec3 q = v3(light[0] + lu * e1.x + lv * e2.x, light[1] + lu * e1.y + lv * e2.y,
                          light[2] + lu * e1.z + lv * e2.z);
        vec3 w = v3(q.x - x.x, q.y - x.y, q.z - x.z);
        const vfloat dist2 = dot3(w, w);
        const vfloat dist = sqrt(dist2);
        w = v3(w.x / dist, w.y / dist, w.z / dist);
        /* light normal e1 x e2, emitting to its side only; area |e1 x e2| */
        const vfloat lnx = e1.y * e2.z - e1.z * e2.y, lny = e1.z * e2.x - e1.x * e2.z;
        const vfloat lnz = e1.x * e2.y - e1.y * e2.x;
        const vfloat cos_light = -(lnx * w.x + lny * w.y + lnz * w.z);  /* times the area */
        const vfloat cos_surf = dot3(n, w);
        const vint lit = (cos_light > 0.0f) & (cos_surf > 0.0f);
        const vint shadow = occluded(x, w, time, dist, 0.0f, spheres, nspheres, planes, nplanes,
                                     boxes, nboxes);
        const vfloat direct = select((vfloat)0.0f, light[9] * cos_light * cos_surf / dist2 * (1.0f / PI_F),
                                     lit & NOT(shadow));
#else
        const vfloat direct = 0.0f;
#endif
        vfloat radiance = select((vfloat)shading[1], albedo * (ambient + direct), hit);
        /* lanes past the last sample (spp not a multiple of VW) count nothing */
        radiance = select((vfloat)0.0f, radiance, LANES < (float)(spp - s));
        sum += (double)HSUM(radiance);
    }
    out[i] = (float)(sum / (double)spp);
}
