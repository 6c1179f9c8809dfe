/* The pam-splat node: a painterly art map splatted on the surfaces (Yan et al. 2008 §5,
 * docs/design.md §3.7). The algorithm lives in core/pam/pam_splat.c (on the anchored-point scatter of
 * core/gabor/anchored_scatter.c) and core/pam/pam.c; this file is the descriptor and the glue. */
#include <stddef.h>
#include <string.h>

#include "nprfx/node.h"
#include "nprfx/pam_splat.h"

enum {
    IN_ANCHOR = NPRFX_PAM_SPLAT_IN_ANCHOR,
    IN_TONE = NPRFX_PAM_SPLAT_IN_TONE,
    IN_COLOR = NPRFX_PAM_SPLAT_IN_COLOR,
    IN_DIRECTION = NPRFX_PAM_SPLAT_IN_DIRECTION,
    IN_DEPTH = NPRFX_PAM_SPLAT_IN_DEPTH,
    IN_ID = NPRFX_PAM_SPLAT_IN_ID,
    IN_PAM = NPRFX_PAM_SPLAT_IN_PAM,
    IN_COUNT = NPRFX_PAM_SPLAT_IN_COUNT
};
enum {
    P_ANCHOR_SPACE,
    P_SIZE,
    P_DENSITY,
    P_BETA,
    P_GAMMA,
    P_DETAIL,
    P_SHARPNESS,
    P_ASPECT,
    P_TEXEL,
    P_COLOR_FROM,
    P_ORIENTATION,
    P_FLOW,
    P_JITTER,
    P_SEED,
    P_CELL,
    P_DEPTH_TOLERANCE,
    P_COUNT
};
typedef nprfx_pam_splat_params pnp;

static const char *const color_names[] = {"splat", "pixel", NULL};
static const char *const color_help[] = {
    "at each splat's centre, as the paper: every dab is painted in one colour and dabs blend like"
    " the strokes, so the model's edges (texture, silhouettes of colour) become dab-shaped",
    "per pixel: the model's own edges stay sharp, the PAM only modulates them", NULL};
_Static_assert(sizeof color_names / sizeof color_names[0] == NPRFX_PAM_COLOR_COUNT + 1,
               "pam-splat: colour choice names must follow nprfx_pam_color_from");
static const char *const space_names[] = {"pref", "uv", NULL};
static const char *const space_help[] = {
    "object-space rest position (3 channels, optional 4th = coverage): moving, rotating and "
    "deforming objects",
    "surface parameterisation (U, V, optional 3rd = coverage): objects with a seamless UV map",
    NULL};
