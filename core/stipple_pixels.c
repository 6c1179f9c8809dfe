/* The per-pixel data of the stipple renderer: sequence UVs, darkness, the UV Jacobian from
 * finite differences that do not straddle object edges, repaired silhouette pixels, the smoothed
 * area scale, and the grid of footprint corners shared by neighbouring owners.
 *
 * Speed (these passes were a third of a render): each pass has a fast loop over the pixels whose
 * neighbours are all held, two or four pixels at a time with SSE2 where there is SSE2, each lane
 * doing the scalar code's own operations in its order (branches become masks, nothing is
 * reassociated), and hands the pixels where the usual case does not hold (an object edge, a
 * seam, a NaN, the edge of the held pixels) to the scalar code, which is the reference: the
 * results are the same floats with or without SSE2, wherever the units fall. The plate's rows
 * are prefetched two rows ahead while a row is worked on. Nothing is computed that nobody
 * reads: the darkness only on the owners, jid only where fill_jacobian decides it, and id holds
 * NO_ID where there is no UV (what the owners read of it is unchanged), so no second id array
 * is kept. The arrays are reached through local restrict pointers: a store through a byte
 * pointer (ok[]) would otherwise make the compiler reload every pointer of the pixdata. */
#include <math.h>
#include <stdlib.h>
#include <stdint.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "internal_stipple.h"
#include "nprfx/rng.h"

/* Hash stream of the per-object sequence offsets. */
#define STREAM_OBJECT 0x53544950u

/* Grow *p to hold n elements (keeping nothing: scratch is refilled each time). */
int internal_stipple_reserve(void **p, size_t *cap, size_t n, size_t elem)
{
    if (n <= *cap) return 1;
    free(*p);
    *p = malloc(n * elem);
    *cap = *p ? n : 0;
    return *p != NULL;
}

void internal_stipple_scratch_free(scratch *s)
{
    free(s->d.su);
    free(s->d.sv);
    free(s->d.jac);
    free(s->d.g);
    free(s->d.adet);
    free(s->d.hs);
    free(s->d.hc);
    free(s->d.id);
    free(s->d.jid);
    free(s->d.ok);
    free(s->d.fixes);
    free(s->g.gu);
    free(s->g.gv);
    free(s->g.good);
    free(s->sdet);
    free(s->kl.k);
    free(s->sl.s);
    free(s->t);
}

static int pixdata_reserve(pixdata *d, nprfx_rect r)
{
    d->r = r;
    d->w = nprfx_rect_width(r);
    size_t n = (size_t)d->w * (size_t)nprfx_rect_height(r) + 1;
    if (n <= d->cap) return 1;
    size_t c;
    int ok = 1;
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->su, &c, n, sizeof(double));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->sv, &c, n, sizeof(double));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->jac, &c, n, 4 * sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->g, &c, n, sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->adet, &c, n, sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->hs, &c, n, sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->hc, &c, n, sizeof(float));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->id, &c, n, sizeof(int));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->jid, &c, n, sizeof(int));
    c = d->cap, ok &= internal_stipple_reserve((void **)&d->ok, &c, n, 1);
    d->cap = ok ? n : 0;
    return ok;
}

static double apply_curve(const float *curve, double g)
{
    double t = g * (NPRFX_STIPPLE_CURVE_SIZE - 1);
    int i = (int)t;
    if (i >= NPRFX_STIPPLE_CURVE_SIZE - 1) return curve[NPRFX_STIPPLE_CURVE_SIZE - 1];
    if (i < 0) return curve[0];
    return curve[i] + (t - i) * (curve[i + 1] - curve[i]);
}

/* The darkness 1 - tone of a tone value, through the curve. */
static inline float darkness(const float *curve, double tone)
{
    if (!(tone == tone)) tone = 1.0; /* NaN reads as paper */
    tone = tone < 0 ? 0 : tone > 1 ? 1 : tone;
    return (float)(curve ? apply_curve(curve, 1.0 - tone) : 1.0 - tone);
}

/* One input's pixels on one row: columns [lo, hi), p pointing at column lo. */
typedef struct rowsrc {
    const float *p;
    ptrdiff_t ps;
    int lo, hi;
} rowsrc;

static rowsrc row_source(const nprfx_image *im, int y, int x0, int x1)
{
    rowsrc s = {NULL, 0, x0, x0};
    if (!im || y < im->bounds.y0 || y >= im->bounds.y1) return s;
    int lo = x0 > im->bounds.x0 ? x0 : im->bounds.x0, hi = x1 < im->bounds.x1 ? x1 : im->bounds.x1;
    if (hi <= lo) return s;
    s.lo = lo;
    s.hi = hi;
    s.p = nprfx_image_at(im, lo, y);
    s.ps = im->pixel_stride;
    return s;
}

/* Pixel x of the row, or NULL outside the input's bounds. */
static inline const float *row_at(const rowsrc *s, int x)
{
    return x >= s->lo && x < s->hi ? s->p + (ptrdiff_t)(x - s->lo) * s->ps : NULL;
}

/* floor(v + 0.5) for |v| < 2e9, without a libm call. */
static inline int round_half_up(double v)
{
    double f = v + 0.5;
    int i = (int)f; /* towards zero */
    return i - (f < (double)i);
}

/* The object id a pixel's id value names: -1 (no object) for NaN or infinities. */
static inline int id_of(double v)
{
    return !(v > -2e9 && v < 2e9) ? -1 : round_half_up(v);
}

/* What fill_raw keeps from row to row: the constants, and the offsets of the last object seen
 * (different objects get unrelated parts of the torus). */
typedef struct rawstate {
    const nprfx_stipple_params *p;
    double inv_tile_u, inv_tile_v;
    int luma;
    int last_id;
    double off_u, off_v;
    /* apply_curve's operands as doubles: curve[i], and curve[i + 1] - curve[i] (a float
     * difference; 0 past the end) */
    double cv[NPRFX_STIPPLE_CURVE_SIZE], dcv[NPRFX_STIPPLE_CURVE_SIZE];
} rawstate;

static inline void object_offsets(rawstate *c, int id)
{
    c->off_u = nprfx_rand_u01(c->p->seed, 0, id, 0, 0, STREAM_OBJECT);
    c->off_v = nprfx_rand_u01(c->p->seed, 0, id, 0, 1, STREAM_OBJECT);
    c->last_id = id;
}

/* The plate comes from memory: the bytes of the inputs of the row two rows ahead are
 * fetched in step with the pixels of this one, so that reading overlaps the work (a loop that
 * waited for them would wait for each). They are up to three address ranges (inputs
 * interleaved in one plate fall in one), each walked a cache line at a time. */
typedef struct rowahead {
    int n;
    uintptr_t lo[3], hi[3]; /* lo: the start of its first line */
    ptrdiff_t bpp[3];       /* bytes a pixel */
} rowahead;

#if defined(__SSE2__)
#define PREFETCH(p) _mm_prefetch((const char *)(p), _MM_HINT_T0)
#else
#define PREFETCH(p) ((void)(p))
#endif

/* Fetch the lines of range r of a up to where `px` pixels reach, line[r] being the next one. A
 * macro: GCC deems a function made of prefetches pure and drops the calls to it. */
