/* PAM builder: packed work images, orientation, alignment by rotation, the Gaussian pyramid and
 * the CSS features (docs/design.md §3.7). All serial and cheap next to the searches; every loop
 * runs in a fixed order, so results do not depend on the executor. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_pam.h"

#define PI 3.14159265358979323846

nprfx_result internal_pam_img_alloc(nprfx_context *ctx, int w, int h, int c, internal_pam_img *out)
{
    memset(out, 0, sizeof *out);
    if (w < 1 || h < 1 || c < 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "pam: empty work image %dx%d", w, h);
    out->px = calloc((size_t)w * (size_t)h * (size_t)c, sizeof(float));
    if (!out->px)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam: out of memory (%dx%d image)", w, h);
    out->w = w;
    out->h = h;
    out->c = c;
    return NPRFX_OK;
}

void internal_pam_img_free(internal_pam_img *im)
{
    free(im->px);
    memset(im, 0, sizeof *im);
}

nprfx_result internal_pam_from_view(nprfx_context *ctx, const nprfx_image *v, internal_pam_img *out)
{
    int w = nprfx_rect_width(v->bounds), h = nprfx_rect_height(v->bounds);
    nprfx_result r = internal_pam_img_alloc(ctx, w, h, 3, out);
    if (r) return r;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = nprfx_image_at(v, v->bounds.x0 + x, v->bounds.y0 + y);
            float *q = internal_pam_px(out, x, y);
            for (int c = 0; c < 3; c++)
                q[c] = isfinite(p[c]) ? p[c] : 0.0f; /* a NaN would poison every SSD */
        }
    return NPRFX_OK;
}

static double luma(const float *p)
{
    return nprfx_luma(p[0], p[1], p[2]);
}

void internal_pam_orientation(const internal_pam_img *im, double *degrees, double *coherence)
{
    /* The structure tensor summed over the image (Bigun & Granlund) of the luma smoothed by the
     * 3x3 binomial filter, so bristle-scale texture weighs less than the strokes' edges: the
     * gradient's dominant axis is 0.5 atan2(2 Jxy, Jxx - Jyy); strokes run across it. Sums in
     * double, in a fixed order. */
    int w = im->w, h = im->h;
    double jxx = 0, jyy = 0, jxy = 0;
#define LS(x, y)                                                                                   \
    (4 * luma(internal_pam_px(im, x, y)) +                                                         \
     2 * (luma(internal_pam_px(im, (x)-1, y)) + luma(internal_pam_px(im, (x) + 1, y)) +            \
          luma(internal_pam_px(im, x, (y)-1)) + luma(internal_pam_px(im, x, (y) + 1))) +           \
     luma(internal_pam_px(im, (x)-1, (y)-1)) + luma(internal_pam_px(im, (x) + 1, (y)-1)) +         \
     luma(internal_pam_px(im, (x)-1, (y) + 1)) + luma(internal_pam_px(im, (x) + 1, (y) + 1)))
    for (int y = 2; y + 2 < h; y++)
        for (int x = 2; x + 2 < w; x++) {
            double gx = (LS(x + 1, y) - LS(x - 1, y)) / 32.0;
            double gy = (LS(x, y + 1) - LS(x, y - 1)) / 32.0;
            jxx += gx * gx;
            jyy += gy * gy;
            jxy += gx * gy;
        }
#undef LS
    double tr = jxx + jyy, an = sqrt((jxx - jyy) * (jxx - jyy) + 4 * jxy * jxy);
    double grad = 0.5 * atan2(2 * jxy, jxx - jyy) * 180.0 / PI;
    *degrees = fmod(grad + 90.0 + 360.0, 180.0);
    *coherence = tr > 0 ? an / tr : 0.0;
}

nprfx_result nprfx_pam_orientation(nprfx_context *ctx, const nprfx_image *im, double *degrees,
                                   double *coherence)
{
    if (!im || !im->data || im->channels < 3 || !degrees || !coherence)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam orientation: needs an image of 3 or more channels");
    internal_pam_img p;
    nprfx_result r = internal_pam_from_view(ctx, im, &p);
    if (r) return r;
    internal_pam_orientation(&p, degrees, coherence);
    internal_pam_img_free(&p);
    return NPRFX_OK;
}

static void bilinear(const internal_pam_img *im, double x, double y, float *out)
{
    /* Clamped to the image: the rotated square lies inside it, so the clamp only catches
     * rounding at its rim. */
    if (x < 0) x = 0;
    if (y < 0) y = 0;
    if (x > im->w - 1) x = im->w - 1;
    if (y > im->h - 1) y = im->h - 1;
    int x0 = (int)floor(x), y0 = (int)floor(y);
    int x1 = x0 + 1 < im->w ? x0 + 1 : x0, y1 = y0 + 1 < im->h ? y0 + 1 : y0;
    double fx = x - x0, fy = y - y0;
    for (int c = 0; c < im->c; c++) {
        double a = internal_pam_px(im, x0, y0)[c] * (1 - fx) + internal_pam_px(im, x1, y0)[c] * fx;
        double b = internal_pam_px(im, x0, y1)[c] * (1 - fx) + internal_pam_px(im, x1, y1)[c] * fx;
        out[c] = (float)(a * (1 - fy) + b * fy);
    }
}