_Static_assert(sizeof space_names / sizeof space_names[0] == NPRFX_PAM_SPACE_COUNT + 1,
               "pam-splat: anchor space names must follow nprfx_pam_anchor_space");

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "anchor",
     .label = "Anchor",
     .help = "The surface coordinates the splats are anchored to, as anchor_space says: Pref "
             "(3 channels) or UV (2), an optional coverage channel after them. As gabor-splat's "
             "anchor: name UV channels explicitly (plate:UV.U,UV.V).",
     .aov = "rest",
     .channels = 0,
     .flags = NPRFX_INPUT_IN_PLACE},
    {.name = "tone",
     .label = "Tone",
     .help = "The tone w in [0, 1] (the lighting, e.g. a tone node on the diffuse light) that "
             "picks the PAM's maps, dark to light. Read per pixel; values outside [0, 1] are "
             "clamped, NaN reads as 0. 1 channel.",
     .aov = "diffuse|tone|Y",
     .channels = 1},
    {.name = "color",
     .label = "Colour",
     .help = "The model colour (RGB or RGBA; the output has its channels): the PAM changes its "
             "luminance and chroma by the strokes' deviations (Eq. 10). Background pixels (no "
             "surface in depth) pass through unchanged, and so does alpha.",
     .aov = "R,G,B,A|R,G,B",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN},
    {.name = "direction",
     .label = "Direction",
     .help = "Where strokes run: 1 channel, an angle in degrees (counter-clockwise from +x); 2 "
             "channels, a direction in pixels (x right, y down), e.g. a projected principal "
             "curvature or tangent. Read at each splat's owner pixel and added to orientation. "
             "Not connected: orientation alone.",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
    {.name = "depth",
     .label = "Depth",
     .help = "Depth (larger = farther; background <= 0, >= 1e9, inf or NaN): the visibility "
             "buffer of the first pass and the surface edges of the scatter.",
     .aov = "depth",
     .channels = 1,
     .flags = NPRFX_INPUT_IN_PLACE},
    {.name = "id",
     .label = "Object ID",
     .help = "Object index: a splat reaches only pixels of its own object. Not connected: one "
             "object.",
     .aov = "id",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
    {.name = "pam",
     .label = "Painterly Art Map",
     .help = "The PAM: one RGB image of N >= 2 square, tileable maps of S x S pixels side by side"
             " (width N x S, height S), dark to light, linear (nprfx pam build writes them). "
             "Any size, read whole. An image whose width is not a multiple (2 or more) of its "
             "height is refused. Not connected: a builtin PAM of 6 maps of 64 px of short "
             "vertical strokes.",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_UNALIGNED},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "anchor_space",
     NPRFX_FIELD(pnp, anchor_space),
     .label = "Anchor Space",
     .help = "What the anchor input holds.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_PAM_SPACE_PREF},
     NPRFX_CHOICE_RANGE(NPRFX_PAM_SPACE_COUNT),
     .choices = space_names,
     .choice_help = space_help},
    {.name = "size",
     NPRFX_FIELD(pnp, size),
     .label = "Splat Size",
     .help = "Diameter of a splat in pixels. Its alpha is a Gaussian that falls to 5% at the "
             "rim, so a splat reads as a dab about half this wide. Kept in screen space at "
             "every zoom: strokes keep their size as objects approach.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {32},
     .soft_min = 4,
     .soft_max = 96,
     .hard_min = 1,
     .hard_max = 4096,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "density",
     NPRFX_FIELD(pnp, density),
     .label = "Density",
     .help = "Expected number of splats overlapping a pixel (splats per pixel^2 = density / "
             "(pi (size/2)^2)). Under 3 leaves pixels no splat reaches (they keep the "
             "model colour); more blends the dabs into a smoother texture. Cost grows with it.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {4},
     .soft_min = 1,
     .soft_max = 16,
     .hard_min = 0.01,
     .hard_max = 10000},
    {.name = "beta",
     NPRFX_FIELD(pnp, beta),
     .label = "Luminance Strength",
     .help = "beta of Eq. 10: how much of the PAM's luminance deviation (texel Y minus the "
             "PAM's mean Y) is added to the model colour's. 1 copies the paint's light and "
             "dark; 0 keeps the model's luminance (no shading from the tone).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = -100,
     .hard_max = 100},
    {.name = "gamma",
     NPRFX_FIELD(pnp, gamma),
     .label = "Chroma Strength",
     .help = "gamma of Eq. 10: how much of the PAM's chroma deviation (texel U, V minus its "
             "mean) is added to the model colour's; 0 keeps the model's hue. 0.5 keeps a "
             "coloured model's hues under a tinted PAM; 1 or more on a grey model lets the "
             "PAM's own colours carry the look.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.5},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = -100,
     .hard_max = 100},
    {.name = "detail",
     NPRFX_FIELD(pnp, detail),
     .label = "Stroke Contrast",
     .help = "How strongly the strokes show: the PAM's deviation is split into the tone's part "
             "(the mean of the maps at the local tone minus the PAM's mean: shading) and the "
             "strokes' part (each texel minus its map's mean), and the strokes' part is scaled "
             "by this before beta and gamma apply. 1 is the paper's Eq. 10; overlapping splats "
             "average their strokes away, which this gives back without darkening the shadows "
             "further. 0: the tone alone, no strokes.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {3},
     .soft_min = 0,
     .soft_max = 5,
     .hard_min = -100,
     .hard_max = 100},
    {.name = "sharpness",
     NPRFX_FIELD(pnp, sharpness),
     .label = "Dab Sharpness",
     .help = "Where splats overlap, each pixel averages them weighted by a Gaussian of its "
             "distance to their centres; sharpness narrows that Gaussian (its exponent times "
             "this), so the nearest splat's strokes dominate and the others fade in only near "
             "the borders between dabs. 1: the paper's smooth blend, which blurs strokes where "
             "splats overlap; 3-6: distinct dabs; higher: hard edges between them.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1.5},
     .soft_min = 1,
     .soft_max = 10,
     .hard_min = 1,
     .hard_max = 100},
    {.name = "aspect",
     NPRFX_FIELD(pnp, aspect),
     .label = "Dab Aspect",
     .help = "Length over width of a dab's weight: across the direction its Gaussian is this "
             "many times narrower, so where splats overlap the one whose axis passes nearest "
             "wins, and dabs are long and thin along the strokes instead of round (1: round, "
             "the paper's).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {3},
     .soft_min = 1,
     .soft_max = 6,
     .hard_min = 1,
     .hard_max = 100},
    {.name = "texel",
     NPRFX_FIELD(pnp, texel),
     .label = "Texel Size",
     .help = "Screen pixels per PAM pixel: 1 shows the maps at their own resolution, 2 twice as"
             " large (coarser strokes). 0: relative to the splat, size / (S / 4) for maps of S "
             "px, so that a splat spans a quarter of a map, as wide as a few strokes of any "
             "PAM, at any splat size (the builder's strokes are about a third of a map long).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = 0,
     .soft_max = 8,
     .hard_min = 0,
     .hard_max = 1e4,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "color_from",
     NPRFX_FIELD(pnp, color_from),
     .label = "Colour From",
     .help = "Where the model colour is read.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_PAM_COLOR_SPLAT},
     NPRFX_CHOICE_RANGE(NPRFX_PAM_COLOR_COUNT),
     .choices = color_names,
     .choice_help = color_help},
    {.name = "orientation",
     NPRFX_FIELD(pnp, orientation),
     .label = "Orientation",
     .help = "Degrees (counter-clockwise from +x) added to the direction input: the direction "
             "the PAM's rows, and so its strokes (painted along v), run on screen. Without a "
             "direction input, 90 gives upright strokes.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = -180,
     .soft_max = 180,
     .hard_min = -1e6,
     .hard_max = 1e6},
    {.name = "flow",
     NPRFX_FIELD(pnp, flow),
     .label = "Flow Speed",
     .help = "Stroke flow (Eq. 11): the texture inside each splat moves along the direction at"
             " this many pixels per frame (negative: against it), while the splats stay on the "
             "surface. 0: still strokes.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = -4,
     .soft_max = 4,
     .hard_min = -1e4,
     .hard_max = 1e4,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "jitter",
     NPRFX_FIELD(pnp, jitter),
     .label = "Texture Jitter",
     .help = "Eq. 11's noise offsets: each splat shows the PAM from its own hashed origin, up to"
             " this fraction of a map away (1: anywhere), so neighbouring splats show different "
             "strokes. 0: every splat starts the map at its centre (neighbouring dabs repeat the "
             "same strokes).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "seed",
     NPRFX_FIELD(pnp, seed),
     .label = "Seed",
     .help = "Selects the splats and their texture origins.",
     .type = NPRFX_PARAM_INT,
     .def = {0},
     .soft_min = 0,
     .soft_max = 100,
     .hard_min = 0,
     .hard_max = 2147483647},
    {.name = "cell",
     NPRFX_FIELD(pnp, cell),
     .label = "Cell Size",
     .help = "The scatter's level-0 cell in anchor units (gabor-splat's cell): it matters only "
             "where an object is so small on screen that fewer than one splat per cell is "
             "wanted. About an object's size (1 for Blender's default scale and for UV).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0.01,
     .soft_max = 10,
     .hard_min = 1e-9,
     .hard_max = 1e9},
    {.name = "depth_tolerance",
     NPRFX_FIELD(pnp, depth_tolerance),
     .label = "Depth Tolerance",
     .help = "Relative depth error a splat's fragment tolerates against the depth expected on "
             "the splat's plane (the per-fragment depth test), and the largest relative depth "
             "step inside one surface.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.05},
     .soft_min = 0,
     .soft_max = 0.2,
     .hard_min = 0,
     .hard_max = 10},
};

