/* The advect node (core/advect.c, plugins/advect.c): the layers' schedule and weights by hand,
 * exact transport along an integer motion, fresh starts where the confidence fails or the motion
 * is NaN or leaves the frame, and the same pixels whatever the order of the frames, the state
 * kept, the tiles and the threads. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/advect.h"

extern const nprfx_node_desc nprfx_node_advect;

enum { W = 64, H = 32, FIRST = 1, LAST = 24 };

/* The test's footage: motion_prev (-2, 0) everywhere (the picture moves right 2 px a frame),
 * with a NaN at one pixel on frame 6; confidence 1 but 0 in a box. */
typedef struct footage {
    nprfx_image motion[LAST + 1], confidence[LAST + 1];
    int fetches;
} footage;

static nprfx_result fetch(void *user, int input, double time, nprfx_image *out)
{
    footage *f = user;
    int t = (int)time;
    if (t < FIRST || t > LAST) return NPRFX_ERR_INVALID_ARGUMENT;
    f->fetches++;
    *out = input == NPRFX_ADVECT_IN_MOTION ? f->motion[t] : f->confidence[t];
    return NPRFX_OK;
}

static void make_footage(footage *f)
{
    memset(f, 0, sizeof *f);
    for (int t = FIRST; t <= LAST; t++) {
        f->motion[t] = th_image(W, H, 2, NULL);
        f->confidence[t] = th_image(W, H, 1, NULL);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                float *m = nprfx_image_at(&f->motion[t], x, y);
                m[0] = -2.0f;
                m[1] = 0.0f;
                *nprfx_image_at(&f->confidence[t], x, y) =
                    x >= 40 && x < 48 && y >= 10 && y < 20 ? 0.0f : 1.0f;
            }
    }
    nprfx_image_at(&f->motion[6], 30, 5)[0] = NAN;
}

static nprfx_result render_at(nprfx_context *ctx, footage *f, const nprfx_advect_params *p, int t,
                              void **state, nprfx_rect window, nprfx_image *out, int with_fetch)
{
    nprfx_image inputs[NPRFX_ADVECT_IN_COUNT] = {f->motion[t], f->confidence[t]};
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = &nprfx_node_advect;
    a.time = t;
    a.render_scale = 1;
    a.frame = nprfx_rect_make(0, 0, W, H);
    a.window = window;
    a.first_frame = FIRST;
    a.last_frame = LAST;
    a.inputs = inputs;
    a.output = out;
    a.fetch = with_fetch ? fetch : NULL;
    a.fetch_user = f;
    a.state = state;
    return nprfx_advect_render(&a, p);
}

static int same_image(const nprfx_image *a, const nprfx_image *b)
{
    return memcmp(a->data, b->data, sizeof(float) * W * H * NPRFX_ADVECT_CHANNELS) == 0;
}

static void test_schedule(void)
{
    nprfx_advect_params p = {8, 16, 0.5, 0};
    /* A starts at multiples of 8, B at 4 + multiples of 8, never before the shot */
    CHECK(nprfx_advect_start(&p, 0, 5, 1, 24) == 1 && nprfx_advect_start(&p, 0, 9, 1, 24) == 8);
    CHECK(nprfx_advect_start(&p, 0, 16, 1, 24) == 16 && nprfx_advect_start(&p, 1, 5, 1, 24) == 4);
    CHECK(nprfx_advect_start(&p, 1, 3, 1, 24) == 1 && nprfx_advect_start(&p, 1, 11, 1, 24) == 4);
    CHECK(nprfx_advect_start(&p, 1, 3, 1, 0) == -4); /* unknown shot: no clamp */
    /* A's weight: 0 at its start, 1 at B's, a half between */
    CHECK(nprfx_advect_weight(&p, 8) == 0.0 && nprfx_advect_weight(&p, 12) == 1.0);
    CHECK(nprfx_advect_weight(&p, 10) == 0.5 && nprfx_advect_weight(&p, 15) == 0.25);
    /* frames read: motion from the earlier start (exclusive) to the frame */
    nprfx_value v[4];
    memset(v, 0, sizeof v);
    for (int i = 0; i < nprfx_node_advect.num_params; i++) {
        memcpy(v[i].v, nprfx_node_advect.params[i].def, sizeof v[i].v);
        v[i].s = "";
    }
    v[th_param(&nprfx_node_advect, "period")].v[0] = 8;
    int ch[2] = {2, 1}, n = 0;
    nprfx_frames_query q = {13, 1, 24, ch};
    nprfx_frame_range r[8];
    CHECK_OK(nprfx_node_frames_needed(NULL, &nprfx_node_advect, v, &q, 0, r, &n));
    CHECK(n == 1 && r[0].first == 9 && r[0].last == 13);
}

