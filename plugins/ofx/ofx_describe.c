/* nprfx OpenFX adapter — the describe and describeInContext actions (declared in
 * ofx_describe.h): a node descriptor becomes the effect's properties, its clips (Source first,
 * Mask for maskable nodes in the General context) and its params (the node's, a channel selector
 * per input that has a choice, Mix and Invert Mask), all derived from the descriptor. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ofx_derive.h"
#include "ofx_describe.h"
#include "ofx_messages.h"
#include "ofx_names.h"
#include "ofx_suites.h"

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
    int main = ofx_names_main_input(d);
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

OfxStatus ofx_describe_unavailable(OfxImageEffectHandle fx, const char *who, const char *why)
{
    char text[1024];
    snprintf(text, sizeof text, "nprfx: %s is not available in this host: %s", who, why);
    ofx_post(fx, kOfxMessageLog, text);
    return kOfxStatErrMissingHostFeature;
}

OfxStatus ofx_describe_refuse(OfxImageEffectHandle fx, const char *who, const char *reads)
{
    char why[512];
    snprintf(why, sizeof why,
             "%s, and the host offers no temporal clip access "
             "(kOfxImageEffectPropTemporalClipAccess = 0)",
             reads);
    return ofx_describe_unavailable(fx, who, why);
}

void ofx_describe_labels(OfxPropertySetHandle p, const char *label)
{
    ofx_set_str(p, kOfxPropLabel, 0, label);
    ofx_set_str(p, kOfxPropShortLabel, 0, label);
    ofx_set_str(p, kOfxPropLongLabel, 0, label);
}

OfxStatus ofx_describe(const nprfx_node_desc *d, OfxImageEffectHandle fx)
{
    /* A node that only works with other frames is not offered where they cannot be had: a
     * missing plug-in with a logged reason beats one that silently shows the current frame. */
    if (filter_only(d) && !filter_derives(d))
        return ofx_describe_refuse(fx, d->id, "it reads its inputs at other frames");
    OfxPropertySetHandle p;
    if (ofx_g.fx->getPropertySet(fx, &p) != kOfxStatOK) return kOfxStatErrBadHandle;
    ofx_describe_labels(p, d->label);
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
    ofx_set_str(p, kOfxPropPluginDescription, 0, text ? text : help);
    free(text);
    /* Everything under "NPR" in the host's menus; a node's own group below it ("NPR/Filter"). */
    char grouping[NPRFX_OFX_NAME_MAX];
    if (!d->group || !d->group[0] || !strcmp(d->group, "NPR"))
        snprintf(grouping, sizeof grouping, "NPR");
    else if (snprintf(grouping, sizeof grouping, "NPR/%s", d->group) >= (int)sizeof grouping)
        grouping[sizeof grouping - 1] = 0;
    ofx_set_str(p, kOfxImageEffectPluginPropGrouping, 0, grouping);
    /* The node's version (as in OfxPlugin), the library's in the label. */
    ofx_set_int(p, kOfxPropVersion, 0, d->version_major);
    ofx_set_int(p, kOfxPropVersion, 1, d->version_minor);
    char vlabel[64];
    snprintf(vlabel, sizeof vlabel, "%d.%d (nprfx %s)", d->version_major, d->version_minor,
             NPRFX_VERSION_STRING);
    ofx_set_str(p, kOfxPropVersionLabel, 0, vlabel);
    int nctx = 0;
    if (!filter_only(d))
        ofx_set_str(p, kOfxImageEffectPropSupportedContexts, nctx++, kOfxImageEffectContextGeneral);
    if (filter_capable(d))
        ofx_set_str(p, kOfxImageEffectPropSupportedContexts, nctx++, kOfxImageEffectContextFilter);
    /* Pixels are scene-linear float32 throughout nprfx, and the clip preferences ask for float;
     * hosts that only have 8 or 16 bits (MLT) still get a plug-in, converting at the edges. */
    ofx_set_str(p, kOfxImageEffectPropSupportedPixelDepths, 0, kOfxBitDepthFloat);
    ofx_set_str(p, kOfxImageEffectPropSupportedPixelDepths, 1, kOfxBitDepthShort);
    ofx_set_str(p, kOfxImageEffectPropSupportedPixelDepths, 2, kOfxBitDepthByte);
    ofx_set_int(p, kOfxImageEffectPluginPropSingleInstance, 0, 0);
    /* A stateful node's cache is shared by the renders of its instance. */
    ofx_set_str(p, kOfxImageEffectPluginRenderThreadSafety, 0,
                (d->flags & NPRFX_NODE_STATEFUL) ? kOfxImageEffectRenderInstanceSafe
                                                 : kOfxImageEffectRenderFullySafe);
    /* The nodes split their work themselves through the multithread suite. */
    ofx_set_int(p, kOfxImageEffectPluginPropHostFrameThreading, 0, 0);
    ofx_set_int(p, kOfxImageEffectPropSupportsMultiResolution, 0, 1);
    ofx_set_int(p, kOfxImageEffectPropSupportsTiles, 0, 1);
    ofx_set_int(p, kOfxImageEffectPropTemporalClipAccess, 0,
                has_temporal_input(d) && ofx_g.temporal);
    ofx_set_int(p, kOfxImageEffectPropSupportsMultipleClipDepths, 0, 0);
    ofx_set_int(p, kOfxImageEffectPropSupportsMultipleClipPARs, 0, 0);
    ofx_set_int(p, kOfxImageEffectPluginPropFieldRenderTwiceAlways, 0, 0);
    /* Results never depend on the state cache, but in-order rendering makes it cost O(1)
     * frames per frame: "better sequential" (2) rather than "must" (1). */
    ofx_set_int(p, kOfxImageEffectInstancePropSequentialRender, 0,
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
    if (page) ofx_set_str(page, kOfxParamPropPageChild, (*nchildren)++, name);
}

