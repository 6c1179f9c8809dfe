/* The watercolor node: Bousseau, Kaplan, Thollot, Sillion 2006 — wobbling edges, edge darkening,
 * pigment turbulence, dispersion and paper granulation, all through the pigment-density model.
 * The math lives in core/looks/watercolor.c; this file is the descriptor and the call into it. */
#include <math.h>
#include <stddef.h>

#include "nprfx/node.h"
#include "nprfx/watercolor.h"

enum {
    IN_IMAGE = NPRFX_WATERCOLOR_IN_IMAGE,
    IN_TURBULENCE = NPRFX_WATERCOLOR_IN_TURBULENCE,
    IN_DISPERSION = NPRFX_WATERCOLOR_IN_DISPERSION,
    IN_PAPER = NPRFX_WATERCOLOR_IN_PAPER,
    IN_COVERAGE = NPRFX_WATERCOLOR_IN_COVERAGE,
    IN_COUNT = NPRFX_WATERCOLOR_IN_COUNT
};
enum {
    P_TURBULENCE,
    P_DISPERSION,
    P_GRANULATION,
    P_EDGE_DARKENING,
    P_EDGE_WIDTH,
    P_WOBBLE,
    P_WOBBLE_SCALE,
    P_COUNT
};
typedef nprfx_watercolor_params wp;

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "image",
     .label = "Image",
     .help = "The colour to paint, as a reflectance in [0, 1] (the beauty, or albedo times "
             "tone). Sets the output's channels; with 4 channels the 4th is alpha and passes "
             "through unchanged.",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN},
    {.name = "turbulence",
     .label = "Turbulence Noise",
     .help = "Pigment turbulence T in [0, 1] (1 channel): low-frequency coherent noise, e.g. "
             "coherent-noise bandpass with large sigmas and output unit01. Darkens where T > 0.5 "
             "and lightens where T < 0.5: the soft blotches of an uneven wash. Not connected: "
             "no turbulence.",
     .aov = "turbulence|Y",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "dispersion",
     .label = "Dispersion Noise",
     .help = "Pigment dispersion D in [0, 1] (1 channel): high-frequency coherent noise, the "
             "fine grain of pigment settling. Not connected: no dispersion.",
     .aov = "dispersion|Y",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "paper",
     .label = "Paper",
     .help = "Paper height P in [0, 1] (1 channel), in screen space: granulation follows it, "
             "and its low-passed gradient makes the edges wobble. Not connected: no paper "
             "texture, no wobble.",
     .aov = "paper|Y",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "coverage",
     .label = "Coverage",
     .help = "Object coverage K in [0, 1] (1 channel): the colour is painted over white paper, "
             "Q = K image + (1 - K), so silhouettes wobble and darken like any colour edge and "
             "the background stays paper-white. Not connected: the image is painted as it is.",
     .aov = "coverage|A",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "turbulence",
     NPRFX_FIELD(wp, turbulence),
     .label = "Turbulence",
     .help = "Strength of the turbulence blotches: density d = 1 + turbulence (T - 0.5).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1.5},
     .soft_min = 0,
     .soft_max = 6,
     .hard_min = 0,
     .hard_max = 20},
    {.name = "dispersion",
     NPRFX_FIELD(wp, dispersion),
     .label = "Dispersion",
     .help = "Strength of the fine pigment grain: density d = 1 + dispersion (D - 0.5).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.4},
     .soft_min = 0,
     .soft_max = 6,
     .hard_min = 0,
     .hard_max = 20},
    {.name = "granulation",
     NPRFX_FIELD(wp, granulation),
     .label = "Granulation",
     .help = "Strength of the paper texture: pigment settles in the paper's hollows, density "
             "d = 1 + granulation (P - 0.5).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.6},
     .soft_min = 0,
     .soft_max = 6,
     .hard_min = 0,
     .hard_max = 20},
    {.name = "edge_darkening",
     NPRFX_FIELD(wp, edge_darkening),
     .label = "Edge Darkening",
     .help = "Pigment pooling at the boundaries of colour regions: density "
             "d = min(1 + edge_darkening g, 2), g the colour gradient (a step of height h gives "
             "g = h/2 beside it, whatever edge_width). 0: no darkening.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {12},
     .soft_min = 0,
     .soft_max = 12,
     .hard_min = 0,
     .hard_max = 100},
    {.name = "edge_width",
     NPRFX_FIELD(wp, edge_width),
     .label = "Edge Width",
     .help = "How far the darkening spreads from an edge: the sigma of a Gaussian blur of the "
             "colour before its gradient. 0: only the two pixels beside an edge.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {2.5},
     .soft_min = 0,
     .soft_max = 8,
     .hard_min = 0,
     .hard_max = 32,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "wobble",
     NPRFX_FIELD(wp, wobble),
     .label = "Wobble",
     .help = "How far the paper pushes the image (and so its edges) around: the offset "
             "wobble G / max(|G|, N), at most wobble px, G the gradient of the low-passed paper "
             "and N its local RMS. Needs the paper input; keep it below wobble_scale.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {3},
     .soft_min = 0,
     .soft_max = 10,
     .hard_min = 0,
     .hard_max = 64,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "wobble_scale",
     NPRFX_FIELD(wp, wobble_scale),
     .label = "Wobble Scale",
     .help = "Size of the wobbles: the sigma of the Gaussian low-pass of the paper whose "
             "gradient displaces the image (and the radius of the box its RMS is taken over).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {8},
     .soft_min = 0,
     .soft_max = 32,
     .hard_min = 0,
     .hard_max = 256,
     .flags = NPRFX_PARAM_PIXELS},
};

