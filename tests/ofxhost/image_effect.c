/* nprfx OpenFX test host — the objects behind the handles (effects, which double as param sets,
 * clips, params and images, each tagged with its kind) and the image effect suite: clips defined
 * in describeInContext, and at render time the clip images served from the runner's inputs in
 * the profile's depth (at other frames through its fetch, only within what getFramesNeeded
 * declared and where the profile has temporal clip access; every frame served is recorded for
 * the frames check of frames.c) and the output image over the render in flight, plus the image
 * memory functions. */
#define _POSIX_C_SOURCE 200809L /* strdup, posix_memalign */
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "util/cli_util.h"
#include "ofx_host_internal.h"

heffect *internal_effect_of(const void *h)
{
    heffect *e = (heffect *)h;
    return e && e->props.magic == PROPS_MAGIC && e->props.kind == K_EFFECT ? e : NULL;
}
static hclip *clip_of(const void *h)
{
    hclip *c = (hclip *)h;
    return c && c->props.magic == PROPS_MAGIC && c->props.kind == K_CLIP ? c : NULL;
}
hparam *internal_param_of(const void *h)
{
    hparam *p = (hparam *)h;
    return p && p->props.magic == PROPS_MAGIC && p->props.kind == K_PARAM ? p : NULL;
}

static void param_free(hparam *p)
{
    if (!p) return;
    internal_props_free(&p->props);
    free(p->name);
    free(p->type);
    free(p->s);
    free(p);
}

static void clip_free(hclip *c)
{
    if (!c) return;
    internal_props_free(&c->props);
    free(c->name);
    free(c);
}

void internal_effect_free(heffect *e)
{
    if (!e) return;
    for (int i = 0; i < e->nclips; i++)
        clip_free(e->clips[i]);
    for (int i = 0; i < e->nparams; i++)
        param_free(e->params[i]);
    free(e->clips);
    free(e->params);
    internal_props_free(&e->props);
    free(e);
}

heffect *internal_effect_new(struct hplugin *pl, const char *type)
{
    heffect *e = calloc(1, sizeof *e);
    if (!e) return NULL;
    internal_props_init(&e->props, K_EFFECT);
    e->pl = pl;
    if (internal_set_string((OfxPropertySetHandle)&e->props, kOfxPropType, 0, type) != kOfxStatOK) {
        internal_effect_free(e);
        return NULL;
    }
    return e;
}

hclip *internal_effect_clip(const heffect *e, const char *name)
{
    for (int i = 0; i < e->nclips; i++)
        if (!strcmp(e->clips[i]->name, name)) return e->clips[i];
    return NULL;
}

hparam *internal_effect_param(const heffect *e, const char *name)
{
    for (int i = 0; i < e->nparams; i++)
        if (!strcmp(e->params[i]->name, name)) return e->params[i];
    return NULL;
}

hclip *internal_clip_add(heffect *e, const char *name)
{
    hclip **clips = realloc(e->clips, (size_t)(e->nclips + 1) * sizeof *clips);
    if (!clips) return NULL;
    e->clips = clips;
    hclip *c = calloc(1, sizeof *c);
    if (!c || !(c->name = strdup(name))) {
        free(c);
        return NULL;
    }
    internal_props_init(&c->props, K_CLIP);
    c->fx = e;
    c->input = -2;
    e->clips[e->nclips++] = c;
    return c;
}

hparam *internal_param_add(heffect *e, const char *type, const char *name)
{
    hparam **params = realloc(e->params, (size_t)(e->nparams + 1) * sizeof *params);
    if (!params) return NULL;
    e->params = params;
    hparam *p = calloc(1, sizeof *p);
    if (!p || !(p->name = strdup(name)) || !(p->type = strdup(type)) || !(p->s = strdup(""))) {
        if (p) {
            free(p->name);
            free(p->type);
        }
        free(p);
        return NULL;
    }
    internal_props_init(&p->props, K_PARAM);
    e->params[e->nparams++] = p;
    return p;
}

/* ---- image effect suite ---------------------------------------------------------------------- */

static OfxStatus fx_get_property_set(OfxImageEffectHandle fx, OfxPropertySetHandle *out)
{
    heffect *e = internal_effect_of(fx);
    if (!e || !out) return kOfxStatErrBadHandle;
    *out = (OfxPropertySetHandle)&e->props;
    return kOfxStatOK;
}

