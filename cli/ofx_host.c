#define _POSIX_C_SOURCE 200809L /* strdup, posix_memalign */
/* nprfx CLI — the OpenFX test host (see ofx_host.h).
 *
 * Objects. Every handle the plug-in sees points at an hprops (a property set) or at a struct
 * that starts with one, tagged with a kind, so a wrong handle is caught instead of read as
 * garbage: effects (plug-in descriptors, context descriptors, instances) double as param sets,
 * and clips, params and images carry their own properties.
 *
 * Strictness. The host is lenient where hosts differ (unknown properties may be set) and strict
 * where a mistake in the adapter would go unnoticed in a real host: getting a property of the
 * wrong type, describing params that do not match the node descriptor, fetching a frame the
 * plug-in did not declare in getFramesNeeded, a region of definition other than the frame, or
 * an image not released by the end of an action all fail. */
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "ofx/ofx_api.h"
#include "ofx/ofx_names.h"
#include "ofx_host.h"

/* ---- property sets --------------------------------------------------------------------------- */

typedef enum pkind { K_PLAIN = 1, K_EFFECT, K_CLIP, K_PARAM, K_IMAGE } pkind;
typedef enum ptype { PT_INT, PT_DOUBLE, PT_STRING, PT_POINTER } ptype;

typedef struct prop {
    char *name;
    ptype type;
    int dim;
    union {
        int *i;
        double *d;
        char **s;
        void **p;
    } v;
} prop;

#define PROPS_MAGIC 0x6e70f0f0u /* "np" and a pattern: tags every live object */
typedef struct hprops {
    uint32_t magic;
    pkind kind;
    prop *items;
    int count, cap;
} hprops;

static void props_init(hprops *p, pkind kind)
{
    memset(p, 0, sizeof *p);
    p->magic = PROPS_MAGIC;
    p->kind = kind;
}

static void prop_clear(prop *q)
{
    if (q->type == PT_STRING)
        for (int k = 0; k < q->dim; k++)
            free(q->v.s[k]);
    free(q->v.p);
    q->v.p = NULL;
    q->dim = 0;
}

static void props_free(hprops *p)
{
    if (!p) return;
    for (int i = 0; i < p->count; i++) {
        prop_clear(&p->items[i]);
        free(p->items[i].name);
    }
    free(p->items);
    p->items = NULL;
    p->count = p->cap = 0;
    p->magic = 0;
}

static hprops *props_of(OfxPropertySetHandle h)
{
    hprops *p = (hprops *)h;
    return p && p->magic == PROPS_MAGIC ? p : NULL;
}

static prop *prop_find(hprops *p, const char *name)
{
    for (int i = 0; i < p->count; i++)
        if (!strcmp(p->items[i].name, name)) return &p->items[i];
    return NULL;
}

/* The property `name` of `type` with at least `dim` values, created (zeroed) when absent. */
static OfxStatus prop_get_for_set(hprops *p, const char *name, ptype type, int dim, prop **out)
{
    prop *q = prop_find(p, name);
    if (q && q->type != type) return kOfxStatErrValue;
    if (!q) {
        if (p->count == p->cap) {
            int cap = p->cap ? p->cap * 2 : 16;
            prop *items = realloc(p->items, (size_t)cap * sizeof *items);
            if (!items) return kOfxStatErrMemory;
            p->items = items;
            p->cap = cap;
        }
        q = &p->items[p->count];
        memset(q, 0, sizeof *q);
        if (!(q->name = strdup(name))) return kOfxStatErrMemory;
        q->type = type;
        p->count++;
    }
    if (dim > q->dim) {
        size_t esize = type == PT_INT      ? sizeof(int)
                       : type == PT_DOUBLE ? sizeof(double)
                                           : sizeof(void *);
        void *v = realloc(q->v.p, (size_t)dim * esize);
        if (!v) return kOfxStatErrMemory;
        memset((char *)v + (size_t)q->dim * esize, 0, (size_t)(dim - q->dim) * esize);
        q->v.p = v;
        q->dim = dim;
    }
    *out = q;
    return kOfxStatOK;
}

static OfxStatus prop_get_for_get(OfxPropertySetHandle h, const char *name, ptype type, int index,
                                  prop **out)
{
    hprops *p = props_of(h);
    if (!p || !name) return kOfxStatErrBadHandle;
    prop *q = prop_find(p, name);
    if (!q) return kOfxStatErrUnknown;
    if (q->type != type) return kOfxStatErrValue;
    if (index < 0 || index >= q->dim) return kOfxStatErrBadIndex;
    *out = q;
    return kOfxStatOK;
}

static OfxStatus set_pointer(OfxPropertySetHandle h, const char *name, int i, void *v)
{
    prop *q;
    hprops *p = props_of(h);
    if (!p || i < 0) return kOfxStatErrBadHandle;
    OfxStatus st = prop_get_for_set(p, name, PT_POINTER, i + 1, &q);
    if (st == kOfxStatOK) q->v.p[i] = v;
    return st;
}

static OfxStatus set_string(OfxPropertySetHandle h, const char *name, int i, const char *v)
{
    prop *q;
    hprops *p = props_of(h);
    if (!p || i < 0) return kOfxStatErrBadHandle;
    OfxStatus st = prop_get_for_set(p, name, PT_STRING, i + 1, &q);
    if (st != kOfxStatOK) return st;
    char *copy = strdup(v ? v : ""); /* the host owns its copy of every string */
    if (!copy) return kOfxStatErrMemory;
    free(q->v.s[i]);
    q->v.s[i] = copy;
    return kOfxStatOK;
}

static OfxStatus set_double(OfxPropertySetHandle h, const char *name, int i, double v)
{
    prop *q;
    hprops *p = props_of(h);
    if (!p || i < 0) return kOfxStatErrBadHandle;
    OfxStatus st = prop_get_for_set(p, name, PT_DOUBLE, i + 1, &q);
    if (st == kOfxStatOK) q->v.d[i] = v;
    return st;
}

static OfxStatus set_int(OfxPropertySetHandle h, const char *name, int i, int v)
{
    prop *q;
    hprops *p = props_of(h);
    if (!p || i < 0) return kOfxStatErrBadHandle;
    OfxStatus st = prop_get_for_set(p, name, PT_INT, i + 1, &q);
    if (st == kOfxStatOK) q->v.i[i] = v;
    return st;
}

static OfxStatus set_pointer_n(OfxPropertySetHandle h, const char *name, int n, void *const *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = n - 1; i >= 0 && st == kOfxStatOK; i--)
        st = set_pointer(h, name, i, v[i]);
    return st;
}
static OfxStatus set_string_n(OfxPropertySetHandle h, const char *name, int n, const char *const *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = n - 1; i >= 0 && st == kOfxStatOK; i--)
        st = set_string(h, name, i, v[i]);
    return st;
}
static OfxStatus set_double_n(OfxPropertySetHandle h, const char *name, int n, const double *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = n - 1; i >= 0 && st == kOfxStatOK; i--)
        st = set_double(h, name, i, v[i]);
    return st;
}
static OfxStatus set_int_n(OfxPropertySetHandle h, const char *name, int n, const int *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = n - 1; i >= 0 && st == kOfxStatOK; i--)
        st = set_int(h, name, i, v[i]);
    return st;
}

static OfxStatus get_pointer(OfxPropertySetHandle h, const char *name, int i, void **v)
{
    prop *q;
    OfxStatus st = prop_get_for_get(h, name, PT_POINTER, i, &q);
    if (st == kOfxStatOK) *v = q->v.p[i];
    return st;
}
static OfxStatus get_string(OfxPropertySetHandle h, const char *name, int i, char **v)
{
    prop *q;
    OfxStatus st = prop_get_for_get(h, name, PT_STRING, i, &q);
    if (st == kOfxStatOK) *v = q->v.s[i];
    return st;
}
static OfxStatus get_double(OfxPropertySetHandle h, const char *name, int i, double *v)
{
    prop *q;
    OfxStatus st = prop_get_for_get(h, name, PT_DOUBLE, i, &q);
    if (st == kOfxStatOK) *v = q->v.d[i];
    return st;
}
static OfxStatus get_int(OfxPropertySetHandle h, const char *name, int i, int *v)
{
    prop *q;
    OfxStatus st = prop_get_for_get(h, name, PT_INT, i, &q);
    if (st == kOfxStatOK) *v = q->v.i[i];
    return st;
}
static OfxStatus get_pointer_n(OfxPropertySetHandle h, const char *name, int n, void **v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = 0; i < n && st == kOfxStatOK; i++)
        st = get_pointer(h, name, i, &v[i]);
    return st;
}
static OfxStatus get_string_n(OfxPropertySetHandle h, const char *name, int n, char **v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = 0; i < n && st == kOfxStatOK; i++)
        st = get_string(h, name, i, &v[i]);
    return st;
}
static OfxStatus get_double_n(OfxPropertySetHandle h, const char *name, int n, double *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = 0; i < n && st == kOfxStatOK; i++)
        st = get_double(h, name, i, &v[i]);
    return st;
}
static OfxStatus get_int_n(OfxPropertySetHandle h, const char *name, int n, int *v)
{
    OfxStatus st = kOfxStatOK;
    for (int i = 0; i < n && st == kOfxStatOK; i++)
        st = get_int(h, name, i, &v[i]);
    return st;
}

static OfxStatus prop_reset(OfxPropertySetHandle h, const char *name)
{
    hprops *p = props_of(h);
    if (!p) return kOfxStatErrBadHandle;
    prop *q = prop_find(p, name);
    if (!q) return kOfxStatErrUnknown;
    return kOfxStatOK; /* no defaults are tracked: values stay as they are */
}

