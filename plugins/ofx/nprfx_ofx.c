/* nprfx OpenFX adapter — every registered node descriptor becomes one OFX image-effect plug-in
 * of the bundle nprfx.ofx.bundle. Nothing here knows a particular node: identifiers, clips,
 * params, defaults, ranges and hints are all derived from the descriptors (node.h), so a node
 * file added to plugins/ appears in hosts without touching the adapter.
 *
 * This file is the adapter's top: the two exported entry points, the plug-in table and setHost,
 * and the dispatch of each action to the file that handles it (load: ofx_suites.c; describe:
 * ofx_describe.c; instance lifecycle: ofx_instance.c; render: ofx_render.c; the questions before
 * a render: ofx_actions.c). It has no header: nothing in the adapter calls into it. */
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "nprfx/node.h"
#include "ofx_actions.h"
#include "ofx_api.h"
#include "ofx_describe.h"
#include "ofx_handover.h"
#include "ofx_instance.h"
#include "ofx_look.h"
#include "ofx_names.h"
#include "ofx_render.h"
#include "ofx_suites.h"
#include "support/data_files.h"

#if defined(__GNUC__)
#define NPRFX_OFX_EXPORT __attribute__((visibility("default")))
#else
#define NPRFX_OFX_EXPORT
#endif

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
static int plugin_count, node_count; /* the nodes first, then the looks (ofx_look.h) */
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
        ofx_names_plugin_id(nprfx_node_at(i), plugin_ids[i], sizeof plugin_ids[i]);
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
    node_count = n;
    int looks = ofx_looks_discover(MAX_PLUGINS - n);
    for (int i = 0; i < looks; i++) {
        OfxPlugin *p = &plugins[n + i];
        snprintf(plugin_ids[n + i], sizeof plugin_ids[n + i], "%s", ofx_look_at(i)->d.id);
        p->pluginApi = kOfxImageEffectPluginApi;
        p->apiVersion = kOfxImageEffectPluginApiVersion;
        p->pluginIdentifier = plugin_ids[n + i];
        p->pluginVersionMajor = 1;
        p->pluginVersionMinor = ofx_look_at(i)->version;
        p->setHost = set_host;
        p->mainEntry = entries[n + i];
    }
    plugin_count = n + looks;
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

/* ---- dispatch -------------------------------------------------------------------------------- */

static OfxStatus main_entry(int index, const char *action, const void *handle,
                            OfxPropertySetHandle in_args, OfxPropertySetHandle out_args)
{
    if (index >= node_count)
        return ofx_look_main(index - node_count, action, handle, in_args, out_args);
    const nprfx_node_desc *d = nprfx_node_at(index);
    OfxImageEffectHandle fx = (OfxImageEffectHandle)handle;
    if (!d || !action) return kOfxStatErrUnknown;
    if (!strcmp(action, kOfxActionLoad)) return ofx_suites_load();
    if (!strcmp(action, kOfxActionUnload)) {
        internal_stipple_shipped_release(); /* the process-wide dot sequence; instances keep theirs
                                             */
        return kOfxStatOK;
    }
    if (!ofx_g.prop || !ofx_g.fx || !ofx_g.param) return kOfxStatErrFatal;
    if (!strcmp(action, kOfxActionDescribe)) return ofx_describe(d, fx);
    if (!strcmp(action, kOfxImageEffectActionDescribeInContext))
        return ofx_describe_in_context(d, fx, in_args);
    if (!strcmp(action, kOfxActionCreateInstance)) return ofx_instance_create(d, fx);
    ofx_instance *inst = ofx_instance_get(fx);
    if (!inst) return kOfxStatErrBadHandle;
    if (!strcmp(action, kOfxActionDestroyInstance)) {
        /* a host that makes an instance per frame finds what this one kept in the next */
        if (!ofx_g.temporal) ofx_handover_leave(inst);
        return ofx_instance_destroy(fx);
    }
    if (!strcmp(action, kOfxImageEffectActionRender)) return ofx_render(inst, in_args);
    if (!strcmp(action, kOfxImageEffectActionGetRegionOfDefinition))
        return ofx_region_of_definition(inst, in_args, out_args);
    if (!strcmp(action, kOfxImageEffectActionGetRegionsOfInterest))
        return ofx_regions_of_interest(inst, in_args, out_args);
    if (!strcmp(action, kOfxImageEffectActionGetFramesNeeded))
        return ofx_frames_needed(inst, in_args, out_args);
    if (!strcmp(action, kOfxImageEffectActionGetClipPreferences))
        return ofx_clip_preferences(inst, out_args);
    if (!strcmp(action, kOfxActionInstanceChanged))
        return ofx_is_analyze(inst, in_args) ? ofx_analyze(inst)
                                             : ofx_instance_changed(inst, in_args);
    if (!strcmp(action, kOfxActionPurgeCaches)) {
        ofx_instance_drop_state(inst);
        return kOfxStatOK;
    }
    if (!strcmp(action, kOfxImageEffectActionBeginSequenceRender)) {
        ofx_instance_forget_export(inst);
        return kOfxStatOK;
    }
    if (!strcmp(action, kOfxImageEffectActionEndSequenceRender) ||
        !strcmp(action, kOfxActionBeginInstanceChanged) ||
        !strcmp(action, kOfxActionEndInstanceChanged))
        return kOfxStatOK;
    /* isIdentity, getTimeDomain, syncPrivateData, instance edit: the host's default. */
    return kOfxStatReplyDefault;
}
