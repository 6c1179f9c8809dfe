/* Unit tests for core/looks/threshold_map.c (erf threshold, its mean, the builtin step position, tone
 * quantisation, bilinear map lookup with its orientation) and the threshold-map node (the three
 * modes, channels, errors, the mean-reproduces-tone property with uniform noise, determinism
 * across thread counts and tile splits). */
#include <string.h>

#include "check.h"
#include "looks/internal_threshold.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/node.h"
#include "nprfx/rng.h"
#include "nprfx/threshold.h"

#define TOL 1e-6

/* ---- helpers: tiny images and direct calls of a node's render function ---- */

static const nprfx_node_desc *node;
static nprfx_image in[8];
static nprfx_value pv[16];

static int PI(const char *name)
{
    return th_param(node, name);
}
static int II(const char *name)
{
    return th_input(node, name);
}

static void reset(void)
{
    for (int i = 0; i < 8; i++)
        nprfx_image_free(&in[i]);
    nprfx_node_defaults(node, pv);
}

static void set_mode(const char *name)
{
    th_set_choice(node, pv, "mode", name);
}

/* Output channels as the node declares them for the connected inputs and params. */
static int out_channels(void)
{
    int ich[8] = {0};
    for (int i = 0; i < node->num_inputs; i++)
        ich[i] = in[i].data ? in[i].channels : 0;
    nprfx_output_info info;
    if (nprfx_node_output_info(NULL, node, pv, ich, &info) != NPRFX_OK) return -1;
    return info.channels;
}

static nprfx_image run(nprfx_context *ctx, int w, int h, int channels, nprfx_result *res)
{
    nprfx_image out = th_image(w, h, channels, NULL);
    *res = th_render(ctx, node, in, pv, &out, out.bounds);
    return out;
}

/* ---- core ---- */

static void test_erf(void)
{
    /* threshold(mu) = 1/2; one 1/sigma step above: (erf(1) + 1) / 2 */
    const double erf1 = 0.8427007929497149;
    CHECK_NEAR(nprfx_threshold_erf(0.5, 25, 0.5), 0.5, 1e-15);
    CHECK_NEAR(nprfx_threshold_erf(0.54, 25, 0.5), (erf1 + 1) / 2, 1e-12); /* 0.92135039647 */
    CHECK_NEAR(nprfx_threshold_erf(0.46, 25, 0.5), (1 - erf1) / 2, 1e-12); /* 0.07864960353 */
    CHECK_NEAR(nprfx_threshold_erf(0.6, 10, 0.5), 0.9213503964748575, 1e-12);
    CHECK_NEAR(nprfx_threshold_erf(0.0, 25, 0.5), 0.0, 1e-12);
    CHECK_NEAR(nprfx_threshold_erf(1.0, 25, 0.5), 1.0, 1e-12);
}

/* Midpoint rule over [0,1] of the erf threshold, n intervals. */
static double integrate_erf(double sigma, double mu, int n)
{
    double s = 0;
    for (int i = 0; i < n; i++)
        s += nprfx_threshold_erf((i + 0.5) / n, sigma, mu);
    return s / n;
}