#define AHEAD(a, line, r, px)                                                                      \
    do {                                                                                           \
        uintptr_t t_ = (a).lo[r] + (uintptr_t)(px) * (uintptr_t)(a).bpp[r];                        \
        if (t_ > (a).hi[r]) t_ = (a).hi[r];                                                        \
        for (; line[r] < t_; line[r] += 64)                                                        \
            PREFETCH(line[r]);                                                                     \
    } while (0)

#if defined(__SSE2__)
static inline __m128d select_pd(__m128d mask, __m128d a, __m128d b)
{
    return _mm_or_pd(_mm_and_pd(mask, a), _mm_andnot_pd(mask, b));
}

/* Four bytes from p. */
static inline uint32_t load_u32(const unsigned char *p)
{
    uint32_t v;
    memcpy(&v, p, sizeof v);
    return v;
}

/* Two floats from p into the low lanes (an 8-byte load that may alias anything). */
static inline __m128 load_2f(const float *p)
{
    return _mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)p));
}

/* darkness() for two tone values, one a lane, with the same operations. The clamp with NaN
 * reading as 1 is max(0, t) then min(., 1): MAXPD and MINPD return their second operand when
 * the comparison fails, so NaN passes the max and becomes 1 at the min, and -0 stays -0, as
 * in the scalar code. The curve's operands come from c's tables by index. */
static inline __m128 darkness2(const rawstate *c, int curve, __m128d tone)
{
    const __m128d one = _mm_set1_pd(1.0);
    tone = _mm_min_pd(_mm_max_pd(_mm_setzero_pd(), tone), one);
    const __m128d g = _mm_sub_pd(one, tone);
    if (!curve) return _mm_cvtpd_ps(g);
    /* apply_curve: g is in [0, 1], so i = (int)t is in [0, last], and i = last (the curve's
     * end, taken as is) exactly where t >= last */
    const int last = NPRFX_STIPPLE_CURVE_SIZE - 1;
    const __m128d t = _mm_mul_pd(g, _mm_set1_pd(last));
    const __m128i ii = _mm_cvttpd_epi32(t);
    const int i0 = _mm_cvtsi128_si32(ii), i1 = _mm_cvtsi128_si32(_mm_shuffle_epi32(ii, 1));
    const __m128d cv = _mm_loadh_pd(_mm_load_sd(c->cv + i0), c->cv + i1);
    const __m128d dcv = _mm_loadh_pd(_mm_load_sd(c->dcv + i0), c->dcv + i1);
    const __m128d r = _mm_add_pd(cv, _mm_mul_pd(_mm_sub_pd(t, _mm_cvtepi32_pd(ii)), dcv));
    return _mm_cvtpd_ps(select_pd(_mm_cmpge_pd(t, _mm_set1_pd(last)), _mm_set1_pd(c->cv[last]), r));
}

/* The tone values of the pixels at q0 and q1, one a lane, as the scalar code reads them. */
static inline __m128d tone2(const float *q0, const float *q1, int luma)
{
    if (!luma) return _mm_cvtps_pd(_mm_unpacklo_ps(_mm_load_ss(q0), _mm_load_ss(q1)));
    const __m128d rg0 = _mm_cvtps_pd(load_2f(q0)), rg1 = _mm_cvtps_pd(load_2f(q1));
    const __m128d b = _mm_cvtps_pd(_mm_unpacklo_ps(_mm_load_ss(q0 + 2), _mm_load_ss(q1 + 2)));
    return _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_set1_pd(0.2126), _mm_unpacklo_pd(rg0, rg1)),
                                 _mm_mul_pd(_mm_set1_pd(0.7152), _mm_unpackhi_pd(rg0, rg1))),
                      _mm_mul_pd(_mm_set1_pd(0.0722), b));
}
#endif

/* Where raw_row is along its row: the last id value read and the object it names, and the
 * constants and offsets of rawstate, held in registers. */
typedef struct rowstate {
    float prev;
    int pid, last_id;
    double itu, itv, off_u, off_v;
} rowstate;

/* Pixel i of a row that every input covers, qi and qu pointing at its id and UV: the
 * arithmetic of fill_raw's generic loop. */
static inline void raw_pixel(rawstate *c, rowstate *st, const float *qi, const float *qu,
                             int *restrict id, double *restrict su, double *restrict sv,
                             unsigned char *restrict ok, int i)
{
    /* neighbours mostly share their id value: id_of only where it changes (equal values name
     * the same object; NaN never compares equal and is worked out each time) */
    if (!(qi[0] == st->prev)) st->prev = qi[0], st->pid = id_of(qi[0]);
    const double u = qu[0], v = qu[1];
    if (!isfinite(u) || !isfinite(v) || st->pid < 0) {
        id[i] = NO_ID;
        ok[i] = 0;
        return;
    }
    if (st->pid != st->last_id) {
        object_offsets(c, st->pid);
        st->last_id = st->pid, st->off_u = c->off_u, st->off_v = c->off_v;
    }
    su[i] = u * st->itu + st->off_u;
    sv[i] = v * st->itv + st->off_v;
    ok[i] = OK_UV;
    id[i] = st->pid;
}

/* A row that every input covers (the usual case): the generic loop's arithmetic without its
 * bounds tests. Where there is SSE2, four pixels at a time in the usual case (one object, the
 * last one seen, finite UVs), their (u, v) from two loads, and the darkness four at a time
 * (two a vector). The darkness is only needed on the owners (the columns [gx0, gx1), on owner
 * rows: owner_build and the limits read it nowhere else), so only those read the tone. */
