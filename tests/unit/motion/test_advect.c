/* The advect node (docs/design.md §3.16): the restart schedule and weights against hand-computed
 * numbers, exact coordinates under a uniform translation, re-seeding (low confidence, non-finite
 * motion, a previous position outside the frame), a frame rendered alone equal to the in-order
 * and the reverse-order result bit for bit, tiles and threads, the frames it declares against
 * those it fetches, error paths, lint; and what the node is for: stipples anchored on
 * the advected coordinates follow the motion (few appear or vanish between frames) where
 * screen-anchored stipples do not. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/advect.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/stipple.h"

#define MAX_FRAMES 64

static const nprfx_node_desc *node;
static int P_LAYERS, P_PERIOD, P_MAXD, P_MINC, P_OUTPUT, I_MOTION, I_CONF;

/* A sequence of inputs by frame (1..MAX_FRAMES-1), read by the fetch callback, which records
 * which frames it was asked for. */
typedef struct seq {
    nprfx_image motion[MAX_FRAMES], conf[MAX_FRAMES];
    int have_conf;
    int fetched[2][MAX_FRAMES];
    int first, last;
} seq;

static nprfx_result fetch_cb(void *user, int input, double time, nprfx_image *out)
{
    seq *s = user;
    int f = (int)floor(time + 0.5);
    if (f < 0 || f >= MAX_FRAMES || input < 0 || input > 1) return NPRFX_ERR_INVALID_ARGUMENT;
    s->fetched[input][f] = 1;
    const nprfx_image *im = input == I_MOTION ? &s->motion[f] : &s->conf[f];
    if (input == I_CONF && !s->have_conf) return NPRFX_ERR_MISSING_INPUT;
    if (!im->data) return NPRFX_ERR_INVALID_ARGUMENT;
    *out = *im;
    return NPRFX_OK;
}

static void seq_free(seq *s)
{
    for (int f = 0; f < MAX_FRAMES; f++) {
        nprfx_image_free(&s->motion[f]);
        nprfx_image_free(&s->conf[f]);
    }
}

static void defaults(nprfx_value *v, int layers, int period)
{
    nprfx_node_defaults(node, v);
    v[P_LAYERS].v[0] = layers;
    v[P_PERIOD].v[0] = period;
}

/* The render scale render() gives (a host's proxy: below 1). */
static double g_render_scale = 1;

/* Render `window` of out (5 channels over the frame) at frame t through the descriptor. */
static nprfx_result render(nprfx_context *ctx, seq *s, const nprfx_value *v, int t, void **state,
                           nprfx_rect window, nprfx_image *out, int with_fetch)
{
    nprfx_image ins[2];
    memset(ins, 0, sizeof ins);
    ins[I_MOTION] = s->motion[t];
    if (s->have_conf) ins[I_CONF] = s->conf[t];
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = node;
    a.time = t;
    a.render_scale = g_render_scale;
    a.frame = out->bounds;
    a.window = window;
    a.first_frame = s->first;
    a.last_frame = s->last;
    a.inputs = ins;
    a.params = v;
    a.output = out;
    a.fetch = with_fetch ? fetch_cb : NULL;
    a.fetch_user = s;
    a.state = state;
    return nprfx_node_render(&a);
}

static void free_state(void **state)
{
    if (*state) node->state_free(*state);
    *state = NULL;
}

/* ---- schedule and weights ------------------------------------------------------------------ */

