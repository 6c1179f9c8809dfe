/* Gaussian blur and point sampling: kernels against hand-computed values, boundary handling
 * against padded references, statistics of blurred noise against theory, and invariance of the
 * result under thread count, tiling and memory layout. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "nprfx/context.h"
#include "nprfx/filter.h"
#include "nprfx/metrics.h"
#include "nprfx/rng.h"

static const double pi = 3.14159265358979323846;

static nprfx_context *make_ctx(nprfx_pool *pool)
{
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.executor = pool ? nprfx_pool_executor(pool) : NULL;
    nprfx_context *ctx = NULL;
    nprfx_context_create(&init, &ctx);
    return ctx;
}

static void fill_noise(nprfx_image *im, uint64_t seed)
{
    for (int y = im->bounds.y0; y < im->bounds.y1; y++)
        for (int x = im->bounds.x0; x < im->bounds.x1; x++)
            for (int c = 0; c < im->channels; c++)
                nprfx_image_at(im, x, y)[c] = (float)nprfx_rand_gauss(seed, 0, x, y, c, 0);
}

/* Bitwise equality of two views over b (both must hold b). */
static int same_bits(const nprfx_image *a, const nprfx_image *b, nprfx_rect r)
{
    for (int y = r.y0; y < r.y1; y++)
        for (int x = r.x0; x < r.x1; x++)
            if (memcmp(nprfx_image_at(a, x, y), nprfx_image_at(b, x, y),
                       sizeof(float) * (size_t)a->channels) != 0)
                return 0;
    return 1;
}

static double max_abs_diff(const nprfx_image *a, const nprfx_image *b, nprfx_rect r)
{
    double m = 0.0;
    for (int y = r.y0; y < r.y1; y++)
        for (int x = r.x0; x < r.x1; x++)
            for (int c = 0; c < a->channels; c++) {
                double d = fabs((double)nprfx_image_at(a, x, y)[c] - nprfx_image_at(b, x, y)[c]);
                if (!(d <= m)) m = d; /* NaN wins */
            }
    return m;
}

/* The normalised sampled Gaussian truncated at ceil(4 sigma), as the kernel is specified. */
static double sampled_gauss(double sigma, int k)
{
    int r = (int)ceil(4.0 * sigma);
    if (k < -r || k > r) return 0.0;
    double s = 0.0;
    for (int i = -r; i <= r; i++)
        s += exp(-0.5 * i * i / (sigma * sigma));
    return exp(-0.5 * k * k / (sigma * sigma)) / s;
}

static void test_impulse_small_sigma(nprfx_context *ctx)
{
    nprfx_image im, out;
    CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(-20, -20, 21, 21), 2, &im));
    CHECK_OK(nprfx_image_alloc(ctx, im.bounds, 2, &out));
    nprfx_image_at(&im, 0, 0)[0] = 1.0f;
    nprfx_image_at(&im, 0, 0)[1] = -2.0f;
    CHECK_OK(nprfx_gaussian_blur(ctx, &im, &out, 1.0, NPRFX_BORDER_CLAMP));
    /* sigma 1, radius 4: the centre tap is 1 / sum_{k=-4..4} exp(-k^2/2) = 1 / 2.5066208042,
     * the 2D centre its square; the next pixel exp(-1/2) times that. */
    CHECK_NEAR(nprfx_image_at(&out, 0, 0)[0], 0.1591558917, 1e-7);
    CHECK_NEAR(nprfx_image_at(&out, 1, 0)[0], 0.0965329280, 1e-7);
    double worst = 0.0, total = 0.0;
    for (int y = -20; y <= 20; y++)
        for (int x = -20; x <= 20; x++) {
            double want = sampled_gauss(1.0, x) * sampled_gauss(1.0, y);
            worst = fmax(worst, fabs(nprfx_image_at(&out, x, y)[0] - want));
            worst = fmax(worst, fabs(nprfx_image_at(&out, x, y)[1] + 2.0 * want));
            total += nprfx_image_at(&out, x, y)[0];
        }
    CHECK(worst < 1e-7);
    CHECK_NEAR(total, 1.0, 1e-6);

    /* Just below the recursive filter's threshold, off-centre and asymmetric in x and y. */
    memset(im.data, 0, sizeof(float) * 41 * 41 * 2);
    nprfx_image_at(&im, 3, -2)[0] = 1.0f;
    CHECK_OK(nprfx_gaussian_blur(ctx, &im, &out, 2.9, NPRFX_BORDER_BLACK));
    worst = 0.0;
    for (int y = -20; y <= 20; y++)
        for (int x = -20; x <= 20; x++) {
            double want = sampled_gauss(2.9, x - 3) * sampled_gauss(2.9, y + 2);
            worst = fmax(worst, fabs(nprfx_image_at(&out, x, y)[0] - want));
        }
    CHECK(worst < 1e-7);
    nprfx_image_free(&im);
    nprfx_image_free(&out);
}