static void raw_row(rawstate *c, pixdata *d, int y, const rowsrc *sid, const rowsrc *suv,
                    const rowsrc *sto, int gx0, int gx1, const rowahead *ahead)
{
    const int n = d->w;
    const size_t k0 = pd_at(d, d->r.x0, y);
    int *restrict id = d->id + k0;
    double *restrict su = d->su + k0, *restrict sv = d->sv + k0;
    unsigned char *restrict ok = d->ok + k0;
    const float zero = 0.0f, *qi = sid->p ? sid->p : &zero, *qu = suv->p;
    const ptrdiff_t is = sid->p ? sid->ps : 0, us = suv->ps;
    const rowahead a = *ahead;
    uintptr_t line[3] = {a.lo[0], a.lo[1], a.lo[2]};
    rowstate st = {qi[0],         id_of(qi[0]), c->last_id, c->inv_tile_u,
                   c->inv_tile_v, c->off_u,     c->off_v};
    int i = 0;
#if defined(__SSE2__)
    const __m128d su_scale = _mm_set1_pd(st.itu), sv_scale = _mm_set1_pd(st.itv);
    const __m128 sign = _mm_set1_ps(-0.0f), fmax = _mm_set1_ps(3.40282346638528859812e38f);
    for (; i + 4 <= n; i += 4) {
        for (int m = 0; m < a.n; m++)
            AHEAD(a, line, m, i + 4);
        const float *p = qi + i * is, *q = qu + i * us;
        const __m128 iv = _mm_setr_ps(p[0], p[is], p[2 * is], p[3 * is]);
        if (_mm_movemask_ps(_mm_cmpeq_ps(iv, _mm_set1_ps(st.prev))) == 15 && st.pid >= 0 &&
            st.pid == st.last_id) {
            const __m128 a01 = _mm_loadh_pi(load_2f(q), (const __m64 *)(q + us));
            const __m128 a23 = _mm_loadh_pi(load_2f(q + 2 * us), (const __m64 *)(q + 3 * us));
            const __m128 u4 = _mm_shuffle_ps(a01, a23, _MM_SHUFFLE(2, 0, 2, 0));
            const __m128 v4 = _mm_shuffle_ps(a01, a23, _MM_SHUFFLE(3, 1, 3, 1));
            /* isfinite as |x| <= FLT_MAX (false for NaN); the same for the float as read
             * and the double it converts to exactly */
            const __m128 fin = _mm_and_ps(_mm_cmple_ps(_mm_andnot_ps(sign, u4), fmax),
                                          _mm_cmple_ps(_mm_andnot_ps(sign, v4), fmax));
            if (_mm_movemask_ps(fin) == 15) {
                const __m128d ou = _mm_set1_pd(st.off_u), ov = _mm_set1_pd(st.off_v);
                const __m128 u23 = _mm_movehl_ps(u4, u4), v23 = _mm_movehl_ps(v4, v4);
                _mm_storeu_pd(su + i, _mm_add_pd(_mm_mul_pd(_mm_cvtps_pd(u4), su_scale), ou));
                _mm_storeu_pd(su + i + 2, _mm_add_pd(_mm_mul_pd(_mm_cvtps_pd(u23), su_scale), ou));
                _mm_storeu_pd(sv + i, _mm_add_pd(_mm_mul_pd(_mm_cvtps_pd(v4), sv_scale), ov));
                _mm_storeu_pd(sv + i + 2, _mm_add_pd(_mm_mul_pd(_mm_cvtps_pd(v23), sv_scale), ov));
                _mm_storeu_si128((__m128i *)(id + i), _mm_set1_epi32(st.pid));
                memset(ok + i, OK_UV, 4);
                continue;
            }
        }
        for (int e = i; e < i + 4; e++)
            raw_pixel(c, &st, qi + e * is, qu + e * us, id, su, sv, ok, e);
    }
#endif
    for (; i < n; i++) {
        for (int m = 0; m < a.n; m++)
            AHEAD(a, line, m, i + 1);
        raw_pixel(c, &st, qi + i * is, qu + i * us, id, su, sv, ok, i);
    }
    c->last_id = st.last_id, c->off_u = st.off_u, c->off_v = st.off_v;
    if (gx1 <= gx0) return;
    /* the darkness on the owners */
    const int m = gx1 - gx0, luma = c->luma;
    const ptrdiff_t ts = sto->ps;
    const float *q = sto->p + (ptrdiff_t)(gx0 - d->r.x0) * ts;
    const size_t kg = k0 + (size_t)(gx0 - d->r.x0);
    const float *curve = c->p->tone_curve;
    float *restrict g = d->g + kg;
    const unsigned char *restrict okg = d->ok + kg;
    i = 0;
#if defined(__SSE2__)
    for (; i + 4 <= m; i += 4, q += 4 * ts) {
        const __m128 d01 = darkness2(c, curve != NULL, tone2(q, q + ts, luma));
        const __m128 d23 = darkness2(c, curve != NULL, tone2(q + 2 * ts, q + 3 * ts, luma));
        /* 0 where the pixel has no UV */
        __m128i none = _mm_cvtsi32_si128((int)load_u32(okg + i));
        none =
            _mm_unpacklo_epi16(_mm_unpacklo_epi8(none, _mm_setzero_si128()), _mm_setzero_si128());
        none = _mm_cmpeq_epi32(none, _mm_setzero_si128());
        _mm_storeu_ps(g + i, _mm_andnot_ps(_mm_castsi128_ps(none), _mm_movelh_ps(d01, d23)));
    }
#endif
    for (; i < m; i++, q += ts) {
        double tone = luma ? 0.2126 * q[0] + 0.7152 * q[1] + 0.0722 * q[2] : q[0];
        g[i] = okg[i] ? darkness(curve, tone) : 0.0f;
    }
}

/* The byte ranges of the inputs of row y over columns [x0, x1): the UV and the id, and the
 * tone where tone is set (owner rows). */
static rowahead row_ahead(const nprfx_stipple_inputs *in, int y, int x0, int x1, int tone)
{
    rowahead a;
    a.n = 0;
    const nprfx_image *im[3] = {in->uv, in->id, tone ? in->tone : NULL};
    const int nch[3] = {2, 1, in->tone->channels >= 3 ? 3 : 1};
    for (int s = 0; s < 3; s++) {
        rowsrc r = row_source(im[s], y, x0, x1);
        if (!r.p) continue;
        const uintptr_t lo = (uintptr_t)r.p;
        const uintptr_t hi = (uintptr_t)(r.p + (ptrdiff_t)(r.hi - r.lo - 1) * r.ps + nch[s]);
        const ptrdiff_t bpp = r.ps * (ptrdiff_t)sizeof(float);
        int m = 0;
        for (; m < a.n; m++) /* one plate: one range */
            if (a.bpp[m] == bpp && lo < a.hi[m] + 64 && a.lo[m] < hi + 64) break;
        if (m == a.n) {
            a.lo[m] = lo, a.hi[m] = hi, a.bpp[m] = bpp, a.n++;
        } else {
            a.lo[m] = lo < a.lo[m] ? lo : a.lo[m];
            a.hi[m] = hi > a.hi[m] ? hi : a.hi[m];
        }
    }
    for (int m = 0; m < a.n; m++)
        a.lo[m] &= ~(uintptr_t)63;
    return a;
}

/* Fill id (NO_ID where there is no UV), ok (OK_UV or 0), su, sv over the held pixels, and g
 * on E. */
