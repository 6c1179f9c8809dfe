/* The bump node (core/looks/bump.c): a flat height leaves the image bit-identical, a linear ramp gives
 * the hand-computed Lambert value, the light's direction picks which slopes brighten, alpha
 * passes through, edges clamp, and the result does not depend on windows or threads; the error
 * paths, through its descriptor. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/bump.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/node.h"
#include "nprfx/rng.h"

extern const nprfx_node_desc nprfx_node_bump;
static const nprfx_node_desc *N = &nprfx_node_bump;

static nprfx_value pv[8];
static nprfx_image in[2];

enum { W = 23, H = 17 };

static void reset(void)
{
    memset(pv, 0, sizeof pv);
    nprfx_node_defaults(N, pv);
    for (int i = 0; i < N->num_params; i++)
        if (!pv[i].s) pv[i].s = "";
}

static void set(const char *name, double v)
{
    pv[th_param(N, name)].v[0] = v;
}

/* A random image with ch channels (some negative zeros and negatives among them). */
static nprfx_image random_image(int ch, int seed)
{
    nprfx_image im = th_image(W, H, ch, NULL);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            for (int c = 0; c < ch; c++) {
                double u = nprfx_rand_u01((uint64_t)seed, 0, x, y, (uint32_t)c, 0);
                nprfx_image_at(&im, x, y)[c] = u < 0.05 ? -0.0f : (float)(1.5 * u - 0.1);
            }
    return im;
}

/* height(x, y) = a x + b y */
static nprfx_image ramp(double a, double b)
{
    nprfx_image h = th_image(W, H, 1, NULL);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            nprfx_image_at(&h, x, y)[0] = (float)(a * x + b * y);
    return h;
}

static int same(const nprfx_image *a, const nprfx_image *b)
{
    return memcmp(a->data, b->data, sizeof(float) * W * H * (size_t)a->channels) == 0;
}

static void test_lint(nprfx_context *ctx)
{
    CHECK_OK(nprfx_node_lint(ctx, N));
    CHECK(strcmp(N->id, "bump") == 0 && strcmp(N->group, "NPR") == 0);
    CHECK(N->inputs[th_input(N, "image")].flags & NPRFX_INPUT_MAIN);
    CHECK(N->inputs[th_input(N, "height")].channels == 1);
}

static void test_flat(nprfx_context *ctx)
{
    for (int ch = 1; ch <= 4; ch++) {
        reset();
        set("strength", 7);
        set("azimuth", 33);
        set("elevation", 20);
        set("amount", 1.7);
        set("specular", ch == 3 ? 0.8 : 0.0); /* the highlight of flat paper is taken away too */
        in[0] = random_image(ch, ch);
        in[1] = th_image(W, H, 1, NULL);
        float c = 0.37f;
        nprfx_image_fill(&in[1], &c);
        nprfx_image out = th_image(W, H, ch, NULL);
        CHECK_OK(th_render(ctx, N, in, pv, &out, out.bounds));
        CHECK(same(&in[0], &out));
        nprfx_image_free(&in[0]);
        nprfx_image_free(&in[1]);
        nprfx_image_free(&out);
    }
}

/* A ramp of slope k along x: n = (-s k, 0, 1) / sqrt(1 + s^2 k^2) inside the frame; at the
 * left and right edges the clamped central difference halves the slope. */
static void test_ramp(nprfx_context *ctx)
{
    const double k = 0.1, s = 3, az = 200, el = 35, amount = 0.8;
    reset();
    set("strength", s);
    set("azimuth", az);
    set("elevation", el);
    set("amount", amount);
    in[0] = random_image(4, 9);
    in[1] = ramp(k, 0);
    nprfx_image out = th_image(W, H, 4, NULL);
    CHECK_OK(th_render(ctx, N, in, pv, &out, out.bounds));
    const double d2r = 3.14159265358979323846 / 180;
    double lx = cos(el * d2r) * cos(az * d2r), ly = -cos(el * d2r) * sin(az * d2r),
           lz = sin(el * d2r);
    (void)ly;
    double err = 0, aerr = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double slope = (x == 0 || x == W - 1) ? k / 2 : k; /* clamped at the edges */
            double nx = -s * slope, len = sqrt(1 + nx * nx);
            double shade = fmax(0.0, (nx * lx + lz) / len) / lz;
            const float *i = nprfx_image_at(&in[0], x, y), *o = nprfx_image_at(&out, x, y);
            for (int c = 0; c < 3; c++)
                err = fmax(err, fabs(o[c] - i[c] * (1 + amount * (shade - 1))));
            aerr = fmax(aerr, fabs(o[3] - i[3]));
        }
    CHECK(err < 2e-6);
    CHECK(aerr == 0); /* alpha passes through */
    /* the hand value once more, written out: a pixel inside, s k = 0.3, light from azimuth 200 */
    double want =
        (0.3 * cos(el * d2r) * cos(20 * d2r) + sin(el * d2r)) / sqrt(1.09) / sin(el * d2r);
    CHECK_NEAR(nprfx_image_at(&out, 5, 5)[0],
               nprfx_image_at(&in[0], 5, 5)[0] * (1 + amount * (want - 1)), 2e-6);
    nprfx_image_free(&in[0]);
    nprfx_image_free(&in[1]);
    nprfx_image_free(&out);
}