static OfxStatus fx_get_param_set(OfxImageEffectHandle fx, OfxParamSetHandle *out)
{
    heffect *e = internal_effect_of(fx);
    if (!e || !out) return kOfxStatErrBadHandle;
    *out = (OfxParamSetHandle)e;
    return kOfxStatOK;
}

static OfxStatus fx_clip_define(OfxImageEffectHandle fx, const char *name,
                                OfxPropertySetHandle *out)
{
    heffect *e = internal_effect_of(fx);
    if (!e || !name) return kOfxStatErrBadHandle;
    if (e->ni) return kOfxStatErrUnsupported; /* only in describeInContext */
    if (internal_effect_clip(e, name)) return kOfxStatErrExists;
    hclip *c = internal_clip_add(e, name);
    if (!c) return kOfxStatErrMemory;
    OfxPropertySetHandle p = (OfxPropertySetHandle)&c->props;
    internal_set_string(p, kOfxPropType, 0, kOfxTypeClip);
    internal_set_string(p, kOfxPropName, 0, name);
    internal_set_string(p, kOfxPropLabel, 0, name);
    internal_set_int(p, kOfxImageClipPropOptional, 0, 0);
    internal_set_int(p, kOfxImageClipPropIsMask, 0, 0);
    internal_set_int(p, kOfxImageEffectPropTemporalClipAccess, 0, 0);
    internal_set_int(p, kOfxImageEffectPropSupportsTiles, 0, 1);
    if (out) *out = p;
    return kOfxStatOK;
}

static OfxStatus fx_clip_get_handle(OfxImageEffectHandle fx, const char *name,
                                    OfxImageClipHandle *clip, OfxPropertySetHandle *props)
{
    heffect *e = internal_effect_of(fx);
    if (!e || !name) return kOfxStatErrBadHandle;
    hclip *c = internal_effect_clip(e, name);
    if (!c) return kOfxStatErrUnknown;
    if (clip) *clip = (OfxImageClipHandle)c;
    if (props) *props = (OfxPropertySetHandle)&c->props;
    return kOfxStatOK;
}

static OfxStatus fx_clip_get_property_set(OfxImageClipHandle clip, OfxPropertySetHandle *out)
{
    hclip *c = clip_of(clip);
    if (!c || !out) return kOfxStatErrBadHandle;
    *out = (OfxPropertySetHandle)&c->props;
    return kOfxStatOK;
}

/* OFX pixel rectangle of an nprfx rectangle, flipped with y_up = f - y_down. */
OfxRectI internal_ofx_rect(nprfx_rect r, int f)
{
    OfxRectI o = {r.x0, f - (r.y1 - 1), r.x1, f - r.y0 + 1};
    return o;
}

static int input_flip(const node_inst *ni, int k, const nprfx_image *v)
{
    if (ni->desc->inputs[k].flags & NPRFX_INPUT_UNALIGNED) return v->bounds.y0 + v->bounds.y1 - 1;
    return ni->frame_flip;
}

static void image_props(himage *im, const node_inst *ni, const char *comps, void *data, OfxRectI b,
                        int row_bytes, const char *id)
{
    OfxPropertySetHandle p = (OfxPropertySetHandle)&im->props;
    double s = internal_host_scale(ni->args);
    int bv[4] = {b.x1, b.y1, b.x2, b.y2};
    internal_set_string(p, kOfxPropType, 0, kOfxTypeImage);
    internal_set_string(p, kOfxImageEffectPropPixelDepth, 0,
                        internal_depth_name(ni->h->profile->depth));
    internal_set_string(p, kOfxImageEffectPropComponents, 0, comps);
    internal_set_string(p, kOfxImageEffectPropPreMultiplication, 0, kOfxImageUnPreMultiplied);
    internal_set_double(p, kOfxImageEffectPropRenderScale, 0, s);
    internal_set_double(p, kOfxImageEffectPropRenderScale, 1, s);
    internal_set_double(p, kOfxImagePropPixelAspectRatio, 0, 1.0);
    internal_set_pointer(p, kOfxImagePropData, 0, data);
    internal_set_int_n(p, kOfxImagePropBounds, 4, bv);
    internal_set_int_n(p, kOfxImagePropRegionOfDefinition, 4, bv);
    internal_set_int(p, kOfxImagePropRowBytes, 0, row_bytes);
    internal_set_string(p, kOfxImagePropField, 0, kOfxImageFieldNone);
    internal_set_string(p, kOfxImagePropUniqueIdentifier, 0, id);
}

