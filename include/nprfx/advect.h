/* nprfx — the advect node: texture coordinates carried along the motion vectors, for footage
 * without UV or rest-position AOVs (Neyret 2003, "Advected textures"; Bousseau et al. 2007,
 * "Video watercolorization using bidirectional texture advection"; docs/design.md §3.16).
 *
 * Two layers, a and b, each restart from the identity (uv = pixel / 1024) every `period` frames,
 * b half a period after a, and between restarts follow the motion: X_t(x) = X_{t-1}(x + m_t(x)),
 * m = motion_prev, a bilinear lookup. A pixel whose previous position is outside the frame, whose
 * motion is not finite or whose confidence is low gets a fresh coordinate (the identity). The
 * output's `mix` blends the two (temporal triangle weights times a distortion factor), so no
 * restart ever shows. A layer's history starts at its last restart, so any frame is the same
 * whether rendered in order or alone. */
#ifndef NPRFX_ADVECT_H
#define NPRFX_ADVECT_H

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The node's inputs, in the descriptor's order (args->inputs and args->fetch use them). */
enum { NPRFX_ADVECT_IN_MOTION_PREV = 0, NPRFX_ADVECT_IN_CONFIDENCE = 1, NPRFX_ADVECT_IN_COUNT };

/* Output channels: a.U, a.V, b.U, b.V, mix. */
#define NPRFX_ADVECT_CHANNELS 5

/* Pixels per coordinate unit at render scale 1: the identity is pixel / 1024, the UV the stipple
 * node gives an image without a uv input (NPRFX_STIPPLE_PLANE_PIXELS). */
#define NPRFX_ADVECT_PLANE_PIXELS 1024.0

/* Which channels the node outputs (its `output` param). An OpenFX host carries at most four
 * channels (R, G, B and the last one in alpha, docs/design.md §1), so a host takes `layers` and
 * `mix` from two instances; the runner takes `all` from one. */
typedef enum nprfx_advect_output {
    NPRFX_ADVECT_OUTPUT_ALL = 0,    /* a.U, a.V, b.U, b.V, mix */
    NPRFX_ADVECT_OUTPUT_LAYERS = 1, /* a.U, a.V, b.U, b.V */
    NPRFX_ADVECT_OUTPUT_MIX = 2,    /* mix */
    NPRFX_ADVECT_OUTPUT_COUNT
} nprfx_advect_output;

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_advect_params {
    int layers;            /* 1 or 2 */
    int period;            /* frames between two restarts of a layer (2 layers) */
    double max_distortion; /* stretch ratio s1/s2 of dX/dx where a layer's weight starts to fall */
    double min_confidence; /* below it (or NaN) a pixel is re-seeded */
    int output;            /* nprfx_advect_output */
    /* Not a param: what the motion input is multiplied by to be in the frame's pixels (the render
     * args' vector_scale: a host's proxy render gives vectors in full-resolution pixels); 0: 1. */
    double motion_scale;
} nprfx_advect_params;

/* The output's channel count and names for an nprfx_advect_output (0 and NULL when there is no
 * such option); names[] has room for NPRFX_ADVECT_CHANNELS. */
NPRFX_API int nprfx_advect_output_channels(int output, const char **names);

/* Where layer `layer` (0: a, 1: b) stands at frame `time` of the shot [first_frame, last_frame]
 * (last < first: unknown; frames are then counted from 0). */
typedef struct nprfx_advect_layer_time {
    int restart; /* the frame its coordinates were the identity: its history starts there */
    int age;     /* frames since its last periodic restart, in [0, period) (2 layers) */
    double tri;  /* temporal weight 1 - |2 age / period - 1|: 0 at a restart (2 layers); 1 (1) */
} nprfx_advect_layer_time;

/* Params in range: layers 1 or 2, period >= 2, max_distortion >= 1, min_confidence finite, an
 * output option. */
NPRFX_API nprfx_result nprfx_advect_check(nprfx_context *ctx, const nprfx_advect_params *p);

