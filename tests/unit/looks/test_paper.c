/* The paper node (core/looks/paper.c): exact tileability, no dependence on time, window, tile split or
 * thread count, the height's range and mean, kinds and seeds that differ, the canvas weave's
 * period, the colour formula on a flat paper, the optional format input, the error paths and
 * the per-instance cache (the same pixels), through its descriptor. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/node.h"
#include "nprfx/paper.h"

extern const nprfx_node_desc nprfx_node_paper;
static const nprfx_node_desc *N = &nprfx_node_paper;

static nprfx_value pv[16];

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

static int out_channels(void)
{
    return (int)pv[th_param(N, "output")].v[0] == NPRFX_PAPER_HEIGHT ? 1 : 4;
}

/* Render `window` of out at `time`; `format` is the optional image input (NULL: none); state:
 * the node's state slot (NULL: none, so no cache). */
static nprfx_result render_with(nprfx_context *ctx, nprfx_image *out, nprfx_rect window,
                                double time, const nprfx_image *format, void **state)
{
    nprfx_image in[1];
    memset(in, 0, sizeof in);
    if (format) in[0] = *format;
    nprfx_render_args a = th_args(ctx, N, in, pv, out, window);
    a.time = time;
    a.last_frame = 100;
    a.state = state;
    return nprfx_node_render(&a);
}

static nprfx_result render_at(nprfx_context *ctx, nprfx_image *out, nprfx_rect window, double time,
                              const nprfx_image *format)
{
    return render_with(ctx, out, window, time, format, NULL);
}

static nprfx_image make(nprfx_rect r)
{
    nprfx_image im;
    if (nprfx_image_alloc(NULL, r, out_channels(), &im) != NPRFX_OK) exit(2);
    return im;
}

static int same(const nprfx_image *a, const nprfx_image *b)
{
    size_t n = (size_t)nprfx_rect_width(a->bounds) * (size_t)nprfx_rect_height(a->bounds) *
               (size_t)a->channels;
    return a->channels == b->channels && nprfx_rect_equal(a->bounds, b->bounds) &&
           memcmp(a->data, b->data, n * sizeof(float)) == 0;
}

static const char *const kinds[] = {"paper", "watercolor", "canvas"};

/* The per-instance cache (nprfx_paper_render_cached through the node's state slot): the same
 * pixels as without it, when it serves a later frame, a window inside the kept one, params
 * changed, a window reaching outside it, and the other output. */
static nprfx_result render_state(nprfx_context *ctx, nprfx_image *out, nprfx_rect window,
                                 double time, void **state)
{
    return render_with(ctx, out, window, time, NULL, state);
}

static void test_cache(nprfx_context *ctx)
{
    reset();
    set("kind", 1);
    nprfx_rect f = nprfx_rect_make(0, 0, 96, 64), part = nprfx_rect_make(10, 20, 50, 40);
    void *state = NULL;
    nprfx_image ref = make(f), got = make(f);
    CHECK_OK(render_at(ctx, &ref, f, 1, NULL));
    for (int t = 1; t <= 3; t++) { /* the first a miss, then hits */
        memset(got.data, 0, sizeof(float) * 96 * 64 * 4);
        CHECK_OK(render_state(ctx, &got, f, t, &state));
        CHECK(same(&ref, &got));
    }
    memset(got.data, 0, sizeof(float) * 96 * 64 * 4);
    CHECK_OK(render_state(ctx, &got, part, 4, &state)); /* inside the kept window */
    int bad = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 96; x++)
            for (int c = 0; c < 4; c++) {
                float want = nprfx_rect_contains(part, x, y) ? nprfx_image_at(&ref, x, y)[c] : 0;
                bad += nprfx_image_at(&got, x, y)[c] != want;
            }
    CHECK(bad == 0);
    set("seed", 7); /* other params: made anew */
    CHECK_OK(render_at(ctx, &ref, f, 1, NULL));
    CHECK_OK(render_state(ctx, &got, f, 5, &state));
    CHECK(same(&ref, &got));
    nprfx_rect wide = nprfx_rect_make(0, 0, 128, 64); /* reaches outside the kept window */
    nprfx_image ref2 = make(wide), got2 = make(wide);
    CHECK_OK(render_at(ctx, &ref2, wide, 1, NULL));
    CHECK_OK(render_state(ctx, &got2, wide, 6, &state));
    CHECK(same(&ref2, &got2));
    set("output", NPRFX_PAPER_HEIGHT); /* another channel count */
    nprfx_image h1 = make(f), h2 = make(f);
    CHECK_OK(render_at(ctx, &h1, f, 1, NULL));
    CHECK_OK(render_state(ctx, &h2, f, 7, &state));
    CHECK(same(&h1, &h2));
    N->state_free(state);
    nprfx_image_free(&ref);
    nprfx_image_free(&got);
    nprfx_image_free(&ref2);
    nprfx_image_free(&got2);
    nprfx_image_free(&h1);
    nprfx_image_free(&h2);
}

