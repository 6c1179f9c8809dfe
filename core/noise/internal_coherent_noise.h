/* Internal to coherent noise (core/noise/coherent_noise.c, cn_*.c), never installed: the build's
 * vector and clone switches, the noise hash, the kernels and tap tables the files share, and the
 * step's per-pixel kernels (the occlusion test, the vector resampler), which are static inline so
 * that the step's row loops inline them. coherent_noise.h has the maths.
 *
 * GCC/Clang vector extensions express the vector code (INTERNAL_VEC); on x86-64 Linux with GCC the
 * hot functions (INTERNAL_CLONES) are also cloned for AVX2 and AVX-512 and picked at load time.
 * Vector and scalar paths do the same IEEE operations in the same order (the project builds with
 * -ffp-contract=off), so every path, CPU and thread count gives the same numbers. */
#ifndef NPRFX_INTERNAL_COHERENT_NOISE_H
#define NPRFX_INTERNAL_COHERENT_NOISE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "nprfx/coherent_noise.h"
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

/* The build's vector switches (internal_simd.h, shared with the other nodes' vector code):
 * NPRFX_SCALAR, or NPRFX_CN_SCALAR, builds the scalar path only (it computes the same numbers). */
#if defined(NPRFX_CN_SCALAR) && !defined(NPRFX_SCALAR)
#define NPRFX_SCALAR
#endif
#include "base/internal_simd.h"
#define INTERNAL_VEC INTERNAL_SIMD
#define INTERNAL_CLONES INTERNAL_SIMD_CLONES

#if INTERNAL_VEC
#define INTERNAL_VINLINE INTERNAL_SIMD_INLINE
typedef float internal_v2f __attribute__((vector_size(8)));
typedef float internal_v4f __attribute__((vector_size(16)));
typedef float internal_v8f __attribute__((vector_size(32)));
typedef float internal_v16f __attribute__((vector_size(64)));
typedef uint64_t internal_v8u __attribute__((vector_size(64)));
typedef int32_t internal_v8i __attribute__((vector_size(32)));
typedef double internal_v8d __attribute__((vector_size(64)));
typedef unsigned char internal_v8u8 __attribute__((vector_size(8)));
#endif

#if INTERNAL_VEC
#define INTERNAL_INLINE static inline __attribute__((always_inline))
#else
#define INTERNAL_INLINE static inline
#endif

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

/* Input mode's one step with source sample s: alpha * carried + (1 - alpha) * s. A NaN or
 * infinite s is a missing sample (docs/design.md §2.2): the carried value goes on alone, since
 * the filter's weights sum to 1, rather than a NaN that the next frames would resample into
 * their neighbours along the motion. */
static inline float internal_mix_source(float a, float carried, float g, float s)
{
    return isfinite(s) ? a * carried + g * s : carried;
}

/* Input mode's value at a (re)start: the source, or 0 where it is missing (nothing to carry). */
static inline float internal_source_fresh(float s)
{
    return isfinite(s) ? s : 0.0f;
}

static inline int internal_is_background(float z)
{
    return !(fabsf(z) < (float)NPRFX_CN_BACKGROUND_DEPTH);
}

static inline int internal_is_bandpass(const nprfx_cn_params *p)
{
    return p->noise == NPRFX_CN_NOISE_BANDPASS && (p->sigma_lo > 0.0 || p->sigma_hi > 0.0);
}

typedef struct internal_kernel {
    int radius;  /* taps -radius..radius */
    double *w;   /* 2*radius+1 weights, sum 1 */
    float *half; /* w[radius..2*radius] as floats: the symmetric kernel folded (band-pass) */
} internal_kernel;

typedef struct internal_taps {
    float b[4]; /* interpolation weights (bilinear: b[0], b[1] at offsets 0, 1; cubic: -1..2) */
    float g[4]; /* compensation filter, taps at offsets 0..3 (bilinear: 0..1) */
} internal_taps;

/* coherent_noise.c: 0 when the view is there with at least `channels` channels and not empty,
 * else the error, naming the input. */
nprfx_result internal_cn_check_view(nprfx_context *ctx, const nprfx_image *im, int channels,
                                    const char *name);

/* cn_noise.c: the noise rows, the 1D Gaussian kernels and the convolution they share. */
/* Channels 0..C-1 (C <= 4, keys[c] the row keys) of pixels x0..x0+n-1, interleaved:
 * dst[i*C + c] = internal_gauss_at(keys[c], x0 + i). */
void internal_cn_gauss_row_il(const uint64_t *keys, int C, int x0, int n, float *dst);
/* Channels 0..C-1 of the noise row y over x0..x0+n-1, interleaved: dst[i*C + c]. tmp holds n
 * floats. */
void internal_cn_noise_row(const nprfx_cn_params *p, int64_t frame, uint32_t stream, int y, int x0,
                           int n, int C, float *tmp, float *dst);
/* The normalised Gaussian of sigma (a delta when sigma is 0); 0 when out of memory. */
int internal_cn_kernel_make(internal_kernel *k, double sigma);
void internal_cn_kernel_free(internal_kernel *k);
/* dst[e] = (float)((sum_k w[k] * src[e + k * step]) * gain) for e in [0, n), the sum in double in
 * ascending k. */
void internal_cn_conv(const double *w, int taps, const float *src, ptrdiff_t step, int n,
                      double gain, float *dst);

/* cn_stationary.c: the table of the resampler's taps, INTERNAL_TAB + 1 entries (and slack), made
 * once per process. */
const internal_taps *internal_cn_taps_for(int resample);

/* ---- the step's per-pixel kernels (cn_step.c) ---------------------------------------------- */

/* The occlusion test: 1 when the predicted depth zpred is farther than the previous depth at
 * (ix + fx, iy + fy) times (1 + eps), or when every tap there is background. The previous depth is
 * bilinear over the taps that are not background (weights renormalised). internal_step_row_v does
 * the same operations eight pixels at a time. */
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

#endif
