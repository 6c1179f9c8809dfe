/* Stippling from UV and shading (Ma et al. 2018; DESIGN.md §3.3). stipple.h has the model.
 *
 * A render works in two parallel phases. First the pixels that can reach the window (the window
 * plus a margin of the largest disc radius) are split into units, and each unit finds the
 * stipples its pixels own, in row-major order of the owners, with where each owner row starts;
 * every owner is handled once. Then each tile of the window draws the stipples that reach it,
 * owner row by owner row and unit by unit from the left. Every pixel therefore sees the same
 * stipples in the same order whatever the tile, unit or thread it is rendered in (or the host's
 * own tiling), which makes the output bit-identical across splits. What an owner finds depends
 * only on the inputs within a few pixels of it, which each unit reads with a margin.
 *
 * Speed (1080p, `nprfx bench stipple`): the per-pixel passes read their inputs a row at a time
 * (plates interleave many channels), test neighbours through per-pixel object ids that already
 * say whether the pixel is usable, and add without branching where the result is the same
 * float; owners are queried in blocks whose per-sample tests are branch-free; the disc coverage
 * evaluates its P and quadrant-area terms two at a time with SSE2 where there is SSE2, each
 * lane doing the scalar code's operations, so every build gives the same floats. */
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "nprfx/exec.h"
#include "nprfx/rng.h"
#include "nprfx/stipple.h"

/* Drawing tiles of the window (and the stripes of nprfx_stipple_collect). */
#define STRIPE_ROWS 64
#define TILE_COLS 256
/* Owners are found in units of this many rows and columns, each owner once per render: small
 * enough for their per-pixel data (~70 bytes a pixel) to stay in cache, large enough that the
 * margin of inputs read around each stays cheap. */
#define UNIT_ROWS 64
#define UNIT_COLS 256
#define PI_D 3.14159265358979323846
/* Hash stream of the per-object sequence offsets. */
#define STREAM_OBJECT 0x53544950u

/* ---- parameters ---- */

void nprfx_stipple_params_default(nprfx_stipple_params *p)
{
    memset(p, 0, sizeof *p);
    p->size = sizeof *p;
    p->mode = NPRFX_STIPPLE_UNIFORM;
    p->area = 6.0;
    p->a0 = 6.0;
    p->delta_min = 0.5;
    p->num_tones = 3;
    p->tones[0] = 1.0 / 3.0;
    p->tones[1] = 2.0 / 3.0;
    p->tones[2] = 1.0;
    p->tile = 1.0;
    p->plane_scale = NPRFX_STIPPLE_PLANE_PIXELS;
    p->aspect = 1.0;
    p->ink[3] = 1.0f;
    for (int c = 0; c < 4; c++)
        p->paper[c] = 1.0f;
}

nprfx_result nprfx_stipple_parse_tones(nprfx_context *ctx, const char *text,
                                       nprfx_stipple_params *p)
{
    int n = 0;
    const char *s = text ? text : "";
    double prev = 0.0;
    while (*s) {
        while (*s == ' ' || *s == ',' || *s == '\t')
            s++;
        if (!*s) break;
        char *end;
        double v = strtod(s, &end);
        if (end == s)
            return nprfx_error(ctx, NPRFX_ERR_PARSE,
                               "stipple.tones: cannot read a number at \"%s\" (expected pen "
                               "darknesses like \"0.33, 0.67, 1\")",
                               s);
        if (!(v > prev && v <= 1.0))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                               "stipple.tones: %g must be above the previous tone (%g) and at "
                               "most 1: list pen darknesses in ascending order",
                               v, prev);
        if (n == NPRFX_STIPPLE_MAX_TONES)
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.tones: at most %d pens",
                               NPRFX_STIPPLE_MAX_TONES);
        p->tones[n++] = v;
        prev = v;
        s = end;
    }
    if (n == 0)
        return nprfx_error(ctx, NPRFX_ERR_PARSE, "stipple.tones: give at least one pen tone");
    p->num_tones = n;
    return NPRFX_OK;
}

static nprfx_result check_params(nprfx_context *ctx, const nprfx_stipple_params *p)
{
    if (!p || p->size < sizeof *p)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: bad params struct");
    if (p->mode < 0 || p->mode > NPRFX_STIPPLE_MULTITONE)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.mode: no mode %d", p->mode);
    if (!(p->area > 0) || !(p->a0 > 0) || !(p->delta_min >= 0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "stipple: size (%g) and a0 (%g) must be positive, delta_min (%g) not "
                           "negative",
                           p->area, p->a0, p->delta_min);
    if (!(p->tile > 0) || !(p->plane_scale > 0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.tile: %g is not positive",
                           p->tile);
    if (!(p->aspect > 0) || !isfinite(p->aspect))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.aspect: %g is not positive",
                           p->aspect);
    if (p->mode == NPRFX_STIPPLE_MULTITONE &&
        (p->num_tones < 1 || p->num_tones > NPRFX_STIPPLE_MAX_TONES))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "stipple.tones: need 1 to %d pens",
                           NPRFX_STIPPLE_MAX_TONES);
    return NPRFX_OK;
}

/* The largest disc radius the params can produce. */
static double max_radius(const nprfx_stipple_params *p)
{
    double a = p->mode == NPRFX_STIPPLE_RADIUS ? p->a0 : p->area;
    return sqrt(a / PI_D);
}

/* ---- the sequence: caller-owned, grown on demand ---- */

typedef struct seq_version {
    nprfx_ivs_index *index;
    struct seq_version *older; /* kept until destroy: renders may still read them */
} seq_version;

struct nprfx_stipple_sequence {
    pthread_mutex_t lock;        /* held while a longer version is built */
    _Atomic(seq_version *) head; /* the longest version; read without the lock */
};

nprfx_result nprfx_stipple_sequence_create(nprfx_context *ctx, nprfx_stipple_sequence **out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL output");
    *out = NULL;
    nprfx_stipple_sequence *s = calloc(1, sizeof *s);
    if (!s) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory");
    if (pthread_mutex_init(&s->lock, NULL) != 0) {
        free(s);
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "stipple: cannot create a mutex");
    }
    atomic_init(&s->head, NULL);
    *out = s;
    return NPRFX_OK;
}

void nprfx_stipple_sequence_destroy(nprfx_stipple_sequence *s)
{
    if (!s) return;
    seq_version *v = atomic_load(&s->head);
    while (v) {
        seq_version *older = v->older;
        nprfx_ivs_index_destroy(v->index);
        free(v);
        v = older;
    }
    pthread_mutex_destroy(&s->lock);
    free(s);
}

