/* nprfx — coherent noise (Kass & Pesare 2011), the core of the `coherent-noise` node.
 *
 * A recursion over frames, per pixel x of frame i (docs/design.md §3.1):
 *   p = x + motion(x)                              (where the surface point was in the pass's
 *                                                   previous frame: i-1 forward, i+1 backward)
 *   fresh if p leaves the frame, the depth at x is background, or the predicted depth
 *   z(x) -/+ zvel(x) is farther than depth_prev(p) * (1 + epsilon)
 *   u_i(x) = w_i(x)                                        if fresh
 *          = alpha * R[u_{i-1}](p) + sqrt(1 - alpha^2) * w_i(x)   otherwise
 * in unit-variance form: u = c / k(alpha) with k = sqrt((1-alpha)/(1+alpha)) (the paper's Eq. 6-7
 * divided by k, which keeps alpha = 1 well defined: frozen noise).
 *
 * R is the resampler. The paper's bilinear lookup lowers variance and removes high frequencies at
 * every fractional step, so a long shot fades and blurs. The default resampler here is Catmull-Rom
 * plus *spectral compensation*: fresh noise, shaped by a small filter G(f) with
 * |H_f(w)|^2 + |G_f(w)|^2 = 1 for the interpolation filter H_f of the pixel's fractional offset f,
 * replaces exactly the power the interpolation removed. For locally uniform motion a field with the
 * innovation's spectrum keeps that spectrum, hence its variance, frame after frame.
 *
 * Input mode filters a clip instead: u_i = alpha * R[u_{i-1}](p) + (1 - alpha) s_i, fresh: s_i, and
 * no compensation (it is not noise). */
#ifndef NPRFX_COHERENT_NOISE_H
#define NPRFX_COHERENT_NOISE_H

#include <stdint.h>

#include "nprfx/image.h"
#include "nprfx/export.h"
#include "nprfx/node.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum nprfx_cn_noise {
    NPRFX_CN_NOISE_WHITE = 0,
    NPRFX_CN_NOISE_BANDPASS = 1,
    NPRFX_CN_NOISE_INPUT = 2
} nprfx_cn_noise;

typedef enum nprfx_cn_resample {
    NPRFX_CN_RESAMPLE_STATIONARY = 0, /* Catmull-Rom + spectral compensation (default) */
    NPRFX_CN_RESAMPLE_BILINEAR = 1    /* the paper's bilinear lookup (fades on sub-pixel motion) */
} nprfx_cn_resample;

#define NPRFX_CN_FORWARD 1   /* causal pass, motion to the previous frame */
#define NPRFX_CN_BACKWARD -1 /* time-reversed pass, motion to the next frame */

/* Depth at or beyond this (or not finite) is background. */
#define NPRFX_CN_BACKGROUND_DEPTH 1e9

typedef struct nprfx_cn_params {
    size_t size;     /* sizeof(nprfx_cn_params) */
    double alpha;    /* [0, 1] */
    double epsilon;  /* relative depth tolerance of the occlusion test, >= 0 */
    int noise;       /* nprfx_cn_noise */
    double sigma_lo; /* band-pass: the smaller Gaussian sigma (pixels; 0: no high cut) */
    double sigma_hi; /* band-pass: the larger Gaussian sigma (pixels; 0: no low cut) */
    int channels;    /* channels of the state: 1..4 for noise, the source's for input mode */
    uint64_t seed;
    int resample;        /* nprfx_cn_resample */
    double motion_scale; /* motion vectors are multiplied by this (render scale); 1 normally */
} nprfx_cn_params;

NPRFX_API void nprfx_cn_params_default(nprfx_cn_params *p);
/* Range checks; the message names the offending field. */
NPRFX_API nprfx_result nprfx_cn_params_check(nprfx_context *ctx, const nprfx_cn_params *p);

/* k(alpha) = sqrt((1 - alpha) / (1 + alpha)) (Eq. 6). */
NPRFX_API double nprfx_cn_k(double alpha);

/* One pass's state at one frame, covering the whole frame rectangle. */
typedef struct nprfx_cn_state {
    nprfx_image value;    /* `channels` floats per pixel: unit-variance noise or filtered input */
    unsigned char *fresh; /* per pixel (row-major over value.bounds): 1 where the pass restarted */
} nprfx_cn_state;

