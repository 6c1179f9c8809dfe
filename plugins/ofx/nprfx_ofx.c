/* nprfx OpenFX adapter — every registered node descriptor becomes one OFX image-effect plug-in
 * of the bundle nprfx.ofx.bundle. Nothing here knows a particular node: identifiers, clips,
 * params, defaults, ranges and hints are all derived from the descriptors (node.h), so a node
 * file added to plugins/ appears in hosts without touching this file.
 *
 * This file: the two exported entry points, the plug-in table, describe / describeInContext,
 * instance lifecycle and the actions other than render (ofx_render.c). */
#define _GNU_SOURCE /* dladdr */
#include <dlfcn.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flow_opencv.h"
#include "ofx_internal.h"
#include "support/data_files.h"

#if defined(__GNUC__)
#define NPRFX_OFX_EXPORT __attribute__((visibility("default")))
#else
#define NPRFX_OFX_EXPORT
#endif

ofx_suites ofx_g;

/* ---- memory ---------------------------------------------------------------------------------- */

/* Through the host's memory suite when it has one (hosts account plug-in memory that way);
 * the choice is fixed at load, so alloc and free always pair up. */
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

static void *zalloc(size_t bytes)
{
    void *p = ofx_alloc(bytes);
    if (p) memset(p, 0, bytes);
    return p;
}

/* ---- property shorthands --------------------------------------------------------------------- */

/* Optional properties: a host that does not know one answers kOfxStatErrUnknown, which must not
 * stop the plug-in from loading, so these ignore the status on purpose. */
static void set_str(OfxPropertySetHandle p, const char *name, int i, const char *v)
{
    (void)ofx_g.prop->propSetString(p, name, i, v);
}
static void set_int(OfxPropertySetHandle p, const char *name, int i, int v)
{
    (void)ofx_g.prop->propSetInt(p, name, i, v);
}
static void set_dbl(OfxPropertySetHandle p, const char *name, int i, double v)
{
    (void)ofx_g.prop->propSetDouble(p, name, i, v);
}

static OfxPropertySetHandle clip_props(OfxImageClipHandle clip)
{
    OfxPropertySetHandle p = NULL;
    if (!clip || ofx_g.fx->clipGetPropertySet(clip, &p) != kOfxStatOK) return NULL;
    return p;
}

int ofx_clip_connected(OfxImageClipHandle clip)
{
    OfxPropertySetHandle p = clip_props(clip);
    int v = 0;
    if (p && ofx_g.prop->propGetInt(p, kOfxImageClipPropConnected, 0, &v) != kOfxStatOK) v = 0;
    return v;
}

/* ---- the plug-in table ----------------------------------------------------------------------- */

/* The host calls load/unload with a NULL handle and describe with a fresh descriptor, so the
 * only way to know which node an action is for is a distinct entry point per plug-in: a fixed
 * table of trampolines, generated below. 64 is far above the node count; a larger registry is
 * cut to the first 64 (OfxGetNumberOfPlugins says so). */
#define MAX_PLUGINS 64

static OfxStatus main_entry(int index, const char *action, const void *handle,
                            OfxPropertySetHandle in_args, OfxPropertySetHandle out_args);

#define ENTRY(a, b)                                                                                \
    static OfxStatus entry_##a##b(const char *action, const void *h, OfxPropertySetHandle in,      \
                                  OfxPropertySetHandle out)                                        \
    {                                                                                              \
        return main_entry((a)*8 + (b), action, h, in, out);                                        \
    }
#define ENTRY_ROW(a)                                                                               \
    ENTRY(a, 0) ENTRY(a, 1) ENTRY(a, 2) ENTRY(a, 3) ENTRY(a, 4) ENTRY(a, 5) ENTRY(a, 6) ENTRY(a, 7)
ENTRY_ROW(0)
ENTRY_ROW(1)
ENTRY_ROW(2)
ENTRY_ROW(3)
ENTRY_ROW(4)
ENTRY_ROW(5)
ENTRY_ROW(6)
ENTRY_ROW(7)
#define ENTRY_REF_ROW(a)                                                                           \
    entry_##a##0, entry_##a##1, entry_##a##2, entry_##a##3, entry_##a##4, entry_##a##5,            \
        entry_##a##6, entry_##a##7
static OfxPluginEntryPoint *const entries[MAX_PLUGINS] = {
    ENTRY_REF_ROW(0), ENTRY_REF_ROW(1), ENTRY_REF_ROW(2), ENTRY_REF_ROW(3),
    ENTRY_REF_ROW(4), ENTRY_REF_ROW(5), ENTRY_REF_ROW(6), ENTRY_REF_ROW(7)};

static OfxPlugin plugins[MAX_PLUGINS];
static char plugin_ids[MAX_PLUGINS][NPRFX_OFX_NAME_MAX];
static int plugin_count;
static pthread_once_t plugins_once = PTHREAD_ONCE_INIT;

static void set_host(OfxHost *host)
{
    ofx_g.host = host;
}

static void init_plugins(void)
{
    int n = nprfx_node_count();
    if (n > MAX_PLUGINS) {
        fprintf(stderr, "nprfx.ofx: %d nodes registered, only the first %d are exposed\n", n,
                MAX_PLUGINS);
        n = MAX_PLUGINS;
    }
    for (int i = 0; i < n; i++) {
        nprfx_ofx_plugin_id(nprfx_node_at(i), plugin_ids[i], sizeof plugin_ids[i]);
        plugins[i].pluginApi = kOfxImageEffectPluginApi;
        plugins[i].apiVersion = kOfxImageEffectPluginApiVersion;
        plugins[i].pluginIdentifier = plugin_ids[i];
        /* Each node's own version: a host keeps projects made with another major version
         * apart, and a minor bump tells it the pixels changed (cached frames are stale). */
        plugins[i].pluginVersionMajor = (unsigned)nprfx_node_at(i)->version_major;
        plugins[i].pluginVersionMinor = (unsigned)nprfx_node_at(i)->version_minor;
        plugins[i].setHost = set_host;
        plugins[i].mainEntry = entries[i];
    }
    plugin_count = n;
}

NPRFX_OFX_EXPORT int OfxGetNumberOfPlugins(void)
{
    pthread_once(&plugins_once, init_plugins);
    return plugin_count;
}

