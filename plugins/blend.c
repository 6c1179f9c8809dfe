/* The blend node: the cookbook's compositing functions (alphaBlend, overlay, overlayAlpha),
 * multiply, screen, Bousseau et al.'s pigment density, and the background colour where the
 * coverage AOV is 0. The formulas themselves live in core/blend.c; this file is the
 * descriptor and the per-pixel glue (gains, channel broadcast, opacity, coverage). */
#include <stddef.h>

#include "nprfx/blend.h"
#include "nprfx/node.h"

enum { IN_BASE, IN_LAYER, IN_BACK, IN_ALPHA, IN_COVERAGE, IN_COUNT };
enum { P_MODE, P_FACTOR, P_OPACITY, P_GAIN_BASE, P_GAIN_LAYER, P_BACKGROUND, P_COUNT };

/* Same order as nprfx_blend_mode. */
static const char *const mode_names[] = {"alphablend", "overlay", "overlayalpha", "multiply",
                                         "screen",     "pigment", "difference",   NULL};
_Static_assert(sizeof mode_names / sizeof mode_names[0] == NPRFX_BLEND_MODE_COUNT + 1,
               "blend: mode names must follow nprfx_blend_mode");

static const char *const mode_help[] = {
    "(1 - a) c0 + a c1 (cookbook alphaBlend)",
    "c0 f (1 - (1 - c0)(1 - c1)), mixed over c0 by a (cookbook overlay)",
    "back (1 - a) + a c0 f (1 - (1 - c0 a)(1 - c1)) (cookbook overlayAlpha)",
    "c0 c1, mixed over c0 by a",
    "1 - (1 - c0)(1 - c1), mixed over c0 by a",
    "C - (C - C^2)(d - 1) with C = c0, d = 1 + f (c1 - 0.5), mixed over c0 by a (Bousseau et al. "
    "2006 pigment density: d > 1 darkens, d < 1 lightens)",
    "f |c0 - c1|, mixed over c0 by a: e.g. two frames of coherent noise, which differ only "
    "where things move (Kass & Pesare's Figure 2)",
    NULL};

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "base",
     .label = "Base",
     .help = "The image blended onto (the colour, c0 = gain_base * base). Sets the output's "
             "channels; with 4 channels the 4th is alpha and passes through unchanged.",
     .channels = 0,
     .flags = NPRFX_INPUT_MAIN},
    {.name = "layer",
     .label = "Layer",
     .help = "The image blended in (c1 = gain_layer * layer): a pattern, a stroke colour, a paper "
             "or pigment texture. A 1-channel layer is used for every colour channel of base; "
             "otherwise it needs base's colour channels (an extra alpha channel of the layer is "
             "ignored).",
     .channels = 0},
    {.name = "back",
     .label = "Back",
     .help = "overlayalpha only: the colour under the stroke (the cookbook's backColor). Not "
             "connected: base itself, without gain_base. 1 channel or base's colour channels.",
     .channels = 0,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "alpha",
     .label = "Alpha",
     .help = "Per-pixel blend weight a, e.g. a threshold-map output; multiplied by opacity and "
             "clamped to [0, 1]. Not connected: a = opacity.",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
    {.name = "coverage",
     .label = "Coverage",
     .help = "Object coverage (the cookbook's isBackground, antialiased): out = coverage * blended"
             " + (1 - coverage) * background, coverage clamped to [0, 1], on every channel "
             "including alpha. Not connected: coverage 1 everywhere.",
     .aov = "coverage|Coverage|A",
     .channels = 1,
     .flags = NPRFX_INPUT_OPTIONAL},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "mode",
     .label = "Mode",
     .help = "The compositing formula. c0 = gain_base * base, c1 = gain_layer * layer, a = "
             "clamp(alpha * opacity, 0, 1), f = factor. Values are not clamped.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {0},
     NPRFX_CHOICE_RANGE(NPRFX_BLEND_MODE_COUNT),
     .choices = mode_names,
     .choice_help = mode_help},
    {.name = "factor",
     .label = "Factor",
     .help = "f: the overlay factor of overlay and overlayalpha (the cookbook uses 0.7 to 1.2: "
             "above 1 brightens, below 1 darkens), and the pigment strength beta of pigment (0: no"
             " effect; negative: a bright layer lightens instead of darkening).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = -100,
     .hard_max = 100},
    {.name = "opacity",
     .label = "Opacity",
     .help = "Blend weight, multiplied by the alpha input when connected: 0 leaves c0 "
             "(overlayalpha: back), 1 applies the mode fully.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1},
    {.name = "gain_base",
     .label = "Base Gain",
     .help = "Multiplies base before blending (the cookbook's `color * 0.85`).",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 1000},
    {.name = "gain_layer",
     .label = "Layer Gain",
     .help = "Multiplies layer before blending.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {1},
     .soft_min = 0,
     .soft_max = 2,
     .hard_min = 0,
     .hard_max = 1000},
    {.name = "background",
     .label = "Background",
     .help = "Colour (RGBA) where coverage is 0 (the paper). A 1-channel base takes its Rec. 709 "
             "luminance, a 2-channel base its R and G.",
     .type = NPRFX_PARAM_COLOR,
     .def = {1, 1, 1, 1},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 1000},
};

