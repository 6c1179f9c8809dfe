/* The PAM builder (core/pam_*.c, docs/design.md §3.7): key maps tile seamlessly (the error across
 * the wrap is no larger than between neighbours inside), every key map's dominant stroke direction
 * is within 10 degrees of the first one's, the in-between count follows Eq. 7 and the blends are
 * Eq. 8 exactly, key maps follow the first one's layout better than independent synthesis,
 * results are the same bits for any thread count, and bad input is refused with clear errors. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "nprfx/exec.h"
#include "nprfx/pam.h"

#define N 128 /* samples; the maps are 64 x 64 with 16-pixel patches (the seam test: defaults) */

static nprfx_pam_build_params small_params(void)
{
    nprfx_pam_build_params p = NPRFX_PAM_BUILD_PARAMS_DEFAULT;
    p.map_size = 64;
    p.patch = 16;
    p.overlap = 4;
    p.levels = 3;
    return p;
}

/* Map m of a strip as a view. */
static nprfx_image map_view(const nprfx_image *strip, int m, int S)
{
    return nprfx_image_crop(strip, nprfx_rect_make(m * S, 0, (m + 1) * S, S));
}

static double sq(const float *a, const float *b)
{
    double s = 0;
    for (int c = 0; c < 3; c++)
        s += ((double)a[c] - b[c]) * ((double)a[c] - b[c]);
    return s;
}

/* Mean squared difference across each pair of adjacent columns (or rows) inside the map; the
 * worst of them, and the one across the wrap (last column against the first). A synthesised map
 * has seams inside; tileable means the wrap is no worse than they are. */
static void seam_errors(const nprfx_image *v, int vertical, double *inside, double *wrap)
{
    int S = nprfx_rect_height(v->bounds), x0 = v->bounds.x0;
    *inside = 0;
    for (int b = 0; b < S; b++) {
        double e = 0;
        for (int a = 0; a < S; a++) {
            int b1 = (b + 1) % S;
            e += vertical ? sq(nprfx_image_at(v, x0 + a, b), nprfx_image_at(v, x0 + a, b1))
                          : sq(nprfx_image_at(v, x0 + b, a), nprfx_image_at(v, x0 + b1, a));
        }
        e /= S;
        if (b == S - 1)
            *wrap = e;
        else if (e > *inside)
            *inside = e;
    }
}

/* Patch seams: the mean squared step between adjacent rows (vertical = 0: columns) that lie in the
 * overlap bands where blocks are cut, over the mean step between the other (interior) rows. The
 * strokes run along v, so steps between rows are small inside a stroke and large where a pasted
 * block chops one: a quilted map's boundary rows stand out. */
static double seam_ratio(const nprfx_image *v, int vertical, int patch, int overlap)
{
    int S = nprfx_rect_height(v->bounds), x0 = v->bounds.x0;
    double eb = 0, ei = 0;
    int nb = 0, ni = 0;
    for (int b = 0; b < S; b++) {
        /* The pair (b, b + 1) is in a band when b + 1 lies in [j * patch - overlap, j * patch]:
         * the cut and its feather stay inside the overlap, one pixel either side. */
        int r = (b + 1 + overlap) % patch;
        int band = r <= overlap;
        double e = 0;
        for (int a = 0; a < S; a++) {
            int b1 = (b + 1) % S;
            e += vertical ? sq(nprfx_image_at(v, x0 + b, a), nprfx_image_at(v, x0 + b1, a))
                          : sq(nprfx_image_at(v, x0 + a, b), nprfx_image_at(v, x0 + a, b1));
        }
        if (band) {
            eb += e;
            nb++;
        } else {
            ei += e;
            ni++;
        }
    }
    return (eb / nb) / (ei / ni);
}

/* Normalised correlation of the luma gradient magnitudes of two maps: how much their stroke
 * edges coincide (layout). */
