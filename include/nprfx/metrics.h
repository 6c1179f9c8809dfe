/* nprfx — image metrics the tests and the `nprfx diff` command measure with. */
#ifndef NPRFX_METRICS_H
#define NPRFX_METRICS_H

#include "nprfx/image.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct nprfx_stats {
    double mean, variance; /* population variance */
    double min, max;
    long long count; /* pixels that entered the statistics */
} nprfx_stats;

/* Statistics of channel `channel` of im over its bounds; pixels where mask (1 channel, may be
 * NULL) is <= 0.5 are skipped. Non-finite values are skipped too. When no pixel enters, every
 * field is 0. */
NPRFX_API nprfx_result nprfx_image_stats(nprfx_context *ctx, const nprfx_image *im, int channel,
                                         const nprfx_image *mask, nprfx_stats *out);

/* In-place complex FFT of length n (a power of two); inverse = 1 for the inverse transform
 * (unnormalised). re/im are arrays of n doubles. */
NPRFX_API nprfx_result nprfx_fft(nprfx_context *ctx, double *re, double *im, int n, int inverse);

/* Radially averaged power spectrum of one channel. The largest centred power-of-two square that
 * fits in im->bounds is taken, its mean removed, a Hann window applied, and |F|^2 averaged over
 * rings of integer radius. out[k] for k in [0, nbins) is the mean power at radial frequency
 * k / N cycles per pixel (N = square size); *nbins_out = N / 2. `out` must hold N/2 doubles;
 * call with out = NULL to get nbins only. Power is |F|^2 / sum(window^2), so white noise of
 * variance v has power v at every frequency. Non-finite pixels enter as the mean. */
NPRFX_API nprfx_result nprfx_radial_spectrum(nprfx_context *ctx, const nprfx_image *im, int channel,
                                             double *out, int *nbins_out);

/* Full 2D power spectrum (N x N, DC at (N/2, N/2)) of the same square, for orientation tests.
 * power must hold N*N doubles; *n_out receives N (call with power = NULL to get N only). */
NPRFX_API nprfx_result nprfx_power_spectrum_2d(nprfx_context *ctx, const nprfx_image *im,
                                               int channel, double *power, int *n_out);

/* Peak signal-to-noise ratio in dB between a and b over channel ch of each, over their common
 * bounds, with peak value `peak` (1 for [0,1] images). Identical images give +INFINITY. */
NPRFX_API nprfx_result nprfx_psnr(nprfx_context *ctx, const nprfx_image *a, int ch_a,
                                  const nprfx_image *b, int ch_b, double peak, double *out);

/* Mean SSIM (Wang et al. 2004: 11x11 Gaussian window sigma 1.5, K1 0.01, K2 0.03, dynamic
 * range `peak`) between channel ch_a of a and ch_b of b over their common bounds: the mean over
 * the window positions that fit inside (needs at least 11x11 common pixels). */
NPRFX_API nprfx_result nprfx_ssim(nprfx_context *ctx, const nprfx_image *a, int ch_a,
                                  const nprfx_image *b, int ch_b, double peak, double *out);

/* Warp test along a motion field. For each pixel p of cur inside its bounds, with mask (may be
 * NULL) > 0.5, the previous frame is sampled bilinearly at p + motion_prev(p) (motion: 2
 * channels, pixels, docs/design.md §2); pixels whose source falls outside prev are skipped. Reports
 * the RMS difference and the Pearson correlation between cur and the warped prev (channel ch);
 * pixels with a non-finite value are skipped. correlation is NaN where undefined (no pixels, or
 * one side constant). */
typedef struct nprfx_warp_error {
    double rms;
    double correlation;
    long long count;
} nprfx_warp_error;
NPRFX_API nprfx_result nprfx_warp_compare(nprfx_context *ctx, const nprfx_image *cur,
                                          const nprfx_image *prev, int ch,
                                          const nprfx_image *motion_prev, const nprfx_image *mask,
                                          nprfx_warp_error *out);

/* Optical flow against ground truth (the flow node's accuracy, docs/design.md §3.15). Mean
 * endpoint error |est(p) - truth(p)| (2 channels each, pixels) over the pixels of est's bounds
 * inside truth's where `valid` (1 channel, may be NULL) is > 0.5 and all four values are finite;
 * *count: how many (0: *mean is 0). */
NPRFX_API nprfx_result nprfx_metric_epe(nprfx_context *ctx, const nprfx_image *est,
                                        const nprfx_image *truth, const nprfx_image *valid,
                                        double *mean, long long *count);

/* Which pixels of frame i were visible at frame i-1, from exact motion: pixel p with
 * q = round(p + motion_prev(p)) is visible when q lies in the previous frame's bounds, its id
 * there equals id(p) (when both ids are given) and |motion_prev(p) + motion_next_prev(q)| <=
 * tol pixels (the point comes back). motion_prev (2 channels) and id (1, may be NULL) are frame
 * i's; motion_next_prev and id_prev frame i-1's. visible (1 channel, bounds of motion_prev)
 * receives 1 or 0. Non-finite vectors are not visible. */
NPRFX_API nprfx_result nprfx_motion_visible(nprfx_context *ctx, const nprfx_image *motion_prev,
                                            const nprfx_image *id,
                                            const nprfx_image *motion_next_prev,
                                            const nprfx_image *id_prev, double tol,
                                            nprfx_image *visible);

#ifdef __cplusplus
}
#endif
#endif