/* Light from the left (azimuth 180) brightens slopes that face left (height rising to the
 * right) and darkens those that face right; from the top (90, y down) those facing up. */
static void test_light_direction(nprfx_context *ctx)
{
    struct {
        double az, a, b;
        int brighter;
    } cases[] = {{180, 0.1, 0, 1}, {180, -0.1, 0, 0}, {0, -0.1, 0, 1},
                 {90, 0, 0.1, 1},  {90, 0, -0.1, 0},  {270, 0, -0.1, 1}};
    for (int t = 0; t < 6; t++) {
        reset();
        set("azimuth", cases[t].az);
        set("elevation", 40);
        in[0] = th_image(W, H, 3, NULL);
        float grey[3] = {0.5f, 0.5f, 0.5f};
        nprfx_image_fill(&in[0], grey);
        in[1] = ramp(cases[t].a, cases[t].b);
        nprfx_image out = th_image(W, H, 3, NULL);
        CHECK_OK(th_render(ctx, N, in, pv, &out, out.bounds));
        float v = nprfx_image_at(&out, 10, 8)[1];
        CHECK(cases[t].brighter ? v > 0.55f : v < 0.45f);
        nprfx_image_free(&in[0]);
        nprfx_image_free(&in[1]);
        nprfx_image_free(&out);
    }
    /* a highlight only adds */
    reset();
    set("specular", 0.5);
    set("azimuth", 180);
    in[0] = random_image(3, 4);
    in[1] = ramp(0.2, 0.05);
    nprfx_image with = th_image(W, H, 3, NULL), without = th_image(W, H, 3, NULL);
    CHECK_OK(th_render(ctx, N, in, pv, &with, with.bounds));
    set("specular", 0);
    CHECK_OK(th_render(ctx, N, in, pv, &without, without.bounds));
    int ge = 1, gt = 0;
    for (int i = 0; i < W * H * 3; i++) {
        ge &= with.data[i] >= without.data[i];
        gt += with.data[i] > without.data[i];
    }
    CHECK(ge && gt > 0);
    nprfx_image_free(&in[0]);
    nprfx_image_free(&in[1]);
    nprfx_image_free(&with);
    nprfx_image_free(&without);
}

static void test_invariance(nprfx_context *serial)
{
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(3, &pool);
    reset();
    set("specular", 0.3);
    set("strength", 9);
    in[0] = random_image(4, 11);
    in[1] = random_image(1, 12);
    nprfx_image whole = th_image(W, H, 4, NULL), tiled = th_image(W, H, 4, NULL);
    CHECK_OK(th_render(serial, N, in, pv, &whole, whole.bounds));
    for (int ty = 0; ty < H; ty += 5)
        for (int tx = 0; tx < W; tx += 7)
            CHECK_OK(th_render(par, N, in, pv, &tiled, nprfx_rect_make(tx, ty, tx + 7, ty + 5)));
    CHECK(same(&whole, &tiled));
    nprfx_image_free(&in[0]);
    nprfx_image_free(&in[1]);
    nprfx_image_free(&whole);
    nprfx_image_free(&tiled);
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
}

static void test_errors(nprfx_context *ctx)
{
    reset();
    in[0] = random_image(3, 1);
    memset(&in[1], 0, sizeof in[1]);
    nprfx_image out = th_image(W, H, 3, NULL);
    CHECK(th_render(ctx, N, in, pv, &out, out.bounds) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "height") != NULL);
    in[1] = th_image(W, H, 2, NULL); /* the height has one channel */
    CHECK(th_render(ctx, N, in, pv, &out, out.bounds) != NPRFX_OK);
    nprfx_image_free(&in[1]);
    in[1] = th_image(W, H, 1, NULL);
    set("elevation", 0);
    CHECK(th_render(ctx, N, in, pv, &out, out.bounds) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "bump.elevation") != NULL);
    reset();
    set("amount", -1);
    CHECK(th_render(ctx, N, in, pv, &out, out.bounds) == NPRFX_ERR_OUT_OF_RANGE);
    /* the core function checks its own params */
    nprfx_bump_params p = {
        .strength = 1, .azimuth = 0, .elevation = 95, .amount = 1, .shininess = 10};
    nprfx_render_args a = th_core_args(ctx, in, &out, out.bounds, out.bounds);
    CHECK(nprfx_bump_render(&a, &p) == NPRFX_ERR_OUT_OF_RANGE);
    p.elevation = 45;
    CHECK_OK(nprfx_bump_render(&a, &p));
    nprfx_image no_height[2] = {in[0]};
    a.inputs = no_height;
    CHECK(nprfx_bump_render(&a, &p) == NPRFX_ERR_MISSING_INPUT);
    nprfx_image_free(&in[0]);
    nprfx_image_free(&in[1]);
    nprfx_image_free(&out);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    test_lint(ctx);
    test_flat(ctx);
    test_ramp(ctx);
    test_light_direction(ctx);
    test_invariance(ctx);
    test_errors(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
