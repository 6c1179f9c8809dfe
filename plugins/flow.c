/* The flow node: dense optical flow between neighbouring frames of any sequence, in the motion
 * convention of docs/design.md §2, with a confidence per direction (§3.15). For footage without
 * a renderer's motion vectors. The luminance, scaling and confidence live in core/motion/flow.c, the
 * solver in the front end's provider (common/flow_opencv.cpp); this file is the descriptor and the
 * call into it. */
#include <stddef.h>
#include <string.h>

#include "nprfx/flow.h"
#include "nprfx/node.h"

enum { IN_IMAGE = NPRFX_FLOW_IN_IMAGE, IN_COUNT = NPRFX_FLOW_IN_COUNT };
enum { P_PRESET, P_SCALE, P_CONSISTENCY, P_PHOTOMETRIC, P_OUTPUT, P_COUNT };
typedef nprfx_flow_params fp;

/* Same order as nprfx_flow_preset. */
static const char *const preset_names[] = {"ultrafast", "fast", "medium", NULL};
static const char *const preset_help[] = {
    "DIS's fastest: coarse patches, no refinement at the finest scales",
    "DIS's balance of speed and accuracy",
    "DIS's most accurate: denser patches and more refinement, several times slower", NULL};
_Static_assert(sizeof preset_names / sizeof preset_names[0] == NPRFX_FLOW_PRESET_COUNT + 1,
               "flow: preset names must follow nprfx_flow_preset");

/* Same order as nprfx_flow_output. */
static const char *const output_names[] = {"all", "prev", "next", "vectors", NULL};
static const char *const output_help[] = {
    "motion_prev.X/Y, motion_next.X/Y, confidence.prev, confidence.next",
    "motion_prev.X/Y and confidence.prev (RGB in a host); only the previous frame is solved",
    "motion_next.X/Y and confidence.next (RGB in a host); only the next frame is solved",
    "motion_prev.X/Y and motion_next.X/Y (RGBA in a host, as Nuke's motion vectors)", NULL};
_Static_assert(sizeof output_names / sizeof output_names[0] == NPRFX_FLOW_OUTPUT_COUNT + 1,
               "flow: output names must follow nprfx_flow_output");

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "image",
     .label = "Image",
     .help = "The sequence to measure motion on: 1 to 4 channels, RGB(A) read as Rec. 709 luma, "
             "else the first channel; every frame of one size.",
     .flags = NPRFX_INPUT_MAIN | NPRFX_INPUT_TEMPORAL,
     .fetch_before = 1,
     .fetch_after = 1},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "preset",
     NPRFX_FIELD(fp, preset),
     .label = "Preset",
     .help = "How hard the solver works (the presets of OpenCV's DIS optical flow).",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_FLOW_MEDIUM},
     NPRFX_CHOICE_RANGE(NPRFX_FLOW_PRESET_COUNT),
     .choices = preset_names,
     .choice_help = preset_help},
    {.name = "scale",
     NPRFX_FIELD(fp, scale),
     .label = "Scale",
     .help = "Solve at this fraction of the resolution (box-downscaled), then upsample the flow "
             "bilinearly: 0.5 is about four times faster, and loses motion detail finer than "
             "two pixels.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0.125,
     .soft_max = 1,
     .hard_min = 0.125,
     .hard_max = 1},
    {.name = "consistency",
     NPRFX_FIELD(fp, consistency),
     .label = "Consistency",
     .help = "Forward-backward threshold in pixels: a pixel whose flow there and back misses it "
             "by this much gets confidence exp(-1/2) = 0.61 from that check, by twice this "
             "exp(-2) = 0.14.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0.1,
     .soft_max = 5,
     .hard_min = 0.01,
     .hard_max = 1000,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "photometric",
     NPRFX_FIELD(fp, photometric),
     .label = "Photometric",
     .help = "Luminance threshold of the confidence (on x/(1+x) luma, 0..1): where the pixel and "
             "the one its flow lands on differ by this much, confidence falls by exp(-1/2). It "
             "makes a cut (unrelated frames) unconfident everywhere. 0: no photometric check.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.05},
     .soft_min = 0,
     .soft_max = 0.5,
     .hard_min = 0,
     .hard_max = 1000},
    {.name = "output",
     NPRFX_FIELD(fp, output),
     .label = "Output",
     .help = "Which channels to output. An OpenFX host image holds four channels, so in a host "
             "choose one direction or the vectors alone.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_FLOW_OUT_ALL},
     NPRFX_CHOICE_RANGE(NPRFX_FLOW_OUTPUT_COUNT),
     .choices = output_names,
     .choice_help = output_help},
};

