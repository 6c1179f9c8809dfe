/* coherent-noise: the recursion's formulas by hand, stationarity over long sub-pixel shots
 * (translation, rotation, zoom; causal and symmetric), coherence along the true motion,
 * disocclusion on the synthetic orbit scene, and bit-identical results across threads, tiles and
 * render orders. The node is driven through its descriptor with a fetch callback over frames
 * computed in memory. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/coherent_noise.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/metrics.h"
#include "nprfx/node.h"
#include "nprfx/rng.h"
#include "nprfx/synth.h"

extern const nprfx_node_desc nprfx_node_coherent_noise;
static const nprfx_node_desc *node = &nprfx_node_coherent_noise;

enum { IN_DEPTH, IN_MPREV, IN_MNEXT, IN_ZVEL, IN_SOURCE, IN_CONFIDENCE, IN_COUNT };
enum { SC_TRANSLATE, SC_ROTATE, SC_ZOOM, SC_TINY, SC_SYNTH };

/* ---- in-memory scenes -------------------------------------------------------------------- */

#define ARENA_MAX 2048
#define SYNTH_MAX 160

typedef struct scene {
    int kind, W, H;
    double vx, vy;      /* translate: px/frame */
    double theta, zs;   /* rotate: rad/frame; zoom: scale/frame */
    unsigned connected; /* bit per input */
    long long fetches;  /* calls to scene_fetch */
    /* when declared_on: the frames declared per input, and the fetches outside them */
    int declared_on;
    nprfx_frame_range declared[IN_COUNT];
    long long outside;
    nprfx_context *ctx;
    nprfx_image arena[ARENA_MAX];
    int narena;
    /* tiny: explicit per-frame depth (constant motion) */
    const float *tiny_depth[8];
    float tiny_mx;
    /* synth */
    const char *synth;
    nprfx_image plates[SYNTH_MAX];
    int ch_z, ch_mp, ch_mn, ch_id, ch_r;
} scene;

/* Where the surface point at pixel (x, y) is dt frames away (dt = -1 previous, +1 next). */
static void scene_map(const scene *s, double x, double y, int dt, double *ox, double *oy)
{
    double cx = (s->W - 1) * 0.5, cy = (s->H - 1) * 0.5;
    switch (s->kind) {
    case SC_TRANSLATE:
        *ox = x + dt * s->vx;
        *oy = y + dt * s->vy;
        return;
    case SC_ROTATE: {
        double a = dt * s->theta, dx = x - cx, dy = y - cy;
        *ox = cx + cos(a) * dx - sin(a) * dy;
        *oy = cy + sin(a) * dx + cos(a) * dy;
        return;
    }
    case SC_ZOOM: {
        double k = pow(s->zs, dt);
        *ox = cx + (x - cx) * k;
        *oy = cy + (y - cy) * k;
        return;
    }
    default:
        *ox = x + dt * s->tiny_mx;
        *oy = y;
    }
}

static nprfx_image *arena_new(scene *s, int channels)
{
    if (s->narena >= ARENA_MAX) return NULL;
    nprfx_image *im = &s->arena[s->narena++];
    if (nprfx_image_alloc(s->ctx, nprfx_rect_make(0, 0, s->W, s->H), channels, im)) return NULL;
    return im;
}

static void arena_clear(scene *s)
{
    for (int i = 0; i < s->narena; i++)
        nprfx_image_free(&s->arena[i]);
    s->narena = 0;
}

static const nprfx_image *synth_plate(scene *s, int frame)
{
    int k = frame + 20;
    if (k < 0 || k >= SYNTH_MAX) return NULL;
    if (!s->plates[k].data) {
        nprfx_image_alloc(s->ctx, nprfx_rect_make(0, 0, s->W, s->H), nprfx_synth_channel_count(),
                          &s->plates[k]);
        if (nprfx_synth_render(s->ctx, s->synth, frame, &s->plates[k])) return NULL;
    }
    return &s->plates[k];
}

static nprfx_result scene_fetch(void *user, int input, double time, nprfx_image *out)
{
    scene *s = user;
    int f = (int)floor(time + 0.5);
    s->fetches++;
    if (!(s->connected & (1u << input))) return NPRFX_ERR_MISSING_INPUT;
    if (s->declared_on && (f < s->declared[input].first || f > s->declared[input].last))
        s->outside++;
    if (s->kind == SC_SYNTH) {
        const nprfx_image *pl = synth_plate(s, f);
        if (!pl) return NPRFX_ERR_IO;
        switch (input) {
        case IN_DEPTH:
            *out = nprfx_image_channels(pl, s->ch_z, 1);
            return NPRFX_OK;
        case IN_MPREV:
            *out = nprfx_image_channels(pl, s->ch_mp, 2);
            return NPRFX_OK;
        case IN_MNEXT:
            *out = nprfx_image_channels(pl, s->ch_mn, 2);
            return NPRFX_OK;
        case IN_SOURCE: {
            /* a flickering source: beauty plus per-frame noise */
            nprfx_image *im = arena_new(s, 3);
            if (!im) return NPRFX_ERR_OUT_OF_MEMORY;
            for (int y = 0; y < s->H; y++)
                for (int x = 0; x < s->W; x++)
                    for (int c = 0; c < 3; c++)
                        nprfx_image_at(im, x, y)[c] =
                            nprfx_image_at(pl, x, y)[s->ch_r + c] +
                            0.1f * (float)nprfx_rand_gauss(99, f, x, y, (uint32_t)c, 0);
            *out = *im;
            return NPRFX_OK;
        }
        default:
            return NPRFX_ERR_MISSING_INPUT;
        }
    }
    nprfx_image *im =
        arena_new(s, input == IN_DEPTH || input == IN_ZVEL ? 1 : (input == IN_SOURCE ? 2 : 2));
    if (!im) return NPRFX_ERR_OUT_OF_MEMORY;
    for (int y = 0; y < s->H; y++)
        for (int x = 0; x < s->W; x++) {
            float *p = nprfx_image_at(im, x, y);
            if (input == IN_DEPTH) {
                p[0] = s->kind == SC_TINY ? s->tiny_depth[f][y * s->W + x] : 1.0f;
            } else if (input == IN_ZVEL) {
                p[0] = 0.0f;
            } else if (input == IN_SOURCE) {
                p[0] = (float)(x + 10 * f);
                p[1] = (float)y;
            } else {
                double ox, oy;
                scene_map(s, x, y, input == IN_MPREV ? -1 : 1, &ox, &oy);
                p[0] = (float)(ox - x);
                p[1] = (float)(oy - y);
            }
        }
    *out = *im;
    return NPRFX_OK;
}