static void test_lint(nprfx_context *ctx)
{
    CHECK_OK(nprfx_node_lint(ctx, N));
    CHECK(strcmp(N->id, "paper") == 0 && strcmp(N->group, "NPR") == 0);
    CHECK(N->inputs[0].flags & NPRFX_INPUT_OPTIONAL);
}

/* out(x + T, y) = out(x, y + T) = out(x, y), bit for bit, also across negative coordinates. */
static void test_tileable(nprfx_context *ctx)
{
    const int T = 48;
    nprfx_rect r = nprfx_rect_make(-50, -20, 60, 90);
    for (int k = 0; k < 3; k++)
        for (int o = 0; o < 2; o++) {
            reset();
            th_set_choice(N, pv, "kind", kinds[k]);
            set("output", o);
            set("tile", T);
            set("scale", 2.3); /* cells that do not divide the tile: they are fitted */
            set("thread", 5.3);
            nprfx_image im = make(r);
            CHECK_OK(render_at(ctx, &im, r, 1, NULL));
            int C = im.channels, ok = 1, varies = 0;
            for (int y = r.y0; y < r.y1; y++)
                for (int x = r.x0; x < r.x1; x++) {
                    const float *a = nprfx_image_at(&im, x, y);
                    if (x + T < r.x1) ok &= !memcmp(a, nprfx_image_at(&im, x + T, y), C * 4);
                    if (y + T < r.y1) ok &= !memcmp(a, nprfx_image_at(&im, x, y + T), C * 4);
                    varies |= a[0] != nprfx_image_at(&im, r.x0, r.y0)[0];
                }
            CHECK(ok);
            CHECK(varies);
            nprfx_image_free(&im);
        }
    /* tile 0: not periodic */
    reset();
    set("output", NPRFX_PAPER_HEIGHT);
    set("tile", 0);
    nprfx_image im = make(nprfx_rect_make(0, 0, 2 * T + 4, 8));
    CHECK_OK(render_at(ctx, &im, im.bounds, 1, NULL));
    int differs = 0;
    for (int x = 0; x + T < 2 * T + 4; x++)
        differs += nprfx_image_at(&im, x, 3)[0] != nprfx_image_at(&im, x + T, 3)[0];
    CHECK(differs > T / 2);
    nprfx_image_free(&im);
}

/* The same pixels at any time, for any window split and thread count, with or without the
 * format input. */
static void test_invariance(nprfx_context *serial)
{
    nprfx_pool *pool = NULL;
    nprfx_context *par = th_parallel_context(3, &pool);
    nprfx_rect r = nprfx_rect_make(0, 0, 83, 61);
    for (int k = 0; k < 3; k++)
        for (int o = 0; o < 2; o++) {
            reset();
            th_set_choice(N, pv, "kind", kinds[k]);
            set("output", o);
            nprfx_image whole = make(r), tiled = make(r), later = make(r), fmt_out = make(r);
            CHECK_OK(render_at(serial, &whole, r, 1, NULL));
            for (int ty = 0; ty < 61; ty += 16)
                for (int tx = 0; tx < 83; tx += 16) /* 16-px tiles, on 3 threads */
                    CHECK_OK(
                        render_at(par, &tiled, nprfx_rect_make(tx, ty, tx + 16, ty + 16), 1, NULL));
            CHECK(same(&whole, &tiled));
            CHECK_OK(render_at(par, &later, r, 57.5, NULL));
            CHECK(same(&whole, &later));
            /* the format input sets the frame only: its pixels are not read */
            nprfx_image fmt = th_image(83, 61, 3, NULL);
            float grey[3] = {0.3f, 0.7f, 0.1f};
            nprfx_image_fill(&fmt, grey);
            CHECK_OK(render_at(serial, &fmt_out, r, 1, &fmt));
            CHECK(same(&whole, &fmt_out));
            nprfx_image_free(&fmt);
            nprfx_image_free(&whole);
            nprfx_image_free(&tiled);
            nprfx_image_free(&later);
            nprfx_image_free(&fmt_out);
        }
    nprfx_context_destroy(par);
    nprfx_pool_destroy(pool);
}

