/* The flow node's core (docs/design.md §3.15): luminance, the provider call at a fraction of the
 * resolution, and the confidence of a flow from a forward-backward and a photometric check. The
 * solver itself is the front end's (nprfx_context_init.flow): core stays C11 + libm. See
 * nprfx/flow.h. */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "base/internal_state.h"
#include "nprfx/exec.h"
#include "nprfx/flow.h"

#define FLOW_NO_PROVIDER_MESSAGE                                                                   \
    "flow: this build has no optical flow provider (build with OpenCV: install "                   \
    "libopencv-video-dev and re-run cmake)"

void nprfx_flow_luminance(const nprfx_image *im, float *lum, unsigned char *ok)
{
    int w = nprfx_rect_width(im->bounds), h = nprfx_rect_height(im->bounds);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = nprfx_image_at(im, im->bounds.x0 + x, im->bounds.y0 + y);
            int good = 1;
            for (int c = 0; c < im->channels && c < 4; c++)
                good &= isfinite(p[c]) != 0;
            double v = 0;
            if (good) {
                v = im->channels >= 3 ? 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] : p[0];
                /* Scene-linear values reach far above 1: x / (1 + x) keeps their order and detail
                 * inside [0, 1), where a solver on 8 bits (DIS) resolves them. */
                v = v > 0 ? v / (1 + v) : 0;
            }
            lum[(size_t)y * (size_t)w + (size_t)x] = (float)v;
            if (ok) ok[(size_t)y * (size_t)w + (size_t)x] = (unsigned char)good;
        }
}

/* Box average of src (w x h) into dst (sw x sh): output pixel i covers the source pixels
 * [floor(i w / sw), floor((i + 1) w / sw)), at least one. */
static void downscale(const float *src, int w, int h, float *dst, int sw, int sh)
{
    for (int j = 0; j < sh; j++) {
        int y0 = (int)((long long)j * h / sh), y1 = (int)((long long)(j + 1) * h / sh);
        if (y1 <= y0) y1 = y0 + 1;
        for (int i = 0; i < sw; i++) {
            int x0 = (int)((long long)i * w / sw), x1 = (int)((long long)(i + 1) * w / sw);
            if (x1 <= x0) x1 = x0 + 1;
            double s = 0;
            for (int y = y0; y < y1; y++)
                for (int x = x0; x < x1; x++)
                    s += src[(size_t)y * (size_t)w + (size_t)x];
            dst[(size_t)j * (size_t)sw + (size_t)i] = (float)(s / ((double)(x1 - x0) * (y1 - y0)));
        }
    }
}

/* The small flow (sw x sh) bilinearly at full-resolution pixel centres, vectors multiplied by
 * the size ratio: pixel x of the full image is at (x + 0.5) sw / w - 0.5 in the small one. */
static void upsample(const float *small, int sw, int sh, float *flow, int w, int h)
{
    double kx = (double)sw / w, ky = (double)sh / h;
    for (int y = 0; y < h; y++) {
        double v = (y + 0.5) * ky - 0.5;
        if (v < 0) v = 0;
        if (v > sh - 1) v = sh - 1;
        int j0 = (int)floor(v), j1 = j0 + 1 < sh ? j0 + 1 : j0;
        double fy = v - j0;
        for (int x = 0; x < w; x++) {
            double u = (x + 0.5) * kx - 0.5;
            if (u < 0) u = 0;
            if (u > sw - 1) u = sw - 1;
            int i0 = (int)floor(u), i1 = i0 + 1 < sw ? i0 + 1 : i0;
            double fx = u - i0;
            for (int c = 0; c < 2; c++) {
                double a = small[2 * ((size_t)j0 * sw + i0) + c],
                       b = small[2 * ((size_t)j0 * sw + i1) + c],
                       d = small[2 * ((size_t)j1 * sw + i0) + c],
                       e = small[2 * ((size_t)j1 * sw + i1) + c];
                double s = (a * (1 - fx) + b * fx) * (1 - fy) + (d * (1 - fx) + e * fx) * fy;
                flow[2 * ((size_t)y * w + x) + c] = (float)(s / (c == 0 ? kx : ky));
            }
        }
    }
}

