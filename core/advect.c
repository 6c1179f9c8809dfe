/* Texture coordinates advected along the motion of footage (nprfx/advect.h, design §3.15).
 *
 * Each layer is a recursion over frames that restarts every period, so a frame depends only on
 * the frames since its layers' last starts: at most period - 1 motion fields back, which bounds
 * the warm-up of a chunk that starts mid-shot as well as what a host must fetch. The whole
 * frame is computed once per frame and kept for the next, which then takes one step; a frame
 * reached any other way (a jump, another order, no state) is recomputed from the starts with the
 * same operations, so what was kept never changes a result. */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/advect.h"
#include "nprfx/exec.h"
#include "nprfx/rng.h"

/* Hash stream of the per-start coordinate shifts. */
#define STREAM_ADVECT 0x41445643u

static int floor_mod(int a, int m)
{
    int r = a % m;
    return r < 0 ? r + m : r;
}

int nprfx_advect_start(const nprfx_advect_params *p, int layer, int time, int first_frame,
                       int last_frame)
{
    const int period = p->period >= 2 ? p->period : 2;
    const int offset = layer ? period / 2 : 0;
    int s = time - floor_mod(time - offset, period);
    if (first_frame <= last_frame && s < first_frame) s = first_frame;
    return s;
}

/* 0 at a layer's start, 1 halfway through its life, falling to 0 again at its end */
static double life(int age, int period)
{
    double a = (double)age / period;
    return 1.0 - fabs(2.0 * a - 1.0);
}

double nprfx_advect_weight(const nprfx_advect_params *p, int time)
{
    const int period = p->period >= 2 ? p->period : 2;
    double a = life(floor_mod(time, period), period);
    double b = life(floor_mod(time - period / 2, period), period);
    return a + b > 0 ? a / (a + b) : 0.5;
}

/* ---- the recursion ---- */

typedef struct layer_job {
    const nprfx_advect_params *p;
    nprfx_rect fr;
    const float *prev; /* 2 floats a pixel of fr, or NULL: start */
    float *next;
    const nprfx_image *motion, *confidence; /* at the frame stepped to */
    double ou, ov;                          /* this start's shift */
} layer_job;

/* The coordinates a layer starts with at pixel (x, y): the image plane, shifted. */
static inline void start_uv(const layer_job *j, int x, int y, float *uv)
{
    uv[0] = (float)((x + 0.5) / j->p->scale + j->ou);
    uv[1] = (float)((y + 0.5) / j->p->scale + j->ov);
}

/* Channel c of view at (x, y); 0 outside its data window (as an EXR reader gives). */
static inline float read_at(const nprfx_image *v, int x, int y, int c)
{
    if (x < v->bounds.x0 || x >= v->bounds.x1 || y < v->bounds.y0 || y >= v->bounds.y1) return 0;
    return nprfx_image_at(v, x, y)[c];
}

static void layer_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const layer_job *j = user;
    const nprfx_rect fr = j->fr;
    const int w = nprfx_rect_width(fr);
    const float thr = (float)j->p->threshold;
    for (int y = fr.y0 + begin; y < fr.y0 + end; y++)
        for (int x = fr.x0; x < fr.x1; x++) {
            float *o = j->next + 2 * ((size_t)(y - fr.y0) * w + (size_t)(x - fr.x0));
            if (!j->prev) {
                start_uv(j, x, y, o);
                continue;
            }
            /* where the pixel was in the previous frame (design §2.1) */
            const float mx = read_at(j->motion, x, y, 0), my = read_at(j->motion, x, y, 1);
            const float px = (float)x + mx, py = (float)y + my;
            int fresh = !isfinite(mx) || !isfinite(my) ||
                        !(px >= (float)fr.x0 && px <= (float)(fr.x1 - 1) && py >= (float)fr.y0 &&
                          py <= (float)(fr.y1 - 1));
            if (!fresh && j->confidence) {
                const float c = read_at(j->confidence, x, y, 0);
                fresh = !(c >= thr); /* NaN: fresh */
            }
            if (fresh) {
                start_uv(j, x, y, o);
                continue;
            }
            int ix = (int)px, iy = (int)py; /* px, py >= frame origin: see below */
            ix -= (float)ix > px;
            iy -= (float)iy > py;
            if (ix >= fr.x1 - 1) ix = fr.x1 - 2 >= fr.x0 ? fr.x1 - 2 : fr.x0;
            if (iy >= fr.y1 - 1) iy = fr.y1 - 2 >= fr.y0 ? fr.y1 - 2 : fr.y0;
            const int ix1 = ix + 1 < fr.x1 ? ix + 1 : ix, iy1 = iy + 1 < fr.y1 ? iy + 1 : iy;
            const float fx = px - (float)ix, fy = py - (float)iy;
            const float *a = j->prev + 2 * ((size_t)(iy - fr.y0) * w + (size_t)(ix - fr.x0));
            const float *b = j->prev + 2 * ((size_t)(iy - fr.y0) * w + (size_t)(ix1 - fr.x0));
            const float *c = j->prev + 2 * ((size_t)(iy1 - fr.y0) * w + (size_t)(ix - fr.x0));
            const float *d = j->prev + 2 * ((size_t)(iy1 - fr.y0) * w + (size_t)(ix1 - fr.x0));
            for (int k = 0; k < 2; k++) {
                const float top = a[k] + fx * (b[k] - a[k]);
                const float bottom = c[k] + fx * (d[k] - c[k]);
                o[k] = top + fy * (bottom - top);
            }
        }
}