static void fill_raw(const sjob *j, pixdata *d, nprfx_rect E)
{
    const nprfx_stipple_params *p = j->p;
    const nprfx_stipple_inputs *in = j->in;
    /* periods tile / sqrt(aspect) in u and tile * sqrt(aspect) in v (exactly 1 / tile for
     * both at aspect 1) */
    const double sa = sqrt(p->aspect);
    rawstate c;
    c.p = p;
    c.inv_tile_u = sa / p->tile;
    c.inv_tile_v = 1.0 / (sa * p->tile);
    c.luma = in->tone->channels >= 3;
    c.last_id = 0x7fffffff;
    c.off_u = c.off_v = 0;
    const float *curve = p->tone_curve;
    if (curve)
        for (int i = 0; i < NPRFX_STIPPLE_CURVE_SIZE; i++) {
            c.cv[i] = curve[i];
            c.dcv[i] = i + 1 < NPRFX_STIPPLE_CURVE_SIZE ? curve[i + 1] - curve[i] : 0.0f;
        }
    const int x0 = d->r.x0, x1 = d->r.x1, luma = c.luma;
    const int gx0 = E.x0 > x0 ? E.x0 : x0, gx1 = E.x1 < x1 ? E.x1 : x1;
    /* the first two rows, ahead of their reading */
    for (int y = d->r.y0; y < d->r.y1 && y < d->r.y0 + 2; y++) {
        rowahead a = row_ahead(in, y, x0, x1, y >= E.y0 && y < E.y1);
        uintptr_t line[3] = {a.lo[0], a.lo[1], a.lo[2]};
        for (int m = 0; m < a.n; m++)
            AHEAD(a, line, m, x1 - x0);
    }
    for (int y = d->r.y0; y < d->r.y1; y++) {
        rowsrc sid = row_source(in->id, y, x0, x1), suv = row_source(in->uv, y, x0, x1);
        rowsrc sto = row_source(in->tone, y, x0, x1);
        size_t k = pd_at(d, x0, y);
        if ((!in->id || (sid.lo == x0 && sid.hi == x1)) && in->uv && suv.lo == x0 && suv.hi == x1 &&
            sto.lo == x0 && sto.hi == x1) {
            const int owners = y >= E.y0 && y < E.y1;
            rowahead a = {0, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
            if (y + 2 < d->r.y1) a = row_ahead(in, y + 2, x0, x1, y + 2 >= E.y0 && y + 2 < E.y1);
            raw_row(&c, d, y, &sid, &suv, &sto, owners ? gx0 : 0, owners ? gx1 : 0, &a);
            continue;
        }
        for (int x = x0; x < x1; x++, k++) {
            d->ok[k] = 0;
            d->g[k] = 0.0f;
            d->id[k] = NO_ID;
            int id = 0; /* no id input, or outside it: object 0 */
            const float *q = row_at(&sid, x);
            if (q) id = id_of(q[0]); /* NaN/inf: -1, no object */
            double u, v;
            if (in->uv) {
                if (!(q = row_at(&suv, x))) continue;
                u = q[0];
                v = q[1];
            } else {
                u = (x - in->frame.x0) / p->plane_scale;
                v = (y - in->frame.y0) / p->plane_scale;
            }
            if (!isfinite(u) || !isfinite(v) || id < 0) continue;
            if (id != c.last_id) object_offsets(&c, id);
            d->su[k] = u * c.inv_tile_u + c.off_u;
            d->sv[k] = v * c.inv_tile_v + c.off_v;
            double tone = 1.0;
            if ((q = row_at(&sto, x)))
                tone = luma ? 0.2126 * q[0] + 0.7152 * q[1] + 0.0722 * q[2] : q[0];
            d->g[k] = darkness(curve, tone);
            d->ok[k] = OK_UV;
            d->id[k] = id;
        }
    }
}

/* One column of the Jacobian at pixel k along a neighbour `step` away, given which of the
 * neighbours k + step (hf) and k - step (hb) are usable (same object, with a UV): differences
 * to those; central where both sides agree, else the smaller one-sided difference (a UV seam
 * gives a jump on one side only). Returns 0 when no neighbour qualifies, 2 when the sides
 * disagree. */
static inline int derivative(const double *su, const double *sv, size_t k, size_t step, int hf,
                             int hb, double *du, double *dv)
{
    double fu = 0, fv = 0, bu = 0, bv = 0;
    if (hf) {
        fu = su[k + step] - su[k];
        fv = sv[k + step] - sv[k];
    }
    if (hb) {
        bu = su[k] - su[k - step];
        bv = sv[k] - sv[k - step];
    }
    if (hf && hb) {
        double nf = fu * fu + fv * fv, nb = bu * bu + bv * bv;
        if (nf <= 4.0 * nb && nb <= 4.0 * nf) {
            *du = 0.5 * (fu + bu);
            *dv = 0.5 * (fv + bv);
            return 1;
        }
        if (nf < nb)
            *du = fu, *dv = fv;
        else
            *du = bu, *dv = bv;
        return 2;
    }
    if (hf) {
        *du = fu, *dv = fv;
        return 1;
    }
    if (hb) {
        *du = bu, *dv = bv;
        return 1;
    }
    return 0;
}

/* The Jacobian of pixel (x, y) at k (the reference for the fast path below). */
static void jac_pixel(pixdata *d, size_t k, int x, int up, int down)
{
    const size_t w = (size_t)d->w;
    const int *ids = d->id;
    d->jid[k] = NO_ID;
    if (!(d->ok[k] & OK_UV)) return;
    const int id = ids[k];
    double ux, vx, uy, vy;
    int ex = derivative(d->su, d->sv, k, 1, x + 1 < d->r.x1 && ids[k + 1] == id,
                        x - 1 >= d->r.x0 && ids[k - 1] == id, &ux, &vx);
    int ey =
        derivative(d->su, d->sv, k, w, down && ids[k + w] == id, up && ids[k - w] == id, &uy, &vy);
    if (!ex || !ey) return;
    if (ex == 2 || ey == 2) d->ok[k] |= OK_SEAM;
    float *jc = d->jac + 4 * k;
    jc[0] = (float)ux;
    jc[1] = (float)uy;
    jc[2] = (float)vx;
    jc[3] = (float)vy;
    double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2];
    d->adet[k] = (float)fabs(det);
    if (det != 0.0 && isfinite(det) && d->adet[k] > 0) {
        d->ok[k] |= OK_J;
        d->jid[k] = id;
    }
}

#if defined(__SSE2__)
/* The arrays fill_jacobian's fast path uses, held in registers across the byte stores to ok
 * (which could otherwise alias every pointer of the pixdata). */
typedef struct jacview {
    const double *su, *sv;
    const int *id;
    float *jac, *adet;
    int *jid;
    unsigned char *ok;
    size_t w;
} jacview;

/* For pixels k .. k + 3 (one lane each, their ids in id): do the four neighbours share the
 * pixel's id, and has it a UV? -1 in the lanes where so. */
static inline __m128i same_around(const jacview *v, size_t k, __m128i id)
{
    const int *p = v->id + k;
    const ptrdiff_t w = (ptrdiff_t)v->w;
    __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(p - 1)), id);
    same = _mm_and_si128(same, _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(p + 1)), id));
    same = _mm_and_si128(same, _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(p - w)), id));
    same = _mm_and_si128(same, _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(p + w)), id));
    return _mm_andnot_si128(_mm_cmpeq_epi32(id, _mm_set1_epi32(NO_ID)), same);
}

/* jac_pixel for pixels k and k + 1 (one lane each, ids in the low lanes of id) whose
 * neighbours all share their id, where both sides agree in x and in y for both (the usual
 * case). Returns 0, having written nothing, where they do not. */
