/* nprfx OpenFX adapter — a render's inputs derived from the Source clip with the flow node
 * (ofx_footage.c), for an instance whose plan derives some (inst->derive). All but
 * ofx_footage_release are called with inst->lock held, as the instance's kept frames and flow
 * cache are shared by its renders. */
#ifndef NPRFX_OFX_FOOTAGE_H
#define NPRFX_OFX_FOOTAGE_H

#include "nprfx/nprfx.h"
#include "ofx_fetch.h"

/* Without temporal clip access, before the render of frame t: whether t continues what the
 * instance kept (the frame after it, or the same again), or, for a fresh instance, what the
 * instance before it left (key: ofx_handover_key; a host that makes one per frame); anything
 * else restarts the effect at t as at a cut (the node's cache and the kept frames go, and the
 * shot starts at t). An error when several effects left what this one could continue. */
nprfx_result ofx_footage_continue(ofx_render_call *rc, int t, unsigned long long key);

/* The derived inputs at the render time (frame t) into rc->inputs, their channel counts into
 * in_ch and rc->count. */
nprfx_result ofx_footage_inputs(ofx_render_call *rc, int t, int *in_ch);

/* The node's nprfx_fetch_fn (user: the ofx_render_call) when inputs are derived: a derived input
 * from the flow at that frame, the main input fed by Source from the host (or, without temporal
 * access, the kept frame). */
nprfx_result ofx_footage_fetch(void *user, int input, double time, nprfx_image *out);

/* After a render of frame t without temporal access: keep Source and the flow for the next. */
nprfx_result ofx_footage_keep(ofx_render_call *rc, int t);

/* Free what the render call derived (flows, copies, Source's scratch). */
void ofx_footage_release(ofx_render_call *rc);

#endif