static void test_schedule(void)
{
    nprfx_advect_params p = {2, 8, 2.0, 0.5};
    nprfx_advect_layer_time a, b;
    /* Shot 1-40, period 8: a restarts at 1, 9, 17...; b at 1 (the shot's start) and 5, 13, 21... */
    static const struct {
        int t, ra, age_a, rb, age_b;
    } want[] = {{1, 1, 0, 1, 4},   {2, 1, 1, 1, 5},    {4, 1, 3, 1, 7},   {5, 1, 4, 5, 0},
                {8, 1, 7, 5, 3},   {9, 9, 0, 5, 4},    {12, 9, 3, 5, 7},  {13, 9, 4, 13, 0},
                {16, 9, 7, 13, 3}, {17, 17, 0, 13, 4}, {40, 33, 7, 37, 3}};
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        nprfx_advect_schedule(&p, 0, want[i].t, 1, 40, &a);
        nprfx_advect_schedule(&p, 1, want[i].t, 1, 40, &b);
        CHECK(a.restart == want[i].ra && a.age == want[i].age_a);
        CHECK(b.restart == want[i].rb && b.age == want[i].age_b);
        /* tri = 1 - |2 age / 8 - 1|: 0, 0.25, 0.5, 0.75, 1, 0.75, ... */
        CHECK_NEAR(a.tri, 1.0 - fabs(want[i].age_a / 4.0 - 1.0), 0);
        CHECK_NEAR(b.tri, 1.0 - fabs(want[i].age_b / 4.0 - 1.0), 0);
    }
    /* Even period: the triangles of the staggered layers sum to 1 at every frame. */
    for (int t = 1; t <= 40; t++) {
        nprfx_advect_schedule(&p, 0, t, 1, 40, &a);
        nprfx_advect_schedule(&p, 1, t, 1, 40, &b);
        CHECK_NEAR(a.tri + b.tri, 1.0, 1e-15);
        CHECK(a.restart <= t && t - a.restart < 8 && b.restart <= t && t - b.restart < 8);
    }
    /* By hand: t = 3, ages 2 and 6: 0.5 and 0.5; t = 7, ages 6 and 2. */
    nprfx_advect_schedule(&p, 0, 3, 1, 40, &a);
    CHECK(a.tri == 0.5);
    nprfx_advect_schedule(&p, 1, 7, 1, 40, &b);
    CHECK(b.restart == 5 && b.age == 2 && b.tri == 0.5);
    /* Odd period 7: b's phase is 3; a restarts at 11 + 7k for a shot from 11. */
    p.period = 7;
    nprfx_advect_schedule(&p, 0, 20, 11, 90, &a);
    nprfx_advect_schedule(&p, 1, 20, 11, 90, &b);
    CHECK(a.restart == 18 && a.age == 2 && b.restart == 14 && b.age == 6);
    CHECK_NEAR(a.tri, 1.0 - fabs(4.0 / 7.0 - 1.0), 1e-15);
    CHECK_NEAR(b.tri, 1.0 - fabs(12.0 / 7.0 - 1.0), 1e-15);
    /* Unknown shot: counted from frame 0, negative frames too. */
    p.period = 8;
    nprfx_advect_schedule(&p, 0, -3, 1, 0, &a);
    nprfx_advect_schedule(&p, 1, -3, 1, 0, &b);
    CHECK(a.restart == -8 && a.age == 5 && b.restart == -4 && b.age == 1);
    /* One layer: history from the shot's first frame, full weight. */
    p.layers = 1;
    nprfx_advect_schedule(&p, 0, 30, 3, 40, &a);
    CHECK(a.restart == 3 && a.tri == 1.0);
}

static void test_distortion_and_mix(nprfx_context *ctx)
{
    double I[4] = {1, 0, 0, 1}, zoom[4] = {3, 0, 0, 3}, rot[4] = {0.6, -0.8, 0.8, 0.6};
    double s3[4] = {3, 0, 0, 1}, s15[4] = {1.5, 0, 0, 1}, fold[4] = {-1, 0, 0, 1};
    double shear[4] = {1, 1, 0, 1}, bad[4] = {NAN, 0, 0, 1};
    CHECK(nprfx_advect_distortion(I, 2) == 1.0);
    CHECK(nprfx_advect_distortion(zoom, 2) == 1.0); /* a uniform scale is no distortion */
    CHECK_NEAR(nprfx_advect_distortion(rot, 2), 1.0, 1e-12);
    CHECK_NEAR(nprfx_advect_distortion(s15, 2), 1.0, 0);
    CHECK_NEAR(nprfx_advect_distortion(s3, 2), 0.5, 1e-12); /* 2 - 3/2 */
    CHECK_NEAR(nprfx_advect_distortion(s3, 1.5), 0.0, 0);   /* 2 - 3/1.5 */
    CHECK(nprfx_advect_distortion(fold, 2) == 0.0);
    CHECK(nprfx_advect_distortion(bad, 2) == 0.0);
    /* shear [[1,1],[0,1]]: s1/s2 = (3 + sqrt 5)/2 = 2.618..., factor 2 - 2.618/2 */
    CHECK_NEAR(nprfx_advect_distortion(shear, 2), 2.0 - (3.0 + sqrt(5.0)) / 4.0, 1e-12);

    /* mix by hand: layer a stretched 3x along x (factor 0.5 at max_distortion 2), b the
     * identity, tri 0.5 each: w_a = 0.25, w_b = 0.5, mix = 1/3, and w_a + w_b normalised. */
    enum { w = 9, h = 7 };
    nprfx_advect_params p = {2, 8, 2.0, 0.5};
    nprfx_rect fr = nprfx_rect_make(0, 0, w, h);
    nprfx_image a = th_image(w, h, 2, NULL), b = th_image(w, h, 2, NULL),
                o = th_image(w, h, 5, NULL);
    nprfx_advect_seed(fr, 1024.0, fr, &b);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *q = nprfx_image_at(&a, x, y);
            q[0] = (float)(3.0 * x / 1024.0);
            q[1] = (float)(y / 1024.0);
        }
    nprfx_advect_layer_time ta = {1, 2, 0.5}, tb = {5, 6, 0.5};
    CHECK_OK(nprfx_advect_combine(ctx, &p, fr, 1024.0, &a, &b, &ta, &tb, fr, &o));
    int ok = 1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *q = nprfx_image_at(&o, x, y);
            ok &= fabsf(q[4] - 1.0f / 3.0f) < 1e-6f && q[0] == nprfx_image_at(&a, x, y)[0] &&
                  q[3] == nprfx_image_at(&b, x, y)[1];
        }
    CHECK(ok);
    /* Both weights 0 (a at its restart, b folded): the younger layer, a. */
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            nprfx_image_at(&b, x, y)[0] = (float)(-x / 1024.0);
    ta.tri = 0;
    ta.age = 0;
    CHECK_OK(nprfx_advect_combine(ctx, &p, fr, 1024.0, &a, &b, &ta, &tb, fr, &o));
    ok = 1;
    for (int i = 0; i < w * h; i++)
        ok &= o.data[5 * i + 4] == 1.0f;
    CHECK(ok);
    /* ... and b when b is the younger one. */
    ta.age = 7;
    tb.age = 0;
    tb.tri = 0;
    ta.tri = 0;
    CHECK_OK(nprfx_advect_combine(ctx, &p, fr, 1024.0, &a, &b, &ta, &tb, fr, &o));
    ok = 1;
    for (int i = 0; i < w * h; i++)
        ok &= o.data[5 * i + 4] == 0.0f;
    CHECK(ok);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
    nprfx_image_free(&o);
}

