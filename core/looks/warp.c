/* The displacement warp: out(p) = image(p + amount * offset(p)), sampled bilinearly or with the
 * Catmull-Rom bicubic of core/base/sample.c — the local image-plane warp of Kass & Pesare's Figure 3a,
 * driven by two channels of coherent noise (docs/design.md §3.8). See nprfx/filter.h. */
#include "nprfx/exec.h"
#include "nprfx/filter.h"

typedef struct warp_job {
    const nprfx_image *image, *offset;
    nprfx_image *out;
    nprfx_rect window;
    double amount, reach;
    int bicubic;
    nprfx_border border;
} warp_job;

static void warp_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const warp_job *j = user;
    float tmp[NPRFX_MAX_CHANNELS];
    int C = j->out->channels;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++)
        for (int x = j->window.x0; x < j->window.x1; x++) {
            double dx = 0.0, dy = 0.0;
            if (nprfx_rect_contains(j->offset->bounds, x, y)) {
                const float *o = nprfx_image_at(j->offset, x, y);
                dx = o[0];
                dy = o[1];
            }
            double mx = j->amount * dx, my = j->amount * dy;
            float *dst = nprfx_image_at(j->out, x, y);
            if (!(mx == mx) || !(my == my)) /* NaN offset: leave the pixel where it is */
                mx = my = 0.0;
            if (j->reach > 0.0) { /* bounded: what a strip of rows can be rendered from */
                mx = mx < -j->reach ? -j->reach : mx > j->reach ? j->reach : mx;
                my = my < -j->reach ? -j->reach : my > j->reach ? j->reach : my;
            }
            double sx = x + mx, sy = y + my;
            if (j->bicubic)
                nprfx_sample_bicubic(j->image, sx, sy, j->border, tmp);
            else
                nprfx_sample_bilinear(j->image, sx, sy, j->border, tmp);
            for (int c = 0; c < C; c++)
                dst[c] = tmp[c];
        }
}

nprfx_result nprfx_warp_render(const nprfx_render_args *args, const nprfx_warp_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const nprfx_image *image = nprfx_render_input(args, NPRFX_WARP_IN_IMAGE);
    const nprfx_image *offset = nprfx_render_input(args, NPRFX_WARP_IN_OFFSET);
    nprfx_rect window = args->window;
    nprfx_image *out = args->output;
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "warp: no params or output");
    if (p->filter < 0 || p->filter >= NPRFX_WARP_FILTER_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "warp.filter: no filter %d", p->filter);
    if (p->border != NPRFX_BORDER_CLAMP && p->border != NPRFX_BORDER_BLACK)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "warp.border: no border mode %d",
                           p->border);
    if (!image || !image->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "warp: input 'image' is not connected");
    if (!offset || !offset->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "warp: input 'offset' is not connected");
    if (offset->channels < 2)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "warp: input 'offset' has %d channel(s), needs 2", offset->channels);
    if (out->channels != image->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "warp: output has %d channels, input 'image' %d", out->channels,
                           image->channels);
    if (!(p->reach >= 0.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "warp.reach: %g is negative", p->reach);
    if (nprfx_rect_empty(image->bounds))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "warp: input 'image' is empty");
    warp_job j = {image,
                  offset,
                  out,
                  window,
                  p->amount,
                  p->reach,
                  p->filter == NPRFX_WARP_BICUBIC,
                  (nprfx_border)p->border};
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(window), 8, warp_rows, &j);
    return NPRFX_OK;
}
