/* The coherent-noise node: Kass & Pesare's depth- and motion-aware recursive noise filter. This
 * file holds its descriptor and hands the param values to core: the recursion is in
 * core/noise/cn_step.c, the render-order independent driver (a per-instance cache of pass states
 * with checkpoints) in core/cn_temporal.c. */
#include <stdint.h>
#include <string.h>

#include "nprfx/coherent_noise.h"
#include "nprfx/node.h"

/* In the order core reads them (args->inputs and args->fetch). */
enum {
    IN_DEPTH = NPRFX_CN_IN_DEPTH,
    IN_MOTION_PREV = NPRFX_CN_IN_MOTION_PREV,
    IN_MOTION_NEXT = NPRFX_CN_IN_MOTION_NEXT,
    IN_ZVEL = NPRFX_CN_IN_ZVEL,
    IN_SOURCE = NPRFX_CN_IN_SOURCE,
    IN_CONFIDENCE = NPRFX_CN_IN_CONFIDENCE,
    IN_COUNT = NPRFX_CN_IN_COUNT
};
enum {
    P_ALPHA,
    P_MODE,
    P_EPSILON,
    P_NOISE,
    P_SIGMA_LO,
    P_SIGMA_HI,
    P_SMOOTH,
    P_CHANNELS,
    P_SEED,
    P_START,
    P_WINDOW,
    P_OUTPUT,
    P_CONTRAST,
    P_CACHE_MB,
    P_MIN_CONFIDENCE,
    P_COUNT
};
/* The choices' names below are in the order of core's values. */
enum {
    MODE_CAUSAL = NPRFX_CN_MODE_CAUSAL,
    MODE_SYMMETRIC = NPRFX_CN_MODE_SYMMETRIC,
    MODE_COUNT = NPRFX_CN_MODE_COUNT
};
enum {
    OUT_UNIT = NPRFX_CN_OUTPUT_UNIT,
    OUT_UNIT01 = NPRFX_CN_OUTPUT_UNIT01,
    OUT_COUNT = NPRFX_CN_OUTPUT_COUNT
};

static const char *const mode_names[] = {"causal", "symmetric", NULL};
static const char *const mode_help[] = {
    "one pass forward in time (paper §3.2): frame i depends on frames start..i only",
    "forward and backward passes added (paper §3.3, Eq. 11): C = c_fwd + c_bwd - (1-alpha) w, "
    "impulse response (1-alpha) alpha^|t|; needs motion_next and the shot's last frame",
    NULL};
static const char *const noise_names[] = {"white", "bandpass", "input", NULL};
static const char *const noise_help[] = {
    "independent unit-variance noise per pixel, frame and channel",
    "G(sigma_lo) * w - G(sigma_hi) * w, renormalised analytically to unit variance",
    "filter the source clip instead of noise: disocclusions reset to the source (the paper's "
    "suggested extension for making a flickering sequence coherent)",
    NULL};
static const char *const output_names[] = {"unit", "unit01", NULL};
static const char *const output_help[] = {"zero mean, unit variance",
                                          "0.5 + contrast * n, for thresholding", NULL};