static void test_mean_and_builtin(void)
{
    /* the closed-form mean against numerical integration, both sides of 0.5 and outside [0,1] */
    const double sig[] = {2, 25, 100};
    const double mus[] = {-0.1, 0.0, 0.02, 0.3, 0.5, 0.77, 0.99, 1.0, 1.05};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 9; k++)
            CHECK_NEAR(nprfx_threshold_erf_mean(sig[i], mus[k]),
                       integrate_erf(sig[i], mus[k], 200000), 1e-8);
    /* interior: the mean of a step at mu is 1 - mu */
    CHECK_NEAR(nprfx_threshold_erf_mean(25, 0.3), 0.7, 1e-12);
    CHECK_NEAR(nprfx_threshold_erf_mean(25, 0.5), 0.5, 1e-15);
    /* at the end the step is half outside: mean(sigma, 1) = 1 / (2 sigma sqrt(pi))
     * = 0.0112837916709551 for sigma 25 */
    CHECK_NEAR(nprfx_threshold_erf_mean(25, 1.0), 0.0112837916709551, 1e-12);

    /* builtin: interior tones put the step at 1 - tone */
    CHECK_NEAR(nprfx_threshold_builtin_mu(0.3, 25), 0.7, 1e-12);
    CHECK_NEAR(nprfx_threshold_builtin_mu(0.5, 25), 0.5, 1e-15);
    CHECK_NEAR(nprfx_threshold_builtin_mu(0.7, 25), 0.3, 1e-12);
    /* the defining property: mean over uniform p in [0,1] equals the tone, checked by
     * integrating the threshold numerically too (independent of the closed form) */
    const double tones[] = {0.001, 0.01, 0.05, 0.1, 0.2, 0.35, 0.5, 0.65, 0.9, 0.97, 0.999};
    for (int i = 0; i < 3; i++) {
        double prev = 1e300;
        for (int k = 0; k < 11; k++) {
            double mu = nprfx_threshold_builtin_mu(tones[k], sig[i]);
            CHECK_NEAR(nprfx_threshold_erf_mean(sig[i], mu), tones[k], 1e-12);
            CHECK_NEAR(integrate_erf(sig[i], mu, 200000), tones[k], 1e-8);
            CHECK(nprfx_threshold_builtin(0.3, tones[k], sig[i]) ==
                  nprfx_threshold_erf(0.3, sig[i], mu));
            CHECK(mu < prev); /* darker tone => step further right => more ink */
            prev = mu;
        }
    }
    /* near the ends the position leaves [0,1]: tone 0.01 at sigma 25 needs mu > 1 */
    CHECK(nprfx_threshold_builtin_mu(0.01, 25) > 1.0);
    CHECK(nprfx_threshold_builtin_mu(0.99, 25) < 0.0);
    /* tone 0 / 1: all ink / all paper */
    for (int i = 0; i <= 10; i++) {
        CHECK(nprfx_threshold_builtin(i / 10.0, 0.0, 25) == 0.0);
        CHECK(nprfx_threshold_builtin(i / 10.0, 1.0, 25) == 1.0);
        CHECK(nprfx_threshold_builtin(i / 10.0, -3.0, 25) == 0.0);
    }
}

static void test_quantize(void)
{
    /* 3 levels: 0, 0.5, 1 */
    CHECK_NEAR(nprfx_threshold_quantize(0.2, 3), 0.0, 1e-15);
    CHECK_NEAR(nprfx_threshold_quantize(0.4, 3), 0.5, 1e-15);
    CHECK_NEAR(nprfx_threshold_quantize(0.74, 3), 0.5, 1e-15);
    CHECK_NEAR(nprfx_threshold_quantize(0.76, 3), 1.0, 1e-15);
    /* 5 levels: 0.6 -> 0.5 (2.4 rounds to 2), 0.65 -> 0.75 */
    CHECK_NEAR(nprfx_threshold_quantize(0.6, 5), 0.5, 1e-15);
    CHECK_NEAR(nprfx_threshold_quantize(0.65, 5), 0.75, 1e-15);
    /* continuous, clamped */
    CHECK_NEAR(nprfx_threshold_quantize(0.37, 0), 0.37, 1e-15);
    CHECK_NEAR(nprfx_threshold_quantize(0.37, 1), 0.37, 1e-15);
    CHECK_NEAR(nprfx_threshold_quantize(-0.2, 0), 0.0, 1e-15);
    CHECK_NEAR(nprfx_threshold_quantize(1.7, 4), 1.0, 1e-15);
}