/* One step (prev != NULL) or a start (prev == NULL) of a layer into next. */
static void layer_step(nprfx_context *ctx, const nprfx_advect_params *p, nprfx_rect fr, int layer,
                       int start, const float *prev, float *next, const nprfx_image *motion,
                       const nprfx_image *confidence)
{
    layer_job j = {p, fr, prev, next, motion, confidence, 0, 0};
    j.ou = nprfx_rand_u01((uint64_t)(uint32_t)p->seed, start, layer, 0, 0, STREAM_ADVECT);
    j.ov = nprfx_rand_u01((uint64_t)(uint32_t)p->seed, start, layer, 0, 1, STREAM_ADVECT);
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(fr), 8, layer_rows, &j);
}

/* ---- the kept state ---- */

typedef struct adv_state {
    pthread_mutex_t lock;
    int valid, frame;
    nprfx_rect fr;
    nprfx_advect_params key;
    int first, last;
    float *uv[2]; /* 2 floats a pixel of fr per layer, at `frame` */
} adv_state;

void nprfx_advect_state_free(void *state)
{
    adv_state *s = state;
    if (!s) return;
    free(s->uv[0]);
    free(s->uv[1]);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

static adv_state *get_state(const nprfx_render_args *a)
{
    if (!a->state) return NULL;
    _Atomic(void *) *slot = (_Atomic(void *) *)a->state;
    adv_state *s = atomic_load(slot);
    if (s) return s;
    adv_state *fresh = calloc(1, sizeof *fresh);
    if (!fresh) return NULL;
    pthread_mutex_init(&fresh->lock, NULL);
    void *expected = NULL;
    if (atomic_compare_exchange_strong(slot, &expected, fresh)) return fresh;
    nprfx_advect_state_free(fresh); /* another tile's thread made it first */
    return expected;
}

static int same_params(const nprfx_advect_params *a, const nprfx_advect_params *b)
{
    return a->period == b->period && a->scale == b->scale && a->threshold == b->threshold &&
           a->seed == b->seed;
}

/* The input at frame f: the render's own at its time, else fetched. */
static nprfx_result input_at(const nprfx_render_args *a, int input, int f, nprfx_image *view,
                             const nprfx_image **out)
{
    *out = NULL;
    if (!a->inputs[input].data) return NPRFX_OK; /* not connected */
    if (f == (int)a->time) {
        *out = &a->inputs[input];
        return NPRFX_OK;
    }
    if (!a->fetch)
        return nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED,
                           "advect: frame %d needs its inputs at frame %d, and the caller cannot "
                           "fetch other frames",
                           (int)a->time, f);
    nprfx_result r = a->fetch(a->fetch_user, input, (double)f, view);
    if (r != NPRFX_OK) return r;
    *out = view;
    return NPRFX_OK;
}

/* Both layers at frame t into uv[0], uv[1] (each 2 floats a pixel of fr): one step from `have`
 * (the layers at t - 1) when given, else from the layers' starts. */