/* One row of n pixels (1 channel); the vertical pass of a single clamped row is the identity. */
static void impulse_moments(nprfx_context *ctx, double sigma, double *mass, double *mean,
                            double *var, double *peak_err)
{
    const int n = (int)(24 * sigma) | 1, c = n / 2;
    nprfx_image im, out;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, 1), 1, &im);
    nprfx_image_alloc(ctx, im.bounds, 1, &out);
    im.data[c] = 1.0f;
    CHECK_OK(nprfx_gaussian_blur(ctx, &im, &out, sigma, NPRFX_BORDER_CLAMP));
    double m0 = 0, m1 = 0, m2 = 0, err = 0;
    for (int x = 0; x < n; x++) {
        double v = out.data[x], d = x - c;
        m0 += v;
        m1 += v * d;
        m2 += v * d * d;
        double g = exp(-0.5 * d * d / (sigma * sigma)) / (sqrt(2 * pi) * sigma);
        err = fmax(err, fabs(v - g));
    }
    *mass = m0;
    *mean = m1 / m0;
    *var = m2 / m0 - (*mean) * (*mean);
    *peak_err = err * sqrt(2 * pi) * sigma; /* relative to the Gaussian's peak */
    nprfx_image_free(&im);
    nprfx_image_free(&out);
}

static void test_impulse_large_sigma(nprfx_context *ctx)
{
    const double sigmas[] = {3.0, 5.0, 12.5, 40.0};
    for (int i = 0; i < 4; i++) {
        double s = sigmas[i], mass, mean, var, perr;
        impulse_moments(ctx, s, &mass, &mean, &var, &perr);
        CHECK_NEAR(mass, 1.0, 1e-4);
        CHECK_NEAR(mean, 0.0, 1e-3 * s);
        CHECK_NEAR(var / (s * s), 1.0, 0.02); /* Deriche's fit: within 0.5% */
        CHECK(perr < 2e-3);                   /* and within 5e-4 of the peak pointwise */
    }
    /* 2D: the separable response is the product of the 1D ones. */
    nprfx_image im, out;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 121, 121), 1, &im);
    nprfx_image_alloc(ctx, im.bounds, 1, &out);
    nprfx_image_at(&im, 60, 60)[0] = 1.0f;
    CHECK_OK(nprfx_gaussian_blur(ctx, &im, &out, 5.0, NPRFX_BORDER_BLACK));
    double m0 = 0, mxx = 0, myy = 0, mxy = 0;
    for (int y = 0; y < 121; y++)
        for (int x = 0; x < 121; x++) {
            double v = nprfx_image_at(&out, x, y)[0];
            m0 += v;
            mxx += v * (x - 60) * (x - 60);
            myy += v * (y - 60) * (y - 60);
            mxy += v * (x - 60) * (y - 60);
        }
    CHECK_NEAR(m0, 1.0, 1e-4);
    CHECK_NEAR(mxx / m0, 25.0, 0.5);
    CHECK_NEAR(myy / m0, 25.0, 0.5);
    CHECK_NEAR(mxy / m0, 0.0, 1e-3);
    CHECK_NEAR(nprfx_image_at(&out, 60, 60)[0], 1.0 / (2 * pi * 25.0), 2e-3 / (2 * pi * 25.0));
    nprfx_image_free(&im);
    nprfx_image_free(&out);
}

