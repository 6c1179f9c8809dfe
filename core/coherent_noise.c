/* Coherent noise (Kass & Pesare 2011): the per-frame recursion, its noise sources and the
 * stationary resampler. See include/nprfx/coherent_noise.h for the maths; the node's caching and
 * render-order logic lives in core/cn_temporal.c.
 *
 * Everything here is a pure function of its arguments: row-parallel loops write disjoint rows and
 * every random number is a hash of its counter, so results do not depend on the thread count.
 *
 * Speed (the target: a 1080p frame of 3 channels in 30 ms on two cores, where moving the data
 * alone takes about 10 ms): one pass over the pixels per step. The noise fields are generated row
 * by row into per-worker scratch (a ring of four rows for the compensation field that reaches three
 * rows down) instead of as full frames; pixels whose 4x4 taps lie inside the frame take a vector
 * path with no clamping, all channels at once (lanes are (tap column, channel) pairs). Vector and
 * scalar paths perform the same IEEE operations in the same order per channel (no fused
 * multiply-adds: the project builds with -ffp-contract=off), so the result is the same on every
 * path, CPU and thread count. GCC/Clang vector extensions express the vector code; on x86-64 Linux
 * with GCC the hot functions are also cloned for AVX2 and AVX-512 and picked at load time. Other
 * compilers get the scalar path, which computes the same numbers. */
#include "nprfx/coherent_noise.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/rng.h"

/* Fractional offsets are quantised to 1/INTERNAL_TAB pixel so that the interpolation weights and
 * their compensation filter come from one table entry and stay exactly complementary. */
#define INTERNAL_TAB 1024
/* Compensation noise taps reach 3 pixels right/below the target pixel. */
#define INTERNAL_COMP_MARGIN 3
/* Floats of slack after every scratch row and noise buffer: vector loads of 4 taps x C channels
 * may read up to 16 floats from a tap's first channel. */
#define INTERNAL_PAD 16
/* Rows per parallel chunk of a step (the compensation ring costs 3 extra rows per chunk). */
#define INTERNAL_STEP_GRAIN 32

/* NPRFX_CN_SCALAR: build the scalar path only (it computes the same numbers). */
#if !defined(NPRFX_CN_SCALAR) &&                                                                   \
    ((defined(__GNUC__) && __GNUC__ >= 12) || (defined(__clang__) && __clang_major__ >= 13))
#define INTERNAL_VEC 1
#else
#define INTERNAL_VEC 0
#endif

#if INTERNAL_VEC && defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) &&             \
    defined(__linux__) && !defined(NPRFX_NO_CLONES)
#define INTERNAL_CLONES                                                                            \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define INTERNAL_CLONES
#endif

#if INTERNAL_VEC
/* Vector helpers are always inlined: no vector type crosses a call (no ABI question). */
#define INTERNAL_VINLINE static inline __attribute__((always_inline))
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wpsabi"
#elif defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
typedef float internal_v2f __attribute__((vector_size(8)));
typedef float internal_v4f __attribute__((vector_size(16)));
typedef float internal_v8f __attribute__((vector_size(32)));
typedef float internal_v16f __attribute__((vector_size(64)));
typedef uint64_t internal_v8u __attribute__((vector_size(64)));
typedef int32_t internal_v8i __attribute__((vector_size(32)));
typedef double internal_v8d __attribute__((vector_size(64)));
typedef unsigned char internal_v8u8 __attribute__((vector_size(8)));
#endif

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

/* ---- counter-based Gaussian-like noise ----------------------------------------------------- */

/* One 64-bit hash per sample: the row's counter is hashed once with nprfx_hash and each x is
 * folded in through one more SplitMix round. The four 16-bit quarters are summed (Irwin-Hall of
 * four uniforms): mean 0 and variance exactly 1 after scaling, nearly Gaussian, made of integer
 * arithmetic only, so the field is bit-identical on every platform (log/cos of libm are not), and
 * about ten times cheaper than Box-Muller, which matters at three fields per channel per frame. */
#define INTERNAL_IH_MEAN 131070.0
/* 1 / sqrt(4 * (65536^2 - 1) / 12) */
#define INTERNAL_IH_SCALE 2.6429055847179917e-05
#define INTERNAL_X_MUL 0xd1b54a32d192ed03ull

static inline uint64_t internal_row_key(uint64_t seed, int64_t frame, int y, uint32_t ch,
                                        uint32_t stream)
{
    return nprfx_hash(seed, frame, 0, (int32_t)y, ch, stream);
}

static inline float internal_gauss_at(uint64_t row_key, int x)
{
    uint64_t h = nprfx_mix64(row_key ^ ((uint64_t)(uint32_t)x * INTERNAL_X_MUL));
    uint32_t s = (uint32_t)(h & 0xffffu) + (uint32_t)((h >> 16) & 0xffffu) +
                 (uint32_t)((h >> 32) & 0xffffu) + (uint32_t)(h >> 48);
    return (float)(((double)s - INTERNAL_IH_MEAN) * INTERNAL_IH_SCALE);
}

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
static void internal_gauss_row_il(const uint64_t *keys, int C, int x0, int n, float *dst)
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
    internal_gauss_row_il(&key, 1, x0, n, dst);
}

/* Channels 0..C-1 of the noise row y over x0..x0+n-1, interleaved: dst[i*C + c]. tmp holds n
 * floats. */
