/* nprfx OpenFX adapter — an instance's lifecycle: lookup, create and destroy, and what a change,
 * a cache purge or a new sequence render drops (declared in ofx_instance.h). */
#include <string.h>

#include "ofx_derive.h"
#include "ofx_instance.h"
#include "ofx_names.h"
#include "ofx_suites.h"

/* ---- lookup, create, destroy ----------------------------------------------------------------- */

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

OfxStatus ofx_instance_create(const nprfx_node_desc *d, OfxImageEffectHandle fx)
{
    ofx_instance *inst = ofx_zalloc(sizeof *inst);
    if (!inst) return kOfxStatErrMemory;
    inst->desc = d;
    inst->fx = fx;
    pthread_mutex_init(&inst->lock, NULL);
    size_t ni = (size_t)(d->num_inputs > 0 ? d->num_inputs : 1);
    size_t np = (size_t)(d->num_params > 0 ? d->num_params : 1);
    inst->clips = ofx_zalloc(ni * sizeof *inst->clips);
    inst->selectors = ofx_zalloc(ni * sizeof *inst->selectors);
    inst->params = ofx_zalloc(np * sizeof *inst->params);
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
        ofx_names_clip_name(d, k, name, sizeof name);
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
        ofx_names_selector_name(d, k, name, sizeof name);
        if (!inst->clips[k] ||
            pm->paramGetHandle(ps, name, &inst->selectors[k], NULL) != kOfxStatOK)
            inst->selectors[k] = NULL;
    }
    ofx_names_extra_param(d, "designWidth", name, sizeof name);
    if (!ofx_names_has_pixel_params(d) ||
        pm->paramGetHandle(ps, name, &inst->design_width, NULL) != kOfxStatOK)
        inst->design_width = NULL;
    ofx_names_extra_param(d, "analysis", name, sizeof name);
    if (!nprfx_node_measures_shot(d) ||
        pm->paramGetHandle(ps, name, &inst->analysis, NULL) != kOfxStatOK)
        inst->analysis = NULL;
    if (inst->mask) {
        ofx_names_extra_param(d, "mix", name, sizeof name);
        if (pm->paramGetHandle(ps, name, &inst->mix, NULL) != kOfxStatOK) inst->mix = NULL;
        ofx_names_extra_param(d, "maskInvert", name, sizeof name);
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

OfxStatus ofx_instance_destroy(OfxImageEffectHandle fx)
{
    ofx_instance *inst = ofx_instance_get(fx);
    if (!inst) return kOfxStatErrBadHandle;
    OfxPropertySetHandle p;
    if (ofx_g.fx->getPropertySet(fx, &p) == kOfxStatOK)
        (void)ofx_g.prop->propSetPointer(p, kOfxPropInstanceData, 0, NULL);
    instance_free(inst);
    return kOfxStatOK;
}

/* ---- what a change drops --------------------------------------------------------------------- */

/* Drop the node's cache: it only ever saves work, and a changed param or clip may make it
 * stale (the runner drops it on --set likewise). */
void ofx_instance_drop_state(ofx_instance *inst)
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
void ofx_instance_forget_export(ofx_instance *inst)
{
    pthread_mutex_lock(&inst->lock);
    inst->export_done = 0;
    pthread_mutex_unlock(&inst->lock);
}

OfxStatus ofx_instance_changed(ofx_instance *inst, OfxPropertySetHandle in_args)
{
    char *type = NULL, *name = NULL;
    if (in_args) {
        (void)ofx_g.prop->propGetString(in_args, kOfxPropType, 0, &type);
        (void)ofx_g.prop->propGetString(in_args, kOfxPropName, 0, &name);
    }
    if (type && name && !strcmp(type, kOfxTypeParameter)) {
        char mix[NPRFX_OFX_NAME_MAX], inv[NPRFX_OFX_NAME_MAX];
        ofx_names_extra_param(inst->desc, "mix", mix, sizeof mix);
        ofx_names_extra_param(inst->desc, "maskInvert", inv, sizeof inv);
        if (!strcmp(name, mix) || !strcmp(name, inv)) return kOfxStatOK; /* after the node */
    }
    ofx_instance_drop_state(inst);
    return kOfxStatOK;
}

void ofx_instance_forget_footage(ofx_instance *inst)
{
    nprfx_image_free(&inst->kept_src);
    nprfx_image_free(&inst->kept_flow);
    inst->kept = 0;
    if (inst->flow_state && inst->plan.flow && inst->plan.flow->state_free)
        inst->plan.flow->state_free(inst->flow_state);
    inst->flow_state = NULL;
}
