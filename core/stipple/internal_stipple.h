/* Internal to the stipple renderer (core/stipple*.c), never installed: the per-pixel data,
 * the per-worker scratch and the job that the files share. stipple.h has the model. */
#ifndef NPRFX_INTERNAL_STIPPLE_H
#define NPRFX_INTERNAL_STIPPLE_H

#include <limits.h>
#include <stdatomic.h>
#include <stddef.h>

#include "base/internal_simd.h"
#include "nprfx/stipple.h"

/* The per-pixel passes (Jacobian, outlier search, smoothing) and the block member tests have
 * AVX2 copies of their fast loops where INTERNAL_X86 (internal_simd.h), picked per render
 * (sjob.avx2; docs/design.md §1: each lane does the baseline loop's IEEE operations in its
 * order, so the output is the same). */
/* A helper that a baseline loop and its AVX2 copy both run per element: inlined into each, as
 * into the loop it came from (GCC's heuristics leave it out of line in the AVX2 copy). */
#if defined(__GNUC__)
#define STIPPLE_SHARED static inline __attribute__((always_inline))
#else
#define STIPPLE_SHARED static inline
#endif

/* Drawing tiles of the window (and the stripes of nprfx_stipple_collect). */
#define STRIPE_ROWS 64
#define TILE_COLS 256
/* Owners are found in units of this many rows and columns, each owner once per render: small
 * enough for their per-pixel data (~57 bytes a pixel) to stay in cache, large enough that the
 * margin of inputs read around each stays cheap. */
#define UNIT_ROWS 64
#define UNIT_COLS 256
#define PI_D 3.14159265358979323846
/* Half-width of the window over which |det J| is averaged for the density thresholds. */
#define SMOOTH 2

typedef struct pixdata {
    nprfx_rect r; /* the pixels held */
    int w;
    double *su, *sv; /* UV in sequence units (uv / tile + object offset) */
    float *jac;      /* 4 per pixel: du/dx, du/dy, dv/dx, dv/dy in sequence units */
    float *g;        /* darkness 1 - tone, on the owners (E) only */
    float *adet;     /* |det J| */
    float *hs, *hc;  /* smoothing scratch: horizontal sums of adet and their counts */
    int *id;         /* the object where the pixel has a UV (OK_UV), else NO_ID */
    int *jid;        /* id where it also has usable derivatives (OK_J), else NO_ID; set where
                      * whether a derivative is usable is known (E plus SMOOTH + 1) */
    unsigned char *ok;
    size_t cap;    /* pixels allocated */
    void *fixes;   /* repair_outliers: the repaired values */
    size_t fixcap; /* repairs they have room for */
    /* Every held row is of a frame without uv and id inputs (fill_raw's plane_row): su depends
     * on the column only and sv on the row only, one object, so the Jacobian is separable. */
    int plane;
} pixdata;

/* OK_SEAM: the two one-sided differences disagree (a UV seam next to the pixel, or a fold).
 * OK_DROP: only while repair_outliers runs out of memory, a repair to be dropped. */
enum { OK_UV = 1, OK_J = 2, OK_SEAM = 4, OK_DROP = 8 };
#define OK_BOTH (OK_UV | OK_J)
/* Never an object's number (nprfx_id_to_uint gives 0x80000000 to no id). */
#define NO_ID INT_MIN

static inline size_t pd_at(const pixdata *d, int x, int y)
{
    return (size_t)(y - d->r.y0) * (size_t)d->w + (size_t)(x - d->r.x0);
}

/* Corner (x - 0.5, y - 0.5) for x in [E.x0, E.x1], y in [E.y0, E.y1], computed once per tile
 * where the 2x2 pixels around it are one object with usable derivatives, and agree on it. */
typedef struct cgrid {
    nprfx_rect E;
    int gw, gh;
    double *gu, *gv;
    unsigned char *good;
} cgrid;

/* A stipple with the key that orders it: its owner pixel, then its sample. */
typedef struct keyed {
    int oy, ox;
    int level; /* the anisotropy level whose reading of the sequence found it (0: the UVs') */
    double u, v;
    nprfx_stipple s;
} keyed;

/* An owner's shares of the anisotropy levels (stipple_owners.c): at most four have one. */
typedef struct aniso_share {
    unsigned char lv[4];
    float sh[4];
} aniso_share;

/* The share of level l in w (0 where it has none). */
static inline float aniso_share_of(const aniso_share *w, int l)
{
    float s = 0.0f;
    for (int i = 0; i < 4; i++)
        s += w->lv[i] == l ? w->sh[i] : 0.0f;
    return s;
}

typedef struct klist {
    keyed *k;
    size_t n, cap;
    int failed;
    int level; /* given to what emit() adds */
    /* anisotropy passes: each owner's share of the level over E (ew wide), NULL otherwise
     * (how emit() uses it: stipple_owners.c) */
    const aniso_share *share;
    nprfx_rect share_e;
} klist;

typedef struct stlist {
    nprfx_stipple *s;
    size_t n, cap;
    int failed;
} stlist;

/* Dots drawn from tables of exact stencils, one per centre phase (core/stipple/stipple_disc.c):
 * uniform and multitone dots (one radius) at 1/32 px, radius dots (area g a0) from two of
 * RADIUS_LEVELS + 1 areas at 1/16 px. Stencils up to STENCIL_MAX pixels a side (radius ~3.2 px);
 * larger dots are drawn exactly. */
