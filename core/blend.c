/* Compositing formulas: one function per formula, see nprfx/blend.h. */
#include <math.h>

#include "nprfx/blend.h"

double nprfx_blend_alpha(double c0, double c1, double a)
{
    return (1.0 - a) * c0 + a * c1;
}

double nprfx_blend_overlay(double c0, double c1, double f)
{
    return c0 * f * (1.0 - (1.0 - c0) * (1.0 - c1));
}

double nprfx_blend_overlay_alpha(double back, double c0, double c1, double f, double a)
{
    return back * (1.0 - a) + a * c0 * f * (1.0 - (1.0 - c0 * a) * (1.0 - c1));
}

double nprfx_blend_multiply(double c0, double c1)
{
    return c0 * c1;
}

double nprfx_blend_screen(double c0, double c1)
{
    return 1.0 - (1.0 - c0) * (1.0 - c1);
}

double nprfx_blend_pigment(double c, double d)
{
    return c - (c - c * c) * (d - 1.0);
}

double nprfx_blend_difference(double c0, double c1, double f)
{
    return f * fabs(c0 - c1);
}

double nprfx_blend_pigment_density(double t, double beta)
{
    return 1.0 + beta * (t - 0.5);
}

double nprfx_blend_apply(nprfx_blend_mode mode, double back, double c0, double c1, double f,
                         double a)
{
    switch (mode) {
    case NPRFX_BLEND_ALPHABLEND:
        return nprfx_blend_alpha(c0, c1, a);
    case NPRFX_BLEND_OVERLAYALPHA:
        return nprfx_blend_overlay_alpha(back, c0, c1, f, a);
    case NPRFX_BLEND_OVERLAY:
        return nprfx_blend_alpha(c0, nprfx_blend_overlay(c0, c1, f), a);
    case NPRFX_BLEND_MULTIPLY:
        return nprfx_blend_alpha(c0, nprfx_blend_multiply(c0, c1), a);
    case NPRFX_BLEND_SCREEN:
        return nprfx_blend_alpha(c0, nprfx_blend_screen(c0, c1), a);
    case NPRFX_BLEND_PIGMENT:
        return nprfx_blend_alpha(c0, nprfx_blend_pigment(c0, nprfx_blend_pigment_density(c1, f)),
                                 a);
    case NPRFX_BLEND_DIFFERENCE:
        return nprfx_blend_alpha(c0, nprfx_blend_difference(c0, c1, f), a);
    default:
        return c0;
    }
}
