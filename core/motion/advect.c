/* The advect node: two staggered layers of texture coordinates carried along motion_prev, each
 * restarted from the identity every period frames, blended by temporal and distortion weights
 * (Neyret 2003; Bousseau et al. 2007; docs/design.md §3.16). See nprfx/advect.h.
 *
 * Frame t of a layer is defined by the recursion from its last restart, at most `period` frames
 * back, so a frame rendered alone (a farm chunk's first) is the in-order result bit for bit. The
 * per-instance cache keeps each layer's latest state and the latest result: it only saves work
 * (in-order rendering steps each layer once a frame; the tiles of one frame share one result). */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/advect.h"
#include "nprfx/rng.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"

#include "base/internal_state.h"

enum { IN_MOTION = NPRFX_ADVECT_IN_MOTION_PREV, IN_CONF = NPRFX_ADVECT_IN_CONFIDENCE };

nprfx_result nprfx_advect_check(nprfx_context *ctx, const nprfx_advect_params *p)
{
    if (!p) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "advect: no params");
    if (p->layers != 1 && p->layers != 2)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "advect.layers: %d is not 1 or 2",
                           p->layers);
    if (p->period < 2)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "advect.period: %d is below 2", p->period);
    if (!(p->max_distortion >= 1.0) || !isfinite(p->max_distortion))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "advect.max_distortion: %g is not a finite ratio >= 1",
                           p->max_distortion);
    if (!isfinite(p->min_confidence))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "advect.min_confidence: %g is not finite",
                           p->min_confidence);
    if (p->output < 0 || p->output >= NPRFX_ADVECT_OUTPUT_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "advect.output: no option %d", p->output);
    return NPRFX_OK;
}

int nprfx_advect_output_channels(int output, const char **names)
{
    static const char *const all[NPRFX_ADVECT_CHANNELS] = {"a.U", "a.V", "b.U", "b.V", "mix"};
    int first, count;
    switch (output) {
    case NPRFX_ADVECT_OUTPUT_ALL:
        first = 0, count = 5;
        break;
    case NPRFX_ADVECT_OUTPUT_LAYERS:
        first = 0, count = 4;
        break;
    case NPRFX_ADVECT_OUTPUT_MIX:
        first = 4, count = 1;
        break;
    default:
        return 0;
    }
    for (int c = 0; names && c < count; c++)
        names[c] = all[first + c];
    return count;
}

/* floor(a / b) for b > 0: frames before the origin belong to the period that holds them. */
static int64_t floor_div(int64_t a, int64_t b)
{
    int64_t q = a / b;
    return (a % b != 0 && a < 0) ? q - 1 : q;
}

void nprfx_advect_schedule(const nprfx_advect_params *p, int layer, int time, int first_frame,
                           int last_frame, nprfx_advect_layer_time *out)
{
    int known = last_frame >= first_frame;
    int64_t t = time, origin = known ? first_frame : 0, r;
    if (p->layers == 1) {
        /* No periodic restart: it would show, with no second layer to hide it. */
        r = known && t >= origin ? origin : t;
        out->restart = (int)r;
        out->age = (int)(t - r);
        out->tri = 1.0;
        return;
    }
    int64_t period = p->period, phase = layer ? period / 2 : 0;
    int64_t last_periodic = origin + phase + floor_div(t - origin - phase, period) * period;
    int64_t age = t - last_periodic; /* in [0, period) */
    r = last_periodic;
    /* No history before the shot: a layer whose periodic restart lies before the first frame
     * starts there (it carries its periodic weight, which the schedule alone decides). */
    if (known && r < origin) r = origin;
    if (r > t) r = t;
    out->restart = (int)r;
    out->age = (int)age;
    out->tri = 1.0 - fabs(2.0 * (double)age / (double)period - 1.0);
}

/* ---- one step ------------------------------------------------------------------------------ */

static inline void seed_px(const nprfx_rect *frame, double plane, int x, int y, float *o)
{
    o[0] = (float)((double)(x - frame->x0) / plane);
    o[1] = (float)((double)(y - frame->y0) / plane);
}

void nprfx_advect_seed(nprfx_rect frame, double plane, nprfx_rect window, nprfx_image *coords)
{
    window = nprfx_rect_intersect(window, coords->bounds);
    for (int y = window.y0; y < window.y1; y++)
        for (int x = window.x0; x < window.x1; x++)
            seed_px(&frame, plane, x, y, nprfx_image_at(coords, x, y));
}

