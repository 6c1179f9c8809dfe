/* Stippling from UV and shading (Ma et al. 2018; DESIGN.md §3.3). stipple.h has the model.
 *
 * Work is split into tiles of the window. A tile first finds the stipples owned by the pixels
 * within reach of it (the tile plus a margin of the largest disc radius), in row-major order of
 * the owners, then splats them into its pixels. Every pixel therefore sees the same stipples in
 * the same order whatever the tile or thread it is rendered in (or the host's own tiling), which
 * makes the output bit-identical across splits. Owners near a tile edge are found by both
 * tiles; that duplicated work (a few rows and columns) is the price of not sharing state. */
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/exec.h"
#include "nprfx/rng.h"
#include "nprfx/stipple.h"

/* Work units: tiles of the window, small enough for their per-pixel data (~40 bytes a pixel)
 * to stay in cache, large enough that the margin recomputed around each stays cheap. */
#define STRIPE_ROWS 64
#define TILE_COLS 256
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

/* ---- the shared sequence ---- */

typedef struct shared_seq {
    nprfx_ivs_index *index;
    struct shared_seq *older; /* kept: callers may still hold them */
} shared_seq;

static pthread_mutex_t shared_lock = PTHREAD_MUTEX_INITIALIZER;
static shared_seq *shared_head;

nprfx_result nprfx_stipple_shared_index(nprfx_context *ctx, int min_count,
                                        const nprfx_ivs_index **out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL output");
    if (min_count > NPRFX_STIPPLE_MAX_SAMPLES) min_count = NPRFX_STIPPLE_MAX_SAMPLES;
    int want = 1 << 16;
    while (want < min_count)
        want *= 2;
    nprfx_result r = NPRFX_OK;
    pthread_mutex_lock(&shared_lock);
    if (!shared_head || nprfx_ivs_index_count(shared_head->index) < want) {
        /* Regenerating rather than extending is simpler and costs at most twice the final
         * size; the prefix property makes the new sequence start with the old one. */
        float *xy = malloc(sizeof(float) * 2 * (size_t)want);
        shared_seq *s = calloc(1, sizeof *s);
        if (!xy || !s) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory for %d points",
                            want);
        } else if ((r = nprfx_ivs_generate(ctx, NPRFX_IVS_DEFAULT_SEED, want, xy, NULL)) ==
                       NPRFX_OK &&
                   (r = nprfx_ivs_index_create(ctx, xy, want, &s->index)) == NPRFX_OK) {
            s->older = shared_head;
            shared_head = s;
            s = NULL;
        }
        free(xy);
        free(s);
    }
    *out = r == NPRFX_OK ? shared_head->index : NULL;
    pthread_mutex_unlock(&shared_lock);
    return r;
}

/* ---- exact disc coverage ---- */

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
static double half_chord_integral(double x, double r)
{
    double t = x / r;
    t = t < -1 ? -1 : t > 1 ? 1 : t;
    double h = sqrt(fmax(0.0, r * r - x * x));
    return 0.5 * (x * h + r * r * asin_fast(t));
}

/* Row-boundary quantities of the quadrant-area function below. */
typedef struct row_term {
    double y, w, pw;
} row_term;

/* Area of the disc of radius r at the origin within {X <= x, Y <= y}, given px = P(clamp(x))
 * and the row term of y. Integrates the vertical chord length min(y, h) + h over X, split where
 * y crosses the chord (|X| = w = sqrt(r^2 - y^2)). */
static double quadrant_area(double x, double px, const row_term *rt, double r, double pr)
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
    for (int k = 0; k < nx; k++) {
        xs[k] = (ci0 + k - 0.5) - cx;
        double xc = xs[k] < -r ? -r : xs[k] > r ? r : xs[k];
        pxs[k] = half_chord_integral(xc, r);
    }
    for (int k = 0; k < ny; k++) {
        double y = (cj0 + k - 0.5) - cy;
        rows[k].y = y;
        rows[k].w = fabs(y) < r ? sqrt(r * r - y * y) : 0.0;
        rows[k].pw = half_chord_integral(rows[k].w, r);
    }
    double pr = 0.25 * PI_D * r * r;
    int width = rect.x1 - rect.x0;
    double prev_row[65];
    for (int k = 0; k < nx; k++)
        prev_row[k] = quadrant_area(xs[k], pxs[k], &rows[0], r, pr);
    for (int jr = 1; jr < ny; jr++) {
        double left = quadrant_area(xs[0], pxs[0], &rows[jr], r, pr);
        float *trow = t + (size_t)(cj0 + jr - 1 - rect.y0) * width - rect.x0;
        for (int k = 1; k < nx; k++) {
            double right = quadrant_area(xs[k], pxs[k], &rows[jr], r, pr);
            double c = right - left - prev_row[k] + prev_row[k - 1];
            prev_row[k - 1] = left;
            left = right;
            c = c < 0 ? 0 : c > 1 ? 1 : c;
            if (c > 0) trow[ci0 + k - 1] *= (float)(1.0 - c * tone);
        }
        prev_row[nx - 1] = left;
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
    unsigned char *ok;
    size_t cap; /* pixels allocated */
} pixdata;

