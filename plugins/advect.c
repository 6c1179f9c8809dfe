/* The advect node: texture coordinates carried along the motion of footage, the UV anchor that
 * footage lacks (issue 17; docs/design.md §3.15). The recursion lives in core/advect.c; this file
 * is the descriptor and the call into it. */
#include <stddef.h>
#include <string.h>

#include "nprfx/advect.h"
#include "nprfx/node.h"

enum { IN_MOTION = NPRFX_ADVECT_IN_MOTION, IN_CONFIDENCE = NPRFX_ADVECT_IN_CONFIDENCE };
enum { P_PERIOD, P_SCALE, P_THRESHOLD, P_SEED, P_COUNT };
typedef nprfx_advect_params ap;

static const nprfx_input_desc inputs[NPRFX_ADVECT_IN_COUNT] = {
    {"motion_prev", "Motion Prev",
     "Per-pixel offset in pixels (y down) from a pixel to where the same point was in the "
     "previous frame: the flow node's motion_prev on footage, or a render's vectors (Blender: "
     "(Vector.X, -Vector.Y)). The coordinates are carried along it.",
     "motion_prev.X,motion_prev.Y", 2, NPRFX_INPUT_MAIN | NPRFX_INPUT_TEMPORAL, 0, 0},
    {"confidence", "Confidence",
     "Optional, 1 channel in [0, 1]: how far motion_prev can be trusted (the flow node's "
     "forward-backward check). Pixels below 'threshold' start afresh, as newly seen surface "
     "does. Not connected: only pixels whose motion leaves the frame start afresh.",
     "confidence|confidence.Y|A", 1, NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL, 0, 0},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "period",
     NPRFX_FIELD(ap, period),
     .label = "Period",
     .help = "Frames a layer of coordinates lives before it starts again from the image plane; "
             "the other layer starts half a period later. Longer: the pattern follows the "
             "motion longer but stretches more where the motion is not rigid; at most period - 1 "
             "frames of motion are read before any frame.",
     .type = NPRFX_PARAM_INT,
     .def = {24},
     .soft_min = 4,
     .soft_max = 96,
     .hard_min = 2,
     .hard_max = 100000},
    {.name = "scale",
     NPRFX_FIELD(ap, scale),
     .label = "Scale",
     .help = "Pixels per unit of the coordinates where a layer starts: 1024 matches stipple's "
             "own image-plane coordinates (its 'tile' is then in units of 1024 px).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1024},
     .soft_min = 64,
     .soft_max = 4096,
     .hard_min = 1e-3,
     .hard_max = 1e9,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "threshold",
     NPRFX_FIELD(ap, threshold),
     .label = "Confidence Threshold",
     .help = "Pixels whose confidence is below this start afresh (fresh coordinates instead of "
             "smearing unreliable motion).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.5},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "seed",
     NPRFX_FIELD(ap, seed),
     .label = "Seed",
     .help = "Shifts the coordinates each layer starts with (a different shift at every start, "
             "so that successive starts do not repeat one pattern).",
     .type = NPRFX_PARAM_INT,
     .def = {0},
     .soft_min = 0,
     .soft_max = 100,
     .hard_min = 0,
     .hard_max = 2147483647},
};

static nprfx_result advect_output(const nprfx_value *pv, const int *ich, nprfx_output_info *out)
{
    (void)pv;
    (void)ich;
    memset(out, 0, sizeof *out);
    out->channels = NPRFX_ADVECT_CHANNELS;
    out->names[0] = "A.U";
    out->names[1] = "A.V";
    out->names[2] = "B.U";
    out->names[3] = "B.V";
    out->names[4] = "weight";
    return NPRFX_OK;
}

static nprfx_result advect_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_advect_render(a, params);
}

/* Motion and confidence from the earlier of the layers' starts (exclusive) to the frame. */
static int advect_frames_needed(const void *params, const nprfx_frames_query *q, int input,
                                nprfx_frame_range *ranges)
{
    (void)input;
    const ap *p = params;
    int s0 = nprfx_advect_start(p, 0, q->time, q->first_frame, q->last_frame);
    int s1 = nprfx_advect_start(p, 1, q->time, q->first_frame, q->last_frame);
    int s = s0 < s1 ? s0 : s1;
    ranges[0].first = s < q->time ? s + 1 : q->time;
    ranges[0].last = q->time;
    return 1;
}

/* A pixel reads the previous coordinates where its motion points: anywhere. */
static int advect_footprint(const void *params)
{
    (void)params;
    return -1;
}

const nprfx_node_desc nprfx_node_advect = {
    .size = sizeof(nprfx_node_desc),
    .id = "advect",
    .label = "Advect",
    .group = "NPR",
    .help = "Texture coordinates that move with the picture, for footage without a UV pass: the "
            "'uv' anchor of stipple (and gabor-splat's anchor) on live action, phone video or a "
            "finished edit. Two layers of coordinates, A and B, start from the image plane "
            "(pixel / scale, shifted by a seeded offset) at staggered times, half a period "
            "apart, and are carried frame by frame along motion_prev (bilinear); each starts "
            "again every 'period' frames, before it stretches too far. The fifth channel, "
            "'weight', is A's share (B's is 1 - weight): a triangle over each layer's life, 0 "
            "when it starts, so that two renders, one on each layer, mixed by the weight never "
            "show a restart (Neyret, \"Advected Textures\", SCA 2003; Bousseau et al., \"Video "
            "Watercolorization using Bidirectional Texture Advection\", SIGGRAPH 2007). Pixels "
            "whose motion is unreliable (confidence below 'threshold', a NaN, a source outside "
            "the frame) start afresh where they are."
            "\n\nOutput: A.U, A.V, B.U, B.V, weight. A frame reads the motion of at most "
            "period - 1 frames before it (its layers' last starts), so a chunk that starts "
            "mid-shot warms up over at most that many frames, and renders the same pixels."
            "\n\nNaN and infinities (docs/design.md §2.2): a NaN or infinite motion, or a NaN "
            "confidence, makes the pixel start afresh; the output stays finite.",
    .inputs = inputs,
    .num_inputs = NPRFX_ADVECT_IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output = advect_output,
    .flags = NPRFX_NODE_TEMPORAL | NPRFX_NODE_STATEFUL | NPRFX_NODE_NEEDS_OTHER_FRAMES,
    .render = advect_render,
    .state_free = nprfx_advect_state_free,
    .frames_needed = advect_frames_needed,
    .footprint = advect_footprint,
    .params_size = sizeof(ap),
    .version_major = 1,
};
