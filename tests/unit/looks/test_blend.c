/* Unit tests for core/looks/blend.c (each formula against hand-computed numbers) and the blend node
 * (broadcast, alpha vs opacity, coverage/background, back, window, errors, determinism across
 * thread counts and tile splits). */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/blend.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/node.h"
#include "nprfx/rng.h"

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

/* Render into a fresh output with base's channels over the whole frame. */
static nprfx_image run(nprfx_context *ctx, int w, int h, nprfx_result *res)
{
    nprfx_image out = th_image(w, h, in[II("base")].channels, NULL);
    *res = th_render(ctx, node, in, pv, &out, out.bounds);
    return out;
}

/* ---- the formulas ---- */

static void test_formulas(void)
{
    /* alphaBlend: 0.75 * 0.2 + 0.25 * 0.8 = 0.35 */
    CHECK_NEAR(nprfx_blend_alpha(0.2, 0.8, 0.25), 0.35, 1e-12);
    CHECK_NEAR(nprfx_blend_alpha(0.2, 0.8, 0.0), 0.2, 1e-12);
    CHECK_NEAR(nprfx_blend_alpha(0.2, 0.8, 1.0), 0.8, 1e-12);
    /* overlay: base 0.5, layer 0.25, f 1.2 => 0.5 * 1.2 * (1 - 0.5 * 0.75) = 0.375 */
    CHECK_NEAR(nprfx_blend_overlay(0.5, 0.25, 1.2), 0.375, 1e-12);
    /* overlay of white layer: c0 f (1 - 0) = 0.3 * 0.7 = 0.21 */
    CHECK_NEAR(nprfx_blend_overlay(0.3, 1.0, 0.7), 0.21, 1e-12);
    /* overlayAlpha: back 0.1, c0 0.5, c1 0.25, f 1.2, a 0.5
     * => 0.1 * 0.5 + 0.5 * 0.5 * 1.2 * (1 - (1 - 0.25)(1 - 0.25)) = 0.05 + 0.3 * 0.4375
     *  = 0.18125 */
    CHECK_NEAR(nprfx_blend_overlay_alpha(0.1, 0.5, 0.25, 1.2, 0.5), 0.18125, 1e-12);
    /* a = 1: the overlay itself; a = 0: back */
    CHECK_NEAR(nprfx_blend_overlay_alpha(0.1, 0.5, 0.25, 1.2, 1.0), 0.375, 1e-12);
    CHECK_NEAR(nprfx_blend_overlay_alpha(0.1, 0.5, 0.25, 1.2, 0.0), 0.1, 1e-12);
    /* multiply 0.5 * 0.25 = 0.125; screen 1 - 0.5 * 0.75 = 0.625 */
    CHECK_NEAR(nprfx_blend_multiply(0.5, 0.25), 0.125, 1e-12);
    CHECK_NEAR(nprfx_blend_screen(0.5, 0.25), 0.625, 1e-12);
    /* pigment: C 0.5, d 1.5 => 0.5 - (0.5 - 0.25) * 0.5 = 0.375 (denser pigment: darker) */
    CHECK_NEAR(nprfx_blend_pigment(0.5, 1.5), 0.375, 1e-12);
    /* d 0.5 => 0.5 + 0.25 * 0.5 = 0.625 (thinner: lighter); C 0.2, d 2 => 0.2 - 0.16 = 0.04 */
    CHECK_NEAR(nprfx_blend_pigment(0.5, 0.5), 0.625, 1e-12);
    CHECK_NEAR(nprfx_blend_pigment(0.2, 2.0), 0.04, 1e-12);
    /* fixed points 0 and 1, identity at d = 1 */
    CHECK_NEAR(nprfx_blend_pigment(0.0, 3.0), 0.0, 1e-12);
    CHECK_NEAR(nprfx_blend_pigment(1.0, 3.0), 1.0, 1e-12);
    CHECK_NEAR(nprfx_blend_pigment(0.37, 1.0), 0.37, 1e-12);
    /* densities clamp to [0, 2] (beyond, mid colours leave [0, 1]): d 5 acts as 2, C^2 = 0.25
     * (the bare formula gives -0.5); d -3 acts as 0, 2C - C^2 = 0.75 (the bare formula 1.5) */
    CHECK_NEAR(nprfx_blend_pigment(0.5, 5.0), 0.25, 1e-12);
    CHECK_NEAR(nprfx_blend_pigment(0.5, -3.0), 0.75, 1e-12);
    /* colour beyond [0, 1]: the part within takes the pigment, the rest passes (the bare formula
     * gives 100 - (100 - 1e4) = 10000 at d 2 and -9800 at d 0) */
    CHECK_NEAR(nprfx_blend_pigment(100.0, 2.0), 100.0, 1e-12);
    CHECK_NEAR(nprfx_blend_pigment(100.0, 0.0), 100.0, 1e-12);
    CHECK_NEAR(nprfx_blend_pigment(2.5, 1.7), 2.5, 1e-12);
    CHECK_NEAR(nprfx_blend_pigment(-0.25, 2.0), -0.25, 1e-12);
    /* continuous at 1: just below, the pigment's pull is (C - C^2)(d - 1) ~ 1e-6 */
    CHECK_NEAR(nprfx_blend_pigment(1.0 - 1e-6, 2.0), 1.0, 3e-6);
    CHECK(isnan(nprfx_blend_pigment(NAN, 1.5)) && isnan(nprfx_blend_pigment(0.5, NAN)));
    /* screen only lightens: above 1 it is the larger value (the formula gives 5 + 5 - 25 = -15
     * and 2 + 0.5 - 1 = 1.5); continuous at 1 */
    CHECK_NEAR(nprfx_blend_screen(5.0, 5.0), 5.0, 1e-12);
    CHECK_NEAR(nprfx_blend_screen(2.0, 0.5), 2.0, 1e-12);
    CHECK_NEAR(nprfx_blend_screen(0.25, 40.0), 40.0, 1e-12);
    CHECK_NEAR(nprfx_blend_screen(1.0, 0.3), 1.0, 1e-12);
    CHECK(isnan(nprfx_blend_screen(NAN, 0.5)));
    /* the overlays modulate a base above 1 as white: overlay(40, 0.3, 1.2) = 40 * 1.2 * 1 = 48
     * (the formula as written: 40 * 1.2 * (1 + 39 * 0.7) = 1358.4); overlayalpha, back 0.1, a
     * 0.5: 0.05 + 0.5 * 40 * 1.2 * (1 - 0.5 * 0.7) = 15.65 (as written: 343.25); continuous at 1 */
    CHECK_NEAR(nprfx_blend_overlay(40.0, 0.3, 1.2), 48.0, 1e-12);
    CHECK_NEAR(nprfx_blend_overlay_alpha(0.1, 40.0, 0.3, 1.2, 0.5), 15.65, 1e-12);
    CHECK_NEAR(nprfx_blend_overlay(1.0, 0.3, 1.2), 1.2, 1e-12);
    /* density d = 1 + beta (T - 0.5): T 0.75, beta 2 => 1.5; T 0.5 => 1 */
    CHECK_NEAR(nprfx_blend_pigment_density(0.75, 2.0), 1.5, 1e-12);
    CHECK_NEAR(nprfx_blend_pigment_density(0.5, 7.0), 1.0, 1e-12);

    /* the node's opacity rule: modes other than alphablend/overlayalpha mix over c0 by a */
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_ALPHABLEND, 9, 0.2, 0.8, 5, 0.25), 0.35, 1e-12);
    /* overlay, a 0.5: 0.5 * 0.5 + 0.5 * 0.375 = 0.4375 */
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_OVERLAY, 9, 0.5, 0.25, 1.2, 0.5), 0.4375, 1e-12);
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_OVERLAY, 9, 0.5, 0.25, 1.2, 1.0), 0.375, 1e-12);
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_OVERLAYALPHA, 0.1, 0.5, 0.25, 1.2, 0.5), 0.18125,
               1e-12);
    /* multiply, a 0.5: 0.25 + 0.0625 = 0.3125; screen, a 0.25: 0.375 + 0.15625 = 0.53125 */
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_MULTIPLY, 9, 0.5, 0.25, 1, 0.5), 0.3125, 1e-12);
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_SCREEN, 9, 0.5, 0.25, 1, 0.25), 0.53125, 1e-12);
    /* pigment: c0 0.5, layer 0.75, f 2 => d 1.5 => 0.375; a 0.5 => 0.4375 */
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_PIGMENT, 9, 0.5, 0.75, 2, 1.0), 0.375, 1e-12);
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_PIGMENT, 9, 0.5, 0.75, 2, 0.5), 0.4375, 1e-12);
    /* difference: f |c0 - c1|: 2 |0.5 - 0.75| = 0.5 both ways; a 0.5 => 0.25 + 0.25 = 0.5 */
    CHECK_NEAR(nprfx_blend_difference(0.5, 0.75, 2), 0.5, 1e-12);
    CHECK_NEAR(nprfx_blend_difference(0.75, 0.5, 2), 0.5, 1e-12);
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_DIFFERENCE, 9, 0.5, 0.75, 2, 1.0), 0.5, 1e-12);
    CHECK_NEAR(nprfx_blend_apply(NPRFX_BLEND_DIFFERENCE, 9, 0.2, 0.75, 2, 0.5), 0.65, 1e-12);
}