nprfx_result nprfx_flow_solve(nprfx_context *ctx, const float *a, const float *b, int w, int h,
                              double scale, nprfx_flow_preset preset, float *flow)
{
    const nprfx_flow_provider *fp = nprfx_context_flow(ctx);
    if (!fp || fp->size < offsetof(nprfx_flow_provider, user) + sizeof fp->user || !fp->compute)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED, FLOW_NO_PROVIDER_MESSAGE);
    if (w < 1 || h < 1 || !a || !b || !flow)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "flow: no images to solve");
    if (!(scale > 0) || scale > 1) scale = 1;
    int sw = (int)ceil(w * scale), sh = (int)ceil(h * scale);
    if (sw < 1) sw = 1;
    if (sh < 1) sh = 1;
    nprfx_result r;
    size_t n = (size_t)w * (size_t)h;
    if (sw >= w && sh >= h) {
        r = fp->compute(fp->user, ctx, a, b, w, h, preset, flow);
    } else {
        size_t sn = (size_t)sw * (size_t)sh;
        float *sa = malloc(sn * sizeof *sa), *sb = malloc(sn * sizeof *sb),
              *sf = malloc(2 * sn * sizeof *sf);
        if (!sa || !sb || !sf) {
            free(sa), free(sb), free(sf);
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "flow: out of memory at %dx%d", sw,
                               sh);
        }
        downscale(a, w, h, sa, sw, sh);
        downscale(b, w, h, sb, sw, sh);
        r = fp->compute(fp->user, ctx, sa, sb, sw, sh, preset, sf);
        if (!r) upsample(sf, sw, sh, flow, w, h);
        free(sa), free(sb), free(sf);
    }
    if (r) return r;
    /* A provider's NaN would travel into the confidence lookups: it is no vector. */
    for (size_t i = 0; i < 2 * n; i++)
        if (!isfinite(flow[i])) flow[i] = 0;
    return NPRFX_OK;
}

/* Bilinear sample of channel c of a (w x h, stride `ch` floats a pixel) at (u, v), which lies
 * inside [0, w-1] x [0, h-1]; *good: every tap with a weight in ok (NULL: all). */
static double bilinear(const float *a, int ch, int c, const unsigned char *ok, int w, int h,
                       double u, double v, int *good)
{
    int i0 = (int)floor(u), j0 = (int)floor(v);
    if (i0 > w - 1) i0 = w - 1;
    if (j0 > h - 1) j0 = h - 1;
    int i1 = i0 + 1 < w ? i0 + 1 : i0, j1 = j0 + 1 < h ? j0 + 1 : j0;
    double fx = u - i0, fy = v - j0;
    size_t p00 = (size_t)j0 * w + i0, p01 = (size_t)j0 * w + i1, p10 = (size_t)j1 * w + i0,
           p11 = (size_t)j1 * w + i1;
    if (ok && good)
        *good = ok[p00] && (fx == 0 || ok[p01]) && (fy == 0 || ok[p10]) &&
                (fx == 0 || fy == 0 || ok[p11]);
    return (a[p00 * ch + c] * (1 - fx) + a[p01 * ch + c] * fx) * (1 - fy) +
           (a[p10 * ch + c] * (1 - fx) + a[p11 * ch + c] * fx) * fy;
}