static void scene_free(scene *s)
{
    arena_clear(s);
    for (int i = 0; i < SYNTH_MAX; i++)
        nprfx_image_free(&s->plates[i]);
}

static void scene_synth(scene *s, nprfx_context *ctx, const char *name, int W, int H)
{
    memset(s, 0, sizeof *s);
    s->kind = SC_SYNTH;
    s->ctx = ctx;
    s->W = W;
    s->H = H;
    s->synth = name;
    s->connected = (1u << IN_DEPTH) | (1u << IN_MPREV) | (1u << IN_MNEXT) | (1u << IN_SOURCE);
    s->ch_z = th_synth_channel("Z");
    s->ch_mp = th_synth_channel("motion_prev.X");
    s->ch_mn = th_synth_channel("motion_next.X");
    s->ch_id = th_synth_channel("id");
    s->ch_r = th_synth_channel("R");
}

/* ---- driving the node -------------------------------------------------------------------- */

static void set_param(nprfx_value *pv, const char *name, double v)
{
    int i = nprfx_node_param_index(node, name);
    if (i < 0) {
        fprintf(stderr, "no param %s\n", name);
        exit(2);
    }
    pv[i].v[0] = v;
}

static nprfx_result render(scene *s, nprfx_context *ctx, const nprfx_value *pv, int frame,
                           int first, int last, void **state, nprfx_image *out, nprfx_rect win)
{
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    nprfx_image ins[IN_COUNT];
    memset(ins, 0, sizeof ins);
    s->ctx = ctx;
    for (int i = 0; i < IN_COUNT; i++)
        if (s->connected & (1u << i)) scene_fetch(s, i, frame, &ins[i]);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = node;
    a.time = frame;
    a.render_scale = 1.0;
    a.frame = nprfx_rect_make(0, 0, s->W, s->H);
    a.window = win;
    a.first_frame = first;
    a.last_frame = last;
    a.inputs = ins;
    a.params = pv;
    a.output = out;
    a.fetch = scene_fetch;
    a.fetch_user = s;
    a.state = state;
    nprfx_result r = nprfx_node_render(&a);
    arena_clear(s);
    return r;
}

static nprfx_result render_full(scene *s, nprfx_context *ctx, const nprfx_value *pv, int frame,
                                int first, int last, void **state, nprfx_image *out)
{
    return render(s, ctx, pv, frame, first, last, state, out, nprfx_rect_make(0, 0, s->W, s->H));
}

static void state_release(void **state)
{
    if (*state) node->state_free(*state);
    *state = NULL;
}

static void defaults(nprfx_value *pv)
{
    nprfx_node_defaults(node, pv);
    for (int i = 0; i < node->num_params; i++)
        if (!pv[i].s) pv[i].s = "";
}

/* ---- metrics ----------------------------------------------------------------------------- */

static double std_of(nprfx_context *ctx, const nprfx_image *im, int ch)
{
    nprfx_stats st;
    nprfx_image_stats(ctx, im, ch, NULL, &st);
    return sqrt(st.variance);
}

/* Power in the upper half of the radial frequencies (0.25..0.5 cycles/pixel). */
static double high_band(nprfx_context *ctx, const nprfx_image *im, int ch)
{
    int nb = 0;
    nprfx_radial_spectrum(ctx, im, ch, NULL, &nb);
    double *sp = calloc((size_t)nb, sizeof(double)), e = 0.0;
    nprfx_radial_spectrum(ctx, im, ch, sp, &nb);
    for (int k = nb / 2; k < nb; k++)
        e += sp[k];
    free(sp);
    return e;
}

/* ---- tests ------------------------------------------------------------------------------- */

static void test_k_and_first_frame(nprfx_context *ctx)
{
    CHECK_NEAR(nprfx_cn_k(0.0), 1.0, 1e-15);
    CHECK_NEAR(nprfx_cn_k(0.5), sqrt(0.5 / 1.5), 1e-15);
    CHECK_NEAR(nprfx_cn_k(0.98), sqrt(0.02 / 1.98), 1e-15);
    CHECK_NEAR(nprfx_cn_k(1.0), 0.0, 1e-15);
    /* stationarity condition (Eq. 4): k^2 = alpha^2 k^2 + (1-alpha)^2 */
    double a = 0.7, k = nprfx_cn_k(a);
    CHECK_NEAR(k * k, a * a * k * k + (1 - a) * (1 - a), 1e-15);

    /* The start frame is k w in the paper's units, i.e. w in the node's unit output. */
    scene s;
    memset(&s, 0, sizeof s);
    s.kind = SC_TRANSLATE;
    s.W = 16;
    s.H = 12;
    s.vx = 0.3;
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV);
    nprfx_value pv[32];
    defaults(pv);
    set_param(pv, "channels", 2);
    set_param(pv, "seed", 7);
    set_param(pv, "start", 3);
    void *state = NULL;
    nprfx_image out, w;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 16, 12), 2, &out);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 16, 12), 2, &w);
    CHECK_OK(render_full(&s, ctx, pv, 3, 1, 10, &state, &out));
    nprfx_cn_params p;
    nprfx_cn_params_default(&p);
    p.channels = 2;
    p.seed = 7;
    CHECK_OK(nprfx_cn_noise_fill(ctx, &p, 3, 0, &w));
    CHECK(memcmp(out.data, w.data, sizeof(float) * 16 * 12 * 2) == 0);
    /* the two channels are independent fields */
    CHECK(nprfx_image_at(&out, 5, 5)[0] != nprfx_image_at(&out, 5, 5)[1]);
    state_release(&state);
    nprfx_image_free(&out);
    nprfx_image_free(&w);
}

/* One step by hand on an 8x4 image moving 1 px/frame to the right (motion_prev = -1): where the
 * surface was visible, c1 = alpha c0(x-1) + (1-alpha) w1; the entering column and a pixel whose
 * previous position was covered by something closer get k w1. Checked in the paper's units. */
