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
 * kernels keep their density up to the frame edge and slide in smoothly instead of popping. */
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

#define BLOCK 32 /* emission blocks: the enumeration of anchor cells is shared by 1024 pixels */
#define PW (BLOCK + 2) /* a block's pixel attributes include a 1-pixel ring, for ownership */
#define PW_PIXELS (PW * PW)
#define HALO 3 /* raw data around those: repair (1) + FD (1) + interior (1) */
#define CACHE_W (PW + 2 * HALO)
#define TILE_SAMPLES                                                                               \
    256                      /* splat tiles, in samples: few kernels straddle two (each does its   \
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

/* One input pixel, packed: the inputs are often views into interleaved multi-channel plates
 * (two cache lines per pixel for anchor, depth and id), and emission reads each pixel about
 * twice, splatting once more; a packed copy is read from the plates once per render. */
typedef struct gpacked {
    float A[3];
    float z;
    float id;
    unsigned char valid, full;
} gpacked;

typedef struct gsrc {
    const nprfx_image *anchor, *depth, *id, *orient, *freq;
    int dims;   /* 2 or 3 */
    int cov_ch; /* coverage channel of the anchor, -1: none */
    nprfx_rect region;
    double step_tol;  /* largest relative depth step between neighbours of one surface */
    gpacked **packed; /* the inputs over prect (inside region), one allocation per row: small
                         blocks the allocator reuses from frame to frame, where one large one
                         would be fresh zeroed pages (page faults) every time */
    nprfx_rect prect;
} gsrc;

static int is_surface_depth(double z)
{
    return z > 0.0 && z < BACKGROUND_DEPTH; /* NaN and inf fail */
}

/* Raw data of one real pixel and the flags the block pipeline derives from it. Floats: the
 * inputs are floats, and a block's working set must stay in cache. */
typedef struct graw {
    float A[3];
    float z;
    float id;
    unsigned char present;  /* inside the inputs */
    unsigned char valid;    /* a surface: finite anchor, depth not background */
    unsigned char full;     /* full coverage (no coverage channel: always) */
    unsigned char interior; /* every present 4-neighbour is on the same surface */
    unsigned char jdone;    /* the Jacobian is computed (lazily: only where a pixel needs it) */
    unsigned char hasj;
} graw;

/* The Jacobian dA/dx, dA/dy and the depth gradient of a raw pixel. */
typedef struct gjac {
    float J[2][3];
    float gz[2];
} gjac;

static void pack_pixel(const gsrc *S, int x, int y, gpacked *p)
{
    const float *a = nprfx_image_at(S->anchor, x, y);
    p->A[0] = a[0];
    p->A[1] = a[1];
    p->A[2] = S->dims == 3 ? a[2] : 0.0f;
    p->z = nprfx_image_at(S->depth, x, y)[0];
    p->id = S->id ? nprfx_image_at(S->id, x, y)[0] + 0.0f : 0.0f;
    p->valid = (unsigned char)(is_surface_depth(p->z) && isfinite(p->A[0]) && isfinite(p->A[1]) &&
                               isfinite(p->A[2]) && isfinite(p->id));
    p->full = (unsigned char)(S->cov_ch < 0 || a[S->cov_ch] >= COVERAGE_FULL);
}

/* The packed pixel (x, y), which must lie in S->prect. */
static const gpacked *packed_at(const gsrc *S, int x, int y)
{
    return &S->packed[y - S->prect.y0][x - S->prect.x0];
}

static void read_raw(const gsrc *S, int x, int y, graw *r)
{
    r->present = (unsigned char)nprfx_rect_contains(S->region, x, y);
    r->valid = r->full = r->interior = r->jdone = r->hasj = 0;
    if (!r->present) return;
    const gpacked *p = packed_at(S, x, y);
    r->A[0] = p->A[0];
    r->A[1] = p->A[1];
    r->A[2] = p->A[2];
    r->z = p->z;
    r->id = p->id;
    r->valid = p->valid;
    r->full = p->full;
}

/* Neighbour d lies on c's surface: same object id and no depth step beyond the tolerance. */
static int same_surface(const gsrc *S, const graw *c, const graw *d)
{
    if (!d->present || !d->valid || d->id != c->id) return 0;
    double zmin = c->z < d->z ? c->z : d->z;
    return fabs((double)d->z - c->z) <= S->step_tol * zmin;
}

/* ---- per-block pixel attributes ---------------------------------------------------------------
 */

typedef struct gpix {
    float A[3];
    float P[2][3]; /* J+ = (J^T J)^-1 J^T: anchor offset -> screen offset */
    float id;
    short emit;   /* may own points */
    short comp;   /* surface patch within the block (-1: none) */
    float n[3];   /* unit normal of the anchor surface (3D) */
    float ext[3]; /* half extent of the pixel's anchor footprint, per axis */
    float z, gz[2];
    float mu;   /* wanted points per level-0 cell area */
    int rx, ry; /* the real pixel whose orientation / frequency inputs it uses */
} gpix;