/* The host image of an nprfx view: RGBA with the channels in R, G, B, A order and the rest 0, or
 * Alpha for a 1-channel main input (see inst_create, render.c), in the profile's depth. Rows are
 * laid out top-down in memory, padded by one pixel, so rowBytes is negative and wider than the
 * row: the adapter must cope with both, as with hosts that do this. */
static himage *pack_image(node_inst *ni, int f, const nprfx_image *v, int nc, const char *comps,
                          const char *id)
{
    int w = nprfx_rect_width(v->bounds), hgt = nprfx_rect_height(v->bounds);
    hdepth depth = ni->h->profile->depth;
    size_t es = internal_depth_size(depth);
    himage *im = calloc(1, sizeof *im);
    size_t stride = ((size_t)w + 1) * (size_t)nc; /* components per memory row */
    if (!im || !(im->pixels = calloc(stride * (size_t)(hgt > 0 ? hgt : 1), es))) {
        free(im);
        return NULL;
    }
    internal_props_init(&im->props, K_IMAGE);
    im->ni = ni;
    int n = v->channels < nc ? v->channels : nc;
    for (int y = v->bounds.y0; y < v->bounds.y1; y++)
        for (int x = v->bounds.x0; x < v->bounds.x1; x++) {
            const float *s = nprfx_image_at(v, x, y);
            size_t d =
                (size_t)(y - v->bounds.y0) * stride + (size_t)(x - v->bounds.x0) * (size_t)nc;
            for (int c = 0; c < n; c++)
                internal_depth_store(depth, im->pixels, d + (size_t)c, s[c]);
        }
    OfxRectI b = internal_ofx_rect(v->bounds, f);
    /* OFX data points at the bottom row (y1), the last one in memory */
    char *data = (char *)im->pixels + (size_t)(hgt > 0 ? hgt - 1 : 0) * stride * es;
    image_props(im, ni, comps, data, b, -(int)(stride * es), id);
    return im;
}

/* The host image of an nprfx view: RGBA with the channels in R, G, B, A order and the rest 0, or
 * Alpha for a 1-channel main input (see inst_create, render.c), in the profile's depth. Rows are
 * laid out top-down in memory, padded by one pixel, so rowBytes is negative and wider than the
 * row: the adapter must cope with both, as with hosts that do this. */
static himage *pack_input(node_inst *ni, int k, const nprfx_image *v, double time)
{
    char id[64];
    snprintf(id, sizeof id, "input%d@%g", k, time);
    int nc = ni->in_comps[k];
    return pack_image(ni, input_flip(ni, k, v), v, nc,
                      nc == 1 ? kOfxImageComponentAlpha : kOfxImageComponentRGBA, id);
}

/* A fetch of input k at time other than the render's must be declared, and possible in this
 * host; every fetch is recorded (frames.c). Called with the host's lock held. */
