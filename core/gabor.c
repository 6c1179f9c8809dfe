/* NPR Gabor noise splatted from point-cloud AOVs (DESIGN.md §3.2; Benard et al. 2010, Lagae et
 * al. 2009). See nprfx/gabor.h for the interface.
 *
 * The render runs in two phases over a region E = window grown by the kernel reach, cut into
 * BLOCK x BLOCK pixel blocks on a grid fixed in frame coordinates:
 *
 * 1. Emission, per block. Each pixel (of the block and of a 1-pixel ring around it) gets its
 *    anchor A, the Jacobian J = dA/d(x,y) from finite differences that stay on its own surface,
 *    the pseudo-inverse J+ that maps anchor offsets to screen offsets, and its wanted point
 *    density. Per surface patch of the block and per level, the block enumerates the
 *    anchor-space cells its pixels' footprints touch (once per block, not once per pixel, so
 *    the cost per pixel stays bounded) and, for each cell's point, finds the pixel that owns
 *    it: the one in whose own linearisation p + J+_p (a - A_p) the point lies nearest the
 *    pixel centre. Each visible point is emitted once, by its owner, with the level weight and
 *    (3D anchors) the slab test evaluated on the surface interpolated at its exact position.
 * 2. Splatting, per output tile. A tile visits the blocks within kernel reach in block raster
 *    order and each block's points in emission order, and adds every kernel to the samples it
 *    covers that pass the object-id and depth tests. Every sample therefore sums the same
 *    kernels in the same order whatever the tile split or thread count, and each kernel's value
 *    at a sample is a function of (kernel, sample) only (its tables start at the kernel's own
 *    bounding box, never at a tile edge): the output is bit-identical for any tiling.
 *
 * Where this departs from the letter of DESIGN.md §3.2, and why:
 *  - the level window: W levels are kept whole, the finer one fades in and the coarser one
 *    fades out, instead of levels 0..L all whole; the cost per pixel then does not grow with
 *    zoom, and the fading-out level carries at most 3 / (4^(W+1) - 1) of the variance;
 *  - ownership by nearest centre rather than "falls in the owner's square": on curved surfaces
 *    neighbouring linearisations disagree and a square rule leaves gaps (lost, popping points)
 *    and overlaps; the nearest-centre rule is a partition;
 *  - the 3D slab has a soft edge, and the slab distance and level weight are read on the
 *    surface interpolated at the point rather than at the owner's centre: both then barely
 *    change when ownership passes between pixels, so points do not flicker;
 *  - one point per cell (K = 1: a jittered grid; the spectrum of the noise does not depend on
 *    the point process, only on the density and the amplitudes);
 *  - the depth test compares with the depth expected on the kernel's plane (its centre's depth
 *    extended along the depth gradient), so kernels are not cut on slanted surfaces.
 *
 * Pixels outside the inputs (a margin the kernels must still come from, or the frame edge) are
 * virtual: they extrapolate the nearest real pixel's anchor and depth along its Jacobian, so
 * kernels keep their density up to the frame edge and slide in smoothly instead of popping.
 *
 * Speed (issue 5's target: a 1080p frame at N0 = 32 in 150 ms on two cores). The work per
 * frame is about 2.2M pixel attributes, 1.3M anchor cells hashed, 0.75M owner searches, 0.24M
 * kernels and 190M kernel-sample evaluations (N0 = 128: 4x the last three). What keeps it fast:
 *  - the inputs are read from the plates once per row of blocks into a worker's strip (planes),
 *    each block's window is copied from it, and emission also writes the window's depth and id
 *    planes the splat tiles read; scratch is allocated once per render and worker, never per
 *    block or tile (no frame-sized copies, few fresh pages);
 *  - a block's pixels live in planes (structure of arrays); interior flags, Jacobians and the
 *    per-pixel attributes are computed 8 pixels at a time, with scalar code only for pixels at
 *    edges or outside the inputs; patch links are vector masks, and a block whose pixels all
 *    link is one patch without a flood fill; patch footprints are vector reductions;
 *  - the owner search's 3 x 3 descent evaluates the 8 neighbours in one vector;
 *  - splatting computes a kernel's row spans and row depths 8 (AVX2: 4) rows at a time, runs
 *    the factor-table recurrences of 4 kernels in the lanes of a vector, and adds rows 8
 *    samples at a time with the depth-test mode a constant.
 * The vector code is GCC/Clang vector extensions compiled for AVX-512 and AVX2 and picked at
 * run time; it performs the scalar code's IEEE operations in the same order, lane by lane (no
 * FMA: -ffp-contract=off), so every path gives bit-identical output (nprfx_gabor_params.simd
 * selects one for the tests). Other CPUs run the scalar emission and 4-lane vector rows.
 * Profile, one thread on a 2-core AMD EPYC (Zen 4, AVX-512), N0 = 32, ms per frame: emission
 * ~150 (inputs 14, pixel attributes 40, patches 6, owner search 35, cell enumeration, level
 * weights, slab tests and kernel setup 55), splatting ~90 (rows 55, spans 15, tables 10, tile
 * setup and output 10). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#define GABOR_SSE 1
#else
#define GABOR_SSE 0
#endif

#include "nprfx/gabor.h"
#include "nprfx/rng.h"

/* Vector code (DESIGN.md §1: output bit-identical whatever the path): GCC/Clang vector
 * extensions. On x86-64 the emission and splatting are compiled again for AVX2 and AVX-512
 * (picked at run time); elsewhere, and on CPUs without AVX2, only the splat rows are vectors (4
 * lanes: 8-lane and double vectors split into more pieces than the registers hold). Every vector
 * path performs the scalar path's IEEE operations in the same order, lane by lane (no fused
 * multiply-adds: the build uses -ffp-contract=off; sqrt, division and conversions are exactly
 * rounded), so every path gives the same numbers; the params' simd field selects a path for the
 * tests. NPRFX_GABOR_SCALAR builds the scalar path only. */
#if !defined(NPRFX_GABOR_SCALAR) &&                                                                \
    ((defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12) ||                               \
     (defined(__clang__) && __clang_major__ >= 13))
#define GABOR_VEC 1
#else
#define GABOR_VEC 0
#endif
#if GABOR_VEC && defined(__GNUC__) && defined(__x86_64__)
#define GABOR_X86 1
#else
#define GABOR_X86 0
#endif

#if GABOR_VEC
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wpsabi"
#elif defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
typedef float gv8f __attribute__((vector_size(32)));
typedef int32_t gv8i __attribute__((vector_size(32)));
typedef double gv8d __attribute__((vector_size(64)));
typedef int64_t gv8l __attribute__((vector_size(64)));
typedef float gv4f __attribute__((vector_size(16)));
typedef int32_t gv4i __attribute__((vector_size(16)));
typedef double gv4d __attribute__((vector_size(32)));
typedef int64_t gv4l __attribute__((vector_size(32)));
typedef double gv2d __attribute__((vector_size(16)));
/* always inlined: no vector type crosses a call, and each target's copy of a vector function
 * gets its own instructions */
#define GV_INLINE static inline __attribute__((always_inline))

GV_INLINE gv8f gv_loadf(const float *p)
{
    gv8f v;
    memcpy(&v, p, sizeof v);
    return v;
}

GV_INLINE gv8i gv_loadi(const int32_t *p)
{
    gv8i v;
    memcpy(&v, p, sizeof v);
    return v;
}

/* Helpers that take vectors are macros (vector arguments are passed by pointer otherwise): no
 * vector type crosses a call, so no ABI question (nor GCC's psabi notes) */
#define gv_storef(p, v)                                                                            \
    __extension__({                                                                                \
        gv8f gv_t_ = (v);                                                                          \
        memcpy((p), &gv_t_, sizeof gv_t_);                                                         \
    })
#define gv_storei(p, v)                                                                            \
    __extension__({                                                                                \
        gv8i gv_t_ = (v);                                                                          \
        memcpy((p), &gv_t_, sizeof gv_t_);                                                         \
    })
#define gv_wide(v) __builtin_convertvector((v), gv8d)

#define gv_narrow(v) __builtin_convertvector((v), gv8f)
#define gv_mask(m) __builtin_convertvector((m), gv8i)

/* m ? a : b for lane masks m (all bits set or clear; m is evaluated twice) */
#define gv_self(m, a, b) ((gv8f)(((gv8i)(a) & (m)) | ((gv8i)(b) & ~(m))))
#define gv_seli(m, a, b) (((a) & (m)) | ((b) & ~(m)))

#define gv_seld(m, a, b) ((gv8d)(((gv8l)(a) & (m)) | ((gv8l)(b) & ~(m))))

#define gv_absf(v) ((gv8f)((gv8i)(v)&0x7fffffff))

#define gv_absd(v) ((gv8d)((gv8l)(v)&0x7fffffffffffffffll))
#define gv_sqrt(v)                                                                                 \
    __extension__({                                                                                \
        gv8d gv_t_ = (v);                                                                          \
        gv_sqrt_(&gv_t_);                                                                          \
    })
#define gv_iceil(v)                                                                                \
    __extension__({                                                                                \
        gv8d gv_t_ = (v);                                                                          \
        gv_iceil_(&gv_t_);                                                                         \
    })
#define gv_ifloor(v)                                                                               \
    __extension__({                                                                                \
        gv8d gv_t_ = (v);                                                                          \
        gv_ifloor_(&gv_t_);                                                                        \
    })

/* (no generic vector sqrt: SSE2's, on register pieces) */
GV_INLINE gv8d gv_sqrt_(const gv8d *px)
{
    gv8d x = *px;
#if GABOR_SSE
    gv2d q0 = (gv2d)_mm_sqrt_pd((__m128d)__builtin_shufflevector(x, x, 0, 1));
    gv2d q1 = (gv2d)_mm_sqrt_pd((__m128d)__builtin_shufflevector(x, x, 2, 3));
    gv2d q2 = (gv2d)_mm_sqrt_pd((__m128d)__builtin_shufflevector(x, x, 4, 5));
    gv2d q3 = (gv2d)_mm_sqrt_pd((__m128d)__builtin_shufflevector(x, x, 6, 7));
    gv4d lo = __builtin_shufflevector(q0, q1, 0, 1, 2, 3);
    gv4d hi = __builtin_shufflevector(q2, q3, 0, 1, 2, 3);
    x = __builtin_shufflevector(lo, hi, 0, 1, 2, 3, 4, 5, 6, 7);
#else
    for (int k = 0; k < 8; k++)
        x[k] = sqrt(x[k]);
#endif
    return x;
}

GV_INLINE gv4d gv_sqrt4_(const gv4d *px)
{
    gv4d x = *px;
#if GABOR_SSE
    gv2d q0 = (gv2d)_mm_sqrt_pd((__m128d)__builtin_shufflevector(x, x, 0, 1));
    gv2d q1 = (gv2d)_mm_sqrt_pd((__m128d)__builtin_shufflevector(x, x, 2, 3));
    x = __builtin_shufflevector(q0, q1, 0, 1, 2, 3);
#else
    for (int k = 0; k < 4; k++)
        x[k] = sqrt(x[k]);
#endif
    return x;
}

GV_INLINE gv4i gv4_maxi(gv4i a, gv4i b)
{
    gv4i m = a < b;
    return (b & m) | (a & ~m);
}

GV_INLINE gv4i gv4_mini(gv4i a, gv4i b)
{
    gv4i m = a > b;
    return (b & m) | (a & ~m);
}

#define gv_sqrt4(v)                                                                                \
    __extension__({                                                                                \
        gv4d gv_t_ = (v);                                                                          \
        gv_sqrt4_(&gv_t_);                                                                         \
    })
#define gv_any(v)                                                                                  \
    __extension__({                                                                                \
        gv8i gv_t_ = (v);                                                                          \
        gv_any_(&gv_t_);                                                                           \
    })

GV_INLINE int gv_any_(const gv8i *pm)
{
    gv8i m = *pm;
    int32_t r = 0;
    for (int k = 0; k < 8; k++)
        r |= m[k];
    return r != 0;
}
#endif /* GABOR_VEC */

/* A function whose scalar and vector variants are instantiated from one body (a constant
 * argument picks the path): always inlined into each variant where vector code is built. */
#if GABOR_VEC
#define GABOR_BODY static inline __attribute__((always_inline))
#else
#define GABOR_BODY static
#endif

#define BLOCK 32 /* emission blocks: the enumeration of anchor cells is shared by 1024 pixels */
#define PW (BLOCK + 2) /* a block's pixel attributes include a 1-pixel ring, for ownership */
#define HALO 3         /* raw data around those: repair (1) + FD (1) + interior (1) */
#define CACHE_W (PW + 2 * HALO)
#define TILE_SAMPLES                                                                               \
    320                      /* splat tiles, in samples: few kernels straddle two (each does its   \
                                tables again), and a tile's buffers stay in cache */
#define VPAD 8               /* floats readable past a row's end (masked vector tails) */
#define MAX_LEVEL 40         /* cells h0 / 2^40: far below float anchor precision */
#define MAX_CELLS 65536      /* per block, id and level: beyond, the footprint is degenerate */
#define BACKGROUND_DEPTH 1e9 /* depth at or above this is background (Blender writes 1e10) */
#define COVERAGE_FULL 0.999  /* an anchor coverage channel below this marks a blended pixel */
#define MIN_STEP_TOLERANCE 0.01 /* a finite difference may always cross a 1% depth step */
#define OWNER_STEPS 8
/* 3D slab: squared weight 1 out to SLAB_IN c from the surface, then s^2 with s falling linearly
 * to 0 at SLAB_OUT c (so a point's amplitude changes linearly as it nears the edge); the
 * integral across the slab stays c: SLAB_IN = 1/2 - SLAB_SOFT/3, SLAB_OUT = SLAB_IN + SLAB_SOFT */
#define SLAB_SOFT 0.1
#define SLAB_IN (0.5 - SLAB_SOFT / 3.0)
#define SLAB_OUT (SLAB_IN + SLAB_SOFT)
/* staggered fade: each point's amplitude ramps over STAGGER of the ramp variable x, its start
 * uniform in [0, 1 - STAGGER]; x(q) is tabulated so that E[w^2] = q */
#define STAGGER 0.25
#define STAGGER_N 256

static const double k_pi = 3.14159265358979323846;
static const double k_cutoff = 0.05; /* kernel envelope at the truncation radius */

/* ---- parameters ----------------------------------------------------------------------------- */

void nprfx_gabor_params_default(nprfx_gabor_params *p)
{
    memset(p, 0, sizeof *p);
    p->size = sizeof *p;
    p->anchor_dims = 3;
    p->frequency = 0.1;
    p->orientation = 0.0;
    p->isotropic = 0;
    p->radius = 16.0;
    p->n0 = 32.0;
    p->seed = 0;
    p->cell = 1.0;
    p->lod_levels = 4;
    p->fade = NPRFX_GABOR_FADE_LEVEL;
    p->depth_test = NPRFX_GABOR_DEPTH_HARD;
    p->depth_tolerance = 0.05;
    p->supersample = 1;
    p->amplitude = NPRFX_GABOR_AMP_UNIFORM;
    p->output = NPRFX_GABOR_OUT_UNIT;
    p->contrast = 0.15;
    p->points = 0;
}

/* A frequency param in cycles per pixel at the host's render scale: the radius is scaled by the
 * host (a PIXELS param), so a frequency per pixel scales inversely. */
double nprfx_gabor_frequency_at_scale(double frequency, double render_scale)
{
    double scale = render_scale > 0.0 ? render_scale : 1.0;
    return frequency / scale;
}

double nprfx_gabor_bandwidth(double radius)
{
    /* exp(-pi a^2 r^2) = 0.05 at the truncation radius */
    return sqrt(-log(k_cutoff) / k_pi) / radius;
}

static double amplitude_power(int law)
{
    return law == NPRFX_GABOR_AMP_UNIFORM ? 1.0 / 3.0 : 1.0;
}

/* |h(f)|^2 of the average of s samples spaced 1/s: the box filter of supersampling. */
static double box_gain2(double f, int s)
{
    double d = s * sin(k_pi * f / s);
    if (fabs(d) < 1e-12) return 1.0;
    double h = sin(k_pi * f) / d;
    return h * h;
}

/* Fraction of the noise's variance left after averaging s x s samples per pixel: the kernel's
 * power spectrum |G(f)|^2 (two Gaussian lobes at +-F0 w0, width a) weighted by the box filter's
 * response, integrated numerically (isotropic: averaged over orientations). */