static double edge_corr(const nprfx_image *a, const nprfx_image *b)
{
    int S = nprfx_rect_height(a->bounds);
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, n = 0;
    for (int y = 1; y + 1 < S; y++)
        for (int x = 1; x + 1 < S; x++) {
            double g[2];
            const nprfx_image *im[2] = {a, b};
            for (int k = 0; k < 2; k++) {
                float yl[3], yr[3], yu[3], yd[3];
                int x0 = im[k]->bounds.x0;
                nprfx_pam_rgb_to_yuv(nprfx_image_at(im[k], x0 + x - 1, y), yl);
                nprfx_pam_rgb_to_yuv(nprfx_image_at(im[k], x0 + x + 1, y), yr);
                nprfx_pam_rgb_to_yuv(nprfx_image_at(im[k], x0 + x, y - 1), yu);
                nprfx_pam_rgb_to_yuv(nprfx_image_at(im[k], x0 + x, y + 1), yd);
                g[k] = hypot(yr[0] - yl[0], yd[0] - yu[0]);
            }
            sa += g[0];
            sb += g[1];
            saa += g[0] * g[0];
            sbb += g[1] * g[1];
            sab += g[0] * g[1];
            n++;
        }
    double ca = saa - sa * sa / n, cb = sbb - sb * sb / n, cab = sab - sa * sb / n;
    return cab / sqrt(ca * cb);
}

