/* nprfx OpenFX adapter — the look plug-ins' table and what the host is told before an instance
 * exists (declared in ofx_look.h). */
#define _DEFAULT_SOURCE /* scandir, alphasort */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/aov.h"
#include "ofx_describe.h"
#include "ofx_look.h"
#include "ofx_suites.h"

static ofx_look **looks;
static int nlooks;

const ofx_look *ofx_look_at(int i)
{
    return i >= 0 && i < nlooks ? looks[i] : NULL;
}

static int json_file(const struct dirent *e)
{
    size_t n = strlen(e->d_name);
    return n > 5 && !strcmp(e->d_name + n - 5, ".json") && e->d_name[0] != '.';
}

/* FNV-1a of the file's bytes, folded to 16 bits (a version number hosts keep as an int). */
static unsigned file_version(const char *path)
{
    FILE *f = fopen(path, "rb");
    uint32_t h = 2166136261u;
    for (int c; f && (c = fgetc(f)) != EOF;)
        h = (h ^ (uint32_t)c) * 16777619u;
    if (f) fclose(f);
    return (unsigned)((h >> 16) ^ (h & 0xffffu));
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
            seen |= !strcmp(looks[k]->d.id, id);
        ofx_look *lk = seen || nlooks >= max ? NULL : calloc(1, sizeof *lk);
        ofx_look **grown = lk ? realloc(looks, (size_t)(nlooks + 1) * sizeof *grown) : NULL;
        if (grown) looks = grown;
        if (!grown) {
            free(lk);
            free(list[i]);
            continue;
        }
        snprintf(lk->path, sizeof lk->path, "%s/%s", dir, list[i]->d_name);
        nprfx_context *ctx = NULL;
        nprfx_graph *g = NULL;
        char why[1024] = "";
        nprfx_graph_options opt;
        memset(&opt, 0, sizeof opt);
        opt.size = sizeof opt;
        int ok = nprfx_context_create(NULL, &ctx) == NPRFX_OK &&
                 nprfx_graph_load(ctx, lk->path, &opt, &g) == NPRFX_OK;
        if (!ok && ctx) nprfx_context_last_error(ctx, why, sizeof why);
        if (ok) ok = look_desc_build(g, stem, &lk->d, why, sizeof why) == NPRFX_OK;
        if (ok) lk->version = file_version(lk->path);
        if (ok) {
            looks[nlooks++] = lk;
        } else {
            fprintf(stderr, "nprfx.ofx: %s is no look: %s\n", lk->path, why[0] ? why : "?");
            look_desc_free(&lk->d);
            free(lk);
        }
        nprfx_graph_free(g);
        nprfx_context_destroy(ctx);
        free(list[i]);
    }
    free(list);
}

