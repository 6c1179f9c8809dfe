/* The coherent-noise node's temporal driver (Kass & Pesare 2011): frame i is defined by the
 * recursion from the start frame (or from max(start, i - window)), so a render of any frame walks
 * the passes there from the nearest saved state. A per-instance cache of pass states with
 * checkpoints makes that render-order independent: in-order rendering costs one step per frame,
 * random access recomputes from the nearest checkpoint within the cache's memory bound. Inputs at
 * other frames come from the host through args->fetch. */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/coherent_noise.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/node.h"

#include "base/internal_state.h"
#include "cn_cache.h"

enum {
    IN_DEPTH = NPRFX_CN_IN_DEPTH,
    IN_MOTION_PREV = NPRFX_CN_IN_MOTION_PREV,
    IN_MOTION_NEXT = NPRFX_CN_IN_MOTION_NEXT,
    IN_ZVEL = NPRFX_CN_IN_ZVEL,
    IN_SOURCE = NPRFX_CN_IN_SOURCE,
    IN_CONFIDENCE = NPRFX_CN_IN_CONFIDENCE,
    IN_COUNT = NPRFX_CN_IN_COUNT
};

/* ---- one render ---------------------------------------------------------------------------- */

typedef struct cn_run {
    const nprfx_render_args *args;
    nprfx_context *ctx;
    nprfx_cn_params p;
    int symmetric, window, have_zvel;
    /* Footage: no depth input, only the flow's confidence. Depth then reads as unit_depth, a
     * constant foreground, so the occlusion test never fires and confidence alone decides. */
    int have_depth, have_conf;
    float min_conf;
    nprfx_image unit_depth;
    int64_t frame, start, last;
    size_t budget; /* bytes for pass states */
} cn_run;

static nprfx_result cn_fetch(const cn_run *run, int input, int64_t frame, nprfx_image *out)
{
    const nprfx_render_args *a = run->args;
    static const char *const names[IN_COUNT] = {"depth", "motion_prev", "motion_next",
                                                "zvel",  "source",      "confidence"};
    memset(out, 0, sizeof *out);
    if (input == IN_DEPTH && !run->have_depth) {
        *out = run->unit_depth;
        return NPRFX_OK;
    }
    if (frame == run->frame && a->inputs[input].data) {
        /* The render call's own inputs are the inputs at this frame: no second fetch. */
        *out = a->inputs[input];
        return NPRFX_OK;
    }
    if (!a->fetch) {
        if (frame != run->frame)
            return nprfx_error(run->ctx, NPRFX_ERR_UNSUPPORTED,
                               "coherent-noise: frame %lld needs input '%s' at frame %lld, but "
                               "the host cannot fetch other frames",
                               (long long)run->frame, names[input], (long long)frame);
        *out = a->inputs[input];
    } else {
        nprfx_result r = a->fetch(a->fetch_user, input, (double)frame, out);
        if (r)
            return nprfx_error(run->ctx, r,
                               "coherent-noise: could not fetch input '%s' at frame %lld",
                               names[input], (long long)frame);
    }
    if (!out->data)
        return nprfx_error(run->ctx, NPRFX_ERR_MISSING_INPUT,
                           "coherent-noise: input '%s' is not connected", names[input]);
    return NPRFX_OK;
}

static nprfx_result cn_frame_fingerprint(const cn_run *run, int dir, int64_t f, uint64_t *fp)
{
    nprfx_image im;
    uint64_t h = CN_HASH_INIT;
    nprfx_result r;
    int ins[4] = {IN_DEPTH, dir > 0 ? IN_MOTION_PREV : IN_MOTION_NEXT,
                  run->p.noise == NPRFX_CN_NOISE_INPUT ? IN_SOURCE : -1,
                  run->have_conf ? IN_CONFIDENCE : -1};
    for (int k = 0; k < 4; k++) {
        if (ins[k] < 0) continue;
        if ((r = cn_fetch(run, ins[k], f, &im))) return r;
        h = internal_cn_fingerprint(h, &im);
    }
    *fp = h;
    return NPRFX_OK;
}

static nprfx_result cn_slot_ensure(const cn_run *run, nprfx_cn_state *st)
{
    if (st->value.data) return NPRFX_OK;
    return nprfx_cn_state_alloc(run->ctx, run->args->frame, run->p.channels, st);
}

