/* Frames needed: what nprfx_node_frames_needed declares for a frame is exactly the set of frames
 * the node fetches when it renders that frame with an empty cache — no fewer (a host would not
 * have them ready) and no more (a host would render upstream frames for nothing, such as
 * coherent-noise asking for the whole shot). Each case renders with a fetch callback that records
 * every (input, frame) and compares with the declaration; plus hand-computed spans for the
 * recursion's start, window and symmetric end, the default rule and unconnected inputs. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "flow_test_provider.h"
#include "node_harness.h"
#include "nprfx/node.h"

#define W 12
#define H 8
#define MAX_IN 8
#define SHOT_FIRST 1
#define SHOT_LAST 9

/* fetched[k][f]: input k was read at frame f (1-based frames up to 15) */
static int fetched[MAX_IN][16];
static nprfx_image images[MAX_IN];

static nprfx_result record_fetch(void *user, int input, double time, nprfx_image *out)
{
    (void)user;
    int f = (int)time;
    if (input >= 0 && input < MAX_IN && f >= 0 && f < 16) fetched[input][f] = 1;
    if (!images[input].data) return NPRFX_ERR_MISSING_INPUT;
    *out = images[input];
    return NPRFX_OK;
}

static void set_param(nprfx_context *ctx, const nprfx_node_desc *d, nprfx_value *v,
                      const char *name, const char *text)
{
    int i = th_param(d, name);
    if (nprfx_param_parse(ctx, d, &d->params[i], text, &v[i]) != NPRFX_OK) {
        fprintf(stderr, "test: %s.%s = %s refused: %s\n", d->id, name, text, th_error(ctx));
        exit(2);
    }
}

/* Render frame t of the shot with inputs `connected` (input names, NULL-terminated) and compare,
 * per input, the frames read with the frames declared. Returns the declared ranges of input
 * `report` in *out (count in *nout) for span checks. */
static void run_case(nprfx_context *ctx, const char *what, const nprfx_node_desc *d,
                     const nprfx_value *values, const char *const *connected, int t,
                     const char *report, nprfx_frame_range *out, int *nout)
{
    memset(fetched, 0, sizeof fetched);
    int channels[MAX_IN] = {0};
    for (int k = 0; k < d->num_inputs; k++) {
        images[k].data = NULL;
        for (int j = 0; connected[j]; j++)
            if (!strcmp(connected[j], d->inputs[k].name)) {
                int ch = d->inputs[k].channels > 0 ? d->inputs[k].channels : 1;
                float *px = calloc((size_t)W * H * (size_t)ch, sizeof *px);
                for (int i = 0; i < W * H * ch; i++)
                    px[i] = 1.0f + (float)(i % 5) * 0.1f; /* depth-like, no background */
                images[k] = th_image(W, H, ch, px);
                free(px);
                channels[k] = ch;
            }
    }
    nprfx_output_info oi;
    CHECK_OK(nprfx_node_output_info(ctx, d, values, channels, &oi));
    nprfx_image out_im = th_image(W, H, oi.channels, NULL);
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = d;
    a.time = t;
    a.render_scale = 1;
    a.frame = out_im.bounds;
    a.window = out_im.bounds;
    a.first_frame = SHOT_FIRST;
    a.last_frame = SHOT_LAST;
    a.inputs = images;
    a.params = values;
    a.output = &out_im;
    a.fetch = record_fetch;
    void *state = NULL;
    a.state = &state;
    nprfx_result r = nprfx_node_render(&a);
    if (r) fprintf(stderr, "%s: render failed: %s\n", what, th_error(ctx));
    CHECK(r == NPRFX_OK);
    /* the render's own inputs are frame t */
    for (int k = 0; k < d->num_inputs; k++)
        if (images[k].data) fetched[k][t] = 1;
    nprfx_frames_query q = {t, SHOT_FIRST, SHOT_LAST, channels};
    for (int k = 0; k < d->num_inputs; k++) {
        nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
        int n = -1;
        CHECK_OK(nprfx_node_frames_needed(ctx, d, values, &q, k, rg, &n));
        int declared[16] = {0};
        for (int i = 0; i < n; i++)
            for (int f = rg[i].first; f <= rg[i].last; f++)
                if (f >= 0 && f < 16) declared[f] = 1;
        int same = !memcmp(declared, fetched[k], sizeof declared);
        if (!same) {
            fprintf(stderr, "%s: input %s: declared", what, d->inputs[k].name);
            for (int f = 0; f < 16; f++)
                if (declared[f]) fprintf(stderr, " %d", f);
            fprintf(stderr, ", read");
            for (int f = 0; f < 16; f++)
                if (fetched[k][f]) fprintf(stderr, " %d", f);
            fprintf(stderr, "\n");
        }
        CHECK(same);
        if (!images[k].data) CHECK(n == 0); /* nothing on unconnected inputs */
        if (report && !strcmp(report, d->inputs[k].name)) {
            memcpy(out, rg, sizeof rg);
            *nout = n;
        }
    }
    if (d->state_free && state) d->state_free(state);
    nprfx_image_free(&out_im);
    for (int k = 0; k < d->num_inputs; k++)
        if (images[k].data) nprfx_image_free(&images[k]);
}

