/* Image metrics: statistics, FFT and power spectra, PSNR, SSIM, warp error along motion.
 *
 * Everything accumulates in double, in an order fixed by the image (rows top to bottom, pixels
 * left to right; parallel work keeps per-row partial results and sums them in row order), so a
 * metric does not depend on the executor either. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/filter.h"
#include "nprfx/metrics.h"

static const double two_pi = 6.283185307179586476925286766559;

static int channel_ok(const nprfx_image *im, int ch)
{
    return im && im->data && ch >= 0 && ch < im->channels;
}

static double value_at(const nprfx_image *im, int x, int y, int ch)
{
    return nprfx_image_at(im, x, y)[ch];
}

/* A pixel enters a masked measurement when there is no mask, or the mask covers it with > 0.5. */
static int mask_admits(const nprfx_image *mask, int x, int y)
{
    if (!mask || !mask->data) return 1;
    if (!nprfx_rect_contains(mask->bounds, x, y)) return 0;
    return nprfx_image_at(mask, x, y)[0] > 0.5f;
}

/* ---- statistics ---------------------------------------------------------------------------- */

nprfx_result nprfx_image_stats(nprfx_context *ctx, const nprfx_image *im, int channel,
                               const nprfx_image *mask, nprfx_stats *out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "image stats: NULL output");
    memset(out, 0, sizeof *out);
    if (!channel_ok(im, channel))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "image stats: no channel %d in the image",
                           channel);
    /* Two passes (mean, then squared deviations): exact enough for any offset of the data. */
    const nprfx_rect b = im->bounds;
    long long n = 0;
    double sum = 0.0, lo = INFINITY, hi = -INFINITY;
    for (int y = b.y0; y < b.y1; y++)
        for (int x = b.x0; x < b.x1; x++) {
            const double v = value_at(im, x, y, channel);
            if (!isfinite(v) || !mask_admits(mask, x, y)) continue;
            n++;
            sum += v;
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    if (n == 0) return NPRFX_OK; /* all zero, count 0 */
    const double mean = sum / (double)n;
    double ss = 0.0;
    for (int y = b.y0; y < b.y1; y++)
        for (int x = b.x0; x < b.x1; x++) {
            const double v = value_at(im, x, y, channel);
            if (!isfinite(v) || !mask_admits(mask, x, y)) continue;
            ss += (v - mean) * (v - mean);
        }
    out->mean = mean;
    out->variance = ss / (double)n;
    out->min = lo;
    out->max = hi;
    out->count = n;
    return NPRFX_OK;
}

/* ---- FFT ----------------------------------------------------------------------------------- */

static int is_pow2(int n)
{
    return n >= 1 && (n & (n - 1)) == 0;
}

/* cos and sin of 2 pi k / n for k < n/2, each computed directly (a recurrence would drift). */
static double *twiddles(int n)
{
    const int half = n / 2 > 0 ? n / 2 : 1;
    double *t = malloc(2 * (size_t)half * sizeof *t);
    if (!t) return NULL;
    for (int k = 0; k < half; k++) {
        t[2 * k] = cos(two_pi * k / n);
        t[2 * k + 1] = sin(two_pi * k / n);
    }
    return t;
}

/* Iterative radix-2 decimation in time: bit-reversal permutation, then log2(n) butterfly
 * stages. Forward uses exp(-2 pi i k / n). */
static void fft_run(const double *tw, double *re, double *im, int n, int inverse)
{
    for (int i = 1, j = 0; i < n; i++) {
        int bit = n >> 1;
        for (; j & bit; bit >>= 1)
            j ^= bit;
        j ^= bit;
        if (i < j) {
            double t = re[i];
            re[i] = re[j];
            re[j] = t;
            t = im[i];
            im[i] = im[j];
            im[j] = t;
        }
    }
    const double sign = inverse ? 1.0 : -1.0;
    for (int len = 2; len <= n; len <<= 1) {
        const int half = len / 2, step = n / len;
        for (int i = 0; i < n; i += len)
            for (int k = 0; k < half; k++) {
                const double wr = tw[2 * k * step], wi = sign * tw[2 * k * step + 1];
                const int a = i + k, b = a + half;
                const double tr = wr * re[b] - wi * im[b];
                const double ti = wr * im[b] + wi * re[b];
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
            }
    }
}

