/* nprfx OpenFX adapter — a render's last step (declared in ofx_mix.h): the result mixed with the
 * Source by mix * Mask, and written into the host's output image in its components and depth. */
#include <string.h>

#include "ofx_image.h"
#include "ofx_mix.h"

/* The host component values for a result pixel with n channels (as ofx_clip_preferences in
 * ofx_actions.c declares the output). */
static void result_rgba(const float *px, int n, float rgba[4])
{
    switch (n) {
    case 1:
        rgba[0] = rgba[1] = rgba[2] = px[0], rgba[3] = 1.0f;
        break;
    case 2:
        rgba[0] = px[0], rgba[1] = px[1], rgba[2] = 0.0f, rgba[3] = 1.0f;
        break;
    case 3:
        rgba[0] = px[0], rgba[1] = px[1], rgba[2] = px[2], rgba[3] = 1.0f;
        break;
    case 4:
        memcpy(rgba, px, 4 * sizeof(float));
        break;
    default: /* more than a host image holds: the colour, and the last channel as alpha */
        rgba[0] = px[0], rgba[1] = px[1], rgba[2] = px[2], rgba[3] = px[n - 1];
        break;
    }
}

/* Mix with the Source by mix * Mask, then write the host components the result does not
 * already fill in place. Rows are independent, so this runs on the executor too. */
void ofx_finish_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const ofx_finish_job *j = user;
    const int ncomp = j->out->ncomp;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++)
        for (int x = j->window.x0; x < j->window.x1; x++) {
            float *px = nprfx_image_at(j->res, x, y);
            if (j->mask || j->mix != 1.0) {
                double m = j->mix;
                if (j->mask) {
                    double mv = nprfx_rect_contains(j->mask->bounds, x, y)
                                    ? nprfx_image_at(j->mask, x, y)[0]
                                    : 0.0;
                    mv = mv > 0.0 ? (mv < 1.0 ? mv : 1.0) : 0.0;
                    m *= j->mask_invert ? 1.0 - mv : mv;
                }
                int nc = j->src && j->src->channels < j->nout ? j->src->channels : j->nout;
                const float *s = j->src && nprfx_rect_contains(j->src->bounds, x, y)
                                     ? nprfx_image_at(j->src, x, y)
                                     : NULL;
                for (int c = 0; j->src && c < nc; c++) {
                    double sv = s ? s[c] : 0.0;
                    px[c] = (float)(sv + ((double)px[c] - sv) * m);
                }
            }
            float rgba[4];
            result_rgba(px, j->nout, rgba);
            int yu = j->f - y;
            if (ncomp == 1)
                ofx_img_store(j->out, x, yu, 0, j->nout >= 4 ? rgba[3] : px[0]);
            else
                for (int c = 0; c < ncomp; c++)
                    ofx_img_store(j->out, x, yu, c, rgba[c]);
        }
}
