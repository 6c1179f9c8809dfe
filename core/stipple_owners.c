/* Which stipples the owner pixels keep: each pixel's footprint in sequence space (a quad from
 * the corner grid), one index query per block of owners, the half-open ownership test that gives
 * every sample exactly one owner, the mode's threshold (Eq. 5-8), and the position of the dot in
 * the pixel by inverse bilinear interpolation of the footprint. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_stipple.h"

/* ---- the footprint of an owner pixel ---- */

typedef struct owner {
    const nprfx_stipple_params *p;
    int x, y, id;
    double cu[4], cv[4]; /* corners TL, TR, BR, BL in sequence units */
    double sigma;        /* orientation of the map: sign of det J */
    double su, sv;       /* the pixel's own UV (sequence units) */
    double inv[4];       /* J^-1 */
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

static void owner_build(const sjob *j, const pixdata *d, const cgrid *g, double i_max, owner *o,
                        int x, int y)
{
    size_t k = pd_at(d, x, y);
    const float *jc = d->jac + 4 * k;
    o->p = j->p;
    o->x = x;
    o->y = y;
    o->id = d->id[k];
    o->su = d->su[k];
    o->sv = d->sv[k];
    o->g = d->g[k];
    o->i_max = i_max;
    double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2], rdet = 1.0 / det;
    o->sigma = det > 0 ? 1.0 : -1.0;
    o->inv[0] = jc[3] * rdet;
    o->inv[1] = -jc[1] * rdet;
    o->inv[2] = -jc[2] * rdet;
    o->inv[3] = jc[0] * rdet;
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

static double orient(double ax, double ay, double bx, double by, double sx, double sy)
{
    return (bx - ax) * (sy - ay) - (by - ay) * (sx - ax);
}

/* Does the owner's footprint contain (u, v)? Half-open quad: the top and left edges belong to
 * this pixel, the others to its neighbours, and each shared edge is evaluated from the same
 * corners in the same order on both sides, so a sample has exactly one owner. */
static int owns(const owner *o, double u, double v)
{
    double s = o->sigma;
    double ht = orient(o->cu[0], o->cv[0], o->cu[1], o->cv[1], u, v) * s;
    double hb = orient(o->cu[3], o->cv[3], o->cu[2], o->cv[2], u, v) * s;
    double vl = orient(o->cu[0], o->cv[0], o->cu[3], o->cv[3], u, v) * s;
    double vr = orient(o->cu[1], o->cv[1], o->cu[2], o->cv[2], u, v) * s;
    return ht >= 0 && hb < 0 && vl <= 0 && vr > 0;
}

/* Position of (u, v) in the owner's quad as fractions (a, b) from its top-left corner (inverse
 * bilinear map); returns 0 when the quad is too degenerate to invert. */
static int inverse_bilinear(const owner *o, double u, double v, double *a, double *b)
{
    double ex = o->cu[1] - o->cu[0], ey = o->cv[1] - o->cv[0]; /* TL -> TR */
    double fx = o->cu[3] - o->cu[0], fy = o->cv[3] - o->cv[0]; /* TL -> BL */
    double gx = o->cu[0] - o->cu[1] + o->cu[2] - o->cu[3];
    double gy = o->cv[0] - o->cv[1] + o->cv[2] - o->cv[3];
    double hx = u - o->cu[0], hy = v - o->cv[0];
    double k2 = gx * fy - gy * fx, k1 = ex * fy - ey * fx + hx * gy - hy * gx;
    double k0 = hx * ey - hy * ex;
    double bb;
    if (fabs(k2) < 1e-9 * fabs(k1)) {
        if (k1 == 0) return 0;
        bb = -k0 / k1;
    } else {
        double disc = k1 * k1 - 4 * k0 * k2;
        if (disc < 0) return 0;
        double w = sqrt(disc);
        /* the numerically stable pair of roots; the one inside the quad is wanted */
        double q = -0.5 * (k1 + (k1 >= 0 ? w : -w));
        double r1 = q / k2, r2 = q != 0 ? k0 / q : r1;
        bb = fabs(r1 - 0.5) <= fabs(r2 - 0.5) ? r1 : r2;
    }
    double dx = ex + gx * bb, dy = ey + gy * bb, aa;
    if (fabs(dx) >= fabs(dy)) {
        if (dx == 0) return 0;
        aa = (hx - fx * bb) / dx;
    } else {
        aa = (hy - fy * bb) / dy;
    }
    if (!isfinite(aa) || !isfinite(bb)) return 0;
    *a = aa < 0 ? 0 : aa > 1 ? 1 : aa;
    *b = bb < 0 ? 0 : bb > 1 ? 1 : bb;
    return 1;
}

/* The stipple sample `index` at (u, v) makes in its owner, if the mode keeps it. */
static void emit(const owner *o, int index, double u, double v, klist *out)
{
    const nprfx_stipple_params *p = o->p;
    double area, tone = 1.0;
    switch (p->mode) {
    case NPRFX_STIPPLE_RADIUS:
        area = o->g * p->a0;
        if (area <= 0 || area < p->delta_min) return;
        break;
    case NPRFX_STIPPLE_MULTITONE: {
        area = p->area;
        double tau = o->g * p->a0 / p->area;
        int l = 0; /* tau_l <= tau < tau_l+1 with tau_0 = 0 (white paper) */
        while (l < p->num_tones && tau >= p->tones[l])
            l++;
        if (l == p->num_tones) {
            tone = p->tones[l - 1]; /* darker than the darkest pen: all take it */
        } else {
            double lo = l ? p->tones[l - 1] : 0.0, hi = p->tones[l];
            double frac = (tau - lo) / (hi - lo);
            /* low indices take the darker pen: a prefix of the sequence, so both pens stay
             * evenly spread, and the split moves smoothly as the tone changes */
            tone = (index + 1.0) / o->i_max <= frac ? hi : lo;
        }
        if (tone <= 0) return;
        break;
    }
    default:
        area = p->area;
        break;
    }
    double a, b, x, y;
    if (inverse_bilinear(o, u, v, &a, &b)) {
        x = o->x - 0.5 + a;
        y = o->y - 0.5 + b;
    } else {
        double du = u - o->su, dv = v - o->sv;
        double ox = o->inv[0] * du + o->inv[1] * dv, oy = o->inv[2] * du + o->inv[3] * dv;
        x = o->x + (ox < -0.5 ? -0.5 : ox > 0.5 ? 0.5 : ox);
        y = o->y + (oy < -0.5 ? -0.5 : oy > 0.5 ? 0.5 : oy);
    }
    if (out->n == out->cap) {
        size_t cap = out->cap ? 2 * out->cap : 256;
        keyed *nk = realloc(out->k, cap * sizeof *nk);
        if (!nk) {
            out->failed = 1;
            return;
        }
        out->k = nk;
        out->cap = cap;
    }
    keyed *k = &out->k[out->n++];
    k->oy = o->y;
    k->ox = o->x;
    k->u = u;
    k->v = v;
    k->s.x = x;
    k->s.y = y;
    k->s.radius = p->mode == NPRFX_STIPPLE_RADIUS ? (float)sqrt(area / PI_D) : o->radius;
    k->s.tone = (float)tone;
    k->s.sample = index;
    k->s.object = o->id;
}

/* The samples below its limit that emit() keeps for an owner of darkness g are a prefix of
 * them: none in radius mode where the disc would be too small, and in multitone, where the
 * lighter pen is the paper, those with (i + 1) / i_max <= frac. The length of that prefix, from
 * emit()'s own expressions, so that not visiting the rest changes nothing. */
static int kept_limit(const nprfx_stipple_params *p, double g, double i_max, int limit)
{
    if (p->mode == NPRFX_STIPPLE_RADIUS) {
        double area = g * p->a0;
        return area <= 0 || area < p->delta_min ? 0 : limit;
    }
    if (p->mode != NPRFX_STIPPLE_MULTITONE || p->num_tones < 1) return limit;
    double tau = g * p->a0 / p->area;
    if (tau >= p->tones[0]) return limit; /* both pens are ink: every sample is drawn */
    double lo = 0.0, hi = p->tones[0];
    double frac = (tau - lo) / (hi - lo);
    /* (i + 1) / i_max grows with i: find where it passes frac, from an estimate */
    int k = frac > 0 ? (frac * i_max < limit ? (int)(frac * i_max) : limit) : 0;
    while (k < limit && (k + 1.0) / i_max <= frac)
        k++;
    while (k > 0 && !(((k - 1) + 1.0) / i_max <= frac))
        k--;
    return k;
}

static int keyed_cmp(const void *pa, const void *pb)
{
    const keyed *a = pa, *b = pb;
    if (a->oy != b->oy) return a->oy < b->oy ? -1 : 1;
    if (a->ox != b->ox) return a->ox < b->ox ? -1 : 1;
    if (a->s.sample != b->s.sample) return a->s.sample < b->s.sample ? -1 : 1;
    /* the same sample twice in one footprint: only when the footprint spans tiles */
    if (a->u != b->u) return a->u < b->u ? -1 : 1;
    if (a->v != b->v) return a->v < b->v ? -1 : 1;
    return 0;
}

/* ---- the stipples of a rectangle of owners ---- */

/* Owners are handled in blocks: one index query per block, for the union of the owners'
 * footprint boxes and the largest of their limits; each sample found is then tested against
 * every owner of the block whose box and limit admit it. That is the same per-pixel decision
 * as one query per pixel, at a fraction of the cost, and the result does not depend on where
 * the blocks fall (the list is sorted by owner afterwards). */
#define BLOCK 4
#define BLOCK_PX (BLOCK * BLOCK)

typedef struct block_ctx {
    const sjob *j;
    const pixdata *d;
    const cgrid *grid;
    nprfx_rect E;
    const oinfo *info;
    int n; /* owners in the block that keep something (limit > 0), in raster order: */
    int ox[BLOCK_PX], oy[BLOCK_PX], oid[BLOCK_PX];
    const oinfo *oi[BLOCK_PX];
    int lim[BLOCK_PX]; /* copies of their limits and boxes, for the per-sample tests */
    double bu0[BLOCK_PX], bv0[BLOCK_PX], bu1[BLOCK_PX], bv1[BLOCK_PX];
    owner own[BLOCK_PX];
    unsigned char built[BLOCK_PX];
    int members[BLOCK_PX]; /* the owners the current query is for */
    int nm;
    klist *out;
} block_ctx;

static inline int lowest_bit(unsigned m)
{
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_ctz(m);
#else
    int i = 0;
    while (!(m & 1u))
        m >>= 1, i++;
    return i;
#endif
}

static int block_visit(void *user, int index, double u, double v)
{
    block_ctx *b = user;
    /* which members' boxes and limits admit the sample, without a branch per test (the
     * values are finite, so these comparisons are the negations of the rejecting ones) */
    unsigned hits = 0;
    for (int m = 0; m < b->nm; m++) {
        const int s = b->members[m];
        unsigned in = (unsigned)((index < b->lim[s]) & (u >= b->bu0[s]) & (v >= b->bv0[s]) &
                                 (u <= b->bu1[s]) & (v <= b->bv1[s]));
        hits |= in << m;
    }
    while (hits) {
        const int s = b->members[lowest_bit(hits)];
        hits &= hits - 1;
        owner *o = &b->own[s];
        if (!b->built[s]) {
            owner_build(b->j, b->d, b->grid, b->oi[s]->i_max, o, b->ox[s], b->oy[s]);
            b->built[s] = 1;
        }
        if (owns(o, u, v)) emit(o, index, u, v, b->out);
    }
    return 0;
}

static void query_members(block_ctx *b, const nprfx_ivs_index *ix)
{
    int lim = 0;
    double u0 = INFINITY, v0 = INFINITY, u1 = -INFINITY, v1 = -INFINITY;
    for (int m = 0; m < b->nm; m++) {
        const oinfo *in = b->oi[b->members[m]];
        lim = in->limit > lim ? in->limit : lim;
        u0 = in->bb[0] < u0 ? in->bb[0] : u0;
        v0 = in->bb[1] < v0 ? in->bb[1] : v0;
        u1 = in->bb[2] > u1 ? in->bb[2] : u1;
        v1 = in->bb[3] > v1 ? in->bb[3] : v1;
    }
    if (lim <= 0) return;
    /* the query's rectangle is half-open, the boxes closed: widen a hair */
    u1 += 1e-12 * (1.0 + fabs(u1));
    v1 += 1e-12 * (1.0 + fabs(v1));
    nprfx_ivs_index_query(ix, lim, u0, v0, u1, v1, block_visit, b);
}

/* The block's queries: one per object in it (objects live in unrelated parts of the sequence),
 * or one per owner where an object's footprints lie far apart (a UV seam, a fold), so that a
 * query's box never spans empty UV space full of samples nobody owns. Every owner sees exactly
 * the samples in its box below its limit whichever way the queries go (the boxes are tested
 * again per owner), so how owners are grouped changes the cost, not the result. The boxes are
 * finite (corners from finite UVs and derivatives), so plain comparisons give the extremes. */
static void block_queries(block_ctx *b, const nprfx_ivs_index *ix)
{
    unsigned char done[BLOCK_PX];
    memset(done, 0, sizeof done);
    for (int i = 0; i < b->n; i++) {
        if (done[i]) continue;
        const int id = b->oid[i];
        double u0 = INFINITY, v0 = INFINITY, u1 = -INFINITY, v1 = -INFINITY, sum = 0;
        b->nm = 0;
        for (int k = i; k < b->n; k++) {
            if (done[k] || b->oid[k] != id) continue;
            const double *bb = b->oi[k]->bb;
            u0 = bb[0] < u0 ? bb[0] : u0;
            v0 = bb[1] < v0 ? bb[1] : v0;
            u1 = bb[2] > u1 ? bb[2] : u1;
            v1 = bb[3] > v1 ? bb[3] : v1;
            sum += (bb[2] - bb[0]) * (bb[3] - bb[1]);
            done[k] = 1;
            b->members[b->nm++] = k;
        }
        if (b->nm > 1 && (u1 - u0) * (v1 - v0) > 16.0 * sum) {
            /* scattered footprints: one query each */
            int group[BLOCK_PX], ng = b->nm;
            memcpy(group, b->members, sizeof(int) * (size_t)ng);
            for (int k = 0; k < ng; k++) {
                b->members[0] = group[k];
                b->nm = 1;
                query_members(b, ix);
            }
        } else {
            query_members(b, ix);
        }
    }
}

/* The stipples owned by the pixels of E, appended to out in row-major order of their owners. */
nprfx_result internal_stipple_owner_stipples(const sjob *j, scratch *s, nprfx_rect E, stlist *out,
                                             int *row_start)
{
    const nprfx_stipple_params *p = j->p;
    if (nprfx_rect_empty(E)) return NPRFX_OK;
    if (!internal_stipple_prepare(j, s, E)) return NPRFX_ERR_OUT_OF_MEMORY;
    const int ew = nprfx_rect_width(E), eh = nprfx_rect_height(E);
    const pixdata *d = &s->d;
    const cgrid *g = &s->g;

    /* per owner: its limit and footprint box; and the longest prefix any of them needs */
    oinfo *info = s->info;
    const double inv_area = 1.0 / p->area, inv_a0 = 1.0 / p->a0;
    int need = 0;
    for (int y = E.y0; y < E.y1; y++)
        for (int x = E.x0; x < E.x1; x++) {
            size_t k = pd_at(d, x, y);
            oinfo *in = &info[(size_t)(y - E.y0) * ew + (x - E.x0)];
            in->limit = 0;
            if ((d->ok[k] & OK_BOTH) != OK_BOTH) continue;
            double adet = s->sdet[(size_t)(y - E.y0) * ew + (x - E.x0)];
            /* keep i while k * A0 / i >= threshold; in sequence units A0 = 1 and k = 1/|det|:
             * i_max = 1 / (threshold |det|), the threshold being area / g (uniform) or a0 */
            double v = p->mode == NPRFX_STIPPLE_UNIFORM ? d->g[k] * inv_area / adet : inv_a0 / adet;
            if (!(v >= 1.0)) continue; /* also NaN, and g = 0 in uniform mode */
            in->i_max = v;
            in->limit = kept_limit(
                p, d->g[k], v, v >= NPRFX_STIPPLE_MAX_SAMPLES ? NPRFX_STIPPLE_MAX_SAMPLES : (int)v);
            if (in->limit <= 0) {
                in->limit = 0;
                continue;
            }
            if (in->limit > need) need = in->limit;
            /* the footprint's box, straight from the grid where it has all four corners */
            double cu[4], cv[4];
            size_t g0 = (size_t)(y - E.y0) * g->gw + (size_t)(x - E.x0), g1 = g0 + g->gw;
            if (g->good[g0] && g->good[g0 + 1] && g->good[g1] && g->good[g1 + 1]) {
                cu[0] = g->gu[g0], cu[1] = g->gu[g0 + 1], cu[2] = g->gu[g1 + 1];
                cu[3] = g->gu[g1];
                cv[0] = g->gv[g0], cv[1] = g->gv[g0 + 1], cv[2] = g->gv[g1 + 1];
                cv[3] = g->gv[g1];
            } else {
                owner o;
                owner_build(j, d, g, v, &o, x, y);
                memcpy(cu, o.cu, sizeof cu);
                memcpy(cv, o.cv, sizeof cv);
            }
            double u0 = cu[0], u1 = cu[0], v0 = cv[0], v1 = cv[0];
            for (int q = 1; q < 4; q++) {
                u0 = cu[q] < u0 ? cu[q] : u0;
                u1 = cu[q] > u1 ? cu[q] : u1;
                v0 = cv[q] < v0 ? cv[q] : v0;
                v1 = cv[q] > v1 ? cv[q] : v1;
            }
            in->bb[0] = u0;
            in->bb[1] = v0;
            in->bb[2] = u1;
            in->bb[3] = v1;
        }
    const nprfx_ivs_index *ix = p->index;
    nprfx_result r = NPRFX_OK;
    if (!ix && need > 0) r = nprfx_stipple_sequence_index(j->ctx, j->seq, need, &ix);
    klist *kl = &s->kl;
    kl->n = 0;
    kl->failed = 0;
    block_ctx b;
    b.j = j;
    b.d = d;
    b.grid = g;
    b.E = E;
    b.info = info;
    b.out = kl;
    for (int by = E.y0; by < E.y1 && r == NPRFX_OK && ix && need > 0; by += BLOCK)
        for (int bx = E.x0; bx < E.x1; bx += BLOCK) {
            const int bx1 = bx + BLOCK < E.x1 ? bx + BLOCK : E.x1;
            const int by1 = by + BLOCK < E.y1 ? by + BLOCK : E.y1;
            b.n = 0;
            for (int y = by; y < by1; y++) {
                const oinfo *row = info + (size_t)(y - E.y0) * ew + (bx - E.x0);
                const int *idrow = d->id + pd_at(d, bx, y);
                for (int i = 0; i < bx1 - bx; i++) {
                    /* written whatever the limit, kept (n advanced) when it is positive */
                    b.ox[b.n] = bx + i;
                    b.oy[b.n] = y;
                    b.oid[b.n] = idrow[i];
                    b.oi[b.n] = &row[i];
                    b.lim[b.n] = row[i].limit;
                    b.bu0[b.n] = row[i].bb[0];
                    b.bv0[b.n] = row[i].bb[1];
                    b.bu1[b.n] = row[i].bb[2];
                    b.bv1[b.n] = row[i].bb[3];
                    b.built[b.n] = 0;
                    b.n += row[i].limit > 0;
                }
            }
            if (b.n) block_queries(&b, ix);
        }
    if (kl->failed && r == NPRFX_OK) r = NPRFX_ERR_OUT_OF_MEMORY;
    if (r == NPRFX_OK && !kl->n && row_start)
        for (int y = 0; y <= eh; y++)
            row_start[y] = (int)out->n;
    if (r == NPRFX_OK && kl->n) {
        /* into row-major owner order: a counting sort by owner, then by sample within an
         * owner (owners rarely have more than one) */
        if (out->cap < out->n + kl->n) {
            size_t cap = out->n + kl->n;
            nprfx_stipple *ns = realloc(out->s, cap * sizeof *ns);
            if (!ns) return NPRFX_ERR_OUT_OF_MEMORY;
            out->s = ns;
            out->cap = cap;
        }
        size_t npx = (size_t)ew * (size_t)eh;
        for (size_t i = 0; i < npx; i++)
            info[i].start = 0;
        for (size_t i = 0; i < kl->n; i++)
            info[(size_t)(kl->k[i].oy - E.y0) * ew + (kl->k[i].ox - E.x0)].start++;
        int run = 0;
        for (size_t i = 0; i < npx; i++) {
            int here = info[i].start;
            info[i].start = run;
            run += here;
        }
        if (row_start) { /* where each row of owners starts in out */
            for (int y = 0; y < eh; y++)
                row_start[y] = (int)out->n + info[(size_t)y * ew].start;
            row_start[eh] = (int)(out->n + kl->n);
        }
        keyed *tmp = malloc(kl->n * sizeof *tmp);
        if (!tmp) return NPRFX_ERR_OUT_OF_MEMORY;
        for (size_t i = 0; i < kl->n; i++)
            tmp[info[(size_t)(kl->k[i].oy - E.y0) * ew + (kl->k[i].ox - E.x0)].start++] = kl->k[i];
        for (size_t i = 1; i < kl->n; i++) /* insertion sort: runs per owner are tiny */
            for (size_t m = i; m > 0 && keyed_cmp(&tmp[m - 1], &tmp[m]) > 0; m--) {
                keyed t = tmp[m];
                tmp[m] = tmp[m - 1];
                tmp[m - 1] = t;
            }
        for (size_t i = 0; i < kl->n; i++)
            out->s[out->n++] = tmp[i].s;
        free(tmp);
    }
    return r;
}