static nprfx_result cn_pass_configure(const cn_run *run, cn_pass *ps, int dir, int64_t origin,
                                      int64_t n)
{
    if (ps->valid && ps->dir == dir && ps->origin == origin) return NPRFX_OK;
    internal_cn_pass_free(ps);
    ps->dir = dir;
    ps->origin = origin;
    internal_cn_pass_shape(nprfx_cn_state_bytes(run->args->frame, run->p.channels), run->budget, n,
                           &ps->K, &ps->nring, &ps->ncap);
    ps->ckpt = ps->ncap ? calloc((size_t)ps->ncap, sizeof(cn_slot)) : NULL;
    ps->ring = calloc((size_t)ps->nring, sizeof(cn_slot));
    if ((ps->ncap && !ps->ckpt) || !ps->ring) {
        internal_cn_pass_free(ps);
        return nprfx_error(run->ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory");
    }
    ps->valid = 1;
    return NPRFX_OK;
}

static nprfx_result cn_pass_checkpoint(const cn_run *run, cn_pass *ps, const cn_slot *s)
{
    if (ps->K <= 0 || ((s->frame - ps->origin) * ps->dir) % ps->K != 0) return NPRFX_OK;
    int idx = (int)(((s->frame - ps->origin) * ps->dir) / ps->K);
    if (idx >= ps->ncap) return NPRFX_OK;
    cn_slot *c = &ps->ckpt[idx];
    if (c->used && c->frame == s->frame) return NPRFX_OK;
    nprfx_result r = cn_slot_ensure(run, &c->st);
    if (r) return r;
    if ((r = nprfx_cn_state_copy(run->ctx, &s->st, &c->st))) return r;
    c->used = 1;
    c->frame = s->frame;
    c->fingerprint = s->fingerprint;
    return NPRFX_OK;
}

/* Keep a copy of the depth a step read at frame f (its state's fingerprint fp). Best effort:
 * without memory the next step fetches the depth instead. */
static void cn_copy(nprfx_context *ctx, const nprfx_image *src, nprfx_image *dst, nprfx_rect win,
                    int unit01, float contrast);

static void cn_pass_keep_depth(nprfx_context *ctx, cn_pass *ps, const nprfx_image *depth, int64_t f,
                               uint64_t fp)
{
    ps->depth_valid = 0;
    if (!ps->depth.data || !nprfx_rect_equal(ps->depth.bounds, depth->bounds)) {
        nprfx_image_free(&ps->depth);
        if (nprfx_image_alloc(NULL, depth->bounds, 1, &ps->depth)) return;
    }
    cn_copy(ctx, depth, &ps->depth, depth->bounds, 0, 0.0f);
    ps->depth_frame = f;
    ps->depth_fp = fp;
    ps->depth_valid = 1;
}

/* Depth at a step's own frame h gated by the confidence there (channel 0 for the forward pass,
 * which follows motion_prev; channel 1, when there is one, for the backward pass): +inf where the
 * confidence is below min_confidence or NaN, so the step restarts the pixel as it does on
 * background. Outside its data window confidence reads 0 (untrusted). The previous frame's depth
 * is not gated: a pixel that restarted there holds fresh noise, which is fine to carry. */
typedef struct cn_gate_job {
    const nprfx_image *depth, *conf;
    nprfx_image *out;
    int ch;
    float min_conf;
} cn_gate_job;

static void cn_gate_rows(void *user, int y0, int y1, int worker)
{
    (void)worker;
    const cn_gate_job *j = user;
    const nprfx_rect b = j->out->bounds, cb = j->conf->bounds;
    for (int y = b.y0 + y0; y < b.y0 + y1; y++) {
        float *o = nprfx_image_at(j->out, b.x0, y);
        for (int x = b.x0; x < b.x1; x++, o += j->out->pixel_stride) {
            float c = 0.0f;
            if (x >= cb.x0 && x < cb.x1 && y >= cb.y0 && y < cb.y1)
                c = nprfx_image_at(j->conf, x, y)[j->ch];
            *o = c >= j->min_conf ? *nprfx_image_at(j->depth, x, y) : INFINITY;
        }
    }
}

static nprfx_result cn_gate(const cn_run *run, cn_pass *ps, int64_t h, const nprfx_image *depth,
                            nprfx_image *out)
{
    nprfx_image conf;
    nprfx_result r = cn_fetch(run, IN_CONFIDENCE, h, &conf);
    if (r) return r;
    if (!ps->gated.data || !nprfx_rect_equal(ps->gated.bounds, depth->bounds)) {
        nprfx_image_free(&ps->gated);
        if ((r = nprfx_image_alloc(run->ctx, depth->bounds, 1, &ps->gated))) return r;
    }
    cn_gate_job job = {depth, &conf, &ps->gated, ps->dir < 0 && conf.channels > 1 ? 1 : 0,
                       run->min_conf};
    nprfx_parallel_for(nprfx_context_executor(run->ctx), nprfx_rect_height(depth->bounds), 16,
                       cn_gate_rows, &job);
    *out = ps->gated;
    return NPRFX_OK;
}

/* The pass's state at frame f, computed from the nearest saved state (or the origin). */
static nprfx_result cn_pass_get(const cn_run *run, cn_pass *ps, int64_t f, const cn_slot **out)
{
    nprfx_result r;
    cn_slot *s = internal_cn_pass_find(ps, f);
    if (s) {
        *out = s;
        return NPRFX_OK;
    }
    if ((r = cn_slot_ensure(run, &ps->scratch))) return r;
    const cn_slot *cur = internal_cn_pass_nearest(ps, f);
    int64_t g;
    if (!cur) {
        nprfx_image src = {0};
        g = ps->origin;
        if (run->p.noise == NPRFX_CN_NOISE_INPUT && (r = cn_fetch(run, IN_SOURCE, g, &src)))
            return r;
        uint64_t fp;
        if ((r = cn_frame_fingerprint(run, ps->dir, g, &fp))) return r;
        if ((r = nprfx_cn_begin(run->ctx, &run->p, g, &src, &ps->scratch))) return r;
        cn_slot *ns = internal_cn_pass_push(ps, g, fp);
        if ((r = cn_pass_checkpoint(run, ps, ns))) return r;
        cur = ns;
    }
    g = cur->frame;
    int minput = ps->dir > 0 ? IN_MOTION_PREV : IN_MOTION_NEXT;
    while (g != f) {
        int64_t h = g + ps->dir;
        nprfx_image depth, motion, zvel = {0}, depth_prev, src = {0};
        if ((r = cn_fetch(run, IN_DEPTH, h, &depth)) || (r = cn_fetch(run, minput, h, &motion)))
            return r;
        if (ps->depth_valid && ps->depth_frame == g && ps->depth_fp == cur->fingerprint)
            depth_prev = ps->depth;
        else if ((r = cn_fetch(run, IN_DEPTH, g, &depth_prev)))
            return r;
        if (run->have_zvel && (r = cn_fetch(run, IN_ZVEL, h, &zvel))) return r;
        if (run->p.noise == NPRFX_CN_NOISE_INPUT && (r = cn_fetch(run, IN_SOURCE, h, &src)))
            return r;
        uint64_t fp =
            internal_cn_fingerprint(internal_cn_fingerprint(CN_HASH_INIT, &depth), &motion);
        if (run->p.noise == NPRFX_CN_NOISE_INPUT) fp = internal_cn_fingerprint(fp, &src);
        nprfx_image gated = depth;
        if (run->have_conf) {
            nprfx_image conf;
            if ((r = cn_fetch(run, IN_CONFIDENCE, h, &conf))) return r;
            fp = internal_cn_fingerprint(fp, &conf);
            if ((r = cn_gate(run, ps, h, &depth, &gated))) return r;
        }
        nprfx_cn_inputs in = {&gated, &motion, run->have_zvel ? &zvel : NULL, &depth_prev, &src};
        if ((r = cn_slot_ensure(run, &ps->scratch))) return r;
        if ((r = nprfx_cn_step(run->ctx, &run->p, ps->dir, h, &in, &cur->st, &ps->scratch)))
            return r;
        cn_slot *ns = internal_cn_pass_push(ps, h, fp);
        if ((r = cn_pass_checkpoint(run, ps, ns))) return r;
        cn_pass_keep_depth(run->ctx, ps, &depth, h, fp);
        cur = ns;
        g = h;
    }
    *out = cur;
    return NPRFX_OK;
}

/* Rows of win from src into dst (dst->channels channels); unit01: 0.5 + contrast * v. Row-parallel
 * over the context's executor: the copies are a sizeable part of a frame's memory traffic. */
typedef struct cn_copy_job {
    const nprfx_image *src;
    nprfx_image *dst;
    nprfx_rect win;
    int unit01;
    float contrast;
} cn_copy_job;

static void cn_copy_rows(void *user, int begin, int end, int worker)
{
    const cn_copy_job *j = user;
    const int C = j->dst->channels, w = nprfx_rect_width(j->win);
    const size_t n = (size_t)w * (size_t)C;
    const int packed = j->src->pixel_stride == C && j->dst->pixel_stride == C;
    (void)worker;
    for (int y = j->win.y0 + begin; y < j->win.y0 + end; y++) {
        const float *s = nprfx_image_at(j->src, j->win.x0, y);
        float *o = nprfx_image_at(j->dst, j->win.x0, y);
        if (packed && !j->unit01) {
            memcpy(o, s, n * sizeof(float));
        } else if (packed) {
            for (size_t i = 0; i < n; i++)
                o[i] = 0.5f + j->contrast * s[i];
        } else {
            for (int x = 0; x < w; x++)
                for (int c = 0; c < C; c++) {
                    float v = s[(ptrdiff_t)x * j->src->pixel_stride + c];
                    o[(ptrdiff_t)x * j->dst->pixel_stride + c] =
                        j->unit01 ? 0.5f + j->contrast * v : v;
                }
        }
    }
}

static void cn_copy(nprfx_context *ctx, const nprfx_image *src, nprfx_image *dst, nprfx_rect win,
                    int unit01, float contrast)
{
    if (nprfx_rect_empty(win)) return;
    cn_copy_job job = {src, dst, win, unit01, contrast};
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(win), 32, cn_copy_rows, &job);
}

