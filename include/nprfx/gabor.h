/* nprfx — NPR Gabor noise splatted from point-cloud AOVs (Benard et al., EGSR 2010; Gabor noise
 * of Lagae et al. 2009), docs/design.md §3.2.
 *
 * The noise is a sum of Gabor kernels whose frequency, orientation and size are set in pixels (so
 * it looks 2D) while their centres are points anchored on the surfaces through an anchor AOV
 * (Pref, world P or UV), so it moves with the objects. A hierarchy of cells in anchor space gives
 * each pixel the points it needs for a constant screen-space density, with continuous fade-in
 * (and fade-out) weights that keep the variance and spectrum constant at every zoom. Each
 * visible point is emitted by the one pixel that owns its screen position, and its kernel
 * reaches only pixels of the same object id and the same depth layer.
 *
 * Every random number is a hash of (seed, level, cell, object id): output is bit-identical for
 * any thread count, tile split and render order. */
#ifndef NPRFX_GABOR_H
#define NPRFX_GABOR_H

#include <stdint.h>

#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum nprfx_gabor_amplitude {
    NPRFX_GABOR_AMP_UNIFORM = 0, /* v uniform in [-1, 1], E[v^2] = 1/3 (Lagae et al.) */
    NPRFX_GABOR_AMP_SIGN = 1,    /* v = +-1, E[v^2] = 1: every kernel at full contrast */
    NPRFX_GABOR_AMP_GAUSS = 2,   /* v standard normal, E[v^2] = 1 */
    NPRFX_GABOR_AMP_COUNT
} nprfx_gabor_amplitude;

typedef enum nprfx_gabor_depth_test {
    NPRFX_GABOR_DEPTH_OFF = 0,  /* object-id test only */
    NPRFX_GABOR_DEPTH_HARD = 1, /* reject where the relative depth error exceeds the tolerance */
    NPRFX_GABOR_DEPTH_SOFT =
        2, /* weight 1 up to the tolerance, falling linearly to 0 at twice it */
    NPRFX_GABOR_DEPTH_COUNT
} nprfx_gabor_depth_test;

typedef enum nprfx_gabor_fade {
    /* docs/design.md §3.2: every point of the level fading in has the squared weight
     * (D - D_L) / (density of the level) */
    NPRFX_GABOR_FADE_LEVEL = 0,
    /* each point of that level fades in on its own (a hashed start), its amplitude ramping
     * linearly over a quarter of the regime; the ramps are set so that the expected squared
     * weight equals the level rule's: same density, variance and spectrum, about half the
     * kernels, and no synchronised onset */
    NPRFX_GABOR_FADE_STAGGERED = 1,
    NPRFX_GABOR_FADE_COUNT
} nprfx_gabor_fade;

typedef enum nprfx_gabor_output {
    NPRFX_GABOR_OUT_UNIT = 0,   /* zero mean, unit variance */
    NPRFX_GABOR_OUT_UNIT01 = 1, /* 0.5 + contrast * n */
    NPRFX_GABOR_OUT_COUNT
} nprfx_gabor_output;

typedef struct nprfx_gabor_params {
    size_t size;        /* sizeof(nprfx_gabor_params) */
    int anchor_dims;    /* 2: UV (u, v); 3: Pref or P (x, y, z) */
    double frequency;   /* F0, cycles per pixel */
    double orientation; /* w0, degrees, counter-clockwise in the image, of the wave vector */
    int isotropic;      /* a random w0 per kernel */
    double radius;      /* truncation radius r in pixels: a = sqrt(-ln 0.05 / pi) / r */
    double n0;          /* expected number of overlapping kernels: lambda = n0 / (pi r^2) */
    uint64_t seed;
    double cell;            /* h0: size of a level-0 cell in anchor units */
    int lod_levels;         /* W: whole levels kept between the fading-in and fading-out ones */
    int fade;               /* nprfx_gabor_fade: how the finest level fades in */
    int depth_test;         /* nprfx_gabor_depth_test */
    double depth_tolerance; /* relative depth error allowed (and largest relative depth step
                               a finite difference may cross) */
    int supersample;        /* s: s x s samples per pixel, box-averaged */
    int amplitude;          /* nprfx_gabor_amplitude */
    int output;             /* nprfx_gabor_output */
    double contrast;        /* unit01: 0.5 + contrast * n */
    int points;             /* 1: write a second channel, the squared weights of the kernels each
                               pixel owns (debugging; their sum per pixel^2 is lambda) */
    int simd;               /* testing: 0 the fastest path available, 1 scalar, 2 the baseline
                               ISA's vectors (SSE2, NEON: scalar emission, vector rows), 3 AVX2
                               (where the CPU has it, else as 2); every path gives bit-identical
                               output */
} nprfx_gabor_params;

/* Defaults: pref anchors, F0 0.1 cycles/px, w0 0, anisotropic, r 16 px, N0 32, seed 0, h0 1,
 * W 4, hard depth test at 5%, no supersampling, uniform amplitudes, unit output, contrast 0.15. */
NPRFX_API void nprfx_gabor_params_default(nprfx_gabor_params *p);

