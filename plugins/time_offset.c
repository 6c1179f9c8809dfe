/* The time-offset node: an input as it is at another frame (Nuke's TimeOffset). Handy for
 * comparing a frame with its neighbours in a graph, e.g. warping frame i-1 onto frame i along the
 * motion vectors to check their convention. */
#include <math.h>
#include <string.h>

#include "nprfx/node.h"

enum { IN_IMAGE, IN_COUNT };
enum { P_OFFSET, P_COUNT };

static const nprfx_input_desc inputs[IN_COUNT] = {
    {.name = "image",
     .label = "Image",
     .help = "The image to take from another frame (any channel count).",
     .flags = NPRFX_INPUT_MAIN | NPRFX_INPUT_TEMPORAL,
     .fetch_before = NPRFX_FETCH_UNBOUNDED,
     .fetch_after = NPRFX_FETCH_UNBOUNDED},
};

static const nprfx_param_desc params[P_COUNT] = {
    {.name = "offset",
     .label = "Offset",
     .help = "Frames to shift by: the output at frame i is the input at frame i + offset (-1: the "
             "previous frame), held at the shot's first and last frames.",
     .type = NPRFX_PARAM_INT,
     .def = {-1},
     .soft_min = -10,
     .soft_max = 10,
     .hard_min = -100000,
     .hard_max = 100000},
};

static nprfx_result time_offset_render(const nprfx_render_args *args, const void *typed)
{
    nprfx_context *ctx = args->ctx;
    int offset = (int)args->params[P_OFFSET].v[0];
    if (offset == 0) return nprfx_image_copy(ctx, &args->inputs[IN_IMAGE], args->output);
    if (!args->fetch)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "time-offset: this host cannot fetch other frames");
    /* Frames outside the shot hold its first or last frame, so frame 1 of a "previous frame"
     * graph does not ask for a frame 0 that was never rendered. */
    double t = args->time + offset;
    if (args->first_frame <= args->last_frame) {
        if (t < args->first_frame) t = args->first_frame;
        if (t > args->last_frame) t = args->last_frame;
    }
    nprfx_image other;
    nprfx_result r = args->fetch(args->fetch_user, IN_IMAGE, t, &other);
    if (r) return r;
    if (other.channels != args->output->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "time-offset: input 'image' has %d channels at frame %g but %d at %g",
                           other.channels, t, args->output->channels, args->time);
    /* Outside the other frame's data window the output is 0, as EXR readers do. */
    nprfx_image win = nprfx_image_crop(args->output, args->window);
    float zero[NPRFX_MAX_CHANNELS] = {0};
    nprfx_image_fill(&win, zero);
    other = nprfx_image_crop(&other, args->window);
    return nprfx_image_copy(ctx, &other, &win);
}

const nprfx_node_desc nprfx_node_time_offset = {
    .size = sizeof(nprfx_node_desc),
    .id = "time-offset",
    .label = "Time Offset",
    .group = "Time",
    .help = "Outputs its input as it is at another frame: out_i = image_{i + offset}. The runner "
            "fetches and caches the other frame; in a host it is a temporal clip access.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .flags = NPRFX_NODE_TEMPORAL,
    .render = time_offset_render,
};