/* The render window of src into the output. */
static void cn_copy_window(const nprfx_render_args *args, const nprfx_image *src, int unit01,
                           float contrast)
{
    cn_copy(args->ctx, src, args->output, nprfx_rect_intersect(args->window, args->frame), unit01,
            contrast);
}

int64_t nprfx_coherent_noise_auto_window(double alpha)
{
    /* alpha^W <= tol. Frozen noise (alpha = 1) is defined by the whole recursion: no window. */
    if (!(alpha < 1.0)) return 0;
    if (!(alpha > 0.0)) return 1;
    double w = ceil(log(NPRFX_CN_WINDOW_TOLERANCE) / log(alpha));
    return w < 1.0 ? 1 : (w > 1e15 ? (int64_t)1e15 : (int64_t)w);
}

/* The recursion's span for frame t: the forward pass runs from *start to t, the backward one
 * (symmetric mode) from *last down to t. One definition for the render and for the frames a
 * host must prepare (nprfx_coherent_noise_frames).
 *
 * window W > 0 slides: frame t starts at t - W. window 0 is automatic: W from alpha
 * (nprfx_coherent_noise_auto_window), and the start on a grid of W frames from the shot's
 * start, the latest grid frame at least W before t. So t is 1 to 2W steps from its start (the
 * cut weight is below the tolerance), any frame alone costs under 2W steps, and in-order
 * rendering shares one start for W frames: two steps a frame, where a sliding window costs W.
 * A shot shorter than 2W never moves its start, so it renders as without a window. */