NPRFX_API nprfx_result nprfx_cn_state_alloc(nprfx_context *ctx, nprfx_rect frame, int channels,
                                            nprfx_cn_state *out);
NPRFX_API void nprfx_cn_state_free(nprfx_cn_state *s);
/* Row-parallel over ctx's executor. */
NPRFX_API nprfx_result nprfx_cn_state_copy(nprfx_context *ctx, const nprfx_cn_state *src,
                                           nprfx_cn_state *dst);
NPRFX_API size_t nprfx_cn_state_bytes(nprfx_rect frame, int channels);

/* What one step reads (views may have any bounds; reads outside them clamp to the edge). */
typedef struct nprfx_cn_inputs {
    const nprfx_image *depth;      /* frame i, channel 0 */
    const nprfx_image *motion;     /* frame i, channels 0-1: to the pass's previous frame */
    const nprfx_image *zvel;       /* frame i, channel 0, depth units per frame; may be NULL */
    const nprfx_image *depth_prev; /* depth at the pass's previous frame */
    const nprfx_image *source;     /* input mode: the clip at frame i */
} nprfx_cn_inputs;

/* Unit-variance innovation noise of frame `frame` (white, or band-pass renormalised analytically)
 * for every pixel of out->bounds, which may reach outside the frame (the noise is an unbounded
 * counter-based field). out->channels channels; channel c is independent of the others. Stream 0 is
 * the paper's w_i; other streams give independent fields. */
NPRFX_API nprfx_result nprfx_cn_noise_fill(nprfx_context *ctx, const nprfx_cn_params *p,
                                           int64_t frame, uint32_t stream, nprfx_image *out);

/* The first frame of a pass: u = w (noise) or the source (input mode); fresh everywhere.
 * out must be allocated over the frame with p->channels. */
NPRFX_API nprfx_result nprfx_cn_begin(nprfx_context *ctx, const nprfx_cn_params *p, int64_t frame,
                                      const nprfx_image *source, nprfx_cn_state *out);

/* One recursion step of a pass in `direction` from prev (frame - direction) to `frame`.
 * out and prev must be distinct states over the same frame.
 * Cost: one row-parallel pass over the pixels. White noise is made row by row (the compensation
 * fields only where a pixel interpolates), so no frame-sized temporaries are allocated; band-pass
 * noise is filtered as whole fields first. The result does not depend on the executor, the CPU's
 * vector width or the states' memory layout (vector and scalar code do the same float operations
 * in the same order). */
NPRFX_API nprfx_result nprfx_cn_step(nprfx_context *ctx, const nprfx_cn_params *p, int direction,
                                     int64_t frame, const nprfx_cn_inputs *in,
                                     const nprfx_cn_state *prev, nprfx_cn_state *out);

/* The node's value at `frame` from the passes' states (bwd NULL: causal). Noise: unit variance,
 * C = (u_f + u_b - g w) / sqrt(1 + alpha^2) with g = sqrt(1 - alpha^2), or 2 - sqrt(1 + alpha^2)
 * where both passes restarted (Eq. 11 in unit form, keeping the variance 1 there too).
 * Input mode: (c_f + c_b - (1 - alpha) s) / (1 + alpha), unit gain. out: over the frame. */
NPRFX_API nprfx_result nprfx_cn_combine(nprfx_context *ctx, const nprfx_cn_params *p, int64_t frame,
                                        const nprfx_cn_state *fwd, const nprfx_cn_state *bwd,
                                        const nprfx_image *source, nprfx_image *out);

/* Post-smoothing: Gaussian blur of sigma (edge pixels repeated), and for noise the analytic gain
 * that brings a field with the innovation's spectrum back to unit variance. In place. */
NPRFX_API nprfx_result nprfx_cn_smooth(nprfx_context *ctx, const nprfx_cn_params *p, double sigma,
                                       nprfx_image *img);
/* The variance of a unit innovation field after a Gaussian blur of sigma (1 when sigma is 0). */
NPRFX_API double nprfx_cn_smoothed_variance(const nprfx_cn_params *p, double sigma);

/* ---- the node: any frame of a shot, in any order (core/noise/cn_temporal.c) ---- */

