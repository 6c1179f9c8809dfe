/* nprfx OpenFX test host — render driving, the graph's render hook: a plug-in instance per graph
 * node created at its first render in the context the profile picks, params and channel
 * selectors synced from the graph with the instance-changed actions of an edit, clip
 * preferences, the region and frame queries a host makes, begin/endSequenceRender, then render
 * of the window into a whole-frame output image in the profile's depth that is converted back;
 * on the first render the frames fetched are checked against the frames declared; a failure
 * carries the plug-in's message (messages.c); release destroys the instance. */
#define _POSIX_C_SOURCE 200809L /* strdup */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ofx_host_internal.h"

/* ---- instances ------------------------------------------------------------------------------- */

static void inst_free(node_inst *ni)
{
    if (!ni) return;
    internal_effect_free(ni->fx);
    free(ni->in_comps);
    for (int k = 0; ni->frames && ni->desc && k < ni->desc->num_inputs; k++)
        internal_frames_free(&ni->frames[k]);
    free(ni->frames);
    free(ni);
}

static hplugin *find_plugin(nprfx_ofx_host *h, const nprfx_node_desc *d)
{
    char id[NPRFX_OFX_NAME_MAX];
    /* a look (look.c) stands as a node whose id is its plug-in's identifier */
    if (!strncmp(d->id, NPRFX_OFX_LOOK_PREFIX, strlen(NPRFX_OFX_LOOK_PREFIX)))
        snprintf(id, sizeof id, "%s", d->id);
    else
        ofx_names_plugin_id(d, id, sizeof id);
    for (int i = 0; i < h->nplugins; i++)
        if (h->plugins[i].p->pluginIdentifier && !strcmp(h->plugins[i].p->pluginIdentifier, id))
            return &h->plugins[i];
    return NULL;
}

/* The context of a new instance. Strict: Filter when the plug-in offers it and only the main
 * input is connected (as a host would for a plain filter), so both contexts get exercised;
 * General otherwise, and for a node with flow-derivable inputs unless on footage (its Filter
 * context takes footage, not the graph's input). Natron: General always. MLT: Filter always, so
 * a node with another input connected cannot be built there. Returns 1 for Filter, 0 for
 * General, -1 (error raised). */
static int choose_context(nprfx_ofx_host *h, hplugin *pl, const nprfx_render_args *a, int footage)
{
    const nprfx_node_desc *d = a->node;
    int main = ofx_names_main_input(d), only_main = 1, derivable = 0;
    for (int k = 0; k < d->num_inputs; k++) {
        only_main &= k == main || !a->inputs[k].data;
        derivable |= ofx_derivable(d, k);
    }
    if (!h->profile->filter) return 0;
    if (h->profile->general) return pl->filter && only_main && (footage || !derivable);
    for (int k = 0; k < d->num_inputs; k++)
        if (k != main && a->inputs[k].data) {
            nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED,
                        "%s: this host (%s) has only the Filter context, whose one input clip is "
                        "Source ('%s'): input '%s' cannot be connected",
                        pl->p->pluginIdentifier, h->profile->like, d->inputs[main].name,
                        d->inputs[k].name);
            return -1;
        }
    return 1;
}

/* The instance of a graph node, created at its first render in the context the profile picks:
 * clips connected as the graph connects the node's inputs, params at their defaults. */