static void cn_span(const nprfx_coherent_noise_params *np, int64_t t, int first, int last_frame,
                    int64_t *start, int64_t *last)
{
    int shot_known = last_frame >= first;
    int64_t s = np->start;
    if (shot_known && s < first) s = first;
    int64_t l = shot_known ? last_frame : t;
    int64_t aw = np->window > 0 ? 0 : nprfx_coherent_noise_auto_window(np->alpha);
    if (np->window > 0 && t - np->window > s) s = t - np->window;
    if (aw > 0 && t - aw > s) s += (t - aw - s) / aw * aw;
    if (t < s) s = t;
    if (np->mode == NPRFX_CN_MODE_SYMMETRIC) {
        if (np->window > 0 && t + np->window < l) l = t + np->window;
        if (aw > 0 && t + aw < l) l -= (l - t - aw) / aw * aw;
        if (t > l) l = t;
    }
    *start = s;
    *last = l;
}

/* What decides which frames a render reads from a warm cache: the params the pass states and
 * their span depend on, the inputs connected (channels: 0 where not), the shot. A render stores
 * it; nprfx_coherent_noise_frames trusts the cache only when its own is the same. */
static uint64_t cn_span_key(const nprfx_coherent_noise_params *np, const int *channels,
                            int first_frame, int last_frame)
{
    uint64_t k = CN_HASH_INIT;
    k = internal_cn_hash_f64(k, np->alpha);
    k = internal_cn_hash_f64(k, np->epsilon);
    k = internal_cn_hash_i64(k, np->noise);
    k = internal_cn_hash_f64(k, np->sigma_lo);
    k = internal_cn_hash_f64(k, np->sigma_hi);
    k = internal_cn_hash_i64(k, np->channels);
    k = internal_cn_hash_i64(k, np->seed);
    k = internal_cn_hash_i64(k, np->mode);
    k = internal_cn_hash_i64(k, np->start);
    k = internal_cn_hash_i64(k, np->window);
    k = internal_cn_hash_i64(k, np->cache_mb);
    k = internal_cn_hash_f64(k, np->min_confidence);
    /* which inputs are connected (not their channel counts, which a host may give otherwise
     * at render) */
    for (int i = 0; i < IN_COUNT; i++)
        k = internal_cn_hash_i64(k, channels && channels[i] > 0);
    k = internal_cn_hash_i64(k, first_frame);
    return internal_cn_hash_i64(k, last_frame);
}

