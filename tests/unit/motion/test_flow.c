/* The flow node's core (core/motion/flow.c, docs/design.md §3.15) with exact test providers (unit tests
 * link no OpenCV; tests/cli/flow.sh measures OpenCV's DIS): the confidence formula against
 * hand-computed values, luminance, the solve at a fraction of the resolution, the motion
 * convention and the shot's ends, the cache (never changing a result), size mismatch and no
 * provider errors, NaN as missing, bit identity across tiles, threads and frame order, lint. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "flow_test_provider.h"
#include "node_harness.h"
#include "nprfx/flow.h"
#include "nprfx/metrics.h"
#include "nprfx/node.h"

extern const nprfx_node_desc nprfx_node_flow;

enum { W = 24, H = 16, FIRST = 1, LAST = 5 };

/* ---- the confidence, by hand ---- */

static void test_confidence(void)
{
    /* 4 x 1 frames: a moves +1 in x to b; b's flow back is -1 except at x = 2 (-1.5). */
    float fab[8] = {1, 0, 1, 0, 1, 0, 1, 0};
    float fba[8] = {-1, 0, -1, 0, -1.5f, 0, -1, 0};
    float la[4] = {0.1f, 0.2f, 0.3f, 0.4f}, lb[4] = {0.0f, 0.1f, 0.2f, 0.5f};
    float conf[4];
    nprfx_flow_confidence(fab, fba, la, lb, NULL, NULL, 4, 1, 1.0, 0, conf);
    CHECK_NEAR(conf[0], 1.0, 1e-7);            /* lands on x = 1, comes home */
    CHECK_NEAR(conf[1], exp(-0.25 / 2), 1e-7); /* lands on x = 2: misses by 0.5 */
    CHECK_NEAR(conf[2], 1.0, 1e-7);            /* lands on x = 3 */
    CHECK(conf[3] == 0.0f);                    /* lands on x = 4: outside */
    /* photometric: x = 2 lands on x = 3, |0.3 - 0.5| = 0.2 at sigma 0.1: exp(-2) */
    nprfx_flow_confidence(fab, fba, la, lb, NULL, NULL, 4, 1, 1.0, 0.1, conf);
    CHECK_NEAR(conf[0], exp(-(0.1 - 0.1) * (0.1 - 0.1) / 0.02), 1e-6);
    CHECK_NEAR(conf[2], exp(-0.04 / 0.02), 1e-6);
    CHECK_NEAR(conf[1], exp(-0.25 / 2) * exp(-pow(0.2 - 0.2, 2) / 0.02), 1e-6);
    /* a bilinear lookup half way: x = 0 lands on 1.5, f_ba there (-1 + -1.5) / 2 = -1.25, lum
     * (0.1 + 0.2) / 2 = 0.15; e_fb = 0.5 - 0.25 = 0.25, e_ph = 0.1 - 0.15 */
    float fh[8] = {1.5f, 0, 0, 0, 0, 0, 0, 0};
    nprfx_flow_confidence(fh, fba, la, lb, NULL, NULL, 4, 1, 0.5, 0.1, conf);
    double efb = 1.5 - 1.25, eph = 0.1 - 0.15;
    CHECK_NEAR(conf[0], exp(-efb * efb / (2 * 0.25) - eph * eph / (2 * 0.01)), 1e-6);
    /* within half a pixel of the edge the lookup clamps; beyond, nothing */
    float fe[8] = {-0.4f, 0, 0, 0, 0, 0, 0.45f, 0};
    float zero[8] = {0};
    nprfx_flow_confidence(fe, zero, la, la, NULL, NULL, 4, 1, 1.0, 0, conf);
    CHECK_NEAR(conf[0], exp(-0.16 / 2), 1e-6);
    CHECK_NEAR(conf[3], exp(-0.2025 / 2), 1e-6);
    fe[0] = -0.6f;
    nprfx_flow_confidence(fe, zero, la, la, NULL, NULL, 4, 1, 1.0, 0, conf);
    CHECK(conf[0] == 0.0f);
    /* missing pixels: at x, or a tap of the landing point */
    unsigned char oka[4] = {1, 0, 1, 1}, okb[4] = {1, 1, 1, 0};
    nprfx_flow_confidence(fab, fba, la, lb, oka, okb, 4, 1, 1.0, 0, conf);
    CHECK(conf[1] == 0.0f && conf[2] == 0.0f && conf[0] == 1.0f);
}

