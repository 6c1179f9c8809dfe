/* NaN and infinity policy (docs/design.md §2.2), for every registered node, so a new node is
 * covered without a line here. Each input in turn gets one bad pixel (all its channels NaN, +inf
 * or -inf) at a known spot of one frame, T0, of a 9-frame shot whose other pixels and frames are
 * smooth and finite; the node renders frames T0-1 .. T0+2 in order with one instance state, for its
 * defaults and for every option of every choice param. What a node may do with the bad pixel:
 *  - treat it as missing: the output stays finite everywhere;
 *  - pass it through: a non-finite value may show only within the node's declared footprint
 *    (nprfx_node_footprint, -1: anywhere) of the bad pixel, and only in frames that read the bad
 *    frame itself or one other (a time shift), never along a recursion over many frames;
 *  - never turn NaN into an infinity: with a NaN input no output pixel is infinite.
 *  - or refuse the frame with a message naming the input (pam-splat's art map).
 * The clean inputs must give a finite output, or the checks above would mean nothing. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "flow_test_provider.h"
#include "node_harness.h"
#include "nprfx/context.h"
#include "nprfx/node.h"

enum { W = 40, H = 32, BX = 19, BY = 14, FIRST = 1, LAST = 9, T0 = 5, MAX_IN = 16 };

/* The inputs of one render sequence: a clean view per input and, for input `bad_input` at frame
 * T0 only, the view with the bad pixel. */
typedef struct feed {
    nprfx_image clean[MAX_IN], bad[MAX_IN];
    int connected[MAX_IN];
    int bad_input; /* -1: all clean */
    int fetches;
} feed;

static const nprfx_image *feed_at(const feed *f, int input, int frame)
{
    return input == f->bad_input && frame == T0 ? &f->bad[input] : &f->clean[input];
}

static nprfx_result fetch_cb(void *user, int input, double time, nprfx_image *out)
{
    feed *f = user;
    if (input < 0 || input >= MAX_IN || !f->connected[input]) return NPRFX_ERR_MISSING_INPUT;
    f->fetches++;
    *out = *feed_at(f, input, (int)floor(time + 0.5));
    return NPRFX_OK;
}

/* Smooth finite content that every kind of input accepts: depth-like positive values, sub-pixel
 * motion, UV and anchors with a full-rank gradient, ids, coverage and tones in [0.2, 0.8]. */
static nprfx_image clean_image(int w, int h, int channels)
{
    nprfx_image im = th_image(w, h, channels, NULL);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *p = nprfx_image_at(&im, x, y);
            for (int c = 0; c < channels; c++)
                p[c] = c == 0   ? 0.2f + 0.6f * (float)x / (float)w
                       : c == 1 ? 0.2f + 0.6f * (float)y / (float)h
                       : c == 2 ? 0.5f
                                : 1.0f;
        }
    return im;
}

static nprfx_image copy_image(const nprfx_image *src)
{
    nprfx_image im = th_image(nprfx_rect_width(src->bounds), nprfx_rect_height(src->bounds),
                              src->channels, src->data);
    return im;
}

/* Render frames T0-1 .. T0+2 in order into outs[4] with one state; the first failure's code. */
static nprfx_result render_run(nprfx_context *ctx, const nprfx_node_desc *d,
                               const nprfx_value *params, feed *f, int out_ch, nprfx_image *outs)
{
    void *state = NULL;
    nprfx_result r = NPRFX_OK;
    nprfx_image views[MAX_IN];
    for (int k = 0; k < 4 && !r; k++) {
        int t = T0 - 1 + k;
        memset(views, 0, sizeof views);
        for (int i = 0; i < d->num_inputs; i++)
            if (f->connected[i]) views[i] = *feed_at(f, i, t);
        outs[k] = th_image(W, H, out_ch, NULL);
        nprfx_render_args a;
        memset(&a, 0, sizeof a);
        a.size = sizeof a;
        a.ctx = ctx;
        a.node = d;
        a.time = t;
        a.render_scale = 1;
        a.frame = a.window = outs[k].bounds;
        a.first_frame = FIRST;
        a.last_frame = LAST;
        a.inputs = views;
        a.params = params;
        a.output = &outs[k];
        a.fetch = fetch_cb;
        a.fetch_user = f;
        a.state = &state;
        r = nprfx_node_render(&a);
    }
    if (state && d->state_free) d->state_free(state);
    return r;
}

