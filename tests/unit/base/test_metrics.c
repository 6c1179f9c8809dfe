/* Metrics: statistics, FFT, power spectra, PSNR, SSIM and warp error against hand-computed
 * values and known signals. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "nprfx/context.h"
#include "nprfx/metrics.h"
#include "nprfx/rng.h"

static const double two_pi = 6.283185307179586;

static void fill_noise(nprfx_image *im, int ch, uint64_t seed)
{
    for (int y = im->bounds.y0; y < im->bounds.y1; y++)
        for (int x = im->bounds.x0; x < im->bounds.x1; x++)
            nprfx_image_at(im, x, y)[ch] = (float)nprfx_rand_gauss(seed, 0, x, y, 0, 0);
}

static void test_stats(nprfx_context *ctx)
{
    nprfx_image im, mask;
    nprfx_image_alloc(ctx, nprfx_rect_make(5, 5, 7, 8), 2, &im);   /* 2 x 3 */
    nprfx_image_alloc(ctx, nprfx_rect_make(5, 5, 7, 7), 1, &mask); /* covers 2 rows only */
    const float v[6] = {1, 2, 3, 4, NAN, INFINITY};
    for (int i = 0; i < 6; i++)
        nprfx_image_at(&im, 5 + i % 2, 5 + i / 2)[1] = v[i];
    nprfx_stats s;
    /* finite values 1 2 3 4: mean 2.5, population variance 1.25 */
    CHECK_OK(nprfx_image_stats(ctx, &im, 1, NULL, &s));
    CHECK(s.count == 4);
    CHECK_NEAR(s.mean, 2.5, 1e-12);
    CHECK_NEAR(s.variance, 1.25, 1e-12);
    CHECK(s.min == 1.0 && s.max == 4.0);
    /* mask keeps 1, 3, 4 (0.5 itself is out; pixels outside the mask are out):
     * mean 8/3, variance ((5/3)^2 + (1/3)^2 + (4/3)^2) / 3 = 42/27 */
    const float mv[4] = {1.0f, 0.5f, 0.7f, 2.0f};
    for (int i = 0; i < 4; i++)
        nprfx_image_at(&mask, 5 + i % 2, 5 + i / 2)[0] = mv[i];
    CHECK_OK(nprfx_image_stats(ctx, &im, 1, &mask, &s));
    CHECK(s.count == 3);
    CHECK_NEAR(s.mean, 8.0 / 3.0, 1e-12);
    CHECK_NEAR(s.variance, 42.0 / 27.0, 1e-12);
    CHECK(s.min == 1.0 && s.max == 4.0);
    /* channel 0 is all zeros */
    CHECK_OK(nprfx_image_stats(ctx, &im, 0, NULL, &s));
    CHECK(s.count == 6 && s.mean == 0.0 && s.variance == 0.0);
    /* a large offset does not cost precision (two-pass) */
    nprfx_image big;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 100, 100), 1, &big);
    for (int i = 0; i < 10000; i++)
        big.data[i] = 1.0e4f + (i % 2 ? 0.5f : -0.5f);
    CHECK_OK(nprfx_image_stats(ctx, &big, 0, NULL, &s));
    CHECK_NEAR(s.variance, 0.25, 1e-9);
    CHECK(nprfx_image_stats(ctx, &im, 2, NULL, &s) == NPRFX_ERR_MISSING_INPUT);
    nprfx_image_free(&big);
    nprfx_image_free(&im);
    nprfx_image_free(&mask);
}