static void test_one_step_by_hand(nprfx_context *ctx)
{
    enum { W = 8, H = 4 };
    static float d0[W * H], d1[W * H];
    for (int i = 0; i < W * H; i++)
        d0[i] = d1[i] = 10.0f;
    d0[2 * W + 4] = 2.0f;     /* at frame 0, something close covers (4, 2) */
    d1[1 * W + 6] = INFINITY; /* at frame 1, (6, 1) is background */
    d1[3 * W + 3] = NAN;      /* and (3, 3) has no depth at all */
    scene s;
    memset(&s, 0, sizeof s);
    s.kind = SC_TINY;
    s.W = W;
    s.H = H;
    s.tiny_mx = 1.0f; /* motion_prev = -1 */
    s.tiny_depth[0] = d0;
    s.tiny_depth[1] = d1;
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV);
    const double alpha = 0.8, k = nprfx_cn_k(alpha);
    nprfx_value pv[32];
    defaults(pv);
    set_param(pv, "alpha", alpha);
    set_param(pv, "start", 0);
    set_param(pv, "seed", 11);
    void *state = NULL;
    nprfx_image o1;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &o1);
    CHECK_OK(render_full(&s, ctx, pv, 1, 0, 1, &state, &o1));
    nprfx_cn_params p;
    nprfx_cn_params_default(&p);
    p.seed = 11;
    nprfx_image w0, w1;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &w0);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &w1);
    nprfx_cn_noise_fill(ctx, &p, 0, 0, &w0);
    nprfx_cn_noise_fill(ctx, &p, 1, 0, &w1);
    int bad = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double wv1 = nprfx_image_at(&w1, x, y)[0];
            double c1 = k * nprfx_image_at(&o1, x, y)[0];
            int fresh = x == 0 || (x == 5 && y == 2) || (x == 6 && y == 1) || (x == 3 && y == 3);
            double want = fresh
                              ? k * wv1
                              : alpha * (k * nprfx_image_at(&w0, x - 1, y)[0]) + (1 - alpha) * wv1;
            if (fabs(c1 - want) > 1e-5) {
                bad++;
                fprintf(stderr, "one step: (%d,%d) got %g want %g\n", x, y, c1, want);
            }
        }
    CHECK(bad == 0);
    state_release(&state);
    nprfx_image_free(&o1);
    nprfx_image_free(&w0);
    nprfx_image_free(&w1);
}

/* Symmetric mode on a static 6x4 image over frames 0..3: by hand, with the same w, the forward
 * and backward unit recursions and Eq. 11 in unit form. */
static void test_symmetric_by_hand(nprfx_context *ctx)
{
    enum { W = 6, H = 4, N = 4 };
    scene s;
    memset(&s, 0, sizeof s);
    s.kind = SC_TRANSLATE;
    s.W = W;
    s.H = H; /* vx = vy = 0: static */
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV) | (1u << IN_MNEXT);
    const double a = 0.6, g = sqrt(1 - a * a);
    nprfx_value pv[32];
    defaults(pv);
    set_param(pv, "alpha", a);
    set_param(pv, "mode", 1);
    set_param(pv, "start", 0);
    nprfx_cn_params p;
    nprfx_cn_params_default(&p);
    nprfx_image w[N], o;
    for (int i = 0; i < N; i++) {
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &w[i]);
        nprfx_cn_noise_fill(ctx, &p, i, 0, &w[i]);
    }
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &o);
    void *state = NULL;
    int bad = 0;
    for (int i = 0; i < N; i++) {
        CHECK_OK(render_full(&s, ctx, pv, i, 0, N - 1, &state, &o));
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double f = nprfx_image_at(&w[0], x, y)[0], b = nprfx_image_at(&w[N - 1], x, y)[0];
                for (int j = 1; j <= i; j++)
                    f = a * f + g * nprfx_image_at(&w[j], x, y)[0];
                for (int j = N - 2; j >= i; j--)
                    b = a * b + g * nprfx_image_at(&w[j], x, y)[0];
                double wi = nprfx_image_at(&w[i], x, y)[0];
                /* at the ends one pass has just started (fresh) and the other has not */
                double want = (f + b - g * wi) / sqrt(1 + a * a);
                if (fabs(nprfx_image_at(&o, x, y)[0] - want) > 1e-5) bad++;
            }
    }
    CHECK(bad == 0);
    /* the variance of Eq. 11 is 2k^2 - (1-alpha)^2 = k^2 (1 + alpha^2) in the paper's units */
    double k = nprfx_cn_k(a);
    CHECK_NEAR(2 * k * k - (1 - a) * (1 - a), k * k * (1 + a * a), 1e-15);
    state_release(&state);
    for (int i = 0; i < N; i++)
        nprfx_image_free(&w[i]);
    nprfx_image_free(&o);
}

/* Stationarity over 100 frames of sub-pixel motion, through the node. */
static void stationarity_case(nprfx_context *ctx, const char *label, scene *s, int symmetric,
                              double alpha)
{
    enum { F0 = 1, F1 = 101 };
    nprfx_value pv[32];
    defaults(pv);
    set_param(pv, "alpha", alpha);
    set_param(pv, "mode", symmetric);
    void *state = NULL;
    nprfx_image a, b;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, s->W, s->H), 1, &a);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, s->W, s->H), 1, &b);
    nprfx_result r0 = render_full(s, ctx, pv, F0, F0, F1, &state, &a);
    if (r0) fprintf(stderr, "render: %s\n", th_error(ctx));
    CHECK_OK(r0);
    if (symmetric) {
        CHECK_OK(render_full(s, ctx, pv, F1, F0, F1, &state, &b));
    } else {
        for (int f = F0 + 1; f <= F1; f++)
            render_full(s, ctx, pv, f, F0, F1, &state, &b);
    }
    double sr = std_of(ctx, &b, 0) / std_of(ctx, &a, 0);
    double hr = high_band(ctx, &b, 0) / high_band(ctx, &a, 0);
    printf("stationarity %-9s %-9s alpha %.2f: std ratio %.3f, high-band ratio %.3f\n", label,
           symmetric ? "symmetric" : "causal", alpha, sr, hr);
    CHECK(fabs(sr - 1.0) <= 0.05);
    CHECK(hr >= 0.8 && hr <= 1.25);
    state_release(&state);
    nprfx_image_free(&a);
    nprfx_image_free(&b);
}

static void test_stationarity(nprfx_context *ctx)
{
    scene s;
    memset(&s, 0, sizeof s);
    s.W = 128;
    s.H = 128;
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV) | (1u << IN_MNEXT);
    s.kind = SC_TRANSLATE;
    s.vx = 0.37;
    s.vy = 0.23;
    stationarity_case(ctx, "translate", &s, 0, 0.9);
    stationarity_case(ctx, "translate", &s, 0, 0.98);
    stationarity_case(ctx, "translate", &s, 1, 0.9);
    s.kind = SC_ROTATE;
    s.theta = 0.5 * 3.14159265358979 / 180.0;
    stationarity_case(ctx, "rotate", &s, 0, 0.9);
    stationarity_case(ctx, "rotate", &s, 1, 0.9);
    s.kind = SC_ZOOM;
    s.zs = 1.005;
    stationarity_case(ctx, "zoom", &s, 0, 0.9);
    s.zs = 1.0 / 1.005;
    stationarity_case(ctx, "zoom-out", &s, 0, 0.9);
}