typedef struct step_job {
    const nprfx_image *prev, *motion, *conf;
    nprfx_image *next;
    nprfx_rect frame;
    double plane, min_conf, motion_scale;
} step_job;

static void step_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const step_job *j = user;
    const nprfx_rect f = j->frame;
    for (int y = f.y0 + begin; y < f.y0 + end; y++)
        for (int x = f.x0; x < f.x1; x++) {
            float *o = nprfx_image_at(j->next, x, y);
            double mx = 0.0, my = 0.0;
            if (nprfx_rect_contains(j->motion->bounds, x, y)) {
                const float *m = nprfx_image_at(j->motion, x, y);
                mx = m[0] * j->motion_scale;
                my = m[1] * j->motion_scale;
            }
            int fresh = !isfinite(mx) || !isfinite(my);
            if (j->conf) {
                double c = 0.0; /* outside its data window: 0, as EXR readers give */
                if (nprfx_rect_contains(j->conf->bounds, x, y))
                    c = nprfx_image_at(j->conf, x, y)[0];
                fresh |= !(c >= j->min_conf) || !isfinite(c); /* non-finite: missing */
            }
            double px = x + mx, py = y + my;
            /* Only where all the taps are inside: the previous frame knows nothing beyond. */
            fresh |= !(px >= f.x0 && px <= f.x1 - 1 && py >= f.y0 && py <= f.y1 - 1);
            if (fresh) {
                seed_px(&f, j->plane, x, y, o);
                continue;
            }
            int ix = (int)floor(px), iy = (int)floor(py);
            double fx = px - ix, fy = py - iy;
            int ix1 = ix + 1 < f.x1 ? ix + 1 : ix, iy1 = iy + 1 < f.y1 ? iy + 1 : iy;
            const float *p00 = nprfx_image_at(j->prev, ix, iy);
            const float *p10 = nprfx_image_at(j->prev, ix1, iy);
            const float *p01 = nprfx_image_at(j->prev, ix, iy1);
            const float *p11 = nprfx_image_at(j->prev, ix1, iy1);
            for (int c = 0; c < 2; c++) {
                /* a + f (b - a): exact on a linear field whose values and offsets are dyadic,
                 * and it copies exactly at integer offsets. */
                double top = p00[c] + fx * ((double)p10[c] - p00[c]);
                double bot = p01[c] + fx * ((double)p11[c] - p01[c]);
                o[c] = (float)(top + fy * (bot - top));
            }
        }
}

nprfx_result nprfx_advect_step(nprfx_context *ctx, const nprfx_advect_params *p, nprfx_rect frame,
                               double plane, const nprfx_image *prev, const nprfx_image *motion,
                               const nprfx_image *confidence, nprfx_image *next)
{
    nprfx_result r = nprfx_advect_check(ctx, p);
    if (r) return r;
    if (!prev || !prev->data || !next || !next->data || !motion || !motion->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "advect: step without images");
    if (!nprfx_rect_equal(prev->bounds, frame) || !nprfx_rect_equal(next->bounds, frame) ||
        prev->channels < 2 || next->channels < 2 || motion->channels < 2)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "advect: the coordinates must cover the frame with 2 channels");
    if (!(plane > 0))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "advect: plane %g", plane);
    step_job j = {prev,
                  motion,
                  confidence && confidence->data ? confidence : NULL,
                  next,
                  frame,
                  plane,
                  p->min_confidence,
                  p->motion_scale > 0.0 ? p->motion_scale : 1.0};
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(frame), 16, step_rows, &j);
    return NPRFX_OK;
}

/* ---- weights ------------------------------------------------------------------------------- */

double nprfx_advect_distortion(const double J[4], double max_distortion)
{
    double a = J[0], b = J[1], c = J[2], d = J[3];
    double det = a * d - b * c;
    if (!isfinite(det) || !(det > 0.0)) return 0.0; /* folded or degenerate */
    /* Singular values of [[a, b], [c, d]]: s1^2 + s2^2 = |J|_F^2 and s1 s2 = det. */
    double e = 0.5 * (a * a + b * b + c * c + d * d);
    double disc = e * e - det * det;
    double s1 = sqrt(e + sqrt(disc > 0.0 ? disc : 0.0));
    double s2 = det / s1;
    double q = s1 / s2;
    if (!isfinite(q)) return 0.0;
    double w = 2.0 - q / max_distortion;
    return w >= 1.0 ? 1.0 : w <= 0.0 ? 0.0 : w;
}

