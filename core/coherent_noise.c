/* Coherent noise (Kass & Pesare 2011): the per-frame recursion, its noise sources and the
 * stationary resampler. See include/nprfx/coherent_noise.h for the maths; the node's caching and
 * render-order logic lives in plugins/coherent_noise.c.
 *
 * Everything here is a pure function of its arguments: row-parallel loops write disjoint rows and
 * every random number is a hash of its counter, so results do not depend on the thread count. */
#include "nprfx/coherent_noise.h"

#include <float.h>
#include <math.h>
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

nprfx_result nprfx_cn_state_copy(nprfx_context *ctx, const nprfx_cn_state *src, nprfx_cn_state *dst)
{
    if (!nprfx_rect_equal(src->value.bounds, dst->value.bounds) ||
        src->value.channels != dst->value.channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH, "coherent-noise: state shape differs");
    /* Both are packed allocations of the same shape. */
    size_t n =
        (size_t)nprfx_rect_width(src->value.bounds) * (size_t)nprfx_rect_height(src->value.bounds);
    memcpy(dst->value.data, src->value.data, n * (size_t)src->value.channels * sizeof(float));
    memcpy(dst->fresh, src->fresh, n);
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

static inline uint64_t internal_row_key(uint64_t seed, int64_t frame, int y, uint32_t ch,
                                        uint32_t stream)
{
    return nprfx_hash(seed, frame, 0, (int32_t)y, ch, stream);
}

static inline float internal_gauss_at(uint64_t row_key, int x)
{
    uint64_t h = nprfx_mix64(row_key ^ ((uint64_t)(uint32_t)x * 0xd1b54a32d192ed03ull));
    uint32_t s = (uint32_t)(h & 0xffffu) + (uint32_t)((h >> 16) & 0xffffu) +
                 (uint32_t)((h >> 32) & 0xffffu) + (uint32_t)(h >> 48);
    return (float)(((double)s - INTERNAL_IH_MEAN) * INTERNAL_IH_SCALE);
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
    float *scratch; /* per worker: one white row of width + 2R */
    int scratch_len;
    double gain;
    int channel;
} internal_noise_job;

static void internal_white_rows(void *user, int begin, int end, int worker)
{
    internal_noise_job *j = user;
    nprfx_image *o = j->out;
    for (int row = begin; row < end; row++) {
        int y = o->bounds.y0 + row;
        for (int c = 0; c < o->channels; c++) {
            uint64_t key = internal_row_key(j->p->seed, j->frame, y, (uint32_t)c, j->stream);
            float *dst = nprfx_image_at(o, o->bounds.x0, y) + c;
            for (int x = o->bounds.x0; x < o->bounds.x1; x++, dst += o->pixel_stride)
                *dst = internal_gauss_at(key, x);
        }
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
        for (int i = 0; i < W + 2 * R; i++)
            row[i] = internal_gauss_at(key, o->bounds.x0 - R + i);
        float *dlo = j->tmp_lo + (size_t)r * (size_t)W;
        float *dhi = j->tmp_hi ? j->tmp_hi + (size_t)r * (size_t)W : NULL;
        int rl = j->lo->radius;
        for (int x = 0; x < W; x++) {
            double s = 0.0;
            const float *src = row + R + x - rl;
            for (int k = 0; k <= 2 * rl; k++)
                s += j->lo->w[k] * src[k];
            dlo[x] = (float)s;
        }
        if (dhi) {
            int rh = j->hi->radius;
            for (int x = 0; x < W; x++) {
                double s = 0.0;
                const float *src = row + R + x - rh;
                for (int k = 0; k <= 2 * rh; k++)
                    s += j->hi->w[k] * src[k];
                dhi[x] = (float)s;
            }
        }
    }
}

static void internal_bp_vrows(void *user, int begin, int end, int worker)
{
    internal_noise_job *j = user;
    nprfx_image *o = j->out;
    int W = nprfx_rect_width(o->bounds), R = j->R;
    int rl = j->lo->radius;
    for (int r = begin; r < end; r++) {
        float *dst = nprfx_image_at(o, o->bounds.x0, o->bounds.y0 + r) + j->channel;
        for (int x = 0; x < W; x++, dst += o->pixel_stride) {
            double s = 0.0;
            const float *src = j->tmp_lo + (size_t)(r + R - rl) * (size_t)W + x;
            for (int k = 0; k <= 2 * rl; k++)
                s += j->lo->w[k] * src[(size_t)k * (size_t)W];
            if (j->tmp_hi) {
                int rh = j->hi->radius;
                const float *sh = j->tmp_hi + (size_t)(r + R - rh) * (size_t)W + x;
                for (int k = 0; k <= 2 * rh; k++)
                    s -= j->hi->w[k] * sh[(size_t)k * (size_t)W];
            }
            *dst = (float)(s * j->gain);
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
    int bandpass = p->noise == NPRFX_CN_NOISE_BANDPASS && (p->sigma_lo > 0.0 || p->sigma_hi > 0.0);
    if (!bandpass) {
        nprfx_parallel_for(ex, H, 8, internal_white_rows, &job);
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
    int workers = nprfx_executor_workers(ex);
    if (workers < 1) workers = 1;
    job.scratch_len = W + 2 * job.R;
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

/* ---- the recursion ------------------------------------------------------------------------- */

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

/* Bilinear depth at (px, py) over the taps that are not background (weights renormalised);
 * returns 0 when every tap is background. */
static int internal_depth_at(const nprfx_image *d, int ix, int iy, float fx, float fy, float *out)
{
    float w[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy, fx * fy};
    float z[4] = {internal_read(d, ix, iy, 0), internal_read(d, ix + 1, iy, 0),
                  internal_read(d, ix, iy + 1, 0), internal_read(d, ix + 1, iy + 1, 0)};
    float sw = 0.0f, sz = 0.0f;
    for (int k = 0; k < 4; k++) {
        if (internal_is_background(z[k]) || w[k] <= 0.0f) continue;
        sw += w[k];
        sz += w[k] * z[k];
    }
    if (!(sw > 0.0f)) return 0;
    *out = sz / sw;
    return 1;
}

typedef struct internal_step_job {
    const nprfx_cn_params *p;
    int direction;
    const nprfx_cn_inputs *in;
    const nprfx_cn_state *prev;
    nprfx_cn_state *out;
    const nprfx_image *w;       /* innovation over the frame (noise) */
    const nprfx_image *n1, *n2; /* compensation fields over frame + margin (noise, stationary) */
    const internal_taps *tab;
    float a, fresh_gain; /* alpha; sqrt(1-alpha^2) for noise, 1-alpha for input */
    int input_mode;
} internal_step_job;

static void internal_step_rows(void *user, int begin, int end, int worker)
{
    const internal_step_job *j = user;
    const nprfx_image *U = &j->prev->value;
    nprfx_image *O = &j->out->value;
    const nprfx_rect fr = O->bounds;
    const int C = O->channels, W = nprfx_rect_width(fr);
    const float ms = (float)j->p->motion_scale, eps = (float)j->p->epsilon;
    const float dir = (float)j->direction;
    const int bilinear = j->p->resample == NPRFX_CN_RESAMPLE_BILINEAR;
    const int compensate = j->n1 != NULL; /* noise with the stationary resampler */
    const float xmax = (float)(fr.x1 - 1), ymax = (float)(fr.y1 - 1);

    for (int y = fr.y0 + begin; y < fr.y0 + end; y++) {
        unsigned char *fresh = j->out->fresh + (size_t)(y - fr.y0) * (size_t)W;
        for (int x = fr.x0; x < fr.x1; x++) {
            float *o = nprfx_image_at(O, x, y);
            float z = internal_read(j->in->depth, x, y, 0);
            float mx = internal_read(j->in->motion, x, y, 0) * ms;
            float my = internal_read(j->in->motion, x, y, 1) * ms;
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
                if (j->in->zvel) {
                    float vz = internal_read(j->in->zvel, x, y, 0);
                    if (isfinite(vz)) zpred = z - dir * vz;
                }
                float zp;
                /* The occlusion test uses the unquantised position: it decides visibility, not
                 * the noise's reconstruction. */
                if (!internal_depth_at(j->in->depth_prev, ix, iy, px - (float)ix, py - (float)iy,
                                       &zp))
                    is_fresh = 1;
                else if (zpred > zp + eps * fabsf(zp))
                    is_fresh = 1;
            }
            fresh[x - fr.x0] = (unsigned char)is_fresh;
            if (is_fresh) {
                if (j->input_mode)
                    for (int c = 0; c < C; c++)
                        o[c] = internal_read(j->in->source, x, y, c);
                else {
                    const float *w = nprfx_image_at(j->w, x, y);
                    for (int c = 0; c < C; c++)
                        o[c] = w[c];
                }
                continue;
            }
            /* A quantised offset of exactly one pixel belongs to the next pixel. */
            if (qx == INTERNAL_TAB) ix++, qx = 0;
            if (qy == INTERNAL_TAB) iy++, qy = 0;
            float v[4] = {0, 0, 0, 0}, comp[4] = {0, 0, 0, 0};
            if (qx == 0 && qy == 0) {
                /* Integer motion: an exact copy, nothing lost, nothing to compensate. */
                const float *u = nprfx_image_at(U, ix, iy);
                for (int c = 0; c < C; c++)
                    v[c] = u[c];
            } else if (bilinear) {
                const float *bx = j->tab[qx].b, *by = j->tab[qy].b;
                int x1 = ix + 1 <= fr.x1 - 1 ? ix + 1 : ix, y1 = iy + 1 <= fr.y1 - 1 ? iy + 1 : iy;
                const float *u00 = nprfx_image_at(U, ix, iy), *u10 = nprfx_image_at(U, x1, iy);
                const float *u01 = nprfx_image_at(U, ix, y1), *u11 = nprfx_image_at(U, x1, y1);
                for (int c = 0; c < C; c++)
                    v[c] = by[0] * (bx[0] * u00[c] + bx[1] * u10[c]) +
                           by[1] * (bx[0] * u01[c] + bx[1] * u11[c]);
            } else {
                const float *bx = j->tab[qx].b, *by = j->tab[qy].b;
                if (ix - 1 >= fr.x0 && ix + 2 < fr.x1 && iy - 1 >= fr.y0 && iy + 2 < fr.y1) {
                    /* interior: all 16 taps inside, plain strides */
                    const float *u0 = nprfx_image_at(U, ix - 1, iy - 1);
                    const ptrdiff_t ps = U->pixel_stride, rs = U->row_stride;
                    for (int c = 0; c < C; c++) {
                        float acc = 0.0f;
                        for (int k = 0; k < 4; k++) {
                            const float *u = u0 + k * rs + c;
                            acc += by[k] * (bx[0] * u[0] + bx[1] * u[ps] + bx[2] * u[2 * ps] +
                                            bx[3] * u[3 * ps]);
                        }
                        v[c] = acc;
                    }
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
                if (compensate) {
                    /* 1 - |Bx By|^2 = Lx + |Bx|^2 Ly: one field through Gx along x, an
                     * independent one through Bx along x and Gy along y. */
                    const float *gx = j->tab[qx].g, *gy = j->tab[qy].g;
                    ptrdiff_t ps1 = j->n1->pixel_stride, ps = j->n2->pixel_stride,
                              rs = j->n2->row_stride;
                    for (int c = 0; c < C; c++) {
                        const float *a0 = nprfx_image_at(j->n1, x, y) + c;
                        float c1 = gx[0] * a0[0] + gx[1] * a0[ps1] + gx[2] * a0[2 * ps1] +
                                   gx[3] * a0[3 * ps1];
                        const float *b0 = nprfx_image_at(j->n2, x, y) + c;
                        float c2 = 0.0f;
                        for (int i = 0; i < 4; i++) {
                            const float *col = b0 + i * ps;
                            c2 += bx[i] * (gy[0] * col[0] + gy[1] * col[rs] + gy[2] * col[2 * rs] +
                                           gy[3] * col[3 * rs]);
                        }
                        comp[c] = c1 + c2;
                    }
                }
            }
            if (j->input_mode) {
                for (int c = 0; c < C; c++)
                    o[c] = j->a * v[c] + j->fresh_gain * internal_read(j->in->source, x, y, c);
            } else {
                const float *w = nprfx_image_at(j->w, x, y);
                for (int c = 0; c < C; c++)
                    o[c] = j->a * (v[c] + comp[c]) + j->fresh_gain * w[c];
            }
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

    nprfx_cn_inputs local = *in;
    if (local.zvel && !local.zvel->data) local.zvel = NULL;

    internal_step_job job;
    memset(&job, 0, sizeof job);
    job.p = p;
    job.direction = direction;
    job.in = &local;
    job.prev = prev;
    job.out = out;
    job.input_mode = input_mode;
    job.a = (float)p->alpha;
    job.fresh_gain = input_mode ? (float)(1.0 - p->alpha) : (float)sqrt(1.0 - p->alpha * p->alpha);

    nprfx_image w = {0}, n1 = {0}, n2 = {0};
    internal_taps *tab = malloc(sizeof(internal_taps) * (INTERNAL_TAB + 1));
    if (!tab) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "coherent-noise: out of memory");
    internal_make_taps(p->resample, tab);
    job.tab = tab;
    if (!input_mode) {
        nprfx_rect ext = nprfx_rect_make(fr.x0, fr.y0, fr.x1 + INTERNAL_COMP_MARGIN,
                                         fr.y1 + INTERNAL_COMP_MARGIN);
        /* Stream 0 is w_i, shared by both passes (Eq. 11 needs the same w); the compensation
         * fields are per pass so the passes stay independent apart from w. */
        uint32_t s1 = direction > 0 ? 1u : 3u, s2 = s1 + 1u;
        if ((r = nprfx_image_alloc(ctx, fr, p->channels, &w)) ||
            (r = nprfx_cn_noise_fill(ctx, p, frame, 0, &w)))
            goto done;
        if (p->alpha > 0.0 && p->resample == NPRFX_CN_RESAMPLE_STATIONARY) {
            if ((r = nprfx_image_alloc(ctx, ext, p->channels, &n1)) ||
                (r = nprfx_cn_noise_fill(ctx, p, frame, s1, &n1)) ||
                (r = nprfx_image_alloc(ctx, ext, p->channels, &n2)) ||
                (r = nprfx_cn_noise_fill(ctx, p, frame, s2, &n2)))
                goto done;
            job.n1 = &n1;
            job.n2 = &n2;
        }
        job.w = &w;
    }
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(fr), 4, internal_step_rows,
                       &job);
done:
    nprfx_image_free(&w);
    nprfx_image_free(&n1);
    nprfx_image_free(&n2);
    free(tab);
    return r;
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
    const int C = p->channels, W = nprfx_rect_width(fr);
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
    nprfx_image w = {0};
    const nprfx_image *s = source;
    if (input_mode) {
        if ((r = internal_check_view(ctx, source, C, "source"))) return r;
    } else {
        if ((r = nprfx_image_alloc(ctx, fr, C, &w)) ||
            (r = nprfx_cn_noise_fill(ctx, p, frame, 0, &w))) {
            nprfx_image_free(&w);
            return r;
        }
        s = &w;
    }
    double a = p->alpha;
    float g_both, g_one, norm;
    if (input_mode) {
        g_both = g_one = (float)(1.0 - a);
        norm = (float)(1.0 / (1.0 + a));
    } else {
        g_one = (float)sqrt(1.0 - a * a);
        g_both = (float)(2.0 - sqrt(1.0 + a * a));
        norm = (float)(1.0 / sqrt(1.0 + a * a));
    }
    for (int y = fr.y0; y < fr.y1; y++) {
        const unsigned char *ff = fwd->fresh + (size_t)(y - fr.y0) * (size_t)W;
        const unsigned char *fb = bwd->fresh + (size_t)(y - fr.y0) * (size_t)W;
        for (int x = fr.x0; x < fr.x1; x++) {
            const float *f = nprfx_image_at(&fwd->value, x, y);
            const float *b = nprfx_image_at(&bwd->value, x, y);
            float *o = nprfx_image_at(out, x, y);
            float g = ff[x - fr.x0] && fb[x - fr.x0] ? g_both : g_one;
            for (int c = 0; c < C; c++)
                o[c] = (f[c] + b[c] - g * internal_read(s, x, y, c)) * norm;
        }
    }
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

static void internal_blur_rows(void *user, int begin, int end, int worker)
{
    const internal_blur_job *j = user;
    const nprfx_rect b = j->dst->bounds;
    const int C = j->dst->channels, R = j->k->radius;
    for (int y = b.y0 + begin; y < b.y0 + end; y++)
        for (int x = b.x0; x < b.x1; x++) {
            float *o = nprfx_image_at(j->dst, x, y);
            for (int c = 0; c < C; c++) {
                double s = 0.0;
                for (int i = -R; i <= R; i++)
                    s += j->k->w[i + R] * (j->vertical ? internal_read(j->src, x, y + i, c)
                                                       : internal_read(j->src, x + i, y, c));
                o[c] = (float)(s * j->gain);
            }
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
