/* The gabor-splat node: NPR Gabor noise anchored on surfaces through position/UV AOVs (Benard et
 * al. 2010, docs/design.md §3.2). The algorithm lives in core/gabor/; this file is the descriptor,
 * binding the params into nprfx_gabor_splat_params (most of them its nprfx_gabor_params), and the
 * call into core/gabor/gabor_splat.c. */
#include <stddef.h>
#include <string.h>

#include "nprfx/gabor.h"
#include "nprfx/node.h"

enum {
    IN_ANCHOR = NPRFX_GABOR_SPLAT_IN_ANCHOR,
    IN_DEPTH = NPRFX_GABOR_SPLAT_IN_DEPTH,
    IN_ID = NPRFX_GABOR_SPLAT_IN_ID,
    IN_ORIENTATION = NPRFX_GABOR_SPLAT_IN_ORIENTATION,
    IN_FREQUENCY = NPRFX_GABOR_SPLAT_IN_FREQUENCY,
    IN_COUNT = NPRFX_GABOR_SPLAT_IN_COUNT
};
enum {
    P_ANCHOR_SPACE,
    P_FREQUENCY,
    P_ORIENTATION,
    P_ISOTROPIC,
    P_RADIUS,
    P_N0,
    P_AMPLITUDE,
    P_SEED,
    P_CELL,
    P_LOD_LEVELS,
    P_FADE,
    P_DEPTH_TEST,
    P_DEPTH_TOLERANCE,
    P_SUPERSAMPLE,
    P_OUTPUT,
    P_CONTRAST,
    P_POINTS,
    P_COUNT
};
enum { SPACE_COUNT = NPRFX_GABOR_SPACE_COUNT };
typedef nprfx_gabor_splat_params gnp;

static const char *const space_names[] = {"pref", "uv", "p", NULL};
static const char *const space_help[] = {
    "object-space rest position (3 channels, optional 4th = coverage): moving, rotating and "
    "deforming objects",
    "surface parameterisation (U, V, optional 3rd = coverage): any object with a seamless UV map",
    "world position (3 channels): static objects only (a moving object would swim through it)",
    NULL};
_Static_assert(sizeof space_names / sizeof space_names[0] == SPACE_COUNT + 1,
               "gabor-splat: anchor space names must follow the SPACE_ enum");

static const char *const amp_names[] = {"uniform", "sign", "gauss", NULL};
static const char *const amp_help[] = {
    "v uniform in [-1, 1] (Lagae et al.), E[v^2] = 1/3",
    "v = +1 or -1: every kernel at full contrast, more even stroke weight", "v standard normal",
    NULL};
_Static_assert(sizeof amp_names / sizeof amp_names[0] == NPRFX_GABOR_AMP_COUNT + 1,
               "gabor-splat: amplitude names must follow nprfx_gabor_amplitude");

static const char *const dtest_names[] = {"off", "hard", "soft", NULL};
static const char *const dtest_help[] = {
    "object-id test only",
    "a kernel reaches a pixel only where the relative depth error is "
    "within depth_tolerance",
    "weight 1 up to depth_tolerance, falling linearly to 0 at twice it: partial visibility "
    "instead of a binary cut, less popping at (dis)occlusions",
    NULL};
_Static_assert(sizeof dtest_names / sizeof dtest_names[0] == NPRFX_GABOR_DEPTH_COUNT + 1,
               "gabor-splat: depth test names must follow nprfx_gabor_depth_test");

static const char *const fade_names[] = {"level", "staggered", NULL};
static const char *const fade_help[] = {
    "docs/design.md's rule: every point of the finer level fades in together, squared weight "
    "(D - D_L) / (K 4^(L+1) / h0^2) (the paper's a(N) = sqrt(N/M - 1))",
    "each point of the finer level fades in on its own (a hashed start, its amplitude ramping "
    "linearly over a quarter of the level's zoom range); the expected squared weight is the "
    "level rule's, so density, variance and spectrum are the same, with about half the kernels "
    "(faster) and no synchronised onset of a whole level",
    NULL};
