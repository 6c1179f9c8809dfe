/* nprfx OpenFX adapter — mask, mix and the host's output image (ofx_mix.c). */
#ifndef NPRFX_OFX_MIX_H
#define NPRFX_OFX_MIX_H

#include "nprfx/nprfx.h"
#include "ofx_image.h"

/* One render's finish: the host output image, the node's result (res, nout channels), the Source
 * and Mask views (NULL: none), the window in nprfx coordinates and the frame's flip f. */
typedef struct ofx_finish_job {
    const ofx_img *out;
    const nprfx_image *res, *src, *mask;
    nprfx_rect window; /* nprfx coordinates, inside the frame */
    int f, nout, mask_invert;
    double mix;
} ofx_finish_job;

/* nprfx_range_fn over the rows of job->window (user: the ofx_finish_job): mix with the Source by
 * mix * Mask (1 - Mask with mask_invert), then write the host components the result does not
 * already fill in place. */
void ofx_finish_rows(void *user, int begin, int end, int worker);

#endif
