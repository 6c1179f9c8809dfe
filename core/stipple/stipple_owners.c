/* Which stipples the owner pixels keep: each pixel's footprint in sequence space (a quad from
 * the corner grid), one index query per block of owners, the half-open ownership test that gives
 * every sample exactly one owner, the mode's threshold (Eq. 5-8), and the position of the dot in
 * the pixel by inverse bilinear interpolation of the footprint.
 *
 * Speed (1080p, radius mode, one thread: ~43 ms a frame here, from ~75 ms with a pass over all
 * owners, a callback per sample and a counting sort over all owners): the owners' limits and
 * boxes are made for a row of blocks 64 columns at a time, into a strip that stays in the L1
 * cache while its blocks are done (two owners at a time with SSE2, the same operations); the
 * index hands a query's samples over in batches, found without a branch per entry; a block's
 * tests take four owners of a row at once; ownership is decided without a branch, and the
 * positions are computed apart from the tests; each block's stipples are sorted on their own,
 * and the rows of blocks dealt out owner row by owner row at the end. */
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "internal_ivs.h"
#include "nprfx/rng.h"
#include "internal_stipple.h"
#include "stipple_footprint.h"
#include "stipple_strip.h"
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if INTERNAL_X86
#include <immintrin.h>
#endif

/* ---- the footprint of an owner pixel ---- */
static double orient(double ax, double ay, double bx, double by, double sx, double sy)
{
    return (bx - ax) * (sy - ay) - (by - ay) * (sx - ax);
}

/* Does the owner's footprint contain (u, v)? Half-open quad: the top and left edges belong to
 * this pixel, the others to its neighbours, and each shared edge is evaluated from the same
 * corners in the same order on both sides, so a sample has exactly one owner. */
STIPPLE_SHARED int owns(const owner *o, double u, double v)
{
    double s = o->sigma;
    double ht = orient(o->cu[0], o->cv[0], o->cu[1], o->cv[1], u, v) * s;
    double hb = orient(o->cu[3], o->cv[3], o->cu[2], o->cv[2], u, v) * s;
    double vl = orient(o->cu[0], o->cv[0], o->cu[3], o->cv[3], u, v) * s;
    double vr = orient(o->cu[1], o->cv[1], o->cu[2], o->cv[2], u, v) * s;
    return (ht >= 0) & (hb < 0) & (vl <= 0) & (vr > 0); /* no branch: often false */
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

/* Levels: 0 the UVs as they are; 1 + 4 (l - 1) + k a stretch r = 2^l (l = 1, 2, 3) along the
 * UV direction k * 45 degrees. */
#define ANISO_LEVELS 13
#define ANISO_MAX_L 3
#define ANISO_DEAD 0.25
#define ANISO_DEAD_RATIO 1.5 /* the stretch^2 where 0.5 log2_pl() reaches ANISO_DEAD */
/* ANISO_FADE: an owner shared between levels fades its dots in and out over this fraction of
 * its samples (emit()), so that a dot changing level as a surface turns dissolves over frames
 * instead of popping. */
#define ANISO_FADE 1.0
/* ANISO_FAR: beyond a stretch of 2^(ANISO_MAX_L + 1) = 16 (towards a horizon) the UVs as they
 * are. There a level's map leaves the footprints long and, at 45 degrees off, turns them
 * diagonal, so their bounding boxes (what the index is queried with) grow with the square of
 * the stretch: a 1080p ground plane took a minute a frame; the dots there are tiny anyway. */

/* The integral of the fade ramp min(1, max(0, z / ANISO_FADE)) from -infinity to z. */
static double aniso_ramp_integral(double z)
{
    if (z <= 0.0) return 0.0;
    if (z < ANISO_FADE) return z * z / (2.0 * ANISO_FADE);
    return z - 0.5 * ANISO_FADE;
}

/* The stipple sample `index` at (u, v) makes in its owner, if the mode keeps it. */
static void emit(const owner *o, int index, double u, double v, klist *out)
{
    const nprfx_stipple_params *p = o->p;
    double area, tone = 1.0, i_max = o->i_max, ink = 1.0;
    /* An owner with a share w < 1 of this level (anisotropy) sees the samples up to
     * min(1, w (1 + f)) of its whole i_max I, plus one (aniso_passes()). Sample i, at
     * u = (i + h) / I with h a hash of (i, level) in [0, 1), takes ink falling linearly from 1 to
     * 0 as u goes from a - f to a, a = w (1 + f), up to u = 1: none at w = 0, the whole prefix at
     * w = 1, and as w changes each dot fades over a change of f in w instead of popping. Its
     * mean over u, E(w) = H(a) - H(a - 1) (H the integral of the ramp), is scaled to w, so that
     * the levels' inks sum to the owner's whatever the shares (tone at most 1: a few of the
     * first dots of a level with a share below ~0.4 lose a little). With f = 0 it would be the
     * count the share asks for, in expectation. */
    if (out->share) {
        const nprfx_rect e = out->share_e;
        const float share =
            aniso_share_of(&out->share[(size_t)(o->y - e.y0) * (size_t)nprfx_rect_width(e) +
                                       (size_t)(o->x - e.x0)],
                           out->level);
        if (share < 1.0f) {
            const double f = ANISO_FADE, w = share, a = w * (1.0 + f), m = a < 1.0 ? a : 1.0;
            const double I = (i_max - 1.0) / m;
            const double u = (index + nprfx_rand_u01(p->seed, out->level, index, 0, 0, 0)) / I;
            if (u >= 1.0 || u >= a) return;
            const double ramp = (a - u) / f;
            const double E = aniso_ramp_integral(a) - aniso_ramp_integral(a - 1.0);
            ink = (ramp < 1.0 ? ramp : 1.0) * (w / E);
            if (ink > 1.0) ink = 1.0;
            i_max = w * I;
        }
    }
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
            tone = (index + 1.0) / i_max <= frac ? hi : lo;
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
        /* the linear map about the pixel's own UV (J^-1, only needed here) */
        const size_t k = pd_at(o->d, o->x, o->y);
        const float *jc = o->d->jac + 4 * k;
        double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2], rdet = 1.0 / det;
        double inv0 = jc[3] * rdet, inv1 = -jc[1] * rdet, inv2 = -jc[2] * rdet;
        double inv3 = jc[0] * rdet;
        double du = u - o->d->su[k], dv = v - o->d->sv[k];
        double ox = inv0 * du + inv1 * dv, oy = inv2 * du + inv3 * dv;
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
    k->level = out->level;
    k->u = u;
    k->v = v;
    k->s.x = x;
    k->s.y = y;
    k->s.radius = p->mode == NPRFX_STIPPLE_RADIUS ? (float)sqrt(area / PI_D) : o->radius;
    k->s.tone = (float)(tone * ink);
    k->s.sample = index;
    k->s.object = o->id;
}

