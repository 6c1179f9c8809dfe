/* The tone node: the mapping and percentiles against hand-computed values, a range
 * measured once over the shot (the same value maps the same at every frame, whatever the order
 * frames are rendered in), a cache that notices a changed input, and coverage. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/exec.h"
#include "nprfx/tone.h"

extern const nprfx_node_desc nprfx_node_tone;

static float px(const nprfx_image *im, int x, int y)
{
    return nprfx_image_at(im, x, y)[0];
}

static nprfx_tone_params plain(void)
{
    nprfx_tone_params p;
    memset(&p, 0, sizeof p);
    p.range = NPRFX_TONE_RANGE_MANUAL;
    p.high = 100;
    p.white = 1;
    p.gamma = 1;
    p.out_high = 1;
    p.background = 1;
    return p;
}

static void test_map(void)
{
    nprfx_tone_params p = plain();
    CHECK(nprfx_tone_map(&p, 2, 4, 3, 1) == 0.5);
    CHECK(nprfx_tone_map(&p, 2, 4, 1, 1) == 0.0);
    CHECK(nprfx_tone_map(&p, 2, 4, 9, 1) == 1.0);
    CHECK(nprfx_tone_map(&p, 2, 4, NAN, 1) == 0.0);
    /* coverage mixes towards the background */
    CHECK(nprfx_tone_map(&p, 2, 4, 3, 0.25) == 0.875);
    CHECK(nprfx_tone_map(&p, 2, 4, 3, 0) == 1.0);
    /* exposure: one stop doubles t */
    p.exposure = 1;
    CHECK(nprfx_tone_map(&p, 2, 4, 2.5, 1) == 0.5);
    CHECK(nprfx_tone_map(&p, 2, 4, 3, 1) == 1.0);
    p.exposure = 0;
    p.gamma = 2;
    CHECK_NEAR(nprfx_tone_map(&p, 2, 4, 3, 1), sqrt(0.5), 1e-15);
    p.gamma = 1;
    p.out_low = 0.2;
    p.out_high = 0.8;
    CHECK_NEAR(nprfx_tone_map(&p, 2, 4, 2.5, 1), 0.35, 1e-15);
    /* solid blacks 0.2 over out 0.4 + 0.5 t: t 0 -> 0 (solid ink, not 0.4); t 0.1 -> 0.45 * 0.5
     * = 0.225; from t 0.2 on as without (0.5 at 0.2, 0.65 at 0.5) */
    p.out_low = 0.4;
    p.out_high = 0.9;
    p.solid_blacks = 0.2;
    CHECK(nprfx_tone_map(&p, 0, 1, 0.0, 1) == 0.0);
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.1, 1), 0.225, 1e-15);
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.2, 1), 0.5, 1e-15);
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.5, 1), 0.65, 1e-15);
    p.solid_blacks = 0;
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.0, 1), 0.4, 1e-15);
    /* an empty range is a step at lo */
    p = plain();
    CHECK(nprfx_tone_map(&p, 2, 2, 2, 1) == 0.0 && nprfx_tone_map(&p, 2, 2, 2.001, 1) == 1.0);
    /* bands: 4 levels 0, 1/3, 2/3, 1; a hard step at each quarter; softness ramps up to it */
    p = plain();
    p.bands = 4;
    CHECK(nprfx_tone_map(&p, 0, 1, 0.1, 1) == 0.0);
    CHECK(nprfx_tone_map(&p, 0, 1, 0.3, 1) == 1.0 / 3.0);
    CHECK(nprfx_tone_map(&p, 0, 1, 0.6, 1) == 2.0 / 3.0);
    CHECK(nprfx_tone_map(&p, 0, 1, 0.8, 1) == 1.0 && nprfx_tone_map(&p, 0, 1, 1.0, 1) == 1.0);
    p.band_softness = 0.2;
    /* x = 0.7 * 4 = 2.8: f = 0.8 is where the ramp to level 3 starts; x = 2.9: halfway */
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.7, 1), 2.0 / 3.0, 1e-12);
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.725, 1), 2.5 / 3.0, 1e-12);
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.2, 1), 0.0, 1e-12);
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.225, 1), 0.5 / 3.0, 1e-12);
    CHECK_NEAR(nprfx_tone_map(&p, 0, 1, 0.2375, 1), 0.75 / 3.0, 1e-12);
    /* luminance and light */
    float rgb[3] = {1, 0, 0}, g[1] = {0.25f};
    CHECK_NEAR(nprfx_tone_value(rgb, 3), 0.2126, 1e-15);
    CHECK(nprfx_tone_value(g, 1) == 0.25);
    CHECK(nprfx_tone_light(0.3, 0.6) == 0.5 && nprfx_tone_light(0.3, 0) == 0.0);
}

