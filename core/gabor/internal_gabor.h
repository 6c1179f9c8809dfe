/* Internal to the Gabor noise renderer (core/gabor*.c), never installed: the vector helpers, the
 * constants, the per-block raw data and pixel attributes, the render's configuration, points,
 * tiles and job, the hot helpers every file inlines (the level-of-detail rule among them), and
 * the functions the files share. gabor.c has the model and the order of a render. */
#ifndef NPRFX_INTERNAL_GABOR_H
#define NPRFX_INTERNAL_GABOR_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#define GABOR_SSE 1
#else
#define GABOR_SSE 0
#endif

#include "nprfx/gabor.h"
#include "nprfx/objectid.h"

/* Ids in the gabor planes are canonical (nprfx_id_canonical: one bit pattern an object) and are
 * compared by their bits: a NaN id names an object too, which float == would never match.
 * Pixels with no surface hold NPRFX_ID_NONE, which no emitted point's id is. */
static inline uint32_t id_bits(float id)
{
    uint32_t u;
    memcpy(&u, &id, sizeof u);
    return u;
}

static inline int id_eq(float a, float b)
{
    return id_bits(a) == id_bits(b);
}

static inline float id_none(void)
{
    const uint32_t b = NPRFX_ID_NONE;
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

/* Vector code (docs/design.md §1: output bit-identical whatever the path): GCC/Clang vector
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
typedef uint64_t gv8u __attribute__((vector_size(64)));
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

/* 8 ids as their bits (id_eq lane by lane is ==) */
GV_INLINE gv8i gv_loadid(const float *p)
{
    gv8i v;
    memcpy(&v, p, sizeof v);
    return v;
}

/* an id in every lane, by its bits (arithmetic would quiet a signalling-NaN id) */
GV_INLINE gv8f gv_splatid(float id)
{
    return (gv8f)((gv8i){0} + (int32_t)id_bits(id));
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

/* The instruction set an instance of a body is compiled for (its constant vec argument; nonzero:
 * the vector path): bodies in other files are instantiated for the same one. */
enum { GABOR_ISA_BASE = 0, GABOR_ISA_AVX2 = 1, GABOR_ISA_AVX512 = 2 };

#define BLOCK 32 /* emission blocks: the enumeration of anchor cells is shared by 1024 pixels */
#define PW (BLOCK + 2) /* a block's pixel attributes include a 1-pixel ring, for ownership */
#define HALO 3         /* raw data around those: repair (1) + FD (1) + interior (1) */
#define CACHE_W (PW + 2 * HALO)
#define VPAD 8               /* floats readable past a row's end (masked vector tails) */
#define MAX_LEVEL 40         /* cells h0 / 2^40: far below float anchor precision */
#define BACKGROUND_DEPTH 1e9 /* depth at or above this is background (Blender writes 1e10) */
/* staggered fade: each point's amplitude ramps over STAGGER of the ramp variable x, its start
 * uniform in [0, 1 - STAGGER]; x(q) is tabulated so that E[w^2] = q */
#define STAGGER 0.25
#define STAGGER_N 256

#define SPLAT_BATCH 4 /* kernels whose tables the vector splat computes together */

static const double k_pi = 3.14159265358979323846;

/* ---- level of detail ------------------------------------------------------------------------
 *
 * Level l has one point per cell of size h0 / 2^l: 4^l points per level-0 cell area. mu is the
 * wanted density in those units. In regime L the levels L-W+1..L are whole (weight 1), level
 * L+1 fades in with squared weight f and level L-W fades out with squared weight 1-f, where
 * S(L) = sum_{l=max(0,L-W)}^{L} 4^l <= mu < S(L+1):
 *   L < W (no level to fade out yet): f = (mu - S(L)) / 4^(L+1)   (docs/design.md's rule)
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

/* The ramp variable for a wanted mean squared weight q (the table, interpolated). */
static inline double stagger_x(const double *tab, double q)
{
    double t = q * STAGGER_N;
    int i = (int)t;
    if (i >= STAGGER_N) return 1.0;
    if (i < 0) return 0.0;
    return tab[i] + (t - i) * (tab[i + 1] - tab[i]);
}

static inline double stagger_w2(double x, double u)
{
    double w = (x - u * (1.0 - STAGGER)) * (1.0 / STAGGER);
    w = w < 0.0 ? 0.0 : (w > 1.0 ? 1.0 : w);
    return w * w;
}

static inline void lod_regime(const lod_table *t, double mu, int *L_out, double *f_out)
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

static inline double lod_w2(int L, double f, int W, int l)
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

static inline void lod_range(int L, double f, int W, int *lo, int *hi)
{
    if (L < 0) {
        *lo = 0;
        *hi = f > 0.0 ? 0 : -1;
        return;
    }
    *lo = L - W >= 0 ? (f < 1.0 ? L - W : L - W + 1) : 0;
    *hi = f > 0.0 ? L + 1 : L;
}

/* ---- inputs ---------------------------------------------------------------------------------- */

typedef struct gsrc {
    const nprfx_image *anchor, *depth, *id, *orient, *freq;
    int dims;   /* 2 or 3 */
    int cov_ch; /* coverage channel of the anchor, -1: none */
    nprfx_rect region;
    double step_tol; /* largest relative depth step between neighbours of one surface */
} gsrc;

static inline int is_surface_depth(double z)
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

static inline double dot3(const double *u, const double *v)
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

static inline float *strip_plane(const gstrip *T, int p, int x, int y)
{
    return T->data + ((size_t)(y - T->y0) * ST_PLANES + (size_t)p) * (size_t)T->w + (x - T->x0);
}

/* ---- points ---------------------------------------------------------------------------------- */

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
    int rx, ry;         /* the real pixel whose per-point inputs it reads */
    uint64_t h;         /* its hash (seed, level, cell, object id): the point's own randoms */
    int X0, X1, Y0, Y1; /* first and last samples of the bounding box (sample coordinates) */
    gaxis ax, ay;
} gpoint;

/* Points are stored in chunks, a list per emission worker, each block's points contiguous in
 * one chunk: a block's list used to grow by doubling realloc, four or five allocations and
 * copies per block and frame (a tenth of the render). */
typedef struct gchunk {
    struct gchunk *next;
    int n, cap; /* points used by finished blocks, room */
    gpoint p[];
} gchunk;
#define CHUNK_POINTS 8192

typedef struct gblock {
    gpoint *p; /* in a chunk of its worker's list */
    int n, cap;
} gblock;

static inline double sample_pos(int X, int s)
{
    return (X + 0.5) / s - 0.5;
}

static inline float sample_input(const nprfx_image *im, int x, int y, int ch, float def)
{
    if (!im || !nprfx_rect_contains(im->bounds, x, y)) return def;
    float v = nprfx_image_at(im, x, y)[ch];
    return isfinite(v) ? v : def;
}

/* Two neighbouring pixels lie on one surface patch: same object, no depth step, and anchors
 * no farther apart than about two pixel footprints (not across a UV seam, or two objects
 * sharing an id input that is not connected). */
static inline int patch_link(const gconf *G, const gpixels *X, int a, int b)
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

/* The arguments of a kernel's exp and sincos (internal_gabor_point_begin) */
enum { GABOR_ARG_ENV = 0, GABOR_ARG_PHASE = 4, GABOR_ARG_STEP = 6, GABOR_ARGS = 8 };

/* A worker's emission memory: a block's raw data and pixels, and its row of blocks' inputs. */
typedef struct emit_scratch {
    gcache C;
    gpixels X;
    gstrip T;
    /* vector paths: points whose exp and sincos wait to be computed 8 at a time */
    gpoint pend[8];
    double pargs[GABOR_ARGS][8];
    int npend;
    gchunk **chunks; /* the worker's list of point chunks (the job's, which outlives this) */
} emit_scratch;

/* ---- the render ------------------------------------------------------------------------------ */

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
    gchunk **chunks; /* per worker: its points' chunks, the current one first */
    /* the window's depth and id as the visibility tests read them (0 and NaN where there is no
     * surface), written by emission from its strips: splatting then does not read the plates
     * again */
    float *zwin, *idwin;
} gjob;

