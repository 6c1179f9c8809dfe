/* nprfx OpenFX adapter — the render action (declared in ofx_render.h): the effect's frame and
 * the render window in host pixels at the render scale, params evaluated at the render time,
 * host images as nprfx views (ofx_image.c), derived inputs on footage (ofx_footage.c), the
 * node's render function with the host's executor (ofx_executor.c) and a fetch of clip images at
 * other times (ofx_fetch.c), then mix and the output image (ofx_mix.c) and the node's export
 * (ofx_export.c). Errors go to the host as a message (ofx_messages.c) and as the status. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "flow_opencv.h"
#include "ofx_executor.h"
#include "ofx_export.h"
#include "ofx_fetch.h"
#include "ofx_footage.h"
#include "ofx_handover.h"
#include "ofx_image.h"
#include "ofx_messages.h"
#include "ofx_mix.h"
#include "ofx_names.h"
#include "ofx_params.h"
#include "ofx_render.h"
#include "ofx_suites.h"

static OfxRectI to_pixels(OfxRectD r, double sx, double sy, double par)
{
    OfxRectI p;
    p.x1 = (int)floor(r.x1 * sx / par + 1e-9);
    p.y1 = (int)floor(r.y1 * sy + 1e-9);
    p.x2 = (int)ceil(r.x2 * sx / par - 1e-9);
    p.y2 = (int)ceil(r.y2 * sy - 1e-9);
    return p;
}

const char *ofx_analysis_text(const ofx_instance *inst)
{
    char *text = NULL;
    if (!inst->analysis || ofx_g.param->paramGetValue(inst->analysis, &text) != kOfxStatOK ||
        !text || !*text)
        return NULL;
    return text;
}

static OfxStatus render_at(ofx_instance *inst, double time, double *scale, const int *win,
                           int measure);

int ofx_is_analyze(const ofx_instance *inst, OfxPropertySetHandle in_args)
{
    char *type = NULL, *name = NULL, analyze[NPRFX_OFX_NAME_MAX];
    if (!inst->analysis || !in_args ||
        ofx_g.prop->propGetString(in_args, kOfxPropType, 0, &type) != kOfxStatOK ||
        ofx_g.prop->propGetString(in_args, kOfxPropName, 0, &name) != kOfxStatOK || !type ||
        !name || strcmp(type, kOfxTypeParameter))
        return 0;
    ofx_names_extra_param(inst->desc, "analyze", analyze, sizeof analyze);
    return !strcmp(name, analyze);
}

OfxStatus ofx_render(ofx_instance *inst, OfxPropertySetHandle in_args)
{
    double time, scale[2];
    int win[4];
    OfxStatus st = ofx_render_request(in_args, &time, scale, win);
    return st == kOfxStatOK ? render_at(inst, time, scale, win, 0) : st;
}

OfxStatus ofx_analyze(ofx_instance *inst)
{
    double first = 0, last = 0, scale[2] = {1, 1};
    ofx_shot_range(inst, &first, &last);
    /* measured afresh: what the param held goes */
    ofx_instance_drop_state(inst);
    if (ofx_g.param->paramSetValue(inst->analysis, "") != kOfxStatOK) return kOfxStatFailed;
    /* one pixel of the first frame: the node measures the shot whatever the window */
    OfxRectD rod;
    if (ofx_frame_rod(inst, first, &rod) != kOfxStatOK) return kOfxStatFailed;
    int x = (int)floor(rod.x1), y = (int)floor(rod.y1);
    int win[4] = {x, y, x + 1, y + 1};
    return render_at(inst, first, scale, win, 1);
}

/* Render the window at time into the output clip's image; measure: into a scratch image of the
 * window alone (no host image: the instance-changed action has none), then keep what the state
 * measured in the analysis param. */