static nprfx_result compute(const nprfx_render_args *a, const nprfx_advect_params *p, nprfx_rect fr,
                            int t, float *const have[2], float *uv[2], float *scratch)
{
    const size_t n = 2 * (size_t)nprfx_rect_width(fr) * (size_t)nprfx_rect_height(fr);
    for (int layer = 0; layer < 2; layer++) {
        const int start = nprfx_advect_start(p, layer, t, a->first_frame, a->last_frame);
        int f = have && start < t ? t : start;
        const float *prev = have && start < t ? have[layer] : NULL;
        /* ping-pong between uv[layer] and scratch, ending in uv[layer] */
        float *bufs[2] = {uv[layer], scratch};
        int at = (t - f) % 2 == 0 ? 0 : 1;
        for (; f <= t; f++) {
            nprfx_image mv, cv;
            const nprfx_image *m = NULL, *c = NULL;
            nprfx_result r = NPRFX_OK;
            if (prev) {
                if ((r = input_at(a, NPRFX_ADVECT_IN_MOTION, f, &mv, &m)) == NPRFX_OK)
                    r = input_at(a, NPRFX_ADVECT_IN_CONFIDENCE, f, &cv, &c);
                if (r == NPRFX_OK && m->channels < 2)
                    r = nprfx_error(a->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                    "advect: motion_prev at frame %d has %d channel(s), needs 2", f,
                                    m->channels);
            }
            if (r != NPRFX_OK) return r;
            float *next = bufs[at];
            layer_step(a->ctx, p, fr, layer, start, prev, next, m, c);
            prev = next;
            at ^= 1;
        }
        if (prev != uv[layer]) memcpy(uv[layer], prev, n * sizeof(float)); /* never: parity */
    }
    return NPRFX_OK;
}

nprfx_result nprfx_advect_render(const nprfx_render_args *a, const nprfx_advect_params *p)
{
    if (!a || !p || !a->output)
        return nprfx_error(a ? a->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "advect: incomplete render arguments");
    if (a->output->channels != NPRFX_ADVECT_CHANNELS)
        return nprfx_error(a->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "advect: the output needs %d channels, it has %d", NPRFX_ADVECT_CHANNELS,
                           a->output->channels);
    const nprfx_rect fr = a->frame;
    const int t = (int)a->time;
    const size_t n = 2 * (size_t)nprfx_rect_width(fr) * (size_t)nprfx_rect_height(fr);
    if (!n) return NPRFX_OK;
    adv_state *s = get_state(a);
    if (s) pthread_mutex_lock(&s->lock);
    nprfx_result r = NPRFX_OK;
    float *own[2] = {NULL, NULL}, *scratch = malloc(n * sizeof(float));
    float **uv = s ? s->uv : own;
    const int same = s && s->valid && same_params(&s->key, p) && nprfx_rect_equal(s->fr, fr) &&
                     s->first == a->first_frame && s->last == a->last_frame;
    if (!scratch) {
        r = nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "advect: out of memory");
    } else if (!(same && s->frame == t)) {
        float *have[2] = {NULL, NULL};
        float *next[2] = {NULL, NULL};
        for (int k = 0; k < 2 && r == NPRFX_OK; k++) {
            next[k] = malloc(n * sizeof(float));
            if (!next[k]) r = nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "advect: out of memory");
        }
        if (same && s->frame == t - 1) have[0] = s->uv[0], have[1] = s->uv[1];
        if (r == NPRFX_OK) r = compute(a, p, fr, t, have[0] ? have : NULL, next, scratch);
        if (s) s->valid = 0;
        for (int k = 0; k < 2; k++) {
            free(uv[k]);
            uv[k] = next[k];
        }
        if (r == NPRFX_OK && s) {
            s->valid = 1;
            s->frame = t;
            s->fr = fr;
            s->key = *p;
            s->first = a->first_frame;
            s->last = a->last_frame;
        }
    }
    if (r == NPRFX_OK) {
        const float w = (float)nprfx_advect_weight(p, t);
        const nprfx_rect win = nprfx_rect_intersect(a->window, fr);
        const int fw = nprfx_rect_width(fr);
        for (int y = win.y0; y < win.y1; y++)
            for (int x = win.x0; x < win.x1; x++) {
                const size_t k = 2 * ((size_t)(y - fr.y0) * fw + (size_t)(x - fr.x0));
                float *o = nprfx_image_at(a->output, x, y);
                o[0] = uv[0][k];
                o[1] = uv[0][k + 1];
                o[2] = uv[1][k];
                o[3] = uv[1][k + 1];
                o[4] = w;
            }
    }
    free(scratch);
    if (!s) {
        free(own[0]);
        free(own[1]);
    }
    if (s) pthread_mutex_unlock(&s->lock);
    return r;
}