/* The table lives as long as the module: freed when the host unloads the bundle. */
#if defined(__GNUC__)
__attribute__((destructor))
#endif
static void
looks_free(void)
{
    for (int i = 0; i < nlooks; i++) {
        look_desc_free(&looks[i]->d);
        free(looks[i]);
    }
    free(looks);
    looks = NULL;
    nlooks = 0;
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
    const look_desc *d = &lk->d;
    if (d->temporal && !ofx_g.temporal) {
        char who[NPRFX_OFX_NAME_MAX + 16];
        snprintf(who, sizeof who, "the look %s", d->label);
        return ofx_describe_refuse(fx, who, "its nodes read other frames of the plates");
    }
    /* Integer images clip at 0 and 1: depth, positions, normals, ids and motion would arrive
     * as other numbers, and the look be wrong without a word. */
    for (int k = 0; k < d->desc.num_inputs && !ofx_g.float_images; k++) {
        int aov = d->aov[k];
        if (aov < 0 || aov == NPRFX_AOV_BEAUTY || aov == NPRFX_AOV_ALBEDO ||
            aov == NPRFX_AOV_DIFFUSE_LIGHT || aov == NPRFX_AOV_COVERAGE)
            continue;
        char who[NPRFX_OFX_NAME_MAX + 16], why[256];
        snprintf(who, sizeof who, "the look %s", d->label);
        snprintf(why, sizeof why,
                 "its clip %s carries %s, numbers outside 0-1 that this host's 8- and 16-bit "
                 "images cannot hold (a host with float images can)",
                 d->clip[k], nprfx_aov_name(aov));
        return ofx_describe_unavailable(fx, who, why);
    }
    OfxPropertySetHandle p;
    if (ofx_g.fx->getPropertySet(fx, &p) != kOfxStatOK) return kOfxStatErrBadHandle;
    ofx_describe_labels(p, d->label);
    static const char how[] =
        "\n\nA look: the graph file %s evaluated as `nprfx run` evaluates it, on the clips: "
        "Source is the render's picture (its alpha the coverage), each other clip one AOV in "
        "nprfx's conventions (depth as camera z, motion in pixels with y down, object ids as "
        "numbers). A clip left unconnected is as a plate without that AOV.";
    const char *comment = d->comment ? d->comment : "";
    size_t len = strlen(comment) + sizeof how + strlen(lk->path);
    char *text = malloc(len);
    if (text) {
        snprintf(text, len, "%s", comment);
        size_t k = strlen(text);
        snprintf(text + k, len - k, how, lk->path);
    }
    ofx_set_str(p, kOfxPropPluginDescription, 0, text ? text : d->label);
    free(text);
    ofx_set_str(p, kOfxImageEffectPluginPropGrouping, 0, "NPR/Looks");
    ofx_set_int(p, kOfxPropVersion, 0, 1);
    ofx_set_int(p, kOfxPropVersion, 1, (int)lk->version);
    char label[32];
    snprintf(label, sizeof label, "1.%u", lk->version);
    ofx_set_str(p, kOfxPropVersionLabel, 0, label);
    int nctx = 0;
    ofx_set_str(p, kOfxImageEffectPropSupportedContexts, nctx++, kOfxImageEffectContextGeneral);
    if (ofx_look_filter(lk, ofx_g.multiplanar))
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
    ofx_set_int(p, kOfxImageEffectPropTemporalClipAccess, 0, d->temporal && ofx_g.temporal);
    ofx_set_int(p, kOfxImageEffectPropSupportsMultipleClipDepths, 0, 0);
    ofx_set_int(p, kOfxImageEffectPropSupportsMultipleClipPARs, 0, 0);
    ofx_set_int(p, kOfxImageEffectPluginPropFieldRenderTwiceAlways, 0, 0);
    ofx_set_int(p, kOfxImageEffectInstancePropSequentialRender, 0, d->temporal ? 2 : 0);
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

/* A param of the look's own (not a knob): defined with its label and hint, not animated (a
 * button has no value to animate). */
static OfxStatus own_param(OfxParamSetHandle ps, const char *type, const char *name,
                           const char *label, const char *hint, OfxPropertySetHandle *pp)
{
    OfxStatus st = ofx_g.param->paramDefine(ps, type, name, pp);
    if (st != kOfxStatOK) return st;
    ofx_set_str(*pp, kOfxPropLabel, 0, label);
    ofx_set_str(*pp, kOfxParamPropHint, 0, hint);
    if (strcmp(type, kOfxParamTypePushButton)) ofx_set_int(*pp, kOfxParamPropAnimates, 0, 0);
    return kOfxStatOK;
}

static OfxStatus look_describe_in_context(const ofx_look *lk, OfxImageEffectHandle fx,
                                          OfxPropertySetHandle in_args)
{
    char *context = NULL;
    if (ofx_g.prop->propGetString(in_args, kOfxImageEffectPropContext, 0, &context) != kOfxStatOK ||
        !context)
        return kOfxStatErrValue;
    const look_desc *d = &lk->d;
    int general = !strcmp(context, kOfxImageEffectContextGeneral);
    if (!general &&
        !(ofx_look_filter(lk, ofx_g.multiplanar) && !strcmp(context, kOfxImageEffectContextFilter)))
        return kOfxStatErrUnsupported;
    OfxPropertySetHandle cp = NULL;
    if (ofx_g.fx->clipDefine(fx, NPRFX_OFX_OUTPUT_CLIP, &cp) != kOfxStatOK) return kOfxStatFailed;
    ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
    for (int i = 0; i < d->desc.num_inputs; i++) {
        if (!look_desc_has_clip(d, i, ofx_g.multiplanar)) continue;
        if (ofx_g.fx->clipDefine(fx, d->clip[i], &cp) != kOfxStatOK) return kOfxStatFailed;
        ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 0, kOfxImageComponentRGBA);
        ofx_set_str(cp, kOfxImageEffectPropSupportedComponents, 1, kOfxImageComponentAlpha);
        ofx_set_int(cp, kOfxImageClipPropOptional, 0, i != d->source);
        ofx_set_int(cp, kOfxImageEffectPropTemporalClipAccess, 0, d->temporal && ofx_g.temporal);
        ofx_set_int(cp, kOfxImageEffectPropSupportsTiles, 0, 0);
        ofx_set_int(cp, kOfxImageClipPropIsMask, 0, 0);
        char hint[512];
        if (d->aov[i] >= 0)
            snprintf(hint, sizeof hint, "%s%s%s", d->main[i] ? "" : d->clip[i],
                     d->main[i] ? "" : ": ", aov_help(d->aov[i]));
        else
            snprintf(hint, sizeof hint,
                     "the image the look's read node reads from one file (a "
                     "map): connect a Read of it");
        ofx_set_str(cp, kOfxParamPropHint, 0, hint);
        if (!general) break; /* Filter: Source alone */
        if (i == d->source && ofx_g.multiplanar)
            ofx_set_str(cp, kOfxParamPropHint, 0,
                        "the render: every layer of a multilayer EXR; the look finds each AOV "
                        "it reads among them by the renderer's names (Renderer)");
    }
    OfxParamSetHandle ps;
    if (ofx_g.fx->getParamSet(fx, &ps) != kOfxStatOK) return kOfxStatErrBadHandle;
    OfxStatus st;
    for (int i = 0; i < d->desc.num_params; i++) {
        const nprfx_param_desc *p = &d->params[i];
        if ((st = ofx_define_param(ps, p, p->name, p->label, d->knob_help[i], NULL)) != kOfxStatOK)
            return st;
    }
    OfxPropertySetHandle pp;
    if (ofx_g.multiplanar) {
        /* which layer feeds each AOV: found on request, shown, and the user's to change */
        if ((st = own_param(ps, kOfxParamTypePushButton, LOOK_PARAM_FIND_LAYERS, "Find AOV Layers",
                            "List Source's layers in the layer menus and fill AOV Layers with the "
                            "layers the look reads each AOV from, as it finds them now, to check "
                            "them or change one.",
                            &pp)) != kOfxStatOK)
            return st;
        if ((st = own_param(ps, kOfxParamTypeString, LOOK_PARAM_AOV_LAYERS, "AOV Layers",
                            "One line per AOV the look reads from another layer than it would "
                            "find: AOV = CHANNELS, e.g. depth = ViewLayer.Depth.Z or normal = "
                            "N.X,N.Y,N.Z (AOVs: beauty, albedo, diffuse_light, depth, normal, "
                            "position, rest, uv, id, coverage). Empty: each AOV by the renderer's "
                            "names (Renderer). Motion vectors follow the renderer's convention.",
                            &pp)) != kOfxStatOK)
            return st;
        ofx_set_str(pp, kOfxParamPropStringMode, 0, kOfxParamStringIsMultiLine);
        ofx_set_str(pp, kOfxParamPropDefault, 0, "");
        for (int k = 0; k < d->desc.num_inputs; k++) {
            int aov = look_desc_layer_aov(d, k);
            if (aov < 0) continue;
            char name[64], label[64], hint[300];
            look_desc_layer_name(aov, name, sizeof name);
            look_desc_layer_label(aov, label, sizeof label);
            snprintf(hint, sizeof hint,
                     "The layer of Source the look reads %s from: auto finds it by the "
                     "renderer's names; Find AOV Layers lists Source's layers here and shows the "
                     "one in use. A choice is a line of AOV Layers.",
                     nprfx_aov_name(aov));
            if ((st = own_param(ps, kOfxParamTypeChoice, name, label, hint, &pp)) != kOfxStatOK)
                return st;
            ofx_set_str(pp, kOfxParamPropChoiceOption, 0, "auto");
            ofx_set_int(pp, kOfxParamPropDefault, 0, 0);
            /* the menu changes no pixels itself: the text it writes does */
            ofx_set_int(pp, kOfxParamPropEvaluateOnChange, 0, 0);
        }
        if ((st = own_param(ps, kOfxParamTypeChoice, LOOK_PARAM_RENDERER, "Renderer",
                            "Whose names the look finds its AOVs under among Source's layers "
                            "(nprfx info --aovs FILE shows them for a file): auto tells from the "
                            "layer names.",
                            &pp)) != kOfxStatOK)
            return st;
        ofx_set_str(pp, kOfxParamPropChoiceOption, 0, "auto");
        for (int i = 0; i < NPRFX_PROFILE_COUNT; i++)
            ofx_set_str(pp, kOfxParamPropChoiceOption, i + 1, nprfx_aov_profile_name(i));
        ofx_set_int(pp, kOfxParamPropDefault, 0, 0);
    }
    if (d->measures) {
        char name[NPRFX_OFX_NAME_MAX];
        if ((st = ofx_define_analyze(ps, &d->desc,
                                     "the look measures over the whole shot (the light's range)",
                                     name, sizeof name)) != kOfxStatOK)
            return st;
    }
    if ((st = own_param(ps, kOfxParamTypeDouble, "designWidth", "Design width",
                        "The plate width in pixels the look's sizes were set for: on a plate W "
                        "pixels wide every size in pixels is multiplied by W / this (0: sizes in "
                        "the plate's own pixels). Proxy renders follow from it.",
                        &pp)) != kOfxStatOK)
        return st;
    ofx_set_dbl(pp, kOfxParamPropDefault, 0, d->design_width);
    ofx_set_dbl(pp, kOfxParamPropMin, 0, 0);
    ofx_set_dbl(pp, kOfxParamPropMax, 0, 1000000);
    ofx_set_dbl(pp, kOfxParamPropDisplayMin, 0, 0);
    ofx_set_dbl(pp, kOfxParamPropDisplayMax, 0, 4096);
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
