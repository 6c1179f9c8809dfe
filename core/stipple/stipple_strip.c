/* The strip of owners the stipple renderer's block tests read (stipple_owners.c): for a row of
 * blocks, CHUNK columns at a time, each owner's limit, and where it keeps something its i_max,
 * darkness and footprint box (two owners at a time with SSE2, the scalar code's operations). */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "stipple_footprint.h"
#include "stipple_strip.h"
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

/* The box of strip owner i (of the strip row at r0, pixel row y, columns from x0; k0 the
 * row's first owner in the per-pixel data) from the corners owner_build finds, for an owner
 * that keeps something but lacks a corner in the grid. */
static void box_off_grid(const sjob *j, const pixdata *d, const cgrid *g, strip *st, size_t r0,
                         size_t k0, int x0, int y, int i)
{
    const size_t a = r0 + (size_t)i;
    owner o;
    owner_build(j, d, g, st->imax[a], st->g[a], d->id[k0 + (size_t)i], &o, x0 + i, y);
    quad_box(o.cu, o.cv, &st->bu0[a], &st->bv0[a], &st->bu1[a], &st->bv1[a]);
}

#if defined(__SSE2__)
/* A bit for each of 16 owners (limits lim[0..16), top corners gt[0..17), bottom corners
 * gb[0..17)) that keeps something (limit > 0) but lacks one of its four corners in the grid:
 * the test of the scalar loop in strip_fill, 16 owners without a branch each (at object edges
 * those branches were missed about once an edge owner). */
static inline unsigned off_grid16(const int32_t *lim, const unsigned char *gt,
                                  const unsigned char *gb)
{
    const __m128i z = _mm_setzero_si128();
    __m128i miss = _mm_cmpeq_epi8(_mm_loadu_si128((const __m128i *)gt), z);
    miss = _mm_or_si128(miss, _mm_cmpeq_epi8(_mm_loadu_si128((const __m128i *)(gt + 1)), z));
    miss = _mm_or_si128(miss, _mm_cmpeq_epi8(_mm_loadu_si128((const __m128i *)gb), z));
    miss = _mm_or_si128(miss, _mm_cmpeq_epi8(_mm_loadu_si128((const __m128i *)(gb + 1)), z));
    __m128i k[4];
    for (int q = 0; q < 4; q++)
        k[q] = _mm_cmpgt_epi32(_mm_loadu_si128((const __m128i *)(lim + 4 * q)), z);
    /* -1 and 0 pack to -1 and 0, in lane order */
    const __m128i keep = _mm_packs_epi16(_mm_packs_epi32(k[0], k[1]), _mm_packs_epi32(k[2], k[3]));
    return (unsigned)_mm_movemask_epi8(_mm_and_si128(keep, miss));
}
#endif

/* The owners of rows [y0, y1) and columns [x0, x1) of E into the strip (from its column 0):
 * the limit of every owner, and where it keeps something, i_max, the darkness and the
 * footprint's box (where it keeps nothing, an empty box). */