/* ---- the node ---- */

static void test_descriptor(nprfx_context *ctx)
{
    CHECK(node != NULL);
    CHECK_OK(nprfx_node_lint(ctx, node));
    CHECK(node->params_size == sizeof(nprfx_blend_params));
    CHECK(strcmp(node->id, "blend") == 0);
    const nprfx_param_desc *m = &node->params[PI("mode")];
    const char *want[] = {"alphablend", "overlay", "overlayalpha", "multiply",
                          "screen",     "pigment", "difference"};
    for (int i = 0; i < NPRFX_BLEND_MODE_COUNT; i++)
        CHECK(m->choices[i] && strcmp(m->choices[i], want[i]) == 0);
    CHECK(m->choices[NPRFX_BLEND_MODE_COUNT] == NULL);
    for (int i = 0; i < NPRFX_BLEND_MODE_COUNT; i++)
        CHECK(m->choice_help && m->choice_help[i]);
    const char *names[] = {"factor", "opacity", "gain_base", "gain_layer", "background"};
    for (int i = 0; i < 5; i++)
        CHECK(nprfx_node_param_index(node, names[i]) >= 0);
    const char *inames[] = {"base", "layer", "back", "alpha", "coverage"};
    for (int i = 0; i < 5; i++)
        CHECK(nprfx_node_input_index(node, inames[i]) >= 0);
    for (int i = 0; i < node->num_params; i++)
        CHECK(node->params[i].help && node->params[i].help[0]);
}

