/* Unit tests for the watercolor node (core/looks/watercolor.c, plugins/watercolor.c): identity when
 * every effect is off, the pigment densities of the textures against hand-computed values, edge
 * darkening on a step of known height, the exact wobble of a linear-ramp paper and its bound on
 * any paper, coverage over white paper, alpha, the error paths, and bit-identity across thread
 * counts and tile splits. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/blend.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/node.h"
#include "nprfx/rng.h"
#include "nprfx/watercolor.h"

#define TOL 1e-6

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
static void set(const char *name, double v)
{
    pv[PI(name)].v[0] = v;
}

static void reset(void)
{
    for (int i = 0; i < 8; i++)
        nprfx_image_free(&in[i]);
    nprfx_node_defaults(node, pv);
}

/* Everything off: no darkening, no wobble (the texture amounts only act with their inputs). */
static void effects_off(void)
{
    set("edge_darkening", 0);
    set("wobble", 0);
}

static nprfx_image run(nprfx_context *ctx, int w, int h, nprfx_result *res)
{
    nprfx_image out = th_image(w, h, in[II("image")].channels, NULL);
    *res = th_render(ctx, node, in, pv, &out, out.bounds);
    return out;
}

/* A w x h image of ch channels, every value u01-random from (seed, x, y, c). */
static nprfx_image random_image(int w, int h, int ch, uint64_t seed)
{
    nprfx_image im = th_image(w, h, ch, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < ch; c++)
                nprfx_image_at(&im, x, y)[c] = (float)nprfx_rand_u01(seed, 1, x, y, (uint32_t)c, 0);
    return im;
}

static nprfx_image constant_image(int w, int h, int ch, float v)
{
    nprfx_image im = th_image(w, h, ch, NULL);
    for (size_t i = 0; i < (size_t)w * (size_t)h * (size_t)ch; i++)
        im.data[i] = v;
    return im;
}

static float px(const nprfx_image *im, int x, int y, int c)
{
    return nprfx_image_at(im, x, y)[c];
}

static void test_descriptor(nprfx_context *ctx)
{
    CHECK(node != NULL);
    CHECK_OK(nprfx_node_lint(ctx, node));
    CHECK(node->params_size == sizeof(nprfx_watercolor_params));
    CHECK(strcmp(node->id, "watercolor") == 0);
    CHECK(strcmp(node->label, "Watercolor") == 0);
    CHECK(strcmp(node->group, "NPR") == 0);
    const char *names[] = {"turbulence", "dispersion", "granulation", "edge_darkening",
                           "edge_width", "wobble",     "wobble_scale"};
    for (int i = 0; i < 7; i++)
        CHECK(nprfx_node_param_index(node, names[i]) >= 0);
    /* lengths follow the render scale */
    CHECK(node->params[PI("edge_width")].flags & NPRFX_PARAM_PIXELS);
    CHECK(node->params[PI("wobble")].flags & NPRFX_PARAM_PIXELS);
    CHECK(node->params[PI("wobble_scale")].flags & NPRFX_PARAM_PIXELS);
    const char *inames[] = {"image", "turbulence", "dispersion", "paper", "coverage"};
    for (int i = 0; i < 5; i++)
        CHECK(nprfx_node_input_index(node, inames[i]) == i);
    CHECK(node->inputs[0].flags & NPRFX_INPUT_MAIN);
    for (int i = 1; i < 5; i++)
        CHECK((node->inputs[i].flags & NPRFX_INPUT_OPTIONAL) && node->inputs[i].channels == 1);
}

/* Nothing optional connected, no darkening, no wobble: the image bit for bit, NaN and values
 * outside [0, 1] included. A wobble without paper, or a paper with no wobble and no granulation,
 * changes nothing either. */
