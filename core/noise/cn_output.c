/* The coherent-noise node's value from the passes' states: the causal state itself, or the
 * symmetric combination of the forward and backward passes (Eq. 11, normalised to unit variance),
 * and the post-smoothing (paper section 3.4) with its analytic renormalisation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_coherent_noise.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"

typedef struct internal_combine_job {
    const nprfx_cn_params *p;
    int64_t frame;
    const nprfx_cn_state *fwd, *bwd;
    const nprfx_image *s; /* source (input mode) or a band-pass w; NULL: white w made per row */
    nprfx_image *out;
    float g_both, g_one, norm;
    int input_mode; /* s is the source clip, whose non-finite samples are missing */
    float *scratch;
    size_t scratch_len;
} internal_combine_job;

static void internal_combine_rows(void *user, int begin, int end, int worker)
{
    const internal_combine_job *j = user;
    const nprfx_rect fr = j->out->bounds;
    const int C = j->out->channels, W = nprfx_rect_width(fr);
    float *wbuf = j->scratch + (size_t)worker * j->scratch_len, *tmp = wbuf + (size_t)W * C;
    for (int y = fr.y0 + begin; y < fr.y0 + end; y++) {
        if (!j->s) internal_cn_noise_row(j->p, j->frame, 0, y, fr.x0, W, C, tmp, wbuf);
        const unsigned char *ff = j->fwd->fresh + (size_t)(y - fr.y0) * (size_t)W;
        const unsigned char *fb = j->bwd->fresh + (size_t)(y - fr.y0) * (size_t)W;
        for (int x = fr.x0; x < fr.x1; x++) {
            const float *f = nprfx_image_at(&j->fwd->value, x, y);
            const float *b = nprfx_image_at(&j->bwd->value, x, y);
            float *o = nprfx_image_at(j->out, x, y);
            float g = ff[x - fr.x0] && fb[x - fr.x0] ? j->g_both : j->g_one;
            if (j->s && j->input_mode)
                for (int c = 0; c < C; c++) {
                    /* A missing source sample is in neither pass (internal_mix_source): their
                     * mean, each of unit gain, is the filter without it. */
                    float sv = internal_read(j->s, x, y, c);
                    o[c] = isfinite(sv) ? (f[c] + b[c] - g * sv) * j->norm : 0.5f * (f[c] + b[c]);
                }
            else if (j->s)
                for (int c = 0; c < C; c++)
                    o[c] = (f[c] + b[c] - g * internal_read(j->s, x, y, c)) * j->norm;
            else
                for (int c = 0; c < C; c++)
                    o[c] = (f[c] + b[c] - g * wbuf[(size_t)(x - fr.x0) * (size_t)C + c]) * j->norm;
        }
    }
}

nprfx_result nprfx_cn_combine(nprfx_context *ctx, const nprfx_cn_params *p, int64_t frame,
                              const nprfx_cn_state *fwd, const nprfx_cn_state *bwd,
                              const nprfx_image *source, nprfx_image *out)
{
    nprfx_result r = nprfx_cn_params_check(ctx, p);
    if (r) return r;
    if (!fwd || !out || out->channels != p->channels ||
        !nprfx_rect_equal(out->bounds, fwd->value.bounds) ||
        (bwd && !nprfx_rect_equal(bwd->value.bounds, fwd->value.bounds)))
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "coherent-noise: combine buffers differ in size or channels");
    const nprfx_rect fr = out->bounds;
    const int C = p->channels, W = nprfx_rect_width(fr), H = nprfx_rect_height(fr);
    if (W <= 0 || H <= 0) return NPRFX_OK;
    if (!bwd) {
        for (int y = fr.y0; y < fr.y1; y++)
            for (int x = fr.x0; x < fr.x1; x++) {
                const float *f = nprfx_image_at(&fwd->value, x, y);
                float *o = nprfx_image_at(out, x, y);
                for (int c = 0; c < C; c++)
                    o[c] = f[c];
            }
        return NPRFX_OK;
    }
    int input_mode = p->noise == NPRFX_CN_NOISE_INPUT;
    internal_combine_job job;
    memset(&job, 0, sizeof job);
    job.p = p;
    job.frame = frame;
    job.fwd = fwd;
    job.bwd = bwd;
    job.out = out;
    nprfx_image w = {0};
    if (input_mode) {
        if ((r = internal_cn_check_view(ctx, source, C, "source"))) return r;
        job.s = source;
    } else if (internal_is_bandpass(p)) {
        if ((r = nprfx_image_alloc(ctx, fr, C, &w)) ||
            (r = nprfx_cn_noise_fill(ctx, p, frame, 0, &w))) {
            nprfx_image_free(&w);
            return r;
        }
        job.s = &w;
    }
    double a = p->alpha;
    job.input_mode = input_mode;
    if (input_mode) {
        job.g_both = job.g_one = (float)(1.0 - a);
        job.norm = (float)(1.0 / (1.0 + a));
    } else {
        job.g_one = (float)sqrt(1.0 - a * a);
        job.g_both = (float)(2.0 - sqrt(1.0 + a * a));
        job.norm = (float)(1.0 / sqrt(1.0 + a * a));
    }
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    int workers = nprfx_executor_workers(ex);
    if (workers < 1) workers = 1;
    job.scratch_len = (size_t)W * (size_t)C + (size_t)W + INTERNAL_PAD;
    job.scratch = malloc((size_t)workers * job.scratch_len * sizeof(float));
    if (!job.scratch) {
        nprfx_image_free(&w);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory");
    }
    nprfx_parallel_for(ex, H, 16, internal_combine_rows, &job);
    free(job.scratch);
    nprfx_image_free(&w);
    return NPRFX_OK;
}