static void test_broadcast(nprfx_context *ctx)
{
    nprfx_result r;
    /* RGBA base, 1-channel layer, multiply: the layer value scales R, G, B; A passes through */
    reset();
    const float base[] = {0.5f, 0.2f, 0.8f, 0.7f, 1.0f, 0.0f, 0.25f, 0.3f};
    const float layer[] = {0.25f, 0.5f};
    in[II("base")] = th_image(2, 1, 4, base);
    in[II("layer")] = th_image(2, 1, 1, layer);
    set_mode("multiply");
    nprfx_image out = run(ctx, 2, 1, &r);
    CHECK_OK(r);
    const float want[] = {0.125f, 0.05f, 0.2f, 0.7f, 0.5f, 0.0f, 0.125f, 0.3f};
    for (int i = 0; i < 8; i++)
        CHECK_NEAR(out.data[i], want[i], TOL);
    nprfx_image_free(&out);

    /* RGB layer onto RGBA base, screen, gains: c0 = 2 * base, c1 = 0.5 * layer */
    nprfx_image_free(&in[II("layer")]);
    const float layer3[] = {0.2f, 0.4f, 0.6f, 1.0f, 0.0f, 0.5f};
    in[II("layer")] = th_image(2, 1, 3, layer3);
    set_mode("screen");
    pv[PI("gain_base")].v[0] = 2.0;
    pv[PI("gain_layer")].v[0] = 0.5;
    out = run(ctx, 2, 1, &r);
    CHECK_OK(r);
    /* pixel 0: c0 = (1, 0.4, 1.6), c1 = (0.1, 0.2, 0.3):
     * 1 - 0 * 0.9 = 1; 1 - 0.6 * 0.8 = 0.52; 1.6 above 1: max 1.6; alpha 0.7 unchanged */
    CHECK_NEAR(out.data[0], 1.0, TOL);
    CHECK_NEAR(out.data[1], 0.52, TOL);
    CHECK_NEAR(out.data[2], 1.6, TOL);
    CHECK_NEAR(out.data[3], 0.7, TOL);
    /* pixel 1: c0 = (2, 0, 0.5), c1 = (0.5, 0, 0.25): max 2; 0; 1 - 0.5*0.75 */
    CHECK_NEAR(out.data[4], 2.0, TOL);
    CHECK_NEAR(out.data[5], 0.0, TOL);
    CHECK_NEAR(out.data[6], 0.625, TOL);
    CHECK_NEAR(out.data[7], 0.3, TOL);
    nprfx_image_free(&out);

    /* An RGBA layer onto an RGB base: the layer's alpha is ignored */
    reset();
    const float b3[] = {0.5f, 0.5f, 0.5f};
    const float l4[] = {0.2f, 0.4f, 0.6f, 0.0f};
    in[II("base")] = th_image(1, 1, 3, b3);
    in[II("layer")] = th_image(1, 1, 4, l4);
    set_mode("alphablend");
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.2, TOL);
    CHECK_NEAR(out.data[1], 0.4, TOL);
    CHECK_NEAR(out.data[2], 0.6, TOL);
    nprfx_image_free(&out);

    /* A 2-channel layer onto an RGB base has no reading: refused, naming the input */
    nprfx_image_free(&in[II("layer")]);
    const float l2[] = {0.1f, 0.2f};
    in[II("layer")] = th_image(1, 1, 2, l2);
    out = run(ctx, 1, 1, &r);
    CHECK(r == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "layer") != NULL);
    nprfx_image_free(&out);

    /* A missing layer is reported as such */
    nprfx_image_free(&in[II("layer")]);
    out = run(ctx, 1, 1, &r);
    CHECK(r == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "blend: input 'layer' is not connected") != NULL);
    nprfx_image_free(&out);
}