/* The paper's bilinear lookup, through the core API: the measurement that motivates the
 * stationary resampler. It must fade (if it did not, the comparison would be meaningless). */
static void test_bilinear_fades(nprfx_context *ctx)
{
    scene s;
    memset(&s, 0, sizeof s);
    s.kind = SC_TRANSLATE;
    s.W = s.H = 128;
    s.vx = 0.37;
    s.vy = 0.23;
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV);
    s.ctx = ctx;
    for (int method = 0; method < 2; method++) {
        nprfx_cn_params p;
        nprfx_cn_params_default(&p);
        p.alpha = 0.9;
        p.resample = method ? NPRFX_CN_RESAMPLE_BILINEAR : NPRFX_CN_RESAMPLE_STATIONARY;
        nprfx_rect fr = nprfx_rect_make(0, 0, 128, 128);
        nprfx_cn_state st[2], first;
        nprfx_cn_state_alloc(ctx, fr, 1, &st[0]);
        nprfx_cn_state_alloc(ctx, fr, 1, &st[1]);
        nprfx_cn_state_alloc(ctx, fr, 1, &first);
        CHECK_OK(nprfx_cn_begin(ctx, &p, 1, NULL, &st[0]));
        nprfx_cn_state_copy(ctx, &st[0], &first);
        int cur = 0;
        for (int f = 2; f <= 101; f++) {
            nprfx_image d, m, dp;
            scene_fetch(&s, IN_DEPTH, f, &d);
            scene_fetch(&s, IN_MPREV, f, &m);
            scene_fetch(&s, IN_DEPTH, f - 1, &dp);
            nprfx_cn_inputs in = {&d, &m, NULL, &dp, NULL};
            CHECK_OK(nprfx_cn_step(ctx, &p, NPRFX_CN_FORWARD, f, &in, &st[cur], &st[1 - cur]));
            cur = 1 - cur;
            arena_clear(&s);
        }
        double sr = std_of(ctx, &st[cur].value, 0) / std_of(ctx, &first.value, 0);
        double hr = high_band(ctx, &st[cur].value, 0) / high_band(ctx, &first.value, 0);
        printf("resampler %-10s translate alpha 0.90, frame 101 vs 1: std ratio %.3f, high-band "
               "ratio %.3f\n",
               method ? "bilinear" : "stationary", sr, hr);
        if (method) {
            CHECK(sr < 0.8);
            CHECK(hr < 0.5);
        } else {
            CHECK(fabs(sr - 1.0) <= 0.05);
            CHECK(hr >= 0.8);
        }
        nprfx_cn_state_free(&st[0]);
        nprfx_cn_state_free(&st[1]);
        nprfx_cn_state_free(&first);
    }
}

/* Pearson correlation of a and b over the pairs accumulated. */
typedef struct corr_acc {
    double sa, sb, saa, sbb, sab;
    long long n;
} corr_acc;
static void corr_add(corr_acc *c, double a, double b)
{
    c->sa += a;
    c->sb += b;
    c->saa += a * a;
    c->sbb += b * b;
    c->sab += a * b;
    c->n++;
}
static double corr_get(const corr_acc *c)
{
    double n = (double)c->n, ma = c->sa / n, mb = c->sb / n;
    return (c->sab / n - ma * mb) / sqrt((c->saa / n - ma * ma) * (c->sbb / n - mb * mb));
}

static double bilinear(const nprfx_image *im, double x, double y, int ch)
{
    int ix = (int)floor(x), iy = (int)floor(y);
    double fx = x - ix, fy = y - iy;
    int x1 = ix + 1 < im->bounds.x1 ? ix + 1 : ix, y1 = iy + 1 < im->bounds.y1 ? iy + 1 : iy;
    return (1 - fy) *
               ((1 - fx) * nprfx_image_at(im, ix, iy)[ch] + fx * nprfx_image_at(im, x1, iy)[ch]) +
           fy * ((1 - fx) * nprfx_image_at(im, ix, y1)[ch] + fx * nprfx_image_at(im, x1, y1)[ch]);
}

/* Coherence on a fast pan (2.37, 1.23 px/frame) with band-pass noise: the coherent noise follows
 * the motion (warp correlation >= alpha - 0.05), independent noise does not (~0), and noise fixed
 * to the screen fails the warp test. */
static void test_coherence_pan(nprfx_context *ctx)
{
    scene s;
    memset(&s, 0, sizeof s);
    s.kind = SC_TRANSLATE;
    s.W = s.H = 96;
    s.vx = 2.37;
    s.vy = 1.23;
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV);
    const double alpha = 0.9;
    double res[3];
    for (int variant = 0; variant < 3; variant++) {
        nprfx_value pv[32];
        defaults(pv);
        set_param(pv, "noise", 1);
        set_param(pv, "sigma_lo", 1.0);
        set_param(pv, "sigma_hi", 0.0);
        set_param(pv, "alpha", variant == 1 ? 0.0 : alpha);
        nprfx_image prev, cur;
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 96, 96), 1, &prev);
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 96, 96), 1, &cur);
        void *state = NULL;
        corr_acc acc;
        memset(&acc, 0, sizeof acc);
        for (int f = 1; f <= 30; f++) {
            /* screen-fixed: the same start frame every time */
            render_full(&s, ctx, pv, variant == 2 ? 1 : f, 1, 30, &state, &cur);
            if (f > 20)
                for (int y = 4; y < 92; y++)
                    for (int x = 4; x < 92; x++)
                        corr_add(&acc, nprfx_image_at(&cur, x, y)[0],
                                 bilinear(&prev, x - s.vx, y - s.vy, 0));
            nprfx_image t = prev;
            prev = cur;
            cur = t;
        }
        res[variant] = corr_get(&acc);
        state_release(&state);
        nprfx_image_free(&prev);
        nprfx_image_free(&cur);
    }
    printf("coherence pan (2.37,1.23) px/frame, band-pass: coherent %.3f (alpha %.2f), white %.3f, "
           "screen-fixed %.3f\n",
           res[0], alpha, res[1], res[2]);
    CHECK(res[0] >= alpha - 0.05);
    CHECK(fabs(res[1]) < 0.05);
    CHECK(res[2] < 0.5);
}

