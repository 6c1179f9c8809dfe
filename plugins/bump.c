/* The bump node: an image shaded by the relief of a height field (emboss), for painterly
 * brush-fibre relief (Hertzmann 2002) and watercolour paper grain (docs/design.md §3.13). The
 * shading lives in core/looks/bump.c; this file is the descriptor and the call into it. */
#include <stddef.h>

#include "nprfx/bump.h"
#include "nprfx/node.h"

enum {
    IN_IMAGE = NPRFX_BUMP_IN_IMAGE,
    IN_HEIGHT = NPRFX_BUMP_IN_HEIGHT,
    IN_COUNT = NPRFX_BUMP_IN_COUNT
};
enum { P_STRENGTH, P_AZIMUTH, P_ELEVATION, P_AMOUNT, P_SPECULAR, P_SHININESS, P_COUNT };
typedef nprfx_bump_params bp;

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "image",
     .label = "Image",
     .help = "The image to shade (1 to 4 channels; a 4th channel is alpha and passes through).",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN},
    {.name = "height",
     .label = "Height",
     .help = "The relief: one channel, higher is nearer the viewer (a paper node's height, a "
             "noise, a brush-stroke height). Reads outside the frame repeat the edge.",
     .channels = 1},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "strength",
     NPRFX_FIELD(bp, strength),
     .label = "Strength",
     .help = "Height scale s in pixels: the normal is normalize(-s dh/dx, -s dh/dy, 1), with "
             "slopes per pixel from central differences (s scales with the render scale, so a "
             "proxy shades alike). A height in [0, 1] with features a few pixels wide wants s "
             "of a few pixels.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {4},
     .soft_min = 0,
     .soft_max = 20,
     .hard_min = 0,
     .hard_max = 10000,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "azimuth",
     NPRFX_FIELD(bp, azimuth),
     .label = "Azimuth",
     .help = "Direction the light comes from, in degrees in the image plane, counter-clockwise "
             "on screen: 0 from the right, 90 from the top, 180 from the left, 270 from the "
             "bottom (l = (cos e cos a, -cos e sin a, sin e) with y down).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {135},
     .soft_min = 0,
     .soft_max = 360,
     .hard_min = -360,
     .hard_max = 360},
    {.name = "elevation",
     NPRFX_FIELD(bp, elevation),
     .label = "Elevation",
     .help = "Height of the light above the image plane, in degrees (90: straight above, "
             "where slopes only darken). Low lights exaggerate the relief.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {45},
     .soft_min = 10,
     .soft_max = 90,
     .hard_min = 1,
     .hard_max = 90},
    {.name = "amount",
     NPRFX_FIELD(bp, amount),
     .label = "Amount",
     .help = "out = image * (1 + amount * (shade - 1)), with shade = max(0, n . l) / l_z, "
             "which is exactly 1 where the height is flat: flat regions keep their colour.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 4},
    {.name = "specular",
     NPRFX_FIELD(bp, specular),
     .label = "Specular",
     .help = "Highlight added to the colour channels: specular * max(0, (n . H)^shininess - "
             "H_z^shininess), H the half vector between the light and the viewer (straight "
             "above), so only slopes that catch more light than flat paper shine (wet paint).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 4},
    {.name = "shininess",
     NPRFX_FIELD(bp, shininess),
     .label = "Shininess",
     .help = "Exponent of the highlight: higher is smaller and sharper.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {20},
     .soft_min = 2,
     .soft_max = 200,
     .hard_min = 1,
     .hard_max = 10000},
};

static nprfx_result bump_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_bump_render(a, params);
}

const nprfx_node_desc nprfx_node_bump = {
    .size = sizeof(nprfx_node_desc),
    .id = "bump",
    .label = "Bump",
    .group = "NPR",
    .help = "Shades an image by the relief of a height field, as if embossed: the brush-fibre "
            "relief of painterly rendering (Hertzmann, \"Fast Paint Texture\", NPAR 2002) or "
            "the grain of watercolour paper.\n"
            "\n"
            "The normal is n = normalize(-s dh/dx, -s dh/dy, 1) from central differences of "
            "the height (clamped at the frame's edges), the light l comes from azimuth and "
            "elevation, and shade = max(0, n . l) / l_z, the Lambert term divided by a flat "
            "surface's: a flat height leaves the image exactly unchanged. On the colour "
            "channels, out = image * (1 + amount * (shade - 1)) plus an optional highlight; a "
            "4-channel image keeps its alpha."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "image passes through at the pixel. A NaN or infinite height is missing: no slope "
            "there, the output stays finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 0, /* as many as image */
    .render = bump_render,
    .params_size = sizeof(bp),
    .version_major = 1,
};