static void test_alpha_opacity(nprfx_context *ctx)
{
    nprfx_result r;
    reset();
    const float base[] = {0.2f, 0.2f, 0.2f};
    const float layer[] = {0.8f, 0.8f, 0.8f};
    const float alpha[] = {0.5f, 1.0f, 2.0f};
    in[II("base")] = th_image(3, 1, 1, base);
    in[II("layer")] = th_image(3, 1, 1, layer);
    set_mode("alphablend");
    /* opacity alone: a = 0.25 everywhere => 0.35 */
    pv[PI("opacity")].v[0] = 0.25;
    nprfx_image out = run(ctx, 3, 1, &r);
    CHECK_OK(r);
    for (int i = 0; i < 3; i++)
        CHECK_NEAR(out.data[i], 0.35, TOL);
    nprfx_image_free(&out);
    /* alpha input times opacity 0.5: a = 0.25, 0.5, 1 (2 * 0.5) => 0.35, 0.5, 0.8 */
    in[II("alpha")] = th_image(3, 1, 1, alpha);
    pv[PI("opacity")].v[0] = 0.5;
    out = run(ctx, 3, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.35, TOL);
    CHECK_NEAR(out.data[1], 0.5, TOL);
    CHECK_NEAR(out.data[2], 0.8, TOL);
    nprfx_image_free(&out);
    /* alpha 2 with opacity 1 is clamped to a = 1 => layer exactly */
    pv[PI("opacity")].v[0] = 1.0;
    out = run(ctx, 3, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[2], 0.8, TOL);
    nprfx_image_free(&out);

    /* overlay mixed over c0 by a: base 0.5, layer 0.25, f 1.2, a 0.5 => 0.4375 */
    reset();
    const float b[] = {0.5f};
    const float l[] = {0.25f};
    const float a[] = {0.5f};
    in[II("base")] = th_image(1, 1, 1, b);
    in[II("layer")] = th_image(1, 1, 1, l);
    in[II("alpha")] = th_image(1, 1, 1, a);
    set_mode("overlay");
    pv[PI("factor")].v[0] = 1.2;
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.4375, TOL);
    nprfx_image_free(&out);

    /* overlayalpha without back: back = base (no gain). base 0.5, gain_base 1, layer 0.25,
     * f 1.2, a 0.5 => 0.5 * 0.5 + 0.5 * 0.5 * 1.2 * (1 - 0.75 * 0.75) = 0.25 + 0.13125 */
    set_mode("overlayalpha");
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.38125, TOL);
    nprfx_image_free(&out);
    /* with back 0.1 => 0.18125 */
    const float k[] = {0.1f};
    in[II("back")] = th_image(1, 1, 1, k);
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.18125, TOL);
    nprfx_image_free(&out);
    /* gain_base 0.5 makes c0 0.25 (back stays 0.1): 0.05 + 0.5 * 0.25 * 1.2 * (1 - 0.875 * 0.75)
     * = 0.05 + 0.15 * 0.34375 = 0.1015625 */
    pv[PI("gain_base")].v[0] = 0.5;
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.1015625, TOL);
    nprfx_image_free(&out);

    /* pigment through the node: c0 0.5, layer 0.75, factor 2, a 1 => 0.375 */
    reset();
    in[II("base")] = th_image(1, 1, 1, b);
    const float t[] = {0.75f};
    in[II("layer")] = th_image(1, 1, 1, t);
    set_mode("pigment");
    pv[PI("factor")].v[0] = 2.0;
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.375, TOL);
    nprfx_image_free(&out);
}

