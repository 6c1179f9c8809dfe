/* Exact anti-aliased disc coverage for the stipple renderer: each pixel gets the area of the
 * disc inside its square, from the integral of the chord length, so a disc's pixels sum to
 * exactly pi r^2 and overlapping discs multiply their paper (a union of ink). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "internal_stipple.h"

#if defined(__SSE2__)
static inline __m128d select_pd(__m128d mask, __m128d a, __m128d b)
{
    return _mm_or_pd(_mm_and_pd(mask, a), _mm_andnot_pd(mask, b));
}
#endif

/* asin to 2e-8 (Abramowitz & Stegun 4.4.46), exact at +-1. Coverage is a difference of this
 * function's values at pixel edges, so the error cancels from a disc's total, which stays
 * exactly pi r^2: only the split between pixels carries it. libm's asin was a sixth of the
 * whole render time. */
static double asin_fast(double t)
{
    double a = fabs(t);
    double p = -0.0012624911;
    p = p * a + 0.0066700901;
    p = p * a - 0.0170881256;
    p = p * a + 0.0308918810;
    p = p * a - 0.0501743046;
    p = p * a + 0.0889789874;
    p = p * a - 0.2145988016;
    p = p * a + 1.5707963050;
    double r = 1.57079632679489661923 - sqrt(1.0 - a) * p;
    return t < 0 ? -r : r;
}

/* P(X) = integral from 0 to X of sqrt(r^2 - t^2) dt, for |X| <= r. */
static inline double half_chord_integral(double x, double r)
{
    double t = x / r;
    t = t < -1 ? -1 : t > 1 ? 1 : t;
    double h = sqrt(fmax(0.0, r * r - x * x));
    return 0.5 * (x * h + r * r * asin_fast(t));
}

/* half_chord_integral at n points x[] (|x| <= r) into out[]: two at a time where SSE2 is
 * there, each lane doing the scalar functions' own operations (fabs, the clamp and the sign
 * choice as masks), so the results are the same floats. */
static void half_chord_batch(const double *x, double *out, int n, double r)
{
    int k = 0;
#if defined(__SSE2__)
    const __m128d vr = _mm_set1_pd(r), rr = _mm_set1_pd(r * r), one = _mm_set1_pd(1.0);
    const __m128d mone = _mm_set1_pd(-1.0), zero = _mm_setzero_pd(), half = _mm_set1_pd(0.5);
    const __m128d sign = _mm_set1_pd(-0.0), pi2 = _mm_set1_pd(1.57079632679489661923);
    for (; k + 2 <= n; k += 2) {
        __m128d xv = _mm_loadu_pd(x + k);
        __m128d t = _mm_div_pd(xv, vr);
        t = select_pd(_mm_cmplt_pd(t, mone), mone, select_pd(_mm_cmpgt_pd(t, one), one, t));
        __m128d h = _mm_sqrt_pd(_mm_max_pd(_mm_sub_pd(rr, _mm_mul_pd(xv, xv)), zero));
        /* asin_fast(t) */
        __m128d a = _mm_andnot_pd(sign, t);
        __m128d p = _mm_set1_pd(-0.0012624911);
        p = _mm_add_pd(_mm_mul_pd(p, a), _mm_set1_pd(0.0066700901));
        p = _mm_sub_pd(_mm_mul_pd(p, a), _mm_set1_pd(0.0170881256));
        p = _mm_add_pd(_mm_mul_pd(p, a), _mm_set1_pd(0.0308918810));
        p = _mm_sub_pd(_mm_mul_pd(p, a), _mm_set1_pd(0.0501743046));
        p = _mm_add_pd(_mm_mul_pd(p, a), _mm_set1_pd(0.0889789874));
        p = _mm_sub_pd(_mm_mul_pd(p, a), _mm_set1_pd(0.2145988016));
        p = _mm_add_pd(_mm_mul_pd(p, a), _mm_set1_pd(1.5707963050));
        __m128d as = _mm_sub_pd(pi2, _mm_mul_pd(_mm_sqrt_pd(_mm_sub_pd(one, a)), p));
        as = select_pd(_mm_cmplt_pd(t, zero), _mm_xor_pd(as, sign), as);
        __m128d res = _mm_mul_pd(half, _mm_add_pd(_mm_mul_pd(xv, h), _mm_mul_pd(rr, as)));
        _mm_storeu_pd(out + k, res);
    }
#endif
    for (; k < n; k++)
        out[k] = half_chord_integral(x[k], r);
}