/* The confidence of one pixel; see nprfx_flow_confidence. */
static float confidence_at(const float *f_ab, const float *f_ba, const float *lum_a,
                           const float *lum_b, const unsigned char *ok_a, const unsigned char *ok_b,
                           int w, int h, double inv_fb, double inv_ph, int x, int y)
{
    size_t i = (size_t)y * w + x;
    if (ok_a && !ok_a[i]) return 0;
    /* Outside the other frame: beyond its pixels' squares. Within half a pixel of the edge the
     * lookups clamp to the edge pixels (the point is in the frame, only not at a centre). */
    double u = x + f_ab[2 * i], v = y + f_ab[2 * i + 1];
    if (!(u >= -0.5 && u < w - 0.5 && v >= -0.5 && v < h - 0.5)) return 0;
    u = u < 0 ? 0 : u > w - 1 ? w - 1 : u;
    v = v < 0 ? 0 : v > h - 1 ? h - 1 : v;
    int good = 1;
    double bx = bilinear(f_ba, 2, 0, ok_b, w, h, u, v, &good);
    double by = bilinear(f_ba, 2, 1, NULL, w, h, u, v, NULL);
    if (!good) return 0;
    double ex = f_ab[2 * i] + bx, ey = f_ab[2 * i + 1] + by;
    double e = (ex * ex + ey * ey) * inv_fb;
    if (inv_ph > 0) {
        double d = lum_a[i] - bilinear(lum_b, 1, 0, NULL, w, h, u, v, NULL);
        e += d * d * inv_ph;
    }
    return (float)exp(-e);
}

void nprfx_flow_confidence(const float *f_ab, const float *f_ba, const float *lum_a,
                           const float *lum_b, const unsigned char *ok_a, const unsigned char *ok_b,
                           int w, int h, double consistency, double photometric, float *conf)
{
    /* exp(-e_fb^2 / (2 c^2) - e_ph^2 / (2 p^2)): the product of the two Gaussians. */
    double inv_fb = consistency > 0 ? 1 / (2 * consistency * consistency) : INFINITY;
    double inv_ph = photometric > 0 ? 1 / (2 * photometric * photometric) : 0;
    if (isinf(inv_fb)) inv_fb = 1e300;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            conf[(size_t)y * w + x] =
                confidence_at(f_ab, f_ba, lum_a, lum_b, ok_a, ok_b, w, h, inv_fb, inv_ph, x, y);
}

/* ---- the node's render, with the last pairs of flows cached ---- */

/* The flows between two frames a < b (the earlier first), solved from their luminances. */
typedef struct flow_pair {
    int used;
    int w, h, preset;
    double scale;
    uint64_t ha, hb;
    float *la, *lb;           /* the luminances they were solved from: a hit compares them whole */
    unsigned char *oka, *okb; /* and which pixels were missing (the confidences depend on it) */
    float *fab, *fba;         /* a to b, b to a */
    /* The gated confidences of fab (over a's pixels) and fba (over b's), once computed, for
     * these thresholds: tiles of one frame, and the next frame's prev, reuse them. */
    float *conf[2];
    double conf_c[2], conf_p[2];
    unsigned long long stamp;
} flow_pair;

/* Two pairs: frame t needs (t-1, t) and (t, t+1), and (t, t+1) is frame t+1's (t, t+1) again. */
enum { FLOW_CACHE_PAIRS = 2 };

typedef struct flow_cache {
    pthread_mutex_t lock; /* first member (internal_state.h); held through a whole render */
    flow_pair pairs[FLOW_CACHE_PAIRS];
    unsigned long long clock;
} flow_cache;

static void pair_clear(flow_pair *p)
{
    free(p->la), free(p->lb), free(p->oka), free(p->okb), free(p->fab), free(p->fba);
    free(p->conf[0]), free(p->conf[1]);
    memset(p, 0, sizeof *p);
}

double nprfx_flow_state_bytes(int width, int height)
{
    /* per pixel of a pair: la, lb, fab (2), fba (2), conf (2) floats, and oka, okb */
    double per_pixel = 8.0 * sizeof(float) + 2.0;
    return (double)FLOW_CACHE_PAIRS * width * height * per_pixel;
}

void nprfx_flow_state_free(void *state)
{
    flow_cache *c = state;
    if (!c) return;
    for (int i = 0; i < FLOW_CACHE_PAIRS; i++)
        pair_clear(&c->pairs[i]);
    internal_state_free(c);
}

static uint64_t fingerprint(const float *lum, size_t n)
{
    uint64_t hsh = 0x9e3779b97f4a7c15ull ^ n;
    for (size_t i = 0; i < n; i++) {
        uint32_t bits;
        memcpy(&bits, &lum[i], sizeof bits);
        hsh = (hsh ^ bits) * 0x100000001b3ull;
        hsh ^= hsh >> 29;
    }
    return hsh;
}