static void test_cut_gate(void)
{
    CHECK(nprfx_flow_cut_gate(0.3) == 0.0 && nprfx_flow_cut_gate(0.6) == 0.0);
    CHECK(nprfx_flow_cut_gate(0.85) == 1.0 && nprfx_flow_cut_gate(1.0) == 1.0);
    CHECK_NEAR(nprfx_flow_cut_gate(0.725), 0.5, 1e-12); /* smoothstep's middle */
    CHECK_NEAR(nprfx_flow_cut_gate(0.65), 0.2 * 0.2 * (3 - 0.4), 1e-12);
}

static void test_luminance(void)
{
    float px[8] = {1, 1, 1, 0.5f, NAN, 0, 0, 1};
    nprfx_image im = th_image(2, 1, 4, px);
    float lum[2];
    unsigned char ok[2];
    nprfx_flow_luminance(&im, lum, ok);
    CHECK_NEAR(lum[0], 0.5, 1e-6); /* luma 1 -> 1 / 2; alpha ignored */
    CHECK(lum[1] == 0.0f && ok[1] == 0 && ok[0] == 1);
    nprfx_image_free(&im);
    float g[3] = {3, -1, INFINITY};
    nprfx_image m = th_image(3, 1, 1, g);
    float l3[3];
    unsigned char ok3[3];
    nprfx_flow_luminance(&m, l3, ok3);
    CHECK_NEAR(l3[0], 0.75, 1e-6);
    CHECK(l3[1] == 0.0f && ok3[1] == 1 && l3[2] == 0.0f && ok3[2] == 0);
    nprfx_image_free(&m);
}

/* A provider that returns a linear field f(x, y) = (0.1 x, -0.05 y) at whatever size it is
 * called: at scale s the upsampled flow must be the same field, scaled back. */
static nprfx_result linear_compute(void *user, nprfx_context *ctx, const float *from,
                                   const float *to, int w, int h, nprfx_flow_preset preset,
                                   float *flow)
{
    (void)ctx, (void)from, (void)to, (void)preset;
    int *size = user;
    size[0] = w, size[1] = h;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            flow[2 * (y * w + x)] = 1.0f;
            flow[2 * (y * w + x) + 1] = (float)(0.25 * x);
        }
    return NPRFX_OK;
}

static void test_scale(void)
{
    int size[2] = {0, 0};
    nprfx_flow_provider lp = {sizeof lp, "test: linear", linear_compute, size};
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.flow = &lp;
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(&init, &ctx));
    float a[W * H] = {0}, b[W * H] = {0}, f[2 * W * H];
    CHECK_OK(nprfx_flow_solve(ctx, a, b, W, H, 0.5, NPRFX_FLOW_FAST, f));
    CHECK(size[0] == 12 && size[1] == 8);
    /* (1, 0.25 i) at 12 wide is (2, 0.25 u * 2) at full size, with u = (x + 0.5) / 2 - 0.5
     * clamped to [0, 11]: x = 0 -> u = 0, x = 5 -> 2.25, x = 23 -> 11 */
    CHECK_NEAR(f[0], 2.0, 1e-6);
    CHECK_NEAR(f[2 * 5 + 1], 2 * 0.25 * 2.25, 1e-6);
    CHECK_NEAR(f[2 * (3 * W + 23) + 1], 2 * 0.25 * 11, 1e-6);
    CHECK_NEAR(f[2 * (7 * W + 5)], 2.0, 1e-6);
    /* at scale 1 the provider sees the full size; 0.3 rounds up (ceil) */
    CHECK_OK(nprfx_flow_solve(ctx, a, b, W, H, 1, NPRFX_FLOW_FAST, f));
    CHECK(size[0] == W && size[1] == H && f[2 * 5 + 1] == 1.25f);
    CHECK_OK(nprfx_flow_solve(ctx, a, b, W, H, 0.3, NPRFX_FLOW_FAST, f));
    CHECK(size[0] == 8 && size[1] == 5);
    nprfx_context_destroy(ctx);
}

