/* render_node.c — render one nprfx node through the installed library, nothing else needed.
 *
 * Makes a synthetic plate (the analytic "orbit" scene), thresholds its UV.U channel with the
 * threshold-map node in builtin mode, the plate's diffuse shading as the tone, and checks a few
 * pixels against the threshold formula of nprfx/threshold.h. Build it with
 *
 *     cc render_node.c $(pkg-config --cflags --libs nprfx) -o render_node
 *
 * or with CMake: find_package(nprfx) and target_link_libraries(... nprfx::nprfx). */
#include <stdio.h>
#include <string.h>

#include "nprfx/nprfx.h"
#include "nprfx/threshold.h"

static void on_error(void *user, const nprfx_context *ctx, nprfx_result code, const char *message)
{
    (void)user, (void)ctx;
    fprintf(stderr, "nprfx error (%s): %s\n", nprfx_result_name(code), message);
}

/* The plate channel called `name` as a 1-channel view (shares the plate's pixels). */
static nprfx_image plate_channel(const nprfx_image *plate, const char *name)
{
    const char *const *names = nprfx_synth_channel_names();
    for (int c = 0; c < nprfx_synth_channel_count(); c++)
        if (strcmp(names[c], name) == 0) return nprfx_image_channels(plate, c, 1);
    nprfx_image none = {0};
    return none;
}

/* Set param `name` of the node from text, as a graph file or the command line would. */
static nprfx_result set_param(nprfx_context *ctx, const nprfx_node_desc *node, nprfx_value *values,
                              const char *name, const char *text)
{
    int i = nprfx_node_param_index(node, name);
    if (i < 0) return nprfx_error(ctx, NPRFX_ERR_UNKNOWN_PARAM, "no param '%s'", name);
    return nprfx_param_parse(ctx, node, &node->params[i], text, &values[i]);
}

int main(void)
{
    enum { W = 64, H = 48, FRAME = 1 };
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.error_handler = on_error;
    nprfx_context *ctx = NULL;
    if (nprfx_context_create(&init, &ctx)) return 1;

    const nprfx_node_desc *node = nprfx_node_find("threshold-map");
    nprfx_rect frame = nprfx_rect_make(0, 0, W, H);
    nprfx_image plate = {0}, out = {0};
    nprfx_value values[16];
    int ok = node && node->num_params <= 16 &&
             !nprfx_image_alloc(ctx, frame, nprfx_synth_channel_count(), &plate) &&
             !nprfx_synth_render(ctx, "orbit", FRAME, &plate);
    if (!ok) return 1;
    printf("libnprfx %s: %d nodes; rendering '%s' (%s) at %dx%d\n", NPRFX_VERSION_STRING,
           nprfx_node_count(), node->id, node->label, W, H);

    /* Inputs in the node's declared order: pattern, tone, map (not connected: data NULL). */
    nprfx_image inputs[3] = {plate_channel(&plate, "UV.U"), plate_channel(&plate, "diffuse")};
    nprfx_node_defaults(node, values);
    ok = node->num_inputs == 3 && inputs[0].data && inputs[1].data &&
         !set_param(ctx, node, values, "mode", "builtin") &&
         !set_param(ctx, node, values, "sigma", "10");
    int in_channels[3] = {1, 1, 0};
    nprfx_output_info info;
    ok = ok && !nprfx_node_output_info(ctx, node, values, in_channels, &info) &&
         !nprfx_image_alloc(ctx, frame, info.channels, &out);

    void *state = NULL; /* the node's per-instance cache, if it keeps one */
    nprfx_render_args args = {.size = sizeof args, .ctx = ctx, .node = node};
    args.time = FRAME, args.render_scale = 1, args.frame = args.window = frame;
    args.first_frame = args.last_frame = FRAME;
    args.inputs = inputs, args.params = values, args.output = &out, args.state = &state;
    ok = ok && !nprfx_node_render(&args);

    /* Check every pixel against the formula of nprfx/threshold.h, and print three: the first
     * inked (near 0), the first on the step, the first paper (near 1). */
    double sum = 0, err = 0;
    int seen[3] = {0, 0, 0};
    for (int y = 0; ok && y < H; y++)
        for (int x = 0; x < W; x++) {
            double p = *nprfx_image_at(&inputs[0], x, y), t = *nprfx_image_at(&inputs[1], x, y);
            double got = *nprfx_image_at(&out, x, y), want = nprfx_threshold_builtin(p, t, 10);
            int kind = got < 0.01 ? 0 : got > 0.99 ? 2 : 1;
            if (!seen[kind]++)
                printf("pixel (%2d,%2d): pattern %7.4f tone %.4f -> %.6f (formula %.6f)\n", x, y, p,
                       t, got, want);
            sum += got;
            double d = got > want ? got - want : want - got;
            err = d > err ? d : err;
        }
    ok = ok && err <= 1e-6 && seen[0] && seen[1] && seen[2];
    if (ok)
        printf("output: %d channel, mean %.4f; ink %d, step %d, paper %d pixels; max error %g\n",
               out.channels, sum / (W * H), seen[0], seen[1], seen[2], err);
    if (state && node->state_free) node->state_free(state);
    nprfx_image_free(&out);
    nprfx_image_free(&plate);
    nprfx_context_destroy(ctx);
    printf("%s\n", ok ? "ok" : "FAILED");
    return ok ? 0 : 1;
}
