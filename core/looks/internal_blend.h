/* Internal to core/ (never installed): Bousseau et al.'s pigment-density formula, written once and
 * inlined by both the blend node (core/looks/blend.c) and the watercolor node
 * (core/looks/watercolor.c). The public nprfx_blend_pigment* functions call these too; a public
 * function itself would stay a call in a per-pixel loop (in position-independent code it may be
 * interposed). docs/design.md §3.5. */
#ifndef NPRFX_INTERNAL_BLEND_H
#define NPRFX_INTERNAL_BLEND_H

/* Densities are clamped to [0, 2], where the formula maps [0, 1] onto itself: 2 gives C^2 (the
 * darkest), 0 gives 2C - C^2 (the lightest); beyond, mid colours would go negative or above 1. */
#define INTERNAL_PIGMENT_DENSITY_MAX 2.0

/* C' = C - (C - C^2)(d - 1): d = 1 leaves C unchanged, d > 1 darkens, d < 1 lightens; 0 and 1
 * are fixed points. The model is reflectance on paper, so it takes the part of a scene-linear
 * colour within [0, 1]: light beyond the paper's white (an HDR highlight of 100) or below black
 * passes unchanged on top of it. Without that split C - C^2 grows with C^2 and a highlight would
 * turn into a large negative (d > 1) or positive (d < 1) value. The result is continuous in C,
 * and a NaN colour or density spreads (NaN compares false, so the split keeps it in the excess). */
static inline double internal_pigment(double c, double d)
{
    const double p = c > 0.0 ? (c < 1.0 ? c : 1.0) : 0.0;
    if (d < 0.0) d = 0.0;
    if (d > INTERNAL_PIGMENT_DENSITY_MAX) d = INTERNAL_PIGMENT_DENSITY_MAX;
    return p - (p - p * p) * (d - 1.0) + (c - p);
}

/* The density from a grey texture value t: d = 1 + beta (t - 0.5). */
static inline double internal_pigment_density(double t, double beta)
{
    return 1.0 + beta * (t - 0.5);
}

#endif