static nprfx_result watercolor_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_watercolor_render(a, params);
}

/* The stages' reach (core/looks/watercolor.c grows each stage's rectangle by it): the edge blur's
 * taps and gradient, the wobble's displacement, the paper's low-pass, gradient and RMS box. */
static int watercolor_footprint(const void *params)
{
    const wp *p = params;
    return (int)ceil(3.0 * p->edge_width) + 2 + (int)ceil(p->wobble) + 1 +
           2 * (int)ceil(p->wobble_scale) + 2;
}

const nprfx_node_desc nprfx_node_watercolor = {
    .size = sizeof(nprfx_node_desc),
    .id = "watercolor",
    .label = "Watercolor",
    .group = "NPR",
    .help =
        "Watercolor after Bousseau, Kaplan, Thollot and Sillion, \"Interactive watercolor "
        "rendering with temporal coherence and abstraction\" (NPAR 2006). Every effect is a "
        "pigment density d applied to the colour through the paper's model "
        "C' = C - (C - C^2)(d - 1): d > 1 darkens, d < 1 lightens, white paper (C = 1) stays "
        "white.\n\n"
        "1. Wobbling edges: the image (and coverage) is sampled at p + o, o = wobble G / "
        "max(|G|, N), G the gradient of the paper low-passed over wobble_scale px and N its local "
        "RMS; with coverage, the colour is laid on white paper, Q = K image + (1 - K).\n\n"
        "2. Edge darkening: d = min(1 + edge_darkening g, 2), g the colour gradient of Q blurred "
        "over edge_width px, normalised so that a step of height h gives g = h/2.\n\n"
        "3. Turbulence d = 1 + turbulence (T - 0.5), dispersion d = 1 + dispersion (D - 0.5) and "
        "paper granulation d = 1 + granulation (P - 0.5), applied one after the other.\n\n"
        "Feed turbulence and dispersion from coherent-noise nodes (coarse and fine, output "
        "unit01) so the pigment sticks to the objects, and the paper from a screen-space paper "
        "texture. With nothing optional connected and edge_darkening 0 the image passes through "
        "unchanged."
        "\n\nNaN and infinities (docs/design.md §2.2): "
        "image passes through within the footprint of the wobble and the edge blur. A NaN "
        "turbulence, dispersion or paper pixel passes through the same way; infinities there "
        "clamp to the density range. A NaN or infinite coverage is missing. Never an infinity "
        "from a NaN.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 0, /* as many as image */
    .render = watercolor_render,
    .footprint = watercolor_footprint,
    .params_size = sizeof(wp),
    .version_major = 1,
};