static void test_percentile(void)
{
    float v[101];
    /* 1..101 in a scrambled order (37 is coprime with 101) */
    for (int i = 0; i < 101; i++)
        v[i] = (float)(1 + (i * 37) % 101);
    CHECK(nprfx_tone_percentile(v, 101, 50) == 51.0);
    CHECK(nprfx_tone_percentile(v, 101, 0) == 1.0);
    CHECK(nprfx_tone_percentile(v, 101, 100) == 101.0);
    CHECK_NEAR(nprfx_tone_percentile(v, 101, 2.5), 3.5, 1e-12);
    float d[6] = {5, 5, 5, 1, 5, 5};
    CHECK(nprfx_tone_percentile(d, 6, 50) == 5.0);
    CHECK(nprfx_tone_percentile(d, 6, 0) == 1.0);
    float one[1] = {7};
    CHECK(nprfx_tone_percentile(one, 1, 30) == 7.0);
    CHECK(nprfx_tone_percentile(one, 0, 30) == 0.0);
}

/* A 5-frame shot of 16x8 frames: frame f holds f + x / 15 (so the shot spans [1, 6]), except
 * the right quarter (x >= 12), which holds 100 and is uncovered. */
enum { W = 16, H = 8, NF = 5 };
typedef struct shot {
    nprfx_image tone[NF + 1], cov[NF + 1];
    int calls;
} shot;

static nprfx_result fetch_shot(void *user, int input, double time, nprfx_image *out)
{
    shot *s = user;
    s->calls++;
    int f = (int)time;
    if (f < 1 || f > NF) return NPRFX_ERR_INVALID_ARGUMENT;
    if (input == 0)
        *out = s->tone[f];
    else if (input == 2)
        *out = s->cov[f];
    else
        return NPRFX_ERR_MISSING_INPUT;
    return NPRFX_OK;
}

static void make_shot(nprfx_context *ctx, shot *s)
{
    memset(s, 0, sizeof *s);
    for (int f = 1; f <= NF; f++) {
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &s->tone[f]);
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &s->cov[f]);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                nprfx_image_at(&s->tone[f], x, y)[0] = x >= 12 ? 100.0f : (float)(f + x / 15.0);
                nprfx_image_at(&s->cov[f], x, y)[0] = x >= 12 ? 0.0f : 1.0f;
            }
    }
}

static void free_shot(shot *s)
{
    for (int f = 1; f <= NF; f++) {
        nprfx_image_free(&s->tone[f]);
        nprfx_image_free(&s->cov[f]);
    }
}

/* Render frame f of the shot through the descriptor. */
static nprfx_result render_frame(nprfx_context *ctx, shot *s, const nprfx_value *pv, int f,
                                 void **state, nprfx_image *out, int fetch)
{
    const nprfx_node_desc *n = &nprfx_node_tone;
    nprfx_image in[3];
    memset(in, 0, sizeof in);
    in[th_input(n, "tone")] = s->tone[f];
    in[th_input(n, "coverage")] = s->cov[f];
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = n;
    a.time = f;
    a.render_scale = 1;
    a.frame = out->bounds;
    a.window = out->bounds;
    a.first_frame = 1;
    a.last_frame = NF;
    a.inputs = in;
    a.params = pv;
    a.output = out;
    a.fetch = fetch ? fetch_shot : NULL;
    a.fetch_user = s;
    a.state = state;
    return nprfx_node_render(&a);
}