nprfx_result nprfx_stipple_sequence_index(nprfx_context *ctx, nprfx_stipple_sequence *s,
                                          int min_count, const nprfx_ivs_index **out)
{
    if (!out || !s)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL sequence or output");
    if (min_count > NPRFX_STIPPLE_MAX_SAMPLES) min_count = NPRFX_STIPPLE_MAX_SAMPLES;
    /* the common case: long enough already (acquire: the index it points to is complete) */
    seq_version *v = atomic_load_explicit(&s->head, memory_order_acquire);
    if (v && nprfx_ivs_index_count(v->index) >= min_count) {
        *out = v->index;
        return NPRFX_OK;
    }
    int want = 1 << 16;
    while (want < min_count)
        want *= 2;
    nprfx_result r = NPRFX_OK;
    pthread_mutex_lock(&s->lock);
    v = atomic_load_explicit(&s->head, memory_order_relaxed);
    if (!v || nprfx_ivs_index_count(v->index) < want) {
        /* Regenerating rather than extending is simpler and costs at most twice the final
         * size; the prefix property makes the new sequence start with the old one. */
        float *xy = malloc(sizeof(float) * 2 * (size_t)want);
        seq_version *nv = calloc(1, sizeof *nv);
        if (!xy || !nv) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory for %d points",
                            want);
        } else if ((r = nprfx_ivs_generate(ctx, NPRFX_IVS_DEFAULT_SEED, want, xy, NULL)) ==
                       NPRFX_OK &&
                   (r = nprfx_ivs_index_create(ctx, xy, want, &nv->index)) == NPRFX_OK) {
            nv->older = v;
            atomic_store_explicit(&s->head, nv, memory_order_release);
            v = nv;
            nv = NULL;
        }
        free(xy);
        free(nv);
    }
    *out = r == NPRFX_OK ? v->index : NULL;
    pthread_mutex_unlock(&s->lock);
    return r;
}

/* ---- exact disc coverage ---- */

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

/* Multiply T (rows [rect.y0, rect.y1) x cols [rect.x0, rect.x1), row stride = width) by
 * (1 - coverage * tone) over the pixels the disc touches. Pixel (i, j) is the unit square
 * centred on (i, j). */
static void splat_disc(float *t, nprfx_rect rect, double cx, double cy, double r, double tone)
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
    int width = rect.x1 - rect.x0;
    /* the quadrant areas at the pixel corners, a row of corners at a time (independent
     * evaluations first, then the differences: the same arithmetic as one running pass) */
    double qa[2][65];
    double *prev_row = qa[0], *cur_row = qa[1];
    quadrant_row(xs, pxs, nx, &rows[0], r, pr, prev_row);
    for (int jr = 1; jr < ny; jr++) {
        quadrant_row(xs, pxs, nx, &rows[jr], r, pr, cur_row);
        float *trow = t + (size_t)(cj0 + jr - 1 - rect.y0) * width - rect.x0;
        /* a pixel the disc misses has c = 0 and is multiplied by exactly 1: no branch */
        for (int k = 1; k < nx; k++) {
            double c = cur_row[k] - cur_row[k - 1] - prev_row[k] + prev_row[k - 1];
            c = c < 0 ? 0 : c > 1 ? 1 : c;
            trow[ci0 + k - 1] *= (float)(1.0 - c * tone);
        }
        double *swap = prev_row;
        prev_row = cur_row;
        cur_row = swap;
    }
}

/* ---- per-pixel data ---- */

typedef struct pixdata {
    nprfx_rect r; /* the pixels held */
    int w;
    double *su, *sv; /* UV in sequence units (uv / tile + object offset) */
    float *jac;      /* 4 per pixel: du/dx, du/dy, dv/dx, dv/dy in sequence units */
    float *g;        /* darkness 1 - tone */
    float *adet;     /* |det J| */
    float *hs, *hc;  /* smoothing scratch: horizontal sums of adet and their counts */
    int *id;
    int *uid; /* id where the pixel has a UV (OK_UV), else NO_ID */
    int *jid; /* id where it also has usable derivatives (OK_J), else NO_ID */
    unsigned char *ok;
    size_t cap;    /* pixels allocated */
    float *rowbuf; /* fill_raw: one row's input values, 6 a pixel */
    size_t rowcap;
    unsigned char *scratch; /* repair_outliers: per pixel */
    void *fixes;            /* repair_outliers: the repaired values */
    size_t fixcap;
} pixdata;

/* OK_SEAM: the two one-sided differences disagree (a UV seam next to the pixel, or a fold). */
enum { OK_UV = 1, OK_J = 2, OK_SEAM = 4 };
#define OK_BOTH (OK_UV | OK_J)
/* Never a read id (those are -1 or more). */
#define NO_ID INT_MIN

static inline size_t pd_at(const pixdata *d, int x, int y)
{
    return (size_t)(y - d->r.y0) * (size_t)d->w + (size_t)(x - d->r.x0);
}

/* Grow *p to hold n elements (keeping nothing: scratch is refilled each time). */
static int reserve(void **p, size_t *cap, size_t n, size_t elem)
{
    if (n <= *cap) return 1;
    free(*p);
    *p = malloc(n * elem);
    *cap = *p ? n : 0;
    return *p != NULL;
}

/* Corner (x - 0.5, y - 0.5) for x in [E.x0, E.x1], y in [E.y0, E.y1], computed once per tile
 * where the 2x2 pixels around it are one object with usable derivatives, and agree on it. */
typedef struct cgrid {
    nprfx_rect E;
    int gw, gh;
    double *gu, *gv;
    unsigned char *good;
} cgrid;

/* Per owner pixel: how many samples it keeps and the bounding box of its footprint. */
typedef struct oinfo {
    int limit;    /* keeps 0-based indices < limit; 0: nothing */
    int start;    /* counting sort of the stipples by owner */
    double i_max; /* the real-valued bound k A0 / threshold */
    double bb[4]; /* u0, v0, u1, v1 */
} oinfo;

/* A stipple with the key that orders it: its owner pixel, then its sample. */
typedef struct keyed {
    int oy, ox;
    double u, v;
    nprfx_stipple s;
} keyed;

typedef struct klist {
    keyed *k;
    size_t n, cap;
    int failed;
} klist;

typedef struct stlist {
    nprfx_stipple *s;
    size_t n, cap;
    int failed;
} stlist;

/* Per-worker memory, reused from tile to tile. */
typedef struct scratch {
    pixdata d;
    cgrid g;
    size_t gcap;
    oinfo *info;
    size_t icap;
    float *sdet; /* smoothed |det J| over the owners */
    size_t scap;
    klist kl;
    stlist sl;
    float *t;
    size_t tcap;
} scratch;

static void scratch_free(scratch *s)
{
    free(s->d.su);
    free(s->d.sv);
    free(s->d.jac);
    free(s->d.g);
    free(s->d.adet);
    free(s->d.hs);
    free(s->d.hc);
    free(s->d.id);
    free(s->d.uid);
    free(s->d.jid);
    free(s->d.ok);
    free(s->d.rowbuf);
    free(s->d.scratch);
    free(s->d.fixes);
    free(s->g.gu);
    free(s->g.gv);
    free(s->g.good);
    free(s->info);
    free(s->sdet);
    free(s->kl.k);
    free(s->sl.s);
    free(s->t);
}