/* Row-boundary quantities of the quadrant-area function below. */
typedef struct row_term {
    double y, w, pw;
} row_term;

/* Area of the disc of radius r at the origin within {X <= x, Y <= y}, given px = P(clamp(x))
 * and the row term of y. Integrates the vertical chord length min(y, h) + h over X, split where
 * y crosses the chord (|X| = w = sqrt(r^2 - y^2)). */
static inline double quadrant_area(double x, double px, const row_term *rt, double r, double pr)
{
    double xc = x < -r ? -r : x > r ? r : x;
    if (xc <= -r) return 0.0;
    double y = rt->y;
    if (y >= r) return 2.0 * (px + pr);
    if (y <= -r) return 0.0;
    double w = rt->w, pw = rt->pw, a = 0.0;
    if (xc > -w) { /* the band |X| < w where the chord is cut at y: length y + h */
        double m = xc < w ? xc : w, pm = xc < w ? px : pw;
        a += y * (m + w) + (pm + pw);
    }
    if (y > 0.0) { /* outside that band the whole chord lies below y: length 2h */
        a += 2.0 * ((xc < -w ? px : -pw) + pr);
        if (xc > w) a += 2.0 * (px - pw);
    }
    return a;
}

/* quadrant_area at the column boundaries xs[0..nx) (with pxs = P(clamped xs)) for one row
 * boundary: whole rows at once, two columns at a time where SSE2 is there, each lane doing
 * quadrant_area's own operations (its branches become selects), so the results are the same
 * floats. */
static void quadrant_row(const double *xs, const double *pxs, int nx, const row_term *rt, double r,
                         double pr, double *out)
{
    const double y = rt->y;
    int k = 0;
    if (y <= -r) {
        for (; k < nx; k++)
            out[k] = 0.0;
        return;
    }
    if (y >= r) {
        for (; k < nx; k++)
            out[k] = xs[k] <= -r ? 0.0 : 2.0 * (pxs[k] + pr);
        return;
    }
#if defined(__SSE2__)
    const double w = rt->w, pw = rt->pw;
    const __m128d vr = _mm_set1_pd(r), vnr = _mm_set1_pd(-r), vw = _mm_set1_pd(w);
    const __m128d vnw = _mm_set1_pd(-w), vpw = _mm_set1_pd(pw), vnpw = _mm_set1_pd(-pw);
    const __m128d vy = _mm_set1_pd(y), vpr = _mm_set1_pd(pr), two = _mm_set1_pd(2.0);
    const __m128d zero = _mm_setzero_pd();
    for (; k + 2 <= nx; k += 2) {
        __m128d x = _mm_loadu_pd(xs + k), px = _mm_loadu_pd(pxs + k);
        __m128d xc = select_pd(_mm_cmplt_pd(x, vnr), vnr, select_pd(_mm_cmpgt_pd(x, vr), vr, x));
        __m128d inb = _mm_cmplt_pd(xc, vw);
        __m128d m = select_pd(inb, xc, vw), pm = select_pd(inb, px, vpw);
        __m128d t1 = _mm_add_pd(_mm_mul_pd(vy, _mm_add_pd(m, vw)), _mm_add_pd(pm, vpw));
        __m128d a = select_pd(_mm_cmpgt_pd(xc, vnw), _mm_add_pd(zero, t1), zero);
        if (y > 0.0) {
            __m128d q = select_pd(_mm_cmplt_pd(xc, vnw), px, vnpw);
            a = _mm_add_pd(a, _mm_mul_pd(two, _mm_add_pd(q, vpr)));
            __m128d t3 = _mm_mul_pd(two, _mm_sub_pd(px, vpw));
            a = select_pd(_mm_cmpgt_pd(xc, vw), _mm_add_pd(a, t3), a);
        }
        _mm_storeu_pd(out + k, select_pd(_mm_cmple_pd(xc, vnr), zero, a));
    }
#endif
    for (; k < nx; k++)
        out[k] = quadrant_area(xs[k], pxs[k], rt, r, pr);
}