static OfxStatus prop_dimension(OfxPropertySetHandle h, const char *name, int *count)
{
    hprops *p = props_of(h);
    if (!p) return kOfxStatErrBadHandle;
    prop *q = prop_find(p, name);
    if (!q) return kOfxStatErrUnknown;
    *count = q->dim;
    return kOfxStatOK;
}

static const OfxPropertySuiteV1 property_suite = {
    set_pointer,   set_string,   set_double,   set_int,    set_pointer_n, set_string_n,
    set_double_n,  set_int_n,    get_pointer,  get_string, get_double,    get_int,
    get_pointer_n, get_string_n, get_double_n, get_int_n,  prop_reset,    prop_dimension};

/* Copy every property of src into dst (dst's own values of the same names are replaced). */
static OfxStatus props_copy(hprops *dst, const hprops *src)
{
    for (int i = 0; i < src->count; i++) {
        const prop *q = &src->items[i];
        OfxPropertySetHandle d = (OfxPropertySetHandle)dst;
        OfxStatus st = kOfxStatOK;
        for (int k = q->dim - 1; k >= 0 && st == kOfxStatOK; k--)
            switch (q->type) {
            case PT_INT:
                st = set_int(d, q->name, k, q->v.i[k]);
                break;
            case PT_DOUBLE:
                st = set_double(d, q->name, k, q->v.d[k]);
                break;
            case PT_STRING:
                st = set_string(d, q->name, k, q->v.s[k]);
                break;
            case PT_POINTER:
                st = set_pointer(d, q->name, k, q->v.p[k]);
                break;
            }
        if (st != kOfxStatOK) return st;
    }
    return kOfxStatOK;
}

static const char *pstr(hprops *p, const char *name, int i, const char *fallback)
{
    char *v = NULL;
    return get_string((OfxPropertySetHandle)p, name, i, &v) == kOfxStatOK && v ? v : fallback;
}
static int pint(hprops *p, const char *name, int i, int fallback)
{
    int v;
    return get_int((OfxPropertySetHandle)p, name, i, &v) == kOfxStatOK ? v : fallback;
}
static int pdim(hprops *p, const char *name)
{
    int n = 0;
    return prop_dimension((OfxPropertySetHandle)p, name, &n) == kOfxStatOK ? n : 0;
}

/* ---- effects, clips, params, images ---------------------------------------------------------- */

struct node_inst;
struct hplugin;

typedef struct hparam {
    hprops props; /* first: the param's handle is also its property set */
    char *name, *type;
    int i;
    double d[4];
    char *s;
} hparam;

typedef struct hclip {
    hprops props;
    char *name;
    struct heffect *fx;
    int input; /* node input index; -1 Output; -2 another clip (Mask) */
} hclip;

typedef struct heffect {
    hprops props; /* first: getPropertySet and the param set's property set */
    struct hplugin *pl;
    hclip **clips;
    int nclips;
    hparam **params;
    int nparams;
    struct node_inst *ni; /* instances only */
} heffect;

typedef struct himage {
    hprops props;
    float *pixels;        /* owned; NULL for the output image, which points into its node's */
    struct node_inst *ni; /* whose render handed it out */
} himage;

static heffect *effect_of(const void *h)
{
    heffect *e = (heffect *)h;
    return e && e->props.magic == PROPS_MAGIC && e->props.kind == K_EFFECT ? e : NULL;
}
static hclip *clip_of(const void *h)
{
    hclip *c = (hclip *)h;
    return c && c->props.magic == PROPS_MAGIC && c->props.kind == K_CLIP ? c : NULL;
}
static hparam *param_of(const void *h)
{
    hparam *p = (hparam *)h;
    return p && p->props.magic == PROPS_MAGIC && p->props.kind == K_PARAM ? p : NULL;
}

static void param_free(hparam *p)
{
    if (!p) return;
    props_free(&p->props);
    free(p->name);
    free(p->type);
    free(p->s);
    free(p);
}

static void clip_free(hclip *c)
{
    if (!c) return;
    props_free(&c->props);
    free(c->name);
    free(c);
}

static void effect_free(heffect *e)
{
    if (!e) return;
    for (int i = 0; i < e->nclips; i++)
        clip_free(e->clips[i]);
    for (int i = 0; i < e->nparams; i++)
        param_free(e->params[i]);
    free(e->clips);
    free(e->params);
    props_free(&e->props);
    free(e);
}

static heffect *effect_new(struct hplugin *pl, const char *type)
{
    heffect *e = calloc(1, sizeof *e);
    if (!e) return NULL;
    props_init(&e->props, K_EFFECT);
    e->pl = pl;
    if (set_string((OfxPropertySetHandle)&e->props, kOfxPropType, 0, type) != kOfxStatOK) {
        effect_free(e);
        return NULL;
    }
    return e;
}

static hclip *effect_clip(const heffect *e, const char *name)
{
    for (int i = 0; i < e->nclips; i++)
        if (!strcmp(e->clips[i]->name, name)) return e->clips[i];
    return NULL;
}

static hparam *effect_param(const heffect *e, const char *name)
{
    for (int i = 0; i < e->nparams; i++)
        if (!strcmp(e->params[i]->name, name)) return e->params[i];
    return NULL;
}

static hclip *clip_add(heffect *e, const char *name)
{
    hclip **clips = realloc(e->clips, (size_t)(e->nclips + 1) * sizeof *clips);
    if (!clips) return NULL;
    e->clips = clips;
    hclip *c = calloc(1, sizeof *c);
    if (!c || !(c->name = strdup(name))) {
        free(c);
        return NULL;
    }
    props_init(&c->props, K_CLIP);
    c->fx = e;
    c->input = -2;
    e->clips[e->nclips++] = c;
    return c;
}

static hparam *param_add(heffect *e, const char *type, const char *name)
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
    props_init(&p->props, K_PARAM);
    e->params[e->nparams++] = p;
    return p;
}

/* ---- the host
 * ------------------------------------------------------------------------------------ */

typedef struct hplugin {
    OfxPlugin *p;
    const nprfx_node_desc *desc; /* the node of this binary with the same identifier, or NULL */
    int loaded;
    heffect *descriptor, *general, *filter;
} hplugin;

struct nprfx_ofx_host {
    nprfx_context *ctx;
    const nprfx_executor *exec;
    char *bundle, *binary;
    void *dl;
    int nplugins;
    hplugin *plugins;
    hprops props;
    OfxHost ofx;
    nprfx_render_hook hook;
    pthread_mutex_t lock; /* clip image requests: the runner's fetch is not thread-safe */
    char message[1024];   /* the plug-in's last error message */
    int instances;
};

/* Suite functions get no user pointer: they reach the host through this, and one host per
 * process keeps that unambiguous. */
static nprfx_ofx_host *g_host;

/* Per graph node: the instance and what the render in flight needs. */
typedef struct node_inst {
    nprfx_ofx_host *h;
    hplugin *pl;
    heffect *fx;
    const nprfx_node_desc *desc;
    const nprfx_render_args *args; /* set while the runner renders this node */
    int frame_flip;                /* y_up = frame_flip - y_down for frame-aligned images */
    double *need_lo, *need_hi;     /* per input: the frames getFramesNeeded declared */
    int began;                     /* beginSequenceRender sent */
    int *in_comps;                 /* per input clip: 4 RGBA, 1 Alpha */
    int out_comps;                 /* Output clip components: 4 RGBA, 1 Alpha */
    float *out_pixels;             /* the output image of the render in flight */
    OfxRectI out_bounds;
    int out_row_bytes;
    int images; /* images handed out and not yet released */
} node_inst;

static void host_message(nprfx_ofx_host *h, const char *type, const char *text)
{
    if (!h) return;
    if (!strcmp(type, kOfxMessageError) || !strcmp(type, kOfxMessageFatal)) {
        pthread_mutex_lock(&h->lock);
        snprintf(h->message, sizeof h->message, "%s", text);
        pthread_mutex_unlock(&h->lock);
    } else if (strcmp(type, kOfxMessageLog)) {
        fprintf(stderr, "ofx: %s\n", text);
    }
}

/* ---- image effect suite
 * --------------------------------------------------------------------------- */

static OfxStatus fx_get_property_set(OfxImageEffectHandle fx, OfxPropertySetHandle *out)
{
    heffect *e = effect_of(fx);
    if (!e || !out) return kOfxStatErrBadHandle;
    *out = (OfxPropertySetHandle)&e->props;
    return kOfxStatOK;
}

static OfxStatus fx_get_param_set(OfxImageEffectHandle fx, OfxParamSetHandle *out)
{
    heffect *e = effect_of(fx);
    if (!e || !out) return kOfxStatErrBadHandle;
    *out = (OfxParamSetHandle)e;
    return kOfxStatOK;
}

static OfxStatus fx_clip_define(OfxImageEffectHandle fx, const char *name,
                                OfxPropertySetHandle *out)
{
    heffect *e = effect_of(fx);
    if (!e || !name) return kOfxStatErrBadHandle;
    if (e->ni) return kOfxStatErrUnsupported; /* only in describeInContext */
    if (effect_clip(e, name)) return kOfxStatErrExists;
    hclip *c = clip_add(e, name);
    if (!c) return kOfxStatErrMemory;
    OfxPropertySetHandle p = (OfxPropertySetHandle)&c->props;
    set_string(p, kOfxPropType, 0, kOfxTypeClip);
    set_string(p, kOfxPropName, 0, name);
    set_string(p, kOfxPropLabel, 0, name);
    set_int(p, kOfxImageClipPropOptional, 0, 0);
    set_int(p, kOfxImageClipPropIsMask, 0, 0);
    set_int(p, kOfxImageEffectPropTemporalClipAccess, 0, 0);
    set_int(p, kOfxImageEffectPropSupportsTiles, 0, 1);
    if (out) *out = p;
    return kOfxStatOK;
}