static void test_identity(nprfx_context *ctx)
{
    const int w = 19, h = 13;
    for (int ch = 1; ch <= 4; ch++) {
        reset();
        in[II("image")] = random_image(w, h, ch, 11);
        in[II("image")].data[5] = 3.5f;
        in[II("image")].data[9] = -0.25f;
        in[II("image")].data[12] = NAN;
        effects_off();
        nprfx_result r;
        size_t bytes = sizeof(float) * (size_t)(w * h * ch);
        nprfx_image out = run(ctx, w, h, &r);
        CHECK_OK(r);
        CHECK(memcmp(out.data, in[II("image")].data, bytes) == 0);
        nprfx_image_free(&out);
        set("wobble", 5);
        out = run(ctx, w, h, &r);
        CHECK_OK(r);
        CHECK(memcmp(out.data, in[II("image")].data, bytes) == 0);
        nprfx_image_free(&out);
        set("wobble", 0);
        set("granulation", 0);
        in[II("paper")] = random_image(w, h, 1, 12);
        out = run(ctx, w, h, &r);
        CHECK_OK(r);
        CHECK(memcmp(out.data, in[II("image")].data, bytes) == 0);
        nprfx_image_free(&out);
    }
}

/* Constant textures: out = pigment(pigment(pigment(C, d_T), d_D), d_P), d = 1 + beta (t - 0.5). */
static void test_textures(nprfx_context *ctx)
{
    nprfx_result r;
    reset();
    const float c3[] = {0.5f, 0.2f, 0.9f};
    in[II("image")] = th_image(1, 1, 3, c3);
    in[II("turbulence")] = constant_image(1, 1, 1, 0.8f);
    effects_off();
    set("turbulence", 1.5);
    nprfx_image out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    /* d = 1 + 1.5 * 0.3 = 1.45: 0.5 - 0.25 * 0.45 = 0.3875; 0.2 - 0.16 * 0.45 = 0.128;
     * 0.9 - 0.09 * 0.45 = 0.8595 */
    CHECK_NEAR(out.data[0], 0.3875, TOL);
    CHECK_NEAR(out.data[1], 0.128, TOL);
    CHECK_NEAR(out.data[2], 0.8595, TOL);
    /* the same numbers as the blend node's public formula (one formula,
     * core/looks/internal_blend.h) */
    double d = nprfx_blend_pigment_density((double)0.8f, 1.5);
    for (int c = 0; c < 3; c++)
        CHECK(out.data[c] == (float)nprfx_blend_pigment(c3[c], d));
    nprfx_image_free(&out);

    /* T 0.8 (beta 1), D 0.3 (beta 2), P 0.6 (beta 1) on C 0.5, in that order:
     * d 1.3: 0.5 - 0.25 * 0.3 = 0.425
     * d 0.6: 0.425 - (0.425 - 0.180625)(-0.4) = 0.425 + 0.09775 = 0.52275
     * d 1.1: 0.52275 - (0.52275 - 0.2732675625) * 0.1 = 0.52275 - 0.02494824375 = 0.49780175625 */
    reset();
    const float c1[] = {0.5f};
    in[II("image")] = th_image(1, 1, 1, c1);
    in[II("turbulence")] = constant_image(1, 1, 1, 0.8f);
    in[II("dispersion")] = constant_image(1, 1, 1, 0.3f);
    in[II("paper")] = constant_image(1, 1, 1, 0.6f);
    effects_off();
    set("turbulence", 1);
    set("dispersion", 2);
    set("granulation", 1);
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.49780175625, TOL);
    nprfx_image_free(&out);

    /* densities are clamped to [0, 2]: T 1, beta 4 gives d 3 -> 2, C^2 = 0.25 (not -0.0 / black);
     * T 0, beta 4 gives d -1 -> 0, 2C - C^2 = 0.75 */
    reset();
    in[II("image")] = th_image(1, 1, 1, c1);
    in[II("turbulence")] = constant_image(1, 1, 1, 1.0f);
    effects_off();
    set("turbulence", 4);
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.25, TOL);
    nprfx_image_free(&out);
    in[II("turbulence")].data[0] = 0.0f;
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.75, TOL);
    nprfx_image_free(&out);
    /* white paper and black stay as they are */
    in[II("image")].data[0] = 1.0f;
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK(out.data[0] == 1.0f);
    nprfx_image_free(&out);
}

