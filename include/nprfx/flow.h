/* nprfx — dense optical flow between neighbouring frames (the `flow` node, docs/design.md §3.15).
 *
 * The solver is not part of the library: core stays C11 + libm, so a front end hands the context
 * a flow provider (the runner and the OpenFX bundle give OpenCV's DIS, common/flow_opencv.h). Core
 * turns any image into luminance, downscales it, calls the provider for each direction, upsamples
 * the flow, and derives a confidence from a forward-backward and a photometric check. */
#ifndef NPRFX_FLOW_H
#define NPRFX_FLOW_H

#include <stddef.h>

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* How hard the provider works: DIS's presets (OpenCV's PRESET_ULTRAFAST, _FAST, _MEDIUM). */
typedef enum nprfx_flow_preset {
    NPRFX_FLOW_ULTRAFAST = 0,
    NPRFX_FLOW_FAST = 1,
    NPRFX_FLOW_MEDIUM = 2,
    NPRFX_FLOW_PRESET_COUNT = 3
} nprfx_flow_preset;

/* Dense flow from `from` to `to`: both w x h single-channel float images, packed rows (pixel
 * (x, y) at [y * w + x]), y down, finite values in [0, 1] (core has mapped luminance there).
 * Writes flow[2 * (y * w + x) + 0/1] = where pixel (x, y) of `from` is in `to`, minus (x, y), in
 * pixels. The result must depend only on the two images, the size and the preset (never on
 * threads or earlier calls): the node's output is bit-identical whatever the order. May be called
 * from several threads at once. Returns NPRFX_OK, or an error code after raising a message on ctx
 * that names the provider. */
typedef nprfx_result (*nprfx_flow_compute_fn)(void *user, nprfx_context *ctx, const float *from,
                                              const float *to, int w, int h,
                                              nprfx_flow_preset preset, float *flow);

/* A flow provider, size-versioned like every init struct: fields are appended. The typedef is in
 * nprfx/context.h (nprfx_context_init.flow points to one). */
struct nprfx_flow_provider {
    size_t size;      /* sizeof(nprfx_flow_provider) */
    const char *name; /* "OpenCV 4.6.0 DIS": messages */
    nprfx_flow_compute_fn compute;
    void *user;
};

/* The flow node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_flow_params {
    int preset;         /* nprfx_flow_preset */
    double scale;       /* solve at this fraction of the resolution, (0, 1] */
    double consistency; /* forward-backward threshold in pixels (the Gaussian's sigma) */
    double photometric; /* luminance difference threshold (sigma), 0: no photometric term */
    int output;         /* nprfx_flow_output: which channels */
} nprfx_flow_params;

/* The flow channels, in the order the whole output (NPRFX_FLOW_OUT_ALL) has them. */
enum {
    NPRFX_FLOW_PREV_X = 0,
    NPRFX_FLOW_PREV_Y = 1,
    NPRFX_FLOW_NEXT_X = 2,
    NPRFX_FLOW_NEXT_Y = 3,
    NPRFX_FLOW_CONF_PREV = 4,
    NPRFX_FLOW_CONF_NEXT = 5,
    NPRFX_FLOW_CHANNELS = 6
};

/* Which channels the node outputs. An OpenFX host image carries at most four, so a host takes
 * one direction or the vectors alone; a direction no channel shows is not solved. */
typedef enum nprfx_flow_output {
    NPRFX_FLOW_OUT_ALL = 0,     /* the six channels above */
    NPRFX_FLOW_OUT_PREV = 1,    /* motion_prev.X/Y, confidence.prev */
    NPRFX_FLOW_OUT_NEXT = 2,    /* motion_next.X/Y, confidence.next */
    NPRFX_FLOW_OUT_VECTORS = 3, /* motion_prev.X/Y, motion_next.X/Y */
    NPRFX_FLOW_OUTPUT_COUNT = 4
} nprfx_flow_output;

/* The flow channels (NPRFX_FLOW_PREV_X ...) output `output` has, in order, into which (up to
 * NPRFX_FLOW_CHANNELS; may be NULL); returns how many, 0 for no such output. */