/* ---- the recursion through the node -------------------------------------------------------- */

static void fill_uniform(seq *s, int w, int h, int f0, int f1, float mx, float my)
{
    for (int f = f0; f <= f1; f++) {
        s->motion[f] = th_image(w, h, 2, NULL);
        for (int i = 0; i < w * h; i++) {
            s->motion[f].data[2 * i] = mx;
            s->motion[f].data[2 * i + 1] = my;
        }
    }
}

/* Uniform translation by a dyadic (-0.5, -0.25) px/frame (each point was 0.5 px left and 0.25 px
 * up a frame before): after k steps every pixel whose k-step history stays clear of the
 * re-seeded edge holds the identity moved by exactly k (0.5, 0.25) px; the pixels whose previous
 * position is outside the frame (column 0, row 0) hold the identity. */
/* Frame T of a uniform translation by (mx, my) a frame over frames 1..T of a shot 1-30 (two
 * layers, period 24) at the given render scale: the sequence in *s, the result in *out. */
enum { TW = 24, TH = 20, TT = 7 };
static void translated(nprfx_context *ctx, float mx, float my, double scale, seq *s, nprfx_value *v,
                       nprfx_image *out, void **state)
{
    memset(s, 0, sizeof *s);
    s->first = 1;
    s->last = 30;
    fill_uniform(s, TW, TH, 1, TT, mx, my);
    defaults(v, 2, 24);
    *out = th_image(TW, TH, 5, NULL);
    *state = NULL;
    g_render_scale = scale;
    CHECK_OK(render(ctx, s, v, TT, state, out->bounds, out, 1));
    g_render_scale = 1;
}

static void test_translation(nprfx_context *ctx)
{
    enum { w = TW, h = TH, T = TT };
    seq s;
    nprfx_value v[8];
    nprfx_image out;
    void *state;
    translated(ctx, -0.5f, -0.25f, 1, &s, v, &out, &state);
    int k = T - 1, exact = 1, seeded = 1, same_b = 1, mix = 1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *o = nprfx_image_at(&out, x, y);
            if (x >= k + 1 && y >= k + 1) {
                exact &= o[0] == (float)((x - 0.5 * k) / 1024.0) &&
                         o[1] == (float)((y - 0.25 * k) / 1024.0);
                /* J = I, tri 0.5 and 0.5 (ages 6 and 18 of 24) */
                if (x < w - 1 && y < h - 1 && x > k + 1 && y > k + 1) mix &= o[4] == 0.5f;
            }
            if (x == 0 || y == 0)
                seeded &= o[0] == (float)(x / 1024.0) && o[1] == (float)(y / 1024.0);
            same_b &= o[2] == o[0] && o[3] == o[1]; /* one life so far: b = a */
        }
    CHECK(exact);
    CHECK(seeded);
    CHECK(same_b);
    CHECK(mix);
    /* The frames it fetched are the frames it declared: 2..6 (7 is the call's own input). */
    int fetched_ok = !s.fetched[0][1] && !s.fetched[0][T];
    for (int f = 2; f < T; f++)
        fetched_ok &= s.fetched[0][f];
    CHECK(fetched_ok);
    int chan[2] = {2, 0};
    nprfx_frames_query q = {T, s.first, s.last, chan};
    nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
    int n = 0;
    CHECK_OK(nprfx_node_frames_needed(ctx, node, v, &q, I_MOTION, rg, &n));
    CHECK(n == 1 && rg[0].first == 2 && rg[0].last == T);
    free_state(&state);
    nprfx_image_free(&out);
    seq_free(&s);
}