static nprfx_result inst_create(nprfx_ofx_host *h, const nprfx_render_args *a, int footage,
                                node_inst **out)
{
    const nprfx_node_desc *d = a->node;
    hplugin *pl = find_plugin(h, d);
    if (!pl)
        return nprfx_error(a->ctx, NPRFX_ERR_UNKNOWN_NODE, "the bundle %s has no plug-in for %s",
                           h->bundle, d->id);
    if (pl->unavailable)
        return nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED, "%s is not available in this host: %s",
                           pl->p->pluginIdentifier, pl->reason);
    int filter = choose_context(h, pl, a, footage);
    if (filter < 0) return NPRFX_ERR_UNSUPPORTED;
    node_inst *ni = calloc(1, sizeof *ni);
    size_t ni_n = (size_t)d->num_inputs + 1;
    if (!ni || !(ni->frames = calloc(ni_n, sizeof *ni->frames)) ||
        !(ni->in_comps = calloc(ni_n, sizeof(int))) ||
        !(ni->fx = internal_effect_new(pl, kOfxTypeImageEffectInstance))) {
        inst_free(ni);
        return nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    ni->h = h;
    ni->pl = pl;
    ni->desc = d;
    ni->out_comps = 4;
    ni->filter = filter;
    const hprofile *pf = h->profile;
    heffect *e = ni->fx, *src = filter ? pl->filter : pl->general;
    OfxStatus st = internal_props_copy(&e->props, &src->props);
    OfxPropertySetHandle ep = (OfxPropertySetHandle)&e->props;
    int w = nprfx_rect_width(a->frame), hgt = nprfx_rect_height(a->frame);
    double s = internal_host_scale(a);
    internal_set_string(ep, kOfxPropType, 0, kOfxTypeImageEffectInstance);
    internal_set_string(ep, kOfxImageEffectPropContext, 0,
                        filter ? kOfxImageEffectContextFilter : kOfxImageEffectContextGeneral);
    internal_set_pointer(ep, kOfxPropInstanceData, 0, NULL);
    internal_set_pointer(ep, kOfxImageEffectPropPluginHandle, 0, pl->descriptor);
    internal_set_double(ep, kOfxImageEffectPropProjectSize, 0, w / s);
    internal_set_double(ep, kOfxImageEffectPropProjectSize, 1, hgt / s);
    internal_set_double(ep, kOfxImageEffectPropProjectOffset, 0, a->frame.x0 / s);
    internal_set_double(ep, kOfxImageEffectPropProjectOffset, 1, a->frame.y0 / s);
    internal_set_double(ep, kOfxImageEffectPropProjectExtent, 0, a->frame.x1 / s);
    internal_set_double(ep, kOfxImageEffectPropProjectExtent, 1, a->frame.y1 / s);
    internal_set_double(ep, kOfxImageEffectPropProjectPixelAspectRatio, 0, 1.0);
    internal_set_double(ep, kOfxImageEffectInstancePropEffectDuration, 0,
                        (double)(a->last_frame - a->first_frame + 1));
    internal_set_double(ep, kOfxImageEffectPropFrameRate, 0, 24.0);
    internal_set_int(ep, kOfxPropIsInteractive, 0, 0);
    e->ni = ni;
    char name[NPRFX_OFX_NAME_MAX];
    for (int i = 0; st == kOfxStatOK && i < src->nclips; i++) {
        hclip *c = internal_clip_add(e, src->clips[i]->name);
        if (!c || internal_props_copy(&c->props, &src->clips[i]->props) != kOfxStatOK) {
            st = kOfxStatErrMemory;
            break;
        }
        int connected = 0, alpha = 0;
        if (!strcmp(c->name, NPRFX_OFX_OUTPUT_CLIP)) {
            c->input = -1;
            connected = 1;
        }
        for (int k = 0; k < d->num_inputs && c->input == -2; k++) {
            ofx_names_clip_name(d, k, name, sizeof name);
            if (!strcmp(name, c->name)) {
                c->input = k;
                connected = a->inputs[k].data != NULL;
                /* A 1-channel main input comes as Alpha, the other inputs as RGBA: both kinds
                 * of host image reach the adapter, and a 1-channel result goes out as Alpha
                 * (where the profile's host has Alpha images). */
                alpha = connected && pf->alpha && k == ofx_names_main_input(d) &&
                        a->inputs[k].channels == 1;
                ni->in_comps[k] = alpha ? 1 : 4;
            }
        }
        OfxPropertySetHandle cp = (OfxPropertySetHandle)&c->props;
        internal_set_int(cp, kOfxImageClipPropConnected, 0, connected);
        const char *comps = !connected ? kOfxImageComponentNone
                            : alpha    ? kOfxImageComponentAlpha
                                       : kOfxImageComponentRGBA;
        internal_set_string(cp, kOfxImageEffectPropComponents, 0, comps);
        internal_set_string(cp, kOfxImageClipPropUnmappedComponents, 0, comps);
        const char *depth = connected ? internal_depth_name(pf->depth) : kOfxBitDepthNone;
        internal_set_string(cp, kOfxImageEffectPropPixelDepth, 0, depth);
        internal_set_string(cp, kOfxImageClipPropUnmappedPixelDepth, 0, depth);
        /* a picture without alpha (RGB footage) is opaque, as hosts mark it */
        int rgb = c->input >= 0 && connected && a->inputs[c->input].channels == 3;
        internal_set_string(cp, kOfxImageEffectPropPreMultiplication, 0,
                            rgb ? kOfxImageOpaque : kOfxImageUnPreMultiplied);
        internal_set_double(cp, kOfxImagePropPixelAspectRatio, 0, 1.0);
        internal_set_double(cp, kOfxImageEffectPropFrameRate, 0, 24.0);
        internal_set_double(cp, kOfxImageEffectPropUnmappedFrameRate, 0, 24.0);
        internal_set_double(cp, kOfxImageEffectPropFrameRange, 0, a->first_frame);
        internal_set_double(cp, kOfxImageEffectPropFrameRange, 1, a->last_frame);
        internal_set_double(cp, kOfxImageEffectPropUnmappedFrameRange, 0, a->first_frame);
        internal_set_double(cp, kOfxImageEffectPropUnmappedFrameRange, 1, a->last_frame);
        internal_set_string(cp, kOfxImageClipPropFieldOrder, 0, kOfxImageFieldNone);
        /* a multi-plane host's main input carries the layers look.c serves */
        if (pf->planes && h->nplanes && c->input >= 0 && c->input == ofx_names_main_input(d))
            for (int pl = 0; pl < h->nplanes; pl++)
                internal_set_string(cp, kFnOfxImageEffectPropComponentsPresent, pl, h->planes[pl]);
        internal_set_int(cp, kOfxImageClipPropContinuousSamples, 0, 0);
    }
    for (int i = 0; st == kOfxStatOK && i < src->nparams; i++) {
        const hparam *sp = src->params[i];
        hparam *p = internal_param_add(e, sp->type, sp->name);
        if (!p || internal_props_copy(&p->props, &sp->props) != kOfxStatOK) {
            st = kOfxStatErrMemory;
            break;
        }
        OfxPropertySetHandle pp = (OfxPropertySetHandle)&p->props;
        internal_set_string(pp, kOfxPropType, 0, kOfxTypeParameterInstance);
        int is_int, n = internal_param_dims(p, &is_int);
        char *sv;
        if (internal_type_is(p, kOfxParamTypeString) &&
            internal_get_string(pp, kOfxParamPropDefault, 0, &sv) == kOfxStatOK) {
            free(p->s);
            p->s = strdup(sv);
        } else if (n == 1 && is_int) {
            internal_get_int(pp, kOfxParamPropDefault, 0, &p->i);
        } else {
            for (int c = 0; c < n; c++)
                internal_get_double(pp, kOfxParamPropDefault, c, &p->d[c]);
        }
    }
    if (st != kOfxStatOK) {
        inst_free(ni);
        return nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    ni->args = a;
    ni->frame_flip = a->frame.y0 + a->frame.y1 - 1;
    internal_messages_reset(ni);
    st = internal_call(pl, kOfxActionCreateInstance, e, NULL, NULL);
    ni->args = NULL;
    if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
        char what[64];
        snprintf(what, sizeof what, "createInstance failed (OFX status %d)", st);
        nprfx_result r = internal_failure(ni, a->ctx, what);
        inst_free(ni);
        return r;
    }
    pthread_mutex_lock(&h->lock); /* look.c --outputs all makes instances on several threads */
    h->instances++;
    pthread_mutex_unlock(&h->lock);
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
    internal_set_string(p, kOfxPropChangeReason, 0, kOfxChangeUserEdited);
    if (!type) return;
    internal_set_string(p, kOfxPropType, 0, type);
    internal_set_string(p, kOfxPropName, 0, name);
    internal_set_double(p, kOfxPropTime, 0, a->time);
    internal_set_double(p, kOfxImageEffectPropRenderScale, 0, internal_host_scale(a));
    internal_set_double(p, kOfxImageEffectPropRenderScale, 1, internal_host_scale(a));
}

