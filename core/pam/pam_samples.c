/* Procedural brushstroke samples for the PAM builder (docs/design.md §3.7): the project cannot
 * ship cut-outs of someone's painting, so `nprfx pam samples` paints its own. A sample is a ground
 * of paint covered by overlapping strokes that run roughly along one direction: each stroke is a
 * tapered band whose bristles leave streaks of lighter and darker paint and dry out towards the
 * tail, in a colour varied around the tone's paint. Strokes are composited in index order and
 * every random number is a hash of (seed, stroke, bristle), so a sample is the same everywhere. */
#include <math.h>

#include "nprfx/pam.h"
#include "nprfx/rng.h"

#define PI 3.14159265358979323846
#define BRISTLES 6

enum { S_STROKE = 1, S_BRISTLE = 2 };

/* The paint at a tone, linear RGB: umber and blue in the shadows through a warm mid-tone to a
 * light ochre cream, so the samples of a set differ in hue as well as value. */
static void paint(double t, double rgb[3])
{
    static const double stops[4][3] = {
        {0.018, 0.022, 0.045}, {0.10, 0.06, 0.035}, {0.38, 0.24, 0.09}, {0.85, 0.75, 0.52}};
    double x = t < 0 ? 0 : t > 1 ? 3 : t * 3;
    int i = (int)x < 3 ? (int)x : 2;
    double f = x - i;
    for (int c = 0; c < 3; c++)
        rgb[c] = stops[i][c] * (1 - f) + stops[i + 1][c] * f;
}

static double u01(uint64_t seed, int a, int b, int stream)
{
    return nprfx_rand_u01(seed, 0, a, b, 0, (uint32_t)stream);
}

static double smooth(double e0, double e1, double x)
{
    double t = (x - e0) / (e1 - e0);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return t * t * (3 - 2 * t);
}

/* Value noise along a stroke, period-free: linear interpolation of hashed knots every 6 px. */
static double streak(uint64_t seed, int stroke, int bristle, double u)
{
    double x = u / 6.0;
    int i = (int)floor(x);
    double f = x - i;
    double a = u01(seed, stroke * 64 + bristle, i, S_BRISTLE + 8);
    double b = u01(seed, stroke * 64 + bristle, i + 1, S_BRISTLE + 8);
    return a + (b - a) * f * f * (3 - 2 * f);
}

nprfx_result nprfx_pam_sample_strokes(nprfx_context *ctx, double tone, double degrees,
                                      uint64_t seed, nprfx_image *out)
{
    if (!out || !out->data || out->channels < 3 || nprfx_rect_empty(out->bounds))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam samples: needs an image of 3 or more channels");
    if (!(tone >= 0 && tone <= 1) || !isfinite(degrees))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam samples: tone %g is outside [0, 1] (or the angle is not finite)",
                           tone);
    int W = nprfx_rect_width(out->bounds), H = nprfx_rect_height(out->bounds);
    double side = W < H ? W : H;
    double base[3];
    paint(tone, base);
    /* The ground: the paint a little darker, so gaps between strokes read as an underlayer. It is
     * flat: any texture of its own would carry gradients across the strokes' direction. */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *p = nprfx_image_at(out, out->bounds.x0 + x, out->bounds.y0 + y);
            for (int c = 0; c < 3; c++)
                p[c] = (float)(base[c] * 0.7);
            for (int c = 3; c < out->channels; c++)
                p[c] = 1.0f;
        }
    double len0 = 0.3 * side, wid0 = 0.05 * side;
    int strokes = (int)(2.2 * W * H / (len0 * wid0)) + 1;
    for (int s = 0; s < strokes; s++) {
        double cx = u01(seed, s, 0, S_STROKE) * W, cy = u01(seed, s, 1, S_STROKE) * H;
        double ang = (degrees + (u01(seed, s, 2, S_STROKE) - 0.5) * 16.0) * PI / 180.0;
        double half = 0.5 * len0 * (0.7 + 0.6 * u01(seed, s, 3, S_STROKE));
        double hw = 0.5 * wid0 * (0.7 + 0.6 * u01(seed, s, 4, S_STROKE));
        double col[3], v = 0.8 + 0.4 * u01(seed, s, 5, S_STROKE);
        for (int c = 0; c < 3; c++) /* value and a little hue variation per stroke */
            col[c] = base[c] * v * (0.9 + 0.2 * u01(seed, s, 6 + c, S_STROKE));
        double dx = cos(ang), dy = sin(ang);
        double ext = half + hw + 1;
        int x0 = (int)floor(cx - ext), x1 = (int)ceil(cx + ext);
        int y0 = (int)floor(cy - ext), y1 = (int)ceil(cy + ext);
        for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < H; y++)
            for (int x = x0 < 0 ? 0 : x0; x <= x1 && x < W; x++) {
                double rx = x - cx, ry = y - cy;
                double u = rx * dx + ry * dy, w = (-rx * dy + ry * dx) / hw; /* along, across */
                if (fabs(u) > half || fabs(w) > 1) continue;
                /* Bristle b's paint, interpolated smoothly across the stroke: hard steps between
                 * sub-pixel bristles would alias into texture in every direction. */
                double bw = (w + 1) * 0.5 * (BRISTLES - 1);
                int b = (int)floor(bw);
                if (b >= BRISTLES - 1) b = BRISTLES - 2;
                double fb = bw - b;
                double ink = 0.75 + 0.5 * (u01(seed, s, b, S_BRISTLE) * (1 - fb) +
                                           u01(seed, s, b + 1, S_BRISTLE) * fb);
                if (fb > 0.5) b++; /* the nearest bristle's dryness and streaks */
                double tail = (u + half) / (2 * half); /* 0 at the head, 1 at the tail */
                /* Bristles run dry towards the tail: each stops where its paint runs out. */
                double dry = 0.55 + 0.45 * u01(seed, s, b, S_BRISTLE + 1);
                double a = smooth(1.0, 0.8, fabs(w)) * smooth(0.0, 0.08, tail) *
                           smooth(dry, dry - 0.1, tail);
                if (a <= 0) continue;
                double k = ink * (0.8 + 0.4 * streak(seed, s, b, u));
                float *p = nprfx_image_at(out, out->bounds.x0 + x, out->bounds.y0 + y);
                for (int c = 0; c < 3; c++)
                    p[c] = (float)(p[c] * (1 - a) + col[c] * k * a);
            }
    }
    return NPRFX_OK;
}