static void test_transport(nprfx_context *ctx)
{
    footage f;
    make_footage(&f);
    nprfx_advect_params p = {8, 16, 0.5, 3};
    nprfx_image out[LAST + 1];
    void *state = NULL;
    for (int t = FIRST; t <= LAST; t++) {
        out[t] = th_image(W, H, NPRFX_ADVECT_CHANNELS, NULL);
        CHECK_OK(render_at(ctx, &f, &p, t, &state, nprfx_rect_make(0, 0, W, H), &out[t], 1));
    }
    /* layer A at frame 13 started at 8: each pixel holds what the pixel 2 (13 - 8) px to its
     * left held at 8, exactly (integer motion), unless its path crossed the box of zero
     * confidence or came in from the left edge; those in the box, and the two columns whose
     * source is left of the frame, start afresh at 13 with what they had at their start */
    int moved = 0, fresh = 0, bad = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float *o = nprfx_image_at(&out[13], x, y);
            const int sx = x - 10;
            int in_box_path = y >= 10 && y < 20 && x >= 40 && x < 58; /* box or moved out of it */
            if (sx >= 0 && !in_box_path) {
                const float *s = nprfx_image_at(&out[8], sx, y);
                bad += o[0] != s[0] || o[1] != s[1];
                moved++;
            } else if (x < 2 || (x >= 40 && x < 48 && y >= 10 && y < 20)) {
                /* fresh at this very frame: a source left of the frame, or no confidence */
                const float *s = nprfx_image_at(&out[8], x, y);
                bad += o[0] != s[0] || o[1] != s[1];
                fresh++;
            }
        }
    printf("transport: %d pixels carried, %d fresh, %d wrong\n", moved, fresh, bad);
    CHECK(bad == 0 && moved > 1000 && fresh == 80 + 2 * H);
    /* the start: pixel / scale plus a shift in [0, 1) */
    const float *o8 = nprfx_image_at(&out[8], 5, 7), *o9 = nprfx_image_at(&out[8], 6, 7);
    CHECK(fabsf((o9[0] - o8[0]) - 1.0f / 16) < 1e-6f && o8[0] >= 5.5f / 16 &&
          o8[0] < 5.5f / 16 + 1);
    /* the weight channel */
    CHECK(nprfx_image_at(&out[12], 3, 3)[4] == 1.0f && nprfx_image_at(&out[16], 3, 3)[4] == 0.0f);
    /* a NaN motion (frame 6, pixel (30, 5)) starts afresh; nothing is NaN */
    int finite = 1;
    for (int t = FIRST; t <= LAST; t++)
        for (size_t i = 0; i < (size_t)W * H * NPRFX_ADVECT_CHANNELS; i++)
            finite &= isfinite(out[t].data[i]) != 0;
    CHECK(finite);
    /* order, state, tiles and threads: frame 13 alone, after 24, in tiles on 4 threads */
    nprfx_image alone = th_image(W, H, NPRFX_ADVECT_CHANNELS, NULL);
    CHECK_OK(render_at(ctx, &f, &p, 13, NULL, nprfx_rect_make(0, 0, W, H), &alone, 1));
    CHECK(same_image(&alone, &out[13]));
    memset(alone.data, 0, sizeof(float) * W * H * NPRFX_ADVECT_CHANNELS);
    CHECK_OK(render_at(ctx, &f, &p, 13, &state, nprfx_rect_make(0, 0, W, H), &alone, 1));
    CHECK(same_image(&alone, &out[13]));
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(4, &pool);
    void *st2 = NULL;
    memset(alone.data, 0, sizeof(float) * W * H * NPRFX_ADVECT_CHANNELS);
    for (int ty = 0; ty < H; ty += 13)
        for (int tx = 0; tx < W; tx += 21)
            CHECK_OK(render_at(par, &f, &p, 13, &st2, nprfx_rect_make(tx, ty, tx + 21, ty + 13),
                               &alone, 1));
    CHECK(same_image(&alone, &out[13]));
    /* frames 14..24 with the kept state took one step each: two fetches a frame at most */
    f.fetches = 0;
    CHECK_OK(render_at(par, &f, &p, 14, &st2, nprfx_rect_make(0, 0, W, H), &alone, 1));
    CHECK(f.fetches == 0 && same_image(&alone, &out[14]));
    /* without fetch, a frame past its layers' starts cannot be made, and says so */
    CHECK(render_at(ctx, &f, &p, 13, NULL, nprfx_rect_make(0, 0, W, H), &alone, 0) ==
          NPRFX_ERR_UNSUPPORTED);
    CHECK(strstr(th_error(ctx), "cannot fetch other frames") != NULL);
    nprfx_advect_state_free(st2);
    nprfx_advect_state_free(state);
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
    nprfx_image_free(&alone);
    for (int t = FIRST; t <= LAST; t++) {
        nprfx_image_free(&out[t]);
        nprfx_image_free(&f.motion[t]);
        nprfx_image_free(&f.confidence[t]);
    }
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    CHECK_OK(nprfx_context_create(&ci, &ctx));
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_advect));
    test_schedule();
    test_transport(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
