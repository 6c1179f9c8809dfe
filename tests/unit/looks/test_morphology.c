/* morphology (core/looks/morphology.c), checked against hand-computed results: footprints and
 * the open/close identities, through its descriptor and by direct calls of the core function. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/filter.h"
#include "nprfx/node.h"

extern const nprfx_node_desc nprfx_node_morphology;

static float px(const nprfx_image *im, int x, int y)
{
    return nprfx_image_at(im, x, y)[0];
}

static void test_morphology(nprfx_context *ctx)
{
    const nprfx_node_desc *n = &nprfx_node_morphology;
    nprfx_rect r = nprfx_rect_make(0, 0, 12, 10);
    nprfx_image in, out, tiled;
    nprfx_image_alloc(ctx, r, 1, &in);
    nprfx_image_alloc(ctx, r, 1, &out);
    nprfx_image_alloc(ctx, r, 1, &tiled);
    nprfx_value pv[8];
    th_defaults(n, pv);
    nprfx_image_at(&in, 5, 5)[0] = 1.0f;

    /* dilate, disc radius 1: the 5-pixel cross */
    th_set(n, pv, "operation", 0);
    th_set(n, pv, "radius", 1);
    th_set(n, pv, "footprint", 0);
    CHECK_OK(th_render(ctx, n, &in, pv, &out, r));
    int cross = 0, total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++) {
            total += px(&out, x, y) == 1.0f;
            cross += px(&out, x, y) == 1.0f && abs(x - 5) + abs(y - 5) <= 1;
        }
    CHECK(total == 5 && cross == 5);
    /* square radius 1: 3x3; disc radius 1.5: 3x3 too (corners at distance sqrt 2) */
    th_set(n, pv, "footprint", 1);
    CHECK_OK(th_render(ctx, n, &in, pv, &out, r));
    total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            total += px(&out, x, y) == 1.0f;
    CHECK(total == 9);
    th_set(n, pv, "footprint", 0);
    th_set(n, pv, "radius", 2);
    CHECK_OK(th_render(ctx, n, &in, pv, &out, r));
    total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            total += px(&out, x, y) == 1.0f;
    CHECK(total == 13); /* offsets with dx^2 + dy^2 <= 4 */

    /* erode a 3x3 block with a square of radius 1: its centre only */
    for (int y = 4; y <= 6; y++)
        for (int x = 4; x <= 6; x++)
            nprfx_image_at(&in, x, y)[0] = 1.0f;
    th_set(n, pv, "operation", 1);
    th_set(n, pv, "footprint", 1);
    th_set(n, pv, "radius", 1);
    CHECK_OK(th_render(ctx, n, &in, pv, &out, r));
    total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            total += px(&out, x, y) == 1.0f;
    CHECK(total == 1 && px(&out, 5, 5) == 1.0f);

    /* open keeps the 3x3 block and removes an isolated speck; close fills a one-pixel hole */
    nprfx_image_at(&in, 10, 1)[0] = 1.0f;
    th_set(n, pv, "operation", 2);
    CHECK_OK(th_render(ctx, n, &in, pv, &out, r));
    CHECK(px(&out, 10, 1) == 0.0f && px(&out, 4, 4) == 1.0f && px(&out, 6, 6) == 1.0f);
    total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            total += px(&out, x, y) == 1.0f;
    CHECK(total == 9);
    float one = 1.0f;
    nprfx_image_fill(&in, &one);
    nprfx_image_at(&in, 3, 3)[0] = 0.25f;
    th_set(n, pv, "operation", 3);
    CHECK_OK(th_render(ctx, n, &in, pv, &out, r));
    CHECK(px(&out, 3, 3) == 1.0f);

    /* tiles agree with the whole frame (open/close compute their first pass on a grown area) */
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            nprfx_image_at(&in, x, y)[0] = (float)((x * 7 + y * 13) % 5);
    for (int op = 0; op < 4; op++) {
        th_set(n, pv, "operation", op);
        th_set(n, pv, "footprint", 0);
        th_set(n, pv, "radius", 1.5);
        CHECK_OK(th_render(ctx, n, &in, pv, &out, r));
        nprfx_rect tiles[3] = {nprfx_rect_make(0, 0, 5, 10), nprfx_rect_make(5, 0, 12, 4),
                               nprfx_rect_make(5, 4, 12, 10)};
        for (int t = 0; t < 3; t++)
            CHECK_OK(th_render(ctx, n, &in, pv, &tiled, tiles[t]));
        CHECK(memcmp(out.data, tiled.data, sizeof(float) * 120) == 0);
    }
    /* erode <= image <= dilate; open <= image <= close */
    nprfx_image lo, hi;
    nprfx_image_alloc(ctx, r, 1, &lo);
    nprfx_image_alloc(ctx, r, 1, &hi);
    th_set(n, pv, "operation", 2);
    th_render(ctx, n, &in, pv, &lo, r);
    th_set(n, pv, "operation", 3);
    th_render(ctx, n, &in, pv, &hi, r);
    int order_ok = 1;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            order_ok &= px(&lo, x, y) <= px(&in, x, y) && px(&in, x, y) <= px(&hi, x, y);
    CHECK(order_ok);
    /* the core function with the typed params the descriptor binds: the same pixels */
    nprfx_morphology_params mp = {
        .operation = NPRFX_MORPHOLOGY_CLOSE, .radius = 1.5, .footprint = NPRFX_MORPHOLOGY_DISC};
    nprfx_render_args ma = th_core_args(ctx, &in, &lo, r, r);
    CHECK_OK(nprfx_morphology_render(&ma, &mp));
    CHECK(memcmp(lo.data, hi.data, sizeof(float) * 120) == 0);
    /* the frame clamps reads as the image's edges do: dilating a frame cut one column short
     * repeats column 10 into column 11's neighbourhood, never reading column 11 */
    nprfx_image_at(&in, 11, 5)[0] = 100.0f;
    mp.operation = NPRFX_MORPHOLOGY_DILATE;
    mp.footprint = NPRFX_MORPHOLOGY_SQUARE;
    mp.radius = 1;
    ma = th_core_args(ctx, &in, &lo, nprfx_rect_make(0, 0, 11, 10), nprfx_rect_make(10, 5, 11, 6));
    CHECK_OK(nprfx_morphology_render(&ma, &mp));
    CHECK(px(&lo, 10, 5) < 100.0f);
    ma = th_core_args(ctx, &in, &lo, r, nprfx_rect_make(10, 5, 11, 6));
    CHECK_OK(nprfx_morphology_render(&ma, &mp));
    CHECK(px(&lo, 10, 5) == 100.0f);
    mp.radius = 5000;
    ma = th_core_args(ctx, &in, &lo, r, r);
    CHECK(nprfx_morphology_render(&ma, &mp) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "morphology.radius") != NULL);
    nprfx_image_free(&lo);
    nprfx_image_free(&hi);
    nprfx_image_free(&in);
    nprfx_image_free(&out);
    nprfx_image_free(&tiled);
}

static void test_descriptor(nprfx_context *ctx)
{
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_morphology));
    CHECK(nprfx_node_morphology.params_size == sizeof(nprfx_morphology_params));
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context_create(&ci, &ctx);
    test_descriptor(ctx);
    test_morphology(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