static OfxStatus fetch_allowed(node_inst *ni, const hclip *c, int k, double time)
{
    nprfx_ofx_host *h = ni->h;
    const nprfx_render_args *a = ni->args;
    if (time != a->time) {
        if (!h->profile->temporal) {
            snprintf(ni->host_error, sizeof ni->host_error,
                     "clip %s fetched at frame %g while rendering frame %g: this host (%s) has no "
                     "temporal clip access",
                     c->name, time, a->time, h->profile->like);
            return kOfxStatFailed;
        }
        if (!ni->analyzing && !internal_frames_allows(&ni->frames[k], time)) {
            snprintf(ni->host_error, sizeof ni->host_error,
                     "clip %s fetched at frame %g, outside the frames that getFramesNeeded "
                     "declared",
                     c->name, time);
            return kOfxStatFailed;
        }
    }
    /* The render time counts as fetched too: a clip the plug-in reads only at other frames must
     * not declare the current one (frames.c). */
    return internal_frames_fetched(&ni->frames[k], time) ? kOfxStatOK : kOfxStatErrMemory;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static OfxStatus clip_get_image(OfxImageClipHandle clip, OfxTime time, const OfxRectD *region,
                                OfxPropertySetHandle *out);

/* Every image the host serves, timed: what the host spends, apart from the plug-in's own work
 * (look.c reports both). */
static OfxStatus fx_clip_get_image(OfxImageClipHandle clip, OfxTime time, const OfxRectD *region,
                                   OfxPropertySetHandle *out)
{
    double t0 = now_seconds();
    OfxStatus st = clip_get_image(clip, time, region, out);
    nprfx_ofx_host *h = internal_g_host;
    if (h) { /* several look nodes render at once (look.c --outputs all) */
        pthread_mutex_lock(&h->lock);
        h->serve_seconds += now_seconds() - t0;
        pthread_mutex_unlock(&h->lock);
    }
    return st;
}

static OfxStatus clip_get_image(OfxImageClipHandle clip, OfxTime time, const OfxRectD *region,
                                OfxPropertySetHandle *out)
{
    (void)region; /* inputs are served whole */
    hclip *c = clip_of(clip);
    if (!c || !out) return kOfxStatErrBadHandle;
    node_inst *ni = c->fx->ni;
    if (!ni || !ni->args) return kOfxStatFailed;
    nprfx_ofx_host *h = ni->h;
    const nprfx_render_args *a = ni->args;
    if (c->input == -1) {
        if (!ni->out_pixels) return kOfxStatFailed; /* only while rendering */
        himage *im = calloc(1, sizeof *im);
        if (!im) return kOfxStatErrMemory;
        internal_props_init(&im->props, K_IMAGE);
        im->ni = ni;
        image_props(im, ni, ni->out_comps == 1 ? kOfxImageComponentAlpha : kOfxImageComponentRGBA,
                    ni->out_pixels, ni->out_bounds, ni->out_row_bytes, "output");
        __atomic_add_fetch(&ni->images, 1, __ATOMIC_RELAXED);
        *out = (OfxPropertySetHandle)&im->props;
        return kOfxStatOK;
    }
    int k = c->input;
    if (k < 0 || !a->inputs[k].data) return kOfxStatFailed;
    pthread_mutex_lock(&h->lock);
    nprfx_image view = a->inputs[k];
    OfxStatus st = fetch_allowed(ni, c, k, time);
    if (st == kOfxStatOK && time != a->time &&
        (!a->fetch || a->fetch(a->fetch_user, k, time, &view) != NPRFX_OK)) {
        snprintf(ni->host_error, sizeof ni->host_error, "clip %s: no image at frame %g: %s",
                 c->name, time, cli_message(a->ctx));
        st = kOfxStatFailed;
    }
    himage *im = NULL;
    if (st == kOfxStatOK && !(im = pack_input(ni, k, &view, time))) st = kOfxStatErrMemory;
    pthread_mutex_unlock(&h->lock);
    if (st != kOfxStatOK) return st;
    __atomic_add_fetch(&ni->images, 1, __ATOMIC_RELAXED);
    *out = (OfxPropertySetHandle)&im->props;
    return kOfxStatOK;
}

/* The plane suite (profile planes): the colour plane as clipGetImage gives it; another layer of
 * the main input from the plane source (look.c), with the frame checks of any fetch. */
static OfxStatus fx_clip_get_image_plane(OfxImageClipHandle clip, OfxTime time, const char *plane,
                                         OfxRectD *region, OfxPropertySetHandle *out)
{
    if (!plane || !out) return kOfxStatErrBadHandle;
    if (!strcmp(plane, kFnOfxImagePlaneColour)) return fx_clip_get_image(clip, time, region, out);
    double t0 = now_seconds();
    hclip *c = clip_of(clip);
    if (!c) return kOfxStatErrBadHandle;
    node_inst *ni = c->fx->ni;
    if (!ni || !ni->args) return kOfxStatFailed;
    nprfx_ofx_host *h = ni->h;
    int k = c->input, listed = 0;
    for (int i = 0; i < h->nplanes; i++)
        listed |= !strcmp(h->planes[i], plane);
    if (k < 0 || k != ofx_names_main_input(ni->desc) || !listed || !h->plane_fetch) {
        snprintf(ni->host_error, sizeof ni->host_error,
                 "clip %s has no plane '%s' (kFnOfxImageEffectPropComponentsPresent lists what "
                 "it has)",
                 c->name, plane);
        return kOfxStatFailed;
    }
    /* each render's own server (look.c: the look node's) */
    void *plane_user = ni->args->fetch_user;
    pthread_mutex_lock(&h->lock);
    OfxStatus st = fetch_allowed(ni, c, k, time);
    nprfx_image view;
    memset(&view, 0, sizeof view);
    if (st == kOfxStatOK && h->plane_fetch(plane_user, time, plane, &view) != NPRFX_OK) {
        snprintf(ni->host_error, sizeof ni->host_error, "clip %s: no plane '%s' at frame %g",
                 c->name, plane, time);
        st = kOfxStatFailed;
    }
    himage *im = NULL;
    char id[300];
    snprintf(id, sizeof id, "plane %.200s@%g", plane, time);
    if (st == kOfxStatOK && !(im = pack_image(ni, ni->frame_flip, &view, view.channels, plane, id)))
        st = kOfxStatErrMemory;
    h->serve_seconds += now_seconds() - t0;
    pthread_mutex_unlock(&h->lock);
    if (st != kOfxStatOK) return st;
    __atomic_add_fetch(&ni->images, 1, __ATOMIC_RELAXED);
    *out = (OfxPropertySetHandle)&im->props;
    return kOfxStatOK;
}

const FnOfxImageEffectPlaneSuiteV1 internal_plane_suite = {fx_clip_get_image_plane};

static OfxStatus fx_clip_release_image(OfxPropertySetHandle image)
{
    himage *im = (himage *)image;
    if (!im || im->props.magic != PROPS_MAGIC || im->props.kind != K_IMAGE)
        return kOfxStatErrBadHandle;
    if (im->ni) __atomic_sub_fetch(&im->ni->images, 1, __ATOMIC_RELAXED);
    internal_props_free(&im->props);
    free(im->pixels);
    free(im);
    return kOfxStatOK;
}

static OfxStatus fx_clip_get_rod(OfxImageClipHandle clip, OfxTime time, OfxRectD *bounds)
{
    (void)time; /* plates keep their size over a shot */
    hclip *c = clip_of(clip);
    if (!c || !bounds) return kOfxStatErrBadHandle;
    node_inst *ni = c->fx->ni;
    if (!ni || !ni->args) return kOfxStatFailed;
    const nprfx_render_args *a = ni->args;
    OfxRectI r;
    if (c->input == -1)
        r = internal_ofx_rect(a->frame, ni->frame_flip);
    else if (c->input >= 0 && a->inputs[c->input].data)
        r = internal_ofx_rect(a->inputs[c->input].bounds,
                              input_flip(ni, c->input, &a->inputs[c->input]));
    else
        return kOfxStatFailed;
    double s = internal_host_scale(a);
    bounds->x1 = r.x1 / s;
    bounds->y1 = r.y1 / s;
    bounds->x2 = r.x2 / s;
    bounds->y2 = r.y2 / s;
    return kOfxStatOK;
}

static int fx_abort(OfxImageEffectHandle fx)
{
    (void)fx;
    return 0;
}

typedef struct hmemory {
    uint32_t magic;
    void *ptr;
} hmemory;

static OfxStatus fx_memory_alloc(OfxImageEffectHandle fx, size_t n, OfxImageMemoryHandle *out)
{
    (void)fx;
    hmemory *m = calloc(1, sizeof *m);
    if (!m || posix_memalign(&m->ptr, 16, n ? n : 1)) {
        free(m);
        if (out) *out = NULL;
        return kOfxStatErrMemory;
    }
    m->magic = PROPS_MAGIC ^ 1u;
    *out = (OfxImageMemoryHandle)m;
    return kOfxStatOK;
}
static OfxStatus fx_memory_free(OfxImageMemoryHandle h)
{
    hmemory *m = (hmemory *)h;
    if (!m || m->magic != (PROPS_MAGIC ^ 1u)) return kOfxStatErrBadHandle;
    free(m->ptr);
    free(m);
    return kOfxStatOK;
}
static OfxStatus fx_memory_lock(OfxImageMemoryHandle h, void **ptr)
{
    hmemory *m = (hmemory *)h;
    if (!m || m->magic != (PROPS_MAGIC ^ 1u)) return kOfxStatErrBadHandle;
    *ptr = m->ptr;
    return kOfxStatOK;
}
static OfxStatus fx_memory_unlock(OfxImageMemoryHandle h)
{
    hmemory *m = (hmemory *)h;
    return m && m->magic == (PROPS_MAGIC ^ 1u) ? kOfxStatOK : kOfxStatErrBadHandle;
}

const OfxImageEffectSuiteV1 internal_image_effect_suite = {
    fx_get_property_set,   fx_get_param_set,         fx_clip_define,
    fx_clip_get_handle,    fx_clip_get_property_set, fx_clip_get_image,
    fx_clip_release_image, fx_clip_get_rod,          fx_abort,
    fx_memory_alloc,       fx_memory_free,           fx_memory_lock,
    fx_memory_unlock};