/* ---- the node ---- */

/* A shot of 1-channel frames: a smooth ramp, frame t marked in pixel (0, 0). */
typedef struct shot {
    nprfx_image frames[LAST + 2];
    int odd; /* a frame whose size differs (0: none) */
    int fetches;
} shot;

static void shot_make(shot *s)
{
    memset(s, 0, sizeof *s);
    for (int t = FIRST; t <= LAST; t++) {
        s->frames[t] = th_image(W, H, 1, NULL);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                nprfx_image_at(&s->frames[t], x, y)[0] = 0.02f * (float)(x + y);
        nprfx_image_at(&s->frames[t], 0, 0)[0] = th_flow_mark(t);
    }
}

static void shot_free(shot *s)
{
    for (int t = 0; t < LAST + 2; t++)
        nprfx_image_free(&s->frames[t]);
}

static nprfx_result shot_fetch(void *user, int input, double time, nprfx_image *out)
{
    shot *s = user;
    int t = (int)floor(time + 0.5);
    s->fetches++;
    if (input != 0 || t < FIRST || t > LAST) return NPRFX_ERR_MISSING_INPUT;
    *out = s->frames[t];
    return NPRFX_OK;
}

static nprfx_result render_at(nprfx_context *ctx, shot *s, const nprfx_value *pv, int t, int first,
                              int last, void **state, nprfx_image *out, nprfx_rect window)
{
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = &nprfx_node_flow;
    a.time = t;
    a.render_scale = 1;
    a.frame = out->bounds;
    a.window = window;
    a.first_frame = first;
    a.last_frame = last;
    a.inputs = &s->frames[t];
    a.params = pv;
    a.output = out;
    a.fetch = shot_fetch;
    a.fetch_user = s;
    a.state = state;
    return nprfx_node_render(&a);
}

