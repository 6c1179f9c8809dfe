/* The advect node: texture coordinates carried along the motion vectors, two staggered layers
 * and their blend weight, as surface-like anchors for footage without UV (Neyret 2003; Bousseau
 * et al. 2007). The recursion, its schedule and its cache live in core/motion/advect.c; this file
 * is the descriptor and the call into it. */
#include <stddef.h>

#include "nprfx/advect.h"
#include "nprfx/node.h"

/* In the order core reads them (nprfx/advect.h). */
enum {
    IN_MOTION_PREV = NPRFX_ADVECT_IN_MOTION_PREV,
    IN_CONFIDENCE = NPRFX_ADVECT_IN_CONFIDENCE,
    IN_COUNT = NPRFX_ADVECT_IN_COUNT
};
enum { P_LAYERS, P_PERIOD, P_MAX_DISTORTION, P_MIN_CONFIDENCE, P_OUTPUT, P_COUNT };
enum { OUTPUT_COUNT = NPRFX_ADVECT_OUTPUT_COUNT };
typedef nprfx_advect_params ap;

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "motion_prev",
     .label = "Motion Prev",
     .help = "Per pixel, the offset in pixels (y down) to where the same surface point was at the "
             "previous frame (docs/design.md §2): a renderer's vectors or the flow node's "
             "estimate. Sets the output's size. Not finite: the pixel is re-seeded.",
     .aov = "motion_prev",
     .channels = 2,
     .flags = NPRFX_INPUT_TEMPORAL,
     .fetch_before = NPRFX_FETCH_UNBOUNDED,
     .fetch_after = 0},
    {.name = "confidence",
     .label = "Confidence",
     .help = "How far motion_prev can be trusted at each pixel (e.g. the flow node's "
             "confidence.prev, in [0, 1]). Below min_confidence, or not finite, the pixel is "
             "re-seeded as disoccluded content. Not connected: every vector is trusted.",
     .aov = "confidence.prev|confidence",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL,
     .fetch_before = NPRFX_FETCH_UNBOUNDED,
     .fetch_after = 0},
};

/* Same order as nprfx_advect_output. */
static const char *const output_names[] = {"all", "layers", "mix", NULL};
static const char *const output_help[] = {
    "a.U, a.V, b.U, b.V, mix: everything a graph needs from one node (the runner; an OpenFX "
    "host carries four channels, so there b.V is lost: use layers and mix)",
    "a.U, a.V, b.U, b.V: the two layers' coordinates, for a host (R, G, B, A)",
    "mix: the weight of layer a, for a host's blend", NULL};
_Static_assert(sizeof output_names / sizeof output_names[0] == OUTPUT_COUNT + 1,
               "advect: output names must follow nprfx_advect_output");

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "layers",
     NPRFX_FIELD(ap, layers),
     .label = "Layers",
     .help = "2: layers a and b restart in turn every period frames and the mix channel blends "
             "them so no restart shows. 1: one layer, restarted only at the shot's first frame "
             "and where pixels are re-seeded; b = a and mix = 1. Its history is the whole shot, "
             "so a frame rendered alone costs a step per frame since the shot's start.",
     .type = NPRFX_PARAM_INT,
     .def = {2},
     .soft_min = 1,
     .soft_max = 2,
     .hard_min = 1,
     .hard_max = 2},
    {.name = "period",
     NPRFX_FIELD(ap, period),
     .label = "Period",
     .help = "Frames between two restarts of a layer (2 layers): layer a restarts at the shot's "
             "first frame + k period, layer b half a period later. Longer periods keep the "
             "pattern on the surface longer but let it stretch more; any frame costs at most "
             "period steps per layer.",
     .type = NPRFX_PARAM_INT,
     .def = {24},
     .soft_min = 4,
     .soft_max = 96,
     .hard_min = 2,
     .hard_max = 100000},
    {.name = "max_distortion",
     NPRFX_FIELD(ap, max_distortion),
     .label = "Max Distortion",
     .help = "Stretch (ratio of the singular values of the coordinates' Jacobian) a layer may "
             "reach at full weight; its weight then falls linearly to 0 at twice this ratio, and "
             "the other layer takes over. Folds weigh 0. A uniform zoom is no distortion.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {2},
     .soft_min = 1,
     .soft_max = 8,
     .hard_min = 1,
     .hard_max = 1e6},
    {.name = "min_confidence",
     NPRFX_FIELD(ap, min_confidence),
     .label = "Min Confidence",
     .help = "Pixels whose confidence is below this get a fresh coordinate (the identity), as "
             "disoccluded content. Unused without the confidence input.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.5},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "output",
     NPRFX_FIELD(ap, output),
     .label = "Output",
     .help = "The channels output. An OpenFX host carries at most four (R, G, B and the last one "
             "in alpha), so in a host use one instance with layers and one with mix; the values "
             "are the same as all's.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_ADVECT_OUTPUT_ALL},
     NPRFX_CHOICE_RANGE(OUTPUT_COUNT),
     .choices = output_names,
     .choice_help = output_help},
};

