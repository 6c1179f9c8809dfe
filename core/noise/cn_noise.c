/* The innovation noise of coherent noise: unit-variance counter-based noise rows (white, four
 * 16-bit quarters of a hash summed), whole white or band-pass fields (G(sigma_lo) * w -
 * G(sigma_hi) * w, renormalised analytically), the 1D Gaussian kernels, and the variance of the
 * innovation after post-smoothing. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_coherent_noise.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"

/* ---- counter-based Gaussian-like noise ----------------------------------------------------- */

#if INTERNAL_VEC
/* Eight samples from eight hash inputs (row key ^ x * INTERNAL_X_MUL): internal_gauss_at's
 * integer and double operations, lane by lane. */
INTERNAL_VINLINE internal_v8f internal_gauss_v8(const internal_v8u *in)
{
    internal_v8u z = *in;
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    /* the sum of the four 16-bit quarters: pairwise into two 32-bit halves, then the halves (the
     * sum is below 2^18) */
    const internal_v8u m = (internal_v8u){0, 0, 0, 0, 0, 0, 0, 0} + 0x0000ffff0000ffffull;
    internal_v8u t = (z & m) + ((z >> 16) & m);
    t = (t + (t >> 32)) & 0xffffffffu;
    internal_v8d d =
        __builtin_convertvector(__builtin_convertvector(t, internal_v8i), internal_v8d);
    return __builtin_convertvector((d - INTERNAL_IH_MEAN) * INTERNAL_IH_SCALE, internal_v8f);
}
#endif

/* Channels 0..C-1 (C <= 4, keys[c] the row keys) of pixels x0..x0+n-1, interleaved:
 * dst[i*C + c] = internal_gauss_at(keys[c], x0 + i). The vector loop covers 8 pixels (C vectors)
 * at a time; each lane knows its channel's key and its x. */
#if INTERNAL_VEC
INTERNAL_VINLINE int internal_gauss_il_v(const uint64_t *keys, const int C, int x0, int n,
                                         float *dst)
{
    internal_v8u key[4], xm[4];
    for (int v = 0; v < C; v++)
        for (int l = 0; l < 8; l++) {
            int q = 8 * v + l;
            key[v][l] = keys[q % C];
            xm[v][l] = (uint64_t)(uint32_t)(x0 + q / C) * INTERNAL_X_MUL;
        }
    int i = 0;
    if (x0 >= 0 && (int64_t)x0 + n <= INT32_MAX) {
        /* x >= 0: (uint32_t)x * MUL steps by 8 * MUL (mod 2^64) every 8 pixels */
        for (; i + 8 <= n; i += 8)
            for (int v = 0; v < C; v++) {
                const internal_v8u h = xm[v] ^ key[v];
                internal_v8f f = internal_gauss_v8(&h);
                memcpy(dst + (size_t)i * (size_t)C + 8 * (size_t)v, &f, sizeof f);
                xm[v] += 8 * INTERNAL_X_MUL;
            }
    } else {
        for (; i + 8 <= n; i += 8)
            for (int v = 0; v < C; v++) {
                for (int l = 0; l < 8; l++)
                    xm[v][l] = (uint64_t)(uint32_t)(x0 + i + (8 * v + l) / C) * INTERNAL_X_MUL;
                const internal_v8u h = xm[v] ^ key[v];
                internal_v8f f = internal_gauss_v8(&h);
                memcpy(dst + (size_t)i * (size_t)C + 8 * (size_t)v, &f, sizeof f);
            }
    }
    return i;
}
#endif

INTERNAL_CLONES
void internal_cn_gauss_row_il(const uint64_t *keys, int C, int x0, int n, float *dst)
{
    int i = 0;
#if INTERNAL_VEC
    switch (C) {
    case 1:
        i = internal_gauss_il_v(keys, 1, x0, n, dst);
        break;
    case 2:
        i = internal_gauss_il_v(keys, 2, x0, n, dst);
        break;
    case 3:
        i = internal_gauss_il_v(keys, 3, x0, n, dst);
        break;
    case 4:
        i = internal_gauss_il_v(keys, 4, x0, n, dst);
        break;
    }
#endif
    for (; i < n; i++)
        for (int c = 0; c < C; c++)
            dst[(size_t)i * (size_t)C + (size_t)c] = internal_gauss_at(keys[c], x0 + i);
}