/* ---- post-smoothing ------------------------------------------------------------------------ */

typedef struct internal_blur_job {
    const internal_kernel *k;
    const nprfx_image *src;
    nprfx_image *dst;
    int vertical;
    float gain;
} internal_blur_job;

static void internal_blur_px(const internal_blur_job *j, int x, int y)
{
    const int C = j->dst->channels, R = j->k->radius;
    float *o = nprfx_image_at(j->dst, x, y);
    for (int c = 0; c < C; c++) {
        double s = 0.0;
        for (int i = -R; i <= R; i++)
            s += j->k->w[i + R] * (j->vertical ? internal_read(j->src, x, y + i, c)
                                               : internal_read(j->src, x + i, y, c));
        o[c] = (float)(s * j->gain);
    }
}

/* Edge pixels (taps clamped to the image) one by one; elsewhere, on packed images, both passes are
 * 1D convolutions of the interleaved row: taps C floats apart (horizontal) or a row apart
 * (vertical), the same sums in the same order. */
static void internal_blur_rows(void *user, int begin, int end, int worker)
{
    const internal_blur_job *j = user;
    const nprfx_rect b = j->dst->bounds;
    const int C = j->dst->channels, R = j->k->radius, W = nprfx_rect_width(b);
    const int packed = j->src->pixel_stride == C && j->dst->pixel_stride == C &&
                       nprfx_rect_equal(j->src->bounds, b);
    (void)worker;
    for (int y = b.y0 + begin; y < b.y0 + end; y++) {
        if (packed && j->vertical && y - R >= b.y0 && y + R < b.y1) {
            internal_cn_conv(j->k->w, 2 * R + 1, nprfx_image_at(j->src, b.x0, y - R),
                             j->src->row_stride, W * C, j->gain, nprfx_image_at(j->dst, b.x0, y));
            continue;
        }
        if (packed && !j->vertical && W > 2 * R) {
            for (int x = b.x0; x < b.x0 + R; x++)
                internal_blur_px(j, x, y);
            internal_cn_conv(j->k->w, 2 * R + 1, nprfx_image_at(j->src, b.x0, y), C,
                             (W - 2 * R) * C, j->gain, nprfx_image_at(j->dst, b.x0 + R, y));
            for (int x = b.x1 - R; x < b.x1; x++)
                internal_blur_px(j, x, y);
            continue;
        }
        for (int x = b.x0; x < b.x1; x++)
            internal_blur_px(j, x, y);
    }
}

nprfx_result nprfx_cn_smooth(nprfx_context *ctx, const nprfx_cn_params *p, double sigma,
                             nprfx_image *img)
{
    if (!(sigma > 0.0)) return NPRFX_OK;
    internal_kernel k;
    if (!internal_cn_kernel_make(&k, sigma))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory (smooth)");
    nprfx_image tmp;
    nprfx_result r = nprfx_image_alloc(ctx, img->bounds, img->channels, &tmp);
    if (r) {
        internal_cn_kernel_free(&k);
        return r;
    }
    double v = p->noise == NPRFX_CN_NOISE_INPUT ? 1.0 : nprfx_cn_smoothed_variance(p, sigma);
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    internal_blur_job h = {&k, img, &tmp, 0, 1.0f};
    nprfx_parallel_for(ex, nprfx_rect_height(img->bounds), 8, internal_blur_rows, &h);
    internal_blur_job vj = {&k, &tmp, img, 1, (float)(v > 0.0 ? 1.0 / sqrt(v) : 1.0)};
    nprfx_parallel_for(ex, nprfx_rect_height(img->bounds), 8, internal_blur_rows, &vj);
    nprfx_image_free(&tmp);
    internal_cn_kernel_free(&k);
    return NPRFX_OK;
}