static OfxStatus render_at(ofx_instance *inst, double time, double *scale, const int *win,
                           int measure)
{
    const nprfx_node_desc *d = inst->desc;
    const OfxPropertySuiteV1 *ps = ofx_g.prop;

    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.executor = &ofx_host_executor;
    ci.data_dir = ofx_g.data_dir[0] ? ofx_g.data_dir : NULL;
    ci.flow = flow_opencv_provider(); /* the flow node's solver; NULL without OpenCV */
    ofx_render_call rc;
    memset(&rc, 0, sizeof rc);
    rc.inst = inst;
    rc.time = time;
    if (nprfx_context_create(&ci, &rc.ctx) != NPRFX_OK) return kOfxStatErrMemory;
    pthread_mutex_init(&rc.lock, NULL);
    pthread_mutex_init(&rc.dlock, NULL);
    size_t ni = (size_t)d->num_inputs + 1, np = (size_t)d->num_params + 1;
    nprfx_value *values = calloc(np, sizeof *values);
    char **strings = calloc(np, sizeof *strings);
    int *in_ch = calloc(ni, sizeof *in_ch);
    rc.inputs = calloc(ni, sizeof *rc.inputs);
    rc.cur = calloc(ni, sizeof *rc.cur);
    rc.first = calloc(ni, sizeof *rc.first);
    rc.count = calloc(ni, sizeof *rc.count);
    ofx_img out, mask;
    memset(&out, 0, sizeof out);
    memset(&mask, 0, sizeof mask);
    nprfx_image res, mask_view;
    float *res_scratch = NULL, *mask_scratch = NULL;
    int res_owned = 0;
    memset(&res, 0, sizeof res);
    memset(&mask_view, 0, sizeof mask_view);
    OfxStatus status = kOfxStatFailed;
    nprfx_result r = NPRFX_OK;
    int locked = 0;
    if (!values || !strings || !in_ch || !rc.inputs || !rc.cur || !rc.first || !rc.count) {
        r = nprfx_error(rc.ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        status = kOfxStatErrMemory;
        goto done;
    }

    /* the frame, in host pixels at this render scale */
    OfxRectD rod;
    if (ofx_frame_rod(inst, time, &rod) != kOfxStatOK) {
        r = nprfx_error(rc.ctx, NPRFX_ERR_MISSING_INPUT,
                        "%s: no input is connected and the host gives no project size", d->id);
        goto done;
    }
    double par = 1;
    OfxPropertySetHandle op = NULL;
    if (ofx_g.fx->clipGetPropertySet(inst->output, &op) != kOfxStatOK ||
        ps->propGetDouble(op, kOfxImagePropPixelAspectRatio, 0, &par) != kOfxStatOK || !(par > 0))
        par = 1;
    OfxRectI fr = to_pixels(rod, scale[0], scale[1], par);
    rc.f = fr.y1 + fr.y2 - 1;
    nprfx_rect frame = ofx_flip_rect(fr, rc.f);
    OfxRectI wr = {win[0], win[1], win[2], win[3]};
    nprfx_rect host_window = ofx_flip_rect(wr, rc.f);

    if ((r = ofx_eval_params(inst, rc.ctx, time, 0, values, strings))) goto done;
    /* Params in pixels follow the render scale (a proxy) and, with a design width, the input's
     * full-resolution width; motion vectors come in full-resolution pixels: the render scale
     * alone. */
    double param_scale = scale[0];
    int design = 0;
    if (inst->design_width &&
        ofx_g.param->paramGetValue(inst->design_width, &design) == kOfxStatOK && design > 0 &&
        rod.x2 > rod.x1)
        param_scale *= (rod.x2 - rod.x1) / par / design;
    nprfx_node_apply_render_scale(d, values, param_scale);

    for (int k = 0; k < d->num_inputs; k++) {
        if (!ofx_clip_connected(inst->clips[k])) continue;
        if (inst->derive && inst->plan.count[k]) continue; /* below */
        ofx_input_selection(inst, k, time, 0, &rc.first[k], &rc.count[k]);
        OfxStatus st = ofx_img_fetch(inst->clips[k], time, 1, &rc.cur[k].img);
        if (st == kOfxStatFailed) continue; /* no image at this time: as if not connected */
        if (st != kOfxStatOK) {
            r = nprfx_error(rc.ctx, NPRFX_ERR_MISSING_INPUT,
                            "%s: the host gave no usable image of input '%s' (OFX status %d)",
                            d->id, d->inputs[k].name, st);
            status = st;
            goto done;
        }
        if ((r = ofx_img_view(&rc.cur[k].img, ofx_input_flip(&rc, k, &rc.cur[k].img), rc.first[k],
                              rc.count[k], &rc.inputs[k], &rc.cur[k].scratch))) {
            status = kOfxStatErrMemory;
            goto done;
        }
        in_ch[k] = rc.count[k];
    }

    double first = 0, last = 0;
    ofx_shot_range(inst, &first, &last);
    rc.first_frame = ofx_round_frame(first);
    rc.last_frame = ofx_round_frame(last);
    /* A stateful node's cache, and the flow's and the kept frames of footage, are shared by the
     * renders of the instance. */
    if ((d->flags & NPRFX_NODE_STATEFUL) || inst->derive) {
        pthread_mutex_lock(&inst->lock);
        locked = 1;
    }
    if (inst->derive) {
        /* Footage: the derived inputs from the flow node run on Source (ofx_footage.c). */
        int main = ofx_names_main_input(d);
        if (!ofx_clip_connected(inst->clips[main])) {
            r = nprfx_error(rc.ctx, NPRFX_ERR_MISSING_INPUT,
                            "%s: the Source clip is not connected: it is the footage this effect "
                            "computes its motion from",
                            d->id);
            goto done;
        }
        OfxStatus st = kOfxStatOK;
        if (!rc.cur[main].img.h) st = ofx_img_fetch(inst->clips[main], time, 1, &rc.cur[main].img);
        if (st != kOfxStatOK) {
            r = nprfx_error(rc.ctx, NPRFX_ERR_MISSING_INPUT,
                            "%s: the host gave no image of the Source clip at frame %g (OFX "
                            "status %d)",
                            d->id, time, st);
            status = st == kOfxStatErrMemory ? st : kOfxStatFailed;
            goto done;
        }
        const ofx_img *si = &rc.cur[main].img;
        if ((r = ofx_img_view(si, ofx_input_flip(&rc, main, si), 0, si->ncomp, &rc.src,
                              &rc.src_scratch))) {
            status = kOfxStatErrMemory;
            goto done;
        }
        memcpy(rc.fvalues, inst->plan.values, sizeof rc.fvalues);
        nprfx_node_apply_render_scale(inst->plan.flow, rc.fvalues, param_scale);
        rc.scale = param_scale;
        rc.vector_scale = scale[0];
        rc.frame = frame;
        if (!ofx_g.temporal && (r = ofx_footage_continue(&rc, ofx_round_frame(time),
                                                         ofx_handover_key(d, values, &rc.src))))
            goto done;
        if ((r = ofx_footage_inputs(&rc, ofx_round_frame(time), in_ch))) goto done;
    }

    nprfx_output_info oi;
    if ((r = nprfx_node_output_info(rc.ctx, d, values, in_ch, &oi))) goto done;
    int nout = oi.channels;
    OfxStatus st = measure ? kOfxStatOK : ofx_img_fetch(inst->output, time, 0, &out);
    if (measure) out.b = wr;
    if (st != kOfxStatOK) {
        r = nprfx_error(rc.ctx, NPRFX_ERR_INTERNAL, "%s: the host gave no output image (%d)", d->id,
                        st);
        status = st;
        goto done;
    }
    host_window = nprfx_rect_intersect(host_window, ofx_flip_rect(out.b, rc.f));
    nprfx_rect window = nprfx_rect_intersect(host_window, frame);
    /* The result: in place where the host image holds the first nout components in order,
     * else in a scratch image covering the window. */
    if (!measure && out.bytes == 4 && (out.ncomp == 4 || out.ncomp == 3) && nout <= out.ncomp &&
        !nprfx_rect_empty(window)) {
        if ((r = ofx_img_view(&out, rc.f, 0, nout, &res, &res_scratch))) goto done;
    } else if (!nprfx_rect_empty(window)) {
        if ((r = nprfx_image_alloc(rc.ctx, window, nout, &res))) goto done;
        res_owned = 1;
    }

    int main = ofx_names_main_input(d);
    ofx_finish_job fj;
    memset(&fj, 0, sizeof fj);
    fj.out = &out;
    fj.res = &res;
    fj.window = window;
    fj.f = rc.f;
    fj.nout = nout;
    fj.mix = 1.0;
    if (inst->mix && !measure) {
        double mix = 1.0;
        int inv = 0;
        if (ofx_g.param->paramGetValueAtTime(inst->mix, time, &mix) == kOfxStatOK) fj.mix = mix;
        if (inst->mask_invert &&
            ofx_g.param->paramGetValueAtTime(inst->mask_invert, time, &inv) == kOfxStatOK)
            fj.mask_invert = inv != 0;
        if (ofx_clip_connected(inst->mask) &&
            ofx_img_fetch(inst->mask, time, 1, &mask) == kOfxStatOK) {
            if ((r = ofx_img_view(&mask, rc.f, mask.ncomp == 4 ? 3 : 0, 1, &mask_view,
                                  &mask_scratch)))
                goto done;
            fj.mask = &mask_view;
        }
        if (main >= 0 && rc.inputs[main].data) fj.src = &rc.inputs[main];
    }

    if (!nprfx_rect_empty(window)) {
        nprfx_render_args a;
        memset(&a, 0, sizeof a);
        a.size = sizeof a;
        a.ctx = rc.ctx;
        a.node = d;
        a.time = time;
        a.render_scale = param_scale;
        a.vector_scale = scale[0];
        a.frame = frame;
        a.window = window;
        a.first_frame = rc.first_frame;
        a.last_frame = rc.last_frame;
        a.inputs = rc.inputs;
        a.params = values;
        a.output = &res;
        /* Without temporal access the host would answer with the current frame: no fetch, and
         * a node that needs another frame says so. */
        a.fetch = inst->derive ? ofx_footage_fetch : ofx_g.temporal ? ofx_fetch_input : NULL;
        a.fetch_user = &rc;
        a.state = &inst->state;
        /* What Analyze Shot measured, into a fresh state (the text is checked as it is used:
         * a frame that differs measures again); unreadable text is as none. */
        const char *analysis = measure ? NULL : ofx_analysis_text(inst);
        if (analysis && !inst->state &&
            nprfx_node_state_load(rc.ctx, d, &inst->state, analysis) != NPRFX_OK && inst->state) {
            d->state_free(inst->state);
            inst->state = NULL;
        }
        r = nprfx_node_render(&a);
        if (!r && measure) {
            char *text = NULL;
            if (!(r = nprfx_node_state_save(rc.ctx, d, inst->state, &text)) && text &&
                ofx_g.param->paramSetValue(inst->analysis, text) != kOfxStatOK)
                r = nprfx_error(rc.ctx, NPRFX_ERR_INTERNAL,
                                "%s: the host did not keep the analysis", d->id);
            free(text);
        }
        if (!r && inst->derive && !ofx_g.temporal) r = ofx_footage_keep(&rc, ofx_round_frame(time));
        if (locked) pthread_mutex_unlock(&inst->lock);
        locked = 0;
        if (r) goto done;
        if (measure) {
            status = kOfxStatOK;
            goto done;
        }
        nprfx_parallel_for(&ofx_host_executor, nprfx_rect_height(window), 16, ofx_finish_rows, &fj);
        /* The export param writes the frame's vectors from hosts as from the runner; proxy
         * renders do not (their coordinates would be scaled). */
        if (d->export_text && scale[0] == 1.0 && scale[1] == 1.0) {
            a.window = frame;
            a.output = NULL;
            if ((r = ofx_export(inst, &a))) goto done;
        }
    }
    /* Pixels the host asked for outside the frame: transparent black. */
    for (int y = host_window.y0; y < host_window.y1; y++)
        for (int x = host_window.x0; x < host_window.x1; x++)
            if (!nprfx_rect_contains(frame, x, y))
                for (int c = 0; c < out.ncomp; c++)
                    ofx_img_store(&out, x, rc.f - y, c, 0.0f);
    status = kOfxStatOK;
    ofx_clear_error(inst);

done:
    if (locked) pthread_mutex_unlock(&inst->lock);
    if (r && status == kOfxStatOK) status = kOfxStatFailed;
    if (r) {
        char msg[1024];
        nprfx_context_last_error(rc.ctx, msg, sizeof msg);
        ofx_post_error(inst, msg);
    }
    ofx_footage_release(&rc);
    for (int i = 0; i < OFX_FETCH_RING; i++)
        ofx_fetched_release(&rc.ring[i]);
    for (int k = 0; rc.cur && k < d->num_inputs; k++)
        ofx_fetched_release(&rc.cur[k]);
    ofx_img_release(&mask);
    ofx_free(mask_scratch);
    ofx_free(res_scratch);
    if (res_owned) nprfx_image_free(&res);
    ofx_img_release(&out);
    for (int i = 0; strings && i < d->num_params; i++)
        free(strings[i]);
    free(values);
    free(strings);
    free(in_ch);
    free(rc.inputs);
    free(rc.cur);
    free(rc.first);
    free(rc.count);
    pthread_mutex_destroy(&rc.lock);
    pthread_mutex_destroy(&rc.dlock);
    nprfx_context_destroy(rc.ctx);
    return status;
}