/* dst[i] = internal_gauss_at(key, x0 + i) for i in [0, n). */
static void internal_gauss_row(uint64_t key, int x0, int n, float *dst)
{
    internal_cn_gauss_row_il(&key, 1, x0, n, dst);
}

/* Channels 0..C-1 of the noise row y over x0..x0+n-1, interleaved: dst[i*C + c]. tmp holds n
 * floats. */
void internal_cn_noise_row(const nprfx_cn_params *p, int64_t frame, uint32_t stream, int y, int x0,
                           int n, int C, float *tmp, float *dst)
{
    uint64_t keys[NPRFX_MAX_CHANNELS];
    for (int c = 0; c < C; c++)
        keys[c] = internal_row_key(p->seed, frame, y, (uint32_t)c, stream);
    if (C <= 4) {
        internal_cn_gauss_row_il(keys, C, x0, n, dst);
        return;
    }
    for (int c = 0; c < C; c++) {
        internal_gauss_row(keys[c], x0, n, tmp);
        float *d = dst + c;
        for (int i = 0; i < n; i++)
            d[(size_t)i * (size_t)C] = tmp[i];
    }
}

/* ---- 1D Gaussian kernels and the band-pass variance ----------------------------------------- */

int internal_cn_kernel_make(internal_kernel *k, double sigma)
{
    k->w = NULL;
    k->half = NULL;
    k->radius = sigma > 0.0 ? (int)ceil(4.0 * sigma) : 0;
    if (k->radius < 1 && sigma > 0.0) k->radius = 1;
    k->w = malloc(sizeof(double) * (size_t)(2 * k->radius + 1));
    k->half = malloc(sizeof(float) * (size_t)(k->radius + 1));
    if (!k->w || !k->half) {
        internal_cn_kernel_free(k);
        return 0;
    }
    if (k->radius == 0) {
        k->w[0] = 1.0;
        k->half[0] = 1.0f;
        return 1;
    }
    double sum = 0.0;
    for (int i = -k->radius; i <= k->radius; i++) {
        double v = exp(-(double)i * i / (2.0 * sigma * sigma));
        k->w[i + k->radius] = v;
        sum += v;
    }
    for (int i = 0; i <= 2 * k->radius; i++)
        k->w[i] /= sum;
    for (int i = 0; i <= k->radius; i++)
        k->half[i] = (float)k->w[k->radius + i];
    return 1;
}

void internal_cn_kernel_free(internal_kernel *k)
{
    free(k->half);
    k->half = NULL;
    free(k->w);
    k->w = NULL;
}

/* Full convolution a*b (radius ra+rb). */
static int internal_kernel_conv(const internal_kernel *a, const internal_kernel *b,
                                internal_kernel *out)
{
    out->radius = a->radius + b->radius;
    out->half = NULL; /* a variance's kernel, never folded */
    out->w = calloc((size_t)(2 * out->radius + 1), sizeof(double));
    if (!out->w) return 0;
    for (int i = -a->radius; i <= a->radius; i++)
        for (int j = -b->radius; j <= b->radius; j++)
            out->w[i + j + out->radius] += a->w[i + a->radius] * b->w[j + b->radius];
    return 1;
}

/* Sum over taps of a_i * b_i, both centred. */
static double internal_kernel_dot(const internal_kernel *a, const internal_kernel *b)
{
    int r = a->radius < b->radius ? a->radius : b->radius;
    double s = 0.0;
    for (int i = -r; i <= r; i++)
        s += a->w[i + a->radius] * b->w[i + b->radius];
    return s;
}

/* Variance of (a(x)a(y) - b(x)b(y)) * white (b absent: a(x)a(y) * white): the sum of squares of
 * the 2D kernel, which factors because each term is separable. */
static double internal_bandpass_variance(const internal_kernel *a, const internal_kernel *b)
{
    double aa = internal_kernel_dot(a, a);
    if (!b) return aa * aa;
    double bb = internal_kernel_dot(b, b), ab = internal_kernel_dot(a, b);
    return aa * aa - 2.0 * ab * ab + bb * bb;
}

