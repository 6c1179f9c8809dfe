/* nprfx OpenFX test host — opening and closing a bundle: the host's properties (as its profile
 * has them), dlopen of the binary inside the bundle, and for every plug-in load, describe and
 * describeInContext in the contexts both it and the host support, each context descriptor
 * checked against the node descriptor of the same identifier (params with their types, defaults
 * and ranges, clips with their optional flags). A plug-in that refuses to load here
 * (kOfxStatErrMissingHostFeature) or has no context the host supports stays unavailable with
 * its reason; the others load. */
#define _POSIX_C_SOURCE 200809L /* strdup */
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ofx_host_internal.h"

/* ---- actions --------------------------------------------------------------------------------- */

OfxStatus internal_call(hplugin *pl, const char *action, const void *handle, hprops *in,
                        hprops *out)
{
    return pl->p->mainEntry(action, handle, (OfxPropertySetHandle)in, (OfxPropertySetHandle)out);
}

static void host_properties(nprfx_ofx_host *h)
{
    OfxPropertySetHandle p = (OfxPropertySetHandle)&h->props;
    internal_set_string(p, kOfxPropType, 0, kOfxTypeImageEffectHost);
    internal_set_string(p, kOfxPropName, 0, "org.nprfx.testhost");
    internal_set_string(p, kOfxPropLabel, 0, "nprfx test host");
    internal_set_int(p, kOfxPropAPIVersion, 0, 1);
    internal_set_int(p, kOfxPropAPIVersion, 1, 4);
    internal_set_int(p, kOfxPropVersion, 0, NPRFX_VERSION_MAJOR);
    internal_set_int(p, kOfxPropVersion, 1, NPRFX_VERSION_MINOR);
    internal_set_int(p, kOfxPropVersion, 2, NPRFX_VERSION_PATCH);
    internal_set_string(p, kOfxPropVersionLabel, 0, NPRFX_VERSION_STRING);
    internal_set_int(p, kOfxImageEffectHostPropIsBackground, 0, 1);
    internal_set_int(p, kOfxImageEffectPropSupportsOverlays, 0, 0);
    internal_set_int(p, kOfxImageEffectPropSupportsTiles, 0, 1);
    /* contexts, temporal access, multi-resolution, components and depths */
    internal_profile_host_props(h->profile, p);
    internal_set_int(p, kOfxImageEffectPropSupportsMultipleClipDepths, 0, 0);
    internal_set_int(p, kOfxImageEffectPropSupportsMultipleClipPARs, 0, 0);
    internal_set_int(p, kOfxImageEffectPropSetableFrameRate, 0, 0);
    internal_set_int(p, kOfxImageEffectPropSetableFielding, 0, 0);
    internal_set_int(p, kOfxImageEffectInstancePropSequentialRender, 0, 1);
    internal_set_int(p, kOfxParamHostPropSupportsCustomInteract, 0, 0);
    internal_set_int(p, kOfxParamHostPropSupportsStringAnimation, 0, 0);
    internal_set_int(p, kOfxParamHostPropSupportsChoiceAnimation, 0, 0);
    internal_set_int(p, kOfxParamHostPropSupportsBooleanAnimation, 0, 0);
    internal_set_int(p, kOfxParamHostPropSupportsCustomAnimation, 0, 0);
    internal_set_int(p, kOfxParamHostPropMaxParameters, 0, -1);
    internal_set_int(p, kOfxParamHostPropMaxPages, 0, 0);
    internal_set_int(p, kOfxParamHostPropPageRowColumnCount, 0, 0);
    internal_set_int(p, kOfxParamHostPropPageRowColumnCount, 1, 0);
}

/* The plug-in refused to load in this host (kOfxStatErrMissingHostFeature from an action): it
 * stays unavailable, the others load. Its reason is what it posted while loading; the refusal
 * itself is no error, but a blank reason is, when a node uses the plug-in (render.c). */