NPRFX_OFX_EXPORT OfxPlugin *OfxGetPlugin(int nth)
{
    pthread_once(&plugins_once, init_plugins);
    return nth >= 0 && nth < plugin_count ? &plugins[nth] : NULL;
}

/* ---- load ------------------------------------------------------------------------------------ */

/* The module is BUNDLE/Contents/ARCH/nprfx.ofx; its data sit in BUNDLE/Contents/Resources. */
static void find_data_dir(void)
{
    ofx_g.data_dir[0] = 0;
    Dl_info info;
    if (!dladdr((void *)&OfxGetPlugin, &info) || !info.dli_fname) return;
    char path[sizeof ofx_g.data_dir];
    if (snprintf(path, sizeof path, "%s", info.dli_fname) >= (int)sizeof path) return;
    for (int up = 0; up < 2; up++) { /* drop the file name, then the architecture folder */
        char *slash = strrchr(path, '/');
        if (!slash) return;
        *slash = 0;
    }
    snprintf(ofx_g.data_dir, sizeof ofx_g.data_dir, "%.4000s/Resources", path);
}

static OfxStatus load(void)
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
    ofx_g.flow = nprfx_flow_opencv(); /* NULL without OpenCV: nothing is derived */
    find_data_dir();
    return kOfxStatOK;
}

/* ---- describe -------------------------------------------------------------------------------- */

/* Whether the Filter context derives inputs from Source in this host (ofx_derive.c). */
static int filter_derives(const nprfx_node_desc *d)
{
    ofx_derive_plan plan;
    return ofx_derive_make_plan(d, ofx_g.temporal, &plan);
}

/* The Filter context has exactly one input, Source: offered when the node has a main input and
 * can run without every other one, or when it derives the others from Source (footage). */
static int filter_capable(const nprfx_node_desc *d)
{
    int main = nprfx_ofx_main_input(d);
    if (main < 0) return 0;
    if (filter_derives(d)) return 1;
    for (int k = 0; k < d->num_inputs; k++)
        if (k != main && !(d->inputs[k].flags & NPRFX_INPUT_OPTIONAL)) return 0;
    return 1;
}

/* A node that only works with other frames, in a host without temporal clip access: offered
 * only in the Filter context on footage, where the plug-in keeps the previous Source frame. */
static int filter_only(const nprfx_node_desc *d)
{
    return (d->flags & NPRFX_NODE_NEEDS_OTHER_FRAMES) && !ofx_g.temporal;
}

static int has_temporal_input(const nprfx_node_desc *d)
{
    if (!(d->flags & NPRFX_NODE_TEMPORAL)) return 0;
    for (int k = 0; k < d->num_inputs; k++)
        if (d->inputs[k].flags & NPRFX_INPUT_TEMPORAL) return 1;
    return 0;
}

static OfxStatus describe(const nprfx_node_desc *d, OfxImageEffectHandle fx)
{
    /* A node that only works with other frames is not offered where they cannot be had: a
     * missing plug-in with a logged reason beats one that silently shows the current frame. */
    if (filter_only(d) && !filter_derives(d)) {
        char why[512];
        snprintf(why, sizeof why,
                 "nprfx: %s is not available in this host: it reads its inputs at other frames, "
                 "and the host offers no temporal clip access "
                 "(kOfxImageEffectPropTemporalClipAccess = 0)",
                 d->id);
        ofx_post(fx, kOfxMessageLog, why);
        return kOfxStatErrMissingHostFeature;
    }
    OfxPropertySetHandle p;
    if (ofx_g.fx->getPropertySet(fx, &p) != kOfxStatOK) return kOfxStatErrBadHandle;
    set_str(p, kOfxPropLabel, 0, d->label);
    set_str(p, kOfxPropShortLabel, 0, d->label);
    set_str(p, kOfxPropLongLabel, 0, d->label);
    /* The host's help: the node's, and on footage what the Filter context does with Source. */
    static const char footage[] =
        "\n\nIn the Filter context the Source clip is footage: the plug-in computes the motion "
        "inputs from it with the flow node (default params), as a graph with a flow node "
        "connected to them would. A host without temporal clip access (MLT: Shotcut, Kdenlive) "
        "cannot give the neighbouring frames, so the plug-in keeps the previous frame: results "
        "there depend on rendering in order, and a seek, an out-of-order frame or a change of "
        "params restarts the effect as at a cut.";
    const char *help = d->help ? d->help : "";
    char *text = NULL;
    if (filter_derives(d) && (text = malloc(strlen(help) + sizeof footage))) {
        memcpy(text, help, strlen(help));
        memcpy(text + strlen(help), footage, sizeof footage);
    }
    set_str(p, kOfxPropPluginDescription, 0, text ? text : help);
    free(text);
    /* Everything under "NPR" in the host's menus; a node's own group below it ("NPR/Filter"). */
    char grouping[NPRFX_OFX_NAME_MAX];
    if (!d->group || !d->group[0] || !strcmp(d->group, "NPR"))
        snprintf(grouping, sizeof grouping, "NPR");
    else if (snprintf(grouping, sizeof grouping, "NPR/%s", d->group) >= (int)sizeof grouping)
        grouping[sizeof grouping - 1] = 0;
    set_str(p, kOfxImageEffectPluginPropGrouping, 0, grouping);
    /* The node's version (as in OfxPlugin), the library's in the label. */
    set_int(p, kOfxPropVersion, 0, d->version_major);
    set_int(p, kOfxPropVersion, 1, d->version_minor);
    char vlabel[64];
    snprintf(vlabel, sizeof vlabel, "%d.%d (nprfx %s)", d->version_major, d->version_minor,
             NPRFX_VERSION_STRING);
    set_str(p, kOfxPropVersionLabel, 0, vlabel);
    int nctx = 0;
    if (!filter_only(d))
        set_str(p, kOfxImageEffectPropSupportedContexts, nctx++, kOfxImageEffectContextGeneral);
    if (filter_capable(d))
        set_str(p, kOfxImageEffectPropSupportedContexts, nctx++, kOfxImageEffectContextFilter);
    /* Pixels are scene-linear float32 throughout nprfx, and the clip preferences ask for float;
     * hosts that only have 8 or 16 bits (MLT) still get a plug-in, converting at the edges. */
    set_str(p, kOfxImageEffectPropSupportedPixelDepths, 0, kOfxBitDepthFloat);
    set_str(p, kOfxImageEffectPropSupportedPixelDepths, 1, kOfxBitDepthShort);
    set_str(p, kOfxImageEffectPropSupportedPixelDepths, 2, kOfxBitDepthByte);
    set_int(p, kOfxImageEffectPluginPropSingleInstance, 0, 0);
    /* A stateful node's cache is shared by the renders of its instance. */
    set_str(p, kOfxImageEffectPluginRenderThreadSafety, 0,
            (d->flags & NPRFX_NODE_STATEFUL) ? kOfxImageEffectRenderInstanceSafe
                                             : kOfxImageEffectRenderFullySafe);
    /* The nodes split their work themselves through the multithread suite. */
    set_int(p, kOfxImageEffectPluginPropHostFrameThreading, 0, 0);
    set_int(p, kOfxImageEffectPropSupportsMultiResolution, 0, 1);
    set_int(p, kOfxImageEffectPropSupportsTiles, 0, 1);
    set_int(p, kOfxImageEffectPropTemporalClipAccess, 0, has_temporal_input(d) && ofx_g.temporal);
    set_int(p, kOfxImageEffectPropSupportsMultipleClipDepths, 0, 0);
    set_int(p, kOfxImageEffectPropSupportsMultipleClipPARs, 0, 0);
    set_int(p, kOfxImageEffectPluginPropFieldRenderTwiceAlways, 0, 0);
    /* Results never depend on the state cache, but in-order rendering makes it cost O(1)
     * frames per frame: "better sequential" (2) rather than "must" (1). */
    set_int(p, kOfxImageEffectInstancePropSequentialRender, 0,
            (d->flags & NPRFX_NODE_STATEFUL) ? 2 : 0);
    return kOfxStatOK;
}