nprfx_result nprfx_fft(nprfx_context *ctx, double *re, double *im, int n, int inverse)
{
    if (!re || !im) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "fft: NULL array");
    if (!is_pow2(n))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "fft: length %d is not a power of two",
                           n);
    if (n == 1) return NPRFX_OK;
    double *tw = twiddles(n);
    if (!tw) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "fft: out of memory (n = %d)", n);
    fft_run(tw, re, im, n, inverse);
    free(tw);
    return NPRFX_OK;
}

/* ---- power spectra ------------------------------------------------------------------------- */

typedef struct fft2_job {
    const double *tw;
    double *re, *im; /* n x n, row-major */
    int n;
    double *scratch; /* 2n per worker */
} fft2_job;

static void fft2_rows(void *user, int begin, int end, int worker)
{
    const fft2_job *job = user;
    for (int r = begin; r < end; r++)
        fft_run(job->tw, job->re + (size_t)r * job->n, job->im + (size_t)r * job->n, job->n, 0);
}

static void fft2_cols(void *user, int begin, int end, int worker)
{
    const fft2_job *job = user;
    const int n = job->n;
    double *cr = job->scratch + 2 * (size_t)n * worker, *ci = cr + n;
    for (int c = begin; c < end; c++) {
        for (int r = 0; r < n; r++) {
            cr[r] = job->re[(size_t)r * n + c];
            ci[r] = job->im[(size_t)r * n + c];
        }
        fft_run(job->tw, cr, ci, n, 0);
        for (int r = 0; r < n; r++) {
            job->re[(size_t)r * n + c] = cr[r];
            job->im[(size_t)r * n + c] = ci[r];
        }
    }
}

/* Side of the analysed square: the largest power of two that fits in both dimensions. */
static int square_side(const nprfx_image *im)
{
    const int w = nprfx_rect_width(im->bounds), h = nprfx_rect_height(im->bounds);
    const int m = w < h ? w : h;
    int n = 1;
    while (n <= m / 2)
        n *= 2;
    return m >= 1 ? n : 0;
}

/* |F|^2 of the centred square, DC at (N/2, N/2), normalised by the window's energy
 * sum(w^2) so that white noise of variance v has expected power v at every frequency. */
static nprfx_result power_2d(nprfx_context *ctx, const nprfx_image *im, int channel, int n,
                             double *power, const char *what)
{
    const size_t nn = (size_t)n * n;
    double *re = malloc(nn * sizeof *re), *imag = calloc(nn, sizeof *imag);
    double *hann = malloc((size_t)n * sizeof *hann), *tw = twiddles(n);
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    int workers = nprfx_executor_workers(ex);
    if (workers < 1) workers = 1;
    double *scratch = malloc(2 * (size_t)n * workers * sizeof *scratch);
    if (!re || !imag || !hann || !tw || !scratch) {
        free(re);
        free(imag);
        free(hann);
        free(tw);
        free(scratch);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "%s: out of memory for %dx%d", what, n, n);
    }
    const int x0 = im->bounds.x0 + (nprfx_rect_width(im->bounds) - n) / 2;
    const int y0 = im->bounds.y0 + (nprfx_rect_height(im->bounds) - n) / 2;
    /* Mean over the finite values; non-finite ones enter as the mean (zero after removal). */
    double sum = 0.0;
    long long cnt = 0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            const double v = value_at(im, x0 + i, y0 + j, channel);
            if (isfinite(v)) sum += v, cnt++;
        }
    const double mean = cnt ? sum / (double)cnt : 0.0;
    /* Periodic Hann: the window of a length-n DFT frame. */
    double wsum = 0.0;
    for (int i = 0; i < n; i++) {
        hann[i] = 0.5 - 0.5 * cos(two_pi * i / n);
        wsum += hann[i] * hann[i];
    }
    const double energy = wsum * wsum; /* sum over the square of (w_i w_j)^2 */
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            const double v = value_at(im, x0 + i, y0 + j, channel);
            re[(size_t)j * n + i] = isfinite(v) ? (v - mean) * hann[i] * hann[j] : 0.0;
        }
    fft2_job job = {tw, re, imag, n, scratch};
    nprfx_parallel_for(ex, n, 8, fft2_rows, &job);
    nprfx_parallel_for(ex, n, 8, fft2_cols, &job);
    for (int ky = 0; ky < n; ky++)
        for (int kx = 0; kx < n; kx++) {
            const size_t s = (size_t)ky * n + kx;
            /* frequency index k maps to k (k < n/2) or k - n; shift so DC lands at n/2 */
            const int ox = (kx + n / 2) % n, oy = (ky + n / 2) % n;
            power[(size_t)oy * n + ox] = (re[s] * re[s] + imag[s] * imag[s]) / energy;
        }
    free(re);
    free(imag);
    free(hann);
    free(tw);
    free(scratch);
    return NPRFX_OK;
}

