/* The PAM builder's internals (docs/design.md §3.7), shared by core/pam_*.c:
 *   pam_image.c   packed work images, the Gaussian pyramid, alignment (rotation), features
 *   pam_css.c     the coherence search space: links from a patch of A to similar patches of B
 *   pam_quilt.c   one level of tile synthesis: overlap error, DP seams, pasting
 *   pam_build.c   the entry point: checks, samples to pyramids, the key maps level by level
 *   pam_strip.c   key maps sorted into the strip with in-between maps; describing a strip
 * Nothing here is exported. */
#ifndef NPRFX_INTERNAL_PAM_H
#define NPRFX_INTERNAL_PAM_H

#include <stdint.h>

#include "nprfx/pam.h"

/* A packed float image with c channels per pixel, rows top first. */
typedef struct internal_pam_img {
    int w, h, c;
    float *px;
} internal_pam_img;

nprfx_result internal_pam_img_alloc(nprfx_context *ctx, int w, int h, int c, internal_pam_img *out);
void internal_pam_img_free(internal_pam_img *im);
static inline float *internal_pam_px(const internal_pam_img *im, int x, int y)
{
    return im->px + ((size_t)y * (size_t)im->w + (size_t)x) * (size_t)im->c;
}

/* RGB of the first three channels of a view, packed. */
nprfx_result internal_pam_from_view(nprfx_context *ctx, const nprfx_image *v,
                                    internal_pam_img *out);
/* The stroke direction (degrees in [0, 180)) and coherence of a packed RGB image. */
void internal_pam_orientation(const internal_pam_img *im, double *degrees, double *coherence);
/* The largest centred square of src rotated by `degrees` (bilinear), so that a direction at angle
 * a in src lies at a + degrees in out. */
nprfx_result internal_pam_rotate(nprfx_context *ctx, const internal_pam_img *src, double degrees,
                                 internal_pam_img *out);
/* One level down the Gaussian pyramid: the 5-tap binomial filter [1 4 6 4 1]/16 (edges clamped),
 * then every second pixel (Burt & Adelson 1983). */
nprfx_result internal_pam_reduce(nprfx_context *ctx, const internal_pam_img *src,
                                 internal_pam_img *out);
/* The CSS features of §4.2 (2 channels): F, the gradient magnitude (Sobel) of the luma smoothed by
 * the binomial filter, and H, the hue (atan2(V, U)); each normalised to zero mean and unit
 * standard deviation over the image (Eq. 2), so samples of different tone compare. */
nprfx_result internal_pam_features(nprfx_context *ctx, const internal_pam_img *rgb,
                                   internal_pam_img *out);

/* ---- the CSS (Eq. 1, 3) ---- */

/* Links of one patch: block positions (top-left) in B, best first. */
typedef struct internal_pam_links {
    int n;
    int x[32], y[32];
    double s[32];
} internal_pam_links;
#define INTERNAL_PAM_MAX_LINKS 32

/* For each of np block positions (px[i], py[i]) of feature image fa, the links into fb: block
 * positions q of fb (block `b` pixels square) with S_css(p, q) <= (1 + tolerance) * min_q, at most
 * max_links, best first (ties: scan order). Runs over ctx's executor. */
nprfx_result internal_pam_css_links(nprfx_context *ctx, const internal_pam_img *fa,
                                    const internal_pam_img *fb, int b, const int *px, const int *py,
                                    int np, int max_links, double tolerance,
                                    internal_pam_links *out);

/* ---- one level of tile synthesis ---- */

/* The output map at one level: size n * tile, tiles of `tile` pixels, blocks of tile + overlap
 * pixels starting `overlap` pixels before their tile (wrapped, so the map tiles). */
typedef struct internal_pam_level {
    int n, tile, overlap, size;
    internal_pam_img out;  /* RGB */
    unsigned char *filled; /* size * size */
    int *qx, *qy;          /* n * n: the chosen block of each tile, in the source */
} internal_pam_level;

nprfx_result internal_pam_level_init(nprfx_context *ctx, int n, int tile, int overlap,
                                     internal_pam_level *lv);
void internal_pam_level_free(internal_pam_level *lv);

/* Overlap errors (Eq. 4: sum of squared RGB differences over the already filled pixels of the
 * block) of placing source blocks at (cx[i], cy[i]) on tile t; written to cost[i]. */
nprfx_result internal_pam_overlap_costs(nprfx_context *ctx, const internal_pam_level *lv,
                                        const internal_pam_img *src, int t, const int *cx,
                                        const int *cy, int nc, double *cost);
/* Paste the source block at (qx, qy) on tile t, cut along minimum-error seams (dynamic
 * programming, Efros & Freeman 2001) through each overlap strip that is already filled (left and
 * top; right and bottom across the wrap), cross-faded over two pixels at the cut, and record the
 * choice. */
nprfx_result internal_pam_paste(nprfx_context *ctx, internal_pam_level *lv,
                                const internal_pam_img *src, int t, int qx, int qy);

/* ---- the strip ---- */

/* Sort the K key maps (S x S RGB, packed) by mean Y, insert the in-between maps of Eq. 7-8 and
 * write the strip; info (when not NULL) flags the keys and holds every map's mean YUV. */
nprfx_result internal_pam_assemble(nprfx_context *ctx, const internal_pam_img *keys, int K,
                                   double k, nprfx_image *strip, nprfx_pam_info *info);

#endif
