/* Internal to core/ (never installed): Bousseau et al.'s pigment-density formula, written once and
 * inlined by both the blend node (core/looks/blend.c) and the watercolor node (core/looks/watercolor.c). The
 * public nprfx_blend_pigment* functions call these too; a public function itself would stay a call
 * in a per-pixel loop (in position-independent code it may be interposed). docs/design.md §3.5. */
#ifndef NPRFX_INTERNAL_BLEND_H
#define NPRFX_INTERNAL_BLEND_H

/* C' = C - (C - C^2)(d - 1): d = 1 leaves C unchanged, d > 1 darkens, d < 1 lightens (for C in
 * [0, 1]; 0 and 1 are fixed points). */
static inline double internal_pigment(double c, double d)
{
    return c - (c - c * c) * (d - 1.0);
}

/* The density from a grey texture value t: d = 1 + beta (t - 0.5). */
static inline double internal_pigment_density(double t, double beta)
{
    return 1.0 + beta * (t - 0.5);
}

#endif