static nprfx_result spectrum_side(nprfx_context *ctx, const nprfx_image *im, int channel,
                                  const char *what, int *n)
{
    if (!channel_ok(im, channel))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "%s: no channel %d in the image", what,
                           channel);
    *n = square_side(im);
    if (*n < 2)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "%s: a %dx%d image holds no 2x2 square to analyse", what,
                           nprfx_rect_width(im->bounds), nprfx_rect_height(im->bounds));
    return NPRFX_OK;
}

nprfx_result nprfx_power_spectrum_2d(nprfx_context *ctx, const nprfx_image *im, int channel,
                                     double *power, int *n_out)
{
    int n = 0;
    nprfx_result r = spectrum_side(ctx, im, channel, "power spectrum", &n);
    if (r) return r;
    if (n_out) *n_out = n;
    if (!power) return NPRFX_OK;
    return power_2d(ctx, im, channel, n, power, "power spectrum");
}

nprfx_result nprfx_radial_spectrum(nprfx_context *ctx, const nprfx_image *im, int channel,
                                   double *out, int *nbins_out)
{
    int n = 0;
    nprfx_result r = spectrum_side(ctx, im, channel, "radial spectrum", &n);
    if (r) return r;
    const int nb = n / 2;
    if (nbins_out) *nbins_out = nb;
    if (!out) return NPRFX_OK;
    double *power = malloc((size_t)n * n * sizeof *power);
    long long *count = calloc((size_t)nb, sizeof *count);
    if (!power || !count) {
        free(power);
        free(count);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "radial spectrum: out of memory");
    }
    r = power_2d(ctx, im, channel, n, power, "radial spectrum");
    if (r == NPRFX_OK) {
        for (int k = 0; k < nb; k++)
            out[k] = 0.0;
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                const double fx = i - n / 2, fy = j - n / 2;
                const int k = (int)floor(sqrt(fx * fx + fy * fy) + 0.5); /* nearest ring */
                if (k >= nb) continue;
                out[k] += power[(size_t)j * n + i];
                count[k]++;
            }
        for (int k = 0; k < nb; k++)
            out[k] = count[k] ? out[k] / (double)count[k] : 0.0;
    }
    free(power);
    free(count);
    return r;
}

/* ---- PSNR and SSIM ------------------------------------------------------------------------- */

static nprfx_result pair_check(nprfx_context *ctx, const nprfx_image *a, int ch_a,
                               const nprfx_image *b, int ch_b, double peak, const char *what,
                               nprfx_rect *common)
{
    if (!channel_ok(a, ch_a) || !channel_ok(b, ch_b))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "%s: no channel %d in the %s image", what,
                           channel_ok(a, ch_a) ? ch_b : ch_a,
                           channel_ok(a, ch_a) ? "second" : "first");
    if (!(peak > 0.0) || !isfinite(peak))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: peak %g is not positive", what,
                           peak);
    *common = nprfx_rect_intersect(a->bounds, b->bounds);
    if (nprfx_rect_empty(*common))
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH, "%s: the images do not overlap", what);
    return NPRFX_OK;
}

