/* warp (core/looks/warp.c), checked against hand-computed results: the exact displacement of
 * linear ramps, through its descriptor and by direct calls of the core function. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/filter.h"
#include "nprfx/node.h"

extern const nprfx_node_desc nprfx_node_warp;

static void test_warp(nprfx_context *ctx)
{
    const nprfx_node_desc *n = &nprfx_node_warp;
    nprfx_rect r = nprfx_rect_make(0, 0, 16, 12);
    nprfx_image ins[2], out;
    nprfx_image_alloc(ctx, r, 2, &ins[0]);
    nprfx_image_alloc(ctx, r, 2, &ins[1]);
    nprfx_image_alloc(ctx, r, 2, &out);
    for (int y = 0; y < 12; y++)
        for (int x = 0; x < 16; x++) {
            float *p = nprfx_image_at(&ins[0], x, y);
            p[0] = 2.0f * x + 3.0f * y; /* a linear ramp: both filters reproduce it exactly */
            p[1] = -1.0f;
            float *o = nprfx_image_at(&ins[1], x, y);
            o[0] = 0.25f;
            o[1] = -0.5f;
        }
    nprfx_value pv[8];
    th_defaults(n, pv);
    th_set(n, pv, "amount", 2.0); /* displacement (0.5, -1) */
    for (int filter = 0; filter < 2; filter++) {
        th_set(n, pv, "filter", filter);
        CHECK_OK(th_render(ctx, n, ins, pv, &out, r));
        int bad = 0;
        for (int y = 3; y < 10; y++)
            for (int x = 2; x < 13; x++) {
                const float *o = nprfx_image_at(&out, x, y);
                bad += fabsf(o[0] - (2.0f * (x + 0.5f) + 3.0f * (y - 1.0f))) > 1e-4f;
                bad += o[1] != -1.0f;
            }
        CHECK(bad == 0);
    }
    /* black border: a lookup far outside reads zero; clamp reads the edge */
    nprfx_image_at(&ins[1], 0, 0)[0] = -4.0f; /* x - 8 */
    th_set(n, pv, "filter", 0);
    th_set(n, pv, "border", 1);
    CHECK_OK(th_render(ctx, n, ins, pv, &out, r));
    CHECK(nprfx_image_at(&out, 0, 0)[0] == 0.0f);
    th_set(n, pv, "border", 0);
    CHECK_OK(th_render(ctx, n, ins, pv, &out, r));
    CHECK_NEAR(nprfx_image_at(&out, 0, 0)[0], 0.0f, 1e-6); /* clamped at (0, 0): ramp value 0 */
    /* a NaN offset leaves the pixel in place; amount 0 is the identity */
    nprfx_image_at(&ins[1], 5, 5)[0] = NAN;
    CHECK_OK(th_render(ctx, n, ins, pv, &out, r));
    CHECK(nprfx_image_at(&out, 5, 5)[0] == nprfx_image_at(&ins[0], 5, 5)[0]);
    th_set(n, pv, "amount", 0.0);
    CHECK_OK(th_render(ctx, n, ins, pv, &out, r));
    CHECK(memcmp(out.data, ins[0].data, sizeof(float) * 16 * 12 * 2) == 0);
    /* a one-channel offset is refused with a message naming the input: by nprfx_node_render
     * (the descriptor declares 2 channels) and by the core function called directly */
    nprfx_image one = nprfx_image_channels(&ins[1], 0, 1);
    nprfx_image bad_ins[2] = {ins[0], one};
    CHECK(th_render(ctx, n, bad_ins, pv, &out, r) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "warp: input 'offset' has 1 channels, expected 2") != NULL);
    nprfx_warp_params wp = {
        .amount = 2.0, .filter = NPRFX_WARP_BICUBIC, .border = NPRFX_BORDER_CLAMP};
    nprfx_render_args wa = th_core_args(ctx, bad_ins, &out, r, r);
    CHECK(nprfx_warp_render(&wa, &wp) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "offset") != NULL);
    /* the core function with the typed params the descriptor binds: the same pixels */
    nprfx_image direct;
    nprfx_image_alloc(ctx, r, 2, &direct);
    th_set(n, pv, "amount", 2.0);
    th_set(n, pv, "filter", 1);
    CHECK_OK(th_render(ctx, n, ins, pv, &out, r));
    wa = th_core_args(ctx, ins, &direct, r, r);
    CHECK_OK(nprfx_warp_render(&wa, &wp));
    CHECK(memcmp(out.data, direct.data, sizeof(float) * 16 * 12 * 2) == 0);
    wp.border = 2;
    CHECK(nprfx_warp_render(&wa, &wp) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "warp.border") != NULL);
    /* reach clamps each component: displacement (0.5, -1) with reach 0.75 reads (0.5, -0.75);
     * with reach 2 nothing changes; the footprint is the reach plus two rows of taps, and -1
     * (anywhere) without one */
    th_set(n, pv, "filter", 0);
    th_set(n, pv, "reach", 0.75);
    CHECK_OK(th_render(ctx, n, ins, pv, &out, r));
    CHECK_NEAR(nprfx_image_at(&out, 6, 6)[0], 2.0f * 6.5f + 3.0f * 5.25f, 1e-4);
    int fp = 0;
    CHECK_OK(nprfx_node_footprint(ctx, n, pv, &fp));
    CHECK(fp == 3);
    th_set(n, pv, "reach", 2.0);
    CHECK_OK(th_render(ctx, n, ins, pv, &out, r));
    CHECK_NEAR(nprfx_image_at(&out, 6, 6)[0], 2.0f * 6.5f + 3.0f * 5.0f, 1e-4);
    th_set(n, pv, "reach", 0.0);
    CHECK_OK(nprfx_node_footprint(ctx, n, pv, &fp));
    CHECK(fp == -1);
    wp.border = NPRFX_BORDER_CLAMP;
    wp.reach = -1;
    CHECK(nprfx_warp_render(&wa, &wp) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "warp.reach") != NULL);
    nprfx_image_free(&direct);
    nprfx_image_free(&ins[0]);
    nprfx_image_free(&ins[1]);
    nprfx_image_free(&out);
}

static void test_descriptor(nprfx_context *ctx)
{
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_warp));
    CHECK(nprfx_node_warp.params_size == sizeof(nprfx_warp_params));
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context_create(&ci, &ctx);
    test_descriptor(ctx);
    test_warp(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