static void test_shot_range(nprfx_context *ctx)
{
    const nprfx_node_desc *n = &nprfx_node_tone;
    CHECK(th_input(n, "tone") == 0 && th_input(n, "coverage") == 2);
    shot s;
    make_shot(ctx, &s);
    nprfx_value pv[16];
    nprfx_node_defaults(n, pv);
    pv[th_param(n, "low")].v[0] = 0;
    pv[th_param(n, "high")].v[0] = 100;
    nprfx_image out, again;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &out);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &again);
    void *state = NULL;
    /* frames out of order: every one maps with the shot's range [1, 1 + 4 + 11/15] */
    int order[NF] = {3, 5, 1, 4, 2};
    double hi = 5 + 11 / 15.0;
    for (int k = 0; k < NF; k++) {
        int f = order[k];
        CHECK_OK(render_frame(ctx, &s, pv, f, &state, &out, 1));
        for (int x = 0; x < 12; x++) {
            double v = (float)(f + x / 15.0);
            CHECK_NEAR(px(&out, x, 3), (v - 1) / (hi - 1), 1e-6);
        }
        /* uncovered: the background, and the 100s were not measured */
        CHECK(px(&out, 12, 0) == 1.0f && px(&out, 15, 7) == 1.0f);
    }
    double lo_m = 0, hi_m = 0;
    CHECK(nprfx_tone_state_range(state, &lo_m, &hi_m) && lo_m == 1.0);
    CHECK_NEAR(hi_m, hi, 1e-6);
    /* measured once: after the first frame, a render fetches nothing but its own frame */
    s.calls = 0;
    CHECK_OK(render_frame(ctx, &s, pv, 2, &state, &out, 1));
    CHECK(s.calls == 0);
    /* a fresh instance gives the same pixels (the cache never changes a result) */
    void *fresh = NULL;
    CHECK_OK(render_frame(ctx, &s, pv, 2, &fresh, &again, 1));
    CHECK(memcmp(out.data, again.data, sizeof(float) * W * H) == 0);
    nprfx_tone_state_free(fresh);
    /* an upstream change at the rendered frame is noticed: the range is measured again */
    for (int y = 0; y < H; y++)
        nprfx_image_at(&s.tone[2], 0, y)[0] = 0.0f;
    CHECK_OK(render_frame(ctx, &s, pv, 2, &state, &out, 1));
    fresh = NULL;
    CHECK_OK(render_frame(ctx, &s, pv, 2, &fresh, &again, 1));
    CHECK(memcmp(out.data, again.data, sizeof(float) * W * H) == 0);
    CHECK(px(&out, 0, 0) == 0.0f && px(&out, 1, 0) > 0.0f);
    nprfx_tone_state_free(fresh);
    nprfx_tone_state_free(state);
    state = NULL;
    /* range 'frame': frame 3 alone spans [3, 3 + 11/15] */
    th_set_choice(n, pv, "range", "frame");
    pv[th_param(n, "reference_frame")].v[0] = 3;
    CHECK_OK(render_frame(ctx, &s, pv, 5, &state, &out, 1));
    CHECK(px(&out, 0, 0) == 1.0f); /* 5 is above frame 3's range */
    CHECK_OK(render_frame(ctx, &s, pv, 3, &state, &out, 1));
    CHECK(px(&out, 0, 0) == 0.0f && px(&out, 11, 0) == 1.0f);
    CHECK_NEAR(px(&out, 5, 0), 5.0 / 11.0, 1e-6);
    nprfx_tone_state_free(state);
    state = NULL;
    /* a host that cannot fetch: 'frame' works on the reference frame, 'shot' says why not */
    CHECK_OK(render_frame(ctx, &s, pv, 3, &state, &out, 0));
    CHECK(render_frame(ctx, &s, pv, 4, &state, &out, 0) == NPRFX_ERR_UNSUPPORTED);
    CHECK(strstr(th_error(ctx), "range 'frame' measures frame 3") != NULL);
    th_set_choice(n, pv, "range", "shot");
    CHECK(render_frame(ctx, &s, pv, 4, &state, &out, 0) == NPRFX_ERR_UNSUPPORTED);
    CHECK(strstr(th_error(ctx), "range 'shot' measures every frame of the shot (1-5)") != NULL);
    nprfx_tone_state_free(state);
    /* bad params are refused with the param's name */
    pv[th_param(n, "low")].v[0] = 60;
    pv[th_param(n, "high")].v[0] = 40;
    CHECK(render_frame(ctx, &s, pv, 1, NULL, &out, 1) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "low (60) must be below high (40)") != NULL);
    nprfx_image_free(&out);
    nprfx_image_free(&again);
    free_shot(&s);
}