/* The coverage of the disc of radius r at (cx, cy) over the pixels it touches, clipped to
 * rect: calls put(user, x, y, c) for each pixel (x, y) of the clipped box, c = 0 where the disc
 * misses it. Pixel (i, j) is the unit square centred on (i, j). */
static inline void disc_coverage(nprfx_rect rect, double cx, double cy, double r,
                                 void (*put)(void *, int, int, double), void *user)
{
    int i0 = (int)floor(cx - r - 0.5) + 1, i1 = (int)ceil(cx + r + 0.5) - 1;
    int j0 = (int)floor(cy - r - 0.5) + 1, j1 = (int)ceil(cy + r + 0.5) - 1;
    int ci0 = i0 > rect.x0 ? i0 : rect.x0, ci1 = i1 < rect.x1 - 1 ? i1 : rect.x1 - 1;
    int cj0 = j0 > rect.y0 ? j0 : rect.y0, cj1 = j1 < rect.y1 - 1 ? j1 : rect.y1 - 1;
    if (ci0 > ci1 || cj0 > cj1 || !(r > 0)) return;
    int nx = ci1 - ci0 + 2, ny = cj1 - cj0 + 2;
    double xs[64], pxs[64];
    row_term rows[64];
    if (nx > 64 || ny > 64) return; /* radius capped by the params' hard range */
    /* P(+-r) = +-r^2 asin(1) / 2: what half_chord_integral gives there, without its work
     * (x / r is exactly +-1, the chord 0, asin_fast(+-1) exactly +-pi/2) */
    const double p_edge = 0.5 * (r * r * asin_fast(1.0));
    /* the arguments of the non-trivial P values, columns' then rows', evaluated together */
    double arg[128], val[128];
    int na = 0;
    for (int k = 0; k < nx; k++) {
        xs[k] = (ci0 + k - 0.5) - cx;
        if (xs[k] <= -r)
            pxs[k] = -p_edge;
        else if (xs[k] >= r)
            pxs[k] = p_edge;
        else
            arg[na++] = xs[k];
    }
    const int ncol = na;
    for (int k = 0; k < ny; k++) {
        double y = (cj0 + k - 0.5) - cy;
        rows[k].y = y;
        /* w and pw are read only for |y| < r (quadrant_area) */
        rows[k].w = fabs(y) < r ? sqrt(r * r - y * y) : 0.0;
        rows[k].pw = 0.0;
        if (fabs(y) < r) arg[na++] = rows[k].w;
    }
    half_chord_batch(arg, val, na, r);
    for (int k = 0, i = 0; k < nx; k++)
        if (xs[k] > -r && xs[k] < r) pxs[k] = val[i++];
    for (int k = 0, i = ncol; k < ny; k++)
        if (fabs(rows[k].y) < r) rows[k].pw = val[i++];
    double pr = 0.25 * PI_D * r * r;
    /* the quadrant areas at the pixel corners, a row of corners at a time (independent
     * evaluations first, then the differences: the same arithmetic as one running pass) */
    double qa[2][65];
    double *prev_row = qa[0], *cur_row = qa[1];
    quadrant_row(xs, pxs, nx, &rows[0], r, pr, prev_row);
    for (int jr = 1; jr < ny; jr++) {
        quadrant_row(xs, pxs, nx, &rows[jr], r, pr, cur_row);
        for (int k = 1; k < nx; k++) {
            double c = cur_row[k] - cur_row[k - 1] - prev_row[k] + prev_row[k - 1];
            put(user, ci0 + k - 1, cj0 + jr - 1, c < 0 ? 0 : c > 1 ? 1 : c);
        }
        double *swap = prev_row;
        prev_row = cur_row;
        cur_row = swap;
    }
}

typedef struct splat_target {
    float *t;
    nprfx_rect rect;
    double tone;
} splat_target;

/* a pixel the disc misses has c = 0 and is multiplied by exactly 1: no branch */
static inline void put_splat(void *user, int x, int y, double c)
{
    const splat_target *s = user;
    s->t[(size_t)(y - s->rect.y0) * (size_t)(s->rect.x1 - s->rect.x0) + (size_t)(x - s->rect.x0)] *=
        (float)(1.0 - c * s->tone);
}

/* Multiply T (rows [rect.y0, rect.y1) x cols [rect.x0, rect.x1), row stride = width) by
 * (1 - coverage * tone) over the pixels the disc touches. */