/* The Jacobian of coords at (x, y) in units of the identity's: central differences, one-sided at
 * the frame's edges (a 1-pixel-wide frame has no derivative: 0, which weighs nothing). */
static void jacobian(const nprfx_image *co, nprfx_rect f, double plane, int x, int y, double J[4])
{
    int xl = x > f.x0 ? x - 1 : x, xr = x + 1 < f.x1 ? x + 1 : x;
    int yu = y > f.y0 ? y - 1 : y, yd = y + 1 < f.y1 ? y + 1 : y;
    const float *l = nprfx_image_at(co, xl, y), *r = nprfx_image_at(co, xr, y);
    const float *u = nprfx_image_at(co, x, yu), *d = nprfx_image_at(co, x, yd);
    double sx = xr > xl ? plane / (xr - xl) : 0.0, sy = yd > yu ? plane / (yd - yu) : 0.0;
    J[0] = ((double)r[0] - l[0]) * sx;
    J[1] = ((double)d[0] - u[0]) * sy;
    J[2] = ((double)r[1] - l[1]) * sx;
    J[3] = ((double)d[1] - u[1]) * sy;
}

typedef struct combine_job {
    const nprfx_image *a, *b;
    nprfx_image *out;
    nprfx_rect frame, window;
    double plane, max_distortion, tri_a, tri_b;
    int a_younger; /* where both weights are 0 */
} combine_job;

static void combine_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const combine_job *j = user;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++)
        for (int x = j->window.x0; x < j->window.x1; x++) {
            const float *pa = nprfx_image_at(j->a, x, y);
            float *o = nprfx_image_at(j->out, x, y);
            o[0] = pa[0];
            o[1] = pa[1];
            if (!j->b) {
                o[2] = pa[0];
                o[3] = pa[1];
                o[4] = 1.0f;
                continue;
            }
            const float *pb = nprfx_image_at(j->b, x, y);
            o[2] = pb[0];
            o[3] = pb[1];
            double J[4], wa = 0.0, wb = 0.0;
            if (j->tri_a > 0.0) {
                jacobian(j->a, j->frame, j->plane, x, y, J);
                wa = j->tri_a * nprfx_advect_distortion(J, j->max_distortion);
            }
            if (j->tri_b > 0.0) {
                jacobian(j->b, j->frame, j->plane, x, y, J);
                wb = j->tri_b * nprfx_advect_distortion(J, j->max_distortion);
            }
            double s = wa + wb;
            o[4] = s > 0.0 ? (float)(wa / s) : (j->a_younger ? 1.0f : 0.0f);
        }
}

nprfx_result nprfx_advect_combine(nprfx_context *ctx, const nprfx_advect_params *p,
                                  nprfx_rect frame, double plane, const nprfx_image *a,
                                  const nprfx_image *b, const nprfx_advect_layer_time *ta,
                                  const nprfx_advect_layer_time *tb, nprfx_rect window,
                                  nprfx_image *out)
{
    nprfx_result r = nprfx_advect_check(ctx, p);
    if (r) return r;
    if (!a || !a->data || !out || !out->data || !ta || (b && !tb))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "advect: combine without images");
    if (out->channels != NPRFX_ADVECT_CHANNELS)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH, "advect: output has %d channels, not %d",
                           out->channels, NPRFX_ADVECT_CHANNELS);
    window = nprfx_rect_intersect(nprfx_rect_intersect(window, out->bounds), frame);
    if (nprfx_rect_empty(window)) return NPRFX_OK;
    combine_job j = {a,
                     b && b->data ? b : NULL,
                     out,
                     frame,
                     window,
                     plane,
                     p->max_distortion,
                     ta->tri,
                     tb ? tb->tri : 0.0,
                     !tb || ta->age <= tb->age};
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(window), 16, combine_rows,
                       &j);
    return NPRFX_OK;
}

/* ---- the frame driver and its cache -------------------------------------------------------- */

typedef struct adv_layer {
    int valid;
    int restart, frame; /* the state is layer's coordinates at `frame`, restarted at `restart` */
    uint64_t fp;        /* fingerprint of the inputs read at `frame` (frame > restart) */
    nprfx_image coords; /* 2 channels over the frame */
} adv_layer;