/* A growing text buffer for hints (help texts are long and choice help adds lines). */
typedef struct strbuf {
    char *s;
    size_t len, cap;
} strbuf;

static void sb_add(strbuf *b, const char *text)
{
    size_t n = strlen(text);
    if (b->len + n + 1 > b->cap) {
        size_t cap = (b->len + n + 1) * 2;
        char *s = realloc(b->s, cap);
        if (!s) return; /* a shorter hint is no reason to fail */
        b->s = s;
        b->cap = cap;
    }
    memcpy(b->s + b->len, text, n + 1);
    b->len += n;
}

static int int_bound(double v)
{
    if (!(v == v)) return 0;
    if (v >= (double)INT32_MAX) return INT32_MAX;
    if (v <= (double)INT32_MIN) return INT32_MIN;
    return (int)v;
}

static void add_page_child(OfxPropertySetHandle page, int *nchildren, const char *name)
{
    if (page) set_str(page, kOfxParamPropPageChild, (*nchildren)++, name);
}

static OfxStatus define_param(OfxParamSetHandle ps, const nprfx_node_desc *d,
                              const nprfx_param_desc *p)
{
    static const char *const types[] = {kOfxParamTypeDouble,  kOfxParamTypeInteger,
                                        kOfxParamTypeBoolean, kOfxParamTypeChoice,
                                        kOfxParamTypeRGBA,    kOfxParamTypeString};
    if ((int)p->type < 0 || (int)p->type >= (int)(sizeof types / sizeof types[0]))
        return kOfxStatErrUnsupported;
    OfxPropertySetHandle pp;
    OfxStatus st = ofx_g.param->paramDefine(ps, types[p->type], p->name, &pp);
    if (st != kOfxStatOK) return st;
    set_str(pp, kOfxPropLabel, 0, p->label ? p->label : p->name);
    set_str(pp, kOfxParamPropScriptName, 0, p->name);
    strbuf hint = {0};
    sb_add(&hint, p->help ? p->help : "");
    if (p->flags & (NPRFX_PARAM_PIXELS | NPRFX_PARAM_AREA))
        sb_add(&hint, p->flags & NPRFX_PARAM_PIXELS
                          ? "\n\nIn pixels at full resolution; proxy renders scale it."
                          : "\n\nIn pixels^2 at full resolution; proxy renders scale it.");
    switch (p->type) {
    case NPRFX_PARAM_DOUBLE:
        set_dbl(pp, kOfxParamPropDefault, 0, p->def[0]);
        set_dbl(pp, kOfxParamPropMin, 0, p->hard_min);
        set_dbl(pp, kOfxParamPropMax, 0, p->hard_max);
        set_dbl(pp, kOfxParamPropDisplayMin, 0, p->soft_min);
        set_dbl(pp, kOfxParamPropDisplayMax, 0, p->soft_max);
        set_str(pp, kOfxParamPropDoubleType, 0, kOfxParamDoubleTypePlain);
        set_int(pp, kOfxParamPropDigits, 0, 4);
        set_dbl(pp, kOfxParamPropIncrement, 0,
                p->soft_max > p->soft_min ? (p->soft_max - p->soft_min) / 100.0 : 0.01);
        break;
    case NPRFX_PARAM_INT:
        set_int(pp, kOfxParamPropDefault, 0, int_bound(p->def[0]));
        set_int(pp, kOfxParamPropMin, 0, int_bound(p->hard_min));
        set_int(pp, kOfxParamPropMax, 0, int_bound(p->hard_max));
        set_int(pp, kOfxParamPropDisplayMin, 0, int_bound(p->soft_min));
        set_int(pp, kOfxParamPropDisplayMax, 0, int_bound(p->soft_max));
        break;
    case NPRFX_PARAM_BOOL:
        set_int(pp, kOfxParamPropDefault, 0, p->def[0] != 0.0);
        set_int(pp, kOfxParamPropAnimates, 0, 0);
        break;
    case NPRFX_PARAM_CHOICE: {
        int n = 0;
        for (; p->choices && p->choices[n]; n++) {
            set_str(pp, kOfxParamPropChoiceOption, n, p->choices[n]);
            if (p->choice_help && p->choice_help[n]) {
                sb_add(&hint, n ? "\n" : "\n\n");
                sb_add(&hint, p->choices[n]);
                sb_add(&hint, ": ");
                sb_add(&hint, p->choice_help[n]);
            }
        }
        set_int(pp, kOfxParamPropDefault, 0, int_bound(p->def[0]));
        set_int(pp, kOfxParamPropAnimates, 0, 0);
        break;
    }
    case NPRFX_PARAM_COLOR:
        for (int c = 0; c < 4; c++) {
            set_dbl(pp, kOfxParamPropDefault, c, p->def[c]);
            set_dbl(pp, kOfxParamPropMin, c, p->hard_min);
            set_dbl(pp, kOfxParamPropMax, c, p->hard_max);
            set_dbl(pp, kOfxParamPropDisplayMin, c, p->soft_min);
            set_dbl(pp, kOfxParamPropDisplayMax, c, p->soft_max);
        }
        break;
    case NPRFX_PARAM_STRING:
        set_str(pp, kOfxParamPropDefault, 0, p->def_string ? p->def_string : "");
        set_str(pp, kOfxParamPropStringMode, 0,
                (p->flags & NPRFX_PARAM_PATH) ? kOfxParamStringIsFilePath
                                              : kOfxParamStringIsSingleLine);
        /* sequence patterns ("####") never exist as such */
        if (p->flags & NPRFX_PARAM_PATH) set_int(pp, kOfxParamPropStringFilePathExists, 0, 0);
        set_int(pp, kOfxParamPropAnimates, 0, 0);
        break;
    }
    set_str(pp, kOfxParamPropHint, 0, hint.s ? hint.s : "");
    free(hint.s);
    return kOfxStatOK;
}