/* The saved forward state a render at t would step from (its frame in *from), when the cache in
 * state was made for the same span key and the pass starts where t's span does: a render in order
 * then reads its inputs from there on only. */
static int cn_warm_from(const void *state, uint64_t key, int64_t start, int64_t t, int64_t *from)
{
    cn_cache *c = (cn_cache *)state; /* its lock is taken, nothing else changed */
    int warm = 0;
    pthread_mutex_lock(&c->lock);
    cn_pass *ps = &c->pass[0];
    if (c->have_span_key && c->span_key == key && ps->valid && ps->origin == start) {
        const cn_slot *s = internal_cn_pass_nearest(ps, t);
        if (s) {
            *from = s->frame;
            warm = 1;
        }
    }
    pthread_mutex_unlock(&c->lock);
    return warm;
}

double nprfx_coherent_noise_state_bytes(const nprfx_coherent_noise_params *np, int width,
                                        int height, int source_channels, int first_frame,
                                        int last_frame)
{
    nprfx_rect frame = nprfx_rect_make(0, 0, width, height);
    int channels = np->noise == NPRFX_CN_NOISE_INPUT ? (source_channels > 4   ? 4
                                                        : source_channels > 0 ? source_channels
                                                                              : 1)
                                                     : np->channels;
    int passes = np->mode == NPRFX_CN_MODE_SYMMETRIC ? 2 : 1;
    double mb = np->cache_mb > 0 ? np->cache_mb : 0;
    size_t budget = (size_t)(mb * 1048576.0) / (size_t)passes;
    /* the longest pass: the window's steps, else the shot (unknown: as long as the budget
     * allows, the bound then) */
    int64_t n = np->window > 0              ? (int64_t)np->window + 1
                : last_frame >= first_frame ? (int64_t)last_frame - first_frame + 1
                                            : INT64_C(1) << 40;
    size_t sb = nprfx_cn_state_bytes(frame, channels);
    int K, nring, ncap;
    internal_cn_pass_shape(sb, budget, n, &K, &nring, &ncap);
    double px = (double)width * height;
    /* a pass: its checkpoints and ring, the depth it keeps and the gated depth */
    double pass = (double)(ncap + nring) * sb + 2.0 * px * sizeof(float);
    return passes * pass + px * channels * sizeof(float); /* and the last result */
}

