/* The time-offset node: an input as it is at another frame (Nuke's TimeOffset). Handy for
 * comparing a frame with its neighbours in a graph, e.g. warping frame i-1 onto frame i along the
 * motion vectors to check their convention. The frame arithmetic and the copy live in
 * core/motion/time_offset.c; this file is the descriptor and the call into it. */
#include <stddef.h>

#include "nprfx/node.h"
#include "nprfx/time_offset.h"

enum { IN_IMAGE = NPRFX_TIME_OFFSET_IN_IMAGE, IN_COUNT = NPRFX_TIME_OFFSET_IN_COUNT };
enum { P_OFFSET, P_COUNT };
typedef nprfx_time_offset_params top;

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
     NPRFX_FIELD(top, offset),
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

static nprfx_result time_offset_render(const nprfx_render_args *a, const void *params)
{
    return nprfx_time_offset_render(a, params);
}

/* The one other frame it shows (nprfx_node_frames_needed adds the frame itself). */
static int time_offset_frames_needed(const void *params, const nprfx_frames_query *q, int input,
                                     nprfx_frame_range *ranges)
{
    (void)input;
    const top *p = params;
    int f = (int)nprfx_time_offset_frame(q->time, p->offset, q->first_frame, q->last_frame);
    ranges[0].first = ranges[0].last = f;
    return 1;
}

const nprfx_node_desc nprfx_node_time_offset = {
    .size = sizeof(nprfx_node_desc),
    .id = "time-offset",
    .label = "Time Offset",
    .group = "Time",
    .help = "Outputs its input as it is at another frame: out_i = image_{i + offset}. The runner "
            "fetches and caches the other frame; in a host it is a temporal clip access."
            "\n\nNaN and infinities (docs/design.md §2.2): "
            "Values pass through unchanged, NaN and infinities included, at the shifted frame.",
    .inputs = inputs,
    .num_inputs = IN_COUNT,
    .params = params,
    .num_params = P_COUNT,
    .flags = NPRFX_NODE_TEMPORAL | NPRFX_NODE_NEEDS_OTHER_FRAMES,
    .render = time_offset_render,
    .params_size = sizeof(top),
    .version_major = 1,
    .frames_needed = time_offset_frames_needed,
};