void internal_stipple_splat_disc(float *t, nprfx_rect rect, double cx, double cy, double r,
                                 double tone)
{
    splat_target s = {t, rect, tone};
    disc_coverage(rect, cx, cy, r, put_splat, &s);
}

/* ---- discs from tables ----
 *
 * Uniform and multitone dots all have one radius, so a dot's coverage depends only on where its
 * centre falls within its pixel. A table holds the exact coverage (above) of the phases^2
 * centres (i + a / phases, j + b / phases), and a dot is drawn with the stencil of the nearest
 * one: its centre moves by at most half a phase (1/64 px), its ink still sums to exactly its
 * area, and the drawing is a few multiplies a pixel instead of the chord integrals (which were
 * a third of the render). Radius dots (area g a0) take two tables of neighbouring areas, mixed
 * so that the ink is again exactly the dot's area (below). */

typedef struct stencil_fill {
    double *c;
    int x0, y0, s;
} stencil_fill;

static void put_stencil(void *user, int x, int y, double c)
{
    const stencil_fill *f = user;
    f->c[(size_t)(y - f->y0) * (size_t)f->s + (size_t)(x - f->x0)] = c;
}

/* The pixels any centre in [0, 1)^2 touches with a disc of radius `extent`: i0 = floor(c - r -
 * 0.5) + 1 from c = 0, i1 = ceil(c + r + 0.5) - 1 up to c = 1. */
static void stencil_span(double extent, int *lo, int *size)
{
    *lo = (int)floor(-extent - 0.5) + 1;
    *size = (int)ceil(1.0 + extent + 0.5) - 1 - *lo + 1;
}

int internal_stipple_stencils_fits(double extent)
{
    int lo, size;
    stencil_span(extent, &lo, &size);
    return extent > 0 && size <= STENCIL_MAX;
}

int internal_stipple_stencils_init(internal_stencils *st, double r, int phases, double extent)
{
    st->cov = NULL;
    st->r = r;
    st->phases = phases;
    st->shift = 0;
    while ((1 << st->shift) < phases)
        st->shift++;
    stencil_span(extent, &st->lo, &st->size);
    if (!(r >= 0) || !(extent >= r) || st->size > STENCIL_MAX) return 0; /* drawn exactly */
    if (phases < 1 || (1 << st->shift) != phases) return 0;              /* stencil_place shifts */
    const int s = st->size, n = s * s;
    st->cov = calloc((size_t)n * (size_t)phases * (size_t)phases, sizeof(float));
    double *c = malloc(sizeof(double) * (size_t)n);
    if (!st->cov || !c) {
        free(st->cov);
        free(c);
        st->cov = NULL;
        return -1;
    }
    for (int b = 0; b < phases && r > 0; b++)
        for (int a = 0; a < phases; a++) {
            for (int k = 0; k < n; k++)
                c[k] = 0;
            stencil_fill f = {c, st->lo, st->lo, s};
            disc_coverage(nprfx_rect_make(st->lo, st->lo, st->lo + s, st->lo + s),
                          (double)a / phases, (double)b / phases, r, put_stencil, &f);
            float *out = st->cov + (size_t)(b * phases + a) * (size_t)n;
            for (int k = 0; k < n; k++)
                out[k] = (float)c[k];
        }
    free(c);
    return 1;
}

void internal_stipple_stencils_free(internal_stencils *st)
{
    free(st->cov);
    st->cov = NULL;
}

/* floor(q / 2^shift) for |q| < 2^40, shift <= 40, without a division: a bias that is a
 * multiple of 2^shift makes q non-negative, where an unsigned shift is a floor division. The
 * phase is then q minus that times 2^shift. (A division by the phase count was a 64-bit idiv,
 * two per stencil placed: tens of cycles each, over 300,000 dots a frame.) */
static inline long long floor_shift(long long q, int shift)
{
    const long long bias = 1LL << 40;
    return (long long)((unsigned long long)(q + bias) >> shift) - (bias >> shift);
}

/* Where the stencil of a dot at (cx, cy) goes: its coverages, its first pixel (x0, y0), and
 * the part of it inside rect, [cx0, cx1) x [cy0, cy1); 0 when nothing is inside. The nearest
 * phase is floor(c P + 0.5), taken as a truncation corrected by one below zero (the same
 * integer as floor() for |c P + 0.5| < 1e9, without a libm call); beyond that the dot is far
 * outside any frame. */
