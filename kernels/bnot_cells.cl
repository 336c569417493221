/* The exact power cells of sites on the unit torus, for bnot's cells="exact"
 * (clsamp/samplers/bnot_cells.py). NumPy twin: power_cells_reference there, the same bits:
 * exactly rounded double operations (+, -, *, /, sqrt) in the same order, no contraction.
 *
 * Site i's power cell is {y : |y - x_i|^2 - w_i <= |y - x_j|^2 - w_j for every other site
 * j and image}. In coordinates z = y - x_i it starts as the square [-1/2, 1/2]^2 (the
 * bisectors with i's own images, whose weight is w_i) and is clipped, one candidate image
 * d = x_j + shift - x_i at a time, by the half-plane z . d <= h, h = (|d|^2 + w_i - w_j) / 2
 * (Sutherland-Hodgman on a convex polygon), unless h > 0 and h^2 >= r^2 |d|^2, r the
 * farthest vertex from x_i so far (then no vertex can lie beyond the line).
 *
 * The candidates are the sites of the (2 R + 1)^2 cells of a G x G grid around i's cell
 * (the points sorted by cell as clsamp.geometry.cells.sorted_by_cell sorts them: start
 * holds each cell's first sorted index), ring by ring (the cells at Chebyshev distance
 * 0, 1, .., R), within a ring the first axis outer, then in sorted order; with G == 1
 * every other site, in the (2 R + 1)^2 images of the torus, by the same rings. They come
 * in two passes of that order: first those with |d|^2 < near (about the natural
 * neighbours, which leave the cell nearly final), then the others, most of which the
 * farthest vertex then shows to miss the cell.
 *
 * A site j at distance d cuts the cell only if d^2 - 2 r d + w_i - w_j < 0, r the distance
 * of the cell's farthest vertex. A site no candidate lies at least reach from x_i, and one
 * beyond the ring R + 1 of grid cells at least far. So the cell is certified (status 0)
 * when r < reach, reach^2 - 2 r reach + w_i - wring >= 0 (wring the largest weight in the
 * cells of ring R + 1, from cellmax, each grid cell's largest weight) and
 * far^2 - 2 r far + w_i - wmax >= 0 (wmax the largest weight); with G == 1 (far = reach)
 * the last alone. Otherwise status 1 (the host takes a wider stencil).
 * Status 2: more than VMAX vertices or LMAX cutting lines.
 *
 * The rows are the sites' own order (order: sorted index -> site). Row order[i] of out
 * (n, 4 + VMAX): the area A, the centroid's offset from x_i (cx, cy), the second moment
 * about x_i (the integral of |z|^2 over the cell), then coef; row order[i] of iout
 * (n, 1 + VMAX): the status, then nbr. Each edge of the cell on the boundary with a site
 * j gives, at slot e of nbr and coef, order[j] and |edge| / (2 |d|), the boundary's move
 * per unit of w_j (-dA_i/dw_j); the other slots hold -1 and 0. An empty cell has A = 0.
 *
 * Build options: VMAX, LMAX. Launch: one work-item a sorted site of todo (the sites to
 * clip, m of them: every one, or those a narrower stencil left uncertified), grid (m,).
 */
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF

#if !defined(VMAX) || !defined(LMAX)
#error "bnot_cells.cl needs VMAX and LMAX (clsamp.samplers.bnot_cells)"
#endif

#include "in_order.h"

