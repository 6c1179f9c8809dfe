/* The morphology node: grey-scale dilation (max) and erosion (min) over a disc or square
 * footprint, and their compositions open and close (Haralick et al. 1987) — the dilate/erode
 * texture step of Kass & Pesare's Figure 3a. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/node.h"

enum { IN_IMAGE, IN_COUNT };
enum { P_OPERATION, P_RADIUS, P_FOOTPRINT, P_COUNT };
enum { OP_DILATE, OP_ERODE, OP_OPEN, OP_CLOSE, OP_COUNT };
enum { FP_DISC, FP_SQUARE, FP_COUNT };

static const char *const op_names[] = {"dilate", "erode", "open", "close", NULL};
static const char *const op_help[] = {"max over the footprint", "min over the footprint",
                                      "erode then dilate: removes bright specks smaller than "
                                      "the footprint",
                                      "dilate then erode: fills dark specks smaller than the "
                                      "footprint",
                                      NULL};
static const char *const fp_names[] = {"disc", "square", NULL};
static const char *const fp_help[] = {"offsets with dx^2 + dy^2 <= radius^2",
                                      "offsets with |dx|, |dy| <= radius", NULL};

static const nprfx_input_desc inputs[IN_COUNT] = {
    {"image", "Image", "The image to filter; every channel on its own.", NULL, 0, NPRFX_INPUT_MAIN,
     0, 0},
};

static const nprfx_param_desc params[P_COUNT] = {
    {"operation",
     "Operation",
     "The morphological operation.",
     NPRFX_PARAM_CHOICE,
     {OP_DILATE},
     0,
     OP_COUNT - 1,
     0,
     OP_COUNT - 1,
     op_names,
     op_help,
     NULL,
     0},
    {"radius",
     "Radius",
     "Footprint radius in pixels (fractional radii pick the integer offsets inside). 0 copies.",
     NPRFX_PARAM_DOUBLE,
     {1},
     0,
     8,
     0,
     256,
     NULL,
     NULL,
     NULL,
     NPRFX_PARAM_PIXELS},
    {"footprint",
     "Footprint",
     "Shape of the structuring element.",
     NPRFX_PARAM_CHOICE,
     {FP_DISC},
     0,
     FP_COUNT - 1,
     0,
     FP_COUNT - 1,
     fp_names,
     fp_help,
     NULL,
     0},
};

typedef struct morph_job {
    const nprfx_image *src;
    nprfx_image *dst;
    nprfx_rect area, clampr; /* pixels to write; reads clamp to clampr */
    int R;
    const int *half; /* half[dy + R]: half-width of the footprint row dy (-1: empty) */
    int dilate;
} morph_job;

static void morph_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const morph_job *j = user;
    int C = j->dst->channels;
    for (int y = j->area.y0 + begin; y < j->area.y0 + end; y++)
        for (int x = j->area.x0; x < j->area.x1; x++) {
            float acc[NPRFX_MAX_CHANNELS];
            for (int c = 0; c < C; c++)
                acc[c] = j->dilate ? -INFINITY : INFINITY;
            for (int dy = -j->R; dy <= j->R; dy++) {
                int hw = j->half[dy + j->R];
                if (hw < 0) continue;
                int yy = y + dy;
                yy =
                    yy < j->clampr.y0 ? j->clampr.y0 : (yy >= j->clampr.y1 ? j->clampr.y1 - 1 : yy);
                for (int dx = -hw; dx <= hw; dx++) {
                    int xx = x + dx;
                    xx = xx < j->clampr.x0 ? j->clampr.x0
                                           : (xx >= j->clampr.x1 ? j->clampr.x1 - 1 : xx);
                    const float *s = nprfx_image_at(j->src, xx, yy);
                    for (int c = 0; c < C; c++) {
                        /* fmaxf/fminf ignore NaN rather than spreading it */
                        acc[c] = j->dilate ? fmaxf(acc[c], s[c]) : fminf(acc[c], s[c]);
                    }
                }
            }
            float *d = nprfx_image_at(j->dst, x, y);
            for (int c = 0; c < C; c++)
                d[c] = acc[c];
        }
}