static const float zeros[NPRFX_MAX_CHANNELS];

/* Outside its data window an input reads as 0 (the OpenEXR convention), so a cropped AOV does
 * not need to cover the whole frame. */
static const float *pixel_or_zero(const nprfx_image *im, int x, int y)
{
    return nprfx_rect_contains(im->bounds, x, y) ? nprfx_image_at(im, x, y) : zeros;
}

static double clamp01(double x)
{
    return x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0; /* NaN -> 0 */
}

typedef struct blend_job {
    nprfx_rect window;
    nprfx_blend_mode mode;
    double factor, opacity, gain_base, gain_layer;
    double bg[4];
    int nch, ncol;             /* output channels; colour channels (alpha excluded) */
    int layer_step, back_step; /* 0: broadcast channel 0; 1: channel c */
    const nprfx_image *base, *layer, *back, *alpha, *coverage; /* NULL when not connected */
    nprfx_image *out;
} blend_job;

/* Pointer to pixel (x0, y) when the whole row span [x0, x1) lies inside im's bounds, else NULL. */
static const float *row_span(const nprfx_image *im, int x0, int x1, int y)
{
    const nprfx_rect b = im->bounds;
    return y >= b.y0 && y < b.y1 && x0 >= b.x0 && x1 <= b.x1 ? nprfx_image_at(im, x0, y) : NULL;
}

/* One pixel; b, l, k (back) and the optional alpha/coverage values already fetched. */
static inline void blend_pixel(const blend_job *j, const float *b, const float *l, const float *k,
                               double a, double cov, float *o)
{
    a = clamp01(a);
    for (int c = 0; c < j->ncol; c++) {
        double c0 = j->gain_base * b[c];
        double c1 = j->gain_layer * l[c * j->layer_step];
        double r = nprfx_blend_apply(j->mode, k[c * j->back_step], c0, c1, j->factor, a);
        /* coverage 1 returns r exactly: (1 - 1) * bg + 1 * r */
        o[c] = (float)nprfx_blend_alpha(j->bg[c], r, cov);
    }
    if (j->nch > j->ncol) o[3] = (float)nprfx_blend_alpha(j->bg[3], b[3], cov);
}

