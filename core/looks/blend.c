/* Compositing formulas and the blend node over an image (style cookbook §4: alphaBlend, overlay,
 * overlayAlpha; Bousseau et al. 2006 for pigment density; docs/design.md §3.5). See
 * nprfx/blend.h.
 *
 * Each mode's formula is written once, below, as a static function that the per-pixel loop
 * inlines; the public nprfx_blend_* functions call the same ones (a public function itself would
 * stay a call in the loop: in position-independent code it may be interposed). */
#include <math.h>
#include <stddef.h>

#include "nprfx/blend.h"
#include "nprfx/exec.h"
#include "internal_blend.h"

/* ---- the formulas ---------------------------------------------------------------------------- */

static inline double alpha_blend(double c0, double c1, double a)
{
    return (1.0 - a) * c0 + a * c1;
}

static inline double multiply(double c0, double c1)
{
    return c0 * c1;
}
/* Screen only lightens: where either value is above 1 (scene-linear light beyond white) the
 * formula would darken it, or go negative when both are, so there it is the larger value (a
 * continuous join: at 1 both give 1). */
static inline double screen(double c0, double c1)
{
    if (c0 > 1.0 || c1 > 1.0) return c0 > c1 ? c0 : c1;
    return 1.0 - (1.0 - c0) * (1.0 - c1);
}
/* The overlays scale c0 by a modulation, f times the screen of c0 and the layer. A base above 1
 * modulates as white does (the formula's c0 inside the screen would square a highlight of 40
 * into 1600, and overlays stacked in a look compound that): c0 enters the screen at most 1, so a
 * highlight is scaled by f like white is; below 1 the formulas are the cookbook's. */
static inline double white_at_most(double c)
{
    return c > 1.0 ? 1.0 : c;
}
static inline double overlay(double c0, double c1, double f)
{
    return c0 * f * screen(white_at_most(c0), c1);
}
static inline double overlay_alpha(double back, double c0, double c1, double f, double a)
{
    return back * (1.0 - a) + a * c0 * f * screen(white_at_most(c0) * a, c1);
}
static inline double difference(double c0, double c1, double f)
{
    return f * fabs(c0 - c1);
}
/* pigment and its density are in internal_blend.h: the watercolor node applies the same formula. */

/* The opacity rule of nprfx_blend_apply (see nprfx/blend.h). */
static inline double apply_mode(nprfx_blend_mode mode, double back, double c0, double c1, double f,
                                double a)
{
    switch (mode) {
    case NPRFX_BLEND_ALPHABLEND:
        return alpha_blend(c0, c1, a);
    case NPRFX_BLEND_OVERLAYALPHA:
        return overlay_alpha(back, c0, c1, f, a);
    case NPRFX_BLEND_OVERLAY:
        return alpha_blend(c0, overlay(c0, c1, f), a);
    case NPRFX_BLEND_MULTIPLY:
        return alpha_blend(c0, multiply(c0, c1), a);
    case NPRFX_BLEND_SCREEN:
        return alpha_blend(c0, screen(c0, c1), a);
    case NPRFX_BLEND_PIGMENT:
        return alpha_blend(c0, internal_pigment(c0, internal_pigment_density(c1, f)), a);
    case NPRFX_BLEND_DIFFERENCE:
        return alpha_blend(c0, difference(c0, c1, f), a);
    default:
        return c0;
    }
}

double nprfx_blend_alpha(double c0, double c1, double a)
{
    return alpha_blend(c0, c1, a);
}
double nprfx_blend_overlay(double c0, double c1, double f)
{
    return overlay(c0, c1, f);
}
double nprfx_blend_overlay_alpha(double back, double c0, double c1, double f, double a)
{
    return overlay_alpha(back, c0, c1, f, a);
}
double nprfx_blend_multiply(double c0, double c1)
{
    return multiply(c0, c1);
}
double nprfx_blend_screen(double c0, double c1)
{
    return screen(c0, c1);
}
double nprfx_blend_pigment(double c, double d)
{
    return internal_pigment(c, d);
}
double nprfx_blend_difference(double c0, double c1, double f)
{
    return difference(c0, c1, f);
}
double nprfx_blend_pigment_density(double t, double beta)
{
    return internal_pigment_density(t, beta);
}
double nprfx_blend_apply(nprfx_blend_mode mode, double back, double c0, double c1, double f,
                         double a)
{
    return apply_mode(mode, back, c0, c1, f, a);
}

/* ---- the blend node over an image ------------------------------------------------------------ */

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
        double r = apply_mode(j->mode, k[c * j->back_step], c0, c1, j->factor, a);
        /* coverage 1 returns r exactly: (1 - 1) * bg + 1 * r */
        o[c] = (float)alpha_blend(j->bg[c], r, cov);
    }
    if (j->nch > j->ncol) o[3] = (float)alpha_blend(j->bg[3], b[3], cov);
}

#if defined(__GNUC__)
#define BLEND_INLINE static inline __attribute__((always_inline))
#else
#define BLEND_INLINE static inline
#endif

/* The fast path's pixels when neither alpha nor coverage is connected (the usual case): one copy
 * per mode, so that the mode's switch, the opacity clamp and the coverage test leave the loop.
 * The same operations in the same order as blend_pixel with a = opacity and cov = 1. */