/* The node's inputs, in this order in args->inputs and for args->fetch. */
enum {
    NPRFX_CN_IN_DEPTH,       /* channel 0 */
    NPRFX_CN_IN_MOTION_PREV, /* channels 0-1 */
    NPRFX_CN_IN_MOTION_NEXT, /* channels 0-1; symmetric mode */
    NPRFX_CN_IN_ZVEL,        /* channel 0; optional */
    NPRFX_CN_IN_SOURCE,      /* noise = input: 1 to 4 channels */
    NPRFX_CN_IN_CONFIDENCE,  /* channel 0: of motion_prev; channel 1 (if any): of motion_next */
    NPRFX_CN_IN_COUNT
};

typedef enum nprfx_cn_mode {
    NPRFX_CN_MODE_CAUSAL = 0,    /* the forward pass alone */
    NPRFX_CN_MODE_SYMMETRIC = 1, /* forward and backward passes combined (Eq. 11) */
    NPRFX_CN_MODE_COUNT
} nprfx_cn_mode;

typedef enum nprfx_cn_output {
    NPRFX_CN_OUTPUT_UNIT = 0,   /* zero mean, unit variance */
    NPRFX_CN_OUTPUT_UNIT01 = 1, /* 0.5 + contrast * n */
    NPRFX_CN_OUTPUT_COUNT
} nprfx_cn_output;

/* The node's params, as its descriptor binds them by offset (plugins/coherent_noise.c has their
 * help and ranges; nprfx_node_render checks them). */
typedef struct nprfx_coherent_noise_params {
    double alpha;
    int mode; /* nprfx_cn_mode */
    double epsilon;
    int noise; /* nprfx_cn_noise */
    double sigma_lo, sigma_hi;
    double smooth; /* post-smoothing sigma in pixels */
    int channels;  /* noise channels, 1-4 (input mode: the source's) */
    int seed;      /* >= 0 */
    int start;     /* first frame of the recursion (the shot's first frame if later) */
    int window;    /* 0: from start; W > 0: at most W steps back (and forward) */
    int output;    /* nprfx_cn_output; not for noise = input */
    double contrast;
    int cache_mb; /* memory bound of the per-instance state cache */
    /* Where the confidence input is below this (or not finite), the pixel restarts as at a
     * disocclusion: footage, whose flow says where it cannot be trusted (docs/design.md §3.1). */
    double min_confidence;
} nprfx_coherent_noise_params;

/* Render args->window of the frame at args->time (NPRFX_NODE_TEMPORAL: other frames of the
 * inputs through args->fetch; symmetric mode needs the shot's frame range). *args->state holds the
 * instance's cache of pass states (NPRFX_NODE_STATEFUL): the result never depends on it, it only
 * saves work; free it with nprfx_coherent_noise_state_free. */
NPRFX_API nprfx_result nprfx_coherent_noise_render(const nprfx_render_args *args,
                                                   const nprfx_coherent_noise_params *p);
NPRFX_API void nprfx_coherent_noise_state_free(void *state);
/* The most bytes that state holds for frames of width x height over the shot first..last
 * (last < first: unknown), source_channels: the source input's (input mode): each pass's
 * checkpoints and ring as cache_mb lets them be, its depths, and the last result. */
NPRFX_API double nprfx_coherent_noise_state_bytes(const nprfx_coherent_noise_params *p, int width,
                                                  int height, int source_channels, int first_frame,
                                                  int last_frame);

/* The automatic window (the node's window = 0): the fewest frames W with alpha^W at most
 * NPRFX_CN_WINDOW_TOLERANCE, the weight the frames cut off would have had (66 frames at alpha
 * 0.9, 342 at 0.98); 0 (no window) for alpha = 1, frozen noise. docs/design.md §3.1. */
#define NPRFX_CN_WINDOW_TOLERANCE 1e-3
NPRFX_API int64_t nprfx_coherent_noise_auto_window(double alpha);

/* The frames input `input` (NPRFX_CN_IN_*) is read at to render frame q->time with an empty
 * cache: one range, the recursion's span (the node's desc->frames_needed). */
NPRFX_API int nprfx_coherent_noise_frames(const nprfx_coherent_noise_params *p,
                                          const nprfx_frames_query *q, int input,
                                          nprfx_frame_range *ranges);

#ifdef __cplusplus
}
#endif
#endif