static inline int jac_lanes(const jacview *v, size_t k, __m128i id)
{
    const size_t w = v->w;
    const double *su = v->su + k, *sv = v->sv + k;
    const __m128d u0 = _mm_loadu_pd(su), v0 = _mm_loadu_pd(sv), four = _mm_set1_pd(4.0);
    const __m128d half = _mm_set1_pd(0.5);
    /* x: forward and backward differences, their squared lengths, the agreement test */
    __m128d fu = _mm_sub_pd(_mm_loadu_pd(su + 1), u0), fv = _mm_sub_pd(_mm_loadu_pd(sv + 1), v0);
    __m128d bu = _mm_sub_pd(u0, _mm_loadu_pd(su - 1)), bv = _mm_sub_pd(v0, _mm_loadu_pd(sv - 1));
    __m128d nf = _mm_add_pd(_mm_mul_pd(fu, fu), _mm_mul_pd(fv, fv));
    __m128d nb = _mm_add_pd(_mm_mul_pd(bu, bu), _mm_mul_pd(bv, bv));
    __m128d agree =
        _mm_and_pd(_mm_cmple_pd(nf, _mm_mul_pd(four, nb)), _mm_cmple_pd(nb, _mm_mul_pd(four, nf)));
    const __m128d ux = _mm_mul_pd(half, _mm_add_pd(fu, bu)),
                  vx = _mm_mul_pd(half, _mm_add_pd(fv, bv));
    /* y */
    fu = _mm_sub_pd(_mm_loadu_pd(su + w), u0), fv = _mm_sub_pd(_mm_loadu_pd(sv + w), v0);
    bu = _mm_sub_pd(u0, _mm_loadu_pd(su - w)), bv = _mm_sub_pd(v0, _mm_loadu_pd(sv - w));
    nf = _mm_add_pd(_mm_mul_pd(fu, fu), _mm_mul_pd(fv, fv));
    nb = _mm_add_pd(_mm_mul_pd(bu, bu), _mm_mul_pd(bv, bv));
    agree = _mm_and_pd(agree, _mm_and_pd(_mm_cmple_pd(nf, _mm_mul_pd(four, nb)),
                                         _mm_cmple_pd(nb, _mm_mul_pd(four, nf))));
    if (_mm_movemask_pd(agree) != 3) return 0;
    const __m128d uy = _mm_mul_pd(half, _mm_add_pd(fu, bu)),
                  vy = _mm_mul_pd(half, _mm_add_pd(fv, bv));
    /* the floats, stored as jac_pixel orders them: ux uy vx vy a pixel */
    const __m128 fux = _mm_cvtpd_ps(ux), fuy = _mm_cvtpd_ps(uy), fvx = _mm_cvtpd_ps(vx);
    const __m128 fvy = _mm_cvtpd_ps(vy);
    const __m128 lu = _mm_unpacklo_ps(fux, fuy), lv = _mm_unpacklo_ps(fvx, fvy);
    _mm_storeu_ps(v->jac + 4 * k, _mm_movelh_ps(lu, lv));
    _mm_storeu_ps(v->jac + 4 * k + 4, _mm_movehl_ps(lv, lu));
    /* det from the stored floats, |det|, and the usability test */
    const __m128d det = _mm_sub_pd(_mm_mul_pd(_mm_cvtps_pd(fux), _mm_cvtps_pd(fvy)),
                                   _mm_mul_pd(_mm_cvtps_pd(fuy), _mm_cvtps_pd(fvx)));
    const __m128d adet = _mm_andnot_pd(_mm_set1_pd(-0.0), det);
    const __m128 fadet = _mm_cvtpd_ps(adet);
    _mm_storel_pi((__m64 *)(v->adet + k), fadet);
    /* usable: det finite (|det| <= DBL_MAX) and |det| > 0 as a float (which implies
     * det != 0); the pixels had OK_UV only */
    const __m128d dm = _mm_cmple_pd(adet, _mm_set1_pd(1.79769313486231570815e308));
    const __m128i usable =
        _mm_and_si128(_mm_shuffle_epi32(_mm_castpd_si128(dm), _MM_SHUFFLE(3, 1, 2, 0)),
                      _mm_castps_si128(_mm_cmpgt_ps(fadet, _mm_setzero_ps())));
    _mm_storel_epi64(
        (__m128i *)(v->jid + k),
        _mm_or_si128(_mm_and_si128(usable, id), _mm_andnot_si128(usable, _mm_set1_epi32(NO_ID))));
    const int bits = _mm_movemask_ps(_mm_castsi128_ps(usable));
    v->ok[k] = (unsigned char)(OK_UV | (bits & 1 ? OK_J : 0));
    v->ok[k + 1] = (unsigned char)(OK_UV | (bits & 2 ? OK_J : 0));
    return 1;
}

/* jac_pixel for pixels k .. k + 3, whose neighbours are all held: the id tests four at a
 * time, the rest by pairs, each pair not in the usual case going to jac_pixel. */
static inline void jac_quad(pixdata *d, const jacview *v, size_t k, int x)
{
    const __m128i id = _mm_loadu_si128((const __m128i *)(v->id + k));
    const int m = _mm_movemask_epi8(same_around(v, k, id));
    for (int h = 0; h < 2; h++) {
        const size_t kh = k + 2 * (size_t)h;
        const __m128i idh = h ? _mm_unpackhi_epi64(id, id) : id;
        if (((m >> (8 * h)) & 0xff) != 0xff || !jac_lanes(v, kh, idh)) {
            jac_pixel(d, kh, x + 2 * h, 1, 1);
            jac_pixel(d, kh + 1, x + 2 * h + 1, 1, 1);
        }
    }
}
#endif

/* The Jacobian, |det J|, OK_J, OK_SEAM and jid (NO_ID where not usable) over r. */
static void fill_jacobian(pixdata *d, nprfx_rect r)
{
#if defined(__SSE2__)
    /* the columns whose left and right neighbours are held */
    const int xa = r.x0 - 1 >= d->r.x0 ? r.x0 : d->r.x0 + 1;
    const int xb = r.x1 + 1 <= d->r.x1 ? r.x1 : d->r.x1 - 1;
    const jacview v = {d->su, d->sv, d->id, d->jac, d->adet, d->jid, d->ok, (size_t)d->w};
#endif
    for (int y = r.y0; y < r.y1; y++) {
        const int up = y - 1 >= d->r.y0, down = y + 1 < d->r.y1;
        const size_t k0 = pd_at(d, r.x0, y);
        int x = r.x0;
#if defined(__SSE2__)
        if (up && down) {
            for (; x < xa; x++)
                jac_pixel(d, k0 + (size_t)(x - r.x0), x, up, down);
            for (; x + 4 <= xb; x += 4)
                jac_quad(d, &v, k0 + (size_t)(x - r.x0), x);
        }
#endif
        for (; x < r.x1; x++)
            jac_pixel(d, k0 + (size_t)(x - r.x0), x, up, down);
    }
}

/* A pixel whose |det J| exceeds OUTLIER times the smallest of its same-object neighbours'
 * sees a jump, not the surface: renderers filter the UV pass, so along a silhouette the
 * pixels hold a blend of the two objects' UVs (and across a UV seam, of the two charts'),
 * which sits between the surfaces and makes a huge footprint there, packed with dots (a dark
 * outline). Half-float steps and perspective change |det J| between neighbours by a few times
 * at most. */
#define OUTLIER 8.0f

/* A repaired pixel's new values, computed from the values before any repair. */
typedef struct fix {
    size_t k;
    double su, sv;
    float jac[4], adet;
} fix;

/* The repairs found so far; failed: one could not be recorded (out of memory). */
typedef struct fixlist {
    pixdata *d;
    size_t n;
    int failed;
} fixlist;

/* Is pixel (x, y) at k an outlier? Then which neighbour it takes: 1 + its index in
 * {-1, +1, -w, +w}; else 0. */
static inline int outlier_source(const pixdata *d, ptrdiff_t k, int x, int up, int down)
{
    const ptrdiff_t w = d->w;
    const int *jid = d->jid;
    const float *adet = d->adet;
    const int id = jid[k];
    if (id == NO_ID) return 0;
    const ptrdiff_t step[4] = {-1, 1, -w, w};
    const int has[4] = {x - 1 >= d->r.x0, x + 1 < d->r.x1, up, down};
    /* an outlier exceeds OUTLIER times some usable neighbour's (exactly: times the
     * smallest); the usual pixel fails all four tests and is done */
    const float a = adet[k] * (1.0f / OUTLIER);
    if (!((has[0] && a > adet[k - 1] && jid[k - 1] == id) ||
          (has[1] && a > adet[k + 1] && jid[k + 1] == id) ||
          (up && a > adet[k - w] && jid[k - w] == id) ||
          (down && a > adet[k + w] && jid[k + w] == id)))
        return 0;
    float ref = INFINITY;
    int best = 0;
    for (int n = 0; n < 4; n++)
        if (has[n] && jid[k + step[n]] == id && adet[k + step[n]] < ref) {
            ref = adet[k + step[n]];
            best = n;
        }
    return 1 + best;
}

