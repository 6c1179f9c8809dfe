/* Emission: per block, per surface patch and level of the anchor-space cell hierarchy, the
 * cells the patch's footprint (and, 3D, its slab) touches, one hashed point per cell, the pixel
 * that owns it (nearest centre under the pixels' own linearisations, a jump-and-descend search
 * over the block and its ring), its level weight and slab test on the surface interpolated at
 * the point, and the kernel it becomes. The body is instantiated for the scalar path and, on
 * x86-64, for AVX2 and AVX-512. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_gabor.h"
#include "base/internal_vmath.h"
#include "nprfx/rng.h"

#define MAX_CELLS 65536 /* per block, id and level: beyond, the footprint is degenerate */
#define OWNER_STEPS 8
/* 3D slab: squared weight 1 out to SLAB_IN c from the surface, then s^2 with s falling linearly
 * to 0 at SLAB_OUT c (so a point's amplitude changes linearly as it nears the edge); the
 * integral across the slab stays c: SLAB_IN = 1/2 - SLAB_SOFT/3, SLAB_OUT = SLAB_IN + SLAB_SOFT */
#define SLAB_SOFT 0.1
#define SLAB_IN (0.5 - SLAB_SOFT / 3.0)
#define SLAB_OUT (SLAB_IN + SLAB_SOFT)

/* A block's points go after those of the worker's blocks before it, in its current chunk; one
 * that outgrows the chunk's room moves to a new chunk (at least twice its points). */
static void block_begin(gblock *b, emit_scratch *scr)
{
    gchunk *c = *scr->chunks;
    b->n = 0;
    b->p = c ? c->p + c->n : NULL;
    b->cap = c ? c->cap - c->n : 0;
}

static int block_push(gblock *b, emit_scratch *scr, const gpoint *pt)
{
    if (b->n == b->cap) {
        int cap = 2 * b->n > CHUNK_POINTS ? 2 * b->n : CHUNK_POINTS;
        gchunk *c = malloc(sizeof(gchunk) + sizeof(gpoint) * (size_t)cap);
        if (!c) return 0;
        c->n = 0;
        c->cap = cap;
        c->next = *scr->chunks;
        *scr->chunks = c;
        if (b->n) memcpy(c->p, b->p, sizeof(gpoint) * (size_t)b->n);
        b->p = c->p;
        b->cap = cap;
    }
    b->p[b->n++] = *pt;
    return 1;
}

static void block_end(gblock *b, emit_scratch *scr)
{
    if (b->n) (*scr->chunks)->n += b->n;
    b->cap = b->n;
    if (!b->n) b->p = NULL;
}

static int in_block(int q)
{
    int i = q % PWS, j = q / PWS;
    return i >= 1 && i <= BLOCK && j >= 1 && j <= BLOCK;
}

/* Offset of anchor point a from pixel p's centre under p's own linearisation, in pixels. */
GABOR_BODY double own_offset(const gpixels *X, int p, const double *a, double *ux, double *uy)
{
    double d[3] = {a[0] - X->A[0][p], a[1] - X->A[1][p], a[2] - X->A[2][p]};
    *ux = X->P[0][p] * d[0] + X->P[1][p] * d[1] + X->P[2][p] * d[2];
    *uy = X->P[3][p] * d[0] + X->P[4][p] * d[1] + X->P[5][p] * d[2];
    double ax = fabs(*ux), ay = fabs(*uy);
    return ax > ay ? ax : ay;
}

/* The owner of anchor point a, if it is a pixel of this block (index in the PW x PW grid), else
 * -1. Ownership: among the pixels of the point's object, the owner is the one in whose own
 * linearisation the point lies nearest its centre (own_offset, L-inf; ties to the first in
 * raster order). Where neighbouring pixels' linearisations disagree (curved surfaces, points
 * off the surface in a 3D slab) a point near a border would land in neither square or in both;
 * this rule gives it exactly one owner, and every block that meets the point finds the same one
 * (the ring of pixels around the block is known too). The search starts at the reference
 * pixel of a patch and jumps to where the current pixel's linearisation puts the point (a few
 * times: off the surface the jumps can overshoot), then descends on the offset over 3x3
 * neighbourhoods until the current pixel is the local minimum. (ox, oy): the point's offset
 * from its owner. */
#if GABOR_VEC
/* Plane p at the 8 neighbours of q (rows above, same, below; raster order), from three row
 * loads. q must not lie on the grid's first column or its first or last row. */