static OfxStatus fx_clip_get_handle(OfxImageEffectHandle fx, const char *name,
                                    OfxImageClipHandle *clip, OfxPropertySetHandle *props)
{
    heffect *e = effect_of(fx);
    if (!e || !name) return kOfxStatErrBadHandle;
    hclip *c = effect_clip(e, name);
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
static OfxRectI ofx_rect(nprfx_rect r, int f)
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
    double s = ni->args->render_scale;
    int bv[4] = {b.x1, b.y1, b.x2, b.y2};
    set_string(p, kOfxPropType, 0, kOfxTypeImage);
    set_string(p, kOfxImageEffectPropPixelDepth, 0, kOfxBitDepthFloat);
    set_string(p, kOfxImageEffectPropComponents, 0, comps);
    set_string(p, kOfxImageEffectPropPreMultiplication, 0, kOfxImageUnPreMultiplied);
    set_double(p, kOfxImageEffectPropRenderScale, 0, s);
    set_double(p, kOfxImageEffectPropRenderScale, 1, s);
    set_double(p, kOfxImagePropPixelAspectRatio, 0, 1.0);
    set_pointer(p, kOfxImagePropData, 0, data);
    set_int_n(p, kOfxImagePropBounds, 4, bv);
    set_int_n(p, kOfxImagePropRegionOfDefinition, 4, bv);
    set_int(p, kOfxImagePropRowBytes, 0, row_bytes);
    set_string(p, kOfxImagePropField, 0, kOfxImageFieldNone);
    set_string(p, kOfxImagePropUniqueIdentifier, 0, id);
}

/* The host image of an nprfx view: RGBA with the channels in R, G, B, A order and the rest 0, or
 * Alpha for a 1-channel main input (see inst_create). Rows are laid out top-down in memory,
 * padded by one pixel, so rowBytes is negative and wider than the row: the adapter must cope
 * with both, as with hosts that do this. */
static himage *pack_input(node_inst *ni, int k, const nprfx_image *v, double time)
{
    int w = nprfx_rect_width(v->bounds), hgt = nprfx_rect_height(v->bounds);
    int f = input_flip(ni, k, v), nc = ni->in_comps[k];
    himage *im = calloc(1, sizeof *im);
    size_t stride = ((size_t)w + 1) * (size_t)nc; /* floats per memory row */
    if (!im || !(im->pixels = calloc(stride * (size_t)(hgt > 0 ? hgt : 1), sizeof(float)))) {
        free(im);
        return NULL;
    }
    props_init(&im->props, K_IMAGE);
    im->ni = ni;
    int n = v->channels < nc ? v->channels : nc;
    for (int y = v->bounds.y0; y < v->bounds.y1; y++)
        for (int x = v->bounds.x0; x < v->bounds.x1; x++) {
            const float *s = nprfx_image_at(v, x, y);
            float *d = im->pixels + (size_t)(y - v->bounds.y0) * stride +
                       (size_t)(x - v->bounds.x0) * (size_t)nc;
            for (int c = 0; c < n; c++)
                d[c] = s[c];
        }
    OfxRectI b = ofx_rect(v->bounds, f);
    /* OFX data points at the bottom row (y1), the last one in memory */
    float *data = im->pixels + (size_t)(hgt > 0 ? hgt - 1 : 0) * stride;
    char id[64];
    snprintf(id, sizeof id, "input%d@%g", k, time);
    image_props(im, ni, nc == 1 ? kOfxImageComponentAlpha : kOfxImageComponentRGBA, data, b,
                -(int)(stride * sizeof(float)), id);
    return im;
}

static OfxStatus fx_clip_get_image(OfxImageClipHandle clip, OfxTime time, const OfxRectD *region,
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
        props_init(&im->props, K_IMAGE);
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
    OfxStatus st = kOfxStatOK;
    nprfx_image view = a->inputs[k];
    if (time != a->time) {
        if (time < ni->need_lo[k] || time > ni->need_hi[k]) {
            snprintf(h->message, sizeof h->message,
                     "clip %s fetched at frame %g, outside the frames %g-%g that getFramesNeeded "
                     "declared",
                     c->name, time, ni->need_lo[k], ni->need_hi[k]);
            st = kOfxStatFailed;
        } else if (!a->fetch || a->fetch(a->fetch_user, k, time, &view) != NPRFX_OK) {
            snprintf(h->message, sizeof h->message, "clip %s: no image at frame %g: %s", c->name,
                     time, nprfx_cli_message(a->ctx));
            st = kOfxStatFailed;
        }
    }
    himage *im = NULL;
    if (st == kOfxStatOK && !(im = pack_input(ni, k, &view, time))) st = kOfxStatErrMemory;
    pthread_mutex_unlock(&h->lock);
    if (st != kOfxStatOK) return st;
    __atomic_add_fetch(&ni->images, 1, __ATOMIC_RELAXED);
    *out = (OfxPropertySetHandle)&im->props;
    return kOfxStatOK;
}

static OfxStatus fx_clip_release_image(OfxPropertySetHandle image)
{
    himage *im = (himage *)image;
    if (!im || im->props.magic != PROPS_MAGIC || im->props.kind != K_IMAGE)
        return kOfxStatErrBadHandle;
    if (im->ni) __atomic_sub_fetch(&im->ni->images, 1, __ATOMIC_RELAXED);
    props_free(&im->props);
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
        r = ofx_rect(a->frame, ni->frame_flip);
    else if (c->input >= 0 && a->inputs[c->input].data)
        r = ofx_rect(a->inputs[c->input].bounds, input_flip(ni, c->input, &a->inputs[c->input]));
    else
        return kOfxStatFailed;
    double s = a->render_scale;
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

static const OfxImageEffectSuiteV1 image_effect_suite = {
    fx_get_property_set,   fx_get_param_set,         fx_clip_define,
    fx_clip_get_handle,    fx_clip_get_property_set, fx_clip_get_image,
    fx_clip_release_image, fx_clip_get_rod,          fx_abort,
    fx_memory_alloc,       fx_memory_free,           fx_memory_lock,
    fx_memory_unlock};

/* ---- parameter suite
 * ------------------------------------------------------------------------------ */

static int type_is(const hparam *p, const char *t)
{
    return !strcmp(p->type, t);
}

static OfxStatus pm_define(OfxParamSetHandle ps, const char *type, const char *name,
                           OfxPropertySetHandle *out)
{
    static const char *const known[] = {
        kOfxParamTypeInteger, kOfxParamTypeDouble, kOfxParamTypeBoolean,  kOfxParamTypeChoice,
        kOfxParamTypeRGBA,    kOfxParamTypeRGB,    kOfxParamTypeDouble2D, kOfxParamTypeInteger2D,
        kOfxParamTypeString,  kOfxParamTypeGroup,  kOfxParamTypePage,     kOfxParamTypePushButton};
    heffect *e = effect_of(ps);
    if (!e || !type || !name) return kOfxStatErrBadHandle;
    if (e->ni) return kOfxStatErrUnsupported;
    int ok = 0;
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++)
        ok |= !strcmp(type, known[i]);
    if (!ok) return kOfxStatErrUnknown;
    if (effect_param(e, name)) return kOfxStatErrExists;
    hparam *p = param_add(e, type, name);
    if (!p) return kOfxStatErrMemory;
    OfxPropertySetHandle pp = (OfxPropertySetHandle)&p->props;
    set_string(pp, kOfxPropType, 0, kOfxTypeParameter);
    set_string(pp, kOfxPropName, 0, name);
    set_string(pp, kOfxPropLabel, 0, name);
    set_string(pp, kOfxParamPropType, 0, type);
    set_string(pp, kOfxParamPropScriptName, 0, name);
    set_string(pp, kOfxParamPropHint, 0, "");
    set_int(pp, kOfxParamPropAnimates, 0, 1);
    if (out) *out = pp;
    return kOfxStatOK;
}

static OfxStatus pm_get_handle(OfxParamSetHandle ps, const char *name, OfxParamHandle *param,
                               OfxPropertySetHandle *props)
{
    heffect *e = effect_of(ps);
    if (!e || !name) return kOfxStatErrBadHandle;
    hparam *p = effect_param(e, name);
    if (!p) return kOfxStatErrUnknown;
    if (param) *param = (OfxParamHandle)p;
    if (props) *props = (OfxPropertySetHandle)&p->props;
    return kOfxStatOK;
}

static OfxStatus pm_set_get_props(OfxParamSetHandle ps, OfxPropertySetHandle *out)
{
    heffect *e = effect_of(ps);
    if (!e || !out) return kOfxStatErrBadHandle;
    *out = (OfxPropertySetHandle)&e->props;
    return kOfxStatOK;
}

static OfxStatus pm_get_props(OfxParamHandle param, OfxPropertySetHandle *out)
{
    hparam *p = param_of(param);
    if (!p || !out) return kOfxStatErrBadHandle;
    *out = (OfxPropertySetHandle)&p->props;
    return kOfxStatOK;
}

static int param_dims(const hparam *p, int *is_int)
{
    *is_int = type_is(p, kOfxParamTypeInteger) || type_is(p, kOfxParamTypeBoolean) ||
              type_is(p, kOfxParamTypeChoice) || type_is(p, kOfxParamTypeInteger2D);
    if (type_is(p, kOfxParamTypeRGBA)) return 4;
    if (type_is(p, kOfxParamTypeRGB)) return 3;
    if (type_is(p, kOfxParamTypeDouble2D) || type_is(p, kOfxParamTypeInteger2D)) return 2;
    if (type_is(p, kOfxParamTypeInteger) || type_is(p, kOfxParamTypeBoolean) ||
        type_is(p, kOfxParamTypeChoice) || type_is(p, kOfxParamTypeDouble))
        return 1;
    return 0; /* strings, pages, groups, buttons */
}