/* Record the repair of pixel k from neighbour n (outlier_source - 1): the neighbour's UV
 * extrapolated by its derivatives, and those derivatives. Where there is no room to record
 * it, the pixel is marked OK_DROP instead. */
static void record_fix(fixlist *fl, size_t k, int n)
{
    pixdata *d = fl->d;
    if (fl->n == d->fixcap) {
        size_t cap = d->fixcap ? 2 * d->fixcap : 256;
        fix *nf = realloc(d->fixes, cap * sizeof *nf);
        if (!nf) {
            fl->failed = 1;
            d->ok[k] |= OK_DROP;
            return;
        }
        d->fixes = nf;
        d->fixcap = cap;
    }
    const ptrdiff_t w = d->w, step[4] = {-1, 1, -w, w};
    const size_t q = (size_t)((ptrdiff_t)k + step[n]);
    const double dx = n == 0 ? 1 : n == 1 ? -1 : 0, dy = n == 2 ? 1 : n == 3 ? -1 : 0;
    const float *jq = d->jac + 4 * q;
    fix *f = (fix *)d->fixes + fl->n++;
    f->k = k;
    f->su = d->su[q] + jq[0] * dx + jq[1] * dy;
    f->sv = d->sv[q] + jq[2] * dx + jq[3] * dy;
    memcpy(f->jac, jq, sizeof f->jac);
    f->adet = d->adet[q];
}

#if defined(__SSE2__)
/* Lanes where a > adet and the id is the same, at the neighbours `s` away from four pixels. */
static inline __m128 exceeds(const int *jid, const float *adet, ptrdiff_t s, __m128 a, __m128i id)
{
    const __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + s)), id);
    return _mm_and_ps(_mm_cmpgt_ps(a, _mm_loadu_ps(adet + s)), _mm_castsi128_ps(same));
}

/* outlier_source's first test for pixels k .. k + 3, whose neighbours are all held: a bit a
 * pixel that may be an outlier. */
static inline int outlier_mask4(const pixdata *d, ptrdiff_t k)
{
    const ptrdiff_t w = d->w;
    const int *jid = d->jid + k;
    const float *adet = d->adet + k;
    const __m128i id = _mm_loadu_si128((const __m128i *)jid);
    const __m128 a = _mm_mul_ps(_mm_loadu_ps(adet), _mm_set1_ps(1.0f / OUTLIER));
    __m128 hit = _mm_or_ps(exceeds(jid, adet, -1, a, id), exceeds(jid, adet, 1, a, id));
    hit = _mm_or_ps(hit, _mm_or_ps(exceeds(jid, adet, -w, a, id), exceeds(jid, adet, w, a, id)));
    hit = _mm_andnot_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(id, _mm_set1_epi32(NO_ID))), hit);
    return _mm_movemask_ps(hit);
}
#endif

/* Such a pixel takes the surface of that neighbour instead: its UV extrapolated from the
 * neighbour's UV and derivatives, and those derivatives, so it owns its share of the surface
 * like the pixels around (and is marked OK_SEAM, so the corners it shares with the other side
 * of a seam are checked). Every repair is computed from the values before any repair, on M,
 * from the derivatives of D1 (M plus 1) as computed: the same whatever the units. The search
 * records each repair as it finds it (the values are all read before any is stored), four
 * pixels at a time where SSE2 is there: a group none of whose pixels is an outlier, the usual
 * case, is done with one test. */
static void repair_outliers(pixdata *d, nprfx_rect M)
{
    fixlist fl = {d, 0, 0};
#if defined(__SSE2__)
    /* the columns whose left and right neighbours are held */
    const int xa = M.x0 - 1 >= d->r.x0 ? M.x0 : d->r.x0 + 1;
    const int xb = M.x1 + 1 <= d->r.x1 ? M.x1 : d->r.x1 - 1;
#endif
    for (int y = M.y0; y < M.y1; y++) {
        const int up = y - 1 >= d->r.y0, down = y + 1 < d->r.y1;
        const ptrdiff_t k0 = (ptrdiff_t)pd_at(d, M.x0, y);
        int x = M.x0;
#if defined(__SSE2__)
        if (up && down) {
            for (; x < xa; x++) {
                const int n = outlier_source(d, k0 + (x - M.x0), x, up, down);
                if (n) record_fix(&fl, (size_t)(k0 + (x - M.x0)), n - 1);
            }
            for (; x + 4 <= xb; x += 4) {
                const ptrdiff_t k = k0 + (x - M.x0);
                for (int m = outlier_mask4(d, k), i = 0; m; i++, m >>= 1) {
                    const int n = m & 1 ? outlier_source(d, k + i, x + i, up, down) : 0;
                    if (n) record_fix(&fl, (size_t)(k + i), n - 1);
                }
            }
        }
#endif
        for (; x < M.x1; x++) {
            const int n = outlier_source(d, k0 + (x - M.x0), x, up, down);
            if (n) record_fix(&fl, (size_t)(k0 + (x - M.x0)), n - 1);
        }
    }
    const fix *fx = d->fixes;
    if (fl.failed) { /* no room for them all: drop them instead (they own nothing) */
        for (size_t i = 0; i < fl.n; i++)
            d->ok[fx[i].k] |= OK_DROP;
        for (int y = M.y0; y < M.y1; y++) {
            size_t k = pd_at(d, M.x0, y);
            for (int x = M.x0; x < M.x1; x++, k++)
                if (d->ok[k] & OK_DROP)
                    d->jid[k] = NO_ID, d->ok[k] &= (unsigned char)~(OK_J | OK_DROP);
        }
        return;
    }
    for (size_t i = 0; i < fl.n; i++) {
        size_t k = fx[i].k;
        d->su[k] = fx[i].su;
        d->sv[k] = fx[i].sv;
        memcpy(d->jac + 4 * k, fx[i].jac, sizeof fx[i].jac);
        d->adet[k] = fx[i].adet;
        d->ok[k] |= OK_SEAM;
    }
}

#if defined(__SSE2__)
/* The horizontal pass of smooth_area for pixels k .. k + 3 (one lane each), whose +-SMOOTH
 * neighbours are all held: the sum of adet over the same-id pixels, and their count (summed as
 * an integer: the float sum of 1s is exact), both 0 where the pixel has no usable
 * derivatives. */
static inline void horizontal4(const int *jid, const float *adet, float *hs, float *hc, size_t k)
{
    const __m128i vid = _mm_loadu_si128((const __m128i *)(jid + k));
    __m128 vs = _mm_setzero_ps();
    __m128i vc = _mm_setzero_si128();
    for (int dx = -SMOOTH; dx <= SMOOTH; dx++) {
        const __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + k + dx)), vid);
        vs = _mm_add_ps(vs, _mm_and_ps(_mm_castsi128_ps(same), _mm_loadu_ps(adet + k + dx)));
        vc = _mm_sub_epi32(vc, same);
    }
    const __m128 none = _mm_castsi128_ps(_mm_cmpeq_epi32(vid, _mm_set1_epi32(NO_ID)));
    _mm_storeu_ps(hs + k, _mm_andnot_ps(none, vs));
    _mm_storeu_ps(hc + k, _mm_andnot_ps(none, _mm_cvtepi32_ps(vc)));
}