/* A param the adapter adds beside the descriptor's (its name from ofx_names_extra_param, into
 * name): defined, labelled, explained, not animated; the caller sets its values. */
static OfxStatus define_extra(OfxParamSetHandle ps, const nprfx_node_desc *d, const char *type,
                              const char *want, const char *label, const char *hint, char *name,
                              size_t n, OfxPropertySetHandle *pp)
{
    ofx_names_extra_param(d, want, name, n);
    OfxStatus st = ofx_g.param->paramDefine(ps, type, name, pp);
    if (st != kOfxStatOK) return st;
    ofx_set_str(*pp, kOfxPropLabel, 0, label);
    ofx_set_int(*pp, kOfxParamPropAnimates, 0, 0);
    ofx_set_str(*pp, kOfxParamPropHint, 0, hint);
    return kOfxStatOK;
}

OfxStatus ofx_define_param(OfxParamSetHandle ps, const nprfx_param_desc *p, const char *name,
                           const char *label, const char *lead, const nprfx_value *def)
{
    static const char *const types[] = {kOfxParamTypeDouble,  kOfxParamTypeInteger,
                                        kOfxParamTypeBoolean, kOfxParamTypeChoice,
                                        kOfxParamTypeRGBA,    kOfxParamTypeString};
    if ((int)p->type < 0 || (int)p->type >= (int)(sizeof types / sizeof types[0]))
        return kOfxStatErrUnsupported;
    OfxPropertySetHandle pp;
    OfxStatus st = ofx_g.param->paramDefine(ps, types[p->type], name, &pp);
    if (st != kOfxStatOK) return st;
    ofx_set_str(pp, kOfxPropLabel, 0, label);
    ofx_set_str(pp, kOfxParamPropScriptName, 0, name);
    const double *dv = def ? def->v : p->def;
    const char *ds = def ? def->s : p->def_string;
    strbuf hint = {0};
    if (lead && lead[0]) {
        sb_add(&hint, lead);
        if (p->help) sb_add(&hint, "\n\n");
    }
    sb_add(&hint, p->help ? p->help : "");
    if (p->flags & (NPRFX_PARAM_PIXELS | NPRFX_PARAM_AREA))
        sb_add(&hint, p->flags & NPRFX_PARAM_PIXELS
                          ? "\n\nIn pixels at full resolution; proxy renders scale it."
                          : "\n\nIn pixels^2 at full resolution; proxy renders scale it.");
    switch (p->type) {
    case NPRFX_PARAM_DOUBLE:
        ofx_set_dbl(pp, kOfxParamPropDefault, 0, dv[0]);
        ofx_set_dbl(pp, kOfxParamPropMin, 0, p->hard_min);
        ofx_set_dbl(pp, kOfxParamPropMax, 0, p->hard_max);
        ofx_set_dbl(pp, kOfxParamPropDisplayMin, 0, p->soft_min);
        ofx_set_dbl(pp, kOfxParamPropDisplayMax, 0, p->soft_max);
        ofx_set_str(pp, kOfxParamPropDoubleType, 0, kOfxParamDoubleTypePlain);
        ofx_set_int(pp, kOfxParamPropDigits, 0, 4);
        ofx_set_dbl(pp, kOfxParamPropIncrement, 0,
                    p->soft_max > p->soft_min ? (p->soft_max - p->soft_min) / 100.0 : 0.01);
        break;
    case NPRFX_PARAM_INT:
        ofx_set_int(pp, kOfxParamPropDefault, 0, int_bound(dv[0]));
        ofx_set_int(pp, kOfxParamPropMin, 0, int_bound(p->hard_min));
        ofx_set_int(pp, kOfxParamPropMax, 0, int_bound(p->hard_max));
        ofx_set_int(pp, kOfxParamPropDisplayMin, 0, int_bound(p->soft_min));
        ofx_set_int(pp, kOfxParamPropDisplayMax, 0, int_bound(p->soft_max));
        break;
    case NPRFX_PARAM_BOOL:
        ofx_set_int(pp, kOfxParamPropDefault, 0, dv[0] != 0.0);
        ofx_set_int(pp, kOfxParamPropAnimates, 0, 0);
        break;
    case NPRFX_PARAM_CHOICE: {
        int n = 0;
        for (; p->choices && p->choices[n]; n++) {
            ofx_set_str(pp, kOfxParamPropChoiceOption, n, p->choices[n]);
            if (p->choice_help && p->choice_help[n]) {
                sb_add(&hint, n ? "\n" : "\n\n");
                sb_add(&hint, p->choices[n]);
                sb_add(&hint, ": ");
                sb_add(&hint, p->choice_help[n]);
            }
        }
        ofx_set_int(pp, kOfxParamPropDefault, 0, int_bound(dv[0]));
        ofx_set_int(pp, kOfxParamPropAnimates, 0, 0);
        break;
    }
    case NPRFX_PARAM_COLOR:
        for (int c = 0; c < 4; c++) {
            ofx_set_dbl(pp, kOfxParamPropDefault, c, dv[c]);
            ofx_set_dbl(pp, kOfxParamPropMin, c, p->hard_min);
            ofx_set_dbl(pp, kOfxParamPropMax, c, p->hard_max);
            ofx_set_dbl(pp, kOfxParamPropDisplayMin, c, p->soft_min);
            ofx_set_dbl(pp, kOfxParamPropDisplayMax, c, p->soft_max);
        }
        break;
    case NPRFX_PARAM_STRING:
        ofx_set_str(pp, kOfxParamPropDefault, 0, ds ? ds : "");
        ofx_set_str(pp, kOfxParamPropStringMode, 0,
                    (p->flags & NPRFX_PARAM_PATH) ? kOfxParamStringIsFilePath
                                                  : kOfxParamStringIsSingleLine);
        /* sequence patterns ("####") never exist as such */
        if (p->flags & NPRFX_PARAM_PATH) ofx_set_int(pp, kOfxParamPropStringFilePathExists, 0, 0);
        ofx_set_int(pp, kOfxParamPropAnimates, 0, 0);
        break;
    }
    ofx_set_str(pp, kOfxParamPropHint, 0, hint.s ? hint.s : "");
    free(hint.s);
    return kOfxStatOK;
}