/* ---- the functions the files share ----------------------------------------------------------- */

/* gabor_kernel.c */
/* The variance without its frequency-dependent term: var = k1 * (1 + exp(-2 pi F^2 / a^2)). */
double internal_gabor_variance_k1(const nprfx_gabor_params *p, double a);
void internal_gabor_lod_table_init(lod_table *t, int W);
/* Fill a point's screen-space data for a kernel centred at (sx, sy), owned by pixel o; 0 when
 * the surface's depth there is not a surface's. */
int internal_gabor_make_point(const gconf *G, const gpixels *X, int o, int ox, int oy, double sx,
                              double sy, double w2, uint64_t h, float id, gpoint *pt);
/* internal_gabor_make_point in two halves around its exp and sincos, so that the vector paths
 * compute those for 8 points at once (internal_vmath.h: the same numbers): begin fills the
 * point but its axes' factors and leaves in args the arguments of exp (GABOR_ARG_ENV: 4, x
 * then y, envelope and ratio) and of sincos (GABOR_ARG_PHASE: 2, then GABOR_ARG_STEP: 2, used
 * only when the wave varies: !G->uniform_wave); end stores the results (ex[4], and sn, cs for
 * the phases then the steps). */
int internal_gabor_point_begin(const gconf *G, const gpixels *X, int o, int ox, int oy, double sx,
                               double sy, double w2, uint64_t h, float id, gpoint *pt,
                               double *args);
