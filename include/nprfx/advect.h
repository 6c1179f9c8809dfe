/* nprfx — the advect node: texture coordinates carried along the motion of any footage, for the
 * surface-anchored nodes (stipple's and gabor-splat's anchors) where there is no UV pass
 * (docs/design.md §3.15). Two layers of coordinates start from the image plane at staggered
 * times, are advected frame by frame along motion_prev (bilinear), and start again each period;
 * a weight fades each layer in after its start and out before the next, so that where the two
 * are mixed no restart ever shows (Neyret, "Advected Textures", SCA 2003; Bousseau, Neyret,
 * Thollot, Salesin, "Video Watercolorization using Bidirectional Texture Advection", SIGGRAPH
 * 2007). Pixels whose motion is unreliable (low confidence, a NaN, a source outside the frame)
 * start afresh on the spot, as disoccluded surface does. */
#ifndef NPRFX_ADVECT_H
#define NPRFX_ADVECT_H

#include "nprfx/context.h"
#include "nprfx/export.h"
#include "nprfx/image.h"
#include "nprfx/node.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_advect_params {
    int period;       /* frames a layer lives before it starts again, >= 2 */
    double scale;     /* pixels per UV unit where a layer starts (1024: stipple's plane) */
    double threshold; /* confidence below which a pixel starts afresh */
    int seed;         /* shifts each start's coordinates */
} nprfx_advect_params;

/* The node's inputs, in its descriptor's order. */
enum { NPRFX_ADVECT_IN_MOTION, NPRFX_ADVECT_IN_CONFIDENCE, NPRFX_ADVECT_IN_COUNT };

/* Output channels: layer A's u, v, layer B's u, v, and the weight of A (B's is 1 - weight). */
#define NPRFX_ADVECT_CHANNELS 5

/* The frame where layer (0 or 1) last started at or before `time`: layers start every `period`
 * frames, B half a period after A, counted from frame 0; never before first_frame (when the
 * shot is known, first_frame <= last_frame), where both start. */
NPRFX_API int nprfx_advect_start(const nprfx_advect_params *p, int layer, int time, int first_frame,
                                 int last_frame);
/* Layer A's weight at `time`: a triangle over each layer's life (0 at its start, 1 halfway),
 * normalised with B's so that the two sum to 1. */
NPRFX_API double nprfx_advect_weight(const nprfx_advect_params *p, int time);

/* Render args->window (a render call's arguments, as nprfx_node_render hands them on): the
 * coordinates are computed for the whole frame once, kept in *args->state (NULL: none kept)
 * for the next frame, which then takes one step. Results never depend on what was kept.
 * Free the state with nprfx_advect_state_free. */
NPRFX_API nprfx_result nprfx_advect_render(const nprfx_render_args *args,
                                           const nprfx_advect_params *p);
NPRFX_API void nprfx_advect_state_free(void *state);

#ifdef __cplusplus
}
#endif
#endif