/* A host's half-size proxy: the identity is pixel / (1024 * 0.5), and the motion vectors come
 * in full-resolution pixels (-1, -0.5 a frame: -0.5, -0.25 of the proxy's pixels), which the
 * node multiplies by the render scale (the args' vector_scale, which defaults to it): the same
 * coordinates as test_translation's, on the proxy's plane. Taken raw, the vectors would move
 * the texture twice as fast as the picture. */
static void test_proxy(nprfx_context *ctx)
{
    enum { w = TW, h = TH, T = TT };
    seq s;
    nprfx_value v[8];
    nprfx_image out;
    void *state;
    translated(ctx, -1.0f, -0.5f, 0.5, &s, v, &out, &state);
    int k = T - 1, exact = 1;
    for (int y = k + 1; y < h; y++)
        for (int x = k + 1; x < w; x++) {
            const float *o = nprfx_image_at(&out, x, y);
            exact &=
                o[0] == (float)((x - 0.5 * k) / 512.0) && o[1] == (float)((y - 0.25 * k) / 512.0);
        }
    CHECK(exact);
    free_state(&state);
    nprfx_image_free(&out);
    seq_free(&s);
}

/* Re-seeding: a pixel with low or NaN confidence, or NaN or infinite motion, gets the identity;
 * its neighbours keep their advected values. */
static void test_reseed(nprfx_context *ctx)
{
    enum { w = 16, h = 12 };
    seq s;
    memset(&s, 0, sizeof s);
    s.first = 1;
    s.last = 10;
    s.have_conf = 1;
    fill_uniform(&s, w, h, 1, 3, -1.0f, 0.0f);
    for (int f = 1; f <= 3; f++) {
        s.conf[f] = th_image(w, h, 1, NULL);
        for (int i = 0; i < w * h; i++)
            s.conf[f].data[i] = 0.9f;
    }
    nprfx_image_at(&s.conf[3], 8, 5)[0] = 0.2f;
    nprfx_image_at(&s.conf[3], 9, 5)[0] = NAN;
    nprfx_image_at(&s.motion[3], 10, 5)[0] = NAN;
    nprfx_image_at(&s.motion[3], 11, 5)[1] = INFINITY;
    nprfx_image_at(&s.motion[3], 12, 5)[0] = 1e30f;
    nprfx_value v[8];
    defaults(v, 2, 24);
    nprfx_image out = th_image(w, h, 5, NULL);
    CHECK_OK(render(ctx, &s, v, 3, NULL, out.bounds, &out, 1));
    int ok = 1, finite = 1;
    for (int x = 8; x <= 12; x++) {
        const float *o = nprfx_image_at(&out, x, 5);
        ok &= o[0] == (float)(x / 1024.0) && o[1] == (float)(5 / 1024.0);
    }
    const float *o = nprfx_image_at(&out, 7, 5);
    ok &= o[0] == (float)(5 / 1024.0); /* advected twice by 1 px */
    for (int i = 0; i < w * h * 5; i++)
        finite &= isfinite(out.data[i]) != 0;
    CHECK(ok);
    CHECK(finite);
    /* The mix stays in [0, 1] next to the seam. */
    int in01 = 1;
    for (int i = 0; i < w * h; i++)
        in01 &= out.data[5 * i + 4] >= 0.0f && out.data[5 * i + 4] <= 1.0f;
    CHECK(in01);
    nprfx_image_free(&out);
    seq_free(&s);
}

/* A sequence with varying sub-pixel motion, a moving disc of low confidence and a NaN: frames
 * 1-30 rendered in order with one state, each alone with a fresh state, in reverse order with one
 * state, in tiles with 3 threads, must agree bit for bit. */