/* The orbit scene: coherence on visible pixels, fresh noise on disoccluded ones. */
static void test_orbit(nprfx_context *ctx)
{
    enum { W = 128, H = 72, FA = 10, FB = 40 };
    scene s;
    scene_synth(&s, ctx, "orbit", W, H);
    s.connected &= ~(1u << IN_SOURCE);
    const double alpha = 0.9;
    double res[2][3]; /* [coherent, screen-fixed][visible, moving, disoccluded] */
    long long counts[3] = {0, 0, 0};
    for (int variant = 0; variant < 2; variant++) {
        nprfx_value pv[32];
        defaults(pv);
        set_param(pv, "alpha", alpha);
        set_param(pv, "noise", 1);
        set_param(pv, "sigma_lo", 1.0);
        set_param(pv, "sigma_hi", 0.0);
        set_param(pv, "start", FA);
        nprfx_image prev, cur;
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &prev);
        nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &cur);
        void *state = NULL;
        corr_acc acc[3];
        memset(acc, 0, sizeof acc);
        for (int f = FA; f <= FB; f++) {
            CHECK_OK(render_full(&s, ctx, pv, variant ? FA : f, FA, FB, &state, &cur));
            if (f >= FA + 10) {
                const nprfx_image *pc = synth_plate(&s, f), *pp = synth_plate(&s, f - 1);
                for (int y = 2; y < H - 2; y++)
                    for (int x = 2; x < W - 2; x++) {
                        const float *q = nprfx_image_at(pc, x, y);
                        double px = x + q[s.ch_mp], py = y + q[s.ch_mp + 1];
                        if (!(px >= 1 && py >= 1 && px <= W - 2 && py <= H - 2)) continue;
                        double z = q[s.ch_z];
                        /* previous depth and id around p */
                        int ix = (int)floor(px), iy = (int)floor(py), same = 1;
                        for (int dy = 0; dy < 2; dy++)
                            for (int dx = 0; dx < 2; dx++)
                                if (nprfx_image_at(pp, ix + dx, iy + dy)[s.ch_id] != q[s.ch_id])
                                    same = 0;
                        double zb = bilinear(pp, px, py, s.ch_z);
                        double a = nprfx_image_at(&cur, x, y)[0], b = bilinear(&prev, px, py, 0);
                        double speed = hypot(q[s.ch_mp], q[s.ch_mp + 1]);
                        if (same && fabs(zb - z) < 0.01 * z) {
                            corr_add(&acc[0], a, b);
                            if (speed > 0.5) corr_add(&acc[1], a, b);
                        } else if (zb * 1.05 < z) {
                            corr_add(&acc[2], a, b); /* was behind something at f-1 */
                        }
                    }
            }
            nprfx_image t = prev;
            prev = cur;
            cur = t;
        }
        for (int k = 0; k < 3; k++) {
            res[variant][k] = corr_get(&acc[k]);
            counts[k] = acc[k].n;
        }
        state_release(&state);
        nprfx_image_free(&prev);
        nprfx_image_free(&cur);
    }
    printf("orbit coherent: visible %.3f (n=%lld), moving %.3f (n=%lld), disoccluded %.3f "
           "(n=%lld); screen-fixed moving %.3f\n",
           res[0][0], counts[0], res[0][1], counts[1], res[0][2], counts[2], res[1][1]);
    CHECK(counts[1] > 1000 && counts[2] > 100);
    CHECK(res[0][0] >= alpha - 0.05);
    CHECK(res[0][1] >= alpha - 0.05);
    CHECK(fabs(res[0][2]) < 0.15);
    CHECK(res[1][1] < res[0][1] - 0.2);
    scene_free(&s);
}

/* The vector path (packed states, taps inside the frame) and the scalar path (any layout) compute
 * the same numbers: steps on packed states, on states with a spare float per pixel (scalar path
 * throughout) and on packed states with strided inputs (the vector path's non-direct loads) agree
 * bit for bit, for 1-4 channels, white and band-pass noise, on a sub-pixel rotation with frame
 * borders, a background region, NaN depth, a depth step and z velocity. */
static void paths_scene(int W, int H, int f, nprfx_image *depth, nprfx_image *motion,
                        nprfx_image *zvel)
{
    const double cx = 0.5 * W - 3.2, cy = 0.5 * H + 1.7, a = 0.035;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double dx = x - cx, dy = y - cy;
            double px = cx + cos(a) * dx + sin(a) * dy + 0.31, py = cy - sin(a) * dx + cos(a) * dy;
            float *m = nprfx_image_at(motion, x, y);
            m[0] = (float)(px - x);
            m[1] = (float)(py - y);
            float z = 10.0f + 0.05f * (float)x + 0.02f * (float)((y + 3 * f) % 7);
            if (x > W / 2 && y < H / 3) z = 4.0f;        /* a closer box */
            if ((x + 2 * y + f) % 53 == 0) z = INFINITY; /* background specks */
            if (y > H - 6 && x < W / 4) z = 1e10f;       /* a background corner */
            if (x == 7 && y == 9) z = NAN;               /* no depth at all */
            if (x == W - 9 && y == 5) m[0] = INFINITY;   /* a broken vector */
            nprfx_image_at(depth, x, y)[0] = z;
            nprfx_image_at(zvel, x, y)[0] = (x * 7 + y) % 11 == 0 ? NAN : 0.003f * (float)(x % 5);
        }
}