typedef struct gconf {
    gsrc S;
    double a, lambda, radius, r2, h0, F0, w0, tol;
    int W, dims, ss, iso, amp, dtest, points, output, stagger;
    double contrast, var_k1;
    uint64_t seed;
    lod_table lod;
    double pa2, rr; /* pi a^2; exp(-2 pi a^2 / s^2), the envelope recurrence's second ratio */
    float step_tolf;
    /* every kernel has the same wave vector (no isotropy, no orientation or frequency input):
     * it and its per-sample phase rotations are computed once */
    int uniform_wave;
    double kx0, ky0;
    float csx, ssx, csy, ssy;
} gconf;

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

/* One axis of the Jacobian of interior pixel c (cache index ci), from its interior neighbours at
 * ci +- step. Where both exist but one difference is much larger (a UV seam, a blended anchor),
 * the smaller one-sided difference is used; with neither, the axis is undefined. */
static int axis_diff(const graw *cache, int ci, int step, float dA[3], float *dz)
{
    const graw *c = &cache[ci], *f = &cache[ci + step], *b = &cache[ci - step];
    int hf = f->present && f->interior && f->id == c->id;
    int hb = b->present && b->interior && b->id == c->id;
    float Df[3], Db[3];
    for (int k = 0; k < 3; k++) {
        Df[k] = f->A[k] - c->A[k];
        Db[k] = c->A[k] - b->A[k];
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
        *dz = 0.5f * (f->z - b->z);
    } else if (hf) {
        memcpy(dA, Df, sizeof Df);
        *dz = f->z - c->z;
    } else if (hb) {
        memcpy(dA, Db, sizeof Db);
        *dz = c->z - b->z;
    } else {
        return 0;
    }
    return 1;
}

/* The Jacobian of interior cache cell ci (row stride cw), computed on first use. */
static int jacobian(graw *cache, gjac *jac, int ci, int cw)
{
    graw *c = &cache[ci];
    if (!c->jdone) {
        c->jdone = 1;
        c->hasj = (unsigned char)(axis_diff(cache, ci, 1, jac[ci].J[0], &jac[ci].gz[0]) &&
                                  axis_diff(cache, ci, cw, jac[ci].J[1], &jac[ci].gz[1]));
    }
    return c->hasj;
}

static void finish_pixel(const gconf *G, gpix *q, const gjac *jc)
{
    double jx[3] = {jc->J[0][0], jc->J[0][1], jc->J[0][2]};
    double jy[3] = {jc->J[1][0], jc->J[1][1], jc->J[1][2]};
    double g11 = dot3(jx, jx), g12 = dot3(jx, jy), g22 = dot3(jy, jy);
    double det = g11 * g22 - g12 * g12; /* = |Jx x Jy|^2 */
    q->emit = 0;
    if (!(det > 0.0) || !isfinite(det)) return;
    double area = sqrt(det), iarea = 1.0 / area, idet = iarea * iarea;
    for (int k = 0; k < 3; k++) {
        q->P[0][k] = (float)((g22 * jx[k] - g12 * jy[k]) * idet);
        q->P[1][k] = (float)((g11 * jy[k] - g12 * jx[k]) * idet);
        q->ext[k] = (float)(0.5 * (fabs(jx[k]) + fabs(jy[k])));
    }
    q->n[0] = (float)((jx[1] * jy[2] - jx[2] * jy[1]) * iarea);
    q->n[1] = (float)((jx[2] * jy[0] - jx[0] * jy[2]) * iarea);
    q->n[2] = (float)((jx[0] * jy[1] - jx[1] * jy[0]) * iarea);
    double mu = G->lambda * G->h0 * G->h0 * iarea;
    q->mu = (float)mu;
    q->emit = q->mu > 0.0f && isfinite(q->mu);
}

/* Attributes of the pixels of block (bx, by) and of the ring of pixels around it (a pixel's
 * attributes depend on the inputs around it only, never on the block). Real pixels use their
 * own anchor where they are interior to their surface; pixels at an edge (renderers filter Pref
 * and UV there, mixing the two surfaces) and virtual pixels outside the inputs extrapolate from
 * an interior neighbour along its Jacobian. */