static void test_coverage(nprfx_context *ctx)
{
    nprfx_result r;
    reset();
    /* RGBA base, alphablend to the layer (a = 1), coverage 1, 0.5, 0 */
    const float base[] = {0.1f, 0.2f, 0.3f, 0.4f, 0.1f, 0.2f, 0.3f, 0.4f, 0.1f, 0.2f, 0.3f, 0.4f};
    const float layer[] = {0.6f, 0.6f, 0.6f};
    const float cov[] = {1.0f, 0.5f, 0.0f};
    in[II("base")] = th_image(3, 1, 4, base);
    in[II("layer")] = th_image(3, 1, 1, layer);
    in[II("coverage")] = th_image(3, 1, 1, cov);
    set_mode("alphablend");
    double *bg = pv[PI("background")].v;
    bg[0] = 0.9, bg[1] = 0.8, bg[2] = 0.7, bg[3] = 1.0;
    nprfx_image out = run(ctx, 3, 1, &r);
    CHECK_OK(r);
    /* covered: the blend (0.6 each), alpha passes (0.4) */
    CHECK_NEAR(out.data[0], 0.6, TOL);
    CHECK_NEAR(out.data[1], 0.6, TOL);
    CHECK_NEAR(out.data[2], 0.6, TOL);
    CHECK_NEAR(out.data[3], 0.4, TOL);
    /* half: (0.6 + 0.9) / 2 = 0.75, (0.6 + 0.8) / 2 = 0.7, 0.65, alpha (0.4 + 1) / 2 = 0.7 */
    CHECK_NEAR(out.data[4], 0.75, TOL);
    CHECK_NEAR(out.data[5], 0.7, TOL);
    CHECK_NEAR(out.data[6], 0.65, TOL);
    CHECK_NEAR(out.data[7], 0.7, TOL);
    /* background exactly */
    CHECK(out.data[8] == 0.9f && out.data[9] == 0.8f && out.data[10] == 0.7f &&
          out.data[11] == 1.0f);
    nprfx_image_free(&out);

    /* 1-channel base: the background's Rec. 709 luminance
     * 0.2126 * 0.9 + 0.7152 * 0.8 + 0.0722 * 0.7 = 0.19134 + 0.57216 + 0.05054 = 0.81404 */
    reset();
    const float b1[] = {0.3f};
    const float z[] = {0.0f};
    in[II("base")] = th_image(1, 1, 1, b1);
    in[II("layer")] = th_image(1, 1, 1, b1);
    in[II("coverage")] = th_image(1, 1, 1, z);
    bg = pv[PI("background")].v;
    bg[0] = 0.9, bg[1] = 0.8, bg[2] = 0.7, bg[3] = 1.0;
    out = run(ctx, 1, 1, &r);
    CHECK_OK(r);
    CHECK_NEAR(out.data[0], 0.81404, TOL);
    nprfx_image_free(&out);
}

