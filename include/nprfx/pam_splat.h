/* nprfx — painterly rendering with a painterly art map (Yan, Chi, Lee, Lin, "Stylized Rendering
 * Using Samples of a Painted Image", IEEE TVCG 14(2), 2008, §5), docs/design.md §3.7.
 *
 * A PAM (painterly art map) is one RGB image: `count` square, tileable maps of S x S pixels side
 * by side, left to right from dark to light (width = count * S, height = S, count >= 2), linear
 * float. The pam-splat node covers the surfaces with splats placed by gabor-splat's
 * anchored-point scatter (constant density on screen, continuous level of detail, so they stay
 * on the surfaces frame to frame). Each splat is a Gaussian-edged patch of the PAM at the local
 * tone, its rows (the PAM's v axis, along which its strokes run) turned along the direction
 * field, and changes the model colour by the PAM's luminance and chroma deviations (Eq. 9-10):
 *
 *     S_Y  = model_Y  + beta  * (texel_Y  - mean_Y)
 *     S_UV = model_UV + gamma * (texel_UV - mean_UV)
 *
 * with mean the PAM's mean over all its maps (Eq. 9's single mean, so darker maps darken and
 * lighter ones lighten). The deviation is split into the tone's part (the local maps' mean minus
 * the PAM's) and the strokes' (the texel minus its map's mean), the latter scaled by `detail`:
 * 1 is the paper's Eq. 10, more shows the strokes without darkening the shadows further. The
 * texture can flow along the direction with time (Eq. 11). */
#ifndef NPRFX_PAM_SPLAT_H
#define NPRFX_PAM_SPLAT_H

#include <stddef.h>
#include <stdint.h>

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"
#include "nprfx/pam.h" /* the format, YUV, NPRFX_PAM_MAX_MAPS */

#ifdef __cplusplus
extern "C" {
#endif

/* ---- the PAM ---- */

/* What the node knows of a PAM: its layout and means, measured from the pixels. */
typedef struct nprfx_pam_stats {
    int count;                        /* maps */
    int size;                         /* S: each map is S x S */
    double map_y[NPRFX_PAM_MAX_MAPS]; /* each map's mean luminance (BT.601 Y) */
    double mean[3];                   /* Eq. 9's mean: Y, U, V over every map */
} nprfx_pam_stats;

/* Check that pam is a PAM (3 or more channels, finite pixels, width a multiple >= 2 of its
 * height, at most NPRFX_PAM_MAX_MAPS maps) and measure it. Errors name `who` ("pam-splat: input
 * 'pam'") and the image's size. */
NPRFX_API nprfx_result nprfx_pam_measure(nprfx_context *ctx, const nprfx_image *pam,
                                         const char *who, nprfx_pam_stats *info);

/* Where tone w lands among the maps: maps i and i + 1 mixed as (1 - t) map_i + t map_(i+1).
 * w is clamped to [0, 1] (NaN: 0) and picks the luminance map_y[0] + w (map_y[count-1] -
 * map_y[0]) on the running maximum of map_y (a PAM whose means dip is read as flat there); when
 * the maps' means do not rise at all, w is spread evenly over the maps. */
NPRFX_API void nprfx_pam_tone_position(const nprfx_pam_stats *info, double w, int *i, double *t);

/* The builtin PAM the node uses when no pam input is connected: `count` maps of `size` px (0:
 * 6 maps of 64 px) of short vertical brush strokes from dark to light, tileable, made from
 * hashes (the same on every machine). Allocates out (3 channels, origin at 0, 0). */
NPRFX_API nprfx_result nprfx_pam_builtin(nprfx_context *ctx, int count, int size, uint64_t seed,
                                         nprfx_image *out);

/* ---- the pam-splat node (its descriptor is plugins/pam_splat.c) ---- */

typedef enum nprfx_pam_anchor_space {
    NPRFX_PAM_SPACE_PREF = 0, /* 3D rest position */
    NPRFX_PAM_SPACE_UV = 1,   /* 2D texture coordinates */
    NPRFX_PAM_SPACE_COUNT
} nprfx_pam_anchor_space;

/* Where the model colour is read (the paper's colour of a splat, or each pixel's own). */
typedef enum nprfx_pam_color_from {
    NPRFX_PAM_COLOR_SPLAT = 0, /* at the splat's centre: each dab one colour, blended like the
                                  strokes (model edges become dab-shaped) */
    NPRFX_PAM_COLOR_PIXEL = 1, /* per pixel: the model's edges stay sharp */
    NPRFX_PAM_COLOR_COUNT
} nprfx_pam_color_from;

/* The node's params as its descriptor binds them (pixel lengths already times the render
 * scale). */
typedef struct nprfx_pam_splat_params {
    int anchor_space;       /* nprfx_pam_anchor_space */
    double size;            /* splat diameter in pixels (Gaussian edge: 5% at the rim) */
    double density;         /* expected number of splats overlapping a pixel */
    double beta, gamma;     /* Eq. 10: luminance and chroma strength */
    double detail;          /* the strokes' share of Eq. 10 against the tone's (1: the paper's) */
    double sharpness;       /* >= 1: how much the nearest splat dominates where splats overlap */
    double aspect;          /* >= 1: dabs this many times longer along the direction */
    double texel;           /* screen pixels per PAM pixel; 0: size / (S / 2) */
    int color_from;         /* nprfx_pam_color_from */
    double orientation;     /* degrees, counter-clockwise, added to the direction */
    double flow;            /* Eq. 11: texture speed along the direction, pixels per frame */
    double jitter;          /* Eq. 11's noise offsets: per splat, in map widths (1: anywhere) */
    int seed;               /* >= 0 */
    double cell;            /* the scatter's level-0 cell (anchor units) */
    double depth_tolerance; /* relative depth error a splat's fragment tolerates */
} nprfx_pam_splat_params;

/* The node's inputs, in the descriptor's order (args->inputs). */
enum {
    NPRFX_PAM_SPLAT_IN_ANCHOR = 0, /* Pref (3 channels) or UV (2), optional coverage after them */
    NPRFX_PAM_SPLAT_IN_TONE = 1,   /* 1 channel, w in [0, 1] (clamped) */
    NPRFX_PAM_SPLAT_IN_COLOR = 2,  /* model colour, RGB or RGBA: the output has its channels */
    NPRFX_PAM_SPLAT_IN_DIRECTION = 3, /* optional: 1 channel degrees, or 2 a direction (x right, y
                                         down) */
    NPRFX_PAM_SPLAT_IN_DEPTH = 4,     /* 1 channel */
    NPRFX_PAM_SPLAT_IN_ID = 5,        /* optional, 1 channel */
    NPRFX_PAM_SPLAT_IN_PAM = 6,       /* optional (not connected: the builtin PAM), passed whole */
    NPRFX_PAM_SPLAT_IN_COUNT
};

/* Render args->window of args->output at frame args->time. args->state: the node instance's
 * cache slot (may be NULL): the measured PAM, keyed by a fingerprint of its pixels; it never
 * changes a result. *args->items, when not NULL, grows by the splats owned by pixels of the
 * window. */
NPRFX_API nprfx_result nprfx_pam_splat_render(const nprfx_render_args *args,
                                              const nprfx_pam_splat_params *p);

/* Free a state left in the node's slot. */
NPRFX_API void nprfx_pam_splat_state_free(void *state);

#ifdef __cplusplus
}
#endif
#endif