/* Height of a whole tile (so that means are over a period). */
static nprfx_image height_tile(nprfx_context *ctx, const char *kind, int T, int seed)
{
    set("output", NPRFX_PAPER_HEIGHT);
    th_set_choice(N, pv, "kind", kind);
    set("tile", T);
    set("seed", seed);
    nprfx_image im = make(nprfx_rect_make(0, 0, T, T));
    CHECK_OK(render_at(ctx, &im, im.bounds, 1, NULL));
    return im;
}

static double mean_abs_diff(const nprfx_image *a, const nprfx_image *b)
{
    double s = 0;
    int n = 0;
    for (int y = a->bounds.y0; y < a->bounds.y1; y++)
        for (int x = a->bounds.x0; x < a->bounds.x1; x++, n++)
            s += fabs((double)nprfx_image_at(a, x, y)[0] - nprfx_image_at(b, x, y)[0]);
    return s / n;
}

static void test_height_kinds_seeds(nprfx_context *ctx)
{
    const int T = 192;
    nprfx_image h[3];
    for (int k = 0; k < 3; k++) {
        reset();
        h[k] = height_tile(ctx, kinds[k], T, 5);
        double s = 0, s2 = 0, lo = 1, hi = 0;
        for (int y = 0; y < T; y++)
            for (int x = 0; x < T; x++) {
                double v = nprfx_image_at(&h[k], x, y)[0];
                s += v;
                s2 += v * v;
                lo = fmin(lo, v);
                hi = fmax(hi, v);
            }
        double mean = s / (T * T), sd = sqrt(s2 / (T * T) - mean * mean);
        printf("paper %s: height mean %.4f sd %.4f range [%.3f, %.3f]\n", kinds[k], mean, sd, lo,
               hi);
        CHECK(lo >= 0.0 && hi <= 1.0);
        CHECK_NEAR(mean, 0.5, 0.03);
        CHECK(sd > 0.02 && sd < 0.2); /* a texture, not a flat sheet nor noise at full swing */
        /* another seed: another sheet of the same kind */
        reset();
        nprfx_image other = height_tile(ctx, kinds[k], T, 6);
        CHECK(mean_abs_diff(&h[k], &other) > 0.5 * sd);
        nprfx_image_free(&other);
    }
    for (int a = 0; a < 3; a++)
        for (int b = a + 1; b < 3; b++)
            CHECK(mean_abs_diff(&h[a], &h[b]) > 0.02);
    for (int k = 0; k < 3; k++)
        nprfx_image_free(&h[k]);

    /* each ingredient moves the height: fibres on paper, weave on canvas */
    reset();
    nprfx_image with = height_tile(ctx, "paper", T, 1);
    set("fibres", 0);
    nprfx_image without = height_tile(ctx, "paper", T, 1);
    CHECK(mean_abs_diff(&with, &without) > 0.001);
    nprfx_image_free(&with);
    nprfx_image_free(&without);
}

/* The weave repeats every two threads (over, under): mean |h(x) - h(x + 2p)| is far below the
 * difference half a thread away, and below the one a thread away (the over/under
 * alternation). */
static void test_weave_period(nprfx_context *ctx)
{
    const int T = 256, p = 8;
    reset();
    set("grain", 0);
    set("thread", p);
    nprfx_image h = height_tile(ctx, "canvas", T, 3);
    double d[3] = {0, 0, 0};
    const int shift[3] = {2 * p, p, p / 2};
    for (int k = 0; k < 3; k++) {
        int n = 0;
        for (int y = 0; y < T; y++)
            for (int x = 0; x + shift[k] < T; x++, n++)
                d[k] += fabs((double)nprfx_image_at(&h, x, y)[0] -
                             nprfx_image_at(&h, x + shift[k], y)[0]) +
                        fabs((double)nprfx_image_at(&h, y, x)[0] -
                             nprfx_image_at(&h, y, x + shift[k])[0]);
        d[k] /= 2.0 * n;
    }
    printf("canvas: mean |dh| at 2p %.4f, p %.4f, p/2 %.4f\n", d[0], d[1], d[2]);
    CHECK(d[0] < 0.35 * d[2]);
    CHECK(d[0] < 0.75 * d[1]);
    nprfx_image_free(&h);
}