/* The kernels of the innovation: lo = G(sigma_lo) (delta when 0); hi = G(sigma_hi) or none. */
static int internal_noise_kernels(const nprfx_cn_params *p, internal_kernel *lo,
                                  internal_kernel *hi, int *has_hi)
{
    int bandpass = p->noise == NPRFX_CN_NOISE_BANDPASS;
    *has_hi = bandpass && p->sigma_hi > 0.0;
    if (!internal_cn_kernel_make(lo, bandpass ? p->sigma_lo : 0.0)) return 0;
    if (*has_hi && !internal_cn_kernel_make(hi, p->sigma_hi)) {
        internal_cn_kernel_free(lo);
        return 0;
    }
    return 1;
}

double nprfx_cn_smoothed_variance(const nprfx_cn_params *p, double sigma)
{
    if (!(sigma > 0.0)) return 1.0;
    internal_kernel lo, hi, s, slo, shi;
    int has_hi;
    if (!internal_noise_kernels(p, &lo, &hi, &has_hi)) return 1.0;
    double v0 = internal_bandpass_variance(&lo, has_hi ? &hi : NULL), v1 = 1.0;
    if (internal_cn_kernel_make(&s, sigma)) {
        if (internal_kernel_conv(&s, &lo, &slo)) {
            if (has_hi && internal_kernel_conv(&s, &hi, &shi)) {
                v1 = internal_bandpass_variance(&slo, &shi);
                internal_cn_kernel_free(&shi);
            } else if (!has_hi) {
                v1 = internal_bandpass_variance(&slo, NULL);
            }
            internal_cn_kernel_free(&slo);
        }
        internal_cn_kernel_free(&s);
    }
    internal_cn_kernel_free(&lo);
    if (has_hi) internal_cn_kernel_free(&hi);
    return v0 > 0.0 ? v1 / v0 : 1.0;
}

/* ---- noise fields -------------------------------------------------------------------------- */

typedef struct internal_noise_job {
    const nprfx_cn_params *p;
    int64_t frame;
    uint32_t stream;
    nprfx_image *out;
    /* band-pass */
    const internal_kernel *lo, *hi;
    int R;         /* white margin = the larger radius */
    float *tmp_lo; /* rows [y0-R, y1+R) x [x0, x1), per channel */
    float *tmp_hi;
    float *scratch; /* per worker: one white row of width + 2R (+ pad) */
    int scratch_len;
    double gain;
    int channel;
} internal_noise_job;

static void internal_white_rows(void *user, int begin, int end, int worker)
{
    internal_noise_job *j = user;
    nprfx_image *o = j->out;
    const int W = nprfx_rect_width(o->bounds), C = o->channels;
    float *tmp = j->scratch + (size_t)worker * (size_t)j->scratch_len;
    for (int row = begin; row < end; row++) {
        int y = o->bounds.y0 + row;
        float *dst = nprfx_image_at(o, o->bounds.x0, y);
        if (o->pixel_stride == C) {
            internal_cn_noise_row(j->p, j->frame, j->stream, y, o->bounds.x0, W, C, tmp, dst);
            continue;
        }
        for (int c = 0; c < C; c++) {
            uint64_t key = internal_row_key(j->p->seed, j->frame, y, (uint32_t)c, j->stream);
            internal_gauss_row(key, o->bounds.x0, W, tmp);
            for (int x = 0; x < W; x++)
                dst[(ptrdiff_t)x * o->pixel_stride + c] = tmp[x];
        }
    }
}

/* dst[e] = (float)((sum_k w[k] * src[e + k * step]) * gain) for e in [0, n), the sum in double in
 * ascending k (the vector loop keeps that order per element). */
INTERNAL_CLONES
void internal_cn_conv(const double *w, int taps, const float *src, ptrdiff_t step, int n,
                      double gain, float *dst)
{
    int e = 0;
#if INTERNAL_VEC
    for (; e + 8 <= n; e += 8) {
        internal_v8d s = {0, 0, 0, 0, 0, 0, 0, 0};
        for (int k = 0; k < taps; k++) {
            internal_v8f v;
            memcpy(&v, src + (ptrdiff_t)k * step + e, sizeof v);
            s += w[k] * __builtin_convertvector(v, internal_v8d);
        }
        internal_v8f f = __builtin_convertvector(s * gain, internal_v8f);
        memcpy(dst + e, &f, sizeof f);
    }
#endif
    for (; e < n; e++) {
        double s = 0.0;
        for (int k = 0; k < taps; k++)
            s += w[k] * src[(ptrdiff_t)k * step + e];
        dst[e] = (float)(s * gain);
    }
}