void internal_gabor_point_end(const gconf *G, gpoint *pt, const double *ex, const double *sn,
                              const double *cs);

/* gabor_pixels.c */
/* Pack the inputs of [x0, x1) x [y0, y1) (cut to the region) into the strip T. */
void internal_gabor_strip_fill(const gsrc *S, gstrip *T, int x0, int x1, int y0, int y1);
/* The window of raw data block (bx, by) reads; 0 when there are no inputs. */
int internal_gabor_block_window(const gsrc *S, int bx, int by, int *cx0, int *cy0, int *cw,
                                int *ch);
/* The attributes of block (bx, by)'s pixels and ring in X (raw data through C, from the strip T)
 * and its surface patches (X->comp); returns their count. One instance per instruction set. */
int internal_gabor_block_prepare_scalar(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                        gcache *C);
#if GABOR_X86
__attribute__((target("avx2"))) int internal_gabor_block_prepare_avx2(const gconf *G,
                                                                      const gstrip *T, int bx,
                                                                      int by, gpixels *X,
                                                                      gcache *C);
__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))) int
internal_gabor_block_prepare_avx512(const gconf *G, const gstrip *T, int bx, int by, gpixels *X,
                                    gcache *C);
#endif

/* gabor_emit.c: emit the points owned by the pixels of block (bx, by) into b; 0 when out of
 * memory. One instance per instruction set (emit_fn; gabor.c picks one). */
int internal_gabor_emit_block_scalar(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr);
#if GABOR_X86
__attribute__((target("avx2"))) int internal_gabor_emit_block_avx2(const gconf *G, int bx, int by,
                                                                   gblock *b, emit_scratch *scr);
__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))) int
internal_gabor_emit_block_avx512(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr);
#endif

/* gabor_splatting.c: add the kernels within reach of tile T to its samples (splat_fn; gabor.c
 * picks one): the scalar reference, the baseline ISA's vector rows, AVX2 and AVX-512. */
void internal_gabor_splat_points_scalar(const gjob *J, gtile *T);
#if GABOR_VEC
void internal_gabor_splat_points_rows(const gjob *J, gtile *T);
#if GABOR_X86
__attribute__((target("avx2"))) void internal_gabor_splat_points_avx2(const gjob *J, gtile *T);
__attribute__((target("avx512f,avx512vl,avx512bw,avx512dq"))) void
internal_gabor_splat_points_avx512(const gjob *J, gtile *T);
#endif
#endif

#endif