static void test_fft(nprfx_context *ctx)
{
    /* hand cases: delta -> ones; shifted delta -> exp(-2 pi i k / 4) = 1, -i, -1, i */
    double re[4] = {1, 0, 0, 0}, im[4] = {0, 0, 0, 0};
    CHECK_OK(nprfx_fft(ctx, re, im, 4, 0));
    for (int k = 0; k < 4; k++)
        CHECK(re[k] == 1.0 && im[k] == 0.0);
    double re2[4] = {0, 1, 0, 0}, im2[4] = {0, 0, 0, 0};
    CHECK_OK(nprfx_fft(ctx, re2, im2, 4, 0));
    const double er[4] = {1, 0, -1, 0}, ei[4] = {0, -1, 0, 1};
    for (int k = 0; k < 4; k++) {
        CHECK_NEAR(re2[k], er[k], 1e-15);
        CHECK_NEAR(im2[k], ei[k], 1e-15);
    }
    /* against a naive DFT, both directions, and the round trip */
    enum { N = 256 };
    static double xr[N], xi[N], fr[N], fi[N];
    for (int i = 0; i < N; i++) {
        xr[i] = fr[i] = nprfx_rand_gauss(5, 0, i, 0, 0, 0);
        xi[i] = fi[i] = nprfx_rand_gauss(5, 0, i, 0, 1, 0);
    }
    for (int inverse = 0; inverse < 2; inverse++) {
        memcpy(fr, xr, sizeof fr);
        memcpy(fi, xi, sizeof fi);
        CHECK_OK(nprfx_fft(ctx, fr, fi, N, inverse));
        double worst = 0.0;
        const double sign = inverse ? 1.0 : -1.0;
        for (int k = 0; k < N; k++) {
            double sr = 0, si = 0;
            for (int n = 0; n < N; n++) {
                double a = sign * two_pi * (double)((long)k * n % N) / N;
                sr += xr[n] * cos(a) - xi[n] * sin(a);
                si += xr[n] * sin(a) + xi[n] * cos(a);
            }
            worst = fmax(worst, fmax(fabs(sr - fr[k]), fabs(si - fi[k])));
        }
        CHECK(worst < 1e-11);
    }
    memcpy(fr, xr, sizeof fr);
    memcpy(fi, xi, sizeof fi);
    CHECK_OK(nprfx_fft(ctx, fr, fi, N, 0));
    CHECK_OK(nprfx_fft(ctx, fr, fi, N, 1));
    double worst = 0.0;
    for (int i = 0; i < N; i++)
        worst = fmax(worst, fmax(fabs(fr[i] / N - xr[i]), fabs(fi[i] / N - xi[i])));
    CHECK(worst < 1e-13);
    double one_r = 3.0, one_i = -1.0;
    CHECK_OK(nprfx_fft(ctx, &one_r, &one_i, 1, 0));
    CHECK(one_r == 3.0 && one_i == -1.0);
    CHECK(nprfx_fft(ctx, fr, fi, 12, 0) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(nprfx_fft(ctx, fr, fi, 0, 0) == NPRFX_ERR_INVALID_ARGUMENT);
}

static void test_spectra(nprfx_context *ctx)
{
    /* 150 x 140 pixels: the analysed square is the centred 128 x 128 one. A plane wave with
     * wave vector (12, 16) cycles per 128 pixels: radius 20, i.e. 20/128 cycles per pixel. */
    nprfx_image im;
    nprfx_image_alloc(ctx, nprfx_rect_make(-3, 7, 147, 147), 2, &im);
    for (int y = im.bounds.y0; y < im.bounds.y1; y++)
        for (int x = im.bounds.x0; x < im.bounds.x1; x++)
            nprfx_image_at(&im, x, y)[0] =
                (float)(0.3 + cos(two_pi * (12.0 * x + 16.0 * y) / 128.0 + 0.4));
    int nb = 0, n = 0;
    CHECK_OK(nprfx_radial_spectrum(ctx, &im, 0, NULL, &nb));
    CHECK(nb == 64);
    double radial[64];
    CHECK_OK(nprfx_radial_spectrum(ctx, &im, 0, radial, &nb));
    int peak = 0;
    for (int k = 1; k < nb; k++)
        if (radial[k] > radial[peak]) peak = k;
    CHECK(peak == 20);
    /* the Hann window spreads the line over +-1 bin only; far bins hold nothing */
    CHECK(radial[5] < 1e-12 * radial[20] && radial[40] < 1e-12 * radial[20]);
    CHECK(radial[0] < 1e-12 * radial[20]); /* the mean (0.3) was removed */

    CHECK_OK(nprfx_power_spectrum_2d(ctx, &im, 0, NULL, &n));
    CHECK(n == 128);
    static double power[128 * 128];
    CHECK_OK(nprfx_power_spectrum_2d(ctx, &im, 0, power, &n));
    int best = 0;
    for (int i = 1; i < n * n; i++)
        if (power[i] > power[best]) best = i;
    const int bx = best % n - n / 2, by = best / n - n / 2;
    CHECK((bx == 12 && by == 16) || (bx == -12 && by == -16));
    CHECK_NEAR(power[(64 + 16) * n + 64 + 12], power[(64 - 16) * n + 64 - 12], 1e-9 * power[best]);
    /* Power of a unit-amplitude wave: the Hann window's DFT has |W(0)| = sum w and the two
     * lines share the energy: |F(k0)|^2 = (A/2)^2 (sum w)^4, normalised by (sum w^2)^2;
     * for the periodic Hann sum w = N/2, sum w^2 = 3N/8: (1/4) (N/2)^4 / (3N/8)^2 = N^2/9. */
    CHECK_NEAR(power[best], 128.0 * 128.0 / 9.0, 1e-6 * 128 * 128);

    /* White noise of variance 1: flat at power 1 per frequency (the normalisation). */
    nprfx_image wn;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 256, 256), 1, &wn);
    fill_noise(&wn, 0, 77);
    double wr[128];
    CHECK_OK(nprfx_radial_spectrum(ctx, &wn, 0, wr, &nb));
    CHECK(nb == 128);
    double lo = 0, hi = 0;
    for (int k = 8; k < 40; k++)
        lo += wr[k] / 32;
    for (int k = 90; k < 122; k++)
        hi += wr[k] / 32;
    CHECK_NEAR(lo, 1.0, 0.1);
    CHECK_NEAR(hi, 1.0, 0.1);

    nprfx_image tiny = nprfx_image_crop(&wn, nprfx_rect_make(0, 0, 1, 5));
    CHECK(nprfx_radial_spectrum(ctx, &tiny, 0, NULL, &nb) == NPRFX_ERR_SIZE_MISMATCH);
    CHECK(nprfx_radial_spectrum(ctx, &wn, 1, NULL, &nb) == NPRFX_ERR_MISSING_INPUT);
    nprfx_image_free(&wn);
    nprfx_image_free(&im);
}