static void block_pixels(const gconf *G, int bx, int by, gpix *px, graw *cache, gjac *jac)
{
    const gsrc *S = &G->S;
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1; /* the ring's first pixel */
    for (int k = 0; k < PW_PIXELS; k++)
        px[k].emit = 0;
    nprfx_rect reg = S->region;
    if (nprfx_rect_empty(reg)) return;
    /* R: the real pixels the block's pixels map to (clamped into the inputs) */
    int rx0 = x0 < reg.x0 ? reg.x0 : (x0 >= reg.x1 ? reg.x1 - 1 : x0);
    int rx1 = x0 + PW - 1 < reg.x0 ? reg.x0 : (x0 + PW - 1 >= reg.x1 ? reg.x1 - 1 : x0 + PW - 1);
    int ry0 = y0 < reg.y0 ? reg.y0 : (y0 >= reg.y1 ? reg.y1 - 1 : y0);
    int ry1 = y0 + PW - 1 < reg.y0 ? reg.y0 : (y0 + PW - 1 >= reg.y1 ? reg.y1 - 1 : y0 + PW - 1);
    int cx0 = rx0 - HALO, cy0 = ry0 - HALO;
    int cw = rx1 - rx0 + 1 + 2 * HALO, ch = ry1 - ry0 + 1 + 2 * HALO;
    for (int j = 0; j < ch; j++)
        for (int i = 0; i < cw; i++)
            read_raw(S, cx0 + i, cy0 + j, &cache[j * cw + i]);
    /* interior flags on R grown by 2 */
    for (int j = 1; j < ch - 1; j++)
        for (int i = 1; i < cw - 1; i++) {
            graw *c = &cache[j * cw + i];
            if (!c->valid || !c->full) continue;
            const graw *nb[4] = {c - 1, c + 1, c - cw, c + cw};
            int ok = 1;
            for (int k = 0; k < 4 && ok; k++)
                if (nb[k]->present && !same_surface(S, c, nb[k])) ok = 0;
            c->interior = (unsigned char)ok;
        }
    for (int k = 0; k < PW_PIXELS; k++) {
        gpix *q = &px[k];
        int x = x0 + k % PW, y = y0 + k / PW;
        int rx = x < reg.x0 ? reg.x0 : (x >= reg.x1 ? reg.x1 - 1 : x);
        int ry = y < reg.y0 ? reg.y0 : (y >= reg.y1 ? reg.y1 - 1 : y);
        int ci = (ry - cy0) * cw + (rx - cx0);
        const graw *c = &cache[ci];
        if (!c->valid) continue;
        int si = -1, sx = rx, sy = ry;
        if (c->interior && jacobian(cache, jac, ci, cw)) {
            si = ci;
        } else {
            static const int dxs[4] = {-1, 1, 0, 0}, dys[4] = {0, 0, -1, 1};
            for (int m = 0; m < 4 && si < 0; m++) {
                int di = ci + dys[m] * cw + dxs[m];
                const graw *d = &cache[di];
                if (d->present && d->interior && same_surface(S, c, d) &&
                    jacobian(cache, jac, di, cw)) {
                    si = di;
                    sx = rx + dxs[m];
                    sy = ry + dys[m];
                }
            }
        }
        if (si < 0) continue;
        const graw *src = &cache[si];
        const gjac *jc = &jac[si];
        double ox = x - sx, oy = y - sy;
        for (int m = 0; m < 3; m++)
            q->A[m] = (float)(src->A[m] + (double)jc->J[0][m] * ox + (double)jc->J[1][m] * oy);
        /* depth is one sample, never filtered: keep the pixel's own, extrapolate only outside */
        double z = c->z + (double)jc->gz[0] * (x - rx) + (double)jc->gz[1] * (y - ry);
        if (!is_surface_depth(z)) continue;
        q->z = (float)z;
        q->gz[0] = jc->gz[0];
        q->gz[1] = jc->gz[1];
        q->id = c->id;
        q->rx = rx;
        q->ry = ry;
        finish_pixel(G, q, jc);
    }
}

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
    int i = q % PW, j = q / PW;
    return i >= 1 && i <= BLOCK && j >= 1 && j <= BLOCK;
}