typedef struct nprfx_gabor_inputs {
    size_t size;                    /* sizeof(nprfx_gabor_inputs) */
    const nprfx_image *anchor;      /* 3D: x,y,z[,coverage]; 2D: u,v[,coverage] */
    const nprfx_image *depth;       /* 1 channel; background: <= 0, >= 1e9, inf or NaN */
    const nprfx_image *id;          /* optional (NULL): object index, 1 channel */
    const nprfx_image *orientation; /* optional: 1 channel angle in degrees, or 2 channels a
                                       direction (x right, y down), added to w0 */
    const nprfx_image *frequency;   /* optional: 1 channel, multiplies F0 */
} nprfx_gabor_inputs;

typedef struct nprfx_gabor_stats {
    long long kernels;     /* points emitted with nonzero weight by pixels inside the window */
    double weight2;        /* the sum of their squared weights (expected: lambda * pixels) */
    long long evaluations; /* kernel-sample evaluations (inside the truncation disk) for the
                              window */
} nprfx_gabor_stats;

/* Kernel bandwidth a for a truncation radius r (pixels). */
NPRFX_API double nprfx_gabor_bandwidth(double radius);

/* A frequency in cycles per pixel at a host's render scale (1 at full resolution, e.g. 0.5 for
 * a proxy; <= 0 is taken as 1): sizes in pixels scale with it, so a frequency per pixel scales
 * inversely. */
NPRFX_API double nprfx_gabor_frequency_at_scale(double frequency, double render_scale);

/* Theoretical variance of the un-normalised sum at frequency F0 * frequency_scale:
 * lambda E[v^2] (1 / (4 a^2)) (1 + exp(-2 pi F^2 / a^2)) times the truncation factor
 * (1 - 0.05^2) and, with supersampling, the box filter's attenuation of the spectrum. */
NPRFX_API double nprfx_gabor_variance(const nprfx_gabor_params *p, double frequency_scale);

/* The level-of-detail rule. mu is the wanted density in points per level-0 cell area
 * (D h0^2 with D = lambda / |det J|); level l has 4^l points per level-0 cell area. Writes the
 * squared weights of levels first, first+1, ... into w2 (at most max) and returns their count
 * (levels past the count have weight 0). sum_l w2 * 4^l = mu for mu up to 4^40. */
NPRFX_API int nprfx_gabor_lod_weights(double mu, int lod_levels, int *first_level, double *w2,
                                      int max);

/* Render the window of out (channel 0 the noise; channel 1 the point weights when p->points;
 * out->channels must be 1 + points). The inputs are read over their bounds; pixels of the
 * window outside them are written as background (0, or 0.5 for unit01). Work is spread over
 * the context's executor. stats may be NULL. */
NPRFX_API nprfx_result nprfx_gabor_render(nprfx_context *ctx, const nprfx_gabor_params *p,
                                          const nprfx_gabor_inputs *in, nprfx_rect window,
                                          nprfx_image *out, nprfx_gabor_stats *stats);

/* ---- the gabor-splat node (its descriptor is plugins/gabor_splat.c) ---- */

/* Anchor spaces of the node's anchor_space param. */
typedef enum nprfx_gabor_anchor_space {
    NPRFX_GABOR_SPACE_PREF = 0, /* 3D object-space position */
    NPRFX_GABOR_SPACE_UV = 1,   /* 2D texture coordinates */
    NPRFX_GABOR_SPACE_P = 2,    /* 3D world position (static objects only) */
    NPRFX_GABOR_SPACE_COUNT
} nprfx_gabor_anchor_space;

/* The node's inputs, in the descriptor's order (args->inputs). */
enum {
    NPRFX_GABOR_SPLAT_IN_ANCHOR = 0,      /* 3D: x,y,z[,coverage]; 2D: u,v[,coverage] */
    NPRFX_GABOR_SPLAT_IN_DEPTH = 1,       /* 1 channel */
    NPRFX_GABOR_SPLAT_IN_ID = 2,          /* optional: object index, 1 channel */
    NPRFX_GABOR_SPLAT_IN_ORIENTATION = 3, /* optional: 1 channel angle or 2 channels direction */
    NPRFX_GABOR_SPLAT_IN_FREQUENCY = 4,   /* optional: 1 channel, multiplies F0 */
    NPRFX_GABOR_SPLAT_IN_COUNT
};

/* The node's params, as its descriptor binds them by offset. gabor's frequency, orientation,
 * isotropic, radius (already multiplied by the render scale), n0, amplitude, cell, lod_levels,
 * fade, depth_test, depth_tolerance, supersample, output, contrast and points are the params of
 * those names; nprfx_gabor_splat_render sets the rest of the algorithm's params: size,
 * anchor_dims (from anchor_space), seed (from seed) and the frequency at the render scale
 * (nprfx_gabor_frequency_at_scale of gabor.frequency, which is at render scale 1). */
typedef struct nprfx_gabor_splat_params {
    nprfx_gabor_params gabor;
    int anchor_space; /* nprfx_gabor_anchor_space */
    int seed;         /* >= 0: gabor.seed */
} nprfx_gabor_splat_params;

/* The node's render of args->window into args->output, inputs NPRFX_GABOR_SPLAT_IN_*: checks
 * what only this node knows (the anchor's channels for its space, the orientation input's), then
 * nprfx_gabor_render. *args->items, when not NULL, grows by the kernels splatted. */
NPRFX_API nprfx_result nprfx_gabor_splat_render(const nprfx_render_args *args,
                                                const nprfx_gabor_splat_params *p);

#ifdef __cplusplus
}
#endif
#endif