GV_INLINE gv8f nb8(const void *p, int q)
{
    const float *f = p;
    gv4f r0, r1, r2;
    memcpy(&r0, f + q - PWS - 1, sizeof r0);
    memcpy(&r1, f + q - 1, sizeof r1);
    memcpy(&r2, f + q + PWS - 1, sizeof r2);
    gv8f t = __builtin_shufflevector(r0, r1, 0, 1, 2, 4, 6, 0, 0, 0);
    gv8f u = __builtin_shufflevector(r2, r2, 0, 1, 2, 3, 0, 0, 0, 0);
    return __builtin_shufflevector(t, u, 0, 1, 2, 3, 4, 8, 9, 10);
}

/* One step of find_owner's descent, the 8 neighbours' offsets in the lanes of a vector (as
 * own_offset lane by lane); the choice then runs in the scalar loop's order. */
GV_INLINE void descend_vec(const gpixels *X, int q, float id, const double *a, int *best,
                           double *bd, double *bx, double *by)
{
    static const int offs[8] = {-PWS - 1, -PWS, -PWS + 1, -1, 1, PWS - 1, PWS, PWS + 1};
    gv8d d0 = a[0] - gv_wide(nb8(X->A[0], q)), d1 = a[1] - gv_wide(nb8(X->A[1], q));
    gv8d d2 = a[2] - gv_wide(nb8(X->A[2], q));
    gv8d ux = gv_wide(nb8(X->P[0], q)) * d0 + gv_wide(nb8(X->P[1], q)) * d1 +
              gv_wide(nb8(X->P[2], q)) * d2;
    gv8d uy = gv_wide(nb8(X->P[3], q)) * d0 + gv_wide(nb8(X->P[4], q)) * d1 +
              gv_wide(nb8(X->P[5], q)) * d2;
    gv8d ax = gv_absd(ux), ay = gv_absd(uy);
    gv8d dd = gv_seld(ax > ay, ax, ay);
    gv8i ok = ((gv8i)nb8(X->emit, q) != 0) & ((gv8i)nb8(X->id, q) == (int32_t)id_bits(id));
    for (int l = 0; l < 8; l++) {
        if (!ok[l]) continue;
        int n = q + offs[l];
        double d = dd[l];
        if (d < *bd || (d == *bd && n < *best)) {
            *bd = d;
            *best = n;
            *bx = ux[l];
            *by = uy[l];
        }
    }
}
#endif

GABOR_BODY int find_owner(const gpixels *X, int ref, const double *a, const double *first,
                          double *ox, double *oy, const int vec)
{
    int q = ref, prev = -1;
    float id = X->id[ref];
    double ux = 0.0, uy = 0.0, dq = 0.0;
    int fresh = 0; /* dq, ux, uy are q's */
    for (int it = 0; it < OWNER_STEPS; it++) {
        if (it == 0 && first) { /* own_offset(X, ref, a), computed by the caller */
            ux = first[0];
            uy = first[1];
            dq = first[2];
        } else {
            dq = own_offset(X, q, a, &ux, &uy);
        }
        fresh = 1;
        if (!(dq < 1e6)) return -1;
        int mx = ifloor(ux + 0.5), my = ifloor(uy + 0.5);
        if (mx == 0 && my == 0) break;
        int ti = q % PWS + mx, tj = q / PWS + my;
        int qi = ti < 0 ? 0 : (ti >= PW ? PW - 1 : ti);
        int qj = tj < 0 ? 0 : (tj >= PW ? PW - 1 : tj);
        int nq = qj * PWS + qi;
        if (nq == q) return -1; /* beyond the ring: not this block's */
        if (!X->emit[nq] || !id_eq(X->id[nq], id)) {
            /* a hole or another object on the way (or the point is not visible): continue
             * from the nearest pixel of the object around the target, if any */
            int best = -1, bd = 1 << 30;
            for (int dj = -2; dj <= 2; dj++)
                for (int di = -2; di <= 2; di++) {
                    int i = qi + di, j = qj + dj;
                    if (i < 0 || i >= PW || j < 0 || j >= PW) continue;
                    int n = j * PWS + i, d = di * di + dj * dj;
                    if (X->emit[n] && id_eq(X->id[n], id) && d < bd) {
                        bd = d;
                        best = n;
                    }
                }
            if (best < 0 || best == q) return -1;
            nq = best;
        }
        if (nq == prev) break; /* jumping back and forth: let the descent settle it */
        prev = q;
        q = nq;
        fresh = 0;
    }
    if (!fresh) dq = own_offset(X, q, a, &ux, &uy);
    for (int it = 0; it < 4 * PW; it++) {
        int best = q, qi = q % PWS, qj = q / PWS;
        double bx = ux, by = uy, bd = dq;
#if GABOR_VEC
        if (vec && qi >= 1 && qj >= 1 && qj <= PW - 2)
            descend_vec(X, q, id, a, &best, &bd, &bx, &by);
        else
#else
        (void)vec;
#endif
            for (int dj = -1; dj <= 1; dj++)
                for (int di = -1; di <= 1; di++) {
                    int i = qi + di, j = qj + dj;
                    if ((di == 0 && dj == 0) || i < 0 || i >= PW || j < 0 || j >= PW) continue;
                    int n = j * PWS + i;
                    if (!X->emit[n] || !id_eq(X->id[n], id)) continue;
                    double vx, vy, d = own_offset(X, n, a, &vx, &vy);
                    if (d < bd || (d == bd && n < best)) {
                        bd = d;
                        best = n;
                        bx = vx;
                        by = vy;
                    }
                }
        if (best == q) break;
        q = best;
        dq = bd;
        ux = bx;
        uy = by;
    }
    /* not near any pixel of the object (beyond a silhouette): no owner */
    if (!in_block(q) || !(dq <= 1.0)) return -1;
    *ox = ux;
    *oy = uy;
    return q;
}

