/* PAM builder: the strip (docs/design.md §3.7). Key maps sorted dark to light with the in-between
 * maps of §4.4 (Eq. 7-8) between them, laid side by side; and the description of a strip that
 * `nprfx pam info` and a host recompute from pixels. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal_pam.h"

int nprfx_pam_steps(double mu_a, double mu_b, double k)
{
    /* The paper's intensities are 8-bit; mean Y * 255 puts k = 5 on the same scale. */
    double n = floor(fabs(mu_a - mu_b) * 255.0 / k + 0.5);
    if (!(n >= 1)) return 1;
    return n > NPRFX_PAM_MAX_MAPS ? NPRFX_PAM_MAX_MAPS : (int)n;
}

/* Mean YUV of an S x S block of a view starting at column x0; double sums in raster order. */
static void mean_yuv(const nprfx_image *im, int x0, int S, double out[3])
{
    double s[3] = {0, 0, 0};
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++) {
            float yuv[3];
            nprfx_pam_rgb_to_yuv(nprfx_image_at(im, x0 + x, im->bounds.y0 + y), yuv);
            for (int c = 0; c < 3; c++)
                s[c] += yuv[c];
        }
    for (int c = 0; c < 3; c++)
        out[c] = s[c] / ((double)S * S);
}

nprfx_result nprfx_pam_describe(nprfx_context *ctx, const nprfx_image *strip, nprfx_pam_info *out)
{
    if (!strip || !out || !strip->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "pam: no strip to describe");
    if (out->size != sizeof *out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "pam: bad nprfx_pam_info size %zu",
                           out->size);
    int w = nprfx_rect_width(strip->bounds), h = nprfx_rect_height(strip->bounds);
    if (strip->channels < 3)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam: a PAM is an RGB image, this one has %d channel(s)",
                           strip->channels);
    if (h < 1 || w % h)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam: a PAM's width is a whole number of square maps, but %dx%d is "
                           "not a multiple of its height",
                           w, h);
    int count = w / h;
    if (count < 2 || count > NPRFX_PAM_MAX_MAPS)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "pam: %dx%d holds %d map(s); a PAM holds 2 to %d", w, h, count,
                           NPRFX_PAM_MAX_MAPS);
    memset(out, 0, sizeof *out);
    out->size = sizeof *out;
    out->map_size = h;
    out->count = count;
    for (int m = 0; m < count; m++)
        mean_yuv(strip, strip->bounds.x0 + m * h, h, out->mean_yuv[m]);
    return NPRFX_OK;
}

typedef struct keyed {
    int index;
    double y;
} keyed;

static int by_tone(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->y != y->y) return x->y < y->y ? -1 : 1;
    return x->index - y->index; /* equal tones keep the samples' order */
}

static void put_map(nprfx_image *strip, int m, const internal_pam_img *a, const internal_pam_img *b,
                    float alpha)
{
    int S = a->w;
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++) {
            float *o = nprfx_image_at(strip, m * S + x, y);
            const float *pa = internal_pam_px(a, x, y), *pb = internal_pam_px(b, x, y);
            for (int c = 0; c < 3; c++)
                o[c] = alpha * pa[c] + (1.0f - alpha) * pb[c]; /* Eq. 8 */
        }
}

nprfx_result internal_pam_assemble(nprfx_context *ctx, const internal_pam_img *keys, int K,
                                   double k, nprfx_image *strip, nprfx_pam_info *info)
{
    int S = keys[0].w;
    keyed *order = malloc(sizeof *order * (size_t)K);
    if (!order) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "pam build: out of memory");
    for (int i = 0; i < K; i++) {
        nprfx_image v = {keys[i].px, 3, (ptrdiff_t)3 * S, 3, nprfx_rect_make(0, 0, S, S)};
        double m[3];
        mean_yuv(&v, 0, S, m);
        order[i].index = i;
        order[i].y = m[0];
    }
    qsort(order, (size_t)K, sizeof *order, by_tone);
    long count = K;
    for (int i = 0; i + 1 < K; i++)
        count += nprfx_pam_steps(order[i].y, order[i + 1].y, k) - 1;
    if (count > NPRFX_PAM_MAX_MAPS) {
        free(order);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "pam build: k = %g gives %ld maps, more than %d; raise k", k, count,
                           NPRFX_PAM_MAX_MAPS);
    }
    nprfx_result r = nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, (int)count * S, S), 3, strip);
    if (r) {
        free(order);
        return r;
    }
    unsigned char key[NPRFX_PAM_MAX_MAPS];
    memset(key, 0, sizeof key);
    int m = 0;
    for (int i = 0; i < K; i++) {
        const internal_pam_img *a = &keys[order[i].index];
        key[m] = 1;
        put_map(strip, m++, a, a, 1.0f);
        if (i + 1 == K) break;
        const internal_pam_img *b = &keys[order[i + 1].index];
        int N = nprfx_pam_steps(order[i].y, order[i + 1].y, k);
        for (int j = 1; j < N; j++) /* alpha = (N-1)/N, ..., 1/N between the two keys */
            put_map(strip, m++, a, b, (float)(N - j) / (float)N);
    }
    free(order);
    if (info) {
        info->size = sizeof *info;
        if ((r = nprfx_pam_describe(ctx, strip, info))) {
            nprfx_image_free(strip);
            return r;
        }
        memcpy(info->key, key, sizeof key);
    }
    return NPRFX_OK;
}