static void test_map_lookup(void)
{
    /* A 3 x 2 map, top row first in memory (core's y grows down):
     *   top    (v = 1): 10 20 30
     *   bottom (v = 0):  0  1  2                                  */
    const float m[] = {10, 20, 30, 0, 1, 2};
    nprfx_image map = th_image(3, 2, 1, m);
    float o;
    nprfx_threshold_map_lookup(&map, 0, 0, &o);
    CHECK_NEAR(o, 0, TOL); /* bottom-left */
    nprfx_threshold_map_lookup(&map, 1, 0, &o);
    CHECK_NEAR(o, 2, TOL); /* bottom-right */
    nprfx_threshold_map_lookup(&map, 0, 1, &o);
    CHECK_NEAR(o, 10, TOL); /* top-left */
    nprfx_threshold_map_lookup(&map, 1, 1, &o);
    CHECK_NEAR(o, 30, TOL); /* top-right */
    /* u 0.25 -> x 0.5: bottom (0 + 1) / 2 = 0.5 */
    nprfx_threshold_map_lookup(&map, 0.25, 0, &o);
    CHECK_NEAR(o, 0.5, TOL);
    /* u 0.75, v 0.5: x 1.5; bottom 1.5, top 25 => 13.25 */
    nprfx_threshold_map_lookup(&map, 0.75, 0.5, &o);
    CHECK_NEAR(o, 13.25, TOL);
    /* u 0.25, v 0.25: bottom 0.5, top 15 => 0.75 * 0.5 + 0.25 * 15 = 4.125 */
    nprfx_threshold_map_lookup(&map, 0.25, 0.25, &o);
    CHECK_NEAR(o, 4.125, TOL);
    /* clamped outside [0,1]; NaN reads as 0 */
    nprfx_threshold_map_lookup(&map, -1, 2, &o);
    CHECK_NEAR(o, 10, TOL);
    nprfx_threshold_map_lookup(&map, 5, -3, &o);
    CHECK_NEAR(o, 2, TOL);
    nprfx_threshold_map_lookup(&map, NAN, 1, &o);
    CHECK_NEAR(o, 10, TOL);

    /* the same map with its data window elsewhere gives the same answers */
    nprfx_image moved = map;
    moved.bounds = nprfx_rect_make(5, -3, 8, -1);
    nprfx_threshold_map_lookup(&moved, 0.75, 0.5, &o);
    CHECK_NEAR(o, 13.25, TOL);
    nprfx_threshold_map_lookup(&moved, 0.25, 0.25, &o);
    CHECK_NEAR(o, 4.125, TOL);

    /* 2 channels; a 1 x 1 map; a 1-wide map */
    const float m2[] = {0, 100, 1, 200, 2, 300, 3, 400};
    nprfx_image map2 = th_image(2, 2, 2, m2); /* top: (0,100) (1,200); bottom: (2,300) (3,400) */
    float o2[2];
    nprfx_threshold_map_lookup(&map2, 0.5, 0.5, o2);
    CHECK_NEAR(o2[0], 1.5, TOL);
    CHECK_NEAR(o2[1], 250, TOL);
    nprfx_threshold_map_lookup(&map2, 1, 0, o2);
    CHECK_NEAR(o2[0], 3, TOL);
    CHECK_NEAR(o2[1], 400, TOL);
    nprfx_image one = th_image(1, 1, 1, m + 1);
    nprfx_threshold_map_lookup(&one, 0.3, 0.8, &o);
    CHECK_NEAR(o, 20, TOL);
    const float col[] = {4, 8}; /* 1 x 2: top 4, bottom 8 */
    nprfx_image narrow = th_image(1, 2, 1, col);
    nprfx_threshold_map_lookup(&narrow, 0.9, 0.25, &o);
    CHECK_NEAR(o, 7, TOL);
    nprfx_image_free(&map);
    nprfx_image_free(&map2);
    nprfx_image_free(&one);
    nprfx_image_free(&narrow);
}

/* ---- the node ---- */

static void test_descriptor(void)
{
    CHECK(strcmp(node->id, "threshold-map") == 0);
    const nprfx_param_desc *m = &node->params[PI("mode")];
    CHECK(strcmp(m->choices[0], "erf") == 0 && strcmp(m->choices[1], "map") == 0 &&
          strcmp(m->choices[2], "builtin") == 0 && m->choices[3] == NULL);
    CHECK(node->params[PI("sigma")].def[0] == 25.0);
    CHECK(node->params[PI("mu")].def[0] == 0.5);
    CHECK(node->params[PI("tone")].def[0] == 0.5);
    CHECK(II("pattern") == 0 && II("tone") >= 0 && II("map") >= 0);
    CHECK(node->inputs[II("tone")].channels == 1);
    /* the map is a lookup table, not a frame-aligned plate */
    CHECK(node->inputs[II("map")].flags & NPRFX_INPUT_UNALIGNED);
    CHECK(node->inputs[II("map")].flags & NPRFX_INPUT_OPTIONAL);
    for (int i = 0; i < node->num_params; i++)
        CHECK(node->params[i].help && node->params[i].help[0]);
}