static double supersample_attenuation(double F, double a, double w0, int iso, int s)
{
    if (s <= 1) return 1.0;
    const int n = 48;
    double sd = a / (2.0 * sqrt(k_pi)); /* std of exp(-2 pi f^2 / a^2) */
    double range = F + 5.0 * sd, step = 2.0 * range / n;
    int nang = iso ? 8 : 1;
    double num = 0.0, den = 0.0;
    for (int k = 0; k < nang; k++) {
        double th = iso ? k_pi * k / nang : w0;
        double f0x = F * cos(th), f0y = -F * sin(th);
        for (int j = 0; j <= n; j++) {
            double fy = -range + j * step;
            double hy = box_gain2(fy, s);
            for (int i = 0; i <= n; i++) {
                double fx = -range + i * step;
                double e1 =
                    exp(-k_pi * ((fx - f0x) * (fx - f0x) + (fy - f0y) * (fy - f0y)) / (a * a));
                double e2 =
                    exp(-k_pi * ((fx + f0x) * (fx + f0x) + (fy + f0y) * (fy + f0y)) / (a * a));
                double g2 = (e1 + e2) * (e1 + e2);
                num += g2 * box_gain2(fx, s) * hy;
                den += g2;
            }
        }
    }
    return den > 0.0 ? num / den : 1.0;
}

/* The variance without its frequency-dependent term: var = k1 * (1 + exp(-2 pi F^2 / a^2)). */
static double variance_k1(const nprfx_gabor_params *p, double a)
{
    double lambda = p->n0 / (k_pi * p->radius * p->radius);
    double trunc = 1.0 - k_cutoff * k_cutoff; /* the disk holds 1 - 0.05^2 of the envelope^2 */
    double att = supersample_attenuation(p->frequency, a, p->orientation * k_pi / 180.0,
                                         p->isotropic, p->supersample);
    return lambda * amplitude_power(p->amplitude) / (4.0 * a * a) * trunc * att;
}

double nprfx_gabor_variance(const nprfx_gabor_params *p, double frequency_scale)
{
    double a = nprfx_gabor_bandwidth(p->radius);
    double F = p->frequency * frequency_scale;
    return variance_k1(p, a) * (1.0 + exp(-2.0 * k_pi * F * F / (a * a)));
}

/* ---- level of detail ------------------------------------------------------------------------
 *
 * Level l has one point per cell of size h0 / 2^l: 4^l points per level-0 cell area. mu is the
 * wanted density in those units. In regime L the levels L-W+1..L are whole (weight 1), level
 * L+1 fades in with squared weight f and level L-W fades out with squared weight 1-f, where
 * S(L) = sum_{l=max(0,L-W)}^{L} 4^l <= mu < S(L+1):
 *   L < W (no level to fade out yet): f = (mu - S(L)) / 4^(L+1)   (DESIGN.md's rule)
 *   L >= W:                            f = (mu - S(L)) / (3 S(L)), since S(L+1) = 4 S(L)
 * In both, sum_l w_l^2 4^l = mu exactly and every weight is continuous in mu, so the variance
 * and spectrum stay constant at every zoom while kernels appear (and, W levels coarser,
 * disappear) gradually. Fading the coarsest level out is what keeps the number of levels, and
 * so the cost per pixel, bounded under unlimited zoom; it carries at most 3 / (4^(W+1) - 1) of
 * the variance (1.2% for W = 3, 0.3% for W = 4). Below one level-0 cell's worth (mu < 1), level
 * 0 alone has squared weight mu (a point standing for less than one, weight sqrt(N)). */

/* S(L) for L = 0..MAX_LEVEL + 1, and 4^l, so the per-pixel rule needs no log or ldexp. */
typedef struct lod_table {
    double S[MAX_LEVEL + 2];
    double p4[MAX_LEVEL + 2];
    int W;
    double x[STAGGER_N + 1]; /* staggered fade: the ramp variable x for q = i / STAGGER_N */
} lod_table;

/* Staggered fade: point k's amplitude is w = clamp((x - u_k (1 - d)) / d, 0, 1) with u_k
 * uniform in [0, 1) and d = STAGGER, so E[w^2] = (G(x) - G(x - 1 + d)) / (1 - d) with
 * G(y) = integral of clamp(v / d, 0, 1)^2 dv up to y. */
static double stagger_g(double y)
{
    const double d = STAGGER;
    if (y <= 0.0) return 0.0;
    if (y <= d) return y * y * y / (3.0 * d * d);
    return d / 3.0 + (y - d);
}

static double stagger_mean(double x)
{
    return (stagger_g(x) - stagger_g(x - 1.0 + STAGGER)) / (1.0 - STAGGER);
}

/* The ramp variable for a wanted mean squared weight q (the table, interpolated). */
static double stagger_x(const double *tab, double q)
{
    double t = q * STAGGER_N;
    int i = (int)t;
    if (i >= STAGGER_N) return 1.0;
    if (i < 0) return 0.0;
    return tab[i] + (t - i) * (tab[i + 1] - tab[i]);
}

static double stagger_w2(double x, double u)
{
    double w = (x - u * (1.0 - STAGGER)) * (1.0 / STAGGER);
    w = w < 0.0 ? 0.0 : (w > 1.0 ? 1.0 : w);
    return w * w;
}

static void lod_table_init(lod_table *t, int W)
{
    t->W = W;
    for (int L = 0; L < MAX_LEVEL + 2; L++) {
        int l0 = L - W > 0 ? L - W : 0;
        t->p4[L] = ldexp(1.0, 2 * L);
        t->S[L] = (ldexp(1.0, 2 * (L + 1)) - ldexp(1.0, 2 * l0)) / 3.0;
    }
    for (int i = 0; i <= STAGGER_N; i++) {
        double q = (double)i / STAGGER_N, lo = 0.0, hi = 1.0;
        for (int it = 0; it < 50; it++) { /* stagger_mean is increasing */
            double mid = 0.5 * (lo + hi);
            if (stagger_mean(mid) < q)
                lo = mid;
            else
                hi = mid;
        }
        t->x[i] = 0.5 * (lo + hi);
    }
}

static void lod_regime(const lod_table *t, double mu, int *L_out, double *f_out)
{
    if (!(mu >= 1.0)) {
        *L_out = -1;
        *f_out = mu > 0.0 ? mu : 0.0;
        return;
    }
    /* 4^L <= S(L) < (4/3) 4^L, so L is floor(log4 mu) or one less */
    int e;
    frexp(mu, &e); /* mu in [2^(e-1), 2^e) */
    int L = (e - 1) / 2;
    if (L > MAX_LEVEL) L = MAX_LEVEL;
    if (L > 0 && mu < t->S[L]) L--;
    double s = t->S[L];
    double f = L < t->W ? (mu - s) / t->p4[L + 1] : (mu - s) / (3.0 * s);
    *L_out = L;
    *f_out = f < 0.0 ? 0.0 : (f > 1.0 ? 1.0 : f);
}

static double lod_w2(int L, double f, int W, int l)
{
    if (L < 0) return l == 0 ? f : 0.0;
    if (l == L + 1) return f;
    if (l > L + 1 || l < 0) return 0.0;
    int l0 = L - W;
    if (l0 >= 0) {
        if (l < l0) return 0.0;
        if (l == l0) return 1.0 - f;
    }
    return 1.0;
}

static void lod_range(int L, double f, int W, int *lo, int *hi)
{
    if (L < 0) {
        *lo = 0;
        *hi = f > 0.0 ? 0 : -1;
        return;
    }
    *lo = L - W >= 0 ? (f < 1.0 ? L - W : L - W + 1) : 0;
    *hi = f > 0.0 ? L + 1 : L;
}

int nprfx_gabor_lod_weights(double mu, int lod_levels, int *first_level, double *w2, int max)
{
    int L, lo, hi;
    double f;
    lod_table t;
    if (lod_levels < 1) lod_levels = 1;
    lod_table_init(&t, lod_levels);
    lod_regime(&t, mu, &L, &f);
    lod_range(L, f, lod_levels, &lo, &hi);
    if (first_level) *first_level = lo;
    int n = 0;
    for (int l = lo; l <= hi && n < max; l++)
        w2[n++] = lod_w2(L, f, lod_levels, l);
    return n;
}

/* ---- inputs --------------------------------------------------------------------------------- */

typedef struct gsrc {
    const nprfx_image *anchor, *depth, *id, *orient, *freq;
    int dims;   /* 2 or 3 */
    int cov_ch; /* coverage channel of the anchor, -1: none */
    nprfx_rect region;
    double step_tol; /* largest relative depth step between neighbours of one surface */
} gsrc;

static int is_surface_depth(double z)
{
    return z > 0.0 && z < BACKGROUND_DEPTH; /* NaN and inf fail */
}

/* ---- per-block pixel attributes ---------------------------------------------------------------
 */

/* A block's raw data: the real pixels it maps to and a halo, CW x CW at most (a fixed row
 * stride; the window may be smaller at the inputs' edges), in planes. Masks are 0 or -1. */
#define CW CACHE_W
#define CN (CW * CW)
#define CNP (CN + 8) /* slack for vector tails */
typedef struct gcache {
    float A[3][CNP], z[CNP], id[CNP];
    int32_t present[CNP];  /* inside the inputs */
    int32_t valid[CNP];    /* a surface */
    int32_t full[CNP];     /* full coverage */
    int32_t interior[CNP]; /* every present 4-neighbour is on the same surface */
    int32_t hasj[CNP];     /* interior, with a Jacobian */
    float J[2][3][CNP];    /* dA/dx, dA/dy */
    float gz[2][CNP];      /* the depth gradient */
} gcache;

/* A block's pixels and the ring around them: PW x PW, row stride PWS (whole vectors; the
 * padding columns never emit), in planes, with a padding row below (vector reads of the lower
 * neighbours). */
#define PWS 40
#define PN (PW * PWS)
#define PNP (PN + PWS + 8)
typedef struct gpixels {
    float A[3][PNP];
    float P[6][PNP];   /* J+ = (J^T J)^-1 J^T: anchor offset -> screen offset (rows x, y) */
    float n[3][PNP];   /* unit normal of the anchor surface (3D) */
    float ext[3][PNP]; /* half extent of the pixel's anchor footprint, per axis */
    float id[PNP], z[PNP], gz[2][PNP];
    float mu[PNP];            /* wanted points per level-0 cell area */
    int32_t emit[PNP];        /* may own points (nonzero) */
    int32_t comp[PNP];        /* surface patch within the block (-1: none) */
    int32_t rx[PNP], ry[PNP]; /* the real pixel whose orientation / frequency inputs it uses */
    int32_t lr[PNP], ld[PNP]; /* vector path: patch_link to the right and lower neighbours */
} gpixels;

typedef struct gconf gconf;
struct gblock;
struct emit_scratch;
typedef int (*emit_fn)(const gconf *G, int bx, int by, struct gblock *b, struct emit_scratch *scr);

struct gconf {
    gsrc S;
    double a, lambda, radius, r2, h0, F0, w0, tol;
    int W, dims, ss, iso, amp, dtest, points, output, stagger;
    double contrast, var_k1;
    uint64_t seed;
    lod_table lod;
    double pa2, rr; /* pi a^2; exp(-2 pi a^2 / s^2), the envelope recurrence's second ratio */
    double lh2;     /* lambda h0^2 */
    float step_tolf;
    /* every kernel has the same wave vector (no isotropy, no orientation or frequency input):
     * it and its per-sample phase rotations are computed once */
    int uniform_wave;
    double kx0, ky0;
    float csx, ssx, csy, ssy;
    emit_fn emit;
};

/* floor / ceil to int for |v| < 2^31 without a libm call (baseline x86-64 has no SSE4.1
 * rounding instruction, and these run per kernel row and per owner-search step). */
static inline int ifloor(double v)
{
    int i = (int)v;
    return i - (v < (double)i);
}

static inline int iceil(double v)
{
    int i = (int)v;
    return i + (v > (double)i);
}