nprfx_result internal_pam_rotate(nprfx_context *ctx, const internal_pam_img *src, double degrees,
                                 internal_pam_img *out)
{
    double a = degrees * PI / 180.0, ca = cos(a), sa = sin(a);
    /* A square of side m rotated by a fits in a side of m (|cos a| + |sin a|); one pixel less
     * keeps bilinear taps inside. */
    int side = src->w < src->h ? src->w : src->h;
    int m = (int)floor(side / (fabs(ca) + fabs(sa))) - 1;
    if (fabs(sa) < 1e-12) m = side; /* no rotation (or half a turn): the whole square */
    if (m < 1) m = 1;
    nprfx_result r = internal_pam_img_alloc(ctx, m, m, src->c, out);
    if (r) return r;
    double cxs = 0.5 * (src->w - 1), cys = 0.5 * (src->h - 1), cxo = 0.5 * (m - 1);
    for (int y = 0; y < m; y++)
        for (int x = 0; x < m; x++) {
            /* out(x) = src(c + R(-a) (x - c')): content turns by +a. */
            double dx = x - cxo, dy = y - cxo;
            double sx = cxs + ca * dx + sa * dy, sy = cys - sa * dx + ca * dy;
            bilinear(src, sx, sy, internal_pam_px(out, x, y));
        }
    return NPRFX_OK;
}

static int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

nprfx_result internal_pam_reduce(nprfx_context *ctx, const internal_pam_img *src,
                                 internal_pam_img *out)
{
    static const float k[5] = {1.0f / 16, 4.0f / 16, 6.0f / 16, 4.0f / 16, 1.0f / 16};
    int w = (src->w + 1) / 2, h = (src->h + 1) / 2, C = src->c;
    internal_pam_img tmp;
    nprfx_result r = internal_pam_img_alloc(ctx, w, src->h, C, &tmp);
    if (r) return r;
    if ((r = internal_pam_img_alloc(ctx, w, h, C, out))) {
        internal_pam_img_free(&tmp);
        return r;
    }
    for (int y = 0; y < src->h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < C; c++) {
                float s = 0;
                for (int t = -2; t <= 2; t++)
                    s += k[t + 2] * internal_pam_px(src, clampi(2 * x + t, 0, src->w - 1), y)[c];
                internal_pam_px(&tmp, x, y)[c] = s;
            }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < C; c++) {
                float s = 0;
                for (int t = -2; t <= 2; t++)
                    s += k[t + 2] * internal_pam_px(&tmp, x, clampi(2 * y + t, 0, src->h - 1))[c];
                internal_pam_px(out, x, y)[c] = s;
            }
    internal_pam_img_free(&tmp);
    return NPRFX_OK;
}

/* Zero mean, unit standard deviation of channel c (a constant channel becomes 0). */
static void normalise(internal_pam_img *im, int c)
{
    size_t n = (size_t)im->w * (size_t)im->h;
    double s = 0, s2 = 0;
    for (size_t i = 0; i < n; i++)
        s += im->px[i * im->c + c];
    double mean = s / (double)n;
    for (size_t i = 0; i < n; i++) {
        double d = im->px[i * im->c + c] - mean;
        s2 += d * d;
    }
    double sd = sqrt(s2 / (double)n);
    for (size_t i = 0; i < n; i++)
        im->px[i * im->c + c] = sd > 1e-9 ? (float)((im->px[i * im->c + c] - mean) / sd) : 0.0f;
}

nprfx_result internal_pam_features(nprfx_context *ctx, const internal_pam_img *rgb,
                                   internal_pam_img *out)
{
    static const float k[5] = {1.0f / 16, 4.0f / 16, 6.0f / 16, 4.0f / 16, 1.0f / 16};
    int w = rgb->w, h = rgb->h;
    internal_pam_img y0, y1;
    nprfx_result r = internal_pam_img_alloc(ctx, w, h, 1, &y0);
    if (r) return r;
    if ((r = internal_pam_img_alloc(ctx, w, h, 1, &y1))) goto done0;
    if ((r = internal_pam_img_alloc(ctx, w, h, 2, out))) goto done1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            y0.px[(size_t)y * w + x] = (float)luma(internal_pam_px(rgb, x, y));
    /* Smooth (binomial, both axes), then Sobel: the "Gaussian smooth filter and edge detection
     * operator" of §4.2. */
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float s = 0;
            for (int t = -2; t <= 2; t++)
                s += k[t + 2] * y0.px[(size_t)y * w + clampi(x + t, 0, w - 1)];
            y1.px[(size_t)y * w + x] = s;
        }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float s = 0;
            for (int t = -2; t <= 2; t++)
                s += k[t + 2] * y1.px[(size_t)clampi(y + t, 0, h - 1) * w + x];
            y0.px[(size_t)y * w + x] = s;
        }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
#define Y(dx, dy) y0.px[(size_t)clampi(y + (dy), 0, h - 1) * w + clampi(x + (dx), 0, w - 1)]
            double gx = (Y(1, -1) + 2 * Y(1, 0) + Y(1, 1)) - (Y(-1, -1) + 2 * Y(-1, 0) + Y(-1, 1));
            double gy = (Y(-1, 1) + 2 * Y(0, 1) + Y(1, 1)) - (Y(-1, -1) + 2 * Y(0, -1) + Y(1, -1));
#undef Y
            float yuv[3];
            nprfx_pam_rgb_to_yuv(internal_pam_px(rgb, x, y), yuv);
            float *o = internal_pam_px(out, x, y);
            o[0] = (float)sqrt(gx * gx + gy * gy);
            o[1] = (float)atan2(yuv[2], yuv[1]);
        }
    normalise(out, 0);
    normalise(out, 1);
done1:
    internal_pam_img_free(&y1);
done0:
    internal_pam_img_free(&y0);
    return r;
}