OfxStatus ofx_define_analyze(OfxParamSetHandle ps, const nprfx_node_desc *d, const char *what,
                             char *name, size_t n)
{
    /* as trackers do: a button that measures, and what it measured kept in the project */
    OfxPropertySetHandle pp;
    ofx_names_extra_param(d, "analyze", name, n);
    OfxStatus st = ofx_g.param->paramDefine(ps, kOfxParamTypePushButton, name, &pp);
    if (st != kOfxStatOK) return st;
    ofx_set_str(pp, kOfxPropLabel, 0, "Analyze Shot");
    char hint[1024];
    snprintf(hint, sizeof hint,
             "Measure what %s now, once, reading every frame of the shot, and keep it with the "
             "project (as nprfx analyze does for the runner): renders then read only the frames "
             "they show. The pixels are the same as without it. Press it again after the plates "
             "change; a frame that differs from what was measured measures the shot again.",
             what);
    ofx_set_str(pp, kOfxParamPropHint, 0, hint);
    char button[NPRFX_OFX_NAME_MAX];
    snprintf(button, sizeof button, "%s", name);
    if ((st = define_extra(ps, d, kOfxParamTypeString, "analysis", "Analysis",
                           "What Analyze Shot measured, kept with the project. Empty: the first "
                           "render measures the shot.",
                           name, n, &pp)) != kOfxStatOK)
        return st;
    ofx_set_str(pp, kOfxParamPropDefault, 0, "");
    ofx_set_int(pp, kOfxParamPropSecret, 0, 1);
    snprintf(name, n, "%s", button); /* the button's, for the page */
    return kOfxStatOK;
}

