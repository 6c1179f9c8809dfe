/* The threshold-map node: the cookbook's erf threshold, X-toon threshold maps given as an image,
 * and a built-in map whose step follows the tone. The math lives in core/looks/threshold_map.c; this
 * file is the descriptor and the call into it. */
#include <stddef.h>
#include <string.h>

#include "nprfx/node.h"
#include "nprfx/threshold.h"

enum {
    IN_PATTERN = NPRFX_THRESHOLD_MAP_IN_PATTERN,
    IN_TONE = NPRFX_THRESHOLD_MAP_IN_TONE,
    IN_MAP = NPRFX_THRESHOLD_MAP_IN_MAP,
    IN_COUNT = NPRFX_THRESHOLD_MAP_IN_COUNT
};
enum { P_MODE, P_SIGMA, P_MU, P_TONE, P_TONE_GAIN, P_STEPS, P_INVERT, P_COUNT };
enum { MODE_COUNT = NPRFX_THRESHOLD_MODE_COUNT };
typedef nprfx_threshold_params tp;

static const char *const mode_names[] = {"erf", "map", "builtin", NULL};
static const char *const mode_help[] = {
    "(erf(sigma (p - mu)) + 1) / 2 per pattern channel (cookbook threshold)",
    "bilinear lookup of the map image at (u = p, v = tone)",
    "(erf(sigma (p - m)) + 1) / 2 with m chosen per pixel so that the mean over uniform p in "
    "[0,1] equals the tone",
    NULL};
_Static_assert(sizeof mode_names / sizeof mode_names[0] == MODE_COUNT + 1,
               "threshold-map: mode names must follow nprfx_threshold_mode");

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "pattern",
     .label = "Pattern",
     .help = "The pattern p to threshold, usually noise mapped to [0,1] (e.g. coherent-noise or "
             "gabor-splat with its [0,1] output mapping). Every channel is thresholded on its own.",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN | NPRFX_INPUT_IN_PLACE},
    {.name = "tone",
     .label = "Tone",
     .help = "The second variable of the threshold map (map and builtin modes), in [0,1]: usually "
             "the diffuse intensity. Not connected: the tone param.",
     .aov = "diffuse|diffuse.Y|Diffuse.Y|tone",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
    {.name = "map",
     .label = "Map",
     .help = "map mode: the X-toon threshold map image, any size and 1 to 4 channels, read whole "
             "(it is not aligned with the frame). Columns are the pattern axis (u = 0 left, u = 1 "
             "right), rows the tone axis (v = 0 bottom, v = 1 top).",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_UNALIGNED},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "mode",
     NPRFX_FIELD(tp, mode),
     .label = "Mode",
     .help = "How the pattern becomes a stroke value; see the node help.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_THRESHOLD_ERF},
     NPRFX_CHOICE_RANGE(MODE_COUNT),
     .choices = mode_names,
     .choice_help = mode_help},
    {.name = "sigma",
     NPRFX_FIELD(tp, sigma),
     .label = "Sigma",
     .help = "erf and builtin: sharpness of the step (the cookbook's sigma): the step rises from "
             "2% to 98% over about 3 / sigma in pattern units; large values give hard, aliased "
             "edges.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {25},
     .soft_min = 1,
     .soft_max = 100,
     .hard_min = 0.01,
     .hard_max = 1e6},
    {.name = "mu",
     NPRFX_FIELD(tp, mu),
     .label = "Mu",
     .help = "erf: position of the step in pattern units (the cookbook's mu). Values above it go "
             "to 1, below to 0.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.5},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = -100,
     .hard_max = 100},
    {.name = "tone",
     NPRFX_FIELD(tp, tone),
     .label = "Tone",
     .help = "map and builtin: the tone used when the tone input is not connected (0 dark, 1 "
             "light).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.5},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "tone_gain",
     NPRFX_FIELD(tp, tone_gain),
     .label = "Tone Gain",
     .help = "map and builtin: multiplies the tone before it is clamped to [0,1] (e.g. to bring a "
             "diffuse pass into range).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 1000},
    {.name = "steps",
     NPRFX_FIELD(tp, steps),
     .label = "Tone Steps",
     .help = "map and builtin: 0 or 1 keeps the tone continuous; n >= 2 rounds it to the nearest "
             "of n levels 0, 1/(n-1), ..., 1, giving toon-like tone bands.",
     .type = NPRFX_PARAM_INT,
     .def = {0},
     .soft_min = 0,
     .soft_max = 8,
     .hard_min = 0,
     .hard_max = 256},
    {.name = "invert",
     NPRFX_FIELD(tp, invert),
     .label = "Invert",
     .help = "Output 1 - value on every channel (builtin: ink coverage instead of brightness, mean"
             " 1 - tone).",
     .type = NPRFX_PARAM_BOOL,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
};

static nprfx_result tm_output(const void *params, const int *ich, nprfx_output_info *out)
{
    memset(out, 0, sizeof *out);
    nprfx_result r = nprfx_threshold_output_channels(((const tp *)params)->mode, ich[IN_PATTERN],
                                                     ich[IN_MAP], &out->channels);
    if (r == NPRFX_ERR_MISSING_INPUT)
        out->problem = "mode 'map' needs the 'map' input (an X-toon map image, e.g. "
                       "samples/maps/soft_step.exr)";
    else if (r)
        out->problem = "a map of several channels needs a 1-channel pattern: pick one channel "
                       "of input 'pattern'";
    return r;
}

static nprfx_result tm_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_threshold_map_render(a, params);
}