static void test_constant(nprfx_context *ctx)
{
    const float value[3] = {0.25f, -3.0f, 100.0f};
    nprfx_image im, out;
    nprfx_image_alloc(ctx, nprfx_rect_make(10, 5, 74, 53), 3, &im);
    nprfx_image_fill(&im, value);
    /* dst reaches 30 pixels beyond src on every side: CLAMP continues the constant there. */
    nprfx_image_alloc(ctx, nprfx_rect_make(-20, -25, 104, 83), 3, &out);
    const double sigmas[] = {0.0, 0.6, 1.7, 3.0, 7.5, 31.0};
    for (int i = 0; i < 6; i++) {
        CHECK_OK(nprfx_gaussian_blur(ctx, &im, &out, sigmas[i], NPRFX_BORDER_CLAMP));
        double worst = 0.0;
        for (int y = out.bounds.y0; y < out.bounds.y1; y++)
            for (int x = out.bounds.x0; x < out.bounds.x1; x++)
                for (int c = 0; c < 3; c++)
                    worst = fmax(worst,
                                 fabs(nprfx_image_at(&out, x, y)[c] - value[c]) / fabs(value[c]));
        CHECK(worst < 1e-6);
    }
    /* BLACK: the corner of a large constant image sees a quarter of the plane plus half of the
     * centre lines: (sum_{k <= 0} g_k)^2 = (1/2 + g_0/2)^2. */
    nprfx_image one, o1;
    const float v1 = 1.0f;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 200, 200), 1, &one);
    nprfx_image_alloc(ctx, one.bounds, 1, &o1);
    nprfx_image_fill(&one, &v1);
    CHECK_OK(nprfx_gaussian_blur(ctx, &one, &o1, 2.0, NPRFX_BORDER_BLACK));
    double h = 0.5 + 0.5 * sampled_gauss(2.0, 0);
    CHECK_NEAR(nprfx_image_at(&o1, 0, 0)[0], h * h, 1e-6);
    CHECK_NEAR(nprfx_image_at(&o1, 100, 0)[0], h, 1e-6);
    CHECK_NEAR(nprfx_image_at(&o1, 100, 100)[0], 1.0, 1e-6);
    CHECK_OK(nprfx_gaussian_blur(ctx, &one, &o1, 6.0, NPRFX_BORDER_BLACK));
    h = 0.5 + 0.5 / (sqrt(2 * pi) * 6.0);
    CHECK_NEAR(nprfx_image_at(&o1, 0, 0)[0], h * h, 1e-3);
    CHECK_NEAR(nprfx_image_at(&o1, 100, 199)[0], h, 1e-3);
    CHECK_NEAR(nprfx_image_at(&o1, 100, 100)[0], 1.0, 1e-5);
    /* one sigma in: Phi(1) = 0.841345 of the kernel falls inside */
    CHECK_NEAR(nprfx_image_at(&o1, 100, 6)[0], 0.841345 + 0.5 / (sqrt(2 * pi) * 6.0) * 0.60653,
               2e-3);
    nprfx_image_free(&one);
    nprfx_image_free(&o1);
    nprfx_image_free(&im);
    nprfx_image_free(&out);
}

/* The recursion's end conditions against a line explicitly padded with what the border rule
 * puts there: they must agree to float precision, inside src and beyond it. */
static void test_recursive_boundaries(nprfx_context *ctx)
{
    const int n = 50, pad = 400;
    const double sigma = 9.0;
    for (int border = 0; border < 2; border++) {
        nprfx_image s, sp, o, op;
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, 1), 1, &s);
        nprfx_image_alloc(ctx, nprfx_rect_make(-pad, 0, n + pad, 1), 1, &sp);
        fill_noise(&s, 7);
        for (int x = -pad; x < n + pad; x++) {
            int xc = x < 0 ? 0 : x >= n ? n - 1 : x;
            int outside = x != xc;
            nprfx_image_at(&sp, x, 0)[0] =
                border == NPRFX_BORDER_BLACK && outside ? 0.0f : nprfx_image_at(&s, xc, 0)[0];
        }
        /* dst reaches 40 pixels past both ends of s */
        nprfx_image_alloc(ctx, nprfx_rect_make(-40, 0, n + 40, 1), 1, &o);
        nprfx_image_alloc(ctx, o.bounds, 1, &op);
        CHECK_OK(nprfx_gaussian_blur(ctx, &s, &o, sigma, (nprfx_border)border));
        CHECK_OK(nprfx_gaussian_blur(ctx, &sp, &op, sigma, (nprfx_border)border));
        CHECK(max_abs_diff(&o, &op, o.bounds) < 2e-6);
        nprfx_image_free(&s);
        nprfx_image_free(&sp);
        nprfx_image_free(&o);
        nprfx_image_free(&op);
    }
}

