/* nprfx — painterly art maps (Yan, Chi, Lee, Lin, "Stylized Rendering Using Samples of a Painted
 * Image", IEEE TVCG 14(2), 2008, §4; docs/design.md §3.7).
 *
 * A PAM is a stack of tileable tone maps, dark to light, whose strokes keep the same orientation
 * and layout from one tone to the next. In memory and on disk it is ONE RGB image, the "strip":
 * `count` square maps of S x S pixels side by side, left to right, dark to light (width count * S,
 * height S), scene-linear float RGB. Map m covers columns [m * S, (m + 1) * S). A host derives
 * count = width / height; the means below are informative and recomputed from the pixels.
 *
 * The builder makes one "key map" per brushstroke sample by multiresolution patch-based synthesis
 * (every key map follows the first one's stroke layout through the coherence search space of
 * §4.2-4.3), sorts the key maps by mean intensity and inserts linear blends between adjacent ones
 * (§4.4, Eq. 7-8). Core does no file I/O: `nprfx pam build` reads the samples and writes the strip
 * as an EXR with the attributes of NPRFX_PAM_ATTR_*. */
#ifndef NPRFX_PAM_H
#define NPRFX_PAM_H

#include <stddef.h>
#include <stdint.h>

#include "nprfx/context.h"
#include "nprfx/export.h"
#include "nprfx/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- colour: the paper's YUV, BT.601 (Kr = 0.299, Kb = 0.114; U in [-0.436, 0.436], V in
 * [-0.615, 0.615]) ----
 *
 * Defined here once so the builder, `nprfx pam info` and the pam-splat node agree to the bit. The
 * inverse is the exact algebraic inverse of the forward transform (not the rounded textbook
 * matrix), so a round trip is exact up to rounding. */
#define NPRFX_YUV_KR 0.299
#define NPRFX_YUV_KB 0.114
#define NPRFX_YUV_UMAX 0.436
#define NPRFX_YUV_VMAX 0.615

/* The luma alone. */
static inline double nprfx_luma(double r, double g, double b)
{
    return NPRFX_YUV_KR * r + (1.0 - NPRFX_YUV_KR - NPRFX_YUV_KB) * g + NPRFX_YUV_KB * b;
}

/* rgb -> yuv: Y = Kr R + (1 - Kr - Kb) G + Kb B, U = Umax (B - Y) / (1 - Kb),
 * V = Vmax (R - Y) / (1 - Kr). In and out may alias. */
static inline void nprfx_rgb_to_yuv(const double rgb[3], double yuv[3])
{
    double r = rgb[0], g = rgb[1], b = rgb[2];
    double y = nprfx_luma(r, g, b);
    yuv[0] = y;
    yuv[1] = NPRFX_YUV_UMAX * (b - y) / (1.0 - NPRFX_YUV_KB);
    yuv[2] = NPRFX_YUV_VMAX * (r - y) / (1.0 - NPRFX_YUV_KR);
}

/* The inverse of nprfx_rgb_to_yuv. In and out may alias. */
static inline void nprfx_yuv_to_rgb(const double yuv[3], double rgb[3])
{
    double y = yuv[0];
    double r = y + yuv[2] * ((1.0 - NPRFX_YUV_KR) / NPRFX_YUV_VMAX);
    double b = y + yuv[1] * ((1.0 - NPRFX_YUV_KB) / NPRFX_YUV_UMAX);
    double g = (y - NPRFX_YUV_KR * r - NPRFX_YUV_KB * b) / (1.0 - NPRFX_YUV_KR - NPRFX_YUV_KB);
    rgb[0] = r;
    rgb[1] = g;
    rgb[2] = b;
}

/* The same for float pixels (the builder's images). */
static inline void nprfx_pam_rgb_to_yuv(const float rgb[3], float yuv[3])
{
    double d[3] = {rgb[0], rgb[1], rgb[2]};
    nprfx_rgb_to_yuv(d, d);
    for (int c = 0; c < 3; c++)
        yuv[c] = (float)d[c];
}

static inline void nprfx_pam_yuv_to_rgb(const float yuv[3], float rgb[3])
{
    double d[3] = {yuv[0], yuv[1], yuv[2]};
    nprfx_yuv_to_rgb(d, d);
    for (int c = 0; c < 3; c++)
        rgb[c] = (float)d[c];
}

/* ---- the file format (an EXR written by `nprfx pam build`) ----
 *
 * Channels R, G, B (half floats by default), width = count * S, height = S, and these header
 * attributes, which `nprfx pam info` checks against the pixels:
 *   nprfx:pam       int     format version, NPRFX_PAM_FORMAT_VERSION
 *   nprfx:pamCount  int     count
 *   nprfx:pamKeys   string  indices of the key maps, ascending, comma-separated ("0,4,9")
 *   nprfx:pamMeanY  string  each map's mean Y, comma-separated, %.6g (likewise MeanU, MeanV) */
#define NPRFX_PAM_FORMAT_VERSION 1
#define NPRFX_PAM_ATTR_VERSION "nprfx:pam"
#define NPRFX_PAM_ATTR_COUNT "nprfx:pamCount"
#define NPRFX_PAM_ATTR_KEYS "nprfx:pamKeys"
#define NPRFX_PAM_ATTR_MEAN_Y "nprfx:pamMeanY"
#define NPRFX_PAM_ATTR_MEAN_U "nprfx:pamMeanU"
#define NPRFX_PAM_ATTR_MEAN_V "nprfx:pamMeanV"