static void make_varying(seq *s, int w, int h, int f0, int f1)
{
    for (int f = f0; f <= f1; f++) {
        s->motion[f] = th_image(w, h, 2, NULL);
        s->conf[f] = th_image(w, h, 1, NULL);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                float *m = nprfx_image_at(&s->motion[f], x, y);
                m[0] = (float)(0.7 * sin(0.05 * y + 0.3 * f) + 0.3 - 0.004 * (x - w / 2));
                m[1] = (float)(0.5 * cos(0.07 * x - 0.2 * f) - 0.2 + 0.003 * (y - h / 2));
                double dx = x - (10 + 2 * f), dy = y - 20;
                nprfx_image_at(&s->conf[f], x, y)[0] = dx * dx + dy * dy < 36 ? 0.1f : 0.95f;
            }
        if (f == 13) nprfx_image_at(&s->motion[f], 30, 9)[0] = NAN;
    }
}

static void test_order_tiles(nprfx_context *ctx, nprfx_context *par)
{
    enum { w = 61, h = 43, N = 30 };
    seq s;
    memset(&s, 0, sizeof s);
    s.first = 1;
    s.last = N;
    s.have_conf = 1;
    make_varying(&s, w, h, 1, N);
    for (int layers = 1; layers <= 2; layers++) {
        nprfx_value v[8];
        defaults(v, layers, 8);
        v[P_MAXD].v[0] = 1.3;
        nprfx_image seq_out[N + 1];
        void *state = NULL;
        for (int t = 1; t <= N; t++) {
            seq_out[t] = th_image(w, h, 5, NULL);
            CHECK_OK(render(ctx, &s, v, t, &state, seq_out[t].bounds, &seq_out[t], 1));
        }
        free_state(&state);
        size_t bytes = sizeof(float) * w * h * 5;
        int alone = 0, reverse = 0, tiles = 0, changes = 0;
        nprfx_image o = th_image(w, h, 5, NULL);
        for (int t = 1; t <= N; t++) {
            CHECK_OK(render(ctx, &s, v, t, &state, o.bounds, &o, 1));
            free_state(&state);
            alone += memcmp(o.data, seq_out[t].data, bytes) != 0;
            if (t > 1) changes += memcmp(seq_out[t - 1].data, seq_out[t].data, bytes) != 0;
        }
        for (int t = N; t >= 1; t--) {
            CHECK_OK(render(ctx, &s, v, t, &state, o.bounds, &o, 1));
            reverse += memcmp(o.data, seq_out[t].data, bytes) != 0;
        }
        free_state(&state);
        /* tiles of 16x16 (3 threads, one state) and 13x7 columns (serial, no state) */
        for (int t = 5; t <= N; t += 6) {
            memset(o.data, 0, bytes);
            for (int y = 0; y < h; y += 16)
                for (int x = 0; x < w; x += 16)
                    CHECK_OK(render(
                        par, &s, v, t, &state,
                        nprfx_rect_make(x, y, x + 16 < w ? x + 16 : w, y + 16 < h ? y + 16 : h), &o,
                        1));
            tiles += memcmp(o.data, seq_out[t].data, bytes) != 0;
            memset(o.data, 0, bytes);
            for (int y = 0; y < h; y += 7)
                for (int x = 0; x < w; x += 13)
                    CHECK_OK(render(
                        ctx, &s, v, t, NULL,
                        nprfx_rect_make(x, y, x + 13 < w ? x + 13 : w, y + 7 < h ? y + 7 : h), &o,
                        1));
            tiles += memcmp(o.data, seq_out[t].data, bytes) != 0;
        }
        free_state(&state);
        printf("layers %d: %d of %d frames differ alone, %d in reverse, %d tiled renders\n", layers,
               alone, N, reverse, tiles);
        CHECK(alone == 0);
        CHECK(reverse == 0);
        CHECK(tiles == 0);
        CHECK(changes == N - 1); /* it does move */
        int finite = 1;
        for (int t = 1; t <= N; t++)
            for (size_t i = 0; i < (size_t)w * h * 5; i++)
                finite &= isfinite(seq_out[t].data[i]) != 0;
        CHECK(finite);
        /* The declared frames are exactly those fetched, with an empty cache. */
        for (int t = 1; t <= N; t++) {
            memset(s.fetched, 0, sizeof s.fetched);
            CHECK_OK(render(ctx, &s, v, t, NULL, o.bounds, &o, 1));
            int chan[2] = {2, 1};
            nprfx_frames_query q = {t, s.first, s.last, chan};
            for (int in = 0; in < 2; in++) {
                nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
                int n = 0, match = 1;
                CHECK_OK(nprfx_node_frames_needed(ctx, node, v, &q, in, rg, &n));
                for (int f = 1; f <= N; f++) {
                    int declared = 0;
                    for (int i = 0; i < n; i++)
                        declared |= rg[i].first <= f && f <= rg[i].last;
                    /* the frame itself is the call's own input, declared but not fetched */
                    if (f != t) match &= declared == s.fetched[in][f];
                }
                if (!match)
                    printf("layers %d frame %d input %d: declared and fetched differ\n", layers, t,
                           in);
                CHECK(match);
            }
        }
        for (int t = 1; t <= N; t++)
            nprfx_image_free(&seq_out[t]);
        nprfx_image_free(&o);
    }
    seq_free(&s);
}