static double tm_state_bytes(const void *params, const nprfx_state_query *q)
{
    (void)params, (void)q;
    return nprfx_threshold_state_bytes();
}

const nprfx_node_desc nprfx_node_threshold_map = {
    .size = sizeof(nprfx_node_desc),
    .id = "threshold-map",
    .label = "Threshold Map",
    .group = "NPR",
    .help =
        "Turns a pattern (noise in [0,1]) into strokes with a threshold, as in the NPR Gabor "
        "noise style cookbook (Benard et al. 2010, supplemental section 3), either with the "
        "cookbook's sigmoid or with an X-toon threshold map (Barla, Thollot, Markosian, NPAR "
        "2006) that makes the threshold follow a second variable, the tone (usually diffuse "
        "intensity).\n"
        "\n"
        "Modes, for each pattern value p:\n"
        "  erf      (erf(sigma (p - mu)) + 1) / 2: 0 below mu, 1 above, through a step about\n"
        "           3 / sigma wide. The tone is not used.\n"
        "  map      T(u = p, v = tone): bilinear lookup in the map image. u runs along the\n"
        "           map's columns, from the centre of the leftmost (u = 0) to the centre of the\n"
        "           rightmost (u = 1); v along its rows, from the centre of the bottom row\n"
        "           (v = 0) to the centre of the top row (v = 1). That is the OpenGL texture\n"
        "           orientation of the cookbook's texture(thresholdMap, vec2(pattern,\n"
        "           diffuseIntensity)): a map reads like a graph, pattern to the right, lighter\n"
        "           tones up. u and v are clamped to [0,1]. The output has the map's channels;\n"
        "           a 1-channel map is applied to each pattern channel, a map with more\n"
        "           channels needs a 1-channel pattern. samples/maps/ has examples.\n"
        "  builtin  an X-toon map computed on the fly: the erf step at a position m that\n"
        "           follows the tone, chosen per pixel so that the mean output over uniform\n"
        "           pattern values in [0,1] equals the tone exactly. For tones between\n"
        "           6 / sigma and 1 - 6 / sigma, m = 1 - tone; nearer the ends m moves outside\n"
        "           [0,1], so that tone 0 gives 0 (all ink) and tone 1 gives 1 (all paper).\n"
        "           Darker tones let more of the pattern fall below the step, as ink.\n"
        "\n"
        "So with a uniform [0,1] pattern the builtin mode reproduces the tone on average (for"
        " a Gaussian-looking noise the mean follows the tone monotonically, but not exactly);"
        " sharper sigma gives crisper strokes with the same mean. The output is brightness: 1"
        " paper, 0 ink; invert gives ink coverage. Inputs read as 0 outside their data "
        "window."
        "\n\nNaN and infinities (docs/design.md §2.2): "
        "A NaN pattern passes through at the pixel; infinities clamp to the ends of the "
        "threshold. tone is clamped to [0, 1], NaN as 0. A NaN or infinite texel of the map "
        "is missing: the lookup blends its finite neighbours.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output = tm_output,
    /* per pixel, or within its footprint; the builtin table is kept between calls */
    .flags = NPRFX_NODE_ROWS | NPRFX_NODE_STATEFUL | NPRFX_NODE_WRITES_WINDOW,
    .render = tm_render,
    .state_free = nprfx_threshold_state_free,
    .state_bytes = tm_state_bytes,
    .params_size = sizeof(tp),
    .version_major = 1,
    .version_minor = 1, /* 1.1: NaN and infinities as docs/design.md §2.2 says */
};