/* The measurement as text (what `nprfx analyze` stores): a state seeded from it maps every frame
 * as the measured one, bit for bit, without fetching; a frame whose fingerprint differs from the
 * text measures the shot again; bad text is refused naming the line. */
static void test_state_text(nprfx_context *ctx)
{
    const nprfx_node_desc *n = &nprfx_node_tone;
    CHECK(nprfx_node_measures_shot(n));
    shot s;
    make_shot(ctx, &s);
    nprfx_value pv[16];
    nprfx_node_defaults(n, pv);
    nprfx_image out, again;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &out);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &again);
    void *state = NULL;
    char *text = NULL;
    CHECK_OK(nprfx_node_state_save(ctx, n, state, &text));
    CHECK(text == NULL); /* nothing measured yet */
    CHECK_OK(render_frame(ctx, &s, pv, 1, &state, &out, 1));
    CHECK_OK(nprfx_node_state_save(ctx, n, state, &text));
    CHECK(text && strstr(text, "range shot\nframes 1 5\npercentiles 1 99\n") == text);
    CHECK(strstr(text, "\nbits ") && strstr(text, "\nfingerprints "));
    void *seeded = NULL;
    CHECK_OK(nprfx_node_state_load(ctx, n, &seeded, text));
    char *back = NULL;
    CHECK_OK(nprfx_node_state_save(ctx, n, seeded, &back));
    CHECK(back && !strcmp(back, text));
    free(back);
    for (int f = 1; f <= NF; f++) {
        s.calls = 0;
        CHECK_OK(render_frame(ctx, &s, pv, f, &seeded, &again, 1));
        CHECK(s.calls == 0); /* seeded: nothing fetched */
        CHECK_OK(render_frame(ctx, &s, pv, f, &state, &out, 1));
        CHECK(memcmp(out.data, again.data, sizeof(float) * W * H) == 0);
    }
    nprfx_tone_state_free(seeded);
    /* frame 4's fingerprint differs: rendering frame 4 measures again (fetches the shot) */
    char *tampered = strdup(text);
    char *fp = strstr(tampered, "fingerprints ") + 13 + 3 * 17;
    *fp = *fp == '0' ? '1' : '0';
    seeded = NULL;
    CHECK_OK(nprfx_node_state_load(ctx, n, &seeded, tampered));
    s.calls = 0;
    CHECK_OK(render_frame(ctx, &s, pv, 3, &seeded, &again, 1));
    CHECK(s.calls == 0);
    CHECK_OK(render_frame(ctx, &s, pv, 4, &seeded, &again, 1));
    CHECK(s.calls > 0);
    CHECK_OK(nprfx_node_state_save(ctx, n, seeded, &back));
    CHECK(back && !strcmp(back, text)); /* measured again: the true fingerprints */
    free(back);
    nprfx_tone_state_free(seeded);
    free(tampered);
    /* bad text */
    const char *bad[][2] = {
        {"frames 1 5\n", "line 'range': missing"},
        {"range all\n", "line 'range': neither 'shot' nor 'frame'"},
        {"range shot\nframes 5 1\npercentiles 1 99\nbits 0 0\nfingerprints 1 2 3 4 5\n",
         "line 'frames'"},
        {"range shot\nframes 1 5\npercentiles 1 99\nbits 0 0\nfingerprints 1 2 3\n",
         "fewer than one a frame"},
        {"range shot\nframes 1 2\npercentiles 1 99\nbits 0 0\nfingerprints 1 2 3\n",
         "more than one a frame"},
        {"range frame\nframes 3 3\npercentiles 1 99\nbits x 0\nfingerprints 1\n", "line 'bits'"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        seeded = NULL;
        CHECK(nprfx_node_state_load(ctx, n, &seeded, bad[k][0]) == NPRFX_ERR_PARSE);
        CHECK(strstr(th_error(ctx), bad[k][1]) != NULL);
        nprfx_tone_state_free(seeded);
    }
    free(text);
    nprfx_tone_state_free(state);
    nprfx_image_free(&out);
    nprfx_image_free(&again);
    free_shot(&s);
}

