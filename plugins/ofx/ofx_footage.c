/* nprfx OpenFX adapter — inputs derived from the Source clip during a render (footage in the
 * Filter context; what is derived is planned in ofx_derive.c; declared in ofx_footage.h): Source
 * at the frames the flow needs, the flow node run on it inside the plug-in, each derived input's
 * channels copied out of the flow, and, where the host has no temporal clip access, the previous
 * frame and its flow kept between renders. */
#include <string.h>

#include "ofx_fetch.h"
#include "ofx_footage.h"
#include "ofx_handover.h"
#include "ofx_image.h"
#include "ofx_instance.h"
#include "ofx_names.h"
#include "ofx_suites.h"

/* Source whole (all the components the host image has) at frame t, for the flow: the render
 * time's image, another frame from the host, or, without temporal clip access, the previous
 * frame the instance kept. */
static nprfx_result source_at(ofx_render_call *rc, int t, nprfx_image *out)
{
    ofx_instance *inst = rc->inst;
    const nprfx_node_desc *d = inst->desc;
    if (t == ofx_round_frame(rc->time)) {
        *out = rc->src;
        return NPRFX_OK;
    }
    if (!ofx_g.temporal) {
        if (inst->kept && inst->kept_frame == t) {
            *out = inst->kept_src;
            return NPRFX_OK;
        }
        return nprfx_error(rc->ctx, NPRFX_ERR_MISSING_INPUT,
                           "%s: the Source clip at frame %d, while rendering frame %d: this host "
                           "gives no other frame (no temporal clip access), and the plug-in keeps "
                           "only the previous one (render in order)",
                           d->id, t, ofx_round_frame(rc->time));
    }
    int main = ofx_names_main_input(d);
    pthread_mutex_lock(&rc->lock);
    ofx_fetched *s = &rc->ring[rc->nfetch++ % OFX_FETCH_RING];
    ofx_fetched_release(s);
    OfxStatus st = ofx_img_fetch(inst->clips[main], t, 1, &s->img);
    nprfx_result r = NPRFX_OK;
    if (st != kOfxStatOK)
        r = nprfx_error(rc->ctx,
                        st == kOfxStatErrMemory ? NPRFX_ERR_OUT_OF_MEMORY : NPRFX_ERR_MISSING_INPUT,
                        "%s: the host gave no image of the Source clip at frame %d (OFX status %d)",
                        d->id, t, st);
    else if ((r = ofx_img_view(&s->img, ofx_input_flip(rc, main, &s->img), 0, s->img.ncomp, out,
                               &s->scratch)))
        r = nprfx_error(rc->ctx, r, "%s: out of memory", d->id);
    pthread_mutex_unlock(&rc->lock);
    return r;
}

/* The flow node's fetch: Source at its neighbouring frames. */
static nprfx_result flow_fetch(void *user, int input, double time, nprfx_image *out)
{
    (void)input;
    return source_at(user, ofx_round_frame(time), out);
}

/* The flow at frame t, computed by the flow node on Source as a graph would (held: dlock). */
static nprfx_result flow_at(ofx_render_call *rc, int t, const nprfx_image **out)
{
    ofx_instance *inst = rc->inst;
    for (int i = 0; i < OFX_FLOWS; i++)
        if (rc->flows[i].used && rc->flows[i].frame == t) {
            *out = &rc->flows[i].im;
            return NPRFX_OK;
        }
    if (!ofx_g.temporal && inst->kept && inst->kept_frame == t) {
        *out = &inst->kept_flow;
        return NPRFX_OK;
    }
    ofx_flow_slot *slot = &rc->flows[rc->nflows++ % OFX_FLOWS];
    nprfx_image_free(&slot->im);
    slot->used = 0;
    nprfx_image src;
    nprfx_result r = source_at(rc, t, &src);
    if (!r) r = nprfx_image_alloc(rc->ctx, rc->frame, inst->plan.channels, &slot->im);
    if (r) return r;
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = rc->ctx;
    a.node = inst->plan.flow;
    a.time = t;
    a.render_scale = rc->scale;
    a.vector_scale = rc->vector_scale;
    a.frame = rc->frame;
    a.window = rc->frame;
    a.first_frame = rc->first_frame;
    a.last_frame = rc->last_frame;
    a.inputs = &src;
    a.params = rc->fvalues;
    a.output = &slot->im;
    a.fetch = flow_fetch;
    a.fetch_user = rc;
    a.state = &inst->flow_state;
    if ((r = nprfx_node_render(&a))) {
        nprfx_image_free(&slot->im);
        return r;
    }
    slot->frame = t;
    slot->used = 1;
    *out = &slot->im;
    return NPRFX_OK;
}