static OfxStatus define_selector(OfxParamSetHandle ps, const nprfx_node_desc *d, int k,
                                 const char *clip, char *name, size_t name_size)
{
    const nprfx_input_desc *in = &d->inputs[k];
    int opts[NPRFX_OFX_CHAN_OPTIONS];
    int n = nprfx_ofx_selector_options(in, opts);
    name[0] = 0;
    if (n < 2) return kOfxStatOK; /* nothing to choose */
    nprfx_ofx_selector_name(d, k, name, name_size);
    OfxPropertySetHandle pp;
    OfxStatus st = ofx_g.param->paramDefine(ps, kOfxParamTypeChoice, name, &pp);
    if (st != kOfxStatOK) return st;
    char label[NPRFX_OFX_NAME_MAX + 16];
    snprintf(label, sizeof label, "%s Channels", in->label ? in->label : clip);
    set_str(pp, kOfxPropLabel, 0, label);
    for (int i = 0; i < n; i++)
        set_str(pp, kOfxParamPropChoiceOption, i, nprfx_ofx_chan_options[opts[i]].label);
    set_int(pp, kOfxParamPropDefault, 0, nprfx_ofx_selector_default(in));
    set_int(pp, kOfxParamPropAnimates, 0, 0);
    strbuf hint = {0};
    char head[256];
    if (in->channels > 0)
        snprintf(head, sizeof head, "Which %d channel%s of the %s clip the node reads.",
                 in->channels, in->channels > 1 ? "s" : "", clip);
    else
        snprintf(head, sizeof head, "Which channels (1 to 4) of the %s clip the node reads.", clip);
    sb_add(&hint, head);
    if (in->aov) {
        sb_add(&hint, " The command-line runner looks for the AOV ");
        sb_add(&hint, in->aov);
        sb_add(&hint, "; shuffle it into these channels.");
    }
    if (in->help) {
        sb_add(&hint, "\n\n");
        sb_add(&hint, in->help);
    }
    set_str(pp, kOfxParamPropHint, 0, hint.s ? hint.s : "");
    free(hint.s);
    return kOfxStatOK;
}

static OfxPropertySetHandle define_clip(OfxImageEffectHandle fx, const char *name)
{
    OfxPropertySetHandle p = NULL;
    if (ofx_g.fx->clipDefine(fx, name, &p) != kOfxStatOK) return NULL;
    return p;
}