/* --analyze-shot: the Analyze Shot button pressed, when the plug-in has one; the clips serve
 * the render's frames meanwhile (ni->args is set). What it fetched does not count as the first
 * render's. */
static nprfx_result press_button(node_inst *ni, const nprfx_render_args *a, const char *name);

static nprfx_result press_analyze(node_inst *ni, const nprfx_render_args *a)
{
    char name[NPRFX_OFX_NAME_MAX];
    ofx_names_extra_param(ni->desc, "analyze", name, sizeof name);
    return press_button(ni, a, name);
}

/* --choose NAME=OPTION: the choice set to the option of that text among those it lists now, with
 * the instance-changed actions of a user's edit. */
static nprfx_result choose(node_inst *ni, const nprfx_render_args *a, const char *what)
{
    const char *eq = strchr(what, '=');
    char name[NPRFX_OFX_NAME_MAX];
    snprintf(name, sizeof name, "%.*s", eq ? (int)(eq - what) : 0, what);
    hparam *p = internal_effect_param(ni->fx, name);
    if (!eq || !p || !internal_type_is(p, kOfxParamTypeChoice))
        return nprfx_error(a->ctx, NPRFX_ERR_UNKNOWN_PARAM, "%s: no choice param '%s'",
                           ni->pl->p->pluginIdentifier, name);
    int n = internal_pdim(&p->props, kOfxParamPropChoiceOption), pick = -1;
    for (int i = 0; i < n && pick < 0; i++)
        if (!strcmp(internal_pstr(&p->props, kOfxParamPropChoiceOption, i, ""), eq + 1)) pick = i;
    if (pick < 0)
        return nprfx_error(a->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s: %s lists no option '%s' (%d options)", ni->pl->p->pluginIdentifier,
                           name, eq + 1, n);
    p->i = pick;
    return press_button(ni, a, name);
}

/* Before the first render: the params look.c was given (NAME=VALUE, as a project would hold
 * them), then its buttons pressed, each param's value printed after ("param NAME = VALUE"). */
static nprfx_result first_settings(node_inst *ni, const nprfx_render_args *a)
{
    nprfx_ofx_host *h = ni->h;
    for (int i = 0; i < h->nparam_sets; i++) {
        const char *eq = strchr(h->param_sets[i], '=');
        char name[NPRFX_OFX_NAME_MAX];
        snprintf(name, sizeof name, "%.*s", eq ? (int)(eq - h->param_sets[i]) : 0,
                 h->param_sets[i]);
        hparam *p = internal_effect_param(ni->fx, name);
        if (!eq || !p)
            return nprfx_error(a->ctx, NPRFX_ERR_UNKNOWN_PARAM, "%s: no param '%s'",
                               ni->pl->p->pluginIdentifier, name);
        free(p->s);
        p->s = strdup(eq + 1);
        /* a text's \n is a line break */
        for (char *c = p->s; c && (c = strstr(c, "\\n"));)
            c[0] = '\n', memmove(c + 1, c + 2, strlen(c + 2) + 1);
    }
    for (int i = 0; i < h->npresses + h->nchooses; i++) {
        nprfx_result r = i < h->npresses ? press_button(ni, a, h->presses[i])
                                         : choose(ni, a, h->chooses[i - h->npresses]);
        if (r) return r;
        for (int k = 0; k < ni->fx->nparams; k++) {
            hparam *p = ni->fx->params[k];
            if (internal_type_is(p, kOfxParamTypeString))
                fprintf(stderr, "param %s = %s\n", p->name, p->s ? p->s : "");
            int n = internal_pdim(&p->props, kOfxParamPropChoiceOption);
            if (internal_type_is(p, kOfxParamTypeChoice) && p->i >= 0 && p->i < n)
                fprintf(stderr, "choice %s = %s (%d of %d)\n", p->name,
                        internal_pstr(&p->props, kOfxParamPropChoiceOption, p->i, ""), p->i, n);
        }
    }
    return NPRFX_OK;
}