/* Input k's channels of a flow, copied into dst. */
static nprfx_result derived_copy(ofx_render_call *rc, const nprfx_image *flow, int k,
                                 nprfx_image *dst)
{
    const ofx_derive_plan *p = &rc->inst->plan;
    nprfx_result r = nprfx_image_alloc(rc->ctx, flow->bounds, p->count[k], dst);
    if (r) return r;
    for (int y = flow->bounds.y0; y < flow->bounds.y1; y++)
        for (int x = flow->bounds.x0; x < flow->bounds.x1; x++) {
            const float *s = nprfx_image_at(flow, x, y);
            float *o = nprfx_image_at(dst, x, y);
            for (int c = 0; c < p->count[k]; c++)
                o[c] = s[p->idx[k][c]];
        }
    return NPRFX_OK;
}

/* The derived inputs at the render time: each one's channels of the flow at frame t, into
 * rc->inputs (copies held in rc->dcur), with in_ch and rc->count set to the channels they take. */
nprfx_result ofx_footage_inputs(ofx_render_call *rc, int t, int *in_ch)
{
    ofx_instance *inst = rc->inst;
    const nprfx_node_desc *d = inst->desc;
    const nprfx_image *flow = NULL;
    pthread_mutex_lock(&rc->dlock);
    nprfx_result r = flow_at(rc, t, &flow);
    for (int k = 0; !r && k < d->num_inputs; k++)
        if (inst->plan.count[k] && !(r = derived_copy(rc, flow, k, &rc->dcur[k]))) {
            rc->inputs[k] = rc->dcur[k];
            in_ch[k] = rc->count[k] = inst->plan.count[k];
        }
    pthread_mutex_unlock(&rc->dlock);
    return r;
}

/* The node's fetch when inputs are derived: a derived input from the flow at that frame, the
 * main input fed by Source from the host (or, without temporal access, the kept frame). */
