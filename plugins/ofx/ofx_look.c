/* nprfx OpenFX adapter — the look plug-ins' table and what the host is told before an instance
 * exists (declared in ofx_look.h). */
#define _DEFAULT_SOURCE /* scandir, alphasort */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/aov.h"
#include "ofx_describe.h"
#include "ofx_look.h"
#include "ofx_messages.h"
#include "ofx_suites.h"

static ofx_look *looks;
static int nlooks;

const ofx_look *ofx_look_at(int i)
{
    return i >= 0 && i < nlooks ? &looks[i] : NULL;
}

static char *dup_text(const char *s)
{
    if (!s) return NULL;
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

static int add_clip(ofx_look *lk, const char *read, int node, int aov, int main)
{
    if (lk->nclips >= LOOK_MAX_CLIPS) return 0;
    look_clip *c = &lk->clips[lk->nclips++];
    ofx_names_look_clip(read, main, aov >= 0 ? nprfx_aov_name(aov) : NULL, c->name, sizeof c->name);
    c->node = node;
    c->aov = aov;
    c->main = main;
    return 1;
}

/* What of graph g makes a look: its clips, knobs, outputs; 0 with a reason when it is none. */
static int describe_graph(nprfx_graph *g, ofx_look *lk, char *why, size_t n)
{
    int nsrc = nprfx_graph_source_count(g), main = -1;
    for (int i = 0; i < nsrc; i++) {
        nprfx_graph_source_info s = {sizeof s};
        if (nprfx_graph_source(g, i, &s)) continue;
        if (s.raw) {
            snprintf(why, n,
                     "read node '%s' is read by channel names ('%s'), which only the renderer's "
                     "own files have: name the AOV instead (docs/graphs.md)",
                     s.name, s.raw);
            return 0;
        }
        int is_main = s.sequence && main < 0;
        if (is_main) main = s.node;
        if (!s.sequence) {
            add_clip(lk, s.name, s.node, -1, 0);
            continue;
        }
        for (int aov = 0; aov < NPRFX_AOV_COUNT; aov++)
            if ((s.aovs & (1u << aov)) && aov != NPRFX_AOV_COVERAGE)
                add_clip(lk, s.name, s.node, aov, is_main);
    }
    if (main < 0) {
        snprintf(why, n, "it reads no frame sequence (a look's Source is the render's plates)");
        return 0;
    }
    lk->filter = lk->nclips == 1;
    for (int i = 0; i < lk->nclips; i++)
        if (lk->clips[i].main && lk->clips[i].aov == NPRFX_AOV_BEAUTY) lk->source = i;
    int count = nprfx_graph_node_count(g);
    for (int i = 0; i < count; i++) {
        nprfx_graph_node_info ni = {sizeof ni};
        if (nprfx_graph_node(g, i, &ni)) continue;
        if (ni.kind == NPRFX_GRAPH_NODE && ni.desc &&
            (ni.desc->flags & (NPRFX_NODE_TEMPORAL | NPRFX_NODE_STATEFUL)))
            lk->temporal = 1;
        if (ni.kind == NPRFX_GRAPH_WRITE && ni.ninputs > 0 && ni.inputs[0].src >= 0) {
            char **o = realloc(lk->outputs, (size_t)(lk->noutputs + 1) * sizeof *o);
            char **l =
                o ? realloc(lk->output_labels, (size_t)(lk->noutputs + 1) * sizeof *l) : NULL;
            if (o) lk->outputs = o;
            if (l) lk->output_labels = l;
            if (!o || !l) return 0;
            lk->outputs[lk->noutputs] = dup_text(ni.inputs[0].text);
            lk->output_labels[lk->noutputs] = dup_text(ni.name);
            lk->noutputs++;
        }
    }
    if (!lk->noutputs) {
        snprintf(why, n, "it has no write node (the image a look makes is what its write writes)");
        return 0;
    }
    lk->measures = nprfx_graph_measuring_nodes(g);
    lk->design_width = nprfx_graph_design_width(g);
    lk->comment = dup_text(nprfx_graph_comment(g));
    int nk = nprfx_graph_knob_count(g);
    lk->knobs = calloc((size_t)(nk > 0 ? nk : 1), sizeof *lk->knobs);
    if (!lk->knobs) return 0;
    for (int i = 0; i < nk; i++) {
        nprfx_graph_knob_info k = {sizeof k};
        if (nprfx_graph_knob(g, i, &k)) continue;
        look_knob *o = &lk->knobs[lk->nknobs++];
        o->name = dup_text(k.name);
        ofx_names_look_knob(k.name, o->param, sizeof o->param);
        o->help = dup_text(k.help);
        o->p = k.param;
        o->def = *k.value;
        o->def_string = dup_text(k.value->s);
        o->def.s = o->def_string;
        /* "ink.width" reads "ink width"; the param's own label when the node is the look's
         * only one of its kind would lose which node it is */
        o->label = dup_text(k.name);
        for (char *c = o->label; c && *c; c++)
            if (*c == '.' || *c == '_') *c = ' ';
    }
    return 1;
}

static void look_free(ofx_look *lk)
{
    free(lk->comment);
    for (int i = 0; i < lk->nknobs; i++) {
        free(lk->knobs[i].name);
        free(lk->knobs[i].label);
        free(lk->knobs[i].help);
        free(lk->knobs[i].def_string);
    }
    free(lk->knobs);
    for (int i = 0; i < lk->noutputs; i++) {
        free(lk->outputs[i]);
        free(lk->output_labels[i]);
    }
    free(lk->outputs);
    free(lk->output_labels);
    memset(lk, 0, sizeof *lk);
}

static int json_file(const struct dirent *e)
{
    size_t n = strlen(e->d_name);
    return n > 5 && !strcmp(e->d_name + n - 5, ".json") && e->d_name[0] != '.';
}

static void scan_folder(const char *dir, int max)
{
    struct dirent **list = NULL;
    int n = scandir(dir, &list, json_file, alphasort);
    for (int i = 0; i < n; i++) {
        char stem[256], id[NPRFX_OFX_NAME_MAX];
        snprintf(stem, sizeof stem, "%.*s", (int)(strlen(list[i]->d_name) - 5), list[i]->d_name);
        ofx_names_look_id(stem, id, sizeof id);
        int seen = 0;
        for (int k = 0; k < nlooks; k++)
            seen |= !strcmp(looks[k].id, id);
        if (seen || nlooks >= max) {
            free(list[i]);
            continue;
        }
        ofx_look lk;
        memset(&lk, 0, sizeof lk);
        snprintf(lk.path, sizeof lk.path, "%s/%s", dir, list[i]->d_name);
        snprintf(lk.id, sizeof lk.id, "%s", id);
        /* "cross_hatching" -> "Cross hatching" */
        snprintf(lk.label, sizeof lk.label, "%.100s", stem);
        for (char *c = lk.label; *c; c++)
            if (*c == '_' || *c == '-') *c = ' ';
        if (lk.label[0] >= 'a' && lk.label[0] <= 'z') lk.label[0] = (char)(lk.label[0] - 32);
        nprfx_context *ctx = NULL;
        nprfx_graph *g = NULL;
        char why[1024] = "";
        nprfx_graph_options opt;
        memset(&opt, 0, sizeof opt);
        opt.size = sizeof opt;
        int ok = nprfx_context_create(NULL, &ctx) == NPRFX_OK &&
                 nprfx_graph_load(ctx, lk.path, &opt, &g) == NPRFX_OK;
        if (!ok && ctx) nprfx_context_last_error(ctx, why, sizeof why);
        if (ok) ok = describe_graph(g, &lk, why, sizeof why);
        if (ok) {
            ofx_look *grown = realloc(looks, (size_t)(nlooks + 1) * sizeof *grown);
            if (grown) {
                looks = grown;
                looks[nlooks++] = lk;
            } else {
                look_free(&lk);
            }
        } else {
            fprintf(stderr, "nprfx.ofx: %s is no look: %s\n", lk.path, why[0] ? why : "?");
            look_free(&lk);
        }
        nprfx_graph_free(g);
        nprfx_context_destroy(ctx);
        free(list[i]);
    }
    free(list);
}

int ofx_looks_discover(int max)
{
    const char *env = getenv("NPRFX_LOOK_PATH");
    for (const char *p = env; p && *p;) {
        const char *e = strchr(p, ':');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        char dir[4096];
        if (len > 0 && len < sizeof dir) {
            memcpy(dir, p, len);
            dir[len] = 0;
            scan_folder(dir, max);
        }
        p = e ? e + 1 : NULL;
    }
    ofx_find_data_dir();
    if (ofx_g.data_dir[0]) {
        char dir[sizeof ofx_g.data_dir + 8];
        snprintf(dir, sizeof dir, "%s/looks", ofx_g.data_dir);
        scan_folder(dir, max);
    }
    return nlooks;
}

/* ---- describe -------------------------------------------------------------------------------- */

static OfxStatus look_describe(const ofx_look *lk, OfxImageEffectHandle fx)
{
    if (lk->temporal && !ofx_g.temporal) {
        char why[512];
        snprintf(why, sizeof why,
                 "nprfx: the look %s is not available in this host: its nodes read other frames "
                 "of the plates, and the host offers no temporal clip access "
                 "(kOfxImageEffectPropTemporalClipAccess = 0)",
                 lk->label);
        ofx_post(fx, kOfxMessageLog, why);
        return kOfxStatErrMissingHostFeature;
    }
    OfxPropertySetHandle p;
    if (ofx_g.fx->getPropertySet(fx, &p) != kOfxStatOK) return kOfxStatErrBadHandle;
    ofx_set_str(p, kOfxPropLabel, 0, lk->label);
    ofx_set_str(p, kOfxPropShortLabel, 0, lk->label);
    ofx_set_str(p, kOfxPropLongLabel, 0, lk->label);
    static const char how[] =
        "\n\nA look: the graph file %s evaluated as `nprfx run` evaluates it, on the clips: "
        "Source is the render's picture (its alpha the coverage), each other clip one AOV in "
        "nprfx's conventions (depth as camera z, motion in pixels with y down, object ids as "
        "numbers). A clip left unconnected is as a plate without that AOV.";
    const char *comment = lk->comment ? lk->comment : "";
    size_t len = strlen(comment) + sizeof how + strlen(lk->path);
    char *text = malloc(len);
    if (text) {
        snprintf(text, len, "%s", comment);
        size_t k = strlen(text);
        snprintf(text + k, len - k, how, lk->path);
    }
    ofx_set_str(p, kOfxPropPluginDescription, 0, text ? text : lk->label);
    free(text);
    ofx_set_str(p, kOfxImageEffectPluginPropGrouping, 0, "NPR/Looks");
    ofx_set_int(p, kOfxPropVersion, 0, 1);
    ofx_set_int(p, kOfxPropVersion, 1, 0);
    int nctx = 0;
    ofx_set_str(p, kOfxImageEffectPropSupportedContexts, nctx++, kOfxImageEffectContextGeneral);
    if (lk->filter)
        ofx_set_str(p, kOfxImageEffectPropSupportedContexts, nctx++, kOfxImageEffectContextFilter);
    ofx_set_str(p, kOfxImageEffectPropSupportedPixelDepths, 0, kOfxBitDepthFloat);
    ofx_set_str(p, kOfxImageEffectPropSupportedPixelDepths, 1, kOfxBitDepthShort);
    ofx_set_str(p, kOfxImageEffectPropSupportedPixelDepths, 2, kOfxBitDepthByte);
    ofx_set_int(p, kOfxImageEffectPluginPropSingleInstance, 0, 0);
    /* one graph per instance, evaluated whole frames at a time under the instance's lock */
    ofx_set_str(p, kOfxImageEffectPluginRenderThreadSafety, 0, kOfxImageEffectRenderInstanceSafe);
    ofx_set_int(p, kOfxImageEffectPluginPropHostFrameThreading, 0, 0);
    ofx_set_int(p, kOfxImageEffectPropSupportsMultiResolution, 0, 0);
    ofx_set_int(p, kOfxImageEffectPropSupportsTiles, 0, 0);
    ofx_set_int(p, kOfxImageEffectPropTemporalClipAccess, 0, lk->temporal && ofx_g.temporal);
    ofx_set_int(p, kOfxImageEffectPropSupportsMultipleClipDepths, 0, 0);
    ofx_set_int(p, kOfxImageEffectPropSupportsMultipleClipPARs, 0, 0);
    ofx_set_int(p, kOfxImageEffectPluginPropFieldRenderTwiceAlways, 0, 0);
    ofx_set_int(p, kOfxImageEffectInstancePropSequentialRender, 0, lk->temporal ? 2 : 0);
    /* a multi-plane host gives the render's layers on Source: no clip per AOV */
    if (ofx_g.multiplanar) {
        ofx_set_int(p, kFnOfxImageEffectPropMultiPlanar, 0, 1);
        ofx_set_int(p, kFnOfxImageEffectPropPassThroughComponents, 0, 0);
    }
    return kOfxStatOK;
}

static const char *aov_help(int aov)
{
    switch (aov) {
    case NPRFX_AOV_BEAUTY:
        return "the render's picture, scene-linear RGBA (alpha: coverage)";
    case NPRFX_AOV_ALBEDO:
        return "diffuse colour (albedo), RGB";
    case NPRFX_AOV_DIFFUSE_LIGHT:
        return "diffuse lighting without the albedo, RGB";
    case NPRFX_AOV_DEPTH:
        return "camera depth z in R (or alpha of an Alpha clip)";
    case NPRFX_AOV_NORMAL:
        return "surface normal, RGB = XYZ";
    case NPRFX_AOV_POSITION:
        return "position, RGB = XYZ";
    case NPRFX_AOV_REST:
        return "rest (reference) position, RGB = XYZ";
    case NPRFX_AOV_UV:
        return "texture coordinates, RG = UV";
    case NPRFX_AOV_ID:
        return "object id in R: one number per object, 0 none";
    case NPRFX_AOV_MOTION_PREV:
        return "motion to the previous frame in RG: pixels at full resolution, x right, y down";
    case NPRFX_AOV_MOTION_NEXT:
        return "motion to the next frame in RG: pixels at full resolution, x right, y down";
    default:
        return "";
    }
}

static OfxStatus look_describe_in_context(const ofx_look *lk, OfxImageEffectHandle fx,
                                          OfxPropertySetHandle in_args)
{
    char *context = NULL;
    if (ofx_g.prop->propGetString(in_args, kOfxImageEffectPropContext, 0, &context) != kOfxStatOK ||
        !context)
        return kOfxStatErrValue;
    int general = !strcmp(context, kOfxImageEffectContextGeneral);
    if (!general && !(lk->filter && !strcmp(context, kOfxImageEffectContextFilter)))
        return kOfxStatErrUnsupported;
    OfxPropertySetHandle cp = NULL;
    if (ofx_g.fx->clipDefine(fx, NPRFX_OFX_OUTPUT_CLIP, &cp) != kOfxStatOK) return kOfxStatFailed;
    ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
    for (int i = 0; i < lk->nclips; i++) {
        const look_clip *c = &lk->clips[i];
        if (ofx_g.multiplanar && c->main && c->aov != NPRFX_AOV_BEAUTY) continue;
        if (ofx_g.fx->clipDefine(fx, c->name, &cp) != kOfxStatOK) return kOfxStatFailed;
        ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
        ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 1, kOfxImageComponentAlpha);
        ofx_set_int(cp, kOfxImageClipPropOptional, 0, strcmp(c->name, NPRFX_OFX_SOURCE_CLIP) != 0);
        ofx_set_int(cp, kOfxImageEffectPropTemporalClipAccess, 0, lk->temporal && ofx_g.temporal);
        ofx_set_int(cp, kOfxImageEffectPropSupportsTiles, 0, 0);
        ofx_set_int(cp, kOfxImageClipPropIsMask, 0, 0);
        char hint[512];
        if (c->aov >= 0)
            snprintf(hint, sizeof hint, "%s%s%s", c->main ? "" : c->name, c->main ? "" : ": ",
                     aov_help(c->aov));
        else
            snprintf(hint, sizeof hint,
                     "the image the look's read node reads from one file (a "
                     "map): connect a Read of it");
        ofx_set_str(cp, kOfxParamPropHint, 0, hint);
        if (!general) break; /* Filter: Source alone */
        if (c->main && ofx_g.multiplanar)
            ofx_set_str(cp, kOfxParamPropHint, 0,
                        "the render: every layer of a multilayer EXR; the look finds each AOV "
                        "it reads among them by the renderer's names (Renderer)");
    }
    OfxParamSetHandle ps;
    if (ofx_g.fx->getParamSet(fx, &ps) != kOfxStatOK) return kOfxStatErrBadHandle;
    OfxStatus st;
    for (int i = 0; i < lk->nknobs; i++) {
        const look_knob *k = &lk->knobs[i];
        if ((st = ofx_define_param(ps, k->p, k->param, k->label, k->help, &k->def)) != kOfxStatOK)
            return st;
    }
    OfxPropertySetHandle pp;
    if (lk->noutputs > 1) {
        if ((st = ofx_g.param->paramDefine(ps, kOfxParamTypeChoice, "output", &pp)) != kOfxStatOK)
            return st;
        ofx_set_str(pp, kOfxPropLabel, 0, "Output");
        ofx_set_str(pp, kOfxParamPropHint, 0, "Which of the graph's write nodes' images to show");
        for (int i = 0; i < lk->noutputs; i++)
            ofx_set_str(pp, kOfxParamPropChoiceOption, i, lk->output_labels[i]);
        ofx_set_int(pp, kOfxParamPropDefault, 0, 0);
        ofx_set_int(pp, kOfxParamPropAnimates, 0, 0);
    }
    if (ofx_g.multiplanar) {
        if ((st = ofx_g.param->paramDefine(ps, kOfxParamTypeChoice, "renderer", &pp)) != kOfxStatOK)
            return st;
        ofx_set_str(pp, kOfxPropLabel, 0, "Renderer");
        ofx_set_str(pp, kOfxParamPropHint, 0,
                    "Whose names the look finds its AOVs under among Source's layers (nprfx info "
                    "--aovs FILE shows them for a file): auto tells from the layer names.");
        ofx_set_str(pp, kOfxParamPropChoiceOption, 0, "auto");
        for (int i = 0; i < NPRFX_PROFILE_COUNT; i++)
            ofx_set_str(pp, kOfxParamPropChoiceOption, i + 1, nprfx_aov_profile_name(i));
        ofx_set_int(pp, kOfxParamPropDefault, 0, 0);
        ofx_set_int(pp, kOfxParamPropAnimates, 0, 0);
    }
    if ((st = ofx_g.param->paramDefine(ps, kOfxParamTypeDouble, "designWidth", &pp)) != kOfxStatOK)
        return st;
    ofx_set_str(pp, kOfxPropLabel, 0, "Design width");
    ofx_set_str(pp, kOfxParamPropHint, 0,
                "The plate width in pixels the look's sizes were set for: on a plate W pixels "
                "wide every size in pixels is multiplied by W / this (0: sizes in the plate's "
                "own pixels). Proxy renders follow from it.");
    ofx_set_dbl(pp, kOfxParamPropDefault, 0, lk->design_width);
    ofx_set_dbl(pp, kOfxParamPropMin, 0, 0);
    ofx_set_dbl(pp, kOfxParamPropMax, 0, 1000000);
    ofx_set_dbl(pp, kOfxParamPropDisplayMin, 0, 0);
    ofx_set_dbl(pp, kOfxParamPropDisplayMax, 0, 4096);
    ofx_set_int(pp, kOfxParamPropAnimates, 0, 0);
    return kOfxStatOK;
}

OfxStatus ofx_look_main(int i, const char *action, const void *handle, OfxPropertySetHandle in_args,
                        OfxPropertySetHandle out_args)
{
    const ofx_look *lk = ofx_look_at(i);
    OfxImageEffectHandle fx = (OfxImageEffectHandle)handle;
    if (!lk || !action) return kOfxStatErrUnknown;
    if (!strcmp(action, kOfxActionLoad)) return ofx_suites_load();
    if (!strcmp(action, kOfxActionUnload)) return kOfxStatOK;
    if (!ofx_g.prop || !ofx_g.fx || !ofx_g.param) return kOfxStatErrFatal;
    if (!strcmp(action, kOfxActionDescribe)) return look_describe(lk, fx);
    if (!strcmp(action, kOfxImageEffectActionDescribeInContext))
        return look_describe_in_context(lk, fx, in_args);
    if (!strcmp(action, kOfxActionCreateInstance)) return ofx_look_create(lk, fx);
    return ofx_look_instance_action(lk, action, fx, in_args, out_args);
}