/* No animation: every time gives the current value. */
static OfxStatus param_get(hparam *p, va_list ap)
{
    int is_int;
    int n = param_dims(p, &is_int);
    if (type_is(p, kOfxParamTypeString)) {
        char **s = va_arg(ap, char **);
        *s = p->s;
        return kOfxStatOK;
    }
    if (!n) return kOfxStatErrBadHandle;
    for (int k = 0; k < n; k++) {
        if (is_int)
            *va_arg(ap, int *) = n == 1 ? p->i : (int)p->d[k];
        else
            *va_arg(ap, double *) = p->d[k];
    }
    return kOfxStatOK;
}

static OfxStatus param_set(hparam *p, va_list ap)
{
    int is_int;
    int n = param_dims(p, &is_int);
    if (type_is(p, kOfxParamTypeString)) {
        char *s = strdup(va_arg(ap, const char *));
        if (!s) return kOfxStatErrMemory;
        free(p->s);
        p->s = s;
        return kOfxStatOK;
    }
    if (!n) return kOfxStatErrBadHandle;
    for (int k = 0; k < n; k++) {
        if (is_int && n == 1)
            p->i = va_arg(ap, int);
        else if (is_int)
            p->d[k] = va_arg(ap, int);
        else
            p->d[k] = va_arg(ap, double);
    }
    return kOfxStatOK;
}

static OfxStatus pm_get_value(OfxParamHandle param, ...)
{
    hparam *p = param_of(param);
    if (!p) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, param);
    OfxStatus st = param_get(p, ap);
    va_end(ap);
    return st;
}

static OfxStatus pm_get_value_at_time(OfxParamHandle param, OfxTime time, ...)
{
    hparam *p = param_of(param);
    if (!p) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, time);
    OfxStatus st = param_get(p, ap);
    va_end(ap);
    return st;
}

static OfxStatus pm_get_derivative(OfxParamHandle param, OfxTime time, ...)
{
    (void)param;
    (void)time;
    return kOfxStatErrUnsupported;
}

static OfxStatus pm_get_integral(OfxParamHandle param, OfxTime t1, OfxTime t2, ...)
{
    (void)param;
    (void)t1;
    (void)t2;
    return kOfxStatErrUnsupported;
}

static OfxStatus pm_set_value(OfxParamHandle param, ...)
{
    hparam *p = param_of(param);
    if (!p) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, param);
    OfxStatus st = param_set(p, ap);
    va_end(ap);
    return st;
}

static OfxStatus pm_set_value_at_time(OfxParamHandle param, OfxTime time, ...)
{
    hparam *p = param_of(param);
    if (!p) return kOfxStatErrBadHandle;
    va_list ap;
    va_start(ap, time);
    OfxStatus st = param_set(p, ap);
    va_end(ap);
    return st;
}

static OfxStatus pm_num_keys(OfxParamHandle param, unsigned int *n)
{
    if (!param_of(param) || !n) return kOfxStatErrBadHandle;
    *n = 0;
    return kOfxStatOK;
}
static OfxStatus pm_key_time(OfxParamHandle param, unsigned int nth, OfxTime *time)
{
    (void)nth;
    (void)time;
    return param_of(param) ? kOfxStatErrBadIndex : kOfxStatErrBadHandle;
}
static OfxStatus pm_key_index(OfxParamHandle param, OfxTime time, int dir, int *index)
{
    (void)time;
    (void)dir;
    (void)index;
    return param_of(param) ? kOfxStatFailed : kOfxStatErrBadHandle;
}
static OfxStatus pm_delete_key(OfxParamHandle param, OfxTime time)
{
    (void)time;
    return param_of(param) ? kOfxStatErrBadIndex : kOfxStatErrBadHandle;
}
static OfxStatus pm_delete_all_keys(OfxParamHandle param)
{
    return param_of(param) ? kOfxStatOK : kOfxStatErrBadHandle;
}
static OfxStatus pm_copy(OfxParamHandle to, OfxParamHandle from, OfxTime offset,
                         const OfxRangeD *range)
{
    (void)to;
    (void)from;
    (void)offset;
    (void)range;
    return kOfxStatErrUnsupported;
}
static OfxStatus pm_edit_begin(OfxParamSetHandle ps, const char *name)
{
    (void)name;
    return effect_of(ps) ? kOfxStatOK : kOfxStatErrBadHandle;
}
static OfxStatus pm_edit_end(OfxParamSetHandle ps)
{
    return effect_of(ps) ? kOfxStatOK : kOfxStatErrBadHandle;
}

static const OfxParameterSuiteV1 parameter_suite = {
    pm_define,     pm_get_handle,        pm_set_get_props,   pm_get_props,
    pm_get_value,  pm_get_value_at_time, pm_get_derivative,  pm_get_integral,
    pm_set_value,  pm_set_value_at_time, pm_num_keys,        pm_key_time,
    pm_key_index,  pm_delete_key,        pm_delete_all_keys, pm_copy,
    pm_edit_begin, pm_edit_end};

/* ---- multithread suite: the runner's executor ------------------------------------------------ */

static _Thread_local int mt_spawned;
static _Thread_local unsigned int mt_index;

typedef struct mt_call {
    OfxThreadFunctionV1 *fn;
    unsigned int n;
    void *arg;
} mt_call;

/* One executor item per OFX thread. The pool may run fewer items at once than asked, which is
 * allowed: the spec only promises that all nThreads calls have returned when multiThread does. */
static void mt_items(void *user, int begin, int end, int worker)
{
    (void)worker;
    const mt_call *c = user;
    for (int i = begin; i < end; i++) {
        mt_spawned = 1;
        mt_index = (unsigned int)i;
        c->fn((unsigned int)i, c->n, c->arg);
        mt_spawned = 0;
        mt_index = 0;
    }
}

static OfxStatus mt_multi_thread(OfxThreadFunctionV1 fn, unsigned int n, void *arg)
{
    if (!fn) return kOfxStatFailed;
    if (mt_spawned) return kOfxStatErrExists; /* the suite is not re-entrant */
    if (n == 0) return kOfxStatOK;
    mt_call c = {fn, n, arg};
    nprfx_parallel_for(g_host ? g_host->exec : NULL, (int)n, 1, mt_items, &c);
    return kOfxStatOK;
}

static OfxStatus mt_num_cpus(unsigned int *n)
{
    if (!n) return kOfxStatFailed;
    *n = (unsigned int)nprfx_executor_workers(g_host ? g_host->exec : NULL);
    return kOfxStatOK;
}

static OfxStatus mt_thread_index(unsigned int *index)
{
    if (!index) return kOfxStatFailed;
    *index = mt_spawned ? mt_index : 0;
    return kOfxStatOK;
}

static int mt_is_spawned(void)
{
    return mt_spawned;
}

static OfxStatus mt_mutex_create(OfxMutexHandle *out, int lock_count)
{
    pthread_mutex_t *m = malloc(sizeof *m);
    pthread_mutexattr_t at;
    if (!m || !out) {
        free(m);
        return kOfxStatErrMemory;
    }
    pthread_mutexattr_init(&at);
    pthread_mutexattr_settype(&at, PTHREAD_MUTEX_RECURSIVE);
    pthread_mutex_init(m, &at);
    pthread_mutexattr_destroy(&at);
    for (int i = 0; i < lock_count; i++)
        pthread_mutex_lock(m);
    *out = (OfxMutexHandle)m;
    return kOfxStatOK;
}
static OfxStatus mt_mutex_destroy(const OfxMutexHandle h)
{
    if (!h) return kOfxStatErrBadHandle;
    pthread_mutex_destroy((pthread_mutex_t *)h);
    free(h);
    return kOfxStatOK;
}
static OfxStatus mt_mutex_lock(const OfxMutexHandle h)
{
    return h && !pthread_mutex_lock((pthread_mutex_t *)h) ? kOfxStatOK : kOfxStatErrBadHandle;
}
static OfxStatus mt_mutex_unlock(const OfxMutexHandle h)
{
    return h && !pthread_mutex_unlock((pthread_mutex_t *)h) ? kOfxStatOK : kOfxStatErrBadHandle;
}
static OfxStatus mt_mutex_try_lock(const OfxMutexHandle h)
{
    if (!h) return kOfxStatErrBadHandle;
    return pthread_mutex_trylock((pthread_mutex_t *)h) ? kOfxStatFailed : kOfxStatOK;
}

static const OfxMultiThreadSuiteV1 multithread_suite = {
    mt_multi_thread,  mt_num_cpus,   mt_thread_index, mt_is_spawned,    mt_mutex_create,
    mt_mutex_destroy, mt_mutex_lock, mt_mutex_unlock, mt_mutex_try_lock};

/* ---- memory and message suites --------------------------------------------------------------- */

static OfxStatus mem_alloc(void *handle, size_t n, void **out)
{
    (void)handle;
    if (!out) return kOfxStatErrBadHandle;
    *out = NULL;
    return posix_memalign(out, 16, n ? n : 1) ? kOfxStatErrMemory : kOfxStatOK;
}
static OfxStatus mem_free(void *p)
{
    free(p);
    return kOfxStatOK;
}
static const OfxMemorySuiteV1 memory_suite = {mem_alloc, mem_free};

static OfxStatus msg_message(void *handle, const char *type, const char *id, const char *fmt, ...)
{
    (void)handle;
    (void)id;
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt ? fmt : "", ap);
    va_end(ap);
    if (type && !strcmp(type, "OfxMessageQuestion")) return kOfxStatFailed; /* not interactive */
    host_message(g_host, type ? type : kOfxMessageMessage, text);
    return kOfxStatOK;
}
static const OfxMessageSuiteV1 message_suite = {msg_message};

