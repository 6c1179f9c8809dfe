/* nprfx — compositing formulas and the blend node over an image (style cookbook §4; Bousseau et
 * al. 2006 for pigment density; design: docs/design.md §3.5).
 *
 * Each blend mode is one formula, written once in core/looks/blend.c (as openfx-supportext's
 * ofxsMerging.h does for merge operators); nprfx_blend_render runs them over an image. All
 * formulas work on one channel value and do not clamp: values are scene-linear floats.
 *
 *   alphaBlend(c0, c1, a)              = (1 - a) c0 + a c1
 *   overlay(c0, c1, f)                 = c0 f (1 - (1 - c0)(1 - c1))
 *   overlayAlpha(b, c0, c1, f, a)      = b (1 - a) + a c0 f (1 - (1 - c0 a)(1 - c1))
 *   multiply(c0, c1)                   = c0 c1
 *   screen(c0, c1)                     = 1 - (1 - c0)(1 - c1)
 *   pigment(C, d)                      = C - (C - C^2)(d - 1)
 *   difference(c0, c1, f)              = f |c0 - c1|
 *
 * pigment is the colour modification of Bousseau, Kaplan, Thollot, Sillion, "Interactive
 * watercolor rendering with temporal coherence and abstraction" (NPAR 2006): d is a pigment
 * density, d = 1 leaves C unchanged, d > 1 darkens and d < 1 lightens (for C in [0,1]; C = 0 and
 * C = 1 are fixed points). The paper derives d from a grey texture T as d = 1 + beta (T - 0.5);
 * nprfx_blend_pigment_density computes exactly that.
 *
 * Scene-linear colour above 1 (HDR highlights): screen, the overlays and pigment are display
 * formulas, exact as written for values in [0, 1]. Beyond, screen is max(c0, c1) where either
 * value is above 1 (it only lightens); the overlays' c0 inside the screen is at most 1 (a
 * highlight is modulated as white is, scaled by f); pigment clamps d to [0, 2] and acts on the
 * part of C within [0, 1], the rest passing unchanged. Each join is continuous. */
#ifndef NPRFX_BLEND_H
#define NPRFX_BLEND_H

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The blend node's modes, in the order of its `mode` choice (whose names live in
 * plugins/blend.c). */
typedef enum nprfx_blend_mode {
    NPRFX_BLEND_ALPHABLEND = 0,
    NPRFX_BLEND_OVERLAY = 1,
    NPRFX_BLEND_OVERLAYALPHA = 2,
    NPRFX_BLEND_MULTIPLY = 3,
    NPRFX_BLEND_SCREEN = 4,
    NPRFX_BLEND_PIGMENT = 5,
    NPRFX_BLEND_DIFFERENCE = 6,
    NPRFX_BLEND_MODE_COUNT = 7
} nprfx_blend_mode;

/* ---- the formulas, one channel value at a time ---- */

NPRFX_API double nprfx_blend_alpha(double c0, double c1, double a);
NPRFX_API double nprfx_blend_overlay(double c0, double c1, double f);
NPRFX_API double nprfx_blend_overlay_alpha(double back, double c0, double c1, double f, double a);
NPRFX_API double nprfx_blend_multiply(double c0, double c1);
NPRFX_API double nprfx_blend_screen(double c0, double c1);
NPRFX_API double nprfx_blend_pigment(double c, double d);
/* Scaled absolute difference (a compositor's "difference" merge): what changed between two
 * frames (Kass & Pesare's Figure 2). */
NPRFX_API double nprfx_blend_difference(double c0, double c1, double f);
/* Bousseau et al.'s density from a texture value: d = 1 + beta (t - 0.5). */
NPRFX_API double nprfx_blend_pigment_density(double t, double beta);

/* One channel in one mode with the opacity rule the blend node documents:
 *   alphablend    nprfx_blend_alpha(c0, c1, a)
 *   overlayalpha  nprfx_blend_overlay_alpha(back, c0, c1, f, a)
 *   overlay       nprfx_blend_alpha(c0, overlay(c0, c1, f), a)
 *   multiply      nprfx_blend_alpha(c0, multiply(c0, c1), a)
 *   screen        nprfx_blend_alpha(c0, screen(c0, c1), a)
 *   pigment       nprfx_blend_alpha(c0, pigment(c0, pigment_density(c1, f)), a)
 *   difference    nprfx_blend_alpha(c0, difference(c0, c1, f), a)
 * i.e. the last four are mixed over c0 by a, as compositors apply a layer's opacity; `back` is
 * used by overlayalpha only. An out-of-range mode returns c0. */
NPRFX_API double nprfx_blend_apply(nprfx_blend_mode mode, double back, double c0, double c1,
                                   double f, double a);

/* ---- the blend node over an image ---- */

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_blend_params {
    int mode;       /* nprfx_blend_mode */
    double factor;  /* f: overlay factor, pigment strength beta, difference scale */
    double opacity; /* a = clamp(alpha * opacity, 0, 1); opacity alone without alpha */
    double gain_base, gain_layer; /* c0 = gain_base * base, c1 = gain_layer * layer */
    double background[4];         /* RGBA where coverage is 0 */
} nprfx_blend_params;

/* The node's inputs, in the descriptor's order (args->inputs). */
enum {
    NPRFX_BLEND_IN_BASE = 0,
    NPRFX_BLEND_IN_LAYER = 1,
    NPRFX_BLEND_IN_BACK = 2,     /* optional */
    NPRFX_BLEND_IN_ALPHA = 3,    /* optional */
    NPRFX_BLEND_IN_COVERAGE = 4, /* optional */
    NPRFX_BLEND_IN_COUNT
};

/* Blend args->window of out = args->output (which has base's channels, 1 to 4; with 4 the 4th is
 * alpha and passes through), the inputs NPRFX_BLEND_IN_*. Per colour channel: r =
 * nprfx_blend_apply(mode, back, c0, c1, factor, a), then out = nprfx_blend_alpha(background, r,
 * coverage) on every channel (alpha too), coverage clamped to [0, 1]. A 1-channel base takes the
 * background's Rec. 709 luminance, a 2-channel one its R and G.
 *
 * layer: 1 channel (used for every colour channel) or base's colour channels (an extra alpha
 * channel is ignored). back (overlayalpha only; NULL: base without gain), alpha (NULL: a =
 * opacity) and coverage (NULL: 1) may be NULL; back needs 1 channel or base's colour channels,
 * alpha and coverage are read from channel 0. Inputs read as 0 outside their data windows. Runs
 * on ctx's executor; bit-identical for any thread count and window split. */
NPRFX_API nprfx_result nprfx_blend_render(const nprfx_render_args *args,
                                          const nprfx_blend_params *p);

#ifdef __cplusplus
}
#endif
#endif