/* The vertical pass of smooth_area for pixels k .. k + 3 (one lane each) over rows lo .. hi
 * around them: cnt > 0 ? sum / cnt : 0, and 0 where the pixel has no usable derivatives. */
static inline __m128 vertical4(const int *jid, const float *hs, const float *hc, ptrdiff_t k,
                               ptrdiff_t w, int lo, int hi)
{
    const __m128i vid = _mm_loadu_si128((const __m128i *)(jid + k));
    __m128 vs = _mm_setzero_ps(), vc = _mm_setzero_ps();
    for (int dy = lo; dy <= hi; dy++) {
        const ptrdiff_t q = k + dy * w;
        const __m128 same =
            _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + q)), vid));
        vs = _mm_add_ps(vs, _mm_and_ps(same, _mm_loadu_ps(hs + q)));
        vc = _mm_add_ps(vc, _mm_and_ps(same, _mm_loadu_ps(hc + q)));
    }
    const __m128 use = _mm_andnot_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(vid, _mm_set1_epi32(NO_ID))),
                                     _mm_cmpgt_ps(vc, _mm_setzero_ps()));
    return _mm_and_ps(use, _mm_div_ps(vs, vc));
}
#endif

/* The area scale |det J| averaged over the same-object pixels of a (2 SMOOTH + 1)^2 window
 * (a horizontal pass within the object, then a vertical one), for the density thresholds only.
 * UV passes are often stored as half floats, whose steps make per-pixel differences of a slowly
 * varying UV jump by factors of two; the kept prefix would then change from pixel to pixel,
 * which scatters the dots like white noise. Needs adet on E plus SMOOTH; writes out[] over E.
 * Sums start at +0 and add values >= +0 (|det|, and sums of them), so adding +0 for a pixel
 * that does not count gives the same float as skipping it: the interior loops test without
 * branching, four pixels at a time where SSE2 is there, each lane adding in the scalar
 * order. */
static void smooth_area(pixdata *d, nprfx_rect E, nprfx_rect R, float *out)
{
    const ptrdiff_t w = d->w;
    const int *restrict jid = d->jid;
    const float *restrict adet = d->adet;
    float *restrict hs = d->hs, *restrict hc = d->hc;
    /* columns of E whose +-SMOOTH neighbours are all held */
    const int xa = E.x0 - SMOOTH >= d->r.x0 ? E.x0 : d->r.x0 + SMOOTH;
    const int xb = E.x1 + SMOOTH <= d->r.x1 ? E.x1 : d->r.x1 - SMOOTH;
    for (int y = R.y0; y < R.y1; y++) {
        const size_t k0 = pd_at(d, E.x0, y);
        for (int x = E.x0; x < E.x1; x++) {
            const size_t k = k0 + (size_t)(x - E.x0);
#if defined(__SSE2__)
            if (x >= xa && x + 4 <= xb) {
                horizontal4(jid, adet, hs, hc, k);
                x += 3;
                continue;
            }
#endif
            float sum = 0, cnt = 0;
            const int id = jid[k];
            if (id == NO_ID) {
            } else if (x >= xa && x < xb) {
                for (int dx = -SMOOTH; dx <= SMOOTH; dx++) {
                    const int same = jid[k + dx] == id;
                    sum += same ? adet[k + dx] : 0.0f;
                    cnt += same ? 1.0f : 0.0f;
                }
            } else {
                int lo = x - SMOOTH < d->r.x0 ? d->r.x0 - x : -SMOOTH;
                int hi = x + SMOOTH >= d->r.x1 ? d->r.x1 - 1 - x : SMOOTH;
                for (int dx = lo; dx <= hi; dx++)
                    if (jid[k + dx] == id) {
                        sum += adet[k + dx];
                        cnt += 1;
                    }
            }
            hs[k] = sum;
            hc[k] = cnt;
        }
    }
    int ew = nprfx_rect_width(E);
    for (int y = E.y0; y < E.y1; y++) {
        int lo = y - SMOOTH < R.y0 ? R.y0 - y : -SMOOTH;
        int hi = y + SMOOTH >= R.y1 ? R.y1 - 1 - y : SMOOTH;
        const ptrdiff_t k0 = (ptrdiff_t)pd_at(d, E.x0, y);
        float *restrict o = out + (size_t)(y - E.y0) * ew;
        int i = 0;
#if defined(__SSE2__)
        if (lo == -SMOOTH && hi == SMOOTH) /* the usual row: the taps unrolled */
            for (; i + 4 <= ew; i += 4)
                _mm_storeu_ps(o + i, vertical4(jid, hs, hc, k0 + i, w, -SMOOTH, SMOOTH));
        for (; i + 4 <= ew; i += 4)
            _mm_storeu_ps(o + i, vertical4(jid, hs, hc, k0 + i, w, lo, hi));
#endif
        for (; i < ew; i++) {
            const ptrdiff_t k = k0 + i;
            float sum = 0, cnt = 0;
            const int id = jid[k];
            if (id != NO_ID)
                for (int dy = lo; dy <= hi; dy++) {
                    const ptrdiff_t q = k + dy * w;
                    const int same = jid[q] == id;
                    sum += same ? hs[q] : 0.0f;
                    cnt += same ? hc[q] : 0.0f;
                }
            o[i] = cnt > 0 ? sum / cnt : 0.0f;
        }
    }
}

/* Is (u, v) more than half a pixel, measured with pixel k's own derivatives, from where pixel
 * k's derivatives put the corner at offset (ox, oy) pixels? Then the corner straddles a UV seam
 * (or a fold) as seen from k. */
int internal_stipple_off_corner(const pixdata *d, size_t k, double ox, double oy, double u,
                                double v)
{
    const float *jc = d->jac + 4 * k;
    double du = u - (d->su[k] + jc[0] * ox + jc[1] * oy);
    double dv = v - (d->sv[k] + jc[2] * ox + jc[3] * oy);
    /* J^-1 (du, dv), within half a pixel: compared as |adj(J) (du, dv)| <= |det| / 2 */
    double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2];
    double px = jc[3] * du - jc[1] * dv, py = -jc[2] * du + jc[0] * dv;
    double lim = 0.5 * fabs(det);
    return !(fabs(px) <= lim && fabs(py) <= lim);
}

/* The corner whose top-left pixel is k: good where the 2x2 pixels around it are one object with
 * usable derivatives, and agree on it (the reference for the fast path in cgrid_fill). */
static void cgrid_corner(cgrid *g, const pixdata *d, size_t i, size_t k0)
{
    static const double ox[4] = {0.5, -0.5, 0.5, -0.5}, oy[4] = {0.5, 0.5, -0.5, -0.5};
    const size_t w = (size_t)d->w;
    size_t k[4] = {k0, k0 + 1, k0 + w, k0 + w + 1};
    g->good[i] = 0;
    /* the 2x2 pixels around the corner: one object, all with usable derivatives */
    int id = d->jid[k[0]];
    if (id == NO_ID || d->jid[k[1]] != id || d->jid[k[2]] != id || d->jid[k[3]] != id) return;
    double u = ((d->su[k[0]] + d->su[k[1]]) + (d->su[k[2]] + d->su[k[3]])) * 0.25;
    double v = ((d->sv[k[0]] + d->sv[k[1]]) + (d->sv[k[2]] + d->sv[k[3]])) * 0.25;
    /* the seam test, only where a pixel's differences hinted at one */
    int good = 1;
    if ((d->ok[k[0]] | d->ok[k[1]] | d->ok[k[2]] | d->ok[k[3]]) & OK_SEAM)
        for (int q = 0; q < 4 && good; q++)
            if (internal_stipple_off_corner(d, k[q], ox[q], oy[q], u, v)) good = 0;
    g->gu[i] = u;
    g->gv[i] = v;
    g->good[i] = (unsigned char)good;
}