static int keyed_cmp(const void *pa, const void *pb)
{
    const keyed *a = pa, *b = pb;
    if (a->oy != b->oy) return a->oy < b->oy ? -1 : 1;
    if (a->ox != b->ox) return a->ox < b->ox ? -1 : 1;
    if (a->level != b->level) return a->level < b->level ? -1 : 1;
    if (a->s.sample != b->s.sample) return a->s.sample < b->s.sample ? -1 : 1;
    /* the same sample twice in one footprint: only when the footprint spans tiles */
    if (a->u != b->u) return a->u < b->u ? -1 : 1;
    if (a->v != b->v) return a->v < b->v ? -1 : 1;
    return 0;
}

/* ---- the stipples of a rectangle of owners ---- */

/* member_hits, block_owners and block_queries take a row of a block as one SSE2 vector */
_Static_assert(BLOCK == 4, "a block row is four lanes");
#define BLOCK_PX (BLOCK * BLOCK)
/* owned samples waiting for emit() */
#define PENDING 64

typedef struct block_ctx {
    const sjob *j;
    const pixdata *d;
    const cgrid *grid;
    /* the index: the params' own, or the sequence's, fetched again when a limit needs more */
    const nprfx_ivs_index *ix;
    int ix_count;
    nprfx_result r;
    /* the block: owner (x0 + c, y0 + r) is slot 4 r + c; its row r of the strip from `at` */
    int x0, y0, rows;
    const strip *st;
    size_t at;
    unsigned group;   /* the slots the current query is for */
    unsigned built;   /* the slots whose own[] is built */
    int id[BLOCK_PX]; /* the slots' objects */
    owner own[BLOCK_PX];
    /* owned samples waiting for emit(): slot, index, position */
    int np;
    int pslot[PENDING];
    int32_t pindex[PENDING];
    double pu[PENDING], pv[PENDING];
    klist *out;
} block_ctx;

#if defined(__SSE2__)
/* member_hits for the strip row at a: four boxes and limits. */
static inline unsigned member_row(const strip *st, size_t a, __m128d U, __m128d V, __m128i I)
{
    __m128d in0 = _mm_and_pd(_mm_and_pd(_mm_cmpge_pd(U, _mm_loadu_pd(st->bu0 + a)),
                                        _mm_cmpge_pd(V, _mm_loadu_pd(st->bv0 + a))),
                             _mm_and_pd(_mm_cmple_pd(U, _mm_loadu_pd(st->bu1 + a)),
                                        _mm_cmple_pd(V, _mm_loadu_pd(st->bv1 + a))));
    __m128d in1 = _mm_and_pd(_mm_and_pd(_mm_cmpge_pd(U, _mm_loadu_pd(st->bu0 + a + 2)),
                                        _mm_cmpge_pd(V, _mm_loadu_pd(st->bv0 + a + 2))),
                             _mm_and_pd(_mm_cmple_pd(U, _mm_loadu_pd(st->bu1 + a + 2)),
                                        _mm_cmple_pd(V, _mm_loadu_pd(st->bv1 + a + 2))));
    __m128i l = _mm_cmplt_epi32(I, _mm_loadu_si128((const __m128i *)(st->lim + a)));
    unsigned box = (unsigned)(_mm_movemask_pd(in0) | _mm_movemask_pd(in1) << 2);
    return box & (unsigned)_mm_movemask_ps(_mm_castsi128_ps(l));
}
#endif

/* The slots of the current query whose boxes and limits admit sample i at (u, v). The values
 * are finite, so these comparisons are the negations of the rejecting ones, and the SSE2 ones
 * (two boxes, four limits at a time) are the same comparisons. */
static inline unsigned member_hits(const block_ctx *b, int i, double u, double v)
{
    const strip *st = b->st;
    unsigned hits = 0;
#if defined(__SSE2__)
    const __m128d U = _mm_set1_pd(u), V = _mm_set1_pd(v);
    const __m128i I = _mm_set1_epi32(i);
    const size_t a = b->at, w = (size_t)st->stride;
    if (b->rows == BLOCK) /* a whole block (all but the last row of blocks): no loop */
        hits = member_row(st, a, U, V, I) | member_row(st, a + w, U, V, I) << BLOCK |
               member_row(st, a + 2 * w, U, V, I) << (2 * BLOCK) |
               member_row(st, a + 3 * w, U, V, I) << (3 * BLOCK);
    else
        for (int r = 0; r < b->rows; r++)
            hits |= member_row(st, a + (size_t)r * w, U, V, I) << (BLOCK * r);
#else
    for (int r = 0; r < b->rows; r++)
        for (int c = 0; c < BLOCK; c++) {
            const size_t a = b->at + (size_t)r * st->stride + c;
            hits |= (unsigned)((i < st->lim[a]) & (u >= st->bu0[a]) & (v >= st->bv0[a]) &
                               (u <= st->bu1[a]) & (v <= st->bv1[a]))
                    << (BLOCK * r + c);
        }
#endif
    return hits & b->group;
}

