/* nprfx — Gaussian blur and image resampling. */
#ifndef NPRFX_FILTER_H
#define NPRFX_FILTER_H

#include "nprfx/image.h"
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

#ifdef __cplusplus
}
#endif
#endif