/* A push button pressed, or a param the caller has set, as a user edits it: the instance-changed
 * actions of an edit. */
static nprfx_result press_button(node_inst *ni, const nprfx_render_args *a, const char *name)
{
    if (!internal_effect_param(ni->fx, name)) return NPRFX_OK;
    hprops in;
    internal_props_init(&in, K_PLAIN);
    set_change_args(&in, a, NULL, NULL);
    OfxStatus st = internal_call(ni->pl, kOfxActionBeginInstanceChanged, ni->fx, &in, NULL);
    internal_props_free(&in);
    internal_props_init(&in, K_PLAIN);
    set_change_args(&in, a, kOfxTypeParameter, name);
    ni->analyzing = 1;
    if (st == kOfxStatOK || st == kOfxStatReplyDefault)
        st = internal_call(ni->pl, kOfxActionInstanceChanged, ni->fx, &in, NULL);
    ni->analyzing = 0;
    internal_props_free(&in);
    internal_props_init(&in, K_PLAIN);
    set_change_args(&in, a, NULL, NULL);
    if (st == kOfxStatOK || st == kOfxStatReplyDefault)
        st = internal_call(ni->pl, kOfxActionEndInstanceChanged, ni->fx, &in, NULL);
    internal_props_free(&in);
    for (int k = 0; k < ni->desc->num_inputs; k++)
        ni->frames[k].nfetched = 0;
    if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
        char what[NPRFX_OFX_NAME_MAX + 48];
        snprintf(what, sizeof what, "instanceChanged of %s failed", name);
        return internal_failure(ni, a->ctx, what);
    }
    return NPRFX_OK;
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
        hparam *p = internal_effect_param(e, pd->name);
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
    /* A graph's design width: the runner's param scale beyond the host's render scale is the
     * full-resolution width over the design width. */
    ofx_names_extra_param(d, "designWidth", name, sizeof name);
    hparam *dw = ofx_names_has_pixel_params(d) ? internal_effect_param(e, name) : NULL;
    if (dw) {
        double hs = internal_host_scale(a), extra = a->render_scale / hs;
        int design = extra != 1.0 ? (int)lround(nprfx_rect_width(a->frame) / hs / extra) : 0;
        if (dw->i != design) {
            dw->i = design;
            changed[nchanged++] = dw->name;
        }
    }
    for (int k = 0; k < d->num_inputs; k++) {
        if (!a->inputs[k].data) continue;
        /* on footage a derived main input is Source read whole: no selector */
        if (ni->footage && ofx_derivable(d, k)) continue;
        int n = a->inputs[k].channels;
        int opt = ofx_names_selector_find(&d->inputs[k], 0, n);
        if (n > 4 || opt < 0) {
            r = nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED,
                            "input '%s' has %d channels: an OFX clip carries 1 to 4 (RGBA)",
                            d->inputs[k].name, n);
            goto done;
        }
        ofx_names_selector_name(d, k, name, sizeof name);
        hparam *p = internal_effect_param(e, name);
        if (!p) {
            int opts[NPRFX_OFX_CHAN_OPTIONS];
            /* a look's clips carry their AOVs whole: no selectors */
            if (ofx_names_selector_options(&d->inputs[k], opts) > 1 &&
                strncmp(d->id, NPRFX_OFX_LOOK_PREFIX, strlen(NPRFX_OFX_LOOK_PREFIX))) {
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
        internal_props_init(&in, K_PLAIN);
        set_change_args(&in, a, NULL, NULL);
        OfxStatus st = internal_call(ni->pl, kOfxActionBeginInstanceChanged, e, &in, NULL);
        for (int i = 0; i < nchanged && (st == kOfxStatOK || st == kOfxStatReplyDefault); i++) {
            set_change_args(&in, a, kOfxTypeParameter, changed[i]);
            st = internal_call(ni->pl, kOfxActionInstanceChanged, e, &in, NULL);
        }
        internal_props_free(&in);
        internal_props_init(&in, K_PLAIN);
        set_change_args(&in, a, NULL, NULL);
        if (st == kOfxStatOK || st == kOfxStatReplyDefault)
            st = internal_call(ni->pl, kOfxActionEndInstanceChanged, e, &in, NULL);
        internal_props_free(&in);
        if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: instanceChanged failed (%d)", id, st);
            goto done;
        }
    }
    if (nchanged || first) {
        hprops out;
        internal_props_init(&out, K_PLAIN);
        OfxStatus st =
            internal_call(ni->pl, kOfxImageEffectActionGetClipPreferences, e, NULL, &out);
        if (st == kOfxStatOK) {
            char key[NPRFX_OFX_NAME_MAX + 32];
            snprintf(key, sizeof key, "%s%s", kOfxImageClipPropComponentsPrefix,
                     NPRFX_OFX_OUTPUT_CLIP);
            const char *comps = internal_pstr(&out, key, 0, kOfxImageComponentRGBA);
            /* A host without Alpha images keeps the output RGBA whatever the plug-in asks. */
            ni->out_comps =
                !strcmp(comps, kOfxImageComponentAlpha) && ni->h->profile->alpha ? 1 : 4;
            hclip *oc = internal_effect_clip(e, NPRFX_OFX_OUTPUT_CLIP);
            internal_set_string((OfxPropertySetHandle)&oc->props, kOfxImageEffectPropComponents, 0,
                                ni->out_comps == 1 ? kOfxImageComponentAlpha
                                                   : kOfxImageComponentRGBA);
            internal_set_string((OfxPropertySetHandle)&oc->props,
                                kOfxImageEffectPropPreMultiplication, 0,
                                internal_pstr(&out, kOfxImageEffectPropPreMultiplication, 0,
                                              kOfxImageUnPreMultiplied));
        } else if (st != kOfxStatReplyDefault) {
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: getClipPreferences failed (%d)", id,
                            st);
        }
        internal_props_free(&out);
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
    double s = internal_host_scale(a);
    hprops in, out;
    internal_props_init(&in, K_PLAIN);
    internal_props_init(&out, K_PLAIN);
    OfxPropertySetHandle ip = (OfxPropertySetHandle)&in;
    internal_set_double(ip, kOfxPropTime, 0, a->time);
    internal_set_double(ip, kOfxImageEffectPropRenderScale, 0, s);
    internal_set_double(ip, kOfxImageEffectPropRenderScale, 1, s);
    nprfx_result r = NPRFX_OK;
    OfxStatus st = internal_call(ni->pl, kOfxImageEffectActionGetRegionOfDefinition, e, &in, &out);
    double rod[4];
    OfxRectI fr = internal_ofx_rect(a->frame, ni->frame_flip);
    if (st != kOfxStatOK ||
        internal_get_double_n((OfxPropertySetHandle)&out, kOfxImageEffectPropRegionOfDefinition, 4,
                              rod) ||
        rod[0] * s != fr.x1 || rod[1] * s != fr.y1 || rod[2] * s != fr.x2 || rod[3] * s != fr.y2) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL,
                        "%s: getRegionOfDefinition (status %d) does not give the frame %d,%d-%d,%d",
                        id, st, fr.x1, fr.y1, fr.x2, fr.y2);
        goto done;
    }
    internal_props_free(&out);
    internal_props_init(&out, K_PLAIN);
    double roi[4] = {fr.x1 / s, fr.y1 / s, fr.x2 / s, fr.y2 / s};
    internal_set_double_n(ip, kOfxImageEffectPropRegionOfInterest, 4, roi);
    st = internal_call(ni->pl, kOfxImageEffectActionGetRegionsOfInterest, e, &in, &out);
    if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: getRegionsOfInterest failed (%d)", id, st);
        goto done;
    }
    internal_props_free(&out);
    internal_props_init(&out, K_PLAIN);
    st = internal_call(ni->pl, kOfxImageEffectActionGetFramesNeeded, e, &in, &out);
    if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: getFramesNeeded failed (%d)", id, st);
        goto done;
    }
    /* Frames on a clip that is not connected are a plan for nothing: a host may act on them
     * (Nuke pre-fetches them), so the declaration must be exact. */
    size_t plen = strlen(kOfxImageClipPropFrameRangePrefix);
    for (int i = 0; st == kOfxStatOK && i < out.count; i++) {
        const char *key = out.items[i].name;
        if (strncmp(key, kOfxImageClipPropFrameRangePrefix, plen)) continue;
        hclip *c = internal_effect_clip(e, key + plen);
        if (!c || c->input < 0 || !a->inputs[c->input].data) {
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL,
                            "%s: getFramesNeeded declares frames on unconnected clip %s", id,
                            key + plen);
            goto done;
        }
    }
    char key[NPRFX_OFX_NAME_MAX + 32], name[NPRFX_OFX_NAME_MAX];
    for (int k = 0; k < d->num_inputs; k++) {
        ofx_names_clip_name(d, k, name, sizeof name);
        snprintf(key, sizeof key, "%s%s", kOfxImageClipPropFrameRangePrefix, name);
        int n = st == kOfxStatOK ? internal_pdim(&out, key) : 0;
        double v[64];
        if (n > 64) n = 64;
        if (n % 2 || (n && internal_get_double_n((OfxPropertySetHandle)&out, key, n, v)) ||
            !internal_frames_declare(&ni->frames[k], v, n, a->time)) {
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL,
                            "%s: getFramesNeeded: %s is not a list of "
                            "[lo, hi] pairs",
                            id, key);
            goto done;
        }
    }
    /* $NPRFX_OFXTEST_FRAMES_LOG: every declaration, a line a pair ("ID CLIP TIME LO HI"), for
     * tests of how much a plug-in makes a host prepare */
    const char *log = getenv("NPRFX_OFXTEST_FRAMES_LOG");
    FILE *lf = log && *log ? fopen(log, "a") : NULL;
    for (int k = 0; lf && k < d->num_inputs; k++) {
        const hframes *f = &ni->frames[k];
        if (!a->inputs[k].data) continue;
        ofx_names_clip_name(d, k, name, sizeof name);
        for (int j = 0; j < f->ndecl; j++)
            fprintf(lf, "%s %s %g %g %g\n", id, name, a->time, f->decl[2 * j], f->decl[2 * j + 1]);
    }
    if (lf) fclose(lf);
