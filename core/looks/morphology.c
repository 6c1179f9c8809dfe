/* Grey-scale morphology per channel: dilation (max over a flat footprint), erosion (min), and
 * their compositions open (erode then dilate) and close (dilate then erode), after Haralick,
 * Sternberg, Zhuang, "Image analysis using mathematical morphology", IEEE PAMI 9(4), 1987 — the
 * dilate/erode texture step of Kass & Pesare's Figure 3a (docs/design.md §3.8). See
 * nprfx/filter.h. */
#include <math.h>
#include <stdlib.h>

#include "nprfx/exec.h"
#include "nprfx/filter.h"

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
            /* NaN is the identity of fmaxf/fminf, which skip a NaN tap as missing: a footprint
             * of NaN only stays NaN (docs/design.md §2.2). Starting from -inf/+inf, as max/min
             * usually do, turned it into an infinity the input never had. */
            for (int c = 0; c < C; c++)
                acc[c] = NAN;
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

nprfx_result nprfx_morphology_render(const nprfx_render_args *args,
                                     const nprfx_morphology_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const nprfx_image *image = nprfx_render_input(args, NPRFX_MORPHOLOGY_IN_IMAGE);
    nprfx_rect frame = args->frame, window = args->window;
    nprfx_image *out = args->output;
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "morphology: no params or output");
    int op = p->operation, fp = p->footprint;
    double radius = p->radius;
    if (op < 0 || op >= NPRFX_MORPHOLOGY_OP_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "morphology.operation: no operation %d",
                           op);
    if (fp < 0 || fp >= NPRFX_MORPHOLOGY_FOOTPRINT_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "morphology.footprint: no footprint %d",
                           fp);
    if (!(radius >= 0.0 && radius <= 4096.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "morphology.radius: %g is outside [0, 4096]", radius);
    if (!image || !image->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "morphology: input 'image' is not connected");
    if (out->channels != image->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "morphology: output has %d channels, input 'image' %d", out->channels,
                           image->channels);
    if (nprfx_rect_empty(window)) return NPRFX_OK;
    /* Reads clamp to the frame (within the input's data): the same for every tile. */
    nprfx_rect clampr = nprfx_rect_intersect(image->bounds, frame);
    if (nprfx_rect_empty(clampr))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "morphology: input 'image' is empty");
    int R = (int)floor(radius + 1e-9);
    int *half = malloc(sizeof(int) * (size_t)(2 * R + 1));
    if (!half) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "morphology: out of memory");
    for (int dy = -R; dy <= R; dy++)
        half[dy + R] = fp == NPRFX_MORPHOLOGY_SQUARE
                           ? R
                           : (int)floor(sqrt(fmax(0.0, radius * radius - dy * dy)) + 1e-9);
    nprfx_result r = NPRFX_OK;
    nprfx_rect win = window;
    if (op == NPRFX_MORPHOLOGY_DILATE || op == NPRFX_MORPHOLOGY_ERODE) {
        morph_pass(ctx, image, out, win, clampr, R, half, op == NPRFX_MORPHOLOGY_DILATE);
    } else {
        /* The first operation over the window grown by the footprint, so that tiles agree. */
        nprfx_rect grown = nprfx_rect_intersect(
            nprfx_rect_make(win.x0 - R, win.y0 - R, win.x1 + R, win.y1 + R), clampr);
        nprfx_image tmp;
        if ((r = nprfx_image_alloc(ctx, grown, image->channels, &tmp)) == NPRFX_OK) {
            int first_dilate = op == NPRFX_MORPHOLOGY_CLOSE;
            morph_pass(ctx, image, &tmp, grown, clampr, R, half, first_dilate);
            /* Reads of the second pass clamp to `grown`, which equals clampr wherever the
             * footprint of a window pixel can reach. */
            morph_pass(ctx, &tmp, out, win, grown, R, half, !first_dilate);
            nprfx_image_free(&tmp);
        }
    }
    free(half);
    return r;
}