static void test_paths_agree(nprfx_context *ctx)
{
    enum {
        W = 62,
        H = 43,
        NF = 4
    }; /* W + 3 is not a multiple of 8: the last noise block overhangs */
    nprfx_rect fr = nprfx_rect_make(0, 0, W, H);
    nprfx_image depth[NF], motion[NF], zvel[NF], wide_d[NF], wide_m[NF];
    for (int f = 0; f < NF; f++) {
        nprfx_image_alloc(ctx, fr, 1, &depth[f]);
        nprfx_image_alloc(ctx, fr, 2, &motion[f]);
        nprfx_image_alloc(ctx, fr, 1, &zvel[f]);
        paths_scene(W, H, f, &depth[f], &motion[f], &zvel[f]);
        /* the same data in wider images: pixel strides 2 and 3 */
        nprfx_image_alloc(ctx, fr, 2, &wide_d[f]);
        nprfx_image_alloc(ctx, fr, 3, &wide_m[f]);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                nprfx_image_at(&wide_d[f], x, y)[0] = nprfx_image_at(&depth[f], x, y)[0];
                nprfx_image_at(&wide_m[f], x, y)[0] = nprfx_image_at(&motion[f], x, y)[0];
                nprfx_image_at(&wide_m[f], x, y)[1] = nprfx_image_at(&motion[f], x, y)[1];
            }
        wide_d[f].channels = 1;
        wide_m[f].channels = 2;
    }
    int bad = 0, cases = 0;
    for (int noise = 0; noise < 2; noise++)
        for (int C = 1; C <= 4; C++)
            for (int use_zvel = 0; use_zvel < 2; use_zvel++) {
                nprfx_cn_params p;
                nprfx_cn_params_default(&p);
                p.channels = C;
                p.seed = 17;
                p.alpha = 0.8;
                p.noise = noise ? NPRFX_CN_NOISE_BANDPASS : NPRFX_CN_NOISE_WHITE;
                nprfx_cn_state st[3][2];
                nprfx_image wide[3][2];
                for (int v = 0; v < 3; v++)
                    for (int k = 0; k < 2; k++) {
                        nprfx_cn_state_alloc(ctx, fr, C, &st[v][k]);
                        if (v == 1) {
                            /* a spare float per pixel: not packed */
                            nprfx_image_alloc(ctx, fr, C + 1, &wide[v][k]);
                            nprfx_image view = wide[v][k];
                            view.channels = C;
                            nprfx_image_free(&st[v][k].value);
                            st[v][k].value = view;
                        }
                    }
                int cur = 0;
                for (int v = 0; v < 3; v++)
                    CHECK_OK(nprfx_cn_begin(ctx, &p, 0, NULL, &st[v][0]));
                for (int f = 1; f < NF; f++) {
                    for (int v = 0; v < 3; v++) {
                        nprfx_cn_inputs in = {v == 2 ? &wide_d[f] : &depth[f],
                                              v == 2 ? &wide_m[f] : &motion[f],
                                              use_zvel ? &zvel[f] : NULL,
                                              v == 2 ? &wide_d[f - 1] : &depth[f - 1], NULL};
                        CHECK_OK(nprfx_cn_step(ctx, &p, NPRFX_CN_FORWARD, f, &in, &st[v][cur],
                                               &st[v][1 - cur]));
                    }
                    cur = 1 - cur;
                }
                for (int v = 1; v < 3; v++) {
                    for (int y = 0; y < H; y++)
                        for (int x = 0; x < W; x++) {
                            const float *a = nprfx_image_at(&st[0][cur].value, x, y);
                            const float *b = nprfx_image_at(&st[v][cur].value, x, y);
                            if (memcmp(a, b, sizeof(float) * (size_t)C) ||
                                st[0][cur].fresh[y * W + x] != st[v][cur].fresh[y * W + x]) {
                                if (bad < 5)
                                    fprintf(stderr,
                                            "paths: noise %d C %d zvel %d variant %d differs at "
                                            "(%d, %d): %.9g vs %.9g\n",
                                            noise, C, use_zvel, v, x, y, a[0], b[0]);
                                bad++;
                            }
                        }
                    cases++;
                }
                long fresh = 0;
                for (int i = 0; i < W * H; i++)
                    fresh += st[0][cur].fresh[i];
                CHECK(fresh > 20 && fresh < W * H / 2); /* both kinds of pixel occur */
                for (int v = 0; v < 3; v++)
                    for (int k = 0; k < 2; k++) {
                        if (v == 1) {
                            st[v][k].value = wide[v][k];
                            st[v][k].value.channels = C + 1;
                        }
                        nprfx_cn_state_free(&st[v][k]);
                    }
            }
    printf("paths: vector and scalar paths agree in %d of %d cases\n", bad ? 0 : cases, cases);
    CHECK(bad == 0);
    for (int f = 0; f < NF; f++) {
        nprfx_image_free(&depth[f]);
        nprfx_image_free(&motion[f]);
        nprfx_image_free(&zvel[f]);
        wide_d[f].channels = 2;
        wide_m[f].channels = 3;
        nprfx_image_free(&wide_d[f]);
        nprfx_image_free(&wide_m[f]);
    }
}

/* ---- determinism ------------------------------------------------------------------------- */

typedef struct det_cfg {
    const char *label;
    int symmetric, noise, channels, window;
    double smooth, cache_mb;
} det_cfg;

/* Frames first..last of cfg rendered under an executor of `threads`, in `order` (0 forward,
 * 1 reverse, 2 each frame with a fresh state, 3 forward in four tiles), into out[]. */
static void det_run(const det_cfg *cfg, int threads, int order, scene *s, int first, int last,
                    nprfx_image *out)
{
    nprfx_pool *pool = NULL;
    nprfx_pool_create(threads, &pool);
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.executor = nprfx_pool_executor(pool);
    nprfx_context *ctx = NULL;
    nprfx_context_create(&ci, &ctx);
    nprfx_value pv[32];
    defaults(pv);
    set_param(pv, "mode", cfg->symmetric);
    set_param(pv, "noise", cfg->noise);
    set_param(pv, "channels", cfg->channels);
    set_param(pv, "window", cfg->window);
    set_param(pv, "smooth", cfg->smooth);
    set_param(pv, "cache_mb", cfg->cache_mb);
    set_param(pv, "alpha", 0.85);
    set_param(pv, "seed", 5);
    if (cfg->noise == 1) set_param(pv, "output", 1);
    void *state = NULL;
    int n = last - first + 1;
    for (int k = 0; k < n; k++) {
        int f = order == 1 ? last - k : first + k;
        nprfx_image *o = &out[f - first];
        if (order == 2) state_release(&state);
        if (order == 3) {
            int hx = s->W / 2, hy = s->H / 3;
            nprfx_rect tiles[4] = {nprfx_rect_make(hx, hy, s->W, s->H),
                                   nprfx_rect_make(0, 0, hx, hy), nprfx_rect_make(hx, 0, s->W, hy),
                                   nprfx_rect_make(0, hy, hx, s->H)};
            for (int t = 0; t < 4; t++)
                CHECK_OK(render(s, ctx, pv, f, first, last, &state, o, tiles[t]));
        } else {
            CHECK_OK(render_full(s, ctx, pv, f, first, last, &state, o));
        }
    }
    state_release(&state);
    nprfx_context_destroy(ctx);
    nprfx_pool_destroy(pool);
}