_Static_assert(sizeof fade_names / sizeof fade_names[0] == NPRFX_GABOR_FADE_COUNT + 1,
               "gabor-splat: fade names must follow nprfx_gabor_fade");

static const char *const output_names[] = {"unit", "unit01", NULL};
static const char *const output_help[] = {"zero mean, unit variance",
                                          "0.5 + contrast * n, for thresholding", NULL};

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "anchor",
     .label = "Anchor",
     .help = "The surface coordinates the kernels are anchored to, as anchor_space says: Pref "
             "(rest position, 3 channels), UV (2) or world P (3). An extra channel after them is "
             "read as coverage (Blender's Pref.A, UV.A): pixels with coverage below 1 are treated"
             " as edge pixels. Name the channels in that order: a Blender plate's UV layer is "
             "stored A, U, V, so take plate:UV.UVA (or plate:UV.U,UV.V), not plate:UV; Pref "
             "layers come as R, G, B, A (plate:Pref). The default picks a Pref layer, so for UV "
             "anchors always name the channels. Use full float data: half-float anchors "
             "(1/2000 of a unit) make the per-pixel Jacobian noisy at high resolutions.",
     .aov = "rest",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN | NPRFX_INPUT_IN_PLACE},
    {.name = "depth",
     .label = "Depth",
     .help = "Depth (view-space z or camera distance, larger = farther) for the depth test and "
             "to find surface edges. Background: <= 0, >= 1e9, inf or NaN (Blender writes 1e10, "
             "inf in half-float files): no noise there.",
     .aov = "depth",
     .channels = 1,
     .flags = NPRFX_INPUT_IN_PLACE},
    {.name = "id",
     .label = "Object ID",
     .help = "Object index (integers): a kernel reaches only pixels of its own object, and "
             "anchors of different objects get independent points. Not connected: one object.",
     .aov = "id",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
    {.name = "orientation",
     .label = "Orientation",
     .help = "Per-pixel orientation added to the orientation param: 1 channel, an angle in "
             "degrees (counter-clockwise); 2 channels, a direction in pixels (x right, y down). "
             "Read where each kernel's point is, so a kernel keeps one orientation. Ignored when "
             "isotropic.",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
    {.name = "frequency",
     .label = "Frequency Scale",
     .help = "Per-pixel factor on the frequency param (e.g. from the shading, for finer "
             "strokes in the darks), read where each kernel's point is. 1 channel.",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL | NPRFX_INPUT_IN_PLACE},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "anchor_space",
     NPRFX_FIELD(gnp, anchor_space),
     .label = "Anchor Space",
     .help = "What the anchor input holds; see the node help on choosing it.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_GABOR_SPACE_PREF},
     NPRFX_CHOICE_RANGE(SPACE_COUNT),
     .choices = space_names,
     .choice_help = space_help},
    {.name = "frequency",
     NPRFX_FIELD(gnp, gabor.frequency),
     .label = "Frequency",
     .help = "F0: the kernels' frequency in cycles per pixel (1 / wavelength: 0.1 = stripes 10 "
             "px apart). Kept in screen space at every zoom. Above 0.5 it aliases unless "
             "supersampled.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.1},
     .soft_min = 0.01,
     .soft_max = 0.5,
     .hard_min = 1e-4,
     .hard_max = 100},
    {.name = "orientation",
     NPRFX_FIELD(gnp, gabor.orientation),
     .label = "Orientation",
     .help = "w0: direction of the wave vector in degrees, counter-clockwise from the image's +x"
             " axis. The stripes run across it: 0 gives vertical stripes, 90 horizontal ones "
             "(to hatch along a direction, add 90).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0},
     .soft_min = -180,
     .soft_max = 180,
     .hard_min = -1e6,
     .hard_max = 1e6},
    {.name = "isotropic",
     NPRFX_FIELD(gnp, gabor.isotropic),
     .label = "Isotropic",
     .help = "A random orientation per kernel: no preferred direction (blobs and stipples "
             "when thresholded instead of hatches).",
     .type = NPRFX_PARAM_BOOL,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "radius",
     NPRFX_FIELD(gnp, gabor.radius),
     .label = "Kernel Radius",
     .help = "Truncation radius r of the kernels in pixels; the bandwidth is a = sqrt(-ln 0.05 /"
             " pi) / r (the envelope is 5% at r). Larger kernels hold more stripes: more regular,"
             " longer strokes.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {16},
     .soft_min = 2,
     .soft_max = 64,
     .hard_min = 0.25,
     .hard_max = 4096,
     .flags = NPRFX_PARAM_PIXELS},
    {.name = "n0",
     NPRFX_FIELD(gnp, gabor.n0),
     .label = "Kernel Overlap",
     .help = "N0: expected number of kernels overlapping a pixel (point density lambda = N0 / "
             "(pi r^2)). Cost and quality grow with it; 16 to 128 (the paper), 32 is usually "
             "enough.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {32},
     .soft_min = 4,
     .soft_max = 128,
     .hard_min = 0.01,
     .hard_max = 100000},
    {.name = "amplitude",
     NPRFX_FIELD(gnp, gabor.amplitude),
     .label = "Amplitude Law",
     .help = "Distribution of the kernels' random weights (zero mean).",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_GABOR_AMP_UNIFORM},
     NPRFX_CHOICE_RANGE(NPRFX_GABOR_AMP_COUNT),
     .choices = amp_names,
     .choice_help = amp_help},
    {.name = "seed",
     NPRFX_FIELD(gnp, seed),
     .label = "Seed",
     .help = "Selects the point set; layers of one style need different seeds.",
     .type = NPRFX_PARAM_INT,
     .def = {0},
     .soft_min = 0,
     .soft_max = 100,
     .hard_min = 0,
     .hard_max = 2147483647},
    {.name = "cell",
     NPRFX_FIELD(gnp, gabor.cell),
     .label = "Cell Size",
     .help = "h0: size of a level-0 cell of the anchor-space hierarchy, in anchor units. It "
             "matters only where fewer than one point per level-0 cell is wanted (objects tiny "
             "on screen): there every level-0 point is kept with weight sqrt(N), N < 1 being the "
             "wanted count per point. About an object's size works (1 at Blender's default "
             "scale; 1 for UV).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0.01,
     .soft_max = 10,
     .hard_min = 1e-9,
     .hard_max = 1e9},
    {.name = "lod_levels",
     NPRFX_FIELD(gnp, gabor.lod_levels),
     .label = "LOD Levels",
     .help = "W: number of whole levels kept between the level fading in and the level fading "
             "out. The coarsest level carries at most 3 / (4^(W+1) - 1) of the variance; "
             "larger W costs a little more per pixel.",
     .type = NPRFX_PARAM_INT,
     .def = {4},
     .soft_min = 1,
     .soft_max = 8,
     .hard_min = 1,
     .hard_max = 30},
    {.name = "fade",
     NPRFX_FIELD(gnp, gabor.fade),
     .label = "LOD Fade",
     .help = "How the next finer level of points fades in as an object approaches (and the "
             "coarsest one out).",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_GABOR_FADE_LEVEL},
     NPRFX_CHOICE_RANGE(NPRFX_GABOR_FADE_COUNT),
     .choices = fade_names,
     .choice_help = fade_help},
    {.name = "depth_test",
     NPRFX_FIELD(gnp, gabor.depth_test),
     .label = "Depth Test",
     .help = "How a kernel is trimmed where the depth under it is not its own surface's (the "
             "paper's per-fragment depth test). The depth expected under the kernel is its "
             "centre's, extended along the surface's depth gradient, so slanted surfaces are not "
             "cut.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_GABOR_DEPTH_HARD},
     NPRFX_CHOICE_RANGE(NPRFX_GABOR_DEPTH_COUNT),
     .choices = dtest_names,
     .choice_help = dtest_help},
    {.name = "depth_tolerance",
     NPRFX_FIELD(gnp, gabor.depth_tolerance),
     .label = "Depth Tolerance",
     .help = "Relative depth error |z - z_expected| / z_expected a kernel tolerates. Also the "
             "largest relative depth step between neighbouring pixels of one surface (at least "
             "1%), which finds the edges the Jacobian must not straddle.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.05},
     .soft_min = 0,
     .soft_max = 0.2,
     .hard_min = 0,
     .hard_max = 10},
    {.name = "supersample",
     NPRFX_FIELD(gnp, gabor.supersample),
     .label = "Supersample",
     .help = "s: evaluate s x s samples per pixel and average them (anti-aliasing of high "
             "frequencies and of the trimmed edges). The normaliser accounts for the box filter, "
             "so the output stays unit variance. Cost grows as s^2.",
     .type = NPRFX_PARAM_INT,
     .def = {1},
     .soft_min = 1,
     .soft_max = 4,
     .hard_min = 1,
     .hard_max = 16},
    {.name = "output",
     NPRFX_FIELD(gnp, gabor.output),
     .label = "Output",
     .help = "Mapping of the noise n (normalised by the theoretical standard deviation of the "
             "sum).",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_GABOR_OUT_UNIT},
     NPRFX_CHOICE_RANGE(2),
     .choices = output_names,
     .choice_help = output_help},
    {.name = "contrast",
     NPRFX_FIELD(gnp, gabor.contrast),
     .label = "Contrast",
     .help = "unit01: the gain on n (0.15 maps +-3.3 sigma to [0, 1]).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.15},
     .soft_min = 0,
     .soft_max = 0.5,
     .hard_min = -100,
     .hard_max = 100},
    {.name = "points",
     NPRFX_FIELD(gnp, gabor.points),
     .label = "Point Channel",
     .help = "Debugging: add a second channel 'points' holding, at each pixel, the squared "
             "weights of the kernels it owns (their sum per pixel^2 is lambda; a kernel's centre"
             " lies in its owner pixel).",
     .type = NPRFX_PARAM_BOOL,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
};

