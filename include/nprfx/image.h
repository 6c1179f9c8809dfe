/* nprfx — strided float image views.
 *
 * A view does not own its pixels unless it came from nprfx_image_alloc. Coordinates are integer
 * pixel indices with y growing downward; `bounds` is the half-open rectangle of pixels the view
 * holds (an EXR data window, an OFX image's bounds after the adapter's flip). Strides are in
 * floats and may be negative (OFX hosts hand out bottom-up rows). Sampling functions treat pixel
 * (i, j) as the sample at continuous position (i, j): integer positions return pixels exactly. */
#ifndef NPRFX_IMAGE_H
#define NPRFX_IMAGE_H

#include <stddef.h>

#include "nprfx/context.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct nprfx_rect {
    int x0, y0; /* first pixel */
    int x1, y1; /* one past the last pixel */
} nprfx_rect;

typedef struct nprfx_image {
    float *data; /* channel 0 of pixel (bounds.x0, bounds.y0); NULL for an absent input */
    ptrdiff_t pixel_stride; /* floats between horizontally adjacent pixels */
    ptrdiff_t row_stride;   /* floats between vertically adjacent pixels; may be negative */
    int channels;           /* 1..NPRFX_MAX_CHANNELS */
    nprfx_rect bounds;
} nprfx_image;

#define NPRFX_MAX_CHANNELS 16

static inline int nprfx_rect_width(nprfx_rect r)
{
    return r.x1 > r.x0 ? r.x1 - r.x0 : 0;
}
static inline int nprfx_rect_height(nprfx_rect r)
{
    return r.y1 > r.y0 ? r.y1 - r.y0 : 0;
}
static inline int nprfx_rect_empty(nprfx_rect r)
{
    return r.x1 <= r.x0 || r.y1 <= r.y0;
}
static inline int nprfx_rect_contains(nprfx_rect r, int x, int y)
{
    return x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1;
}
static inline nprfx_rect nprfx_rect_make(int x0, int y0, int x1, int y1)
{
    nprfx_rect r = {x0, y0, x1, y1};
    return r;
}
NPRFX_API nprfx_rect nprfx_rect_intersect(nprfx_rect a, nprfx_rect b);
NPRFX_API int nprfx_rect_equal(nprfx_rect a, nprfx_rect b);

/* Pointer to channel 0 of pixel (x, y); (x, y) must lie inside bounds. */
static inline float *nprfx_image_at(const nprfx_image *im, int x, int y)
{
    return im->data + (ptrdiff_t)(x - im->bounds.x0) * im->pixel_stride +
           (ptrdiff_t)(y - im->bounds.y0) * im->row_stride;
}

/* Allocate a packed, zeroed image (pixel_stride = channels, row_stride = width * channels). */
NPRFX_API nprfx_result nprfx_image_alloc(nprfx_context *ctx, nprfx_rect bounds, int channels,
                                         nprfx_image *out);
/* Free pixels from nprfx_image_alloc and reset the view; safe on a zeroed view. */
NPRFX_API void nprfx_image_free(nprfx_image *im);

/* A view of `count` channels starting at `first` of im (shares pixels). */
NPRFX_API nprfx_image nprfx_image_channels(const nprfx_image *im, int first, int count);
/* A view restricted to rect (must lie inside im->bounds; shares pixels). */
NPRFX_API nprfx_image nprfx_image_crop(const nprfx_image *im, nprfx_rect rect);

/* Copy the overlap of src and dst (channel counts must match). */
NPRFX_API nprfx_result nprfx_image_copy(nprfx_context *ctx, const nprfx_image *src,
                                        nprfx_image *dst);
NPRFX_API void nprfx_image_fill(nprfx_image *im, const float *value /* channels values */);

/* Border handling for sampling and filtering outside bounds. */
typedef enum nprfx_border {
    NPRFX_BORDER_CLAMP = 0, /* repeat the edge pixel */
    NPRFX_BORDER_BLACK = 1  /* zero outside */
} nprfx_border;

#ifdef __cplusplus
}
#endif
#endif
