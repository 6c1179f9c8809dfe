/* The warp node: displaces an image by two channels, out(p) = image(p + amount * offset(p)) — the
 * local image-plane warp of Kass & Pesare's Figure 3a, driven by two channels of coherent noise.
 * The warp lives in core/looks/warp.c; this file is the descriptor and the call into it. */
#include <math.h>
#include <stddef.h>

#include "nprfx/filter.h"
#include "nprfx/node.h"

enum {
    IN_IMAGE = NPRFX_WARP_IN_IMAGE,
    IN_OFFSET = NPRFX_WARP_IN_OFFSET,
    IN_COUNT = NPRFX_WARP_IN_COUNT
};
enum { P_AMOUNT, P_FILTER, P_BORDER, P_REACH, P_COUNT };
enum { FILTER_COUNT = NPRFX_WARP_FILTER_COUNT, BORDER_COUNT = 2 };
typedef nprfx_warp_params wp;

/* Same order as nprfx_warp_filter and nprfx_border. */
static const char *const filter_names[] = {"bilinear", "bicubic", NULL};
static const char *const filter_help[] = {"2x2 taps, never overshoots",
                                          "Catmull-Rom 4x4 taps, sharper, may overshoot", NULL};
static const char *const border_names[] = {"clamp", "black", NULL};
static const char *const border_help[] = {"positions outside the image repeat its edge",
                                          "positions outside the image read zero", NULL};
_Static_assert(sizeof filter_names / sizeof filter_names[0] == FILTER_COUNT + 1,
               "warp: filter names must follow nprfx_warp_filter");
_Static_assert(sizeof border_names / sizeof border_names[0] == BORDER_COUNT + 1 &&
                   NPRFX_BORDER_CLAMP == 0 && NPRFX_BORDER_BLACK == 1,
               "warp: border names must follow nprfx_border");

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "image",
     .label = "Image",
     .help = "The image to displace (any channel count).",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN},
    {.name = "offset",
     .label = "Offset",
     .help = "Two channels (x, y; y down) scaled by amount to give the displacement in pixels, "
             "e.g. two channels of coherent-noise. Outside its data window it reads as 0 (no "
             "displacement).",
     .channels = 2},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "amount",
     NPRFX_FIELD(wp, amount),
     .label = "Amount",
     .help = "Displacement in pixels per unit of offset: out(p) = image(p + amount * offset(p)).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {2},
     .soft_min = -16,
     .soft_max = 16,
     .hard_min = -4096,
     .hard_max = 4096,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "filter",
     NPRFX_FIELD(wp, filter),
     .label = "Filter",
     .help = "Reconstruction filter of the displaced lookup.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_WARP_BILINEAR},
     NPRFX_CHOICE_RANGE(FILTER_COUNT),
     .choices = filter_names,
     .choice_help = filter_help},
    {.name = "border",
     NPRFX_FIELD(wp, border),
     .label = "Border",
     .help = "What lookups outside the image read.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_BORDER_CLAMP},
     NPRFX_CHOICE_RANGE(BORDER_COUNT),
     .choices = border_names,
     .choice_help = border_help},
    {.name = "reach",
     NPRFX_FIELD(wp, reach),
     .label = "Reach",
     .help = "The farthest the warp moves a pixel, per axis: each component of amount * offset "
             "is clamped to [-reach, reach]. 0: unbounded. A reach lets the runner render the "
             "warp a strip of rows at a time, reading only the rows within reach (bounded memory "
             "on 4K and 8K frames, docs/design.md §1 \"Memory\"); set it to the largest "
             "displacement the look needs, e.g. amount for offsets in [-1, 1].",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = 0,
     .soft_max = 64,
     .hard_min = 0,
     .hard_max = 4096,
     .flags = NPRFX_PARAM_PIXELS},
};

static nprfx_result warp_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_warp_render(a, params);
}

/* Without a reach, where the image is read depends on the offset input's values: anywhere.
 * With one, within the reach plus the bicubic filter's taps (two pixels beyond the floor). */
static int warp_footprint(const void *params)
{
    const wp *p = params;
    return p->reach > 0 ? (int)ceil(p->reach) + 2 : -1;
}

const nprfx_node_desc nprfx_node_warp = {
    .size = sizeof(nprfx_node_desc),
    .id = "warp",
    .label = "Warp",
    .group = "Filter",
    .help = "Displaces an image by a two-channel offset field: out(p) = image(p + amount * "
            "offset(p)), sampled with a bilinear or Catmull-Rom bicubic filter. Driven by two "
            "channels of coherent-noise it gives the wobbling, hand-made edges of Kass & Pesare's "
            "Figure 3a that stick to the moving objects."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "image passes through: a NaN or infinity shows wherever the filter's taps read it, "
            "which the offsets decide. A NaN offset leaves the pixel where it is; an infinite one "
            "reads outside, which the border decides (with a reach, it reads reach pixels away).",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 0, /* as many as image */
    .render = warp_render,
    .footprint = warp_footprint,
    .flags = NPRFX_NODE_ROWS, /* with a reach; without one its footprint is -1: whole frames */
    .params_size = sizeof(wp),
    .version_major = 1,
};
