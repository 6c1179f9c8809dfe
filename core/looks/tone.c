/* The tone node (docs/design.md §3.9). A style's threshold wants a tone in [0, 1], and a render's
 * shading AOV is anything but: direct light is 0 in shadow and in the sky, its top depends on the
 * light's strength, and a beauty's range on the exposure. Mapping each frame by its own range
 * would pump the tone from frame to frame, so the range is measured once — over every frame of
 * the shot, or on one reference frame — and every frame is mapped with it. */
#include <math.h>
#include <stddef.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/exec.h"
#include "base/internal_state.h"
#include "internal_tone.h"
#include "nprfx/rng.h"
#include "nprfx/tone.h"

/* A shot's measured samples are capped so that a long shot stays in bounded memory (16 MB). */
#define TONE_FRAME_SAMPLES 65536
#define TONE_SHOT_SAMPLES (4u << 20)

double nprfx_tone_value(const float *px, int channels)
{
    if (channels >= 3) return 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2];
    return px[0];
}

double nprfx_tone_band(double t, int bands, double softness)
{
    double x = t * bands;
    double k = floor(x), f = x - k;
    /* The ramp ends at the band's top, so a level starts exactly where the hard step would
     * put it and the bands keep their width whatever the softness. */
    double up = softness > 0.0 ? (f - 1.0 + softness) / softness : (f >= 1.0 ? 1.0 : 0.0);
    up = up > 0.0 ? (up < 1.0 ? up : 1.0) : 0.0;
    double level = k + up;
    if (level > bands - 1) level = bands - 1;
    return level / (bands - 1);
}

double nprfx_tone_map(const nprfx_tone_params *p, double lo, double hi, double v, double coverage)
{
    if (v != v) v = lo;
    double t;
    if (hi > lo)
        t = (v - lo) / (hi - lo);
    else
        t = v > lo ? 1.0 : 0.0;
    t *= exp2(p->exposure);
    t = t > 0.0 ? (t < 1.0 ? t : 1.0) : 0.0;
    if (p->gamma != 1.0 && t > 0.0 && t < 1.0) t = pow(t, 1.0 / p->gamma);
    if (p->bands >= 2) t = nprfx_tone_band(t, p->bands, p->band_softness);
    double out = p->out_low + (p->out_high - p->out_low) * t;
    /* spotted blacks: the deepest tones fade to 0 (the threshold's solid ink) continuously, so a
     * shadow's solid core grows and shrinks smoothly with the light instead of popping */
    if (p->solid_blacks > 0.0 && t < p->solid_blacks) out *= t / p->solid_blacks;
    if (coverage != coverage || coverage < 0.0) coverage = 0.0;
    if (coverage < 1.0) out = coverage * out + (1.0 - coverage) * p->background;
    return out;
}

/* ---- percentiles ---------------------------------------------------------------------------- */

static void swapf(float *a, float *b)
{
    float t = *a;
    *a = *b;
    *b = t;
}

/* Reorder v so that v[k] is the k-th smallest, smaller ones before it and larger after
 * (Hoare's selection with a median-of-three pivot: deterministic, linear on average). */
static void select_kth(float *v, size_t n, size_t k)
{
    ptrdiff_t lo = 0, hi = (ptrdiff_t)n - 1, kk = (ptrdiff_t)k;
    while (hi > lo) {
        ptrdiff_t mid = lo + (hi - lo) / 2;
        if (v[mid] < v[lo]) swapf(&v[mid], &v[lo]);
        if (v[hi] < v[lo]) swapf(&v[hi], &v[lo]);
        if (v[hi] < v[mid]) swapf(&v[hi], &v[mid]);
        float pivot = v[mid];
        ptrdiff_t i = lo, j = hi;
        while (i <= j) {
            while (v[i] < pivot)
                i++;
            while (pivot < v[j])
                j--;
            if (i <= j) swapf(&v[i++], &v[j--]);
        }
        /* now v[lo..j] <= pivot <= v[i..hi], and anything between equals the pivot */
        if (kk <= j)
            hi = j;
        else if (kk >= i)
            lo = i;
        else
            return;
    }
}

double nprfx_tone_percentile(float *values, size_t n, double q)
{
    if (n == 0) return 0.0;
    if (!(q > 0.0)) q = 0.0;
    if (q > 100.0) q = 100.0;
    double pos = q / 100.0 * (double)(n - 1);
    size_t k = (size_t)floor(pos);
    if (k >= n - 1) k = n - 1;
    double f = pos - (double)k;
    select_kth(values, n, k);
    double a = values[k];
    if (f <= 0.0 || k + 1 >= n) return a;
    /* the next order statistic is the smallest of what follows v[k] */
    float b = values[k + 1];
    for (size_t i = k + 2; i < n; i++)
        if (values[i] < b) b = values[i];
    return a + f * (b - a);
}