void internal_stipple_strip_fill(const sjob *j, const scratch *s, nprfx_rect E, int y0, int y1,
                                 int x0, int x1, strip *st)
{
    const nprfx_stipple_params *p = j->p;
    const pixdata *d = &s->d;
    const cgrid *g = &s->g;
    const int ew = x1 - x0;
    const double inv_area = 1.0 / p->area, inv_a0 = 1.0 / p->a0;
    const int uniform = p->mode == NPRFX_STIPPLE_UNIFORM;
#if defined(__SSE2__)
    const int simple = uniform || p->mode == NPRFX_STIPPLE_RADIUS; /* not multitone */
#endif
    for (int y = y0; y < y1; y++) {
        const size_t r0 = (size_t)(y - y0) * st->stride;
        int32_t *lim = st->lim + r0;
        double *imax = st->imax + r0;
        float *gs = st->g + r0;
        double *bu0 = st->bu0 + r0, *bv0 = st->bv0 + r0, *bu1 = st->bu1 + r0, *bv1 = st->bv1 + r0;
        const size_t k0 = pd_at(d, x0, y);
        const unsigned char *ok = d->ok + k0;
        const float *gk = d->g + k0;
        const float *sd = s->sdet + (size_t)(y - E.y0) * nprfx_rect_width(E) + (x0 - E.x0);
        /* keep i while k * A0 / i >= threshold; in sequence units A0 = 1 and k = 1/|det|:
         * i_max = 1 / (threshold |det|), the threshold being area / g (uniform) or a0; kept
         * where the pixel has usable derivatives and i_max >= 1 (not NaN, and not g = 0 in
         * uniform mode), up to kept_limit(). Two at a time where there is SSE2: the same
         * divisions, and in radius and uniform mode kept_limit()'s own comparisons. */
        int i = 0;
#if defined(__SSE2__)
        const __m128d va0 = _mm_set1_pd(inv_a0), varea = _mm_set1_pd(inv_area);
        const __m128d one = _mm_set1_pd(1.0), zero = _mm_setzero_pd();
        const __m128d vmax = _mm_set1_pd(NPRFX_STIPPLE_MAX_SAMPLES);
        const __m128d a0 = _mm_set1_pd(p->a0), dmin = _mm_set1_pd(p->delta_min);
        for (; i + 2 <= ew; i += 2) {
            const __m128d gv =
                _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(gk + i))));
            const __m128d adet =
                _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(sd + i))));
            const __m128d v = _mm_div_pd(uniform ? _mm_mul_pd(gv, varea) : va0, adet);
            _mm_storeu_pd(imax + i, v);
            if (!simple) continue;
            __m128d keep = _mm_and_pd(
                _mm_cmpge_pd(v, one),
                _mm_castsi128_pd(_mm_set_epi64x(-(long long)((ok[i + 1] & OK_BOTH) == OK_BOTH),
                                                -(long long)((ok[i] & OK_BOTH) == OK_BOTH))));
            if (!uniform) {
                const __m128d area = _mm_mul_pd(gv, a0);
                keep = _mm_andnot_pd(_mm_or_pd(_mm_cmple_pd(area, zero), _mm_cmplt_pd(area, dmin)),
                                     keep);
            }
            /* (int) of min(v, MAX) is kept_limit()'s limit; v only where kept */
            const __m128i l = _mm_cvttpd_epi32(
                _mm_or_pd(_mm_and_pd(keep, _mm_min_pd(v, vmax)), _mm_andnot_pd(keep, one)));
            const __m128i k = _mm_shuffle_epi32(_mm_castpd_si128(keep), _MM_SHUFFLE(3, 3, 2, 0));
            _mm_storel_epi64((__m128i *)(lim + i), _mm_and_si128(l, k));
        }
        const int done = simple ? i : 0;
#else
        const int done = 0;
#endif
        for (; i < ew; i++) {
            double adet = sd[i];
            imax[i] = uniform ? gk[i] * inv_area / adet : inv_a0 / adet;
        }
        for (i = done; i < ew; i++) {
            const double v = imax[i];
            int limit = 0;
            if ((ok[i] & OK_BOTH) == OK_BOTH && v >= 1.0)
                limit =
                    kept_limit(p, gk[i], v,
                               v >= NPRFX_STIPPLE_MAX_SAMPLES ? NPRFX_STIPPLE_MAX_SAMPLES : (int)v);
            lim[i] = limit > 0 ? limit : 0;
        }
        memcpy(gs, gk, sizeof(float) * (size_t)ew);
        for (i = ew; i < (ew + BLOCK - 1) / BLOCK * BLOCK; i++)
            lim[i] = 0;
        /* the footprint's box, straight from the grid where it has all four corners: the
         * extremes of each column of corners (top, bottom), then of two columns (min and max
         * are exact, so the order does not matter, but for the sign of a zero, which no test of
         * a box sees); for every owner without a branch (where a corner is not in the grid,
         * its values are not used: the box is replaced below) */
        const size_t g0 = (size_t)(y - g->E.y0) * g->gw + (size_t)(x0 - g->E.x0);
        const size_t g1 = g0 + g->gw;
        const double *ut = g->gu + g0, *ub = g->gu + g1, *vt = g->gv + g0, *vb = g->gv + g1;
        const unsigned char *gt = g->good + g0, *gb = g->good + g1;
        i = 0;
