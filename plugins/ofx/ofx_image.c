/* nprfx OpenFX adapter — host images as nprfx sees them (declared in ofx_image.h): fetched from a
 * clip, converted from 8/16 bits to float, viewed as nprfx images flipped in y, and written back
 * at the host's depth.
 *
 * Coordinates. OFX pixel coordinates grow upward; nprfx's grow downward (docs/design.md §2). Every
 * frame-aligned image is flipped about the effect's frame [fy1, fy2): y_down = fy1 + fy2 - 1 -
 * y_up, which maps the frame onto itself, so a frame at (0, 0, W, H) keeps those numbers and
 * clips that share the canonical space stay aligned. An unaligned input (a lookup map) is
 * flipped about its own bounds, as the runner passes it whole. The flip is free: a view starts
 * at the top row and steps by -rowBytes, which also covers hosts whose rowBytes are negative. */
#include <stdint.h>
#include <string.h>

#include "ofx_image.h"
#include "ofx_suites.h"

void ofx_img_release(ofx_img *im)
{
    if (im->h) ofx_g.fx->clipReleaseImage(im->h);
    ofx_free(im->conv);
    memset(im, 0, sizeof *im);
}

static int depth_bytes(const char *depth)
{
    return !strcmp(depth, kOfxBitDepthFloat)   ? 4
           : !strcmp(depth, kOfxBitDepthShort) ? 2
           : !strcmp(depth, kOfxBitDepthByte)  ? 1
                                               : 0;
}

/* An 8/16-bit image as float in [0, 1]: the nodes read float only, and a host that gives
 * integers (MLT) gives display-referred video, for which that is the natural scale. */
static OfxStatus img_to_float(ofx_img *im)
{
    int w = im->b.x2 - im->b.x1, h = im->b.y2 - im->b.y1, n = w * im->ncomp;
    if (w <= 0 || h <= 0) return kOfxStatOK;
    float *f = ofx_alloc((size_t)n * (size_t)h * sizeof *f);
    if (!f) return kOfxStatErrMemory;
    for (int y = 0; y < h; y++) {
        const char *row = im->data + (ptrdiff_t)y * im->row_bytes;
        float *d = f + (size_t)y * (size_t)n;
        for (int i = 0; i < n; i++)
            d[i] = im->bytes == 2 ? ((const unsigned short *)row)[i] / 65535.0f
                                  : ((const unsigned char *)row)[i] / 255.0f;
    }
    im->conv = f;
    im->data = (char *)f;
    im->row_bytes = n * (int)sizeof *f;
    im->bytes = 4;
    return kOfxStatOK;
}

/* An image of clip at t. Inputs (convert = 1) always come out as float; the output keeps the
 * host's depth and is written with ofx_img_store. */
/* The components of an image: the standard ones, 2 for Natron's XY, and a Natron layer's channel
 * count (one "_Channel_" per channel); 0 for anything else. */
static int components_count(const char *comps)
{
    if (!strcmp(comps, kOfxImageComponentRGBA)) return 4;
    if (!strcmp(comps, kOfxImageComponentRGB)) return 3;
    if (!strcmp(comps, kOfxImageComponentAlpha)) return 1;
    if (!strcmp(comps, kNatronOfxImageComponentXY)) return 2;
    if (strncmp(comps, kNatronOfxImageComponentsPlane, strlen(kNatronOfxImageComponentsPlane)))
        return 0;
    int n = 0;
    for (const char *s = strstr(comps, kNatronOfxImageComponentsPlaneChannel); s;
         s = strstr(s + 1, kNatronOfxImageComponentsPlaneChannel))
        n++;
    return n >= 1 && n <= 4 ? n : 0;
}

static OfxStatus img_from_handle(OfxPropertySetHandle h, int convert, ofx_img *im)
{
    im->h = h;
    void *data = NULL;
    char *depth = NULL, *comps = NULL;
    int b[4] = {0, 0, 0, 0};
    if (ofx_g.prop->propGetPointer(h, kOfxImagePropData, 0, &data) != kOfxStatOK ||
        ofx_g.prop->propGetInt(h, kOfxImagePropRowBytes, 0, &im->row_bytes) != kOfxStatOK ||
        ofx_g.prop->propGetIntN(h, kOfxImagePropBounds, 4, b) != kOfxStatOK ||
        ofx_g.prop->propGetString(h, kOfxImageEffectPropPixelDepth, 0, &depth) != kOfxStatOK ||
        ofx_g.prop->propGetString(h, kOfxImageEffectPropComponents, 0, &comps) != kOfxStatOK) {
        ofx_img_release(im);
        return kOfxStatErrBadHandle;
    }
    im->data = data;
    im->b.x1 = b[0], im->b.y1 = b[1], im->b.x2 = b[2], im->b.y2 = b[3];
    im->ncomp = components_count(comps);
    im->bytes = depth_bytes(depth);
    if (!im->bytes || !im->ncomp || im->row_bytes % im->bytes ||
        (!im->data && im->b.x2 > im->b.x1 && im->b.y2 > im->b.y1)) {
        ofx_img_release(im);
        return kOfxStatErrImageFormat;
    }
    OfxStatus st;
    if (convert && im->bytes != 4 && (st = img_to_float(im)) != kOfxStatOK) {
        ofx_img_release(im);
        return st;
    }
    return kOfxStatOK;
}