static void test_albedo(nprfx_context *ctx)
{
    /* tone / albedo: a checker texture under even light maps to one value */
    nprfx_image tone = th_image(4, 1, 3, NULL), alb = th_image(4, 1, 3, NULL), out;
    float a[2] = {0.2f, 0.8f};
    for (int x = 0; x < 4; x++)
        for (int c = 0; c < 3; c++) {
            nprfx_image_at(&alb, x, 0)[c] = a[x & 1];
            nprfx_image_at(&tone, x, 0)[c] = a[x & 1] * (x < 2 ? 0.5f : 1.0f);
        }
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 4, 1), 1, &out);
    nprfx_tone_params p = plain();
    nprfx_image ins[NPRFX_TONE_IN_COUNT] = {0};
    ins[NPRFX_TONE_IN_TONE] = tone;
    ins[NPRFX_TONE_IN_ALBEDO] = alb;
    nprfx_render_args ta = th_core_args(ctx, ins, &out, out.bounds, out.bounds);
    CHECK_OK(nprfx_tone_render(&ta, &p));
    CHECK_NEAR(px(&out, 0, 0), 0.5, 1e-6);
    CHECK_NEAR(px(&out, 1, 0), 0.5, 1e-6);
    CHECK_NEAR(px(&out, 2, 0), 1.0, 1e-6);
    CHECK_NEAR(px(&out, 3, 0), 1.0, 1e-6);
    nprfx_image_free(&tone);
    nprfx_image_free(&alb);
    nprfx_image_free(&out);
}

/* The pixels do not depend on the thread count. */
static void test_threads(void)
{
    nprfx_pool *pool = NULL;
    nprfx_context *mt = th_parallel_context(3, &pool), *st = NULL;
    nprfx_context_init cs = NPRFX_CONTEXT_INIT_DEFAULT;
    CHECK_OK(nprfx_context_create(&cs, &st));
    shot s;
    make_shot(st, &s);
    nprfx_value pv[16];
    nprfx_node_defaults(&nprfx_node_tone, pv);
    nprfx_image a, b;
    nprfx_image_alloc(st, nprfx_rect_make(0, 0, W, H), 1, &a);
    nprfx_image_alloc(st, nprfx_rect_make(0, 0, W, H), 1, &b);
    CHECK_OK(render_frame(st, &s, pv, 4, NULL, &a, 1));
    CHECK_OK(render_frame(mt, &s, pv, 4, NULL, &b, 1));
    CHECK(memcmp(a.data, b.data, sizeof(float) * W * H) == 0);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
    free_shot(&s);
    nprfx_context_destroy(mt);
    nprfx_context_destroy(st);
    nprfx_pool_destroy(pool);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context_create(&ci, &ctx);
    CHECK_OK(nprfx_node_lint(ctx, &nprfx_node_tone));
    test_map();
    test_percentile();
    test_shot_range(ctx);
    test_state_text(ctx);
    test_albedo(ctx);
    test_threads();
    nprfx_context_destroy(ctx);
    return check_finish();
}