/* Offset of anchor point a from pixel p's centre under p's own linearisation, in pixels. */
static double own_offset(const gpix *p, const double *a, double *ux, double *uy)
{
    double d[3] = {a[0] - p->A[0], a[1] - p->A[1], a[2] - p->A[2]};
    *ux = p->P[0][0] * d[0] + p->P[0][1] * d[1] + p->P[0][2] * d[2];
    *uy = p->P[1][0] * d[0] + p->P[1][1] * d[1] + p->P[1][2] * d[2];
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
static int find_owner(const gpix *px, int ref, const double *a, double *ox, double *oy)
{
    int q = ref, prev = -1;
    float id = px[ref].id;
    double ux = 0.0, uy = 0.0, dq = 0.0;
    for (int it = 0; it < OWNER_STEPS; it++) {
        dq = own_offset(&px[q], a, &ux, &uy);
        if (!(dq < 1e6)) return -1;
        int mx = ifloor(ux + 0.5), my = ifloor(uy + 0.5);
        if (mx == 0 && my == 0) break;
        int ti = q % PW + mx, tj = q / PW + my;
        int qi = ti < 0 ? 0 : (ti >= PW ? PW - 1 : ti);
        int qj = tj < 0 ? 0 : (tj >= PW ? PW - 1 : tj);
        int nq = qj * PW + qi;
        if (nq == q) return -1; /* beyond the ring: not this block's */
        if (!px[nq].emit || px[nq].id != id) {
            /* a hole or another object on the way (or the point is not visible): continue
             * from the nearest pixel of the object around the target, if any */
            int best = -1, bd = 1 << 30;
            for (int dj = -2; dj <= 2; dj++)
                for (int di = -2; di <= 2; di++) {
                    int i = qi + di, j = qj + dj;
                    if (i < 0 || i >= PW || j < 0 || j >= PW) continue;
                    int n = j * PW + i, d = di * di + dj * dj;
                    if (px[n].emit && px[n].id == id && d < bd) {
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
    }
    dq = own_offset(&px[q], a, &ux, &uy);
    for (int it = 0; it < 4 * PW; it++) {
        int best = q, qi = q % PW, qj = q / PW;
        double bx = ux, by = uy, bd = dq;
        for (int dj = -1; dj <= 1; dj++)
            for (int di = -1; di <= 1; di++) {
                int i = qi + di, j = qj + dj;
                if ((di == 0 && dj == 0) || i < 0 || i >= PW || j < 0 || j >= PW) continue;
                int n = j * PW + i;
                if (!px[n].emit || px[n].id != id) continue;
                double vx, vy, d = own_offset(&px[n], a, &vx, &vy);
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
static int make_point(const gconf *G, const gpix *o, int ox, int oy, double sx, double sy,
                      double w2, uint64_t h, float id, gpoint *pt)
{
    double z = o->z + o->gz[0] * (sx - ox) + o->gz[1] * (sy - oy);
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
    pt->gzx = (float)o->gz[0];
    pt->gzy = (float)o->gz[1];
    pt->id = id;
    pt->ox = ox;
    pt->oy = oy;
    double kx, ky;
    kernel_wave(G, o->rx, o->ry, h, &kx, &ky);
    axis_start(G, sample_pos(pt->X0, s) - sx, 2.0 * k_pi * kx, 0, &pt->ax);
    axis_start(G, sample_pos(pt->Y0, s) - sy, 2.0 * k_pi * ky, 1, &pt->ay);
    return 1;
}

/* Two neighbouring pixels lie on one surface patch: same object, no depth step, and anchors
 * no farther apart than about two pixel footprints (not across a UV seam, or two objects
 * sharing an id input that is not connected). */
static int patch_link(const gconf *G, const gpix *a, const gpix *b)
{
    if (!b->emit || b->id != a->id) return 0;
    float zmin = a->z < b->z ? a->z : b->z;
    if (!(fabsf(a->z - b->z) <= G->step_tolf * zmin)) return 0;
    float d2 = 0.0f, e2 = 0.0f;
    for (int m = 0; m < 3; m++) {
        float d = a->A[m] - b->A[m], e = a->ext[m] + b->ext[m];
        d2 += d * d;
        e2 += e * e;
    }
    return d2 <= 4.0f * e2;
}

/* Label the emitting pixels of a block (not its ring) by connected surface patch (4-neighbours,
 * raster order of each patch's first pixel). Each patch enumerates the anchor cells of its own
 * footprint, so a block straddling two surfaces does not enumerate everything between their
 * anchors. */
static int label_patches(const gconf *G, gpix *px)
{
    int stack[BLOCK * BLOCK], n = 0;
    for (int k = 0; k < PW_PIXELS; k++)
        px[k].comp = -1;
    for (int k = 0; k < PW_PIXELS; k++) {
        if (!in_block(k) || !px[k].emit || px[k].comp >= 0) continue;
        int sp = 0;
        px[k].comp = n;
        stack[sp++] = k;
        while (sp > 0) {
            int c = stack[--sp];
            int nb[4] = {c - 1, c + 1, c - PW, c + PW};
            for (int m = 0; m < 4; m++) {
                int d = nb[m];
                if (!in_block(d) || px[d].comp >= 0 || !patch_link(G, &px[c], &px[d])) continue;
                px[d].comp = n;
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
static void surface_at(const gconf *G, const gpix *px, int q, double gx, double gy, double *A,
                       double *n, double *mu)
{
    const gpix *o = &px[q];
    int i0 = ifloor(gx), j0 = ifloor(gy);
    if (i0 >= 0 && j0 >= 0 && i0 + 1 < PW && j0 + 1 < PW) {
        const gpix *c[4] = {&px[j0 * PW + i0], &px[j0 * PW + i0 + 1], &px[(j0 + 1) * PW + i0],
                            &px[(j0 + 1) * PW + i0 + 1]};
        int ok = 1;
        for (int k = 0; k < 4 && ok; k++)
            ok = c[k] == o || patch_link(G, o, c[k]);
        if (ok) {
            double fx = gx - i0, fy = gy - j0;
            double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
            double nn = 0.0;
            *mu = 0.0;
            for (int m = 0; m < 3; m++) {
                A[m] =
                    w[0] * c[0]->A[m] + w[1] * c[1]->A[m] + w[2] * c[2]->A[m] + w[3] * c[3]->A[m];
                n[m] =
                    w[0] * c[0]->n[m] + w[1] * c[1]->n[m] + w[2] * c[2]->n[m] + w[3] * c[3]->n[m];
                nn += n[m] * n[m];
            }
            for (int k = 0; k < 4; k++)
                *mu += w[k] * c[k]->mu;
            if (nn > 0.0) {
                nn = 1.0 / sqrt(nn);
                for (int m = 0; m < 3; m++)
                    n[m] *= nn;
                return;
            }
        }
    }
    for (int m = 0; m < 3; m++) {
        A[m] = o->A[m];
        n[m] = o->n[m];
    }
    *mu = o->mu;
}

typedef struct emit_scratch {
    graw cache[CACHE_W * CACHE_W];
    gjac jac[CACHE_W * CACHE_W];
    gpix px[PW_PIXELS];
} emit_scratch;

/* Emit the points owned by the pixels of block (bx, by) into b. Returns 0 when out of memory. */
static int emit_block(const gconf *G, int bx, int by, gblock *b, emit_scratch *scr)
{
    gpix *px = scr->px;
    block_pixels(G, bx, by, px, scr->cache, scr->jac);
    int x0 = bx * BLOCK - 1, y0 = by * BLOCK - 1; /* pixel (x0, y0): index 0 of the grid */
    int ncomp = label_patches(G, px);
    const double mid = 0.5 * (PW - 1);
    for (int comp = 0; comp < ncomp; comp++) {
        int ref = -1;
        double best = DBL_MAX;
        /* the patch's footprint: anchor +- pixel extent, and the largest normal component (the
         * slab's reach per level is added below) */
        double fmin[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, fmax[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
        double nmax[3] = {0.0, 0.0, 0.0};
        for (int k = 0; k < PW_PIXELS; k++) {
            const gpix *q = &px[k];
            if (q->comp != comp) continue;
            double dx = k % PW - mid, dy = k / PW - mid, d = dx * dx + dy * dy;
            if (d < best) {
                best = d;
                ref = k;
            }
            for (int m = 0; m < 3; m++) {
                if (q->A[m] - q->ext[m] < fmin[m]) fmin[m] = q->A[m] - q->ext[m];
                if (q->A[m] + q->ext[m] > fmax[m]) fmax[m] = q->A[m] + q->ext[m];
                if (fabs(q->n[m]) > nmax[m]) nmax[m] = fabs(q->n[m]);
            }
        }
        float id = px[ref].id;
        uint32_t idbits = float_bits(id);
        /* A point's level weight and slab test use the surface interpolated from up to four
         * pixels of the object around it, ring pixels included: the levels to enumerate are
         * those of the smallest and largest wanted density among them (the rule is monotone).
         * 3D: how far those pixels' surface reaches from the reference pixel's tangent plane,
         * and how much their normals turn: a point farther from that plane than the slab plus
         * this reach cannot be accepted, which rejects most off-surface cells of the bounding
         * box before the owner search. */
        const gpix *rp = &px[ref];
        double rn[3] = {rp->n[0], rp->n[1], rp->n[2]};
        double reach = 0.0, turn = 0.0, mumin = DBL_MAX, mumax = 0.0;
        for (int k = 0; k < PW_PIXELS; k++) {
            const gpix *q = &px[k];
            if (!q->emit || q->id != id) continue;
            if (q->mu < mumin) mumin = q->mu;
            if (q->mu > mumax) mumax = q->mu;
            if (G->dims != 3 || !(q->comp == comp || !in_block(k))) continue;
            double d[3] = {(double)q->A[0] - rp->A[0], (double)q->A[1] - rp->A[1],
                           (double)q->A[2] - rp->A[2]};
            double e = fabs(dot3(d, rn));
            double dn[3] = {(double)q->n[0] - rn[0], (double)q->n[1] - rn[1],
                            (double)q->n[2] - rn[2]};
            double t = sqrt(dot3(dn, dn));
            if (e > reach) reach = e;
            if (t > turn) turn = t;
        }
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
                        double ustart = nprfx_u01(nprfx_mix64(h ^ 0x510e527fade682d1ull));
                        if (ustart * (1.0 - STAGGER) >= xmax) continue;
                        if (G->dims == 3) {
                            double d[3] = {a[0] - rp->A[0], a[1] - rp->A[1], a[2] - rp->A[2]};
                            if (!(fabs(dot3(d, rn)) < slab)) continue;
                        }
                        double ux, uy;
                        int q = find_owner(px, ref, a, &ux, &uy);
                        if (q < 0) continue;
                        const gpix *o = &px[q];
                        double As[3], ns[3], mus, fs;
                        int Ls;
                        surface_at(G, px, q, q % PW + ux, q / PW + uy, As, ns, &mus);
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
                        int ox = x0 + q % PW, oy = y0 + q / PW;
                        if (!make_point(G, o, ox, oy, ox + ux, oy + uy, w2, h, id, &pt)) continue;
                        if (!block_push(b, &pt)) return 0;
                    }
        }
    }
    return 1;
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
 * v_j = A cx[j] - B sx[j] and the expected depth zp_j = zr + gx (i0 + j). Every path (AVX, SSE,
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

#if GABOR_SSE
static void row_sse(float *restrict acc, const float *restrict zt, const float *restrict idt,
                    const float *restrict cx, const float *restrict sx, const row_job *R)
{
    __m128 va = _mm_set1_ps(R->A), vb = _mm_set1_ps(R->B), vid = _mm_set1_ps(R->idk);
    __m128 vzr = _mm_set1_ps(R->zr), vgx = _mm_set1_ps(R->gx), vtol = _mm_set1_ps(R->tol);
    __m128 sign = _mm_set1_ps(-0.0f), four = _mm_set1_ps(4.0f), two = _mm_set1_ps(2.0f);
    __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    __m128 lane = _mm_setr_ps(0.0f, 1.0f, 2.0f, 3.0f), vn = _mm_set1_ps((float)R->n);
    __m128 vj = lane;
    __m128 vi = _mm_cvtepi32_ps(_mm_setr_epi32(R->i0, R->i0 + 1, R->i0 + 2, R->i0 + 3));
    for (int j = 0; j < R->n; j += 4) {
        __m128 v =
            _mm_sub_ps(_mm_mul_ps(va, _mm_loadu_ps(cx + j)), _mm_mul_ps(vb, _mm_loadu_ps(sx + j)));
        __m128 m = _mm_and_ps(_mm_cmpeq_ps(_mm_loadu_ps(idt + j), vid), _mm_cmplt_ps(vj, vn));
        if (R->mode != NPRFX_GABOR_DEPTH_OFF) {
            __m128 zp = _mm_add_ps(vzr, _mm_mul_ps(vgx, vi));
            __m128 dz = _mm_andnot_ps(sign, _mm_sub_ps(_mm_loadu_ps(zt + j), zp));
            if (R->mode == NPRFX_GABOR_DEPTH_HARD) {
                m = _mm_and_ps(m, _mm_cmple_ps(dz, vtol));
            } else {
                __m128 t = _mm_sub_ps(two, _mm_mul_ps(dz, vtol));
                v = _mm_mul_ps(v, _mm_min_ps(_mm_max_ps(t, zero), one));
            }
            vi = _mm_add_ps(vi, four);
        }
        _mm_storeu_ps(acc + j, _mm_add_ps(_mm_loadu_ps(acc + j), _mm_and_ps(m, v)));
        vj = _mm_add_ps(vj, four);
    }
}
#endif

#if GABOR_SSE && defined(__GNUC__) && defined(__x86_64__)
#define GABOR_AVX 1
#include <immintrin.h>
__attribute__((target("avx"))) static void row_avx(float *restrict acc, const float *restrict zt,
                                                   const float *restrict idt,
                                                   const float *restrict cx,
                                                   const float *restrict sx, const row_job *R)
{
    __m256 va = _mm256_set1_ps(R->A), vb = _mm256_set1_ps(R->B), vid = _mm256_set1_ps(R->idk);
    __m256 vzr = _mm256_set1_ps(R->zr), vgx = _mm256_set1_ps(R->gx);
    __m256 vtol = _mm256_set1_ps(R->tol), sign = _mm256_set1_ps(-0.0f);
    __m256 eight = _mm256_set1_ps(8.0f), two = _mm256_set1_ps(2.0f), one = _mm256_set1_ps(1.0f);
    __m256 zero = _mm256_setzero_ps(), vn = _mm256_set1_ps((float)R->n);
    __m256 vj = _mm256_setr_ps(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f);
    __m256 vi = _mm256_add_ps(_mm256_set1_ps((float)R->i0), vj); /* exact: small integers */
    for (int j = 0; j < R->n; j += 8) {
        __m256 v = _mm256_sub_ps(_mm256_mul_ps(va, _mm256_loadu_ps(cx + j)),
                                 _mm256_mul_ps(vb, _mm256_loadu_ps(sx + j)));
        __m256 m = _mm256_and_ps(_mm256_cmp_ps(_mm256_loadu_ps(idt + j), vid, _CMP_EQ_OQ),
                                 _mm256_cmp_ps(vj, vn, _CMP_LT_OQ));
        if (R->mode != NPRFX_GABOR_DEPTH_OFF) {
            __m256 zp = _mm256_add_ps(vzr, _mm256_mul_ps(vgx, vi));
            __m256 dz = _mm256_andnot_ps(sign, _mm256_sub_ps(_mm256_loadu_ps(zt + j), zp));
            if (R->mode == NPRFX_GABOR_DEPTH_HARD) {
                m = _mm256_and_ps(m, _mm256_cmp_ps(dz, vtol, _CMP_LE_OQ));
            } else {
                __m256 t = _mm256_sub_ps(two, _mm256_mul_ps(dz, vtol));
                v = _mm256_mul_ps(v, _mm256_min_ps(_mm256_max_ps(t, zero), one));
            }
            vi = _mm256_add_ps(vi, eight);
        }
        _mm256_storeu_ps(acc + j, _mm256_add_ps(_mm256_loadu_ps(acc + j), _mm256_and_ps(m, v)));
        vj = _mm256_add_ps(vj, eight);
    }
}
#else
#define GABOR_AVX 0
#endif

typedef void (*row_fn)(float *restrict, const float *restrict, const float *restrict,
                       const float *restrict, const float *restrict, const row_job *);

static row_fn pick_row_fn(int simd)
{
    if (simd == 1) return row_scalar;
#if GABOR_AVX
    if (simd == 0 && __builtin_cpu_supports("avx")) return row_avx;
#endif
#if GABOR_SSE
    return row_sse;
#else
    return row_scalar;
#endif
}

/* ---- the render ----------------------------------------------------------------------------- */

typedef struct gjob {
    const gconf *G;
    /* blocks of the emission region */
    int bx0, by0, nbx, nby;
    gblock *blocks;
    int *row_ok;
    /* tiles of the window */
    nprfx_rect window;
    int tile, ntx, nty, reach;
    row_fn row;
    nprfx_image *out;
    int *tile_ok;
    long long *t_kernels, *t_evals;
    double *t_w2;
} gjob;

static int floor_div(int a, int b)
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

static void pack_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const gsrc *S = user;
    int w = nprfx_rect_width(S->prect);
    for (int j = begin; j < end; j++)
        if (S->packed[j])
            for (int i = 0; i < w; i++)
                pack_pixel(S, S->prect.x0 + i, S->prect.y0 + j, &S->packed[j][i]);
}

static void emit_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    gjob *J = user;
    emit_scratch *scr = malloc(sizeof *scr);
    for (int r = begin; r < end; r++) {
        int ok = scr != NULL;
        for (int i = 0; i < J->nbx && ok; i++)
            ok = emit_block(J->G, J->bx0 + i, J->by0 + r, &J->blocks[r * J->nbx + i], scr);
        J->row_ok[r] = ok;
    }
    free(scr);
}

static void splat_tile(gjob *J, int t)
{
    const gconf *G = J->G;
    const gsrc *S = &G->S;
    int s = G->ss;
    int tx0 = J->window.x0 + (t % J->ntx) * J->tile, ty0 = J->window.y0 + (t / J->ntx) * J->tile;
    int tx1 = tx0 + J->tile < J->window.x1 ? tx0 + J->tile : J->window.x1;
    int ty1 = ty0 + J->tile < J->window.y1 ? ty0 + J->tile : J->window.y1;
    int W = (tx1 - tx0) * s, H = (ty1 - ty0) * s;
    int TX0 = tx0 * s, TY0 = ty0 * s, TX1 = tx1 * s, TY1 = ty1 * s; /* sample coordinates */
    int tabn = (int)ceil(2.0 * G->radius * s) + 4 + VPAD;
    size_t npx = (size_t)W * (size_t)H + VPAD;
    float *acc = calloc(npx, sizeof(float));
    float *zt = calloc(npx, sizeof(float));
    float *idt = calloc(npx, sizeof(float));
    float *tab = calloc(4 * (size_t)tabn, sizeof(float));
    int *span = malloc(sizeof(int) * 2 * (size_t)(H + 1));
    if (!acc || !zt || !idt || !tab || !span) {
        free(acc);
        free(zt);
        free(idt);
        free(tab);
        free(span);
        J->tile_ok[t] = 0;
        return;
    }
    float *CX = tab, *SX = tab + tabn, *CY = tab + 2 * tabn, *SY = tab + 3 * tabn;
    const float nan = nanf("");
    for (int y = ty0; y < ty1; y++)
        for (int x = tx0; x < tx1; x++) {
            float z = 0.0f, id = nan;
            if (nprfx_rect_contains(S->region, x, y)) {
                const gpacked *pk = packed_at(S, x, y);
                double zz = pk->z;
                float ii = pk->id;
                if (is_surface_depth(zz) && isfinite(ii)) {
                    z = (float)zz;
                    id = ii;
                }
            }
            for (int j = 0; j < s; j++)
                for (int i = 0; i < s; i++) {
                    size_t o =
                        (size_t)((y - ty0) * s + j) * (size_t)W + (size_t)((x - tx0) * s + i);
                    zt[o] = z;
                    idt[o] = id;
                }
        }
    for (size_t i = npx - VPAD; i < npx; i++)
        idt[i] = nan;
    double r2 = G->r2;
    long long evals = 0, kernels = 0;
    double w2sum = 0.0;
    int bxa = floor_div(tx0 - J->reach, BLOCK), bxb = floor_div(tx1 - 1 + J->reach, BLOCK);
    int bya = floor_div(ty0 - J->reach, BLOCK), byb = floor_div(ty1 - 1 + J->reach, BLOCK);
    if (bxa < J->bx0) bxa = J->bx0;
    if (bya < J->by0) bya = J->by0;
    if (bxb > J->bx0 + J->nbx - 1) bxb = J->bx0 + J->nbx - 1;
    if (byb > J->by0 + J->nby - 1) byb = J->by0 + J->nby - 1;
    row_job R;
    R.mode = G->dtest;
    for (int by = bya; by <= byb; by++)
        for (int bx = bxa; bx <= bxb; bx++) {
            const gblock *b = &J->blocks[(by - J->by0) * J->nbx + (bx - J->bx0)];
            for (int k = 0; k < b->n; k++) {
                const gpoint *p = &b->p[k];
                if (p->X1 < TX0 || p->X0 >= TX1 || p->Y1 < TY0 || p->Y0 >= TY1) continue;
                double sx = p->sx, sy = p->sy;
                int xe = p->X1 < TX1 - 1 ? p->X1 : TX1 - 1, ye = p->Y1 < TY1 - 1 ? p->Y1 : TY1 - 1;
                int ya = p->Y0 > TY0 ? p->Y0 : TY0;
                /* the disk's span on each row the tile holds; skip the kernel if none */
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
                /* tables from the kernel's own first sample, whatever the tile */
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
                    evals += R.n;
                    J->row(acc + o, zt + o, idt + o, CX + R.i0, SX + R.i0, &R);
                }
            }
        }
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
    J->t_evals[t] = evals;
    J->t_w2[t] = w2sum;
    J->tile_ok[t] = 1;
    free(acc);
    free(zt);
    free(idt);
    free(tab);
    free(span);
}

static void splat_tiles(void *user, int begin, int end, int worker)
{
    (void)worker;
    for (int t = begin; t < end; t++)
        splat_tile(user, t);
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
    J.row = pick_row_fn(p->simd);
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
    /* the inputs the blocks read: their pixels, the ring and the raw halo */
    G.S.prect = nprfx_rect_intersect(
        G.S.region,
        nprfx_rect_make(J.bx0 * BLOCK - 1 - HALO, J.by0 * BLOCK - 1 - HALO,
                        (J.bx0 + J.nbx) * BLOCK + 1 + HALO, (J.by0 + J.nby) * BLOCK + 1 + HALO));
    if (!nprfx_rect_empty(G.S.prect)) {
        int ph = nprfx_rect_height(G.S.prect);
        G.S.packed = calloc((size_t)ph, sizeof(gpacked *));
        int ok = G.S.packed != NULL;
        for (int j = 0; j < ph && ok; j++)
            ok = (G.S.packed[j] = malloc(sizeof(gpacked) * (size_t)nprfx_rect_width(G.S.prect))) !=
                 NULL;
        if (!ok) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory for the inputs");
            goto done;
        }
        nprfx_parallel_for(ex, ph, 8, pack_rows, &G.S);
    }
    nprfx_parallel_for(ex, J.nby, 1, emit_rows, &J);
    for (int i = 0; i < J.nby; i++)
        if (!J.row_ok[i]) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "gabor: out of memory for the points");
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
    if (G.S.packed)
        for (int j = 0; j < nprfx_rect_height(G.S.prect); j++)
            free(G.S.packed[j]);
    free(G.S.packed);
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