static const void *fetch_suite(OfxPropertySetHandle host, const char *name, int version)
{
    if (!g_host || props_of(host) != &g_host->props || !name) return NULL;
    if (version != 1) return NULL;
    if (!strcmp(name, kOfxPropertySuite)) return &property_suite;
    if (!strcmp(name, kOfxImageEffectSuite)) return &image_effect_suite;
    if (!strcmp(name, kOfxParameterSuite)) return &parameter_suite;
    if (!strcmp(name, kOfxMultiThreadSuite)) return &multithread_suite;
    if (!strcmp(name, kOfxMemorySuite)) return &memory_suite;
    if (!strcmp(name, kOfxMessageSuite)) return &message_suite;
    return NULL;
}

/* ---- actions --------------------------------------------------------------------------------- */

static OfxStatus call(hplugin *pl, const char *action, const void *handle, hprops *in, hprops *out)
{
    return pl->p->mainEntry(action, handle, (OfxPropertySetHandle)in, (OfxPropertySetHandle)out);
}

static void host_properties(nprfx_ofx_host *h)
{
    OfxPropertySetHandle p = (OfxPropertySetHandle)&h->props;
    set_string(p, kOfxPropType, 0, kOfxTypeImageEffectHost);
    set_string(p, kOfxPropName, 0, "org.nprfx.testhost");
    set_string(p, kOfxPropLabel, 0, "nprfx test host");
    set_int(p, kOfxPropAPIVersion, 0, 1);
    set_int(p, kOfxPropAPIVersion, 1, 4);
    set_int(p, kOfxPropVersion, 0, NPRFX_VERSION_MAJOR);
    set_int(p, kOfxPropVersion, 1, NPRFX_VERSION_MINOR);
    set_int(p, kOfxPropVersion, 2, NPRFX_VERSION_PATCH);
    set_string(p, kOfxPropVersionLabel, 0, NPRFX_VERSION_STRING);
    set_int(p, kOfxImageEffectHostPropIsBackground, 0, 1);
    set_int(p, kOfxImageEffectPropSupportsOverlays, 0, 0);
    set_int(p, kOfxImageEffectPropSupportsMultiResolution, 0, 1);
    set_int(p, kOfxImageEffectPropSupportsTiles, 0, 1);
    set_int(p, kOfxImageEffectPropTemporalClipAccess, 0, 1);
    set_string(p, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
    set_string(p, kOfxImageEffectPropSupportedComponents, 1, kOfxImageComponentAlpha);
    set_string(p, kOfxImageEffectPropSupportedContexts, 0, kOfxImageEffectContextGeneral);
    set_string(p, kOfxImageEffectPropSupportedContexts, 1, kOfxImageEffectContextFilter);
    set_string(p, kOfxImageEffectPropSupportedPixelDepths, 0, kOfxBitDepthFloat);
    set_int(p, kOfxImageEffectPropSupportsMultipleClipDepths, 0, 0);
    set_int(p, kOfxImageEffectPropSupportsMultipleClipPARs, 0, 0);
    set_int(p, kOfxImageEffectPropSetableFrameRate, 0, 0);
    set_int(p, kOfxImageEffectPropSetableFielding, 0, 0);
    set_int(p, kOfxImageEffectInstancePropSequentialRender, 0, 1);
    set_int(p, kOfxParamHostPropSupportsCustomInteract, 0, 0);
    set_int(p, kOfxParamHostPropSupportsStringAnimation, 0, 0);
    set_int(p, kOfxParamHostPropSupportsChoiceAnimation, 0, 0);
    set_int(p, kOfxParamHostPropSupportsBooleanAnimation, 0, 0);
    set_int(p, kOfxParamHostPropSupportsCustomAnimation, 0, 0);
    set_int(p, kOfxParamHostPropMaxParameters, 0, -1);
    set_int(p, kOfxParamHostPropMaxPages, 0, 0);
    set_int(p, kOfxParamHostPropPageRowColumnCount, 0, 0);
    set_int(p, kOfxParamHostPropPageRowColumnCount, 1, 0);
}

/* describeInContext, then check the context descriptor against the node descriptor: every
 * param with its type, default and ranges, every clip with its optional flag. The adapter must
 * derive these, never restate them; this is where a slip would show. */
static nprfx_result describe_context(nprfx_ofx_host *h, hplugin *pl, const char *context,
                                     heffect **out)
{
    const char *id = pl->p->pluginIdentifier;
    heffect *e = effect_new(pl, kOfxTypeImageEffect);
    hprops in;
    props_init(&in, K_PLAIN);
    if (!e || props_copy(&e->props, &pl->descriptor->props) != kOfxStatOK) {
        effect_free(e);
        return nprfx_error(h->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    set_string((OfxPropertySetHandle)&in, kOfxImageEffectPropContext, 0, context);
    OfxStatus st = call(pl, kOfxImageEffectActionDescribeInContext, e, &in, NULL);
    props_free(&in);
    if (st != kOfxStatOK) {
        effect_free(e);
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: describeInContext(%s) failed (%d)", id,
                           context, st);
    }
    *out = e;
    const nprfx_node_desc *d = pl->desc;
    if (!d) return NPRFX_OK;
    if (!effect_clip(e, NPRFX_OFX_OUTPUT_CLIP))
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: no Output clip", id);
    int general = !strcmp(context, kOfxImageEffectContextGeneral);
    char name[NPRFX_OFX_NAME_MAX];
    for (int k = 0; k < d->num_inputs; k++) {
        if (!general && k != nprfx_ofx_main_input(d)) continue;
        nprfx_ofx_clip_name(d, k, name, sizeof name);
        hclip *c = effect_clip(e, name);
        if (!c)
            return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s (%s): no clip %s for input '%s'", id,
                               context, name, d->inputs[k].name);
        if (pint(&c->props, kOfxImageClipPropOptional, 0, -1) !=
            ((d->inputs[k].flags & NPRFX_INPUT_OPTIONAL) != 0))
            return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: clip %s: wrong optional flag", id,
                               name);
    }
    static const char *const types[] = {kOfxParamTypeDouble,  kOfxParamTypeInteger,
                                        kOfxParamTypeBoolean, kOfxParamTypeChoice,
                                        kOfxParamTypeRGBA,    kOfxParamTypeString};
    for (int i = 0; i < d->num_params; i++) {
        const nprfx_param_desc *p = &d->params[i];
        hparam *hp = effect_param(e, p->name);
        if (!hp || !type_is(hp, types[p->type]))
            return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: param %s missing or not a %s", id,
                               p->name, types[p->type]);
        OfxPropertySetHandle pp = (OfxPropertySetHandle)&hp->props;
        int bad = 0;
        double v;
        int iv;
        char *s;
        switch (p->type) {
        case NPRFX_PARAM_DOUBLE:
        case NPRFX_PARAM_COLOR:
            for (int c = 0; c < (p->type == NPRFX_PARAM_COLOR ? 4 : 1); c++) {
                bad |= get_double(pp, kOfxParamPropDefault, c, &v) || v != p->def[c];
                bad |= get_double(pp, kOfxParamPropMin, c, &v) || v != p->hard_min;
                bad |= get_double(pp, kOfxParamPropMax, c, &v) || v != p->hard_max;
                bad |= get_double(pp, kOfxParamPropDisplayMin, c, &v) || v != p->soft_min;
                bad |= get_double(pp, kOfxParamPropDisplayMax, c, &v) || v != p->soft_max;
            }
            break;
        case NPRFX_PARAM_INT:
            bad |= get_int(pp, kOfxParamPropDefault, 0, &iv) || iv != (int)p->def[0];
            bad |= get_int(pp, kOfxParamPropDisplayMin, 0, &iv) || iv != (int)p->soft_min;
            bad |= get_int(pp, kOfxParamPropDisplayMax, 0, &iv) || iv != (int)p->soft_max;
            break;
        case NPRFX_PARAM_BOOL:
        case NPRFX_PARAM_CHOICE:
            bad |= get_int(pp, kOfxParamPropDefault, 0, &iv) || iv != (int)p->def[0];
            for (int c = 0; p->type == NPRFX_PARAM_CHOICE && p->choices && p->choices[c]; c++)
                bad |= get_string(pp, kOfxParamPropChoiceOption, c, &s) || strcmp(s, p->choices[c]);
            break;
        case NPRFX_PARAM_STRING:
            bad |= get_string(pp, kOfxParamPropDefault, 0, &s) ||
                   strcmp(s, p->def_string ? p->def_string : "");
            break;
        }
        if (bad)
            return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL,
                               "%s: param %s: default, range or options differ from the node's "
                               "descriptor",
                               id, p->name);
    }
    return NPRFX_OK;
}