static void test_node_erf(nprfx_context *ctx)
{
    nprfx_result r;
    reset();
    /* 2-channel pattern: each channel thresholded on its own */
    const float p[] = {0.5f, 0.54f, 0.46f, 0.0f};
    in[II("pattern")] = th_image(2, 1, 2, p);
    CHECK(out_channels() == 2);
    nprfx_image out = run(ctx, 2, 1, 2, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.5, TOL);
    CHECK_NEAR(out.data[1], 0.92135039647, TOL);
    CHECK_NEAR(out.data[2], 0.07864960353, TOL);
    CHECK_NEAR(out.data[3], 0.0, TOL);
    nprfx_image_free(&out);
    /* mu and sigma params, invert: 1 - threshold(0.54, 10, 0.44) = 1 - (erf(1) + 1) / 2 */
    pv[PI("mu")].v[0] = 0.44;
    pv[PI("sigma")].v[0] = 10;
    pv[PI("invert")].v[0] = 1;
    out = run(ctx, 2, 1, 2, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[1], 0.07864960353, TOL);
    nprfx_image_free(&out);
    /* a tone input does not change the erf mode */
    pv[PI("invert")].v[0] = 0;
    const float t[] = {0.1f, 0.9f};
    in[II("tone")] = th_image(2, 1, 1, t);
    out = run(ctx, 2, 1, 2, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[1], 0.92135039647, TOL);
    nprfx_image_free(&out);
    /* no pattern: refused */
    nprfx_image_free(&in[II("pattern")]);
    out = run(ctx, 2, 1, 1, &r);
    CHECK(r == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "pattern") != NULL);
    nprfx_image_free(&out);
}

static void test_node_map(nprfx_context *ctx)
{
    nprfx_result r;
    reset();
    set_mode("map");
    /* 1-channel map, 2-channel pattern: looked up per channel at v = tone */
    const float m[] = {10, 20, 30, 0, 1, 2};
    const float p[] = {0.25f, 0.75f, 0.0f, 1.0f};
    const float t[] = {0.25f, 0.5f};
    in[II("pattern")] = th_image(2, 1, 2, p);
    in[II("tone")] = th_image(2, 1, 1, t);
    in[II("map")] = th_image(3, 2, 1, m);
    CHECK(out_channels() == 2);
    nprfx_image out = run(ctx, 2, 1, 2, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 4.125, TOL); /* (u 0.25, v 0.25): 0.75 * 0.5 + 0.25 * 15 */
    CHECK_NEAR(out.data[1], 7.375, TOL); /* (u 0.75, v 0.25): 0.75 * 1.5 + 0.25 * 25 */
    CHECK_NEAR(out.data[2], 5.0, TOL);   /* (u 0, v 0.5): (0 + 10) / 2 */
    CHECK_NEAR(out.data[3], 16.0, TOL);  /* (u 1, v 0.5): (2 + 30) / 2 */
    nprfx_image_free(&out);
    /* without the tone input: the tone param, 0.5 everywhere */
    nprfx_image_free(&in[II("tone")]);
    pv[PI("tone")].v[0] = 0.5;
    out = run(ctx, 2, 1, 2, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 7.75, TOL);  /* (u 0.25, v 0.5): (0.5 + 15) / 2 */
    CHECK_NEAR(out.data[1], 13.25, TOL); /* (u 0.75, v 0.5): (1.5 + 25) / 2 */
    CHECK_NEAR(out.data[2], 5.0, TOL);
    CHECK_NEAR(out.data[3], 16.0, TOL);
    /* tone_gain 2 on tone 0.25 -> 0.5: same as above */
    pv[PI("tone")].v[0] = 0.25;
    pv[PI("tone_gain")].v[0] = 2;
    nprfx_image out2 = run(ctx, 2, 1, 2, &r);
    CHECK_OK(r);
    CHECK(memcmp(out.data, out2.data, sizeof(float) * 4) == 0);
    nprfx_image_free(&out);
    nprfx_image_free(&out2);
    /* steps 2: tone 0.3 -> 0 (bottom row); invert */
    pv[PI("tone_gain")].v[0] = 1;
    pv[PI("tone")].v[0] = 0.3;
    pv[PI("steps")].v[0] = 2;
    pv[PI("invert")].v[0] = 1;
    out = run(ctx, 2, 1, 2, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 1 - 0.5, TOL); /* u 0.25 on the bottom row: 0.5 */
    CHECK_NEAR(out.data[3], 1 - 2.0, TOL); /* u 1: 2 */
    nprfx_image_free(&out);

    /* 3-channel map, 1-channel pattern: the output has the map's channels */
    reset();
    set_mode("map");
    /* 2 x 1 map (one row: v does not matter): left (0, 0.5, 1), right (1, 0.5, 0) */
    const float m3[] = {0, 0.5f, 1, 1, 0.5f, 0};
    const float p1[] = {0.25f};
    in[II("pattern")] = th_image(1, 1, 1, p1);
    in[II("map")] = th_image(2, 1, 3, m3);
    CHECK(out_channels() == 3);
    out = run(ctx, 1, 1, 3, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.25, TOL);
    CHECK_NEAR(out.data[1], 0.5, TOL);
    CHECK_NEAR(out.data[2], 0.75, TOL);
    nprfx_image_free(&out);
    /* ... but refuses a 2-channel pattern with it */
    nprfx_image_free(&in[II("pattern")]);
    in[II("pattern")] = th_image(1, 1, 2, p);
    CHECK(out_channels() == -1);
    out = run(ctx, 1, 1, 3, &r);
    CHECK(r == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "pattern") != NULL);
    nprfx_image_free(&out);
    /* map mode without a map */
    nprfx_image_free(&in[II("map")]);
    CHECK(out_channels() == -1);
    out = run(ctx, 1, 1, 2, &r);
    CHECK(r == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "map") != NULL);
    nprfx_image_free(&out);
}

