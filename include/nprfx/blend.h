/* nprfx — compositing formulas (style cookbook §4; Bousseau et al. 2006 for pigment density).
 *
 * Each blend mode is one formula written once, here (as openfx-supportext's ofxsMerging.h does
 * for merge operators), inline so the per-pixel loops of the blend node and any other node
 * that calls them compile to straight arithmetic. All
 * functions work on one channel value and do not clamp: values are scene-linear floats.
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
 * nprfx_blend_pigment_density computes exactly that. */
#ifndef NPRFX_BLEND_H
#define NPRFX_BLEND_H

#include <math.h>

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

static inline double nprfx_blend_alpha(double c0, double c1, double a)
{
    return (1.0 - a) * c0 + a * c1;
}
static inline double nprfx_blend_overlay(double c0, double c1, double f)
{
    return c0 * f * (1.0 - (1.0 - c0) * (1.0 - c1));
}
static inline double nprfx_blend_overlay_alpha(double back, double c0, double c1, double f,
                                               double a)
{
    return back * (1.0 - a) + a * c0 * f * (1.0 - (1.0 - c0 * a) * (1.0 - c1));
}
static inline double nprfx_blend_multiply(double c0, double c1)
{
    return c0 * c1;
}
static inline double nprfx_blend_screen(double c0, double c1)
{
    return 1.0 - (1.0 - c0) * (1.0 - c1);
}
static inline double nprfx_blend_pigment(double c, double d)
{
    return c - (c - c * c) * (d - 1.0);
}
/* Scaled absolute difference (a compositor's "difference" merge): what changed between two
 * frames (Kass & Pesare's Figure 2). */
static inline double nprfx_blend_difference(double c0, double c1, double f)
{
    return f * fabs(c0 - c1);
}
/* Bousseau et al.'s density from a texture value: d = 1 + beta (t - 0.5). */
static inline double nprfx_blend_pigment_density(double t, double beta)
{
    return 1.0 + beta * (t - 0.5);
}

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
static inline double nprfx_blend_apply(nprfx_blend_mode mode, double back, double c0, double c1,
                                       double f, double a)
{
    switch (mode) {
    case NPRFX_BLEND_ALPHABLEND: return nprfx_blend_alpha(c0, c1, a);
    case NPRFX_BLEND_OVERLAYALPHA: return nprfx_blend_overlay_alpha(back, c0, c1, f, a);
    case NPRFX_BLEND_OVERLAY: return nprfx_blend_alpha(c0, nprfx_blend_overlay(c0, c1, f), a);
    case NPRFX_BLEND_MULTIPLY: return nprfx_blend_alpha(c0, nprfx_blend_multiply(c0, c1), a);
    case NPRFX_BLEND_SCREEN: return nprfx_blend_alpha(c0, nprfx_blend_screen(c0, c1), a);
    case NPRFX_BLEND_PIGMENT:
        return nprfx_blend_alpha(c0, nprfx_blend_pigment(c0, nprfx_blend_pigment_density(c1, f)),
                                 a);
    case NPRFX_BLEND_DIFFERENCE:
        return nprfx_blend_alpha(c0, nprfx_blend_difference(c0, c1, f), a);
    default: return c0;
    }
}

#ifdef __cplusplus
}
#endif
#endif