static const nprfx_input_desc inputs[IN_COUNT] = {
    {"depth", "Depth",
     "Depth per pixel (camera distance or view-space z, larger = farther). Background: +inf, "
     "NaN or any value >= 1e9 (Blender writes 1e10, inf in half-float files): background pixels "
     "get fresh noise every frame. A Nuke plate's 1/z is inverted by its read. Footage "
     "has none: connect confidence instead (one of the two is needed).",
     "depth", 1, NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL | NPRFX_INPUT_IN_PLACE,
     NPRFX_FETCH_UNBOUNDED, NPRFX_FETCH_UNBOUNDED},
    {"motion_prev", "Motion Prev",
     "Per-pixel offset in pixels (y down) from a pixel to where the same surface point was in "
     "the previous frame. Blender Vector pass: (Vector.X, -Vector.Y). Nuke: (backward.u, "
     "-backward.v).",
     "motion_prev", 2, NPRFX_INPUT_TEMPORAL | NPRFX_INPUT_IN_PLACE,
     NPRFX_FETCH_UNBOUNDED, 0},
    {"motion_next", "Motion Next",
     "symmetric mode: offset in pixels (y down) to where the surface point will be in the next "
     "frame. Blender: (-Vector.Z, Vector.W). Nuke: (forward.u, -forward.v).",
     "motion_next", 2, NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL, 0,
     NPRFX_FETCH_UNBOUNDED},
    {"zvel", "Z Velocity",
     "Optional: change of depth per frame of the surface seen at each pixel (depth units per "
     "frame, positive = moving away). The occlusion test predicts the previous depth as "
     "z - zvel (the next as z + zvel); without it, z itself.",
     "zvel|velocity.Z", 1, NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL, NPRFX_FETCH_UNBOUNDED,
     NPRFX_FETCH_UNBOUNDED},
    {"source", "Source", "noise = input: the clip to make temporally coherent (1 to 4 channels).",
     NULL, 0, NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL, NPRFX_FETCH_UNBOUNDED,
     NPRFX_FETCH_UNBOUNDED},
    {"confidence", "Confidence",
     "Footage: how far the motion can be trusted, per pixel, 0 to 1 (the flow node's "
     "confidence.prev, and confidence.next for symmetric mode). Below min_confidence the pixel "
     "restarts with fresh noise, as at a disocclusion: occlusions, disocclusions and cuts, where "
     "the flow is wrong, get new noise instead of smeared noise. Replaces depth's occlusion "
     "test when depth is not connected; with both, either restarts the pixel.",
     "confidence.prev,confidence.next|confidence.prev|confidence", 0,
     NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL, NPRFX_FETCH_UNBOUNDED, NPRFX_FETCH_UNBOUNDED},
};

typedef nprfx_coherent_noise_params cnp;