static void free_run(nprfx_image *outs)
{
    for (int k = 0; k < 4; k++)
        nprfx_image_free(&outs[k]);
}

/* Does output frame t (T0-1+k) read input `input` at T0 and at most one other frame, so that
 * it may pass a bad pixel of T0 through (a time shift)? Frame T0 itself always may. */
static int reads_bad_frame_directly(nprfx_context *ctx, const nprfx_node_desc *d,
                                    const nprfx_value *params, const int *ich, int input, int t)
{
    if (t == T0) return 1;
    nprfx_frames_query q = {t, FIRST, LAST, ich};
    nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
    int n = 0, frames = 0, has = 0;
    if (nprfx_node_frames_needed(ctx, d, params, &q, input, rg, &n)) return 0;
    for (int i = 0; i < n; i++) {
        frames += rg[i].last - rg[i].first + 1;
        if (rg[i].first <= T0 && T0 <= rg[i].last) has = 1;
    }
    return has && frames <= 2;
}

static int tested_runs, nonfinite_clean, refused;

/* One configuration (params) of node d: every input, every bad value. Inputs of any channel
 * count get anych[i] of them (4, else 3, 2 or 1: an anchor takes 3, a direction 1 or 2);
 * returns 0 when the clean render failed, so the caller can try another count. */
