/* Coherent noise (Kass & Pesare 2011): the parameters, the pass states and a pass's first frame.
 * See include/nprfx/coherent_noise.h for the maths. The files of the model:
 *   cn_noise.c       the innovation noise: counter-based white noise, band-pass fields, kernels
 *   cn_stationary.c  the resampler's tables: Catmull-Rom and its spectral compensation filters
 *   cn_step.c        one recursion step: occlusion test, resampling, vector paths
 *   cn_output.c      the node's value from the passes (Eq. 11) and post-smoothing
 *   cn_temporal.c    the node's render: a per-instance cache of pass states with checkpoints
 *
 * Everything but the cache is a pure function of its arguments: row-parallel loops write disjoint
 * rows and every random number is a hash of its counter, so results do not depend on the thread
 * count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_coherent_noise.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"

void nprfx_cn_params_default(nprfx_cn_params *p)
{
    memset(p, 0, sizeof *p);
    p->size = sizeof *p;
    p->alpha = 0.9;
    p->epsilon = 0.01;
    p->noise = NPRFX_CN_NOISE_WHITE;
    p->sigma_lo = 1.0;
    p->sigma_hi = 3.0;
    p->channels = 1;
    p->seed = 0;
    p->resample = NPRFX_CN_RESAMPLE_STATIONARY;
    p->motion_scale = 1.0;
}

nprfx_result nprfx_cn_params_check(nprfx_context *ctx, const nprfx_cn_params *p)
{
    if (!p || p->size < sizeof *p)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "coherent-noise: bad params struct");
    if (!(p->alpha >= 0.0 && p->alpha <= 1.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "coherent-noise.alpha: %g is outside [0, 1]", p->alpha);
    if (!(p->epsilon >= 0.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "coherent-noise.epsilon: %g must be >= 0",
                           p->epsilon);
    if (p->noise < NPRFX_CN_NOISE_WHITE || p->noise > NPRFX_CN_NOISE_INPUT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "coherent-noise.noise: unknown kind %d",
                           p->noise);
    if (p->channels < 1 || p->channels > NPRFX_MAX_CHANNELS ||
        (p->noise != NPRFX_CN_NOISE_INPUT && p->channels > 4))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "coherent-noise.channels: %d is outside [1, 4]", p->channels);
    if (p->noise == NPRFX_CN_NOISE_BANDPASS) {
        if (!(p->sigma_lo >= 0.0 && p->sigma_lo <= 1024.0))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                               "coherent-noise.sigma_lo: %g is outside [0, 1024]", p->sigma_lo);
        if (!(p->sigma_hi >= 0.0 && p->sigma_hi <= 1024.0))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                               "coherent-noise.sigma_hi: %g is outside [0, 1024]", p->sigma_hi);
        if (p->sigma_hi > 0.0 && !(p->sigma_hi > p->sigma_lo * 1.05 + 0.05))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                               "coherent-noise.sigma_hi: %g must be clearly larger than sigma_lo "
                               "%g (or 0 for no low cut): the band would be empty",
                               p->sigma_hi, p->sigma_lo);
    }
    if (p->resample != NPRFX_CN_RESAMPLE_STATIONARY && p->resample != NPRFX_CN_RESAMPLE_BILINEAR)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "coherent-noise: unknown resampler %d",
                           p->resample);
    if (!(p->motion_scale > 0.0) || !isfinite(p->motion_scale))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "coherent-noise: motion scale %g must be > 0", p->motion_scale);
    return NPRFX_OK;
}

double nprfx_cn_k(double alpha)
{
    if (alpha >= 1.0) return 0.0;
    if (alpha <= 0.0) return 1.0;
    return sqrt((1.0 - alpha) / (1.0 + alpha));
}

/* ---- states ------------------------------------------------------------------------------ */

size_t nprfx_cn_state_bytes(nprfx_rect frame, int channels)
{
    size_t n = (size_t)nprfx_rect_width(frame) * (size_t)nprfx_rect_height(frame);
    return n * ((size_t)channels * sizeof(float) + 1);
}