static OfxStatus describe_in_context(const nprfx_node_desc *d, OfxImageEffectHandle fx,
                                     OfxPropertySetHandle in_args)
{
    char *context = NULL;
    if (ofx_g.prop->propGetString(in_args, kOfxImageEffectPropContext, 0, &context) != kOfxStatOK ||
        !context)
        return kOfxStatErrValue;
    int general = !strcmp(context, kOfxImageEffectContextGeneral);
    if (general && filter_only(d)) return kOfxStatErrUnsupported;
    if (!general && !(filter_capable(d) && !strcmp(context, kOfxImageEffectContextFilter)))
        return kOfxStatErrUnsupported;
    /* Footage: Source is the picture the flow is computed on; it feeds the main input too unless
     * that is itself derived (advect's motion_prev). */
    ofx_derive_plan plan;
    int derives = !general && ofx_derive_make_plan(d, ofx_g.temporal, &plan);
    int main = nprfx_ofx_main_input(d);
    int temporal = (d->flags & NPRFX_NODE_TEMPORAL) && ofx_g.temporal;
    int maskable = general && nprfx_ofx_maskable(d);

    OfxPropertySetHandle cp = define_clip(fx, NPRFX_OFX_OUTPUT_CLIP);
    if (!cp) return kOfxStatFailed;
    set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
    set_str(cp, kOfxImageEffectPropSupportedComponents, 1, kOfxImageComponentAlpha);
    set_int(cp, kOfxImageEffectPropSupportsTiles, 0, 1);

    /* Source first: hosts number inputs in definition order and treat the first as the main
     * one (Nuke's B pipe, Natron's first arrow); the rest follow the descriptor. */
    char clip[NPRFX_OFX_NAME_MAX];
    for (int j = -1; j < d->num_inputs; j++) {
        int k = j < 0 ? main : j;
        if (k < 0 || (j >= 0 && k == main) || (!general && k != main)) continue;
        const nprfx_input_desc *in = &d->inputs[k];
        nprfx_ofx_clip_name(d, k, clip, sizeof clip);
        if (!(cp = define_clip(fx, clip))) return kOfxStatFailed;
        set_str(cp, kOfxPropLabel, 0,
                derives && plan.count[k] ? NPRFX_OFX_SOURCE_CLIP
                : in->label              ? in->label
                                         : clip);
        set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
        set_str(cp, kOfxImageEffectPropSupportedComponents, 1, kOfxImageComponentAlpha);
        /* As the input is (Source of a footage node that is not connected: the render says
         * that the footage is missing) */
        set_int(cp, kOfxImageClipPropOptional, 0, (in->flags & NPRFX_INPUT_OPTIONAL) != 0);
        set_int(cp, kOfxImageEffectPropTemporalClipAccess, 0,
                temporal && ((in->flags & NPRFX_INPUT_TEMPORAL) || derives));
        /* Nodes read neighbourhoods and whole unaligned maps: ask for untiled inputs. */
        set_int(cp, kOfxImageEffectPropSupportsTiles, 0, 0);
    }
    if (maskable) {
        if (!(cp = define_clip(fx, NPRFX_OFX_MASK_CLIP))) return kOfxStatFailed;
        set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentAlpha);
        set_int(cp, kOfxImageClipPropOptional, 0, 1);
        set_int(cp, kOfxImageClipPropIsMask, 0, 1);
        set_int(cp, kOfxImageEffectPropSupportsTiles, 0, 1);
    }

    OfxParamSetHandle ps;
    if (ofx_g.fx->getParamSet(fx, &ps) != kOfxStatOK) return kOfxStatErrBadHandle;
    OfxPropertySetHandle page = NULL;
    if (ofx_g.param->paramDefine(ps, kOfxParamTypePage, "Controls", &page) == kOfxStatOK)
        set_str(page, kOfxPropLabel, 0, "Controls");
    else
        page = NULL; /* a host without pages lays params out itself */
    int nchildren = 0;
    OfxStatus st;
    for (int i = 0; i < d->num_params; i++) {
        if ((st = define_param(ps, d, &d->params[i])) != kOfxStatOK) return st;
        add_page_child(page, &nchildren, d->params[i].name);
    }
    char name[NPRFX_OFX_NAME_MAX + 16];
    for (int k = 0; k < d->num_inputs; k++) {
        if (!general && k != main) continue;
        /* Source read whole by the flow: a main input that is derived has no channels to pick */
        if (derives && plan.count[k]) continue;
        nprfx_ofx_clip_name(d, k, clip, sizeof clip);
        if ((st = define_selector(ps, d, k, clip, name, sizeof name)) != kOfxStatOK) return st;
        if (name[0]) add_page_child(page, &nchildren, name);
    }
    if (maskable) {
        OfxPropertySetHandle pp;
        nprfx_ofx_extra_param(d, "maskInvert", name, sizeof name);
        if ((st = ofx_g.param->paramDefine(ps, kOfxParamTypeBoolean, name, &pp)) != kOfxStatOK)
            return st;
        set_str(pp, kOfxPropLabel, 0, "Invert Mask");
        set_int(pp, kOfxParamPropDefault, 0, 0);
        set_int(pp, kOfxParamPropAnimates, 0, 0);
        set_str(pp, kOfxParamPropHint, 0, "Use 1 - Mask instead of the Mask.");
        add_page_child(page, &nchildren, name);
        nprfx_ofx_extra_param(d, "mix", name, sizeof name);
        if ((st = ofx_g.param->paramDefine(ps, kOfxParamTypeDouble, name, &pp)) != kOfxStatOK)
            return st;
        set_str(pp, kOfxPropLabel, 0, "Mix");
        set_dbl(pp, kOfxParamPropDefault, 0, 1.0);
        set_dbl(pp, kOfxParamPropMin, 0, 0.0);
        set_dbl(pp, kOfxParamPropMax, 0, 1.0);
        set_dbl(pp, kOfxParamPropDisplayMin, 0, 0.0);
        set_dbl(pp, kOfxParamPropDisplayMax, 0, 1.0);
        set_str(pp, kOfxParamPropHint, 0,
                "out = Source + (result - Source) * mix * Mask, per channel the Source has "
                "(Mask: 1 where no Mask clip is connected). 1 with no Mask leaves the result "
                "untouched.");
        add_page_child(page, &nchildren, name);
    }
    return kOfxStatOK;
}

/* ---- instances ------------------------------------------------------------------------------- */

ofx_instance *ofx_instance_get(OfxImageEffectHandle fx)
{
    OfxPropertySetHandle p;
    void *v = NULL;
    if (!fx || ofx_g.fx->getPropertySet(fx, &p) != kOfxStatOK ||
        ofx_g.prop->propGetPointer(p, kOfxPropInstanceData, 0, &v) != kOfxStatOK)
        return NULL;
    return v;
}

static void instance_free(ofx_instance *inst)
{
    if (!inst) return;
    if (inst->state && inst->desc->state_free) inst->desc->state_free(inst->state);
    ofx_instance_forget_footage(inst);
    pthread_mutex_destroy(&inst->lock);
    ofx_free(inst->clips);
    ofx_free(inst->params);
    ofx_free(inst->selectors);
    ofx_free(inst);
}

static OfxStatus create_instance(const nprfx_node_desc *d, OfxImageEffectHandle fx)
{
    ofx_instance *inst = zalloc(sizeof *inst);
    if (!inst) return kOfxStatErrMemory;
    inst->desc = d;
    inst->fx = fx;
    pthread_mutex_init(&inst->lock, NULL);
    size_t ni = (size_t)(d->num_inputs > 0 ? d->num_inputs : 1);
    size_t np = (size_t)(d->num_params > 0 ? d->num_params : 1);
    inst->clips = zalloc(ni * sizeof *inst->clips);
    inst->selectors = zalloc(ni * sizeof *inst->selectors);
    inst->params = zalloc(np * sizeof *inst->params);
    if (!inst->clips || !inst->selectors || !inst->params) {
        instance_free(inst);
        return kOfxStatErrMemory;
    }
    const OfxImageEffectSuiteV1 *fxs = ofx_g.fx;
    if (fxs->clipGetHandle(fx, NPRFX_OFX_OUTPUT_CLIP, &inst->output, NULL) != kOfxStatOK) {
        instance_free(inst);
        return kOfxStatErrBadHandle;
    }
    /* Clips and params the context did not define stay NULL: Filter has Source only. */
    char name[NPRFX_OFX_NAME_MAX + 16];
    for (int k = 0; k < d->num_inputs; k++) {
        nprfx_ofx_clip_name(d, k, name, sizeof name);
        if (fxs->clipGetHandle(fx, name, &inst->clips[k], NULL) != kOfxStatOK)
            inst->clips[k] = NULL;
    }
    if (fxs->clipGetHandle(fx, NPRFX_OFX_MASK_CLIP, &inst->mask, NULL) != kOfxStatOK)
        inst->mask = NULL;
    OfxPropertySetHandle ep;
    char *context = NULL;
    if (fxs->getPropertySet(fx, &ep) == kOfxStatOK &&
        ofx_g.prop->propGetString(ep, kOfxImageEffectPropContext, 0, &context) == kOfxStatOK &&
        context && !strcmp(context, kOfxImageEffectContextFilter))
        inst->derive = ofx_derive_make_plan(d, ofx_g.temporal, &inst->plan);
    OfxParamSetHandle ps;
    if (fxs->getParamSet(fx, &ps) != kOfxStatOK) {
        instance_free(inst);
        return kOfxStatErrBadHandle;
    }
    const OfxParameterSuiteV1 *pm = ofx_g.param;
    for (int i = 0; i < d->num_params; i++)
        if (pm->paramGetHandle(ps, d->params[i].name, &inst->params[i], NULL) != kOfxStatOK) {
            instance_free(inst);
            return kOfxStatErrBadHandle;
        }
    for (int k = 0; k < d->num_inputs; k++) {
        nprfx_ofx_selector_name(d, k, name, sizeof name);
        if (!inst->clips[k] ||
            pm->paramGetHandle(ps, name, &inst->selectors[k], NULL) != kOfxStatOK)
            inst->selectors[k] = NULL;
    }
    if (inst->mask) {
        nprfx_ofx_extra_param(d, "mix", name, sizeof name);
        if (pm->paramGetHandle(ps, name, &inst->mix, NULL) != kOfxStatOK) inst->mix = NULL;
        nprfx_ofx_extra_param(d, "maskInvert", name, sizeof name);
        if (pm->paramGetHandle(ps, name, &inst->mask_invert, NULL) != kOfxStatOK)
            inst->mask_invert = NULL;
    }
    OfxPropertySetHandle p;
    if (fxs->getPropertySet(fx, &p) != kOfxStatOK ||
        ofx_g.prop->propSetPointer(p, kOfxPropInstanceData, 0, inst) != kOfxStatOK) {
        instance_free(inst);
        return kOfxStatErrBadHandle;
    }
    return kOfxStatOK;
}