int nprfx_coherent_noise_frames(const nprfx_coherent_noise_params *np, const nprfx_frames_query *q,
                                int input, nprfx_frame_range *ranges)
{
    int64_t start, last, t = q->time;
    cn_span(np, t, q->first_frame, q->last_frame, &start, &last);
    int symmetric = np->mode == NPRFX_CN_MODE_SYMMETRIC;
    int input_noise = np->noise == NPRFX_CN_NOISE_INPUT;
    /* A warm cache steps on from its last state s <= t: the steps s+1..t read depth at h and h-1
     * (s: the kept depth, or a fetch), the rest at h; the check of frame t reads t. The origin
     * (and its fingerprint) is read only by a cold pass. */
    int64_t from;
    if (q->state && t >= start &&
        cn_warm_from(q->state, cn_span_key(np, q->input_channels, q->first_frame, q->last_frame),
                     start, t, &from)) {
        switch (input) {
        case IN_DEPTH:
        case IN_CONFIDENCE:
            ranges[0].first = (int)from;
            ranges[0].last = (int)(symmetric ? last : t);
            return 1;
        case IN_MOTION_PREV:
        case IN_ZVEL:
            ranges[0].first = (int)(from < t ? from + 1 : t);
            ranges[0].last = (int)(input == IN_ZVEL && symmetric && last - 1 > t ? last - 1 : t);
            return 1;
        case IN_SOURCE:
            if (!input_noise) break;
            ranges[0].first = (int)(from < t ? from + 1 : t);
            ranges[0].last = (int)(symmetric ? last : t);
            return 1;
        default:
            break;
        }
    }
    /* Forward: the origin reads depth, motion_prev (its fingerprint) and source at start; each
     * step h in start+1..t reads depth at h and h-1, motion_prev, zvel and source at h. Backward
     * the same mirrored from last, with motion_next. */
    int64_t lo = t, hi = t;
    switch (input) {
    case IN_DEPTH:
        lo = start;
        hi = symmetric ? last : t;
        break;
    case IN_MOTION_PREV:
        lo = start;
        break;
    case IN_MOTION_NEXT:
        if (symmetric) hi = last;
        break;
    case IN_CONFIDENCE: /* read with depth at every step, and in the fingerprints */
        lo = start;
        hi = symmetric ? last : t;
        break;
    case IN_ZVEL:
        if (start < t) lo = start + 1;
        if (symmetric && last - 1 > t) hi = last - 1;
        break;
    case IN_SOURCE:
        if (input_noise) {
            lo = start;
            if (symmetric) hi = last;
        }
        break;
    default:
        return 0;
    }
    ranges[0].first = (int)lo;
    ranges[0].last = (int)hi;
    return 1;
}

