/* The paper node: a procedural paper, watercolour paper or canvas texture fixed in screen space,
 * the background the style graphs lay their strokes on (docs/design.md §3.12). The texture lives in
 * core/looks/paper.c; this file is the descriptor and the call into it. */
#include <stddef.h>
#include <string.h>

#include "nprfx/node.h"
#include "nprfx/paper.h"

enum { IN_IMAGE = NPRFX_PAPER_IN_IMAGE, IN_COUNT = NPRFX_PAPER_IN_COUNT };
enum {
    P_KIND,
    P_SCALE,
    P_GRAIN,
    P_FIBRES,
    P_WEAVE,
    P_THREAD,
    P_COLOR,
    P_SHADE,
    P_RELIEF,
    P_TILE,
    P_SEED,
    P_OUTPUT,
    P_COUNT
};
enum { KIND_COUNT = NPRFX_PAPER_KIND_COUNT, OUTPUT_COUNT = NPRFX_PAPER_OUTPUT_COUNT };
typedef nprfx_paper_params pp;

/* Same order as nprfx_paper_kind and nprfx_paper_output. */
static const char *const kind_names[] = {"paper", "watercolor", "canvas", NULL};
static const char *const kind_help[] = {
    "drawing paper: fine grain of about 3 x scale, a faint cloudy formation and a few thin "
    "fibres (fibres)",
    "cold-press watercolour paper: rounded bumps of about 6 x scale and 3 x scale, "
    "roughened with coarse noise",
    "canvas: a plain weave of horizontal and vertical threads of period thread (weave), each "
    "going over and under the crossing threads in turn, with a grain along the threads",
    NULL};
static const char *const output_names[] = {"color", "height", NULL};
static const char *const output_help[] = {
    "RGBA: color * (1 - shade * (1 - height)) * light(relief) on R, G, B; A = color's alpha",
    "1 channel: the height in [0, 1], mean about 0.5 (for bump and watercolor paper inputs)", NULL};
_Static_assert(sizeof kind_names / sizeof kind_names[0] == KIND_COUNT + 1,
               "paper: kind names must follow nprfx_paper_kind");