/* output layers and mix (for OpenFX hosts, four channels at most) are channels 0-3 and 4 of all,
 * bit for bit, from one state as from fresh ones. */
static void test_outputs(nprfx_context *ctx)
{
    enum { w = 33, h = 21, T = 11 };
    seq s;
    memset(&s, 0, sizeof s);
    s.first = 1;
    s.last = 20;
    s.have_conf = 1;
    make_varying(&s, w, h, 1, T);
    nprfx_value v[8];
    defaults(v, 2, 6);
    nprfx_image all = th_image(w, h, 5, NULL), lay = th_image(w, h, 4, NULL);
    nprfx_image mix = th_image(w, h, 1, NULL);
    void *state = NULL;
    CHECK_OK(render(ctx, &s, v, T, &state, all.bounds, &all, 1));
    th_set_choice(node, v, "output", "layers");
    CHECK_OK(render(ctx, &s, v, T, &state, lay.bounds, &lay, 1));
    th_set_choice(node, v, "output", "mix");
    CHECK_OK(render(ctx, &s, v, T, NULL, mix.bounds, &mix, 1));
    int same = 1;
    for (int i = 0; i < w * h; i++) {
        same &= memcmp(&all.data[5 * i], &lay.data[4 * i], 4 * sizeof(float)) == 0;
        same &= all.data[5 * i + 4] == mix.data[i];
    }
    CHECK(same);
    int ich[2] = {2, 1};
    nprfx_output_info oi;
    CHECK_OK(nprfx_node_output_info(ctx, node, v, ich, &oi));
    CHECK(oi.channels == 1 && !strcmp(oi.names[0], "mix"));
    th_set_choice(node, v, "output", "layers");
    CHECK_OK(nprfx_node_output_info(ctx, node, v, ich, &oi));
    CHECK(oi.channels == 4 && !strcmp(oi.names[3], "b.V"));
    /* a 5-channel output for a 4-channel option is refused */
    CHECK(render(ctx, &s, v, T, NULL, all.bounds, &all, 1) != NPRFX_OK);
    free_state(&state);
    nprfx_image_free(&all);
    nprfx_image_free(&lay);
    nprfx_image_free(&mix);
    seq_free(&s);
}

static void test_errors(nprfx_context *ctx)
{
    enum { w = 8, h = 6 };
    seq s;
    memset(&s, 0, sizeof s);
    s.first = 1;
    s.last = 0; /* unknown shot */
    fill_uniform(&s, w, h, 1, 3, 0.25f, 0.0f);
    nprfx_value v[8];
    defaults(v, 1, 8);
    nprfx_image out = th_image(w, h, 5, NULL);
    CHECK(render(ctx, &s, v, 3, NULL, out.bounds, &out, 1) != NPRFX_OK);
    CHECK(strstr(th_error(ctx), "shot") != NULL);
    /* no fetch, and the frame needs the previous ones */
    s.last = 10;
    defaults(v, 2, 8);
    CHECK(render(ctx, &s, v, 3, NULL, out.bounds, &out, 0) == NPRFX_ERR_UNSUPPORTED);
    CHECK(strstr(th_error(ctx), "motion_prev") != NULL);
    /* ... but frame 1, both layers' restart, reads nothing else: the identity */
    CHECK_OK(render(ctx, &s, v, 1, NULL, out.bounds, &out, 0));
    CHECK(nprfx_image_at(&out, 5, 4)[0] == (float)(5 / 1024.0) &&
          nprfx_image_at(&out, 5, 4)[3] == (float)(4 / 1024.0));
    v[P_PERIOD].v[0] = 1;
    CHECK(render(ctx, &s, v, 3, NULL, out.bounds, &out, 1) != NPRFX_OK);
    CHECK(strstr(th_error(ctx), "period") != NULL);
    defaults(v, 2, 8);
    v[P_MINC].v[0] = 2;
    CHECK(render(ctx, &s, v, 3, NULL, out.bounds, &out, 1) != NPRFX_OK);
    CHECK(strstr(th_error(ctx), "min_confidence") != NULL);
    nprfx_image_free(&out);
    seq_free(&s);
}