static nprfx_result load_plugin(nprfx_ofx_host *h, hplugin *pl)
{
    const char *id = pl->p->pluginIdentifier ? pl->p->pluginIdentifier : "?";
    if (!pl->p->pluginApi || strcmp(pl->p->pluginApi, kOfxImageEffectPluginApi) ||
        pl->p->apiVersion != kOfxImageEffectPluginApiVersion || !pl->p->setHost ||
        !pl->p->mainEntry)
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: not an image effect plug-in (API 1)",
                           id);
    pl->p->setHost(&h->ofx);
    OfxStatus st = call(pl, kOfxActionLoad, NULL, NULL, NULL);
    if (st != kOfxStatOK && st != kOfxStatReplyDefault)
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: load failed (%d)", id, st);
    pl->loaded = 1;
    if (!(pl->descriptor = effect_new(pl, kOfxTypeImageEffect)))
        return nprfx_error(h->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    set_string((OfxPropertySetHandle)&pl->descriptor->props, kOfxPluginPropFilePath, 0, h->bundle);
    if ((st = call(pl, kOfxActionDescribe, pl->descriptor, NULL, NULL)) != kOfxStatOK)
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: describe failed (%d)", id, st);
    hprops *dp = &pl->descriptor->props;
    if (pl->desc && strcmp(pstr(dp, kOfxPropLabel, 0, ""), pl->desc->label))
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: label differs from the node's", id);
    nprfx_result r;
    for (int i = 0; i < pdim(dp, kOfxImageEffectPropSupportedContexts); i++) {
        const char *c = pstr(dp, kOfxImageEffectPropSupportedContexts, i, "");
        if (!strcmp(c, kOfxImageEffectContextGeneral)) {
            if ((r = describe_context(h, pl, c, &pl->general))) return r;
        } else if (!strcmp(c, kOfxImageEffectContextFilter)) {
            if ((r = describe_context(h, pl, c, &pl->filter))) return r;
        }
    }
    if (!pl->general) return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: no General context", id);
    return NPRFX_OK;
}

/* ---- instances ------------------------------------------------------------------------------- */

static void inst_free(node_inst *ni)
{
    if (!ni) return;
    effect_free(ni->fx);
    free(ni->in_comps);
    free(ni->need_lo);
    free(ni->need_hi);
    free(ni);
}

static hplugin *find_plugin(nprfx_ofx_host *h, const nprfx_node_desc *d)
{
    char id[NPRFX_OFX_NAME_MAX];
    nprfx_ofx_plugin_id(d, id, sizeof id);
    for (int i = 0; i < h->nplugins; i++)
        if (h->plugins[i].p->pluginIdentifier && !strcmp(h->plugins[i].p->pluginIdentifier, id))
            return &h->plugins[i];
    return NULL;
}

/* The instance of a graph node, created at its first render from the General context: clips
 * connected as the graph connects the node's inputs, params at their defaults. */
static nprfx_result inst_create(nprfx_ofx_host *h, const nprfx_render_args *a, node_inst **out)
{
    const nprfx_node_desc *d = a->node;
    hplugin *pl = find_plugin(h, d);
    if (!pl || !pl->general)
        return nprfx_error(a->ctx, NPRFX_ERR_UNKNOWN_NODE, "the bundle %s has no plug-in for %s",
                           h->bundle, d->id);
    node_inst *ni = calloc(1, sizeof *ni);
    size_t ni_n = (size_t)d->num_inputs + 1;
    if (!ni || !(ni->need_lo = calloc(ni_n, sizeof(double))) ||
        !(ni->need_hi = calloc(ni_n, sizeof(double))) ||
        !(ni->in_comps = calloc(ni_n, sizeof(int))) ||
        !(ni->fx = effect_new(pl, kOfxTypeImageEffectInstance))) {
        inst_free(ni);
        return nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    ni->h = h;
    ni->pl = pl;
    ni->desc = d;
    ni->out_comps = 4;
    /* The Filter context when the plug-in offers it and only the main input is connected (as
     * a host would for a plain filter), so both contexts get exercised; General otherwise. */
    int main = nprfx_ofx_main_input(d), filter = pl->filter != NULL;
    for (int k = 0; k < d->num_inputs; k++)
        filter &= k == main || !a->inputs[k].data;
    heffect *e = ni->fx, *src = filter ? pl->filter : pl->general;
    OfxStatus st = props_copy(&e->props, &src->props);
    OfxPropertySetHandle ep = (OfxPropertySetHandle)&e->props;
    int w = nprfx_rect_width(a->frame), hgt = nprfx_rect_height(a->frame);
    double s = a->render_scale;
    set_string(ep, kOfxPropType, 0, kOfxTypeImageEffectInstance);
    set_string(ep, kOfxImageEffectPropContext, 0,
               filter ? kOfxImageEffectContextFilter : kOfxImageEffectContextGeneral);
    set_pointer(ep, kOfxPropInstanceData, 0, NULL);
    set_pointer(ep, kOfxImageEffectPropPluginHandle, 0, pl->descriptor);
    set_double(ep, kOfxImageEffectPropProjectSize, 0, w / s);
    set_double(ep, kOfxImageEffectPropProjectSize, 1, hgt / s);
    set_double(ep, kOfxImageEffectPropProjectOffset, 0, a->frame.x0 / s);
    set_double(ep, kOfxImageEffectPropProjectOffset, 1, a->frame.y0 / s);
    set_double(ep, kOfxImageEffectPropProjectExtent, 0, a->frame.x1 / s);
    set_double(ep, kOfxImageEffectPropProjectExtent, 1, a->frame.y1 / s);
    set_double(ep, kOfxImageEffectPropProjectPixelAspectRatio, 0, 1.0);
    set_double(ep, kOfxImageEffectInstancePropEffectDuration, 0,
               (double)(a->last_frame - a->first_frame + 1));
    set_double(ep, kOfxImageEffectPropFrameRate, 0, 24.0);
    set_int(ep, kOfxPropIsInteractive, 0, 0);
    e->ni = ni;
    char name[NPRFX_OFX_NAME_MAX];
    for (int i = 0; st == kOfxStatOK && i < src->nclips; i++) {
        hclip *c = clip_add(e, src->clips[i]->name);
        if (!c || props_copy(&c->props, &src->clips[i]->props) != kOfxStatOK) {
            st = kOfxStatErrMemory;
            break;
        }
        int connected = 0, alpha = 0;
        if (!strcmp(c->name, NPRFX_OFX_OUTPUT_CLIP)) {
            c->input = -1;
            connected = 1;
        }
        for (int k = 0; k < d->num_inputs && c->input == -2; k++) {
            nprfx_ofx_clip_name(d, k, name, sizeof name);
            if (!strcmp(name, c->name)) {
                c->input = k;
                connected = a->inputs[k].data != NULL;
                /* A 1-channel main input comes as Alpha, the other inputs as RGBA: both kinds
                 * of host image reach the adapter, and a 1-channel result goes out as Alpha. */
                alpha = connected && k == nprfx_ofx_main_input(d) && a->inputs[k].channels == 1;
                ni->in_comps[k] = alpha ? 1 : 4;
            }
        }
        OfxPropertySetHandle cp = (OfxPropertySetHandle)&c->props;
        set_int(cp, kOfxImageClipPropConnected, 0, connected);
        const char *comps = !connected ? kOfxImageComponentNone
                            : alpha    ? kOfxImageComponentAlpha
                                       : kOfxImageComponentRGBA;
        set_string(cp, kOfxImageEffectPropComponents, 0, comps);
        set_string(cp, kOfxImageClipPropUnmappedComponents, 0, comps);
        set_string(cp, kOfxImageEffectPropPixelDepth, 0,
                   connected ? kOfxBitDepthFloat : kOfxBitDepthNone);
        set_string(cp, kOfxImageClipPropUnmappedPixelDepth, 0,
                   connected ? kOfxBitDepthFloat : kOfxBitDepthNone);
        set_string(cp, kOfxImageEffectPropPreMultiplication, 0, kOfxImageUnPreMultiplied);
        set_double(cp, kOfxImagePropPixelAspectRatio, 0, 1.0);
        set_double(cp, kOfxImageEffectPropFrameRate, 0, 24.0);
        set_double(cp, kOfxImageEffectPropUnmappedFrameRate, 0, 24.0);
        set_double(cp, kOfxImageEffectPropFrameRange, 0, a->first_frame);
        set_double(cp, kOfxImageEffectPropFrameRange, 1, a->last_frame);
        set_double(cp, kOfxImageEffectPropUnmappedFrameRange, 0, a->first_frame);
        set_double(cp, kOfxImageEffectPropUnmappedFrameRange, 1, a->last_frame);
        set_string(cp, kOfxImageClipPropFieldOrder, 0, kOfxImageFieldNone);
        set_int(cp, kOfxImageClipPropContinuousSamples, 0, 0);
    }
    for (int i = 0; st == kOfxStatOK && i < src->nparams; i++) {
        const hparam *sp = src->params[i];
        hparam *p = param_add(e, sp->type, sp->name);
        if (!p || props_copy(&p->props, &sp->props) != kOfxStatOK) {
            st = kOfxStatErrMemory;
            break;
        }
        OfxPropertySetHandle pp = (OfxPropertySetHandle)&p->props;
        set_string(pp, kOfxPropType, 0, kOfxTypeParameterInstance);
        int is_int, n = param_dims(p, &is_int);
        char *sv;
        if (type_is(p, kOfxParamTypeString) &&
            get_string(pp, kOfxParamPropDefault, 0, &sv) == kOfxStatOK) {
            free(p->s);
            p->s = strdup(sv);
        } else if (n == 1 && is_int) {
            get_int(pp, kOfxParamPropDefault, 0, &p->i);
        } else {
            for (int c = 0; c < n; c++)
                get_double(pp, kOfxParamPropDefault, c, &p->d[c]);
        }
    }
    if (st != kOfxStatOK) {
        inst_free(ni);
        return nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    ni->args = a;
    ni->frame_flip = a->frame.y0 + a->frame.y1 - 1;
    st = call(pl, kOfxActionCreateInstance, e, NULL, NULL);
    ni->args = NULL;
    if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
        inst_free(ni);
        return nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: createInstance failed (%d): %s",
                           pl->p->pluginIdentifier, st, h->message);
    }
    h->instances++;
    *out = ni;
    return NPRFX_OK;
}