nprfx_result nprfx_psnr(nprfx_context *ctx, const nprfx_image *a, int ch_a, const nprfx_image *b,
                        int ch_b, double peak, double *out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "psnr: NULL output");
    nprfx_rect r;
    nprfx_result res = pair_check(ctx, a, ch_a, b, ch_b, peak, "psnr", &r);
    if (res) return res;
    /* Non-finite values are not skipped: a NaN or inf difference makes the PSNR NaN or -inf,
     * which is what such a comparison should report. */
    double se = 0.0;
    for (int y = r.y0; y < r.y1; y++)
        for (int x = r.x0; x < r.x1; x++) {
            const double d = value_at(a, x, y, ch_a) - value_at(b, x, y, ch_b);
            se += d * d;
        }
    const double mse = se / ((double)nprfx_rect_width(r) * nprfx_rect_height(r));
    *out = mse == 0.0 ? INFINITY : 10.0 * log10(peak * peak / mse);
    return NPRFX_OK;
}

#define SSIM_RADIUS 5 /* 11 x 11 window */
#define SSIM_BAND 32  /* output rows per block of horizontal sums */

typedef struct ssim_job {
    const nprfx_image *a, *b;
    int ch_a, ch_b;
    nprfx_rect r; /* common bounds */
    int ow;       /* output columns: width - 10 */
    double g[2 * SSIM_RADIUS + 1];
    double c1, c2;
    double *rowsum; /* per output row */
    double *scratch;
    size_t scratch_len; /* doubles per worker */
} ssim_job;

/* Output rows [begin, end): windows fully inside the common bounds (Wang et al.'s 'valid'). */
static void ssim_rows(void *user, int begin, int end, int worker)
{
    const ssim_job *job = user;
    const int ow = job->ow, K = 2 * SSIM_RADIUS + 1;
    const size_t plane = (size_t)(SSIM_BAND + 2 * SSIM_RADIUS) * ow;
    double *h = job->scratch + job->scratch_len * worker; /* 5 planes: a, b, aa, bb, ab */
    for (int j0 = begin; j0 < end; j0 += SSIM_BAND) {
        const int j1 = j0 + SSIM_BAND < end ? j0 + SSIM_BAND : end;
        const int rows = j1 - j0 + 2 * SSIM_RADIUS;
        /* Horizontal sums of the input rows the band's windows cover. */
        for (int r = 0; r < rows; r++) {
            const int y = job->r.y0 + j0 + r;
            const float *pa = nprfx_image_at(job->a, job->r.x0, y) + job->ch_a;
            const float *pb = nprfx_image_at(job->b, job->r.x0, y) + job->ch_b;
            for (int x = 0; x < ow; x++) {
                double s[5] = {0, 0, 0, 0, 0};
                for (int k = 0; k < K; k++) {
                    const double va = pa[(ptrdiff_t)(x + k) * job->a->pixel_stride];
                    const double vb = pb[(ptrdiff_t)(x + k) * job->b->pixel_stride];
                    const double g = job->g[k];
                    s[0] += g * va;
                    s[1] += g * vb;
                    s[2] += g * va * va;
                    s[3] += g * vb * vb;
                    s[4] += g * va * vb;
                }
                for (int p = 0; p < 5; p++)
                    h[p * plane + (size_t)r * ow + x] = s[p];
            }
        }
        for (int j = j0; j < j1; j++) {
            double total = 0.0;
            for (int x = 0; x < ow; x++) {
                double s[5] = {0, 0, 0, 0, 0};
                for (int k = 0; k < K; k++)
                    for (int p = 0; p < 5; p++)
                        s[p] += job->g[k] * h[p * plane + (size_t)(j - j0 + k) * ow + x];
                const double ma = s[0], mb = s[1];
                const double va = s[2] - ma * ma, vb = s[3] - mb * mb, cov = s[4] - ma * mb;
                total += ((2.0 * ma * mb + job->c1) * (2.0 * cov + job->c2)) /
                         ((ma * ma + mb * mb + job->c1) * (va + vb + job->c2));
            }
            job->rowsum[j] = total;
        }
    }
}

