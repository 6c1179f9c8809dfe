/* nprfx OpenFX adapter — reading an instance's settings back from the host (declared in
 * ofx_params.h): param values (at a time, or as they are now), the channels each input clip gives
 * through its selector, the effect's frame and the shot's frame range. The render and the actions
 * that answer the host before it (ofx_actions.c) share these. */
#include <stdlib.h>
#include <string.h>

#include "ofx_names.h"
#include "ofx_params.h"
#include "ofx_suites.h"

nprfx_result ofx_eval_params(const ofx_instance *inst, nprfx_context *ctx, OfxTime time,
                             int current, nprfx_value *values, char **strings)
{
    const nprfx_node_desc *d = inst->desc;
    const OfxParameterSuiteV1 *pm = ofx_g.param;
    for (int i = 0; i < d->num_params; i++) {
        const nprfx_param_desc *p = &d->params[i];
        OfxParamHandle h = inst->params[i];
        OfxStatus st = kOfxStatOK;
        int iv = 0;
        char *s = NULL;
        double *v = values[i].v;
        memset(&values[i], 0, sizeof values[i]);
        values[i].s = "";
        switch (p->type) {
        case NPRFX_PARAM_DOUBLE:
            st = current ? pm->paramGetValue(h, &v[0]) : pm->paramGetValueAtTime(h, time, &v[0]);
            break;
        case NPRFX_PARAM_INT:
        case NPRFX_PARAM_BOOL:
        case NPRFX_PARAM_CHOICE:
            st = current ? pm->paramGetValue(h, &iv) : pm->paramGetValueAtTime(h, time, &iv);
            v[0] = iv;
            break;
        case NPRFX_PARAM_COLOR:
            st = current ? pm->paramGetValue(h, &v[0], &v[1], &v[2], &v[3])
                         : pm->paramGetValueAtTime(h, time, &v[0], &v[1], &v[2], &v[3]);
            break;
        case NPRFX_PARAM_STRING:
            st = current ? pm->paramGetValue(h, &s) : pm->paramGetValueAtTime(h, time, &s);
            if (st == kOfxStatOK) {
                size_t n = strlen(s ? s : "") + 1;
                free(strings[i]);
                if (!(strings[i] = malloc(n)))
                    return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
                memcpy(strings[i], s ? s : "", n);
                values[i].s = strings[i];
            }
            break;
        }
        if (st != kOfxStatOK)
            return nprfx_error(ctx, NPRFX_ERR_INTERNAL,
                               "%s.%s: the host gave no value (OFX status %d)", d->id, p->name, st);
        /* Hosts do not all clamp typed-in or expression values: refuse as the runner does. */
        nprfx_result r = nprfx_param_check(ctx, d, p, &values[i]);
        if (r) return r;
    }
    return NPRFX_OK;
}

void ofx_input_selection(const ofx_instance *inst, int k, OfxTime time, int current, int *first,
                         int *count)
{
    const nprfx_input_desc *in = &inst->desc->inputs[k];
    int opts[NPRFX_OFX_CHAN_OPTIONS];
    int n = ofx_names_selector_options(in, opts);
    int choice = ofx_names_selector_default(in);
    if (inst->selectors[k]) {
        int v = choice;
        OfxStatus st = current ? ofx_g.param->paramGetValue(inst->selectors[k], &v)
                               : ofx_g.param->paramGetValueAtTime(inst->selectors[k], time, &v);
        if (st == kOfxStatOK && v >= 0 && v < n) choice = v;
    }
    if (choice >= n) choice = 0;
    *first = ofx_names_chan_options[opts[choice]].first;
    *count = ofx_names_chan_options[opts[choice]].count;
}

void ofx_input_channels(const ofx_instance *inst, OfxTime time, int current, int *channels)
{
    /* Derived inputs have their flow channels once there is footage to derive them from. */
    int main = ofx_names_main_input(inst->desc);
    int footage = inst->derive && main >= 0 && ofx_clip_connected(inst->clips[main]);
    for (int k = 0; k < inst->desc->num_inputs; k++) {
        int first = 0, count = 0;
        if (inst->derive && inst->plan.count[k])
            count = footage ? inst->plan.count[k] : 0;
        else if (ofx_clip_connected(inst->clips[k]))
            ofx_input_selection(inst, k, time, current, &first, &count);
        channels[k] = count;
    }
}

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
    /* Unknown (last < first) where the host says nothing; and where it gives no temporal clip
     * access, whatever it says (MLT reports no range, or the frame rendered): there the shot's
     * other frames cannot be had, and a node that needs them must say so, not measure this frame
     * alone. Footage nodes keep their previous frames themselves (ofx_footage.c). */
    double r[2] = {0, -1};
    OfxPropertySetHandle p = ofx_clip_props(inst->output);
    if (!p || ofx_g.prop->propGetDoubleN(p, kOfxImageEffectPropFrameRange, 2, r) != kOfxStatOK ||
        (!ofx_g.temporal && !inst->derive)) {
        r[0] = 0;
        r[1] = -1;
    }
    *first = r[0];
    *last = r[1];
}
