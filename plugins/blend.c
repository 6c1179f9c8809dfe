/* The blend node: the cookbook's compositing functions (alphaBlend, overlay, overlayAlpha),
 * multiply, screen, Bousseau et al.'s pigment density, and the background colour where the
 * coverage AOV is 0. The formulas and the per-pixel loop live in core/looks/blend.c; this file is
 * the descriptor and the call into it. */
#include <stddef.h>

#include "nprfx/blend.h"
#include "nprfx/node.h"

enum {
    IN_BASE = NPRFX_BLEND_IN_BASE,
    IN_LAYER = NPRFX_BLEND_IN_LAYER,
    IN_BACK = NPRFX_BLEND_IN_BACK,
    IN_ALPHA = NPRFX_BLEND_IN_ALPHA,
    IN_COVERAGE = NPRFX_BLEND_IN_COVERAGE,
    IN_COUNT = NPRFX_BLEND_IN_COUNT
};
enum { P_MODE, P_FACTOR, P_OPACITY, P_GAIN_BASE, P_GAIN_LAYER, P_BACKGROUND, P_COUNT };
typedef nprfx_blend_params bp;

/* Same order as nprfx_blend_mode. */
static const char *const mode_names[] = {"alphablend", "overlay", "overlayalpha", "multiply",
                                         "screen",     "pigment", "difference",   NULL};
_Static_assert(sizeof mode_names / sizeof mode_names[0] == NPRFX_BLEND_MODE_COUNT + 1,
               "blend: mode names must follow nprfx_blend_mode");