static void refuse(nprfx_ofx_host *h, hplugin *pl, const char *action)
{
    (void)h;
    pl->unavailable = 1;
    if (!pl->reason[0])
        snprintf(pl->reason, sizeof pl->reason,
                 "it refused to load (%s: kOfxStatErrMissingHostFeature), and the plug-in's error "
                 "message is empty",
                 action);
}

/* describeInContext, then check the context descriptor against the node descriptor: every
 * param with its type, default and ranges, every clip with its optional flag. The adapter must
 * derive these, never restate them; this is where a slip would show. */
static nprfx_result describe_context(nprfx_ofx_host *h, hplugin *pl, const char *context,
                                     heffect **out)
{
    const char *id = pl->p->pluginIdentifier;
    heffect *e = internal_effect_new(pl, kOfxTypeImageEffect);
    hprops in;
    internal_props_init(&in, K_PLAIN);
    if (!e || internal_props_copy(&e->props, &pl->descriptor->props) != kOfxStatOK) {
        internal_effect_free(e);
        return nprfx_error(h->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    internal_set_string((OfxPropertySetHandle)&in, kOfxImageEffectPropContext, 0, context);
    OfxStatus st = internal_call(pl, kOfxImageEffectActionDescribeInContext, e, &in, NULL);
    internal_props_free(&in);
    if (st == kOfxStatErrMissingHostFeature) {
        internal_effect_free(e);
        refuse(h, pl, kOfxImageEffectActionDescribeInContext);
        return NPRFX_OK;
    }
    if (st != kOfxStatOK) {
        internal_effect_free(e);
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: describeInContext(%s) failed (%d)", id,
                           context, st);
    }
    *out = e;
    const nprfx_node_desc *d = pl->desc;
    if (!d) return NPRFX_OK;
    if (!internal_effect_clip(e, NPRFX_OFX_OUTPUT_CLIP))
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: no Output clip", id);
    int general = !strcmp(context, kOfxImageEffectContextGeneral);
    char name[NPRFX_OFX_NAME_MAX];
    for (int k = 0; k < d->num_inputs; k++) {
        if (!general && k != ofx_names_main_input(d)) continue;
        ofx_names_clip_name(d, k, name, sizeof name);
        hclip *c = internal_effect_clip(e, name);
        if (!c)
            return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s (%s): no clip %s for input '%s'", id,
                               context, name, d->inputs[k].name);
        if (internal_pint(&c->props, kOfxImageClipPropOptional, 0, -1) !=
            ((d->inputs[k].flags & NPRFX_INPUT_OPTIONAL) != 0))
            return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: clip %s: wrong optional flag", id,
                               name);
    }
    static const char *const types[] = {kOfxParamTypeDouble,  kOfxParamTypeInteger,
                                        kOfxParamTypeBoolean, kOfxParamTypeChoice,
                                        kOfxParamTypeRGBA,    kOfxParamTypeString};
    for (int i = 0; i < d->num_params; i++) {
        const nprfx_param_desc *p = &d->params[i];
        hparam *hp = internal_effect_param(e, p->name);
        if (!hp || !internal_type_is(hp, types[p->type]))
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
                bad |= internal_get_double(pp, kOfxParamPropDefault, c, &v) || v != p->def[c];
                bad |= internal_get_double(pp, kOfxParamPropMin, c, &v) || v != p->hard_min;
                bad |= internal_get_double(pp, kOfxParamPropMax, c, &v) || v != p->hard_max;
                bad |= internal_get_double(pp, kOfxParamPropDisplayMin, c, &v) || v != p->soft_min;
                bad |= internal_get_double(pp, kOfxParamPropDisplayMax, c, &v) || v != p->soft_max;
            }
            break;
        case NPRFX_PARAM_INT:
            bad |= internal_get_int(pp, kOfxParamPropDefault, 0, &iv) || iv != (int)p->def[0];
            bad |= internal_get_int(pp, kOfxParamPropDisplayMin, 0, &iv) || iv != (int)p->soft_min;
            bad |= internal_get_int(pp, kOfxParamPropDisplayMax, 0, &iv) || iv != (int)p->soft_max;
            break;
        case NPRFX_PARAM_BOOL:
        case NPRFX_PARAM_CHOICE:
            bad |= internal_get_int(pp, kOfxParamPropDefault, 0, &iv) || iv != (int)p->def[0];
            for (int c = 0; p->type == NPRFX_PARAM_CHOICE && p->choices && p->choices[c]; c++)
                bad |= internal_get_string(pp, kOfxParamPropChoiceOption, c, &s) ||
                       strcmp(s, p->choices[c]);
            break;
        case NPRFX_PARAM_STRING:
            bad |= internal_get_string(pp, kOfxParamPropDefault, 0, &s) ||
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
    OfxStatus st = internal_call(pl, kOfxActionLoad, NULL, NULL, NULL);
    if (st == kOfxStatErrMissingHostFeature) {
        refuse(h, pl, kOfxActionLoad);
        return NPRFX_OK;
    }
    if (st != kOfxStatOK && st != kOfxStatReplyDefault)
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: load failed (%d)", id, st);
    pl->loaded = 1;
    if (!(pl->descriptor = internal_effect_new(pl, kOfxTypeImageEffect)))
        return nprfx_error(h->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    internal_set_string((OfxPropertySetHandle)&pl->descriptor->props, kOfxPluginPropFilePath, 0,
                        h->bundle);
    st = internal_call(pl, kOfxActionDescribe, pl->descriptor, NULL, NULL);
    if (st == kOfxStatErrMissingHostFeature) {
        refuse(h, pl, kOfxActionDescribe);
        return NPRFX_OK;
    }
    if (st != kOfxStatOK)
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: describe failed (%d)", id, st);
    hprops *dp = &pl->descriptor->props;
    /* The version a host lists plug-ins by and the one it shows must agree. */
    if (internal_pint(dp, kOfxPropVersion, 0, -1) != (int)pl->p->pluginVersionMajor ||
        internal_pint(dp, kOfxPropVersion, 1, -1) != (int)pl->p->pluginVersionMinor)
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL,
                           "%s: the descriptor's kOfxPropVersion %d.%d is not the plug-in's %u.%u",
                           id, internal_pint(dp, kOfxPropVersion, 0, -1),
                           internal_pint(dp, kOfxPropVersion, 1, -1), pl->p->pluginVersionMajor,
                           pl->p->pluginVersionMinor);
    if (pl->desc && strcmp(internal_pstr(dp, kOfxPropLabel, 0, ""), pl->desc->label))
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: label differs from the node's", id);
    nprfx_result r;
    const hprofile *pf = h->profile;
    char offered[256] = "";
    size_t len = 0;
    for (int i = 0; i < internal_pdim(dp, kOfxImageEffectPropSupportedContexts); i++) {
        const char *c = internal_pstr(dp, kOfxImageEffectPropSupportedContexts, i, "");
        int w = snprintf(offered + len, sizeof offered - len, "%s%s", len ? ", " : "", c);
        if (w > 0 && (size_t)w < sizeof offered - len) len += (size_t)w;
        /* Only the contexts this host has: a host never describes the others. */
        if (!strcmp(c, kOfxImageEffectContextGeneral) && pf->general) {
            if ((r = describe_context(h, pl, c, &pl->general))) return r;
        } else if (!strcmp(c, kOfxImageEffectContextFilter) && pf->filter) {
            if ((r = describe_context(h, pl, c, &pl->filter))) return r;
        }
        if (pl->unavailable) return NPRFX_OK;
    }
    /* The strict host requires General of every plug-in (nodes with several inputs need it); a
     * host of one context has no use for a plug-in without that context. */
    if (pf->general && pf->filter && !pl->general)
        return nprfx_error(h->ctx, NPRFX_ERR_INTERNAL, "%s: no General context", id);
    if (!pl->general && !pl->filter) {
        pl->unavailable = 1;
        snprintf(pl->reason, sizeof pl->reason,
                 "it offers no context this host supports (the plug-in: %s; this host, %s: %s)",
                 len ? offered : "none", pf->like,
                 pf->general ? kOfxImageEffectContextGeneral : kOfxImageEffectContextFilter);
    }
    return NPRFX_OK;
}