static void internal_noise_row(const nprfx_cn_params *p, int64_t frame, uint32_t stream, int y,
                               int x0, int n, int C, float *tmp, float *dst)
{
    uint64_t keys[NPRFX_MAX_CHANNELS];
    for (int c = 0; c < C; c++)
        keys[c] = internal_row_key(p->seed, frame, y, (uint32_t)c, stream);
    if (C <= 4) {
        internal_gauss_row_il(keys, C, x0, n, dst);
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

typedef struct internal_kernel {
    int radius; /* taps -radius..radius */
    double *w;  /* 2*radius+1 weights, sum 1 */
} internal_kernel;

static int internal_kernel_make(internal_kernel *k, double sigma)
{
    k->radius = sigma > 0.0 ? (int)ceil(4.0 * sigma) : 0;
    if (k->radius < 1 && sigma > 0.0) k->radius = 1;
    k->w = malloc(sizeof(double) * (size_t)(2 * k->radius + 1));
    if (!k->w) return 0;
    if (k->radius == 0) {
        k->w[0] = 1.0;
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
    return 1;
}

static void internal_kernel_free(internal_kernel *k)
{
    free(k->w);
    k->w = NULL;
}

/* Full convolution a*b (radius ra+rb). */
static int internal_kernel_conv(const internal_kernel *a, const internal_kernel *b,
                                internal_kernel *out)
{
    out->radius = a->radius + b->radius;
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
    if (!internal_kernel_make(lo, bandpass ? p->sigma_lo : 0.0)) return 0;
    if (*has_hi && !internal_kernel_make(hi, p->sigma_hi)) {
        internal_kernel_free(lo);
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
    if (internal_kernel_make(&s, sigma)) {
        if (internal_kernel_conv(&s, &lo, &slo)) {
            if (has_hi && internal_kernel_conv(&s, &hi, &shi)) {
                v1 = internal_bandpass_variance(&slo, &shi);
                internal_kernel_free(&shi);
            } else if (!has_hi) {
                v1 = internal_bandpass_variance(&slo, NULL);
            }
            internal_kernel_free(&slo);
        }
        internal_kernel_free(&s);
    }
    internal_kernel_free(&lo);
    if (has_hi) internal_kernel_free(&hi);
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
            internal_noise_row(j->p, j->frame, j->stream, y, o->bounds.x0, W, C, tmp, dst);
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
static void internal_conv(const double *w, int taps, const float *src, ptrdiff_t step, int n,
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

/* The vertical pass: dst[x * ps] = (float)((sum_k lo_k a[k*rs + x] - sum_k hi_k b[k*rs + x]) *
 * gain), sums in double in ascending k, the low-pass terms first. */
INTERNAL_CLONES
static void internal_conv_col(const double *lo, int nlo, const float *a, const double *hi, int nhi,
                              const float *b, size_t rs, double gain, int n, float *dst,
                              ptrdiff_t ps)
{
    int x = 0;
#if INTERNAL_VEC
    for (; x + 8 <= n; x += 8) {
        internal_v8d s = {0, 0, 0, 0, 0, 0, 0, 0};
        internal_v8f v;
        for (int k = 0; k < nlo; k++) {
            memcpy(&v, a + (size_t)k * rs + (size_t)x, sizeof v);
            s += lo[k] * __builtin_convertvector(v, internal_v8d);
        }
        for (int k = 0; k < nhi; k++) {
            memcpy(&v, b + (size_t)k * rs + (size_t)x, sizeof v);
            s -= hi[k] * __builtin_convertvector(v, internal_v8d);
        }
        internal_v8f f = __builtin_convertvector(s * gain, internal_v8f);
        for (int l = 0; l < 8; l++)
            dst[(ptrdiff_t)(x + l) * ps] = f[l];
    }
#endif
    for (; x < n; x++) {
        double s = 0.0;
        for (int k = 0; k < nlo; k++)
            s += lo[k] * a[(size_t)k * rs + (size_t)x];
        for (int k = 0; k < nhi; k++)
            s -= hi[k] * b[(size_t)k * rs + (size_t)x];
        dst[(ptrdiff_t)x * ps] = (float)(s * gain);
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
        int rl = j->lo->radius;
        internal_conv(j->lo->w, 2 * rl + 1, row + R - rl, 1, W, 1.0,
                      j->tmp_lo + (size_t)r * (size_t)W);
        if (j->tmp_hi) {
            int rh = j->hi->radius;
            internal_conv(j->hi->w, 2 * rh + 1, row + R - rh, 1, W, 1.0,
                          j->tmp_hi + (size_t)r * (size_t)W);
        }
    }
}

static void internal_bp_vrows(void *user, int begin, int end, int worker)
{
    internal_noise_job *j = user;
    nprfx_image *o = j->out;
    int W = nprfx_rect_width(o->bounds), R = j->R;
    int rl = j->lo->radius, rh = j->tmp_hi ? j->hi->radius : 0;
    for (int r = begin; r < end; r++) {
        float *dst = nprfx_image_at(o, o->bounds.x0, o->bounds.y0 + r) + j->channel;
        const float *a = j->tmp_lo + (size_t)(r + R - rl) * (size_t)W;
        const float *b = j->tmp_hi ? j->tmp_hi + (size_t)(r + R - rh) * (size_t)W : NULL;
        internal_conv_col(j->lo->w, 2 * rl + 1, a, b ? j->hi->w : NULL, b ? 2 * rh + 1 : 0, b,
                          (size_t)W, j->gain, W, dst, o->pixel_stride);
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
    job.scratch_len = W + 2 * job.R + INTERNAL_PAD;
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
    internal_kernel_free(&lo);
    if (has_hi) internal_kernel_free(&hi);
    return r;
}

/* ---- resampling tables -------------------------------------------------------------------- */

typedef struct internal_taps {
    float b[4]; /* interpolation weights (bilinear: b[0], b[1] at offsets 0, 1; cubic: -1..2) */
    float g[4]; /* compensation filter, taps at offsets 0..3 (bilinear: 0..1) */
} internal_taps;

static void internal_catmull_rom(double t, double *w)
{
    double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
    w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
    w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
    w[3] = 0.5 * (t3 - t2);
}

typedef struct internal_cplx {
    double re, im;
} internal_cplx;

static internal_cplx internal_csqrt(internal_cplx z)
{
    double m = hypot(z.re, z.im);
    internal_cplx r;
    r.re = sqrt(fmax(0.0, 0.5 * (m + z.re)));
    r.im = sqrt(fmax(0.0, 0.5 * (m - z.re)));
    if (z.im < 0.0) r.im = -r.im;
    return r;
}

/* z with z + 1/z = s and |z| <= 1. */
static internal_cplx internal_root_inside(internal_cplx s)
{
    internal_cplx d = {s.re * s.re - s.im * s.im - 4.0, 2.0 * s.re * s.im};
    d = internal_csqrt(d);
    internal_cplx a = {0.5 * (s.re + d.re), 0.5 * (s.im + d.im)};
    internal_cplx b = {0.5 * (s.re - d.re), 0.5 * (s.im - d.im)};
    return hypot(a.re, a.im) <= hypot(b.re, b.im) ? a : b;
}

/* Spectral factor of the power an interpolation filter b (4 taps) removes from white noise:
 * g with |G(w)|^2 = 1 - |B(w)|^2. Because B(0) = 1 the loss has a double zero at w = 0, so
 * L = (2 - 2cos w) Q(w) with Q of degree 2; Q is factored in closed form (s = z + 1/z turns its
 * quartic into a quadratic) and G = (1 - z) * (the minimum-phase factor of Q), scaled to the
 * exact lost variance. */
static void internal_factor_loss(const double *b, double *g)
{
    double r[4];
    for (int l = 0; l < 4; l++) {
        r[l] = 0.0;
        for (int j = 0; j + l < 4; j++)
            r[l] += b[j] * b[j + l];
    }
    double rho0 = 1.0 - r[0], rho1 = -r[1], rho2 = -r[2], rho3 = -r[3];
    g[0] = g[1] = g[2] = g[3] = 0.0;
    if (rho0 < 1e-14) return;
    double q2 = -rho3, q1 = 2.0 * q2 - rho2, q0 = -q2 + 2.0 * q1 - rho1;
    double p[3];
    if (fabs(q2) < 1e-15) {
        /* Q(z) = q1 (z + 1/z) + q0: one root pair. */
        internal_cplx s = {fabs(q1) > 1e-300 ? -q0 / q1 : 2.0, 0.0};
        internal_cplx z = internal_root_inside(s);
        p[0] = -z.re;
        p[1] = 1.0;
        p[2] = 0.0;
    } else {
        double disc = q1 * q1 - 4.0 * q2 * (q0 - 2.0 * q2);
        internal_cplx s1, s2;
        if (disc >= 0.0) {
            double sq = sqrt(disc);
            s1.re = (-q1 + sq) / (2.0 * q2);
            s2.re = (-q1 - sq) / (2.0 * q2);
            s1.im = s2.im = 0.0;
        } else {
            double sq = sqrt(-disc);
            s1.re = s2.re = -q1 / (2.0 * q2);
            s1.im = sq / (2.0 * q2);
            s2.im = -s1.im;
        }
        internal_cplx z1 = internal_root_inside(s1), z2 = internal_root_inside(s2);
        /* (z - z1)(z - z2), ascending powers; the product is real for conjugate or real roots. */
        p[0] = z1.re * z2.re - z1.im * z2.im;
        p[1] = -(z1.re + z2.re);
        p[2] = 1.0;
    }
    double gg[4] = {p[0], p[1] - p[0], p[2] - p[1], -p[2]};
    double s2 = gg[0] * gg[0] + gg[1] * gg[1] + gg[2] * gg[2] + gg[3] * gg[3];
    double c = s2 > 0.0 ? sqrt(rho0 / s2) : 0.0;
    for (int k = 0; k < 4; k++)
        g[k] = gg[k] * c;
}

static void internal_make_taps(int resample, internal_taps *tab)
{
    for (int i = 0; i <= INTERNAL_TAB; i++) {
        double t = (double)i / INTERNAL_TAB, b[4], g[4];
        if (resample == NPRFX_CN_RESAMPLE_BILINEAR) {
            b[0] = 1.0 - t;
            b[1] = t;
            b[2] = b[3] = 0.0;
            double s = sqrt(t * (1.0 - t));
            g[0] = s;
            g[1] = -s;
            g[2] = g[3] = 0.0;
        } else {
            internal_catmull_rom(t, b);
            internal_factor_loss(b, g);
        }
        for (int k = 0; k < 4; k++) {
            tab[i].b[k] = (float)b[k];
            tab[i].g[k] = (float)g[k];
        }
    }
}

/* The two tables are computed once per process (pthread_once: pure functions of the resampler). */
/* Two spare entries: the vector path loads 64 bytes from an entry's b. */
static internal_taps internal_tab_stationary[INTERNAL_TAB + 3],
    internal_tab_bilinear[INTERNAL_TAB + 3];
static pthread_once_t internal_tab_once = PTHREAD_ONCE_INIT;

static void internal_tabs_init(void)
{
    internal_make_taps(NPRFX_CN_RESAMPLE_STATIONARY, internal_tab_stationary);
    internal_make_taps(NPRFX_CN_RESAMPLE_BILINEAR, internal_tab_bilinear);
}

static const internal_taps *internal_taps_for(int resample)
{
    pthread_once(&internal_tab_once, internal_tabs_init);
    return resample == NPRFX_CN_RESAMPLE_BILINEAR ? internal_tab_bilinear : internal_tab_stationary;
}
/* ---- the recursion ------------------------------------------------------------------------- */

#if INTERNAL_VEC
#define INTERNAL_INLINE static inline __attribute__((always_inline))
#else
#define INTERNAL_INLINE static inline
#endif

static inline int internal_clampi(int v, int lo, int hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

static inline float internal_read(const nprfx_image *im, int x, int y, int c)
{
    x = internal_clampi(x, im->bounds.x0, im->bounds.x1 - 1);
    y = internal_clampi(y, im->bounds.y0, im->bounds.y1 - 1);
    return nprfx_image_at(im, x, y)[c];
}

static inline int internal_is_background(float z)
{
    return !(fabsf(z) < (float)NPRFX_CN_BACKGROUND_DEPTH);
}

/* Pixel (fr.x0, y) of a view when the view holds the whole row fr.x0..fr.x1-1; NULL otherwise
 * (then reads clamp pixel by pixel). */
static inline const float *internal_row_of(const nprfx_image *im, nprfx_rect fr, int y)
{
    if (!im || y < im->bounds.y0 || y >= im->bounds.y1 || im->bounds.x0 > fr.x0 ||
        im->bounds.x1 < fr.x1)
        return NULL;
    return nprfx_image_at(im, fr.x0, y);
}

/* The occlusion test: 1 when the predicted depth zpred is farther than the previous depth at
 * (ix + fx, iy + fy) times (1 + eps), or when every tap there is background. The previous depth is
 * bilinear over the taps that are not background (weights renormalised). internal_front_v does the
 * same operations eight pixels at a time. */
INTERNAL_INLINE void internal_depth_taps(const nprfx_image *d, int ix, int iy, float *z)
{
    if (ix >= d->bounds.x0 && ix + 1 < d->bounds.x1 && iy >= d->bounds.y0 &&
        iy + 1 < d->bounds.y1) {
        const float *p = nprfx_image_at(d, ix, iy);
        z[0] = p[0];
        z[1] = p[d->pixel_stride];
        z[2] = p[d->row_stride];
        z[3] = p[d->row_stride + d->pixel_stride];
    } else {
        z[0] = internal_read(d, ix, iy, 0);
        z[1] = internal_read(d, ix + 1, iy, 0);
        z[2] = internal_read(d, ix, iy + 1, 0);
        z[3] = internal_read(d, ix + 1, iy + 1, 0);
    }
}

static inline int internal_occluded(const nprfx_image *d, int ix, int iy, float fx, float fy,
                                    float zpred, float eps)
{
    float z[4];
    internal_depth_taps(d, ix, iy, z);
    const float w[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy, fx * fy};
    float sw = 0.0f, sz = 0.0f;
    int any = 0;
    for (int k = 0; k < 4; k++) {
        if (internal_is_background(z[k]) || !(w[k] > 0.0f)) continue;
        any = 1;
        sw = sw + w[k];
        sz = sz + w[k] * z[k];
    }
    if (!any) return 1;
    const float zp = sz / sw;
    return zpred > zp + eps * fabsf(zp);
}

/* The stationary resampler with compensation, for one pixel, per channel c (by, gy: the
 * vertical taps of the offset's row fraction; bx, gx: horizontal):
 *   vu_i = by0 U[iy-1][ix-1+i] + by1 U[iy][..] + by2 U[iy+1][..] + by3 U[iy+2][..]  (left to right)
 *   vn_i = gy0 n2[y][x+i] + gy1 n2[y+1][x+i] + gy2 n2[y+2][x+i] + gy3 n2[y+3][x+i]
 *   t_i  = bx_i (vu_i + vn_i) + gx_i n1[y][x+i]
 *   out  = ((t_0 + t_1) + t_2) + t_3) a + w g
 * i.e. a (Bx By U + Bx Gy n2 + Gx n1) + g w: Catmull-Rom of the previous state plus the two
 * compensation fields (1 - |Bx By|^2 = |Gx|^2 + |Bx|^2 |Gy|^2). This scalar version clamps taps
 * to the frame; the vector versions below do the same operations for interior pixels. */
static void internal_px_stationary(const nprfx_image *U, nprfx_rect fr, int ix, int iy,
                                   const internal_taps *tx, const internal_taps *ty,
                                   const float *n1p, const float *const *n2p, const float *wp,
                                   float a, float g, int C, float *o)
{
    int xs[4], ys[4];
    for (int k = 0; k < 4; k++) {
        xs[k] = internal_clampi(ix - 1 + k, fr.x0, fr.x1 - 1);
        ys[k] = internal_clampi(iy - 1 + k, fr.y0, fr.y1 - 1);
    }
    for (int c = 0; c < C; c++) {
        float t[4];
        for (int i = 0; i < 4; i++) {
            float vu = ty->b[0] * nprfx_image_at(U, xs[i], ys[0])[c];
            vu = vu + ty->b[1] * nprfx_image_at(U, xs[i], ys[1])[c];
            vu = vu + ty->b[2] * nprfx_image_at(U, xs[i], ys[2])[c];
            vu = vu + ty->b[3] * nprfx_image_at(U, xs[i], ys[3])[c];
            float vn = ty->g[0] * n2p[0][i * C + c];
            vn = vn + ty->g[1] * n2p[1][i * C + c];
            vn = vn + ty->g[2] * n2p[2][i * C + c];
            vn = vn + ty->g[3] * n2p[3][i * C + c];
            t[i] = tx->b[i] * (vu + vn) + tx->g[i] * n1p[i * C + c];
        }
        float r = t[0] + t[1];
        r = r + t[2];
        r = r + t[3];
        o[c] = r * a + wp[c] * g;
    }
}

#if INTERNAL_VEC
/* Vector versions: one vector holds the 4 tap columns x C channels of a row (lane i*C + c),
 * loaded straight from the packed state (the 4 taps of a row are contiguous). Lanes past 4C (C = 3)
 * read the next floats, which the caller guarantees exist, and are never stored. */
INTERNAL_VINLINE internal_v4f internal_ld4(const float *p)
{
    internal_v4f v;
    memcpy(&v, p, sizeof v);
    return v;
}
INTERNAL_VINLINE internal_v8f internal_ld8(const float *p)
{
    internal_v8f v;
    memcpy(&v, p, sizeof v);
    return v;
}
INTERNAL_VINLINE internal_v16f internal_ld16(const float *p)
{
    internal_v16f v;
    memcpy(&v, p, sizeof v);
    return v;
}
/* A tap entry (b[0..3], g[0..3]) spread over the lanes: b_i (or g_i) in lanes i*C..i*C+C-1. The
 * entry is loaded at the vector's width (the tables have slack after the last entry) so that the
 * spreading is one same-width permutation. */
INTERNAL_VINLINE void internal_spread1(const internal_taps *t, internal_v4f *b, internal_v4f *g)
{
    *b = internal_ld4(t->b);
    *g = internal_ld4(t->g);
}
INTERNAL_VINLINE void internal_spread2(const internal_taps *t, internal_v8f *b, internal_v8f *g)
{
    internal_v8f e = internal_ld8(t->b);
    *b = __builtin_shufflevector(e, e, 0, 0, 1, 1, 2, 2, 3, 3);
    *g = __builtin_shufflevector(e, e, 4, 4, 5, 5, 6, 6, 7, 7);
}
INTERNAL_VINLINE void internal_spread3(const internal_taps *t, internal_v16f *b, internal_v16f *g)
{
    internal_v16f e = internal_ld16(t->b);
    *b = __builtin_shufflevector(e, e, 0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3);
    *g = __builtin_shufflevector(e, e, 4, 4, 4, 5, 5, 5, 6, 6, 6, 7, 7, 7, 7, 7, 7, 7);
}
INTERNAL_VINLINE void internal_spread4(const internal_taps *t, internal_v16f *b, internal_v16f *g)
{
    internal_v16f e = internal_ld16(t->b);
    *b = __builtin_shufflevector(e, e, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3);
    *g = __builtin_shufflevector(e, e, 4, 4, 4, 4, 5, 5, 5, 5, 6, 6, 6, 6, 7, 7, 7, 7);
}
/* Lanes 0..C-1 of a result to memory (the first four lanes, then C floats of them). */
INTERNAL_VINLINE void internal_st1(float *o, const internal_v4f *vp)
{
    o[0] = (*vp)[0];
}
INTERNAL_VINLINE void internal_st2(float *o, const internal_v8f *vp)
{
    const internal_v2f l = __builtin_shufflevector(*vp, *vp, 0, 1);
    memcpy(o, &l, sizeof l);
}
INTERNAL_VINLINE void internal_st3(float *o, const internal_v16f *vp)
{
    const internal_v2f l = __builtin_shufflevector(*vp, *vp, 0, 1);
    memcpy(o, &l, sizeof l);
    o[2] = (*vp)[2];
}
INTERNAL_VINLINE void internal_st4(float *o, const internal_v16f *vp)
{
    const internal_v4f l = __builtin_shufflevector(*vp, *vp, 0, 1, 2, 3);
    memcpy(o, &l, sizeof l);
}
/* Lanes 0..C-1 of the result: ((t_0 + t_1) + t_2) + t_3 over the four column groups. */
INTERNAL_VINLINE internal_v4f internal_reduce1(const internal_v4f *tp)
{
    const internal_v4f t = *tp;
    internal_v4f r = t + __builtin_shufflevector(t, t, 1, 2, 3, 0);
    r = r + __builtin_shufflevector(t, t, 2, 3, 0, 1);
    return r + __builtin_shufflevector(t, t, 3, 0, 1, 2);
}
INTERNAL_VINLINE internal_v8f internal_reduce2(const internal_v8f *tp)
{
    const internal_v8f t = *tp;
    internal_v8f r = t + __builtin_shufflevector(t, t, 2, 3, 4, 5, 6, 7, 0, 1);
    r = r + __builtin_shufflevector(t, t, 4, 5, 6, 7, 0, 1, 2, 3);
    return r + __builtin_shufflevector(t, t, 6, 7, 0, 1, 2, 3, 4, 5);
}
INTERNAL_VINLINE internal_v16f internal_reduce3(const internal_v16f *tp)
{
    const internal_v16f t = *tp;
    internal_v16f r =
        t + __builtin_shufflevector(t, t, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2);
    r = r + __builtin_shufflevector(t, t, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5);
    return r + __builtin_shufflevector(t, t, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7, 8);
}
INTERNAL_VINLINE internal_v16f internal_reduce4(const internal_v16f *tp)
{
    const internal_v16f t = *tp;
    internal_v16f r =
        t + __builtin_shufflevector(t, t, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3);
    r = r + __builtin_shufflevector(t, t, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7);
    return r + __builtin_shufflevector(t, t, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11);
}

#define INTERNAL_DEFINE_PX(NAME, VT, LD, SPREAD, REDUCE, ST)                                       \
    INTERNAL_INLINE void NAME(const float *u, ptrdiff_t rs, const internal_taps *tx,               \
                              const internal_taps *ty, const float *n1p, const float *n2a,         \
                              const float *n2b, const float *n2c, const float *n2d,                \
                              const float *wp, float a, float g, float *o)                         \
    {                                                                                              \
        VT vu = LD(u) * ty->b[0];                                                                  \
        vu = vu + LD(u + rs) * ty->b[1];                                                           \
        vu = vu + LD(u + 2 * rs) * ty->b[2];                                                       \
        vu = vu + LD(u + 3 * rs) * ty->b[3];                                                       \
        VT vn = LD(n2a) * ty->g[0];                                                                \
        vn = vn + LD(n2b) * ty->g[1];                                                              \
        vn = vn + LD(n2c) * ty->g[2];                                                              \
        vn = vn + LD(n2d) * ty->g[3];                                                              \
        VT bx, gx;                                                                                 \
        SPREAD(tx, &bx, &gx);                                                                      \
        const VT t = bx * (vu + vn) + gx * LD(n1p);                                                \
        const VT r = REDUCE(&t) * a + LD(wp) * g;                                                  \
        ST(o, &r);                                                                                 \
    }
INTERNAL_DEFINE_PX(internal_px_v1, internal_v4f, internal_ld4, internal_spread1, internal_reduce1,
                   internal_st1)
INTERNAL_DEFINE_PX(internal_px_v2, internal_v8f, internal_ld8, internal_spread2, internal_reduce2,
                   internal_st2)
INTERNAL_DEFINE_PX(internal_px_v3, internal_v16f, internal_ld16, internal_spread3, internal_reduce3,
                   internal_st3)
INTERNAL_DEFINE_PX(internal_px_v4, internal_v16f, internal_ld16, internal_spread4, internal_reduce4,
                   internal_st4)
#endif

typedef struct internal_step_job {
    const nprfx_cn_params *p;
    int direction;
    int64_t frame;
    const nprfx_cn_inputs *in;
    const nprfx_cn_state *prev;
    nprfx_cn_state *out;
    /* band-pass noise: whole fields (w over the frame, n1/n2 over frame + margin, each with a
     * spare row for vector slack); NULL for white noise, which is made row by row here */
    const nprfx_image *w, *n1, *n2;
    const internal_taps *tab;
    float a, fresh_gain; /* alpha; sqrt(1-alpha^2) for noise, 1-alpha for input */
    int input_mode;
    int compensate; /* noise with the stationary resampler and alpha > 0 */
    int fast;       /* compensate, C <= 4, packed previous state: vector path for interior pixels */
    uint32_t s1, s2; /* streams of the compensation fields */
    float *scratch;  /* per worker: scratch_len floats */
    size_t scratch_len, row_len;
} internal_step_job;

/* Everything after the occlusion test for one pixel that is not fresh: (ix, iy) the integer part
 * of its previous position, (qx, qy) the quantised fraction. wp, n1p, n2p: its noise (NULL where
 * unused). CF as in internal_step_row. */
INTERNAL_INLINE void internal_px_carry(const internal_step_job *j, int x, int y, int ix, int iy,
                                       int qx, int qy, const float *wp, const float *n1p,
                                       const float *const *n2p, const int CF, float *o)
{
    const nprfx_image *U = &j->prev->value;
    const nprfx_rect fr = j->out->value.bounds;
    const int C = CF ? CF : j->out->value.channels;
    const float a = j->a, g = j->fresh_gain;
    /* A quantised offset of exactly one pixel belongs to the next pixel. */
    if (qx == INTERNAL_TAB) ix++, qx = 0;
    if (qy == INTERNAL_TAB) iy++, qy = 0;
    if (qx == 0 && qy == 0) {
        /* Integer motion: an exact copy, nothing lost, nothing to compensate. */
        const float *u = nprfx_image_at(U, ix, iy);
        if (j->input_mode)
            for (int c = 0; c < C; c++)
                o[c] = a * u[c] + g * internal_read(j->in->source, x, y, c);
        else
            for (int c = 0; c < C; c++)
                o[c] = a * (u[c] + 0.0f) + g * wp[c];
        return;
    }
    const internal_taps *tx = &j->tab[qx], *ty = &j->tab[qy];
    if (j->compensate) {
#if INTERNAL_VEC
        if (CF && ix - 1 >= fr.x0 && ix + 2 < fr.x1 && iy - 1 >= fr.y0 &&
            iy + (CF == 3 ? 3 : 2) < fr.y1) {
            const float *u0 = nprfx_image_at(U, ix - 1, iy - 1);
            if (CF == 1)
                internal_px_v1(u0, U->row_stride, tx, ty, n1p, n2p[0], n2p[1], n2p[2], n2p[3], wp,
                               a, g, o);
            else if (CF == 2)
                internal_px_v2(u0, U->row_stride, tx, ty, n1p, n2p[0], n2p[1], n2p[2], n2p[3], wp,
                               a, g, o);
            else if (CF == 3)
                internal_px_v3(u0, U->row_stride, tx, ty, n1p, n2p[0], n2p[1], n2p[2], n2p[3], wp,
                               a, g, o);
            else
                internal_px_v4(u0, U->row_stride, tx, ty, n1p, n2p[0], n2p[1], n2p[2], n2p[3], wp,
                               a, g, o);
            return;
        }
#endif
        internal_px_stationary(U, fr, ix, iy, tx, ty, n1p, n2p, wp, a, g, C, o);
        return;
    }
    /* No compensation: the paper's bilinear lookup, or Catmull-Rom alone (input mode,
     * alpha 0). */
    float v[NPRFX_MAX_CHANNELS];
    const float *bx = tx->b, *by = ty->b;
    if (j->p->resample == NPRFX_CN_RESAMPLE_BILINEAR) {
        int x1 = ix + 1 <= fr.x1 - 1 ? ix + 1 : ix, y1 = iy + 1 <= fr.y1 - 1 ? iy + 1 : iy;
        const float *u00 = nprfx_image_at(U, ix, iy), *u10 = nprfx_image_at(U, x1, iy);
        const float *u01 = nprfx_image_at(U, ix, y1), *u11 = nprfx_image_at(U, x1, y1);
        for (int c = 0; c < C; c++)
            v[c] = by[0] * (bx[0] * u00[c] + bx[1] * u10[c]) +
                   by[1] * (bx[0] * u01[c] + bx[1] * u11[c]);
    } else {
        int xs[4], ys[4];
        for (int k = 0; k < 4; k++) {
            xs[k] = internal_clampi(ix - 1 + k, fr.x0, fr.x1 - 1);
            ys[k] = internal_clampi(iy - 1 + k, fr.y0, fr.y1 - 1);
        }
        for (int c = 0; c < C; c++) {
            float acc = 0.0f;
            for (int k = 0; k < 4; k++)
                acc += by[k] * (bx[0] * nprfx_image_at(U, xs[0], ys[k])[c] +
                                bx[1] * nprfx_image_at(U, xs[1], ys[k])[c] +
                                bx[2] * nprfx_image_at(U, xs[2], ys[k])[c] +
                                bx[3] * nprfx_image_at(U, xs[3], ys[k])[c]);
            v[c] = acc;
        }
    }
    if (j->input_mode)
        for (int c = 0; c < C; c++)
            o[c] = a * v[c] + g * internal_read(j->in->source, x, y, c);
    else
        for (int c = 0; c < C; c++)
            o[c] = a * (v[c] + 0.0f) + g * wp[c];
}

/* The fresh (restart) value of a pixel. */
static inline void internal_px_fresh(const internal_step_job *j, int x, int y, const float *wp,
                                     int C, float *o)
{
    if (j->input_mode)
        for (int c = 0; c < C; c++)
            o[c] = internal_read(j->in->source, x, y, c);
    else
        for (int c = 0; c < C; c++)
            o[c] = wp[c];
}

/* One row of a step, pixel by pixel. wr, n1r and n2r[k] point at x = fr.x0 of the noise rows y
 * (w, n1) and y + k (n2), channels interleaved (unused ones NULL). */
static void internal_step_row(const internal_step_job *j, int y, const float *wr, const float *n1r,
                              const float *const *n2r)
{
    const nprfx_image *O = &j->out->value;
    const nprfx_rect fr = O->bounds;
    const int C = O->channels, W = nprfx_rect_width(fr);
    const nprfx_cn_inputs *in = j->in;
    const float ms = (float)j->p->motion_scale, eps = (float)j->p->epsilon;
    const float dir = (float)j->direction;
    const float xmax = (float)(fr.x1 - 1), ymax = (float)(fr.y1 - 1);
    unsigned char *fresh = j->out->fresh + (size_t)(y - fr.y0) * (size_t)W;
    for (int x = fr.x0; x < fr.x1; x++) {
        const int i = x - fr.x0;
        float *o = nprfx_image_at(O, x, y);
        float z = internal_read(in->depth, x, y, 0);
        float mx = internal_read(in->motion, x, y, 0) * ms;
        float my = internal_read(in->motion, x, y, 1) * ms;
        float px = (float)x + mx, py = (float)y + my;
        int is_fresh = internal_is_background(z) || !isfinite(mx) || !isfinite(my) ||
                       !(px >= (float)fr.x0 && px <= xmax && py >= (float)fr.y0 && py <= ymax);
        int ix = 0, iy = 0, qx = 0, qy = 0;
        if (!is_fresh) {
            /* floor without a libm call (px, py are finite here) */
            ix = (int)px;
            ix -= (float)ix > px;
            iy = (int)py;
            iy -= (float)iy > py;
            qx = (int)((px - (float)ix) * INTERNAL_TAB + 0.5f);
            qy = (int)((py - (float)iy) * INTERNAL_TAB + 0.5f);
            float zpred = z;
            if (in->zvel) {
                float vz = internal_read(in->zvel, x, y, 0);
                if (isfinite(vz)) zpred = z - dir * vz;
            }
            /* The occlusion test uses the unquantised position: it decides visibility, not
             * the noise's reconstruction. */
            is_fresh = internal_occluded(in->depth_prev, ix, iy, px - (float)ix, py - (float)iy,
                                         zpred, eps);
        }
        fresh[i] = (unsigned char)is_fresh;
        const size_t off = (size_t)i * (size_t)C;
        const float *wp = wr ? wr + off : NULL;
        if (is_fresh) {
            internal_px_fresh(j, x, y, wp, C, o);
            continue;
        }
        const float *n1p = n1r ? n1r + off : NULL;
        const float *n2p[4] = {NULL, NULL, NULL, NULL};
        if (n2r[0])
            for (int k = 0; k < 4; k++)
                n2p[k] = n2r[k] + off;
        internal_px_carry(j, x, y, ix, iy, qx, qy, wp, n1p, n2p, 0, o);
    }
}

#if INTERNAL_VEC
#define INTERNAL_SEG 64

/* Compensation noise made on demand, per worker: slot 0 holds n1 of the current row, slots 1-4 the
 * ring of n2 rows (row yy in slot 1 + yy mod 4). done[] marks the 8-pixel blocks made so far. */
typedef struct internal_lazy {
    const internal_step_job *j;
    float *buf[5];
    unsigned char *done[5];
    uint64_t keys[5][4];
    int row[5];
    int nblocks; /* blocks of 8 over the noise row's W + margin pixels */
} internal_lazy;

static void internal_lazy_assign(internal_lazy *lz, int slot, int yy)
{
    const internal_step_job *j = lz->j;
    if (lz->row[slot] == yy) return;
    lz->row[slot] = yy;
    uint32_t stream = slot ? j->s2 : j->s1;
    for (int c = 0; c < j->out->value.channels; c++)
        lz->keys[slot][c] = internal_row_key(j->p->seed, j->frame, yy, (uint32_t)c, stream);
    memset(lz->done[slot], 0, (size_t)lz->nblocks);
}

/* Make blocks b0..b1 (clamped) of a slot's row. */
static void internal_lazy_ensure(internal_lazy *lz, int slot, int b0, int b1)
{
    const int C = lz->j->out->value.channels, x0 = lz->j->out->value.bounds.x0;
    if (b1 >= lz->nblocks) b1 = lz->nblocks - 1;
    unsigned char *done = lz->done[slot];
    for (int b = b0; b <= b1; b++) {
        if (done[b]) continue;
        int e = b;
        while (e + 1 <= b1 && !done[e + 1])
            e++;
        internal_gauss_row_il(lz->keys[slot], C, x0 + 8 * b, 8 * (e - b + 1),
                              lz->buf[slot] + (size_t)8 * (size_t)b * (size_t)C);
        memset(done + b, 1, (size_t)(e - b + 1));
        b = e;
    }
}

/* m ? a : b per lane (m: all ones or zero); |v|. Macros: no vector crosses a call. */
#define INTERNAL_SEL8(m, a, b)                                                                     \
    ((internal_v8f)(((internal_v8i)(a) & (m)) | ((internal_v8i)(b) & ~(m))))
#define INTERNAL_ABS8(v) ((internal_v8f)((internal_v8i)(v)&0x7fffffff))

/* internal_step_row for the vector path (noise, stationary resampler, CF = C <= 4 channels, packed
 * previous state), in segments of INTERNAL_SEG pixels: the motion, the previous position, its
 * quantised fraction and the occlusion test run eight pixels at a time (the same operations as
 * the scalar code, lane by lane: the bilinear previous depth over the non-background taps, its
 * renormalisation and the comparison); only the fetch of the four depth taps is scalar. */
INTERNAL_INLINE void internal_step_row_v(const internal_step_job *j, int y, const float *wr,
                                         const float *n1r, const float *const *n2r,
                                         internal_lazy *lz, const int CF)
{
    const nprfx_image *U = &j->prev->value;
    const nprfx_image *O = &j->out->value;
    const nprfx_rect fr = O->bounds;
    const int W = nprfx_rect_width(fr);
    const nprfx_cn_inputs *in = j->in;
    const nprfx_image *dp = in->depth_prev;
    const float ms = (float)j->p->motion_scale, eps = (float)j->p->epsilon;
    const float dir = (float)j->direction;
    const float x0f = (float)fr.x0, y0f = (float)fr.y0;
    const float xmax = (float)(fr.x1 - 1), ymax = (float)(fr.y1 - 1), yf = (float)y;
    const float bg = (float)NPRFX_CN_BACKGROUND_DEPTH;
    unsigned char *fresh = j->out->fresh + (size_t)(y - fr.y0) * (size_t)W;
    const float *zrow = internal_row_of(in->depth, fr, y);
    const float *mrow = internal_row_of(in->motion, fr, y);
    const float *vrow = internal_row_of(in->zvel, fr, y);
    const int direct = zrow && mrow && in->depth->pixel_stride == 1 &&
                       in->motion->pixel_stride == 2 &&
                       (!in->zvel || (vrow && in->zvel->pixel_stride == 1));
    const internal_v8i iota = {0, 1, 2, 3, 4, 5, 6, 7};
    const internal_v8f yv = {yf, yf, yf, yf, yf, yf, yf, yf};
    const ptrdiff_t urs = U->row_stride;
    const int dpx1 = dp->pixel_stride == 1;
    float *orow = nprfx_image_at(O, fr.x0, y); /* packed: pixel stride CF */

    for (int s = 0; s < W; s += INTERNAL_SEG) {
        const int n = W - s < INTERNAL_SEG ? W - s : INTERNAL_SEG;
        int32_t ixa[INTERNAL_SEG], iya[INTERNAL_SEG], qxa[INTERNAL_SEG], qya[INTERNAL_SEG];
        int32_t ok[INTERNAL_SEG], kd[INTERNAL_SEG];
        float fxa[INTERNAL_SEG], fya[INTERNAL_SEG], zpa[INTERNAL_SEG];
        float t0[INTERNAL_SEG], t1[INTERNAL_SEG], t2[INTERNAL_SEG], t3[INTERNAL_SEG];
        /* positions */
        for (int b = 0; b < n; b += 8) {
            internal_v8f z, mx, my, vz = {0, 0, 0, 0, 0, 0, 0, 0};
            const int i0 = s + b;
            if (direct && i0 + 8 <= W) {
                z = internal_ld8(zrow + i0);
                internal_v16f m = internal_ld16(mrow + 2 * (ptrdiff_t)i0);
                mx = __builtin_shufflevector(m, m, 0, 2, 4, 6, 8, 10, 12, 14);
                my = __builtin_shufflevector(m, m, 1, 3, 5, 7, 9, 11, 13, 15);
                if (in->zvel) vz = internal_ld8(vrow + i0);
            } else {
                for (int l = 0; l < 8; l++) {
                    int x = fr.x0 + i0 + l;
                    if (i0 + l < W) {
                        z[l] = internal_read(in->depth, x, y, 0);
                        mx[l] = internal_read(in->motion, x, y, 0);
                        my[l] = internal_read(in->motion, x, y, 1);
                        vz[l] = in->zvel ? internal_read(in->zvel, x, y, 0) : 0.0f;
                    } else {
                        z[l] = INFINITY; /* past the row: background, never used */
                        mx[l] = my[l] = vz[l] = 0.0f;
                    }
                }
            }
            mx = mx * ms;
            my = my * ms;
            const internal_v8f xf = __builtin_convertvector(iota + (fr.x0 + i0), internal_v8f);
            internal_v8f px = xf + mx, py = yv + my;
            internal_v8i valid = (INTERNAL_ABS8(z) < bg) & (INTERNAL_ABS8(mx) <= FLT_MAX) &
                                 (INTERNAL_ABS8(my) <= FLT_MAX) & (px >= x0f) & (px <= xmax) &
                                 (py >= y0f) & (py <= ymax);
            px = INTERNAL_SEL8(valid, px, xf); /* keep conversions in range */
            py = INTERNAL_SEL8(valid, py, yv);
            internal_v8i ix = __builtin_convertvector(px, internal_v8i);
            ix += __builtin_convertvector(ix, internal_v8f) > px; /* floor: true is -1 */
            internal_v8i iy = __builtin_convertvector(py, internal_v8i);
            iy += __builtin_convertvector(iy, internal_v8f) > py;
            internal_v8f fx = px - __builtin_convertvector(ix, internal_v8f);
            internal_v8f fy = py - __builtin_convertvector(iy, internal_v8f);
            internal_v8i qx = __builtin_convertvector(fx * INTERNAL_TAB + 0.5f, internal_v8i);
            internal_v8i qy = __builtin_convertvector(fy * INTERNAL_TAB + 0.5f, internal_v8i);
            internal_v8f zpred = z;
            if (in->zvel) zpred = INTERNAL_SEL8(INTERNAL_ABS8(vz) <= FLT_MAX, z - dir * vz, z);
            memcpy(ixa + b, &ix, sizeof ix);
            memcpy(iya + b, &iy, sizeof iy);
            memcpy(qxa + b, &qx, sizeof qx);
            memcpy(qya + b, &qy, sizeof qy);
            memcpy(ok + b, &valid, sizeof valid);
            memcpy(fxa + b, &fx, sizeof fx);
            memcpy(fya + b, &fy, sizeof fy);
            memcpy(zpa + b, &zpred, sizeof zpred);
        }
        /* the previous depth's taps: four vector loads where the 8 pixels of a block read
         * consecutive columns of one row (smooth motion), else one by one */
        for (int b = 0; b < n; b += 8) {
            internal_v8i ix, iy, valid;
            memcpy(&ix, ixa + b, sizeof ix);
            memcpy(&iy, iya + b, sizeof iy);
            memcpy(&valid, ok + b, sizeof valid);
            const internal_v8i run = (ix - iota == ix[0]) & (iy == iy[0]) & valid;
            if (dpx1 && ix[0] >= dp->bounds.x0 && ix[0] + 8 < dp->bounds.x1 &&
                iy[0] >= dp->bounds.y0 && iy[0] + 1 < dp->bounds.y1 && run[0] && run[1] && run[2] &&
                run[3] && run[4] && run[5] && run[6] && run[7]) {
                const float *p = nprfx_image_at(dp, ix[0], iy[0]);
                const internal_v8f z0 = internal_ld8(p), z1 = internal_ld8(p + 1);
                const internal_v8f z2 = internal_ld8(p + dp->row_stride);
                const internal_v8f z3 = internal_ld8(p + dp->row_stride + 1);
                memcpy(t0 + b, &z0, sizeof z0);
                memcpy(t1 + b, &z1, sizeof z1);
                memcpy(t2 + b, &z2, sizeof z2);
                memcpy(t3 + b, &z3, sizeof z3);
                continue;
            }
            for (int i = b; i < b + 8; i++) {
                float z[4] = {0.0f, 0.0f, 0.0f, 0.0f};
                if (ok[i]) internal_depth_taps(dp, ixa[i], iya[i], z);
                t0[i] = z[0];
                t1[i] = z[1];
                t2[i] = z[2];
                t3[i] = z[3];
            }
        }
        /* the occlusion test */
        for (int b = 0; b < n; b += 8) {
            const internal_v8f fx = internal_ld8(fxa + b), fy = internal_ld8(fya + b);
            const internal_v8f z0 = internal_ld8(t0 + b), z1 = internal_ld8(t1 + b);
            const internal_v8f z2 = internal_ld8(t2 + b), z3 = internal_ld8(t3 + b);
            const internal_v8f w0 = (1.0f - fx) * (1.0f - fy), w1 = fx * (1.0f - fy);
            const internal_v8f w2 = (1.0f - fx) * fy, w3 = fx * fy;
            const internal_v8i u0 = (INTERNAL_ABS8(z0) < bg) & (w0 > 0.0f);
            const internal_v8i u1 = (INTERNAL_ABS8(z1) < bg) & (w1 > 0.0f);
            const internal_v8i u2 = (INTERNAL_ABS8(z2) < bg) & (w2 > 0.0f);
            const internal_v8i u3 = (INTERNAL_ABS8(z3) < bg) & (w3 > 0.0f);
            internal_v8f sw = {0, 0, 0, 0, 0, 0, 0, 0}, sz = sw;
            sw = INTERNAL_SEL8(u0, sw + w0, sw);
            sz = INTERNAL_SEL8(u0, sz + w0 * z0, sz);
            sw = INTERNAL_SEL8(u1, sw + w1, sw);
            sz = INTERNAL_SEL8(u1, sz + w1 * z1, sz);
            sw = INTERNAL_SEL8(u2, sw + w2, sw);
            sz = INTERNAL_SEL8(u2, sz + w2 * z2, sz);
            sw = INTERNAL_SEL8(u3, sw + w3, sw);
            sz = INTERNAL_SEL8(u3, sz + w3 * z3, sz);
            const internal_v8i any = u0 | u1 | u2 | u3;
            sw = INTERNAL_SEL8(any, sw, sw + 1.0f); /* no 0/0 in unused lanes */
            const internal_v8f zp = sz / sw;
            const internal_v8i occ = ~any | (internal_ld8(zpa + b) > zp + eps * INTERNAL_ABS8(zp));
            internal_v8i valid;
            memcpy(&valid, ok + b, sizeof valid);
            const internal_v8i f = ~valid | occ;
            /* a quantised offset of exactly one pixel belongs to the next pixel */
            internal_v8i ix, iy, qx, qy;
            memcpy(&ix, ixa + b, sizeof ix);
            memcpy(&iy, iya + b, sizeof iy);
            memcpy(&qx, qxa + b, sizeof qx);
            memcpy(&qy, qya + b, sizeof qy);
            const internal_v8i ox = qx == INTERNAL_TAB, oy = qy == INTERNAL_TAB;
            ix -= ox; /* true is -1 */
            iy -= oy;
            qx &= ~ox;
            qy &= ~oy;
            memcpy(ixa + b, &ix, sizeof ix);
            memcpy(iya + b, &iy, sizeof iy);
            memcpy(qxa + b, &qx, sizeof qx);
            memcpy(qya + b, &qy, sizeof qy);
            /* 0 fresh, 1 exact copy (integer motion), 2 interpolated near the frame's edge,
             * 3 interpolated with all 4x4 taps inside (and, C = 3, the vector slack after them) */
            const internal_v8i inner = (ix - 1 >= fr.x0) & (ix + 2 < fr.x1) & (iy - 1 >= fr.y0) &
                                       (iy + (CF == 3 ? 3 : 2) < fr.y1);
            const internal_v8i copy = (qx == 0) & (qy == 0); /* true is -1 */
            const internal_v8i kind = ~f & ((copy & 1) | (~copy & (2 - inner)));
            memcpy(kd + b, &kind, sizeof kind);
            const internal_v8u8 fb = __builtin_convertvector(f & 1, internal_v8u8);
            memcpy(fresh + s + b, &fb, (size_t)(n - b < 8 ? n - b : 8));
        }
        /* compensation noise for the pixels that interpolate */
        if (lz) {
            int lo = n, hi = -1;
            for (int i = 0; i < n; i++)
                if (kd[i] > 1) {
                    lo = i < lo ? i : lo;
                    hi = i;
                }
            if (hi >= 0) {
                const int b0 = (s + lo) >> 3, b1 = (s + hi + INTERNAL_COMP_MARGIN) >> 3;
                for (int k = 0; k < 5; k++)
                    internal_lazy_ensure(lz, k, b0, b1);
            }
        }
        /* the values */
        for (int b = 0; b < n; b += 8) {
            const int m = n - b < 8 ? n - b : 8;
            if (m == 8 && kd[b] == 1 && kd[b + 1] == 1 && kd[b + 2] == 1 && kd[b + 3] == 1 &&
                kd[b + 4] == 1 && kd[b + 5] == 1 && kd[b + 6] == 1 && kd[b + 7] == 1 &&
                ixa[b + 7] == ixa[b] + 7 && iya[b + 7] == iya[b] && iya[b + 1] == iya[b] &&
                iya[b + 2] == iya[b] && iya[b + 3] == iya[b] && iya[b + 4] == iya[b] &&
                iya[b + 5] == iya[b] && iya[b + 6] == iya[b] && ixa[b + 1] == ixa[b] + 1 &&
                ixa[b + 2] == ixa[b] + 2 && ixa[b + 3] == ixa[b] + 3 && ixa[b + 4] == ixa[b] + 4 &&
                ixa[b + 5] == ixa[b] + 5 && ixa[b + 6] == ixa[b] + 6) {
                /* eight exact copies from consecutive pixels: internal_px_carry's copy, 8C floats
                 * at a time (both states are packed) */
                const float *u = nprfx_image_at(U, ixa[b], iya[b]);
                const float *w = wr + (size_t)(s + b) * (size_t)CF;
                float *o = orow + (size_t)(s + b) * (size_t)CF;
                for (int k = 0; k < CF; k++) {
                    internal_v8f r = j->a * (internal_ld8(u + 8 * k) + 0.0f) +
                                     j->fresh_gain * internal_ld8(w + 8 * k);
                    memcpy(o + 8 * k, &r, sizeof r);
                }
                continue;
            }
            for (int i = b; i < b + m; i++) {
                const int xi = fr.x0 + s + i;
                const size_t off = (size_t)(s + i) * (size_t)CF;
                float *o = orow + off;
                if (kd[i] == 3) {
                    const float *u0 = U->data + (ptrdiff_t)(iya[i] - 1 - fr.y0) * urs +
                                      (ptrdiff_t)(ixa[i] - 1 - fr.x0) * CF;
                    const internal_taps *tx = j->tab + qxa[i], *ty = j->tab + qya[i];
                    const float a = j->a, g = j->fresh_gain;
                    if (CF == 1)
                        internal_px_v1(u0, urs, tx, ty, n1r + off, n2r[0] + off, n2r[1] + off,
                                       n2r[2] + off, n2r[3] + off, wr + off, a, g, o);
                    else if (CF == 2)
                        internal_px_v2(u0, urs, tx, ty, n1r + off, n2r[0] + off, n2r[1] + off,
                                       n2r[2] + off, n2r[3] + off, wr + off, a, g, o);
                    else if (CF == 3)
                        internal_px_v3(u0, urs, tx, ty, n1r + off, n2r[0] + off, n2r[1] + off,
                                       n2r[2] + off, n2r[3] + off, wr + off, a, g, o);
                    else
                        internal_px_v4(u0, urs, tx, ty, n1r + off, n2r[0] + off, n2r[1] + off,
                                       n2r[2] + off, n2r[3] + off, wr + off, a, g, o);
                    continue;
                }
                if (kd[i] == 0) {
                    internal_px_fresh(j, xi, y, wr + off, CF, o);
                    continue;
                }
                const float *n2p[4] = {n2r[0] + off, n2r[1] + off, n2r[2] + off, n2r[3] + off};
                internal_px_carry(j, xi, y, ixa[i], iya[i], qxa[i], qya[i], wr + off, n1r + off,
                                  n2p, CF, o);
            }
        }
    }
}
#endif

INTERNAL_CLONES
static void internal_step_rows(void *user, int begin, int end, int worker)
{
    const internal_step_job *j = user;
    const nprfx_rect fr = j->out->value.bounds;
    const int C = j->out->value.channels, W = nprfx_rect_width(fr);
    const int Wn = W + INTERNAL_COMP_MARGIN;
    const size_t L = j->row_len;
    float *base = j->scratch + (size_t)worker * j->scratch_len;
    float *wbuf = base, *n1buf = base + L, *tmp = base + 6 * L;
    float *ring[4] = {base + 2 * L, base + 3 * L, base + 4 * L, base + 5 * L};
    const int made_here = !j->input_mode && !j->w; /* white noise, generated row by row */
    int lazy_noise = 0;
#if INTERNAL_VEC
    /* the vector path makes the compensation noise only where a pixel interpolates */
    internal_lazy lazy, *lz = NULL;
    if (j->fast && made_here && j->compensate) {
        lz = &lazy;
        lazy_noise = 1;
        lazy.j = j;
        lazy.nblocks = (Wn + 7) / 8;
        unsigned char *flags = (unsigned char *)(tmp + Wn + INTERNAL_PAD);
        for (int k = 0; k < 5; k++) {
            lazy.buf[k] = k ? ring[k - 1] : n1buf;
            lazy.done[k] = flags + (size_t)k * (size_t)lazy.nblocks;
            lazy.row[k] = INT32_MIN;
        }
    }
#endif
    for (int r = begin; r < end; r++) {
        const int y = fr.y0 + r;
        const float *wr = NULL, *n1r = NULL, *n2r[4] = {NULL, NULL, NULL, NULL};
        if (!j->input_mode) {
            if (made_here) {
                internal_noise_row(j->p, j->frame, 0, y, fr.x0, W, C, tmp, wbuf);
                wr = wbuf;
            } else {
                wr = nprfx_image_at(j->w, fr.x0, y);
            }
            if (j->compensate) {
                if (made_here) {
#if INTERNAL_VEC
                    if (lz) {
                        internal_lazy_assign(lz, 0, y);
                        for (int k = 0; k < 4; k++)
                            internal_lazy_assign(lz, 1 + (int)((unsigned)(y + k) & 3u), y + k);
                    }
#endif
                    if (!lazy_noise) {
                        internal_noise_row(j->p, j->frame, j->s1, y, fr.x0, Wn, C, tmp, n1buf);
                        /* the ring holds rows y..y+3 of n2 (row yy in slot yy mod 4) */
                        for (int yy = r == begin ? y : y + 3; yy <= y + 3; yy++)
                            internal_noise_row(j->p, j->frame, j->s2, yy, fr.x0, Wn, C, tmp,
                                               ring[(unsigned)yy & 3u]);
                    }
                    n1r = n1buf;
                    for (int k = 0; k < 4; k++)
                        n2r[k] = ring[(unsigned)(y + k) & 3u];
                } else {
                    n1r = nprfx_image_at(j->n1, fr.x0, y);
                    for (int k = 0; k < 4; k++)
                        n2r[k] = nprfx_image_at(j->n2, fr.x0, y + k);
                }
            }
        }
        switch (j->fast ? C : 0) {
#if INTERNAL_VEC
        case 1:
            internal_step_row_v(j, y, wr, n1r, n2r, lz, 1);
            break;
        case 2:
            internal_step_row_v(j, y, wr, n1r, n2r, lz, 2);
            break;
        case 3:
            internal_step_row_v(j, y, wr, n1r, n2r, lz, 3);
            break;
        case 4:
            internal_step_row_v(j, y, wr, n1r, n2r, lz, 4);
            break;
#endif
        default:
            internal_step_row(j, y, wr, n1r, n2r);
        }
    }
}

static nprfx_result internal_check_view(nprfx_context *ctx, const nprfx_image *im, int channels,
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

static int internal_is_bandpass(const nprfx_cn_params *p)
{
    return p->noise == NPRFX_CN_NOISE_BANDPASS && (p->sigma_lo > 0.0 || p->sigma_hi > 0.0);
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
        if ((r = internal_check_view(ctx, source, p->channels, "source"))) return r;
        for (int y = O->bounds.y0; y < O->bounds.y1; y++)
            for (int x = O->bounds.x0; x < O->bounds.x1; x++) {
                float *o = nprfx_image_at(O, x, y);
                for (int c = 0; c < p->channels; c++)
                    o[c] = internal_read(source, x, y, c);
            }
        return NPRFX_OK;
    }
    return nprfx_cn_noise_fill(ctx, p, frame, 0, O);
}

/* A band-pass field over `r` plus one spare row (vector slack), filled for stream s. */
static nprfx_result internal_field(nprfx_context *ctx, const nprfx_cn_params *p, int64_t frame,
                                   uint32_t s, nprfx_rect r, nprfx_image *out)
{
    nprfx_result res =
        nprfx_image_alloc(ctx, nprfx_rect_make(r.x0, r.y0, r.x1, r.y1 + 1), p->channels, out);
    if (res) return res;
    return nprfx_cn_noise_fill(ctx, p, frame, s, out);
}

nprfx_result nprfx_cn_step(nprfx_context *ctx, const nprfx_cn_params *p, int direction,
                           int64_t frame, const nprfx_cn_inputs *in, const nprfx_cn_state *prev,
                           nprfx_cn_state *out)
{
    nprfx_result r = nprfx_cn_params_check(ctx, p);
    if (r) return r;
    if (direction != NPRFX_CN_FORWARD && direction != NPRFX_CN_BACKWARD)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "coherent-noise: bad direction %d",
                           direction);
    if (!in || !prev || !out || prev == out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "coherent-noise: bad step buffers");
    const char *mname = direction > 0 ? "motion_prev" : "motion_next";
    if ((r = internal_check_view(ctx, in->depth, 1, "depth"))) return r;
    if ((r = internal_check_view(ctx, in->motion, 2, mname))) return r;
    if ((r = internal_check_view(ctx, in->depth_prev, 1, "depth (neighbouring frame)"))) return r;
    if (in->zvel && in->zvel->data && (r = internal_check_view(ctx, in->zvel, 1, "zvel"))) return r;
    int input_mode = p->noise == NPRFX_CN_NOISE_INPUT;
    if (input_mode && (r = internal_check_view(ctx, in->source, p->channels, "source"))) return r;
    nprfx_rect fr = out->value.bounds;
    if (!nprfx_rect_equal(fr, prev->value.bounds) || out->value.channels != p->channels ||
        prev->value.channels != p->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "coherent-noise: states differ in size or channel count");
    const int C = p->channels, W = nprfx_rect_width(fr), H = nprfx_rect_height(fr);
    if (W <= 0 || H <= 0) return NPRFX_OK;

    nprfx_cn_inputs local = *in;
    if (local.zvel && !local.zvel->data) local.zvel = NULL;

    internal_step_job job;
    memset(&job, 0, sizeof job);
    job.p = p;
    job.direction = direction;
    job.frame = frame;
    job.in = &local;
    job.prev = prev;
    job.out = out;
    job.input_mode = input_mode;
    job.a = (float)p->alpha;
    job.fresh_gain = input_mode ? (float)(1.0 - p->alpha) : (float)sqrt(1.0 - p->alpha * p->alpha);
    job.tab = internal_taps_for(p->resample);
    job.compensate = !input_mode && p->alpha > 0.0 && p->resample == NPRFX_CN_RESAMPLE_STATIONARY;
    /* Stream 0 is w_i, shared by both passes (Eq. 11 needs the same w); the compensation fields
     * are per pass so the passes stay independent apart from w. */
    job.s1 = direction > 0 ? 1u : 3u;
    job.s2 = job.s1 + 1u;
    const nprfx_image *U = &prev->value;
    const nprfx_image *O = &out->value;
    job.fast = INTERNAL_VEC && job.compensate && C <= 4 && U->pixel_stride == C &&
               U->row_stride == (ptrdiff_t)W * C && O->pixel_stride == C;

    nprfx_image w = {0}, n1 = {0}, n2 = {0};
    if (!input_mode && internal_is_bandpass(p)) {
        /* Band-pass noise is a filtered field: made whole, once per step. */
        nprfx_rect ext = nprfx_rect_make(fr.x0, fr.y0, fr.x1 + INTERNAL_COMP_MARGIN,
                                         fr.y1 + INTERNAL_COMP_MARGIN);
        if ((r = internal_field(ctx, p, frame, 0, fr, &w))) goto done;
        job.w = &w;
        if (job.compensate) {
            if ((r = internal_field(ctx, p, frame, job.s1, ext, &n1)) ||
                (r = internal_field(ctx, p, frame, job.s2, ext, &n2)))
                goto done;
            job.n1 = &n1;
            job.n2 = &n2;
        }
    }
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    int workers = nprfx_executor_workers(ex);
    if (workers < 1) workers = 1;
    /* a noise row: W + margin pixels rounded up to whole blocks of 8 (the lazy path makes
     * blocks), plus vector slack */
    job.row_len = (size_t)((W + INTERNAL_COMP_MARGIN + 7) & ~7) * (size_t)C + INTERNAL_PAD;
    /* w, n1, the n2 ring, a planar row, and the lazy path's block flags */
    job.scratch_len = 6 * job.row_len + (size_t)(W + INTERNAL_COMP_MARGIN) + INTERNAL_PAD +
                      (size_t)(W + INTERNAL_COMP_MARGIN + 7) / 8 * 5 / sizeof(float) + 8;
    job.scratch = malloc((size_t)workers * job.scratch_len * sizeof(float));
    if (!job.scratch) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory");
        goto done;
    }
    nprfx_parallel_for(ex, H, INTERNAL_STEP_GRAIN, internal_step_rows, &job);
done:
    free(job.scratch);
    nprfx_image_free(&w);
    nprfx_image_free(&n1);
    nprfx_image_free(&n2);
    return r;
}

typedef struct internal_combine_job {
    const nprfx_cn_params *p;
    int64_t frame;
    const nprfx_cn_state *fwd, *bwd;
    const nprfx_image *s; /* source (input mode) or a band-pass w; NULL: white w made per row */
    nprfx_image *out;
    float g_both, g_one, norm;
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
        if (!j->s) internal_noise_row(j->p, j->frame, 0, y, fr.x0, W, C, tmp, wbuf);
        const unsigned char *ff = j->fwd->fresh + (size_t)(y - fr.y0) * (size_t)W;
        const unsigned char *fb = j->bwd->fresh + (size_t)(y - fr.y0) * (size_t)W;
        for (int x = fr.x0; x < fr.x1; x++) {
            const float *f = nprfx_image_at(&j->fwd->value, x, y);
            const float *b = nprfx_image_at(&j->bwd->value, x, y);
            float *o = nprfx_image_at(j->out, x, y);
            float g = ff[x - fr.x0] && fb[x - fr.x0] ? j->g_both : j->g_one;
            if (j->s)
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
        if ((r = internal_check_view(ctx, source, C, "source"))) return r;
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
            internal_conv(j->k->w, 2 * R + 1, nprfx_image_at(j->src, b.x0, y - R),
                          j->src->row_stride, W * C, j->gain, nprfx_image_at(j->dst, b.x0, y));
            continue;
        }
        if (packed && !j->vertical && W > 2 * R) {
            for (int x = b.x0; x < b.x0 + R; x++)
                internal_blur_px(j, x, y);
            internal_conv(j->k->w, 2 * R + 1, nprfx_image_at(j->src, b.x0, y), C, (W - 2 * R) * C,
                          j->gain, nprfx_image_at(j->dst, b.x0 + R, y));
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
    if (!internal_kernel_make(&k, sigma))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory (smooth)");
    nprfx_image tmp;
    nprfx_result r = nprfx_image_alloc(ctx, img->bounds, img->channels, &tmp);
    if (r) {
        internal_kernel_free(&k);
        return r;
    }
    double v = p->noise == NPRFX_CN_NOISE_INPUT ? 1.0 : nprfx_cn_smoothed_variance(p, sigma);
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    internal_blur_job h = {&k, img, &tmp, 0, 1.0f};
    nprfx_parallel_for(ex, nprfx_rect_height(img->bounds), 8, internal_blur_rows, &h);
    internal_blur_job vj = {&k, &tmp, img, 1, (float)(v > 0.0 ? 1.0 / sqrt(v) : 1.0)};
    nprfx_parallel_for(ex, nprfx_rect_height(img->bounds), 8, internal_blur_rows, &vj);
    nprfx_image_free(&tmp);
    internal_kernel_free(&k);
    return NPRFX_OK;
}