static nprfx_result gabor_output(const void *params, const int *ich, nprfx_output_info *out)
{
    (void)ich;
    memset(out, 0, sizeof *out);
    out->channels = ((const gnp *)params)->gabor.points ? 2 : 1;
    out->names[0] = "Y";
    if (out->channels == 2) out->names[1] = "points";
    return NPRFX_OK;
}

static nprfx_result gabor_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_gabor_splat_render(a, params);
}

const nprfx_node_desc nprfx_node_gabor_splat = {
    .size = sizeof(nprfx_node_desc),
    .id = "gabor-splat",
    .label = "Gabor Splat",
    .group = "NPR",
    .help =
        "NPR Gabor noise (Benard, Lagae, Vangorp, Lefebvre, Drettakis, Thollot, \"A Dynamic "
        "Noise Primitive for Coherent Stylization\", EGSR 2010): a sum of Gabor kernels "
        "g(d) = exp(-pi a^2 |d|^2) cos(2 pi F0 d.w0) whose frequency, orientation and size are "
        "set in pixels, so the pattern keeps a flat 2D look, while their centres are points "
        "anchored on the surfaces, so the pattern moves with the objects. Thresholded "
        "(threshold-map on the unit01 output) it gives hatching (anisotropic) or stipples "
        "(isotropic); several layers with different seeds and orientations, multiplied, give "
        "cross-hatching; a fine layer on top, graphite.\n"
        "\n"
        "No mesh is needed: the points live in the space of an anchor AOV. Per pixel the node "
        "takes the Jacobian J of the anchor with respect to the pixel position (finite "
        "differences that never cross an object-id or depth edge), wants lambda = N0 / (pi "
        "r^2) points per pixel^2, i.e. D = lambda / |det J| per unit anchor area, and draws them"
        " from a hierarchy of anchor-space cells (level l: cells h0 / 2^l, one hashed point "
        "each). Whole levels are kept and the next finer level fades in with a weight that "
        "keeps the sum of squared weights equal to D (the paper's a(N) = sqrt(N/M - 1) on a "
        "hierarchy), so as an object approaches, kernels appear continuously while density, "
        "contrast and spectrum stay constant; W levels coarser, a level fades out, so the cost "
        "per pixel does not grow with zoom (fade = staggered lets each point fade in on its own:"
        " the same statistics with about half the kernels). Each point is emitted once, by the"
        " pixel in whose own linearisation it lies nearest the centre, and its kernel reaches "
        "only pixels with the same object id and a depth within depth_tolerance of the "
        "kernel's surface. For 3D anchors a level's points are those within half a cell of the"
        " surface (a slab, with a soft edge so that points do not flicker in and out).\n"
        "\n"
        "Choosing the anchor:\n"
        "  pref  object-space rest position. The right choice for anything that moves, rotates "
        "or deforms: a surface point keeps its Pref, so its kernels stay on it. Deforming "
        "objects need the rest (undeformed) position, not the current object-space one.\n"
        "  uv    the UV map: 2D anchors, fine for any object with a seamless, non-overlapping "
        "UV layout. Kernels follow the UV density, and UV seams are treated as edges.\n"
        "  p     world position: only for static objects under a moving camera; a moving object "
        "slides through world space and its pattern would swim.\n"
        "\n"
        "Exporting the anchors from Blender (Cycles or EEVEE): for UV, enable View Layer "
        "Properties > Passes > Data > UV (channels UV.U, UV.V, UV.A). For Pref, store the rest "
        "position as a point attribute before any shape key or modifier (Python: "
        "`attr = mesh.attributes.new(\"rest\", 'FLOAT_VECTOR', 'POINT')`, filled from the "
        "vertex coordinates), add a shader AOV named Pref of type Color (View Layer > Shader "
        "AOV), and in each material feed an Attribute node (name: rest, Vector output) into an "
        "AOV Output node named Pref. For a rigid object a Texture Coordinate node's Object "
        "output does the same. Also enable the Z (Depth) and Object Index passes and give each "
        "object its own pass index (Object Properties > Relations). Save as multilayer OpenEXR "
        "with full float for the data passes; samples/blender/make_plates.py does all of this. "
        "Blender's Pref.A and UV.A coverage channels are read as coverage: pixels at a "
        "silhouette mix two surfaces, so they take their anchor from an interior neighbour.\n"
        "\n"
        "Output: zero-mean, unit-variance noise, normalised by the theoretical variance of the "
        "sum, sigma^2 = lambda E[v^2] (1 / (4 a^2)) (1 + exp(-2 pi F0^2 / a^2)); or 0.5 + "
        "contrast * n (output unit01). Background pixels get 0 (unit01: 0.5). Near object edges"
        " the variance drops, since kernels from the other side are cut. Output is "
        "bit-identical for any thread count and tile split."
        "\n\nNaN and infinities (docs/design.md §2.2): "
        "A pixel whose anchor, depth or id is NaN or infinite is background (no kernels are "
        "anchored there); a NaN or infinite orientation or frequency emits no kernel. The "
        "output stays finite.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output = gabor_output,
    .flags = NPRFX_NODE_WRITES_WINDOW, /* every tile's pixels are normalised and written */
    .render = gabor_render,
    .params_size = sizeof(gnp),
    .version_major = 1,
    .item_name = "kernels",
};