/* Emit the owned samples waiting. Apart from the tests that found them, so that their
 * positions (square roots and divisions) overlap from one to the next. */
static void block_emit(block_ctx *b)
{
    for (int k = 0; k < b->np; k++)
        emit(&b->own[b->pslot[k]], b->pindex[k], b->pu[k], b->pv[k], b->out);
    b->np = 0;
}

/* Sample i at (u, v) in the slots of hits: the ownership tests (each slot's owner built on
 * its first hit), the owned ones put with the samples waiting for emit(). */
STIPPLE_SHARED void take_hits(block_ctx *b, unsigned hits, int32_t i, double u, double v)
{
    while (hits) {
        const int s = lowest_bit(hits);
        hits &= hits - 1;
        owner *o = &b->own[s];
        if (!(b->built & 1u << s)) {
            const int r = s / BLOCK, c = s % BLOCK;
            const size_t a = b->at + (size_t)r * b->st->stride + c;
            owner_build(b->j, b->d, b->grid, b->st->imax[a], b->st->g[a], b->id[s], o, b->x0 + c,
                        b->y0 + r);
            b->built |= 1u << s;
        }
        /* written whether owned or not (a quarter are not), kept where owned */
        if (b->np == PENDING) block_emit(b);
        b->pslot[b->np] = s;
        b->pindex[b->np] = i;
        b->pu[b->np] = u;
        b->pv[b->np] = v;
        b->np += owns(o, u, v);
    }
}

static int block_batch(void *user, int n, const int32_t *index, const double *u, const double *v)
{
    block_ctx *b = user;
    for (int k = 0; k < n; k++)
        take_hits(b, member_hits(b, index[k], u[k], v[k]), index[k], u[k], v[k]);
    return 0;
}

#if INTERNAL_X86
/* member_row with AVX2: the four boxes in one vector each, the same comparisons. */
__attribute__((target("avx2"))) static inline unsigned member_row4(const strip *st, size_t a,
                                                                   __m256d U, __m256d V, __m128i I)
{
    const __m256d lo = _mm256_and_pd(_mm256_cmp_pd(U, _mm256_loadu_pd(st->bu0 + a), _CMP_GE_OQ),
                                     _mm256_cmp_pd(V, _mm256_loadu_pd(st->bv0 + a), _CMP_GE_OQ));
    const __m256d hi = _mm256_and_pd(_mm256_cmp_pd(U, _mm256_loadu_pd(st->bu1 + a), _CMP_LE_OQ),
                                     _mm256_cmp_pd(V, _mm256_loadu_pd(st->bv1 + a), _CMP_LE_OQ));
    const __m128i l = _mm_cmplt_epi32(I, _mm_loadu_si128((const __m128i *)(st->lim + a)));
    return (unsigned)_mm256_movemask_pd(_mm256_and_pd(lo, hi)) &
           (unsigned)_mm_movemask_ps(_mm_castsi128_ps(l));
}

/* member_hits with AVX2. */
__attribute__((target("avx2"))) static inline unsigned member_hits_avx2(const block_ctx *b, int i,
                                                                        double u, double v)
{
    const strip *st = b->st;
    const __m256d U = _mm256_set1_pd(u), V = _mm256_set1_pd(v);
    const __m128i I = _mm_set1_epi32(i);
    const size_t a = b->at, w = (size_t)st->stride;
    unsigned hits = 0;
    if (b->rows == BLOCK) /* a whole block (all but the last row of blocks): no loop */
        hits = member_row4(st, a, U, V, I) | member_row4(st, a + w, U, V, I) << BLOCK |
               member_row4(st, a + 2 * w, U, V, I) << (2 * BLOCK) |
               member_row4(st, a + 3 * w, U, V, I) << (3 * BLOCK);
    else
        for (int r = 0; r < b->rows; r++)
            hits |= member_row4(st, a + (size_t)r * w, U, V, I) << (BLOCK * r);
    return hits & b->group;
}

/* block_batch with AVX2's member tests. */
__attribute__((target("avx2"))) static int block_batch_avx2(void *user, int n, const int32_t *index,
                                                            const double *u, const double *v)
{
    block_ctx *b = user;
    for (int k = 0; k < n; k++)
        take_hits(b, member_hits_avx2(b, index[k], u[k], v[k]), index[k], u[k], v[k]);
    return 0;
}
#endif

/* One query for the slots of `group`: the union of their boxes, the largest of their limits. */
static void query_group(block_ctx *b, unsigned group, int lim, double u0, double v0, double u1,
                        double v1)
{
    if (b->ix_count < lim) {
        /* a longer sequence: it starts with the shorter one, so what is found is the same */
        nprfx_result r = nprfx_stipple_sequence_index(b->j->ctx, b->j->seq, lim, &b->ix);
        if (r != NPRFX_OK) {
            b->r = r;
            return;
        }
        b->ix_count = nprfx_ivs_index_count(b->ix);
    }
    b->group = group;
    /* the query's rectangle is half-open, the boxes closed: widen a hair */
    u1 += 1e-12 * (1.0 + fabs(u1));
    v1 += 1e-12 * (1.0 + fabs(v1));
#if INTERNAL_X86
    if (b->j->avx2) {
        internal_ivs_index_query_batch(b->ix, lim, u0, v0, u1, v1, block_batch_avx2, b, 1);
        return;
    }
#endif
    internal_ivs_index_query_batch(b->ix, lim, u0, v0, u1, v1, block_batch, b, 0);
}