static void test_node(void)
{
    th_flow_shift_d d = {0.5, -0.25, 0};
    nprfx_flow_provider sp = {sizeof sp, "test: shift", th_flow_shift_compute, &d};
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.flow = &sp;
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(&init, &ctx));
    CHECK(nprfx_context_flow(ctx) == &sp);
    nprfx_context *scoped = NULL;
    CHECK_OK(nprfx_context_create_scoped(ctx, "node 'f'", &scoped));
    CHECK(nprfx_context_flow(scoped) == &sp);

    const nprfx_node_desc *n = &nprfx_node_flow;
    CHECK_OK(nprfx_node_lint(ctx, n));
    nprfx_value pv[8];
    nprfx_node_defaults(n, pv);
    pv[th_param(n, "photometric")].v[0] = 0; /* the ramp moves, the test frames do not */
    int ich[1] = {1};
    nprfx_output_info oi;
    CHECK_OK(nprfx_node_output_info(ctx, n, pv, ich, &oi));
    CHECK(oi.channels == 6 && !strcmp(oi.names[0], "motion_prev.X") &&
          !strcmp(oi.names[3], "motion_next.Y") && !strcmp(oi.names[4], "confidence.prev") &&
          !strcmp(oi.names[5], "confidence.next"));

    shot s;
    shot_make(&s);
    nprfx_image out = th_image(W, H, 6, NULL);
    /* frame 3: prev = t -> t-1 = -d, next = +d; both consistent: confidence 1 inside, 0 where
     * the shifted pixel leaves the frame (x + 0.5 >= W - 0.5 for next: the last column; y - 0.25
     * stays inside) */
    CHECK_OK(render_at(scoped, &s, pv, 3, FIRST, LAST, NULL, &out, out.bounds));
    const float *p = nprfx_image_at(&out, 5, 5);
    CHECK(p[0] == -0.5f && p[1] == 0.25f && p[2] == 0.5f && p[3] == -0.25f);
    CHECK(p[4] == 1.0f && p[5] == 1.0f);
    CHECK(nprfx_image_at(&out, W - 1, 5)[5] == 0.0f && nprfx_image_at(&out, W - 1, 5)[4] == 1.0f);
    /* x - 0.5 = -0.5 is the edge of pixel 0's square: inside; y + 0.25 at the last row too */
    CHECK(nprfx_image_at(&out, 0, 5)[4] == 1.0f && nprfx_image_at(&out, 3, H - 1)[4] == 1.0f);
    CHECK(d.calls == 4);

    /* the shot's ends: no previous frame at the first, no next at the last */
    CHECK_OK(render_at(ctx, &s, pv, FIRST, FIRST, LAST, NULL, &out, out.bounds));
    p = nprfx_image_at(&out, 5, 5);
    CHECK(p[0] == 0 && p[1] == 0 && p[4] == 0 && p[2] == 0.5f && p[5] == 1.0f);
    CHECK_OK(render_at(ctx, &s, pv, LAST, FIRST, LAST, NULL, &out, out.bounds));
    p = nprfx_image_at(&out, 5, 5);
    CHECK(p[2] == 0 && p[3] == 0 && p[5] == 0 && p[0] == -0.5f && p[4] == 1.0f);
    /* a one-frame shot: runs without fetching or solving, all zero */
    int calls = d.calls, fetches = s.fetches;
    CHECK_OK(render_at(ctx, &s, pv, 3, 3, 3, NULL, &out, out.bounds));
    int zero = 1;
    for (int i = 0; i < W * H * 6; i++)
        zero &= out.data[i] == 0.0f;
    CHECK(zero && d.calls == calls && s.fetches == fetches);

    /* the cache: in order, frame t+1 reuses frame t's (t, t+1) pair (2 solves a frame, not 4),
     * and every frame is bit-identical to an uncached render; tiles of one frame hit too */
    void *state = NULL;
    nprfx_image ref = th_image(W, H, 6, NULL);
    int same = 1;
    calls = d.calls;
    for (int t = FIRST; t <= LAST; t++) {
        CHECK_OK(render_at(ctx, &s, pv, t, FIRST, LAST, &state, &out, out.bounds));
        CHECK_OK(render_at(ctx, &s, pv, t, FIRST, LAST, NULL, &ref, ref.bounds));
        same &= !memcmp(out.data, ref.data, sizeof(float) * W * H * 6);
    }
    CHECK(same);
    /* cached: 2 + 2 + 2 + 2 (the first frame solves its next pair, each later one its own
     * next pair); uncached: 2 + 4 + 4 + 4 + 2 */
    CHECK(d.calls - calls == 8 + 16);
    calls = d.calls;
    memset(out.data, 0, sizeof(float) * W * H * 6);
    /* th_render_tiled renders a one-frame shot (frame 1): all zero, no solve */
    CHECK_OK(th_render_tiled(ctx, n, &s.frames[LAST], pv, &out, 7, 5));
    CHECK(d.calls == calls);
    /* tiles of frame 3 through the state: one pair of solves per pair, same pixels */
    nprfx_image whole = th_image(W, H, 6, NULL);
    CHECK_OK(render_at(ctx, &s, pv, 3, FIRST, LAST, NULL, &whole, whole.bounds));
    calls = d.calls;
    for (int y = 0; y < H; y += 5)
        for (int x = 0; x < W; x += 7) {
            nprfx_rect w = nprfx_rect_make(x, y, x + 7 < W ? x + 7 : W, y + 5 < H ? y + 5 : H);
            CHECK_OK(render_at(ctx, &s, pv, 3, FIRST, LAST, &state, &out, w));
        }
    CHECK(!memcmp(out.data, whole.data, sizeof(float) * W * H * 6));
    CHECK(d.calls - calls <= 4);
    /* a changed frame is a miss, never a stale hit */
    nprfx_image_at(&s.frames[4], 3, 3)[0] += 0.5f;
    calls = d.calls;
    CHECK_OK(render_at(ctx, &s, pv, 3, FIRST, LAST, &state, &out, out.bounds));
    CHECK(d.calls - calls == 2);
    nprfx_image_at(&s.frames[4], 3, 3)[0] -= 0.5f;
    n->state_free(state);
    state = NULL;

    /* one direction alone: its three channels, half the solves, the same values */
    nprfx_image full = th_image(W, H, 6, NULL);
    CHECK_OK(render_at(ctx, &s, pv, 3, FIRST, LAST, NULL, &full, full.bounds));
    static const char *const outs[] = {"prev", "next", "vectors"};
    static const int chans[3][4] = {{0, 1, 4, -1}, {2, 3, 5, -1}, {0, 1, 2, 3}};
    for (int o = 0; o < 3; o++) {
        th_set_choice(n, pv, "output", outs[o]);
        CHECK_OK(nprfx_node_output_info(ctx, n, pv, ich, &oi));
        int nc = o == 2 ? 4 : 3;
        CHECK(oi.channels == nc && !strcmp(oi.names[nc - 1], o == 0   ? "confidence.prev"
                                                             : o == 1 ? "confidence.next"
                                                                      : "motion_next.Y"));
        nprfx_image part = th_image(W, H, nc, NULL);
        calls = d.calls;
        CHECK_OK(render_at(ctx, &s, pv, 3, FIRST, LAST, NULL, &part, part.bounds));
        CHECK(d.calls - calls == (o == 2 ? 4 : 2));
        int same_vals = 1;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                for (int c = 0; c < nc; c++)
                    same_vals &=
                        nprfx_image_at(&part, x, y)[c] == nprfx_image_at(&full, x, y)[chans[o][c]];
        CHECK(same_vals);
        /* frames: one neighbour for one direction */
        nprfx_frames_query fq = {3, FIRST, LAST, ich};
        nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
        int nr = 0;
        CHECK_OK(nprfx_node_frames_needed(ctx, n, pv, &fq, 0, rg, &nr));
        CHECK(nr == 1 && rg[0].first == (o == 1 ? 3 : 2) && rg[0].last == (o == 0 ? 3 : 4));
        nprfx_image_free(&part);
    }
    nprfx_image_free(&full);
    nprfx_node_defaults(n, pv);
    pv[th_param(n, "photometric")].v[0] = 0;

    /* the photometric term: the ramp moves under the shift, so it lowers the confidence */
    nprfx_node_defaults(n, pv);
    CHECK_OK(render_at(ctx, &s, pv, 3, FIRST, LAST, NULL, &out, out.bounds));
    p = nprfx_image_at(&out, 5, 5);
    /* lum(5, 5) - lum(5.5, 4.75), lum = g(0.02 (x + y)), g(v) = v / (1 + v), bilinear */