/* The surface at grid position (gx, gy) (a point's screen position): anchor, unit normal and
 * wanted density, bilinear over the four pixels around it where they are all on the owner's
 * surface patch, else the owner's own. A point's distance to the surface and its level weight
 * are read here rather than at the owner's centre, so they barely change when the pixel grid
 * slides under the point and ownership passes to a neighbour (no slab-test flips, no weight
 * jumps: no popping). */
/* patch_link(G, X, q, c) for a pixel q of the block; vector paths: the links the patch labels
 * computed for q's 4-neighbours (X->lr, X->ld: the same booleans, patch_link is symmetric) */
GABOR_BODY int link_of(const gconf *G, const gpixels *X, int q, int c, const int vec)
{
    if (vec) {
        if (c == q + 1) return X->lr[q] != 0;
        if (c == q - 1) return X->lr[c] != 0;
        if (c == q + PWS) return X->ld[q] != 0;
        if (c == q - PWS) return X->ld[c] != 0;
    }
    return patch_link(G, X, q, c);
}

GABOR_BODY void surface_at(const gconf *G, const gpixels *X, int q, double gx, double gy, double *A,
                           double *n, double *mu, const int vec)
{
    int i0 = ifloor(gx), j0 = ifloor(gy);
    if (i0 >= 0 && j0 >= 0 && i0 + 1 < PW && j0 + 1 < PW) {
        const int c[4] = {j0 * PWS + i0, j0 * PWS + i0 + 1, (j0 + 1) * PWS + i0,
                          (j0 + 1) * PWS + i0 + 1};
        int ok = 1;
        for (int k = 0; k < 4 && ok; k++)
            ok = c[k] == q || link_of(G, X, q, c[k], vec);
        if (ok) {
            double fx = gx - i0, fy = gy - j0;
            double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
            double nn = 0.0;
            *mu = 0.0;
            for (int m = 0; m < 3; m++) {
                const float *Am = X->A[m], *nm = X->n[m];
                A[m] = w[0] * Am[c[0]] + w[1] * Am[c[1]] + w[2] * Am[c[2]] + w[3] * Am[c[3]];
                n[m] = w[0] * nm[c[0]] + w[1] * nm[c[1]] + w[2] * nm[c[2]] + w[3] * nm[c[3]];
                nn += n[m] * n[m];
            }
            for (int k = 0; k < 4; k++)
                *mu += w[k] * X->mu[c[k]];
            if (nn > 0.0) {
                nn = 1.0 / sqrt(nn);
                for (int m = 0; m < 3; m++)
                    n[m] *= nn;
                return;
            }
        }
    }
    for (int m = 0; m < 3; m++) {
        A[m] = X->A[m][q];
        n[m] = X->n[m][q];
    }
    *mu = X->mu[q];
}

/* A patch's footprint: its reference pixel (nearest the block centre, first in raster order),
 * the bounds of its pixels' anchor footprints and the largest normal component. */
static int patch_footprint(const gpixels *X, int comp, double *fmin, double *fmax, double *nmax)
{
    const double mid = 0.5 * (PW - 1);
    int ref = -1;
    double best = DBL_MAX;
    for (int m = 0; m < 3; m++) {
        fmin[m] = DBL_MAX;
        fmax[m] = -DBL_MAX;
        nmax[m] = 0.0;
    }
    for (int k = 0; k < PN; k++) {
        if (X->comp[k] != comp) continue;
        double dx = k % PWS - mid, dy = k / PWS - mid, d = dx * dx + dy * dy;
        if (d < best) {
            best = d;
            ref = k;
        }
        for (int m = 0; m < 3; m++) {
            float A = X->A[m][k], e = X->ext[m][k], nm = X->n[m][k];
            if (A - e < fmin[m]) fmin[m] = A - e;
            if (A + e > fmax[m]) fmax[m] = A + e;
            if (fabs(nm) > nmax[m]) nmax[m] = fabs(nm);
        }
    }
    return ref;
}