/* One frame as the flow sees it. */
typedef struct flow_frame {
    int t;
    float *lum;
    unsigned char *ok;
    uint64_t hash;
} flow_frame;

/* The flows between frames a and b (a earlier), from the cache, else a slot to solve them into
 * (*solve = 1): the least recently used cache entry, or `owned` without a cache. */
static nprfx_result find_pair(nprfx_context *ctx, flow_cache *cache, const nprfx_flow_params *p,
                              const flow_frame *a, const flow_frame *b, int w, int h,
                              flow_pair **out, flow_pair *owned, int *solve)
{
    size_t n = (size_t)w * (size_t)h;
    *solve = 0;
    if (cache) {
        for (int i = 0; i < FLOW_CACHE_PAIRS; i++) {
            flow_pair *q = &cache->pairs[i];
            if (q->used && q->w == w && q->h == h && q->preset == p->preset &&
                q->scale == p->scale && q->ha == a->hash && q->hb == b->hash &&
                !memcmp(q->la, a->lum, n * sizeof(float)) &&
                !memcmp(q->lb, b->lum, n * sizeof(float)) && !memcmp(q->oka, a->ok, n) &&
                !memcmp(q->okb, b->ok, n)) {
                q->stamp = ++cache->clock;
                *out = q;
                return NPRFX_OK;
            }
        }
    }
    flow_pair *q = owned;
    if (cache) {
        /* The least recently stamped (an empty slot's stamp is 0). Frame t's other pair, hit or
         * about to be solved, was stamped just now, so it is never the one given up. */
        q = &cache->pairs[0];
        for (int i = 1; i < FLOW_CACHE_PAIRS; i++)
            if (cache->pairs[i].stamp < q->stamp) q = &cache->pairs[i];
    }
    pair_clear(q);
    q->la = malloc(n * sizeof(float));
    q->lb = malloc(n * sizeof(float));
    q->fab = malloc(2 * n * sizeof(float));
    q->fba = malloc(2 * n * sizeof(float));
    q->oka = malloc(n);
    q->okb = malloc(n);
    if (!q->la || !q->lb || !q->fab || !q->fba || !q->oka || !q->okb) {
        pair_clear(q);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "flow: out of memory for %dx%d flows", w,
                           h);
    }
    memcpy(q->la, a->lum, n * sizeof(float));
    memcpy(q->lb, b->lum, n * sizeof(float));
    memcpy(q->oka, a->ok, n);
    memcpy(q->okb, b->ok, n);
    q->w = w, q->h = h, q->preset = p->preset, q->scale = p->scale;
    q->ha = a->hash, q->hb = b->hash;
    q->stamp = cache ? ++cache->clock : 0;
    *out = q;
    *solve = 1;
    return NPRFX_OK;
}

/* Up to four solves of one render, run side by side through the executor: each is one provider
 * call writing its own buffer, so the order they finish in changes nothing. */
typedef struct solve_job {
    const float *from, *to;
    float *flow;
    nprfx_result r;
} solve_job;

typedef struct solve_batch {
    nprfx_context *ctx;
    const nprfx_flow_params *p;
    int w, h;
    solve_job jobs[4];
} solve_batch;

static void solve_range(void *user, int begin, int end, int worker)
{
    (void)worker;
    solve_batch *sb = user;
    for (int i = begin; i < end; i++) {
        solve_job *j = &sb->jobs[i];
        j->r = nprfx_flow_solve(sb->ctx, j->from, j->to, sb->w, sb->h, sb->p->scale,
                                (nprfx_flow_preset)sb->p->preset, j->flow);
    }
}