static double dot3(const double *u, const double *v)
{
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

/* The inputs under one row of blocks, packed: the plates are often interleaved multi-channel
 * images (two cache lines per pixel for anchor, depth and id) and the blocks' windows overlap,
 * so each worker copies the rows a row of blocks reads (the region's part of its windows) once,
 * as planes: anchor x, y, z, depth, id, and the valid and full masks. */
enum { ST_A0, ST_A1, ST_A2, ST_Z, ST_ID, ST_VALID, ST_FULL, ST_PLANES };
typedef struct gstrip {
    int x0, y0, w, h; /* the pixels it holds, all inside the region */
    float *data;      /* h rows of ST_PLANES planes of w floats (masks as int32) */
} gstrip;

static float *strip_plane(const gstrip *T, int p, int x, int y)
{
    return T->data + ((size_t)(y - T->y0) * ST_PLANES + (size_t)p) * (size_t)T->w + (x - T->x0);
}

static void strip_fill(const gsrc *S, gstrip *T, int x0, int x1, int y0, int y1)
{
    nprfx_rect reg = S->region;
    T->x0 = x0 > reg.x0 ? x0 : reg.x0;
    T->y0 = y0 > reg.y0 ? y0 : reg.y0;
    T->w = (x1 < reg.x1 ? x1 : reg.x1) - T->x0;
    T->h = (y1 < reg.y1 ? y1 : reg.y1) - T->y0;
    if (T->w <= 0 || T->h <= 0) {
        T->w = T->h = 0;
        return;
    }
    ptrdiff_t sa = S->anchor->pixel_stride, sz = S->depth->pixel_stride;
    ptrdiff_t si = S->id ? S->id->pixel_stride : 0;
    int dims = S->dims, cov = S->cov_ch;
    for (int y = T->y0; y < T->y0 + T->h; y++) {
        const float *a = nprfx_image_at(S->anchor, T->x0, y);
        const float *zp = nprfx_image_at(S->depth, T->x0, y);
        const float *ip = S->id ? nprfx_image_at(S->id, T->x0, y) : NULL;
        float *A0 = strip_plane(T, ST_A0, T->x0, y), *A1 = strip_plane(T, ST_A1, T->x0, y);
        float *A2 = strip_plane(T, ST_A2, T->x0, y), *Z = strip_plane(T, ST_Z, T->x0, y);
        float *ID = strip_plane(T, ST_ID, T->x0, y);
        int32_t *V = (int32_t *)strip_plane(T, ST_VALID, T->x0, y);
        int32_t *F = (int32_t *)strip_plane(T, ST_FULL, T->x0, y);
        for (int i = 0; i < T->w; i++, a += sa, zp += sz) {
            float a0 = a[0], a1 = a[1], a2 = dims == 3 ? a[2] : 0.0f, z = *zp;
            float id = ip ? ip[i * si] + 0.0f : 0.0f;
            A0[i] = a0;
            A1[i] = a1;
            A2[i] = a2;
            Z[i] = z;
            ID[i] = id;
            V[i] = -(is_surface_depth(z) && isfinite(a0) && isfinite(a1) && isfinite(a2) &&
                     isfinite(id));
            F[i] = -(cov < 0 || a[cov] >= COVERAGE_FULL);
        }
    }
}

/* Copy the raw data of the window at (cx0, cy0), cw x ch, from the strip (the rest of the
 * CW x CW planes is outside the inputs). */
static void cache_fill(const gsrc *S, const gstrip *T, gcache *C, int cx0, int cy0, int cw, int ch)
{
    nprfx_rect reg = S->region;
    int ia = reg.x0 - cx0 > 0 ? reg.x0 - cx0 : 0;
    int ib = reg.x1 - cx0 < cw ? reg.x1 - cx0 : cw;
    memset(C->interior, 0, sizeof C->interior);
    memset(C->hasj, 0, sizeof C->hasj);
    if (ia == 0 && ib == CW && ch == CW && cy0 >= reg.y0 && cy0 + CW <= reg.y1) {
        /* the whole window lies in the inputs (most blocks): whole rows, fixed-size copies */
        for (int j = 0; j < CW; j++) {
            int y = cy0 + j, o = j * CW;
            const float *src = strip_plane(T, ST_A0, cx0, y);
            size_t pl = (size_t)T->w; /* the strip's planes follow each other in a row */
            memcpy(C->A[0] + o, src + ST_A0 * pl, sizeof(float) * CW);
            memcpy(C->A[1] + o, src + ST_A1 * pl, sizeof(float) * CW);
            memcpy(C->A[2] + o, src + ST_A2 * pl, sizeof(float) * CW);
            memcpy(C->z + o, src + ST_Z * pl, sizeof(float) * CW);
            memcpy(C->id + o, src + ST_ID * pl, sizeof(float) * CW);
            memcpy(C->valid + o, src + ST_VALID * pl, sizeof(float) * CW);
            memcpy(C->full + o, src + ST_FULL * pl, sizeof(float) * CW);
            for (int i = 0; i < CW; i++)
                C->present[o + i] = -1;
        }
        return;
    }
    memset(C->present, 0, sizeof C->present);
    memset(C->valid, 0, sizeof C->valid);
    memset(C->full, 0, sizeof C->full);
    if (ia >= ib) return;
    size_t nb = sizeof(float) * (size_t)(ib - ia);
    for (int j = 0; j < ch; j++) {
        int y = cy0 + j, o = j * CW + ia;
        if (y < reg.y0 || y >= reg.y1) continue;
        memcpy(C->A[0] + o, strip_plane(T, ST_A0, cx0 + ia, y), nb);
        memcpy(C->A[1] + o, strip_plane(T, ST_A1, cx0 + ia, y), nb);
        memcpy(C->A[2] + o, strip_plane(T, ST_A2, cx0 + ia, y), nb);
        memcpy(C->z + o, strip_plane(T, ST_Z, cx0 + ia, y), nb);
        memcpy(C->id + o, strip_plane(T, ST_ID, cx0 + ia, y), nb);
        memcpy(C->valid + o, strip_plane(T, ST_VALID, cx0 + ia, y), nb);
        memcpy(C->full + o, strip_plane(T, ST_FULL, cx0 + ia, y), nb);
        for (int i = 0; i < ib - ia; i++)
            C->present[o + i] = -1;
    }
}

/* Neighbour d lies on c's surface: same object id and no depth step beyond the tolerance. */
static int same_surface(const gsrc *S, const gcache *C, int c, int d)
{
    if (!C->present[d] || !C->valid[d] || C->id[d] != C->id[c]) return 0;
    double zmin = C->z[c] < C->z[d] ? C->z[c] : C->z[d];
    return fabs((double)C->z[d] - C->z[c]) <= S->step_tol * zmin;
}

/* One axis of the Jacobian of interior pixel c, from its interior neighbours at c +- step.
 * Where both exist but one difference is much larger (a UV seam, a blended anchor), the smaller
 * one-sided difference is used; with neither, the axis is undefined. */
static int axis_diff(const gcache *C, int c, int step, float dA[3], float *dz)
{
    int f = c + step, b = c - step;
    int hf = C->present[f] && C->interior[f] && C->id[f] == C->id[c];
    int hb = C->present[b] && C->interior[b] && C->id[b] == C->id[c];
    float Df[3], Db[3];
    for (int k = 0; k < 3; k++) {
        Df[k] = C->A[k][f] - C->A[k][c];
        Db[k] = C->A[k][c] - C->A[k][b];
    }
    if (hf && hb) {
        float nf = Df[0] * Df[0] + Df[1] * Df[1] + Df[2] * Df[2];
        float nb = Db[0] * Db[0] + Db[1] * Db[1] + Db[2] * Db[2];
        if (nf > 9.0f * nb) /* squared: one difference 3x the other */
            hf = 0;
        else if (nb > 9.0f * nf)
            hb = 0;
    }
    if (hf && hb) {
        for (int k = 0; k < 3; k++)
            dA[k] = 0.5f * (Df[k] + Db[k]);
        *dz = 0.5f * (C->z[f] - C->z[b]);
    } else if (hf) {
        memcpy(dA, Df, sizeof Df);
        *dz = C->z[f] - C->z[c];
    } else if (hb) {
        memcpy(dA, Db, sizeof Db);
        *dz = C->z[c] - C->z[b];
    } else {
        return 0;
    }
    return 1;
}

/* Interior flags on the window less its outer ring, then the Jacobians of the interior pixels
 * (scalar path). */
static void cache_derive_scalar(const gsrc *S, gcache *C, int cw, int ch)
{
    for (int j = 1; j < ch - 1; j++)
        for (int i = 1; i < cw - 1; i++) {
            int c = j * CW + i;
            if (!C->valid[c] || !C->full[c]) continue;
            const int nb[4] = {c - 1, c + 1, c - CW, c + CW};
            int ok = 1;
            for (int k = 0; k < 4 && ok; k++)
                if (C->present[nb[k]] && !same_surface(S, C, c, nb[k])) ok = 0;
            C->interior[c] = -ok;
        }
    for (int j = 1; j < ch - 1; j++)
        for (int i = 1; i < cw - 1; i++) {
            int c = j * CW + i;
            if (!C->interior[c]) continue;
            float jx[3], jy[3], gx, gy;
            if (!axis_diff(C, c, 1, jx, &gx) || !axis_diff(C, c, CW, jy, &gy)) continue;
            for (int m = 0; m < 3; m++) {
                C->J[0][m][c] = jx[m];
                C->J[1][m][c] = jy[m];
            }
            C->gz[0][c] = gx;
            C->gz[1][c] = gy;
            C->hasj[c] = -1;
        }
}

static void finish_pixel(const gconf *G, gpixels *X, int k, const double *jx, const double *jy)
{
    double g11 = dot3(jx, jx), g12 = dot3(jx, jy), g22 = dot3(jy, jy);
    double det = g11 * g22 - g12 * g12; /* = |Jx x Jy|^2 */
    X->emit[k] = 0;
    if (!(det > 0.0) || !isfinite(det)) return;
    double area = sqrt(det), iarea = 1.0 / area, idet = iarea * iarea;
    for (int m = 0; m < 3; m++) {
        X->P[m][k] = (float)((g22 * jx[m] - g12 * jy[m]) * idet);
        X->P[3 + m][k] = (float)((g11 * jy[m] - g12 * jx[m]) * idet);
        X->ext[m][k] = (float)(0.5 * (fabs(jx[m]) + fabs(jy[m])));
    }
    X->n[0][k] = (float)((jx[1] * jy[2] - jx[2] * jy[1]) * iarea);
    X->n[1][k] = (float)((jx[2] * jy[0] - jx[0] * jy[2]) * iarea);
    X->n[2][k] = (float)((jx[0] * jy[1] - jx[1] * jy[0]) * iarea);
    float mu = (float)(G->lh2 * iarea);
    X->mu[k] = mu;
    X->emit[k] = mu > 0.0f && isfinite(mu);
}

/* The attributes of block pixel (x, y) (index k): real pixels use their own anchor where they
 * are interior to their surface; pixels at an edge (renderers filter Pref and UV there, mixing
 * the two surfaces) and virtual pixels outside the inputs extrapolate from an interior
 * neighbour along its Jacobian. */
static void pixel_scalar(const gconf *G, gpixels *X, const gcache *C, int k, int x, int y, int cx0,
                         int cy0)
{
    const gsrc *S = &G->S;
    nprfx_rect reg = S->region;
    int rx = x < reg.x0 ? reg.x0 : (x >= reg.x1 ? reg.x1 - 1 : x);
    int ry = y < reg.y0 ? reg.y0 : (y >= reg.y1 ? reg.y1 - 1 : y);
    int ci = (ry - cy0) * CW + (rx - cx0);
    X->emit[k] = 0;
    if (!C->valid[ci]) return;
    int si = -1, sx = rx, sy = ry;
    if (C->hasj[ci]) {
        si = ci;
    } else {
        static const int dxs[4] = {-1, 1, 0, 0}, dys[4] = {0, 0, -1, 1};
        for (int m = 0; m < 4 && si < 0; m++) {
            int di = ci + dys[m] * CW + dxs[m];
            if (C->present[di] && C->interior[di] && same_surface(S, C, ci, di) && C->hasj[di]) {
                si = di;
                sx = rx + dxs[m];
                sy = ry + dys[m];
            }
        }
    }
    if (si < 0) return;
    double ox = x - sx, oy = y - sy;
    double jx[3], jy[3];
    for (int m = 0; m < 3; m++) {
        jx[m] = C->J[0][m][si];
        jy[m] = C->J[1][m][si];
        X->A[m][k] = (float)(C->A[m][si] + jx[m] * ox + jy[m] * oy);
    }
    /* depth is one sample, never filtered: keep the pixel's own, extrapolate only outside */
    double z = C->z[ci] + (double)C->gz[0][si] * (x - rx) + (double)C->gz[1][si] * (y - ry);
    if (!is_surface_depth(z)) return;
    X->z[k] = (float)z;
    X->gz[0][k] = C->gz[0][si];
    X->gz[1][k] = C->gz[1][si];
    X->id[k] = C->id[ci];
    X->rx[k] = rx;
    X->ry[k] = ry;
    finish_pixel(G, X, k, jx, jy);
}

/* The window of raw data block (bx, by) reads: the real pixels its pixels map to (clamped into
 * the inputs) and a halo. Returns 0 when there are no inputs. (A pixel's attributes depend on
 * the inputs around it only, never on the block.) */
static int block_window(const gsrc *S, int bx, int by, int *cx0, int *cy0, int *cw, int *ch)
{
    nprfx_rect reg = S->region;
    if (nprfx_rect_empty(reg)) return 0;
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1; /* the ring's first pixel */
    int rx0 = x0 < reg.x0 ? reg.x0 : (x0 >= reg.x1 ? reg.x1 - 1 : x0);
    int rx1 = x0 + PW - 1 < reg.x0 ? reg.x0 : (x0 + PW - 1 >= reg.x1 ? reg.x1 - 1 : x0 + PW - 1);
    int ry0 = y0 < reg.y0 ? reg.y0 : (y0 >= reg.y1 ? reg.y1 - 1 : y0);
    int ry1 = y0 + PW - 1 < reg.y0 ? reg.y0 : (y0 + PW - 1 >= reg.y1 ? reg.y1 - 1 : y0 + PW - 1);
    *cx0 = rx0 - HALO;
    *cy0 = ry0 - HALO;
    *cw = rx1 - rx0 + 1 + 2 * HALO;
    *ch = ry1 - ry0 + 1 + 2 * HALO;
    return 1;
}

static void block_pixels_scalar(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                gcache *C)
{
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1, cx0, cy0, cw, ch;
    memset(X->emit, 0, sizeof X->emit);
    if (!block_window(&G->S, bx, by, &cx0, &cy0, &cw, &ch)) return;
    cache_fill(&G->S, T, C, cx0, cy0, cw, ch);
    cache_derive_scalar(&G->S, C, cw, ch);
    for (int j = 0; j < PW; j++)
        for (int i = 0; i < PW; i++)
            pixel_scalar(G, X, C, j * PWS + i, x0 + i, y0 + j, cx0, cy0);
}

#if GABOR_VEC
/* Interior flags and Jacobians 8 pixels at a time, as cache_derive_scalar lane by lane (on the
 * whole rows; the flags are then cut to the window less its ring, as the scalar path leaves
 * them). */
GV_INLINE void cache_derive_vec(const gsrc *S, gcache *C, int cw, int ch)
{
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    double step_tol = S->step_tol;
    for (int j = 1; j < ch - 1; j++)
        for (int i0 = 0; i0 < CW; i0 += 8) {
            int c = j * CW + i0;
            gv8i col = i0 + lane;
            gv8f zc = gv_loadf(C->z + c), idc = gv_loadf(C->id + c);
            gv8d zcd = gv_wide(zc);
            gv8i ok = gv_loadi(C->valid + c) & gv_loadi(C->full + c) & (col >= 1) & (col < cw - 1);
            const int nb[4] = {c - 1, c + 1, c - CW, c + CW};
            for (int k = 0; k < 4; k++) {
                int d = nb[k];
                gv8f zd = gv_loadf(C->z + d);
                gv8f zmin = gv_self(zc < zd, zc, zd);
                gv8i same = gv_loadi(C->valid + d) & (gv_loadf(C->id + d) == idc) &
                            gv_mask(gv_absd(gv_wide(zd) - zcd) <= step_tol * gv_wide(zmin));
                ok &= ~gv_loadi(C->present + d) | same;
            }
            gv_storei(C->interior + c, ok);
        }
    for (int j = 1; j < ch - 1; j++)
        for (int i0 = 0; i0 < CW; i0 += 8) {
            int c = j * CW + i0;
            gv8i in = gv_loadi(C->interior + c);
            if (!gv_any(in)) {
                gv_storei(C->hasj + c, in);
                continue;
            }
            gv8f idc = gv_loadf(C->id + c), zc = gv_loadf(C->z + c);
            gv8f Ac[3];
            for (int m = 0; m < 3; m++)
                Ac[m] = gv_loadf(C->A[m] + c);
            gv8i okall = in;
            for (int ax = 0; ax < 2; ax++) {
                int step = ax ? CW : 1, f = c + step, b = c - step;
                gv8i hf = gv_loadi(C->present + f) & gv_loadi(C->interior + f) &
                          (gv_loadf(C->id + f) == idc);
                gv8i hb = gv_loadi(C->present + b) & gv_loadi(C->interior + b) &
                          (gv_loadf(C->id + b) == idc);
                gv8f Df[3], Db[3];
                for (int m = 0; m < 3; m++) {
                    Df[m] = gv_loadf(C->A[m] + f) - Ac[m];
                    Db[m] = Ac[m] - gv_loadf(C->A[m] + b);
                }
                gv8f nf = Df[0] * Df[0] + Df[1] * Df[1] + Df[2] * Df[2];
                gv8f nb = Db[0] * Db[0] + Db[1] * Db[1] + Db[2] * Db[2];
                gv8i both = hf & hb;
                gv8i dropf = both & (nf > 9.0f * nb);
                gv8i dropb = both & ~dropf & (nb > 9.0f * nf);
                hf &= ~dropf;
                hb &= ~dropb;
                both = hf & hb;
                gv8f zf = gv_loadf(C->z + f), zb = gv_loadf(C->z + b);
                for (int m = 0; m < 3; m++) {
                    gv8f d = gv_self(both, 0.5f * (Df[m] + Db[m]), gv_self(hf, Df[m], Db[m]));
                    gv_storef(C->J[ax][m] + c, d);
                }
                gv_storef(C->gz[ax] + c,
                          gv_self(both, 0.5f * (zf - zb), gv_self(hf, zf - zc, zc - zb)));
                okall &= hf | hb;
            }
            gv_storei(C->hasj + c, okall);
        }
}

/* The attributes of 8 block pixels k.. (row j, columns i0..) whose real pixels are themselves
 * and interior with a Jacobian (the lanes in sel; the others are left to pixel_scalar): as
 * pixel_scalar and finish_pixel lane by lane. */
GV_INLINE void pixels_vec8(const gconf *G, gpixels *X, const gcache *C, int k, int c, int x, int y,
                           const gv8i *psel)
{
    gv8i sel = *psel;
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    gv8d jx[3], jy[3], zero = {0};
    for (int m = 0; m < 3; m++) {
        jx[m] = gv_wide(gv_loadf(C->J[0][m] + c));
        jy[m] = gv_wide(gv_loadf(C->J[1][m] + c));
        gv_storef(X->A[m] + k,
                  gv_narrow(gv_wide(gv_loadf(C->A[m] + c)) + jx[m] * zero + jy[m] * zero));
    }
    gv8f gz0 = gv_loadf(C->gz[0] + c), gz1 = gv_loadf(C->gz[1] + c);
    gv8d z = gv_wide(gv_loadf(C->z + c)) + gv_wide(gz0) * zero + gv_wide(gz1) * zero;
    gv8i ok = sel & gv_mask((z > 0.0) & (z < BACKGROUND_DEPTH));
    gv_storef(X->z + k, gv_narrow(z));
    gv_storef(X->gz[0] + k, gz0);
    gv_storef(X->gz[1] + k, gz1);
    gv_storef(X->id + k, gv_loadf(C->id + c));
    gv_storei(X->rx + k, x + lane);
    gv_storei(X->ry + k, y + (gv8i){0});
    gv8d g11 = jx[0] * jx[0] + jx[1] * jx[1] + jx[2] * jx[2];
    gv8d g12 = jx[0] * jy[0] + jx[1] * jy[1] + jx[2] * jy[2];
    gv8d g22 = jy[0] * jy[0] + jy[1] * jy[1] + jy[2] * jy[2];
    gv8d det = g11 * g22 - g12 * g12;
    gv8l okd = (det > 0.0) & (det < HUGE_VAL);
    gv8d one = zero + 1.0;
    gv8d area = gv_sqrt(gv_seld(okd, det, one)), iarea = 1.0 / area, idet = iarea * iarea;
    for (int m = 0; m < 3; m++) {
        gv_storef(X->P[m] + k, gv_narrow((g22 * jx[m] - g12 * jy[m]) * idet));
        gv_storef(X->P[3 + m] + k, gv_narrow((g11 * jy[m] - g12 * jx[m]) * idet));
        gv_storef(X->ext[m] + k, gv_narrow(0.5 * (gv_absd(jx[m]) + gv_absd(jy[m]))));
    }
    gv_storef(X->n[0] + k, gv_narrow((jx[1] * jy[2] - jx[2] * jy[1]) * iarea));
    gv_storef(X->n[1] + k, gv_narrow((jx[2] * jy[0] - jx[0] * jy[2]) * iarea));
    gv_storef(X->n[2] + k, gv_narrow((jx[0] * jy[1] - jx[1] * jy[0]) * iarea));
    gv8f mu = gv_narrow(G->lh2 * iarea);
    gv_storef(X->mu + k, mu);
    ok &= gv_mask(okd) & (mu > 0.0f) & (mu < HUGE_VALF);
    gv_storei(X->emit + k, ok);
}

GV_INLINE void block_pixels_body(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                 gcache *C)
{
    const gsrc *S = &G->S;
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1, cx0, cy0, cw, ch;
    memset(X->emit, 0, sizeof X->emit);
    if (!block_window(S, bx, by, &cx0, &cy0, &cw, &ch)) return;
    cache_fill(S, T, C, cx0, cy0, cw, ch);
    cache_derive_vec(S, C, cw, ch);
    nprfx_rect reg = S->region;
    /* every pixel of the block is real: pixel (i, j) is raw pixel (i + HALO, j + HALO) */
    int inside = x0 >= reg.x0 && x0 + PW <= reg.x1 && y0 >= reg.y0 && y0 + PW <= reg.y1;
    for (int j = 0; j < PW; j++)
        for (int i0 = 0; i0 < PWS; i0 += 8) {
            int k = j * PWS + i0;
            gv8i real = (i0 + lane) < PW;
            gv8i self = real;
            if (inside) {
                int c = (j + HALO) * CW + i0 + HALO;
                self &= gv_loadi(C->hasj + c);
                pixels_vec8(G, X, C, k, c, x0 + i0, y0 + j, &self);
            } else {
                self &= 0;
            }
            for (int l = 0; l < 8; l++)
                if (real[l] && !self[l])
                    pixel_scalar(G, X, C, k + l, x0 + i0 + l, y0 + j, cx0, cy0);
        }
}

#endif /* GABOR_VEC */

#if GABOR_X86
static int cpu_avx512(void)
{
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
           __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq");
}

static int cpu_avx2(void)
{
    return __builtin_cpu_supports("avx2");
}
#endif

/* ---- emission ------------------------------------------------------------------------------- */

/* One axis of a kernel's separable factors, sampled at its first sample and stepped by the
 * sample spacing: the envelope g = exp(-pi a^2 d^2) and its ratio r to the next sample, the
 * phase's cosine and sine and their rotation per step. Computed once per kernel, at emission,
 * so splatting runs recurrences only (no exp or sincos per kernel and tile). */
typedef struct gaxis {
    float g, r, c, s, cs, ss;
} gaxis;

typedef struct gpoint {
    float sx, sy; /* screen position, pixels */
    float amp;    /* v * w */
    float w2;     /* w^2 */
    float z;      /* depth at (sx, sy) */
    float gzx, gzy;
    float id;
    int ox, oy;         /* owner pixel */
    int X0, X1, Y0, Y1; /* first and last samples of the bounding box (sample coordinates) */
    gaxis ax, ay;
} gpoint;

typedef struct gblock {
    gpoint *p;
    int n, cap;
} gblock;

static int block_push(gblock *b, const gpoint *pt)
{
    if (b->n == b->cap) {
        int cap = b->cap ? 2 * b->cap : 32;
        gpoint *np = realloc(b->p, sizeof(gpoint) * (size_t)cap);
        if (!np) return 0;
        b->p = np;
        b->cap = cap;
    }
    b->p[b->n++] = *pt;
    return 1;
}

static double sample_pos(int X, int s)
{
    return (X + 0.5) / s - 0.5;
}

static void axis_start(const gconf *G, double d0, double k, int axis, gaxis *ax)
{
    double step = 1.0 / G->ss;
    ax->g = (float)exp(-G->pa2 * d0 * d0);
    ax->r = (float)exp(-G->pa2 * (2.0 * d0 * step + step * step));
    ax->c = (float)cos(k * d0);
    ax->s = (float)sin(k * d0);
    if (G->uniform_wave) {
        ax->cs = axis ? G->csy : G->csx;
        ax->ss = axis ? G->ssy : G->ssx;
    } else {
        ax->cs = (float)cos(k * step);
        ax->ss = (float)sin(k * step);
    }
}

static int in_block(int q)
{
    int i = q % PWS, j = q / PWS;
    return i >= 1 && i <= BLOCK && j >= 1 && j <= BLOCK;
}

/* Offset of anchor point a from pixel p's centre under p's own linearisation, in pixels. */
GABOR_BODY double own_offset(const gpixels *X, int p, const double *a, double *ux, double *uy)
{
    double d[3] = {a[0] - X->A[0][p], a[1] - X->A[1][p], a[2] - X->A[2][p]};
    *ux = X->P[0][p] * d[0] + X->P[1][p] * d[1] + X->P[2][p] * d[2];
    *uy = X->P[3][p] * d[0] + X->P[4][p] * d[1] + X->P[5][p] * d[2];
    double ax = fabs(*ux), ay = fabs(*uy);
    return ax > ay ? ax : ay;
}

/* The owner of anchor point a, if it is a pixel of this block (index in the PW x PW grid), else
 * -1. Ownership: among the pixels of the point's object, the owner is the one in whose own
 * linearisation the point lies nearest its centre (own_offset, L-inf; ties to the first in
 * raster order). Where neighbouring pixels' linearisations disagree (curved surfaces, points
 * off the surface in a 3D slab) a point near a border would land in neither square or in both;
 * this rule gives it exactly one owner, and every block that meets the point finds the same one
 * (the ring of pixels around the block is known too). The search starts at the reference
 * pixel of a patch and jumps to where the current pixel's linearisation puts the point (a few
 * times: off the surface the jumps can overshoot), then descends on the offset over 3x3
 * neighbourhoods until the current pixel is the local minimum. (ox, oy): the point's offset
 * from its owner. */
#if GABOR_VEC
/* Plane p at the 8 neighbours of q (rows above, same, below; raster order), from three row
 * loads. q must not lie on the grid's first column or its first or last row. */
GV_INLINE gv8f nb8(const void *p, int q)
{
    const float *f = p;
    gv4f r0, r1, r2;
    memcpy(&r0, f + q - PWS - 1, sizeof r0);
    memcpy(&r1, f + q - 1, sizeof r1);
    memcpy(&r2, f + q + PWS - 1, sizeof r2);
    gv8f t = __builtin_shufflevector(r0, r1, 0, 1, 2, 4, 6, 0, 0, 0);
    gv8f u = __builtin_shufflevector(r2, r2, 0, 1, 2, 3, 0, 0, 0, 0);
    return __builtin_shufflevector(t, u, 0, 1, 2, 3, 4, 8, 9, 10);
}

/* One step of find_owner's descent, the 8 neighbours' offsets in the lanes of a vector (as
 * own_offset lane by lane); the choice then runs in the scalar loop's order. */
GV_INLINE void descend_vec(const gpixels *X, int q, float id, const double *a, int *best,
                           double *bd, double *bx, double *by)
{
    static const int offs[8] = {-PWS - 1, -PWS, -PWS + 1, -1, 1, PWS - 1, PWS, PWS + 1};
    gv8d d0 = a[0] - gv_wide(nb8(X->A[0], q)), d1 = a[1] - gv_wide(nb8(X->A[1], q));
    gv8d d2 = a[2] - gv_wide(nb8(X->A[2], q));
    gv8d ux = gv_wide(nb8(X->P[0], q)) * d0 + gv_wide(nb8(X->P[1], q)) * d1 +
              gv_wide(nb8(X->P[2], q)) * d2;
    gv8d uy = gv_wide(nb8(X->P[3], q)) * d0 + gv_wide(nb8(X->P[4], q)) * d1 +
              gv_wide(nb8(X->P[5], q)) * d2;
    gv8d ax = gv_absd(ux), ay = gv_absd(uy);
    gv8d dd = gv_seld(ax > ay, ax, ay);
    gv8i ok = ((gv8i)nb8(X->emit, q) != 0) & (nb8(X->id, q) == id);
    for (int l = 0; l < 8; l++) {
        if (!ok[l]) continue;
        int n = q + offs[l];
        double d = dd[l];
        if (d < *bd || (d == *bd && n < *best)) {
            *bd = d;
            *best = n;
            *bx = ux[l];
            *by = uy[l];
        }
    }
}
#endif

GABOR_BODY int find_owner(const gpixels *X, int ref, const double *a, double *ox, double *oy,
                          const int vec)
{
    int q = ref, prev = -1;
    float id = X->id[ref];
    double ux = 0.0, uy = 0.0, dq = 0.0;
    int fresh = 0; /* dq, ux, uy are q's */
    for (int it = 0; it < OWNER_STEPS; it++) {
        dq = own_offset(X, q, a, &ux, &uy);
        fresh = 1;
        if (!(dq < 1e6)) return -1;
        int mx = ifloor(ux + 0.5), my = ifloor(uy + 0.5);
        if (mx == 0 && my == 0) break;
        int ti = q % PWS + mx, tj = q / PWS + my;
        int qi = ti < 0 ? 0 : (ti >= PW ? PW - 1 : ti);
        int qj = tj < 0 ? 0 : (tj >= PW ? PW - 1 : tj);
        int nq = qj * PWS + qi;
        if (nq == q) return -1; /* beyond the ring: not this block's */
        if (!X->emit[nq] || X->id[nq] != id) {
            /* a hole or another object on the way (or the point is not visible): continue
             * from the nearest pixel of the object around the target, if any */
            int best = -1, bd = 1 << 30;
            for (int dj = -2; dj <= 2; dj++)
                for (int di = -2; di <= 2; di++) {
                    int i = qi + di, j = qj + dj;
                    if (i < 0 || i >= PW || j < 0 || j >= PW) continue;
                    int n = j * PWS + i, d = di * di + dj * dj;
                    if (X->emit[n] && X->id[n] == id && d < bd) {
                        bd = d;
                        best = n;
                    }
                }
            if (best < 0 || best == q) return -1;
            nq = best;
        }
        if (nq == prev) break; /* jumping back and forth: let the descent settle it */
        prev = q;
        q = nq;
        fresh = 0;
    }
    if (!fresh) dq = own_offset(X, q, a, &ux, &uy);
    for (int it = 0; it < 4 * PW; it++) {
        int best = q, qi = q % PWS, qj = q / PWS;
        double bx = ux, by = uy, bd = dq;
#if GABOR_VEC
        if (vec && qi >= 1 && qj >= 1 && qj <= PW - 2)
            descend_vec(X, q, id, a, &best, &bd, &bx, &by);
        else
#else
        (void)vec;
#endif
            for (int dj = -1; dj <= 1; dj++)
                for (int di = -1; di <= 1; di++) {
                    int i = qi + di, j = qj + dj;
                    if ((di == 0 && dj == 0) || i < 0 || i >= PW || j < 0 || j >= PW) continue;
                    int n = j * PWS + i;
                    if (!X->emit[n] || X->id[n] != id) continue;
                    double vx, vy, d = own_offset(X, n, a, &vx, &vy);
                    if (d < bd || (d == bd && n < best)) {
                        bd = d;
                        best = n;
                        bx = vx;
                        by = vy;
                    }
                }
        if (best == q) break;
        q = best;
        dq = bd;
        ux = bx;
        uy = by;
    }
    /* not near any pixel of the object (beyond a silhouette): no owner */
    if (!in_block(q) || !(dq <= 1.0)) return -1;
    *ox = ux;
    *oy = uy;
    return q;
}

static float sample_input(const nprfx_image *im, int x, int y, int ch, float def)
{
    if (!im || !nprfx_rect_contains(im->bounds, x, y)) return def;
    float v = nprfx_image_at(im, x, y)[ch];
    return isfinite(v) ? v : def;
}

/* Wave vector (cycles per pixel, pixel axes with y down) of a kernel owned at real pixel
 * (rx, ry): orientation from the param, the orientation input or (isotropic) the point's hash;
 * frequency from the param times the frequency input. */
static void kernel_wave(const gconf *G, int rx, int ry, uint64_t h, double *kx, double *ky)
{
    if (G->uniform_wave) {
        *kx = G->kx0;
        *ky = G->ky0;
        return;
    }
    double th = G->w0;
    if (G->iso) {
        th = k_pi * nprfx_u01(nprfx_mix64(h ^ 0x3c6ef372fe94f82bull));
    } else if (G->S.orient) {
        const nprfx_image *o = G->S.orient;
        if (o->channels >= 2) {
            float dx = sample_input(o, rx, ry, 0, 0.0f), dy = sample_input(o, rx, ry, 1, 0.0f);
            if (dx != 0.0f || dy != 0.0f) th += atan2(-(double)dy, (double)dx);
        } else {
            th += sample_input(o, rx, ry, 0, 0.0f) * (k_pi / 180.0);
        }
    }
    double sc = G->S.freq ? sample_input(G->S.freq, rx, ry, 0, 1.0f) : 1.0;
    if (sc < 0.0) sc = 0.0;
    if (sc > 1e3) sc = 1e3;
    double F = G->F0 * sc;
    *kx = F * cos(th);
    *ky = -F * sin(th); /* counter-clockwise in the image: y points down */
}

static double amplitude(int law, uint64_t h)
{
    uint64_t h2 = nprfx_mix64(h ^ 0xa54ff53a5f1d36f1ull);
    switch (law) {
    case NPRFX_GABOR_AMP_SIGN:
        return (h2 >> 63) ? 1.0 : -1.0;
    case NPRFX_GABOR_AMP_GAUSS: {
        double u1 = ((double)(h2 >> 11) + 0.5) * (1.0 / 9007199254740992.0);
        double u2 = nprfx_u01(nprfx_mix64(h2));
        return sqrt(-2.0 * log(u1)) * cos(2.0 * k_pi * u2);
    }
    default:
        return 2.0 * nprfx_u01(h2) - 1.0;
    }
}

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

/* Fill a point's screen-space data for a kernel centred at (sx, sy), owned by pixel o. */
static int make_point(const gconf *G, const gpixels *X, int o, int ox, int oy, double sx, double sy,
                      double w2, uint64_t h, float id, gpoint *pt)
{
    double z = X->z[o] + X->gz[0][o] * (sx - ox) + X->gz[1][o] * (sy - oy);
    if (!is_surface_depth(z)) return 0;
    int s = G->ss;
    double r = G->radius;
    pt->sx = (float)sx;
    pt->sy = (float)sy;
    /* everything below derives from the float position, which is what splatting sees */
    sx = pt->sx;
    sy = pt->sy;
    pt->X0 = iceil((sx - r + 0.5) * s - 0.5);
    pt->X1 = ifloor((sx + r + 0.5) * s - 0.5);
    pt->Y0 = iceil((sy - r + 0.5) * s - 0.5);
    pt->Y1 = ifloor((sy + r + 0.5) * s - 0.5);
    pt->w2 = (float)w2;
    pt->amp = (float)(amplitude(G->amp, h) * sqrt(w2));
    pt->z = (float)z;
    pt->gzx = X->gz[0][o];
    pt->gzy = X->gz[1][o];
    pt->id = id;
    pt->ox = ox;
    pt->oy = oy;
    double kx, ky;
    kernel_wave(G, X->rx[o], X->ry[o], h, &kx, &ky);
    axis_start(G, sample_pos(pt->X0, s) - sx, 2.0 * k_pi * kx, 0, &pt->ax);
    axis_start(G, sample_pos(pt->Y0, s) - sy, 2.0 * k_pi * ky, 1, &pt->ay);
    return 1;
}

/* Two neighbouring pixels lie on one surface patch: same object, no depth step, and anchors
 * no farther apart than about two pixel footprints (not across a UV seam, or two objects
 * sharing an id input that is not connected). */
static int patch_link(const gconf *G, const gpixels *X, int a, int b)
{
    if (!X->emit[b] || X->id[b] != X->id[a]) return 0;
    float za = X->z[a], zb = X->z[b];
    float zmin = za < zb ? za : zb;
    if (!(fabsf(za - zb) <= G->step_tolf * zmin)) return 0;
    float d2 = 0.0f, e2 = 0.0f;
    for (int m = 0; m < 3; m++) {
        float d = X->A[m][a] - X->A[m][b], e = X->ext[m][a] + X->ext[m][b];
        d2 += d * d;
        e2 += e * e;
    }
    return d2 <= 4.0f * e2;
}

/* Label the emitting pixels of a block (not its ring) by connected surface patch (4-neighbours,
 * raster order of each patch's first pixel). Each patch enumerates the anchor cells of its own
 * footprint, so a block straddling two surfaces does not enumerate everything between their
 * anchors. */
#if GABOR_VEC
/* patch_link between the block's pixels and their right and lower neighbours, 8 at a time (as
 * patch_link lane by lane; it is symmetric). */
GV_INLINE void patch_links_vec(const gconf *G, gpixels *X)
{
    gv8f tol = G->step_tolf + (gv8f){0};
    for (int j = 1; j <= BLOCK; j++)
        for (int i0 = 0; i0 < PWS; i0 += 8) {
            int k = j * PWS + i0;
            gv8f za = gv_loadf(X->z + k), ida = gv_loadf(X->id + k);
            gv8i ea = gv_loadi(X->emit + k) != 0;
            for (int dir = 0; dir < 2; dir++) {
                int o = k + (dir ? PWS : 1);
                gv8f zb = gv_loadf(X->z + o);
                gv8f zmin = gv_self(za < zb, za, zb);
                gv8i m = ea & (gv_loadi(X->emit + o) != 0) & (gv_loadf(X->id + o) == ida) &
                         (gv_absf(za - zb) <= tol * zmin);
                gv8f d2 = {0}, e2 = {0};
                for (int c = 0; c < 3; c++) {
                    gv8f d = gv_loadf(X->A[c] + k) - gv_loadf(X->A[c] + o);
                    gv8f e = gv_loadf(X->ext[c] + k) + gv_loadf(X->ext[c] + o);
                    d2 += d * d;
                    e2 += e * e;
                }
                m &= d2 <= 4.0f * e2;
                gv_storei((dir ? X->ld : X->lr) + k, m);
            }
        }
}
#endif

#if GABOR_VEC
/* Every pixel of the block emits and links to its right and lower neighbours in the block. */
GV_INLINE int one_patch_vec(const gpixels *X)
{
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    gv8i all = (gv8i){0} - 1;
    for (int j = 1; j <= BLOCK; j++)
        for (int i0 = 1; i0 <= BLOCK; i0 += 8) {
            int k = j * PWS + i0;
            all &= gv_loadi(X->emit + k) != 0;
            all &= (gv_loadi(X->lr + k) != 0) | ((i0 + lane) == BLOCK); /* the last: no link */
            if (j < BLOCK) all &= gv_loadi(X->ld + k) != 0;
        }
    for (int l = 0; l < 8; l++)
        if (!all[l]) return 0;
    return 1;
}
#endif

GABOR_BODY int label_patches(const gconf *G, gpixels *X, const int vec)
{
    int stack[BLOCK * BLOCK], n = 0;
    for (int k = 0; k < PN; k++)
        X->comp[k] = -1;
#if GABOR_VEC
    if (vec) {
        patch_links_vec(G, X);
        if (one_patch_vec(X)) {
            /* every pixel of the block emits and links to its neighbours: one patch */
            for (int j = 1; j <= BLOCK; j++)
                for (int i = 1; i <= BLOCK; i++)
                    X->comp[j * PWS + i] = 0;
            return 1;
        }
    }
#endif
    for (int kj = 1; kj <= BLOCK; kj++)
        for (int ki = 1; ki <= BLOCK; ki++) {
            int k = kj * PWS + ki; /* raster order over the block */
            if (!X->emit[k] || X->comp[k] >= 0) continue;
            int sp = 0;
            X->comp[k] = n;
            stack[sp++] = k;
            while (sp > 0) {
                int c = stack[--sp], ci = c % PWS, cj = c / PWS;
                const int nb[4] = {c - 1, c + 1, c - PWS, c + PWS};
                const int in[4] = {ci > 1, ci<BLOCK, cj> 1, cj < BLOCK}; /* in_block(nb[m]) */
                for (int m = 0; m < 4; m++) {
                    int d = nb[m];
                    if (!in[m] || X->comp[d] >= 0) continue;
                    int link;
                    if (vec) {
                        static const int lo[4] = {-1, 0, -PWS, 0};
                        link = (m < 2 ? X->lr : X->ld)[c + lo[m]] != 0;
                    } else {
                        link = patch_link(G, X, c, d);
                    }
                    if (!link) continue;
                    X->comp[d] = n;
                    stack[sp++] = d;
                }
            }
            n++;
        }
    return n;
}

/* The surface at grid position (gx, gy) (a point's screen position): anchor, unit normal and
 * wanted density, bilinear over the four pixels around it where they are all on the owner's
 * surface patch, else the owner's own. A point's distance to the surface and its level weight
 * are read here rather than at the owner's centre, so they barely change when the pixel grid
 * slides under the point and ownership passes to a neighbour (no slab-test flips, no weight
 * jumps: no popping). */
static void surface_at(const gconf *G, const gpixels *X, int q, double gx, double gy, double *A,
                       double *n, double *mu)
{
    int i0 = ifloor(gx), j0 = ifloor(gy);
    if (i0 >= 0 && j0 >= 0 && i0 + 1 < PW && j0 + 1 < PW) {
        const int c[4] = {j0 * PWS + i0, j0 * PWS + i0 + 1, (j0 + 1) * PWS + i0,
                          (j0 + 1) * PWS + i0 + 1};
        int ok = 1;
        for (int k = 0; k < 4 && ok; k++)
            ok = c[k] == q || patch_link(G, X, q, c[k]);
        if (ok) {
            double fx = gx - i0, fy = gy - j0;
            double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
            double nn = 0.0;
            *mu = 0.0;
            for (int m = 0; m < 3; m++) {
                const float *Am = X->A[m], *nm = X->n[m];
                A[m] = w[0] * Am[c[0]] + w[1] * Am[c[1]] + w[2] * Am[c[2]] + w[3] * Am[c[3]];
                n[m] = w[0] * nm[c[0]] + w[1] * nm[c[1]] + w[2] * nm[c[2]] + w[3] * nm[c[3]];
                nn += n[m] * n[m];
            }
            for (int k = 0; k < 4; k++)
                *mu += w[k] * X->mu[c[k]];
            if (nn > 0.0) {
                nn = 1.0 / sqrt(nn);
                for (int m = 0; m < 3; m++)
                    n[m] *= nn;
                return;
            }
        }
    }
    for (int m = 0; m < 3; m++) {
        A[m] = X->A[m][q];
        n[m] = X->n[m][q];
    }
    *mu = X->mu[q];
}

/* A patch's footprint: its reference pixel (nearest the block centre, first in raster order),
 * the bounds of its pixels' anchor footprints and the largest normal component. */
static int patch_footprint(const gpixels *X, int comp, double *fmin, double *fmax, double *nmax)
{
    const double mid = 0.5 * (PW - 1);
    int ref = -1;
    double best = DBL_MAX;
    for (int m = 0; m < 3; m++) {
        fmin[m] = DBL_MAX;
        fmax[m] = -DBL_MAX;
        nmax[m] = 0.0;
    }
    for (int k = 0; k < PN; k++) {
        if (X->comp[k] != comp) continue;
        double dx = k % PWS - mid, dy = k / PWS - mid, d = dx * dx + dy * dy;
        if (d < best) {
            best = d;
            ref = k;
        }
        for (int m = 0; m < 3; m++) {
            float A = X->A[m][k], e = X->ext[m][k], nm = X->n[m][k];
            if (A - e < fmin[m]) fmin[m] = A - e;
            if (A + e > fmax[m]) fmax[m] = A + e;
            if (fabs(nm) > nmax[m]) nmax[m] = fabs(nm);
        }
    }
    return ref;
}

/* Over the pixels of the object (ring included): the smallest and largest wanted density; 3D,
 * over the patch and the ring: how far their anchors lie from the reference tangent plane
 * (rA, rn) and how far their normals turn from rn. */
static void patch_reach(const gconf *G, const gpixels *X, int comp, float id, const double *rA,
                        const double *rn, double *mumin, double *mumax, double *reach, double *turn)
{
    *mumin = DBL_MAX;
    *mumax = 0.0;
    *reach = *turn = 0.0;
    for (int k = 0; k < PN; k++) {
        if (!X->emit[k] || X->id[k] != id) continue;
        if (X->mu[k] < *mumin) *mumin = X->mu[k];
        if (X->mu[k] > *mumax) *mumax = X->mu[k];
        if (G->dims != 3 || !(X->comp[k] == comp || !in_block(k))) continue;
        double d[3] = {(double)X->A[0][k] - rA[0], (double)X->A[1][k] - rA[1],
                       (double)X->A[2][k] - rA[2]};
        double e = fabs(dot3(d, rn));
        double dn[3] = {(double)X->n[0][k] - rn[0], (double)X->n[1][k] - rn[1],
                        (double)X->n[2][k] - rn[2]};
        double t = sqrt(dot3(dn, dn));
        if (e > *reach) *reach = e;
        if (t > *turn) *turn = t;
    }
}

#if GABOR_VEC
GV_INLINE gv8i in_block_cols(int i0)
{
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    return ((i0 + lane) >= 1) & ((i0 + lane) <= BLOCK);
}

/* patch_footprint 8 pixels at a time (the patch lies in the block; the squared distances to
 * the centre are exact in float as in double; min and max are exact) */
GV_INLINE int patch_footprint_vec(const gpixels *X, int comp, double *fmin, double *fmax,
                                  double *nmax)
{
    const gv8i lane = {0, 1, 2, 3, 4, 5, 6, 7};
    const float mid = 0.5f * (PW - 1);
    gv8f inf = (gv8f){0} + HUGE_VALF, bestd = inf, lo[3], hi[3], nx[3];
    gv8i bestk = (gv8i){0} - 1;
    for (int m = 0; m < 3; m++) {
        lo[m] = inf;
        hi[m] = -inf;
        nx[m] = (gv8f){0};
    }
    for (int j = 1; j <= BLOCK; j++) {
        float dy = (float)j - mid;
        for (int i0 = 0; i0 < PWS; i0 += 8) {
            int k = j * PWS + i0;
            gv8i in = gv_loadi(X->comp + k) == comp;
            if (!gv_any(in)) continue;
            gv8f dx = __builtin_convertvector(i0 + lane, gv8f) - mid;
            gv8f d = dx * dx + dy * dy;
            gv8i up = in & (d < bestd);
            bestd = gv_self(up, d, bestd);
            bestk = gv_seli(up, k + lane, bestk);
            for (int m = 0; m < 3; m++) {
                gv8f A = gv_loadf(X->A[m] + k), e = gv_loadf(X->ext[m] + k);
                gv8f a = A - e, b = A + e, n = gv_absf(gv_loadf(X->n[m] + k));
                lo[m] = gv_self(in & (a < lo[m]), a, lo[m]);
                hi[m] = gv_self(in & (b > hi[m]), b, hi[m]);
                nx[m] = gv_self(in & (n > nx[m]), n, nx[m]);
            }
        }
    }
    int ref = -1;
    float bd = HUGE_VALF;
    for (int l = 0; l < 8; l++)
        if (bestk[l] >= 0 && (bestd[l] < bd || (bestd[l] == bd && bestk[l] < ref))) {
            bd = bestd[l];
            ref = bestk[l];
        }
    for (int m = 0; m < 3; m++) {
        float a = HUGE_VALF, b = -HUGE_VALF, n = 0.0f;
        for (int l = 0; l < 8; l++) {
            a = lo[m][l] < a ? lo[m][l] : a;
            b = hi[m][l] > b ? hi[m][l] : b;
            n = nx[m][l] > n ? nx[m][l] : n;
        }
        fmin[m] = a;
        fmax[m] = b;
        nmax[m] = n;
    }
    return ref;
}

/* patch_reach 8 pixels at a time (the largest turn is the square root of the largest squared
 * turn: sqrt is monotone and exactly rounded) */
GV_INLINE void patch_reach_vec(const gconf *G, const gpixels *X, int comp, float id,
                               const double *rA, const double *rn, double *mumin, double *mumax,
                               double *reach, double *turn)
{
    gv8f mlo = (gv8f){0} + HUGE_VALF, mhi = {0};
    gv8d rch = {0}, trn = {0};
    for (int j = 0; j < PW; j++) {
        int jin = j >= 1 && j <= BLOCK;
        for (int i0 = 0; i0 < PWS; i0 += 8) {
            int k = j * PWS + i0;
            gv8i m = (gv_loadi(X->emit + k) != 0) & (gv_loadf(X->id + k) == id);
            if (!gv_any(m)) continue;
            gv8f mu = gv_loadf(X->mu + k);
            mlo = gv_self(m & (mu < mlo), mu, mlo);
            mhi = gv_self(m & (mu > mhi), mu, mhi);
            if (G->dims != 3) continue;
            gv8i ring = jin ? ~in_block_cols(i0) : (gv8i){0} - 1;
            m &= (gv_loadi(X->comp + k) == comp) | ring;
            gv8l ml = __builtin_convertvector(m, gv8l);
            gv8d d0 = gv_wide(gv_loadf(X->A[0] + k)) - rA[0];
            gv8d d1 = gv_wide(gv_loadf(X->A[1] + k)) - rA[1];
            gv8d d2 = gv_wide(gv_loadf(X->A[2] + k)) - rA[2];
            gv8d e = gv_absd(d0 * rn[0] + d1 * rn[1] + d2 * rn[2]);
            gv8d n0 = gv_wide(gv_loadf(X->n[0] + k)) - rn[0];
            gv8d n1 = gv_wide(gv_loadf(X->n[1] + k)) - rn[1];
            gv8d n2 = gv_wide(gv_loadf(X->n[2] + k)) - rn[2];
            gv8d t2 = n0 * n0 + n1 * n1 + n2 * n2;
            rch = gv_seld(ml & (e > rch), e, rch);
            trn = gv_seld(ml & (t2 > trn), t2, trn);
        }
    }
    float a = HUGE_VALF, b = 0.0f;
    double r = 0.0, t = 0.0;
    for (int l = 0; l < 8; l++) {
        a = mlo[l] < a ? mlo[l] : a;
        b = mhi[l] > b ? mhi[l] : b;
        r = rch[l] > r ? rch[l] : r;
        t = trn[l] > t ? trn[l] : t;
    }
    *mumin = a == HUGE_VALF ? DBL_MAX : a;
    *mumax = b;
    *reach = r;
    *turn = sqrt(t);
}
#endif

typedef struct emit_scratch {
    gcache C;
    gpixels X;
    gstrip T;
} emit_scratch;

/* Emit the points owned by the pixels of block (bx, by) into b. Returns 0 when out of memory.
 * vec: the vector path (a constant in each instance). */
GABOR_BODY int emit_block_body(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr,
                               const int vec)
{
    gpixels *X = &scr->X;
#if GABOR_VEC
    if (vec)
        block_pixels_body(G, &scr->T, bx, by, X, &scr->C);
    else
#endif
        block_pixels_scalar(G, &scr->T, bx, by, X, &scr->C);
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1; /* pixel (x0, y0): index 0 of the grid */
    int ncomp = label_patches(G, X, vec);
    for (int comp = 0; comp < ncomp; comp++) {
        /* the patch's footprint: anchor +- pixel extent, and the largest normal component (the
         * slab's reach per level is added below) */
        double fmin[3], fmax[3], nmax[3];
        int ref;
#if GABOR_VEC
        if (vec)
            ref = patch_footprint_vec(X, comp, fmin, fmax, nmax);
        else
#endif
            ref = patch_footprint(X, comp, fmin, fmax, nmax);
        float id = X->id[ref];
        uint32_t idbits = float_bits(id);
        /* A point's level weight and slab test use the surface interpolated from up to four
         * pixels of the object around it, ring pixels included: the levels to enumerate are
         * those of the smallest and largest wanted density among them (the rule is monotone).
         * 3D: how far those pixels' surface reaches from the reference pixel's tangent plane,
         * and how much their normals turn: a point farther from that plane than the slab plus
         * this reach cannot be accepted, which rejects most off-surface cells of the bounding
         * box before the owner search. */
        double rA[3] = {X->A[0][ref], X->A[1][ref], X->A[2][ref]};
        double rn[3] = {X->n[0][ref], X->n[1][ref], X->n[2][ref]};
        double reach, turn, mumin, mumax;
#if GABOR_VEC
        if (vec)
            patch_reach_vec(G, X, comp, id, rA, rn, &mumin, &mumax, &reach, &turn);
        else
#endif
            patch_reach(G, X, comp, id, rA, rn, &mumin, &mumax, &reach, &turn);
        int Lmin, Lmax, lo, hi, dummy;
        double fmin_, fmax_;
        lod_regime(&G->lod, mumin, &Lmin, &fmin_);
        lod_regime(&G->lod, mumax, &Lmax, &fmax_);
        lod_range(Lmin, fmin_, G->W, &lo, &dummy);
        lod_range(Lmax, fmax_, G->W, &dummy, &hi);
        for (int l = lo; l <= hi; l++) {
            double c = ldexp(G->h0, -l), ic = 1.0 / c;
            /* accepted: |(a - A(s)) . n(s)| < SLAB_OUT c with A(s), n(s) interpolated; so
             * |(a - A_ref) . n_ref| < SLAB_OUT c + |a - A(s)| |n(s) - n_ref| + reach, with a
             * generous allowance for the interpolation's own error */
            double slab = (SLAB_OUT + 0.1) * c * (1.0 + turn) + reach;
            /* staggered fade: where level l fades in for every pixel a point may take its
             * surface from, a point whose ramp has not started at the largest ramp variable
             * among them has weight 0 whoever owns it: skip it before the owner search */
            double xmax = 2.0;
            if (G->stagger && Lmin == l - 1 && Lmax == l - 1) xmax = stagger_x(G->lod.x, fmax_);
            /* nprfx_hash(seed, l, ix, iy, iz, id) with its first two rounds hoisted */
            uint64_t hl =
                nprfx_mix64(nprfx_mix64(G->seed ^ 0x6a09e667f3bcc908ull) ^ (uint64_t)(int64_t)l);
            double i0[3] = {0, 0, 0}, i1[3] = {0, 0, 0}, cells = 1.0;
            for (int m = 0; m < G->dims; m++) {
                /* 3D: the slab around the tangent planes */
                double e = G->dims == 3 ? SLAB_OUT * c * nmax[m] : 0.0;
                i0[m] = floor((fmin[m] - e) * ic);
                i1[m] = floor((fmax[m] + e) * ic);
                cells *= i1[m] - i0[m] + 1.0;
            }
            if (!(cells <= MAX_CELLS)) continue;
            for (double iz = i0[2]; iz <= i1[2]; iz++)
                for (double iy = i0[1]; iy <= i1[1]; iy++)
                    for (double ix = i0[0]; ix <= i1[0]; ix++) {
                        uint64_t xy = ((uint64_t)(uint32_t)(int32_t)(int64_t)ix << 32) |
                                      (uint64_t)(uint32_t)(int32_t)(int64_t)iy;
                        uint64_t h =
                            nprfx_mix64(nprfx_mix64(hl ^ xy) ^
                                        (((uint64_t)(uint32_t)(int64_t)iz << 32) | idbits));
                        /* three 21-bit uniforms for the position inside the cell */
                        double a[3];
                        a[0] = (ix + ((double)(h >> 43) + 0.5) * (1.0 / 2097152.0)) * c;
                        a[1] =
                            (iy + ((double)((h >> 22) & 0x1fffff) + 0.5) * (1.0 / 2097152.0)) * c;
                        a[2] =
                            G->dims == 3
                                ? (iz + ((double)((h >> 1) & 0x1fffff) + 0.5) * (1.0 / 2097152.0)) *
                                      c
                                : 0.0;
                        double ustart = 0.0;
                        if (G->stagger) {
                            ustart = nprfx_u01(nprfx_mix64(h ^ 0x510e527fade682d1ull));
                            if (ustart * (1.0 - STAGGER) >= xmax) continue;
                        }
                        if (G->dims == 3) {
                            double d[3] = {a[0] - rA[0], a[1] - rA[1], a[2] - rA[2]};
                            if (!(fabs(dot3(d, rn)) < slab)) continue;
                        }
                        double ux, uy;
                        int q = find_owner(X, ref, a, &ux, &uy, vec);
                        if (q < 0) continue;
                        double As[3], ns[3], mus, fs;
                        int Ls;
                        surface_at(G, X, q, q % PWS + ux, q / PWS + uy, As, ns, &mus);
                        lod_regime(&G->lod, mus, &Ls, &fs);
                        double w2 = lod_w2(Ls, fs, G->W, l);
                        if (G->stagger && Ls >= 0 && l == Ls + 1)
                            w2 = stagger_w2(stagger_x(G->lod.x, fs), ustart);
                        if (!(w2 > 0.0)) continue;
                        if (G->dims == 3) {
                            /* a slab of (weighted) thickness c around the surface: 1 / c^3
                             * points per volume give 1 / c^2 per surface area */
                            double d[3] = {a[0] - As[0], a[1] - As[1], a[2] - As[2]};
                            double x = fabs(dot3(d, ns)) * ic;
                            if (!(x < SLAB_OUT)) continue;
                            if (x > SLAB_IN) {
                                double t = (SLAB_OUT - x) * (1.0 / SLAB_SOFT);
                                w2 *= t * t;
                            }
                        }
                        gpoint pt;
                        int ox = x0 + q % PWS, oy = y0 + q / PWS;
                        if (!make_point(G, X, q, ox, oy, ox + ux, oy + uy, w2, h, id, &pt))
                            continue;
                        if (!block_push(b, &pt)) return 0;
                    }
        }
    }
    return 1;
}

static int emit_block_scalar(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr)
{
    return emit_block_body(G, bx, by, b, scr, 0);
}

#if GABOR_X86
__attribute__((target("avx2"))) static int emit_block_avx2(const gconf *G, int bx, int by,
                                                           gblock *b, emit_scratch *scr)
{
    return emit_block_body(G, bx, by, b, scr, 1);
}

__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))) static int
emit_block_avx512(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr)
{
    return emit_block_body(G, bx, by, b, scr, 1);
}
#endif