static const nprfx_param_desc params[P_COUNT] = {
    {"alpha",
     "Alpha",
     "Temporal coherence: the recursive filter keeps alpha of the previous frame's noise "
     "(carried along the motion) and adds (1-alpha) of fresh noise. 0: independent noise every "
     "frame; 1: frozen noise that only moves. The paper used 0.98; large values over fast "
     "changes of projected area distort the noise (paper §3.5).",
     NPRFX_PARAM_DOUBLE,
     {0.9},
     0,
     0.99,
     0,
     1,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, alpha)},
    {"mode",
     "Mode",
     "Causal (one pass) or time-symmetric (two passes).",
     NPRFX_PARAM_CHOICE,
     {MODE_CAUSAL},
     0,
     MODE_COUNT - 1,
     0,
     MODE_COUNT - 1,
     mode_names,
     mode_help,
     NULL,
     0,
     NPRFX_FIELD(cnp, mode)},
    {"epsilon",
     "Epsilon",
     "Occlusion tolerance, relative: a pixel is disoccluded (gets fresh noise) when its "
     "predicted previous depth is farther than the previous depth at its previous position "
     "times (1 + epsilon).",
     NPRFX_PARAM_DOUBLE,
     {0.01},
     0,
     0.1,
     0,
     10,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, epsilon)},
    {"noise",
     "Noise",
     "What is filtered.",
     NPRFX_PARAM_CHOICE,
     {0},
     0,
     2,
     0,
     2,
     noise_names,
     noise_help,
     NULL,
     0,
     NPRFX_FIELD(cnp, noise)},
    {"sigma_lo",
     "Sigma Lo",
     "bandpass: the smaller Gaussian sigma in pixels, which sets the finest detail (0: none "
     "removed).",
     NPRFX_PARAM_DOUBLE,
     {1},
     0,
     8,
     0,
     256,
     NULL,
     NULL,
     NULL,
     NPRFX_PARAM_PIXELS,
     NPRFX_FIELD(cnp, sigma_lo)},
    {"sigma_hi",
     "Sigma Hi",
     "bandpass: the larger Gaussian sigma in pixels, whose blur is subtracted to remove coarse "
     "structure; must exceed sigma_lo, or 0 for a plain low-pass.",
     NPRFX_PARAM_DOUBLE,
     {3},
     0,
     32,
     0,
     256,
     NULL,
     NULL,
     NULL,
     NPRFX_PARAM_PIXELS,
     NPRFX_FIELD(cnp, sigma_hi)},
    {"smooth",
     "Smooth",
     "Gaussian post-smoothing sigma in pixels, applied to the coherent result (paper §3.4); "
     "noise is renormalised to unit variance afterwards.",
     NPRFX_PARAM_DOUBLE,
     {0},
     0,
     8,
     0,
     256,
     NULL,
     NULL,
     NULL,
     NPRFX_PARAM_PIXELS,
     NPRFX_FIELD(cnp, smooth)},
    {"channels",
     "Channels",
     "Independent noise channels (1-4); ignored for noise = input.",
     NPRFX_PARAM_INT,
     {1},
     1,
     4,
     1,
     4,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, channels)},
    {"seed",
     "Seed",
     "Random seed: every noise value is a hash of (seed, frame, x, y, channel).",
     NPRFX_PARAM_INT,
     {0},
     0,
     1000,
     0,
     2147483647.0,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, seed)},
    {"start",
     "Start Frame",
     "First frame of the recursion (the later of this and the shot's first frame is used). "
     "Frames before it get fresh, uncorrelated noise.",
     NPRFX_PARAM_INT,
     {1},
     0,
     1000,
     -1e9,
     1e9,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, start)},
    {"window",
     "Window",
     "0 (automatic): W is the fewest frames whose cut-off weight alpha^W is at most 0.001 "
     "(66 frames at alpha 0.9, 342 at 0.98, 688 at 0.99; no window at alpha 1, frozen noise), "
     "and frame i starts at the latest frame of a grid of W frames from the start that lies at "
     "least W before i (symmetric: the same backwards from the last frame). Any frame alone "
     "then costs under 2W steps, however long the shot (frame 200,000 renders as fast as frame "
     "200), in-order rendering about 2 steps per frame, and a shot shorter than 2W frames is "
     "exactly the recursion from the start frame. W > 0: from max(start, i - W) (and, "
     "symmetric, back from min(last, i + W)), a sliding window: at most W steps for any frame, "
     "W steps per frame in order. 1000000: from the start frame, whatever the shot's length.",
     NPRFX_PARAM_INT,
     {0},
     0,
     200,
     0,
     1e6,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, window)},
    {"output",
     "Output",
     "Mapping of the noise (ignored for noise = input).",
     NPRFX_PARAM_CHOICE,
     {OUT_UNIT},
     0,
     OUT_COUNT - 1,
     0,
     OUT_COUNT - 1,
     output_names,
     output_help,
     NULL,
     0,
     NPRFX_FIELD(cnp, output)},
    {"contrast",
     "Contrast",
     "unit01: the output is 0.5 + contrast * n.",
     NPRFX_PARAM_DOUBLE,
     {0.15},
     0,
     0.5,
     0,
     100,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, contrast)},
    {"cache_mb",
     "Cache (MB)",
     "Memory bound of the frame-state cache (checkpoints every ~sqrt(shot length) frames plus "
     "the latest run of states). In-order rendering costs one step per frame with any bound; "
     "random access recomputes from the nearest checkpoint. 0 keeps only the current state "
     "(plus a 2-3 frame working set that is always needed).",
     NPRFX_PARAM_INT,
     {1024},
     0,
     8192,
     0,
     1048576,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, cache_mb)},
    {"min_confidence",
     "Min Confidence",
     "With the confidence input: pixels whose confidence is below this get fresh noise (a "
     "restart). Higher restarts more (less smearing at occlusions, more boiling where the flow "
     "is merely uncertain).",
     NPRFX_PARAM_DOUBLE,
     {0.5},
     0,
     1,
     0,
     1,
     NULL,
     NULL,
     NULL,
     0,
     NPRFX_FIELD(cnp, min_confidence)},
};

