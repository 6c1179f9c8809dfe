/* nprfx OpenFX adapter — host images (ofx_image.c): fetching, 8/16-bit to float, the y flip
 * into nprfx views, storing at the host's depth. A flip f maps host row y_up to nprfx row
 * f - y_up; for the frame, f = fy1 + fy2 - 1 (see ofx_image.c). */
#ifndef NPRFX_OFX_IMAGE_H
#define NPRFX_OFX_IMAGE_H

#include "nprfx/nprfx.h"
#include "ofx_api.h"

typedef struct ofx_img {
    OfxPropertySetHandle h; /* NULL: nothing fetched */
    char *data;             /* pixel (bounds.x1, bounds.y1) */
    int row_bytes;
    OfxRectI b;
    int ncomp;   /* 1 Alpha, 3 RGB, 4 RGBA; a plane's: its channels (2: XY) */
    int bytes;   /* per component of data: 4 float, 2 unsigned short, 1 unsigned char */
    float *conv; /* an 8/16-bit input converted to float (data points here then) */
} ofx_img;

/* Give the image back to the host and free its conversion; *im is zeroed. */
void ofx_img_release(ofx_img *im);

/* An image of clip at t. Inputs (convert = 1) always come out as float; the output keeps the
 * host's depth and is written with ofx_img_store. */
OfxStatus ofx_img_fetch(OfxImageClipHandle clip, OfxTime t, int convert, ofx_img *im);
/* An image of one plane of clip at t through the host's plane suite (a multi-plane host), as
 * float; its components may be any 1 to 4 (a Natron layer's channels). */
OfxStatus ofx_img_fetch_plane(OfxImageClipHandle clip, OfxTime t, const char *plane, ofx_img *im);

/* Write v into component c of pixel (x, y_up) of a host image of any depth (integers clamp to
 * [0, 1] and round; NaN becomes 0). */
void ofx_img_store(const ofx_img *im, int x, int y, int c, float v);

/* Host bounds b as an nprfx rectangle under flip f (empty stays empty). */
nprfx_rect ofx_flip_rect(OfxRectI b, int f);

/* A view of `count` RGBA components from `first` of a float image, flipped about f; where the
 * components cannot be shared they are copied into *scratch (free with ofx_free), else *scratch
 * is NULL. */
nprfx_result ofx_img_view(const ofx_img *im, int f, int first, int count, nprfx_image *v,
                          float **scratch);

#endif