/* Scene-linear colour of any range (an HDR highlight up to 100): a lit yellow in four patches of
 * brightness 1, 5, 20 and 100 under random textures. Without wobble the pigment acts on each
 * channel's part within [0, 1] and the rest passes, so a channel at or above 1 comes out as it
 * went in and one below stays in [0, 1]; with every effect on (the edges of the HDR patches
 * darken hardest) the output stays finite and within [0, 100], no channel pushed negative. */
static void test_hdr(nprfx_context *ctx)
{
    const int w = 64, h = 16;
    const float gain[4] = {1.0f, 5.0f, 20.0f, 100.0f};
    nprfx_result r;
    for (int wob = 0; wob < 2; wob++) {
        reset();
        in[II("image")] = th_image(w, h, 3, NULL);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                float *c = nprfx_image_at(&in[II("image")], x, y), k = gain[x / 16];
                c[0] = 0.9f * k;
                c[1] = 0.8f * k;
                c[2] = 0.02f * k;
            }
        in[II("turbulence")] = random_image(w, h, 1, 11);
        in[II("dispersion")] = random_image(w, h, 1, 12);
        in[II("paper")] = random_image(w, h, 1, 13);
        set("turbulence", 2);
        set("dispersion", 2);
        set("granulation", 2);
        if (!wob) effects_off();
        nprfx_image out = run(ctx, w, h, &r);
        CHECK_OK(r);
        int bad = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                for (int c = 0; c < 3; c++) {
                    float v = px(&out, x, y, c), c0 = px(&in[II("image")], x, y, c);
                    if (!isfinite(v) || v < 0.0f || v > 100.0f)
                        bad++;
                    else if (!wob && c0 >= 1.0f && v != c0)
                        bad++;
                    else if (!wob && c0 < 1.0f && v > 1.0f)
                        bad++;
                }
        CHECK(bad == 0);
        if (bad)
            fprintf(stderr, "  hdr (wobble and edges %s): %d channel values out\n",
                    wob ? "on" : "off", bad);
        nprfx_image_free(&out);
    }
}

/* A vertical step from a to b between x = 19 and x = 20 of a 40 x 9 RGB image. */
static nprfx_image step_image(const float *a, const float *b)
{
    nprfx_image im = th_image(40, 9, 3, NULL);
    for (int y = 0; y < 9; y++)
        for (int x = 0; x < 40; x++)
            for (int c = 0; c < 3; c++)
                nprfx_image_at(&im, x, y)[c] = x < 20 ? a[c] : b[c];
    return im;
}