static const char help[] =
    "Coherent noise (Kass & Pesare, \"Coherent Noise for Non-Photorealistic Rendering\", ACM "
    "TOG 30(4), SIGGRAPH 2011): noise whose every frame looks like independent noise with the "
    "same statistics everywhere on screen, yet whose variations stick to the moving surfaces. "
    "Subtract two consecutive frames and the objects appear. It drives thresholds, warps and "
    "blends; with noise = input the same filter makes a flickering clip coherent.\n"
    "\n"
    "Recursion, per pixel x of frame i: p = x + motion_prev(x) is where the surface point was "
    "at frame i-1. The pixel is disoccluded when p is outside the frame, its depth is "
    "background, or its predicted previous depth z - zvel is farther than the previous depth at "
    "p (bilinear, background taps ignored) times (1 + epsilon). Then c_i = k w_i if disoccluded, "
    "else alpha c_{i-1}(p) + (1-alpha) w_i, with k = sqrt((1-alpha)/(1+alpha)) and "
    "c_start = k w_start (Eq. 6-7), which keeps the variance constant. The output is c / k "
    "(unit variance). Symmetric mode runs the same recursion backwards from the last frame with "
    "motion_next and outputs c_fwd + c_bwd - (1-alpha) w (Eq. 11), normalised; where both passes "
    "restart at once the weight of w is adjusted so the variance stays 1 there too.\n"
    "\n"
    "Footage (no depth, no render motion): take motion_prev (and motion_next) and confidence "
    "from the flow node. A pixel whose confidence is below min_confidence is disoccluded "
    "instead, so noise sticks to what moves and restarts where the flow fails (occlusions, "
    "cuts).\n"
    "\n"
    "Motion convention (docs/design.md §2): motion vectors are in pixels of the full-resolution "
    "frame, y pointing down; motion_prev(x) goes from x to the same surface point in the "
    "previous frame, motion_next(x) to the next frame. Blender's Vector pass holds (to previous "
    "X, Y, and this frame's position minus the next one) with y up, as measured on the sample "
    "plates: motion_prev = (Vector.X, -Vector.Y), motion_next = (-Vector.Z, Vector.W); a read "
    "node with \"vectors\": \"blender\" applies exactly this mapping. Nuke's ScanlineRender motion "
    "vectors: "
    "motion_prev = (backward.u, -backward.v), motion_next = (forward.u, -forward.v); check the "
    "sign on one frame (some tools store the offset from the other frame to this one: negate "
    "it). Under a host proxy the vectors are scaled by the render scale.\n"
    "\n"
    "Stationarity under sub-pixel motion: looking up c_{i-1} at a fractional position with the "
    "paper's bilinear filter lowers its variance and removes high frequencies at every frame; "
    "over a long shot the noise fades and blurs (measured, white noise, alpha 0.9, 100 frames of "
    "a (0.37, 0.23) px/frame pan: std x0.57, high-band power x0.26). Tracking the variance each "
    "pixel carries and renormalising fixes the level only if the carried noise stayed white, "
    "which it does not (std x1.08-1.47, spectrum tilted). This node instead resamples with "
    "Catmull-Rom, which keeps more, and adds fresh noise shaped by a 4-tap filter G(f) with "
    "|H_f|^2 + |G_f|^2 = 1 for the interpolation filter H_f of the pixel's sub-pixel offset f "
    "(a closed-form spectral factor, tabulated per 1/1024 px): exactly the power the "
    "interpolation removed is put back, with the innovation's own spectrum (white or band-pass), "
    "so variance and spectrum hold over any number of frames (std within 2%, high band within "
    "5%, for pans, rotations and zooms). The price: the finest detail (near 0.5 cycles/pixel, "
    "which no grid can move by a fraction of a pixel) renews faster than alpha on sub-pixel "
    "motion; a little smooth or band-pass noise hides it, and integer or zero motion is an exact "
    "copy.\n"
    "\n"
    "Noise values are counter-based hashes of (seed, frame, x, y, channel), so a frame is the "
    "same on any machine, thread count, tile split or render order: frame i is defined by the "
    "recursion from its start frame (see window). In-order rendering costs "
    "one step per frame through a cache of states; random access restarts from checkpoints "
    "within cache_mb.\n"
    "\n"
    "Patent notice: Pixar holds US patent 8,760,466 B1, \"Coherent noise for non-photorealistic "
    "rendering\" (M. Kass, D. Pesare; priority from US provisional 61/295,981 filed January 18, "
    "2010; issued June 24, 2014). Its claims cover generating image-space noise by a causal "
    "(recursive) filter selected per pixel from depth, velocity and an occlusion test - what "
    "this node does. Check whether your use needs a licence.\n"
    "\n"
    "NaN and infinities, docs/design.md §2.2: a depth that is NaN or infinite is background (fresh "
    "noise); a NaN or infinite motion vector is a disocclusion (fresh noise); a NaN confidence is "
    "below any min_confidence (fresh noise); a non-finite zvel is "
    "ignored (z itself is predicted). noise = input: a NaN or infinite source sample is missing, "
    "and the filter carries the previous value on alone there (0 at a restart), so it never "
    "travels along the motion into other pixels or frames.";