static nprfx_result pam_output(const void *params, const int *ich, nprfx_output_info *out)
{
    (void)params;
    memset(out, 0, sizeof *out);
    out->channels = ich[IN_COLOR] == 4 ? 4 : 3;
    if (ich[IN_COLOR] && ich[IN_COLOR] != 3 && ich[IN_COLOR] != 4) {
        out->problem = "input 'color' must be RGB or RGBA";
        return NPRFX_ERR_INVALID_ARGUMENT;
    }
    return NPRFX_OK;
}

static nprfx_result pam_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_pam_splat_render(a, params);
}

const nprfx_node_desc nprfx_node_pam_splat = {
    .size = sizeof(nprfx_node_desc),
    .id = "pam-splat",
    .label = "PAM Splat",
    .group = "NPR",
    .help =
        "Painterly rendering with a painterly art map (Yan, Chi, Lee, Lin, \"Stylized Rendering "
        "Using Samples of a Painted Image\", IEEE TVCG 2008, section 5). A PAM is a strip of "
        "tileable paint samples from dark to light; the node covers every surface with "
        "splats, each a Gaussian-edged patch of the PAM at the local tone, turned so its strokes"
        " run along the direction field, that changes the model colour by the paint's "
        "luminance and chroma variations (Eq. 10 in YUV: Y + beta (texel Y - mean Y), UV + "
        "gamma (texel UV - mean UV), the mean taken over the whole PAM, so dark maps darken and "
        "light maps lighten); the strokes' own part of the deviation (texel minus its map's "
        "mean) is scaled by detail, since overlapping splats average it away. Dabs are long "
        "along the direction (aspect) and the nearest one dominates (sharpness), so single "
        "strokes show. With flow, the strokes move along the direction inside the "
        "splats (Eq. 11).\n"
        "\n"
        "The splats are gabor-splat's anchored points: anchored on the surfaces through Pref or"
        " UV, at a constant density on screen with a continuous level of detail (as an object "
        "approaches, new splats fade in), each emitted once. So the paint sticks to the "
        "surfaces frame to frame, and when the light moves only the tone changes: the strokes "
        "do not swim. A splat reaches only pixels of its own object whose depth is on its "
        "plane (the per-fragment id and depth tests), and the three passes of the paper's "
        "section 5.1 are: the depth and id AOVs as the visibility buffer, Gaussian-weighted "
        "accumulation of the PAM's deviations, normalisation by the summed weights.\n"
        "\n"
        "The tone picks the maps by their mean luminance: w = 0 the darkest, 1 the lightest, "
        "in between the two maps whose mean luminance brackets the darkest mean plus w times "
        "the range, mixed linearly, so the mean brightness follows the tone. Tones outside [0,"
        " 1] are clamped. The tone is read per pixel, the model colour at each splat's "
        "centre (color_from splat: dab-shaped colour) or per pixel; background pixels pass "
        "through. Output is bit-identical for any thread count and tile split."
        "\n\nNaN and infinities (docs/design.md §2.2): "
        "color passes through at the pixel. A NaN or infinite anchor, tone, direction, depth "
        "or id is missing (no surface there); the output stays finite. A non-finite pixel in "
        "the art map (pam) refuses the frame with a message that names it.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output = pam_output,
    .flags = NPRFX_NODE_STATEFUL,
    .render = pam_render,
    .state_free = nprfx_pam_splat_state_free,
    .params_size = sizeof(pnp),
    .version_major = 1,
    .item_name = "splats",
};
