/* The matte node (docs/design.md §3.10). Blender's film is usually not transparent, so its alpha
 * is 1 everywhere and the sky has to be found from the depth (infinite, or Blender's 1e10) or
 * from the object index (0 where no object was hit). Neither is antialiased, so the hard matte
 * made from them can be softened by a small Gaussian; a real alpha is used as it is. */
#include <math.h>
#include <stdlib.h>

#include "nprfx/exec.h"
#include "nprfx/filter.h"
#include "nprfx/matte.h"
#include "nprfx/objectid.h"

#define MATTE_MAX_SOFTEN 2.0

static double clamp01(double x)
{
    return x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0; /* NaN -> 0 */
}

/* The depth/id factor: 1 on an object, 0 on the background. */
static double hard_part(const nprfx_matte_params *p, const float *depth, const float *id)
{
    if (depth) {
        double z = depth[0];
        if (!(z > 0.0) || !isfinite(z) || z >= p->far) return 0.0;
    }
    if (id && p->background_id >= 0 && nprfx_id_to_uint(id[0]) == (uint32_t)p->background_id)
        return 0.0;
    return 1.0;
}

double nprfx_matte_pixel(const nprfx_matte_params *p, const float *alpha, const float *depth,
                         const float *id)
{
    double a = alpha ? clamp01(alpha[0]) : 1.0;
    return a * hard_part(p, depth, id);
}

/* A pixel of an optional input, NULL outside its data window reads as 0. */
static const float zero1[1];
static const float *px(const nprfx_image *im, int x, int y)
{
    if (!im) return NULL;
    return nprfx_rect_contains(im->bounds, x, y) ? nprfx_image_at(im, x, y) : zero1;
}

typedef struct matte_job {
    const nprfx_matte_params *p;
    const nprfx_image *alpha, *depth, *id, *soft; /* soft: softened hard part, or NULL */
    nprfx_rect rect;                              /* rows/columns filled */
    nprfx_image *out;
    int hard_only; /* fill the hard part alone (the input of the blur) */
} matte_job;

static void matte_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const matte_job *j = user;
    for (int y = j->rect.y0 + begin; y < j->rect.y0 + end; y++)
        for (int x = j->rect.x0; x < j->rect.x1; x++) {
            float *o = nprfx_image_at(j->out, x, y);
            double h = j->soft ? nprfx_image_at(j->soft, x, y)[0]
                               : hard_part(j->p, px(j->depth, x, y), px(j->id, x, y));
            if (j->hard_only) {
                o[0] = (float)h;
                continue;
            }
            const float *a = px(j->alpha, x, y);
            double c = (a ? clamp01(a[0]) : 1.0) * clamp01(h);
            o[0] = (float)(j->p->invert ? 1.0 - c : c);
        }
}

nprfx_result nprfx_matte_render(const nprfx_render_args *args, const nprfx_matte_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const nprfx_image *alpha = nprfx_render_input(args, NPRFX_MATTE_IN_ALPHA);
    const nprfx_image *depth = nprfx_render_input(args, NPRFX_MATTE_IN_DEPTH);
    const nprfx_image *id = nprfx_render_input(args, NPRFX_MATTE_IN_ID);
    nprfx_rect frame = args->frame, window = args->window;
    nprfx_image *out = args->output;
    if (!p || !out || !out->data || out->channels != 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "matte: no params, or an output without exactly 1 channel");
    if (alpha && !alpha->data) alpha = NULL;
    if (depth && !depth->data) depth = NULL;
    if (id && !id->data) id = NULL;
    if (!alpha && !depth && !id)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "matte: connect at least one of the inputs 'alpha', 'depth', 'id'");
    if (!(p->soften >= 0.0 && p->soften <= MATTE_MAX_SOFTEN))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "matte.soften: %g is outside [0, %g]",
                           p->soften, MATTE_MAX_SOFTEN);
    if (nprfx_rect_empty(window)) return NPRFX_OK;
    const nprfx_executor *ex = nprfx_context_executor(ctx);
    matte_job j = {p, alpha, depth, id, NULL, window, out, 0};
    if (p->soften <= 0.0 || (!depth && !id)) {
        nprfx_parallel_for(ex, nprfx_rect_height(window), 16, matte_rows, &j);
        return NPRFX_OK;
    }
    /* The hard part over the window grown by the kernel's reach (inside the frame: the blur
     * clamps at the frame's edge, as it does for the whole frame), blurred onto the window. */
    int reach = (int)ceil(4.0 * p->soften) + 1;
    nprfx_rect grown = {window.x0 - reach, window.y0 - reach, window.x1 + reach, window.y1 + reach};
    grown = nprfx_rect_intersect(grown, frame);
    nprfx_image hard, soft;
    nprfx_result r = nprfx_image_alloc(ctx, grown, 1, &hard);
    if (r) return r;
    if ((r = nprfx_image_alloc(ctx, window, 1, &soft))) {
        nprfx_image_free(&hard);
        return r;
    }
    matte_job hj = {p, NULL, depth, id, NULL, grown, &hard, 1};
    nprfx_parallel_for(ex, nprfx_rect_height(grown), 16, matte_rows, &hj);
    r = nprfx_gaussian_blur(ctx, &hard, &soft, p->soften, NPRFX_BORDER_CLAMP);
    if (!r) {
        j.soft = &soft;
        nprfx_parallel_for(ex, nprfx_rect_height(window), 16, matte_rows, &j);
    }
    nprfx_image_free(&hard);
    nprfx_image_free(&soft);
    return r;
}