/* simd: 0 the fastest path, 1 scalar, 2 the baseline ISA's vectors (emission: scalar; its vector
 * code needs AVX2's registers to pay), 3 AVX2 (as 2 without it) */
static emit_fn pick_emit_fn(int simd)
{
#if GABOR_X86
    if (simd == 0 && cpu_avx512()) return emit_block_avx512;
    if ((simd == 0 || simd == 3) && cpu_avx2()) return emit_block_avx2;
#endif
    (void)simd;
    return emit_block_scalar;
}

/* ---- splatting ------------------------------------------------------------------------------- */

/* The kernel's factor tables along x (nx samples) and y (ny samples) from their start values:
 * g (c, s) by recurrences in double, the two axes interleaved so their dependency chains
 * overlap. */
static void kernel_tables(const gaxis *ax, const gaxis *ay, double rr, int nx, int ny, float *CX,
                          float *SX, float *CY, float *SY)
{
    double g0 = ax->g, r0 = ax->r, c0 = ax->c, s0 = ax->s, cs0 = ax->cs, ss0 = ax->ss;
    double g1 = ay->g, r1 = ay->r, c1 = ay->c, s1 = ay->s, cs1 = ay->cs, ss1 = ay->ss;
    int n = nx > ny ? nx : ny;
    for (int i = 0; i < n; i++) {
        if (i < nx) {
            CX[i] = (float)(g0 * c0);
            SX[i] = (float)(g0 * s0);
        }
        if (i < ny) {
            CY[i] = (float)(g1 * c1);
            SY[i] = (float)(g1 * s1);
        }
        g0 *= r0;
        r0 *= rr;
        g1 *= r1;
        r1 *= rr;
        double t0 = c0 * cs0 - s0 * ss0, t1 = c1 * cs1 - s1 * ss1;
        s0 = s0 * cs0 + c0 * ss0;
        s1 = s1 * cs1 + c1 * ss1;
        c0 = t0;
        c1 = t1;
    }
}