static OfxStatus define_selector(OfxParamSetHandle ps, const nprfx_node_desc *d, int k,
                                 const char *clip, char *name, size_t name_size)
{
    const nprfx_input_desc *in = &d->inputs[k];
    int opts[NPRFX_OFX_CHAN_OPTIONS];
    int n = ofx_names_selector_options(in, opts);
    name[0] = 0;
    if (n < 2) return kOfxStatOK; /* nothing to choose */
    ofx_names_selector_name(d, k, name, name_size);
    OfxPropertySetHandle pp;
    OfxStatus st = ofx_g.param->paramDefine(ps, kOfxParamTypeChoice, name, &pp);
    if (st != kOfxStatOK) return st;
    char label[NPRFX_OFX_NAME_MAX + 16];
    snprintf(label, sizeof label, "%s Channels", in->label ? in->label : clip);
    ofx_set_str(pp, kOfxPropLabel, 0, label);
    for (int i = 0; i < n; i++)
        ofx_set_str(pp, kOfxParamPropChoiceOption, i, ofx_names_chan_options[opts[i]].label);
    ofx_set_int(pp, kOfxParamPropDefault, 0, ofx_names_selector_default(in));
    ofx_set_int(pp, kOfxParamPropAnimates, 0, 0);
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
    ofx_set_str(pp, kOfxParamPropHint, 0, hint.s ? hint.s : "");
    free(hint.s);
    return kOfxStatOK;
}

static OfxPropertySetHandle define_clip(OfxImageEffectHandle fx, const char *name)
{
    OfxPropertySetHandle p = NULL;
    if (ofx_g.fx->clipDefine(fx, name, &p) != kOfxStatOK) return NULL;
    return p;
}