#define G(v) ((v) / (1 + (v)))
    double l54 = G(0.02f * 9), l64 = G(0.02f * 10), l55 = G(0.02f * 10), l65 = G(0.02f * 11);
    double lb = (l54 * 0.5 + l64 * 0.5) * 0.25 + (l55 * 0.5 + l65 * 0.5) * 0.75;
    double e = G(0.02f * 10) - lb, sig = 0.05;
#undef G
    CHECK_NEAR(p[5], exp(-e * e / (2 * sig * sig)), 1e-4);

    /* NaN and inf: missing, confidence 0 there, output finite */
    nprfx_image_at(&s.frames[3], 8, 8)[0] = NAN;
    nprfx_image_at(&s.frames[2], 10, 10)[0] = INFINITY;
    CHECK_OK(render_at(ctx, &s, pv, 3, FIRST, LAST, NULL, &out, out.bounds));
    int finite = 1;
    for (int i = 0; i < W * H * 6; i++)
        finite &= isfinite(out.data[i]) != 0;
    CHECK(finite);
    CHECK(nprfx_image_at(&out, 8, 8)[4] == 0.0f && nprfx_image_at(&out, 8, 8)[5] == 0.0f);
    /* frame 3's (10, 10) lands on frame 2 at (9.5, 10.25), whose taps include (10, 10), missing
     * at frame 2 */
    CHECK(nprfx_image_at(&out, 10, 10)[4] == 0.0f);
    CHECK(nprfx_image_at(&out, 15, 3)[4] > 0.0f);
    nprfx_image_at(&s.frames[3], 8, 8)[0] = 0.32f;
    nprfx_image_at(&s.frames[2], 10, 10)[0] = 0.4f;

    /* a neighbour of another size: the message names both frames and sizes */
    nprfx_image small = th_image(W - 2, H, 1, NULL);
    nprfx_image keep = s.frames[4];
    s.frames[4] = small;
    CHECK(render_at(ctx, &s, pv, 3, FIRST, LAST, NULL, &out, out.bounds) ==
          NPRFX_ERR_SIZE_MISMATCH);
    CHECK(strstr(th_error(ctx), "22x16") && strstr(th_error(ctx), "frame 4") &&
          strstr(th_error(ctx), "24x16") && strstr(th_error(ctx), "frame 3"));
    s.frames[4] = keep;
    nprfx_image_free(&small);

    /* no fetch: fine for a one-frame shot, an error otherwise */
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a, a.ctx = ctx, a.node = n, a.time = 3, a.render_scale = 1;
    a.frame = a.window = out.bounds;
    a.first_frame = FIRST, a.last_frame = LAST, a.inputs = &s.frames[3], a.params = pv;
    a.output = &out;
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_UNSUPPORTED);
    CHECK(strstr(th_error(ctx), "cannot fetch") != NULL);

    nprfx_image_free(&whole);
    nprfx_image_free(&ref);
    nprfx_image_free(&out);
    shot_free(&s);
    nprfx_context_destroy(scoped);
    nprfx_context_destroy(ctx);
}

