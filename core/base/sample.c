/* Point sampling of image views: nearest, bilinear, bicubic (Catmull-Rom).
 *
 * Pixel (i, j) is the sample at continuous position (i, j). Taps whose weight is exactly zero
 * are not read, so sampling at an integer position returns the pixel itself even when a
 * neighbour is +inf (a depth background) or NaN. */
#include <math.h>

#include "nprfx/filter.h"

/* Coordinates are first limited to this many pixels outside the bounds: every tap beyond it
 * reads the same clamped edge (CLAMP) or zero (BLACK), and the limit keeps far-off or huge
 * coordinates inside int range. */
#define SAMPLE_MARGIN 4.0

static void zero_out(const nprfx_image *im, float *out)
{
    for (int c = 0; c < im->channels; c++)
        out[c] = 0.0f;
}

/* A view with pixels to read. */
static int readable(const nprfx_image *im)
{
    return im->data && !nprfx_rect_empty(im->bounds) && im->channels >= 1 &&
           im->channels <= NPRFX_MAX_CHANNELS;
}

/* The pixel a tap reads under the border rule, or NULL for a BLACK zero. */
static const float *tap(const nprfx_image *im, int x, int y, nprfx_border border)
{
    const nprfx_rect b = im->bounds;
    if (!nprfx_rect_contains(b, x, y)) {
        if (border == NPRFX_BORDER_BLACK) return NULL;
        x = x < b.x0 ? b.x0 : x >= b.x1 ? b.x1 - 1 : x;
        y = y < b.y0 ? b.y0 : y >= b.y1 ? b.y1 - 1 : y;
    }
    return nprfx_image_at(im, x, y);
}

/* Limits (x, y) to the margin around the bounds; 0 when a coordinate is not a number. */
static int limit(const nprfx_image *im, double *x, double *y)
{
    if (isnan(*x) || isnan(*y)) return 0;
    const double x0 = im->bounds.x0 - SAMPLE_MARGIN, x1 = im->bounds.x1 - 1 + SAMPLE_MARGIN;
    const double y0 = im->bounds.y0 - SAMPLE_MARGIN, y1 = im->bounds.y1 - 1 + SAMPLE_MARGIN;
    *x = *x < x0 ? x0 : *x > x1 ? x1 : *x;
    *y = *y < y0 ? y0 : *y > y1 ? y1 : *y;
    return 1;
}

void nprfx_sample_nearest(const nprfx_image *im, double x, double y, nprfx_border border,
                          float *out)
{
    if (!readable(im) || !limit(im, &x, &y)) {
        zero_out(im, out);
        return;
    }
    /* Halves round up: x = 0.5 reads pixel 1. */
    const float *p = tap(im, (int)floor(x + 0.5), (int)floor(y + 0.5), border);
    for (int c = 0; c < im->channels; c++)
        out[c] = p ? p[c] : 0.0f;
}

/* Accumulate a separable n x n footprint starting at integer (ix, iy) with weights wx, wy. */
static void accumulate(const nprfx_image *im, int ix, int iy, const double *wx, const double *wy,
                       int n, nprfx_border border, float *out)
{
    const int C = im->channels;
    double acc[NPRFX_MAX_CHANNELS] = {0};
    const nprfx_rect b = im->bounds;
    const int inside = ix >= b.x0 && iy >= b.y0 && ix + n <= b.x1 && iy + n <= b.y1;
    for (int j = 0; j < n; j++) {
        if (wy[j] == 0.0) continue;
        for (int i = 0; i < n; i++) {
            const double w = wx[i] * wy[j];
            if (w == 0.0) continue;
            const float *p =
                inside ? nprfx_image_at(im, ix + i, iy + j) : tap(im, ix + i, iy + j, border);
            if (!p) continue;
            for (int c = 0; c < C; c++)
                acc[c] += w * p[c];
        }
    }
    for (int c = 0; c < C; c++)
        out[c] = (float)acc[c];
}

void nprfx_sample_bilinear(const nprfx_image *im, double x, double y, nprfx_border border,
                           float *out)
{
    if (!readable(im) || !limit(im, &x, &y)) {
        zero_out(im, out);
        return;
    }
    const double fx = floor(x), fy = floor(y);
    const double tx = x - fx, ty = y - fy;
    const double wx[2] = {1.0 - tx, tx}, wy[2] = {1.0 - ty, ty};
    accumulate(im, (int)fx, (int)fy, wx, wy, 2, border, out);
}

/* Catmull-Rom (Keys, a = -0.5) weights of the taps at -1, 0, 1, 2 for fraction t in [0, 1). */
static void catmull_rom(double t, double *w)
{
    const double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
    w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
    w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
    w[3] = 0.5 * (t3 - t2);
}

void nprfx_sample_bicubic(const nprfx_image *im, double x, double y, nprfx_border border,
                          float *out)
{
    if (!readable(im) || !limit(im, &x, &y)) {
        zero_out(im, out);
        return;
    }
    const double fx = floor(x), fy = floor(y);
    double wx[4], wy[4];
    catmull_rom(x - fx, wx);
    catmull_rom(y - fy, wy);
    accumulate(im, (int)fx - 1, (int)fy - 1, wx, wy, 4, border, out);
}