done:
    internal_props_free(&in);
    internal_props_free(&out);
    return r;
}

/* The output channels of the runner from the host image's components at pixel px: one each,
 * the first four. A node with more channels than RGBA has one case so far, stipple's 'coverage'
 * (5 channels: R, G, B, A, coverage), which the adapter hands out as R, G, B and the coverage in
 * A, so that a host that composites it sees the dots and where they are; here channels 0-2 come
 * from R, G, B, channel 4 (coverage) from A, and channel 3 (the runner's alpha, which the host
 * image does not carry) from A as well. A test compares R, G, B and coverage with the runner's
 * (tests/cli/ofx_profiles.sh); channel 3 is not comparable. */
static void unpack_pixel(const node_inst *ni, const void *pixels, size_t px, float *d, int nout)
{
    hdepth depth = ni->h->profile->depth;
    int nc = ni->out_comps;
    for (int c = 0; c < nout && c < nc; c++)
        d[c] = internal_depth_load(depth, pixels, px * (size_t)nc + (size_t)c);
    for (int c = nc; c < nout; c++)
        d[c] = internal_depth_load(depth, pixels, px * (size_t)nc + (size_t)(nc - 1));
}

/* On an instance's first render (no cache yet), every connected input must have been fetched at
 * exactly the frames getFramesNeeded declared (frames.c). */
