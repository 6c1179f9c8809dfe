/* The stipple node: instant stippling from UV and shading (Ma et al. 2018). The math lives in
 * core/stipple*.c and core/ivs*.c, the node's params and instance cache in
 * core/stipple/stipple_node.c; the shipped dot sequence is read and the dots exported as CSV/SVG in
 * plugins/support/. This file is the descriptor and the glue. */
#include <string.h>

#include "nprfx/node.h"
#include "nprfx/stipple.h"
#include "support/data_files.h"
#include "support/stipple_export.h"

/* In the order core reads them (nprfx/stipple.h). */
enum {
    IN_TONE = NPRFX_STIPPLE_IN_TONE,
    IN_UV = NPRFX_STIPPLE_IN_UV,
    IN_ID = NPRFX_STIPPLE_IN_ID,
    IN_COUNT = NPRFX_STIPPLE_IN_COUNT
};
enum {
    P_MODE,
    P_SIZE,
    P_A0,
    P_DELTA_MIN,
    P_TONES,
    P_TILE,
    P_ASPECT,
    P_ANISOTROPY,
    P_INK,
    P_PAPER,
    P_SEED,
    P_TONE_CORRECTION,
    P_COVERAGE,
    P_EXPORT,
    P_COUNT
};
typedef nprfx_stipple_node_params sp;

static const char *const mode_names[] = {"uniform", "radius", "multitone", NULL};
static const char *const mode_help[] = {
    "dots of one size (size px^2); sample i is kept while k A0 / i >= size / g (Eq. 5), so the "
    "dot density follows the darkness g = 1 - tone",
    "dots at a fixed density, one per a0 px^2 (k A0 / i >= a0), each of area g * a0 (Eq. 6); "
    "dots smaller than delta_min are dropped",
    "dots of one size (size px^2) at one per a0 px^2, each drawn with one of the pens in "
    "'tones': the two pens around tau = g a0 / size are mixed by sample index (Eq. 7-8)",
    NULL};