__kernel void bnot_cells(__global const double *sites, __global const double *w,
                         __global const uint *start, __global const uint *order,
                         __global const uint *todo, const uint m, const int G, const int R,
                         const double near, const double reach, const double far,
                         const double wmax,
                         __global const double *cellmax, __global double *out,
                         __global int *iout)
{
    const uint g = get_global_id(0);
    if (g >= m)
        return;
    const uint i = todo[g];
    const size_t row = order[i];
    const double xi = sites[2 * i], yi = sites[2 * i + 1], wi = w[i];
    double px[VMAX], py[VMAX], qx[VMAX], qy[VMAX], s[VMAX];
    int lab[VMAX], qlab[VMAX];
    int tj[LMAX];
    double tn[LMAX];
    px[0] = -0.5; py[0] = -0.5; px[1] = 0.5; py[1] = -0.5;
    px[2] = 0.5; py[2] = 0.5; px[3] = -0.5; py[3] = 0.5;
    lab[0] = lab[1] = lab[2] = lab[3] = -1;
    int cnt = 4, lines = 0, st = 0;
    double r2 = 0.5;        /* the largest |z|^2 of a vertex */
    int cx = 0, cy = 0;
    if (G > 1) {
        cx = (int)(xi * (double)G);
        cy = (int)(yi * (double)G);
        cx = cx < G - 1 ? cx : G - 1;
        cy = cy < G - 1 ? cy : G - 1;
    }
    for (int pass = 0; pass < 2 && cnt > 0 && st == 0; ++pass)
    for (int ring = 0; ring <= R && cnt > 0 && st == 0; ++ring)
    for (int ox = -ring; ox <= ring && cnt > 0 && st == 0; ++ox) {
        for (int oy = -ring; oy <= ring && cnt > 0 && st == 0; ++oy) {
            if (ox != -ring && ox != ring && oy != -ring && oy != ring)
                continue;
            int gx = cx + ox, gy = cy + oy, shx, shy;
            if (G == 1) {
                shx = ox; shy = oy; gx = 0; gy = 0;
            } else {
                shx = gx < 0 ? -1 : gx >= G ? 1 : 0;
                shy = gy < 0 ? -1 : gy >= G ? 1 : 0;
                gx -= shx * G;
                gy -= shy * G;
            }
            const uint cell = (uint)(gx * G + gy);
            for (uint j = start[cell]; j < start[cell + 1] && cnt > 0; ++j) {
                if (j == i)
                    continue;
                const double dx = (sites[2 * j] + (double)shx) - xi;
                const double dy = (sites[2 * j + 1] + (double)shy) - yi;
                const double dd = dx * dx + dy * dy;
                if ((dd < near) != (pass == 0))
                    continue;       /* the near sites in the first pass, the rest after */
                const double h = 0.5 * ((dd + wi) - w[j]);
                if (h > 0.0 && h * h >= r2 * dd)
                    continue;       /* the cell lies within |z| <= sqrt(r2): no cut */
                int out_count = 0;
                for (int a = 0; a < cnt; ++a) {
                    s[a] = (px[a] * dx + py[a] * dy) - h;
                    out_count += s[a] > 0.0;
                }
                if (out_count == 0)
                    continue;
                if (lines == LMAX) {
                    st = 2;
                    break;
                }
                int m = 0;
                for (int a = 0; a < cnt; ++a) {
                    const int b = a + 1 < cnt ? a + 1 : 0;
                    const int ina = s[a] <= 0.0, inb = s[b] <= 0.0;
                    if (m + ina + (ina != inb) > VMAX) {
                        st = 2;
                        break;
                    }
                    if (ina) {
                        qx[m] = px[a]; qy[m] = py[a]; qlab[m] = lab[a];
                        ++m;
                    }
                    if (ina != inb) {
                        const double t = s[a] / (s[a] - s[b]);
                        qx[m] = px[a] + t * (px[b] - px[a]);
                        qy[m] = py[a] + t * (py[b] - py[a]);
                        qlab[m] = ina ? lines : lab[a];
                        ++m;
                    }
                }
                if (st != 0)
                    break;
                tj[lines] = (int)j;
                tn[lines] = sqrt(dx * dx + dy * dy);
                ++lines;
                cnt = m;
                r2 = 0.0;
                for (int a = 0; a < cnt; ++a) {
                    px[a] = qx[a]; py[a] = qy[a]; lab[a] = qlab[a];
                    const double ra = px[a] * px[a] + py[a] * py[a];
                    r2 = ra > r2 ? ra : r2;
                }
            }
        }
    }
    double A2 = 0.0, mx = 0.0, my = 0.0, I = 0.0;
    IN_ORDER
    for (int a = 0; a < cnt; ++a) {
        const int b = a + 1 < cnt ? a + 1 : 0;
        const double cr = px[a] * py[b] - py[a] * px[b];
        A2 += cr;
        mx += cr * (px[a] + px[b]);
        my += cr * (py[a] + py[b]);
        I += cr * (((px[a] * px[a] + py[a] * py[a]) + (px[b] * px[b] + py[b] * py[b]))
                   + (px[a] * px[b] + py[a] * py[b]));
    }
    __global double *coef = out + row * (4 + VMAX) + 4;
    __global int *nbr = iout + row * (1 + VMAX) + 1;
    int e = 0;
    for (int a = 0; a < cnt; ++a) {
        if (lab[a] < 0)
            continue;
        const int b = a + 1 < cnt ? a + 1 : 0;
        const double ex = px[b] - px[a], ey = py[b] - py[a];
        nbr[e] = (int)order[tj[lab[a]]];
        coef[e] = sqrt(ex * ex + ey * ey) / (2.0 * tn[lab[a]]);
        ++e;
    }
    for (; e < VMAX; ++e) {
        nbr[e] = -1;
        coef[e] = 0.0;
    }
    if (st == 0) {
        double wring = wmax;
        if (G > 1) {
            const int k = R + 1;
            wring = -INFINITY;
            for (int ox = -k; ox <= k; ++ox)
            for (int oy = -k; oy <= k; ++oy) {
                if (ox != -k && ox != k && oy != -k && oy != k)
                    continue;
                const int gx = ((cx + ox) % G + G) % G, gy = ((cy + oy) % G + G) % G;
                const double c = cellmax[gx * G + gy];
                wring = c > wring ? c : wring;
            }
        }
        const double r = sqrt(r2);
        st = (r < reach && (reach * reach - 2.0 * r * reach) + (wi - wring) >= 0.0
              && (far * far - 2.0 * r * far) + (wi - wmax) >= 0.0) ? 0 : 1;
    }
    const double area = 0.5 * A2;
    __global double *moments = out + row * (4 + VMAX);
    moments[0] = area;
    moments[1] = A2 > 0.0 ? mx / (3.0 * A2) : 0.0;
    moments[2] = A2 > 0.0 ? my / (3.0 * A2) : 0.0;
    moments[3] = I / 12.0;
    iout[row * (1 + VMAX)] = st;
}