/* Set instance param `p` to the graph's value; returns 1 when it changed. */
static int param_assign(hparam *p, const nprfx_param_desc *pd, const nprfx_value *v)
{
    switch (pd->type) {
    case NPRFX_PARAM_DOUBLE:
        if (p->d[0] == v->v[0]) return 0;
        p->d[0] = v->v[0];
        return 1;
    case NPRFX_PARAM_COLOR:
        if (!memcmp(p->d, v->v, sizeof p->d)) return 0;
        memcpy(p->d, v->v, sizeof p->d);
        return 1;
    case NPRFX_PARAM_STRING: {
        const char *s = v->s ? v->s : "";
        char *copy;
        if (!strcmp(p->s, s) || !(copy = strdup(s))) return 0;
        free(p->s);
        p->s = copy;
        return 1;
    }
    default:
        if (p->i == (int)v->v[0]) return 0;
        p->i = (int)v->v[0];
        return 1;
    }
}

static void set_change_args(hprops *in, const nprfx_render_args *a, const char *type,
                            const char *name)
{
    OfxPropertySetHandle p = (OfxPropertySetHandle)in;
    set_string(p, kOfxPropChangeReason, 0, kOfxChangeUserEdited);
    if (!type) return;
    set_string(p, kOfxPropType, 0, type);
    set_string(p, kOfxPropName, 0, name);
    set_double(p, kOfxPropTime, 0, a->time);
    set_double(p, kOfxImageEffectPropRenderScale, 0, a->render_scale);
    set_double(p, kOfxImageEffectPropRenderScale, 1, a->render_scale);
}

/* Params and channel selectors from the graph, with the instance-changed actions a host sends
 * for edits; then the clip preferences they imply. */
static nprfx_result sync_params(node_inst *ni, const nprfx_render_args *a, int first)
{
    const nprfx_node_desc *d = ni->desc;
    heffect *e = ni->fx;
    const char *id = ni->pl->p->pluginIdentifier;
    char **changed = calloc((size_t)(d->num_params + d->num_inputs) + 1, sizeof *changed);
    int nchanged = 0;
    nprfx_result r = NPRFX_OK;
    if (!changed) return nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    for (int i = 0; i < d->num_params; i++) {
        const nprfx_param_desc *pd = &d->params[i];
        hparam *p = effect_param(e, pd->name);
        if (!p) {
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: no param %s", id, pd->name);
            goto done;
        }
        /* The runner's values have the render scale applied; OFX params hold full-resolution
         * values and the adapter applies the scale itself. */
        nprfx_value v = a->params[i];
        if (a->render_scale != 1.0 && (pd->flags & NPRFX_PARAM_PIXELS)) v.v[0] /= a->render_scale;
        if (a->render_scale != 1.0 && (pd->flags & NPRFX_PARAM_AREA))
            v.v[0] /= a->render_scale * a->render_scale;
        if (param_assign(p, pd, &v)) changed[nchanged++] = p->name;
    }
    char name[NPRFX_OFX_NAME_MAX];
    for (int k = 0; k < d->num_inputs; k++) {
        if (!a->inputs[k].data) continue;
        int n = a->inputs[k].channels;
        int opt = nprfx_ofx_selector_find(&d->inputs[k], 0, n);
        if (n > 4 || opt < 0) {
            r = nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED,
                            "input '%s' has %d channels: an OFX clip carries 1 to 4 (RGBA)",
                            d->inputs[k].name, n);
            goto done;
        }
        nprfx_ofx_selector_name(d, k, name, sizeof name);
        hparam *p = effect_param(e, name);
        if (!p) {
            int opts[NPRFX_OFX_CHAN_OPTIONS];
            if (nprfx_ofx_selector_options(&d->inputs[k], opts) > 1) {
                r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: no selector %s", id, name);
                goto done;
            }
            continue;
        }
        if (p->i != opt) {
            p->i = opt;
            changed[nchanged++] = p->name;
        }
    }
    if (nchanged) { /* after creation too: as a user editing a fresh node */
        hprops in;
        props_init(&in, K_PLAIN);
        set_change_args(&in, a, NULL, NULL);
        OfxStatus st = call(ni->pl, kOfxActionBeginInstanceChanged, e, &in, NULL);
        for (int i = 0; i < nchanged && (st == kOfxStatOK || st == kOfxStatReplyDefault); i++) {
            set_change_args(&in, a, kOfxTypeParameter, changed[i]);
            st = call(ni->pl, kOfxActionInstanceChanged, e, &in, NULL);
        }
        props_free(&in);
        props_init(&in, K_PLAIN);
        set_change_args(&in, a, NULL, NULL);
        if (st == kOfxStatOK || st == kOfxStatReplyDefault)
            st = call(ni->pl, kOfxActionEndInstanceChanged, e, &in, NULL);
        props_free(&in);
        if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: instanceChanged failed (%d)", id, st);
            goto done;
        }
    }
    if (nchanged || first) {
        hprops out;
        props_init(&out, K_PLAIN);
        OfxStatus st = call(ni->pl, kOfxImageEffectActionGetClipPreferences, e, NULL, &out);
        if (st == kOfxStatOK) {
            char key[NPRFX_OFX_NAME_MAX + 32];
            snprintf(key, sizeof key, "%s%s", kOfxImageClipPropComponentsPrefix,
                     NPRFX_OFX_OUTPUT_CLIP);
            const char *comps = pstr(&out, key, 0, kOfxImageComponentRGBA);
            ni->out_comps = !strcmp(comps, kOfxImageComponentAlpha) ? 1 : 4;
            hclip *oc = effect_clip(e, NPRFX_OFX_OUTPUT_CLIP);
            set_string((OfxPropertySetHandle)&oc->props, kOfxImageEffectPropComponents, 0,
                       ni->out_comps == 1 ? kOfxImageComponentAlpha : kOfxImageComponentRGBA);
            set_string(
                (OfxPropertySetHandle)&oc->props, kOfxImageEffectPropPreMultiplication, 0,
                pstr(&out, kOfxImageEffectPropPreMultiplication, 0, kOfxImageUnPreMultiplied));
        } else if (st != kOfxStatReplyDefault) {
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: getClipPreferences failed (%d)", id,
                            st);
        }
        props_free(&out);
    }
done:
    free(changed);
    return r;
}

/* getRegionOfDefinition must give the runner's frame; getFramesNeeded bounds what the render
 * may fetch; getRegionsOfInterest is asked as a host would. */
static nprfx_result query_regions(node_inst *ni, const nprfx_render_args *a)
{
    const nprfx_node_desc *d = ni->desc;
    const char *id = ni->pl->p->pluginIdentifier;
    heffect *e = ni->fx;
    double s = a->render_scale;
    hprops in, out;
    props_init(&in, K_PLAIN);
    props_init(&out, K_PLAIN);
    OfxPropertySetHandle ip = (OfxPropertySetHandle)&in;
    set_double(ip, kOfxPropTime, 0, a->time);
    set_double(ip, kOfxImageEffectPropRenderScale, 0, s);
    set_double(ip, kOfxImageEffectPropRenderScale, 1, s);
    nprfx_result r = NPRFX_OK;
    OfxStatus st = call(ni->pl, kOfxImageEffectActionGetRegionOfDefinition, e, &in, &out);
    double rod[4];
    OfxRectI fr = ofx_rect(a->frame, ni->frame_flip);
    if (st != kOfxStatOK ||
        get_double_n((OfxPropertySetHandle)&out, kOfxImageEffectPropRegionOfDefinition, 4, rod) ||
        rod[0] * s != fr.x1 || rod[1] * s != fr.y1 || rod[2] * s != fr.x2 || rod[3] * s != fr.y2) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL,
                        "%s: getRegionOfDefinition (status %d) does not give the frame %d,%d-%d,%d",
                        id, st, fr.x1, fr.y1, fr.x2, fr.y2);
        goto done;
    }
    props_free(&out);
    props_init(&out, K_PLAIN);
    double roi[4] = {fr.x1 / s, fr.y1 / s, fr.x2 / s, fr.y2 / s};
    set_double_n(ip, kOfxImageEffectPropRegionOfInterest, 4, roi);
    st = call(ni->pl, kOfxImageEffectActionGetRegionsOfInterest, e, &in, &out);
    if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: getRegionsOfInterest failed (%d)", id, st);
        goto done;
    }
    props_free(&out);
    props_init(&out, K_PLAIN);
    st = call(ni->pl, kOfxImageEffectActionGetFramesNeeded, e, &in, &out);
    if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: getFramesNeeded failed (%d)", id, st);
        goto done;
    }
    char key[NPRFX_OFX_NAME_MAX + 32], name[NPRFX_OFX_NAME_MAX];
    for (int k = 0; k < d->num_inputs; k++) {
        nprfx_ofx_clip_name(d, k, name, sizeof name);
        snprintf(key, sizeof key, "%s%s", kOfxImageClipPropFrameRangePrefix, name);
        int n = st == kOfxStatOK ? pdim(&out, key) : 0;
        ni->need_lo[k] = ni->need_hi[k] = a->time; /* the default: the frame itself */
        for (int j = 0; j + 1 < n; j += 2) {
            double lo = a->time, hi = a->time;
            get_double((OfxPropertySetHandle)&out, key, j, &lo);
            get_double((OfxPropertySetHandle)&out, key, j + 1, &hi);
            if (lo < ni->need_lo[k]) ni->need_lo[k] = lo;
            if (hi > ni->need_hi[k]) ni->need_hi[k] = hi;
        }
    }
done:
    props_free(&in);
    props_free(&out);
    return r;
}