static OfxStatus destroy_instance(OfxImageEffectHandle fx)
{
    ofx_instance *inst = ofx_instance_get(fx);
    if (!inst) return kOfxStatErrBadHandle;
    OfxPropertySetHandle p;
    if (ofx_g.fx->getPropertySet(fx, &p) == kOfxStatOK)
        (void)ofx_g.prop->propSetPointer(p, kOfxPropInstanceData, 0, NULL);
    instance_free(inst);
    return kOfxStatOK;
}

/* Drop the node's cache: it only ever saves work, and a changed param or clip may make it
 * stale (the runner drops it on --set likewise). */
static void drop_state(ofx_instance *inst)
{
    pthread_mutex_lock(&inst->lock);
    if (inst->state && inst->desc->state_free) inst->desc->state_free(inst->state);
    inst->state = NULL;
    inst->export_done = 0;
    /* Without temporal access the node cannot recompute its history: the next frame restarts
     * the effect, as after a cut (the kept Source frame goes with it). */
    ofx_instance_forget_footage(inst);
    pthread_mutex_unlock(&inst->lock);
}

/* A new sequence render exports its frames again (files may have been removed meanwhile). */
static void forget_export(ofx_instance *inst)
{
    pthread_mutex_lock(&inst->lock);
    inst->export_done = 0;
    pthread_mutex_unlock(&inst->lock);
}

static OfxStatus instance_changed(ofx_instance *inst, OfxPropertySetHandle in_args)
{
    char *type = NULL, *name = NULL;
    if (in_args) {
        (void)ofx_g.prop->propGetString(in_args, kOfxPropType, 0, &type);
        (void)ofx_g.prop->propGetString(in_args, kOfxPropName, 0, &name);
    }
    if (type && name && !strcmp(type, kOfxTypeParameter)) {
        char mix[NPRFX_OFX_NAME_MAX], inv[NPRFX_OFX_NAME_MAX];
        nprfx_ofx_extra_param(inst->desc, "mix", mix, sizeof mix);
        nprfx_ofx_extra_param(inst->desc, "maskInvert", inv, sizeof inv);
        if (!strcmp(name, mix) || !strcmp(name, inv)) return kOfxStatOK; /* after the node */
    }
    drop_state(inst);
    return kOfxStatOK;
}

/* ---- selections, frames, ranges -------------------------------------------------------------- */

OfxStatus ofx_frame_rod(const ofx_instance *inst, OfxTime time, OfxRectD *rod)
{
    const nprfx_node_desc *d = inst->desc;
    for (int k = 0; k < d->num_inputs; k++) {
        if (d->inputs[k].flags & NPRFX_INPUT_UNALIGNED) continue;
        if (!ofx_clip_connected(inst->clips[k])) continue;
        if (ofx_g.fx->clipGetRegionOfDefinition(inst->clips[k], time, rod) == kOfxStatOK)
            return kOfxStatOK;
    }
    OfxPropertySetHandle p;
    double off[2] = {0, 0}, size[2] = {0, 0};
    if (ofx_g.fx->getPropertySet(inst->fx, &p) != kOfxStatOK) return kOfxStatErrBadHandle;
    (void)ofx_g.prop->propGetDoubleN(p, kOfxImageEffectPropProjectOffset, 2, off);
    if (ofx_g.prop->propGetDoubleN(p, kOfxImageEffectPropProjectSize, 2, size) != kOfxStatOK ||
        size[0] <= 0 || size[1] <= 0)
        return kOfxStatFailed;
    rod->x1 = off[0];
    rod->y1 = off[1];
    rod->x2 = off[0] + size[0];
    rod->y2 = off[1] + size[1];
    return kOfxStatOK;
}

void ofx_shot_range(const ofx_instance *inst, double *first, double *last)
{
    double r[2] = {0, 0};
    OfxPropertySetHandle p = clip_props(inst->output);
    if (!p || ofx_g.prop->propGetDoubleN(p, kOfxImageEffectPropFrameRange, 2, r) != kOfxStatOK)
        r[0] = r[1] = 0;
    *first = r[0];
    *last = r[1];
}

/* ---- the other image effect actions ---------------------------------------------------------- */

static OfxStatus region_of_definition(ofx_instance *inst, OfxPropertySetHandle in_args,
                                      OfxPropertySetHandle out_args)
{
    double t = 0;
    (void)ofx_g.prop->propGetDouble(in_args, kOfxPropTime, 0, &t);
    OfxRectD rod;
    OfxStatus st = ofx_frame_rod(inst, t, &rod);
    if (st != kOfxStatOK) return kOfxStatReplyDefault;
    double v[4] = {rod.x1, rod.y1, rod.x2, rod.y2};
    return ofx_g.prop->propSetDoubleN(out_args, kOfxImageEffectPropRegionOfDefinition, 4, v);
}

