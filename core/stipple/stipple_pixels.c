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
#include "nprfx/objectid.h"
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
    free(s->aniso);
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

/* The object a pixel's id value names: its number (nprfx/objectid.h, all 32 bits) as an int,
 * NO_OBJECT for arithmetic's NaNs. Never NO_ID: no id's number is 0x80000000. */
#define NO_OBJECT ((int)NPRFX_ID_NONE)
static inline int id_of(float v)
{
    return (int)nprfx_id_to_uint(v);
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

/* Where each group of pixels moves every range on by at most a line (packed inputs: 4 pixels of
 * UV are 32 bytes), AHEAD's loop runs 0 or 1 times from group to group, which the branch
 * predictor misses about once a group (a third of fill_raw's time with uv and id connected).
 * Then one prefetch a range and group instead, of the line holding the group's end (clamped,
 * branch-free): every line is still fetched, some twice, which costs next to nothing. */
#define AHEAD_DENSE(a, r, px)                                                                      \
    do {                                                                                           \
        const uintptr_t t_ = (a).lo[r] + (uintptr_t)(px) * (uintptr_t)(a).bpp[r];                  \
        PREFETCH(t_ < (a).hi[r] ? t_ : (a).hi[r]);                                                 \
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
    if (!isfinite(u) || !isfinite(v) || st->pid == NO_OBJECT) {
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

/* The darkness of the owners of a row (the columns [gx0, gx1); owner_build and the limits
 * read it nowhere else, so only those read the tone), k0 the row's first held pixel: four at a
 * time where there is SSE2 (two a vector), 0 where the pixel has no UV. */
static void raw_darkness(const rawstate *c, pixdata *d, size_t k0, const rowsrc *sto, int gx0,
                         int gx1)
{
    if (gx1 <= gx0) return;
    const int m = gx1 - gx0, luma = c->luma;
    const ptrdiff_t ts = sto->ps;
    const float *q = sto->p + (ptrdiff_t)(gx0 - d->r.x0) * ts;
    const size_t kg = k0 + (size_t)(gx0 - d->r.x0);
    const float *curve = c->p->tone_curve;
    float *restrict g = d->g + kg;
    const unsigned char *restrict okg = d->ok + kg;
    int i = 0;
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
    int dense = 1;
    for (int m = 0; m < a.n; m++)
        dense &= 4 * a.bpp[m] <= 64;
    for (; i + 4 <= n; i += 4) {
        if (dense)
            for (int m = 0; m < a.n; m++)
                AHEAD_DENSE(a, m, i + 4);
        else
            for (int m = 0; m < a.n; m++)
                AHEAD(a, line, m, i + 4);
        const float *p = qi + i * is, *q = qu + i * us;
        const __m128 iv = _mm_setr_ps(p[0], p[is], p[2 * is], p[3 * is]);
        if (_mm_movemask_ps(_mm_cmpeq_ps(iv, _mm_set1_ps(st.prev))) == 15 && st.pid != NO_OBJECT &&
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
#if defined(__SSE2__)
        if (dense) {
            for (int m = 0; m < a.n; m++)
                AHEAD_DENSE(a, m, i + 1);
        } else
#endif
            for (int m = 0; m < a.n; m++)
                AHEAD(a, line, m, i + 1);
        raw_pixel(c, &st, qi + i * is, qu + i * us, id, su, sv, ok, i);
    }
    c->last_id = st.last_id, c->off_u = st.off_u, c->off_v = st.off_v;
    raw_darkness(c, d, k0, sto, gx0, gx1);
}

/* A row of a frame without uv and id inputs (the image is its own UV space, one object 0)
 * that the tone covers: the generic loop's arithmetic, u = (x - frame.x0) / plane_scale a
 * lane each, two at a time with SSE2 (the same division); v, and so sv, is the row's. The
 * caller has checked that u and v are finite over the row (|u| is largest at its ends). */
static void plane_row(rawstate *c, pixdata *d, int y, int fx0, double v, const rowsrc *sto, int gx0,
                      int gx1)
{
    const int n = d->w, x0 = d->r.x0;
    const size_t k0 = pd_at(d, x0, y);
    int *restrict id = d->id + k0;
    double *restrict su = d->su + k0, *restrict sv = d->sv + k0;
    unsigned char *restrict ok = d->ok + k0;
    if (c->last_id != 0) object_offsets(c, 0);
    const double ps = c->p->plane_scale, itu = c->inv_tile_u, ou = c->off_u;
    const double svr = v * c->inv_tile_v + c->off_v;
    int i = 0;
#if defined(__SSE2__)
    const __m128d vps = _mm_set1_pd(ps), vitu = _mm_set1_pd(itu), vou = _mm_set1_pd(ou);
    const __m128d vsv = _mm_set1_pd(svr);
    for (; i + 2 <= n; i += 2) {
        const __m128i xi = _mm_setr_epi32(x0 + i - fx0, x0 + i + 1 - fx0, 0, 0);
        const __m128d u = _mm_div_pd(_mm_cvtepi32_pd(xi), vps);
        _mm_storeu_pd(su + i, _mm_add_pd(_mm_mul_pd(u, vitu), vou));
        _mm_storeu_pd(sv + i, vsv);
    }
#endif
    for (; i < n; i++) {
        const double u = (x0 + i - fx0) / ps;
        su[i] = u * itu + ou;
        sv[i] = svr;
    }
    for (i = 0; i < n; i++)
        id[i] = 0;
    memset(ok, OK_UV, (size_t)n);
    raw_darkness(c, d, k0, sto, gx0, gx1);
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
    c.last_id = NO_ID; /* no object's number: the first sets its offsets */
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
    d->plane = !in->uv && !in->id; /* until a row is not a plane_row */
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
        if (!in->uv && !in->id && sto.lo == x0 && sto.hi == x1) {
            /* the generic loop's u and v, finite over the row where they are at its ends */
            const double v = (y - in->frame.y0) / p->plane_scale;
            if (isfinite(v) && isfinite((x0 - in->frame.x0) / p->plane_scale) &&
                isfinite((x1 - 1 - in->frame.x0) / p->plane_scale)) {
                const int owners = y >= E.y0 && y < E.y1;
                plane_row(&c, d, y, in->frame.x0, v, &sto, owners ? gx0 : 0, owners ? gx1 : 0);
                continue;
            }
        }
        d->plane = 0;
        for (int x = x0; x < x1; x++, k++) {
            d->ok[k] = 0;
            d->g[k] = 0.0f;
            d->id[k] = NO_ID;
            int id = 0; /* no id input, or outside it: object 0 */
            const float *q = row_at(&sid, x);
            if (q) id = id_of(q[0]);
            double u, v;
            if (in->uv) {
                if (!(q = row_at(&suv, x))) continue;
                u = q[0];
                v = q[1];
            } else {
                u = (x - in->frame.x0) / p->plane_scale;
                v = (y - in->frame.y0) / p->plane_scale;
            }
            if (!isfinite(u) || !isfinite(v) || id == NO_OBJECT) continue;
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
    internal_stipple_fill_jacobian(d, D1, j->avx2);
    internal_stipple_repair_outliers(d, M, j->avx2);
    internal_stipple_smooth_area(d, E, M, s->sdet, j->avx2);
    g->E = E;
    g->gw = ew + 1;
    g->gh = eh + 1;
    cgrid_fill(g, d);
    return 1;
}
