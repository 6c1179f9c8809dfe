/* coherent-noise on footage: the confidence input replaces the depth test. Checked
 * against the node itself with other inputs, exactly:
 *  - confidence 1 everywhere without depth is the same noise as a constant depth without
 *    confidence (the occlusion test of a flat depth never fires);
 *  - where confidence is below min_confidence the pixel is fresh: it equals alpha = 0 noise (w_i
 *    itself), and elsewhere it carries (differs from w_i);
 *  - symmetric mode reads channel 1 for the backward pass: with confidence.next 0 everywhere the
 *    backward pass is w_i, so C = (u_fwd + w - g w) / sqrt(1 + alpha^2) with u_fwd the causal
 *    output;
 *  - a NaN confidence restarts like a low one; neither depth nor confidence is an error naming
 *    both; a 3-channel confidence is refused.
 * Frame order and tiles do not matter (the same frame rendered alone). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "nprfx/coherent_noise.h"
#include "nprfx/context.h"
#include "nprfx/node.h"
#include "node_harness.h"

extern const nprfx_node_desc nprfx_node_coherent_noise;
static const nprfx_node_desc *node = &nprfx_node_coherent_noise;

/* CHECK with a formatted message. */
#define CHECKF(cond, ...)                                                                          \
    do {                                                                                           \
        if (cond) {                                                                                \
            check_passed++;                                                                        \
        } else {                                                                                   \
            check_failed++;                                                                        \
            fprintf(stderr, "%s:%d: ", __FILE__, __LINE__);                                        \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
        }                                                                                          \
    } while (0)

enum { W = 48, H = 32, FIRST = 1, LAST = 6 };

/* A pan of (1.25, -0.5) px/frame; confidence.prev drops to 0 in a band that moves with the frame
 * (x in [10, 20) at frame f: 10 + 2f), and is NaN at one pixel; confidence.next is `next_conf`. */
typedef struct footage {
    unsigned connected; /* bit per NPRFX_CN_IN_* */
    float next_conf;
    int conf_channels;
    nprfx_image arena[64];
    int n;
} footage;

static int low_band(int x, int f)
{
    return x >= 10 + 2 * f && x < 20 + 2 * f;
}

static nprfx_result fetch(void *user, int input, double time, nprfx_image *out)
{
    footage *s = user;
    int f = (int)floor(time + 0.5);
    if (!(s->connected & (1u << input))) return NPRFX_ERR_MISSING_INPUT;
    if (s->n >= 64) return NPRFX_ERR_OUT_OF_MEMORY;
    int ch = input == NPRFX_CN_IN_DEPTH        ? 1
             : input == NPRFX_CN_IN_CONFIDENCE ? s->conf_channels
                                               : 2;
    nprfx_image *im = &s->arena[s->n++];
    *im = th_image(W, H, ch, NULL);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *p = nprfx_image_at(im, x, y);
            switch (input) {
            case NPRFX_CN_IN_DEPTH:
                p[0] = 1.0f;
                break;
            case NPRFX_CN_IN_MOTION_PREV:
                p[0] = -1.25f;
                p[1] = 0.5f;
                break;
            case NPRFX_CN_IN_MOTION_NEXT:
                p[0] = 1.25f;
                p[1] = -0.5f;
                break;
            case NPRFX_CN_IN_CONFIDENCE:
                p[0] = low_band(x, f) ? 0.0f : (x == 40 && y == 20 && f == 4 ? NAN : 1.0f);
                if (ch > 1) p[1] = s->next_conf;
                if (ch > 2) p[2] = 1.0f;
                break;
            }
        }
    *out = *im;
    return NPRFX_OK;
}

/* Pixels the NaN restart at (40, 20) of frame 4 may reach by frame f along the pan, with the
 * resampler's 4x4 taps. */
static int nan_reach(int x, int y, int f)
{
    if (f < 4) return 0;
    double cx = 40 + 1.25 * (f - 4), cy = 20 - 0.5 * (f - 4);
    return fabs(x - cx) <= 2.0 * (f - 4) + 1 && fabs(y - cy) <= 2.0 * (f - 4) + 1;
}