nprfx_result nprfx_coherent_noise_render(const nprfx_render_args *args,
                                         const nprfx_coherent_noise_params *np)
{
    if (!args || args->size < sizeof(nprfx_render_args) || !np || !args->output || !args->inputs ||
        !args->state)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "coherent-noise: incomplete render arguments");
    nprfx_context *ctx = args->ctx;
    const nprfx_image *in = args->inputs;
    cn_run run;
    memset(&run, 0, sizeof run);
    run.args = args;
    run.ctx = ctx;
    nprfx_cn_params_default(&run.p);
    run.p.alpha = np->alpha;
    run.p.epsilon = np->epsilon;
    run.p.noise = np->noise;
    run.p.sigma_lo = np->sigma_lo;
    run.p.sigma_hi = np->sigma_hi;
    run.p.seed = (uint64_t)np->seed;
    run.p.motion_scale = args->vector_scale > 0.0 ? args->vector_scale : 1.0;
    int mode = np->mode, outmap = np->output;
    double smooth = np->smooth, contrast = np->contrast;
    run.symmetric = mode == NPRFX_CN_MODE_SYMMETRIC;
    run.window = np->window;
    run.frame = (int64_t)floor(args->time + 0.5);
    if (mode < 0 || mode >= NPRFX_CN_MODE_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "coherent-noise.mode: no mode %d", mode);
    if (outmap < 0 || outmap >= NPRFX_CN_OUTPUT_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "coherent-noise.output: no mapping %d",
                           outmap);
    if (run.window < 0)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "coherent-noise.window: %d is negative",
                           run.window);
    if (!(smooth >= 0.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "coherent-noise.smooth: %g is negative",
                           smooth);
    run.have_depth = in[IN_DEPTH].data != NULL;
    run.have_conf = in[IN_CONFIDENCE].data != NULL;
    run.min_conf = (float)np->min_confidence;
    if (!run.have_depth && !run.have_conf)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "coherent-noise: connect input 'depth' (render plates) or "
                           "'confidence' (footage: the flow node's confidence.prev)");
    if (run.have_conf && in[IN_CONFIDENCE].channels > 2)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "coherent-noise: input 'confidence' has %d channels; it takes 1 (of "
                           "motion_prev) or 2 (of motion_prev, then of motion_next)",
                           in[IN_CONFIDENCE].channels);
    if (!(np->min_confidence >= 0.0 && np->min_confidence <= 1.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "coherent-noise.min_confidence: %g is outside [0, 1]",
                           np->min_confidence);
    if (!in[IN_MOTION_PREV].data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "coherent-noise: input 'motion_prev' is not connected");
    if (run.symmetric && !in[IN_MOTION_NEXT].data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "coherent-noise: mode 'symmetric' needs input 'motion_next'");
    run.have_zvel = in[IN_ZVEL].data != NULL;
    if (run.p.noise == NPRFX_CN_NOISE_INPUT) {
        if (!in[IN_SOURCE].data)
            return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                               "coherent-noise: noise 'input' needs input 'source'");
        run.p.channels = in[IN_SOURCE].channels > 4 ? 4 : in[IN_SOURCE].channels;
    } else {
        run.p.channels = np->channels;
    }
    nprfx_result r = nprfx_cn_params_check(ctx, &run.p);
    if (r) return r;
    if (args->output->channels != run.p.channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "coherent-noise: output has %d channels, expected %d",
                           args->output->channels, run.p.channels);
    if (nprfx_rect_empty(args->frame)) return NPRFX_OK;

    /* The recursion's span for this frame. */
    int shot_known = args->last_frame >= args->first_frame;
    if (run.symmetric && !shot_known)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "coherent-noise: mode 'symmetric' needs the shot's frame range");
    cn_span(np, run.frame, args->first_frame, args->last_frame, &run.start, &run.last);
    if (!run.have_depth) {
        if ((r = nprfx_image_alloc(ctx, args->frame, 1, &run.unit_depth))) return r;
        size_t n = (size_t)nprfx_rect_width(args->frame) * (size_t)nprfx_rect_height(args->frame);
        for (size_t i = 0; i < n; i++)
            run.unit_depth.data[i] = 1.0f;
    }
    double mb = np->cache_mb;
    run.budget = (size_t)((mb > 0 ? mb : 0) * 1048576.0);
    if (run.symmetric) run.budget /= 2;

    cn_cache *cache = internal_state_get(args->state, sizeof *cache);
    if (!cache) {
        nprfx_image_free(&run.unit_depth);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory");
    }

    /* What the pass states depend on (not the output mapping, not the cache size). */
    uint64_t key = CN_HASH_INIT;
    key = internal_cn_hash_f64(key, run.p.alpha);
    key = internal_cn_hash_f64(key, run.p.epsilon);
    key = internal_cn_hash_i64(key, (int64_t)(run.p.noise));
    if (run.p.noise == NPRFX_CN_NOISE_BANDPASS) {
        key = internal_cn_hash_f64(key, run.p.sigma_lo);
        key = internal_cn_hash_f64(key, run.p.sigma_hi);
    }
    key = internal_cn_hash_i64(key, (int64_t)(run.p.channels));
    key = internal_cn_hash_i64(key, (int64_t)(run.p.seed));
    key = internal_cn_hash_i64(key, (int64_t)(run.p.resample));
    key = internal_cn_hash_f64(key, run.p.motion_scale);
    key = internal_cn_hash_i64(key, (int64_t)(run.have_zvel));
    key = internal_cn_hash_i64(key, (int64_t)(run.have_depth));
    key = internal_cn_hash_i64(key, (int64_t)(run.have_conf));
    if (run.have_conf) key = internal_cn_hash_f64(key, run.min_conf);
    key = internal_cn_hash_i64(key, (int64_t)(run.symmetric));
    key = internal_cn_hash_i64(key, (int64_t)(run.window));
    key = internal_cn_hash_bytes(key, &args->frame, sizeof args->frame);
    key = internal_cn_hash_i64(key, np->start);
    key = internal_cn_hash_i64(key, (int64_t)(args->first_frame));
    key = internal_cn_hash_i64(key, (int64_t)(args->last_frame));
    key = internal_cn_hash_i64(key, (int64_t)(run.budget));
    uint64_t okey = key;
    okey = internal_cn_hash_f64(okey, smooth);
    okey = internal_cn_hash_i64(okey, (int64_t)(outmap));
    okey = internal_cn_hash_f64(okey, contrast);

    /* Causal without smoothing: the output is the forward state itself (mapped), copied to the
     * window straight from the pass; no full-frame result is kept. */
    int direct = !run.symmetric && !(smooth > 0.0);

    pthread_mutex_lock(&cache->lock);
    if (!cache->have_key || cache->key != key) {
        internal_cn_pass_free(&cache->pass[0]);
        internal_cn_pass_free(&cache->pass[1]);
        cache->has_result = 0;
        cache->key = key;
        cache->have_key = 1;
    }
    uint64_t fp = 0;
    if ((r = cn_frame_fingerprint(&run, NPRFX_CN_FORWARD, run.frame, &fp))) goto unlock;
    if (!(cache->has_result && cache->result_frame == run.frame && cache->result_key == okey &&
          cache->result_fp == fp)) {
        cache->has_result = 0;
        /* A changed input at this frame invalidates every state that read it. */
        for (int d = 0; d < 2; d++) {
            cn_pass *ps = &cache->pass[d];
            if (!ps->valid) continue;
            cn_slot *s = internal_cn_pass_find(ps, run.frame);
            if (s && d == 0 && s->fingerprint != fp) internal_cn_pass_invalidate(ps);
        }
        int64_t aw = run.window > 0 ? 0 : nprfx_coherent_noise_auto_window(np->alpha);
        int64_t nf = shot_known ? args->last_frame - run.start + 1 : 1024;
        if (run.window > 0) nf = run.window + 1;
        if (aw > 0 && 2 * aw < nf) nf = 2 * aw;
        if ((r = cn_pass_configure(&run, &cache->pass[0], NPRFX_CN_FORWARD, run.start, nf)))
            goto unlock;
        const cn_slot *fw = NULL, *bw = NULL;
        if ((r = cn_pass_get(&run, &cache->pass[0], run.frame, &fw))) goto unlock;
        if (direct) {
            nprfx_image_free(&cache->result);
            cn_copy_window(args, &fw->st.value,
                           outmap == NPRFX_CN_OUTPUT_UNIT01 && run.p.noise != NPRFX_CN_NOISE_INPUT,
                           (float)contrast);
            goto unlock;
        }
        if (run.symmetric) {
            int64_t nb = run.window > 0 ? run.window + 1 : run.last - run.start + 1;
            if (aw > 0 && 2 * aw < nb) nb = 2 * aw;
            if ((r = cn_pass_configure(&run, &cache->pass[1], NPRFX_CN_BACKWARD, run.last, nb)))
                goto unlock;
            if ((r = cn_pass_get(&run, &cache->pass[1], run.frame, &bw))) goto unlock;
        }
        if (!cache->result.data || !nprfx_rect_equal(cache->result.bounds, args->frame) ||
            cache->result.channels != run.p.channels) {
            nprfx_image_free(&cache->result);
            if ((r = nprfx_image_alloc(ctx, args->frame, run.p.channels, &cache->result)))
                goto unlock;
        }
        nprfx_image src = {0};
        if (run.symmetric && run.p.noise == NPRFX_CN_NOISE_INPUT &&
            (r = cn_fetch(&run, IN_SOURCE, run.frame, &src)))
            goto unlock;
        if ((r = nprfx_cn_combine(ctx, &run.p, run.frame, &fw->st, bw ? &bw->st : NULL, &src,
                                  &cache->result)))
            goto unlock;
        if ((r = nprfx_cn_smooth(ctx, &run.p, smooth, &cache->result))) goto unlock;
        if (outmap == NPRFX_CN_OUTPUT_UNIT01 && run.p.noise != NPRFX_CN_NOISE_INPUT) {
            nprfx_image *o = &cache->result;
            size_t n = (size_t)nprfx_rect_width(o->bounds) * (size_t)nprfx_rect_height(o->bounds) *
                       (size_t)o->channels;
            float c = (float)contrast;
            for (size_t i = 0; i < n; i++)
                o->data[i] = 0.5f + c * o->data[i];
        }
        cache->has_result = 1;
        cache->result_frame = run.frame;
        cache->result_key = okey;
        cache->result_fp = fp;
    }
    cn_copy_window(args, &cache->result, 0, 0.0f);
unlock:
    /* what the frames a next render reads depend on (nprfx_coherent_noise_frames) */
    cache->have_span_key = r == NPRFX_OK;
    if (r == NPRFX_OK) {
        int ch[IN_COUNT];
        for (int k = 0; k < IN_COUNT; k++)
            ch[k] = in[k].data ? in[k].channels : 0;
        cache->span_key = cn_span_key(np, ch, args->first_frame, args->last_frame);
    }
    pthread_mutex_unlock(&cache->lock);
    nprfx_image_free(&run.unit_depth);
    return r;
}