/* The block's owners that keep something (as slots), with their objects into b->id. */
static unsigned block_owners(block_ctx *b, int cols)
{
    const strip *st = b->st;
    unsigned kept = 0;
    for (int r = 0; r < b->rows; r++) {
        const int32_t *lim = st->lim + b->at + (size_t)r * st->stride;
        const int *id = b->d->id + pd_at(b->d, b->x0, b->y0 + r);
        if (cols == BLOCK) /* a fixed size: a move, not a call */
            memcpy(b->id + BLOCK * r, id, sizeof(int) * BLOCK);
        else
            memcpy(b->id + BLOCK * r, id, sizeof(int) * (size_t)cols);
#if defined(__SSE2__)
        /* the strip is padded with limits of 0; a row's four at once (BLOCK is 4) */
        const __m128i l = _mm_loadu_si128((const __m128i *)lim);
        kept |= (unsigned)_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(l, _mm_setzero_si128())))
                << (BLOCK * r);
#else
        for (int c = 0; c < BLOCK; c++) /* the strip is padded with limits of 0 */
            kept |= (unsigned)(lim[c] > 0) << (BLOCK * r + c);
#endif
    }
    return kept;
}

/* All the block's owners that keep something are one group: the union of the boxes in the
 * block (empty where an owner keeps nothing), the largest limit, and the sum of the boxes'
 * areas of those that keep something. */
static void block_union(const block_ctx *b, int *lim, double *bb, double *sum)
{
    const strip *st = b->st;
    int l = 0;
#if defined(__SSE2__)
    __m128d u0 = _mm_set1_pd(INFINITY), v0 = u0, u1 = _mm_set1_pd(-INFINITY), v1 = u1;
    __m128d area = _mm_setzero_pd();
    for (int r = 0; r < b->rows; r++) {
        const size_t a = b->at + (size_t)r * st->stride;
        const __m128i k =
            _mm_cmpgt_epi32(_mm_loadu_si128((const __m128i *)(st->lim + a)), _mm_setzero_si128());
        for (int h = 0; h < BLOCK; h += 2) {
            const __m128d a0 = _mm_loadu_pd(st->bu0 + a + h), b0 = _mm_loadu_pd(st->bv0 + a + h);
            const __m128d a1 = _mm_loadu_pd(st->bu1 + a + h), b1 = _mm_loadu_pd(st->bv1 + a + h);
            u0 = _mm_min_pd(u0, a0);
            v0 = _mm_min_pd(v0, b0);
            u1 = _mm_max_pd(u1, a1);
            v1 = _mm_max_pd(v1, b1);
            const __m128d keep =
                _mm_castsi128_pd(h ? _mm_unpackhi_epi32(k, k) : _mm_unpacklo_epi32(k, k));
            area = _mm_add_pd(area,
                              _mm_and_pd(keep, _mm_mul_pd(_mm_sub_pd(a1, a0), _mm_sub_pd(b1, b0))));
        }
        for (int c = 0; c < BLOCK; c++)
            l = st->lim[a + c] > l ? st->lim[a + c] : l;
    }
    bb[0] = _mm_cvtsd_f64(_mm_min_sd(u0, _mm_unpackhi_pd(u0, u0)));
    bb[1] = _mm_cvtsd_f64(_mm_min_sd(v0, _mm_unpackhi_pd(v0, v0)));
    bb[2] = _mm_cvtsd_f64(_mm_max_sd(u1, _mm_unpackhi_pd(u1, u1)));
    bb[3] = _mm_cvtsd_f64(_mm_max_sd(v1, _mm_unpackhi_pd(v1, v1)));
    *sum = _mm_cvtsd_f64(_mm_add_sd(area, _mm_unpackhi_pd(area, area)));
#else
    double u0 = INFINITY, v0 = INFINITY, u1 = -INFINITY, v1 = -INFINITY, area = 0;
    for (int r = 0; r < b->rows; r++)
        for (int c = 0; c < BLOCK; c++) {
            const size_t a = b->at + (size_t)r * st->stride + c;
            u0 = st->bu0[a] < u0 ? st->bu0[a] : u0;
            v0 = st->bv0[a] < v0 ? st->bv0[a] : v0;
            u1 = st->bu1[a] > u1 ? st->bu1[a] : u1;
            v1 = st->bv1[a] > v1 ? st->bv1[a] : v1;
            if (st->lim[a] > 0) area += (st->bu1[a] - st->bu0[a]) * (st->bv1[a] - st->bv0[a]);
            l = st->lim[a] > l ? st->lim[a] : l;
        }
    bb[0] = u0, bb[1] = v0, bb[2] = u1, bb[3] = v1;
    *sum = area;
#endif
    *lim = l;
}

/* The block's queries: one per object in it (objects live in unrelated parts of the sequence),
 * or one per owner where an object's footprints lie far apart (a UV seam, a fold), so that a
 * query's box never spans empty UV space full of samples nobody owns. Every owner sees exactly
 * the samples in its box below its limit whichever way the queries go (the boxes are tested
 * again per owner), so how owners are grouped changes the cost, not the result. The boxes are
 * finite (corners from finite UVs and derivatives), so plain comparisons give the extremes. */
static void block_queries(block_ctx *b, unsigned kept)
{
    const strip *st = b->st;
    const int *id = b->id;
    const unsigned all = kept;
    while (kept && b->r == NPRFX_OK) {
        const int id0 = id[lowest_bit(kept)];
        unsigned group = 0;
#if defined(__SSE2__)
        /* a row's four ids at once (BLOCK is 4); slots outside the block are not in kept */
        const __m128i i0 = _mm_set1_epi32(id0);
        for (int r = 0; r < b->rows; r++)
            group |= (unsigned)_mm_movemask_ps(_mm_castsi128_ps(
                         _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(id + BLOCK * r)), i0)))
                     << (BLOCK * r);
        group &= kept;
