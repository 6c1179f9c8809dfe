/* Descriptors and the shared render path: every registered node passes the descriptor lint; the
 * lint catches each kind of mistake it promises to; nprfx_node_render binds every param type at
 * its offset, does the shared checks once (with messages that name the node, input or param) and
 * keeps the size-versioned promise for older, shorter render args. */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "node_harness.h"
#include "nprfx/node.h"

/* ---- a test node whose render records what it was given ---- */

typedef struct probe_params {
    double gain;
    int count;
    int on;
    int mode;
    double tint[4];
    const char *label;
} probe_params;

static probe_params seen;
static int renders;
static const long long *seen_items;

static const char *const probe_modes[] = {"first", "second", "third", NULL};

static const nprfx_input_desc probe_inputs[] = {
    {.name = "image", .label = "Image", .help = "Any image.", .flags = NPRFX_INPUT_MAIN},
    {.name = "uv",
     .label = "UV",
     .help = "Two channels.",
     .channels = 2,
     .flags = NPRFX_INPUT_OPTIONAL},
};

static nprfx_param_desc probe_params_desc[] = {
    {.name = "gain",
     NPRFX_FIELD(probe_params, gain),
     .label = "Gain",
     .help = "A double.",
     .type = NPRFX_PARAM_DOUBLE,
     .def = {0.5},
     .soft_min = 0,
     .soft_max = 1,
     .hard_min = 0,
     .hard_max = 2},
    {.name = "count",
     NPRFX_FIELD(probe_params, count),
     .label = "Count",
     .help = "An int.",
     .type = NPRFX_PARAM_INT,
     .def = {3},
     .soft_min = 0,
     .soft_max = 10,
     .hard_min = -5,
     .hard_max = 100},
    {.name = "on",
     NPRFX_FIELD(probe_params, on),
     .label = "On",
     .help = "A bool.",
     .type = NPRFX_PARAM_BOOL,
     .def = {1},
     .hard_max = 1},
    {.name = "mode",
     NPRFX_FIELD(probe_params, mode),
     .label = "Mode",
     .help = "A choice.",
     .type = NPRFX_PARAM_CHOICE,
     .def = {1},
     NPRFX_CHOICE_RANGE(3),
     .choices = probe_modes},
    {.name = "tint",
     NPRFX_FIELD(probe_params, tint),
     .label = "Tint",
     .help = "A colour.",
     .type = NPRFX_PARAM_COLOR,
     .def = {0.1, 0.2, 0.3, 1},
     .soft_max = 1,
     .hard_max = 1},
    {.name = "label",
     NPRFX_FIELD(probe_params, label),
     .label = "Label",
     .help = "A string.",
     .type = NPRFX_PARAM_STRING,
     .def_string = "hello"},
};
#define PROBE_NPARAMS ((int)(sizeof probe_params_desc / sizeof probe_params_desc[0]))

static nprfx_result probe_render(const nprfx_render_args *args, const void *params)
{
    renders++;
    seen = *(const probe_params *)params;
    seen_items = args->items;
    return NPRFX_OK;
}

static nprfx_node_desc probe = {
    .size = sizeof(nprfx_node_desc),
    .id = "probe",
    .label = "Probe",
    .group = "Test",
    .help = "Records its params.",
    .inputs = probe_inputs,
    .num_inputs = 2,
    .params = probe_params_desc,
    .num_params = PROBE_NPARAMS,
    .render = probe_render,
    .params_size = sizeof(probe_params),
    .version_major = 1,
};

static nprfx_render_args probe_args(nprfx_context *ctx, nprfx_image *in, nprfx_value *pv,
                                    nprfx_image *out, long long *items)
{
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = ctx;
    a.node = &probe;
    a.time = 1;
    a.render_scale = 1;
    a.frame = out->bounds;
    a.window = out->bounds;
    a.inputs = in;
    a.params = pv;
    a.output = out;
    a.items = items;
    return a;
}

