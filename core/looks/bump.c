/* Bump shading (docs/design.md §3.13): the image lit by the normals of a height field, Lambert's
 * cosine normalised by the flat surface's so that flat regions keep their colour exactly, plus an
 * optional Blinn highlight. See nprfx/bump.h. */
#include <math.h>

#include "nprfx/bump.h"
#include "nprfx/exec.h"

typedef struct bump_job {
    const nprfx_bump_params *p;
    const nprfx_image *image, *height;
    nprfx_image *out;
    nprfx_rect win, clampr; /* pixels to write; height reads clamp to clampr */
    double s;               /* strength */
    double l[3], hv[3];     /* light and half vector */
    double spec_flat;       /* H_z^shininess: the flat surface's highlight */
} bump_job;

static int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

static void bump_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const bump_job *j = user;
    const nprfx_bump_params *p = j->p;
    int C = j->out->channels, colour = C == 4 ? 3 : C;
    nprfx_rect cr = j->clampr;
    for (int y = j->win.y0 + begin; y < j->win.y0 + end; y++) {
        int yc = clampi(y, cr.y0, cr.y1 - 1);
        int ym = clampi(y - 1, cr.y0, cr.y1 - 1), yp = clampi(y + 1, cr.y0, cr.y1 - 1);
        for (int x = j->win.x0; x < j->win.x1; x++) {
            int xc = clampi(x, cr.x0, cr.x1 - 1);
            int xm = clampi(x - 1, cr.x0, cr.x1 - 1), xp = clampi(x + 1, cr.x0, cr.x1 - 1);
            double hx = 0.5 * ((double)nprfx_image_at(j->height, xp, yc)[0] -
                               (double)nprfx_image_at(j->height, xm, yc)[0]);
            double hy = 0.5 * ((double)nprfx_image_at(j->height, xc, yp)[0] -
                               (double)nprfx_image_at(j->height, xc, ym)[0]);
            double nx = -j->s * hx, ny = -j->s * hy;
            double len = sqrt(nx * nx + ny * ny + 1.0);
            nx /= len;
            ny /= len;
            double nz = 1.0 / len;
            double lam = nx * j->l[0] + ny * j->l[1] + nz * j->l[2];
            double shade = (lam > 0.0 ? lam : 0.0) / j->l[2];
            /* shade is exactly 1 on a flat height, and so is k: the image passes unchanged */
            double k = 1.0 + p->amount * (shade - 1.0);
            double add = 0.0;
            if (p->specular > 0.0) {
                double nh = nx * j->hv[0] + ny * j->hv[1] + nz * j->hv[2];
                double sp = nh > 0.0 ? pow(nh, p->shininess) : 0.0;
                add = sp > j->spec_flat ? p->specular * (sp - j->spec_flat) : 0.0;
            }
            float *o = nprfx_image_at(j->out, x, y);
            if (!nprfx_rect_contains(j->image->bounds, x, y)) {
                /* outside its data window the image reads as 0 (OpenEXR) */
                for (int c = 0; c < C; c++)
                    o[c] = c < colour ? (float)add : 0.0f;
                continue;
            }
            const float *in = nprfx_image_at(j->image, x, y);
            /* without a highlight nothing is added: adding 0 would turn -0 into +0 */
            for (int c = 0; c < colour; c++)
                o[c] = add > 0.0 ? (float)((double)in[c] * k + add) : (float)((double)in[c] * k);
            if (C == 4) o[3] = in[3];
        }
    }
}

nprfx_result nprfx_bump_render(const nprfx_render_args *args, const nprfx_bump_params *p)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const nprfx_image *image = nprfx_render_input(args, NPRFX_BUMP_IN_IMAGE);
    const nprfx_image *height = nprfx_render_input(args, NPRFX_BUMP_IN_HEIGHT);
    nprfx_rect frame = args->frame, window = args->window;
    nprfx_image *out = args->output;
    if (!p || !out || !out->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "bump: no params or output");
    if (!(p->strength >= 0.0 && p->strength <= 1e4))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "bump.strength: %g is outside [0, 10000]",
                           p->strength);
    if (!(p->azimuth >= -360.0 && p->azimuth <= 360.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "bump.azimuth: %g is outside [-360, 360]",
                           p->azimuth);
    if (!(p->elevation >= 1.0 && p->elevation <= 90.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "bump.elevation: %g is outside [1, 90]",
                           p->elevation);
    if (!(p->amount >= 0.0 && p->amount <= 4.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "bump.amount: %g is outside [0, 4]",
                           p->amount);
    if (!(p->specular >= 0.0 && p->specular <= 4.0))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "bump.specular: %g is outside [0, 4]",
                           p->specular);
    if (!(p->shininess >= 1.0 && p->shininess <= 1e4))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "bump.shininess: %g is outside [1, 10000]",
                           p->shininess);
    if (!image || !image->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "bump: input 'image' is not connected");
    if (!height || !height->data)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "bump: input 'height' is not connected");
    if (out->channels != image->channels)
        return nprfx_error(ctx, NPRFX_ERR_SIZE_MISMATCH,
                           "bump: output has %d channels, input 'image' %d", out->channels,
                           image->channels);
    window = nprfx_rect_intersect(window, out->bounds);
    if (nprfx_rect_empty(window)) return NPRFX_OK;
    /* Reads clamp to the frame (within the height's data): the same for every tile. */
    nprfx_rect clampr = nprfx_rect_intersect(height->bounds, frame);
    if (nprfx_rect_empty(clampr))
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "bump: input 'height' is empty");

    bump_job j;
    j.p = p;
    j.image = image;
    j.height = height;
    j.out = out;
    j.win = window;
    j.clampr = clampr;
    j.s = p->strength;
    const double rad = 3.14159265358979323846 / 180.0;
    double az = p->azimuth * rad, el = p->elevation * rad;
    j.l[0] = cos(el) * cos(az);
    j.l[1] = -cos(el) * sin(az); /* y down: azimuth 90 is the top of the image */
    j.l[2] = p->elevation == 90.0 ? 1.0 : sin(el);
    double hx = j.l[0], hy = j.l[1], hz = j.l[2] + 1.0, hl = sqrt(hx * hx + hy * hy + hz * hz);
    j.hv[0] = hx / hl;
    j.hv[1] = hy / hl;
    j.hv[2] = hz / hl;
    j.spec_flat = pow(j.hv[2], p->shininess);
    nprfx_parallel_for(nprfx_context_executor(ctx), nprfx_rect_height(window), 8, bump_rows, &j);
    return NPRFX_OK;
}