/* Without a provider: the message says how to get one. */
static void test_no_provider(void)
{
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    CHECK(nprfx_context_flow(ctx) == NULL);
    shot s;
    shot_make(&s);
    nprfx_value pv[8];
    nprfx_node_defaults(&nprfx_node_flow, pv);
    nprfx_image out = th_image(W, H, 6, NULL);
    CHECK(render_at(ctx, &s, pv, 3, FIRST, LAST, NULL, &out, out.bounds) == NPRFX_ERR_UNSUPPORTED);
    CHECK(strstr(th_error(ctx), "no optical flow provider") &&
          strstr(th_error(ctx), "libopencv-video-dev"));
    /* an older caller's init struct, without the field, reads as none */
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.size = offsetof(nprfx_context_init, flow);
    init.flow = &th_flow_zero;
    nprfx_context *old = NULL;
    CHECK_OK(nprfx_context_create(&init, &old));
    CHECK(nprfx_context_flow(old) == NULL);
    nprfx_context_destroy(old);
    nprfx_image_free(&out);
    shot_free(&s);
    nprfx_context_destroy(ctx);
}

/* Bit identity over threads and tiles, in a shot with a real (non-constant) field. */
static void test_threads(void)
{
    th_flow_shift_d d = {1.25, 0.75, 0};
    nprfx_flow_provider sp = {sizeof sp, "test: shift", th_flow_shift_compute, &d};
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(2, &pool);
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.flow = &sp;
    nprfx_context *ser = NULL;
    CHECK_OK(nprfx_context_create(&init, &ser));
    /* th_parallel_context has no provider: give the parallel one the same through a fresh
     * context on the pool's executor */
    nprfx_context_init pinit = NPRFX_CONTEXT_INIT_DEFAULT;
    pinit.flow = &sp;
    pinit.executor = nprfx_context_executor(par);
    nprfx_context *par2 = NULL;
    CHECK_OK(nprfx_context_create(&pinit, &par2));
    shot s;
    shot_make(&s);
    nprfx_value pv[8];
    nprfx_node_defaults(&nprfx_node_flow, pv);
    nprfx_image a = th_image(W, H, 6, NULL), b = th_image(W, H, 6, NULL);
    int same = 1;
    void *state = NULL;
    for (int t = LAST; t >= FIRST; t--) { /* reverse order, with a cache, in tiles */
        CHECK_OK(render_at(ser, &s, pv, t, FIRST, LAST, NULL, &a, a.bounds));
        for (int y = 0; y < H; y += 4)
            CHECK_OK(render_at(par2, &s, pv, t, FIRST, LAST, &state, &b,
                               nprfx_rect_make(0, y, W, y + 4)));
        same &= !memcmp(a.data, b.data, sizeof(float) * W * H * 6);
    }
    CHECK(same);
    nprfx_flow_state_free(state);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
    shot_free(&s);
    nprfx_context_destroy(par2);
    nprfx_context_destroy(ser);
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
}

