/* Painterly art maps as pam-splat reads them (docs/design.md §3.7): checking and measuring a PAM
 * strip, placing a tone among its maps, and the builtin strip used when none is connected. */
#include <math.h>
#include <string.h>

#include "nprfx/pam_splat.h"
#include "nprfx/rng.h"

nprfx_result nprfx_pam_measure(nprfx_context *ctx, const nprfx_image *pam, const char *who,
                               nprfx_pam_stats *info)
{
    if (!pam || !pam->data || !info)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "%s is missing", who);
    int w = nprfx_rect_width(pam->bounds), h = nprfx_rect_height(pam->bounds);
    if (pam->channels < 3)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s has %d channel(s); a painterly art map is RGB", who, pam->channels);
    /* the layout is the format's only marker: a foreign image almost never has it */
    if (h < 1 || w < 2 * h || w % h != 0)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s is %dx%d, not a painterly art map: its width must be a multiple "
                           "(2 or more) of its height (square maps side by side, dark to light)",
                           who, w, h);
    int count = w / h;
    if (count > NPRFX_PAM_MAX_MAPS)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s is %dx%d: %d maps, more than the %d supported", who, w, h, count,
                           NPRFX_PAM_MAX_MAPS);
    memset(info, 0, sizeof *info);
    info->count = count;
    info->size = h;
    double tot[3] = {0.0, 0.0, 0.0};
    for (int m = 0; m < count; m++) {
        double sy = 0.0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < h; x++) {
                const float *px =
                    nprfx_image_at(pam, pam->bounds.x0 + m * h + x, pam->bounds.y0 + y);
                double rgb[3] = {px[0], px[1], px[2]}, yuv[3];
                if (!isfinite(rgb[0]) || !isfinite(rgb[1]) || !isfinite(rgb[2]))
                    return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                       "%s has a non-finite pixel at (%d, %d)", who,
                                       pam->bounds.x0 + m * h + x, pam->bounds.y0 + y);
                nprfx_rgb_to_yuv(rgb, yuv);
                sy += yuv[0];
                for (int c = 0; c < 3; c++)
                    tot[c] += yuv[c];
            }
        info->map_y[m] = sy / ((double)h * h);
    }
    for (int c = 0; c < 3; c++)
        info->mean[c] = tot[c] / ((double)count * h * h);
    return NPRFX_OK;
}

void nprfx_pam_tone_position(const nprfx_pam_stats *info, double w, int *i, double *t)
{
    int n = info->count;
    if (!(w > 0.0)) w = 0.0; /* NaN too */
    if (w > 1.0) w = 1.0;
    double lo = info->map_y[0], hi = lo;
    for (int m = 1; m < n; m++)
        if (info->map_y[m] > hi) hi = info->map_y[m];
    if (!(hi - lo > 1e-9 * (fabs(lo) + fabs(hi)) && hi > lo)) {
        /* no rise in luminance to follow: spread the tones evenly */
        double q = w * (n - 1);
        int k = (int)q;
        if (k > n - 2) k = n - 2;
        *i = k;
        *t = q - k;
        return;
    }
    double target = lo + w * (hi - lo);
    /* the running maximum of the means: the first map whose envelope reaches the target */
    double env = lo;
    for (int m = 0; m < n - 1; m++) {
        double next = info->map_y[m + 1] > env ? info->map_y[m + 1] : env;
        if (target <= next || m == n - 2) {
            double d = next - env;
            double f = d > 0.0 ? (target - env) / d : 0.0;
            *i = m;
            *t = f < 0.0 ? 0.0 : (f > 1.0 ? 1.0 : f);
            return;
        }
        env = next;
    }
    *i = 0;
    *t = 0.0;
}

/* ---- the builtin PAM ---------------------------------------------------------------------- */

/* Short vertical strokes (along v, as the paper's PAMs are synthesised) on a flat ground of the
 * map's tone: each stroke a ridge of hashed sign, width, length and slight tilt, a few bristle
 * streaks across it, a tint. Offsets are wrapped, so every map tiles. */
static void builtin_map(float *px, int stride, int S, int m, int count, uint64_t seed)
{
    double base = 0.08 + 0.84 * m / (count - 1);
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++)
            for (int c = 0; c < 3; c++)
                px[((size_t)y * stride + x) * 3 + c] = (float)base;
    int strokes = S * S / 90 + 4;
    for (int k = 0; k < strokes; k++) {
        uint64_t h = nprfx_hash(seed, m, k, 0, 0, 0x9a17);
        double cx = S * nprfx_u01(h), cy = S * nprfx_u01(nprfx_mix64(h ^ 1));
        double len = S * (0.2 + 0.25 * nprfx_u01(nprfx_mix64(h ^ 2)));
        double wid = 1.5 + 2.5 * nprfx_u01(nprfx_mix64(h ^ 3)) * S / 64.0;
        double tilt = 0.25 * (nprfx_u01(nprfx_mix64(h ^ 4)) - 0.5);
        double amp = 0.16 * (2.0 * nprfx_u01(nprfx_mix64(h ^ 5)) - 1.0);
        double tint[3];
        for (int c = 0; c < 3; c++)
            tint[c] = 1.0 + 0.25 * (nprfx_u01(nprfx_mix64(h ^ (6 + (uint64_t)c))) - 0.5);
        double ct = cos(tilt), st = sin(tilt);
        int rx = (int)ceil(wid * 2.0 + len * fabs(st) / 2.0), ry = (int)ceil(len / 2.0 + wid);
        for (int j = -ry; j <= ry; j++)
            for (int i = -rx; i <= rx; i++) {
                double dx = i + 0.5 - (cx - floor(cx)), dy = j + 0.5 - (cy - floor(cy));
                double along = dy * ct + dx * st, across = dx * ct - dy * st;
                double e = fabs(along) / (len / 2.0);
                if (e >= 1.0) continue;
                double g = exp(-across * across / (wid * wid)) * (1.0 - e * e);
                g *= 0.75 + 0.25 * cos(across * 6.0 / wid); /* bristles */
                int X = ((int)floor(cx) + i) % S, Y = ((int)floor(cy) + j) % S;
                if (X < 0) X += S;
                if (Y < 0) Y += S;
                for (int c = 0; c < 3; c++) {
                    float *v = &px[((size_t)Y * stride + X) * 3 + c];
                    *v = (float)(*v + amp * g * tint[c] * (0.5 + base));
                }
            }
    }
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++)
            for (int c = 0; c < 3; c++) {
                float *v = &px[((size_t)y * stride + x) * 3 + c];
                *v = *v < 0.0f ? 0.0f : (*v > 1.0f ? 1.0f : *v);
            }
}

nprfx_result nprfx_pam_builtin(nprfx_context *ctx, int count, int size, uint64_t seed,
                               nprfx_image *out)
{
    if (count == 0) count = 6;
    if (size == 0) size = 64;
    if (count < 2 || count > NPRFX_PAM_MAX_MAPS || size < 4 || size > 4096)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam: builtin map of %d maps of %d px: 2 to %d maps of 4 to 4096 px",
                           count, size, NPRFX_PAM_MAX_MAPS);
    nprfx_result r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, count * size, size), 3, out);
    if (r) return r;
    for (int m = 0; m < count; m++)
        builtin_map(out->data + (size_t)m * size * 3, count * size, size, m, count, seed);
    return NPRFX_OK;
}