/* OK_SEAM: the two one-sided differences disagree (a UV seam next to the pixel, or a fold). */
enum { OK_UV = 1, OK_J = 2, OK_SEAM = 4 };
#define OK_BOTH (OK_UV | OK_J)

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
    free(s->d.ok);
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
    c = d->cap, ok &= reserve((void **)&d->ok, &c, n, 1);
    d->cap = ok ? n : 0;
    return ok;
}

typedef struct sjob {
    nprfx_context *ctx;
    const nprfx_stipple_params *p;
    const nprfx_stipple_inputs *in;
    nprfx_rect region; /* window (render) or region (collect) */
    int margin;        /* owner rows/columns around a tile that can reach it */
    nprfx_image *out;  /* render */
    stlist *lists;     /* collect: one per stripe */
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

static int read_id(const nprfx_image *im, int x, int y)
{
    if (!im || !nprfx_rect_contains(im->bounds, x, y)) return 0;
    double v = nprfx_image_at(im, x, y)[0];
    if (!(v > -2e9 && v < 2e9)) return -1; /* NaN/inf: no object */
    return (int)floor(v + 0.5);
}

static void fill_raw(const sjob *j, pixdata *d)
{
    const nprfx_stipple_params *p = j->p;
    const nprfx_stipple_inputs *in = j->in;
    const double inv_tile = 1.0 / p->tile;
    const float *curve = p->tone_curve;
    int last_id = 0x7fffffff;
    double off_u = 0, off_v = 0;
    for (int y = d->r.y0; y < d->r.y1; y++)
        for (int x = d->r.x0; x < d->r.x1; x++) {
            size_t k = pd_at(d, x, y);
            d->ok[k] = 0;
            d->g[k] = 0.0f;
            int id = read_id(in->id, x, y);
            d->id[k] = id;
            double u, v;
            if (in->uv) {
                if (!nprfx_rect_contains(in->uv->bounds, x, y)) continue;
                const float *q = nprfx_image_at(in->uv, x, y);
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
            d->su[k] = u * inv_tile + off_u;
            d->sv[k] = v * inv_tile + off_v;
            double tone = 1.0;
            if (nprfx_rect_contains(in->tone->bounds, x, y)) {
                const float *t = nprfx_image_at(in->tone, x, y);
                tone =
                    in->tone->channels >= 3 ? 0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2] : t[0];
            }
            if (!(tone == tone)) tone = 1.0; /* NaN reads as paper */
            tone = tone < 0 ? 0 : tone > 1 ? 1 : tone;
            d->g[k] = (float)(curve ? apply_curve(curve, 1.0 - tone) : 1.0 - tone);
            d->ok[k] = OK_UV;
        }
}

static inline int usable(const pixdata *d, int x, int y, int id)
{
    if (!nprfx_rect_contains(d->r, x, y)) return 0;
    size_t k = pd_at(d, x, y);
    return (d->ok[k] & OK_UV) && d->id[k] == id;
}

static inline int usable_j(const pixdata *d, int x, int y, int id)
{
    if (!nprfx_rect_contains(d->r, x, y)) return 0;
    size_t k = pd_at(d, x, y);
    return (d->ok[k] & OK_BOTH) == OK_BOTH && d->id[k] == id;
}

/* One column of the Jacobian at (x, y) along (dx, dy): differences to same-object neighbours;
 * central where both sides agree, else the smaller one-sided difference (a UV seam gives a
 * jump on one side only). Returns 0 when no neighbour qualifies, 2 when the sides disagree. */
static inline int derivative(const pixdata *d, int x, int y, int dx, int dy, double *du, double *dv)
{
    size_t k = pd_at(d, x, y);
    int id = d->id[k];
    int hf = usable(d, x + dx, y + dy, id), hb = usable(d, x - dx, y - dy, id);
    double fu = 0, fv = 0, bu = 0, bv = 0;
    if (hf) {
        size_t kf = pd_at(d, x + dx, y + dy);
        fu = d->su[kf] - d->su[k];
        fv = d->sv[kf] - d->sv[k];
    }
    if (hb) {
        size_t kb = pd_at(d, x - dx, y - dy);
        bu = d->su[k] - d->su[kb];
        bv = d->sv[k] - d->sv[kb];
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
    for (int y = r.y0; y < r.y1; y++)
        for (int x = r.x0; x < r.x1; x++) {
            size_t k = pd_at(d, x, y);
            if (!(d->ok[k] & OK_UV)) continue;
            double ux, vx, uy, vy;
            int ex = derivative(d, x, y, 1, 0, &ux, &vx), ey = derivative(d, x, y, 0, 1, &uy, &vy);
            if (!ex || !ey) continue;
            if (ex == 2 || ey == 2) d->ok[k] |= OK_SEAM;
            float *jc = d->jac + 4 * k;
            jc[0] = (float)ux;
            jc[1] = (float)uy;
            jc[2] = (float)vx;
            jc[3] = (float)vy;
            double det = (double)jc[0] * jc[3] - (double)jc[1] * jc[2];
            d->adet[k] = (float)fabs(det);
            if (det != 0.0 && isfinite(det) && d->adet[k] > 0) d->ok[k] |= OK_J;
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
    for (int y = R.y0; y < R.y1; y++)
        for (int x = E.x0; x < E.x1; x++) {
            size_t k = pd_at(d, x, y);
            float sum = 0, cnt = 0;
            if ((d->ok[k] & OK_BOTH) == OK_BOTH) {
                int id = d->id[k];
                for (int dx = -SMOOTH; dx <= SMOOTH; dx++)
                    if (usable_j(d, x + dx, y, id)) {
                        sum += d->adet[k + dx];
                        cnt += 1;
                    }
            }
            d->hs[k] = sum;
            d->hc[k] = cnt;
        }
    int ew = nprfx_rect_width(E);
    for (int y = E.y0; y < E.y1; y++)
        for (int x = E.x0; x < E.x1; x++) {
            size_t k = pd_at(d, x, y);
            float sum = 0, cnt = 0;
            if ((d->ok[k] & OK_BOTH) == OK_BOTH) {
                int id = d->id[k];
                for (int dy = -SMOOTH; dy <= SMOOTH; dy++)
                    if (y + dy >= R.y0 && y + dy < R.y1 && usable_j(d, x, y + dy, id)) {
                        size_t q = pd_at(d, x, y + dy);
                        sum += d->hs[q];
                        cnt += d->hc[q];
                    }
            }
            out[(size_t)(y - E.y0) * ew + (x - E.x0)] = cnt > 0 ? sum / cnt : 0.0f;
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
    for (int gy = 0; gy < g->gh; gy++)
        for (int gx = 0; gx < g->gw; gx++) {
            size_t i = (size_t)gy * g->gw + gx;
            int xa = g->E.x0 + gx - 1, ya = g->E.y0 + gy - 1;
            g->good[i] = 0;
            if (!nprfx_rect_contains(d->r, xa, ya)) continue;
            int id = d->id[pd_at(d, xa, ya)];
            if (!usable_j(d, xa, ya, id) || !usable_j(d, xa + 1, ya, id) ||
                !usable_j(d, xa, ya + 1, id) || !usable_j(d, xa + 1, ya + 1, id))
                continue;
            size_t k[4] = {pd_at(d, xa, ya), pd_at(d, xa + 1, ya), pd_at(d, xa, ya + 1),
                           pd_at(d, xa + 1, ya + 1)};
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
    k->s.radius = (float)sqrt(area / PI_D);
    k->s.tone = (float)tone;
    k->s.sample = index;
    k->s.object = o->id;
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

typedef struct block_ctx {
    const sjob *j;
    const pixdata *d;
    const cgrid *grid;
    nprfx_rect E;
    const oinfo *info;
    int bx0, by0, bx1, by1; /* the block's pixels */
    owner own[BLOCK * BLOCK];
    unsigned char built[BLOCK * BLOCK];
    unsigned char member[BLOCK * BLOCK]; /* the owners the current query is for */
    klist *out;
} block_ctx;

static int block_visit(void *user, int index, double u, double v)
{
    block_ctx *b = user;
    int ew = nprfx_rect_width(b->E), bw = b->bx1 - b->bx0;
    for (int y = b->by0; y < b->by1; y++)
        for (int x = b->bx0; x < b->bx1; x++) {
            int slot = (y - b->by0) * bw + (x - b->bx0);
            const oinfo *in = &b->info[(size_t)(y - b->E.y0) * ew + (x - b->E.x0)];
            if (!b->member[slot] || index >= in->limit || u < in->bb[0] || v < in->bb[1] ||
                u > in->bb[2] || v > in->bb[3])
                continue;
            owner *o = &b->own[slot];
            if (!b->built[slot]) {
                owner_build(b->j, b->d, b->grid, in->i_max, o, x, y);
                b->built[slot] = 1;
            }
            if (owns(o, u, v)) emit(o, index, u, v, b->out);
        }
    return 0;
}

static void query_members(block_ctx *b, const nprfx_ivs_index *ix)
{
    int ew = nprfx_rect_width(b->E), bw = b->bx1 - b->bx0, lim = 0;
    double u0 = INFINITY, v0 = INFINITY, u1 = -INFINITY, v1 = -INFINITY;
    for (int y = b->by0; y < b->by1; y++)
        for (int x = b->bx0; x < b->bx1; x++) {
            if (!b->member[(y - b->by0) * bw + (x - b->bx0)]) continue;
            const oinfo *in = &b->info[(size_t)(y - b->E.y0) * ew + (x - b->E.x0)];
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
 * query's box never spans empty UV space full of samples nobody owns. */
static void block_queries(block_ctx *b, const nprfx_ivs_index *ix)
{
    int ew = nprfx_rect_width(b->E), bw = b->bx1 - b->bx0, bh = b->by1 - b->by0;
    unsigned char done[BLOCK * BLOCK];
    for (int i = 0; i < bw * bh; i++) {
        const oinfo *in =
            &b->info[(size_t)(b->by0 + i / bw - b->E.y0) * ew + (b->bx0 + i % bw - b->E.x0)];
        done[i] = in->limit <= 0;
    }
    for (int i = 0; i < bw * bh; i++) {
        if (done[i]) continue;
        int id = b->d->id[pd_at(b->d, b->bx0 + i % bw, b->by0 + i / bw)];
        double u0 = INFINITY, v0 = INFINITY, u1 = -INFINITY, v1 = -INFINITY, sum = 0;
        int n = 0;
        for (int k = i; k < bw * bh; k++) {
            int x = b->bx0 + k % bw, y = b->by0 + k / bw;
            b->member[k] = !done[k] && b->d->id[pd_at(b->d, x, y)] == id;
            if (!b->member[k]) continue;
            const oinfo *in = &b->info[(size_t)(y - b->E.y0) * ew + (x - b->E.x0)];
            u0 = fmin(u0, in->bb[0]);
            v0 = fmin(v0, in->bb[1]);
            u1 = fmax(u1, in->bb[2]);
            v1 = fmax(v1, in->bb[3]);
            sum += (in->bb[2] - in->bb[0]) * (in->bb[3] - in->bb[1]);
            done[k] = 1;
            n++;
        }
        for (int k = 0; k < i; k++)
            b->member[k] = 0;
        if (n > 1 && (u1 - u0) * (v1 - v0) > 16.0 * sum) {
            /* scattered footprints: one query each */
            unsigned char group[BLOCK * BLOCK];
            memcpy(group, b->member, sizeof group);
            memset(b->member, 0, sizeof b->member);
            for (int k = i; k < bw * bh; k++) {
                if (!group[k]) continue;
                b->member[k] = 1;
                query_members(b, ix);
                b->member[k] = 0;
            }
        } else {
            query_members(b, ix);
        }
    }
}

/* The stipples owned by the pixels of E, appended to out in row-major order of their owners. */
static nprfx_result owner_stipples(const sjob *j, scratch *s, nprfx_rect E, stlist *out)
{
    const nprfx_stipple_params *p = j->p;
    if (nprfx_rect_empty(E)) return NPRFX_OK;
    nprfx_rect frame = j->in->frame;
    /* derivatives are needed on E plus 1 (corners) and plus SMOOTH (densities), and take the
     * neighbours of those */
    const int mj = SMOOTH > 1 ? SMOOTH : 1;
    nprfx_rect D = nprfx_rect_intersect(
        frame, nprfx_rect_make(E.x0 - mj - 1, E.y0 - mj - 1, E.x1 + mj + 1, E.y1 + mj + 1));
    nprfx_rect D1 =
        nprfx_rect_intersect(frame, nprfx_rect_make(E.x0 - mj, E.y0 - mj, E.x1 + mj, E.y1 + mj));
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
    smooth_area(d, E, D1, s->sdet);
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
            in->limit = v >= NPRFX_STIPPLE_MAX_SAMPLES ? NPRFX_STIPPLE_MAX_SAMPLES : (int)v;
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
    if (!ix && need > 0) r = nprfx_stipple_shared_index(j->ctx, need, &ix);
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
            b.bx0 = bx;
            b.by0 = by;
            b.bx1 = bx + BLOCK < E.x1 ? bx + BLOCK : E.x1;
            b.by1 = by + BLOCK < E.y1 ? by + BLOCK : E.y1;
            memset(b.built, 0, sizeof b.built);
            block_queries(&b, ix);
        }
    if (kl->failed && r == NPRFX_OK) r = NPRFX_ERR_OUT_OF_MEMORY;
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

static void render_tiles(void *user, int begin, int end, int worker)
{
    sjob *j = user;
    scratch *s = &j->scr[worker];
    const nprfx_stipple_params *p = j->p;
    nprfx_rect win = j->region;
    int tiles_x = (nprfx_rect_width(win) + TILE_COLS - 1) / TILE_COLS;
    for (int st = begin; st < end; st++) {
        if (atomic_load(&j->error) != NPRFX_OK) return;
        int x0 = win.x0 + (st % tiles_x) * TILE_COLS, y0 = win.y0 + (st / tiles_x) * STRIPE_ROWS;
        int x1 = x0 + TILE_COLS < win.x1 ? x0 + TILE_COLS : win.x1;
        int y1 = y0 + STRIPE_ROWS < win.y1 ? y0 + STRIPE_ROWS : win.y1;
        nprfx_rect rows = nprfx_rect_make(x0, y0, x1, y1);
        nprfx_rect E =
            nprfx_rect_intersect(j->in->frame, nprfx_rect_make(x0 - j->margin, y0 - j->margin,
                                                               x1 + j->margin, y1 + j->margin));
        int width = x1 - x0;
        size_t npx = (size_t)width * (size_t)(y1 - y0);
        s->sl.n = 0;
        nprfx_result r = reserve((void **)&s->t, &s->tcap, npx, sizeof(float))
                             ? owner_stipples(j, s, E, &s->sl)
                             : NPRFX_ERR_OUT_OF_MEMORY;
        if (r != NPRFX_OK) {
            set_error(j, r);
            return;
        }
        float *t = s->t;
        for (size_t i = 0; i < npx; i++)
            t[i] = 1.0f;
        for (size_t i = 0; i < s->sl.n; i++) {
            const nprfx_stipple *q = &s->sl.s[i];
            splat_disc(t, rows, q->x, q->y, q->radius, q->tone);
        }
        nprfx_image *o = j->out;
        int extra = p->coverage_channel;
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++) {
                float dk = 1.0f - t[(size_t)(y - y0) * width + (x - x0)];
                float *px = nprfx_image_at(o, x, y);
                for (int c = 0; c < 4; c++)
                    px[c] = p->paper[c] + dk * (p->ink[c] - p->paper[c]);
                if (extra) px[4] = dk;
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
    atomic_init(&j->error, NPRFX_OK);
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
    int tiles = ((nprfx_rect_height(window) + STRIPE_ROWS - 1) / STRIPE_ROWS) *
                ((nprfx_rect_width(window) + TILE_COLS - 1) / TILE_COLS);
    nprfx_parallel_for(nprfx_context_executor(ctx), tiles, 1, render_tiles, &j);
    r = atomic_load(&j.error);
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
        set_error(j, owner_stipples(j, &j->scr[worker], E, &j->lists[st]));
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
    p.coverage_channel = 1;
    p.plane_scale = NPRFX_STIPPLE_PLANE_PIXELS;
    p.tile = 0.25;
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
    if ((r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, n), 1, &tone)) != NPRFX_OK) return r;
    if ((r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, n), 5, &out)) != NPRFX_OK) {
        nprfx_image_free(&tone);
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
