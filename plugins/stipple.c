/* The stipple node: instant stippling from UV and shading (Ma et al. 2018). The math lives in
 * core/stipple.c and core/ivs*.c; this file is the descriptor and the glue. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/node.h"
#include "nprfx/stipple.h"
#include "support/data_files.h"
#include "support/stipple_export.h"

enum { IN_TONE, IN_UV, IN_ID, IN_COUNT };
enum {
    P_MODE,
    P_SIZE,
    P_A0,
    P_DELTA_MIN,
    P_TONES,
    P_TILE,
    P_ASPECT,
    P_INK,
    P_PAPER,
    P_SEED,
    P_TONE_CORRECTION,
    P_COVERAGE,
    P_EXPORT,
    P_COUNT
};

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
     .aov = "UV.UV|uv.UV|UV.U,UV.V|UV.XY|uv.XY|uv",
     .channels = 2,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "id",
     .label = "Object ID",
     .help = "Object index (1 channel, rounded). Derivatives never cross an id edge, and each "
             "object gets its own part of the sequence. Not connected: one object.",
     .aov = "id|IndexOB.X|IndexOB|ID|object_id",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "mode",
     .label = "Mode",
     .help = "How the tone is reproduced; see the node help.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {NPRFX_STIPPLE_UNIFORM},
     NPRFX_CHOICE_RANGE(NPRFX_STIPPLE_MULTITONE + 1),
     .choices = mode_names,
     .choice_help = mode_help},
    {.name = "size",
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
     .label = "Pen Tones",
     .help = "multitone: the darkness of each pen, ascending, in (0, 1] (1 = the ink colour, "
             "0.5 = halfway to the paper), separated by commas. White paper is the implicit "
             "lightest pen.",
     .type = NPRFX_PARAM_STRING,
     .def_string = "0.33,0.67,1"},
    {.name = "tile",
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
    {.name = "ink",
     .label = "Ink",
     .help = "Colour of the dots (RGBA, premultiplied).",
     .type = NPRFX_PARAM_COLOR,
     .def = {0, 0, 0, 1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = -1e9,
     .hard_max = 1e9},
    {.name = "paper",
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
     .label = "Coverage Channel",
     .help = "Add a fifth output channel, 'coverage': the ink coverage d in [0, 1] each pixel "
             "was drawn with (out = paper + d (ink - paper)).",
     .type = NPRFX_PARAM_BOOL,
     .def = {0},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "export",
     .label = "Export",
     .help = "Also write the dots of each frame as vectors to this frame-sequence path; the "
             "extension picks the format. .csv: the header x,y,radius,tone,sample,object, one "
             "dot a row, in pixels with y down and the frame's top-left corner at 0,0. .svg: "
             "the same discs, viewBox = the frame size, paper as background. Empty: no export.",
     .type = NPRFX_PARAM_STRING,
     .def_string = "",
     .flags = NPRFX_PARAM_PATH | NPRFX_PARAM_EXPORT},
};

static nprfx_result st_output(const nprfx_value *pv, const int *ich, nprfx_output_info *out)
{
    (void)ich;
    memset(out, 0, sizeof *out);
    out->channels = pv[P_COVERAGE].v[0] != 0.0 ? 5 : 4;
    out->names[0] = "R";
    out->names[1] = "G";
    out->names[2] = "B";
    out->names[3] = "A";
    if (out->channels == 5) out->names[4] = "coverage";
    return NPRFX_OK;
}

/* ---- the per-instance cache: the dot sequence, and the tone-correction curve of the last
 * params ---- */

typedef struct st_state {
    nprfx_stipple_sequence *seq; /* grown on demand, thread-safe on its own */
    pthread_mutex_t lock;        /* guards the curve */
    int valid;
    nprfx_stipple_params key; /* the params the curve was measured for */
    float curve[NPRFX_STIPPLE_CURVE_SIZE];
} st_state;

