/* The time-offset node: an input as it is at another frame (Nuke's TimeOffset), held at the
 * shot's ends; with warp it compares a frame with its neighbour along the motion vectors
 * (docs/design.md §3.8). See nprfx/time_offset.h. */
#include "nprfx/time_offset.h"

double nprfx_time_offset_frame(double time, int offset, int first_frame, int last_frame)
{
    double t = time + offset;
    if (first_frame <= last_frame) {
        if (t < first_frame) t = first_frame;
        if (t > last_frame) t = last_frame;
    }
    return t;
}

nprfx_result nprfx_time_offset_render(const nprfx_render_args *args,
                                      const nprfx_time_offset_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const int input = NPRFX_TIME_OFFSET_IN_IMAGE;
    const nprfx_image *image = nprfx_render_input(args, input);
    double time = args->time;
    nprfx_fetch_fn fetch = args->fetch;
    nprfx_rect window = args->window;
    nprfx_image *out = args->output;
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "time-offset: no params or output");
    if (p->offset == 0) {
        if (!image || !image->data)
            return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                               "time-offset: input 'image' is not connected");
        return nprfx_image_copy(ctx, image, out);
    }
    if (!fetch)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "time-offset: this host cannot fetch other frames");
    double t = nprfx_time_offset_frame(time, p->offset, args->first_frame, args->last_frame);
    nprfx_image other;
    nprfx_result r = fetch(args->fetch_user, input, t, &other);
    if (r) return r;
    if (other.channels != out->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "time-offset: input 'image' has %d channels at frame %g but %d at %g",
                           other.channels, t, out->channels, time);
    /* Outside the other frame's data window the output is 0, as EXR readers do. */
    nprfx_image win = nprfx_image_crop(out, window);
    float zero[NPRFX_MAX_CHANNELS] = {0};
    nprfx_image_fill(&win, zero);
    other = nprfx_image_crop(&other, window);
    return nprfx_image_copy(ctx, &other, &win);
}