static void test_binding(nprfx_context *ctx)
{
    CHECK_OK(nprfx_node_lint(ctx, &probe));
    nprfx_image in[2] = {th_image(4, 3, 3, NULL), {0}};
    nprfx_image out = th_image(4, 3, 3, NULL);
    nprfx_value pv[PROBE_NPARAMS];
    nprfx_node_defaults(&probe, pv);
    long long items = 0;
    nprfx_render_args a = probe_args(ctx, in, pv, &out, &items);

    /* defaults arrive typed, each at its own offset */
    CHECK_OK(nprfx_node_render(&a));
    CHECK(renders == 1);
    CHECK(seen.gain == 0.5 && seen.count == 3 && seen.on == 1 && seen.mode == 1);
    CHECK(seen.tint[0] == 0.1 && seen.tint[1] == 0.2 && seen.tint[2] == 0.3 && seen.tint[3] == 1);
    CHECK(seen.label && strcmp(seen.label, "hello") == 0);
    CHECK(seen_items == &items);

    /* values parsed from text, as the runner and hosts give them */
    CHECK_OK(nprfx_param_parse(ctx, &probe, &probe_params_desc[0], "1.75", &pv[0]));
    CHECK_OK(nprfx_param_parse(ctx, &probe, &probe_params_desc[1], "-5", &pv[1]));
    CHECK_OK(nprfx_param_parse(ctx, &probe, &probe_params_desc[2], "off", &pv[2]));
    CHECK_OK(nprfx_param_parse(ctx, &probe, &probe_params_desc[3], "third", &pv[3]));
    CHECK_OK(nprfx_param_parse(ctx, &probe, &probe_params_desc[4], "1, 0.5, 0.25", &pv[4]));
    CHECK_OK(nprfx_param_parse(ctx, &probe, &probe_params_desc[5], "", &pv[5]));
    CHECK_OK(nprfx_node_render(&a));
    CHECK(seen.gain == 1.75 && seen.count == -5 && seen.on == 0 && seen.mode == 2);
    CHECK(seen.tint[0] == 1 && seen.tint[1] == 0.5 && seen.tint[2] == 0.25 && seen.tint[3] == 1);
    CHECK(seen.label && seen.label[0] == 0);

    /* a value outside the hard range never reaches the node, and the message names the param */
    pv[0].v[0] = 2.5;
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "probe.gain") != NULL);
    pv[0].v[0] = 1;
    pv[1].v[0] = 2.5; /* not whole */
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "probe.count") != NULL);
    pv[1].v[0] = 2;
    pv[3].v[0] = 3; /* no fourth option */
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_OUT_OF_RANGE);
    CHECK(strstr(th_error(ctx), "probe.mode") != NULL);
    pv[3].v[0] = 0;
    CHECK(renders == 2);

    /* the shared input and output checks */
    nprfx_image none = in[0];
    in[0].data = NULL;
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_MISSING_INPUT);
    CHECK(strstr(th_error(ctx), "probe: input 'image' is not connected") != NULL);
    in[0] = none;
    in[1] = th_image(4, 3, 3, NULL); /* uv wants 2 channels */
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "input 'uv' has 3 channels, expected 2") != NULL);
    nprfx_image_free(&in[1]);
    memset(&in[1], 0, sizeof in[1]);
    nprfx_image wrong = th_image(4, 3, 1, NULL);
    a.output = &wrong;
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(strstr(th_error(ctx), "output has 1 channels, expected 3") != NULL);
    a.output = &out;
    a.params = NULL;
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_INVALID_ARGUMENT);
    a.params = pv;
    CHECK(nprfx_node_render(NULL) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(renders == 2);

    /* windows are cut to the output; an empty one renders nothing */
    a.window = nprfx_rect_make(2, 1, 40, 30);
    CHECK_OK(nprfx_node_render(&a));
    CHECK(renders == 3);
    a.window = nprfx_rect_make(10, 10, 20, 20);
    CHECK_OK(nprfx_node_render(&a));
    CHECK(renders == 3);
    a.window = out.bounds;

    /* older callers: v1-sized args (no items) are accepted, the node sees items as NULL; a
     * struct shorter than any release is refused */
    a.size = NPRFX_RENDER_ARGS_SIZE_V1;
    CHECK_OK(nprfx_node_render(&a));
    CHECK(renders == 4 && seen_items == NULL);
    a.size = NPRFX_RENDER_ARGS_SIZE_V1 - 1;
    CHECK(nprfx_node_render(&a) == NPRFX_ERR_INVALID_ARGUMENT);
    CHECK(renders == 4);
    a.size = sizeof a;

    /* no export hook: a clear refusal */
    char *text = NULL;
    size_t len = 0;
    CHECK(nprfx_node_export(&a, "x.csv", &text, &len) == NPRFX_ERR_UNSUPPORTED);
    CHECK(text == NULL);

    nprfx_image_free(&in[0]);
    nprfx_image_free(&out);
    nprfx_image_free(&wrong);
}

