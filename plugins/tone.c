/* The tone node: a shading AOV mapped into the [0, 1] tone that threshold-map and the styles
 * expect, with one range for the whole shot. The measuring and the mapping live in
 * core/looks/tone.c; this file is the descriptor and the call into it. */
#include <stddef.h>

#include "nprfx/node.h"
#include "nprfx/tone.h"

enum {
    IN_TONE = NPRFX_TONE_IN_TONE,
    IN_ALBEDO = NPRFX_TONE_IN_ALBEDO,
    IN_COVERAGE = NPRFX_TONE_IN_COVERAGE,
    IN_COUNT = NPRFX_TONE_IN_COUNT
};
enum {
    P_RANGE,
    P_LOW,
    P_HIGH,
    P_REFERENCE,
    P_BLACK,
    P_WHITE,
    P_EXPOSURE,
    P_GAMMA,
    P_BANDS,
    P_BAND_SOFTNESS,
    P_OUT_LOW,
    P_OUT_HIGH,
    P_SOLID_BLACKS,
    P_BACKGROUND,
    P_COUNT
};
typedef nprfx_tone_params tp;

/* Same order as nprfx_tone_range. */
static const char *const range_names[] = {"shot", "frame", "manual", NULL};
static const char *const range_help[] = {
    "percentiles low/high of the covered pixels of every frame of the shot, measured once",
    "percentiles low/high of the covered pixels of reference_frame",
    "black maps to 0 and white to 1, as given", NULL};
_Static_assert(sizeof range_names / sizeof range_names[0] == NPRFX_TONE_RANGE_COUNT + 1,
               "tone: range names must follow nprfx_tone_range");

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "tone",
     .label = "Tone",
     .help = "The shading to map: the beauty (Combined), a light pass, a diffuse pass. RGB(A) is "
             "taken as Rec. 709 luminance, one channel as it is.",
     .aov = "beauty",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN | NPRFX_INPUT_TEMPORAL,
     .fetch_before = NPRFX_FETCH_UNBOUNDED,
     .fetch_after = NPRFX_FETCH_UNBOUNDED},
    {.name = "albedo",
     .label = "Albedo",
     .help = "The surface colour (Blender's DiffCol): when connected the tone is divided by it, "
             "so what is mapped is the light alone (direct plus ambient) and the strokes do not "
             "copy the textures. Not connected: the tone as it is, textures included.",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL,
     .fetch_before = NPRFX_FETCH_UNBOUNDED,
     .fetch_after = NPRFX_FETCH_UNBOUNDED},
    {.name = "coverage",
     .label = "Coverage",
     .help = "Object coverage (e.g. a matte node): only covered pixels are measured, and where "
             "it is 0 the output is 'background'. Not connected: every pixel is an object.",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_TEMPORAL,
     .fetch_before = NPRFX_FETCH_UNBOUNDED,
     .fetch_after = NPRFX_FETCH_UNBOUNDED},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "range",
     NPRFX_FIELD(tp, range),
     .label = "Range",
     .help = "Where the values that map to 0 and 1 come from. Never measured per frame, so the "
             "tone cannot flicker.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_TONE_RANGE_SHOT},
     NPRFX_CHOICE_RANGE(NPRFX_TONE_RANGE_COUNT),
     .choices = range_names,
     .choice_help = range_help},
    {.name = "low",
     NPRFX_FIELD(tp, low),
     .label = "Low Percentile",
     .help = "The percentile of the measured values that maps to 0 (darkest).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 20,
     .hard_min = 0,
     .hard_max = 100},
    {.name = "high",
     NPRFX_FIELD(tp, high),
     .label = "High Percentile",
     .help = "The percentile of the measured values that maps to 1 (lightest).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {99},
     .soft_min = 80,
     .soft_max = 100,
     .hard_min = 0,
     .hard_max = 100},
    {.name = "reference_frame",
     NPRFX_FIELD(tp, reference_frame),
     .label = "Reference Frame",
     .help = "range 'frame': the frame measured.",
     .type = NPRFX_PARAM_INT,
     .def = {1},
     .soft_min = 1,
     .soft_max = 100,
     .hard_min = -1000000,
     .hard_max = 1000000},
    {.name = "black",
     NPRFX_FIELD(tp, black),
     .label = "Black",
     .help = "range 'manual': the value that maps to 0.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = -1e30,
     .hard_max = 1e30},
    {.name = "white",
     NPRFX_FIELD(tp, white),
     .label = "White",
     .help = "range 'manual': the value that maps to 1.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 4,
     .hard_min = -1e30,
     .hard_max = 1e30},
    {.name = "exposure",
     NPRFX_FIELD(tp, exposure),
     .label = "Exposure",
     .help = "Stops applied after the range: t = clamp((v - lo) / (hi - lo) * 2^exposure, 0, 1). "
             "Positive lightens every tone (fewer strokes).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = -3,
     .soft_max = 3,
     .hard_min = -30,
     .hard_max = 30},
    {.name = "gamma",
     NPRFX_FIELD(tp, gamma),
     .label = "Gamma",
     .help = "t^(1/gamma): above 1 lifts the mid tones.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0.25,
     .soft_max = 4,
     .hard_min = 0.01,
     .hard_max = 100},
    {.name = "bands",
     NPRFX_FIELD(tp, bands),
     .label = "Bands",
     .help = "Cut the tone into this many flat levels, 0 at the darkest and 1 at the lightest "
             "(toon shading); 0 or 1: a continuous tone.",
     .type = NPRFX_PARAM_INT,
     .def = {0},
     .soft_min = 0,
     .soft_max = 6,
     .hard_min = 0,
     .hard_max = 256},
    {.name = "band_softness",
     NPRFX_FIELD(tp, band_softness),
     .label = "Band Softness",
     .help = "With bands: the width of the ramp up to each level, as a fraction of a band (0: a "
             "hard step, aliased; 0.1: a soft edge a few pixels wide on smooth shading).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "out_low",
     NPRFX_FIELD(tp, out_low),
     .label = "Output Low",
     .help = "The output for the darkest tone: above 0 keeps some paper in the deepest shadow.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = -10,
     .hard_max = 10},
    {.name = "out_high",
     NPRFX_FIELD(tp, out_high),
     .label = "Output High",
     .help = "The output for the lightest tone: below 1 keeps some strokes on the lightest "
             "surfaces.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = -10,
     .hard_max = 10},
    {.name = "solid_blacks",
     NPRFX_FIELD(tp, solid_blacks),
     .label = "Solid Blacks",
     .help = "The darkest tones filled with solid ink, as an ink artist spots blacks: below this"
             " tone t the output fades linearly to 0 at t = 0 (out * t / solid_blacks), which a "
             "threshold-map turns into solid ink. 0 (the default): the darkest tone is out_low, "
             "so with out_low above 0 the deepest shadow keeps its texture.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = 0,
     .soft_max = 0.5,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "background",
     NPRFX_FIELD(tp, background),
     .label = "Background",
     .help = "The output where coverage is 0 (mixed by coverage at silhouettes): 1 lets no "
             "stroke through, so the background stays paper.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = -10,
     .hard_max = 10},
};