static void morph_pass(nprfx_context *ctx, const nprfx_image *src, nprfx_image *dst,
                       nprfx_rect area, nprfx_rect clampr, int R, const int *half, int dilate)
{
    morph_job j = {src, dst, area, clampr, R, half, dilate};
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(area), 8, morph_rows, &j);
}

static nprfx_result morph_render(const nprfx_render_args *args, const void *typed)
{
    if (!args || args->size < sizeof(nprfx_render_args) || !args->inputs || !args->params ||
        !args->output)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "morphology: incomplete render arguments");
    nprfx_context *ctx = args->ctx;
    const nprfx_image *img = &args->inputs[IN_IMAGE];
    const nprfx_value *pv = args->params;
    int op = (int)pv[P_OPERATION].v[0], fp = (int)pv[P_FOOTPRINT].v[0];
    double radius = pv[P_RADIUS].v[0];
    if (op < 0 || op >= OP_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "morphology.operation: no operation %d",
                           op);
    if (fp < 0 || fp >= FP_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "morphology.footprint: no footprint %d",
                           fp);
    if (!(radius >= 0.0 && radius <= 4096.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "morphology.radius: %g is outside [0, 4096]", radius);
    if (!img->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "morphology: input 'image' is not connected");
    if (args->output->channels != img->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "morphology: output has %d channels, input 'image' %d",
                           args->output->channels, img->channels);
    /* Reads clamp to the frame (within the input's data): the same for every tile. */
    nprfx_rect clampr = nprfx_rect_intersect(img->bounds, args->frame);
    if (nprfx_rect_empty(clampr))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "morphology: input 'image' is empty");
    int R = (int)floor(radius + 1e-9);
    int *half = malloc(sizeof(int) * (size_t)(2 * R + 1));
    if (!half) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "morphology: out of memory");
    for (int dy = -R; dy <= R; dy++)
        half[dy + R] =
            fp == FP_SQUARE ? R : (int)floor(sqrt(fmax(0.0, radius * radius - dy * dy)) + 1e-9);
    nprfx_result r = NPRFX_OK;
    nprfx_rect win = args->window;
    if (op == OP_DILATE || op == OP_ERODE) {
        morph_pass(ctx, img, args->output, win, clampr, R, half, op == OP_DILATE);
    } else {
        /* The first operation over the window grown by the footprint, so that tiles agree. */
        nprfx_rect grown = nprfx_rect_intersect(
            nprfx_rect_make(win.x0 - R, win.y0 - R, win.x1 + R, win.y1 + R), clampr);
        nprfx_image tmp;
        if ((r = nprfx_image_alloc(ctx, grown, img->channels, &tmp)) == NPRFX_OK) {
            int first_dilate = op == OP_CLOSE;
            morph_pass(ctx, img, &tmp, grown, clampr, R, half, first_dilate);
            /* Reads of the second pass clamp to `grown`, which equals clampr wherever the
             * footprint of a window pixel can reach. */
            morph_pass(ctx, &tmp, args->output, win, grown, R, half, !first_dilate);
            nprfx_image_free(&tmp);
        }
    }
    free(half);
    return r;
}

const nprfx_node_desc nprfx_node_morphology = {
    sizeof(nprfx_node_desc),
    "morphology",
    "Morphology",
    "Filter",
    "Grey-scale mathematical morphology per channel: dilate (max over the footprint), erode "
    "(min), open (erode then dilate) and close (dilate then erode), with a disc or square "
    "footprint of the given radius. Kass & Pesare's Figure 3a runs a dilation and an erosion over "
    "quantised shading plus smoothed coherent noise to make a painterly texture that moves with "
    "the objects. Pixels outside the frame repeat the edge.",
    inputs,
    IN_COUNT,
    params,
    P_COUNT,
    0,
    NULL,
    0,
    morph_render,
    NULL,
};