nprfx_result nprfx_ssim(nprfx_context *ctx, const nprfx_image *a, int ch_a, const nprfx_image *b,
                        int ch_b, double peak, double *out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "ssim: NULL output");
    ssim_job job;
    memset(&job, 0, sizeof job);
    nprfx_result res = pair_check(ctx, a, ch_a, b, ch_b, peak, "ssim", &job.r);
    if (res) return res;
    const int w = nprfx_rect_width(job.r), h = nprfx_rect_height(job.r);
    const int K = 2 * SSIM_RADIUS + 1;
    if (w < K || h < K)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "ssim: the common area %dx%d is smaller than the 11x11 window", w, h);
    job.a = a;
    job.b = b;
    job.ch_a = ch_a;
    job.ch_b = ch_b;
    job.ow = w - 2 * SSIM_RADIUS;
    const int oh = h - 2 * SSIM_RADIUS;
    double gs = 0.0;
    for (int k = 0; k < K; k++) {
        const double d = k - SSIM_RADIUS;
        job.g[k] = exp(-d * d / (2.0 * 1.5 * 1.5));
        gs += job.g[k];
    }
    for (int k = 0; k < K; k++)
        job.g[k] /= gs;
    job.c1 = (0.01 * peak) * (0.01 * peak);
    job.c2 = (0.03 * peak) * (0.03 * peak);
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    int workers = nprfx_executor_workers(ex);
    if (workers < 1) workers = 1;
    job.scratch_len = 5 * (size_t)(SSIM_BAND + 2 * SSIM_RADIUS) * job.ow;
    job.scratch = malloc(job.scratch_len * workers * sizeof(double));
    job.rowsum = malloc((size_t)oh * sizeof(double));
    if (!job.scratch || !job.rowsum) {
        free(job.scratch);
        free(job.rowsum);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "ssim: out of memory for %dx%d", w, h);
    }
    nprfx_parallel_for(ex, oh, SSIM_BAND, ssim_rows, &job);
    double total = 0.0;
    for (int j = 0; j < oh; j++)
        total += job.rowsum[j];
    *out = total / ((double)oh * job.ow);
    free(job.scratch);
    free(job.rowsum);
    return NPRFX_OK;
}

/* ---- warp error ---------------------------------------------------------------------------- */

nprfx_result nprfx_warp_compare(nprfx_context *ctx, const nprfx_image *cur, const nprfx_image *prev,
                                int ch, const nprfx_image *motion_prev, const nprfx_image *mask,
                                nprfx_warp_error *out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "warp compare: NULL output");
    memset(out, 0, sizeof *out);
    if (!channel_ok(cur, ch) || !channel_ok(prev, ch))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "warp compare: no channel %d in the %s frame", ch,
                           channel_ok(cur, ch) ? "previous" : "current");
    if (!motion_prev || !motion_prev->data || motion_prev->channels < 2)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "warp compare: the motion field needs 2 channels");
    const nprfx_image pv = nprfx_image_channels(prev, ch, 1);
    const nprfx_rect pb = prev->bounds;
    /* Streaming means and co-moments (Welford): one pass, no cancellation. */
    long long n = 0;
    double mc = 0.0, mw = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0, se = 0.0;
    for (int y = cur->bounds.y0; y < cur->bounds.y1; y++)
        for (int x = cur->bounds.x0; x < cur->bounds.x1; x++) {
            if (!nprfx_rect_contains(motion_prev->bounds, x, y) || !mask_admits(mask, x, y))
                continue;
            const float *m = nprfx_image_at(motion_prev, x, y);
            const double qx = x + (double)m[0], qy = y + (double)m[1];
            /* Inside prev: every bilinear tap is a real pixel. */
            if (!(qx >= pb.x0 && qx <= pb.x1 - 1 && qy >= pb.y0 && qy <= pb.y1 - 1)) continue;
            float wv;
            nprfx_sample_bilinear(&pv, qx, qy, NPRFX_BORDER_CLAMP, &wv);
            const double c = value_at(cur, x, y, ch), w = wv;
            if (!isfinite(c) || !isfinite(w)) continue;
            n++;
            const double dc = c - mc, dw = w - mw;
            mc += dc / (double)n;
            mw += dw / (double)n;
            sxx += dc * (c - mc);
            syy += dw * (w - mw);
            sxy += dc * (w - mw);
            se += (c - w) * (c - w);
        }
    out->count = n;
    if (n == 0) {
        out->rms = 0.0;
        out->correlation = NAN;
        return NPRFX_OK;
    }
    out->rms = sqrt(se / (double)n);
    /* Undefined (NaN) when either side is constant. */
    out->correlation = sxx > 0.0 && syy > 0.0 ? sxy / sqrt(sxx * syy) : NAN;
    return NPRFX_OK;
}
