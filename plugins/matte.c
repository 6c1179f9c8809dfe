/* The matte node: object coverage from alpha, depth or object id. The rule and the softening
 * live in core/looks/matte.c; this file is the descriptor and the call into it. */
#include <stddef.h>

#include "nprfx/matte.h"
#include "nprfx/node.h"

enum {
    IN_ALPHA = NPRFX_MATTE_IN_ALPHA,
    IN_DEPTH = NPRFX_MATTE_IN_DEPTH,
    IN_ID = NPRFX_MATTE_IN_ID,
    IN_COUNT = NPRFX_MATTE_IN_COUNT
};
enum { P_FAR, P_BACKGROUND_ID, P_SOFTEN, P_INVERT, P_COUNT };
typedef nprfx_matte_params mp;

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "alpha",
     .label = "Alpha",
     .help = "An antialiased alpha (a render with a transparent film), used as it is.",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "depth",
     .label = "Depth",
     .help = "View depth: background where it is not finite, not positive or at least 'far' "
             "(Blender writes 1e10, or inf once stored as half).",
     .aov = "depth",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_MAIN},
    {.name = "id",
     .label = "Object ID",
     .help = "Object index: background where it is background_id (Blender's IndexOB is 0 "
             "where no object was hit). Ids are compared exactly, uint ids with all 32 bits.",
     .aov = "id",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "far",
     NPRFX_FIELD(mp, far),
     .label = "Far",
     .help = "Depth at or beyond which a pixel is background.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1e9},
     .soft_min = 1,
     .soft_max = 1000,
     .hard_min = 0,
     .hard_max = 1e30},
    {.name = "background_id",
     NPRFX_FIELD(mp, background_id),
     .label = "Background ID",
     .help = "The id of the background; -1: every id is an object (ids are then not used).",
     .type = NPRFX_PARAM_INT,
     .def = {0},
     .soft_min = -1,
     .soft_max = 16,
     .hard_min = -1,
     .hard_max = 1000000},
    {.name = "soften",
     NPRFX_FIELD(mp, soften),
     .label = "Soften",
     .help = "Gaussian sigma in pixels over the matte made from depth and id, which are not "
             "antialiased (0: hard). Alpha is not softened.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.6},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 2,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "invert",
     NPRFX_FIELD(mp, invert),
     .label = "Invert",
     .help = "Output 1 - coverage: 1 on the background.",
     .type = NPRFX_PARAM_BOOL,
     .def = {0},
     .soft_max = 1,
     .hard_max = 1},
};

static nprfx_result matte_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_matte_render(a, params);
}

const nprfx_node_desc nprfx_node_matte = {
    .size = sizeof(nprfx_node_desc),
    .id = "matte",
    .label = "Matte",
    .group = "NPR",
    .help = "Object coverage, 1 on objects and 0 on the background (the cookbook's "
            "isBackground, antialiased), from whatever the render has: coverage = alpha * "
            "[depth < far] * [id != background_id], each factor only when its input is "
            "connected. Depth and id are not antialiased, so their matte is softened by a small "
            "Gaussian. Styles put paper where the matte is 0."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "NaN and infinities are missing: a non-finite depth is background, a NaN alpha or id "
            "covers nothing. The output stays finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 1,
    .render = matte_render,
    .params_size = sizeof(mp),
    .version_major = 1,
};