static nprfx_result tone_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_tone_render(a, params);
}

static int tone_frames_needed(const void *params, const nprfx_frames_query *q, int input,
                              nprfx_frame_range *ranges)
{
    (void)input; /* the inputs are sampled together */
    return nprfx_tone_frames(params, q, ranges);
}

const nprfx_node_desc nprfx_node_tone = {
    .size = sizeof(nprfx_node_desc),
    .id = "tone",
    .label = "Tone",
    .group = "NPR",
    .help = "Maps a shading AOV into the tone the styles threshold: the cookbook's "
            "diffuseIntensity, 0 for the darkest surface and 1 for the lightest, whatever the "
            "light's strength or the exposure. The range [lo, hi] comes from percentiles of the "
            "covered pixels over the whole shot (or one reference frame, or given), measured "
            "once and never per frame, so the tone cannot flicker:\n\n"
            "t = clamp((v - lo) / (hi - lo) * 2^exposure, 0, 1)^(1/gamma), out = out_low + "
            "(out_high - out_low) t (times t / solid_blacks below solid_blacks), and out = "
            "background where coverage is 0.\n\n"
            "Feed it the beauty or a light pass that includes the ambient light, not the direct "
            "light alone (0 in every shadow), and a matte as coverage so the sky is not "
            "measured and stays paper."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "NaN and infinities are missing: left out of the range measured over the shot (so one "
            "bad pixel cannot stretch every frame's range) and mapped as background at their "
            "pixel. The output stays finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 1,
    .flags = NPRFX_NODE_TEMPORAL | NPRFX_NODE_STATEFUL,
    .render = tone_render,
    .state_free = nprfx_tone_state_free,
    .params_size = sizeof(tp),
    .version_major = 1,
    .frames_needed = tone_frames_needed,
    .state_save = nprfx_tone_state_save,
    .state_load = nprfx_tone_state_load,
};