static nprfx_result cn_output(const void *params, const int *ich, nprfx_output_info *out)
{
    const cnp *p = params;
    memset(out, 0, sizeof *out);
    if (p->noise == NPRFX_CN_NOISE_INPUT) {
        out->problem = "noise = input needs the 'source' input (the clip to make coherent)";
        if (ich[IN_SOURCE] <= 0) return NPRFX_ERR_MISSING_INPUT;
        out->problem = NULL;
        out->channels = ich[IN_SOURCE] > 4 ? 4 : ich[IN_SOURCE];
        return NPRFX_OK;
    }
    out->channels = p->channels;
    if (out->channels < 1 || out->channels > 4) return NPRFX_ERR_OUT_OF_RANGE;
    return NPRFX_OK;
}

/* core/noise/cn_temporal.c renders (nprfx/coherent_noise.h). */
static nprfx_result cn_render(const nprfx_render_args *args, const void *params)
{
    return nprfx_coherent_noise_render(args, params);
}

/* Exactly the recursion's span, so a host prepares no frame the node does not read. */
static int cn_frames_needed(const void *params, const nprfx_frames_query *q, int input,
                            nprfx_frame_range *ranges)
{
    return nprfx_coherent_noise_frames(params, q, input, ranges);
}

static double cn_state_bytes(const void *params, const nprfx_state_query *q)
{
    return nprfx_coherent_noise_state_bytes(
        params, q->width, q->height, q->input_channels[IN_SOURCE], q->first_frame, q->last_frame);
}

const nprfx_node_desc nprfx_node_coherent_noise = {
    sizeof(nprfx_node_desc),
    "coherent-noise",
    "Coherent Noise",
    "NPR",
    help,
    inputs,
    IN_COUNT,
    params,
    P_COUNT,
    1,
    cn_output,
    NPRFX_NODE_TEMPORAL | NPRFX_NODE_STATEFUL | NPRFX_NODE_NEEDS_OTHER_FRAMES,
    cn_render,
    nprfx_coherent_noise_state_free,
    .params_size = sizeof(cnp),
    .version_major = 1,
    /* 1.1: NaN and infinities as docs/design.md §2.2 says; window 0 is automatic, not
     * unbounded (pixels change only past 2W frames from the start) */
    .version_minor = 1,
    .frames_needed = cn_frames_needed,
    .state_bytes = cn_state_bytes,
};