static const char *const mode_help[] = {
    "(1 - a) c0 + a c1 (cookbook alphaBlend)",
    "c0 f (1 - (1 - c0)(1 - c1)), mixed over c0 by a (cookbook overlay)",
    "back (1 - a) + a c0 f (1 - (1 - c0 a)(1 - c1)) (cookbook overlayAlpha)",
    "c0 c1, mixed over c0 by a",
    "1 - (1 - c0)(1 - c1), mixed over c0 by a",
    "C - (C - C^2)(d - 1) with C = c0, d = 1 + f (c1 - 0.5), mixed over c0 by a (Bousseau et al. "
    "2006 pigment density: d > 1 darkens, d < 1 lightens)",
    "f |c0 - c1|, mixed over c0 by a: e.g. two frames of coherent noise, which differ only "
    "where things move (Kass & Pesare's Figure 2)",
    NULL};

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "base",
     .label = "Base",
     .help = "The image blended onto (the colour, c0 = gain_base * base). Sets the output's "
             "channels; with 4 channels the 4th is alpha and passes through unchanged.",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN | NPRFX_INPUT_IN_PLACE},
    {.name = "layer",
     .label = "Layer",
     .help = "The image blended in (c1 = gain_layer * layer): a pattern, a stroke colour, a paper "
             "or pigment texture. A 1-channel layer is used for every colour channel of base; "
             "otherwise it needs base's colour channels (an extra alpha channel of the layer is "
             "ignored).",
     .channels = 0,
     .flags = NPRFX_INPUT_IN_PLACE},
    {.name = "back",
     .label = "Back",
     .help = "overlayalpha only: the colour under the stroke (the cookbook's backColor). Not "
             "connected: base itself, without gain_base. 1 channel or base's colour channels.",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
    {.name = "alpha",
     .label = "Alpha",
     .help = "Per-pixel blend weight a, e.g. a threshold-map output; multiplied by opacity and "
             "clamped to [0, 1]. Not connected: a = opacity.",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
    {.name = "coverage",
     .label = "Coverage",
     .help = "Object coverage (the cookbook's isBackground, antialiased): out = coverage * blended"
             " + (1 - coverage) * background, coverage clamped to [0, 1], on every channel "
             "including alpha. Not connected: coverage 1 everywhere.",
     .aov = "coverage|A",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "mode",
     NPRFX_FIELD(bp, mode),
     .label = "Mode",
     .help = "The compositing formula. c0 = gain_base * base, c1 = gain_layer * layer, a = "
             "clamp(alpha * opacity, 0, 1), f = factor. Values are not clamped.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {0},
     NPRFX_CHOICE_RANGE(NPRFX_BLEND_MODE_COUNT),
     .choices = mode_names,
     .choice_help = mode_help},
    {.name = "factor",
     NPRFX_FIELD(bp, factor),
     .label = "Factor",
     .help = "f: the overlay factor of overlay and overlayalpha (the cookbook uses 0.7 to 1.2: "
             "above 1 brightens, below 1 darkens), and the pigment strength beta of pigment (0: no"
             " effect; negative: a bright layer lightens instead of darkening).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = -100,
     .hard_max = 100},
    {.name = "opacity",
     NPRFX_FIELD(bp, opacity),
     .label = "Opacity",
     .help = "Blend weight, multiplied by the alpha input when connected: 0 leaves c0 "
             "(overlayalpha: back), 1 applies the mode fully.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "gain_base",
     NPRFX_FIELD(bp, gain_base),
     .label = "Base Gain",
     .help = "Multiplies base before blending (the cookbook's `color * 0.85`).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 1000},
    {.name = "gain_layer",
     NPRFX_FIELD(bp, gain_layer),
     .label = "Layer Gain",
     .help = "Multiplies layer before blending.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 1000},
    {.name = "background",
     NPRFX_FIELD(bp, background),
     .label = "Background",
     .help = "Colour (RGBA) where coverage is 0 (the paper). A 1-channel base takes its Rec. 709 "
             "luminance, a 2-channel base its R and G.",
     .type = NPRFX_PARAM_COLOR,
     .def = {1, 1, 1, 1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1000},
};

static nprfx_result blend_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_blend_render(a, params);
}

const nprfx_node_desc nprfx_node_blend = {
    .size = sizeof(nprfx_node_desc),
    .id = "blend",
    .label = "Blend",
    .group = "NPR",
    .help =
        "Composites a layer onto a base with the compositing functions of the NPR Gabor noise"
        " style cookbook (Benard et al. 2010, supplemental section 4): alphablend, overlay "
        "and overlayalpha exactly as written there, plus multiply, screen and the watercolor "
        "pigment-density modification of Bousseau et al. 2006, then the background colour "
        "where the coverage AOV is 0.\n"
        "\n"
        "Per colour channel, with c0 = gain_base * base, c1 = gain_layer * layer, a = "
        "clamp(alpha * opacity, 0, 1) (opacity alone when alpha is not connected) and f = "
        "factor:\n"
        "  alphablend    (1 - a) c0 + a c1\n"
        "  overlay       (1 - a) c0 + a * c0 f (1 - (1 - c0)(1 - c1))\n"
        "  overlayalpha  back (1 - a) + a c0 f (1 - (1 - c0 a)(1 - c1))\n"
        "  multiply      (1 - a) c0 + a * c0 c1\n"
        "  screen        (1 - a) c0 + a * (1 - (1 - c0)(1 - c1))\n"
        "  pigment       (1 - a) C + a * (C - (C - C^2)(d - 1)), C = c0, d = 1 + f (c1 - 0.5)\n"
        "  difference    (1 - a) c0 + a * f |c0 - c1|\n"
        "overlay, multiply, screen, pigment and difference apply a as a layer opacity over c0, as "
        "compositors do; with a = 1 they are the bare formulas. alphablend and overlayalpha "
        "take a inside the formula, as the cookbook writes them.\n"
        "\n"
        "pigment: d is Bousseau et al.'s pigment density, computed from the layer as in their"
        " paper (d = 1 + beta (T - 0.5), beta = factor, T = c1): a layer value of 0.5 leaves "
        "the colour alone, brighter layer values mean denser pigment (darker, for factor > "
        "0), darker values thinner pigment. Colour values 0 and 1 are fixed points; d is "
        "clamped to [0, 2], where the formula keeps colours within [0, 1].\n"
        "\n"
        "Colour above 1 (scene-linear highlights): the formulas are exact as written for "
        "values in [0, 1] and extended so that a highlight of 100 stays finite and in its "
        "place: screen is max(c0, c1) where either value is above 1 (screen only lightens); "
        "in overlay and overlayalpha, c0 inside the screen term is at most 1 (a highlight is "
        "scaled by f as white is); pigment acts on the part of C within [0, 1] and the rest "
        "passes unchanged (light beyond the paper's white takes no pigment). Every join is "
        "continuous.\n"
        "\n"
        "Channels: the output has base's channels. A 4-channel base is RGBA: its alpha passes"
        " through unblended. A 1-channel layer (a noise pattern) is used for every colour "
        "channel; a layer with base's colour channels is used channel by channel (an RGBA "
        "layer's alpha is ignored: connect it to the alpha input to use it).\n"
        "\n"
        "Background: out = coverage * result + (1 - coverage) * background on every channel "
        "(alpha too), an antialiased form of the cookbook's `if (isBackground) final_color = "
        "background`.\n"
        "\n"
        "Inputs read as 0 outside their data window. No value is clamped except a and "
        "coverage."
        "\n\nNaN and infinities (docs/design.md §2.2): "
        "base, layer and back (overlayalpha) pass through: a NaN or infinity there blends into "
        "a NaN or infinity at that pixel only. alpha and coverage are clamped to [0, 1], NaN as "
        "0, so they never make the output non-finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 0,                                /* as many as base */
    .flags = NPRFX_NODE_ROWS | NPRFX_NODE_WRITES_WINDOW, /* per pixel, or within its footprint */
    .render = blend_render,
    .params_size = sizeof(bp),
    .version_major = 1,
};