#define STENCIL_PHASES 32
#define RADIUS_PHASES 16
#define RADIUS_LEVELS 64
#define STENCIL_MAX 8
typedef struct internal_stencils {
    double r;
    int phases;   /* a power of two */
    int shift;    /* log2(phases) */
    int lo, size; /* the stencil's pixels: offsets lo .. lo + size - 1 from the centre's pixel */
    float *cov;   /* size^2 coverages per phase, phases row by row; NULL: not made */
} internal_stencils;
/* Whether stencils of a disc of radius `extent` fit STENCIL_MAX. */
int internal_stipple_stencils_fits(double extent);
/* The stencils of radius r (>= 0) at phases^2 centres, spanning the pixels a disc of radius
 * extent >= r touches. 1 when made; 0 when too large (draw exactly); -1 out of memory. */
int internal_stipple_stencils_init(internal_stencils *st, double r, int phases, double extent);
void internal_stipple_stencils_free(internal_stencils *st);
void internal_stipple_splat_stencil(float *t, nprfx_rect rect, const internal_stencils *st,
                                    double cx, double cy, double tone);
typedef struct internal_levels {
    int made;
    double amax; /* the area of the top level (a0) */
    internal_stencils level[RADIUS_LEVELS + 1];
} internal_levels;
/* 1 made, 0 too large (draw exactly), -1 out of memory. */
int internal_stipple_levels_init(internal_levels *lv, double amax);
void internal_stipple_levels_free(internal_levels *lv);
/* A dot of radius r <= sqrt(amax / pi). */
void internal_stipple_splat_levels(float *t, nprfx_rect rect, const internal_levels *lv, double cx,
                                   double cy, double r, double tone);

/* Per-worker memory, reused from tile to tile. */
typedef struct scratch {
    pixdata d;
    cgrid g;
    size_t gcap;
    float *sdet; /* smoothed |det J| over the owners */
    size_t scap;
    klist kl;
    stlist sl;
    float *t;
    size_t tcap;
    unsigned char *aniso; /* anisotropy passes: the levels' shares and the UVs as read */
    size_t acap;
} scratch;

typedef struct sjob {
    nprfx_context *ctx;
    const nprfx_stipple_params *p;
    const nprfx_stipple_inputs *in;
    nprfx_stipple_sequence *seq; /* where p->index is NULL: p->sequence or the job's own */
    int own_seq;
    nprfx_rect region; /* window (render) or region (collect) */
    int margin;        /* owner rows/columns around a tile that can reach it */
    float radius;      /* sqrt(area / pi): the disc radius of uniform and multitone stipples */
    nprfx_image *out;  /* render */
    stlist *lists;     /* collect: one per stripe; render: one per unit */
    nprfx_rect owners; /* render: the owners that can reach the window, in units */
    int units_x;       /* render: units per row */
    int *row_start;    /* render: per unit, UNIT_ROWS + 1 offsets of its owner rows */
    scratch *scr;      /* one per worker */
    internal_stencils stencils;    /* render: uniform and multitone discs (cov NULL: none) */
    const internal_levels *levels; /* render: radius discs (NULL: drawn exactly) */
    internal_levels own_levels;    /* ... made for this call when no sequence keeps them */
    int avx2; /* run the AVX2 loops: p->simd allows them and the CPU has them */
    atomic_int error;
} sjob;

/* (x, y) is held, has a UV and usable derivatives, and belongs to object id. */
static inline int internal_usable_j(const pixdata *d, int x, int y, int id)
{
    return nprfx_rect_contains(d->r, x, y) && d->jid[pd_at(d, x, y)] == id;
}

/* stipple_jacobian.c: the UV Jacobian of the pixels of r (from the raw data fill_raw wrote),
 * the repair of outlier silhouette pixels in M, and the smoothed area scale of the pixels of R
 * (inside E) into out. */
/* avx2: run the AVX2 loops (the CPU has AVX2; sjob.avx2). */
void internal_stipple_fill_jacobian(pixdata *d, nprfx_rect r, int avx2);
void internal_stipple_repair_outliers(pixdata *d, nprfx_rect M, int avx2);
void internal_stipple_smooth_area(pixdata *d, nprfx_rect E, nprfx_rect R, float *out, int avx2);

/* stipple_pixels.c */
int internal_stipple_reserve(void **p, size_t *cap, size_t n, size_t elem);
void internal_stipple_scratch_free(scratch *s);
/* Fill the per-pixel data, the smoothed area scale (s->sdet over E) and the corner grid for
 * the owners of E; 0 when out of memory. */
int internal_stipple_prepare(const sjob *j, scratch *s, nprfx_rect E);
int internal_stipple_off_corner(const pixdata *d, size_t k, double ox, double oy, double u,
                                double v);

/* stipple_owners.c: the stipples owned by the pixels of E, appended to out in row-major order
 * of their owners; row_start (if not NULL) gets where each owner row starts in out. */
nprfx_result internal_stipple_owner_stipples(const sjob *j, scratch *s, nprfx_rect E, stlist *out,
                                             int *row_start);

/* stipple_disc.c: multiply t (the rows and columns of rect, row stride its width) by
 * (1 - coverage * tone) where the disc of radius r at (cx, cy) covers a pixel. */
void internal_stipple_splat_disc(float *t, nprfx_rect rect, double cx, double cy, double r,
                                 double tone);

#endif