/* Recursive against a direct convolution with the (untruncated) Gaussian, in 2D, CLAMP. */
static void test_recursive_vs_direct(nprfx_context *ctx)
{
    const int w = 40, h = 30;
    const double sigma = 4.0;
    const int r = 40;
    nprfx_image s, o;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, w, h), 1, &s);
    nprfx_image_alloc(ctx, s.bounds, 1, &o);
    fill_noise(&s, 11);
    CHECK_OK(nprfx_gaussian_blur(ctx, &s, &o, sigma, NPRFX_BORDER_CLAMP));
    double g[2 * 40 + 1], gs = 0;
    for (int k = -r; k <= r; k++)
        gs += g[k + r] = exp(-0.5 * k * k / (sigma * sigma));
    double worst = 0.0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double acc = 0;
            for (int j = -r; j <= r; j++)
                for (int i = -r; i <= r; i++) {
                    int xx = x + i < 0 ? 0 : x + i >= w ? w - 1 : x + i;
                    int yy = y + j < 0 ? 0 : y + j >= h ? h - 1 : y + j;
                    acc += g[i + r] * g[j + r] * nprfx_image_at(&s, xx, yy)[0];
                }
            worst = fmax(worst, fabs(acc / (gs * gs) - nprfx_image_at(&o, x, y)[0]));
        }
    /* unit-variance noise, blurred std ~ 1/(2 sqrt(pi) sigma) = 0.07 */
    CHECK(worst < 2e-3);
    nprfx_image_free(&s);
    nprfx_image_free(&o);
}

/* Blurred unit white noise has variance sum g^2 = 1 / (4 pi sigma^2) (2D). */
static void test_noise_variance(nprfx_context *ctx)
{
    const double sigmas[] = {2.0, 4.0};
    const int sizes[] = {512, 1024};
    for (int i = 0; i < 2; i++) {
        const double s = sigmas[i];
        const int n = sizes[i];
        nprfx_image im, out;
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, n, n), 1, &im);
        nprfx_image_alloc(ctx, im.bounds, 1, &out);
        fill_noise(&im, 1234 + i);
        CHECK_OK(nprfx_gaussian_blur(ctx, &im, &out, s, NPRFX_BORDER_CLAMP));
        const int m = (int)ceil(5 * s); /* away from the clamped edges */
        nprfx_image inner = nprfx_image_crop(&out, nprfx_rect_make(m, m, n - m, n - m));
        nprfx_stats st;
        CHECK_OK(nprfx_image_stats(ctx, &inner, 0, NULL, &st));
        CHECK_NEAR(st.variance * 4 * pi * s * s, 1.0, 0.05);
        CHECK_NEAR(st.mean, 0.0, 0.01);
        nprfx_image_free(&im);
        nprfx_image_free(&out);
    }
}