typedef struct adv_cache {
    pthread_mutex_t lock; /* first: internal_state.h */
    uint64_t key;
    int have_key;
    adv_layer layer[2];
    nprfx_image scratch;
    nprfx_image result; /* the whole output at result_frame */
    int has_result, result_frame;
    uint64_t result_fp;
} adv_cache;

static void cache_clear(adv_cache *c)
{
    for (int l = 0; l < 2; l++) {
        nprfx_image_free(&c->layer[l].coords);
        memset(&c->layer[l], 0, sizeof c->layer[l]);
    }
    nprfx_image_free(&c->scratch);
    nprfx_image_free(&c->result);
    c->has_result = 0;
}

double nprfx_advect_state_bytes(int width, int height, int output_channels)
{
    return (double)width * height * sizeof(float) * (2 * 2 + 2 + output_channels);
}

void nprfx_advect_state_free(void *state)
{
    adv_cache *c = state;
    if (!c) return;
    cache_clear(c);
    internal_state_free(c);
}

#define HASH_INIT NPRFX_FNV_INIT

/* A sparse fingerprint of a view (its shape and a 32x32 grid of samples): cheap enough for every
 * call, and enough for a long-lived host instance to notice that an upstream input changed. */
static uint64_t fingerprint(uint64_t h, const nprfx_image *im)
{
    if (!im || !im->data) return nprfx_fnv1a(h, "none", 4);
    h = nprfx_fnv1a(h, &im->bounds, sizeof im->bounds);
    h = nprfx_fnv1a(h, &im->channels, sizeof im->channels);
    int w = nprfx_rect_width(im->bounds), ht = nprfx_rect_height(im->bounds);
    if (w <= 0 || ht <= 0) return h;
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 32; i++) {
            int x = im->bounds.x0 + (int)(((int64_t)(2 * i + 1) * w) / 64);
            int y = im->bounds.y0 + (int)(((int64_t)(2 * j + 1) * ht) / 64);
            h = nprfx_fnv1a(h, nprfx_image_at(im, x, y), sizeof(float) * (size_t)im->channels);
        }
    return h;
}

typedef struct adv_run {
    const nprfx_render_args *a;
    nprfx_context *ctx;
    const nprfx_advect_params *p;
    int have_conf;
    double plane;
    int t; /* the frame rendered: args->time rounded, whose inputs are args->inputs */
} adv_run;

static nprfx_result adv_fetch(const adv_run *run, int input, int frame, nprfx_image *out)
{
    const nprfx_render_args *a = run->a;
    static const char *const names[2] = {"motion_prev", "confidence"};
    memset(out, 0, sizeof *out);
    if (frame == run->t) {
        *out = a->inputs[input]; /* the call's own inputs: no second fetch */
    } else {
        if (!a->fetch)
            return nprfx_error(run->ctx, NPRFX_ERR_UNSUPPORTED,
                               "advect: frame %d needs input '%s' at frame %d, but the host "
                               "cannot fetch other frames",
                               run->t, names[input], frame);
        nprfx_result r = a->fetch(a->fetch_user, input, (double)frame, out);
        if (r)
            return nprfx_error(run->ctx, r, "advect: could not fetch input '%s' at frame %d",
                               names[input], frame);
    }
    if (!out->data)
        return nprfx_error(run->ctx, NPRFX_ERR_MISSING_INPUT,
                           "advect: input '%s' is not connected at frame %d", names[input], frame);
    if (out->channels < (input == IN_MOTION ? 2 : 1))
        return nprfx_error(run->ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "advect: input '%s' has %d channel(s) at frame %d", names[input],
                           out->channels, frame);
    return NPRFX_OK;
}

/* The inputs at `frame` and their fingerprint. */
static nprfx_result adv_inputs(const adv_run *run, int frame, nprfx_image *motion,
                               nprfx_image *conf, uint64_t *fp)
{
    nprfx_result r = adv_fetch(run, IN_MOTION, frame, motion);
    if (r) return r;
    memset(conf, 0, sizeof *conf);
    if (run->have_conf && (r = adv_fetch(run, IN_CONF, frame, conf))) return r;
    uint64_t h = fingerprint(HASH_INIT, motion);
    *fp = fingerprint(h, run->have_conf ? conf : NULL);
    return NPRFX_OK;
}

