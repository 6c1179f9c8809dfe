/* Image views: allocation, sub-views, copy, fill. */
#include <stdlib.h>
#include <string.h>

#include "nprfx/image.h"

nprfx_rect nprfx_rect_intersect(nprfx_rect a, nprfx_rect b)
{
    nprfx_rect r;
    r.x0 = a.x0 > b.x0 ? a.x0 : b.x0;
    r.y0 = a.y0 > b.y0 ? a.y0 : b.y0;
    r.x1 = a.x1 < b.x1 ? a.x1 : b.x1;
    r.y1 = a.y1 < b.y1 ? a.y1 : b.y1;
    if (r.x1 < r.x0) r.x1 = r.x0;
    if (r.y1 < r.y0) r.y1 = r.y0;
    return r;
}

int nprfx_rect_equal(nprfx_rect a, nprfx_rect b)
{
    return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1;
}

nprfx_result nprfx_image_alloc(nprfx_context *ctx, nprfx_rect bounds, int channels,
                               nprfx_image *out)
{
    memset(out, 0, sizeof *out);
    if (channels < 1 || bounds.x1 < bounds.x0 || bounds.y1 < bounds.y0)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "cannot allocate an image of %dx%d pixels with %d channels",
                           bounds.x1 - bounds.x0, bounds.y1 - bounds.y0, channels);
    size_t w = (size_t)nprfx_rect_width(bounds), h = (size_t)nprfx_rect_height(bounds);
    size_t n = w * h * (size_t)channels;
    float *data = calloc(n ? n : 1, sizeof(float));
    if (!data)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY,
                           "out of memory allocating a %zux%zu image with %d channels", w, h,
                           channels);
    out->data = data;
    out->pixel_stride = channels;
    out->row_stride = (ptrdiff_t)(w * (size_t)channels);
    out->channels = channels;
    out->bounds = bounds;
    return NPRFX_OK;
}

void nprfx_image_free(nprfx_image *im)
{
    if (!im) return;
    free(im->data);
    memset(im, 0, sizeof *im);
}

nprfx_image nprfx_image_channels(const nprfx_image *im, int first, int count)
{
    nprfx_image v = *im;
    v.data = im->data ? im->data + first : NULL;
    v.channels = count;
    return v;
}

nprfx_image nprfx_image_crop(const nprfx_image *im, nprfx_rect rect)
{
    nprfx_image v = *im;
    rect = nprfx_rect_intersect(rect, im->bounds);
    if (im->data && !nprfx_rect_empty(rect)) v.data = nprfx_image_at(im, rect.x0, rect.y0);
    v.bounds = rect;
    return v;
}

nprfx_result nprfx_image_copy(nprfx_context *ctx, const nprfx_image *src, nprfx_image *dst)
{
    if (src->channels != dst->channels)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "image copy: %d channels into %d channels", src->channels,
                           dst->channels);
    nprfx_rect r = nprfx_rect_intersect(src->bounds, dst->bounds);
    for (int y = r.y0; y < r.y1; y++)
        for (int x = r.x0; x < r.x1; x++) {
            const float *s = nprfx_image_at(src, x, y);
            float *d = nprfx_image_at(dst, x, y);
            for (int c = 0; c < src->channels; c++)
                d[c] = s[c];
        }
    return NPRFX_OK;
}

void nprfx_image_fill(nprfx_image *im, const float *value)
{
    for (int y = im->bounds.y0; y < im->bounds.y1; y++)
        for (int x = im->bounds.x0; x < im->bounds.x1; x++) {
            float *d = nprfx_image_at(im, x, y);
            for (int c = 0; c < im->channels; c++)
                d[c] = value[c];
        }
}