/* Indexed by NPRFX_FLOW_PREV_X ... */
static const char *const out_names[NPRFX_FLOW_CHANNELS] = {"motion_prev.X",   "motion_prev.Y",
                                                           "motion_next.X",   "motion_next.Y",
                                                           "confidence.prev", "confidence.next"};

static nprfx_result flow_output(const void *params, const int *ich, nprfx_output_info *out)
{
    (void)ich;
    memset(out, 0, sizeof *out);
    int which[NPRFX_FLOW_CHANNELS];
    out->channels = nprfx_flow_output_channels(((const fp *)params)->output, which);
    for (int c = 0; c < out->channels; c++)
        out->names[c] = out_names[which[c]];
    return out->channels ? NPRFX_OK : NPRFX_ERR_OUT_OF_RANGE;
}

static nprfx_result flow_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_flow_render(a, params);
}

/* The neighbours within the shot (nprfx_node_frames_needed adds the frame itself). */
static int flow_frames_needed(const void *params, const nprfx_frames_query *q, int input,
                              nprfx_frame_range *ranges)
{
    (void)input;
    const fp *p = params;
    int known = q->first_frame <= q->last_frame;
    int prev = p->output != NPRFX_FLOW_OUT_NEXT, next = p->output != NPRFX_FLOW_OUT_PREV;
    ranges[0].first = !prev || (known && q->time - 1 < q->first_frame) ? q->time : q->time - 1;
    ranges[0].last = !next || (known && q->time + 1 > q->last_frame) ? q->time : q->time + 1;
    return 1;
}

static double flow_state_bytes(const void *params, const nprfx_state_query *q)
{
    (void)params;
    return nprfx_flow_state_bytes(q->width, q->height);
}

const nprfx_node_desc nprfx_node_flow = {
    .size = sizeof(nprfx_node_desc),
    .id = "flow",
    .label = "Optical Flow",
    .group = "Motion",
    .help = "Dense optical flow between each frame and its neighbours, for footage without a "
            "renderer's motion vectors: motion_prev (where each pixel was at the previous frame, "
            "minus where it is) and motion_next, in pixels, y down (docs/design.md §2), which "
            "the motion inputs of coherent-noise and stipple take as they are. "
            "confidence.prev/next is in [0, 1]: the product of a forward-backward check (the "
            "flow there and back must come home, within 'consistency' pixels) and a photometric "
            "one (the pixel must look like where it lands, within 'photometric'); occluded and "
            "disoccluded pixels, the frame's borders and cuts get low confidence. At the shot's "
            "first frame the prev channels are 0, at its last the next ones. The solver is the "
            "front end's (OpenCV's DIS in the runner and the OpenFX bundle; docs/design.md "
            "§3.15)."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "image: missing (luma 0 there, confidence 0 at those pixels and where a flow lands "
            "on them); the output is always finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output = flow_output,
    .flags = NPRFX_NODE_TEMPORAL | NPRFX_NODE_NEEDS_OTHER_FRAMES | NPRFX_NODE_STATEFUL,
    .render = flow_render,
    .state_free = nprfx_flow_state_free,
    .state_bytes = flow_state_bytes,
    .params_size = sizeof(fp),
    .version_major = 1,
    .frames_needed = flow_frames_needed,
};
