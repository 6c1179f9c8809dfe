/* nprfx — ink lines from AOVs: outlines where the object id or the coverage changes, depth
 * discontinuities, normal creases and jumps of a custom AOV, drawn as anti-aliased strokes of a
 * set width centred on the edge (docs/design.md §3.11). The anchors are the line passes of
 * stylised renderers: RenderMan's Stylized Lines (outline, id sections, normal + Z, a custom AOV,
 * thickness from lighting) and MoonRay's toon filter (edge detection on depth and normals with
 * thresholds). The node is per-frame and stateless; temporal coherence comes from its inputs
 * (AOVs per frame, wobble and texture from coherent noise). */
#ifndef NPRFX_LINES_H
#define NPRFX_LINES_H

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_lines_params {
    double width;           /* line width in pixels, [0, 256] */
    double thicken;         /* with the width input w: width * (1 + thicken * (1 - w)), >= 0 */
    int outline;            /* lines where id differs or coverage crosses 0.5 */
    int depth_edges;        /* lines at depth discontinuities */
    double depth_threshold; /* relative depth jump that makes a line, >= 0 */
    int creases;            /* lines where neighbouring normals differ by > crease_angle */
    double crease_angle;    /* degrees, [0, 180] */
    int aov_edges;          /* lines where the aov input jumps by > aov_threshold */
    double aov_threshold;   /* >= 0 */
    double wobble;          /* displacement amplitude in pixels, [0, 256] */
    double texture_amount;  /* [0, 1]: ink *= 1 - texture_amount * (1 - texture) */
    double opacity;         /* [0, 1]: multiplies the ink */
} nprfx_lines_params;

/* The node's inputs, in the descriptor's order (args->inputs), each optional; at least one of
 * id, coverage, depth, normal and aov must be connected. */
enum {
    NPRFX_LINES_IN_ID = 0,       /* 1 channel: object index */
    NPRFX_LINES_IN_COVERAGE = 1, /* 1 channel: anti-aliased object coverage */
    NPRFX_LINES_IN_DEPTH = 2,    /* 1 channel; background: not finite, >= 1e9 or <= 0 */
    NPRFX_LINES_IN_NORMAL = 3,   /* 3 channels, any length (normalised here) */
    NPRFX_LINES_IN_AOV = 4,      /* 1 to 4 channels: a custom pass (shadow, light) */
    NPRFX_LINES_IN_WIDTH = 5,    /* 1 channel in [0, 1]: thickness control (tone, lighting) */
    NPRFX_LINES_IN_WOBBLE = 6,   /* 1 or 2 channels in [0, 1] around 0.5: displacement noise */
    NPRFX_LINES_IN_TEXTURE = 7,  /* 1 channel in [0, 1]: multiplies the ink */
    NPRFX_LINES_IN_COUNT
};

/* Render args->window of out = args->output (1 channel: ink coverage in [0, 1], 1 = full ink). Edge
 * points sit between the centres of neighbouring pixels, at the coverage's 0.5 crossing where
 * coverage is connected and crosses there, else at the midpoint; inside each 2x2 cell of pixel
 * centres they are joined into segments (marching squares; three or four points join at their
 * mean). A pixel at distance d from the nearest segment, after the wobble displacement, gets ink =
 * clamp(w / 2 - d + 0.5, 0, 1), the box-filtered coverage of a stroke of width w, with w read at
 * the edge. args->frame is the whole image domain: pairs of pixels never reach outside it, so every
 * tile sees the same edges. Runs on ctx's executor; bit-identical for any thread count and window
 * split. */
NPRFX_API nprfx_result nprfx_lines_render(const nprfx_render_args *args,
                                          const nprfx_lines_params *p);

#ifdef __cplusplus
}
#endif
#endif