/* Adding one kernel row: acc[j] += v_j where the sample passes the visibility test, with
 * v_j = A cx[j] - B sx[j] and the expected depth zp_j = zr + gx (i0 + j). Every path (vector or
 * scalar) does the same float operations in the same order (no FMA: the build uses
 * -ffp-contract=off), and a row's last partial vector is masked rather than finished in scalar
 * code, so a sample's value never depends on where its row starts. Masked lanes add +0.0,
 * which leaves any accumulator unchanged (sums that start at +0.0 are never -0.0); the
 * buffers have VPAD floats of slack for them. */
typedef struct row_job {
    float A, B, idk, zr, gx, tol; /* tol: hard: tolerance; soft: its inverse */
    int i0, n, mode;
} row_job;

static void row_scalar(float *restrict acc, const float *restrict zt, const float *restrict idt,
                       const float *restrict cx, const float *restrict sx, const row_job *R)
{
    for (int j = 0; j < R->n; j++) {
        float v = R->A * cx[j] - R->B * sx[j];
        if (R->mode == NPRFX_GABOR_DEPTH_OFF) {
            acc[j] += idt[j] == R->idk ? v : 0.0f;
            continue;
        }
        float zp = R->zr + R->gx * (float)(R->i0 + j);
        float dz = fabsf(zt[j] - zp);
        if (R->mode == NPRFX_GABOR_DEPTH_HARD) {
            acc[j] += (idt[j] == R->idk && dz <= R->tol) ? v : 0.0f;
        } else {
            float t = 2.0f - dz * R->tol;
            t = t > 0.0f ? t : 0.0f; /* as MAXPS(t, 0) */
            t = t < 1.0f ? t : 1.0f; /* as MINPS(t, 1) */
            acc[j] += idt[j] == R->idk ? v * t : 0.0f;
        }
    }
}