static void st_state_free(void *state)
{
    st_state *s = state;
    if (!s) return;
    nprfx_stipple_sequence_destroy(s->seq);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

/* The instance state, created on first use; NULL when the caller gives no state slot (then
 * each call builds what it needs). Hosts may render tiles of one instance on several threads
 * at once: a fresh state is installed with a compare-and-swap, the loser frees its own. */
static nprfx_result st_get_state(const nprfx_render_args *args, st_state **out)
{
    *out = NULL;
    if (!args->state) return NPRFX_OK;
    _Atomic(void *) *slot = (_Atomic(void *) *)args->state;
    st_state *s = atomic_load(slot);
    if (!s) {
        st_state *fresh = calloc(1, sizeof *fresh);
        if (!fresh)
            return nprfx_error(args->ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory");
        /* the shipped ivs.bin when there is one (plugins/support/data_files.c) */
        nprfx_result r = nprfx_stipple_shipped_sequence(args->ctx, &fresh->seq);
        if (r != NPRFX_OK) {
            free(fresh);
            return r;
        }
        pthread_mutex_init(&fresh->lock, NULL);
        void *expected = NULL;
        if (atomic_compare_exchange_strong(slot, &expected, fresh)) {
            s = fresh;
        } else {
            st_state_free(fresh);
            s = expected;
        }
    }
    *out = s;
    return NPRFX_OK;
}

/* The curve depends on the mode and the dot sizes and pens, nothing else. */
static int same_curve_params(const nprfx_stipple_params *a, const nprfx_stipple_params *b)
{
    if (a->mode != b->mode || a->area != b->area || a->a0 != b->a0 ||
        a->delta_min != b->delta_min || a->num_tones != b->num_tones)
        return 0;
    for (int i = 0; i < a->num_tones; i++)
        if (a->tones[i] != b->tones[i]) return 0;
    return 1;
}

/* Fill curve for p, through the instance cache when there is one (computed under its lock). */
static nprfx_result st_curve(const nprfx_render_args *args, st_state *s,
                             const nprfx_stipple_params *p, float *curve)
{
    if (!s) return nprfx_stipple_tone_curve(args->ctx, p, curve);
    nprfx_result r = NPRFX_OK;
    pthread_mutex_lock(&s->lock);
    if (!s->valid || !same_curve_params(&s->key, p)) {
        s->valid = 0;
        r = nprfx_stipple_tone_curve(args->ctx, p, s->curve);
        if (r == NPRFX_OK) {
            s->key = *p;
            s->valid = 1;
        }
    }
    if (r == NPRFX_OK) memcpy(curve, s->curve, sizeof s->curve);
    pthread_mutex_unlock(&s->lock);
    return r;
}

/* Node params to core params (the render scale is already applied to the areas). */
static nprfx_result st_params(const nprfx_render_args *args, nprfx_stipple_params *p)
{
    const nprfx_value *pv = args->params;
    nprfx_stipple_params_default(p);
    p->mode = (int)pv[P_MODE].v[0];
    p->area = pv[P_SIZE].v[0];
    p->a0 = pv[P_A0].v[0];
    p->delta_min = pv[P_DELTA_MIN].v[0];
    p->tile = pv[P_TILE].v[0];
    p->aspect = pv[P_ASPECT].v[0];
    double scale = args->render_scale > 0 ? args->render_scale : 1.0;
    p->plane_scale = NPRFX_STIPPLE_PLANE_PIXELS * scale;
    for (int c = 0; c < 4; c++) {
        p->ink[c] = (float)pv[P_INK].v[c];
        p->paper[c] = (float)pv[P_PAPER].v[c];
    }
    p->seed = (uint64_t)pv[P_SEED].v[0];
    p->coverage_channel = pv[P_COVERAGE].v[0] != 0.0;
    if (p->mode == NPRFX_STIPPLE_MULTITONE)
        return nprfx_stipple_parse_tones(args->ctx, pv[P_TONES].s, p);
    return NPRFX_OK;
}

/* st_params plus the instance's sequence, and the tone curve when the param asks for it
 * (curve: the caller's storage). */
static nprfx_result st_params_full(const nprfx_render_args *args, nprfx_stipple_params *p,
                                   float *curve)
{
    st_state *s = NULL;
    nprfx_result r = st_params(args, p);
    if (r == NPRFX_OK) r = st_get_state(args, &s);
    if (r != NPRFX_OK) return r;
    p->sequence = s ? s->seq : NULL;
    if (args->params[P_TONE_CORRECTION].v[0] != 0.0) {
        r = st_curve(args, s, p, curve);
        p->tone_curve = curve;
    }
    return r;
}

static nprfx_result st_check(const nprfx_render_args *args)
{
    if (!args || args->size < sizeof(nprfx_render_args) || !args->inputs || !args->params)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple: incomplete render arguments");
    if (!args->inputs[IN_TONE].data)
        return nprfx_error(args->ctx, NPRFX_ERR_MISSING_INPUT,
                           "stipple: input 'tone' is not connected");
    return NPRFX_OK;
}

static nprfx_stipple_inputs st_inputs(const nprfx_render_args *args)
{
    nprfx_stipple_inputs in;
    in.tone = &args->inputs[IN_TONE];
    in.uv = args->inputs[IN_UV].data ? &args->inputs[IN_UV] : NULL;
    in.id = args->inputs[IN_ID].data ? &args->inputs[IN_ID] : NULL;
    in.frame = args->frame;
    return in;
}

static nprfx_result st_render(const nprfx_render_args *args, const void *typed)
{
    nprfx_result r = st_check(args);
    if (r != NPRFX_OK) return r;
    if (!args->output)
        return nprfx_error(args->ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: no output image");
    nprfx_stipple_params p;
    float curve[NPRFX_STIPPLE_CURVE_SIZE];
    if ((r = st_params_full(args, &p, curve)) != NPRFX_OK) return r;
    nprfx_stipple_inputs in = st_inputs(args);
    p.count = args->items;
    return nprfx_stipple_render(args->ctx, &p, &in, args->window, args->output);
}

nprfx_result nprfx_stipple_node_export(const nprfx_render_args *args,
                                       nprfx_stipple_format_kind kind, char **text, size_t *len)
{
    nprfx_result r = st_check(args);
    if (r != NPRFX_OK) return r;
    nprfx_stipple_params p;
    float curve[NPRFX_STIPPLE_CURVE_SIZE];
    if ((r = st_params_full(args, &p, curve)) != NPRFX_OK) return r;
    nprfx_stipple_inputs in = st_inputs(args);
    nprfx_stipple *list = NULL;
    size_t count = 0;
    r = nprfx_stipple_collect(args->ctx, &p, &in, args->frame, &list, &count);
    if (r == NPRFX_OK)
        r = nprfx_stipple_format(args->ctx, list, count, args->frame, kind, p.ink, p.paper, text,
                                 len);
    free(list);
    return r;
}

/* The descriptor's export hook: the format from the path's extension (case-insensitive). */
static nprfx_result st_export_text(const nprfx_render_args *args, const void *typed,
                                   const char *path, char **text, size_t *len)
{
    if (!text)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple.export: NULL output");
    *text = NULL;
    if (len) *len = 0;
    const char *p = path ? path : "";
    const char *slash = strrchr(p, '/'), *dot = strrchr(p, '.');
    if (dot && slash && dot < slash) dot = NULL; /* a dot in a directory name */
    const char *ext = dot ? dot + 1 : "";
    char low[8] = {0};
    size_t n = strlen(ext);
    for (size_t i = 0; i < n && i < sizeof low - 1; i++)
        low[i] = (char)(ext[i] >= 'A' && ext[i] <= 'Z' ? ext[i] - 'A' + 'a' : ext[i]);
    if (n == 3 && !strcmp(low, "csv"))
        return nprfx_stipple_node_export(args, NPRFX_STIPPLE_CSV, text, len);
    if (n == 3 && !strcmp(low, "svg"))
        return nprfx_stipple_node_export(args, NPRFX_STIPPLE_SVG, text, len);
    if (!dot)
        return nprfx_error(args->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple.export: '%s' has no extension: end it in .csv or .svg", p);
    return nprfx_error(args->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                       "stipple.export: unknown extension '.%s' in '%s': use .csv (a table of "
                       "dots) or .svg (vector discs)",
                       ext, p);
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
        "is evenly spread and sample i covers about 1/i of a tile. Its first 2^20 points ship "
        "as share/nprfx/ivs.bin (written by the build with `nprfx ivs`; in the OpenFX bundle, "
        "Contents/Resources/ivs.bin; $NPRFX_DATA_DIR overrides the folder); longer prefixes, "
        "or all of it without the file, are generated on first use (about 2.5 s per million "
        "points), with the same result. The sequence is tiled over UV space "
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
        "CSV or SVG for print or pen plotters.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output = st_output,
    .flags = NPRFX_NODE_STATEFUL,
    .render = st_render,
    .state_free = st_state_free,
    .export_text = st_export_text,
    .item_name = "stipples",
};