static void test_psnr_ssim(nprfx_context *ctx)
{
    nprfx_image a, b;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 4, 4), 1, &a);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 4, 4), 2, &b);
    const float half = 0.5f;
    nprfx_image_fill(&a, &half);
    for (int i = 0; i < 16; i++)
        b.data[2 * i + 1] = 0.5f;
    double v = 0;
    CHECK_OK(nprfx_psnr(ctx, &a, 0, &b, 1, 1.0, &v));
    CHECK(isinf(v) && v > 0);
    /* one pixel off by 0.4 of 16: MSE 0.01, PSNR 10 log10(1 / 0.01) = 20 dB; peak 2: +6.0206 */
    nprfx_image_at(&b, 2, 1)[1] = 0.9f;
    CHECK_OK(nprfx_psnr(ctx, &a, 0, &b, 1, 1.0, &v));
    CHECK_NEAR(v, 20.0, 1e-5);
    CHECK_OK(nprfx_psnr(ctx, &a, 0, &b, 1, 2.0, &v));
    CHECK_NEAR(v, 20.0 + 20.0 * log10(2.0), 1e-5);
    CHECK(nprfx_psnr(ctx, &a, 0, &b, 1, 0.0, &v) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(nprfx_psnr(ctx, &a, 1, &b, 1, 1.0, &v) == NPRFX_ERR_MISSING_INPUT);
    CHECK(nprfx_ssim(ctx, &a, 0, &b, 1, 1.0, &v) == NPRFX_ERR_SIZE_MISMATCH); /* < 11 x 11 */
    nprfx_image_free(&a);
    nprfx_image_free(&b);

    nprfx_image x, y;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 64, 48), 1, &x);
    nprfx_image_alloc(ctx, nprfx_rect_make(-5, 3, 70, 60), 2, &y);
    /* two constants c, d: SSIM = (2cd + C1) / (c^2 + d^2 + C1), C1 = (0.01)^2 */
    const float c = 0.5f, d[2] = {0.25f, 0.25f};
    nprfx_image_fill(&x, &c);
    nprfx_image_fill(&y, d);
    CHECK_OK(nprfx_ssim(ctx, &x, 0, &y, 1, 1.0, &v));
    CHECK_NEAR(v, (0.25 + 1e-4) / (0.3125 + 1e-4), 1e-9);
    /* an image against itself: exactly 1 */
    for (int j = 0; j < 48; j++)
        for (int i = 0; i < 64; i++)
            nprfx_image_at(&x, i, j)[0] = (float)(0.5 + 0.2 * sin(i * 0.3) * cos(j * 0.2));
    CHECK_OK(nprfx_ssim(ctx, &x, 0, &x, 0, 1.0, &v));
    CHECK_NEAR(v, 1.0, 1e-9);
    /* a noisy copy scores below 1, and more noise scores lower */
    double s1, s2;
    for (int j = 3; j < 48; j++)
        for (int i = 0; i < 64; i++)
            nprfx_image_at(&y, i, j)[1] =
                nprfx_image_at(&x, i, j)[0] + 0.02f * (float)nprfx_rand_gauss(3, 0, i, j, 0, 0);
    CHECK_OK(nprfx_ssim(ctx, &x, 0, &y, 1, 1.0, &s1));
    for (int j = 3; j < 48; j++)
        for (int i = 0; i < 64; i++)
            nprfx_image_at(&y, i, j)[1] =
                nprfx_image_at(&x, i, j)[0] + 0.1f * (float)nprfx_rand_gauss(3, 0, i, j, 0, 0);
    CHECK_OK(nprfx_ssim(ctx, &x, 0, &y, 1, 1.0, &s2));
    CHECK(s1 < 0.99 && s1 > 0.5);
    CHECK(s2 < s1);
    /* the same through a 3-thread pool */
    nprfx_pool *pool = NULL;
    CHECK_OK(nprfx_pool_create(3, &pool));
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.executor = nprfx_pool_executor(pool);
    nprfx_context *pc = NULL;
    CHECK_OK(nprfx_context_create(&init, &pc));
    double s3 = 0;
    CHECK_OK(nprfx_ssim(pc, &x, 0, &y, 1, 1.0, &s3));
    CHECK(s3 == s2);
    nprfx_context_destroy(pc);
    nprfx_pool_destroy(pool);
    nprfx_image_free(&x);
    nprfx_image_free(&y);
}