static nprfx_result ensure_image(nprfx_context *ctx, nprfx_rect frame, int channels,
                                 nprfx_image *im)
{
    if (im->data && nprfx_rect_equal(im->bounds, frame) && im->channels == channels)
        return NPRFX_OK;
    nprfx_image_free(im);
    return nprfx_image_alloc(ctx, frame, channels, im);
}

/* Bring layer state L to frame t of its life restarted at `restart`: from its cached frame when
 * that is on the way (and its inputs there are unchanged), else from the identity. */
static nprfx_result layer_advance(const adv_run *run, adv_cache *c, adv_layer *L, int restart,
                                  int t)
{
    nprfx_rect frame = run->a->frame;
    nprfx_result r;
    nprfx_image motion, conf;
    uint64_t fp;
    int usable = L->valid && L->restart == restart && L->frame >= restart && L->frame <= t &&
                 L->coords.data && nprfx_rect_equal(L->coords.bounds, frame);
    if (usable && L->frame > restart) {
        if ((r = adv_inputs(run, L->frame, &motion, &conf, &fp))) return r;
        usable = fp == L->fp;
    }
    if (!usable) {
        L->valid = 0;
        if ((r = ensure_image(run->ctx, frame, 2, &L->coords))) return r;
        nprfx_advect_seed(frame, run->plane, frame, &L->coords);
        L->restart = L->frame = restart;
        L->fp = 0;
        L->valid = 1;
    }
    if ((r = ensure_image(run->ctx, frame, 2, &c->scratch))) return r;
    while (L->frame < t) {
        int s = L->frame + 1;
        if ((r = adv_inputs(run, s, &motion, &conf, &fp))) goto fail;
        if ((r = nprfx_advect_step(run->ctx, run->p, frame, run->plane, &L->coords, &motion,
                                   run->have_conf ? &conf : NULL, &c->scratch)))
            goto fail;
        nprfx_image tmp = L->coords;
        L->coords = c->scratch;
        c->scratch = tmp;
        L->frame = s;
        L->fp = fp;
    }
    return NPRFX_OK;
fail:
    L->valid = 0;
    return r;
}

/* The window of the whole 5-channel result, the channels [first, first + count) of it. */
static void copy_window(const nprfx_image *src, nprfx_rect window, int first, int count,
                        nprfx_image *out)
{
    for (int y = window.y0; y < window.y1; y++)
        for (int x = window.x0; x < window.x1; x++) {
            const float *s = nprfx_image_at(src, x, y) + first;
            float *o = nprfx_image_at(out, x, y);
            for (int k = 0; k < count; k++)
                o[k] = s[k];
        }
}