static void coherent_noise(nprfx_context *ctx)
{
    const nprfx_node_desc *d = nprfx_node_find("coherent-noise");
    nprfx_value v[64];
    nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
    int n = 0;
    const char *basic[] = {"depth", "motion_prev", NULL};
    const char *all[] = {"depth", "motion_prev", "motion_next", "zvel", "source", NULL};

    nprfx_node_defaults(d, v);
    set_param(ctx, d, v, "noise", "white");
    run_case(ctx, "causal", d, v, basic, 6, "depth", rg, &n);
    CHECK(n == 1 && rg[0].first == SHOT_FIRST && rg[0].last == 6); /* start..t, not the shot */
    run_case(ctx, "causal, all inputs", d, v, all, 6, "motion_next", rg, &n);
    CHECK(n == 1 && rg[0].first == 6 && rg[0].last == 6); /* read at t only when causal */

    set_param(ctx, d, v, "window", "2");
    run_case(ctx, "causal, window 2", d, v, all, 6, "zvel", rg, &n);
    CHECK(n == 1 && rg[0].first == 5 && rg[0].last == 6); /* steps 5 and 6 read zvel */

    set_param(ctx, d, v, "window", "0");
    set_param(ctx, d, v, "start", "3");
    run_case(ctx, "causal, start 3", d, v, all, 5, "depth", rg, &n);
    CHECK(n == 1 && rg[0].first == 3 && rg[0].last == 5);
    run_case(ctx, "causal, start 3, frame 2", d, v, all, 2, "depth", rg, &n);
    CHECK(n == 1 && rg[0].first == 2 && rg[0].last == 2); /* before the start: the frame only */

    set_param(ctx, d, v, "start", "1");
    set_param(ctx, d, v, "mode", "symmetric");
    run_case(ctx, "symmetric", d, v, all, 4, "depth", rg, &n);
    CHECK(n == 1 && rg[0].first == SHOT_FIRST && rg[0].last == SHOT_LAST);
    run_case(ctx, "symmetric", d, v, all, 4, "motion_prev", rg, &n);
    CHECK(n == 1 && rg[0].first == SHOT_FIRST && rg[0].last == 4);
    set_param(ctx, d, v, "window", "2");
    run_case(ctx, "symmetric, window 2", d, v, all, 4, "motion_next", rg, &n);
    CHECK(n == 1 && rg[0].first == 4 && rg[0].last == 6);
    run_case(ctx, "symmetric, window 2, last frame", d, v, all, SHOT_LAST, "depth", rg, &n);

    nprfx_node_defaults(d, v);
    set_param(ctx, d, v, "noise", "input");
    run_case(ctx, "noise input", d, v, all, 3, "source", rg, &n);
    CHECK(n == 1 && rg[0].first == SHOT_FIRST && rg[0].last == 3);
}

static void tone(nprfx_context *ctx)
{
    const nprfx_node_desc *d = nprfx_node_find("tone");
    nprfx_value v[64];
    nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
    int n = 0;
    const char *all[] = {"tone", "albedo", "coverage", NULL};
    nprfx_node_defaults(d, v);
    set_param(ctx, d, v, "range", "shot");
    run_case(ctx, "tone shot", d, v, all, 4, "coverage", rg, &n);
    CHECK(n == 1 && rg[0].first == SHOT_FIRST && rg[0].last == SHOT_LAST);
    set_param(ctx, d, v, "range", "frame");
    set_param(ctx, d, v, "reference_frame", "7");
    run_case(ctx, "tone frame", d, v, all, 2, "tone", rg, &n);
    CHECK(n == 2 && rg[0].first == 2 && rg[0].last == 2 && rg[1].first == 7 && rg[1].last == 7);
    set_param(ctx, d, v, "range", "manual");
    run_case(ctx, "tone manual", d, v, all, 2, "albedo", rg, &n);
    CHECK(n == 1 && rg[0].first == 2 && rg[0].last == 2);
}