/* ---- the coherence figure: stipples on the advected coordinates ---------------------------- */

/* Exact affine motions, constant in time: frame t's point x was at back(x) at frame t-1 and is
 * at fwd(x) at t+1. */
typedef struct motion_model {
    const char *name;
    double tx, ty, angle, scale; /* fwd(x) = c + scale R(angle) (x - c) + t */
} motion_model;

static void model_map(const motion_model *m, double cx, double cy, int inverse, double x, double y,
                      double *ox, double *oy)
{
    double c = cos(m->angle), s = sin(m->angle), k = m->scale;
    if (!inverse) {
        double dx = x - cx, dy = y - cy;
        *ox = cx + k * (c * dx - s * dy) + m->tx;
        *oy = cy + k * (s * dx + c * dy) + m->ty;
    } else {
        double dx = (x - m->tx - cx) / k, dy = (y - m->ty - cy) / k;
        *ox = cx + c * dx + s * dy;
        *oy = cy - s * dx + c * dy;
    }
}

static int cmp_sample(const void *pa, const void *pb)
{
    const nprfx_stipple *a = pa, *b = pb;
    if (a->sample != b->sample) return a->sample < b->sample ? -1 : 1;
    return a->x < b->x ? -1 : a->x > b->x;
}

/* As tests/unit/test_stipple_motion.c measures it: a dot of frame f carried by the true motion
 * must find the same sample in frame f+1 within 1.5 px, else it vanished; a dot of f+1 that no
 * dot of f found appeared. Dots near the frame's edges are not counted. */
static void compare(const motion_model *m, int w, int h, const nprfx_stipple *l0, size_t n0,
                    nprfx_stipple *l1, size_t n1, size_t *count, size_t *changed)
{
    qsort(l1, n1, sizeof *l1, cmp_sample);
    unsigned char *used = calloc(n1 ? n1 : 1, 1);
    double cx = (w - 1) * 0.5, cy = (h - 1) * 0.5;
    for (size_t i = 0; i < n0; i++) {
        double px, py;
        model_map(m, cx, cy, 0, l0[i].x, l0[i].y, &px, &py);
        if (px < 2 || py < 2 || px > w - 3 || py > h - 3) continue;
        (*count)++;
        size_t lo = 0, hi = n1;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (l1[mid].sample < l0[i].sample)
                lo = mid + 1;
            else
                hi = mid;
        }
        double best = 1e30;
        size_t bi = 0;
        for (size_t k = lo; k < n1 && l1[k].sample == l0[i].sample; k++) {
            double d = hypot(l1[k].x - px, l1[k].y - py);
            if (d < best) best = d, bi = k;
        }
        /* a pop: a dot appearing or vanishing with at least half its ink, or a kept one whose
         * ink changes by half (stipples changing foreshortening level fade over frames) */
        if (best < 1.5) {
            used[bi] = 1;
            *changed += fabs(l1[bi].tone - l0[i].tone) >= 0.5;
        } else {
            *changed += l0[i].tone >= 0.5;
        }
    }
    for (size_t k = 0; k < n1; k++) {
        if (l1[k].x < 2 || l1[k].y < 2 || l1[k].x > w - 3 || l1[k].y > h - 3) continue;
        (*count)++;
        if (!used[k]) *changed += l1[k].tone >= 0.5;
    }
    free(used);
}

/* The pops per frame (as a fraction of the dots) over frames f0..f1 of the model, with uv =
 * advect's layer a (advected) or no uv (screen-anchored). */