#else
        for (unsigned m = kept; m; m &= m - 1)
            group |= (unsigned)(id[lowest_bit(m)] == id0) << lowest_bit(m);
#endif
        int lim = 0;
        double bb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY}, sum = 0;
        if (group == all) { /* one object: the usual case */
            block_union(b, &lim, bb, &sum);
        } else {
            for (unsigned m = group; m; m &= m - 1) {
                const int s = lowest_bit(m);
                const size_t a = b->at + (size_t)(s / BLOCK) * st->stride + s % BLOCK;
                lim = st->lim[a] > lim ? st->lim[a] : lim;
                bb[0] = st->bu0[a] < bb[0] ? st->bu0[a] : bb[0];
                bb[1] = st->bv0[a] < bb[1] ? st->bv0[a] : bb[1];
                bb[2] = st->bu1[a] > bb[2] ? st->bu1[a] : bb[2];
                bb[3] = st->bv1[a] > bb[3] ? st->bv1[a] : bb[3];
                sum += (st->bu1[a] - st->bu0[a]) * (st->bv1[a] - st->bv0[a]);
            }
        }
        kept &= ~group;
        if ((group & (group - 1)) && (bb[2] - bb[0]) * (bb[3] - bb[1]) > 16.0 * sum) {
            /* scattered footprints: one query each */
            for (unsigned m = group; m && b->r == NPRFX_OK; m &= m - 1) {
                const int s = lowest_bit(m);
                const size_t a = b->at + (size_t)(s / BLOCK) * st->stride + s % BLOCK;
                query_group(b, 1u << s, st->lim[a], st->bu0[a], st->bv0[a], st->bu1[a], st->bv1[a]);
            }
        } else {
            query_group(b, group, lim, bb[0], bb[1], bb[2], bb[3]);
        }
    }
}

/* k[0 .. n) by owner, then sample: few, mostly (insertion sort), or many (a footprint far
 * larger than its pixel). */
static void sort_keyed(keyed *k, size_t n)
{
    if (n > 32) {
        qsort(k, n, sizeof *k, keyed_cmp);
        return;
    }
    for (size_t i = 1; i < n; i++)
        for (size_t m = i; m > 0 && keyed_cmp(&k[m - 1], &k[m]) > 0; m--) {
            keyed t = k[m];
            k[m] = k[m - 1];
            k[m - 1] = t;
        }
}

/* The block loop over the owners of E, or where span is given, over those of each row of
 * blocks br in the columns [span[2 br], span[2 br + 1]) (none where empty): a row of blocks at a
 * time, CHUNK columns at a time, each block's stipples sorted by owner, appended to b->out;
 * where each row of blocks starts in it in brow. */
static void owner_blocks(block_ctx *b, scratch *s, nprfx_rect E, strip *st, size_t *brow, int nbr,
                         const int *span)
{
    klist *kl = b->out;
    for (int br = 0; br < nbr && b->r == NPRFX_OK; br++) {
        const int by = E.y0 + br * BLOCK, by1 = by + BLOCK < E.y1 ? by + BLOCK : E.y1;
        brow[br] = kl->n;
        int x0 = E.x0, x1 = E.x1;
        if (span) {
            if (span[2 * br] >= span[2 * br + 1]) continue;
            x0 = E.x0 + (span[2 * br] - E.x0) / BLOCK * BLOCK; /* on a block of E */
            x1 = span[2 * br + 1];
        }
        b->y0 = by;
        b->rows = by1 - by;
        for (int cx = x0; cx < x1 && b->r == NPRFX_OK; cx += CHUNK) {
            const int cx1 = cx + CHUNK < x1 ? cx + CHUNK : x1;
            internal_stipple_strip_fill(b->j, s, E, by, by1, cx, cx1, st);
            for (int bx = cx; bx < cx1 && b->r == NPRFX_OK; bx += BLOCK) {
                b->x0 = bx;
                b->at = (size_t)(bx - cx);
                const unsigned kept = block_owners(b, bx + BLOCK <= cx1 ? BLOCK : cx1 - bx);
                if (!kept) continue;
                size_t first = kl->n;
                b->built = 0;
                block_queries(b, kept);
                block_emit(b);
                sort_keyed(kl->k + first, kl->n - first);
            }
        }
    }
}

/* ---- anisotropy: the sequence read through the foreshortening ---- */

/* log2 x for x > 0, piecewise linear between powers of 2 (exact there, where the levels are):
 * continuous and increasing, which is all the blend between levels needs, at a fraction of
 * log2()'s cost (each owner takes one). */
static float log2_pl(float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits); /* x is finite and positive: 2^(E - 127) (1 + f / 2^23) */
    const int ex = (int)((bits >> 23) & 0xff) - 127;
    bits = (bits & 0x007fffffu) | 0x3f800000u; /* the mantissa, [1, 2) */
    float m;
    memcpy(&m, &bits, sizeof m);
    return (float)ex + (m - 1.0f);
}

/* The angle of (x, y) in quarter turns, [0, 4), piecewise linear in y / (|x| + |y|) (exact at
 * the axes): continuous and increasing as atan2 is, without its cost. */
static float quarter_turns(float x, float y)
{
    const float s = fabsf(x) + fabsf(y);
    if (!(s > 0.0f)) return 0.0f;
    const float f = y / s; /* in [-1, 1] */
    if (x >= 0.0f) return f >= 0.0f ? f : 4.0f + f;
    return 2.0f - f;
}

/* The shares of the levels at one owner from its Jacobian jc (du/dx, du/dy, dv/dx, dv/dy):
 * M = jc maps screen to UV, so the UV direction the screen stretches most is the eigenvector of
 * M M^T of the smaller eigenvalue, and r = sqrt(ratio of the eigenvalues) = s1 / s2. l =
 * log2 r, blended linearly between its levels, and the direction between its two nearest of
 * the four. Not usable (no derivatives): all on level 0. */