static inline int stencil_place(const internal_stencils *st, nprfx_rect rect, double cx, double cy,
                                const float **cov, long long *x0, long long *y0, int *cx0, int *cx1,
                                int *cy0, int *cy1)
{
    const int P = st->phases, sh = st->shift;
    const double vx = cx * P + 0.5, vy = cy * P + 0.5;
    if (!(fabs(vx) < 1e9 && fabs(vy) < 1e9)) return 0; /* far outside any frame, or NaN */
    long long qx = (long long)vx, qy = (long long)vy;
    qx -= vx < (double)qx;
    qy -= vy < (double)qy;
    /* centre (ix + a / P, iy + b / P) */
    const long long ix = floor_shift(qx, sh), iy = floor_shift(qy, sh);
    const int a = (int)(qx - ix * P), b = (int)(qy - iy * P);
    const int s = st->size;
    *x0 = ix + st->lo;
    *y0 = iy + st->lo;
    *cx0 = *x0 > rect.x0 ? (int)*x0 : rect.x0;
    *cx1 = *x0 + s < rect.x1 ? (int)(*x0 + s) : rect.x1;
    *cy0 = *y0 > rect.y0 ? (int)*y0 : rect.y0;
    *cy1 = *y0 + s < rect.y1 ? (int)(*y0 + s) : rect.y1;
    *cov = st->cov + (size_t)(b * P + a) * (size_t)(s * s);
    return *cx0 < *cx1 && *cy0 < *cy1;
}

#if defined(__GNUC__) || defined(__clang__)
#define ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define ALWAYS_INLINE inline
#endif

/* A whole stencil of s x s pixels (all inside the tile: the usual case), trow its first pixel
 * in t and `width` the tile's row stride; s is a constant where it is called, so that the rows
 * are straight-line code (a dot was ~340 instructions through the clipped loops, for 16
 * pixels). Four pixels at a time with SSE2, each lane the scalar expression's operations:
 * t *= 1 - c tone, and for radius dots c = w0 c0 + w c1. c1 NULL: one stencil. */
static ALWAYS_INLINE void stencil_whole(float *restrict trow, size_t width,
                                        const float *restrict c0, const float *restrict c1,
                                        float w0, float w, float tf, const int s)
{
#if defined(__SSE2__)
    const __m128 one = _mm_set1_ps(1.0f), vt = _mm_set1_ps(tf);
    const __m128 vw0 = _mm_set1_ps(w0), vw = _mm_set1_ps(w);
#endif
    for (int y = 0; y < s; y++, trow += width, c0 += s, c1 = c1 ? c1 + s : NULL) {
        int x = 0;
#if defined(__SSE2__)
        for (; x + 4 <= s; x += 4) {
            __m128 c = _mm_loadu_ps(c0 + x);
            if (c1) c = _mm_add_ps(_mm_mul_ps(vw0, c), _mm_mul_ps(vw, _mm_loadu_ps(c1 + x)));
            const __m128 f = _mm_sub_ps(one, _mm_mul_ps(c, vt));
            _mm_storeu_ps(trow + x, _mm_mul_ps(_mm_loadu_ps(trow + x), f));
        }
#endif
        for (; x < s; x++) {
            const float c = c1 ? w0 * c0[x] + w * c1[x] : c0[x];
            trow[x] *= 1.0f - c * tf;
        }
    }
}

/* stencil_whole with s a constant for each size a stencil can have. 0 when s is none of them. */
static inline int stencil_whole_any(float *trow, size_t width, const float *c0, const float *c1,
                                    float w0, float w, float tf, int s)
{
    switch (s) {
#define SIZE_CASE(n)                                                                               \
    case n:                                                                                        \
        if (c1)                                                                                    \
            stencil_whole(trow, width, c0, c1, w0, w, tf, n);                                      \
        else                                                                                       \
            stencil_whole(trow, width, c0, NULL, w0, w, tf, n);                                    \
        return 1;
        SIZE_CASE(1)
        SIZE_CASE(2)
        SIZE_CASE(3)
        SIZE_CASE(4)
        SIZE_CASE(5)
        SIZE_CASE(6)
        SIZE_CASE(7)
        SIZE_CASE(8)
#undef SIZE_CASE
    default:
        return 0;
    }
}