_Static_assert(sizeof output_names / sizeof output_names[0] == OUTPUT_COUNT + 1,
               "paper: output names must follow nprfx_paper_output");

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "image",
     .label = "Image",
     .help = "Optional, and only for its format: when connected, the paper covers this image's "
             "frame (its pixels are not read). Without it the graph's \"format\" (or the host's "
             "project size) gives the frame.",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN | NPRFX_INPUT_OPTIONAL},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "kind",
     NPRFX_FIELD(pp, kind),
     .label = "Kind",
     .help = "The surface.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_PAPER_DRAWING},
     NPRFX_CHOICE_RANGE(KIND_COUNT),
     .choices = kind_names,
     .choice_help = kind_help},
    {.name = "scale",
     NPRFX_FIELD(pp, scale),
     .label = "Scale",
     .help = "Grain size in pixels: the grain, bumps and fibres grow with it (not the canvas "
             "threads: see thread).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1.5},
     .soft_min = 0.5,
     .soft_max = 8,
     .hard_min = 0.05,
     .hard_max = 1024,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "grain",
     NPRFX_FIELD(pp, grain),
     .label = "Grain",
     .help = "Amount of grain: the noise of paper, the bumps of watercolor paper, the grain "
             "along canvas threads. 0: none.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 4},
    {.name = "fibres",
     NPRFX_FIELD(pp, fibres),
     .label = "Fibres",
     .help = "Amount of fibres: thin straight or curved strokes of any orientation, lighter or "
             "darker, on paper (and, fainter, on watercolor paper). 0: none.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 4},
    {.name = "weave",
     NPRFX_FIELD(pp, weave),
     .label = "Weave",
     .help = "Amount of the canvas weave's relief. 0: a flat canvas with grain only.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 4},
    {.name = "thread",
     NPRFX_FIELD(pp, thread),
     .label = "Thread",
     .help = "Canvas thread period in pixels: the distance between neighbouring parallel "
             "threads (the weave repeats every two).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {7},
     .soft_min = 3,
     .soft_max = 24,
     .hard_min = 1,
     .hard_max = 4096,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "color",
     NPRFX_FIELD(pp, color),
     .label = "Color",
     .help = "Colour (RGBA, scene-linear) of the highest points of the paper; the valleys are "
             "darker by up to shade. Alpha is the output's alpha.",
     .type = NPRFX_PARAM_COLOR,
     .def = {0.96, 0.94, 0.89, 1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1000},
    {.name = "shade",
     NPRFX_FIELD(pp, shade),
     .label = "Shade",
     .help = "How much the height darkens the colour: color * (1 - shade * (1 - height)). 0: a "
             "flat colour.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.4},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "relief",
     NPRFX_FIELD(pp, relief),
     .label = "Relief",
     .help = "Height scale s in pixels of a built-in light from the upper left (azimuth 135, "
             "elevation 45) on the colour output: it is also multiplied by the bump node's "
             "shade max(0, n . l) / l_z, n = normalize(-s dh/dx, -s dh/dy, 1), 1 where the paper "
             "is flat. 0: no light, the colour follows the height only.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {6},
     .soft_min = 0,
     .soft_max = 30,
     .hard_min = 0,
     .hard_max = 10000,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "tile",
     NPRFX_FIELD(pp, tile),
     .label = "Tile",
     .help = "The texture repeats every tile pixels across and down, exactly (rounded to a whole "
             "pixel; scale and thread are adjusted so that a whole number of cells fits). 0: "
             "not periodic.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {512},
     .soft_min = 0,
     .soft_max = 2048,
     .hard_min = 0,
     .hard_max = 65536,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "seed",
     NPRFX_FIELD(pp, seed),
     .label = "Seed",
     .help = "Which sheet: another seed gives another texture of the same kind. The texture "
             "never changes with time (real paper does not move).",
     .type = NPRFX_PARAM_INT,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1000,
     .hard_min = 0,
     .hard_max = 2147483647.0},
    {.name = "output",
     NPRFX_FIELD(pp, output),
     .label = "Output",
     .help = "The paper's colour or its height.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_PAPER_COLOR},
     NPRFX_CHOICE_RANGE(OUTPUT_COUNT),
     .choices = output_names,
     .choice_help = output_help},
};

static nprfx_result paper_output(const void *params, const int *ich, nprfx_output_info *out)
{
    (void)ich;
    memset(out, 0, sizeof *out);
    out->channels = ((const pp *)params)->output == NPRFX_PAPER_HEIGHT ? 1 : 4;
    return NPRFX_OK;
}

static double paper_state_bytes(const void *params, const nprfx_state_query *q)
{
    return nprfx_paper_state_bytes(params, q->width, q->height);
}

static nprfx_result paper_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_paper_render(a, params);
}

const nprfx_node_desc nprfx_node_paper = {
    .size = sizeof(nprfx_node_desc),
    .id = "paper",
    .label = "Paper",
    .group = "NPR",
    .help = "A procedural paper, cold-press watercolour paper or canvas texture: the background "
            "a stylised image is composited over (with blend), or a height for bump and for "
            "watercolor's paper input. Like real paper it is fixed in screen space: it does not "
            "move with the scene and is the same at every frame. It repeats exactly every tile "
            "pixels.\n"
            "\n"
            "The height h lies in [0, 1] with a mean of about 0.5; the colour output is "
            "color * (1 - shade * (1 - h)) * max(0, n . l) / l_z: color is the colour of the "
            "highest points, the valleys are darker, and the relief is lit from the upper left as "
            "the bump node lights it (n from the height's gradient scaled by relief; the factor "
            "is 1 where the paper is flat).\n"
            "\n"
            "The node makes an image from nothing: its frame comes from the optional image input "
            "(whose pixels are not read), or else from the graph's \"format\" (the host's project "
            "size in OpenFX)."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "A NaN or infinite image pixel is missing: the paper alone shows there. The output "
            "stays finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output = paper_output,
    .render = paper_render,
    /* the texture of the last window, copied for every later frame (it never changes) */
    .flags = NPRFX_NODE_STATEFUL,
    .state_free = nprfx_paper_state_free,
    .state_bytes = paper_state_bytes,
    .params_size = sizeof(pp),
    .version_major = 1,
};