static int pixdata_reserve(pixdata *d, nprfx_rect r)
{
    d->r = r;
    d->w = nprfx_rect_width(r);
    if (!reserve((void **)&d->rowbuf, &d->rowcap, 6 * (size_t)d->w + 6, sizeof(float))) return 0;
    size_t n = (size_t)d->w * (size_t)nprfx_rect_height(r) + 1;
    if (n <= d->cap) return 1;
    size_t c;
    int ok = 1;
    c = d->cap, ok &= reserve((void **)&d->su, &c, n, sizeof(double));
    c = d->cap, ok &= reserve((void **)&d->sv, &c, n, sizeof(double));
    c = d->cap, ok &= reserve((void **)&d->jac, &c, n, 4 * sizeof(float));
    c = d->cap, ok &= reserve((void **)&d->g, &c, n, sizeof(float));
    c = d->cap, ok &= reserve((void **)&d->adet, &c, n, sizeof(float));
    c = d->cap, ok &= reserve((void **)&d->hs, &c, n, sizeof(float));
    c = d->cap, ok &= reserve((void **)&d->hc, &c, n, sizeof(float));
    c = d->cap, ok &= reserve((void **)&d->id, &c, n, sizeof(int));
    c = d->cap, ok &= reserve((void **)&d->uid, &c, n, sizeof(int));
    c = d->cap, ok &= reserve((void **)&d->jid, &c, n, sizeof(int));
    c = d->cap, ok &= reserve((void **)&d->ok, &c, n, 1);
    c = d->cap, ok &= reserve((void **)&d->scratch, &c, n, 1);
    d->cap = ok ? n : 0;
    return ok;
}

typedef struct sjob {
    nprfx_context *ctx;
    const nprfx_stipple_params *p;
    const nprfx_stipple_inputs *in;
    nprfx_stipple_sequence *seq; /* where p->index is NULL: p->sequence or the job's own */
    int own_seq;
    nprfx_rect region; /* window (render) or region (collect) */
    int margin;        /* owner rows/columns around a tile that can reach it */
    float radius;      /* sqrt(area / pi): the disc radius of uniform and multitone stipples */
    nprfx_image *out;  /* render */
    stlist *lists;     /* collect: one per stripe; render: one per unit */
    nprfx_rect owners; /* render: the owners that can reach the window, in units */
    int units_x;       /* render: units per row */
    int *row_start;    /* render: per unit, UNIT_ROWS + 1 offsets of its owner rows */
    scratch *scr;      /* one per worker */
    atomic_int error;
} sjob;

