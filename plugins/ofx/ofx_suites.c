/* nprfx OpenFX adapter — the host's suites and capabilities fetched on load, memory through the
 * host, and the property shorthands (declared in ofx_suites.h). */
#define _GNU_SOURCE /* dladdr */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flow_opencv.h"
#include "ofx_suites.h"

ofx_suites ofx_g;

/* ---- load ------------------------------------------------------------------------------------ */

/* The module is BUNDLE/Contents/ARCH/nprfx.ofx (the file that holds this function); its data sit
 * in BUNDLE/Contents/Resources. */
void ofx_find_data_dir(void)
{
    ofx_g.data_dir[0] = 0;
    Dl_info info;
    if (!dladdr((void *)&ofx_suites_load, &info) || !info.dli_fname) return;
    char path[sizeof ofx_g.data_dir];
    if (snprintf(path, sizeof path, "%s", info.dli_fname) >= (int)sizeof path) return;
    for (int up = 0; up < 2; up++) { /* drop the file name, then the architecture folder */
        char *slash = strrchr(path, '/');
        if (!slash) return;
        *slash = 0;
    }
    snprintf(ofx_g.data_dir, sizeof ofx_g.data_dir, "%.4000s/Resources", path);
}

OfxStatus ofx_suites_load(void)
{
    OfxHost *h = ofx_g.host;
    if (!h || !h->fetchSuite) return kOfxStatErrMissingHostFeature;
    ofx_g.prop = h->fetchSuite(h->host, kOfxPropertySuite, 1);
    ofx_g.fx = h->fetchSuite(h->host, kOfxImageEffectSuite, 1);
    ofx_g.param = h->fetchSuite(h->host, kOfxParameterSuite, 1);
    ofx_g.mt = h->fetchSuite(h->host, kOfxMultiThreadSuite, 1);
    ofx_g.mem = h->fetchSuite(h->host, kOfxMemorySuite, 1);
    ofx_g.msg = h->fetchSuite(h->host, kOfxMessageSuite, 1);
    ofx_g.msg2 = h->fetchSuite(h->host, kOfxMessageSuite, 2);
    if (!ofx_g.msg && ofx_g.msg2) /* V2 begins with V1's one function */
        ofx_g.msg = (const OfxMessageSuiteV1 *)ofx_g.msg2;
    if (!ofx_g.prop || !ofx_g.fx || !ofx_g.param) return kOfxStatErrMissingHostFeature;
    /* A host that does not say is taken at its word of the spec's default, which is access. */
    int temporal = 1;
    if (ofx_g.prop->propGetInt(h->host, kOfxImageEffectPropTemporalClipAccess, 0, &temporal) !=
        kOfxStatOK)
        temporal = 1;
    ofx_g.temporal = temporal != 0;
    int ndepths = 0;
    ofx_g.float_images = 1;
    if (ofx_g.prop->propGetDimension(h->host, kOfxImageEffectPropSupportedPixelDepths, &ndepths) ==
            kOfxStatOK &&
        ndepths > 0) {
        ofx_g.float_images = 0;
        for (int i = 0; i < ndepths; i++) {
            char *depth = NULL;
            if (ofx_g.prop->propGetString(h->host, kOfxImageEffectPropSupportedPixelDepths, i,
                                          &depth) == kOfxStatOK &&
                depth && !strcmp(depth, kOfxBitDepthFloat))
                ofx_g.float_images = 1;
        }
    }
    /* Multi-plane (Nuke, Natron): a look then reads the render's layers from Source. */
    int planar = 0;
    ofx_g.planes = h->fetchSuite(h->host, kFnOfxImageEffectPlaneSuite, 1);
    if (ofx_g.prop->propGetInt(h->host, kFnOfxImageEffectPropMultiPlanar, 0, &planar) != kOfxStatOK)
        planar = 0;
    ofx_g.multiplanar = planar && ofx_g.planes && ofx_g.planes->clipGetImagePlane;
    ofx_g.flow = flow_opencv_provider(); /* NULL without OpenCV: nothing is derived */
    ofx_find_data_dir();
    return kOfxStatOK;
}

/* ---- memory ---------------------------------------------------------------------------------- */

void *ofx_alloc(size_t bytes)
{
    void *p = NULL;
    if (ofx_g.mem) {
        if (ofx_g.mem->memoryAlloc(NULL, bytes ? bytes : 1, &p) != kOfxStatOK) return NULL;
        return p;
    }
    return malloc(bytes ? bytes : 1);
}

void ofx_free(void *p)
{
    if (!p) return;
    if (ofx_g.mem)
        ofx_g.mem->memoryFree(p);
    else
        free(p);
}

void *ofx_zalloc(size_t bytes)
{
    void *p = ofx_alloc(bytes);
    if (p) memset(p, 0, bytes);
    return p;
}

/* ---- properties ------------------------------------------------------------------------------ */

void ofx_set_str(OfxPropertySetHandle p, const char *name, int i, const char *v)
{
    (void)ofx_g.prop->propSetString(p, name, i, v);
}
void ofx_set_int(OfxPropertySetHandle p, const char *name, int i, int v)
{
    (void)ofx_g.prop->propSetInt(p, name, i, v);
}
void ofx_set_dbl(OfxPropertySetHandle p, const char *name, int i, double v)
{
    (void)ofx_g.prop->propSetDouble(p, name, i, v);
}

OfxPropertySetHandle ofx_clip_props(OfxImageClipHandle clip)
{
    OfxPropertySetHandle p = NULL;
    if (!clip || ofx_g.fx->clipGetPropertySet(clip, &p) != kOfxStatOK) return NULL;
    return p;
}

int ofx_clip_connected(OfxImageClipHandle clip)
{
    OfxPropertySetHandle p = ofx_clip_props(clip);
    int v = 0;
    if (p && ofx_g.prop->propGetInt(p, kOfxImageClipPropConnected, 0, &v) != kOfxStatOK) v = 0;
    return v;
}

OfxStatus ofx_render_request(OfxPropertySetHandle in_args, double *time, double scale[2],
                             int win[4])
{
    const OfxPropertySuiteV1 *ps = ofx_g.prop;
    *time = 0;
    scale[0] = scale[1] = 1;
    if (ps->propGetDouble(in_args, kOfxPropTime, 0, time) != kOfxStatOK ||
        ps->propGetIntN(in_args, kOfxImageEffectPropRenderWindow, 4, win) != kOfxStatOK)
        return kOfxStatErrBadHandle;
    if (ps->propGetDoubleN(in_args, kOfxImageEffectPropRenderScale, 2, scale) != kOfxStatOK ||
        !(scale[0] > 0))
        scale[0] = scale[1] = 1;
    if (!(scale[1] > 0)) scale[1] = scale[0];
    return kOfxStatOK;
}