static void test_edges(nprfx_context *ctx)
{
    nprfx_result r;
    const float a[] = {0.2f, 0.2f, 0.2f}, b[] = {0.6f, 0.6f, 0.6f};
    reset();
    in[II("image")] = step_image(a, b);
    effects_off();
    set("edge_darkening", 2);
    set("edge_width", 0);
    nprfx_image out = run(ctx, 40, 9, &r);
    CHECK_OK(r);
    /* g = |central difference| = (0.6 - 0.2) / 2 = 0.2 beside the step, d = 1 + 2 * 0.2 = 1.4:
     * 0.2 - 0.16 * 0.4 = 0.136 and 0.6 - 0.24 * 0.4 = 0.504 (both sides darker) */
    for (int y = 0; y < 9; y++) {
        CHECK_NEAR(px(&out, 19, y, 0), 0.136, TOL);
        CHECK_NEAR(px(&out, 20, y, 2), 0.504, TOL);
        /* flat regions are untouched, bit for bit */
        CHECK(px(&out, 18, y, 1) == 0.2f && px(&out, 21, y, 1) == 0.6f);
        CHECK(px(&out, 3, y, 0) == 0.2f && px(&out, 36, y, 0) == 0.6f);
    }
    nprfx_image_free(&out);

    /* A wider darkening: the same strength beside the step (normalised by w_0 + w_1), fading
     * with distance, nothing far away. */
    set("edge_width", 1.5);
    out = run(ctx, 40, 9, &r);
    CHECK_OK(r);
    CHECK_NEAR(px(&out, 19, 4, 0), 0.136, 1e-5);
    CHECK_NEAR(px(&out, 20, 4, 0), 0.504, 1e-5);
    CHECK(px(&out, 18, 4, 0) < 0.2f && px(&out, 18, 4, 0) > px(&out, 19, 4, 0));
    CHECK(px(&out, 21, 4, 0) < 0.6f && px(&out, 21, 4, 0) > px(&out, 20, 4, 0));
    CHECK(px(&out, 17, 4, 0) > px(&out, 18, 4, 0));
    CHECK_NEAR(px(&out, 5, 4, 0), 0.2, 1e-6);
    CHECK_NEAR(px(&out, 34, 4, 0), 0.6, 1e-6);
    nprfx_image_free(&out);

    /* A step in red only: g is the RMS over the colour channels, sqrt(0.2^2 / 3); the density
     * darkens every channel (pigment pools, whatever its colour), capped at 2 */
    reset();
    const float a2[] = {0.2f, 0.5f, 0.5f}, b2[] = {0.6f, 0.5f, 0.5f};
    in[II("image")] = step_image(a2, b2);
    effects_off();
    set("edge_darkening", 3);
    set("edge_width", 0);
    out = run(ctx, 40, 9, &r);
    CHECK_OK(r);
    double dd = 1.0 + 3.0 * sqrt(0.04 / 3.0);
    CHECK_NEAR(px(&out, 19, 4, 0), 0.2 - 0.16 * (dd - 1.0), TOL);
    CHECK_NEAR(px(&out, 19, 4, 1), 0.5 - 0.25 * (dd - 1.0), TOL);
    set("edge_darkening", 100);
    nprfx_image_free(&out);
    out = run(ctx, 40, 9, &r);
    CHECK_OK(r);
    CHECK_NEAR(px(&out, 19, 4, 1), 0.25, TOL); /* d capped at 2: C^2 */
    nprfx_image_free(&out);

    /* Coverage: a flat colour over white paper. The silhouette is a step from 0.5 to 1 (g 0.25),
     * darkened inside; the background stays exactly white. */
    reset();
    const float g5[] = {0.5f, 0.5f, 0.5f};
    in[II("image")] = step_image(g5, g5);
    in[II("coverage")] = th_image(40, 9, 1, NULL);
    for (int y = 0; y < 9; y++)
        for (int x = 0; x < 20; x++)
            nprfx_image_at(&in[II("coverage")], x, y)[0] = 1.0f;
    effects_off();
    set("edge_darkening", 2);
    set("edge_width", 0);
    out = run(ctx, 40, 9, &r);
    CHECK_OK(r);
    /* d = 1.5: 0.5 - 0.25 * 0.5 = 0.375 */
    CHECK_NEAR(px(&out, 19, 4, 0), 0.375, TOL);
    CHECK(px(&out, 10, 4, 0) == 0.5f);
    for (int x = 20; x < 40; x++)
        CHECK(px(&out, x, 4, 0) == 1.0f && px(&out, x, 4, 2) == 1.0f);
    nprfx_image_free(&out);
}

/* A paper ramp P = 0.01 x has gradient (0.01, 0) everywhere inside: the offset is exactly
 * (wobble, 0), and a vertical edge moves by wobble px. */