/* A flat paper (no grain, fibres or relief) is the colour times 1 - shade/2, alpha the colour's. */
static void test_color(nprfx_context *ctx)
{
    reset();
    set("grain", 0);
    set("fibres", 0);
    set("shade", 0.5);
    int ci = th_param(N, "color");
    pv[ci].v[0] = 0.8;
    pv[ci].v[1] = 0.6;
    pv[ci].v[2] = 0.4;
    pv[ci].v[3] = 0.9;
    nprfx_image im = make(nprfx_rect_make(0, 0, 9, 7));
    CHECK(im.channels == 4);
    for (int relief = 0; relief < 2; relief++) {
        set("relief", relief ? 6 : 0);
        CHECK_OK(render_at(ctx, &im, im.bounds, 1, NULL));
        int ok = 1;
        for (int y = 0; y < 7; y++)
            for (int x = 0; x < 9; x++) {
                const float *o = nprfx_image_at(&im, x, y);
                ok &= o[0] == (float)(0.8 * 0.75) && o[1] == (float)(0.6 * 0.75) &&
                      o[2] == (float)(0.4 * 0.75) && o[3] == 0.9f;
            }
        CHECK(ok);
    }
    nprfx_image_free(&im);
    /* with grain, the colour is color * (1 - shade (1 - h)) where relief is 0 */
    reset();
    set("relief", 0);
    set("tile", 64);
    nprfx_image col = make(nprfx_rect_make(0, 0, 20, 20));
    CHECK_OK(render_at(ctx, &col, col.bounds, 1, NULL));
    set("output", NPRFX_PAPER_HEIGHT);
    nprfx_image h = make(col.bounds);
    CHECK_OK(render_at(ctx, &h, h.bounds, 1, NULL));
    double err = 0;
    for (int y = 0; y < 20; y++)
        for (int x = 0; x < 20; x++)
            err = fmax(err, fabs(nprfx_image_at(&col, x, y)[1] -
                                 0.94 * (1.0 - 0.4 * (1.0 - nprfx_image_at(&h, x, y)[0]))));
    CHECK(err < 1e-6);
    nprfx_image_free(&col);
    nprfx_image_free(&h);
}

static void test_errors(nprfx_context *ctx)
{
    reset();
    nprfx_image im = make(nprfx_rect_make(0, 0, 4, 4));
    set("scale", 0);
    CHECK(render_at(ctx, &im, im.bounds, 1, NULL) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "paper.scale") != NULL);
    reset();
    set("shade", 1.5);
    CHECK(render_at(ctx, &im, im.bounds, 1, NULL) == NPRFX_ERR_OUT_OF_RANGE);
    reset();
    set("tile", -1);
    CHECK(render_at(ctx, &im, im.bounds, 1, NULL) == NPRFX_ERR_OUT_OF_RANGE);
    /* the height output has one channel: a 4-channel image is refused */
    reset();
    set("output", NPRFX_PAPER_HEIGHT);
    CHECK(render_at(ctx, &im, im.bounds, 1, NULL) != NPRFX_OK);
    nprfx_image_free(&im);
    /* the core function checks its params itself */
    nprfx_paper_params p = {.kind = 7, .scale = 1, .thread = 4, .color = {1, 1, 1, 1}};
    nprfx_image out = th_image(4, 4, 4, NULL);
    nprfx_render_args a = th_core_args(ctx, NULL, &out, out.bounds, out.bounds);
    CHECK(nprfx_paper_render(&a, &p) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "paper.kind") != NULL);
    p.kind = NPRFX_PAPER_CANVAS;
    p.thread = 0.5;
    CHECK(nprfx_paper_render(&a, &p) == NPRFX_ERR_OUT_OF_RANGE);
    p.thread = 4;
    CHECK_OK(nprfx_paper_render(&a, &p));
    CHECK(nprfx_paper_render(&a, NULL) == NPRFX_ERR_INVALID_ARGUMENT);
    nprfx_image_free(&out);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    test_lint(ctx);
    test_tileable(ctx);
    test_invariance(ctx);
    test_height_kinds_seeds(ctx);
    test_weave_period(ctx);
    test_color(ctx);
    test_errors(ctx);
    test_cache(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
