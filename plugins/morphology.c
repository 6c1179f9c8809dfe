/* The morphology node: grey-scale dilation (max) and erosion (min) over a disc or square
 * footprint, and their compositions open and close (Haralick et al. 1987) — the dilate/erode
 * texture step of Kass & Pesare's Figure 3a. The filter lives in core/looks/morphology.c; this file is
 * the descriptor and the call into it. */
#include <stddef.h>

#include "nprfx/filter.h"
#include "nprfx/node.h"

enum { IN_IMAGE = NPRFX_MORPHOLOGY_IN_IMAGE, IN_COUNT = NPRFX_MORPHOLOGY_IN_COUNT };
enum { P_OPERATION, P_RADIUS, P_FOOTPRINT, P_COUNT };
enum { OP_COUNT = NPRFX_MORPHOLOGY_OP_COUNT, FP_COUNT = NPRFX_MORPHOLOGY_FOOTPRINT_COUNT };
typedef nprfx_morphology_params mp;

/* Same order as nprfx_morphology_op and nprfx_morphology_footprint. */
static const char *const op_names[] = {"dilate", "erode", "open", "close", NULL};
static const char *const op_help[] = {"max over the footprint", "min over the footprint",
                                      "erode then dilate: removes bright specks smaller than "
                                      "the footprint",
                                      "dilate then erode: fills dark specks smaller than the "
                                      "footprint",
                                      NULL};
static const char *const fp_names[] = {"disc", "square", NULL};
static const char *const fp_help[] = {"offsets with dx^2 + dy^2 <= radius^2",
                                      "offsets with |dx|, |dy| <= radius", NULL};
_Static_assert(sizeof op_names / sizeof op_names[0] == OP_COUNT + 1,
               "morphology: operation names must follow nprfx_morphology_op");
_Static_assert(sizeof fp_names / sizeof fp_names[0] == FP_COUNT + 1,
               "morphology: footprint names must follow nprfx_morphology_footprint");

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "image",
     .label = "Image",
     .help = "The image to filter; every channel on its own.",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "operation",
     NPRFX_FIELD(mp, operation),
     .label = "Operation",
     .help = "The morphological operation.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_MORPHOLOGY_DILATE},
     NPRFX_CHOICE_RANGE(OP_COUNT),
     .choices = op_names,
     .choice_help = op_help},
    {.name = "radius",
     NPRFX_FIELD(mp, radius),
     .label = "Radius",
     .help = "Footprint radius in pixels (fractional radii pick the integer offsets inside). 0 "
             "copies.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 8,
     .hard_min = 0,
     .hard_max = 256,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "footprint",
     NPRFX_FIELD(mp, footprint),
     .label = "Footprint",
     .help = "Shape of the structuring element.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_MORPHOLOGY_DISC},
     NPRFX_CHOICE_RANGE(FP_COUNT),
     .choices = fp_names,
     .choice_help = fp_help},
};

static nprfx_result morph_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_morphology_render(a, params);
}

/* The taps an output pixel reads: the radius, twice for open and close (two passes). A NaN
 * tap is skipped (missing); an infinite one is the max or min over this footprint. */
static int morph_footprint(const void *params)
{
    const mp *p = params;
    int R = (int)(p->radius + 1e-9);
    return p->operation == NPRFX_MORPHOLOGY_OPEN || p->operation == NPRFX_MORPHOLOGY_CLOSE ? 2 * R
                                                                                           : R;
}

const nprfx_node_desc nprfx_node_morphology = {
    .size = sizeof(nprfx_node_desc),
    .id = "morphology",
    .label = "Morphology",
    .group = "Filter",
    .help = "Grey-scale mathematical morphology per channel: dilate (max over the footprint), "
            "erode (min), open (erode then dilate) and close (dilate then erode), with a disc or "
            "square footprint of the given radius. Kass & Pesare's Figure 3a runs a dilation and "
            "an erosion over quantised shading plus smoothed coherent noise to make a painterly "
            "texture that moves with the objects. Pixels outside the frame repeat the edge."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "A NaN tap is missing: max and min skip it, and only a footprint of NaN alone stays "
            "NaN (never an infinity). An infinity is a value like any other: dilate spreads +inf, "
            "erode -inf, over the footprint.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 0,     /* as many as image */
    .flags = NPRFX_NODE_ROWS, /* per pixel, or within its footprint */
    .render = morph_render,
    .footprint = morph_footprint,
    .params_size = sizeof(mp),
    .version_major = 1,
    .version_minor = 1, /* 1.1: NaN and infinities as docs/design.md §2.2 says */
};