/* ---- open / close ---------------------------------------------------------------------------- */

/* The one open host, for the suite functions (see ofx_host_internal.h). */
nprfx_ofx_host *internal_g_host;

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

nprfx_result nprfx_ofx_host_open(nprfx_context *ctx, const char *bundle, const char *profile,
                                 nprfx_ofx_host **out)
{
    *out = NULL;
    if (internal_g_host)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "an OpenFX host is already open");
    const hprofile *pf = internal_profile_find(profile ? profile : "strict");
    if (!pf)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "no host profile '%s' (there are %s)",
                           profile, internal_profile_names());
    nprfx_ofx_host *h = calloc(1, sizeof *h);
    if (!h) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    h->ctx = ctx;
    h->profile = pf;
    h->exec = nprfx_context_executor(ctx);
    /* Recursive: a clip fetch evaluates the upstream graph, whose nodes are plug-ins that fetch
     * their own clips on the same thread (tone's coverage from a matte node, at other frames). */
    pthread_mutexattr_t at;
    pthread_mutexattr_init(&at);
    pthread_mutexattr_settype(&at, PTHREAD_MUTEX_RECURSIVE);
    pthread_mutex_init(&h->lock, &at);
    pthread_mutexattr_destroy(&at);
    internal_props_init(&h->props, K_PLAIN);
    host_properties(h);
    h->ofx.host = (OfxPropertySetHandle)&h->props;
    h->ofx.fetchSuite = internal_fetch_suite;
    h->hook.render = internal_hook_render;
    h->hook.release = internal_hook_release;
    h->hook.user = h;
    h->hook.exports = 1; /* the plug-ins write their exports, as in any host */
    internal_g_host = h;
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
            ofx_names_plugin_id(nprfx_node_at(k), id, sizeof id);
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
        h->loading = pl; /* messages with a NULL or descriptor handle are its reason */
        r = load_plugin(h, pl);
        h->loading = NULL;
        if (r) goto fail;
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

