/* morphology, warp and time-offset: the small nodes of Kass & Pesare's Figure 2/3a graphs
 * (core/looks/morphology.c, core/looks/warp.c, core/motion/time_offset.c), checked against hand-computed results
 * (footprints, open/close identities, exact displacement of linear ramps, the held frame), through
 * their descriptors and by direct calls of the core functions. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/filter.h"
#include "nprfx/node.h"
#include "nprfx/time_offset.h"

extern const nprfx_node_desc nprfx_node_morphology, nprfx_node_warp, nprfx_node_time_offset;

static nprfx_result run(nprfx_context *ctx, const nprfx_node_desc *node, const nprfx_image *ins,
                        const nprfx_value *pv, nprfx_image *out, nprfx_rect window)
{
    return th_render(ctx, node, ins, pv, out, window);
}

static void defaults(const nprfx_node_desc *node, nprfx_value *pv)
{
    nprfx_node_defaults(node, pv);
    for (int i = 0; i < node->num_params; i++)
        if (!pv[i].s) pv[i].s = "";
}

static void set(const nprfx_node_desc *node, nprfx_value *pv, const char *name, double v)
{
    pv[th_param(node, name)].v[0] = v;
}

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
    defaults(n, pv);
    nprfx_image_at(&in, 5, 5)[0] = 1.0f;

    /* dilate, disc radius 1: the 5-pixel cross */
    set(n, pv, "operation", 0);
    set(n, pv, "radius", 1);
    set(n, pv, "footprint", 0);
    CHECK_OK(run(ctx, n, &in, pv, &out, r));
    int cross = 0, total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++) {
            total += px(&out, x, y) == 1.0f;
            cross += px(&out, x, y) == 1.0f && abs(x - 5) + abs(y - 5) <= 1;
        }
    CHECK(total == 5 && cross == 5);
    /* square radius 1: 3x3; disc radius 1.5: 3x3 too (corners at distance sqrt 2) */
    set(n, pv, "footprint", 1);
    CHECK_OK(run(ctx, n, &in, pv, &out, r));
    total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            total += px(&out, x, y) == 1.0f;
    CHECK(total == 9);
    set(n, pv, "footprint", 0);
    set(n, pv, "radius", 2);
    CHECK_OK(run(ctx, n, &in, pv, &out, r));
    total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            total += px(&out, x, y) == 1.0f;
    CHECK(total == 13); /* offsets with dx^2 + dy^2 <= 4 */

    /* erode a 3x3 block with a square of radius 1: its centre only */
    for (int y = 4; y <= 6; y++)
        for (int x = 4; x <= 6; x++)
            nprfx_image_at(&in, x, y)[0] = 1.0f;
    set(n, pv, "operation", 1);
    set(n, pv, "footprint", 1);
    set(n, pv, "radius", 1);
    CHECK_OK(run(ctx, n, &in, pv, &out, r));
    total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            total += px(&out, x, y) == 1.0f;
    CHECK(total == 1 && px(&out, 5, 5) == 1.0f);

    /* open keeps the 3x3 block and removes an isolated speck; close fills a one-pixel hole */
    nprfx_image_at(&in, 10, 1)[0] = 1.0f;
    set(n, pv, "operation", 2);
    CHECK_OK(run(ctx, n, &in, pv, &out, r));
    CHECK(px(&out, 10, 1) == 0.0f && px(&out, 4, 4) == 1.0f && px(&out, 6, 6) == 1.0f);
    total = 0;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            total += px(&out, x, y) == 1.0f;
    CHECK(total == 9);
    float one = 1.0f;
    nprfx_image_fill(&in, &one);
    nprfx_image_at(&in, 3, 3)[0] = 0.25f;
    set(n, pv, "operation", 3);
    CHECK_OK(run(ctx, n, &in, pv, &out, r));
    CHECK(px(&out, 3, 3) == 1.0f);

    /* tiles agree with the whole frame (open/close compute their first pass on a grown area) */
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            nprfx_image_at(&in, x, y)[0] = (float)((x * 7 + y * 13) % 5);
    for (int op = 0; op < 4; op++) {
        set(n, pv, "operation", op);
        set(n, pv, "footprint", 0);
        set(n, pv, "radius", 1.5);
        CHECK_OK(run(ctx, n, &in, pv, &out, r));
        nprfx_rect tiles[3] = {nprfx_rect_make(0, 0, 5, 10), nprfx_rect_make(5, 0, 12, 4),
                               nprfx_rect_make(5, 4, 12, 10)};
        for (int t = 0; t < 3; t++)
            CHECK_OK(run(ctx, n, &in, pv, &tiled, tiles[t]));
        CHECK(memcmp(out.data, tiled.data, sizeof(float) * 120) == 0);
    }
    /* erode <= image <= dilate; open <= image <= close */
    nprfx_image lo, hi;
    nprfx_image_alloc(ctx, r, 1, &lo);
    nprfx_image_alloc(ctx, r, 1, &hi);
    set(n, pv, "operation", 2);
    run(ctx, n, &in, pv, &lo, r);
    set(n, pv, "operation", 3);
    run(ctx, n, &in, pv, &hi, r);
    int order_ok = 1;
    for (int y = 0; y < 10; y++)
        for (int x = 0; x < 12; x++)
            order_ok &= px(&lo, x, y) <= px(&in, x, y) && px(&in, x, y) <= px(&hi, x, y);
    CHECK(order_ok);
    /* the core function with the typed params the descriptor binds: the same pixels */
    nprfx_morphology_params mp = {
        .operation = NPRFX_MORPHOLOGY_CLOSE, .radius = 1.5, .footprint = NPRFX_MORPHOLOGY_DISC};
    CHECK_OK(nprfx_morphology_render(ctx, &mp, &in, r, r, &lo));
    CHECK(memcmp(lo.data, hi.data, sizeof(float) * 120) == 0);
    /* the frame clamps reads as the image's edges do: dilating a frame cut one column short
     * repeats column 10 into column 11's neighbourhood, never reading column 11 */
    nprfx_image_at(&in, 11, 5)[0] = 100.0f;
    mp.operation = NPRFX_MORPHOLOGY_DILATE;
    mp.footprint = NPRFX_MORPHOLOGY_SQUARE;
    mp.radius = 1;
    CHECK_OK(nprfx_morphology_render(ctx, &mp, &in, nprfx_rect_make(0, 0, 11, 10),
                                     nprfx_rect_make(10, 5, 11, 6), &lo));
    CHECK(px(&lo, 10, 5) < 100.0f);
    CHECK_OK(nprfx_morphology_render(ctx, &mp, &in, r, nprfx_rect_make(10, 5, 11, 6), &lo));
    CHECK(px(&lo, 10, 5) == 100.0f);
    mp.radius = 5000;
    CHECK(nprfx_morphology_render(ctx, &mp, &in, r, r, &lo) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "morphology.radius") != NULL);
    nprfx_image_free(&lo);
    nprfx_image_free(&hi);
    nprfx_image_free(&in);
    nprfx_image_free(&out);
    nprfx_image_free(&tiled);
}

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
    defaults(n, pv);
    set(n, pv, "amount", 2.0); /* displacement (0.5, -1) */
    for (int filter = 0; filter < 2; filter++) {
        set(n, pv, "filter", filter);
        CHECK_OK(run(ctx, n, ins, pv, &out, r));
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
    set(n, pv, "filter", 0);
    set(n, pv, "border", 1);
    CHECK_OK(run(ctx, n, ins, pv, &out, r));
    CHECK(nprfx_image_at(&out, 0, 0)[0] == 0.0f);
    set(n, pv, "border", 0);
    CHECK_OK(run(ctx, n, ins, pv, &out, r));
    CHECK_NEAR(nprfx_image_at(&out, 0, 0)[0], 0.0f, 1e-6); /* clamped at (0, 0): ramp value 0 */
    /* a NaN offset leaves the pixel in place; amount 0 is the identity */
    nprfx_image_at(&ins[1], 5, 5)[0] = NAN;
    CHECK_OK(run(ctx, n, ins, pv, &out, r));
    CHECK(nprfx_image_at(&out, 5, 5)[0] == nprfx_image_at(&ins[0], 5, 5)[0]);
    set(n, pv, "amount", 0.0);
    CHECK_OK(run(ctx, n, ins, pv, &out, r));
    CHECK(memcmp(out.data, ins[0].data, sizeof(float) * 16 * 12 * 2) == 0);
    /* a one-channel offset is refused with a message naming the input: by nprfx_node_render
     * (the descriptor declares 2 channels) and by the core function called directly */
    nprfx_image one = nprfx_image_channels(&ins[1], 0, 1);
    nprfx_image bad_ins[2] = {ins[0], one};
    CHECK(run(ctx, n, bad_ins, pv, &out, r) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "warp: input 'offset' has 1 channels, expected 2") != NULL);
    nprfx_warp_params wp = {
        .amount = 2.0, .filter = NPRFX_WARP_BICUBIC, .border = NPRFX_BORDER_CLAMP};
    CHECK(nprfx_warp_render(ctx, &wp, &ins[0], &one, r, &out) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "offset") != NULL);
    /* the core function with the typed params the descriptor binds: the same pixels */
    nprfx_image direct;
    nprfx_image_alloc(ctx, r, 2, &direct);
    set(n, pv, "amount", 2.0);
    set(n, pv, "filter", 1);
    CHECK_OK(run(ctx, n, ins, pv, &out, r));
    CHECK_OK(nprfx_warp_render(ctx, &wp, &ins[0], &ins[1], r, &direct));
    CHECK(memcmp(out.data, direct.data, sizeof(float) * 16 * 12 * 2) == 0);
    wp.border = 2;
    CHECK(nprfx_warp_render(ctx, &wp, &ins[0], &ins[1], r, &direct) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "warp.border") != NULL);
    /* reach clamps each component: displacement (0.5, -1) with reach 0.75 reads (0.5, -0.75);
     * with reach 2 nothing changes; the footprint is the reach plus two rows of taps, and -1
     * (anywhere) without one */
    set(n, pv, "filter", 0);
    set(n, pv, "reach", 0.75);
    CHECK_OK(run(ctx, n, ins, pv, &out, r));
    CHECK_NEAR(nprfx_image_at(&out, 6, 6)[0], 2.0f * 6.5f + 3.0f * 5.25f, 1e-4);
    int fp = 0;
    CHECK_OK(nprfx_node_footprint(ctx, n, pv, &fp));
    CHECK(fp == 3);
    set(n, pv, "reach", 2.0);
    CHECK_OK(run(ctx, n, ins, pv, &out, r));
    CHECK_NEAR(nprfx_image_at(&out, 6, 6)[0], 2.0f * 6.5f + 3.0f * 5.0f, 1e-4);
    set(n, pv, "reach", 0.0);
    CHECK_OK(nprfx_node_footprint(ctx, n, pv, &fp));
    CHECK(fp == -1);
    wp.border = NPRFX_BORDER_CLAMP;
    wp.reach = -1;
    CHECK(nprfx_warp_render(ctx, &wp, &ins[0], &ins[1], r, &direct) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "warp.reach") != NULL);
    nprfx_image_free(&direct);
    nprfx_image_free(&ins[0]);
    nprfx_image_free(&ins[1]);
    nprfx_image_free(&out);
}