/* ---- the render ----------------------------------------------------------------------------- */

/* A splat tile's sample buffers (W x H samples with VPAD floats of slack), its extent in sample
 * coordinates, the blocks within kernel reach and scratch for the kernels' tables and spans. */
typedef struct gtile {
    float *acc, *zt, *idt;
    int W, TX0, TY0, TX1, TY1;
    int bxa, bxb, bya, byb;
    int tabn;   /* floats per table */
    float *tab; /* SPLAT_BATCH x (4 tables + row depths) */
    int *span;  /* SPLAT_BATCH x 2 spans of tabn ints */
    long long evals;
} gtile;

struct gjob;
typedef void (*splat_fn)(const struct gjob *J, gtile *T);

typedef struct gjob {
    const gconf *G;
    /* blocks of the emission region */
    int bx0, by0, nbx, nby;
    gblock *blocks;
    int *row_ok;
    /* tiles of the window */
    nprfx_rect window;
    int tile, ntx, nty, reach;
    splat_fn splat;
    nprfx_image *out;
    int *tile_ok;
    long long *t_kernels, *t_evals;
    double *t_w2;
    /* per-worker scratch (a parallel_for's worker index is unique among its running chunks):
     * allocated once per render, not per block row or tile */
    int nworkers;
    void **scratch;
    /* the window's depth and id as the visibility tests read them (0 and NaN where there is no
     * surface), written by emission from its strips: splatting then does not read the plates
     * again */
    float *zwin, *idwin;
} gjob;

#if GABOR_VEC
/* row_scalar 8 samples at a time (the baseline ISA's vectors: SSE2, NEON) */
static void row_vec(float *restrict acc, const float *restrict zt, const float *restrict idt,
                    const float *restrict cx, const float *restrict sx, const row_job *R);
#endif

/* The scalar splat of a tile's kernels: the reference every vector path reproduces bit for bit.
 * Per kernel: the disk's span on each row the tile holds, the factor tables (from the kernel's
 * own first sample, whatever the tile), then the rows (vrow: with row_vec). */
GABOR_BODY void splat_points_sbody(const gjob *J, gtile *T, const int vrow)
{
    const gconf *G = J->G;
    int s = G->ss;
    int TX0 = T->TX0, TY0 = T->TY0, TX1 = T->TX1, TY1 = T->TY1, W = T->W, tabn = T->tabn;
    float *CX = T->tab, *SX = T->tab + tabn, *CY = T->tab + 2 * tabn, *SY = T->tab + 3 * tabn;
    int *span = T->span;
    double r2 = G->r2;
    row_job R;
    R.mode = G->dtest;
    for (int by = T->bya; by <= T->byb; by++)
        for (int bx = T->bxa; bx <= T->bxb; bx++) {
            const gblock *b = &J->blocks[(by - J->by0) * J->nbx + (bx - J->bx0)];
            for (int k = 0; k < b->n; k++) {
                const gpoint *p = &b->p[k];
                if (p->X1 < TX0 || p->X0 >= TX1 || p->Y1 < TY0 || p->Y0 >= TY1) continue;
                double sx = p->sx, sy = p->sy;
                int xe = p->X1 < TX1 - 1 ? p->X1 : TX1 - 1, ye = p->Y1 < TY1 - 1 ? p->Y1 : TY1 - 1;
                int ya = p->Y0 > TY0 ? p->Y0 : TY0;
                int rows = 0;
                for (int Y = ya; Y <= ye; Y++) {
                    double dy = sample_pos(Y, s) - sy, h2 = r2 - dy * dy;
                    int xa = p->X1 + 1, xb = p->X1;
                    if (h2 >= 0.0) {
                        double hw = sqrt(h2);
                        xa = iceil((sx - hw + 0.5) * s - 0.5);
                        xb = ifloor((sx + hw + 0.5) * s - 0.5);
                        if (xa < p->X0) xa = p->X0;
                        if (xb > p->X1) xb = p->X1;
                        if (xa < TX0) xa = TX0;
                        if (xb > TX1 - 1) xb = TX1 - 1;
                        rows += xa <= xb;
                    }
                    span[2 * (Y - ya)] = xa;
                    span[2 * (Y - ya) + 1] = xb;
                }
                if (!rows) continue;
                kernel_tables(&p->ax, &p->ay, G->rr, xe - p->X0 + 1, ye - p->Y0 + 1, CX, SX, CY,
                              SY);
                R.idk = p->id;
                R.gx = (float)(p->gzx / s);
                double zx0 = p->z + p->gzx * (sample_pos(p->X0, s) - sx);
                double tolz = G->tol * p->z;
                R.tol = G->dtest == NPRFX_GABOR_DEPTH_SOFT ? (float)(tolz > 0.0 ? 1.0 / tolz : 1e30)
                                                           : (float)tolz;
                for (int Y = ya; Y <= ye; Y++) {
                    int xa = span[2 * (Y - ya)], xb = span[2 * (Y - ya) + 1];
                    if (xa > xb) continue;
                    R.n = xb - xa + 1;
                    R.i0 = xa - p->X0;
                    R.A = p->amp * CY[Y - p->Y0];
                    R.B = p->amp * SY[Y - p->Y0];
                    R.zr = (float)(zx0 + p->gzy * (sample_pos(Y, s) - sy));
                    size_t o = (size_t)(Y - TY0) * (size_t)W + (size_t)(xa - TX0);
                    T->evals += R.n;
#if GABOR_VEC
                    if (vrow)
                        row_vec(T->acc + o, T->zt + o, T->idt + o, CX + R.i0, SX + R.i0, &R);
                    else
#endif
                        row_scalar(T->acc + o, T->zt + o, T->idt + o, CX + R.i0, SX + R.i0, &R);
                }
            }
        }
}

static void splat_points_scalar(const gjob *J, gtile *T)
{
    splat_points_sbody(J, T, 0);
}

/* The vector splat: the same operations as the scalar path, lane by lane, in GCC/Clang vector
 * extensions (compiled once for the baseline ISA and, on x86-64, again for AVX2 and AVX-512,
 * picked at run time). A kernel's row spans and row depths are computed 8 rows at a time (in
 * double, as the scalar path: sqrt, division and truncation are exact IEEE operations, so
 * every lane rounds as the scalar code does); the factor-table recurrences of SPLAT_BATCH
 * kernels run in the lanes of one vector (x axes in the low lanes, y axes in the high ones),
 * which hides their dependency chains; the kernels are then added in their order, rows of 8
 * samples at a time with the last vector masked. */
#define SPLAT_BATCH 4

#if GABOR_VEC
/* iceil / ifloor lane by lane: truncation, then the same comparison as the scalar code */
GV_INLINE gv8i gv_iceil_(const gv8d *pv)
{
    gv8d v = *pv;
    gv8i i = __builtin_convertvector(v, gv8i);
    return i - gv_mask(v > __builtin_convertvector(i, gv8d));
}

GV_INLINE gv8i gv_ifloor_(const gv8d *pv)
{
    gv8d v = *pv;
    gv8i i = __builtin_convertvector(v, gv8i);
    return i + gv_mask(v < __builtin_convertvector(i, gv8d));
}

#define gv_maxi(a, b) gv_seli((a) < (b), (b), (a))
#define gv_mini(a, b) gv_seli((a) > (b), (b), (a))

/* One batched kernel: its point, rows and tables. */
typedef struct gslot {
    const gpoint *p;
    int ya, ye, xe;
    int *xa, *xb;
    float *zr, *CX, *SX, *CY, *SY;
} gslot;

/* The spans and row depths of kernel p on rows ya..ye of the tile; returns the number of rows
 * with samples. As splat_points_scalar, lane by lane. */
/* The spans and row depths of kernel p on rows ya..ye of the tile, 8 rows at a time (AVX-512:
 * 32 vector registers hold the double vectors). */
GV_INLINE int gv_spans8(const gconf *G, const gpoint *p, const gtile *T, gslot *sl)
{
    const gv8d lane = {0, 1, 2, 3, 4, 5, 6, 7};
    const gv8i lanei = {0, 1, 2, 3, 4, 5, 6, 7};
    int s = G->ss;
    double sx = p->sx, sy = p->sy, r2 = G->r2, ds = (double)s;
    double zx0 = p->z + p->gzx * (sample_pos(p->X0, s) - sx), gzy = p->gzy;
    gv8i X0 = p->X0 + (gv8i){0}, X1 = p->X1 + (gv8i){0};
    gv8i tx0 = T->TX0 + (gv8i){0}, tx1 = (T->TX1 - 1) + (gv8i){0};
    gv8i cnt = {0};
    for (int Y = sl->ya; Y <= sl->ye; Y += 8) {
        gv8d sp = (double)Y + lane;
        if (s != 1) sp = (sp + 0.5) / ds - 0.5; /* sample_pos (for s = 1, the identity) */
        gv8d dy = sp - sy, h2 = r2 - dy * dy;
        gv8l ok = h2 >= 0.0;
        gv8d hw = gv_sqrt(gv_seld(ok, h2, (gv8d){0}));
        gv8d va = sx - hw + 0.5, vb = sx + hw + 0.5;
        if (s != 1) {
            va = va * ds;
            vb = vb * ds;
        }
        gv8i xa = gv_iceil(va - 0.5), xb = gv_ifloor(vb - 0.5);
        xa = gv_maxi(gv_maxi(xa, X0), tx0);
        xb = gv_mini(gv_mini(xb, X1), tx1);
        gv8i oki = __builtin_convertvector(ok, gv8i);
        xa = gv_seli(oki, xa, X1 + 1);
        xb = gv_seli(oki, xb, X1);
        gv8i in = (Y + lanei) <= sl->ye;
        cnt += in & (xa <= xb);
        gv_storei(sl->xa + (Y - sl->ya), xa);
        gv_storei(sl->xb + (Y - sl->ya), xb);
        gv_storef(sl->zr + (Y - sl->ya), __builtin_convertvector(zx0 + gzy * (sp - sy), gv8f));
    }
    int rows = 0;
    for (int k = 0; k < 8; k++)
        rows -= cnt[k];
    return rows;
}