/* Over the pixels of the object (ring included): the smallest and largest wanted density; 3D,
 * over the patch and the ring: how far their anchors lie from the reference tangent plane
 * (rA, rn) and how far their normals turn from rn. */
static void patch_reach(const gconf *G, const gpixels *X, int comp, float id, const double *rA,
                        const double *rn, double *mumin, double *mumax, double *reach, double *turn)
{
    *mumin = DBL_MAX;
    *mumax = 0.0;
    *reach = *turn = 0.0;
    for (int k = 0; k < PN; k++) {
        if (!X->emit[k] || !id_eq(X->id[k], id)) continue;
        if (X->mu[k] < *mumin) *mumin = X->mu[k];
        if (X->mu[k] > *mumax) *mumax = X->mu[k];
        if (G->dims != 3 || !(X->comp[k] == comp || !in_block(k))) continue;
        double d[3] = {(double)X->A[0][k] - rA[0], (double)X->A[1][k] - rA[1],
                       (double)X->A[2][k] - rA[2]};
        double e = fabs(dot3(d, rn));
        double dn[3] = {(double)X->n[0][k] - rn[0], (double)X->n[1][k] - rn[1],
                        (double)X->n[2][k] - rn[2]};
        double t = sqrt(dot3(dn, dn));
        if (e > *reach) *reach = e;
        if (t > *turn) *turn = t;
    }
}

#if GABOR_VEC
GV_INLINE gv8i in_block_cols(int i0)
{
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    return ((i0 + lane) >= 1) & ((i0 + lane) <= BLOCK);
}

/* patch_footprint 8 pixels at a time (the patch lies in the block; the squared distances to
 * the centre are exact in float as in double; min and max are exact) */
GV_INLINE int patch_footprint_vec(const gpixels *X, int comp, double *fmin, double *fmax,
                                  double *nmax)
{
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    const float mid = 0.5f * (PW - 1);
    gv8f inf = (gv8f){0} + HUGE_VALF, bestd = inf, lo[3], hi[3], nx[3];
    gv8i bestk = (gv8i){0} - 1;
    for (int m = 0; m < 3; m++) {
        lo[m] = inf;
        hi[m] = -inf;
        nx[m] = (gv8f){0};
    }
    for (int j = 1; j <= BLOCK; j++) {
        float dy = (float)j - mid;
        for (int i0 = 0; i0 < PWS; i0 += 8) {
            int k = j * PWS + i0;
            gv8i in = gv_loadi(X->comp + k) == comp;
            if (!gv_any(in)) continue;
            gv8f dx = __builtin_convertvector(i0 + lane, gv8f) - mid;
            gv8f d = dx * dx + dy * dy;
            gv8i up = in & (d < bestd);
            bestd = gv_self(up, d, bestd);
            bestk = gv_seli(up, k + lane, bestk);
            for (int m = 0; m < 3; m++) {
                gv8f A = gv_loadf(X->A[m] + k), e = gv_loadf(X->ext[m] + k);
                gv8f a = A - e, b = A + e, n = gv_absf(gv_loadf(X->n[m] + k));
                lo[m] = gv_self(in & (a < lo[m]), a, lo[m]);
                hi[m] = gv_self(in & (b > hi[m]), b, hi[m]);
                nx[m] = gv_self(in & (n > nx[m]), n, nx[m]);
            }
        }
    }
    int ref = -1;
    float bd = HUGE_VALF;
    for (int l = 0; l < 8; l++)
        if (bestk[l] >= 0 && (bestd[l] < bd || (bestd[l] == bd && bestk[l] < ref))) {
            bd = bestd[l];
            ref = bestk[l];
        }
    for (int m = 0; m < 3; m++) {
        float a = HUGE_VALF, b = -HUGE_VALF, n = 0.0f;
        for (int l = 0; l < 8; l++) {
            a = lo[m][l] < a ? lo[m][l] : a;
            b = hi[m][l] > b ? hi[m][l] : b;
            n = nx[m][l] > n ? nx[m][l] : n;
        }
        fmin[m] = a;
        fmax[m] = b;
        nmax[m] = n;
    }
    return ref;
}

/* patch_reach 8 pixels at a time (the largest turn is the square root of the largest squared
 * turn: sqrt is monotone and exactly rounded) */