static void test_wobble_ramp(nprfx_context *ctx)
{
    nprfx_result r;
    const int w = 64, h = 12;
    reset();
    nprfx_image im = th_image(w, h, 3, NULL), paper = th_image(w, h, 1, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            for (int c = 0; c < 3; c++)
                nprfx_image_at(&im, x, y)[c] = x < 32 ? 0.0f : 1.0f;
            nprfx_image_at(&paper, x, y)[0] = 0.01f * (float)x;
        }
    in[II("image")] = im;
    in[II("paper")] = paper;
    effects_off();
    set("granulation", 0);
    set("wobble", 2.5);
    set("wobble_scale", 2);
    nprfx_image out = run(ctx, w, h, &r);
    CHECK_OK(r);
    /* out(x) = C(x + 2.5): 0 up to x = 28, C(31.5) = 0.5 at 29, 1 from 30 (the step was at
     * 31.5, halfway between 31 and 32: it moved to 29, 2.5 px) */
    for (int y = 0; y < h; y++) {
        CHECK(px(&out, 28, y, 0) == 0.0f);
        CHECK_NEAR(px(&out, 29, y, 1), 0.5, 1e-4);
        CHECK(px(&out, 30, y, 2) == 1.0f);
    }
    nprfx_image_free(&out);
    /* wobble 1.25: C(31.25) = 0.25 at x = 30 */
    set("wobble", 1.25);
    out = run(ctx, w, h, &r);
    CHECK_OK(r);
    CHECK_NEAR(px(&out, 30, 5, 0), 0.25, 1e-4);
    nprfx_image_free(&out);
}

/* Any paper: the image is a position ramp, so the output reads back where it was sampled; the
 * displacement never exceeds wobble, and reaches a good part of it. */
static void test_wobble_bound(nprfx_context *ctx)
{
    nprfx_result r;
    const int w = 96, h = 80;
    reset();
    nprfx_image im = th_image(w, h, 3, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            nprfx_image_at(&im, x, y)[0] = (float)x / 128.0f;
            nprfx_image_at(&im, x, y)[1] = (float)y / 128.0f;
            nprfx_image_at(&im, x, y)[2] = 0.5f;
        }
    in[II("image")] = im;
    in[II("paper")] = random_image(w, h, 1, 21);
    effects_off();
    set("granulation", 0);
    const double wob = 3.0;
    set("wobble", wob);
    set("wobble_scale", 5);
    nprfx_image out = run(ctx, w, h, &r);
    CHECK_OK(r);
    double maxd = 0.0, sumd = 0.0;
    int n = 0, over = 0;
    for (int y = 4; y < h - 4; y++)
        for (int x = 4; x < w - 4; x++) {
            double dx = px(&out, x, y, 0) * 128.0 - x, dy = px(&out, x, y, 1) * 128.0 - y;
            double dist = sqrt(dx * dx + dy * dy);
            over += dist > wob + 1e-3;
            maxd = fmax(maxd, dist);
            sumd += dist;
            n++;
        }
    CHECK(over == 0);
    CHECK(maxd > 0.99 * wob);
    CHECK(sumd / n > 0.3 * wob);
    nprfx_image_free(&out);
}

/* Every effect on: the 4th channel is the input's alpha, bit for bit. */
static void fill_all(int w, int h)
{
    reset();
    in[II("image")] = random_image(w, h, 4, 31);
    in[II("turbulence")] = random_image(w, h, 1, 32);
    in[II("dispersion")] = random_image(w, h, 1, 33);
    in[II("paper")] = random_image(w, h, 1, 34);
    in[II("coverage")] = random_image(w, h, 1, 35);
}

static void test_alpha(nprfx_context *ctx)
{
    const int w = 31, h = 23;
    fill_all(w, h);
    nprfx_result r;
    nprfx_image out = run(ctx, w, h, &r);
    CHECK_OK(r);
    int same = 1, changed = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            same &= px(&out, x, y, 3) == px(&in[0], x, y, 3);
            changed += px(&out, x, y, 0) != px(&in[0], x, y, 0);
        }
    CHECK(same);
    CHECK(changed > w * h / 2);
    nprfx_image_free(&out);
}