static void set_clip_rect(OfxPropertySetHandle out_args, const char *prefix, const char *clip,
                          const double *v, int n)
{
    char name[NPRFX_OFX_NAME_MAX + 64];
    snprintf(name, sizeof name, "%s%s", prefix, clip);
    (void)ofx_g.prop->propSetDoubleN(out_args, name, n, v);
}

/* The frames input k's clip is read at, as n ranges (none: the host's default, the frame). */
static void set_frame_ranges(OfxPropertySetHandle out_args, const nprfx_node_desc *d, int k,
                             const nprfx_frame_range *r, int n)
{
    char clip[NPRFX_OFX_NAME_MAX];
    double v[2 * NPRFX_MAX_FRAME_RANGES];
    for (int i = 0; i < n; i++) {
        v[2 * i] = r[i].first;
        v[2 * i + 1] = r[i].last;
    }
    nprfx_ofx_clip_name(d, k, clip, sizeof clip);
    if (n > 0) set_clip_rect(out_args, kOfxImageClipPropFrameRangePrefix, clip, v, 2 * n);
}

/* Inputs are needed whole (nodes filter neighbourhoods, maps are looked up anywhere); the mask
 * only where the output is asked for. */
static OfxStatus regions_of_interest(ofx_instance *inst, OfxPropertySetHandle in_args,
                                     OfxPropertySetHandle out_args)
{
    double t = 0, roi[4] = {0, 0, 0, 0};
    (void)ofx_g.prop->propGetDouble(in_args, kOfxPropTime, 0, &t);
    (void)ofx_g.prop->propGetDoubleN(in_args, kOfxImageEffectPropRegionOfInterest, 4, roi);
    char clip[NPRFX_OFX_NAME_MAX];
    for (int k = 0; k < inst->desc->num_inputs; k++) {
        OfxRectD rod;
        if (!inst->clips[k] ||
            ofx_g.fx->clipGetRegionOfDefinition(inst->clips[k], t, &rod) != kOfxStatOK)
            continue;
        double v[4] = {rod.x1, rod.y1, rod.x2, rod.y2};
        nprfx_ofx_clip_name(inst->desc, k, clip, sizeof clip);
        set_clip_rect(out_args, kOfxImageClipPropRoIPrefix, clip, v, 4);
    }
    if (inst->mask)
        set_clip_rect(out_args, kOfxImageClipPropRoIPrefix, NPRFX_OFX_MASK_CLIP, roi, 4);
    return kOfxStatOK;
}

/* Exactly the frames the node reads (nprfx_node_frames_needed: its own answer, or the
 * fetch_before/after rule), as one or more ranges per connected clip; nothing on clips that are
 * not connected, and without temporal access the frame itself only (the host would not give
 * others). */
static OfxStatus frames_needed(ofx_instance *inst, OfxPropertySetHandle in_args,
                               OfxPropertySetHandle out_args)
{
    const nprfx_node_desc *d = inst->desc;
    double t = 0, first, last;
    (void)ofx_g.prop->propGetDouble(in_args, kOfxPropTime, 0, &t);
    ofx_shot_range(inst, &first, &last);
    size_t np = (size_t)d->num_params + 1, ni = (size_t)d->num_inputs + 1;
    nprfx_value *values = calloc(np, sizeof *values);
    char **strings = calloc(np, sizeof *strings);
    int *channels = calloc(ni, sizeof *channels);
    nprfx_context *ctx = NULL;
    OfxStatus status = kOfxStatOK;
    if (!values || !strings || !channels || nprfx_context_create(NULL, &ctx) != NPRFX_OK) {
        status = kOfxStatErrMemory;
        goto done;
    }
    ofx_input_channels(inst, t, 0, channels);
    int time = (int)floor(t + 0.5);
    nprfx_frames_query q = {time, (int)floor(first + 0.5), (int)floor(last + 0.5), channels};
    /* A param the host holds out of range fails the render with its message; here the defaults
     * stand in, so the frame itself is still declared. */
    if (ofx_eval_params(inst, ctx, t, 0, values, strings) != NPRFX_OK)
        nprfx_node_defaults(d, values);
    int main = nprfx_ofx_main_input(d);
    if (inst->derive && main >= 0 && ofx_clip_connected(inst->clips[main])) {
        /* Footage: Source at the frames the flow reads for each derived input's frames, and at
         * the main input's own when Source feeds it; one frame where the host cannot give
         * others (the plug-in keeps the previous one). */
        nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES];
        int n = 1;
        r[0].first = r[0].last = time;
        if (ofx_g.temporal)
            n = ofx_derive_frames(d, &inst->plan, values, &q, !inst->plan.count[main], r);
        set_frame_ranges(out_args, d, main, r, n);
    }
    for (int k = 0; k < d->num_inputs && !inst->derive; k++) {
        if (!inst->clips[k] || !channels[k]) continue;
        nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES];
        int n = 0;
        if (!ofx_g.temporal) {
            r[0].first = r[0].last = time;
            n = 1;
        } else if (nprfx_node_frames_needed(ctx, d, values, &q, k, r, &n) != NPRFX_OK) {
            continue; /* the host's default: the frame itself */
        }
        set_frame_ranges(out_args, d, k, r, n);
    }
    if (inst->mask && ofx_clip_connected(inst->mask)) {
        double r[2] = {t, t};
        set_clip_rect(out_args, kOfxImageClipPropFrameRangePrefix, NPRFX_OFX_MASK_CLIP, r, 2);
    }
done:
    for (int i = 0; strings && i < d->num_params; i++)
        free(strings[i]);
    free(values);
    free(strings);
    free(channels);
    nprfx_context_destroy(ctx);
    return status;
}

static void set_clip_string(OfxPropertySetHandle out_args, const char *prefix, const char *clip,
                            const char *v)
{
    char name[NPRFX_OFX_NAME_MAX + 64];
    snprintf(name, sizeof name, "%s%s", prefix, clip);
    (void)ofx_g.prop->propSetString(out_args, name, 0, v);
}