static nprfx_result check_frames(node_inst *ni, const nprfx_render_args *a)
{
    const nprfx_node_desc *d = ni->desc;
    char why[600], name[NPRFX_OFX_NAME_MAX];
    for (int k = 0; k < d->num_inputs; k++) {
        if (!a->inputs[k].data || internal_frames_match(&ni->frames[k], why, sizeof why)) continue;
        ofx_names_clip_name(d, k, name, sizeof name);
        return nprfx_error(a->ctx, NPRFX_ERR_INTERNAL,
                           "%s: frames needed differ from frames fetched on clip %s at frame %g "
                           "(first render): %s",
                           ni->pl->p->pluginIdentifier, name, a->time, why);
    }
    return NPRFX_OK;
}

/* ---- --footage: the Filter context on the picture a flow node reads -------------------------- */

/* A footage render: the runner's args, what replaces them, and where Source comes from. */
typedef struct footage_call {
    const nprfx_render_args *orig;
    nprfx_render_args args;
    nprfx_image inputs[NPRFX_OFX_DERIVE_MAX_INPUTS];
    nprfx_image src; /* the picture at the render time, copied (a fetch's view does not last) */
    int main, via;   /* the main input; the input whose flow node's picture is Source, or -1 */
} footage_call;

static nprfx_result footage_fetch(void *user, int input, double time, nprfx_image *out)
{
    footage_call *fc = user;
    const nprfx_render_args *a = fc->orig;
    if (input == fc->main && fc->via >= 0) {
        if (time == a->time) {
            *out = fc->src;
            return NPRFX_OK;
        }
        return nprfx_graph_hook_fetch_upstream(a->fetch_user, fc->via, 0,
                                               (int)(time < 0 ? time - 0.5 : time + 0.5), out);
    }
    return a->fetch(a->fetch_user, input, time, out);
}

/* Whether flow param value v is one the plug-in may choose itself: a choice that changes the
 * channels the flow outputs (the plug-in takes the fewest that cover its inputs). */
static int flow_output_choice(const nprfx_node_desc *f, int i, const nprfx_value *v)
{
    nprfx_value vals[NPRFX_OFX_DERIVE_MAX_PARAMS];
    nprfx_output_info a, b;
    int ich[1] = {4};
    if (f->params[i].type != NPRFX_PARAM_CHOICE) return 0;
    nprfx_node_defaults(f, vals);
    if (nprfx_node_output_info(NULL, f, vals, ich, &a)) return 0;
    vals[i] = *v;
    if (nprfx_node_output_info(NULL, f, vals, ich, &b)) return 0;
    return a.channels != b.channels;
}

/* When node a->node is to be rendered on footage: fc set up, *use = 1. The graph must be the
 * General one the plug-in stands for: its flow-derivable inputs connected to one flow node with
 * the flow's default params (the plug-in derives with those), no other input but the main one. */