static void test_window(nprfx_context *ctx)
{
    /* Only the window is written; an input smaller than the frame reads as 0 outside. */
    reset();
    const float base[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    in[II("base")] = th_image(4, 3, 1, base);
    in[II("layer")] = th_image(2, 2, 1, NULL); /* covers x, y in [0, 2) */
    in[II("layer")].data[0] = 0.5f;
    set_mode("multiply");
    nprfx_image out = th_image(4, 3, 1, NULL);
    for (int i = 0; i < 12; i++)
        out.data[i] = -7.0f;
    CHECK_OK(th_render(ctx, node, in, pv, &out, nprfx_rect_make(0, 0, 3, 2)));
    /* row 0: 1 * 0.5, 2 * 0 (layer zero), 3 * 0 (outside layer), untouched */
    CHECK_NEAR(out.data[0], 0.5, TOL);
    CHECK_NEAR(out.data[1], 0.0, TOL);
    CHECK_NEAR(out.data[2], 0.0, TOL);
    CHECK(out.data[3] == -7.0f);
    CHECK(out.data[7] == -7.0f);
    for (int i = 8; i < 12; i++)
        CHECK(out.data[i] == -7.0f);
    nprfx_image_free(&out);
}

/* nprfx_blend_render called directly, with the typed params the descriptor binds: the same
 * pixels as through the node, and its own checks with messages naming the input or param. */
static void test_core_api(nprfx_context *ctx)
{
    reset();
    const float base[] = {0.5f, 0.2f, 0.8f, 0.7f, 1.0f, 0.0f, 0.25f, 0.3f};
    const float layer[] = {0.25f, 0.5f};
    const float back[] = {0.1f, 0.9f};
    const float cov[] = {1.0f, 0.25f};
    in[II("base")] = th_image(2, 1, 4, base);
    in[II("layer")] = th_image(2, 1, 1, layer);
    in[II("back")] = th_image(2, 1, 1, back);
    in[II("coverage")] = th_image(2, 1, 1, cov);
    set_mode("overlayalpha");
    pv[PI("factor")].v[0] = 1.2;
    pv[PI("opacity")].v[0] = 0.5;
    nprfx_result r;
    nprfx_image via_node = run(ctx, 2, 1, &r);
    CHECK_OK(r);
    nprfx_blend_params p = {.mode = NPRFX_BLEND_OVERLAYALPHA,
                            .factor = 1.2,
                            .opacity = 0.5,
                            .gain_base = 1,
                            .gain_layer = 1,
                            .background = {1, 1, 1, 1}};
    nprfx_image direct = th_image(2, 1, 4, NULL);
    nprfx_render_args a = th_core_args(ctx, in, &direct, direct.bounds, direct.bounds);
    CHECK_OK(nprfx_blend_render(&a, &p));
    CHECK(memcmp(via_node.data, direct.data, sizeof(float) * 8) == 0);
    /* pixel 0, channel 0: back 0.1, c0 0.5, c1 0.25, f 1.2, a 0.5 => 0.18125 (coverage 1) */
    CHECK_NEAR(direct.data[0], 0.18125, TOL);
    /* pixel 1, alpha: coverage 0.25 over background 1 => 0.75 * 1 + 0.25 * 0.3 = 0.825 */
    CHECK_NEAR(direct.data[7], 0.825, TOL);
    /* the checks only the core function can make for a direct caller */
    p.mode = NPRFX_BLEND_MODE_COUNT;
    CHECK(nprfx_blend_render(&a, &p) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "blend.mode") != NULL);
    p.mode = NPRFX_BLEND_MULTIPLY;
    nprfx_image base_only[NPRFX_BLEND_IN_COUNT] = {in[II("base")]};
    a.inputs = base_only;
    CHECK(nprfx_blend_render(&a, &p) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "input 'layer'") != NULL);
    nprfx_image three = th_image(2, 1, 3, NULL);
    a = th_core_args(ctx, in, &three, three.bounds, three.bounds);
    CHECK(nprfx_blend_render(&a, &p) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "output has 3 channels") != NULL);
    nprfx_image_free(&three);
    nprfx_image_free(&via_node);
    nprfx_image_free(&direct);
}