NPRFX_API int nprfx_flow_output_channels(int output, int *which);

/* Luminance of an image, as the flow sees it: Rec. 709 luma for 3 or 4 channels, else channel
 * 0; then x / (1 + x) for x >= 0 (scene-linear highlights compress into [0, 1) so that a flow
 * solver working on 8 bits keeps detail in the darks and the brights), 0 for x < 0 and where a
 * channel is not finite (missing). `lum` holds w x h floats of the image's bounds (packed); `ok`,
 * when not NULL, receives 1 where the pixel was finite, else 0. */
NPRFX_API void nprfx_flow_luminance(const nprfx_image *im, float *lum, unsigned char *ok);

/* Flow from luminance a to luminance b (both w x h packed, as nprfx_flow_luminance gives) by
 * ctx's provider: at `scale` < 1 both are box-downscaled to ceil(w * scale) x ceil(h * scale)
 * first and the flow is bilinearly upsampled and multiplied by w / sw (resp. h / sh) after. Non-
 * finite vectors from the provider become 0. flow: 2 * w * h floats. */
NPRFX_API nprfx_result nprfx_flow_solve(nprfx_context *ctx, const float *a, const float *b, int w,
                                        int h, double scale, nprfx_flow_preset preset, float *flow);

/* Confidence of the flow f_ab (a to b) given the flow f_ba back and both luminances (w x h
 * packed), per pixel x with y = x + f_ab(x) (docs/design.md §3.15):
 *   e_fb = |f_ab(x) + f_ba(y)|,  e_ph = |lum_a(x) - lum_b(y)|   (bilinear at y)
 *   conf = exp(-e_fb^2 / (2 consistency^2)) * exp(-e_ph^2 / (2 photometric^2))
 * and 0 where y lies outside the other frame's pixels ([-0.5, w-0.5) x [-0.5, h-0.5); lookups
 * within half a pixel of the edge clamp to it), where ok_a(x) is 0 or a tap of ok_b at y is 0
 * (either may be NULL: all valid). photometric <= 0 leaves the photometric term out.
 * conf: w x h floats. */
NPRFX_API void nprfx_flow_confidence(const float *f_ab, const float *f_ba, const float *lum_a,
                                     const float *lum_b, const unsigned char *ok_a,
                                     const unsigned char *ok_b, int w, int h, double consistency,
                                     double photometric, float *conf);

/* The cut gate: every confidence of a direction is multiplied by it, from the share of the
 * frame's pixels whose confidence is at least 0.5: smoothstep from 0 at a share of 0.6 (much of
 * the frame has no match: a cut) to 1 at 0.85 and above (docs/design.md §3.15). */
NPRFX_API double nprfx_flow_cut_gate(double consistent);

/* The node's inputs, in the descriptor's order (args->inputs and args->fetch use them). */
enum { NPRFX_FLOW_IN_IMAGE = 0, NPRFX_FLOW_IN_COUNT };

/* Render args->window of out = args->output (the channels of p->output,
 * nprfx_flow_output_channels) at frame args->time of the shot [args->first_frame,
 * args->last_frame]: the flows to the previous and next frames (the input NPRFX_FLOW_IN_IMAGE
 * fetched through args->fetch) in the motion convention of docs/design.md §2, with their
 * confidences. At the shot's first frame the prev channels are 0, at its last the next ones.
 * args->state: NULL, or the node's instance slot, where the last pair of flows is cached (the
 * result never depends on it); free it with nprfx_flow_state_free. */
NPRFX_API nprfx_result nprfx_flow_render(const nprfx_render_args *args, const nprfx_flow_params *p);
NPRFX_API void nprfx_flow_state_free(void *state);
/* The most bytes that state holds for frames of width x height: its solved pairs (luminances,
 * masks, both flows and both confidences of each). */
NPRFX_API double nprfx_flow_state_bytes(int width, int height);

#ifdef __cplusplus
}
#endif
#endif