OfxStatus ofx_describe_in_context(const nprfx_node_desc *d, OfxImageEffectHandle fx,
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
    int main = ofx_names_main_input(d);
    int temporal = (d->flags & NPRFX_NODE_TEMPORAL) && ofx_g.temporal;
    int maskable = general && ofx_names_maskable(d);

    OfxPropertySetHandle cp = define_clip(fx, NPRFX_OFX_OUTPUT_CLIP);
    if (!cp) return kOfxStatFailed;
    ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
    ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 1, kOfxImageComponentAlpha);
    ofx_set_int(cp, kOfxImageEffectPropSupportsTiles, 0, 1);

    /* Source first: hosts number inputs in definition order and treat the first as the main
     * one (Nuke's B pipe, Natron's first arrow); the rest follow the descriptor. */
    char clip[NPRFX_OFX_NAME_MAX];
    for (int j = -1; j < d->num_inputs; j++) {
        int k = j < 0 ? main : j;
        if (k < 0 || (j >= 0 && k == main) || (!general && k != main)) continue;
        const nprfx_input_desc *in = &d->inputs[k];
        ofx_names_clip_name(d, k, clip, sizeof clip);
        if (!(cp = define_clip(fx, clip))) return kOfxStatFailed;
        ofx_set_str(cp, kOfxPropLabel, 0,
                    derives && plan.count[k] ? NPRFX_OFX_SOURCE_CLIP
                    : in->label              ? in->label
                                             : clip);
        ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
        ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 1, kOfxImageComponentAlpha);
        /* As the input is (Source of a footage node that is not connected: the render says
         * that the footage is missing) */
        ofx_set_int(cp, kOfxImageClipPropOptional, 0, (in->flags & NPRFX_INPUT_OPTIONAL) != 0);
        ofx_set_int(cp, kOfxImageEffectPropTemporalClipAccess, 0,
                    temporal && ((in->flags & NPRFX_INPUT_TEMPORAL) || derives));
        /* Nodes read neighbourhoods and whole unaligned maps: ask for untiled inputs. */
        ofx_set_int(cp, kOfxImageEffectPropSupportsTiles, 0, 0);
    }
    if (maskable) {
        if (!(cp = define_clip(fx, NPRFX_OFX_MASK_CLIP))) return kOfxStatFailed;
        ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentAlpha);
        ofx_set_int(cp, kOfxImageClipPropOptional, 0, 1);
        ofx_set_int(cp, kOfxImageClipPropIsMask, 0, 1);
        ofx_set_int(cp, kOfxImageEffectPropSupportsTiles, 0, 1);
    }

    OfxParamSetHandle ps;
    if (ofx_g.fx->getParamSet(fx, &ps) != kOfxStatOK) return kOfxStatErrBadHandle;
    OfxPropertySetHandle page = NULL;
    if (ofx_g.param->paramDefine(ps, kOfxParamTypePage, "Controls", &page) == kOfxStatOK)
        ofx_set_str(page, kOfxPropLabel, 0, "Controls");
    else
        page = NULL; /* a host without pages lays params out itself */
    int nchildren = 0;
    OfxStatus st;
    for (int i = 0; i < d->num_params; i++) {
        const nprfx_param_desc *p = &d->params[i];
        if ((st = ofx_define_param(ps, p, p->name, p->label ? p->label : p->name, NULL, NULL)) !=
            kOfxStatOK)
            return st;
        add_page_child(page, &nchildren, d->params[i].name);
    }
    char name[NPRFX_OFX_NAME_MAX + 16];
    OfxPropertySetHandle pp;
    if (ofx_names_has_pixel_params(d)) {
        if ((st = define_extra(ps, d, kOfxParamTypeInteger, "designWidth", "Design Width",
                               "The image width in pixels the params in pixels were set for, as "
                               "a graph's design_width: on a wider or narrower input every length "
                               "in pixels (and area in pixels^2) follows the width, so the look "
                               "keeps its proportions on a 4K plate or a phone clip. 0: the "
                               "params are in the input's own pixels.",
                               name, sizeof name, &pp)) != kOfxStatOK)
            return st;
        ofx_set_int(pp, kOfxParamPropDefault, 0, 0);
        ofx_set_int(pp, kOfxParamPropMin, 0, 0);
        ofx_set_int(pp, kOfxParamPropMax, 0, NPRFX_DESIGN_WIDTH_MAX);
        ofx_set_int(pp, kOfxParamPropDisplayMin, 0, 0);
        ofx_set_int(pp, kOfxParamPropDisplayMax, 0, 4096);
        add_page_child(page, &nchildren, name);
    }
    if (nprfx_node_measures_shot(d)) {
        if ((st = ofx_define_analyze(ps, d,
                                     "this node measures over the whole shot (the tone "
                                     "range)",
                                     name, sizeof name)) != kOfxStatOK)
            return st;
        add_page_child(page, &nchildren, name);
    }
    for (int k = 0; k < d->num_inputs; k++) {
        if (!general && k != main) continue;
        /* Source read whole by the flow: a main input that is derived has no channels to pick */
        if (derives && plan.count[k]) continue;
        ofx_names_clip_name(d, k, clip, sizeof clip);
        if ((st = define_selector(ps, d, k, clip, name, sizeof name)) != kOfxStatOK) return st;
        if (name[0]) add_page_child(page, &nchildren, name);
    }
    if (maskable) {
        if ((st = define_extra(ps, d, kOfxParamTypeBoolean, "maskInvert", "Invert Mask",
                               "Use 1 - Mask instead of the Mask.", name, sizeof name, &pp)) !=
            kOfxStatOK)
            return st;
        ofx_set_int(pp, kOfxParamPropDefault, 0, 0);
        add_page_child(page, &nchildren, name);
        if ((st = define_extra(ps, d, kOfxParamTypeDouble, "mix", "Mix",
                               "out = Source + (result - Source) * mix * Mask, per channel the "
                               "Source has (Mask: 1 where no Mask clip is connected). 1 with no "
                               "Mask leaves the result untouched.",
                               name, sizeof name, &pp)) != kOfxStatOK)
            return st;
        ofx_set_dbl(pp, kOfxParamPropDefault, 0, 1.0);
        ofx_set_dbl(pp, kOfxParamPropMin, 0, 0.0);
        ofx_set_dbl(pp, kOfxParamPropMax, 0, 1.0);
        ofx_set_dbl(pp, kOfxParamPropDisplayMin, 0, 0.0);
        ofx_set_dbl(pp, kOfxParamPropDisplayMax, 0, 1.0);
        add_page_child(page, &nchildren, name);
    }
    return kOfxStatOK;
}
