/* nprfx OpenFX adapter — the actions in which the host asks about a render before making it
 * (declared in ofx_actions.h): the region of definition, the regions of interest, the frames
 * needed and the clip preferences, each answered from the node's descriptor and params as the
 * runner would decide them. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ofx_actions.h"
#include "ofx_render.h"
#include "ofx_derive.h"
#include "ofx_names.h"
#include "ofx_params.h"
#include "ofx_suites.h"

OfxStatus ofx_region_of_definition(ofx_instance *inst, OfxPropertySetHandle in_args,
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
    ofx_names_clip_name(d, k, clip, sizeof clip);
    if (n > 0) set_clip_rect(out_args, kOfxImageClipPropFrameRangePrefix, clip, v, 2 * n);
}

/* Inputs are needed whole (nodes filter neighbourhoods, maps are looked up anywhere); the mask
 * only where the output is asked for. */
OfxStatus ofx_regions_of_interest(ofx_instance *inst, OfxPropertySetHandle in_args,
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
        ofx_names_clip_name(inst->desc, k, clip, sizeof clip);
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
OfxStatus ofx_frames_needed(ofx_instance *inst, OfxPropertySetHandle in_args,
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
    int main = ofx_names_main_input(d);
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
    /* A stateful node answers with what its state still needs (coherent-noise rendered in
     * order: the new frame, not the recursion from its start). The state is read only when no
     * render holds it: a render may be fetching through the host, which may ask this on another
     * thread; then the whole span, as for a fresh instance. */
    int locked = (d->flags & NPRFX_NODE_STATEFUL) && !inst->derive &&
                 pthread_mutex_trylock(&inst->lock) == 0;
    q.state = locked ? inst->state : NULL;
    for (int k = 0; k < d->num_inputs && !inst->derive; k++) {
        if (!inst->clips[k] || !channels[k]) continue;
        nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES];
        int n = 0;
        if (!ofx_g.temporal) {
            r[0].first = r[0].last = time;
            n = 1;
        } else if (ofx_analysis_text(inst)) {
            /* measured by Analyze Shot: a render reads its own frame */
            r[0].first = r[0].last = time;
            n = 1;
        } else if (nprfx_node_frames_needed(ctx, d, values, &q, k, r, &n) != NPRFX_OK) {
            continue; /* the host's default: the frame itself */
        }
        set_frame_ranges(out_args, d, k, r, n);
    }
    if (locked) pthread_mutex_unlock(&inst->lock);
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
OfxStatus ofx_clip_preferences(ofx_instance *inst, OfxPropertySetHandle out_args)
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
    int main = ofx_names_main_input(d);
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
        OfxPropertySetHandle sp = ofx_clip_props(inst->clips[main]);
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
        ofx_names_clip_name(d, k, clip, sizeof clip);
        set_clip_string(out_args, kOfxImageClipPropDepthPrefix, clip, kOfxBitDepthFloat);
    }
    (void)ofx_g.prop->propSetString(out_args, kOfxImageEffectPropPreMultiplication, 0, premult);
    /* Random numbers hash the frame (docs/design.md §1): the output varies with time even when the
     * inputs do not. */
    (void)ofx_g.prop->propSetInt(out_args, kOfxImageEffectFrameVarying, 0, 1);
    return kOfxStatOK;
}