BLEND_INLINE void plain_span(const blend_job *j, nprfx_blend_mode mode, const float *bp,
                             const float *lp, const float *kp, float *o, int n)
{
    const ptrdiff_t bs = j->base->pixel_stride, ls = j->layer->pixel_stride;
    const ptrdiff_t ks = j->back ? j->back->pixel_stride : bs, os = j->out->pixel_stride;
    const double a = clamp01(j->opacity), f = j->factor, gb = j->gain_base, gl = j->gain_layer;
    const int ncol = j->ncol, lstep = j->layer_step, kstep = j->back_step;
    for (int x = 0; x < n; x++, bp += bs, lp += ls, kp += ks, o += os) {
        for (int c = 0; c < ncol; c++) {
            const double r = apply_mode(mode, kp[c * kstep], gb * bp[c], gl * lp[c * lstep], f, a);
            o[c] = (float)alpha_blend(j->bg[c], r, 1.0);
        }
        if (j->nch > ncol) o[3] = (float)alpha_blend(j->bg[3], bp[3], 1.0);
    }
}

static void plain_row(const blend_job *j, const float *bp, const float *lp, const float *kp,
                      float *o, int n)
{
    switch (j->mode) {
    case NPRFX_BLEND_ALPHABLEND:
        plain_span(j, NPRFX_BLEND_ALPHABLEND, bp, lp, kp, o, n);
        break;
    case NPRFX_BLEND_OVERLAYALPHA:
        plain_span(j, NPRFX_BLEND_OVERLAYALPHA, bp, lp, kp, o, n);
        break;
    case NPRFX_BLEND_OVERLAY:
        plain_span(j, NPRFX_BLEND_OVERLAY, bp, lp, kp, o, n);
        break;
    case NPRFX_BLEND_MULTIPLY:
        plain_span(j, NPRFX_BLEND_MULTIPLY, bp, lp, kp, o, n);
        break;
    case NPRFX_BLEND_SCREEN:
        plain_span(j, NPRFX_BLEND_SCREEN, bp, lp, kp, o, n);
        break;
    case NPRFX_BLEND_DIFFERENCE:
        plain_span(j, NPRFX_BLEND_DIFFERENCE, bp, lp, kp, o, n);
        break;
    default: /* pigment (a log per sample: the loop overhead is small beside it) */
        plain_span(j, j->mode, bp, lp, kp, o, n);
    }
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
        if (bp && lp && kp && !j->alpha && !j->coverage) {
            plain_row(j, bp, lp, kp, o, x1 - x0);
            continue;
        }
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

/* A layer or back image of `have` channels has a reading for a base of nch (ncol colour)
 * channels: one channel broadcast, or base's colour channels with or without alpha. */
static int channels_fit(int have, int nch, int ncol)
{
    return have == 1 || have == ncol || have == nch || (ncol == 3 && have == 4);
}

nprfx_result nprfx_blend_render(const nprfx_render_args *args, const nprfx_blend_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const nprfx_image *base = nprfx_render_input(args, NPRFX_BLEND_IN_BASE);
    const nprfx_image *layer = nprfx_render_input(args, NPRFX_BLEND_IN_LAYER);
    const nprfx_image *back = nprfx_render_input(args, NPRFX_BLEND_IN_BACK);
    const nprfx_image *alpha = nprfx_render_input(args, NPRFX_BLEND_IN_ALPHA);
    const nprfx_image *coverage = nprfx_render_input(args, NPRFX_BLEND_IN_COVERAGE);
    nprfx_rect window = args->window;
    nprfx_image *out = args->output;
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "blend: no params or output");
    if (!base || !base->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "blend: input 'base' is not connected");
    if (!layer || !layer->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "blend: input 'layer' is not connected");
    if (p->mode < 0 || p->mode >= NPRFX_BLEND_MODE_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "blend.mode: no mode with index %d",
                           p->mode);
    blend_job j = {0};
    j.window = window;
    j.out = out;
    j.mode = (nprfx_blend_mode)p->mode;
    j.base = base;
    j.layer = layer;
    /* back is overlayalpha's only */
    j.back = j.mode == NPRFX_BLEND_OVERLAYALPHA && back && back->data ? back : NULL;
    j.alpha = alpha && alpha->data ? alpha : NULL;
    j.coverage = coverage && coverage->data ? coverage : NULL;
    j.nch = base->channels;
    j.ncol = j.nch == 4 ? 3 : j.nch;
    if (j.nch < 1 || j.nch > 4)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: input 'base' has %d channels; 1 to 4 are supported", j.nch);
    if (out->channels != j.nch)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: output has %d channels, base has %d", out->channels, j.nch);
    if (!channels_fit(layer->channels, j.nch, j.ncol))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: input 'layer' has %d channels and base %d; the layer needs 1 "
                           "channel or base's %d colour channels",
                           layer->channels, j.nch, j.ncol);
    if (j.back && !channels_fit(j.back->channels, j.nch, j.ncol))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "blend: input 'back' has %d channels and base %d; it needs 1 channel "
                           "or base's %d colour channels",
                           j.back->channels, j.nch, j.ncol);
    j.layer_step = layer->channels == 1 ? 0 : 1;
    j.back_step = j.back && j.back->channels == 1 ? 0 : 1;
    j.factor = p->factor;
    j.opacity = p->opacity;
    j.gain_base = p->gain_base;
    j.gain_layer = p->gain_layer;
    const double *bg = p->background;
    if (j.nch == 1) {
        j.bg[0] = 0.2126 * bg[0] + 0.7152 * bg[1] + 0.0722 * bg[2];
    } else {
        for (int c = 0; c < 4; c++)
            j.bg[c] = bg[c];
    }
    int rows = nprfx_rect_height(window);
    if (rows == 0 || nprfx_rect_width(window) == 0) return NPRFX_OK;
    nprfx_parallel_for(nprfx_context_executor(ctx), rows, 16, blend_rows, &j);
    return NPRFX_OK;
}