int nprfx_flow_output_channels(int output, int *which)
{
    static const int sets[NPRFX_FLOW_OUTPUT_COUNT][NPRFX_FLOW_CHANNELS + 1] = {
        {6, NPRFX_FLOW_PREV_X, NPRFX_FLOW_PREV_Y, NPRFX_FLOW_NEXT_X, NPRFX_FLOW_NEXT_Y,
         NPRFX_FLOW_CONF_PREV, NPRFX_FLOW_CONF_NEXT},
        {3, NPRFX_FLOW_PREV_X, NPRFX_FLOW_PREV_Y, NPRFX_FLOW_CONF_PREV},
        {3, NPRFX_FLOW_NEXT_X, NPRFX_FLOW_NEXT_Y, NPRFX_FLOW_CONF_NEXT},
        {4, NPRFX_FLOW_PREV_X, NPRFX_FLOW_PREV_Y, NPRFX_FLOW_NEXT_X, NPRFX_FLOW_NEXT_Y}};
    if (output < 0 || output >= NPRFX_FLOW_OUTPUT_COUNT) return 0;
    for (int i = 0; which && i < sets[output][0]; i++)
        which[i] = sets[output][i + 1];
    return sets[output][0];
}

double nprfx_flow_cut_gate(double consistent)
{
    double s = (consistent - 0.6) / 0.25;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    return s * s * (3 - 2 * s);
}

/* The whole frame's confidence in blocks of rows, counting the pixels at 0.5 or more. */
enum { CONF_BLOCK_ROWS = 16 };
typedef struct conf_rows {
    const float *fwd, *back, *la, *lb;
    const unsigned char *oka, *okb;
    int w, h;
    double inv_fb, inv_ph;
    float *conf;
    long long *good;
} conf_rows;

static void conf_range(void *user, int begin, int end, int worker)
{
    (void)worker;
    conf_rows *c = user;
    for (int blk = begin; blk < end; blk++) {
        long long n = 0;
        int y1 = (blk + 1) * CONF_BLOCK_ROWS < c->h ? (blk + 1) * CONF_BLOCK_ROWS : c->h;
        for (int y = blk * CONF_BLOCK_ROWS; y < y1; y++)
            for (int x = 0; x < c->w; x++) {
                float v = confidence_at(c->fwd, c->back, c->la, c->lb, c->oka, c->okb, c->w, c->h,
                                        c->inv_fb, c->inv_ph, x, y);
                c->conf[(size_t)y * c->w + x] = v;
                n += v >= 0.5f;
            }
        c->good[blk] = n;
    }
}

/* The gated confidence of one direction of a pair (dir 0: fab over a's pixels, 1: fba over
 * b's), computed over the whole frame once for these thresholds and kept with the pair. */
static nprfx_result pair_confidence(nprfx_context *ctx, flow_pair *q, int dir,
                                    const nprfx_flow_params *p, const float **out)
{
    if (q->conf[dir] && q->conf_c[dir] == p->consistency && q->conf_p[dir] == p->photometric) {
        *out = q->conf[dir];
        return NPRFX_OK;
    }
    int w = q->w, h = q->h, blocks = (h + CONF_BLOCK_ROWS - 1) / CONF_BLOCK_ROWS;
    if (!q->conf[dir]) q->conf[dir] = malloc((size_t)w * (size_t)h * sizeof(float));
    long long *good = calloc((size_t)blocks, sizeof *good);
    if (!q->conf[dir] || !good) {
        free(good);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "flow: out of memory at %dx%d", w, h);
    }
    q->conf_c[dir] = NAN; /* not valid until done */
    conf_rows cr = {dir ? q->fba : q->fab,
                    dir ? q->fab : q->fba,
                    dir ? q->lb : q->la,
                    dir ? q->la : q->lb,
                    dir ? q->okb : q->oka,
                    dir ? q->oka : q->okb,
                    w,
                    h,
                    1 / (2 * p->consistency * p->consistency),
                    p->photometric > 0 ? 1 / (2 * p->photometric * p->photometric) : 0,
                    q->conf[dir],
                    good};
    nprfx_parallel_for(nprfx_context_executor(ctx), blocks, 1, conf_range, &cr);
    long long total = 0;
    for (int i = 0; i < blocks; i++)
        total += good[i];
    free(good);
    float gate = (float)nprfx_flow_cut_gate((double)total / ((double)w * h));
    if (gate != 1.0f)
        for (size_t i = 0; i < (size_t)w * (size_t)h; i++)
            q->conf[dir][i] *= gate;
    q->conf_c[dir] = p->consistency;
    q->conf_p[dir] = p->photometric;
    *out = q->conf[dir];
    return NPRFX_OK;
}