GV_INLINE void patch_reach_vec(const gconf *G, const gpixels *X, int comp, float id,
                               const double *rA, const double *rn, double *mumin, double *mumax,
                               double *reach, double *turn)
{
    gv8f mlo = (gv8f){0} + HUGE_VALF, mhi = {0};
    gv8d rch = {0}, trn = {0};
    for (int j = 0; j < PW; j++) {
        int jin = j >= 1 && j <= BLOCK;
        for (int i0 = 0; i0 < PWS; i0 += 8) {
            int k = j * PWS + i0;
            gv8i m = (gv_loadi(X->emit + k) != 0) & (gv_loadid(X->id + k) == (int32_t)id_bits(id));
            if (!gv_any(m)) continue;
            gv8f mu = gv_loadf(X->mu + k);
            mlo = gv_self(m & (mu < mlo), mu, mlo);
            mhi = gv_self(m & (mu > mhi), mu, mhi);
            if (G->dims != 3) continue;
            gv8i ring = jin ? ~in_block_cols(i0) : (gv8i){0} - 1;
            m &= (gv_loadi(X->comp + k) == comp) | ring;
            gv8l ml = __builtin_convertvector(m, gv8l);
            gv8d d0 = gv_wide(gv_loadf(X->A[0] + k)) - rA[0];
            gv8d d1 = gv_wide(gv_loadf(X->A[1] + k)) - rA[1];
            gv8d d2 = gv_wide(gv_loadf(X->A[2] + k)) - rA[2];
            gv8d e = gv_absd(d0 * rn[0] + d1 * rn[1] + d2 * rn[2]);
            gv8d n0 = gv_wide(gv_loadf(X->n[0] + k)) - rn[0];
            gv8d n1 = gv_wide(gv_loadf(X->n[1] + k)) - rn[1];
            gv8d n2 = gv_wide(gv_loadf(X->n[2] + k)) - rn[2];
            gv8d t2 = n0 * n0 + n1 * n1 + n2 * n2;
            rch = gv_seld(ml & (e > rch), e, rch);
            trn = gv_seld(ml & (t2 > trn), t2, trn);
        }
    }
    float a = HUGE_VALF, b = 0.0f;
    double r = 0.0, t = 0.0;
    for (int l = 0; l < 8; l++) {
        a = mlo[l] < a ? mlo[l] : a;
        b = mhi[l] > b ? mhi[l] : b;
        r = rch[l] > r ? rch[l] : r;
        t = trn[l] > t ? trn[l] : t;
    }
    *mumin = a == HUGE_VALF ? DBL_MAX : a;
    *mumax = b;
    *reach = r;
    *turn = sqrt(t);
}
#endif

/* What every cell of one level of a patch shares. */
typedef struct cell_row {
    const gconf *G;
    const gpixels *X;
    gblock *b;
    emit_scratch *scr;
    int ref, l;
    double c, ic;
    double rA0, rA1, rA2, rn0, rn1, rn2; /* the reference pixel's anchor and normal */
    double slab, xmax;
    float id;
    int x0, y0;
    double P[6]; /* the reference pixel's J+ (the owner search's first step) */
} cell_row;

/* The staggered fade's start of the point with hash h. */
static inline double stagger_start(uint64_t h)
{
    return nprfx_u01(nprfx_mix64(h ^ 0x510e527fade682d1ull));
}

/* The cheap tests of a cell's point a (hash h), before the owner search: a point whose fade
 * has not started anywhere it may take its surface from, or (3D) that lies beyond the slab
 * around the reference tangent plane, has weight 0 whoever owns it. */
static inline int cell_pass(const cell_row *R, uint64_t h, const double *a)
{
    if (R->G->stagger && R->xmax < 2.0 && stagger_start(h) * (1.0 - STAGGER) >= R->xmax) return 0;
    if (R->G->dims == 3) {
        double d[3] = {a[0] - R->rA0, a[1] - R->rA1, a[2] - R->rA2};
        double rn[3] = {R->rn0, R->rn1, R->rn2};
        if (!(fabs(dot3(d, rn)) < R->slab)) return 0;
    }
    return 1;
}

#if GABOR_VEC
/* The waiting points' exp and sincos, 8 lanes at a time (internal_vmath.h: the numbers of the
 * scalar path's internal_gabor_make_point), then the points into the block, in their order.
 * Returns 0 when out of memory. */