static double stipple_change(nprfx_context *ctx, nprfx_stipple_sequence *sq, const motion_model *m,
                             int advected, int f0, int f1, size_t *dots)
{
    enum { w = 256, h = 192 };
    seq s;
    memset(&s, 0, sizeof s);
    s.first = 1;
    s.last = 48;
    double cx = (w - 1) * 0.5, cy = (h - 1) * 0.5;
    for (int f = 1; f <= f1; f++) {
        s.motion[f] = th_image(w, h, 2, NULL);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                double px, py;
                model_map(m, cx, cy, 1, x, y, &px, &py);
                float *q = nprfx_image_at(&s.motion[f], x, y);
                q[0] = (float)(px - x);
                q[1] = (float)(py - y);
            }
    }
    nprfx_value v[8];
    defaults(v, 2, 24);
    nprfx_image adv = th_image(w, h, 5, NULL), tone = th_image(w, h, 1, NULL);
    for (int i = 0; i < w * h; i++)
        tone.data[i] = 0.5f;
    nprfx_image uv = nprfx_image_channels(&adv, 0, 2);
    nprfx_stipple_params p;
    nprfx_stipple_params_default(&p);
    p.sequence = sq;
    p.tile = 0.125;
    /* an advected layer's UVs stretch as it ages: not a foreshortening, and following it changes
     * the dots' levels (nearly doubling the pops on rotate) */
    p.anisotropy = 0;
    nprfx_stipple_inputs in = {&tone, advected ? &uv : NULL, NULL, tone.bounds};
    void *state = NULL;
    nprfx_stipple *l0 = NULL, *l1 = NULL;
    size_t n0 = 0, n1 = 0, count = 0, changed = 0, total = 0;
    for (int f = f0; f <= f1; f++) {
        CHECK_OK(render(ctx, &s, v, f, &state, adv.bounds, &adv, 1));
        CHECK_OK(nprfx_stipple_collect(ctx, &p, &in, tone.bounds, &l1, &n1));
        total += n1;
        if (f > f0) compare(m, w, h, l0, n0, l1, n1, &count, &changed);
        free(l0);
        l0 = l1;
        n0 = n1;
        l1 = NULL;
    }
    free(l0);
    free_state(&state);
    nprfx_image_free(&adv);
    nprfx_image_free(&tone);
    seq_free(&s);
    *dots = total / (size_t)(f1 - f0 + 1);
    return count ? (double)changed / (double)count : 1.0;
}

static void test_coherence(nprfx_context *ctx)
{
    nprfx_stipple_sequence *sq = NULL;
    CHECK_OK(nprfx_stipple_sequence_create(ctx, &sq));
    /* about 2-3 px a frame at the frame's edges, so a dot left on the screen misses its match */
    const motion_model models[] = {{"translate", 2.3, -1.1, 0, 1},
                                   {"rotate", 0, 0, 1.0 * M_PI / 180.0, 1},
                                   {"zoom", 0, 0, 0, 1.02},
                                   {"rotate+zoom", 0.8, 0.4, 0.6 * M_PI / 180.0, 1.012}};
    for (size_t i = 0; i < sizeof models / sizeof models[0]; i++) {
        size_t dots_a = 0, dots_s = 0;
        /* frames 1-12: layer a from its restart at 1 to age 11 (period 24) */
        double adv = stipple_change(ctx, sq, &models[i], 1, 1, 12, &dots_a);
        double scr = stipple_change(ctx, sq, &models[i], 0, 1, 12, &dots_s);
        printf("%-11s stipples popping per frame, frames 1-12: advected uv "
               "%.2f%% (%zu dots), screen-anchored %.2f%% (%zu dots)\n",
               models[i].name, 100 * adv, dots_a, 100 * scr, dots_s);
        CHECK(adv <= 0.06);
        CHECK(adv <= 0.2 * scr);
    }
    nprfx_stipple_sequence_destroy(sq);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    node = nprfx_node_find("advect");
    CHECK(node != NULL);
    if (!node) return check_finish();
    CHECK_OK(nprfx_node_lint(ctx, node));
    P_LAYERS = th_param(node, "layers");
    P_PERIOD = th_param(node, "period");
    P_MAXD = th_param(node, "max_distortion");
    P_MINC = th_param(node, "min_confidence");
    P_OUTPUT = th_param(node, "output");
    I_MOTION = th_input(node, "motion_prev");
    I_CONF = th_input(node, "confidence");
    CHECK(I_MOTION == NPRFX_ADVECT_IN_MOTION_PREV && I_CONF == NPRFX_ADVECT_IN_CONFIDENCE);
    nprfx_output_info oi;
    int ich[2] = {2, 0};
    nprfx_value v[8];
    defaults(v, 2, 24);
    CHECK_OK(nprfx_node_output_info(ctx, node, v, ich, &oi));
    CHECK(oi.channels == 5 && !strcmp(oi.names[0], "a.U") && !strcmp(oi.names[1], "a.V") &&
          !strcmp(oi.names[2], "b.U") && !strcmp(oi.names[3], "b.V") &&
          !strcmp(oi.names[4], "mix"));

    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(3, &pool);
    test_schedule();
    test_distortion_and_mix(ctx);
    test_translation(ctx);
    test_proxy(ctx);
    test_reseed(ctx);
    test_order_tiles(ctx, par);
    test_outputs(ctx);
    test_errors(ctx);
    test_coherence(par);
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
    nprfx_context_destroy(ctx);
    return check_finish();
}
