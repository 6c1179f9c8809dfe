/* The lines node: ink lines from AOVs — outlines, depth discontinuities, normal creases and jumps
 * of a custom pass, as stylised renderers draw them (RenderMan's Stylized Lines, MoonRay's toon
 * filter). The math lives in core/looks/lines.c (docs/design.md §3.11); this file is the descriptor and
 * the call into it. */
#include <stddef.h>

#include "nprfx/lines.h"
#include "nprfx/node.h"

enum {
    IN_ID = NPRFX_LINES_IN_ID,
    IN_COVERAGE = NPRFX_LINES_IN_COVERAGE,
    IN_DEPTH = NPRFX_LINES_IN_DEPTH,
    IN_NORMAL = NPRFX_LINES_IN_NORMAL,
    IN_AOV = NPRFX_LINES_IN_AOV,
    IN_WIDTH = NPRFX_LINES_IN_WIDTH,
    IN_WOBBLE = NPRFX_LINES_IN_WOBBLE,
    IN_TEXTURE = NPRFX_LINES_IN_TEXTURE,
    IN_COUNT = NPRFX_LINES_IN_COUNT
};
enum {
    P_WIDTH,
    P_THICKEN,
    P_OUTLINE,
    P_DEPTH_EDGES,
    P_DEPTH_THRESHOLD,
    P_CREASES,
    P_CREASE_ANGLE,
    P_AOV_EDGES,
    P_AOV_THRESHOLD,
    P_WOBBLE,
    P_TEXTURE_AMOUNT,
    P_OPACITY,
    P_COUNT
};
typedef nprfx_lines_params lp;

/* No input is the main one: the node draws a new matte rather than modifying an image, and any
 * subset of the edge inputs may be connected (the runner takes the frame from the first one). */