/* A fake front end's fetch: frame t of a 1-channel input whose pixels hold t, with data only in
 * x < 3. */
typedef struct fake_fetch {
    nprfx_image frames[8];
    int calls, last_input;
    double last_time;
} fake_fetch;

static nprfx_result fetch_frame(void *user, int input, double time, nprfx_image *out)
{
    fake_fetch *f = user;
    f->calls++;
    f->last_input = input;
    f->last_time = time;
    int t = (int)time;
    if (t < 0 || t >= 8) return NPRFX_ERR_MISSING_INPUT;
    if (!f->frames[t].data) {
        nprfx_image_alloc(NULL, nprfx_rect_make(0, 0, 3, 4), 1, &f->frames[t]);
        float v = (float)t;
        nprfx_image_fill(&f->frames[t], &v);
    }
    *out = f->frames[t];
    return NPRFX_OK;
}

static void test_time_offset(nprfx_context *ctx)
{
    const nprfx_node_desc *n = &nprfx_node_time_offset;
    /* held at the shot's ends; no clamp without a shot range (first > last) */
    CHECK(nprfx_time_offset_frame(5, -1, 1, 7) == 4.0);
    CHECK(nprfx_time_offset_frame(1, -1, 1, 7) == 1.0);
    CHECK(nprfx_time_offset_frame(6, 3, 1, 7) == 7.0);
    CHECK(nprfx_time_offset_frame(1, -3, 2, 1) == -2.0);

    nprfx_rect r = nprfx_rect_make(0, 0, 5, 4);
    nprfx_image cur, out;
    nprfx_image_alloc(ctx, r, 1, &cur);
    nprfx_image_alloc(ctx, r, 1, &out);
    float nine = 9.0f, minus = -7.0f;
    nprfx_image_fill(&cur, &nine);
    nprfx_value pv[1];
    defaults(n, pv);
    CHECK(pv[0].v[0] == -1.0);
    fake_fetch f;
    memset(&f, 0, sizeof f);
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = n;
    a.time = 5;
    a.render_scale = 1;
    a.frame = r;
    a.window = nprfx_rect_make(1, 1, 5, 3);
    a.first_frame = 1;
    a.last_frame = 7;
    a.inputs = &cur;
    a.params = pv;
    a.output = &out;
    a.fetch = fetch_frame;
    a.fetch_user = &f;
    /* the previous frame (4) in the window, 0 outside its data window (x >= 3), untouched
     * outside the window */
    nprfx_image_fill(&out, &minus);
    CHECK_OK(nprfx_node_render(&a));
    CHECK(f.calls == 1 && f.last_input == 0 && f.last_time == 4.0);
    CHECK(px(&out, 1, 1) == 4.0f && px(&out, 2, 2) == 4.0f);
    CHECK(px(&out, 3, 1) == 0.0f && px(&out, 4, 2) == 0.0f);
    CHECK(px(&out, 0, 1) == -7.0f && px(&out, 1, 0) == -7.0f && px(&out, 1, 3) == -7.0f);
    /* frame 1 holds: no frame 0 is asked for */
    a.time = 1;
    CHECK_OK(nprfx_node_render(&a));
    CHECK(f.last_time == 1.0 && px(&out, 1, 1) == 1.0f);
    /* offset 0 copies the current frame without a fetch */
    pv[0].v[0] = 0;
    f.calls = 0;
    CHECK_OK(nprfx_node_render(&a));
    CHECK(f.calls == 0 && px(&out, 1, 1) == 9.0f && px(&out, 4, 2) == 9.0f);
    /* a host that cannot fetch; a frame with other channels */
    pv[0].v[0] = -1;
    a.fetch = NULL;
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_UNSUPPORTED);
    CHECK(strstr(th_error(ctx), "time-offset") != NULL);
    a.fetch = fetch_frame;
    nprfx_image two, cur2;
    nprfx_image_alloc(ctx, r, 2, &two);
    nprfx_image_alloc(ctx, r, 2, &cur2);
    a.inputs = &cur2;
    a.output = &two;
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_SIZE_MISMATCH);
    CHECK(strstr(th_error(ctx), "input 'image' has 1 channels at frame 1") != NULL);
    /* the core function directly, with the typed params */
    nprfx_time_offset_params tp = {.offset = 2};
    CHECK_OK(nprfx_time_offset_render(ctx, &tp, &cur, 3, 1, 7, fetch_frame, &f, 0, r, &out));
    CHECK(f.last_time == 5.0 && px(&out, 0, 0) == 5.0f && px(&out, 4, 0) == 0.0f);
    for (int i = 0; i < 8; i++)
        nprfx_image_free(&f.frames[i]);
    nprfx_image_free(&two);
    nprfx_image_free(&cur2);
    nprfx_image_free(&cur);
    nprfx_image_free(&out);
}

static void test_descriptors(nprfx_context *ctx)
{
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_morphology));
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_warp));
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_time_offset));
    CHECK(nprfx_node_morphology.params_size == sizeof(nprfx_morphology_params));
    CHECK(nprfx_node_warp.params_size == sizeof(nprfx_warp_params));
    CHECK(nprfx_node_time_offset.params_size == sizeof(nprfx_time_offset_params));
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context_create(&ci, &ctx);
    test_descriptors(ctx);
    test_morphology(ctx);
    test_warp(ctx);
    test_time_offset(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