static void aniso_weights(const float *jc, int usable, aniso_share *w)
{
    static const aniso_share none = {{0, 0, 0, 0}, {1.0f, 0.0f, 0.0f, 0.0f}}; /* the UVs */
    *w = none;
    if (!usable) return;
    /* in float: the derivatives are floats, and the shares only need to vary continuously */
    const float a = jc[0], b = jc[1], c = jc[2], d = jc[3];
    const float p = a * a + b * b, q = a * c + b * d, t = c * c + d * d;
    const float h = 0.5f * (p - t), e = sqrtf(h * h + q * q), m = 0.5f * (p + t);
    const float big = m + e, small = m - e;
    /* small > 0 and finite big, and a stretch r = sqrt(big / small) above 2^ANISO_DEAD */
    if (!(small > 0.0f) || !(big < INFINITY) || big <= small * ANISO_DEAD_RATIO) return;
    /* below a stretch of 2^ANISO_DEAD the UVs as they are (rounding in the derivatives of a
     * square map must not move an owner off level 0), reaching level 1 at a stretch of 2 */
    float l = 0.5f * log2_pl(big / small);
    if (l > ANISO_MAX_L + 1) return; /* ANISO_FAR */
    if (l < 1.0f) l = (l - ANISO_DEAD) / (1.0f - ANISO_DEAD);
    if (!(l > 0.0f)) return;
    if (l > ANISO_MAX_L) l = ANISO_MAX_L;
    /* the eigenvector of the larger eigenvalue is at half the angle of (p - t, 2q): the
     * direction the screen squeezes; the one it stretches is a right angle from it, so in
     * units of 45 degrees, tk = (angle of (p - t, 2q) in quarter turns) + 2, modulo 4 */
    float tk = quarter_turns(p - t, 2.0f * q) + 2.0f;
    if (tk >= 4.0f) tk -= 4.0f;
    int k0 = (int)tk; /* tk >= 0 */
    const float fk = tk - (float)k0;
    k0 &= 3;
    const int k1 = (k0 + 1) & 3;
    const int l0 = (int)l; /* l > 0 */
    const float fl = l - (float)l0;
    /* level l0 (0: the UVs) with 1 - fl, level l0 + 1 with fl */
    int n = 0;
    for (int side = 0; side < 2; side++) {
        const int ll = l0 + side;
        const float share = side ? fl : 1.0f - fl;
        if (share <= 0.0f || ll > ANISO_MAX_L) continue;
        if (ll == 0) {
            w->lv[n] = 0;
            w->sh[n++] = share;
            continue;
        }
        w->lv[n] = (unsigned char)(1 + 4 * (ll - 1) + k0);
        w->sh[n++] = share * (1.0f - fk);
        w->lv[n] = (unsigned char)(1 + 4 * (ll - 1) + k1);
        w->sh[n++] = share * fk;
    }
    for (; n < 4; n++)
        w->lv[n] = 0, w->sh[n] = 0.0f;
}

/* The level's map A = R diag(sqrt r, 1 / sqrt r) R^T (R: the turn by k * 45 degrees). */
static void aniso_matrix(int level, double A[4])
{
    const int ll = 1 + (level - 1) / 4, k = (level - 1) % 4;
    const double sr = sqrt((double)(1 << ll)), th = k * 45.0 * PI_D / 180.0;
    const double c = cos(th), sn = sin(th);
    A[0] = c * c * sr + sn * sn / sr;
    A[1] = c * sn * (sr - 1.0 / sr);
    A[2] = A[1];
    A[3] = sn * sn * sr + c * c / sr;
}

/* The owners' stipples when some owner of E sees its surface foreshortened: one pass of the
 * block loop per level with a share there, over the rows and columns of the owners with a
 * share (a level is mostly a patch of a unit), the UVs (su, sv, the Jacobian and the corner
 * grid) read through the level's map and each owner's i_max as emit() wants it (its smoothed
 * |det J| scaled), then all sorted by owner, level and sample, so the order does not depend on
 * how owners fall into units. Returns 0 where every owner is on level 0 (the caller's single
 * pass is the same), -1 when out of memory, else the number of passes. */