/* The value mapped at (x, y): the tone, divided by the albedo when there is one. Outside an
 * input's data window it reads as 0 (the OpenEXR convention). */
static double pixel_value(const nprfx_image *tone, const nprfx_image *albedo, int x, int y)
{
    if (!nprfx_rect_contains(tone->bounds, x, y)) return 0.0;
    double v = nprfx_tone_value(nprfx_image_at(tone, x, y), tone->channels);
    if (!albedo) return v;
    double a = nprfx_rect_contains(albedo->bounds, x, y)
                   ? nprfx_tone_value(nprfx_image_at(albedo, x, y), albedo->channels)
                   : 0.0;
    return nprfx_tone_light(v, a);
}

double nprfx_tone_light(double tone, double albedo)
{
    /* Black albedo has no light to show: such a surface is as dark as it gets. */
    return albedo > NPRFX_TONE_MIN_ALBEDO ? tone / albedo : 0.0;
}

static nprfx_result tone_samples_capped(nprfx_context *ctx, const nprfx_image *tone,
                                        const nprfx_image *albedo, const nprfx_image *coverage,
                                        size_t cap, float **values, size_t *n,
                                        unsigned long long *hash)
{
    *values = NULL;
    *n = 0;
    int w = nprfx_rect_width(tone->bounds), h = nprfx_rect_height(tone->bounds);
    int s = 1;
    while ((size_t)(w / s) * (size_t)(h / s) > cap)
        s++;
    size_t most = (size_t)((w + s - 1) / s) * (size_t)((h + s - 1) / s);
    float *v = malloc((most ? most : 1) * sizeof *v);
    if (!v)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "tone: no memory for %zu samples", most);
    uint64_t hh = NPRFX_FNV_INIT;
    hh = nprfx_fnv1a(hh, &tone->bounds, sizeof tone->bounds);
    hh = nprfx_fnv1a(hh, &s, sizeof s);
    size_t k = 0;
    for (int y = tone->bounds.y0; y < tone->bounds.y1; y += s)
        for (int x = tone->bounds.x0; x < tone->bounds.x1; x += s) {
            if (coverage) {
                double c = nprfx_rect_contains(coverage->bounds, x, y)
                               ? nprfx_image_at(coverage, x, y)[0]
                               : 0.0;
                if (!(c >= 0.5)) continue;
            }
            double t = pixel_value(tone, albedo, x, y);
            if (!isfinite(t)) continue;
            float f = (float)t;
            v[k++] = f;
            hh = nprfx_fnv1a(hh, &f, sizeof f);
        }
    hh = nprfx_fnv1a(hh, &k, sizeof k);
    *values = v;
    *n = k;
    *hash = hh;
    return NPRFX_OK;
}

nprfx_result nprfx_tone_samples(nprfx_context *ctx, const nprfx_image *tone,
                                const nprfx_image *albedo, const nprfx_image *coverage,
                                float **values, size_t *n, unsigned long long *hash)
{
    if (!tone || !tone->data || !values || !n || !hash)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "tone: no input to sample");
    return tone_samples_capped(ctx, tone, albedo && albedo->data ? albedo : NULL,
                               coverage && coverage->data ? coverage : NULL, TONE_FRAME_SAMPLES,
                               values, n, hash);
}

/* ---- the per-instance cache (internal_tone.h; its text form: tone_state.c) ------------------- */

typedef internal_tone_cache tone_cache;

/* ---- measuring ------------------------------------------------------------------------------- */

typedef struct tone_run {
    nprfx_context *ctx;
    const nprfx_tone_params *p;
    const nprfx_image *tone, *albedo, *coverage; /* at `time`; albedo, coverage may be NULL */
    double time;
    nprfx_fetch_fn fetch;
    void *fetch_user;
    const int *input; /* the input indices of tone, albedo, coverage */
} tone_run;

/* The samples of frame f: the render's own inputs at its time, fetched ones otherwise. */
static nprfx_result frame_samples(const tone_run *run, double f, size_t cap, float **v, size_t *n,
                                  uint64_t *hash)
{
    const nprfx_image *im[3] = {run->tone, run->albedo, run->coverage};
    nprfx_image views[3];
    if (f != run->time)
        for (int i = 0; i < 3; i++) {
            if (!im[i]) continue;
            nprfx_result r = run->fetch(run->fetch_user, run->input[i], f, &views[i]);
            if (r) return r;
            im[i] = &views[i];
        }
    unsigned long long hh = 0;
    nprfx_result r = tone_samples_capped(run->ctx, im[0], im[1], im[2], cap, v, n, &hh);
    *hash = hh;
    return r;
}

