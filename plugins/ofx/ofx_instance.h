/* nprfx OpenFX adapter — one plug-in instance: its data (the handles looked up once at
 * creation, the node's state, what footage keeps between renders) and its lifecycle (the create,
 * destroy and instance-changed actions, and dropping what a change makes stale). */
#ifndef NPRFX_OFX_INSTANCE_H
#define NPRFX_OFX_INSTANCE_H

#include <pthread.h>

#include "nprfx/nprfx.h"
#include "ofx_api.h"
#include "ofx_derive.h"

/* One plug-in instance: the handles looked up once at creation, and the node's state slot. */
typedef struct ofx_instance {
    const nprfx_node_desc *desc;
    OfxImageEffectHandle fx;
    OfxImageClipHandle output, mask;
    OfxImageClipHandle *clips;       /* per input; NULL where the context defines no clip */
    OfxParamHandle *params;          /* per descriptor param */
    OfxParamHandle *selectors;       /* per input; NULL without a channel selector */
    OfxParamHandle mix, mask_invert; /* NULL unless the node is maskable */
    OfxParamHandle design_width;     /* NULL unless the node has params in pixels */
    /* What Analyze Shot measured (nprfx_node_state_save's text), kept in the project; NULL
     * unless the node measures over its shot (ofx_render.c, ofx_analyze). */
    OfxParamHandle analysis;
    pthread_mutex_t lock; /* held around renders of stateful nodes and around freeing state */
    void *state;          /* the node's per-instance slot (nprfx_render_args.state) */
    int persistent;       /* a persistent error message is shown on the effect */
    /* The last export written (what it was made from), so tiles of one frame export once;
     * forgotten at each sequence render and on every change. Guarded by lock. */
    unsigned long long export_key;
    int export_done;
    /* Filter context on footage (ofx_derive.c, ofx_footage.c): the inputs derived from Source, the
     * flow node's cache slot, and, where the host has no temporal clip access (MLT renders in
     * order), the previous Source frame and its flow kept between renders; seg_start is the frame
     * the effect restarted at (the shot's first, or the last jump, treated as a cut). Guarded by
     * lock. */
    ofx_derive_plan plan;
    int derive; /* plan.any, in the Filter context */
    void *flow_state;
    nprfx_image kept_src, kept_flow;
    int kept, kept_frame, seg_start;
    /* what tells this effect from another for a hand-over to the next instance (ofx_handover.h;
     * 0: none yet) */
    unsigned long long footage_key;
} ofx_instance;

/* The instance the host holds for effect fx (its kOfxPropInstanceData); NULL if none. */
ofx_instance *ofx_instance_get(OfxImageEffectHandle fx);

/* The create and destroy actions: look up the clips and params the context defined (those it
 * did not stay NULL) and attach the instance to the effect; detach and free it. */
OfxStatus ofx_instance_create(const nprfx_node_desc *d, OfxImageEffectHandle fx);
OfxStatus ofx_instance_destroy(OfxImageEffectHandle fx);

/* The instance-changed action: any change but that of the mix and invert-mask params (applied
 * after the node) drops the node's cache (ofx_instance_drop_state). */
OfxStatus ofx_instance_changed(ofx_instance *inst, OfxPropertySetHandle in_args);

/* Drop the node's cache, the export record and the kept footage (purge caches, a change). */
void ofx_instance_drop_state(ofx_instance *inst);

/* Forget the exports written, so a new sequence render writes them again. */
void ofx_instance_forget_export(ofx_instance *inst);

/* Forget the kept frames and the flow's cache (with lock held or before the instance is
 * shared). */
void ofx_instance_forget_footage(ofx_instance *inst);

#endif