/* The result must not depend on threads, tiles or the source's memory layout. */
static void test_invariance(void)
{
    nprfx_pool *p1 = NULL, *p4 = NULL;
    CHECK_OK(nprfx_pool_create(1, &p1));
    CHECK_OK(nprfx_pool_create(4, &p4));
    nprfx_context *c1 = make_ctx(p1), *c4 = make_ctx(p4);
    const nprfx_rect sb = nprfx_rect_make(3, -7, 100, 76); /* 97 x 83 */
    nprfx_image src, flipped;
    nprfx_image_alloc(c1, sb, 3, &src);
    fill_noise(&src, 99);
    /* The same pixels stored bottom-up: a negative row stride, as OFX hosts hand out. */
    nprfx_image_alloc(c1, sb, 3, &flipped);
    float *flipped_base = flipped.data;
    flipped.data = nprfx_image_at(&flipped, sb.x0, sb.y1 - 1);
    flipped.row_stride = -flipped.row_stride;
    nprfx_image_copy(c1, &src, &flipped);

    const double sigmas[] = {0.8, 2.5, 3.0, 6.0, 20.0};
    /* whole output larger than the source: exercises the continuation outside it */
    const nprfx_rect whole = nprfx_rect_make(-10, -20, 113, 90);
    for (int b = 0; b < 2; b++)
        for (int si = 0; si < 5; si++) {
            const double s = sigmas[si];
            nprfx_image a, d, t;
            nprfx_image_alloc(c1, whole, 3, &a);
            nprfx_image_alloc(c1, whole, 3, &d);
            nprfx_image_alloc(c1, whole, 3, &t);
            CHECK_OK(nprfx_gaussian_blur(c1, &src, &a, s, (nprfx_border)b));
            CHECK_OK(nprfx_gaussian_blur(c4, &src, &d, s, (nprfx_border)b));
            CHECK(same_bits(&a, &d, whole));
            CHECK_OK(nprfx_gaussian_blur(c4, &flipped, &d, s, (nprfx_border)b));
            CHECK(same_bits(&a, &d, whole));
            /* tiles of several sizes, rendered in reverse order through the 4-thread pool */
            const int tiles[] = {16, 23, 64};
            for (int ti = 0; ti < 3; ti++) {
                memset(t.data, 0xff, sizeof(float) * 3 * 123 * 110); /* NaN everywhere */
                const int ts = tiles[ti];
                for (int y0 = whole.y1 - 1 - (whole.y1 - 1 - whole.y0) % ts; y0 >= whole.y0;
                     y0 -= ts)
                    for (int x0 = whole.x0; x0 < whole.x1; x0 += ts) {
                        nprfx_image tile =
                            nprfx_image_crop(&t, nprfx_rect_make(x0, y0, x0 + ts, y0 + ts));
                        CHECK_OK(nprfx_gaussian_blur(c4, &src, &tile, s, (nprfx_border)b));
                    }
                CHECK(same_bits(&a, &t, whole));
            }
            nprfx_image_free(&a);
            nprfx_image_free(&d);
            nprfx_image_free(&t);
        }
    /* dst with a padded pixel stride (channels of a 5-channel image) */
    nprfx_image wide, a3, ref;
    nprfx_image_alloc(c1, sb, 5, &wide);
    nprfx_image_alloc(c1, sb, 3, &ref);
    a3 = nprfx_image_channels(&wide, 1, 3);
    CHECK_OK(nprfx_gaussian_blur(c4, &src, &a3, 4.0, NPRFX_BORDER_CLAMP));
    CHECK_OK(nprfx_gaussian_blur(c1, &src, &ref, 4.0, NPRFX_BORDER_CLAMP));
    CHECK(same_bits(&a3, &ref, sb));
    CHECK(nprfx_image_at(&wide, 50, 50)[0] == 0.0f && nprfx_image_at(&wide, 50, 50)[4] == 0.0f);

    nprfx_image_free(&wide);
    nprfx_image_free(&ref);
    nprfx_image_free(&src);
    flipped.data = flipped_base;
    nprfx_image_free(&flipped);
    nprfx_context_destroy(c1);
    nprfx_context_destroy(c4);
    nprfx_pool_destroy(p1);
    nprfx_pool_destroy(p4);
}

static void test_blur_errors(nprfx_context *ctx)
{
    nprfx_image a, b, e;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 8, 8), 2, &a);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 8, 8), 3, &b);
    CHECK(nprfx_gaussian_blur(ctx, &a, &b, 1.0, NPRFX_BORDER_CLAMP) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "channels") != NULL);
    nprfx_image_free(&b);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 8, 8), 2, &b);
    CHECK(nprfx_gaussian_blur(ctx, &a, &b, -1.0, NPRFX_BORDER_CLAMP) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(nprfx_gaussian_blur(ctx, &a, &b, NAN, NPRFX_BORDER_CLAMP) == NPRFX_ERR_OUT_OF_RANGE);
    /* sigma 0 copies exactly, and an empty source gives zeros */
    fill_noise(&a, 3);
    CHECK_OK(nprfx_gaussian_blur(ctx, &a, &b, 0.0, NPRFX_BORDER_BLACK));
    CHECK(same_bits(&a, &b, a.bounds));
    e = nprfx_image_crop(&a, nprfx_rect_make(2, 2, 2, 2));
    CHECK_OK(nprfx_gaussian_blur(ctx, &e, &b, 5.0, NPRFX_BORDER_CLAMP));
    CHECK(nprfx_image_at(&b, 3, 3)[1] == 0.0f);
    /* a destination far from a BLACK source is zero */
    nprfx_image far;
    nprfx_image_alloc(ctx, nprfx_rect_make(100, 100, 104, 104), 2, &far);
    CHECK_OK(nprfx_gaussian_blur(ctx, &a, &far, 1.0, NPRFX_BORDER_BLACK));
    CHECK(nprfx_image_at(&far, 101, 101)[0] == 0.0f);
    CHECK_OK(nprfx_gaussian_blur(ctx, &a, &far, 1.0, NPRFX_BORDER_CLAMP));
    CHECK_NEAR(nprfx_image_at(&far, 101, 101)[0], nprfx_image_at(&a, 7, 7)[0], 1e-6);
    nprfx_image_free(&far);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
}