/* The band-pass's sums: a symmetric kernel folded, in float, sum_j h[j] * (c[-j*step] + c[j*step])
 * over j = 0..R with the centre once (h[0] * c[0] first), ascending j per element in the vector
 * loop and the scalar tail alike, so that every element is the same sum on every path. The
 * kernels reach 4 sigma (193 taps at sigma 24): folded floats take half the multiplies of the
 * double sums and twice the lanes, and the band-pass field of a large sigma was most of a look's
 * compute. A float sum of up to a few hundred terms of unit-variance noise is within 1e-5 of the
 * double one, far below what the noise's analytic normalisation or a write to half keeps. */
INTERNAL_CLONES
static void internal_fold(const float *h, int R, const float *c, ptrdiff_t step, int n, float *dst)
{
    int e = 0;
#if INTERNAL_VEC
    /* Two 8-lane sums, not one 16-lane: without AVX-512 GCC splits a 16-lane vector through the
     * stack, and the store-to-load stalls made this loop five times slower on AVX2 machines. */
    for (; e + 16 <= n; e += 16) {
        internal_v8f s0, s1, u0, u1, v0, v1;
        memcpy(&u0, c + e, sizeof u0);
        memcpy(&u1, c + e + 8, sizeof u1);
        s0 = h[0] * u0;
        s1 = h[0] * u1;
        for (int j = 1; j <= R; j++) {
            const float *a = c + e - (ptrdiff_t)j * step, *b = c + e + (ptrdiff_t)j * step;
            memcpy(&u0, a, sizeof u0);
            memcpy(&u1, a + 8, sizeof u1);
            memcpy(&v0, b, sizeof v0);
            memcpy(&v1, b + 8, sizeof v1);
            s0 += h[j] * (u0 + v0);
            s1 += h[j] * (u1 + v1);
        }
        memcpy(dst + e, &s0, sizeof s0);
        memcpy(dst + e + 8, &s1, sizeof s1);
    }
#endif
    for (; e < n; e++) {
        float s = h[0] * c[e];
        for (int j = 1; j <= R; j++)
            s += h[j] * (c[e - (ptrdiff_t)j * step] + c[e + (ptrdiff_t)j * step]);
        dst[e] = s;
    }
}

static void internal_bp_hrows(void *user, int begin, int end, int worker)
{
    internal_noise_job *j = user;
    const nprfx_image *o = j->out;
    int W = nprfx_rect_width(o->bounds), R = j->R;
    float *row = j->scratch + (size_t)worker * (size_t)j->scratch_len;
    for (int r = begin; r < end; r++) {
        int y = o->bounds.y0 - R + r;
        uint64_t key = internal_row_key(j->p->seed, j->frame, y, (uint32_t)j->channel, j->stream);
        internal_gauss_row(key, o->bounds.x0 - R, W + 2 * R, row);
        internal_fold(j->lo->half, j->lo->radius, row + R, 1, W, j->tmp_lo + (size_t)r * (size_t)W);
        if (j->tmp_hi)
            internal_fold(j->hi->half, j->hi->radius, row + R, 1, W,
                          j->tmp_hi + (size_t)r * (size_t)W);
    }
}

#define INTERNAL_VSTRIP 128 /* columns a strip of the vertical pass takes */

/* The vertical pass: (lo sum - hi sum) * gain into the output channel, the sums of a strip's
 * row at a time in the worker's scratch. */
