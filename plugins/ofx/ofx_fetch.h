/* nprfx OpenFX adapter — one render call's state and its inputs (ofx_fetch.c): the images held
 * at the render time, the ring of images fetched at other times, and the footage state that
 * ofx_footage.c fills. */
#ifndef NPRFX_OFX_FETCH_H
#define NPRFX_OFX_FETCH_H

#include <math.h>
#include <pthread.h>

#include "nprfx/nprfx.h"
#include "nprfx/seq.h"
#include "ofx_derive.h"
#include "ofx_image.h"
#include "ofx_instance.h"

#define OFX_FETCH_RING (NPRFX_FETCH_KEEP * 2)

typedef struct ofx_fetched {
    ofx_img img;
    float *scratch;
} ofx_fetched;

#define OFX_FLOWS 4 /* flows kept during one render: a frame and its neighbours */

typedef struct ofx_flow_slot {
    int frame, used;
    nprfx_image im;
} ofx_flow_slot;

/* The state of one render action: the instance, the node's context, the render time and the
 * frame's flip, per input its view, its image at the render time and the channels picked, the
 * fetch ring, and the footage state. */
typedef struct ofx_render_call {
    ofx_instance *inst;
    nprfx_context *ctx;
    OfxTime time;
    int f; /* the frame's flip: y_down = f - y_up */
    nprfx_image *inputs;
    ofx_fetched *cur; /* per input, at the render time */
    int *first, *count;
    pthread_mutex_t lock; /* guards the ring: a node may fetch from several threads */
    ofx_fetched ring[OFX_FETCH_RING];
    long nfetch;
    /* Footage (inst->derive, ofx_footage.c): Source whole at the render time, the flow node's
     * params (render scale applied), the frame, the shot the flow and the node see (from the
     * effect's restart without temporal access), the flows computed in this call and the derived
     * views handed out (copies, so a flow can be dropped while a view lives). dlock guards
     * those; a flow's own fetches take lock. */
    nprfx_image src;
    float *src_scratch;
    nprfx_value fvalues[NPRFX_OFX_DERIVE_MAX_PARAMS];
    double scale;        /* params in pixels: the render scale times the design scale */
    double vector_scale; /* motion vectors: the render scale */
    nprfx_rect frame;
    int first_frame, last_frame;
    pthread_mutex_t dlock;
    ofx_flow_slot flows[OFX_FLOWS];
    long nflows;
    nprfx_image dcur[NPRFX_OFX_DERIVE_MAX_INPUTS];
    nprfx_image dring[OFX_FETCH_RING];
    long ndring;
} ofx_render_call;

/* The frame a host time falls on. */
static inline int ofx_round_frame(double t)
{
    /* A host's time beyond the frames nprfx renders (or NaN) is held at their ends, where the
     * int conversion and a node's reach back or ahead stay defined. */
    double r = floor(t + 0.5);
    if (!(r >= NPRFX_FRAME_MIN)) return NPRFX_FRAME_MIN;
    if (r > NPRFX_FRAME_MAX) return NPRFX_FRAME_MAX;
    return (int)r;
}

/* Give back a fetched image and free its scratch copy. */
void ofx_fetched_release(ofx_fetched *s);

/* The flip of input k's image im: the frame's, or, for an unaligned input, its own bounds'. */
int ofx_input_flip(const ofx_render_call *rc, int k, const ofx_img *im);

/* nprfx_fetch_fn (user: the ofx_render_call): clip k at another time. The current frame is
 * served from the images already held; other frames go into a ring, so a view stays valid for
 * the next OFX_FETCH_RING - 1 fetches, more than NPRFX_FETCH_KEEP promises. */
nprfx_result ofx_fetch_input(void *user, int input, double time, nprfx_image *out);

#endif