static void test_warp(nprfx_context *ctx)
{
    nprfx_image prev, cur, mo, mask;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 64, 64), 1, &prev);
    nprfx_image_alloc(ctx, prev.bounds, 1, &cur);
    nprfx_image_alloc(ctx, prev.bounds, 2, &mo);
    fill_noise(&prev, 0, 21);
    /* cur(p) = prev(p + (3, -2)): exact integer shift */
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            int sx = x + 3, sy = y - 2;
            nprfx_image_at(&cur, x, y)[0] =
                nprfx_rect_contains(prev.bounds, sx, sy) ? nprfx_image_at(&prev, sx, sy)[0] : 7.f;
            nprfx_image_at(&mo, x, y)[0] = 3.0f;
            nprfx_image_at(&mo, x, y)[1] = -2.0f;
        }
    nprfx_warp_error e;
    CHECK_OK(nprfx_warp_compare(ctx, &cur, &prev, 0, &mo, NULL, &e));
    CHECK(e.count == 61 * 62); /* x in [0, 61), y in [2, 64) land inside prev */
    CHECK(e.rms == 0.0);
    CHECK_NEAR(e.correlation, 1.0, 1e-12);
    /* a mask over the left half */
    nprfx_image_alloc(ctx, prev.bounds, 1, &mask);
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 32; x++)
            nprfx_image_at(&mask, x, y)[0] = 1.0f;
    CHECK_OK(nprfx_warp_compare(ctx, &cur, &prev, 0, &mo, &mask, &e));
    CHECK(e.count == 32 * 62);
    /* half-pixel motion: bilinear gives the mean of two neighbours */
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 63; x++) {
            nprfx_image_at(&cur, x, y)[0] =
                0.5f * (nprfx_image_at(&prev, x, y)[0] + nprfx_image_at(&prev, x + 1, y)[0]);
            nprfx_image_at(&mo, x, y)[0] = 0.5f;
            nprfx_image_at(&mo, x, y)[1] = 0.0f;
        }
    CHECK_OK(nprfx_warp_compare(ctx, &cur, &prev, 0, &mo, NULL, &e));
    CHECK(e.count == 63 * 64); /* x = 63 + 0.5 falls outside */
    CHECK(e.rms < 1e-6);
    CHECK_NEAR(e.correlation, 1.0, 1e-9);
    /* against unrelated noise (zero motion): correlation ~ 0, RMS ~ sqrt(2) */
    fill_noise(&cur, 0, 22);
    for (int i = 0; i < 64 * 64 * 2; i++)
        mo.data[i] = 0.0f;
    CHECK_OK(nprfx_warp_compare(ctx, &cur, &prev, 0, &mo, NULL, &e));
    CHECK(e.count == 64 * 64);
    CHECK(fabs(e.correlation) < 0.06);
    CHECK_NEAR(e.rms, sqrt(2.0), 0.1);
    /* cur = 2 prev + 1: correlation 1, RMS = rms of (prev + 1) */
    double ss = 0;
    for (int i = 0; i < 64 * 64; i++) {
        cur.data[i] = 2.0f * prev.data[i] + 1.0f;
        ss += (prev.data[i] + 1.0) * (prev.data[i] + 1.0);
    }
    CHECK_OK(nprfx_warp_compare(ctx, &cur, &prev, 0, &mo, NULL, &e));
    CHECK_NEAR(e.correlation, 1.0, 1e-9);
    CHECK_NEAR(e.rms, sqrt(ss / 4096), 1e-6);
    /* motion pointing entirely off-frame: nothing compared */
    for (int i = 0; i < 64 * 64; i++)
        mo.data[2 * i] = 100.0f;
    CHECK_OK(nprfx_warp_compare(ctx, &cur, &prev, 0, &mo, NULL, &e));
    CHECK(e.count == 0 && isnan(e.correlation));
    nprfx_image one = nprfx_image_channels(&mo, 0, 1);
    CHECK(nprfx_warp_compare(ctx, &cur, &prev, 0, &one, NULL, &e) == NPRFX_ERR_MISSING_INPUT);
    nprfx_image_free(&prev);
    nprfx_image_free(&cur);
    nprfx_image_free(&mo);
    nprfx_image_free(&mask);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_create(NULL, &ctx);
    test_stats(ctx);
    test_fft(ctx);
    test_spectra(ctx);
    test_psnr_ssim(ctx);
    test_warp(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