void nprfx_ofx_host_set_footage(nprfx_ofx_host *h, int on)
{
    if (h) h->footage = on;
}

void nprfx_ofx_host_set_analyze(nprfx_ofx_host *h, int on)
{
    if (h) h->analyze = on;
}

const char *nprfx_ofx_host_profile(const nprfx_ofx_host *h)
{
    return h ? h->profile->name : "";
}

const char *nprfx_ofx_host_unavailable(const nprfx_ofx_host *h, int i, const char **reason)
{
    if (!h || i < 0 || i >= h->nplugins || !h->plugins[i].unavailable) return NULL;
    if (reason) *reason = h->plugins[i].reason;
    return h->plugins[i].p->pluginIdentifier ? h->plugins[i].p->pluginIdentifier : "?";
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
        if (pl->loaded && !h->instances)
            (void)internal_call(pl, kOfxActionUnload, NULL, NULL, NULL);
        internal_effect_free(pl->descriptor);
        internal_effect_free(pl->general);
        internal_effect_free(pl->filter);
    }
    free(h->plugins);
    if (h->dl && !h->instances) dlclose(h->dl);
    internal_props_free(&h->props);
    pthread_mutex_destroy(&h->lock);
    free(h->bundle);
    free(h->binary);
    if (internal_g_host == h) internal_g_host = NULL;
    free(h);
}
