/* nprfx OpenFX adapter — what its two translation units share: the host's suites, the
 * per-instance data, and the helpers both the actions (nprfx_ofx.c) and the render
 * (ofx_render.c) use. Nothing here is exported from the bundle. */
#ifndef NPRFX_OFX_INTERNAL_H
#define NPRFX_OFX_INTERNAL_H

#include <pthread.h>

#include "nprfx/nprfx.h"
#include "ofx_api.h"
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
    /* The bundle's Contents/Resources (data files such as the stipple dot sequence), found from
     * the module's own path on load; empty when unknown. */
    char data_dir[4096];
} ofx_suites;
extern ofx_suites nprfx_ofx_g;

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
} ofx_instance;

void *nprfx_ofx_alloc(size_t bytes);
void nprfx_ofx_free(void *p);

ofx_instance *nprfx_ofx_instance(OfxImageEffectHandle fx);
int nprfx_ofx_clip_connected(OfxImageClipHandle clip);

/* The channels input k reads at `time`: its selector's option, or the only option. */
void nprfx_ofx_input_selection(const ofx_instance *inst, int k, OfxTime time, int current,
                               int *first, int *count);

/* The effect's frame (whole image domain) in canonical coordinates at `time`: the region of
 * definition of the first connected input that is aligned with the frame (as the runner takes
 * the first connected input's bounds), else the project. */
OfxStatus nprfx_ofx_frame_rod(const ofx_instance *inst, OfxTime time, OfxRectD *rod);

/* The shot's first and last frame: the output clip's frame range. */
void nprfx_ofx_shot_range(const ofx_instance *inst, double *first, double *last);

/* Post an error to the host's message suite when it has one. */
void nprfx_ofx_post_error(OfxImageEffectHandle fx, const char *message);

OfxStatus nprfx_ofx_render(ofx_instance *inst, OfxPropertySetHandle in_args);

#endif
