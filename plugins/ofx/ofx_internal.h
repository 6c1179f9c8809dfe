/* nprfx OpenFX adapter — what its two translation units share: the host's suites, the
 * per-instance data, and the helpers both the actions (nprfx_ofx.c) and the render
 * (ofx_render.c) use. Nothing here is exported from the bundle. */
#ifndef NPRFX_OFX_INTERNAL_H
#define NPRFX_OFX_INTERNAL_H

#include <pthread.h>

#include "nprfx/nprfx.h"
#include "nprfx/flow.h"
#include "ofx_api.h"
#include "ofx_derive.h"
#include "ofx_names.h"

/* The suites fetched from the host on load. Property, image effect and parameter suites are
 * required; without multithreading the nodes run serially, without memory the adapter uses
 * malloc, without messages errors only reach the host as a status. */
typedef struct ofx_suites {
    OfxHost *host;
    const OfxPropertySuiteV1 *prop;
    const OfxImageEffectSuiteV1 *fx;
    const OfxParameterSuiteV1 *param;
    const OfxMultiThreadSuiteV1 *mt;
    const OfxMemorySuiteV1 *mem;
    const OfxMessageSuiteV1 *msg;
    const OfxMessageSuiteV2 *msg2; /* NULL when the host has only version 1 */
    /* The host's kOfxImageEffectPropTemporalClipAccess: 0 means images at other times cannot be
     * had (MLT gives the current frame instead), so nodes get no fetch and say so. */
    int temporal;
    /* The flow node's solver (OpenCV's DIS), NULL in a build without one: without it no input is
     * derived from Source (ofx_derive.c) and the footage nodes keep their clips. */
    const nprfx_flow_provider *flow;
    /* The bundle's Contents/Resources (data files such as the stipple dot sequence), found from
     * the module's own path on load; empty when unknown. */
    char data_dir[4096];
} ofx_suites;
extern ofx_suites ofx_g;

/* How a node's inputs are derived from the Source clip with the flow node (ofx_derive.c): the
 * flow's param values (its defaults, with the output choice that covers what the inputs take and
 * that the host can serve), how many channels it then outputs, and per input the flow channels
 * it takes (count 0: not derived). */
typedef struct ofx_derive_plan {
    const nprfx_node_desc *flow;
    nprfx_value values[NPRFX_OFX_DERIVE_MAX_PARAMS];
    int channels;
    int count[NPRFX_OFX_DERIVE_MAX_INPUTS];
    int idx[NPRFX_OFX_DERIVE_MAX_INPUTS][4];
    int any; /* some input is derived and every required one is (or is the main input) */
} ofx_derive_plan;

/* The plan for node d in a host with (1) or without (0) temporal clip access; returns plan->any.
 * Without a flow provider, or for a node without derivable inputs, nothing is derived. */
int ofx_derive_make_plan(const nprfx_node_desc *d, int temporal, ofx_derive_plan *plan);

/* The frames of the Source clip a derived render of q->time reads: the frames the node reads its
 * derived inputs at, each widened by the frames the flow node reads to compute it, and the
 * frames it reads the main input at when Source feeds that too (main_fed). Up to
 * NPRFX_MAX_FRAME_RANGES merged ranges into r; returns how many. */
int ofx_derive_frames(const nprfx_node_desc *d, const ofx_derive_plan *plan,
                      const nprfx_value *values, const nprfx_frames_query *q, int main_fed,
                      nprfx_frame_range *r);

/* One plug-in instance: the handles looked up once at creation, and the node's state slot. */
typedef struct ofx_instance {
    const nprfx_node_desc *desc;
    OfxImageEffectHandle fx;
    OfxImageClipHandle output, mask;
    OfxImageClipHandle *clips;       /* per input; NULL where the context defines no clip */
    OfxParamHandle *params;          /* per descriptor param */
    OfxParamHandle *selectors;       /* per input; NULL without a channel selector */
    OfxParamHandle mix, mask_invert; /* NULL unless the node is maskable */
    pthread_mutex_t lock; /* held around renders of stateful nodes and around freeing state */
    void *state;          /* the node's per-instance slot (nprfx_render_args.state) */
    int persistent;       /* a persistent error message is shown on the effect */
    /* The last export written (what it was made from), so tiles of one frame export once;
     * forgotten at each sequence render and on every change. Guarded by lock. */
    unsigned long long export_key;
    int export_done;
    /* Filter context on footage (ofx_derive.c): the inputs derived from Source, the flow node's
     * cache slot, and, where the host has no temporal clip access (MLT renders in order), the
     * previous Source frame and its flow kept between renders; seg_start is the frame the effect
     * restarted at (the shot's first, or the last jump, treated as a cut). Guarded by lock. */
    ofx_derive_plan plan;
    int derive; /* plan.any, in the Filter context */
    void *flow_state;
    nprfx_image kept_src, kept_flow;
    int kept, kept_frame, seg_start;
} ofx_instance;

/* Forget the kept frames and the flow's cache (with lock held or before the instance is
 * shared). */
void ofx_instance_forget_footage(ofx_instance *inst);

void *ofx_alloc(size_t bytes);
void ofx_free(void *p);

ofx_instance *ofx_instance_get(OfxImageEffectHandle fx);
int ofx_clip_connected(OfxImageClipHandle clip);

/* The channels input k reads at `time`: its selector's option, or the only option. */
void ofx_input_selection(const ofx_instance *inst, int k, OfxTime time, int current, int *first,
                         int *count);

/* The effect's frame (whole image domain) in canonical coordinates at `time`: the region of
 * definition of the first connected input that is aligned with the frame (as the runner takes
 * the first connected input's bounds), else the project. */
OfxStatus ofx_frame_rod(const ofx_instance *inst, OfxTime time, OfxRectD *rod);

/* The shot's first and last frame: the output clip's frame range. */
void ofx_shot_range(const ofx_instance *inst, double *first, double *last);

/* Post a message of `type` (kOfxMessage...) through the message suite, as finished text. */
void ofx_post(void *handle, const char *type, const char *message);
/* Post an error to the host: a persistent message on the effect where the host has message
 * suite V2, else a message; nothing without a message suite. */
void ofx_post_error(ofx_instance *inst, const char *message);
/* A successful render takes down the persistent error of an earlier one. */
void ofx_clear_error(ofx_instance *inst);

/* Param values at `time` (or the current ones), checked as the runner checks them; STRING
 * values are copied into strings[i] (free each with free()). Errors name the param. */
nprfx_result ofx_eval_params(const ofx_instance *inst, nprfx_context *ctx, OfxTime time,
                             int current, nprfx_value *values, char **strings);

/* The channel count each input gives at `time` (0 where its clip is not connected). */
void ofx_input_channels(const ofx_instance *inst, OfxTime time, int current, int *channels);

/* Write the node's text export of the frame a render made (render args with window = frame),
 * when its export param is set; once per frame and params (tiles do not repeat it). */
nprfx_result ofx_export(ofx_instance *inst, const nprfx_render_args *a);

OfxStatus ofx_render(ofx_instance *inst, OfxPropertySetHandle in_args);

#endif