/* ---- sampling ------------------------------------------------------------------------------ */

static void test_sampling(nprfx_context *ctx)
{
    /* 6 x 5 pixels from (-1, -1), channel 0: x + 10 y (linear), channel 1: x * y */
    nprfx_image im;
    nprfx_image_alloc(ctx, nprfx_rect_make(-1, -1, 5, 4), 2, &im);
    for (int y = -1; y < 4; y++)
        for (int x = -1; x < 5; x++) {
            nprfx_image_at(&im, x, y)[0] = (float)(x + 10 * y);
            nprfx_image_at(&im, x, y)[1] = (float)(x * y);
        }
    float o[2];
    /* integer positions return pixels exactly, whatever the filter and border */
    for (int b = 0; b < 2; b++)
        for (int y = -1; y < 4; y++)
            for (int x = -1; x < 5; x++) {
                const float *p = nprfx_image_at(&im, x, y);
                nprfx_sample_nearest(&im, x, y, (nprfx_border)b, o);
                CHECK(o[0] == p[0] && o[1] == p[1]);
                nprfx_sample_bilinear(&im, x, y, (nprfx_border)b, o);
                CHECK(o[0] == p[0] && o[1] == p[1]);
                nprfx_sample_bicubic(&im, x, y, (nprfx_border)b, o);
                CHECK(o[0] == p[0] && o[1] == p[1]);
            }
    /* bilinear at a pixel corner: the mean of the four, (0 + 1 + 10 + 11) / 4 and (0+0+0+1)/4 */
    nprfx_sample_bilinear(&im, 0.5, 0.5, NPRFX_BORDER_CLAMP, o);
    CHECK_NEAR(o[0], 5.5, 1e-6);
    CHECK_NEAR(o[1], 0.25, 1e-6);
    /* x*y is bilinear: exact at any fraction, e.g. (1.25, 2.75) -> 3.4375 */
    nprfx_sample_bilinear(&im, 1.25, 2.75, NPRFX_BORDER_CLAMP, o);
    CHECK_NEAR(o[1], 3.4375, 1e-6);
    CHECK_NEAR(o[0], 1.25 + 27.5, 1e-5);
    /* Catmull-Rom reproduces linear and bilinear functions inside */
    nprfx_sample_bicubic(&im, 1.5, 1.5, NPRFX_BORDER_CLAMP, o);
    CHECK_NEAR(o[0], 16.5, 1e-5);
    CHECK_NEAR(o[1], 2.25, 1e-5);
    nprfx_sample_bicubic(&im, 2.3, 0.6, NPRFX_BORDER_CLAMP, o);
    CHECK_NEAR(o[0], 8.3, 1e-5);
    CHECK_NEAR(o[1], 1.38, 1e-5);
    /* nearest rounds to the closest centre, halves up */
    nprfx_sample_nearest(&im, 2.6, 1.4, NPRFX_BORDER_CLAMP, o);
    CHECK(o[0] == 13.0f);
    nprfx_sample_nearest(&im, 0.5, -0.5, NPRFX_BORDER_CLAMP, o);
    CHECK(o[0] == 1.0f);

    /* borders: half a pixel outside the left edge at row 2 (pixel (-1, 2) = 19) */
    nprfx_sample_bilinear(&im, -1.5, 2.0, NPRFX_BORDER_CLAMP, o);
    CHECK(o[0] == 19.0f);
    nprfx_sample_bilinear(&im, -1.5, 2.0, NPRFX_BORDER_BLACK, o);
    CHECK_NEAR(o[0], 9.5, 1e-6);
    nprfx_sample_nearest(&im, -1.6, 2.0, NPRFX_BORDER_BLACK, o);
    CHECK(o[0] == 0.0f);
    nprfx_sample_nearest(&im, 40.0, -40.0, NPRFX_BORDER_CLAMP, o);
    CHECK(o[0] == 4.0f - 10.0f); /* corner (4, -1) */
    nprfx_sample_bicubic(&im, 1e12, 1e12, NPRFX_BORDER_CLAMP, o);
    CHECK(o[0] == 34.0f); /* corner (4, 3) */
    nprfx_sample_bicubic(&im, -1e12, 2.0, NPRFX_BORDER_BLACK, o);
    CHECK(o[0] == 0.0f && o[1] == 0.0f);
    nprfx_sample_bilinear(&im, NAN, 1.0, NPRFX_BORDER_CLAMP, o);
    CHECK(o[0] == 0.0f);
    /* CLAMP bicubic at the edge of a linear ramp: taps beyond repeat the edge pixel. At x = -0.5
     * on row 0: taps at -2, -1, 0, 1 read -1, -1, 0, 1 with weights -1/16, 9/16, 9/16, -1/16 */
    nprfx_sample_bicubic(&im, -0.5, 0.0, NPRFX_BORDER_CLAMP, o);
    CHECK_NEAR(o[0], (1.0 - 9.0 + 0.0 - 1.0) / 16.0, 1e-6);
    nprfx_sample_bicubic(&im, -0.5, 0.0, NPRFX_BORDER_BLACK, o);
    CHECK_NEAR(o[0], (-9.0 + 0.0 - 1.0) / 16.0, 1e-6);

    /* the 1D hand example: [0 0 1 0 0] at 1.5 -> 9/16, at 1.25 -> w(t = .25) of tap +2:
     * (-3 t^3 + 4 t^2 + t) / 2 = 0.2265625 */
    nprfx_image line;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 5, 1), 1, &line);
    line.data[2] = 1.0f;
    nprfx_sample_bicubic(&line, 1.5, 0.0, NPRFX_BORDER_CLAMP, o);
    CHECK_NEAR(o[0], 0.5625, 1e-7);
    nprfx_sample_bicubic(&line, 1.25, 0.0, NPRFX_BORDER_CLAMP, o);
    CHECK_NEAR(o[0], 0.2265625, 1e-7);
    nprfx_sample_bicubic(&line, 3.5, 0.0, NPRFX_BORDER_CLAMP, o);
    CHECK_NEAR(o[0], -0.0625, 1e-7);
    /* an infinite neighbour is never read by a zero-weight tap */
    line.data[3] = INFINITY;
    nprfx_sample_bilinear(&line, 2.0, 0.0, NPRFX_BORDER_CLAMP, o);
    CHECK(o[0] == 1.0f);
    nprfx_sample_bicubic(&line, 2.0, 0.0, NPRFX_BORDER_CLAMP, o);
    CHECK(o[0] == 1.0f);
    nprfx_image_free(&line);

    /* bottom-up storage gives the same samples */
    nprfx_image flip;
    nprfx_image_alloc(ctx, im.bounds, 2, &flip);
    float *base = flip.data;
    flip.data = base + (ptrdiff_t)4 * flip.row_stride;
    flip.row_stride = -flip.row_stride;
    nprfx_image_copy(ctx, &im, &flip);
    float o2[2];
    nprfx_sample_bicubic(&im, 0.3, 1.7, NPRFX_BORDER_BLACK, o);
    nprfx_sample_bicubic(&flip, 0.3, 1.7, NPRFX_BORDER_BLACK, o2);
    CHECK(o[0] == o2[0] && o[1] == o2[1]);
    flip.data = base;
    nprfx_image_free(&flip);
    nprfx_image_free(&im);
}

int main(void)
{
    nprfx_context *ctx = make_ctx(NULL);
    test_impulse_small_sigma(ctx);
    test_impulse_large_sigma(ctx);
    test_constant(ctx);
    test_recursive_boundaries(ctx);
    test_recursive_vs_direct(ctx);
    test_noise_variance(ctx);
    test_invariance();
    test_blur_errors(ctx);
    test_sampling(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