GV_INLINE int gv_spans(const gconf *G, const gpoint *p, const gtile *T, gslot *sl)
{
    /* 4 rows at a time: the double vectors stay in registers on AVX2 too */
    const gv4d lane = {0, 1, 2, 3};
    const gv4i lanei = {0, 1, 2, 3};
    int s = G->ss;
    double sx = p->sx, sy = p->sy, r2 = G->r2, ds = (double)s;
    double zx0 = p->z + p->gzx * (sample_pos(p->X0, s) - sx), gzy = p->gzy;
    gv4i X0 = p->X0 + (gv4i){0}, X1 = p->X1 + (gv4i){0};
    gv4i tx0 = T->TX0 + (gv4i){0}, tx1 = (T->TX1 - 1) + (gv4i){0};
    gv4i cnt = {0};
    for (int Y = sl->ya; Y <= sl->ye; Y += 4) {
        gv4d sp = (double)Y + lane;
        if (s != 1) sp = (sp + 0.5) / ds - 0.5; /* sample_pos (for s = 1, the identity) */
        gv4d dy = sp - sy, h2 = r2 - dy * dy;
        gv4l ok = h2 >= 0.0;
        gv4d hw = gv_sqrt4((gv4d)((gv4l)h2 & ok));
        gv4d va = sx - hw + 0.5, vb = sx + hw + 0.5;
        if (s != 1) {
            va = va * ds;
            vb = vb * ds;
        }
        va = va - 0.5;
        vb = vb - 0.5;
        /* iceil / ifloor lane by lane: truncation, then the scalar code's comparison */
        gv4i xa = __builtin_convertvector(va, gv4i), xb = __builtin_convertvector(vb, gv4i);
        xa -= __builtin_convertvector(va > __builtin_convertvector(xa, gv4d), gv4i);
        xb += __builtin_convertvector(vb < __builtin_convertvector(xb, gv4d), gv4i);
        xa = gv4_maxi(gv4_maxi(xa, X0), tx0);
        xb = gv4_mini(gv4_mini(xb, X1), tx1);
        gv4i oki = __builtin_convertvector(ok, gv4i);
        xa = (xa & oki) | ((X1 + 1) & ~oki);
        xb = (xb & oki) | (X1 & ~oki);
        cnt += ((Y + lanei) <= sl->ye) & (xa <= xb);
        memcpy(sl->xa + (Y - sl->ya), &xa, sizeof xa);
        memcpy(sl->xb + (Y - sl->ya), &xb, sizeof xb);
        gv4f zr = __builtin_convertvector(zx0 + gzy * (sp - sy), gv4f);
        memcpy(sl->zr + (Y - sl->ya), &zr, sizeof zr);
    }
    return -(cnt[0] + cnt[1] + cnt[2] + cnt[3]);
}

/* The factor tables of nb <= SPLAT_BATCH kernels, the recurrences of kernel_tables in the lanes
 * of two vectors (x and y axes). */
GV_INLINE void gv_tables(const gconf *G, gslot *sl, int nb)
{
    gv4d gx = {0}, rx = {0}, cx = {0}, sx = {0}, csx = {0}, ssx = {0};
    gv4d gy = {0}, ry = {0}, cy = {0}, sy = {0}, csy = {0}, ssy = {0};
    int n = 0;
    for (int k = 0; k < nb; k++) {
        const gpoint *p = sl[k].p;
        gx[k] = p->ax.g, rx[k] = p->ax.r, cx[k] = p->ax.c, sx[k] = p->ax.s;
        csx[k] = p->ax.cs, ssx[k] = p->ax.ss;
        gy[k] = p->ay.g, ry[k] = p->ay.r, cy[k] = p->ay.c, sy[k] = p->ay.s;
        csy[k] = p->ay.cs, ssy[k] = p->ay.ss;
        int nx = sl[k].xe - p->X0 + 1, ny = sl[k].ye - p->Y0 + 1;
        if (nx > n) n = nx;
        if (ny > n) n = ny;
    }
    double rr = G->rr;
    for (int i = 0; i < n; i++) {
        gv4f gcx = __builtin_convertvector(gx * cx, gv4f),
             gsx = __builtin_convertvector(gx * sx, gv4f);
        gv4f gcy = __builtin_convertvector(gy * cy, gv4f),
             gsy = __builtin_convertvector(gy * sy, gv4f);
        for (int k = 0; k < SPLAT_BATCH; k++) {
            if (k >= nb) break;
            sl[k].CX[i] = gcx[k];
            sl[k].SX[i] = gsx[k];
            sl[k].CY[i] = gcy[k];
            sl[k].SY[i] = gsy[k];
        }
        gx = gx * rx;
        rx = rx * rr;
        gy = gy * ry;
        ry = ry * rr;
        gv4d tx = cx * csx - sx * ssx, ty = cy * csy - sy * ssy;
        sx = sx * csx + cx * ssx;
        sy = sy * csy + cy * ssy;
        cx = tx;
        cy = ty;
    }
}

/* Add the rows of one batched kernel to the tile, as row_scalar does. */
/* One vector of a kernel row: 8 samples, the lanes in m (a constant depth-test mode) */
typedef struct gv_rowc {
    gv8f va, vb, vid, vzr, vgx, vtol; /* a row's constants, broadcast */
} gv_rowc;

GV_INLINE void gv_row8(float *acc, const float *zt, const float *idt, const float *cx,
                       const float *sx, const gv_rowc *R, const gv8f *pvi, const gv8i *pm,
                       const int mode)
{
    gv8f va = R->va, vb = R->vb, vid = R->vid, vzr = R->vzr, vgx = R->vgx, vtol = R->vtol;
    gv8f vi = *pvi;
    gv8i m = *pm;
    const gv8i sign = (gv8i){0} + (int32_t)0x7fffffff;
    const gv8f one = (gv8f){0} + 1.0f, two = (gv8f){0} + 2.0f, zero = {0};
    gv8f v = va * gv_loadf(cx) - vb * gv_loadf(sx);
    m &= gv_loadf(idt) == vid;
    if (mode != NPRFX_GABOR_DEPTH_OFF) {
        gv8f zp = vzr + vgx * vi;
        gv8f dz = (gv8f)((gv8i)(gv_loadf(zt) - zp) & sign);
        if (mode == NPRFX_GABOR_DEPTH_HARD) {
            m &= dz <= vtol;
        } else {
            gv8f t = two - dz * vtol;
            t = gv_self(t > zero, t, zero);
            t = gv_self(t < one, t, one);
            v = v * t;
        }
    }
    gv_storef(acc, gv_loadf(acc) + gv_self(m, v, zero));
}

GV_INLINE void gv_rows(const gconf *G, const gslot *sl, gtile *T, const int mode)
{
    const gpoint *p = sl->p;
    const gv8f lanef = {0, 1, 2, 3, 4, 5, 6, 7};
    const gv8i lanei = {0, 1, 2, 3, 4, 5, 6, 7};
    int s = G->ss;
    float gx = (float)(p->gzx / s);
    double tolz = G->tol * p->z;
    float tol =
        mode == NPRFX_GABOR_DEPTH_SOFT ? (float)(tolz > 0.0 ? 1.0 / tolz : 1e30) : (float)tolz;
    gv8f zero = {0};
    gv_rowc R;
    R.vid = p->id + zero;
    R.vgx = gx + zero;
    R.vtol = tol + zero;
    long long evals = 0;
    for (int Y = sl->ya; Y <= sl->ye; Y++) {
        int xa = sl->xa[Y - sl->ya], xb = sl->xb[Y - sl->ya];
        if (xa > xb) continue;
        int n = xb - xa + 1, i0 = xa - p->X0;
        float A = p->amp * sl->CY[Y - p->Y0], B = p->amp * sl->SY[Y - p->Y0];
        R.va = A + zero;
        R.vb = B + zero;
        R.vzr = sl->zr[Y - sl->ya] + zero;
        size_t o = (size_t)(Y - T->TY0) * (size_t)T->W + (size_t)(xa - T->TX0);
        float *acc = T->acc + o;
        const float *zt = T->zt + o, *idt = T->idt + o;
        const float *cx = sl->CX + i0, *sx = sl->SX + i0;
        gv8f vi = (float)i0 + lanef; /* exact: small integers */
        evals += n;
        int j = 0;
        const gv8i all = (gv8i){0} - 1;
        for (; j + 8 <= n; j += 8, vi = vi + 8.0f)
            gv_row8(acc + j, zt + j, idt + j, cx + j, sx + j, &R, &vi, &all, mode);
        if (j < n) { /* the last partial vector, masked */
            gv8i tail = (j + lanei) < n;
            gv_row8(acc + j, zt + j, idt + j, cx + j, sx + j, &R, &vi, &tail, mode);
        }
    }
    T->evals += evals;
}

GV_INLINE void splat_points_body(const gjob *J, gtile *T, const int mode, const int wide)
{
    const gconf *G = J->G;
    int TX0 = T->TX0, TY0 = T->TY0, TX1 = T->TX1, TY1 = T->TY1, tabn = T->tabn;
    gslot sl[SPLAT_BATCH];
    for (int k = 0; k < SPLAT_BATCH; k++) {
        float *t = T->tab + (size_t)k * 5 * (size_t)tabn;
        sl[k].CX = t;
        sl[k].SX = t + tabn;
        sl[k].CY = t + 2 * tabn;
        sl[k].SY = t + 3 * tabn;
        sl[k].zr = t + 4 * tabn;
        sl[k].xa = T->span + (size_t)k * 2 * (size_t)tabn;
        sl[k].xb = sl[k].xa + tabn;
    }
    int nb = 0;
    for (int by = T->bya; by <= T->byb; by++)
        for (int bx = T->bxa; bx <= T->bxb; bx++) {
            const gblock *b = &J->blocks[(by - J->by0) * J->nbx + (bx - J->bx0)];
            for (int k = 0; k < b->n; k++) {
                const gpoint *p = &b->p[k];
                if (p->X1 < TX0 || p->X0 >= TX1 || p->Y1 < TY0 || p->Y0 >= TY1) continue;
                gslot *q = &sl[nb];
                q->p = p;
                q->xe = p->X1 < TX1 - 1 ? p->X1 : TX1 - 1;
                q->ye = p->Y1 < TY1 - 1 ? p->Y1 : TY1 - 1;
                q->ya = p->Y0 > TY0 ? p->Y0 : TY0;
                if (!(wide ? gv_spans8(G, p, T, q) : gv_spans(G, p, T, q))) continue;
                if (++nb < SPLAT_BATCH) continue;
                gv_tables(G, sl, nb);
                for (int m = 0; m < nb; m++)
                    gv_rows(G, &sl[m], T, mode);
                nb = 0;
            }
        }
    if (nb) {
        gv_tables(G, sl, nb);
        for (int m = 0; m < nb; m++)
            gv_rows(G, &sl[m], T, mode);
    }
}

/* (4 lanes: the baseline ISA's native vector width, so that no operation is split lane by
 * lane) */
static void row_vec(float *restrict acc, const float *restrict zt, const float *restrict idt,
                    const float *restrict cx, const float *restrict sx, const row_job *R)
{
    const gv4i lane = {0, 1, 2, 3}, sign = (gv4i){0} + (int32_t)0x7fffffff;
    const gv4f one = (gv4f){0} + 1.0f, two = (gv4f){0} + 2.0f, zero = {0};
    gv4f va = R->A + zero, vb = R->B + zero, vid = R->idk + zero;
    gv4f vzr = R->zr + zero, vgx = R->gx + zero, vtol = R->tol + zero;
    gv4f vi = (float)R->i0 + __builtin_convertvector(lane, gv4f); /* exact: small integers */
    int n = R->n;
    for (int j = 0; j < n; j += 4, vi = vi + 4.0f) {
        gv4f c, s_, z, d, a;
        memcpy(&c, cx + j, sizeof c);
        memcpy(&s_, sx + j, sizeof s_);
        memcpy(&d, idt + j, sizeof d);
        gv4f v = va * c - vb * s_;
        gv4i m = (d == vid) & ((j + lane) < n);
        if (R->mode != NPRFX_GABOR_DEPTH_OFF) {
            memcpy(&z, zt + j, sizeof z);
            gv4f dz = (gv4f)((gv4i)(z - (vzr + vgx * vi)) & sign);
            if (R->mode == NPRFX_GABOR_DEPTH_HARD) {
                m &= dz <= vtol;
            } else {
                gv4f t = two - dz * vtol;
                gv4i up = t > zero, lo = t < one;
                t = (gv4f)((gv4i)t & up);                       /* t > 0 ? t : 0 */
                t = (gv4f)(((gv4i)t & lo) | ((gv4i)one & ~lo)); /* t < 1 ? t : 1 */
                v = v * t;
            }
        }
        memcpy(&a, acc + j, sizeof a);
        a = a + (gv4f)((gv4i)v & m);
        memcpy(acc + j, &a, sizeof a);
    }
}

/* The baseline ISA's path: the scalar spans and tables, vector rows. */
static void splat_points_rows(const gjob *J, gtile *T)
{
    splat_points_sbody(J, T, 1);
}

#if GABOR_X86
__attribute__((target("avx2"))) static void splat_points_avx2(const gjob *J, gtile *T)
{
    switch (J->G->dtest) {
    case NPRFX_GABOR_DEPTH_OFF:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_OFF, 0);
        break;
    case NPRFX_GABOR_DEPTH_HARD:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_HARD, 0);
        break;
    default:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_SOFT, 0);
        break;
    }
}

__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))) static void
splat_points_avx512(const gjob *J, gtile *T)
{
    switch (J->G->dtest) {
    case NPRFX_GABOR_DEPTH_OFF:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_OFF, 1);
        break;
    case NPRFX_GABOR_DEPTH_HARD:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_HARD, 1);
        break;
    default:
        splat_points_body(J, T, NPRFX_GABOR_DEPTH_SOFT, 1);
        break;
    }
}
#endif
#endif /* GABOR_VEC */

/* simd: 0 the fastest path, 1 scalar, 2 the baseline ISA's vectors, 3 AVX2 (as 2 without it) */
static splat_fn pick_splat_fn(int simd)
{
#if GABOR_VEC
    if (simd == 1) return splat_points_scalar;
#if GABOR_X86
    if (simd == 0 && cpu_avx512()) return splat_points_avx512;
    if ((simd == 0 || simd == 3) && cpu_avx2()) return splat_points_avx2;
#endif
    return splat_points_rows;
#else
    (void)simd;
    return splat_points_scalar;
#endif
}

static int floor_div(int a, int b)
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/* The rows [y0, y1) of the window's depth and id planes, from the strip (which holds every
 * pixel of them inside the inputs). */
static void window_rows(const gjob *J, const gstrip *T, int y0, int y1)
{
    const gsrc *S = &J->G->S;
    nprfx_rect w = J->window, reg = S->region;
    int ww = nprfx_rect_width(w);
    const float nan = nanf("");
    if (y0 < w.y0) y0 = w.y0;
    if (y1 > w.y1) y1 = w.y1;
    /* the window's columns inside the inputs */
    int xa = w.x0 > reg.x0 ? w.x0 : reg.x0, xb = w.x1 < reg.x1 ? w.x1 : reg.x1;
    for (int y = y0; y < y1; y++) {
        float *zr = J->zwin + (size_t)(y - w.y0) * (size_t)ww - w.x0;
        float *ir = J->idwin + (size_t)(y - w.y0) * (size_t)ww - w.x0;
        int in = y >= reg.y0 && y < reg.y1 && xa < xb;
        for (int x = w.x0; x < w.x1; x++) {
            zr[x] = 0.0f;
            ir[x] = nan;
        }
        if (!in) continue;
        const float *Z = strip_plane(T, ST_Z, xa, y) - xa, *ID = strip_plane(T, ST_ID, xa, y) - xa;
        for (int x = xa; x < xb; x++) {
            double zz = Z[x];
            float ii = ID[x];
            if (is_surface_depth(zz) && isfinite(ii)) {
                zr[x] = (float)zz;
                ir[x] = ii;
            }
        }
    }
}

static void emit_rows(void *user, int begin, int end, int worker)
{
    gjob *J = user;
    emit_scratch *scr = J->scratch[worker];
    for (int r = begin; r < end; r++) {
        /* the inputs the row's windows read (a window depends on the block row only in y, and
         * grows with the block column in x) */
        int cx0, cy0, cw, ch, lx0, ly0, lw, lh;
        if (block_window(&J->G->S, J->bx0, J->by0 + r, &cx0, &cy0, &cw, &ch) &&
            block_window(&J->G->S, J->bx0 + J->nbx - 1, J->by0 + r, &lx0, &ly0, &lw, &lh))
            strip_fill(&J->G->S, &scr->T, cx0, lx0 + lw, cy0, cy0 + ch);
        else
            scr->T.w = scr->T.h = 0;
        window_rows(J, &scr->T, (J->by0 + r) * BLOCK, (J->by0 + r + 1) * BLOCK);
        int ok = 1;
        for (int i = 0; i < J->nbx && ok; i++)
            ok = J->G->emit(J->G, J->bx0 + i, J->by0 + r, &J->blocks[r * J->nbx + i], scr);
        J->row_ok[r] = ok;
    }
}