/* The node's table of the step position against the exact solve, densely over the tone range
 * (both halves, the tails, the ends) for sharp, soft and extreme sigmas: within 1e-9 / sigma.
 * The output's slope in mu is at most sigma / sqrt(pi), so it moves by under 6e-10, a
 * hundredth of a float's unit in the last place at 0.5. */
static void test_mu_table(void)
{
    static internal_mu_table tab;
    const double sig[] = {0.01, 0.5, 1, 3, 10, 25, 60, 100, 1e3, 1e6};
    for (int i = 0; i < 10; i++) {
        internal_mu_table_init(&tab, sig[i]);
        double worst = 0.0;
        for (int k = 0; k <= 200000; k++) {
            double t = k / 200000.0;
            if (k % 3 == 1) t = pow(10.0, -9.0 * k / 200000.0); /* the tails, geometrically */
            if (k % 3 == 2) t = 1.0 - pow(10.0, -9.0 * k / 200000.0);
            /* the solve itself stops at a few units in the last place of mu (~1): that
             * floor, 4e-15, is allowed besides 1e-9 / sigma (it matters for sigma 1e6) */
            double e =
                fabs(internal_mu_table_eval(&tab, t) - nprfx_threshold_builtin_mu(t, sig[i])) /
                (1e-9 / sig[i] + 4e-15);
            if (e > worst) worst = e;
        }
        if (worst > 1.0) fprintf(stderr, "sigma %g: table off by %g x tolerance\n", sig[i], worst);
        CHECK(worst <= 1.0);
    }
}

/* The per-instance cache of the builtin table: a render through a state that holds another
 * sigma's table, the same sigma's again, and windows of it give the pixels of a render without
 * a state (which builds its own table). */
