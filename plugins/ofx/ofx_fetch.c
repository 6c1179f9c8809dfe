/* nprfx OpenFX adapter — the inputs of one render call (declared in ofx_fetch.h): releasing what
 * was fetched, each input's flip, and the node's fetch of clip images at other times. */
#include "ofx_fetch.h"
#include "ofx_image.h"
#include "ofx_suites.h"

void ofx_fetched_release(ofx_fetched *s)
{
    ofx_img_release(&s->img);
    ofx_free(s->scratch);
    s->scratch = NULL;
}

int ofx_input_flip(const ofx_render_call *rc, int k, const ofx_img *im)
{
    if (rc->inst->desc->inputs[k].flags & NPRFX_INPUT_UNALIGNED) return im->b.y1 + im->b.y2 - 1;
    return rc->f;
}

/* nprfx_fetch_fn: clip k at another time. The current frame is served from the images already
 * held; other frames go into a ring, so a view stays valid for the next OFX_FETCH_RING - 1 fetches,
 * more than NPRFX_FETCH_KEEP promises. */
nprfx_result ofx_fetch_input(void *user, int input, double time, nprfx_image *out)
{
    ofx_render_call *rc = user;
    const nprfx_node_desc *d = rc->inst->desc;
    if (input < 0 || input >= d->num_inputs)
        return nprfx_error(rc->ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: no input %d", d->id, input);
    if (!rc->inputs[input].data)
        return nprfx_error(rc->ctx, NPRFX_ERR_MISSING_INPUT, "%s: input '%s' is not connected",
                           d->id, d->inputs[input].name);
    if (time == rc->time) {
        *out = rc->inputs[input];
        return NPRFX_OK;
    }
    pthread_mutex_lock(&rc->lock);
    ofx_fetched *s = &rc->ring[rc->nfetch++ % OFX_FETCH_RING];
    ofx_fetched_release(s);
    OfxStatus st = ofx_img_fetch(rc->inst->clips[input], time, 1, &s->img);
    nprfx_result r = NPRFX_OK;
    if (st != kOfxStatOK)
        r = nprfx_error(rc->ctx,
                        st == kOfxStatErrMemory ? NPRFX_ERR_OUT_OF_MEMORY : NPRFX_ERR_MISSING_INPUT,
                        "%s: the host gave no image of input '%s' at frame %g (OFX status %d)",
                        d->id, d->inputs[input].name, time, st);
    else if ((r = ofx_img_view(&s->img, ofx_input_flip(rc, input, &s->img), rc->first[input],
                               rc->count[input], out, &s->scratch)))
        r = nprfx_error(rc->ctx, r, "%s: out of memory", d->id);
    pthread_mutex_unlock(&rc->lock);
    return r;
}