GV_INLINE int points_flush(const gconf *G, gblock *b, emit_scratch *scr)
{
    int n = scr->npend;
    scr->npend = 0;
    if (!n) return 1;
    gv8d v[GABOR_ARGS], ex[4], sn[4], cs[4];
    for (int i = 0; i < GABOR_ARGS; i++) {
        memcpy(&v[i], scr->pargs[i], sizeof v[i]);
        for (int k = n; k < 8; k++)
            v[i][k] = 0.0;
    }
    for (int i = 0; i < 4; i++)
        ex[i] = internal_vm_exp8(v[GABOR_ARG_ENV + i]);
    int nt = G->uniform_wave ? 2 : 4;
    for (int i = 0; i < nt; i++)
        internal_vm_sincos8(v[GABOR_ARG_PHASE + i], &sn[i], &cs[i]);
    for (int k = 0; k < n; k++) {
        double e[4], s[4], c[4];
        for (int i = 0; i < 4; i++) {
            e[i] = ex[i][k];
            s[i] = i < nt ? sn[i][k] : 0.0;
            c[i] = i < nt ? cs[i][k] : 0.0;
        }
        internal_gabor_point_end(G, &scr->pend[k], e, s, c);
        if (!block_push(b, scr, &scr->pend[k])) return 0;
    }
    return 1;
}
#endif

/* The rest of a cell whose point a passed cell_pass: its owner, level weight and slab test on
 * the surface at the point, and its kernel. Returns 0 when out of memory. */
GABOR_BODY int emit_cell(const cell_row *R, uint64_t h, const double *a, const double *first,
                         const int vec)
{
    const gconf *G = R->G;
    const gpixels *X = R->X;
    double ux, uy;
    int q = find_owner(X, R->ref, a, first, &ux, &uy, vec);
    if (q < 0) return 1;
    double As[3], ns[3], mus, fs;
    int Ls, l = R->l;
    surface_at(G, X, q, q % PWS + ux, q / PWS + uy, As, ns, &mus, vec);
    lod_regime(&G->lod, mus, &Ls, &fs);
    double w2 = lod_w2(Ls, fs, G->W, l);
    if (G->stagger && Ls >= 0 && l == Ls + 1)
        w2 = stagger_w2(stagger_x(G->lod.x, fs), stagger_start(h));
    if (!(w2 > 0.0)) return 1;
    if (G->dims == 3) {
        /* a slab of (weighted) thickness c around the surface: 1 / c^3 points per volume give
         * 1 / c^2 per surface area */
        double d[3] = {a[0] - As[0], a[1] - As[1], a[2] - As[2]};
        double x = fabs(dot3(d, ns)) * R->ic;
        if (!(x < SLAB_OUT)) return 1;
        if (x > SLAB_IN) {
            double t = (SLAB_OUT - x) * (1.0 / SLAB_SOFT);
            w2 *= t * t;
        }
    }
    int ox = R->x0 + q % PWS, oy = R->y0 + q / PWS;
#if GABOR_VEC
    if (vec) { /* its exp and sincos wait for 7 more points */
        emit_scratch *scr = R->scr;
        double args[GABOR_ARGS];
        if (!internal_gabor_point_begin(G, X, q, ox, oy, ox + ux, oy + uy, w2, h, R->id,
                                        &scr->pend[scr->npend], args))
            return 1;
        for (int i = 0; i < GABOR_ARGS; i++)
            scr->pargs[i][scr->npend] = args[i];
        return ++scr->npend < 8 || points_flush(G, R->b, scr);
    }
#endif
    gpoint pt;
    if (!internal_gabor_make_point(G, X, q, ox, oy, ox + ux, oy + uy, w2, h, R->id, &pt)) return 1;
    return block_push(R->b, R->scr, &pt);
}