void internal_stipple_splat_stencil(float *t, nprfx_rect rect, const internal_stencils *st,
                                    double cx, double cy, double tone)
{
    const float *cov;
    long long x0, y0;
    int cx0, cx1, cy0, cy1;
    if (!stencil_place(st, rect, cx, cy, &cov, &x0, &y0, &cx0, &cx1, &cy0, &cy1)) return;
    const int s = st->size, width = rect.x1 - rect.x0;
    const float tf = (float)tone;
    if (cx0 == x0 && cx1 == x0 + s && cy0 == y0 && cy1 == y0 + s &&
        stencil_whole_any(t + (size_t)(cy0 - rect.y0) * width + (cx0 - rect.x0), (size_t)width, cov,
                          NULL, 0.0f, 0.0f, tf, s))
        return;
    for (int y = cy0; y < cy1; y++) {
        const float *crow = cov + (size_t)(y - y0) * s - x0;
        float *trow = t + (size_t)(y - rect.y0) * width - rect.x0;
        for (int x = cx0; x < cx1; x++)
            trow[x] *= 1.0f - crow[x] * tf;
    }
}

/* ---- radius dots: areas between levels ----
 *
 * A radius dot's area g a0 lies between two of the levels a0 k / RADIUS_LEVELS; the dot is drawn
 * as (1 - w) times the lower level's disc plus w times the upper one's, w the fraction between
 * them: the ink sums to exactly the dot's area, and the two edges, a hair apart, make one. */

int internal_stipple_levels_init(internal_levels *lv, double amax)
{
    memset(lv, 0, sizeof *lv);
    lv->amax = amax;
    const double rmax = sqrt(amax / PI_D);
    if (!internal_stipple_stencils_fits(rmax)) return 0; /* drawn exactly */
    for (int k = 0; k <= RADIUS_LEVELS; k++) {
        const double r = sqrt(amax * k / RADIUS_LEVELS / PI_D);
        if (internal_stipple_stencils_init(&lv->level[k], r, RADIUS_PHASES, rmax) < 0) {
            internal_stipple_levels_free(lv);
            return -1;
        }
    }
    lv->made = 1;
    return 1;
}

void internal_stipple_levels_free(internal_levels *lv)
{
    for (int k = 0; k <= RADIUS_LEVELS; k++)
        internal_stipple_stencils_free(&lv->level[k]);
    lv->made = 0;
}

void internal_stipple_splat_levels(float *t, nprfx_rect rect, const internal_levels *lv, double cx,
                                   double cy, double r, double tone)
{
    double f = PI_D * r * r / lv->amax * RADIUS_LEVELS;
    f = f < 0 ? 0 : f > RADIUS_LEVELS ? RADIUS_LEVELS : f;
    int k = (int)f;
    if (k == RADIUS_LEVELS) k--;
    const float w = (float)(f - k), w0 = 1.0f - w;
    const internal_stencils *lo = &lv->level[k], *hi = &lv->level[k + 1];
    const float *c0, *c1;
    long long x0, y0;
    int cx0, cx1, cy0, cy1;
    if (!stencil_place(lo, rect, cx, cy, &c0, &x0, &y0, &cx0, &cx1, &cy0, &cy1)) return;
    /* the same span and phase (the levels share their extent and phases): the same offset */
    c1 = hi->cov + (c0 - lo->cov);
    const int s = lo->size, width = rect.x1 - rect.x0;
    const float tf = (float)tone;
    if (cx0 == x0 && cx1 == x0 + s && cy0 == y0 && cy1 == y0 + s &&
        stencil_whole_any(t + (size_t)(cy0 - rect.y0) * width + (cx0 - rect.x0), (size_t)width, c0,
                          c1, w0, w, tf, s))
        return;
    for (int y = cy0; y < cy1; y++) {
        const size_t o = (size_t)(y - y0) * s;
        const float *r0 = c0 + o - x0, *r1 = c1 + o - x0;
        float *trow = t + (size_t)(y - rect.y0) * width - rect.x0;
        for (int x = cx0; x < cx1; x++)
            trow[x] *= 1.0f - (w0 * r0[x] + w * r1[x]) * tf;
    }
}