/* The restart schedule. With 2 layers, layer a restarts at frames first + k * period, layer b at
 * first + period / 2 + k * period (integer division), and both at the shot's first frame (no
 * history before it; the weight still follows the periodic age, so the blend's schedule does not
 * depend on where the shot starts within it). With 1 layer, the only restart is the shot's first
 * frame (the shot must be known) and tri = 1. */
NPRFX_API void nprfx_advect_schedule(const nprfx_advect_params *p, int layer, int time,
                                     int first_frame, int last_frame, nprfx_advect_layer_time *out);

/* The identity coordinates over `window` of coords (2 channels): ((x - frame.x0) / plane,
 * (y - frame.y0) / plane), plane = NPRFX_ADVECT_PLANE_PIXELS * render scale. */
NPRFX_API void nprfx_advect_seed(nprfx_rect frame, double plane, nprfx_rect window,
                                 nprfx_image *coords);

/* One step of the recursion over the whole frame: next(x) = prev(x + s motion(x)), bilinear (s =
 * p->motion_scale, 1 when 0), where
 * prev and next are 2-channel images over `frame`. A pixel is re-seeded (the identity) where its
 * motion is not finite, its confidence (NULL: not connected) is below min_confidence or not
 * finite, or x + motion(x) lies outside [x0, x1 - 1] x [y0, y1 - 1]. Inputs read 0 outside their
 * data windows (§2): motion 0, confidence 0. Parallel over rows; deterministic. */
NPRFX_API nprfx_result nprfx_advect_step(nprfx_context *ctx, const nprfx_advect_params *p,
                                         nprfx_rect frame, double plane, const nprfx_image *prev,
                                         const nprfx_image *motion, const nprfx_image *confidence,
                                         nprfx_image *next);

/* The distortion factor of a layer whose Jacobian at a pixel is J = {dU/dx, dU/dy, dV/dx,
 * dV/dy} in units of the identity's (so the identity gives {1, 0, 0, 1}): with singular values
 * s1 >= s2 and q = s1 / s2, 1 for q <= max_distortion, 2 - q / max_distortion down to 0 at twice
 * it; 0 where J folds (det <= 0) or is not finite. A uniform scale (a zoom) is not a distortion:
 * stipple and gabor-splat follow |det J|. */
NPRFX_API double nprfx_advect_distortion(const double J[4], double max_distortion);

/* The output over `window` (5 channels) from the layers' coordinates over `frame` (b NULL: one
 * layer, b = a and mix = 1) and their schedules: w_l = tri_l * distortion_l, mix = w_a / (w_a +
 * w_b), and where both are 0 the younger layer (a on a tie). J by central differences, one-sided
 * at the frame's edges. */
NPRFX_API nprfx_result nprfx_advect_combine(nprfx_context *ctx, const nprfx_advect_params *p,
                                            nprfx_rect frame, double plane, const nprfx_image *a,
                                            const nprfx_image *b, const nprfx_advect_layer_time *ta,
                                            const nprfx_advect_layer_time *tb, nprfx_rect window,
                                            nprfx_image *out);

/* Render args->window of the node at args->time (the channels p->output picks): inputs
 * NPRFX_ADVECT_IN_*, other frames through
 * args->fetch. args->state (may be NULL) keeps the latest layer states and result, so in-order
 * rendering costs one step per layer and frame; results never depend on it. */
NPRFX_API nprfx_result nprfx_advect_render(const nprfx_render_args *args,
                                           const nprfx_advect_params *p);

/* The frames input `input` is read at for frame q->time with an empty cache (frames_needed):
 * motion_prev and a connected confidence from the earliest layer's restart + 1 to the frame. */
NPRFX_API int nprfx_advect_frames(const nprfx_advect_params *p, const nprfx_frames_query *q,
                                  int input, nprfx_frame_range *ranges);

/* Frees what nprfx_advect_render keeps in the instance's state. */
NPRFX_API void nprfx_advect_state_free(void *state);
/* The most bytes that state holds for frames of width x height with output_channels: both
 * layers' coordinates, a step's scratch and the last whole output. */
NPRFX_API double nprfx_advect_state_bytes(int width, int height, int output_channels);

#ifdef __cplusplus
}
#endif
#endif