static int aniso_passes(scratch *s, nprfx_rect E, block_ctx *b, strip *st, size_t *brow, int nbr)
{
    pixdata *d = &s->d;
    cgrid *g = &s->g;
    const int ew = nprfx_rect_width(E), eh = nprfx_rect_height(E);
    const size_t ne = (size_t)ew * (size_t)eh;
    const size_t nd = (size_t)d->w * (size_t)nprfx_rect_height(d->r);
    const size_t ng = (size_t)g->gw * (size_t)g->gh;
    /* kept from unit to unit (fresh pages for each were a fifth of the time): the UVs,
     * corners and Jacobian as a level reads them (written where its owners read them), the
     * smoothed |det J| as it is, the shares */
    const size_t need = sizeof(double) * (2 * nd + 2 * ng) + sizeof(float) * (4 * nd + ne) +
                        sizeof(aniso_share) * ne + sizeof(float) * ne +
                        sizeof(int) * 2 * ANISO_LEVELS * (size_t)nbr;
    if (!internal_stipple_reserve((void **)&s->aniso, &s->acap, need, 1)) return -1;
    double *su1 = (double *)s->aniso, *sv1 = su1 + nd, *gu1 = sv1 + nd, *gv1 = gu1 + ng;
    float *jac1 = (float *)(gv1 + ng), *sdet0 = jac1 + 4 * nd;
    double *const su0 = d->su, *const sv0 = d->sv, *const gu0 = g->gu, *const gv0 = g->gv;
    float *const jac0 = d->jac;
    aniso_share *w = (aniso_share *)(sdet0 + ne);
    /* where each level has a share: in E, and the columns in each row of blocks */
    float *imax0 = (float *)(w + ne);
    int *span = (int *)(imax0 + ne);
    nprfx_rect on[ANISO_LEVELS];
    for (int l = 0; l < ANISO_LEVELS; l++) {
        on[l] = nprfx_rect_make(E.x1, E.y1, E.x0, E.y0);
        for (int br = 0; br < nbr; br++)
            span[2 * (l * nbr + br)] = E.x1, span[2 * (l * nbr + br) + 1] = E.x0;
    }
    for (int y = E.y0; y < E.y1; y++) {
        const int br = (y - E.y0) / BLOCK;
        for (int x = E.x0; x < E.x1; x++) {
            const size_t k = pd_at(d, x, y), e = (size_t)(y - E.y0) * ew + (size_t)(x - E.x0);
            aniso_weights(d->jac + 4 * k, (d->ok[k] & OK_BOTH) == OK_BOTH, &w[e]);
            for (int i = 0; i < 4; i++) {
                if (!(w[e].sh[i] > 0.0f)) continue;
                const int l = w[e].lv[i];
                nprfx_rect *r = &on[l];
                r->x0 = x < r->x0 ? x : r->x0;
                r->x1 = x + 1 > r->x1 ? x + 1 : r->x1;
                r->y0 = y < r->y0 ? y : r->y0;
                r->y1 = y + 1 > r->y1 ? y + 1 : r->y1;
                int *sp = span + 2 * (l * nbr + br);
                sp[0] = x < sp[0] ? x : sp[0];
                sp[1] = x + 1 > sp[1] ? x + 1 : sp[1];
            }
        }
    }
    int any = 0;
    for (int l = 1; l < ANISO_LEVELS; l++)
        any |= !nprfx_rect_empty(on[l]);
    if (!any) return 0;
    memcpy(sdet0, s->sdet, sizeof(float) * ne);
    const int uniform = b->j->p->mode == NPRFX_STIPPLE_UNIFORM;
    const float inv_area = (float)(1.0 / b->j->p->area), inv_a0 = (float)(1.0 / b->j->p->a0);
    for (int y = E.y0; y < E.y1; y++)
        for (int x = E.x0; x < E.x1; x++) {
            const size_t e = (size_t)(y - E.y0) * ew + (size_t)(x - E.x0);
            /* each owner's whole i_max; none keeps anything but where a level has a share */
            imax0[e] = (uniform ? d->g[pd_at(d, x, y)] * inv_area : inv_a0) / sdet0[e];
            s->sdet[e] = INFINITY;
        }
    int passes = 0;
    for (int l = 0; l < ANISO_LEVELS && b->r == NPRFX_OK && !b->out->failed; l++) {
        const nprfx_rect R = on[l];
        if (nprfx_rect_empty(R)) continue;
        double A[4] = {1, 0, 0, 1};
        if (l) aniso_matrix(l, A);
        /* the level's reading (level 0 reads the UVs as they are) */
        if (l) {
            /* the rows of pixels and corners the owners of R read (their footprints' corners and
             * neighbours), a margin of 2 beyond */
            const int y0 = R.y0 - 2 > d->r.y0 ? R.y0 - 2 : d->r.y0;
            const int y1 = R.y1 + 2 < d->r.y1 ? R.y1 + 2 : d->r.y1;
            const int x0 = R.x0 - 2 > d->r.x0 ? R.x0 - 2 : d->r.x0;
            const int x1 = R.x1 + 2 < d->r.x1 ? R.x1 + 2 : d->r.x1;
            for (int y = y0; y < y1; y++)
                for (size_t k = pd_at(d, x0, y); k < pd_at(d, x1, y); k++) {
                    su1[k] = A[0] * su0[k] + A[1] * sv0[k];
                    sv1[k] = A[2] * su0[k] + A[3] * sv0[k];
                    const float *j0 = jac0 + 4 * k;
                    float *j1 = jac1 + 4 * k;
                    /* d(A s)/dx = A ds/dx */
                    j1[0] = (float)(A[0] * j0[0] + A[1] * j0[2]);
                    j1[1] = (float)(A[0] * j0[1] + A[1] * j0[3]);
                    j1[2] = (float)(A[2] * j0[0] + A[3] * j0[2]);
                    j1[3] = (float)(A[2] * j0[1] + A[3] * j0[3]);
                }
            /* corner (x - 0.5, y - 0.5) is at grid (x + 1 - E.x0, y + 1 - E.y0) */
            int gy0 = R.y0 - 2 - g->E.y0, gy1 = R.y1 + 3 - g->E.y0;
            int gx0 = R.x0 - 2 - g->E.x0, gx1 = R.x1 + 3 - g->E.x0;
            gy0 = gy0 < 0 ? 0 : gy0;
            gy1 = gy1 > g->gh ? g->gh : gy1;
            gx0 = gx0 < 0 ? 0 : gx0;
            gx1 = gx1 > g->gw ? g->gw : gx1;
            for (int gy = gy0; gy < gy1; gy++)
                for (size_t k = (size_t)gy * g->gw + gx0; k < (size_t)gy * g->gw + gx1; k++) {
                    gu1[k] = A[0] * gu0[k] + A[1] * gv0[k];
                    gv1[k] = A[2] * gu0[k] + A[3] * gv0[k];
                }
        }
        /* i_max = K / sdet (K = g / area in uniform mode, 1 / a0 otherwise, stipple_strip.c):
         * a share w < 1 looks at the samples up to min(1, w (1 + fade)) i_max + 1 (emit()) */
        for (int y = R.y0; y < R.y1; y++)
            for (int x = R.x0; x < R.x1; x++) {
                const size_t e = (size_t)(y - E.y0) * ew + (size_t)(x - E.x0);
                const float share = aniso_share_of(&w[e], l);
                if (share >= 1.0f) {
                    s->sdet[e] = sdet0[e];
                } else if (share > 0.0f) {
                    const float K = uniform ? d->g[pd_at(d, x, y)] * inv_area : inv_a0;
                    const float m = share * (1.0f + ANISO_FADE);
                    s->sdet[e] = K / ((m < 1.0f ? m : 1.0f) * imax0[e] + 1.0f);
                }
            }
        b->out->level = l;
        b->out->share = w;
        b->out->share_e = E;
        /* the pass reads the level's arrays (level 0: the UVs as they are) */
        if (l) d->su = su1, d->sv = sv1, d->jac = jac1, g->gu = gu1, g->gv = gv1;
        owner_blocks(b, s, E, st, brow, nbr, span + 2 * (size_t)l * nbr);
        d->su = su0, d->sv = sv0, d->jac = jac0, g->gu = gu0, g->gv = gv0;
        for (int y = R.y0; y < R.y1; y++)
            for (int x = R.x0; x < R.x1; x++)
                s->sdet[(size_t)(y - E.y0) * ew + (size_t)(x - E.x0)] = INFINITY;
        passes++;
    }
    memcpy(s->sdet, sdet0, sizeof(float) * ne);
    b->out->level = 0;
    b->out->share = NULL;
    /* all the passes' stipples by owner, level and sample; where each row of blocks starts */
    klist *kl = b->out;
    if (kl->n > 1) qsort(kl->k, kl->n, sizeof *kl->k, keyed_cmp);
    size_t at = 0;
    for (int br = 0; br < nbr; br++) {
        const int by = E.y0 + br * BLOCK;
        while (at < kl->n && kl->k[at].oy < by)
            at++;
        brow[br] = at;
    }
    brow[nbr] = kl->n;
    return passes;
}