static nprfx_result advect_output(const void *params, const int *ich, nprfx_output_info *out)
{
    (void)ich;
    out->channels = nprfx_advect_output_channels(((const ap *)params)->output, out->names);
    return out->channels ? NPRFX_OK : NPRFX_ERR_OUT_OF_RANGE;
}

static nprfx_result advect_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_advect_render(a, params);
}

/* From the earliest layer's last restart to the frame: exactly the steps the recursion takes. */
static int advect_frames_needed(const void *params, const nprfx_frames_query *q, int input,
                                nprfx_frame_range *ranges)
{
    return nprfx_advect_frames(params, q, input, ranges);
}

/* A pixel's coordinates come from wherever the motion led over the frames since its restart. */
static int advect_footprint(const void *params)
{
    (void)params;
    return -1;
}

static double advect_state_bytes(const void *params, const nprfx_state_query *q)
{
    const ap *p = params;
    const char *names[NPRFX_ADVECT_CHANNELS];
    int channels = nprfx_advect_output_channels(p->output, names);
    return nprfx_advect_state_bytes(q->width, q->height, channels);
}

const nprfx_node_desc nprfx_node_advect = {
    .size = sizeof(nprfx_node_desc),
    .id = "advect",
    .label = "Advect",
    .group = "NPR",
    .help =
        "Texture coordinates that move with the picture, for footage without UV or rest "
        "position (Neyret 2003, \"Advected textures\"; Bousseau et al. 2007, bidirectional "
        "texture advection): anchors for stipple's uv and gabor-splat's anchor. Two layers "
        "start from the identity (uv = pixel / 1024, stipple's UV without a uv input) in turn "
        "every period frames and follow motion_prev between restarts, X_t(x) = X_{t-1}(x + "
        "motion_prev_t(x)), bilinear. Pixels coming from outside the frame or with low "
        "confidence are re-seeded. Outputs a.U, a.V, b.U, b.V and mix = w_a / (w_a + w_b), "
        "with w = 1 - |2 age / period - 1| (0 at a restart) times a factor that falls as the "
        "layer stretches beyond max_distortion. Render a look twice, on a.U,a.V and on b.U,b.V, "
        "and blend the first over the second with alpha = mix (in an OpenFX host, which carries "
        "four channels, from two instances: output layers and output mix). Any frame depends "
        "only on the frames since its layers' last restarts, so it renders the same alone (a "
        "farm chunk) as in order."
        "\n\nNaN and infinities (docs/design.md §2.2): motion_prev and confidence: missing "
        "(the pixel is re-seeded: a fresh coordinate, as disoccluded content). The output is "
        "always finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = NPRFX_ADVECT_CHANNELS,
    .output = advect_output,
    .flags = NPRFX_NODE_TEMPORAL | NPRFX_NODE_STATEFUL | NPRFX_NODE_NEEDS_OTHER_FRAMES |
             NPRFX_NODE_PIXEL_SCALED,
    .render = advect_render,
    .state_free = nprfx_advect_state_free,
    .state_bytes = advect_state_bytes,
    .params_size = sizeof(ap),
    .version_major = 1,
    .frames_needed = advect_frames_needed,
    .footprint = advect_footprint,
};