static void test_determinism(nprfx_context *ctx0)
{
    enum { W = 64, H = 36, FIRST = 20, LAST = 31, N = LAST - FIRST + 1 };
    const det_cfg cfgs[] = {
        {"causal white 2ch", 0, 0, 2, 0, 0.0, 1024},
        {"causal bandpass smooth, cache 0", 0, 1, 1, 0, 1.5, 0},
        {"symmetric white 3ch", 1, 0, 3, 0, 0.0, 1024},
        {"symmetric input", 1, 2, 1, 0, 0.0, 1024},
        {"causal window 4", 0, 0, 1, 4, 0.0, 1024},
        {"symmetric window 3 tiny cache", 1, 1, 1, 3, 1.0, 0},
    };
    scene s;
    scene_synth(&s, ctx0, "orbit", W, H);
    for (size_t c = 0; c < sizeof cfgs / sizeof cfgs[0]; c++) {
        int ch = cfgs[c].noise == 2 ? 3 : cfgs[c].channels;
        nprfx_image ref[N], other[N];
        for (int i = 0; i < N; i++) {
            nprfx_image_alloc(ctx0, nprfx_rect_make(0, 0, W, H), ch, &ref[i]);
            nprfx_image_alloc(ctx0, nprfx_rect_make(0, 0, W, H), ch, &other[i]);
        }
        det_run(&cfgs[c], 1, 0, &s, FIRST, LAST, ref);
        const int runs[3][2] = {{2, 1}, {4, 2}, {2, 3}}; /* threads, order */
        int same_all = 1;
        for (int r = 0; r < 3; r++) {
            for (int i = 0; i < N; i++)
                memset(other[i].data, 0xff, sizeof(float) * W * H * (size_t)ch);
            det_run(&cfgs[c], runs[r][0], runs[r][1], &s, FIRST, LAST, other);
            int same = 1;
            for (int i = 0; i < N; i++)
                if (memcmp(ref[i].data, other[i].data, sizeof(float) * W * H * (size_t)ch))
                    same = 0;
            if (!same)
                fprintf(stderr, "determinism: %s differs (threads %d, order %d)\n", cfgs[c].label,
                        runs[r][0], runs[r][1]);
            same_all &= same;
            CHECK(same);
        }
        /* and the output is not trivially constant */
        CHECK(std_of(ctx0, &ref[N - 1], 0) > 0.01);
        printf("determinism %-34s: %s\n", cfgs[c].label, same_all ? "bit-identical" : "DIFFERS");
        for (int i = 0; i < N; i++) {
            nprfx_image_free(&ref[i]);
            nprfx_image_free(&other[i]);
        }
    }
    scene_free(&s);
}

/* Input mode: a constant clip stays constant, the flicker of a noisy clip drops on static
 * pixels, and outputs stay on the clip's scale. */
static void test_input_mode(nprfx_context *ctx)
{
    enum { W = 64, H = 36 };
    scene s;
    scene_synth(&s, ctx, "orbit", W, H);
    nprfx_value pv[32];
    defaults(pv);
    set_param(pv, "noise", 2);
    set_param(pv, "alpha", 0.8);
    set_param(pv, "start", 1);
    nprfx_image o[2];
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 3, &o[0]);
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 3, &o[1]);
    void *state = NULL;
    double flick_in = 0, flick_out = 0;
    long long n = 0;
    for (int f = 1; f <= 25; f++) {
        CHECK_OK(render_full(&s, ctx, pv, f, 1, 25, &state, &o[f & 1]));
        if (f > 15) {
            const nprfx_image *pc = synth_plate(&s, f);
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    const float *q = nprfx_image_at(pc, x, y);
                    if (q[s.ch_mp] != 0.0f || q[s.ch_mp + 1] != 0.0f) continue;
                    double d = nprfx_image_at(&o[f & 1], x, y)[0] -
                               nprfx_image_at(&o[(f + 1) & 1], x, y)[0];
                    double di = 0.1 * (nprfx_rand_gauss(99, f, x, y, 0, 0) -
                                       nprfx_rand_gauss(99, f - 1, x, y, 0, 0));
                    flick_out += d * d;
                    flick_in += di * di;
                    n++;
                }
        }
    }
    /* static pixels: the input flicker (variance 2 * 0.01) drops to about (1-a)/(1+a) of it */
    printf("input mode: frame-to-frame rms on static pixels %.4f -> %.4f (n=%lld)\n",
           sqrt(flick_in / n), sqrt(flick_out / n), n);
    CHECK(n > 1000);
    CHECK(flick_out < 0.25 * flick_in);
    state_release(&state);
    nprfx_image_free(&o[0]);
    nprfx_image_free(&o[1]);
    scene_free(&s);
}

/* In-order rendering of the recursion from the start frame (window 1000000) costs one step per
 * frame (a bounded number of fetches), and reverse-order rendering stays within a constant factor
 * of it (checkpoints + the recent run). The automatic window (the default) costs about two steps
 * a frame in order, and any frame alone, frame 200,000 of a 200,000-frame shot included, under
 * 2W steps (a farm renders frames alone). */
static void test_cost(nprfx_context *ctx)
{
    scene s;
    memset(&s, 0, sizeof s);
    s.kind = SC_TRANSLATE;
    s.W = s.H = 32;
    s.vx = 0.3;
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV);
    nprfx_value pv[32];
    defaults(pv);
    set_param(pv, "window", 1000000);
    nprfx_image o;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 32, 32), 1, &o);
    void *state = NULL;
    long long worst = 0;
    for (int f = 1; f <= 200; f++) {
        long long before = s.fetches;
        render_full(&s, ctx, pv, f, 1, 200, &state, &o);
        if (f > 1 && s.fetches - before > worst) worst = s.fetches - before;
    }
    state_release(&state);
    long long before = s.fetches;
    for (int f = 200; f >= 1; f--)
        render_full(&s, ctx, pv, f, 1, 200, &state, &o);
    long long reverse = s.fetches - before;
    printf("cost: in order at most %lld fetches per frame; reverse order %lld fetches for 200 "
           "frames\n",
           worst, reverse);
    CHECK(worst <= 8);
    CHECK(reverse <= 200 * 20);
    state_release(&state);

    /* The automatic window: W = 66 at alpha 0.9. */
    defaults(pv);
    int64_t W = nprfx_coherent_noise_auto_window(0.9);
    CHECK(W == 66);
    CHECK(nprfx_coherent_noise_auto_window(0.98) == 342);
    CHECK(nprfx_coherent_noise_auto_window(1.0) == 0);
    CHECK(pow(0.9, (double)W) <= NPRFX_CN_WINDOW_TOLERANCE &&
          pow(0.9, (double)(W - 1)) > NPRFX_CN_WINDOW_TOLERANCE);
    long long in_order = s.fetches;
    for (int f = 1; f <= 400; f++)
        render_full(&s, ctx, pv, f, 1, 400, &state, &o);
    in_order = s.fetches - in_order;
    state_release(&state);
    /* Frame 200,000 alone: the span the host prepares, and the fetches the render makes. */
    int ich[NPRFX_CN_IN_COUNT] = {1, 2, 0, 0, 0};
    nprfx_frames_query q = {200000, 1, 200000, ich};
    nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
    int nr = 0;
    CHECK_OK(nprfx_node_frames_needed(ctx, node, pv, &q, IN_DEPTH, rg, &nr));
    CHECK(nr == 1 && rg[0].last == 200000 && rg[0].last - rg[0].first >= W &&
          rg[0].last - rg[0].first < 2 * W);
    long long alone = s.fetches;
    render_full(&s, ctx, pv, 200000, 1, 200000, &state, &o);
    alone = s.fetches - alone;
    state_release(&state);
    printf("cost, automatic window %lld: 400 frames in order %lld fetches; frame 200000 alone "
           "reads frames %d-%d, %lld fetches\n",
           (long long)W, in_order, nr ? rg[0].first : 0, nr ? rg[0].last : 0, alone);
    /* about 4 fetches a step (depth, previous depth, motion, fingerprint) */
    CHECK(alone <= 2 * W * 6);
    CHECK(in_order <= 400 * 2 * 6);
    nprfx_image_free(&o);
}