static void arena_clear(footage *s)
{
    for (int i = 0; i < s->n; i++)
        nprfx_image_free(&s->arena[i]);
    s->n = 0;
}

static nprfx_result render(nprfx_context *ctx, footage *s, const nprfx_value *pv, int frame,
                           void **state, nprfx_image *out)
{
    nprfx_image ins[NPRFX_CN_IN_COUNT];
    memset(ins, 0, sizeof ins);
    for (int i = 0; i < NPRFX_CN_IN_COUNT; i++)
        if (s->connected & (1u << i)) fetch(s, i, frame, &ins[i]);
    nprfx_render_args a = th_args(ctx, node, ins, pv, out, out->bounds);
    a.time = frame;
    a.first_frame = FIRST;
    a.last_frame = LAST;
    a.fetch = fetch;
    a.fetch_user = s;
    a.state = state;
    nprfx_result r = nprfx_node_render(&a);
    arena_clear(s);
    return r;
}

static void defaults(nprfx_value *pv)
{
    nprfx_node_defaults(node, pv);
    for (int i = 0; i < node->num_params; i++)
        if (!pv[i].s) pv[i].s = "";
}

/* Frame `frame` of the shot, rendered alone with a fresh state (the recursion from the start). */
static nprfx_image frame_of(nprfx_context *ctx, footage *s, const nprfx_value *pv, int frame)
{
    void *state = NULL;
    nprfx_image out = th_image(W, H, 1, NULL);
    nprfx_result r = render(ctx, s, pv, frame, &state, &out);
    if (r) {
        fprintf(stderr, "render failed: %s\n", th_error(ctx));
        exit(2);
    }
    if (state) node->state_free(state);
    return out;
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    CHECK(nprfx_context_create(&init, &ctx) == NPRFX_OK);
    nprfx_value pv[32];
    CHECK(node->num_params <= 32);
    defaults(pv);
    pv[th_param(node, "sigma_lo")].v[0] = 0;
    pv[th_param(node, "noise")].v[0] = NPRFX_CN_NOISE_BANDPASS;
    pv[th_param(node, "sigma_lo")].v[0] = 1;
    pv[th_param(node, "sigma_hi")].v[0] = 3;
    const unsigned MP = 1u << NPRFX_CN_IN_MOTION_PREV, MN = 1u << NPRFX_CN_IN_MOTION_NEXT;
    const unsigned D = 1u << NPRFX_CN_IN_DEPTH, C = 1u << NPRFX_CN_IN_CONFIDENCE;
    const size_t bytes = sizeof(float) * W * H;

    /* 1. confidence 1 (outside the band, where it is 0, compare nothing) == flat depth. Use a
     * confidence without the band: next_conf channel as the only one is not possible, so compare
     * a render with min_confidence 0 (every finite confidence passes). */
    footage fd = {D | MP, 1.0f, 1, {{0}}, 0};
    footage fc = {C | MP, 1.0f, 1, {{0}}, 0};
    nprfx_value pv0[32];
    memcpy(pv0, pv, sizeof pv);
    pv0[th_param(node, "min_confidence")].v[0] = 0;
    for (int f = FIRST; f <= LAST; f++) {
        nprfx_image a = frame_of(ctx, &fd, pv0, f), b = frame_of(ctx, &fc, pv0, f);
        int same = 1;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++)
                if (!nan_reach(x, y, f) && /* the NaN restarts there, and carries on */
                    memcmp(nprfx_image_at(&a, x, y), nprfx_image_at(&b, x, y), 4) != 0)
                    same = 0;
        CHECKF(same, "frame %d: confidence >= min everywhere differs from a flat depth", f);
        nprfx_image_free(&a);
        nprfx_image_free(&b);
    }

    /* 2. below min_confidence: w_i itself (alpha = 0 gives w_i everywhere); above: carried. */
    nprfx_value pw[32];
    memcpy(pw, pv, sizeof pv);
    pw[th_param(node, "alpha")].v[0] = 0;
    for (int f = FIRST + 1; f <= LAST; f++) {
        nprfx_image u = frame_of(ctx, &fc, pv, f), w = frame_of(ctx, &fc, pw, f);
        int fresh_ok = 1, carried = 0, total = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                float a = *nprfx_image_at(&u, x, y), b = *nprfx_image_at(&w, x, y);
                int low = low_band(x, f) || (x == 40 && y == 20 && f == 4);
                int inside = x - 1.25 >= 0 && y + 0.5 <= H - 1; /* previous position in frame */
                if (low && a != b) fresh_ok = 0;
                if (!low && inside) {
                    total++;
                    carried += a != b;
                }
            }
        CHECKF(fresh_ok, "frame %d: a pixel below min_confidence is not fresh noise", f);
        CHECKF(carried == total, "frame %d: %d of %d trusted pixels carried", f, carried, total);
        nprfx_image_free(&u);
        nprfx_image_free(&w);
    }

    /* 3. symmetric, confidence.next 0: C = (u_fwd + w - g w) / sqrt(1 + a^2). */
    footage fs = {C | MP | MN, 0.0f, 2, {{0}}, 0};
    nprfx_value ps[32];
    memcpy(ps, pv, sizeof pv);
    ps[th_param(node, "mode")].v[0] = NPRFX_CN_MODE_SYMMETRIC;
    nprfx_value pw2[32];
    memcpy(pw2, pw, sizeof pw);
    double alpha = pv[th_param(node, "alpha")].v[0], g = sqrt(1 - alpha * alpha);
    for (int f = FIRST + 1; f < LAST; f++) {
        nprfx_image cs = frame_of(ctx, &fs, ps, f), uf = frame_of(ctx, &fc, pv, f);
        nprfx_image w = frame_of(ctx, &fc, pw2, f);
        double worst = 0;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                double fwd = *nprfx_image_at(&uf, x, y), ww = *nprfx_image_at(&w, x, y);
                int both = low_band(x, f) || (x == 40 && y == 20 && f == 4) || x - 1.25 < 0 ||
                           y + 0.5 > H - 1;
                double gg = both ? 2 - sqrt(1 + alpha * alpha) : g;
                double want = (fwd + ww - gg * ww) / sqrt(1 + alpha * alpha);
                double d = fabs(want - *nprfx_image_at(&cs, x, y));
                if (d > worst) worst = d;
            }
        CHECKF(worst < 1e-5, "frame %d: symmetric with confidence.next 0 off by %g", f, worst);
        nprfx_image_free(&cs);
        nprfx_image_free(&uf);
        nprfx_image_free(&w);
    }

    /* 4. in-order rendering with one state equals each frame alone. */
    void *state = NULL;
    for (int f = FIRST; f <= LAST; f++) {
        nprfx_image a = th_image(W, H, 1, NULL), b = frame_of(ctx, &fc, pv, f);
        CHECK(render(ctx, &fc, pv, f, &state, &a) == NPRFX_OK);
        CHECKF(memcmp(a.data, b.data, bytes) == 0, "frame %d in order differs from alone", f);
        nprfx_image_free(&a);
        nprfx_image_free(&b);
    }
    if (state) node->state_free(state);

    /* 5. errors */
    footage fn = {MP, 1.0f, 1, {{0}}, 0};
    nprfx_image out = th_image(W, H, 1, NULL);
    state = NULL;
    CHECK(render(ctx, &fn, pv, 2, &state, &out) == NPRFX_ERR_MISSING_INPUT);
    CHECKF(strstr(th_error(ctx), "'depth'") && strstr(th_error(ctx), "'confidence'"), "message: %s",
           th_error(ctx));
    if (state) node->state_free(state);
    state = NULL;
    footage f3 = {C | MP, 1.0f, 3, {{0}}, 0};
    CHECK(render(ctx, &f3, pv, 2, &state, &out) != NPRFX_OK);
    CHECKF(strstr(th_error(ctx), "confidence"), "message: %s", th_error(ctx));
    if (state) node->state_free(state);
    nprfx_image_free(&out);
    CHECK(nprfx_node_lint(ctx, node) == NPRFX_OK);

    nprfx_context_destroy(ctx);
    return check_finish();
}
