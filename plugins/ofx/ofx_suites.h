/* nprfx OpenFX adapter — the host as the plug-in sees it: the suites fetched on load, what the
 * host can do (temporal clip access, the flow provider, the bundle's data folder), memory through
 * the host, and shorthands for properties. The bottom of the adapter: every other file may use
 * this one, and it uses none of them but ofx_api.h. Nothing here is exported from the bundle. */
#ifndef NPRFX_OFX_SUITES_H
#define NPRFX_OFX_SUITES_H

#include <stddef.h>

#include "nprfx/flow.h"
#include "ofx_api.h"

/* The suites fetched from the host on load. Property, image effect and parameter suites are
 * required; without multithreading the nodes run serially, without memory the adapter uses
 * malloc, without messages errors only reach the host as a status. */
typedef struct ofx_suites {
    OfxHost *host; /* set by the host through each plug-in's setHost, before load */
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
    /* Whether the host has float images (kOfxImageEffectPropSupportedPixelDepths lists float;
     * a host that does not say is taken to): 8- and 16-bit images hold 0-1 only, so a look whose
     * clips carry depth, positions or motion is not offered without them. */
    int float_images;
    /* The Foundry's plane suite where the host says it is multi-planar (kFnOfxImageEffectProp-
     * MultiPlanar): a clip then carries a render's layers (ofx_look_render.c); else NULL, 0. */
    const FnOfxImageEffectPlaneSuiteV1 *planes;
    int multiplanar;
    /* The flow node's solver (OpenCV's DIS), NULL in a build without one: without it no input is
     * derived from Source (ofx_derive.c) and the footage nodes keep their clips. */
    const nprfx_flow_provider *flow;
    /* The bundle's Contents/Resources (data files such as the stipple dot sequence), found from
     * the module's own path on load; empty when unknown. */
    char data_dir[4096];
} ofx_suites;
extern ofx_suites ofx_g;

/* The load action: fetch the suites from ofx_g.host and find out what the host can do.
 * kOfxStatErrMissingHostFeature without the required suites. */
OfxStatus ofx_suites_load(void);
/* Find data_dir from the module's own path (the load action does; the plug-in table needs it
 * earlier, for the looks the bundle ships). */
void ofx_find_data_dir(void);

/* Memory through the host's memory suite when it has one (hosts account plug-in memory that
 * way); the choice is fixed at load, so alloc and free always pair up. ofx_zalloc zeroes it. */
void *ofx_alloc(size_t bytes);
void *ofx_zalloc(size_t bytes);
void ofx_free(void *p);

/* Optional properties: a host that does not know one answers kOfxStatErrUnknown, which must not
 * stop the plug-in from loading, so these ignore the status on purpose. */
void ofx_set_str(OfxPropertySetHandle p, const char *name, int i, const char *v);
void ofx_set_int(OfxPropertySetHandle p, const char *name, int i, int v);
void ofx_set_dbl(OfxPropertySetHandle p, const char *name, int i, double v);

/* A clip's property set (NULL for a NULL clip or when the host gives none), and whether the
 * clip is connected. */
OfxPropertySetHandle ofx_clip_props(OfxImageClipHandle clip);
int ofx_clip_connected(OfxImageClipHandle clip);

/* A render action's request: its time, render scale (1 where the host gives none that makes
 * sense) and window. kOfxStatErrBadHandle without a time or window. */
OfxStatus ofx_render_request(OfxPropertySetHandle in_args, double *time, double scale[2],
                             int win[4]);

#endif