_Static_assert(sizeof mode_names / sizeof mode_names[0] == NPRFX_STIPPLE_MULTITONE + 2,
               "stipple: mode names must follow nprfx_stipple_mode");

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "tone",
     .label = "Tone",
     .help = "The shading to reproduce, 1 = white paper, 0 = full ink (e.g. the diffuse pass, "
             "or any image for 2D stippling). 3 or 4 channels are read as Rec. 709 luma.",
     .aov = "diffuse|diffuse.Y|Diffuse.Y|tone|R,G,B",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN},
    {.name = "uv",
     .label = "UV",
     .help = "Surface parameterisation the dots are anchored to (2 channels). Not connected: "
             "the image is its own UV space (uv = pixel / 1024), which stipples a 2D image.",
     .aov = "uv",
     .channels = 2,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "id",
     .label = "Object ID",
     .help =
         "Object index (1 channel, compared exactly). Derivatives never cross an id edge, and each "
         "object gets its own part of the sequence. Not connected: one object.",
     .aov = "id",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "mode",
     NPRFX_FIELD(sp, stipple.mode),
     .label = "Mode",
     .help = "How the tone is reproduced; see the node help.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_STIPPLE_UNIFORM},
     NPRFX_CHOICE_RANGE(NPRFX_STIPPLE_MULTITONE + 1),
     .choices = mode_names,
     .choice_help = mode_help},
    {.name = "size",
     NPRFX_FIELD(sp, stipple.area),
     .label = "Stipple Size",
     .help = "uniform and multitone: the area of every dot in px^2 (the paper's delta; a disc of "
             "radius sqrt(size / pi)). Smaller dots make more of them for the same tone.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {6},
     .soft_min = 0.5,
     .soft_max = 30,
     .hard_min = 0.01,
     .hard_max = 2000,
     .flags = NPRFX_PARAM_AREA},
    {.name = "a0",
     NPRFX_FIELD(sp, stipple.a0),
     .label = "Area per Dot",
     .help = "radius and multitone: the screen area in px^2 each kept dot stands for (the "
             "paper's a0): dots are spread at one per a0 px^2 whatever the tone. The darkest "
             "tone multitone can reach is size / a0 (times the darkest pen): keep size >= a0 for "
             "black.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {6},
     .soft_min = 1,
     .soft_max = 100,
     .hard_min = 0.01,
     .hard_max = 2000,
     .flags = NPRFX_PARAM_AREA},
    {.name = "delta_min",
     NPRFX_FIELD(sp, stipple.delta_min),
     .label = "Minimum Dot Area",
     .help = "radius: dots smaller than this many px^2 are dropped, as an artist would not draw "
             "them (the paper's delta_min).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.5},
     .soft_min = 0,
     .soft_max = 10,
     .hard_min = 0,
     .hard_max = 2000,
     .flags = NPRFX_PARAM_AREA},
    {.name = "tones",
     NPRFX_FIELD(sp, tones),
     .label = "Pen Tones",
     .help = "multitone: the darkness of each pen, ascending, in (0, 1] (1 = the ink colour, "
             "0.5 = halfway to the paper), separated by commas. White paper is the implicit "
             "lightest pen.",
     .type = NPRFX_PARAM_STRING,
     .def_string = "0.33,0.67,1"},
    {.name = "tile",
     NPRFX_FIELD(sp, stipple.tile),
     .label = "UV Tile",
     .help = "Period of the dot sequence in UV units: one copy covers tile x tile of UV space "
             "(the paper's A0 = tile^2). Without a uv input, in units of 1024 pixels. A copy "
             "should span at least a hundred pixels on screen, or its repetition shows as a "
             "lattice; it holds at most 2^21 dots, so a copy spanning more than about 3000 px "
             "saturates in the darkest tones.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0.01,
     .soft_max = 4,
     .hard_min = 1e-6,
     .hard_max = 1e6},
    {.name = "aspect",
     NPRFX_FIELD(sp, stipple.aspect),
     .label = "UV Aspect",
     .help = "How many times longer a unit of u is than a unit of v on the surfaces (1: square "
             "UVs). Where a UV map stretches, e.g. a unit square mapped onto a 2.5:1 plane, the "
             "dots are stretched with it and line up in rows; give the stretch here and the "
             "sequence is tiled with period tile / sqrt(aspect) in u and tile * sqrt(aspect) in "
             "v, the same area per copy, so its copies are square on the surface again. One "
             "value for all objects: pick the typical stretch of the shot's UV maps.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0.25,
     .soft_max = 4,
     .hard_min = 1e-3,
     .hard_max = 1e3},
    {.name = "anisotropy",
     NPRFX_FIELD(sp, stipple.anisotropy),
     .label = "Follow Foreshortening",
     .help = "Keep the dots blue noise where a surface is seen at a grazing angle. The sequence "
             "lies on the UVs, so where the view squeezes a surface in one direction its dots "
             "would be squeezed too and line up in rows (a ground plane, the oblique faces of a "
             "box, the sides of a cylinder). On (the default), the sequence is read through the "
             "inverse of that squeeze (one of 13 fixed stretches, 2x to 8x in four directions, "
             "blended between neighbours), so its dots are evenly spread on screen while they "
             "stay on the surface (up to a 16x squeeze; beyond, towards a horizon, as off). As "
             "a surface turns, its dots dissolve from one stretch to the next over a few frames "
             "(some dots are grey meanwhile) instead of popping. Off, as Ma et al. do, the "
             "sequence follows the UVs alone: faster (on costs 2 to 4 times the render time "
             "where surfaces are foreshortened) and every dot full black.",
     .type = NPRFX_PARAM_BOOL,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "ink",
     NPRFX_FIELD(sp, ink),
     .label = "Ink",
     .help = "Colour of the dots (RGBA, premultiplied).",
     .type = NPRFX_PARAM_COLOR,
     .def = {0, 0, 0, 1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = -1e9,
     .hard_max = 1e9},
    {.name = "paper",
     NPRFX_FIELD(sp, paper),
     .label = "Paper",
     .help = "Colour between the dots (RGBA, premultiplied; alpha 0 gives dots over "
             "transparency, to composite over another image).",
     .type = NPRFX_PARAM_COLOR,
     .def = {1, 1, 1, 1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = -1e9,
     .hard_max = 1e9},
    {.name = "seed",
     NPRFX_FIELD(sp, seed),
     .label = "Seed",
     .help = "Shifts the sequence (per object): a different seed gives different dots with the "
             "same statistics.",
     .type = NPRFX_PARAM_INT,
     .def = {0},
     .soft_min = 0,
     .soft_max = 100,
     .hard_min = 0,
     .hard_max = 2147483647.0},
    {.name = "tone_correction",
     NPRFX_FIELD(sp, tone_correction),
     .label = "Tone Correction",
     .help = "Compensate for overlapping dots: the paper's thresholds lay down ink area g per "
             "unit area, but overlapping discs cover less, so dark tones come out light (by up "
             "to ~0.15). On, the darkness each mode really produces is measured once for these "
             "params (~30 ms) and inverted, so the tone is reproduced; off, the thresholds are "
             "exactly Eq. 5-8.",
     .type = NPRFX_PARAM_BOOL,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "coverage",
     NPRFX_FIELD(sp, stipple.coverage_channel),
     .label = "Coverage Channel",
     .help = "Add a fifth output channel, 'coverage': the ink coverage d in [0, 1] each pixel "
             "was drawn with (out = paper + d (ink - paper)). In an OpenFX host, whose images "
             "hold four channels, the coverage comes in alpha instead.",
     .type = NPRFX_PARAM_BOOL,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "export",
     NPRFX_FIELD(sp, export_path),
     .label = "Export",
     .help = "Also write the dots of each frame as vectors to this frame-sequence path; the "
             "extension picks the format. .csv: the header x,y,radius,tone,sample,object, one "
             "dot a row, in pixels with y down and the frame's top-left corner at 0,0. .svg: "
             "the same discs, viewBox = the frame size, paper as background. Empty: no export. "
             "The runner writes it relative to its output folder; an OpenFX host writes it at "
             "full-resolution renders, relative to the host's working folder (give an absolute "
             "path there).",
     .type = NPRFX_PARAM_STRING,
     .def_string = "",
     .flags = NPRFX_PARAM_PATH | NPRFX_PARAM_EXPORT},
};

static nprfx_result st_output(const void *params, const int *ich, nprfx_output_info *out)
{
    (void)ich;
    memset(out, 0, sizeof *out);
    out->channels = ((const sp *)params)->stipple.coverage_channel ? 5 : 4;
    out->names[0] = "R";
    out->names[1] = "G";
    out->names[2] = "B";
    out->names[3] = "A";
    if (out->channels == 5) out->names[4] = "coverage";
    return NPRFX_OK;
}

/* The bound params with the one field no param binds filled: the dot sequence comes from the
 * shipped data file when there is one (plugins/support/data_files.c). Core reads no files, and
 * this layer is the one that may, so the descriptor names the maker, for render and export alike;
 * the node keeps the one render shape (nprfx/stipple.h, make_sequence). */
static sp with_shipped_sequence(const void *params)
{
    sp p = *(const sp *)params;
    p.make_sequence = internal_stipple_shipped_sequence;
    return p;
}

/* Core renders (core/stipple/stipple_node.c). */
static nprfx_result st_render(const nprfx_render_args *a, const void *params)
{
    sp p = with_shipped_sequence(params);
    return nprfx_stipple_render(a, &p);
}

/* The dots as CSV or SVG, by the path's extension (plugins/support/stipple_export.c). */
static nprfx_result st_export_text(const nprfx_render_args *a, const void *params, const char *path,
                                   char **text, size_t *len)
{
    sp p = with_shipped_sequence(params);
    return internal_stipple_export_text(a, &p, path, text, len);
}

const nprfx_node_desc nprfx_node_stipple = {
    .size = sizeof(nprfx_node_desc),
    .id = "stipple",
    .label = "Stipple",
    .group = "NPR",
    .help =
        "Instant stippling (Ma, Guo, Yan, Sun, Chen, \"Instant Stippling on 3D Scenes\", "
        "Computer Graphics Forum 37(7), 2018): dots of ink whose density, size or pen tone "
        "reproduces the shading, evenly spread on screen in every frame (blue noise) yet "
        "anchored to the surfaces through the UV pass, so that as objects move, turn, approach "
        "or are relit only a few dots appear or vanish between frames. Without a uv input it "
        "stipples any 2D image.\n"
        "\n"
        "The dots are the points of an incremental Voronoi set (IVS, Ma, Chen, Qian, Sun, The "
        "Visual Computer 34(6), 2018), a farthest-point sequence on the torus: every prefix of it "
        "is evenly spread and sample i covers about 1/i of a tile. Its first 2^21 points (all "
        "a pixel may use) ship as share/nprfx/ivs.bin (written by the build with `nprfx ivs`; "
        "in the OpenFX bundle, Contents/Resources/ivs.bin; $NPRFX_DATA_DIR overrides the "
        "folder), read once per process; without the file it is generated on first use "
        "(seconds per million points), with the same result. The sequence is tiled over UV space "
        "(period 'tile') and shifted per object id. A pixel with UV Jacobian J sees k = 1 / "
        "|det J| px^2 per unit of UV area and keeps the samples i whose screen area k A0 / i "
        "passes the mode's threshold, g = 1 - tone being the darkness:\n"
        "  uniform    k A0 / i >= size / g, dots of area size\n"
        "  radius     k A0 / i >= a0, dots of area g a0 (dropped below delta_min)\n"
        "  multitone  k A0 / i >= a0, dots of area size in the pens around g a0 / size\n"
        "\n"
        "Each dot belongs to exactly one pixel (the pixel footprints tile UV space) and is drawn "
        "as an anti-aliased disc of exact area, in ink over paper; overlapping dots combine as "
        "1 - prod(1 - coverage x pen tone). Results do not depend on threads or tiles. Overlapping "
        "discs cover less than their summed area, which 'tone_correction' (on by default) "
        "compensates for by a measured curve applied to g. The 'export' param writes the dots as "
        "CSV or SVG for print or pen plotters."
        "\n\nNaN and infinities (docs/design.md §2.2): "
        "A NaN tone reads as paper (no stipple), infinities clamp; a NaN or infinite uv or id "
        "is no object. The output stays finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output = st_output,
    .flags = NPRFX_NODE_STATEFUL,
    .render = st_render,
    .state_free = nprfx_stipple_state_free,
    .export_text = st_export_text,
    .item_name = "stipples",
    .params_size = sizeof(sp),
    .version_major = 1,
};