static void test_determinism(nprfx_context *serial)
{
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(4, &pool);
    const int w = 67, h = 45;
    for (int mode = 0; mode < NPRFX_BLEND_MODE_COUNT; mode++) {
        reset();
        in[II("base")] = th_image(w, h, 4, NULL);
        in[II("layer")] = th_image(w, h, 1, NULL);
        in[II("back")] = th_image(w, h, 3, NULL);
        in[II("alpha")] = th_image(w, h, 1, NULL);
        in[II("coverage")] = th_image(w, h, 1, NULL);
        for (int i = 0; i < 5; i++) {
            nprfx_image *im = &in[i];
            for (int y = 0; y < h; y++)
                for (int x = 0; x < w; x++)
                    for (int c = 0; c < im->channels; c++)
                        nprfx_image_at(im, x, y)[c] =
                            (float)nprfx_rand_u01(7, 1, x, y, (uint32_t)c, (uint32_t)i);
        }
        pv[PI("mode")].v[0] = mode;
        pv[PI("factor")].v[0] = 1.2;
        pv[PI("opacity")].v[0] = 0.8;
        pv[PI("gain_base")].v[0] = 0.9;
        CHECK(th_same_pixels(serial, par, node, in, pv, w, h, 4, NULL) == 0);
    }
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
}

int main(void)
{
    node = nprfx_node_find("blend");
    if (!node) {
        fprintf(stderr, "blend is not registered\n");
        return 1;
    }
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    test_formulas();
    test_descriptor(ctx);
    test_broadcast(ctx);
    test_alpha_opacity(ctx);
    test_coverage(ctx);
    test_window(ctx);
    test_core_api(ctx);
    test_determinism(ctx);
    reset();
    nprfx_context_destroy(ctx);
    return check_finish();
}