static nprfx_result footage_args(nprfx_ofx_host *h, const nprfx_render_args *a, footage_call *fc,
                                 int *use)
{
    const nprfx_node_desc *d = a->node, *f = ofx_flow_node();
    *use = 0;
    if (!h->footage || !f || d == f || d->num_inputs > NPRFX_OFX_DERIVE_MAX_INPUTS) return NPRFX_OK;
    const nprfx_value *fp = NULL;
    int main = ofx_names_main_input(d), via = -1;
    for (int k = 0; k < d->num_inputs; k++) {
        if (!a->inputs[k].data || !ofx_derivable(d, k)) continue;
        const nprfx_value *p = NULL;
        const nprfx_node_desc *up = nprfx_graph_hook_upstream(a->fetch_user, k, &p);
        if (up != f || (fp && p != fp))
            return nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED,
                               "--footage: input '%s' of %s is not connected to the flow node "
                               "its other derived inputs come from",
                               d->inputs[k].name, d->id);
        fp = p;
        via = k;
    }
    if (via < 0) return NPRFX_OK;
    for (int i = 0; i < f->num_params; i++) {
        nprfx_value def[NPRFX_OFX_DERIVE_MAX_PARAMS];
        nprfx_node_defaults(f, def);
        if (f->params[i].type != NPRFX_PARAM_STRING && !memcmp(def[i].v, fp[i].v, sizeof def[i].v))
            continue;
        if (!flow_output_choice(f, i, &fp[i]))
            return nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED,
                               "--footage: %s's flow node has '%s' other than its default: the "
                               "plug-in derives its inputs with the flow node's defaults",
                               d->id, f->params[i].name);
    }
    if (!h->profile->filter)
        return nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED,
                           "--footage: this host (%s) has no Filter context", h->profile->like);
    memset(fc, 0, sizeof *fc);
    fc->orig = a;
    fc->args = *a;
    fc->main = main;
    for (int k = 0; k < d->num_inputs; k++) {
        if (!a->inputs[k].data || ofx_derivable(d, k)) continue;
        if (k != main)
            return nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED,
                               "--footage: input '%s' of %s has no clip in the Filter context",
                               d->inputs[k].name, d->id);
        fc->inputs[k] = a->inputs[k]; /* Source is the main input itself */
    }
    fc->via = fc->inputs[main].data ? -1 : via;
    if (fc->via >= 0) {
        nprfx_image v;
        nprfx_result r =
            nprfx_graph_hook_fetch_upstream(a->fetch_user, via, 0, (int)(a->time + 0.5), &v);
        if (!r) r = nprfx_image_alloc(a->ctx, v.bounds, v.channels, &fc->src);
        if (!r) r = nprfx_image_copy(a->ctx, &v, &fc->src);
        if (r) {
            nprfx_image_free(&fc->src);
            return r;
        }
        fc->inputs[main] = fc->src;
    }
    fc->args.inputs = fc->inputs;
    fc->args.fetch = footage_fetch;
    fc->args.fetch_user = fc;
    *use = 1;
    return NPRFX_OK;
}

static nprfx_result hook_render(nprfx_ofx_host *h, const nprfx_render_args *a, void **slot,
                                int footage);

nprfx_result internal_hook_render(void *user, const nprfx_render_args *a, void **slot)
{
    nprfx_ofx_host *h = user;
    /* A flow node of the General graph: the runner's, whose result only sizes the frame of the
     * node it feeds (that node's plug-in computes its own from Source). */
    if (h->footage && a->node == ofx_flow_node()) return nprfx_node_render(a);
    footage_call fc;
    int use = 0;
    nprfx_result r = footage_args(h, a, &fc, &use);
    if (r || !use) return r ? r : hook_render(h, a, slot, 0);
    r = hook_render(h, &fc.args, slot, 1);
    nprfx_image_free(&fc.src);
    return r;
}

/* A multi-plane host asks a multi-planar plug-in which planes it needs of each clip before it
 * renders: each must be one the clip carries. */
static nprfx_result check_clip_components(node_inst *ni, const nprfx_render_args *a)
{
    nprfx_ofx_host *h = ni->h;
    if (!h->profile->planes || !h->nplanes ||
        !internal_pint(&ni->pl->descriptor->props, kFnOfxImageEffectPropMultiPlanar, 0, 0))
        return NPRFX_OK;
    hprops in, out;
    internal_props_init(&in, K_PLAIN);
    internal_props_init(&out, K_PLAIN);
    internal_set_double((OfxPropertySetHandle)&in, kOfxPropTime, 0, a->time);
    OfxStatus st =
        internal_call(ni->pl, kFnOfxImageEffectActionGetClipComponents, ni->fx, &in, &out);
    nprfx_result r = NPRFX_OK;
    char key[NPRFX_OFX_NAME_MAX + 64], name[NPRFX_OFX_NAME_MAX];
    ofx_names_clip_name(ni->desc, ofx_names_main_input(ni->desc), name, sizeof name);
    snprintf(key, sizeof key, "%s%s", kFnOfxImageEffectActionGetClipComponentsPropString, name);
    int n = st == kOfxStatOK ? internal_pdim(&out, key) : 0;
    if (st != kOfxStatOK && st != kOfxStatReplyDefault)
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: getClipComponents failed (%d)",
                        ni->pl->p->pluginIdentifier, st);
    for (int i = 0; i < n && !r; i++) {
        const char *want = internal_pstr(&out, key, i, "");
        int have = !strcmp(want, kOfxImageComponentRGBA) || !strcmp(want, kOfxImageComponentAlpha);
        for (int p = 0; p < h->nplanes; p++)
            have |= !strcmp(want, h->planes[p]);
        if (!have)
            r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL,
                            "%s: getClipComponents asks %s for '%s', which it does not carry",
                            ni->pl->p->pluginIdentifier, name, want);
    }
    internal_props_free(&in);
    internal_props_free(&out);
    return r;
}