OfxStatus ofx_img_fetch(OfxImageClipHandle clip, OfxTime t, int convert, ofx_img *im)
{
    memset(im, 0, sizeof *im);
    OfxPropertySetHandle h = NULL;
    OfxStatus st = ofx_g.fx->clipGetImage(clip, t, NULL, &h);
    if (st != kOfxStatOK) return st;
    if (!h) return kOfxStatFailed;
    return img_from_handle(h, convert, im);
}

OfxStatus ofx_img_fetch_plane(OfxImageClipHandle clip, OfxTime t, const char *plane, ofx_img *im)
{
    memset(im, 0, sizeof *im);
    if (!ofx_g.planes) return kOfxStatErrUnsupported;
    OfxPropertySetHandle h = NULL;
    OfxStatus st = ofx_g.planes->clipGetImagePlane(clip, t, plane, NULL, &h);
    if (st != kOfxStatOK) return st;
    if (!h) return kOfxStatFailed;
    return img_from_handle(h, 1, im);
}

/* Write v into component c of pixel (x, y_up) of a host image of any depth (integers clamp to
 * [0, 1] and round; NaN becomes 0). */
void ofx_img_store(const ofx_img *im, int x, int y, int c, float v)
{
    char *row = im->data + (ptrdiff_t)(y - im->b.y1) * im->row_bytes;
    ptrdiff_t i = (ptrdiff_t)(x - im->b.x1) * im->ncomp + c;
    if (im->bytes == 4) {
        ((float *)row)[i] = v;
        return;
    }
    float u = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; /* NaN fails v > 0 */
    if (im->bytes == 2)
        ((unsigned short *)row)[i] = (unsigned short)(u * 65535.0f + 0.5f);
    else
        ((unsigned char *)row)[i] = (unsigned char)(u * 255.0f + 0.5f);
}

/* Pixel (x, y_up) of a host image, component c of its own layout. */
static float *img_at(const ofx_img *im, int x, int y, int c)
{
    return (float *)(im->data + (ptrdiff_t)(y - im->b.y1) * im->row_bytes) +
           (ptrdiff_t)(x - im->b.x1) * im->ncomp + c;
}

nprfx_rect ofx_flip_rect(OfxRectI b, int f)
{
    if (b.x2 <= b.x1 || b.y2 <= b.y1) return nprfx_rect_make(b.x1, 0, b.x1, 0);
    return nprfx_rect_make(b.x1, f - (b.y2 - 1), b.x2, f - b.y1 + 1);
}

/* Which host component holds RGBA component c (-1: the image has none). */
static int host_comp(const ofx_img *im, int c)
{
    if (im->ncomp == 4) return c;
    if (im->ncomp == 3) return c < 3 ? c : -1;
    if (im->ncomp == 2) return c < 2 ? c : -1; /* a plane of two channels (XY) */
    return c == 3 ? 0 : -1;
}

static float dummy_pixel[4];

/* A view of `count` RGBA components from `first` (the selector's pick), flipped about f. It
 * shares the host's pixels when the image has those components; an Alpha image read for a single
 * channel gives its alpha whatever the pick (a matte in an Alpha-only clip is still the data the
 * user routed there); otherwise the components are copied into *scratch, missing ones 0 (1 for
 * the alpha of an RGB image, which is opaque). */
nprfx_result ofx_img_view(const ofx_img *im, int f, int first, int count, nprfx_image *v,
                          float **scratch)
{
    memset(v, 0, sizeof *v);
    *scratch = NULL;
    v->bounds = ofx_flip_rect(im->b, f);
    v->channels = count;
    if (nprfx_rect_empty(v->bounds)) {
        v->data = dummy_pixel; /* connected, but no pixels: reads as outside its bounds */
        v->pixel_stride = count;
        return NPRFX_OK;
    }
    int c0 = host_comp(im, first), direct;
    if (im->ncomp == 1) {
        direct = count == 1;
        c0 = 0;
    } else {
        direct = c0 >= 0;
        for (int k = 1; k < count; k++)
            direct &= host_comp(im, first + k) == c0 + k;
    }
    if (direct) {
        v->data = img_at(im, im->b.x1, im->b.y2 - 1, c0);
        v->pixel_stride = im->ncomp;
        v->row_stride = -(ptrdiff_t)(im->row_bytes / (int)sizeof(float));
        return NPRFX_OK;
    }
    int w = im->b.x2 - im->b.x1, h = im->b.y2 - im->b.y1;
    float *px = ofx_alloc((size_t)w * (size_t)h * (size_t)count * sizeof(float));
    if (!px) return NPRFX_ERR_OUT_OF_MEMORY;
    for (int y = im->b.y1; y < im->b.y2; y++)
        for (int x = im->b.x1; x < im->b.x2; x++) {
            float *d = px + ((size_t)(f - y - v->bounds.y0) * (size_t)w + (size_t)(x - im->b.x1)) *
                                (size_t)count;
            for (int k = 0; k < count; k++) {
                int hc = host_comp(im, first + k);
                d[k] = hc >= 0 ? *img_at(im, x, y, hc)
                               : (im->ncomp == 3 && first + k == 3 ? 1.0f : 0.0f);
            }
        }
    v->data = px;
    v->pixel_stride = count;
    v->row_stride = (ptrdiff_t)w * count;
    *scratch = px;
    return NPRFX_OK;
}