static void time_offset(nprfx_context *ctx)
{
    const nprfx_node_desc *d = nprfx_node_find("time-offset");
    nprfx_value v[8];
    nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
    int n = 0;
    const char *img[] = {"image", NULL};
    nprfx_node_defaults(d, v);
    set_param(ctx, d, v, "offset", "3");
    run_case(ctx, "time-offset +3", d, v, img, 2, "image", rg, &n);
    CHECK(n == 2 && rg[0].first == 2 && rg[0].last == 2 && rg[1].first == 5 && rg[1].last == 5);
    run_case(ctx, "time-offset +3 held at the end", d, v, img, 8, "image", rg, &n);
    CHECK(n == 1 && rg[0].first == 8 && rg[0].last == 9); /* adjacent frames merge */
    CHECK((d->flags & NPRFX_NODE_NEEDS_OTHER_FRAMES) != 0);
}

/* flow: the neighbours within the shot, one at its ends. */
static void flow(nprfx_context *ctx)
{
    const nprfx_node_desc *d = nprfx_node_find("flow");
    nprfx_value v[8];
    nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
    int n = 0;
    const char *img[] = {"image", NULL};
    nprfx_node_defaults(d, v);
    run_case(ctx, "flow", d, v, img, 5, "image", rg, &n);
    CHECK(n == 1 && rg[0].first == 4 && rg[0].last == 6);
    run_case(ctx, "flow at the first frame", d, v, img, SHOT_FIRST, "image", rg, &n);
    CHECK(n == 1 && rg[0].first == SHOT_FIRST && rg[0].last == SHOT_FIRST + 1);
    run_case(ctx, "flow at the last frame", d, v, img, SHOT_LAST, "image", rg, &n);
    CHECK(n == 1 && rg[0].first == SHOT_LAST - 1 && rg[0].last == SHOT_LAST);
    CHECK((d->flags & NPRFX_NODE_NEEDS_OTHER_FRAMES) != 0);
}

/* The default rule, for a node without its own answer, and errors. */
static void defaults(nprfx_context *ctx)
{
    const nprfx_node_desc *d = nprfx_node_find("blend");
    nprfx_value v[64];
    nprfx_node_defaults(d, v);
    int channels[MAX_IN] = {3, 3, 1, 0, 0, 0, 0, 0};
    nprfx_frames_query q = {5, SHOT_FIRST, SHOT_LAST, channels};
    nprfx_frame_range rg[NPRFX_MAX_FRAME_RANGES];
    int n = -1;
    CHECK_OK(nprfx_node_frames_needed(ctx, d, v, &q, 0, rg, &n));
    CHECK(n == 1 && rg[0].first == 5 && rg[0].last == 5);
    channels[0] = 0;
    CHECK_OK(nprfx_node_frames_needed(ctx, d, v, &q, 0, rg, &n));
    CHECK(n == 0);
    CHECK(nprfx_node_frames_needed(ctx, d, v, &q, 99, rg, &n) == NPRFX_ERR_INVALID_ARGUMENT);
    /* a param out of range is refused with its name, as for render */
    const nprfx_node_desc *cn = nprfx_node_find("coherent-noise");
    nprfx_node_defaults(cn, v);
    v[th_param(cn, "alpha")].v[0] = 7;
    channels[0] = 1;
    CHECK(nprfx_node_frames_needed(ctx, cn, v, &q, 0, rg, &n) != NPRFX_OK);
    CHECK(strstr(th_error(ctx), "alpha") != NULL);
    /* every node that needs other frames is temporal */
    for (int i = 0; i < nprfx_node_count(); i++) {
        const nprfx_node_desc *x = nprfx_node_at(i);
        if (x->flags & NPRFX_NODE_NEEDS_OTHER_FRAMES) CHECK(x->flags & NPRFX_NODE_TEMPORAL);
    }
}

int main(void)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.flow = &th_flow_zero; /* the flow node's solver (no OpenCV in unit tests) */
    CHECK_OK(nprfx_context_create(&init, &ctx));
    coherent_noise(ctx);
    tone(ctx);
    time_offset(ctx);
    flow(ctx);
    defaults(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