static void blend_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const blend_job *j = user;
    const int x0 = j->window.x0, x1 = j->window.x1;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++) {
        /* Fast path: every connected input covers the row, so walk pointers by their strides
         * instead of testing bounds per pixel. */
        const float *bp = row_span(j->base, x0, x1, y), *lp = row_span(j->layer, x0, x1, y);
        const float *kp = j->back ? row_span(j->back, x0, x1, y) : bp;
        const float *ap = j->alpha ? row_span(j->alpha, x0, x1, y) : NULL;
        const float *cp = j->coverage ? row_span(j->coverage, x0, x1, y) : NULL;
        float *o = nprfx_image_at(j->out, x0, y);
        if (bp && lp && kp && (!j->alpha || ap) && (!j->coverage || cp)) {
            const ptrdiff_t bs = j->base->pixel_stride, ls = j->layer->pixel_stride;
            const ptrdiff_t ks = j->back ? j->back->pixel_stride : bs;
            const ptrdiff_t as = ap ? j->alpha->pixel_stride : 0;
            const ptrdiff_t cs = cp ? j->coverage->pixel_stride : 0;
            const ptrdiff_t os = j->out->pixel_stride;
            for (int x = x0; x < x1; x++) {
                double a = ap ? j->opacity * ap[0] : j->opacity;
                double cov = cp ? clamp01(cp[0]) : 1.0;
                blend_pixel(j, bp, lp, kp, a, cov, o);
                bp += bs, lp += ls, kp += ks, o += os;
                if (ap) ap += as;
                if (cp) cp += cs;
            }
            continue;
        }
        for (int x = x0; x < x1; x++) {
            const float *b = pixel_or_zero(j->base, x, y);
            const float *l = pixel_or_zero(j->layer, x, y);
            const float *k = j->back ? pixel_or_zero(j->back, x, y) : b;
            double a = j->opacity;
            if (j->alpha) a *= pixel_or_zero(j->alpha, x, y)[0];
            double cov = j->coverage ? clamp01(pixel_or_zero(j->coverage, x, y)[0]) : 1.0;
            blend_pixel(j, b, l, k, a, cov, nprfx_image_at(j->out, x, y));
        }
    }
}

static int channels_fit(int have, int nch, int ncol)
{
    return have == 1 || have == ncol || have == nch || (ncol == 3 && have == 4);
}

static nprfx_result blend_render(const nprfx_render_args *args, const void *typed)
{
    if (!args || args->size < sizeof(nprfx_render_args) || !args->inputs || !args->params ||
        !args->output)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: incomplete render arguments");
    nprfx_context *ctx = args->ctx;
    const nprfx_image *in = args->inputs;
    const nprfx_value *pv = args->params;
    blend_job j = {0};
    j.window = args->window;
    j.out = args->output;
    if (!in[IN_BASE].data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "blend: input 'base' is not connected");
    if (!in[IN_LAYER].data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "blend: input 'layer' is not connected");
    int mode = (int)pv[P_MODE].v[0];
    if (mode < 0 || mode >= NPRFX_BLEND_MODE_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "blend.mode: no mode with index %d", mode);
    j.mode = (nprfx_blend_mode)mode;
    j.base = &in[IN_BASE];
    j.layer = &in[IN_LAYER];
    j.back = j.mode == NPRFX_BLEND_OVERLAYALPHA && in[IN_BACK].data ? &in[IN_BACK] : NULL;
    j.alpha = in[IN_ALPHA].data ? &in[IN_ALPHA] : NULL;
    j.coverage = in[IN_COVERAGE].data ? &in[IN_COVERAGE] : NULL;
    j.nch = j.base->channels;
    j.ncol = j.nch == 4 ? 3 : j.nch;
    if (j.nch < 1 || j.nch > 4)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: input 'base' has %d channels; 1 to 4 are supported", j.nch);
    if (j.out->channels != j.nch)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: output has %d channels, base has %d", j.out->channels, j.nch);
    if (!channels_fit(j.layer->channels, j.nch, j.ncol))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: input 'layer' has %d channels and base %d; the layer needs 1 "
                           "channel or base's %d colour channels",
                           j.layer->channels, j.nch, j.ncol);
    if (j.back && !channels_fit(j.back->channels, j.nch, j.ncol))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: input 'back' has %d channels and base %d; it needs 1 channel "
                           "or base's %d colour channels",
                           j.back->channels, j.nch, j.ncol);
    j.layer_step = j.layer->channels == 1 ? 0 : 1;
    j.back_step = j.back && j.back->channels == 1 ? 0 : 1;
    j.factor = pv[P_FACTOR].v[0];
    j.opacity = pv[P_OPACITY].v[0];
    j.gain_base = pv[P_GAIN_BASE].v[0];
    j.gain_layer = pv[P_GAIN_LAYER].v[0];
    const double *bg = pv[P_BACKGROUND].v;
    if (j.nch == 1) {
        j.bg[0] = 0.2126 * bg[0] + 0.7152 * bg[1] + 0.0722 * bg[2];
    } else {
        for (int c = 0; c < 4; c++)
            j.bg[c] = bg[c];
    }
    int rows = nprfx_rect_height(j.window);
    if (rows == 0 || nprfx_rect_width(j.window) == 0) return NPRFX_OK;
    nprfx_parallel_for(nprfx_context_executor(ctx), rows, 16, blend_rows, &j);
    return NPRFX_OK;
}