nprfx_result ofx_footage_fetch(void *user, int input, double time, nprfx_image *out)
{
    ofx_render_call *rc = user;
    ofx_instance *inst = rc->inst;
    const nprfx_node_desc *d = inst->desc;
    if (input < 0 || input >= d->num_inputs)
        return nprfx_error(rc->ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: no input %d", d->id, input);
    int t = ofx_round_frame(time);
    if (t == ofx_round_frame(rc->time) || !rc->inputs[input].data)
        return ofx_fetch_input(user, input, t, out);
    if (!inst->plan.count[input]) {
        if (ofx_g.temporal) return ofx_fetch_input(user, input, time, out);
        const nprfx_image *k = &inst->kept_src;
        if (inst->kept && inst->kept_frame == t &&
            (k->channels == rc->count[input] ||
             (k->channels == 4 && rc->first[input] + rc->count[input] <= 4))) {
            *out =
                nprfx_image_channels(k, k->channels == 4 ? rc->first[input] : 0, rc->count[input]);
            return NPRFX_OK;
        }
        return nprfx_error(rc->ctx, NPRFX_ERR_MISSING_INPUT,
                           "%s: input '%s' (the Source clip) at frame %d, while rendering frame "
                           "%d: this host gives no other frame (no temporal clip access)",
                           d->id, d->inputs[input].name, t, ofx_round_frame(rc->time));
    }
    pthread_mutex_lock(&rc->dlock);
    const nprfx_image *flow = NULL;
    nprfx_result r = flow_at(rc, t, &flow);
    if (!r) {
        nprfx_image *slot = &rc->dring[rc->ndring++ % OFX_FETCH_RING];
        nprfx_image_free(slot);
        if (!(r = derived_copy(rc, flow, input, slot))) *out = *slot;
    }
    pthread_mutex_unlock(&rc->dlock);
    return r;
}

/* Without temporal clip access, whether frame t continues what the instance kept (the frame
 * after it, or the same again); anything else (the first render, a jump, a change of size or
 * params) restarts the effect at t as at a cut: the node's cache and the kept frames go, and
 * the node and the flow see a shot that starts at t, so its first frame has zero motion and
 * zero confidence and nothing from before the jump shows. Held: inst->lock. */
nprfx_result ofx_footage_continue(ofx_render_call *rc, int t, unsigned long long key)
{
    ofx_instance *inst = rc->inst;
    inst->footage_key = key;
    /* a fresh instance: what the instance before it kept, where the host makes one per frame */
    int left = inst->kept ? 0 : ofx_handover_take(inst, key, t, &rc->src);
    if (left > 1)
        return nprfx_error(rc->ctx, NPRFX_ERR_UNSUPPORTED,
                           "%s: this host makes a new instance for every frame and gives no other "
                           "frame, and %d effects with these params on footage of this size kept "
                           "frame %d: the plug-in cannot tell which is this one's. Give each a "
                           "seed of its own",
                           inst->desc->id, left, t - 1);
    int follows = inst->kept && (inst->kept_frame == t || inst->kept_frame == t - 1) &&
                  nprfx_rect_equal(inst->kept_src.bounds, rc->src.bounds) &&
                  inst->kept_src.channels == rc->src.channels;
    if (!follows) {
        if (inst->state && inst->desc->state_free) inst->desc->state_free(inst->state);
        inst->state = NULL;
        ofx_instance_forget_footage(inst);
        inst->seg_start = t;
    }
    if (inst->seg_start > rc->first_frame) rc->first_frame = inst->seg_start;
    return NPRFX_OK;
}

/* After a render without temporal access: keep Source and the flow at t for the next frame. */
nprfx_result ofx_footage_keep(ofx_render_call *rc, int t)
{
    ofx_instance *inst = rc->inst;
    if (inst->kept && inst->kept_frame == t) return NPRFX_OK;
    const nprfx_image *flow = NULL;
    nprfx_image src, fl;
    memset(&src, 0, sizeof src);
    memset(&fl, 0, sizeof fl);
    nprfx_result r = flow_at(rc, t, &flow);
    if (!r) r = nprfx_image_alloc(rc->ctx, rc->src.bounds, rc->src.channels, &src);
    if (!r) r = nprfx_image_copy(rc->ctx, &rc->src, &src);
    if (!r) r = nprfx_image_alloc(rc->ctx, flow->bounds, flow->channels, &fl);
    if (!r) r = nprfx_image_copy(rc->ctx, flow, &fl);
    if (r) {
        nprfx_image_free(&src);
        nprfx_image_free(&fl);
        return r;
    }
    nprfx_image_free(&inst->kept_src);
    nprfx_image_free(&inst->kept_flow);
    inst->kept_src = src;
    inst->kept_flow = fl;
    inst->kept_frame = t;
    inst->kept = 1;
    return NPRFX_OK;
}

void ofx_footage_release(ofx_render_call *rc)
{
    for (int i = 0; i < OFX_FLOWS; i++)
        nprfx_image_free(&rc->flows[i].im);
    for (int i = 0; i < OFX_FETCH_RING; i++)
        nprfx_image_free(&rc->dring[i]);
    for (int k = 0; k < NPRFX_OFX_DERIVE_MAX_INPUTS; k++)
        nprfx_image_free(&rc->dcur[k]);
    ofx_free(rc->src_scratch);
}