static int check_config_ch(nprfx_context *ctx, const nprfx_node_desc *d, const nprfx_value *params,
                           const char *what, const int *anych, int last_try)
{
    feed f;
    memset(&f, 0, sizeof f);
    f.bad_input = -1;
    int ich[MAX_IN] = {0}, ok = 1;
    if (d->num_inputs > MAX_IN) {
        fprintf(stderr, "%s: more than %d inputs\n", d->id, MAX_IN);
        CHECK(0);
        return 1;
    }
    for (int i = 0; i < d->num_inputs; i++) {
        const nprfx_input_desc *in = &d->inputs[i];
        int ch = in->channels > 0 ? in->channels : anych[i];
        int unaligned = (in->flags & NPRFX_INPUT_UNALIGNED) != 0;
        /* a lookup map, or a painterly art map: square maps side by side */
        f.clean[i] = clean_image(unaligned ? 32 : W, unaligned ? 16 : H, ch);
        f.bad[i] = copy_image(&f.clean[i]);
        f.connected[i] = 1;
        ich[i] = ch;
    }
    nprfx_output_info oi;
    int out_ch = 0;
    if (nprfx_node_output_info(ctx, d, params, ich, &oi) == NPRFX_OK) out_ch = oi.channels;
    int fp = 0;
    nprfx_image clean_out[4];
    memset(clean_out, 0, sizeof clean_out);
    if (!out_ch || nprfx_node_footprint(ctx, d, params, &fp) ||
        render_run(ctx, d, params, &f, out_ch, clean_out)) {
        /* A combination the node refuses (a choice that needs a param set otherwise): skip it,
         * but never the defaults. */
        ok = 0;
        if (last_try && !strcmp(what, "defaults")) {
            fprintf(stderr, "%s (%s): clean render failed: %s\n", d->id, what, th_error(ctx));
            CHECK(0);
        }
        free_run(clean_out);
        goto out;
    }
    for (int k = 0; k < 4; k++) {
        size_t n = (size_t)W * H * (size_t)out_ch;
        for (size_t i = 0; i < n; i++)
            if (!isfinite(clean_out[k].data[i])) {
                fprintf(stderr, "%s (%s): clean inputs give %g at frame %d\n", d->id, what,
                        clean_out[k].data[i], T0 - 1 + k);
                nonfinite_clean++;
                CHECK(0);
                break;
            }
    }
    free_run(clean_out);
    static const float bad_values[3] = {NAN, INFINITY, -INFINITY};
    static const char *const bad_names[3] = {"NaN", "+inf", "-inf"};
    for (int i = 0; i < d->num_inputs; i++) {
        const nprfx_image *cl = &f.clean[i];
        int bx = cl->bounds.x1 < W ? 7 : BX, by = cl->bounds.y1 < H ? 7 : BY;
        for (int b = 0; b < 3; b++) {
            float *p = nprfx_image_at(&f.bad[i], bx, by);
            for (int c = 0; c < f.bad[i].channels; c++)
                p[c] = bad_values[b];
            f.bad_input = i;
            nprfx_image outs[4];
            memset(outs, 0, sizeof outs);
            nprfx_result r = render_run(ctx, d, params, &f, out_ch, outs);
            tested_runs++;
            /* Refusing the frame is a policy too (pam-splat's art map, an asset rather than a
             * render), with a message that names the input. */
            if (r) {
                char quoted[80];
                snprintf(quoted, sizeof quoted, "input '%s'", d->inputs[i].name);
                int named = strstr(th_error(ctx), quoted) && strstr(th_error(ctx), "non-finite");
                if (!named)
                    fprintf(stderr, "%s (%s): input '%s' %s: render failed: %s\n", d->id, what,
                            d->inputs[i].name, bad_names[b], th_error(ctx));
                CHECK(named);
                refused++;
            }
            for (int k = 0; k < 4 && !r; k++) {
                int t = T0 - 1 + k, may = reads_bad_frame_directly(ctx, d, params, ich, i, t);
                int stray = 0, inf_from_nan = 0, sx = 0, sy = 0;
                for (int y = 0; y < H; y++)
                    for (int x = 0; x < W; x++) {
                        const float *o = nprfx_image_at(&outs[k], x, y);
                        int near = may && (fp < 0 || (abs(x - BX) <= fp && abs(y - BY) <= fp));
                        for (int c = 0; c < out_ch; c++) {
                            if (isfinite(o[c])) continue;
                            if (b == 0 && isinf(o[c])) inf_from_nan++;
                            if (!near && !stray++) sx = x, sy = y;
                        }
                    }
                if (stray || inf_from_nan) {
                    fprintf(stderr,
                            "%s (%s): input '%s' %s at (%d, %d) frame %d: frame %d has %d "
                            "non-finite values outside the footprint %d (first at (%d, %d)), "
                            "%d infinities from NaN\n",
                            d->id, what, d->inputs[i].name, bad_names[b], bx, by, T0, t, stray, fp,
                            sx, sy, inf_from_nan);
                }
                CHECK(stray == 0);
                CHECK(inf_from_nan == 0);
                if (getenv("TEST_NAN_VERBOSE") && !strcmp(what, "defaults")) {
                    int any = 0;
                    for (size_t q = 0; q < (size_t)W * H * (size_t)out_ch; q++)
                        any += !isfinite(outs[k].data[q]);
                    printf("POLICY %s %s %s frame%+d nonfinite=%d\n", d->id, d->inputs[i].name,
                           bad_names[b], t - T0, any);
                }
            }
            free_run(outs);
            memcpy(f.bad[i].data, cl->data,
                   sizeof(float) * (size_t)nprfx_rect_width(cl->bounds) *
                       (size_t)nprfx_rect_height(cl->bounds) * (size_t)cl->channels);
        }
        f.bad_input = -1;
    }
out:
    for (int i = 0; i < d->num_inputs; i++) {
        nprfx_image_free(&f.clean[i]);
        nprfx_image_free(&f.bad[i]);
    }
    return ok;
}

