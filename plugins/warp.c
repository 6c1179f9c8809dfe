/* The warp node: displaces an image by two channels, out(p) = image(p + amount * offset(p)) — the
 * local image-plane warp of Kass & Pesare's Figure 3a, driven by two channels of coherent noise. */
#include <string.h>

#include "nprfx/filter.h"
#include "nprfx/node.h"

enum { IN_IMAGE, IN_OFFSET, IN_COUNT };
enum { P_AMOUNT, P_FILTER, P_BORDER, P_COUNT };
enum { FILTER_BILINEAR, FILTER_BICUBIC, FILTER_COUNT };
enum { BORDER_CLAMP, BORDER_BLACK, BORDER_COUNT };

static const char *const filter_names[] = {"bilinear", "bicubic", NULL};
static const char *const filter_help[] = {"2x2 taps, never overshoots",
                                          "Catmull-Rom 4x4 taps, sharper, may overshoot", NULL};
static const char *const border_names[] = {"clamp", "black", NULL};
static const char *const border_help[] = {"positions outside the image repeat its edge",
                                          "positions outside the image read zero", NULL};

static const nprfx_input_desc inputs[IN_COUNT] = {
    {"image", "Image", "The image to displace (any channel count).", NULL, 0, NPRFX_INPUT_MAIN, 0,
     0},
    {"offset", "Offset",
     "Two channels (x, y; y down) scaled by amount to give the displacement in pixels, e.g. two "
     "channels of coherent-noise. Outside its data window it reads as 0 (no displacement).",
     NULL, 2, 0, 0, 0},
};

static const nprfx_param_desc params[P_COUNT] = {
    {"amount",
     "Amount",
     "Displacement in pixels per unit of offset: out(p) = image(p + amount * offset(p)).",
     NPRFX_PARAM_DOUBLE,
     {2},
     -16,
     16,
     -4096,
     4096,
     NULL,
     NULL,
     NULL,
     NPRFX_PARAM_PIXELS},
    {"filter",
     "Filter",
     "Reconstruction filter of the displaced lookup.",
     NPRFX_PARAM_CHOICE,
     {FILTER_BILINEAR},
     0,
     FILTER_COUNT - 1,
     0,
     FILTER_COUNT - 1,
     filter_names,
     filter_help,
     NULL,
     0},
    {"border",
     "Border",
     "What lookups outside the image read.",
     NPRFX_PARAM_CHOICE,
     {BORDER_CLAMP},
     0,
     BORDER_COUNT - 1,
     0,
     BORDER_COUNT - 1,
     border_names,
     border_help,
     NULL,
     0},
};

typedef struct warp_job {
    const nprfx_image *image, *offset;
    nprfx_image *out;
    nprfx_rect window;
    double amount;
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
            double sx = x + j->amount * dx, sy = y + j->amount * dy;
            float *dst = nprfx_image_at(j->out, x, y);
            if (!(sx == sx) || !(sy == sy)) { /* NaN offset: leave the pixel where it is */
                sx = x;
                sy = y;
            }
            if (j->bicubic)
                nprfx_sample_bicubic(j->image, sx, sy, j->border, tmp);
            else
                nprfx_sample_bilinear(j->image, sx, sy, j->border, tmp);
            for (int c = 0; c < C; c++)
                dst[c] = tmp[c];
        }
}

static nprfx_result warp_render(const nprfx_render_args *args, const void *typed)
{
    if (!args || args->size < sizeof(nprfx_render_args) || !args->inputs || !args->params ||
        !args->output)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "warp: incomplete render arguments");
    nprfx_context *ctx = args->ctx;
    const nprfx_image *in = args->inputs;
    const nprfx_value *pv = args->params;
    warp_job j;
    memset(&j, 0, sizeof j);
    j.amount = pv[P_AMOUNT].v[0];
    int filter = (int)pv[P_FILTER].v[0], border = (int)pv[P_BORDER].v[0];
    if (filter < 0 || filter >= FILTER_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "warp.filter: no filter %d", filter);
    if (border < 0 || border >= BORDER_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "warp.border: no border mode %d", border);
    if (!in[IN_IMAGE].data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "warp: input 'image' is not connected");
    if (!in[IN_OFFSET].data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "warp: input 'offset' is not connected");
    if (in[IN_OFFSET].channels < 2)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "warp: input 'offset' has %d channel(s), needs 2",
                           in[IN_OFFSET].channels);
    if (args->output->channels != in[IN_IMAGE].channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "warp: output has %d channels, input 'image' %d", args->output->channels,
                           in[IN_IMAGE].channels);
    if (nprfx_rect_empty(in[IN_IMAGE].bounds))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "warp: input 'image' is empty");
    j.image = &in[IN_IMAGE];
    j.offset = &in[IN_OFFSET];
    j.out = args->output;
    j.window = args->window;
    j.bicubic = filter == FILTER_BICUBIC;
    j.border = border == BORDER_BLACK ? NPRFX_BORDER_BLACK : NPRFX_BORDER_CLAMP;
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(j.window), 8, warp_rows, &j);
    return NPRFX_OK;
}

const nprfx_node_desc nprfx_node_warp = {
    sizeof(nprfx_node_desc),
    "warp",
    "Warp",
    "Filter",
    "Displaces an image by a two-channel offset field: out(p) = image(p + amount * offset(p)), "
    "sampled with a bilinear or Catmull-Rom bicubic filter. Driven by two channels of "
    "coherent-noise it gives the wobbling, hand-made edges of Kass & Pesare's Figure 3a that "
    "stick to the moving objects.",
    inputs,
    IN_COUNT,
    params,
    P_COUNT,
    0,
    NULL,
    0,
    warp_render,
    NULL,
};