#if defined(__SSE2__)
        const __m128d inf = _mm_set1_pd(INFINITY), ninf = _mm_set1_pd(-INFINITY);
        for (; i + 2 <= ew; i += 2) {
            const __m128d tl = _mm_loadu_pd(ut + i), tr = _mm_loadu_pd(ut + i + 1);
            const __m128d bl = _mm_loadu_pd(ub + i), br = _mm_loadu_pd(ub + i + 1);
            const __m128d ul = _mm_loadu_pd(vt + i), ur = _mm_loadu_pd(vt + i + 1);
            const __m128d ll = _mm_loadu_pd(vb + i), lr = _mm_loadu_pd(vb + i + 1);
            /* an empty box where the owner keeps nothing */
            const __m128i k =
                _mm_cmpgt_epi32(_mm_loadl_epi64((const __m128i *)(lim + i)), _mm_setzero_si128());
            const __m128d keep = _mm_castsi128_pd(_mm_unpacklo_epi32(k, k));
            __m128d u0 = _mm_min_pd(_mm_min_pd(tl, bl), _mm_min_pd(tr, br));
            __m128d u1 = _mm_max_pd(_mm_max_pd(tl, bl), _mm_max_pd(tr, br));
            __m128d v0 = _mm_min_pd(_mm_min_pd(ul, ll), _mm_min_pd(ur, lr));
            __m128d v1 = _mm_max_pd(_mm_max_pd(ul, ll), _mm_max_pd(ur, lr));
            _mm_storeu_pd(bu0 + i, _mm_or_pd(_mm_and_pd(keep, u0), _mm_andnot_pd(keep, inf)));
            _mm_storeu_pd(bv0 + i, _mm_or_pd(_mm_and_pd(keep, v0), _mm_andnot_pd(keep, inf)));
            _mm_storeu_pd(bu1 + i, _mm_or_pd(_mm_and_pd(keep, u1), _mm_andnot_pd(keep, ninf)));
            _mm_storeu_pd(bv1 + i, _mm_or_pd(_mm_and_pd(keep, v1), _mm_andnot_pd(keep, ninf)));
        }
#endif
        for (; i < ew; i++) {
            const double cu[4] = {ut[i], ut[i + 1], ub[i + 1], ub[i]};
            const double cv[4] = {vt[i], vt[i + 1], vb[i + 1], vb[i]};
            quad_box(cu, cv, &bu0[i], &bv0[i], &bu1[i], &bv1[i]);
            if (lim[i] <= 0) bu0[i] = bv0[i] = INFINITY, bu1[i] = bv1[i] = -INFINITY;
        }
        for (i = ew; i < (ew + BLOCK - 1) / BLOCK * BLOCK; i++) {
            bu0[i] = bv0[i] = INFINITY;
            bu1[i] = bv1[i] = -INFINITY;
        }
        /* the owners that keep something but lack a corner in the grid (at object edges and
         * seams): their box from their own corners */
        i = 0;
#if defined(__SSE2__)
        for (; i + 16 <= ew; i += 16)
            for (unsigned m = off_grid16(lim + i, gt + i, gb + i); m; m &= m - 1)
                box_off_grid(j, d, g, st, r0, k0, x0, y, i + lowest_bit(m));
#endif
        for (; i < ew; i++)
            if (lim[i] > 0 && !(gt[i] && gt[i + 1] && gb[i] && gb[i + 1]))
                box_off_grid(j, d, g, st, r0, k0, x0, y, i);
    }
}
