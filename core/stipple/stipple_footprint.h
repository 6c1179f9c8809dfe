/* The stipple renderer's owner pixels, shared by the block tests (stipple_owners.c) and the
 * strip of owners they read (stipple_strip.c): an owner's footprint in sequence space, a quad
 * whose corners come from the corner grid (or, off the grid, from the owner's own
 * extrapolation), and the strip of owners' limits and footprint boxes. The functions are
 * static inline: both files call them in their inner loops. Internal, never installed. */
#ifndef NPRFX_STIPPLE_FOOTPRINT_H
#define NPRFX_STIPPLE_FOOTPRINT_H

#include "internal_stipple.h"

typedef struct owner {
    const nprfx_stipple_params *p;
    const pixdata *d; /* for the corners off the grid, and emit()'s fallback */
    int x, y, id;
    double cu[4], cv[4]; /* corners TL, TR, BR, BL in sequence units */
    double sigma;        /* orientation of the map: sign of det J */
    double g, i_max;
    float radius; /* the disc radius where all stipples share it (uniform, multitone) */
} owner;

/* Corner of the owner towards (dx, dy) in {-1, 1}^2. Where the grid has it, the 2x2 pixels
 * around the corner share it bit for bit. At an object edge it is the mean of the same-object
 * pixels' extrapolations (the same for each of them); across a UV seam, the owner's own
 * extrapolation (there a stipple may be doubled or dropped). */
static inline void corner(const pixdata *d, const cgrid *g, const owner *o, int dx, int dy,
                          double *cu, double *cv)
{
    int xa = o->x + (dx < 0 ? -1 : 0), ya = o->y + (dy < 0 ? -1 : 0);
    int gx = xa + 1 - g->E.x0, gy = ya + 1 - g->E.y0;
    if (gx >= 0 && gx < g->gw && gy >= 0 && gy < g->gh && g->good[(size_t)gy * g->gw + gx]) {
        *cu = g->gu[(size_t)gy * g->gw + gx];
        *cv = g->gv[(size_t)gy * g->gw + gx];
        return;
    }
    const int qx[4] = {xa, xa + 1, xa, xa + 1}, qy[4] = {ya, ya, ya + 1, ya + 1};
    double su = 0, sv = 0;
    int n = 0;
    for (int i = 0; i < 4; i++) {
        if (!internal_usable_j(d, qx[i], qy[i], o->id)) continue;
        size_t k = pd_at(d, qx[i], qy[i]);
        const float *jc = d->jac + 4 * k;
        double ox = (xa + 0.5) - qx[i], oy = (ya + 0.5) - qy[i];
        su += d->su[k] + jc[0] * ox + jc[1] * oy;
        sv += d->sv[k] + jc[2] * ox + jc[3] * oy;
        n++;
    }
    double u = su / n, v = sv / n; /* n >= 1: the owner itself qualifies */
    size_t kp = pd_at(d, o->x, o->y);
    if (internal_stipple_off_corner(d, kp, 0.5 * dx, 0.5 * dy, u, v)) {
        const float *jp = d->jac + 4 * kp;
        u = d->su[kp] + jp[0] * (0.5 * dx) + jp[1] * (0.5 * dy);
        v = d->sv[kp] + jp[2] * (0.5 * dx) + jp[3] * (0.5 * dy);
    }
    *cu = u;
    *cv = v;
}

/* The owner (x, y) of object id, darkness gk and bound i_max (what the strip has of it). Reads
 * of the per-pixel data: only the derivatives (the orientation), and where the corner grid
 * lacks a corner, what corner() needs. */
static inline void owner_build(const sjob *j, const pixdata *d, const cgrid *g, double i_max,
                               float gk, int id, owner *o, int x, int y)
{
    const float *jc = d->jac + 4 * pd_at(d, x, y);
    o->p = j->p;
    o->d = d;
    o->x = x;
    o->y = y;
    o->id = id;
    o->g = gk;
    o->i_max = i_max;
    double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2];
    o->sigma = det > 0 ? 1.0 : -1.0;
    o->radius = j->radius;
    /* the corners straight from the grid where it has all four (what corner() returns) */
    size_t g0 = (size_t)(y - g->E.y0) * g->gw + (size_t)(x - g->E.x0), g1 = g0 + g->gw;
    if (g->good[g0] && g->good[g0 + 1] && g->good[g1] && g->good[g1 + 1]) {
        o->cu[0] = g->gu[g0], o->cu[1] = g->gu[g0 + 1], o->cu[2] = g->gu[g1 + 1];
        o->cu[3] = g->gu[g1];
        o->cv[0] = g->gv[g0], o->cv[1] = g->gv[g0 + 1], o->cv[2] = g->gv[g1 + 1];
        o->cv[3] = g->gv[g1];
        return;
    }
    corner(d, g, o, -1, -1, &o->cu[0], &o->cv[0]);
    corner(d, g, o, 1, -1, &o->cu[1], &o->cv[1]);
    corner(d, g, o, 1, 1, &o->cu[2], &o->cv[2]);
    corner(d, g, o, -1, 1, &o->cu[3], &o->cv[3]);
}

/* The owners of a row of blocks (BLOCK rows of E), CHUNK columns at a time (few enough for
 * them and the per-pixel data they come from to stay in the L1 cache while their blocks are
 * done), a row of `stride` in each array: limits (0: keeps nothing, also in the padding),
 * i_max, darkness and footprint boxes (empty where nothing is kept), so that a block's tests
 * read four owners of a row at once. */
#define CHUNK 64
typedef struct strip {
    int stride;
    int32_t *lim;
    double *imax, *bu0, *bv0, *bu1, *bv1;
    float *g; /* darkness */
} strip;

/* The box of a footprint's corners. */
static inline void quad_box(const double *cu, const double *cv, double *u0, double *v0, double *u1,
                            double *v1)
{
    double a0 = cu[0], a1 = cu[0], b0 = cv[0], b1 = cv[0];
    for (int q = 1; q < 4; q++) {
        a0 = cu[q] < a0 ? cu[q] : a0;
        a1 = cu[q] > a1 ? cu[q] : a1;
        b0 = cv[q] < b0 ? cv[q] : b0;
        b1 = cv[q] > b1 ? cv[q] : b1;
    }
    *u0 = a0, *v0 = b0, *u1 = a1, *v1 = b1;
}

static inline int lowest_bit(unsigned m)
{
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_ctz(m);
#else
    int i = 0;
    while (!(m & 1u))
        m >>= 1, i++;
    return i;
/* Owners are handled in blocks: one index query per block, for the union of the owners'
 * footprint boxes and the largest of their limits; each sample found is then tested against
 * every owner of the block whose box and limit admit it. That is the same per-pixel decision
 * as one query per pixel, at a fraction of the cost, and the result does not depend on where
 * the blocks fall (each block's stipples are sorted by owner, and the rows of blocks dealt out
 * by owner row). */
#define BLOCK 4

#endif
}

/* Owners are handled in blocks: one index query per block, for the union of the owners'
 * footprint boxes and the largest of their limits; each sample found is then tested against
 * every owner of the block whose box and limit admit it. That is the same per-pixel decision
 * as one query per pixel, at a fraction of the cost, and the result does not depend on where
 * the blocks fall (each block's stipples are sorted by owner, and the rows of blocks dealt out
 * by owner row). */
#define BLOCK 4

#endif