/* Output components and premultiplication from what the node will output: the channel count
 * follows the params and the selected input channels (nprfx_node_output_info). One channel
 * becomes Alpha where the Source itself is Alpha, else grey RGB with opaque alpha; 2-3
 * channels are R,G(,B) with opaque alpha; 4 are RGBA, premultiplied as the Source is. */
static OfxStatus clip_preferences(ofx_instance *inst, OfxPropertySetHandle out_args)
{
    const nprfx_node_desc *d = inst->desc;
    nprfx_value *values = calloc((size_t)d->num_params + 1, sizeof *values);
    int *in_ch = calloc((size_t)d->num_inputs + 1, sizeof *in_ch);
    if (!values || !in_ch) {
        free(values);
        free(in_ch);
        return kOfxStatErrMemory;
    }
    char **strings = calloc((size_t)d->num_params + 1, sizeof *strings);
    nprfx_context *ctx = NULL;
    (void)nprfx_context_create(NULL, &ctx);
    /* Values the host holds out of range fail the render, with the message; until then the
     * defaults decide the channel count. */
    if (!strings || ofx_eval_params(inst, ctx, 0, 1, values, strings) != NPRFX_OK)
        nprfx_node_defaults(d, values);
    ofx_input_channels(inst, 0, 1, in_ch);
    int main = nprfx_ofx_main_input(d);
    nprfx_output_info oi;
    int nout = nprfx_node_output_info(ctx, d, values, in_ch, &oi) == NPRFX_OK ? oi.channels : 4;
    nprfx_context_destroy(ctx);
    for (int i = 0; strings && i < d->num_params; i++)
        free(strings[i]);
    free(strings);
    free(values);
    free(in_ch);

    const char *src_comp = NULL, *src_premult = NULL;
    if (main >= 0 && ofx_clip_connected(inst->clips[main])) {
        OfxPropertySetHandle sp = clip_props(inst->clips[main]);
        char *s = NULL;
        if (sp && ofx_g.prop->propGetString(sp, kOfxImageEffectPropComponents, 0, &s) == kOfxStatOK)
            src_comp = s;
        s = NULL;
        if (sp && ofx_g.prop->propGetString(sp, kOfxImageEffectPropPreMultiplication, 0, &s) ==
                      kOfxStatOK)
            src_premult = s;
    }
    const char *comp = kOfxImageComponentRGBA, *premult = kOfxImageOpaque;
    if (nout == 1 && src_comp && !strcmp(src_comp, kOfxImageComponentAlpha)) {
        comp = kOfxImageComponentAlpha;
        premult = kOfxImageUnPreMultiplied;
    } else if (nout >= 4) {
        premult = src_premult ? src_premult : kOfxImageUnPreMultiplied;
    }
    set_clip_string(out_args, kOfxImageClipPropComponentsPrefix, NPRFX_OFX_OUTPUT_CLIP, comp);
    set_clip_string(out_args, kOfxImageClipPropDepthPrefix, NPRFX_OFX_OUTPUT_CLIP,
                    kOfxBitDepthFloat);
    char clip[NPRFX_OFX_NAME_MAX];
    for (int k = 0; k < d->num_inputs; k++) {
        if (!inst->clips[k]) continue;
        nprfx_ofx_clip_name(d, k, clip, sizeof clip);
        set_clip_string(out_args, kOfxImageClipPropDepthPrefix, clip, kOfxBitDepthFloat);
    }
    (void)ofx_g.prop->propSetString(out_args, kOfxImageEffectPropPreMultiplication, 0, premult);
    /* Random numbers hash the frame (docs/design.md §1): the output varies with time even when the
     * inputs do not. */
    (void)ofx_g.prop->propSetInt(out_args, kOfxImageEffectFrameVarying, 0, 1);
    return kOfxStatOK;
}

/* ---- dispatch -------------------------------------------------------------------------------- */

static OfxStatus main_entry(int index, const char *action, const void *handle,
                            OfxPropertySetHandle in_args, OfxPropertySetHandle out_args)
{
    const nprfx_node_desc *d = nprfx_node_at(index);
    OfxImageEffectHandle fx = (OfxImageEffectHandle)handle;
    if (!d || !action) return kOfxStatErrUnknown;
    if (!strcmp(action, kOfxActionLoad)) return load();
    if (!strcmp(action, kOfxActionUnload)) {
        nprfx_stipple_shipped_release(); /* the process-wide dot sequence; instances keep theirs */
        return kOfxStatOK;
    }
    if (!ofx_g.prop || !ofx_g.fx || !ofx_g.param) return kOfxStatErrFatal;
    if (!strcmp(action, kOfxActionDescribe)) return describe(d, fx);
    if (!strcmp(action, kOfxImageEffectActionDescribeInContext))
        return describe_in_context(d, fx, in_args);
    if (!strcmp(action, kOfxActionCreateInstance)) return create_instance(d, fx);
    ofx_instance *inst = ofx_instance_get(fx);
    if (!inst) return kOfxStatErrBadHandle;
    if (!strcmp(action, kOfxActionDestroyInstance)) return destroy_instance(fx);
    if (!strcmp(action, kOfxImageEffectActionRender)) return ofx_render(inst, in_args);
    if (!strcmp(action, kOfxImageEffectActionGetRegionOfDefinition))
        return region_of_definition(inst, in_args, out_args);
    if (!strcmp(action, kOfxImageEffectActionGetRegionsOfInterest))
        return regions_of_interest(inst, in_args, out_args);
    if (!strcmp(action, kOfxImageEffectActionGetFramesNeeded))
        return frames_needed(inst, in_args, out_args);
    if (!strcmp(action, kOfxImageEffectActionGetClipPreferences))
        return clip_preferences(inst, out_args);
    if (!strcmp(action, kOfxActionInstanceChanged)) return instance_changed(inst, in_args);
    if (!strcmp(action, kOfxActionPurgeCaches)) {
        drop_state(inst);
        return kOfxStatOK;
    }
    if (!strcmp(action, kOfxImageEffectActionBeginSequenceRender)) {
        forget_export(inst);
        return kOfxStatOK;
    }
    if (!strcmp(action, kOfxImageEffectActionEndSequenceRender) ||
        !strcmp(action, kOfxActionBeginInstanceChanged) ||
        !strcmp(action, kOfxActionEndInstanceChanged))
        return kOfxStatOK;
    /* isIdentity, getTimeDomain, syncPrivateData, instance edit: the host's default. */
    return kOfxStatReplyDefault;
}