static nprfx_result frame_load(nprfx_context *ctx, const nprfx_image *im, int t, flow_frame *f)
{
    int w = nprfx_rect_width(im->bounds), h = nprfx_rect_height(im->bounds);
    size_t n = (size_t)w * (size_t)h;
    f->t = t;
    f->lum = malloc(n * sizeof *f->lum);
    f->ok = malloc(n);
    if (!f->lum || !f->ok)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "flow: out of memory at %dx%d", w, h);
    nprfx_flow_luminance(im, f->lum, f->ok);
    f->hash = fingerprint(f->lum, n);
    return NPRFX_OK;
}

static void frame_free(flow_frame *f)
{
    free(f->lum), free(f->ok);
    f->lum = NULL, f->ok = NULL;
}

nprfx_result nprfx_flow_render(const nprfx_render_args *args, const nprfx_flow_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const int input = NPRFX_FLOW_IN_IMAGE;
    const nprfx_image *image = nprfx_render_input(args, input);
    double time = args->time;
    int first_frame = args->first_frame, last_frame = args->last_frame;
    nprfx_fetch_fn fetch = args->fetch;
    void *fetch_user = args->fetch_user;
    void **state = args->state;
    nprfx_rect window = args->window;
    nprfx_image *out = args->output;
    int which[NPRFX_FLOW_CHANNELS];
    int nch = p ? nprfx_flow_output_channels(p->output, which) : 0;
    if (!p || !out || !out->data || nch < 1 || out->channels != nch)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "flow: no params or output");
    /* at[c]: the output channel of flow channel c, -1 when this output leaves it out */
    int at[NPRFX_FLOW_CHANNELS] = {-1, -1, -1, -1, -1, -1};
    for (int i = 0; i < nch; i++)
        at[which[i]] = i;
    if (!image || !image->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "flow: input 'image' is not connected");
    if (p->preset < 0 || p->preset >= NPRFX_FLOW_PRESET_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "flow.preset: no preset %d", p->preset);
    /* Without a solver nothing here means anything, even where no neighbour exists. */
    if (!nprfx_context_flow(ctx))
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED, FLOW_NO_PROVIDER_MESSAGE);
    window = nprfx_rect_intersect(window, out->bounds);
    if (nprfx_rect_empty(window)) return NPRFX_OK;
    nprfx_image win = nprfx_image_crop(out, window);
    float zero[NPRFX_FLOW_CHANNELS] = {0}; /* nch of them */
    nprfx_image_fill(&win, zero);

    int t = (int)floor(time + 0.5);
    int known = first_frame <= last_frame;
    /* A direction no output channel shows is not solved (nor its neighbour fetched). */
    int want_prev = at[NPRFX_FLOW_PREV_X] >= 0 || at[NPRFX_FLOW_CONF_PREV] >= 0;
    int want_next = at[NPRFX_FLOW_NEXT_X] >= 0 || at[NPRFX_FLOW_CONF_NEXT] >= 0;
    int has_prev = want_prev && (!known || t - 1 >= first_frame);
    int has_next = want_next && (!known || t + 1 <= last_frame);
    nprfx_rect b = image->bounds;
    int w = nprfx_rect_width(b), h = nprfx_rect_height(b);
    if (w < 1 || h < 1 || (!has_prev && !has_next)) return NPRFX_OK;
    if (!fetch)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "flow: this host cannot fetch other frames (frame %d needs its "
                           "neighbours)",
                           t);

    flow_frame cur = {0}, nb[2] = {{0}, {0}};
    flow_cache *cache = NULL;
    flow_pair owned[2], *pairs[2] = {NULL, NULL};
    memset(owned, 0, sizeof owned);
    nprfx_result r = frame_load(ctx, image, t, &cur);
    /* The neighbours: same data window as the frame, or the vectors would mean nothing. */
    for (int k = 0; k < 2 && !r; k++) {
        int tn = k == 0 ? t - 1 : t + 1;
        if (!(k == 0 ? has_prev : has_next)) continue;
        nprfx_image other;
        if ((r = fetch(fetch_user, input, tn, &other))) break;
        if (!other.data) {
            r = nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "flow: input 'image' has no frame %d",
                            tn);
            break;
        }
        if (!nprfx_rect_equal(other.bounds, b)) {
            r = nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                            "flow: input 'image' is %dx%d%+d%+d at frame %d but %dx%d%+d%+d at "
                            "frame %d: the flow needs frames of one size",
                            nprfx_rect_width(other.bounds), nprfx_rect_height(other.bounds),
                            other.bounds.x0, other.bounds.y0, tn, w, h, b.x0, b.y0, t);
            break;
        }
        r = frame_load(ctx, &other, tn, &nb[k]);
    }
    if (!r && state) {
        cache = internal_state_get(state, sizeof *cache);
        if (!cache) r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "flow: out of memory");
    }
    if (cache) pthread_mutex_lock(&cache->lock);
    /* pairs[0] = (t-1, t), pairs[1] = (t, t+1): always the earlier frame first, so frame t+1
     * finds frame t's second pair as its first. */
    solve_batch sb;
    memset(&sb, 0, sizeof sb);
    sb.ctx = ctx, sb.p = p, sb.w = w, sb.h = h;
    int njobs = 0, solved[2] = {0, 0};
    for (int k = 0; k < 2 && !r; k++) {
        if (!(k == 0 ? has_prev : has_next)) continue;
        const flow_frame *fa = k == 0 ? &nb[0] : &cur, *fb = k == 0 ? &cur : &nb[1];
        int solve = 0;
        r = find_pair(ctx, cache, p, fa, fb, w, h, &pairs[k], &owned[k], &solve);
        solved[k] = solve;
        if (!r && solve) {
            sb.jobs[njobs++] = (solve_job){pairs[k]->la, pairs[k]->lb, pairs[k]->fab, NPRFX_OK};
            sb.jobs[njobs++] = (solve_job){pairs[k]->lb, pairs[k]->la, pairs[k]->fba, NPRFX_OK};
        }
    }
    if (!r && njobs) {
        nprfx_parallel_for(nprfx_context_executor(ctx), njobs, 1, solve_range, &sb);
        for (int i = 0; i < njobs && !r; i++)
            r = sb.jobs[i].r;
        for (int k = 0; k < 2; k++)
            if (solved[k]) {
                if (r)
                    pair_clear(pairs[k]); /* a failed solve leaves nothing behind to hit */
                else
                    pairs[k]->used = 1;
            }
    }
    if (!r) {
        nprfx_rect ow = nprfx_rect_intersect(window, b);
        for (int k = 0; k < 2 && !r; k++) {
            if (!pairs[k]) continue;
            /* motion_prev = flow t -> t-1, the pair's b to a; motion_next = t -> t+1, a to b. */
            int dir = k == 0 ? 1 : 0;
            const float *fwd = dir ? pairs[k]->fba : pairs[k]->fab;
            const float *conf = NULL;
            r = pair_confidence(ctx, pairs[k], dir, p, &conf);
            for (int y = ow.y0; y < ow.y1 && !r; y++)
                for (int x = ow.x0; x < ow.x1; x++) {
                    size_t q = (size_t)(y - b.y0) * w + (size_t)(x - b.x0);
                    float *px = nprfx_image_at(out, x, y);
                    if (at[2 * k] >= 0) px[at[2 * k]] = fwd[2 * q];
                    if (at[2 * k + 1] >= 0) px[at[2 * k + 1]] = fwd[2 * q + 1];
                    if (at[NPRFX_FLOW_CONF_PREV + k] >= 0)
                        px[at[NPRFX_FLOW_CONF_PREV + k]] = conf[q];
                }
        }
    }
    if (cache) pthread_mutex_unlock(&cache->lock);
    pair_clear(&owned[0]);
    pair_clear(&owned[1]);
    frame_free(&cur);
    frame_free(&nb[0]);
    frame_free(&nb[1]);
    return r;
}
