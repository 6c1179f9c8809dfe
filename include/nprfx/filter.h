/* nprfx — image filters: Gaussian blur, resampling, grey-scale morphology (Haralick, Sternberg,
 * Zhuang 1987) and the displacement warp (docs/design.md §3.8). */
#ifndef NPRFX_FILTER_H
#define NPRFX_FILTER_H

#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Separable Gaussian blur of src into dst over dst->bounds (src read with `border` outside its
 * bounds). Any sigma in [0, 1e4] (0 copies). Small sigmas (< 3) use an exact sampled kernel;
 * large ones a recursive (IIR) approximation whose cost does not grow with sigma. src and dst
 * must not alias and must have the same channel count; a source with empty bounds gives zeros.
 * Work is spread over the context's executor; the result does not depend on the thread count,
 * nor on how dst tiles the output. */
NPRFX_API nprfx_result nprfx_gaussian_blur(nprfx_context *ctx, const nprfx_image *src,
                                           nprfx_image *dst, double sigma, nprfx_border border);

/* Sample all channels of im at continuous position (x, y) (pixel centres at integers).
 * out receives im->channels floats. */
NPRFX_API void nprfx_sample_nearest(const nprfx_image *im, double x, double y, nprfx_border border,
                                    float *out);
NPRFX_API void nprfx_sample_bilinear(const nprfx_image *im, double x, double y, nprfx_border border,
                                     float *out);
/* Bicubic with the Catmull-Rom kernel (Keys a = -0.5): interpolating, 4x4 taps. */
NPRFX_API void nprfx_sample_bicubic(const nprfx_image *im, double x, double y, nprfx_border border,
                                    float *out);

/* ---- the morphology node over an image (Haralick, Sternberg, Zhuang, "Image analysis using
 * mathematical morphology", IEEE PAMI 9(4), 1987: grey-scale dilation and erosion with a flat
 * structuring element, opening and closing their compositions) ---- */

/* The morphology node's operations, in the order of its `operation` choice. */
typedef enum nprfx_morphology_op {
    NPRFX_MORPHOLOGY_DILATE = 0, /* max over the footprint */
    NPRFX_MORPHOLOGY_ERODE = 1,  /* min over the footprint */
    NPRFX_MORPHOLOGY_OPEN = 2,   /* erode then dilate */
    NPRFX_MORPHOLOGY_CLOSE = 3,  /* dilate then erode */
    NPRFX_MORPHOLOGY_OP_COUNT
} nprfx_morphology_op;

/* Footprints (flat structuring elements), in the order of the node's `footprint` choice. */
typedef enum nprfx_morphology_footprint {
    NPRFX_MORPHOLOGY_DISC = 0,   /* offsets with dx^2 + dy^2 <= radius^2 */
    NPRFX_MORPHOLOGY_SQUARE = 1, /* offsets with |dx|, |dy| <= radius */
    NPRFX_MORPHOLOGY_FOOTPRINT_COUNT
} nprfx_morphology_footprint;

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_morphology_params {
    int operation; /* nprfx_morphology_op */
    double radius; /* in pixels, [0, 4096]; fractional radii pick the integer offsets inside */
    int footprint; /* nprfx_morphology_footprint */
} nprfx_morphology_params;

/* The morphology node's inputs, in the descriptor's order (args->inputs). */
enum { NPRFX_MORPHOLOGY_IN_IMAGE = 0, NPRFX_MORPHOLOGY_IN_COUNT };

/* Filter args->window of args->output (which has the image's channels; every channel on its
 * own), the image input NPRFX_MORPHOLOGY_IN_IMAGE. Reads outside the image's data window or the
 * frame repeat the edge: they clamp to image->bounds and args->frame (the whole image domain),
 * the same for every tile. open and close run their first pass over
 * the window grown by the footprint, so tiles agree with the whole frame. fmaxf/fminf ignore a
 * NaN rather than spreading it. Runs on ctx's executor; bit-identical for any thread count and
 * window split. */
NPRFX_API nprfx_result nprfx_morphology_render(const nprfx_render_args *args,
                                               const nprfx_morphology_params *p);

/* ---- the warp node over an image ---- */

/* Reconstruction filters of the warp, in the order of the node's `filter` choice. */
typedef enum nprfx_warp_filter {
    NPRFX_WARP_BILINEAR = 0, /* nprfx_sample_bilinear */
    NPRFX_WARP_BICUBIC = 1,  /* nprfx_sample_bicubic (Catmull-Rom) */
    NPRFX_WARP_FILTER_COUNT
} nprfx_warp_filter;

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_warp_params {
    double amount; /* displacement in pixels per unit of offset */
    int filter;    /* nprfx_warp_filter */
    int border;    /* nprfx_border: what lookups outside the image read */
    /* > 0: each component of the displacement is clamped to [-reach, reach] pixels, so the warp
     * reads the image no farther than that (plus the filter's taps) and can render a strip of
     * rows from the rows around it; 0: unbounded. */
    double reach;
} nprfx_warp_params;

/* The warp node's inputs, in the descriptor's order (args->inputs). */
enum { NPRFX_WARP_IN_IMAGE = 0, NPRFX_WARP_IN_OFFSET = 1, NPRFX_WARP_IN_COUNT };

/* Warp args->window of out = args->output (which has image's channels), image and offset the
 * inputs NPRFX_WARP_IN_*: out(p) = image(p + amount * offset(p)),
 * each displacement component clamped to +-reach when reach > 0, with p a pixel centre, offset's
 * channels 0 and 1 giving (x, y; y down). Outside its data window the offset reads as 0 (no
 * displacement); a NaN displacement leaves the pixel in place. The image must not be empty; offset
 * needs at least 2 channels. Runs on ctx's executor; bit-identical for any thread count and window
 * split. */
NPRFX_API nprfx_result nprfx_warp_render(const nprfx_render_args *args, const nprfx_warp_params *p);

#ifdef __cplusplus
}
#endif
#endif