static nprfx_result hook_render(void *user, const nprfx_render_args *a, void **slot)
{
    nprfx_ofx_host *h = user;
    node_inst *ni = *slot;
    nprfx_result r;
    int first = 0;
    if (!ni) {
        if ((r = inst_create(h, a, &ni))) return r;
        *slot = ni;
        first = 1;
    }
    const char *id = ni->pl->p->pluginIdentifier;
    h->message[0] = 0;
    ni->args = a;
    ni->frame_flip = a->frame.y0 + a->frame.y1 - 1;
    if ((r = sync_params(ni, a, first)) || (r = query_regions(ni, a))) goto done;
    double s = a->render_scale;
    hprops in;
    props_init(&in, K_PLAIN);
    OfxPropertySetHandle ip = (OfxPropertySetHandle)&in;
    set_double(ip, kOfxImageEffectPropRenderScale, 0, s);
    set_double(ip, kOfxImageEffectPropRenderScale, 1, s);
    set_int(ip, kOfxPropIsInteractive, 0, 0);
    if (!ni->began) {
        set_double(ip, kOfxImageEffectPropFrameRange, 0, a->first_frame);
        set_double(ip, kOfxImageEffectPropFrameRange, 1, a->last_frame);
        set_double(ip, kOfxImageEffectPropFrameStep, 0, 1.0);
        OfxStatus st = call(ni->pl, kOfxImageEffectActionBeginSequenceRender, ni->fx, &in, NULL);
        if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
            props_free(&in);
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: beginSequenceRender failed (%d)", id,
                            st);
            goto done;
        }
        ni->began = 1;
    }
    /* The output image covers the whole frame while the window may be one tile, so the adapter
     * meets bounds that differ from the render window. */
    OfxRectI ob = ofx_rect(a->frame, ni->frame_flip);
    OfxRectI win = ofx_rect(a->window, ni->frame_flip);
    int w = ob.x2 - ob.x1, hgt = ob.y2 - ob.y1;
    ni->out_bounds = ob;
    ni->out_row_bytes = w * ni->out_comps * (int)sizeof(float);
    ni->out_pixels =
        calloc((size_t)w * (size_t)(hgt > 0 ? hgt : 1) * (size_t)ni->out_comps, sizeof(float));
    if (!ni->out_pixels) {
        props_free(&in);
        r = nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        goto done;
    }
    int wv[4] = {win.x1, win.y1, win.x2, win.y2};
    set_double(ip, kOfxPropTime, 0, a->time);
    set_string(ip, kOfxImageEffectPropFieldToRender, 0, kOfxImageFieldNone);
    set_int_n(ip, kOfxImageEffectPropRenderWindow, 4, wv);
    set_int(ip, kOfxImageEffectPropSequentialRenderStatus, 0, 1);
    set_int(ip, kOfxImageEffectPropInteractiveRenderStatus, 0, 0);
    ni->images = 0;
    OfxStatus st = call(ni->pl, kOfxImageEffectActionRender, ni->fx, &in, NULL);
    props_free(&in);
    if (st != kOfxStatOK) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s render failed (OFX status %d)%s%s", id, st,
                        h->message[0] ? ": " : "", h->message);
        goto done;
    }
    if (ni->images) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: %d clip images not released by render", id,
                        ni->images);
        goto done;
    }
    int nout = a->output->channels;
    if (ni->out_comps == 1 && nout != 1) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: Alpha output for %d channels", id, nout);
        goto done;
    }
    for (int y = a->window.y0; y < a->window.y1; y++)
        for (int x = a->window.x0; x < a->window.x1; x++) {
            const float *s_px = ni->out_pixels + ((size_t)(ni->frame_flip - y - ob.y1) * (size_t)w +
                                                  (size_t)(x - ob.x1)) *
                                                     (size_t)ni->out_comps;
            float *d_px = nprfx_image_at(a->output, x, y);
            for (int c = 0; c < nout && c < 4; c++)
                d_px[c] = s_px[c];
        }
done:
    free(ni->out_pixels);
    ni->out_pixels = NULL;
    ni->args = NULL;
    (void)first;
    return r;
}

static void hook_release(void *user, const nprfx_node_desc *node, void *instance)
{
    (void)node;
    nprfx_ofx_host *h = user;
    node_inst *ni = instance;
    if (!ni) return;
    if (ni->began) {
        hprops in;
        props_init(&in, K_PLAIN);
        set_int((OfxPropertySetHandle)&in, kOfxPropIsInteractive, 0, 0);
        (void)call(ni->pl, kOfxImageEffectActionEndSequenceRender, ni->fx, &in, NULL);
        props_free(&in);
    }
    (void)call(ni->pl, kOfxActionDestroyInstance, ni->fx, NULL, NULL);
    h->instances--;
    inst_free(ni);
}

/* ---- open / close ---------------------------------------------------------------------------- */

/* The binary inside a bundle: Contents/<architecture>/<name without .bundle>. */
static char *bundle_binary(const char *bundle)
{
#if defined(__x86_64__)
    const char *arch = "Linux-x86-64";
#elif defined(__aarch64__)
    const char *arch = "Linux-arm64";
#elif defined(__i386__)
    const char *arch = "Linux-x86";
#else
    const char *arch = "Linux";
#endif
    size_t n = strlen(bundle);
    while (n > 1 && bundle[n - 1] == '/')
        n--;
    const char *suffix = ".bundle";
    size_t sl = strlen(suffix);
    if (n <= sl || strncmp(bundle + n - sl, suffix, sl)) return strdup(bundle); /* a binary */
    const char *base = bundle + n;
    while (base > bundle && base[-1] != '/')
        base--;
    size_t len = n + strlen(arch) + (size_t)(bundle + n - base) + 32;
    char *path = malloc(len);
    if (path)
        snprintf(path, len, "%.*s/Contents/%s/%.*s", (int)n, bundle, arch,
                 (int)(bundle + n - base - sl), base);
    return path;
}

nprfx_result nprfx_ofx_host_open(nprfx_context *ctx, const char *bundle, nprfx_ofx_host **out)
{
    *out = NULL;
    if (g_host)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "an OpenFX host is already open");
    nprfx_ofx_host *h = calloc(1, sizeof *h);
    if (!h) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    h->ctx = ctx;
    h->exec = nprfx_context_executor(ctx);
    pthread_mutex_init(&h->lock, NULL);
    props_init(&h->props, K_PLAIN);
    host_properties(h);
    h->ofx.host = (OfxPropertySetHandle)&h->props;
    h->ofx.fetchSuite = fetch_suite;
    h->hook.render = hook_render;
    h->hook.release = hook_release;
    h->hook.user = h;
    g_host = h;
    nprfx_result r = NPRFX_OK;
    if (!(h->bundle = strdup(bundle)) || !(h->binary = bundle_binary(bundle))) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        goto fail;
    }
    h->dl = dlopen(h->binary, RTLD_NOW | RTLD_LOCAL);
    if (!h->dl) {
        r = nprfx_error(ctx, NPRFX_ERR_IO, "cannot load the OpenFX bundle %s: %s", bundle,
                        dlerror());
        goto fail;
    }
    OfxGetNumberOfPluginsFn count_fn;
    OfxGetPluginFn get_fn;
    *(void **)&count_fn = dlsym(h->dl, "OfxGetNumberOfPlugins");
    *(void **)&get_fn = dlsym(h->dl, "OfxGetPlugin");
    if (!count_fn || !get_fn) {
        r = nprfx_error(ctx, NPRFX_ERR_IO, "%s exports no OfxGetNumberOfPlugins/OfxGetPlugin",
                        h->binary);
        goto fail;
    }
    int n = count_fn();
    h->plugins = calloc((size_t)(n > 0 ? n : 1), sizeof *h->plugins);
    if (!h->plugins) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        goto fail;
    }
    for (int i = 0; i < n; i++) {
        hplugin *pl = &h->plugins[i];
        if (!(pl->p = get_fn(i))) {
            r = nprfx_error(ctx, NPRFX_ERR_INTERNAL, "%s: OfxGetPlugin(%d) is NULL", h->binary, i);
            goto fail;
        }
        h->nplugins = i + 1;
        for (int k = 0; k < nprfx_node_count(); k++) {
            char id[NPRFX_OFX_NAME_MAX];
            nprfx_ofx_plugin_id(nprfx_node_at(k), id, sizeof id);
            if (pl->p->pluginIdentifier && !strcmp(id, pl->p->pluginIdentifier))
                pl->desc = nprfx_node_at(k);
        }
        for (int j = 0; j < i; j++)
            if (pl->p->pluginIdentifier && h->plugins[j].p->pluginIdentifier &&
                !strcmp(pl->p->pluginIdentifier, h->plugins[j].p->pluginIdentifier)) {
                r = nprfx_error(ctx, NPRFX_ERR_INTERNAL, "%s: identifier %s appears twice",
                                h->binary, pl->p->pluginIdentifier);
                goto fail;
            }
        if ((r = load_plugin(h, pl))) goto fail;
    }
    *out = h;
    return NPRFX_OK;
fail:
    nprfx_ofx_host_close(h);
    return r;
}

int nprfx_ofx_host_plugin_count(const nprfx_ofx_host *h)
{
    return h ? h->nplugins : 0;
}

const nprfx_render_hook *nprfx_ofx_host_hook(nprfx_ofx_host *h)
{
    return h ? &h->hook : NULL;
}

void nprfx_ofx_host_close(nprfx_ofx_host *h)
{
    if (!h) return;
    for (int i = 0; i < h->nplugins; i++) {
        hplugin *pl = &h->plugins[i];
        /* Unloading under live instances would pull the code from under them. */
        if (pl->loaded && !h->instances) (void)call(pl, kOfxActionUnload, NULL, NULL, NULL);
        effect_free(pl->descriptor);
        effect_free(pl->general);
        effect_free(pl->filter);
    }
    free(h->plugins);
    if (h->dl && !h->instances) dlclose(h->dl);
    props_free(&h->props);
    pthread_mutex_destroy(&h->lock);
    free(h->bundle);
    free(h->binary);
    if (g_host == h) g_host = NULL;
    free(h);
}