static double apply_curve(const float *curve, double g)
{
    double t = g * (NPRFX_STIPPLE_CURVE_SIZE - 1);
    int i = (int)t;
    if (i >= NPRFX_STIPPLE_CURVE_SIZE - 1) return curve[NPRFX_STIPPLE_CURVE_SIZE - 1];
    if (i < 0) return curve[0];
    return curve[i] + (t - i) * (curve[i + 1] - curve[i]);
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

static void fill_raw(const sjob *j, pixdata *d)
{
    const nprfx_stipple_params *p = j->p;
    const nprfx_stipple_inputs *in = j->in;
    /* periods tile / sqrt(aspect) in u and tile * sqrt(aspect) in v (exactly 1 / tile for
     * both at aspect 1) */
    const double sa = sqrt(p->aspect);
    const double inv_tile_u = sa / p->tile, inv_tile_v = 1.0 / (sa * p->tile);
    const float *curve = p->tone_curve;
    const int x0 = d->r.x0, x1 = d->r.x1, luma = in->tone->channels >= 3;
    int last_id = 0x7fffffff;
    double off_u = 0, off_v = 0;
    for (int y = d->r.y0; y < d->r.y1; y++) {
        rowsrc sid = row_source(in->id, y, x0, x1), suv = row_source(in->uv, y, x0, x1);
        rowsrc sto = row_source(in->tone, y, x0, x1);
        size_t k = pd_at(d, x0, y);
        if ((!in->id || (sid.lo == x0 && sid.hi == x1)) && in->uv && suv.lo == x0 && suv.hi == x1 &&
            sto.lo == x0 && sto.hi == x1) {
            /* every input covers the row (the usual case): the loop below without the
             * bounds tests, the same arithmetic. The row's values are first copied out in a
             * tight loop: plates interleave many channels, and a loop that only loads keeps
             * many cache misses in flight where the full one would wait for each. */
            float *rb = d->rowbuf;
            const int n = x1 - x0, nt = luma ? 3 : 1;
            {
                const float *qu = suv.p, *qt = sto.p;
                for (int i = 0; i < n; i++, qu += suv.ps, qt += sto.ps) {
                    rb[6 * i + 1] = qu[0];
                    rb[6 * i + 2] = qu[1];
                    for (int c = 0; c < nt; c++)
                        rb[6 * i + 3 + c] = qt[c];
                }
                const float *qi = sid.p;
                if (qi)
                    for (int i = 0; i < n; i++, qi += sid.ps)
                        rb[6 * i] = qi[0];
            }
            for (int x = x0; x < x1; x++, k++, rb += 6) {
                int id = sid.p ? id_of(rb[0]) : 0;
                d->id[k] = id;
                d->uid[k] = NO_ID;
                d->jid[k] = NO_ID;
                double u = rb[1], v = rb[2];
                if (!isfinite(u) || !isfinite(v) || id < 0) {
                    d->ok[k] = 0;
                    d->g[k] = 0.0f;
                    continue;
                }
                if (id != last_id) {
                    off_u = nprfx_rand_u01(p->seed, 0, id, 0, 0, STREAM_OBJECT);
                    off_v = nprfx_rand_u01(p->seed, 0, id, 0, 1, STREAM_OBJECT);
                    last_id = id;
                }
                d->su[k] = u * inv_tile_u + off_u;
                d->sv[k] = v * inv_tile_v + off_v;
                double tone = luma ? 0.2126 * rb[3] + 0.7152 * rb[4] + 0.0722 * rb[5] : rb[3];
                if (!(tone == tone)) tone = 1.0;
                tone = tone < 0 ? 0 : tone > 1 ? 1 : tone;
                d->g[k] = (float)(curve ? apply_curve(curve, 1.0 - tone) : 1.0 - tone);
                d->ok[k] = OK_UV;
                d->uid[k] = id;
            }
            continue;
        }
        for (int x = x0; x < x1; x++, k++) {
            d->ok[k] = 0;
            d->g[k] = 0.0f;
            d->uid[k] = NO_ID;
            d->jid[k] = NO_ID;
            int id = 0; /* no id input, or outside it: object 0 */
            const float *q = row_at(&sid, x);
            if (q) id = id_of(q[0]); /* NaN/inf: -1, no object */
            d->id[k] = id;
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
            if (id != last_id) {
                /* different objects get unrelated parts of the torus */
                off_u = nprfx_rand_u01(p->seed, 0, id, 0, 0, STREAM_OBJECT);
                off_v = nprfx_rand_u01(p->seed, 0, id, 0, 1, STREAM_OBJECT);
                last_id = id;
            }
            d->su[k] = u * inv_tile_u + off_u;
            d->sv[k] = v * inv_tile_v + off_v;
            double tone = 1.0;
            if ((q = row_at(&sto, x)))
                tone = luma ? 0.2126 * q[0] + 0.7152 * q[1] + 0.0722 * q[2] : q[0];
            if (!(tone == tone)) tone = 1.0; /* NaN reads as paper */
            tone = tone < 0 ? 0 : tone > 1 ? 1 : tone;
            d->g[k] = (float)(curve ? apply_curve(curve, 1.0 - tone) : 1.0 - tone);
            d->ok[k] = OK_UV;
            d->uid[k] = id;
        }
    }
}

/* (x, y) is held, has a UV and usable derivatives, and belongs to object id. */
static inline int usable_j(const pixdata *d, int x, int y, int id)
{
    return nprfx_rect_contains(d->r, x, y) && d->jid[pd_at(d, x, y)] == id;
}

/* One column of the Jacobian at pixel k along a neighbour `step` away, given which of the
 * neighbours k + step (hf) and k - step (hb) are usable (same object, with a UV): differences
 * to those; central where both sides agree, else the smaller one-sided difference (a UV seam
 * gives a jump on one side only). Returns 0 when no neighbour qualifies, 2 when the sides
 * disagree. */
static inline int derivative(const pixdata *d, size_t k, size_t step, int hf, int hb, double *du,
                             double *dv)
{
    double fu = 0, fv = 0, bu = 0, bv = 0;
    if (hf) {
        fu = d->su[k + step] - d->su[k];
        fv = d->sv[k + step] - d->sv[k];
    }
    if (hb) {
        bu = d->su[k] - d->su[k - step];
        bv = d->sv[k] - d->sv[k - step];
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

static void fill_jacobian(pixdata *d, nprfx_rect r)
{
    const size_t w = (size_t)d->w;
    for (int y = r.y0; y < r.y1; y++) {
        const int up = y - 1 >= d->r.y0, down = y + 1 < d->r.y1;
        size_t k = pd_at(d, r.x0, y);
        for (int x = r.x0; x < r.x1; x++, k++) {
            if (!(d->ok[k] & OK_UV)) continue;
            const int id = d->uid[k];
            double ux, vx, uy, vy;
            int ex = derivative(d, k, 1, x + 1 < d->r.x1 && d->uid[k + 1] == id,
                                x - 1 >= d->r.x0 && d->uid[k - 1] == id, &ux, &vx);
            int ey = derivative(d, k, w, down && d->uid[k + w] == id, up && d->uid[k - w] == id,
                                &uy, &vy);
            if (!ex || !ey) continue;
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
    }
}

/* A pixel whose |det J| exceeds OUTLIER times the smallest of its same-object neighbours'
 * sees a jump, not the surface: renderers filter the UV pass, so along a silhouette the
 * pixels hold a blend of the two objects' UVs (and across a UV seam, of the two charts'),
 * which sits between the surfaces and makes a huge footprint there, packed with dots (a dark
 * outline). Half-float steps and perspective change |det J| between neighbours by a few times
 * at most. */
#define OUTLIER 8.0f

/* Such a pixel takes the surface of that neighbour instead: its UV extrapolated from the
 * neighbour's UV and derivatives, and those derivatives, so it owns its share of the surface
 * like the pixels around (and is marked OK_SEAM, so the corners it shares with the other side
 * of a seam are checked). Every repair is computed from the values before any repair, on M,
 * from the derivatives of D1 (M plus 1) as computed: the same whatever the units. */
static void repair_outliers(pixdata *d, nprfx_rect M)
{
    const ptrdiff_t w = d->w;
    const int *jid = d->jid;
    const float *adet = d->adet;
    unsigned char *src = d->scratch; /* 0, or 1 + which neighbour the pixel takes */
    const ptrdiff_t step[4] = {-1, 1, -w, w};
    size_t nfix = 0;
    for (int y = M.y0; y < M.y1; y++) {
        const int up = y - 1 >= d->r.y0, down = y + 1 < d->r.y1;
        ptrdiff_t k = (ptrdiff_t)pd_at(d, M.x0, y);
        for (int x = M.x0; x < M.x1; x++, k++) {
            src[k] = 0;
            const int id = jid[k];
            if (id == NO_ID) continue;
            const int has[4] = {x - 1 >= d->r.x0, x + 1 < d->r.x1, up, down};
            /* an outlier exceeds OUTLIER times some usable neighbour's (exactly: times the
             * smallest); the usual pixel fails all four tests and is done */
            const float a = adet[k] * (1.0f / OUTLIER);
            if (!((has[0] && a > adet[k - 1] && jid[k - 1] == id) ||
                  (has[1] && a > adet[k + 1] && jid[k + 1] == id) ||
                  (up && a > adet[k - w] && jid[k - w] == id) ||
                  (down && a > adet[k + w] && jid[k + w] == id)))
                continue;
            float ref = INFINITY;
            int best = 0;
            for (int n = 0; n < 4; n++)
                if (has[n] && jid[k + step[n]] == id && adet[k + step[n]] < ref) {
                    ref = adet[k + step[n]];
                    best = n;
                }
            src[k] = (unsigned char)(1 + best);
            nfix++;
        }
    }
    if (!nfix) return;
    /* the new values, all from the old ones, then stored */
    typedef struct fix {
        size_t k;
        double su, sv;
        float jac[4], adet;
    } fix;
    fix *fx = d->fixes;
    size_t nf = 0;
    if (nfix > d->fixcap) {
        free(d->fixes);
        d->fixes = fx = malloc(nfix * sizeof *fx);
        d->fixcap = fx ? nfix : 0;
        if (!fx) { /* no room: drop them instead (they own nothing) */
            for (int y = M.y0; y < M.y1; y++) {
                size_t k = pd_at(d, M.x0, y);
                for (int x = M.x0; x < M.x1; x++, k++)
                    if (src[k]) d->jid[k] = NO_ID, d->ok[k] &= (unsigned char)~OK_J;
            }
            return;
        }
    }
    for (int y = M.y0; y < M.y1; y++) {
        size_t k = pd_at(d, M.x0, y);
        for (int x = M.x0; x < M.x1; x++, k++) {
            if (!src[k]) continue;
            const int n = src[k] - 1;
            const size_t q = (size_t)((ptrdiff_t)k + step[n]);
            const double dx = n == 0 ? 1 : n == 1 ? -1 : 0, dy = n == 2 ? 1 : n == 3 ? -1 : 0;
            const float *jq = d->jac + 4 * q;
            fix *f = &fx[nf++];
            f->k = k;
            f->su = d->su[q] + jq[0] * dx + jq[1] * dy;
            f->sv = d->sv[q] + jq[2] * dx + jq[3] * dy;
            memcpy(f->jac, jq, sizeof f->jac);
            f->adet = d->adet[q];
        }
    }
    for (size_t i = 0; i < nf; i++) {
        size_t k = fx[i].k;
        d->su[k] = fx[i].su;
        d->sv[k] = fx[i].sv;
        memcpy(d->jac + 4 * k, fx[i].jac, sizeof fx[i].jac);
        d->adet[k] = fx[i].adet;
        d->ok[k] |= OK_SEAM;
    }
}

/* The area scale |det J| averaged over the same-object pixels of a (2 SMOOTH + 1)^2 window
 * (a horizontal pass within the object, then a vertical one), for the density thresholds only.
 * UV passes are often stored as half floats, whose steps make per-pixel differences of a slowly
 * varying UV jump by factors of two; the kept prefix would then change from pixel to pixel,
 * which scatters the dots like white noise. Needs adet on E plus SMOOTH; writes out[] over E. */
#define SMOOTH 2
static void smooth_area(pixdata *d, nprfx_rect E, nprfx_rect R, float *out)
{
    const ptrdiff_t w = d->w;
    /* Sums start at +0 and add values >= +0 (|det|, and sums of them), so adding +0 for a
     * pixel that does not count gives the same float as skipping it: the interior loops test
     * without branching. */
    const int *jid = d->jid;
    const float *adet = d->adet;
    /* columns of E whose +-SMOOTH neighbours are all held */
    const int xa = E.x0 - SMOOTH >= d->r.x0 ? E.x0 : d->r.x0 + SMOOTH;
    const int xb = E.x1 + SMOOTH <= d->r.x1 ? E.x1 : d->r.x1 - SMOOTH;
    for (int y = R.y0; y < R.y1; y++) {
        size_t k = pd_at(d, E.x0, y);
        for (int x = E.x0; x < E.x1; x++, k++) {
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
            d->hs[k] = sum;
            d->hc[k] = cnt;
        }
    }
    int ew = nprfx_rect_width(E);
    for (int y = E.y0; y < E.y1; y++) {
        int lo = y - SMOOTH < R.y0 ? R.y0 - y : -SMOOTH;
        int hi = y + SMOOTH >= R.y1 ? R.y1 - 1 - y : SMOOTH;
        ptrdiff_t k = (ptrdiff_t)pd_at(d, E.x0, y);
        float *o = out + (size_t)(y - E.y0) * ew;
        for (int x = E.x0; x < E.x1; x++, k++) {
            float sum = 0, cnt = 0;
            const int id = jid[k];
            if (id != NO_ID)
                for (int dy = lo; dy <= hi; dy++) {
                    const ptrdiff_t q = k + dy * w;
                    const int same = jid[q] == id;
                    sum += same ? d->hs[q] : 0.0f;
                    cnt += same ? d->hc[q] : 0.0f;
                }
            o[x - E.x0] = cnt > 0 ? sum / cnt : 0.0f;
        }
    }
}

/* Is (u, v) more than half a pixel, measured with pixel k's own derivatives, from where pixel
 * k's derivatives put the corner at offset (ox, oy) pixels? Then the corner straddles a UV seam
 * (or a fold) as seen from k. */
static int off_corner(const pixdata *d, size_t k, double ox, double oy, double u, double v)
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

static void cgrid_fill(cgrid *g, const pixdata *d)
{
    static const double ox[4] = {0.5, -0.5, 0.5, -0.5}, oy[4] = {0.5, 0.5, -0.5, -0.5};
    const size_t w = (size_t)d->w;
    for (int gy = 0; gy < g->gh; gy++)
        for (int gx = 0; gx < g->gw; gx++) {
            size_t i = (size_t)gy * g->gw + gx;
            int xa = g->E.x0 + gx - 1, ya = g->E.y0 + gy - 1;
            g->good[i] = 0;
            if (!nprfx_rect_contains(d->r, xa, ya) || xa + 1 >= d->r.x1 || ya + 1 >= d->r.y1)
                continue;
            size_t k[4] = {pd_at(d, xa, ya), 0, 0, 0};
            k[1] = k[0] + 1;
            k[2] = k[0] + w;
            k[3] = k[2] + 1;
            /* the 2x2 pixels around the corner: one object, all with usable derivatives */
            int id = d->jid[k[0]];
            if (id == NO_ID || d->jid[k[1]] != id || d->jid[k[2]] != id || d->jid[k[3]] != id)
                continue;
            double u = ((d->su[k[0]] + d->su[k[1]]) + (d->su[k[2]] + d->su[k[3]])) * 0.25;
            double v = ((d->sv[k[0]] + d->sv[k[1]]) + (d->sv[k[2]] + d->sv[k[3]])) * 0.25;
            /* the seam test, only where a pixel's differences hinted at one */
            int good = 1;
            if ((d->ok[k[0]] | d->ok[k[1]] | d->ok[k[2]] | d->ok[k[3]]) & OK_SEAM)
                for (int q = 0; q < 4 && good; q++)
                    if (off_corner(d, k[q], ox[q], oy[q], u, v)) good = 0;
            g->gu[i] = u;
            g->gv[i] = v;
            g->good[i] = (unsigned char)good;
        }
}

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
        if (!usable_j(d, qx[i], qy[i], o->id)) continue;
        size_t k = pd_at(d, qx[i], qy[i]);
        const float *jc = d->jac + 4 * k;
        double ox = (xa + 0.5) - qx[i], oy = (ya + 0.5) - qy[i];
        su += d->su[k] + jc[0] * ox + jc[1] * oy;
        sv += d->sv[k] + jc[2] * ox + jc[3] * oy;
        n++;
    }
    double u = su / n, v = sv / n; /* n >= 1: the owner itself qualifies */
    size_t kp = pd_at(d, o->x, o->y);
    if (off_corner(d, kp, 0.5 * dx, 0.5 * dy, u, v)) {
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
static nprfx_result owner_stipples(const sjob *j, scratch *s, nprfx_rect E, stlist *out,
                                   int *row_start)
{
    const nprfx_stipple_params *p = j->p;
    if (nprfx_rect_empty(E)) return NPRFX_OK;
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
    ok &= reserve((void **)&g->gu, &c, gn, sizeof(double));
    c = s->gcap, ok &= reserve((void **)&g->gv, &c, gn, sizeof(double));
    c = s->gcap, ok &= reserve((void **)&g->good, &c, gn, 1);
    s->gcap = ok ? (gn > s->gcap ? gn : s->gcap) : 0;
    ok &= reserve((void **)&s->info, &s->icap, (size_t)ew * (size_t)eh, sizeof(oinfo));
    ok &= reserve((void **)&s->sdet, &s->scap, (size_t)ew * (size_t)eh, sizeof(float));
    if (!ok) return NPRFX_ERR_OUT_OF_MEMORY;
    fill_raw(j, d);
    fill_jacobian(d, D1);
    repair_outliers(d, M);
    smooth_area(d, E, M, s->sdet);
    g->E = E;
    g->gw = ew + 1;
    g->gh = eh + 1;
    cgrid_fill(g, d);

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

/* ---- render ---- */

static void set_error(sjob *j, nprfx_result r)
{
    int expected = NPRFX_OK;
    if (r != NPRFX_OK) atomic_compare_exchange_strong(&j->error, &expected, r);
}

/* Phase 1 of a render: the stipples of one unit of owners, with where each owner row starts. */
static void unit_stipples(void *user, int begin, int end, int worker)
{
    sjob *j = user;
    nprfx_rect R = j->owners;
    for (int u = begin; u < end; u++) {
        if (atomic_load(&j->error) != NPRFX_OK) return;
        int x0 = R.x0 + (u % j->units_x) * UNIT_COLS, y0 = R.y0 + (u / j->units_x) * UNIT_ROWS;
        nprfx_rect E =
            nprfx_rect_intersect(R, nprfx_rect_make(x0, y0, x0 + UNIT_COLS, y0 + UNIT_ROWS));
        set_error(j, owner_stipples(j, &j->scr[worker], E, &j->lists[u],
                                    j->row_start + (size_t)u * (UNIT_ROWS + 1)));
    }
}

/* Phase 2: draw the stipples that reach a tile of the window. They are taken owner row by
 * owner row, and within a row unit by unit from the left, so every pixel sees its stipples in
 * row-major order of their owners, however the window, units and tiles fall. */
static void render_tiles(void *user, int begin, int end, int worker)
{
    sjob *j = user;
    scratch *s = &j->scr[worker];
    const nprfx_stipple_params *p = j->p;
    nprfx_rect win = j->region, R = j->owners;
    int tiles_x = (nprfx_rect_width(win) + TILE_COLS - 1) / TILE_COLS;
    for (int st = begin; st < end; st++) {
        if (atomic_load(&j->error) != NPRFX_OK) return;
        int x0 = win.x0 + (st % tiles_x) * TILE_COLS, y0 = win.y0 + (st / tiles_x) * STRIPE_ROWS;
        int x1 = x0 + TILE_COLS < win.x1 ? x0 + TILE_COLS : win.x1;
        int y1 = y0 + STRIPE_ROWS < win.y1 ? y0 + STRIPE_ROWS : win.y1;
        nprfx_rect rows = nprfx_rect_make(x0, y0, x1, y1);
        int width = x1 - x0;
        size_t npx = (size_t)width * (size_t)(y1 - y0);
        if (!reserve((void **)&s->t, &s->tcap, npx, sizeof(float))) {
            set_error(j, NPRFX_ERR_OUT_OF_MEMORY);
            return;
        }
        float *t = s->t;
        for (size_t i = 0; i < npx; i++)
            t[i] = 1.0f;
        /* the owners that can reach the tile, and the units holding them */
        nprfx_rect E = nprfx_rect_intersect(
            R, nprfx_rect_make(x0 - j->margin, y0 - j->margin, x1 + j->margin, y1 + j->margin));
        if (!nprfx_rect_empty(E)) {
            int ca = (E.x0 - R.x0) / UNIT_COLS, cb = (E.x1 - 1 - R.x0) / UNIT_COLS;
            const double lx = x0 - 1, hx = x1, ly = y0 - 1, hy = y1;
            for (int oy = E.y0; oy < E.y1; oy++) {
                int ur = (oy - R.y0) / UNIT_ROWS, r = (oy - R.y0) % UNIT_ROWS;
                for (int uc = ca; uc <= cb; uc++) {
                    int u = ur * j->units_x + uc;
                    const int *rs = j->row_start + (size_t)u * (UNIT_ROWS + 1);
                    const nprfx_stipple *q = j->lists[u].s;
                    for (int i = rs[r]; i < rs[r + 1]; i++) {
                        /* discs wholly outside the tile change nothing: skip them cheaply */
                        double rad = q[i].radius;
                        if (q[i].x + rad < lx || q[i].x - rad > hx || q[i].y + rad < ly ||
                            q[i].y - rad > hy)
                            continue;
                        splat_disc(t, rows, q[i].x, q[i].y, rad, q[i].tone);
                    }
                }
            }
        }
        nprfx_image *o = j->out;
        const int extra = p->coverage_channel;
        float diff[4];
        for (int c = 0; c < 4; c++)
            diff[c] = p->ink[c] - p->paper[c];
        for (int y = y0; y < y1; y++) {
            const float *trow = t + (size_t)(y - y0) * width;
            float *px = nprfx_image_at(o, x0, y);
            for (int i = 0; i < width; i++, px += o->pixel_stride) {
                float dk = 1.0f - trow[i];
                for (int c = 0; c < 4; c++)
                    px[c] = p->paper[c] + dk * diff[c];
                if (extra) px[4] = dk;
            }
        }
    }
}

static nprfx_result check_inputs(nprfx_context *ctx, const nprfx_stipple_inputs *in)
{
    if (!in || !in->tone || !in->tone->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "stipple: input 'tone' is required");
    if (in->uv && in->uv->data && in->uv->channels < 2)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple: input 'uv' needs 2 channels, it has %d", in->uv->channels);
    return NPRFX_OK;
}

/* NULL views for absent optional inputs, so the code below tests one thing. */
static nprfx_stipple_inputs normalise_inputs(const nprfx_stipple_inputs *in)
{
    nprfx_stipple_inputs n = *in;
    if (n.uv && !n.uv->data) n.uv = NULL;
    if (n.id && !n.id->data) n.id = NULL;
    return n;
}

/* Set up a job over `region` with one scratch per worker. */
static nprfx_result job_init(sjob *j, nprfx_context *ctx, const nprfx_stipple_params *p,
                             const nprfx_stipple_inputs *in, nprfx_rect region)
{
    memset(j, 0, sizeof *j);
    j->ctx = ctx;
    j->p = p;
    j->in = in;
    j->region = region;
    j->radius = (float)sqrt(p->area / PI_D);
    atomic_init(&j->error, NPRFX_OK);
    if (!p->index) {
        j->seq = p->sequence;
        if (!j->seq) { /* no caller's sequence: one for this call, shared by its threads */
            if (nprfx_stipple_sequence_create(ctx, &j->seq) != NPRFX_OK)
                return NPRFX_ERR_OUT_OF_MEMORY;
            j->own_seq = 1;
        }
    }
    int workers = nprfx_executor_workers(nprfx_context_executor(ctx));
    j->scr = calloc((size_t)(workers > 0 ? workers : 1), sizeof(scratch));
    return j->scr ? NPRFX_OK : NPRFX_ERR_OUT_OF_MEMORY;
}

static void job_free(sjob *j)
{
    int workers = nprfx_executor_workers(nprfx_context_executor(j->ctx));
    for (int w = 0; j->scr && w < (workers > 0 ? workers : 1); w++)
        scratch_free(&j->scr[w]);
    free(j->scr);
    if (j->own_seq) nprfx_stipple_sequence_destroy(j->seq);
}

nprfx_result nprfx_stipple_render(nprfx_context *ctx, const nprfx_stipple_params *p,
                                  const nprfx_stipple_inputs *in_, nprfx_rect window,
                                  nprfx_image *out)
{
    nprfx_result r = check_params(ctx, p);
    if (r == NPRFX_OK) r = check_inputs(ctx, in_);
    if (r != NPRFX_OK) return r;
    if (!out || out->channels != (p->coverage_channel ? 5 : 4))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple: the output needs %d channels, it has %d",
                           p->coverage_channel ? 5 : 4, out ? out->channels : 0);
    window = nprfx_rect_intersect(window, in_->frame);
    window = nprfx_rect_intersect(window, out->bounds);
    if (nprfx_rect_empty(window)) return NPRFX_OK;
    nprfx_stipple_inputs in = normalise_inputs(in_);
    sjob j;
    if (job_init(&j, ctx, p, &in, window) != NPRFX_OK) {
        job_free(&j);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory");
    }
    /* an owner reaches a pixel when its disc (centre anywhere in the owner's square) does */
    j.margin = (int)ceil(max_radius(p) + 1.0);
    j.out = out;
    /* phase 1: the stipples of the owners around the window, unit by unit (each owner once);
     * phase 2: draw them tile by tile */
    j.owners =
        nprfx_rect_intersect(in.frame, nprfx_rect_make(window.x0 - j.margin, window.y0 - j.margin,
                                                       window.x1 + j.margin, window.y1 + j.margin));
    j.units_x = (nprfx_rect_width(j.owners) + UNIT_COLS - 1) / UNIT_COLS;
    int units = j.units_x * ((nprfx_rect_height(j.owners) + UNIT_ROWS - 1) / UNIT_ROWS);
    j.lists = calloc((size_t)units, sizeof(stlist));
    j.row_start = malloc(sizeof(int) * (size_t)units * (UNIT_ROWS + 1));
    if (!j.lists || !j.row_start) {
        r = NPRFX_ERR_OUT_OF_MEMORY;
    } else {
        nprfx_parallel_for(nprfx_context_executor(ctx), units, 1, unit_stipples, &j);
        r = atomic_load(&j.error);
    }
    if (r == NPRFX_OK) {
        int tiles = ((nprfx_rect_height(window) + STRIPE_ROWS - 1) / STRIPE_ROWS) *
                    ((nprfx_rect_width(window) + TILE_COLS - 1) / TILE_COLS);
        nprfx_parallel_for(nprfx_context_executor(ctx), tiles, 1, render_tiles, &j);
        r = atomic_load(&j.error);
    }
    for (int u = 0; j.lists && u < units; u++)
        free(j.lists[u].s);
    free(j.lists);
    free(j.row_start);
    job_free(&j);
    if (r == NPRFX_ERR_OUT_OF_MEMORY)
        return nprfx_error(ctx, r, "stipple: out of memory rendering %dx%d pixels",
                           nprfx_rect_width(window), nprfx_rect_height(window));
    return r; /* other errors were raised where they happened */
}

/* ---- collect ---- */

static void collect_stripes(void *user, int begin, int end, int worker)
{
    sjob *j = user;
    for (int st = begin; st < end; st++) {
        int y0 = j->region.y0 + st * STRIPE_ROWS;
        int y1 = y0 + STRIPE_ROWS < j->region.y1 ? y0 + STRIPE_ROWS : j->region.y1;
        nprfx_rect E = nprfx_rect_make(j->region.x0, y0, j->region.x1, y1);
        set_error(j, owner_stipples(j, &j->scr[worker], E, &j->lists[st], NULL));
    }
}

nprfx_result nprfx_stipple_collect(nprfx_context *ctx, const nprfx_stipple_params *p,
                                   const nprfx_stipple_inputs *in_, nprfx_rect region,
                                   nprfx_stipple **list, size_t *count)
{
    if (!list || !count)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL output list");
    *list = NULL;
    *count = 0;
    nprfx_result r = check_params(ctx, p);
    if (r == NPRFX_OK) r = check_inputs(ctx, in_);
    if (r != NPRFX_OK) return r;
    region = nprfx_rect_intersect(region, in_->frame);
    if (nprfx_rect_empty(region)) return NPRFX_OK;
    nprfx_stipple_inputs in = normalise_inputs(in_);
    sjob j;
    int stripes = (nprfx_rect_height(region) + STRIPE_ROWS - 1) / STRIPE_ROWS;
    r = job_init(&j, ctx, p, &in, region);
    if (r == NPRFX_OK) {
        j.lists = calloc((size_t)stripes, sizeof(stlist));
        if (!j.lists) r = NPRFX_ERR_OUT_OF_MEMORY;
    }
    if (r == NPRFX_OK) {
        nprfx_parallel_for(nprfx_context_executor(ctx), stripes, 1, collect_stripes, &j);
        r = atomic_load(&j.error);
    }
    size_t total = 0;
    for (int st = 0; j.lists && st < stripes; st++)
        total += j.lists[st].n;
    if (r == NPRFX_OK && total) {
        *list = malloc(total * sizeof **list);
        if (!*list) {
            r = NPRFX_ERR_OUT_OF_MEMORY;
        } else {
            for (int st = 0; st < stripes; st++) {
                if (j.lists[st].n)
                    memcpy(*list + *count, j.lists[st].s, j.lists[st].n * sizeof **list);
                *count += j.lists[st].n;
            }
        }
    }
    for (int st = 0; j.lists && st < stripes; st++)
        free(j.lists[st].s);
    free(j.lists);
    job_free(&j);
    if (r == NPRFX_ERR_OUT_OF_MEMORY)
        return nprfx_error(ctx, r, "stipple: out of memory collecting stipples");
    return r;
}

/* ---- tone correction ---- */

nprfx_result nprfx_stipple_tone_curve(nprfx_context *ctx, const nprfx_stipple_params *p_,
                                      float *curve)
{
    nprfx_result r = check_params(ctx, p_);
    if (r != NPRFX_OK) return r;
    if (!curve) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL curve");
    nprfx_stipple_params p = *p_;
    p.tone_curve = NULL;
    nprfx_stipple_sequence *own = NULL; /* the caller gave none: one for all the renders */
    if (!p.index && !p.sequence) {
        if ((r = nprfx_stipple_sequence_create(ctx, &own)) != NPRFX_OK) return r;
        p.sequence = own;
    }
    p.coverage_channel = 1;
    p.plane_scale = NPRFX_STIPPLE_PLANE_PIXELS;
    p.tile = 0.25;
    p.aspect = 1.0; /* the ideal isotropic spread the aspect param aims at */
    /* scale invariance: measure small dots, on a patch holding a few hundred of them */
    double big = p.mode == NPRFX_STIPPLE_UNIFORM ? p.area : p.a0;
    if (big > 8.0) {
        double s = 8.0 / big;
        p.area *= s;
        p.a0 *= s;
        p.delta_min *= s;
    }
    const int n = 160, levels = NPRFX_STIPPLE_CURVE_SIZE;
    nprfx_image tone, out;
    if ((r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, n), 1, &tone)) != NPRFX_OK) {
        nprfx_stipple_sequence_destroy(own);
        return r;
    }
    if ((r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, n), 5, &out)) != NPRFX_OK) {
        nprfx_image_free(&tone);
        nprfx_stipple_sequence_destroy(own);
        return r;
    }
    nprfx_stipple_inputs in = {&tone, NULL, NULL, tone.bounds};
    /* D at g = k / (levels - 1), measured away from the patch border (dots owned outside the
     * patch are missing there) */
    double dk[NPRFX_STIPPLE_CURVE_SIZE];
    dk[0] = 0;
    const int m = 8;
    for (int k = 1; k < levels && r == NPRFX_OK; k++) {
        float t = (float)(1.0 - (double)k / (levels - 1));
        nprfx_image_fill(&tone, &t);
        r = nprfx_stipple_render(ctx, &p, &in, tone.bounds, &out);
        double sum = 0;
        for (int y = m; y < n - m; y++)
            for (int x = m; x < n - m; x++)
                sum += nprfx_image_at(&out, x, y)[4];
        dk[k] = sum / ((double)(n - 2 * m) * (n - 2 * m));
        if (dk[k] < dk[k - 1]) dk[k] = dk[k - 1]; /* keep it monotone */
    }
    nprfx_image_free(&tone);
    nprfx_image_free(&out);
    nprfx_stipple_sequence_destroy(own);
    if (r != NPRFX_OK) return r;
    /* invert the piecewise-linear D */
    for (int k = 0; k < levels; k++) {
        double want = (double)k / (levels - 1);
        if (want <= 0) {
            curve[k] = 0.0f;
            continue;
        }
        int i = 1;
        while (i < levels && dk[i] < want)
            i++;
        if (i == levels) {
            curve[k] = 1.0f;
            continue;
        }
        double f = dk[i] > dk[i - 1] ? (want - dk[i - 1]) / (dk[i] - dk[i - 1]) : 1.0;
        curve[k] = (float)(((i - 1) + f) / (levels - 1));
    }
    return NPRFX_OK;
}