/* A splat worker's buffers, for tiles of up to J->tile x J->tile pixels. */
typedef struct splat_scratch {
    float *acc, *zt, *idt, *tab;
    int *span;
} splat_scratch;

static size_t splat_tabn(const gjob *J)
{
    return (size_t)ceil(2.0 * J->G->radius * J->G->ss) + 4 + VPAD;
}

static size_t splat_npx(const gjob *J)
{
    size_t w = (size_t)J->tile * (size_t)J->G->ss;
    return w * w + VPAD;
}

static void splat_scratch_free(splat_scratch *b)
{
    if (!b) return;
    free(b->acc);
    free(b->zt);
    free(b->idt);
    free(b->tab);
    free(b->span);
    free(b);
}

static splat_scratch *splat_scratch_new(const gjob *J)
{
    splat_scratch *b = calloc(1, sizeof *b);
    if (!b) return NULL;
    size_t npx = splat_npx(J), tabn = splat_tabn(J);
    b->acc = malloc(sizeof(float) * npx);
    b->zt = malloc(sizeof(float) * npx);
    b->idt = malloc(sizeof(float) * npx);
    b->tab = calloc(SPLAT_BATCH * 5 * tabn, sizeof(float));
    b->span = calloc(SPLAT_BATCH * 2 * tabn, sizeof(int));
    if (!b->acc || !b->zt || !b->idt || !b->tab || !b->span) {
        splat_scratch_free(b);
        return NULL;
    }
    return b;
}

static void splat_tile(gjob *J, int t, splat_scratch *B)
{
    const gconf *G = J->G;
    const gsrc *S = &G->S;
    int s = G->ss;
    int tx0 = J->window.x0 + (t % J->ntx) * J->tile, ty0 = J->window.y0 + (t / J->ntx) * J->tile;
    int tx1 = tx0 + J->tile < J->window.x1 ? tx0 + J->tile : J->window.x1;
    int ty1 = ty0 + J->tile < J->window.y1 ? ty0 + J->tile : J->window.y1;
    int W = (tx1 - tx0) * s, H = (ty1 - ty0) * s;
    int TX0 = tx0 * s, TY0 = ty0 * s, TX1 = tx1 * s, TY1 = ty1 * s; /* sample coordinates */
    int tabn = (int)splat_tabn(J);
    size_t npx = (size_t)W * (size_t)H + VPAD;
    float *acc = B->acc, *zt = B->zt, *idt = B->idt, *tab = B->tab;
    int *span = B->span;
    memset(acc, 0, sizeof(float) * npx);
    const float nan = nanf("");
    size_t ww = (size_t)nprfx_rect_width(J->window);
    for (int y = ty0; y < ty1; y++) {
        size_t wo = (size_t)(y - J->window.y0) * ww + (size_t)(tx0 - J->window.x0);
        const float *zr = J->zwin + wo, *ir = J->idwin + wo;
        if (s == 1) {
            memcpy(zt + (size_t)(y - ty0) * (size_t)W, zr, sizeof(float) * (size_t)(tx1 - tx0));
            memcpy(idt + (size_t)(y - ty0) * (size_t)W, ir, sizeof(float) * (size_t)(tx1 - tx0));
            continue;
        }
        for (int x = tx0; x < tx1; x++)
            for (int j = 0; j < s; j++)
                for (int i = 0; i < s; i++) {
                    size_t o =
                        (size_t)((y - ty0) * s + j) * (size_t)W + (size_t)((x - tx0) * s + i);
                    zt[o] = zr[x - tx0];
                    idt[o] = ir[x - tx0];
                }
    }
    for (size_t i = npx - VPAD; i < npx; i++) {
        zt[i] = 0.0f;
        idt[i] = nan;
    }
    long long kernels = 0;
    double w2sum = 0.0;
    gtile T;
    T.acc = acc;
    T.zt = zt;
    T.idt = idt;
    T.W = W;
    T.TX0 = TX0;
    T.TY0 = TY0;
    T.TX1 = TX1;
    T.TY1 = TY1;
    T.tabn = tabn;
    T.tab = tab;
    T.span = span;
    T.evals = 0;
    T.bxa = floor_div(tx0 - J->reach, BLOCK), T.bxb = floor_div(tx1 - 1 + J->reach, BLOCK);
    T.bya = floor_div(ty0 - J->reach, BLOCK), T.byb = floor_div(ty1 - 1 + J->reach, BLOCK);
    if (T.bxa < J->bx0) T.bxa = J->bx0;
    if (T.bya < J->by0) T.bya = J->by0;
    if (T.bxb > J->bx0 + J->nbx - 1) T.bxb = J->bx0 + J->nbx - 1;
    if (T.byb > J->by0 + J->nby - 1) T.byb = J->by0 + J->nby - 1;
    J->splat(J, &T);
    /* normalise and write */
    double inv_ss = 1.0 / ((double)s * s);
    double sigma0 = sqrt(G->var_k1 * (1.0 + exp(-2.0 * k_pi * G->F0 * G->F0 / (G->a * G->a))));
    for (int y = ty0; y < ty1; y++)
        for (int x = tx0; x < tx1; x++) {
            float *o = nprfx_image_at(J->out, x, y);
            double sum = 0.0;
            for (int j = 0; j < s; j++)
                for (int i = 0; i < s; i++)
                    sum +=
                        acc[(size_t)((y - ty0) * s + j) * (size_t)W + (size_t)((x - tx0) * s + i)];
            double sigma = sigma0;
            if (S->freq) {
                double F = G->F0 * sample_input(S->freq, x, y, 0, 1.0f);
                sigma = sqrt(G->var_k1 * (1.0 + exp(-2.0 * k_pi * F * F / (G->a * G->a))));
            }
            double v = sum * inv_ss / sigma;
            if (G->output == NPRFX_GABOR_OUT_UNIT01) v = 0.5 + G->contrast * v;
            o[0] = (float)v;
            if (G->points) o[1] = 0.0f;
        }
    /* owned points: the debug channel and the statistics */
    int cbxa = floor_div(tx0, BLOCK), cbxb = floor_div(tx1 - 1, BLOCK);
    int cbya = floor_div(ty0, BLOCK), cbyb = floor_div(ty1 - 1, BLOCK);
    for (int by = cbya; by <= cbyb; by++)
        for (int bx = cbxa; bx <= cbxb; bx++) {
            const gblock *b = &J->blocks[(by - J->by0) * J->nbx + (bx - J->bx0)];
            for (int k = 0; k < b->n; k++) {
                const gpoint *p = &b->p[k];
                if (p->ox < tx0 || p->ox >= tx1 || p->oy < ty0 || p->oy >= ty1) continue;
                kernels++;
                w2sum += p->w2;
                if (G->points) nprfx_image_at(J->out, p->ox, p->oy)[1] += p->w2;
            }
        }
    J->t_kernels[t] = kernels;
    J->t_evals[t] = T.evals;
    J->t_w2[t] = w2sum;
    J->tile_ok[t] = 1;
}

static void splat_tiles(void *user, int begin, int end, int worker)
{
    gjob *J = user;
    for (int t = begin; t < end; t++)
        splat_tile(J, t, J->scratch[worker]);
}

nprfx_result nprfx_gabor_render(nprfx_context *ctx, const nprfx_gabor_params *p,
                                const nprfx_gabor_inputs *in, nprfx_rect window, nprfx_image *out,
                                nprfx_gabor_stats *stats)
{
    if (stats) memset(stats, 0, sizeof *stats);
    if (!p || p->size < sizeof *p || !in || in->size < sizeof *in || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "gabor: incomplete arguments");
    if (!in->anchor || !in->anchor->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "gabor: input 'anchor' is missing");
    if (!in->depth || !in->depth->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "gabor: input 'depth' is missing");
    if (p->anchor_dims != 2 && p->anchor_dims != 3)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor: anchor_dims is %d; 2 (UV) or 3 (Pref, P) are supported",
                           p->anchor_dims);
    if (in->anchor->channels < p->anchor_dims)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor: input 'anchor' has %d channels; a %dD anchor needs %d",
                           in->anchor->channels, p->anchor_dims, p->anchor_dims);
    if (!(p->frequency > 0.0 && p->frequency <= 1e3))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "gabor: frequency %g is outside (0, 1000] cycles per pixel",
                           p->frequency);
    if (!(p->radius >= 0.25 && p->radius <= 4096))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: radius %g is outside [0.25, 4096]",
                           p->radius);
    if (!(p->n0 > 0.0 && p->n0 <= 1e5))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: n0 %g is outside (0, 100000]",
                           p->n0);
    if (!(p->cell > 0.0 && isfinite(p->cell)))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: cell %g is not positive", p->cell);
    if (p->lod_levels < 1 || p->lod_levels > 30)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: lod_levels %d is outside [1, 30]",
                           p->lod_levels);
    if (p->supersample < 1 || p->supersample > 16)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: supersample %d is outside [1, 16]",
                           p->supersample);
    if (p->depth_test < 0 || p->depth_test >= NPRFX_GABOR_DEPTH_COUNT || p->amplitude < 0 ||
        p->fade < 0 || p->fade >= NPRFX_GABOR_FADE_COUNT || p->amplitude >= NPRFX_GABOR_AMP_COUNT ||
        p->output < 0 || p->output >= NPRFX_GABOR_OUT_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "gabor: depth_test, amplitude, fade or "
                           "output is not a known choice");
    if (!(p->depth_tolerance >= 0.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "gabor: depth_tolerance %g is negative",
                           p->depth_tolerance);
    if (out->channels != 1 + (p->points != 0))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor: the output has %d channels, expected %d", out->channels,
                           1 + (p->points != 0));
    window = nprfx_rect_intersect(window, out->bounds);
    if (nprfx_rect_empty(window)) return NPRFX_OK;

    gconf G;
    memset(&G, 0, sizeof G);
    G.S.anchor = in->anchor;
    G.S.depth = in->depth;
    G.S.id = in->id && in->id->data ? in->id : NULL;
    G.S.orient = in->orientation && in->orientation->data ? in->orientation : NULL;
    G.S.freq = in->frequency && in->frequency->data ? in->frequency : NULL;
    G.S.dims = p->anchor_dims;
    G.S.cov_ch = in->anchor->channels > p->anchor_dims ? p->anchor_dims : -1;
    G.S.region = nprfx_rect_intersect(in->anchor->bounds, in->depth->bounds);
    if (G.S.id) G.S.region = nprfx_rect_intersect(G.S.region, G.S.id->bounds);
    G.S.step_tol =
        p->depth_tolerance > MIN_STEP_TOLERANCE ? p->depth_tolerance : MIN_STEP_TOLERANCE;
    G.a = nprfx_gabor_bandwidth(p->radius);
    G.radius = p->radius;
    G.r2 = p->radius * p->radius;
    G.lambda = p->n0 / (k_pi * G.r2);
    G.h0 = p->cell;
    G.F0 = p->frequency;
    G.w0 = p->orientation * (k_pi / 180.0);
    G.tol = p->depth_tolerance;
    G.W = p->lod_levels;
    G.stagger = p->fade == NPRFX_GABOR_FADE_STAGGERED;
    G.dims = p->anchor_dims;
    G.ss = p->supersample;
    G.iso = p->isotropic != 0;
    G.amp = p->amplitude;
    G.dtest = p->depth_test;
    G.points = p->points != 0;
    G.output = p->output;
    G.contrast = p->contrast;
    G.seed = p->seed;
    G.var_k1 = variance_k1(p, G.a);
    lod_table_init(&G.lod, G.W);
    G.pa2 = k_pi * G.a * G.a;
    G.lh2 = G.lambda * G.h0 * G.h0;
    G.emit = pick_emit_fn(p->simd);
    G.step_tolf = (float)G.S.step_tol;
    G.uniform_wave = !G.iso && !G.S.orient && !G.S.freq;
    if (G.uniform_wave) {
        /* as kernel_wave computes it for every point */
        double F = G.F0 * 1.0, step = 1.0 / G.ss;
        G.kx0 = F * cos(G.w0);
        G.ky0 = -F * sin(G.w0);
        G.csx = (float)cos(2.0 * k_pi * G.kx0 * step);
        G.ssx = (float)sin(2.0 * k_pi * G.kx0 * step);
        G.csy = (float)cos(2.0 * k_pi * G.ky0 * step);
        G.ssy = (float)sin(2.0 * k_pi * G.ky0 * step);
    }
    G.rr = exp(-2.0 * G.pa2 / ((double)G.ss * G.ss));

    gjob J;
    memset(&J, 0, sizeof J);
    J.G = &G;
    J.window = window;
    J.out = out;
    /* an owner lies within r + 1/2 of its point, a sample within 1/2 of its pixel centre */
    J.reach = (int)ceil(p->radius) + 1;
    J.bx0 = floor_div(window.x0 - J.reach, BLOCK);
    J.by0 = floor_div(window.y0 - J.reach, BLOCK);
    J.nbx = floor_div(window.x1 - 1 + J.reach, BLOCK) - J.bx0 + 1;
    J.nby = floor_div(window.y1 - 1 + J.reach, BLOCK) - J.by0 + 1;
    J.tile = TILE_SAMPLES / p->supersample > 32 ? TILE_SAMPLES / p->supersample : 32;
    J.splat = pick_splat_fn(p->simd);
    J.ntx = (nprfx_rect_width(window) + J.tile - 1) / J.tile;
    J.nty = (nprfx_rect_height(window) + J.tile - 1) / J.tile;
    int ntiles = J.ntx * J.nty;
    J.blocks = calloc((size_t)J.nbx * (size_t)J.nby, sizeof(gblock));
    J.row_ok = calloc((size_t)J.nby, sizeof(int));
    J.tile_ok = calloc((size_t)ntiles, sizeof(int));
    J.t_kernels = calloc((size_t)ntiles, sizeof(long long));
    J.t_evals = calloc((size_t)ntiles, sizeof(long long));
    J.t_w2 = calloc((size_t)ntiles, sizeof(double));
    nprfx_result r = NPRFX_OK;
    if (!J.blocks || !J.row_ok || !J.tile_ok || !J.t_kernels || !J.t_evals || !J.t_w2) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory");
        goto done;
    }
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    size_t wpx = (size_t)nprfx_rect_width(window) * (size_t)nprfx_rect_height(window);
    J.zwin = malloc(sizeof(float) * wpx);
    J.idwin = malloc(sizeof(float) * wpx);
    if (!J.zwin || !J.idwin) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory");
        goto done;
    }
    J.nworkers = nprfx_executor_workers(ex);
    if (J.nworkers < 1) J.nworkers = 1;
    J.scratch = calloc((size_t)J.nworkers, sizeof(void *));
    int ok = J.scratch != NULL;
    /* a row of blocks reads at most CW input rows, and columns from its first window to its
     * last */
    size_t strip_w = (size_t)J.nbx * BLOCK + 2 * (1 + HALO);
    for (int i = 0; i < J.nworkers && ok; i++) {
        emit_scratch *e = calloc(1, sizeof(emit_scratch)); /* padding rows: zero */
        J.scratch[i] = e;
        ok = e != NULL && (e->T.data = malloc(sizeof(float) * ST_PLANES * CW * strip_w)) != NULL;
    }
    if (ok) nprfx_parallel_for(ex, J.nby, 1, emit_rows, &J);
    for (int i = 0; J.scratch && i < J.nworkers; i++) {
        emit_scratch *e = J.scratch[i];
        if (e) free(e->T.data);
        free(e);
        J.scratch[i] = NULL;
    }
    if (!ok) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory");
        goto done;
    }
    for (int i = 0; i < J.nby; i++)
        if (!J.row_ok[i]) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory for the points");
            goto done;
        }
    for (int i = 0; i < J.nworkers && ok; i++)
        ok = (J.scratch[i] = splat_scratch_new(&J)) != NULL;
    if (!ok) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory for the tiles");
        goto done;
    }
    nprfx_parallel_for(ex, ntiles, 1, splat_tiles, &J);
    for (int t = 0; t < ntiles; t++) {
        if (!J.tile_ok[t]) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory for a tile");
            goto done;
        }
        if (stats) {
            stats->kernels += J.t_kernels[t];
            stats->evaluations += J.t_evals[t];
            stats->weight2 += J.t_w2[t];
        }
    }
done:
    free(J.zwin);
    free(J.idwin);
    if (J.scratch) {
        /* emission's scratch is freed after emission: what is left is the splat's */
        for (int i = 0; i < J.nworkers; i++)
            splat_scratch_free(J.scratch[i]);
        free(J.scratch);
    }
    if (J.blocks)
        for (int i = 0; i < J.nbx * J.nby; i++)
            free(J.blocks[i].p);
    free(J.blocks);
    free(J.row_ok);
    free(J.tile_ok);
    free(J.t_kernels);
    free(J.t_evals);
    free(J.t_w2);
    return r;
}