nprfx_result nprfx_cn_state_alloc(nprfx_context *ctx, nprfx_rect frame, int channels,
                                  nprfx_cn_state *out)
{
    memset(out, 0, sizeof *out);
    nprfx_result r = nprfx_image_alloc(ctx, frame, channels, &out->value);
    if (r) return r;
    size_t n = (size_t)nprfx_rect_width(frame) * (size_t)nprfx_rect_height(frame);
    out->fresh = calloc(n ? n : 1, 1);
    if (!out->fresh) {
        nprfx_image_free(&out->value);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY,
                           "coherent-noise: out of memory for a %zu-pixel state", n);
    }
    return NPRFX_OK;
}

void nprfx_cn_state_free(nprfx_cn_state *s)
{
    if (!s) return;
    nprfx_image_free(&s->value);
    free(s->fresh);
    s->fresh = NULL;
}

typedef struct internal_copy_job {
    const nprfx_cn_state *src;
    nprfx_cn_state *dst;
} internal_copy_job;

static void internal_copy_rows(void *user, int begin, int end, int worker)
{
    const internal_copy_job *j = user;
    const nprfx_image *s = &j->src->value;
    const size_t w = (size_t)nprfx_rect_width(s->bounds), C = (size_t)s->channels;
    (void)worker;
    /* Both are packed allocations of the same shape. */
    memcpy(j->dst->value.data + (size_t)begin * w * C, s->data + (size_t)begin * w * C,
           (size_t)(end - begin) * w * C * sizeof(float));
    memcpy(j->dst->fresh + (size_t)begin * w, j->src->fresh + (size_t)begin * w,
           (size_t)(end - begin) * w);
}

nprfx_result nprfx_cn_state_copy(nprfx_context *ctx, const nprfx_cn_state *src, nprfx_cn_state *dst)
{
    if (!nprfx_rect_equal(src->value.bounds, dst->value.bounds) ||
        src->value.channels != dst->value.channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH, "coherent-noise: state shape differs");
    internal_copy_job job = {src, dst};
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(src->value.bounds), 32,
                       internal_copy_rows, &job);
    return NPRFX_OK;
}

nprfx_result internal_cn_check_view(nprfx_context *ctx, const nprfx_image *im, int channels,
                                    const char *name)
{
    if (!im || !im->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "coherent-noise: input %s is missing",
                           name);
    if (im->channels < channels)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "coherent-noise: input %s has %d channel(s), needs %d", name,
                           im->channels, channels);
    if (nprfx_rect_empty(im->bounds))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "coherent-noise: input %s is empty", name);
    return NPRFX_OK;
}

nprfx_result nprfx_cn_begin(nprfx_context *ctx, const nprfx_cn_params *p, int64_t frame,
                            const nprfx_image *source, nprfx_cn_state *out)
{
    nprfx_result r = nprfx_cn_params_check(ctx, p);
    if (r) return r;
    nprfx_image *O = &out->value;
    if (O->channels != p->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "coherent-noise: state has %d channels, params say %d", O->channels,
                           p->channels);
    size_t n = (size_t)nprfx_rect_width(O->bounds) * (size_t)nprfx_rect_height(O->bounds);
    memset(out->fresh, 1, n);
    if (p->noise == NPRFX_CN_NOISE_INPUT) {
        if ((r = internal_cn_check_view(ctx, source, p->channels, "source"))) return r;
        for (int y = O->bounds.y0; y < O->bounds.y1; y++)
            for (int x = O->bounds.x0; x < O->bounds.x1; x++) {
                float *o = nprfx_image_at(O, x, y);
                for (int c = 0; c < p->channels; c++)
                    o[c] = internal_source_fresh(internal_read(source, x, y, c));
            }
        return NPRFX_OK;
    }
    return nprfx_cn_noise_fill(ctx, p, frame, 0, O);
}