static double angle_diff(double a, double b)
{
    double d = fmod(fabs(a - b), 180.0);
    return d > 90 ? 180 - d : d;
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    CHECK_OK(nprfx_context_create(&ci, &ctx));

    /* YUV round trip. */
    {
        float rgb[3] = {0.8f, 0.3f, 0.1f}, yuv[3], back[3];
        nprfx_pam_rgb_to_yuv(rgb, yuv);
        nprfx_pam_yuv_to_rgb(yuv, back);
        CHECK_NEAR(yuv[0], 0.299 * 0.8 + 0.587 * 0.3 + 0.114 * 0.1, 1e-6);
        for (int c = 0; c < 3; c++)
            CHECK_NEAR(back[c], rgb[c], 1e-6);
    }

    /* Eq. 7 by hand: |0.1 - 0.3| * 255 / 5 = 10.2 -> 10; tiny gaps still take one step. */
    CHECK(nprfx_pam_steps(0.1, 0.3, 5) == 10);
    CHECK(nprfx_pam_steps(0.3, 0.1, 5) == 10);
    CHECK(nprfx_pam_steps(0.2, 0.2001, 5) == 1);
    CHECK(nprfx_pam_steps(0.0, 0.05, 10) == 1); /* 1.275 -> 1 */
    CHECK(nprfx_pam_steps(0.0, 0.06, 10) == 2); /* 1.53 -> 2 */

    /* Three samples at different tones whose strokes run in different directions. */
    static const double tones[3] = {0.55, 0.15, 0.85}, dirs[3] = {20, 100, 150};
    nprfx_image samples[3];
    for (int s = 0; s < 3; s++) {
        CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, N, N), 3, &samples[s]));
        CHECK_OK(nprfx_pam_sample_strokes(ctx, tones[s], dirs[s], 77 + s, &samples[s]));
        double d, coh;
        CHECK_OK(nprfx_pam_orientation(ctx, &samples[s], &d, &coh));
        CHECK(angle_diff(d, dirs[s]) < 15); /* the generator and the measure agree */
        CHECK(coh > 0.2);
    }

    nprfx_pam_build_params p = small_params();
    nprfx_image strip;
    nprfx_pam_info info;
    memset(&info, 0, sizeof info);
    info.size = sizeof info;
    CHECK_OK(nprfx_pam_build(ctx, &p, samples, 3, &strip, &info));
    int S = info.map_size;
    CHECK(S == 64);
    CHECK(nprfx_rect_width(strip.bounds) == info.count * S && nprfx_rect_height(strip.bounds) == S);

    /* Keys: three, first and last among them, sorted dark to light. */
    int keys[3], nk = 0;
    for (int m = 0; m < info.count; m++)
        if (info.key[m] && nk < 3) keys[nk++] = m;
    CHECK(nk == 3 && keys[0] == 0 && keys[2] == info.count - 1);
    for (int m = 0; m + 1 < info.count; m++)
        CHECK(info.mean_yuv[m][0] <= info.mean_yuv[m + 1][0]);

    /* Eq. 7: the maps between adjacent keys number N - 1; Eq. 8: each is the blend exactly. */
    for (int i = 0; i + 1 < nk; i++) {
        int a = keys[i], b = keys[i + 1];
        int n = nprfx_pam_steps(info.mean_yuv[a][0], info.mean_yuv[b][0], p.k);
        CHECK(b - a == n);
        double worst = 0;
        for (int j = 1; j < n; j++) {
            float alpha = (float)(n - j) / (float)n;
            for (int y = 0; y < S; y++)
                for (int x = 0; x < S; x++)
                    for (int c = 0; c < 3; c++) {
                        float want = alpha * nprfx_image_at(&strip, a * S + x, y)[c] +
                                     (1.0f - alpha) * nprfx_image_at(&strip, b * S + x, y)[c];
                        double d = fabs(nprfx_image_at(&strip, (a + j) * S + x, y)[c] - want);
                        if (d > worst) worst = d;
                    }
        }
        CHECK(worst == 0);
    }

    /* Tileable: across the wrap, no worse than across the seams inside (both axes). */
    for (int i = 0; i < nk; i++) {
        nprfx_image v = map_view(&strip, keys[i], S);
        for (int vert = 0; vert < 2; vert++) {
            double in = 0, wr = 0;
            seam_errors(&v, vert, &in, &wr);
            if (!(wr <= in))
                fprintf(stderr, "key %d axis %d: wrap %.6g inside %.6g\n", i, vert, wr, in);
            CHECK(wr <= in);
        }
    }

    /* Orientation: every key map within 10 degrees of the first (the darkest is not the first
     * sample; the first sample's key map is the one of tone 0.55, the middle key). */
    double d0, c0;
    nprfx_image first = map_view(&strip, keys[1], S);
    CHECK_OK(nprfx_pam_orientation(ctx, &first, &d0, &c0));
    CHECK(angle_diff(d0, 90) < 10); /* aligned upright, along v */
    for (int i = 0; i < nk; i++) {
        nprfx_image v = map_view(&strip, keys[i], S);
        double d, c;
        CHECK_OK(nprfx_pam_orientation(ctx, &v, &d, &c));
        if (!(angle_diff(d, d0) <= 10))
            fprintf(stderr, "key %d: %.1f degrees, first %.1f\n", i, d, d0);
        CHECK(angle_diff(d, d0) <= 10);
    }

    /* Layout: the other key maps' stroke edges follow the first's more closely than those of a
     * key map built alone from the same sample (its own PAM, as the first key map). */
    {
        nprfx_image pair[2] = {samples[1], samples[0]}; /* sample 1 leads, A follows nothing */
        nprfx_image alone;
        nprfx_pam_info ai;
        memset(&ai, 0, sizeof ai);
        ai.size = sizeof ai;
        nprfx_pam_build_params q = p;
        q.seed = 99;
        CHECK_OK(nprfx_pam_build(ctx, &q, pair, 2, &alone, &ai));
        nprfx_image indep = map_view(&alone, 0, S); /* sample 1 (darker) synthesised freely */
        nprfx_image follow = map_view(&strip, keys[0], S);
        double cf = edge_corr(&first, &follow), ci2 = edge_corr(&first, &indep);
        if (!(cf > ci2 + 0.05))
            fprintf(stderr, "layout: following %.3f, independent %.3f\n", cf, ci2);
        CHECK(cf > ci2 + 0.05);
        nprfx_image_free(&alone);
    }

    /* Same bits on 1 and 3 threads. */
    {
        nprfx_pool *pool = NULL;
        CHECK_OK(nprfx_pool_create(3, &pool));
        nprfx_context_init pi = NPRFX_CONTEXT_INIT_DEFAULT;
        pi.executor = nprfx_pool_executor(pool);
        nprfx_context *pctx = NULL;
        CHECK_OK(nprfx_context_create(&pi, &pctx));
        nprfx_image s2;
        CHECK_OK(nprfx_pam_build(pctx, &p, samples, 3, &s2, NULL));
        CHECK(nprfx_rect_equal(s2.bounds, strip.bounds) &&
              !memcmp(s2.data, strip.data,
                      sizeof(float) * 3 * (size_t)nprfx_rect_width(strip.bounds) * S));
        nprfx_image_free(&s2);
        nprfx_context_destroy(pctx);
        nprfx_pool_destroy(pool);
    }

    /* describe() recomputes what build reported. */
    {
        nprfx_pam_info d;
        memset(&d, 0, sizeof d);
        d.size = sizeof d;
        CHECK_OK(nprfx_pam_describe(ctx, &strip, &d));
        CHECK(d.count == info.count && d.map_size == S);
        CHECK(d.mean_yuv[1][0] == info.mean_yuv[1][0]);
        nprfx_image one = map_view(&strip, 0, S);
        CHECK(nprfx_pam_describe(ctx, &one, &d) == NPRFX_ERR_INVALID_ARGUMENT); /* count 1 */
        CHECK(strstr(th_error(ctx), "2 to") != NULL);
        nprfx_image odd = nprfx_image_crop(&strip, nprfx_rect_make(0, 0, 2 * S + 1, S));
        CHECK(nprfx_pam_describe(ctx, &odd, &d) == NPRFX_ERR_INVALID_ARGUMENT);
        CHECK(strstr(th_error(ctx), "not a multiple") != NULL);
    }

    /* Bad input. */
    {
        nprfx_image big, tiny, out;
        CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, N + 8, N), 3, &big));
        nprfx_image mixed[2] = {samples[0], big};
        CHECK(nprfx_pam_build(ctx, &p, mixed, 2, &out, NULL) == NPRFX_ERR_SIZE_MISMATCH);
        CHECK(strstr(th_error(ctx), "sample 1 is 136x128 but sample 0 is 128x128") != NULL);
        CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 12, 12), 3, &tiny));
        nprfx_image small2[2] = {tiny, tiny};
        CHECK(nprfx_pam_build(ctx, &p, small2, 2, &out, NULL) == NPRFX_ERR_INVALID_ARGUMENT);
        CHECK(strstr(th_error(ctx), "sample 0 is too small") != NULL);
        CHECK(nprfx_pam_build(ctx, &p, samples, 1, &out, NULL) == NPRFX_ERR_INVALID_ARGUMENT);
        nprfx_pam_build_params bad = p;
        bad.patch = 12; /* not a multiple of 4 with 3 levels */
        CHECK(nprfx_pam_build(ctx, &bad, samples, 3, &out, NULL) == NPRFX_ERR_OUT_OF_RANGE);
        bad = p;
        bad.map_size = 72; /* not a multiple of the patch */
        CHECK(nprfx_pam_build(ctx, &bad, samples, 3, &out, NULL) == NPRFX_ERR_OUT_OF_RANGE);
        bad = p;
        bad.k = 0.01; /* far too many maps */
        CHECK(nprfx_pam_build(ctx, &bad, samples, 3, &out, NULL) == NPRFX_ERR_OUT_OF_RANGE);
        CHECK(strstr(th_error(ctx), "raise k") != NULL);
        nprfx_image_free(&big);
        nprfx_image_free(&tiny);
    }

    /* No quilting seams at the defaults (256-pixel maps of 64-pixel patches from 256-pixel
     * samples, as `nprfx pam build` makes them): along the strokes, the steps between rows where
     * blocks are cut are within 50% of those inside the blocks (1.1-1.25 as built; the quilt of
     * 32-pixel patches with no feather or varied picks measured 2.3-3.7, its stroke ends chopped at
     * every row of patches); across the strokes, where the steps are large everywhere, within
     * 40% (1.0-1.26 as built). */
    {
        static const double tn[3] = {0.12, 0.45, 0.9}, dn[3] = {80, 65, 110};
        nprfx_image big[3], st;
        for (int s = 0; s < 3; s++) {
            CHECK_OK(nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 256, 256), 3, &big[s]));
            CHECK_OK(nprfx_pam_sample_strokes(ctx, tn[s], dn[s], 5 + s, &big[s]));
        }
        nprfx_pam_build_params d = NPRFX_PAM_BUILD_PARAMS_DEFAULT;
        nprfx_pam_info bi;
        memset(&bi, 0, sizeof bi);
        bi.size = sizeof bi;
        CHECK_OK(nprfx_pam_build(ctx, &d, big, 3, &st, &bi));
        for (int m = 0; m < bi.count; m++) {
            if (!bi.key[m]) continue;
            nprfx_image v = map_view(&st, m, d.map_size);
            double along = seam_ratio(&v, 0, d.patch, d.overlap);
            double across = seam_ratio(&v, 1, d.patch, d.overlap);
            if (!(along < 1.5 && across < 1.4))
                fprintf(stderr, "map %d: seam ratio along %.3f across %.3f\n", m, along, across);
            CHECK(along < 1.5 && across < 1.4);
        }
        nprfx_image_free(&st);
        for (int s = 0; s < 3; s++)
            nprfx_image_free(&big[s]);
    }

    nprfx_image_free(&strip);
    for (int s = 0; s < 3; s++)
        nprfx_image_free(&samples[s]);
    nprfx_context_destroy(ctx);
    return check_finish();
}