static nprfx_result hook_render(nprfx_ofx_host *h, const nprfx_render_args *a, void **slot,
                                int footage)
{
    node_inst *ni = *slot;
    nprfx_result r;
    int first = 0;
    if (!ni) {
        if ((r = inst_create(h, a, footage, &ni))) return r;
        ni->footage = footage;
        *slot = ni;
        first = 1;
    }
    const char *id = ni->pl->p->pluginIdentifier;
    ni->args = a;
    ni->frame_flip = a->frame.y0 + a->frame.y1 - 1;
    internal_messages_reset(ni);
    for (int k = 0; k < ni->desc->num_inputs; k++)
        ni->frames[k].nfetched = 0;
    if ((r = sync_params(ni, a, first)) || (first && (r = first_settings(ni, a))) ||
        (first && h->analyze && (r = press_analyze(ni, a))) || (r = check_clip_components(ni, a)) ||
        (r = query_regions(ni, a)))
        goto done;
    double s = internal_host_scale(a);
    if (s != 1.0 && !h->profile->multires) {
        r = nprfx_error(a->ctx, NPRFX_ERR_UNSUPPORTED, "%s: this host (%s) renders at scale 1 only",
                        id, h->profile->like);
        goto done;
    }
    hprops in;
    internal_props_init(&in, K_PLAIN);
    OfxPropertySetHandle ip = (OfxPropertySetHandle)&in;
    internal_set_double(ip, kOfxImageEffectPropRenderScale, 0, s);
    internal_set_double(ip, kOfxImageEffectPropRenderScale, 1, s);
    internal_set_int(ip, kOfxPropIsInteractive, 0, 0);
    if (!ni->began) {
        internal_set_double(ip, kOfxImageEffectPropFrameRange, 0, a->first_frame);
        internal_set_double(ip, kOfxImageEffectPropFrameRange, 1, a->last_frame);
        internal_set_double(ip, kOfxImageEffectPropFrameStep, 0, 1.0);
        OfxStatus st =
            internal_call(ni->pl, kOfxImageEffectActionBeginSequenceRender, ni->fx, &in, NULL);
        if (st != kOfxStatOK && st != kOfxStatReplyDefault) {
            internal_props_free(&in);
            char what[64];
            snprintf(what, sizeof what, "beginSequenceRender failed (OFX status %d)", st);
            r = internal_failure(ni, a->ctx, what);
            goto done;
        }
        ni->began = 1;
    }
    /* The output image covers the whole frame while the window may be one tile, so the adapter
     * meets bounds that differ from the render window. It has the profile's depth. */
    hdepth depth = h->profile->depth;
    size_t es = internal_depth_size(depth);
    OfxRectI ob = internal_ofx_rect(a->frame, ni->frame_flip);
    OfxRectI win = internal_ofx_rect(a->window, ni->frame_flip);
    int w = ob.x2 - ob.x1, hgt = ob.y2 - ob.y1;
    ni->out_bounds = ob;
    ni->out_row_bytes = w * ni->out_comps * (int)es;
    ni->out_pixels = calloc((size_t)w * (size_t)(hgt > 0 ? hgt : 1) * (size_t)ni->out_comps, es);
    if (!ni->out_pixels) {
        internal_props_free(&in);
        r = nprfx_error(a->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        goto done;
    }
    int wv[4] = {win.x1, win.y1, win.x2, win.y2};
    internal_set_double(ip, kOfxPropTime, 0, a->time);
    internal_set_string(ip, kOfxImageEffectPropFieldToRender, 0, kOfxImageFieldNone);
    internal_set_int_n(ip, kOfxImageEffectPropRenderWindow, 4, wv);
    internal_set_int(ip, kOfxImageEffectPropSequentialRenderStatus, 0, 1);
    internal_set_int(ip, kOfxImageEffectPropInteractiveRenderStatus, 0, 0);
    ni->images = 0;
    OfxStatus st = internal_call(ni->pl, kOfxImageEffectActionRender, ni->fx, &in, NULL);
    internal_props_free(&in);
    if (st != kOfxStatOK) {
        char what[64];
        snprintf(what, sizeof what, "render failed (OFX status %d)", st);
        r = internal_failure(ni, a->ctx, what);
        goto done;
    }
    if (ni->images) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: %d clip images not released by render", id,
                        ni->images);
        goto done;
    }
    if (first && (r = check_frames(ni, a))) goto done;
    int nout = a->output->channels;
    if (ni->out_comps == 1 && nout != 1) {
        r = nprfx_error(a->ctx, NPRFX_ERR_INTERNAL, "%s: Alpha output for %d channels", id, nout);
        goto done;
    }
    for (int y = a->window.y0; y < a->window.y1; y++)
        for (int x = a->window.x0; x < a->window.x1; x++) {
            size_t px = (size_t)(ni->frame_flip - y - ob.y1) * (size_t)w + (size_t)(x - ob.x1);
            unpack_pixel(ni, ni->out_pixels, px, nprfx_image_at(a->output, x, y), nout);
        }
done:
    free(ni->out_pixels);
    ni->out_pixels = NULL;
    ni->args = NULL;
    /* melt: the instance goes with its render; the next render makes another */
    if (h->profile->instance_per_frame) {
        internal_hook_release(h, a->node, ni);
        *slot = NULL;
    }
    return r;
}

void internal_hook_release(void *user, const nprfx_node_desc *node, void *instance)
{
    (void)node;
    nprfx_ofx_host *h = user;
    node_inst *ni = instance;
    if (!ni) return;
    if (ni->began) {
        hprops in;
        internal_props_init(&in, K_PLAIN);
        internal_set_int((OfxPropertySetHandle)&in, kOfxPropIsInteractive, 0, 0);
        (void)internal_call(ni->pl, kOfxImageEffectActionEndSequenceRender, ni->fx, &in, NULL);
        internal_props_free(&in);
    }
    (void)internal_call(ni->pl, kOfxActionDestroyInstance, ni->fx, NULL, NULL);
    pthread_mutex_lock(&h->lock);
    h->instances--;
    pthread_mutex_unlock(&h->lock);
    inst_free(ni);
}