/* The most maps a PAM holds (the strip stays a texture any host can load). */
#define NPRFX_PAM_MAX_MAPS 256

/* What a strip holds: its maps' size and count, which are key maps, and each map's mean YUV. */
typedef struct nprfx_pam_info {
    size_t size;                            /* sizeof(nprfx_pam_info) */
    int map_size;                           /* S */
    int count;                              /* maps, 2..NPRFX_PAM_MAX_MAPS */
    unsigned char key[NPRFX_PAM_MAX_MAPS];  /* 1: a key map, 0: an in-between map */
    double mean_yuv[NPRFX_PAM_MAX_MAPS][3]; /* per map, over its S x S pixels */
} nprfx_pam_info;

/* Describe a strip from its pixels: S = height, count = width / height (the width must be a
 * multiple of the height and count >= 2), means of the first three channels as YUV; key flags
 * are all 0 (a strip does not say which maps are keys; the file's attributes do). */
NPRFX_API nprfx_result nprfx_pam_describe(nprfx_context *ctx, const nprfx_image *strip,
                                          nprfx_pam_info *out);

/* ---- the builder ---- */

typedef struct nprfx_pam_build_params {
    size_t size;   /* sizeof(nprfx_pam_build_params) */
    int map_size;  /* S, the maps' side in pixels; a multiple of `patch` */
    int patch;     /* the tile step of the synthesis at the finest level; each pasted block is
                    * patch + overlap pixels wide. A multiple of 2^(levels-1), at least
                    * 2 * 2^(levels-1). */
    int overlap;   /* the L-shaped overlap in pixels at the finest level, 1..patch/2 */
    int levels;    /* Gaussian pyramid levels, 1..5 */
    double k;      /* Eq. 7: one in-between step per k of mean intensity (Y * 255), > 0 */
    int align;     /* 1: rotate each sample so its dominant stroke direction (structure tensor)
                    * is vertical, along v (§4.1, §5.3); 0: use the samples as they are */
    int css_links; /* the most CSS links kept per patch (Eq. 3), 1..32 */
    double css_tolerance; /* links: S_css <= (1 + tolerance) * the best S_css of the patch */
    double tolerance;     /* the first key map's coarsest level: a random block among those whose
                           * overlap error is within (1 + tolerance) of the best (quilting) */
    uint64_t seed;        /* the first key map's random choices (nprfx_hash) */
} nprfx_pam_build_params;

#define NPRFX_PAM_BUILD_PARAMS_DEFAULT                                                             \
    {                                                                                              \
        sizeof(nprfx_pam_build_params), 256, 64, 16, 3, 5.0, 1, 16, 0.5, 0.1, 2008u                \
    }

/* Build a PAM from nsamples >= 2 brushstroke samples (scene-linear, at least 3 channels: the
 * first three are RGB; all of the same size; each at least patch + overlap pixels after
 * alignment). The first sample's key map sets the stroke layout that the others follow. On
 * success strip_out is allocated (nprfx_image_alloc, 3 channels, bounds (0, 0, count*S, S); free
 * it with nprfx_image_free) and info_out (when not NULL) describes it, key maps flagged.
 * Deterministic: the same bits for any executor and thread count. */
NPRFX_API nprfx_result nprfx_pam_build(nprfx_context *ctx, const nprfx_pam_build_params *params,
                                       const nprfx_image *samples, int nsamples,
                                       nprfx_image *strip_out, nprfx_pam_info *info_out);

/* Eq. 7: the number of steps between two adjacent key maps of mean Y mu_a and mu_b,
 * N = max(1, round(|mu_a - mu_b| * 255 / k)); N - 1 in-between maps lie between them, blended
 * with alpha = (N-1)/N, ..., 1/N (Eq. 8: alpha * I_a + (1 - alpha) * I_b). */
NPRFX_API int nprfx_pam_steps(double mu_a, double mu_b, double k);

/* The dominant stroke direction of an image's first three channels, from the structure tensor of
 * its luma smoothed by the 3x3 binomial filter (central differences over the interior): degrees in
 * [0, 180), measured from +x towards +y (y down, so 90 is vertical), and the coherence in [0, 1]
 * (0: no direction). */
NPRFX_API nprfx_result nprfx_pam_orientation(nprfx_context *ctx, const nprfx_image *im,
                                             double *degrees, double *coherence);

/* A procedural brushstroke sample (for `nprfx pam samples`, since the project cannot ship
 * someone's painting): oriented, tapered strokes with bristle texture and paint colour variation
 * over a ground, at tone `tone` in [0, 1] (0 dark, 1 light), strokes along `degrees` (from +x
 * towards +y). Fills all of out (3 or more channels; RGB in the first three, others 1). */
NPRFX_API nprfx_result nprfx_pam_sample_strokes(nprfx_context *ctx, double tone, double degrees,
                                                uint64_t seed, nprfx_image *out);

#ifdef __cplusplus
}
#endif
#endif