#if GABOR_VEC
GV_INLINE gv8u gv_mix64(gv8u z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* 21 bits of h (below 2^21) as a double, exactly as the scalar code's conversion */
#define gv_bits21(h) __builtin_convertvector(__builtin_convertvector((h)&0x1fffff, gv8i), gv8d)

/* A row of cells (ix from ix0 to ix1 at iy, iz) 8 at a time: hashes, points and cell_pass in
 * the lanes of vectors (the scalar code's integer and IEEE operations lane by lane), then
 * emit_cell for the cells that pass, in order. Returns 0 when out of memory. */
GV_INLINE int cell_row_vec(const cell_row *R, uint64_t hl, uint64_t zid, double ix0, double ix1,
                           double iy, double iz, const int vec)
{
    const gconf *G = R->G;
    const gv8d lane = {0, 1, 2, 3, 4, 5, 6, 7};
    const double k21 = 1.0 / 2097152.0, c = R->c;
    uint64_t yb = (uint64_t)(uint32_t)(int32_t)(int64_t)iy;
    double ay = 0.0;
    int stag = G->stagger && R->xmax < 2.0, d3 = G->dims == 3;
    for (double ix = ix0; ix <= ix1; ix += 8.0) {
        gv8d vx = ix + lane;
        gv8l xl = __builtin_convertvector(vx, gv8l);
        gv8u xy = (((gv8u)xl & 0xffffffffull) << 32) | yb;
        gv8u h = gv_mix64(gv_mix64(hl ^ xy) ^ zid);
        gv8d a0 = (vx + (gv_bits21(h >> 43) + 0.5) * k21) * c;
        gv8d a1 = (iy + (gv_bits21(h >> 22) + 0.5) * k21) * c;
        gv8d a2 = d3 ? (iz + (gv_bits21(h >> 1) + 0.5) * k21) * c : (gv8d){0};
        gv8l ok = vx <= ix1;
        if (stag) {
            gv8u u = gv_mix64(h ^ 0x510e527fade682d1ull) >> 11;
            gv8d us = __builtin_convertvector((gv8l)u, gv8d) * (1.0 / 9007199254740992.0);
            ok &= ~(us * (1.0 - STAGGER) >= R->xmax); /* as cell_pass */
        }
        gv8d d0 = a0 - R->rA0, d1 = a1 - R->rA1, d2 = a2 - R->rA2;
        if (d3) {
            gv8d e = d0 * R->rn0 + d1 * R->rn1 + d2 * R->rn2;
            ok &= gv_absd(e) < R->slab;
        }
        if (!gv_any(__builtin_convertvector(ok, gv8i))) continue;
        /* the owner search's first step: own_offset from the reference pixel */
        gv8d ux = R->P[0] * d0 + R->P[1] * d1 + R->P[2] * d2;
        gv8d uy = R->P[3] * d0 + R->P[4] * d1 + R->P[5] * d2;
        gv8d ax = gv_absd(ux), ayv = gv_absd(uy), dq = gv_seld(ax > ayv, ax, ayv);
        for (int k = 0; k < 8; k++) {
            if (!ok[k]) continue;
            double a[3] = {a0[k], a1[k], d3 ? a2[k] : ay}, first[3] = {ux[k], uy[k], dq[k]};
            if (!emit_cell(R, h[k], a, first, vec)) return 0;
        }
    }
    return 1;
}
#endif

/* Emit the points owned by the pixels of block (bx, by) into b. Returns 0 when out of memory.
 * vec: the vector path, GABOR_ISA_* (a constant in each instance). */
GABOR_BODY int emit_block_body(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr,
                               const int vec)
{
    gpixels *X = &scr->X;
    int ncomp;
#if GABOR_X86
    if (vec == GABOR_ISA_AVX512)
        ncomp = internal_gabor_block_prepare_avx512(G, &scr->T, bx, by, X, &scr->C);
    else if (vec)
        ncomp = internal_gabor_block_prepare_avx2(G, &scr->T, bx, by, X, &scr->C);
    else
#endif
        ncomp = internal_gabor_block_prepare_scalar(G, &scr->T, bx, by, X, &scr->C);
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1; /* pixel (x0, y0): index 0 of the grid */
    block_begin(b, scr);
    for (int comp = 0; comp < ncomp; comp++) {
        /* the patch's footprint: anchor +- pixel extent, and the largest normal component (the
         * slab's reach per level is added below) */
        double fmin[3], fmax[3], nmax[3];
        int ref;
#if GABOR_VEC
        if (vec)
            ref = patch_footprint_vec(X, comp, fmin, fmax, nmax);
        else
#endif
            ref = patch_footprint(X, comp, fmin, fmax, nmax);
        float id = X->id[ref];
        uint32_t idbits = id_bits(id);
        /* A point's level weight and slab test use the surface interpolated from up to four
         * pixels of the object around it, ring pixels included: the levels to enumerate are
         * those of the smallest and largest wanted density among them (the rule is monotone).
         * 3D: how far those pixels' surface reaches from the reference pixel's tangent plane,
         * and how much their normals turn: a point farther from that plane than the slab plus
         * this reach cannot be accepted, which rejects most off-surface cells of the bounding
         * box before the owner search. */
        double rA[3] = {X->A[0][ref], X->A[1][ref], X->A[2][ref]};
        double rn[3] = {X->n[0][ref], X->n[1][ref], X->n[2][ref]};
        double reach, turn, mumin, mumax;
#if GABOR_VEC
        if (vec)
            patch_reach_vec(G, X, comp, id, rA, rn, &mumin, &mumax, &reach, &turn);
        else
#endif
            patch_reach(G, X, comp, id, rA, rn, &mumin, &mumax, &reach, &turn);
        int Lmin, Lmax, lo, hi, dummy;
        double fmin_, fmax_;
        lod_regime(&G->lod, mumin, &Lmin, &fmin_);
        lod_regime(&G->lod, mumax, &Lmax, &fmax_);
        lod_range(Lmin, fmin_, G->W, &lo, &dummy);
        lod_range(Lmax, fmax_, G->W, &dummy, &hi);
        for (int l = lo; l <= hi; l++) {
            double c = ldexp(G->h0, -l), ic = 1.0 / c;
            /* accepted: |(a - A(s)) . n(s)| < SLAB_OUT c with A(s), n(s) interpolated; so
             * |(a - A_ref) . n_ref| < SLAB_OUT c + |a - A(s)| |n(s) - n_ref| + reach, with a
             * generous allowance for the interpolation's own error */
            double slab = (SLAB_OUT + 0.1) * c * (1.0 + turn) + reach;
            /* staggered fade: where level l fades in for every pixel a point may take its
             * surface from, a point whose ramp has not started at the largest ramp variable
             * among them has weight 0 whoever owns it: skip it before the owner search */
            double xmax = 2.0;
            if (G->stagger && Lmin == l - 1 && Lmax == l - 1) xmax = stagger_x(G->lod.x, fmax_);
            /* nprfx_hash(seed, l, ix, iy, iz, id) with its first two rounds hoisted */
            uint64_t hl =
                nprfx_mix64(nprfx_mix64(G->seed ^ 0x6a09e667f3bcc908ull) ^ (uint64_t)(int64_t)l);
            double i0[3] = {0, 0, 0}, i1[3] = {0, 0, 0}, cells = 1.0;
            for (int m = 0; m < G->dims; m++) {
                /* 3D: the slab around the tangent planes */
                double e = G->dims == 3 ? SLAB_OUT * c * nmax[m] : 0.0;
                i0[m] = floor((fmin[m] - e) * ic);
                i1[m] = floor((fmax[m] + e) * ic);
                cells *= i1[m] - i0[m] + 1.0;
            }
            if (!(cells <= MAX_CELLS)) continue;
            cell_row R = {.G = G,
                          .X = X,
                          .b = b,
                          .scr = scr,
                          .ref = ref,
                          .l = l,
                          .c = c,
                          .ic = ic,
                          .rA0 = rA[0],
                          .rA1 = rA[1],
                          .rA2 = rA[2],
                          .rn0 = rn[0],
                          .rn1 = rn[1],
                          .rn2 = rn[2],
                          .slab = slab,
                          .xmax = xmax,
                          .id = id,
                          .x0 = x0,
                          .y0 = y0};
            for (int m = 0; m < 6; m++)
                R.P[m] = X->P[m][ref];
            for (double iz = i0[2]; iz <= i1[2]; iz++) {
                /* the hash's last round folds in iz and the object id */
                uint64_t zid = ((uint64_t)(uint32_t)(int64_t)iz << 32) | idbits;
                double az = 0.0;
                for (double iy = i0[1]; iy <= i1[1]; iy++) {
#if GABOR_VEC
                    if (vec) {
                        if (!cell_row_vec(&R, hl, zid, i0[0], i1[0], iy, iz, vec)) return 0;
                        continue;
                    }
#endif
                    for (double ix = i0[0]; ix <= i1[0]; ix++) {
                        uint64_t xy = ((uint64_t)(uint32_t)(int32_t)(int64_t)ix << 32) |
                                      (uint64_t)(uint32_t)(int32_t)(int64_t)iy;
                        uint64_t h = nprfx_mix64(nprfx_mix64(hl ^ xy) ^ zid);
                        /* three 21-bit uniforms for the position inside the cell */
                        double a[3];
                        a[0] = (ix + ((double)(h >> 43) + 0.5) * (1.0 / 2097152.0)) * c;
                        a[1] =
                            (iy + ((double)((h >> 22) & 0x1fffff) + 0.5) * (1.0 / 2097152.0)) * c;
                        a[2] =
                            G->dims == 3
                                ? (iz + ((double)((h >> 1) & 0x1fffff) + 0.5) * (1.0 / 2097152.0)) *
                                      c
                                : az;
                        if (!cell_pass(&R, h, a)) continue;
                        if (!emit_cell(&R, h, a, NULL, vec)) return 0;
                    }
                }
            }
        }
    }
#if GABOR_VEC
    if (vec && !points_flush(G, b, scr)) return 0;
#endif
    block_end(b, scr);
    return 1;
}

int internal_gabor_emit_block_scalar(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr)
{
    return emit_block_body(G, bx, by, b, scr, GABOR_ISA_BASE);
}

#if GABOR_X86
__attribute__((target("avx2"))) int internal_gabor_emit_block_avx2(const gconf *G, int bx, int by,
                                                                   gblock *b, emit_scratch *scr)
{
    return emit_block_body(G, bx, by, b, scr, GABOR_ISA_AVX2);
}

__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))) int
internal_gabor_emit_block_avx512(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr)
{
    return emit_block_body(G, bx, by, b, scr, GABOR_ISA_AVX512);
}
#endif