static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "id",
     .label = "ID",
     .help = "Object index: an outline wherever neighbouring pixels differ (silhouettes and "
             "sections between objects).",
     .aov = "id",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "coverage",
     .label = "Coverage",
     .help = "Anti-aliased object coverage: an outline where it crosses 0.5, and the sub-pixel "
             "position of every line that crosses it.",
     .aov = "coverage|A",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "depth",
     .label = "Depth",
     .help = "Depth (larger = farther; not finite, >= 1e9 or <= 0 is background): lines at "
             "discontinuities.",
     .aov = "depth",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "normal",
     .label = "Normal",
     .help = "Normals (any space, any length): lines at creases.",
     .aov = "normal",
     .channels = 3,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "aov",
     .label = "AOV",
     .help = "A custom pass of 1 to 4 channels (a shadow or light pass): lines where it jumps.",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "width",
     .label = "Width Control",
     .help = "Thickness control in [0, 1], e.g. the diffuse lighting: lines are thicker where it "
             "is dark (see thicken). Read at the edge, between the two pixels.",
     .aov = "diffuse|diffuse.Y|Diffuse.Y|tone",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "wobble",
     .label = "Wobble",
     .help = "Coherent noise in [0, 1] around 0.5 that displaces the lines: 2 channels for x and "
             "y, or 1 (y then reads it 16 pixels down and right).",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "texture",
     .label = "Texture",
     .help = "A texture in [0, 1] (e.g. coherent noise) that multiplies the ink, so lines "
             "breathe.",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "width",
     NPRFX_FIELD(lp, width),
     .label = "Width",
     .help = "Line width in pixels, centred on the edge.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {2},
     .soft_min = 0.5,
     .soft_max = 8,
     .hard_min = 0,
     .hard_max = 256,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "thicken",
     NPRFX_FIELD(lp, thicken),
     .label = "Thicken",
     .help = "With the width input w connected, the width is width * (1 + thicken * (1 - w)): "
             "thicken 1 doubles it where w is 0.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 4,
     .hard_min = 0,
     .hard_max = 64},
    {.name = "outline",
     NPRFX_FIELD(lp, outline),
     .label = "Outline",
     .help = "Lines where the id differs or the coverage crosses 0.5.",
     .type = NPRFX_PARAM_BOOL,
     .def = {1},
     .soft_max = 1,
     .hard_max = 1},
    {.name = "depth_edges",
     NPRFX_FIELD(lp, depth_edges),
     .label = "Depth Edges",
     .help = "Lines at depth discontinuities.",
     .type = NPRFX_PARAM_BOOL,
     .def = {1},
     .soft_max = 1,
     .hard_max = 1},
    {.name = "depth_threshold",
     NPRFX_FIELD(lp, depth_threshold),
     .label = "Depth Threshold",
     .help = "A depth edge lies between neighbours z1, z2 when |z1 - z2| - s > threshold * "
             "min(z1, z2), where s is the smaller depth step just outside the pair (the slope a "
             "smooth surface explains). Background next to a surface always is one.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.1},
     .soft_min = 0.005,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1e6},
    {.name = "creases",
     NPRFX_FIELD(lp, creases),
     .label = "Creases",
     .help = "Lines where neighbouring normals differ by more than crease_angle.",
     .type = NPRFX_PARAM_BOOL,
     .def = {1},
     .soft_max = 1,
     .hard_max = 1},
    {.name = "crease_angle",
     NPRFX_FIELD(lp, crease_angle),
     .label = "Crease Angle",
     .help = "Angle in degrees between neighbouring normals above which a crease is drawn.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {60},
     .soft_min = 5,
     .soft_max = 120,
     .hard_min = 0,
     .hard_max = 180},
    {.name = "aov_edges",
     NPRFX_FIELD(lp, aov_edges),
     .label = "AOV Edges",
     .help = "Lines where the aov input jumps by more than aov_threshold.",
     .type = NPRFX_PARAM_BOOL,
     .def = {1},
     .soft_max = 1,
     .hard_max = 1},
    {.name = "aov_threshold",
     NPRFX_FIELD(lp, aov_threshold),
     .label = "AOV Threshold",
     .help = "Largest change of any aov channel between neighbours that draws no line.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.25},
     .soft_min = 0.01,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1e30},
    {.name = "wobble",
     NPRFX_FIELD(lp, wobble),
     .label = "Wobble",
     .help = "Largest displacement in pixels by the wobble input: (wobble input - 0.5) * 2 * "
             "wobble along x and y.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 8,
     .hard_min = 0,
     .hard_max = 256,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "texture_amount",
     NPRFX_FIELD(lp, texture_amount),
     .label = "Texture Amount",
     .help = "How much the texture input modulates the ink: ink * (1 - amount * (1 - texture)).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "opacity",
     NPRFX_FIELD(lp, opacity),
     .label = "Opacity",
     .help = "Multiplies the ink.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
};

static nprfx_result lines_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_lines_render(a, params);
}

const nprfx_node_desc nprfx_node_lines = {
    .size = sizeof(nprfx_node_desc),
    .id = "lines",
    .label = "Lines",
    .group = "NPR",
    .help = "Ink lines from AOVs, as stylised renderers draw them (RenderMan's Stylized Lines, "
            "MoonRay's toon filter): outlines where the object id differs or the coverage crosses "
            "0.5, depth discontinuities, normal creases and jumps of a custom AOV. Connect any of "
            "id, coverage, depth, normal and aov (at least one).\n\n"
            "Edge points sit between neighbouring pixel centres (at the coverage's 0.5 crossing "
            "when coverage is connected, else halfway) and are joined into a polyline per 2x2 "
            "cell of pixels. A pixel at distance d from it gets ink clamp(w/2 - d + 0.5, 0, 1): "
            "an anti-aliased stroke of width w centred on the edge. The width input thickens it "
            "where dark, wobble displaces it and texture modulates it; feed both from coherent "
            "noise for lines that move with the scene. The output is ink coverage (1 = ink): "
            "composite it with blend."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "Every input treats NaN and infinities as missing: a NaN id, depth, normal or AOV "
            "makes no line, a NaN width no thickening, a NaN wobble or texture the neutral 0.5. "
            "The output stays finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 1,
    .render = lines_render,
    .params_size = sizeof(lp),
    .version_major = 1,
};