/* What a host prepares: with the instance's state, rendering in order, frame t reads depth at
 * t-1 and t and motion at t (the recursion steps on from its last state); without it, or once the
 * params change, the recursion from its start. Every fetch lies in what was declared. */
static void test_frames_warm(nprfx_context *ctx)
{
    enum { W = 12, H = 10, LAST = 30 };
    scene s;
    memset(&s, 0, sizeof s);
    s.kind = SC_TRANSLATE;
    s.W = W;
    s.H = H;
    s.vx = 0.37;
    s.vy = 0.23;
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV);
    nprfx_value pv[32];
    defaults(pv);
    nprfx_image o;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, W, H), 1, &o);
    void *state = NULL;
    int ich[IN_COUNT] = {1, 2, 0, 0, 0, 0}, bad = 0, narrow = 0;
    for (int t = 1; t <= LAST; t++) {
        nprfx_frames_query cold = {t, 1, LAST, ich, NULL}, warm = {t, 1, LAST, ich, state};
        nprfx_frame_range c[NPRFX_MAX_FRAME_RANGES], d[NPRFX_MAX_FRAME_RANGES];
        int nc = 0, nd = 0;
        CHECK_OK(nprfx_node_frames_needed(ctx, node, pv, &cold, IN_DEPTH, c, &nc));
        CHECK_OK(nprfx_node_frames_needed(ctx, node, pv, &warm, IN_DEPTH, d, &nd));
        s.declared[IN_DEPTH] = d[0];
        CHECK_OK(nprfx_node_frames_needed(ctx, node, pv, &warm, IN_MPREV, d, &nd));
        s.declared[IN_MPREV] = d[0];
        if (nc != 1 || c[0].first != 1 || c[0].last != t) bad++;
        if (t >= 2 && s.declared[IN_DEPTH].first == t - 1 && s.declared[IN_DEPTH].last == t &&
            s.declared[IN_MPREV].first == t && s.declared[IN_MPREV].last == t)
            narrow++;
        s.declared_on = 1;
        CHECK_OK(render_full(&s, ctx, pv, t, 1, LAST, &state, &o));
        s.declared_on = 0;
    }
    CHECK(bad == 0);
    CHECK(narrow == LAST - 1);
    CHECK(s.outside == 0);
    /* another seed: the cache is not for it, so the whole recursion again */
    set_param(pv, "seed", 7);
    nprfx_frames_query q = {LAST + 0, 1, LAST, ich, state};
    nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES];
    int nr = 0;
    CHECK_OK(nprfx_node_frames_needed(ctx, node, pv, &q, IN_DEPTH, r, &nr));
    CHECK(nr == 1 && r[0].first == 1 && r[0].last == LAST);
    /* a frame out of order (back to 5): from the nearest state before it */
    defaults(pv);
    q.time = 5;
    CHECK_OK(nprfx_node_frames_needed(ctx, node, pv, &q, IN_DEPTH, r, &nr));
    printf("frames declared: cold 1-t; in order warm depth t-1..t, motion t (%d of %d frames); "
           "back to 5 after 30: depth %d-%d\n",
           narrow, LAST - 1, r[0].first, r[0].last);
    CHECK(nr == 1 && r[0].first >= 1 && r[0].first <= 5 && r[0].last == 5);
    state_release(&state);
    nprfx_image_free(&o);
}

static void test_errors(nprfx_context *ctx)
{
    scene s;
    memset(&s, 0, sizeof s);
    s.kind = SC_TRANSLATE;
    s.W = s.H = 8;
    s.connected = (1u << IN_DEPTH) | (1u << IN_MPREV);
    nprfx_value pv[32];
    defaults(pv);
    nprfx_image o;
    nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, 8, 8), 1, &o);
    void *state = NULL;
    set_param(pv, "mode", 1); /* symmetric without motion_next */
    CHECK(render_full(&s, ctx, pv, 2, 1, 5, &state, &o) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "motion_next") != NULL);
    set_param(pv, "mode", 0);
    set_param(pv, "noise", 1);
    set_param(pv, "sigma_lo", 3);
    set_param(pv, "sigma_hi", 2);
    CHECK(render_full(&s, ctx, pv, 2, 1, 5, &state, &o) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "sigma_hi") != NULL);
    set_param(pv, "noise", 2);
    CHECK(render_full(&s, ctx, pv, 2, 1, 5, &state, &o) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "source") != NULL);
    /* descriptor facts the runner relies on */
    CHECK(strcmp(node->inputs[IN_DEPTH].aov, "depth") == 0);
    CHECK(strcmp(node->inputs[IN_MPREV].aov, "motion_prev") == 0);
    CHECK(strstr(node->help, "8,760,466") != NULL);
    int ich[IN_COUNT] = {1, 2, 0, 0, 3};
    nprfx_output_info oi;
    defaults(pv);
    set_param(pv, "channels", 3);
    CHECK(nprfx_node_output_info(NULL, node, pv, ich, &oi) == NPRFX_OK && oi.channels == 3);
    set_param(pv, "noise", 2);
    CHECK(nprfx_node_output_info(NULL, node, pv, ich, &oi) == NPRFX_OK && oi.channels == 3);
    state_release(&state);
    nprfx_image_free(&o);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_context_create(&ci, &ctx);
    test_k_and_first_frame(ctx);
    test_one_step_by_hand(ctx);
    test_symmetric_by_hand(ctx);
    test_errors(ctx);
    test_frames_warm(ctx);
    test_cost(ctx);
    test_bilinear_fades(ctx);
    test_paths_agree(ctx);
    test_stationarity(ctx);
    test_coherence_pan(ctx);
    test_orbit(ctx);
    test_input_mode(ctx);
    test_determinism(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