const nprfx_node_desc nprfx_node_blend = {
    .size = sizeof(nprfx_node_desc),
    .id = "blend",
    .label = "Blend",
    .group = "NPR",
    .help =
        "Composites a layer onto a base with the compositing functions of the NPR Gabor noise"
        " style cookbook (Benard et al. 2010, supplemental section 4): alphablend, overlay "
        "and overlayalpha exactly as written there, plus multiply, screen and the watercolor "
        "pigment-density modification of Bousseau et al. 2006, then the background colour "
        "where the coverage AOV is 0.\n"
        "\n"
        "Per colour channel, with c0 = gain_base * base, c1 = gain_layer * layer, a = "
        "clamp(alpha * opacity, 0, 1) (opacity alone when alpha is not connected) and f = "
        "factor:\n"
        "  alphablend    (1 - a) c0 + a c1\n"
        "  overlay       (1 - a) c0 + a * c0 f (1 - (1 - c0)(1 - c1))\n"
        "  overlayalpha  back (1 - a) + a c0 f (1 - (1 - c0 a)(1 - c1))\n"
        "  multiply      (1 - a) c0 + a * c0 c1\n"
        "  screen        (1 - a) c0 + a * (1 - (1 - c0)(1 - c1))\n"
        "  pigment       (1 - a) C + a * (C - (C - C^2)(d - 1)), C = c0, d = 1 + f (c1 - 0.5)\n"
        "  difference    (1 - a) c0 + a * f |c0 - c1|\n"
        "overlay, multiply, screen, pigment and difference apply a as a layer opacity over c0, as "
        "compositors do; with a = 1 they are the bare formulas. alphablend and overlayalpha "
        "take a inside the formula, as the cookbook writes them.\n"
        "\n"
        "pigment: d is Bousseau et al.'s pigment density, computed from the layer as in their"
        " paper (d = 1 + beta (T - 0.5), beta = factor, T = c1): a layer value of 0.5 leaves "
        "the colour alone, brighter layer values mean denser pigment (darker, for factor > "
        "0), darker values thinner pigment. Colour values 0 and 1 are fixed points.\n"
        "\n"
        "Channels: the output has base's channels. A 4-channel base is RGBA: its alpha passes"
        " through unblended. A 1-channel layer (a noise pattern) is used for every colour "
        "channel; a layer with base's colour channels is used channel by channel (an RGBA "
        "layer's alpha is ignored: connect it to the alpha input to use it).\n"
        "\n"
        "Background: out = coverage * result + (1 - coverage) * background on every channel "
        "(alpha too), an antialiased form of the cookbook's `if (isBackground) final_color = "
        "background`.\n"
        "\n"
        "Inputs read as 0 outside their data window. No value is clamped except a and "
        "coverage.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .output_channels = 0, /* as many as base */
    .render = blend_render,
};