/* The accuracy metrics the CLI test reports. */
static void test_metrics(void)
{
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    float e[8] = {1, 0, 0, 0, 3, 4, NAN, 0}, t[8] = {0, 0, 0, 0, 0, 0, 0, 0}, v[4] = {1, 1, 1, 0};
    nprfx_image ei = th_image(4, 1, 2, e), ti = th_image(4, 1, 2, t), vi = th_image(4, 1, 1, v);
    double mean = -1;
    long long n = 0;
    CHECK_OK(nprfx_metric_epe(ctx, &ei, &ti, &vi, &mean, &n));
    CHECK(n == 3);
    CHECK_NEAR(mean, (1 + 0 + 5) / 3.0, 1e-12);
    /* visibility: frame i moves +1 in x from i-1 (motion_prev -1); the point at x = 0 came from
     * outside; x = 2 has another id at i-1; x = 3 does not come back */
    float mp[8] = {-1, 0, -1, 0, -1, 0, -1, 0}, mn[8] = {1, 0, 1, 0, 0, 0, 1, 0};
    float id[4] = {1, 1, 1, 1}, idp[4] = {1, 2, 1, 1};
    nprfx_image mpi = th_image(4, 1, 2, mp), mni = th_image(4, 1, 2, mn),
                idi = th_image(4, 1, 1, id), idpi = th_image(4, 1, 1, idp),
                vis = th_image(4, 1, 1, NULL);
    CHECK_OK(nprfx_motion_visible(ctx, &mpi, &idi, &mni, &idpi, 0.5, &vis));
    CHECK(vis.data[0] == 0 && vis.data[1] == 1 && vis.data[2] == 0 && vis.data[3] == 0);
    nprfx_image im[] = {ei, ti, vi, mpi, mni, idi, idpi, vis};
    for (size_t i = 0; i < sizeof im / sizeof im[0]; i++)
        nprfx_image_free(&im[i]);
    nprfx_context_destroy(ctx);
}

int main(void)
{
    test_confidence();
    test_cut_gate();
    test_luminance();
    test_scale();
    test_node();
    test_no_provider();
    test_threads();
    test_metrics();
    return check_finish();
}