static void percentiles(const nprfx_tone_params *p, float *v, size_t n, double *lo, double *hi)
{
    if (n == 0) {
        *lo = 0.0;
        *hi = 1.0;
        return;
    }
    *lo = nprfx_tone_percentile(v, n, p->low);
    *hi = nprfx_tone_percentile(v, n, p->high);
}

static nprfx_result measure_frame(const tone_run *run, tone_cache *c, int first, int last)
{
    const nprfx_tone_params *p = run->p;
    if (p->reference_frame != run->time && !run->fetch)
        return nprfx_error(run->ctx, NPRFX_ERR_UNSUPPORTED,
                           "tone: range 'frame' measures frame %d, and this host cannot fetch "
                           "other frames: render frame %d, or use range 'manual'",
                           p->reference_frame, p->reference_frame);
    float *v;
    size_t n;
    uint64_t h;
    nprfx_result r = frame_samples(run, p->reference_frame, TONE_FRAME_SAMPLES, &v, &n, &h);
    if (r) return r;
    if (!(c->valid && c->range == NPRFX_TONE_RANGE_FRAME && c->reference == p->reference_frame &&
          c->low == p->low && c->high == p->high && c->nframes == 1 && c->hash[0] == h)) {
        uint64_t *hs = realloc(c->hash, sizeof *hs);
        if (!hs) {
            free(v);
            return nprfx_error(run->ctx, NPRFX_ERR_OUT_OF_MEMORY, "tone: no memory");
        }
        c->hash = hs;
        percentiles(p, v, n, &c->lo, &c->hi);
        c->hash[0] = h;
        c->nframes = 1;
        c->range = NPRFX_TONE_RANGE_FRAME;
        c->reference = p->reference_frame;
        c->low = p->low;
        c->high = p->high;
        c->first = first;
        c->last = last;
        c->valid = 1;
    }
    free(v);
    return NPRFX_OK;
}

static nprfx_result measure_shot(const tone_run *run, tone_cache *c, int first, int last)
{
    const nprfx_tone_params *p = run->p;
    int nframes = last - first + 1;
    size_t cap = TONE_SHOT_SAMPLES / (size_t)nframes;
    if (cap > TONE_FRAME_SAMPLES) cap = TONE_FRAME_SAMPLES;
    if (cap < 256) cap = 256;
    /* This frame's fingerprint decides whether the stored range still holds. */
    float *v;
    size_t n;
    uint64_t h;
    nprfx_result r = frame_samples(run, run->time, cap, &v, &n, &h);
    if (r) return r;
    free(v);
    int at = (int)run->time - first;
    if (c->valid && c->range == NPRFX_TONE_RANGE_SHOT && c->first == first && c->last == last &&
        c->low == p->low && c->high == p->high && c->nframes == nframes && at >= 0 &&
        at < nframes && c->hash[at] == h)
        return NPRFX_OK;
    if (nframes > 1 && !run->fetch)
        return nprfx_error(run->ctx, NPRFX_ERR_UNSUPPORTED,
                           "tone: range 'shot' measures every frame of the shot (%d-%d), and "
                           "this host cannot fetch other frames: use range 'frame' or 'manual'",
                           first, last);
    uint64_t *hs = malloc((size_t)nframes * sizeof *hs);
    float *all = malloc(cap * (size_t)nframes * sizeof *all);
    if (!hs || !all) {
        free(hs);
        free(all);
        return nprfx_error(run->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                           "tone: no memory to measure %d frames", nframes);
    }
    size_t total = 0;
    for (int f = first; f <= last; f++) {
        if ((r = frame_samples(run, f, cap, &v, &n, &hs[f - first]))) {
            free(hs);
            free(all);
            return r;
        }
        memcpy(all + total, v, n * sizeof *v);
        total += n;
        free(v);
    }
    percentiles(p, all, total, &c->lo, &c->hi);
    free(all);
    free(c->hash);
    c->hash = hs;
    c->nframes = nframes;
    c->range = NPRFX_TONE_RANGE_SHOT;
    c->low = p->low;
    c->high = p->high;
    c->first = first;
    c->last = last;
    c->valid = 1;
    return NPRFX_OK;
}

/* ---- mapping --------------------------------------------------------------------------------- */

typedef struct tone_job {
    const nprfx_tone_params *p;
    double lo, hi;
    const nprfx_image *tone, *albedo, *coverage;
    nprfx_rect window;
    nprfx_image *out;
} tone_job;

static void tone_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const tone_job *j = user;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++)
        for (int x = j->window.x0; x < j->window.x1; x++) {
            double v = pixel_value(j->tone, j->albedo, x, y);
            double c = 1.0;
            if (j->coverage)
                c = nprfx_rect_contains(j->coverage->bounds, x, y)
                        ? nprfx_image_at(j->coverage, x, y)[0]
                        : 0.0;
            if (c > 1.0) c = 1.0;
            nprfx_image_at(j->out, x, y)[0] = (float)nprfx_tone_map(j->p, j->lo, j->hi, v, c);
        }
}

