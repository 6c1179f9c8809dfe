/* time-offset (core/motion/time_offset.c): the held frame and the frames it fetches, through its
 * descriptor. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/node.h"
#include "nprfx/time_offset.h"

extern const nprfx_node_desc nprfx_node_time_offset;

static float px(const nprfx_image *im, int x, int y)
{
    return nprfx_image_at(im, x, y)[0];
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
    th_defaults(n, pv);
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
    nprfx_render_args ta = th_core_args(ctx, &cur, &out, r, r);
    ta.time = 3;
    ta.first_frame = 1;
    ta.last_frame = 7;
    ta.fetch = fetch_frame;
    ta.fetch_user = &f;
    CHECK_OK(nprfx_time_offset_render(&ta, &tp));
    CHECK(f.last_time == 5.0 && px(&out, 0, 0) == 5.0f && px(&out, 4, 0) == 0.0f);
    for (int i = 0; i < 8; i++)
        nprfx_image_free(&f.frames[i]);
    nprfx_image_free(&two);
    nprfx_image_free(&cur2);
    nprfx_image_free(&cur);
    nprfx_image_free(&out);
}

static void test_descriptor(nprfx_context *ctx)
{
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_time_offset));
    CHECK(nprfx_node_time_offset.params_size == sizeof(nprfx_time_offset_params));
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context_create(&ci, &ctx);
    test_descriptor(ctx);
    test_time_offset(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