static void test_table_cache(nprfx_context *ctx)
{
    const int w = 64, h = 32;
    nprfx_image pat = th_image(w, h, 1, NULL), tone = th_image(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            nprfx_image_at(&pat, x, y)[0] = (float)nprfx_rand_u01(3, 0, x, y, 0, 0);
            nprfx_image_at(&tone, x, y)[0] = (float)(x + 0.5) / w; /* 0 .. 1 */
        }
    nprfx_threshold_params p = {.mode = NPRFX_THRESHOLD_BUILTIN, .tone_gain = 1};
    void *state = NULL;
    const double sig[] = {10, 25, 25, 3};
    for (int k = 0; k < 4; k++) {
        p.sigma = sig[k];
        nprfx_image ref = th_image(w, h, 1, NULL), got = th_image(w, h, 1, NULL);
        CHECK_OK(nprfx_threshold_render(ctx, &p, &pat, &tone, NULL, ref.bounds, &ref));
        /* two windows through the state, the second hitting the table the first built */
        CHECK_OK(nprfx_threshold_render_cached(ctx, &p, &pat, &tone, NULL,
                                               nprfx_rect_make(0, 0, w, h / 2), &got, &state));
        CHECK_OK(nprfx_threshold_render_cached(ctx, &p, &pat, &tone, NULL,
                                               nprfx_rect_make(0, h / 2, w, h), &got, &state));
        CHECK(memcmp(ref.data, got.data, sizeof(float) * w * h) == 0);
        nprfx_image_free(&ref);
        nprfx_image_free(&got);
    }
    CHECK(state != NULL);
    nprfx_threshold_state_free(state);
    nprfx_image_free(&pat);
    nprfx_image_free(&tone);
}

/* The node's erf rows (a table with a Taylor step, vectorised, libm where the table cannot
 * decide) against the direct computation, bit for bit: (float)nprfx_threshold_erf at the
 * table's step position, for random tones and for patterns that put sigma (p - mu) anywhere in
 * [-7, 5], both past the table's ends and dense where floats round near erf's tails. Packed and
 * strided 1- and 3-channel pixels, odd widths (the scalar tail), invert, sigmas from soft to
 * sharp: 3.9e6 samples. */
static void test_erf_rows_exact(nprfx_context *ctx)
{
    static internal_mu_table tab;
    const double sig[] = {0.7, 10, 12, 25, 100, 3000};
    const int w = 509, h = 211;
    long bad = 0;
    for (int s = 0; s < 6; s++) {
        internal_mu_table_init(&tab, sig[s]);
        const int ch = s % 2 ? 3 : 1, stride = s % 3 == 2 ? ch + 1 : ch;
        nprfx_image pat = th_image(w, h, stride, NULL), tone = th_image(w, h, 1, NULL);
        pat = nprfx_image_channels(&pat, 0, ch);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                const float t = (float)nprfx_rand_u01(7, s, x, y, 0, 0);
                nprfx_image_at(&tone, x, y)[0] = t;
                const double mu = internal_mu_table_eval(&tab, t);
                for (int c = 0; c < ch; c++) {
                    const double u = nprfx_rand_u01(7, s, x, y, (uint32_t)c + 1, 0);
                    nprfx_image_at(&pat, x, y)[c] = (float)(mu + (12.0 * u - 7.0) / sig[s]);
                }
            }
        for (int invert = 0; invert < 2; invert++) {
            nprfx_threshold_params p = {
                .mode = NPRFX_THRESHOLD_BUILTIN, .sigma = sig[s], .tone_gain = 1, .invert = invert};
            nprfx_image out = th_image(w, h, ch, NULL);
            CHECK_OK(nprfx_threshold_render(ctx, &p, &pat, &tone, NULL, out.bounds, &out));
            for (int y = 0; y < h; y++)
                for (int x = 0; x < w; x++) {
                    const double mu = internal_mu_table_eval(&tab, nprfx_image_at(&tone, x, y)[0]);
                    for (int c = 0; c < ch; c++) {
                        const float v =
                            (float)nprfx_threshold_erf(nprfx_image_at(&pat, x, y)[c], sig[s], mu);
                        const float want = invert ? 1.0f - v : v;
                        bad += memcmp(&want, &nprfx_image_at(&out, x, y)[c], sizeof want) != 0;
                    }
                }
            nprfx_image_free(&out);
        }
        pat.channels = stride;
        nprfx_image_free(&pat);
        nprfx_image_free(&tone);
    }
    if (bad) fprintf(stderr, "erf rows: %ld samples differ from the direct computation\n", bad);
    CHECK(bad == 0);
}