static void check_config(nprfx_context *ctx, const nprfx_node_desc *d, const nprfx_value *params,
                         const char *what)
{
    static const int counts[4] = {4, 3, 2, 1};
    int pick[MAX_IN] = {0};
    /* An input of any count that the node refuses names itself in the message: give it the
     * next count and try again. */
    for (int tries = 0; tries < 4 * MAX_IN; tries++) {
        int ch[MAX_IN];
        for (int i = 0; i < MAX_IN; i++)
            ch[i] = counts[pick[i]];
        int last = 1;
        for (int i = 0; i < d->num_inputs; i++)
            if (pick[i] < 3 && !d->inputs[i].channels) last = 0;
        if (check_config_ch(ctx, d, params, what, ch, last)) return;
        const char *msg = th_error(ctx);
        if (getenv("TEST_NAN_VERBOSE")) fprintf(stderr, "%s (%s): %s\n", d->id, what, msg);
        int moved = 0;
        for (int i = 0; i < d->num_inputs && !moved; i++) {
            char quoted[80];
            snprintf(quoted, sizeof quoted, "'%s'", d->inputs[i].name);
            if (!d->inputs[i].channels && pick[i] < 3 && strstr(msg, quoted)) pick[i]++, moved = 1;
        }
        if (!moved) {
            if (!strcmp(what, "defaults")) {
                fprintf(stderr, "%s (%s): clean render failed: %s\n", d->id, what, msg);
                CHECK(0);
            }
            return;
        }
    }
}

int main(void)
{
    nprfx_context *ctx = NULL;
    /* The flow node needs a solver: a test one (unit tests do not link OpenCV). */
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.flow = &th_flow_zero;
    CHECK_OK(nprfx_context_create(&init, &ctx));
    int n = nprfx_node_count();
    CHECK(n > 10);
    for (int ni = 0; ni < n; ni++) {
        const nprfx_node_desc *d = nprfx_node_at(ni);
        nprfx_value *params = calloc((size_t)d->num_params + 1, sizeof *params);
        nprfx_node_defaults(d, params);
        check_config(ctx, d, params, "defaults");
        /* Every option of every choice, the others at their defaults (coherent-noise's
         * noise = input, morphology's open and close, blend's modes, ...). */
        for (int p = 0; p < d->num_params; p++) {
            const nprfx_param_desc *pd = &d->params[p];
            if (pd->type != NPRFX_PARAM_CHOICE) continue;
            for (int o = 0; pd->choices && pd->choices[o]; o++) {
                if (o == (int)pd->def[0]) continue;
                char what[128];
                snprintf(what, sizeof what, "%s = %s", pd->name, pd->choices[o]);
                nprfx_node_defaults(d, params);
                params[p].v[0] = o;
                check_config(ctx, d, params, what);
            }
        }
        /* Every length at its smallest: a footprint of the pixel alone, where a NaN has no
         * finite neighbour to fall back on (morphology at radius 0 made it an infinity). */
        for (int p = 0; p < d->num_params; p++) {
            const nprfx_param_desc *pd = &d->params[p];
            if (!(pd->flags & NPRFX_PARAM_PIXELS) || pd->type != NPRFX_PARAM_DOUBLE) continue;
            char what[128];
            snprintf(what, sizeof what, "%s = %g", pd->name, pd->hard_min);
            nprfx_node_defaults(d, params);
            params[p].v[0] = pd->hard_min;
            check_config(ctx, d, params, what);
        }
        free(params);
    }
    /* The test tests something: every node ran with every input bad in three ways. */
    CHECK(tested_runs >= 3 * n);
    printf("%d runs with a bad pixel over %d nodes, %d refused\n", tested_runs, n, refused);
    nprfx_context_destroy(ctx);
    return check_finish();
}