/* ---- vector export ---- */

typedef struct sbuf {
    char *s;
    size_t n, cap;
    int failed;
} sbuf;

static void sb_printf(sbuf *b, const char *fmt, ...)
{
    if (b->failed) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        size_t room = b->cap - b->n;
        int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? room : 0, fmt, ap);
        va_end(ap);
        if (k < 0) {
            b->failed = 1;
            return;
        }
        if (b->s && (size_t)k < room) {
            b->n += (size_t)k;
            return;
        }
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->n + (size_t)k + 1)
            cap *= 2;
        char *ns = realloc(b->s, cap);
        if (!ns) {
            b->failed = 1;
            return;
        }
        b->s = ns;
        b->cap = cap;
    }
}

/* Scene-linear to an sRGB-encoded 8-bit value, for SVG colours. */
static int srgb8(float v)
{
    double c = v <= 0 ? 0 : v >= 1 ? 1 : v;
    c = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1 / 2.4) - 0.055;
    return (int)floor(c * 255 + 0.5);
}

nprfx_result nprfx_stipple_format(nprfx_context *ctx, const nprfx_stipple *list, size_t count,
                                  nprfx_rect frame, nprfx_stipple_format_kind kind,
                                  const float *ink, const float *paper, char **text, size_t *len)
{
    if (!text || (count && !list))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple export: NULL argument");
    *text = NULL;
    if (len) *len = 0;
    static const float black[4] = {0, 0, 0, 1}, white[4] = {1, 1, 1, 1};
    if (!ink) ink = black;
    if (!paper) paper = white;
    sbuf b = {0};
    double ox = 0.5 - frame.x0, oy = 0.5 - frame.y0;
    if (kind == NPRFX_STIPPLE_CSV) {
        sb_printf(&b, "x,y,radius,tone,sample,object\n");
        for (size_t i = 0; i < count; i++)
            sb_printf(&b, "%.4f,%.4f,%.4f,%.4f,%d,%d\n", list[i].x + ox, list[i].y + oy,
                      list[i].radius, list[i].tone, list[i].sample, list[i].object);
    } else if (kind == NPRFX_STIPPLE_SVG) {
        int w = nprfx_rect_width(frame), h = nprfx_rect_height(frame);
        sb_printf(&b,
                  "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                  "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                  "viewBox=\"0 0 %d %d\">\n",
                  w, h, w, h);
        if (paper[3] > 0)
            sb_printf(&b,
                      "<rect width=\"%d\" height=\"%d\" fill=\"#%02x%02x%02x\" "
                      "fill-opacity=\"%.3f\"/>\n",
                      w, h, srgb8(paper[0]), srgb8(paper[1]), srgb8(paper[2]), fmin(1.0, paper[3]));
        sb_printf(&b, "<g fill=\"#%02x%02x%02x\" fill-opacity=\"%.3f\">\n", srgb8(ink[0]),
                  srgb8(ink[1]), srgb8(ink[2]), fmin(1.0, fmax(0.0, ink[3])));
        for (size_t i = 0; i < count; i++) {
            if (list[i].tone < 1.0f)
                sb_printf(&b, "<circle cx=\"%.3f\" cy=\"%.3f\" r=\"%.3f\" opacity=\"%.3f\"/>\n",
                          list[i].x + ox, list[i].y + oy, list[i].radius, list[i].tone);
            else
                sb_printf(&b, "<circle cx=\"%.3f\" cy=\"%.3f\" r=\"%.3f\"/>\n", list[i].x + ox,
                          list[i].y + oy, list[i].radius);
        }
        sb_printf(&b, "</g>\n</svg>\n");
    } else {
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple export: unknown format %d",
                           (int)kind);
    }
    if (b.failed) {
        free(b.s);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple export: out of memory");
    }
    *text = b.s;
    if (len) *len = b.n;
    return NPRFX_OK;
}