nprfx_result nprfx_advect_render(const nprfx_render_args *args, const nprfx_advect_params *p)
{
    if (!args || !args->output || !args->output->data || !args->inputs)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "advect: no output or inputs");
    nprfx_context *ctx = args->ctx;
    nprfx_result r = nprfx_advect_check(ctx, p);
    if (r) return r;
    int out_channels = nprfx_advect_output_channels(p->output, NULL);
    if (args->output->channels != out_channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH, "advect: output has %d channels, not %d",
                           args->output->channels, out_channels);
    if (!args->inputs[IN_MOTION].data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "advect: input 'motion_prev' is not connected");
    int known = args->last_frame >= args->first_frame;
    if (p->layers == 1 && !known)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "advect: layers 1 needs the shot's frame range (its history starts at "
                           "the shot's first frame)");
    nprfx_rect frame = args->frame;
    nprfx_rect window = nprfx_rect_intersect(args->window, args->output->bounds);
    window = nprfx_rect_intersect(window, frame);
    if (nprfx_rect_empty(frame) || nprfx_rect_empty(window)) return NPRFX_OK;
    double scale = args->render_scale > 0 ? args->render_scale : 1.0;
    int t = (int)floor(args->time + 0.5);
    /* the motion input in this frame's pixels (a host's proxy gives full-resolution vectors) */
    nprfx_advect_params pm = *p;
    pm.motion_scale = args->vector_scale > 0.0 ? args->vector_scale : 1.0;
    adv_run run = {
        args, ctx, &pm, args->inputs[IN_CONF].data != NULL, NPRFX_ADVECT_PLANE_PIXELS * scale, t};

    adv_cache local, *c = &local;
    memset(&local, 0, sizeof local);
    if (args->state) {
        c = internal_state_get(args->state, sizeof *c);
        if (!c) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "advect: out of memory");
    }
    /* What the layer states depend on besides their inputs. */
    uint64_t key = HASH_INIT;
    key = nprfx_fnv1a(key, &p->layers, sizeof p->layers);
    key = nprfx_fnv1a(key, &p->period, sizeof p->period);
    key = nprfx_fnv1a(key, &p->max_distortion, sizeof p->max_distortion);
    key = nprfx_fnv1a(key, &p->min_confidence, sizeof p->min_confidence);
    key = nprfx_fnv1a(key, &frame, sizeof frame);
    key = nprfx_fnv1a(key, &scale, sizeof scale);
    key = nprfx_fnv1a(key, &pm.motion_scale, sizeof pm.motion_scale);
    key = nprfx_fnv1a(key, &args->first_frame, sizeof args->first_frame);
    key = nprfx_fnv1a(key, &args->last_frame, sizeof args->last_frame);
    key = nprfx_fnv1a(key, &run.have_conf, sizeof run.have_conf);

    if (c != &local) pthread_mutex_lock(&c->lock);
    if (!c->have_key || c->key != key) {
        cache_clear(c);
        c->key = key;
        c->have_key = 1;
    }
    nprfx_image motion, conf;
    uint64_t fp;
    if ((r = adv_inputs(&run, t, &motion, &conf, &fp))) goto done;
    if (!(c->has_result && c->result_frame == t && c->result_fp == fp)) {
        c->has_result = 0;
        nprfx_advect_layer_time lt[2];
        for (int l = 0; l < p->layers; l++)
            nprfx_advect_schedule(p, l, t, args->first_frame, args->last_frame, &lt[l]);
        if ((r = layer_advance(&run, c, &c->layer[0], lt[0].restart, t))) goto done;
        if (p->layers == 2) {
            adv_layer *b = &c->layer[1];
            if (lt[1].restart == lt[0].restart) {
                /* The same life (both started at the shot's first frame): the same values. */
                if ((r = ensure_image(ctx, frame, 2, &b->coords))) goto done;
                memcpy(b->coords.data, c->layer[0].coords.data,
                       sizeof(float) * 2 * (size_t)nprfx_rect_width(frame) *
                           (size_t)nprfx_rect_height(frame));
                b->valid = 1;
                b->restart = c->layer[0].restart;
                b->frame = c->layer[0].frame;
                b->fp = c->layer[0].fp;
            } else if ((r = layer_advance(&run, c, b, lt[1].restart, t))) {
                goto done;
            }
        }
        if ((r = ensure_image(ctx, frame, NPRFX_ADVECT_CHANNELS, &c->result))) goto done;
        if ((r = nprfx_advect_combine(ctx, p, frame, run.plane, &c->layer[0].coords,
                                      p->layers == 2 ? &c->layer[1].coords : NULL, &lt[0],
                                      p->layers == 2 ? &lt[1] : NULL, frame, &c->result)))
            goto done;
        c->has_result = 1;
        c->result_frame = t;
        c->result_fp = fp;
    }
    copy_window(&c->result, window, p->output == NPRFX_ADVECT_OUTPUT_MIX ? 4 : 0, out_channels,
                args->output);
done:
    if (c != &local)
        pthread_mutex_unlock(&c->lock);
    else
        cache_clear(&local);
    return r;
}

int nprfx_advect_frames(const nprfx_advect_params *p, const nprfx_frames_query *q, int input,
                        nprfx_frame_range *ranges)
{
    int t = q->time, lo = t;
    if (input == IN_MOTION || input == IN_CONF) {
        int layers = p->layers == 1 ? 1 : 2;
        if (p->layers == 1 && !(q->last_frame >= q->first_frame)) layers = 0; /* refused */
        for (int l = 0; l < layers; l++) {
            nprfx_advect_layer_time lt;
            nprfx_advect_schedule(p, l, t, q->first_frame, q->last_frame, &lt);
            /* Steps restart+1 .. t read the inputs there; the restart itself reads nothing. */
            if (lt.restart < t && lt.restart + 1 < lo) lo = lt.restart + 1;
        }
    }
    ranges[0].first = lo;
    ranges[0].last = t;
    return 1;
}