static void test_node_builtin(nprfx_context *ctx)
{
    nprfx_result r;
    reset();
    set_mode("builtin");
    /* pattern = uniform noise in [0,1]: the mean output reproduces the tone */
    const int w = 256, h = 256;
    in[II("pattern")] = th_image(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            nprfx_image_at(&in[0], x, y)[0] = (float)nprfx_rand_u01(11, 0, x, y, 0, 0);
    const double tones[] = {0.0, 0.03, 0.2, 0.5, 0.8, 0.97, 1.0};
    for (int k = 0; k < 7; k++) {
        pv[PI("tone")].v[0] = tones[k];
        nprfx_image out = run(ctx, w, h, 1, &r);
        CHECK_OK(r);
        double s = 0;
        for (int i = 0; i < w * h; i++)
            s += out.data[i];
        /* 65536 samples of a value in [0,1]: standard error below 0.002 */
        CHECK_NEAR(s / (w * h), tones[k], 0.008);
        nprfx_image_free(&out);
    }
    /* a tone input: a 4-band tone image, each band's mean follows its tone */
    in[II("tone")] = th_image(w, h, 1, NULL);
    const double band[] = {0.1, 0.4, 0.6, 0.9};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            nprfx_image_at(&in[II("tone")], x, y)[0] = (float)band[x / 64];
    pv[PI("sigma")].v[0] = 60;
    nprfx_image out = run(ctx, w, h, 1, &r);
    CHECK_OK(r);
    for (int b = 0; b < 4; b++) {
        double s = 0;
        for (int y = 0; y < h; y++)
            for (int x = b * 64; x < b * 64 + 64; x++)
                s += nprfx_image_at(&out, x, y)[0];
        CHECK_NEAR(s / (64 * h), (float)band[b], 0.015);
    }
    /* invert gives ink coverage: mean 1 - tone */
    pv[PI("invert")].v[0] = 1;
    nprfx_image inv = run(ctx, w, h, 1, &r);
    CHECK_OK(r);
    for (int i = 0; i < w * h; i++)
        CHECK(inv.data[i] == 1.0f - out.data[i]);
    nprfx_image_free(&inv);
    nprfx_image_free(&out);
    /* pixel values against the formula: tone 0.3, p 0.75, sigma 25 => step at 0.7,
     * (erf(25 * 0.05) + 1) / 2 = (erf(1.25) + 1) / 2 = (0.9229001283 + 1) / 2 */
    reset();
    set_mode("builtin");
    const float p[] = {0.75f};
    const float t[] = {0.3f};
    in[II("pattern")] = th_image(1, 1, 1, p);
    in[II("tone")] = th_image(1, 1, 1, t);
    out = run(ctx, 1, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.96145006415, 2e-6);
    nprfx_image_free(&out);
}

static void test_determinism(nprfx_context *serial)
{
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(4, &pool);
    const int w = 61, h = 47;
    const char *modes[] = {"erf", "map", "builtin"};
    for (int k = 0; k < 3; k++) {
        reset();
        set_mode(modes[k]);
        in[II("pattern")] = th_image(w, h, 1, NULL);
        in[II("tone")] = th_image(w, h, 1, NULL);
        in[II("map")] = th_image(32, 8, 3, NULL);
        for (int i = 0; i < 3; i++) {
            nprfx_image *im = &in[i];
            int iw = nprfx_rect_width(im->bounds), ih = nprfx_rect_height(im->bounds);
            for (int y = 0; y < ih; y++)
                for (int x = 0; x < iw; x++)
                    for (int c = 0; c < im->channels; c++)
                        nprfx_image_at(im, x, y)[c] =
                            (float)nprfx_rand_u01(5, 2, x, y, (uint32_t)c, (uint32_t)i);
        }
        pv[PI("steps")].v[0] = k == 2 ? 0 : 5;
        int ch = out_channels();
        CHECK(ch == (k == 1 ? 3 : 1));
        CHECK(th_same_pixels(serial, par, node, in, pv, w, h, ch, NULL) == 0);
    }
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
}

int main(void)
{
    node = nprfx_node_find("threshold-map");
    if (!node) {
        fprintf(stderr, "threshold-map is not registered\n");
        return 1;
    }
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    test_erf();
    test_mean_and_builtin();
    test_mu_table();
    test_quantize();
    test_map_lookup();
    test_descriptor();
    test_node_erf(ctx);
    test_node_map(ctx);
    test_node_builtin(ctx);
    test_table_cache(ctx);
    test_erf_rows_exact(ctx);
    test_determinism(ctx);
    reset();
    nprfx_context_destroy(ctx);
    return check_finish();
}