/* Corners whose 2x2 pixels are not all held are not good. Four at a time where SSE2 is there:
 * a group that is good without a seam test (the usual case) is stored from the lanes, each
 * corner's two horizontal pair sums then their sum, as cgrid_corner adds them; any other group
 * goes to cgrid_corner. */
static void cgrid_fill(cgrid *g, const pixdata *d)
{
    /* the columns gx whose 2x2 pixels (columns xa, xa + 1, xa = E.x0 + gx - 1) are held */
    int ga = d->r.x0 - (g->E.x0 - 1), gb = d->r.x1 - 1 - (g->E.x0 - 1);
    ga = ga < 0 ? 0 : ga;
    gb = gb > g->gw ? g->gw : gb;
    for (int gy = 0; gy < g->gh; gy++) {
        const int ya = g->E.y0 + gy - 1;
        const size_t i0 = (size_t)gy * g->gw;
        unsigned char *good = g->good + i0;
        if (ya < d->r.y0 || ya + 1 >= d->r.y1 || gb <= ga) {
            memset(good, 0, (size_t)g->gw);
            continue;
        }
        memset(good, 0, (size_t)ga);
        if (gb < g->gw) memset(good + gb, 0, (size_t)(g->gw - gb));
        const size_t k0 = pd_at(d, g->E.x0 + ga - 1, ya);
        int gx = ga;
#if defined(__SSE2__)
        const size_t w = (size_t)d->w;
        const int *restrict jid = d->jid + k0;
        const unsigned char *restrict ok = d->ok + k0;
        const double *restrict su = d->su + k0, *restrict sv = d->sv + k0;
        double *restrict gu = g->gu + i0, *restrict gv = g->gv + i0;
        const __m128i none = _mm_set1_epi32(NO_ID);
        const __m128d quarter = _mm_set1_pd(0.25);
        for (; gx + 4 <= gb; gx += 4) {
            const size_t k = (size_t)(gx - ga);
            const __m128i id = _mm_loadu_si128((const __m128i *)(jid + k));
            __m128i same = _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + k + 1)), id);
            same = _mm_and_si128(
                same, _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + k + w)), id));
            same = _mm_and_si128(
                same, _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(jid + k + w + 1)), id));
            same = _mm_andnot_si128(_mm_cmpeq_epi32(id, none), same);
            /* per corner, the OR of its four pixels' ok, in one byte each */
            const uint32_t seam = (load_u32(ok + k) | load_u32(ok + k + 1) | load_u32(ok + k + w) |
                                   load_u32(ok + k + w + 1)) &
                                  (uint32_t)OK_SEAM * 0x01010101u;
            if (_mm_movemask_epi8(same) != 0xffff || seam) {
                for (int e = 0; e < 4; e++)
                    cgrid_corner(g, d, i0 + (size_t)(gx + e), k0 + k + (size_t)e);
                continue;
            }
            const double *a = su + k, *b = su + k + w;
            __m128d t0 = _mm_add_pd(_mm_loadu_pd(a), _mm_loadu_pd(a + 1));
            __m128d t1 = _mm_add_pd(_mm_loadu_pd(a + 2), _mm_loadu_pd(a + 3));
            __m128d b0 = _mm_add_pd(_mm_loadu_pd(b), _mm_loadu_pd(b + 1));
            __m128d b1 = _mm_add_pd(_mm_loadu_pd(b + 2), _mm_loadu_pd(b + 3));
            _mm_storeu_pd(gu + gx, _mm_mul_pd(_mm_add_pd(t0, b0), quarter));
            _mm_storeu_pd(gu + gx + 2, _mm_mul_pd(_mm_add_pd(t1, b1), quarter));
            a = sv + k, b = sv + k + w;
            t0 = _mm_add_pd(_mm_loadu_pd(a), _mm_loadu_pd(a + 1));
            t1 = _mm_add_pd(_mm_loadu_pd(a + 2), _mm_loadu_pd(a + 3));
            b0 = _mm_add_pd(_mm_loadu_pd(b), _mm_loadu_pd(b + 1));
            b1 = _mm_add_pd(_mm_loadu_pd(b + 2), _mm_loadu_pd(b + 3));
            _mm_storeu_pd(gv + gx, _mm_mul_pd(_mm_add_pd(t0, b0), quarter));
            _mm_storeu_pd(gv + gx + 2, _mm_mul_pd(_mm_add_pd(t1, b1), quarter));
            memset(good + gx, 1, 4);
        }
#endif
        for (; gx < gb; gx++)
            cgrid_corner(g, d, i0 + (size_t)gx, k0 + (size_t)(gx - ga));
    }
}

int internal_stipple_prepare(const sjob *j, scratch *s, nprfx_rect E)
{
    nprfx_rect frame = j->in->frame;
    /* usable derivatives are needed on E plus 1 (corners) and plus SMOOTH (densities): that
     * is M; telling whether a derivative is usable takes those of the neighbours (D1), and
     * each derivative the UVs around it (D) */
    const int mj = SMOOTH > 1 ? SMOOTH : 1;
    nprfx_rect M =
        nprfx_rect_intersect(frame, nprfx_rect_make(E.x0 - mj, E.y0 - mj, E.x1 + mj, E.y1 + mj));
    nprfx_rect D1 = nprfx_rect_intersect(
        frame, nprfx_rect_make(E.x0 - mj - 1, E.y0 - mj - 1, E.x1 + mj + 1, E.y1 + mj + 1));
    nprfx_rect D = nprfx_rect_intersect(
        frame, nprfx_rect_make(E.x0 - mj - 2, E.y0 - mj - 2, E.x1 + mj + 2, E.y1 + mj + 2));
    int ew = nprfx_rect_width(E), eh = nprfx_rect_height(E);
    pixdata *d = &s->d;
    cgrid *g = &s->g;
    size_t gn = (size_t)(ew + 1) * (size_t)(eh + 1), c = s->gcap;
    int ok = pixdata_reserve(d, D);
    ok &= internal_stipple_reserve((void **)&g->gu, &c, gn, sizeof(double));
    c = s->gcap, ok &= internal_stipple_reserve((void **)&g->gv, &c, gn, sizeof(double));
    c = s->gcap, ok &= internal_stipple_reserve((void **)&g->good, &c, gn, 1);
    s->gcap = ok ? (gn > s->gcap ? gn : s->gcap) : 0;
    ok &= internal_stipple_reserve((void **)&s->sdet, &s->scap, (size_t)ew * (size_t)eh,
                                   sizeof(float));
    if (!ok) return 0;
    fill_raw(j, d, E);
    fill_jacobian(d, D1);
    repair_outliers(d, M);
    smooth_area(d, E, M, s->sdet);
    g->E = E;
    g->gw = ew + 1;
    g->gh = eh + 1;
    cgrid_fill(g, d);
    return 1;
}