static void test_errors(nprfx_context *ctx)
{
    nprfx_result r;
    reset();
    in[II("image")] = random_image(4, 4, 3, 41);
    in[II("turbulence")] = random_image(4, 4, 3, 42);
    nprfx_image out = run(ctx, 4, 4, &r);
    CHECK(r == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "'turbulence'") != NULL);
    nprfx_image_free(&out);
    nprfx_image_free(&in[II("turbulence")]);
    /* a param outside its hard range is refused by name */
    set("wobble", 1000);
    out = run(ctx, 4, 4, &r);
    CHECK(r != NPRFX_OK);
    CHECK(strstr(th_error(ctx), "watercolor.wobble") != NULL);
    nprfx_image_free(&out);
    nprfx_image_free(&in[II("image")]);
    set("wobble", 1);
    nprfx_image o3 = th_image(4, 4, 3, NULL);
    CHECK(th_render(ctx, node, in, pv, &o3, o3.bounds) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "'image'") != NULL);

    /* the core function's own checks, for direct callers */
    nprfx_image im = random_image(4, 4, 3, 43), p2 = random_image(4, 4, 2, 44);
    nprfx_watercolor_params p = {.edge_darkening = 1, .wobble = 1, .wobble_scale = 2};
    nprfx_image wi[NPRFX_WATERCOLOR_IN_COUNT] = {0};
    wi[NPRFX_WATERCOLOR_IN_IMAGE] = im;
    wi[NPRFX_WATERCOLOR_IN_PAPER] = p2;
    nprfx_rect f = o3.bounds;
    nprfx_render_args a3 = th_core_args(ctx, wi, &o3, f, f);
    CHECK(nprfx_watercolor_render(&a3, &p) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "input 'paper' has 2 channels") != NULL);
    memset(&wi[NPRFX_WATERCOLOR_IN_PAPER], 0, sizeof wi[0]);
    p.wobble_scale = -1;
    CHECK(nprfx_watercolor_render(&a3, &p) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "watercolor.wobble_scale") != NULL);
    p.wobble_scale = 2;
    p.edge_darkening = -1;
    CHECK(nprfx_watercolor_render(&a3, &p) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "watercolor.edge_darkening") != NULL);
    p.edge_darkening = 1;
    nprfx_image o1 = th_image(4, 4, 1, NULL);
    nprfx_render_args a1 = th_core_args(ctx, wi, &o1, f, f);
    CHECK(nprfx_watercolor_render(&a1, &p) == NPRFX_ERR_SIZE_MISMATCH);
    memset(&wi[NPRFX_WATERCOLOR_IN_IMAGE], 0, sizeof wi[0]);
    CHECK(nprfx_watercolor_render(&a3, &p) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "input 'image' is not connected") != NULL);
    wi[NPRFX_WATERCOLOR_IN_IMAGE] = im;
    CHECK_OK(nprfx_watercolor_render(&a3, &p));
    nprfx_image_free(&im);
    nprfx_image_free(&p2);
    nprfx_image_free(&o1);
    nprfx_image_free(&o3);
}

/* The same pixels with 1 or 4 threads, whole or in tiles, for both blurs of the paper (sampled
 * kernel below sigma 3, recursive above) and a wide edge blur. */
static void test_determinism(nprfx_context *serial)
{
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(4, &pool);
    const int w = 67, h = 45;
    const double scales[] = {2, 6.5}, widths[] = {0, 3.5};
    for (int t = 0; t < 2; t++) {
        fill_all(w, h);
        set("wobble_scale", scales[t]);
        set("edge_width", widths[t]);
        set("wobble", 2.5);
        CHECK(th_same_pixels(serial, par, node, in, pv, w, h, 4, NULL) == 0);
    }
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
}

int main(void)
{
    node = nprfx_node_find("watercolor");
    if (!node) {
        fprintf(stderr, "watercolor is not registered\n");
        return 1;
    }
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    test_descriptor(ctx);
    test_identity(ctx);
    test_textures(ctx);
    test_hdr(ctx);
    test_edges(ctx);
    test_wobble_ramp(ctx);
    test_wobble_bound(ctx);
    test_alpha(ctx);
    test_errors(ctx);
    test_determinism(ctx);
    reset();
    nprfx_context_destroy(ctx);
    return check_finish();
}