static void internal_bp_vrows(void *user, int begin, int end, int worker)
{
    internal_noise_job *j = user;
    nprfx_image *o = j->out;
    const int W = nprfx_rect_width(o->bounds), R = j->R;
    const float gain = (float)j->gain;
    float *lo = j->scratch + (size_t)worker * (size_t)j->scratch_len, *hi = lo + W;
    /* Strips of columns, all the rows of one before the next: a column sum reads 2R + 1 rows,
     * and a strip's rows (193 of 512 bytes at sigma 24) stay in the core's cache between output
     * rows, where whole rows (7.5 KiB each at 1920) went back to memory; twice as fast. */
    for (int x0 = 0; x0 < W; x0 += INTERNAL_VSTRIP) {
        const int n = W - x0 < INTERNAL_VSTRIP ? W - x0 : INTERNAL_VSTRIP;
        for (int r = begin; r < end; r++) {
            float *dst = nprfx_image_at(o, o->bounds.x0 + x0, o->bounds.y0 + r) + j->channel;
            const size_t at = (size_t)(r + R) * (size_t)W + (size_t)x0;
            internal_fold(j->lo->half, j->lo->radius, j->tmp_lo + at, (ptrdiff_t)W, n, lo);
            if (j->tmp_hi)
                internal_fold(j->hi->half, j->hi->radius, j->tmp_hi + at, (ptrdiff_t)W, n, hi);
            for (int x = 0; x < n; x++)
                dst[(ptrdiff_t)x * o->pixel_stride] = (j->tmp_hi ? lo[x] - hi[x] : lo[x]) * gain;
        }
    }
}

nprfx_result nprfx_cn_noise_fill(nprfx_context *ctx, const nprfx_cn_params *p, int64_t frame,
                                 uint32_t stream, nprfx_image *out)
{
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "coherent-noise: no noise buffer");
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    internal_noise_job job;
    memset(&job, 0, sizeof job);
    job.p = p;
    job.frame = frame;
    job.stream = stream;
    job.out = out;
    int H = nprfx_rect_height(out->bounds), W = nprfx_rect_width(out->bounds);
    if (H <= 0 || W <= 0) return NPRFX_OK;
    int workers = nprfx_executor_workers(ex);
    if (workers < 1) workers = 1;
    int bandpass = p->noise == NPRFX_CN_NOISE_BANDPASS && (p->sigma_lo > 0.0 || p->sigma_hi > 0.0);
    if (!bandpass) {
        job.scratch_len = W + INTERNAL_PAD;
        job.scratch = malloc((size_t)workers * (size_t)job.scratch_len * sizeof(float));
        if (!job.scratch)
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY,
                               "coherent-noise: out of memory for a noise row");
        nprfx_parallel_for(ex, H, 8, internal_white_rows, &job);
        free(job.scratch);
        return NPRFX_OK;
    }
    internal_kernel lo, hi;
    int has_hi;
    if (!internal_noise_kernels(p, &lo, &hi, &has_hi))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory (kernels)");
    job.lo = &lo;
    job.hi = has_hi ? &hi : NULL;
    job.R = lo.radius > (has_hi ? hi.radius : 0) ? lo.radius : (has_hi ? hi.radius : 0);
    double var = internal_bandpass_variance(&lo, has_hi ? &hi : NULL);
    job.gain = var > 0.0 ? 1.0 / sqrt(var) : 1.0;
    /* a white row with its margins (horizontal pass), or the two sums of a row (vertical) */
    job.scratch_len = (W + 2 * job.R > 2 * W ? W + 2 * job.R : 2 * W) + INTERNAL_PAD;
    size_t rows = (size_t)H + 2 * (size_t)job.R;
    job.tmp_lo = malloc(rows * (size_t)W * sizeof(float));
    job.tmp_hi = has_hi ? malloc(rows * (size_t)W * sizeof(float)) : NULL;
    job.scratch = malloc((size_t)workers * (size_t)job.scratch_len * sizeof(float));
    nprfx_result r = NPRFX_OK;
    if (!job.tmp_lo || (has_hi && !job.tmp_hi) || !job.scratch) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY,
                        "coherent-noise: out of memory for band-pass noise (%dx%d)", W, H);
    } else {
        for (int c = 0; c < out->channels; c++) {
            job.channel = c;
            nprfx_parallel_for(ex, (int)rows, 8, internal_bp_hrows, &job);
            nprfx_parallel_for(ex, H, 8, internal_bp_vrows, &job);
        }
    }
    free(job.tmp_lo);
    free(job.tmp_hi);
    free(job.scratch);
    internal_cn_kernel_free(&lo);
    if (has_hi) internal_cn_kernel_free(&hi);
    return r;
}