/* The frames a 'shot' range measures: the shot, or the frame alone when the shot is unknown or
 * does not hold it. */
static void tone_shot(int time, int first_frame, int last_frame, int *first, int *last)
{
    *first = first_frame;
    *last = last_frame;
    if (*first > *last || time < *first || time > *last) *first = *last = time;
}

int nprfx_tone_frames(const nprfx_tone_params *p, const nprfx_frames_query *q,
                      nprfx_frame_range *ranges)
{
    /* Every connected input (tone, albedo, coverage) is sampled at the measured frames. */
    ranges[0].first = ranges[0].last = q->time;
    /* A state that holds this shot's range, measured with these params, reads the frame itself
     * (whose fingerprint it checks): a host rendering on prepares one frame, not the shot.
     * (Range 'frame' reads its reference frame every time, to check it.) */
    const tone_cache *c = q->state;
    int first = q->first_frame, last = q->last_frame;
    if (p->range == NPRFX_TONE_RANGE_SHOT)
        tone_shot(q->time, q->first_frame, q->last_frame, &first, &last);
    if (p->range == NPRFX_TONE_RANGE_SHOT && c && c->valid && c->range == p->range &&
        c->low == p->low && c->high == p->high && c->first == first && c->last == last &&
        q->time >= first && q->time <= last)
        return 1;
    if (p->range == NPRFX_TONE_RANGE_SHOT)
        ranges[0].first = first, ranges[0].last = last;
    else if (p->range == NPRFX_TONE_RANGE_FRAME)
        ranges[0].first = ranges[0].last = p->reference_frame;
    return 1;
}

nprfx_result nprfx_tone_render(const nprfx_render_args *args, const nprfx_tone_params *p)
{
    /* the inputs measured at other frames, in tone_run's order: tone, albedo, coverage */
    static const int input[3] = {NPRFX_TONE_IN_TONE, NPRFX_TONE_IN_ALBEDO, NPRFX_TONE_IN_COVERAGE};
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const nprfx_image *tone = nprfx_render_input(args, NPRFX_TONE_IN_TONE);
    const nprfx_image *albedo = nprfx_render_input(args, NPRFX_TONE_IN_ALBEDO);
    const nprfx_image *coverage = nprfx_render_input(args, NPRFX_TONE_IN_COVERAGE);
    double time = args->time;
    void **state = args->state;
    nprfx_rect window = args->window;
    nprfx_image *out = args->output;
    if (!p || !tone || !tone->data || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "tone: no params, input or output");
    if (out->channels != 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "tone: output has %d channels, expected 1", out->channels);
    if (p->range < 0 || p->range >= NPRFX_TONE_RANGE_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "tone.range: no range with index %d",
                           p->range);
    if (!(p->gamma > 0.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "tone.gamma: %g is not positive", p->gamma);
    if (p->range != NPRFX_TONE_RANGE_MANUAL && !(p->low < p->high))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "tone: percentile low (%g) must be below high (%g)", p->low, p->high);
    if (coverage && !coverage->data) coverage = NULL;
    if (albedo && !albedo->data) albedo = NULL;
    if (nprfx_rect_empty(window)) return NPRFX_OK;

    double lo = p->black, hi = p->white;
    /* Measuring this frame alone instead would be a silent per-frame answer: a range that
     * changes at every frame (a host without temporal clip access says nothing of the shot). */
    if (p->range == NPRFX_TONE_RANGE_SHOT && args->last_frame < args->first_frame)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "tone: range 'shot' measures every frame of the shot, and which frames "
                           "make it is not known here (a host without temporal clip access gives "
                           "a plug-in only the frame it renders): use range 'frame' or 'manual'");
    if (p->range != NPRFX_TONE_RANGE_MANUAL) {
        int first, last;
        tone_shot((int)time, args->first_frame, args->last_frame, &first, &last);
        tone_cache local;
        memset(&local, 0, sizeof local);
        tone_cache *c = state ? internal_state_get(state, sizeof *c) : &local;
        if (!c) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "tone: no memory for its cache");
        tone_run run = {ctx, p, tone, albedo, coverage, time, args->fetch, args->fetch_user, input};
        if (c != &local) pthread_mutex_lock(&c->lock);
        nprfx_result r = p->range == NPRFX_TONE_RANGE_SHOT ? measure_shot(&run, c, first, last)
                                                           : measure_frame(&run, c, first, last);
        lo = c->lo;
        hi = c->hi;
        if (c != &local)
            pthread_mutex_unlock(&c->lock);
        else
            free(local.hash);
        if (r) return r;
    }
    tone_job j = {p, lo, hi, tone, albedo, coverage, window, out};
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(window), 16, tone_rows, &j);
    return NPRFX_OK;
}