/* Each mistake the lint promises to see, on a copy of the probe. */
static void test_lint_catches(nprfx_context *ctx)
{
    nprfx_param_desc pd[PROBE_NPARAMS];
    nprfx_node_desc d;
#define RESET()                                                                                    \
    do {                                                                                           \
        memcpy(pd, probe_params_desc, sizeof pd);                                                  \
        d = probe;                                                                                 \
        d.params = pd;                                                                             \
    } while (0)
#define EXPECT_LINT(what)                                                                          \
    do {                                                                                           \
        CHECK(nprfx_node_lint(ctx, &d) == NPRFX_ERR_INVALID_ARGUMENT);                             \
        CHECK(strstr(th_error(ctx), what) != NULL);                                                \
        if (!strstr(th_error(ctx), what)) fprintf(stderr, "  lint said: %s\n", th_error(ctx));     \
        RESET();                                                                                   \
    } while (0)
    RESET();
    CHECK_OK(nprfx_node_lint(ctx, &d));
    pd[1].name = "gain";
    EXPECT_LINT("two params named 'gain'");
    pd[0].def[0] = 3;
    EXPECT_LINT("probe.gain: the default");
    pd[0].soft_max = 5;
    EXPECT_LINT("probe.gain: ranges out of order");
    pd[3].hard_max = pd[3].soft_max = 3;
    EXPECT_LINT("probe.mode: 3 options");
    pd[2].help = "";
    EXPECT_LINT("probe.on: label or help missing");
    pd[4].name = "Tint";
    EXPECT_LINT("bad name 'Tint'");
    pd[5].offset = offsetof(probe_params, tint) + sizeof(double);
    EXPECT_LINT("share bytes");
    pd[5].offset = sizeof(probe_params);
    EXPECT_LINT("does not fit");
    d.params_size = 0;
    EXPECT_LINT("params without a typed struct");
    d.help = NULL;
    EXPECT_LINT("probe: label, group, help or render missing");
    d.version_major = 0;
    EXPECT_LINT("version 0.0");
    d.id = "Probe Node";
    EXPECT_LINT("bad id");
#undef EXPECT_LINT
#undef RESET
}

static void test_registry(nprfx_context *ctx)
{
    int n = nprfx_node_count();
    CHECK(n >= 8);
    for (int i = 0; i < n; i++) {
        const nprfx_node_desc *d = nprfx_node_at(i);
        nprfx_result r = nprfx_node_lint(ctx, d);
        CHECK_OK(r);
        if (r) fprintf(stderr, "  %s: %s\n", d ? d->id : "?", th_error(ctx));
        for (int k = 0; k < i; k++)
            CHECK(strcmp(nprfx_node_at(k)->id, d->id) != 0);
        CHECK(nprfx_node_find(d->id) == d);
    }
}

/* The state the stateful nodes say they keep between calls (desc->state_bytes, which a runner
 * counts against its memory limit), hand-computed from each cache's layout for a 100x50 frame
 * (5000 pixels) and the default params. */
static double state_of(nprfx_context *ctx, const char *id, const char *param, double value,
                       int first, int last)
{
    const nprfx_node_desc *d = nprfx_node_find(id);
    CHECK(d != NULL);
    if (!d) return -1;
    nprfx_value pv[64];
    nprfx_node_defaults(d, pv);
    for (int i = 0; param && i < d->num_params; i++)
        if (!strcmp(d->params[i].name, param)) pv[i].v[0] = value;
    int in_ch[32] = {0};
    nprfx_state_query q = {100, 50, first, last, in_ch};
    double bytes = -1;
    CHECK_OK(nprfx_node_state_bytes(ctx, d, pv, &q, &bytes));
    return bytes;
}

static void test_state_bytes(nprfx_context *ctx)
{
    /* paper: one colour window, 4 floats a pixel */
    CHECK(state_of(ctx, "paper", NULL, 0, 1, 10) == 5000 * 4 * 4.0);
    /* flow: 2 pairs of (two luminances, two 2-channel flows, two confidences: 8 floats; two
     * masks: 2 bytes) a pixel */
    CHECK(state_of(ctx, "flow", NULL, 0, 1, 10) == 2 * 5000 * (8 * 4 + 2.0));
    /* advect, output all (5 channels): two 2-channel layers, a 2-channel step scratch, the
     * output */
    CHECK(state_of(ctx, "advect", NULL, 0, 1, 10) == 5000 * 4 * (4 + 2 + 5.0));
    /* coherent-noise, 1 channel, shot of 16 frames, the default 1024 MB bound: a state is a float
     * and a byte a pixel (25000 B); checkpoints every 4 frames (16 / 4 + 2 slots) and a ring of
     * 4: 10 states; and 2 depth frames, the 1-channel result */
    CHECK(state_of(ctx, "coherent-noise", NULL, 0, 1, 16) == 10 * 25000 + 2 * 20000 + 20000.0);
    /* cache_mb 0: the current state only */
    CHECK(state_of(ctx, "coherent-noise", "cache_mb", 0, 1, 16) == 25000 + 2 * 20000 + 20000.0);
    /* a bound of 1 MB holds 41 states of 25000 B: two slots for the ring and checkpoints every
     * ceil(1000 / 40) = 25 frames of a 1000-frame shot (42 slots): 43 states */
    CHECK(state_of(ctx, "coherent-noise", "cache_mb", 1, 1, 1000) ==
          43 * 25000 + 2 * 20000 + 20000.0);
    /* a node without a cache keeps nothing */
    CHECK(state_of(ctx, "blend", NULL, 0, 1, 10) == 0);
}

int main(void)
{
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    test_binding(ctx);
    test_lint_catches(ctx);
    test_registry(ctx);
    test_state_bytes(ctx);
    nprfx_context_destroy(ctx);
    return check_finish();
}