/* The stipples owned by the pixels of E, appended to out in row-major order of their owners. */
nprfx_result internal_stipple_owner_stipples(const sjob *j, scratch *s, nprfx_rect E, stlist *out,
                                             int *row_start)
{
    const nprfx_stipple_params *p = j->p;
    if (nprfx_rect_empty(E)) return NPRFX_OK;
    if (!internal_stipple_prepare(j, s, E)) return NPRFX_ERR_OUT_OF_MEMORY;
    const int eh = nprfx_rect_height(E);
    const pixdata *d = &s->d;
    klist *kl = &s->kl;
    kl->failed = 0;
    strip st;
    st.stride = CHUNK;
    const size_t ns = (size_t)BLOCK * (size_t)st.stride;
    const int nbr = (eh + BLOCK - 1) / BLOCK; /* rows of blocks */
    void *mem = malloc(ns * (5 * sizeof(double) + sizeof(int32_t) + sizeof(float)) +
                       (size_t)(nbr + 1) * sizeof(size_t));
    if (!mem) return NPRFX_ERR_OUT_OF_MEMORY;
    st.imax = mem;
    st.bu0 = st.imax + ns;
    st.bv0 = st.bu0 + ns;
    st.bu1 = st.bv0 + ns;
    st.bv1 = st.bu1 + ns;
    size_t *brow = (size_t *)(st.bv1 + ns); /* where each row of blocks starts in kl */
    st.lim = (int32_t *)(brow + nbr + 1);
    st.g = (float *)(st.lim + ns);
    block_ctx b;
    b.j = j;
    b.d = d;
    b.grid = &s->g;
    b.ix = p->index;
    b.ix_count = p->index ? INT_MAX : 0; /* a fixed index: its length caps the limits */
    b.r = NPRFX_OK;
    b.st = &st;
    b.np = 0;
    b.out = kl;
    memset(b.id, 0, sizeof b.id); /* read four a row (block_queries), outside the block too */
    kl->n = 0;
    kl->level = 0;
    kl->share = NULL;
    int passes = 0;
    if (p->anisotropy) passes = aniso_passes(s, E, &b, &st, brow, nbr);
    if (passes < 0) {
        free(mem);
        return NPRFX_ERR_OUT_OF_MEMORY;
    }
    if (passes == 0) owner_blocks(&b, s, E, &st, brow, nbr, NULL);
    brow[nbr] = kl->n;
    if (b.r == NPRFX_OK && !kl->failed && out->cap < out->n + kl->n) {
        nprfx_stipple *ns = realloc(out->s, (out->n + kl->n) * sizeof *ns);
        if (ns) {
            out->s = ns;
            out->cap = out->n + kl->n;
        } else {
            kl->failed = 1;
        }
    }
    /* into row-major owner order: each row of blocks taken owner row by owner row, stably,
     * so by block, that is by column, within each */
    for (int br = 0; br < nbr && b.r == NPRFX_OK && !kl->failed; br++) {
        const int by = E.y0 + br * BLOCK, by1 = by + BLOCK < E.y1 ? by + BLOCK : E.y1;
        const keyed *k = kl->k + brow[br];
        const size_t n = brow[br + 1] - brow[br];
        size_t at[BLOCK + 1] = {0};
        for (size_t i = 0; i < n; i++)
            at[k[i].oy - by + 1]++;
        at[0] = out->n;
        for (int r = 0; r < BLOCK; r++)
            at[r + 1] += at[r];
        if (row_start)
            for (int y = by; y < by1; y++)
                row_start[y - E.y0] = (int)at[y - by];
        for (size_t i = 0; i < n; i++)
            out->s[at[k[i].oy - by]++] = k[i].s;
        out->n += n;
    }
    free(mem);
    if (b.r != NPRFX_OK) return b.r;
    if (kl->failed) return NPRFX_ERR_OUT_OF_MEMORY;
    if (row_start) row_start[eh] = (int)out->n;
    return NPRFX_OK;
}
