/* nprfx OpenFX adapter — the render action: host images become nprfx views, params are
 * evaluated at the render time, and the node's render function runs with an executor built on
 * the host's multithread suite and a fetch callback that gets clip images at other times.
 *
 * Coordinates. OFX pixel coordinates grow upward; nprfx's grow downward (docs/design.md §2). Every
 * frame-aligned image is flipped about the effect's frame [fy1, fy2): y_down = fy1 + fy2 - 1 -
 * y_up, which maps the frame onto itself, so a frame at (0, 0, W, H) keeps those numbers and
 * clips that share the canonical space stay aligned. An unaligned input (a lookup map) is
 * flipped about its own bounds, as the runner passes it whole. The flip is free: a view starts
 * at the top row and steps by -rowBytes, which also covers hosts whose rowBytes are negative. */
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flow_opencv.h"
#include "ofx_internal.h"

#define G ofx_g

/* ---- the executor on the host's multithread suite -------------------------------------------- */

typedef struct mt_job {
    nprfx_range_fn fn;
    void *user;
    int count, grain;
    atomic_int next;
} mt_job;

static void mt_run(mt_job *j, int worker)
{
    for (;;) {
        int begin = atomic_fetch_add(&j->next, j->grain);
        if (begin >= j->count) break;
        int end = begin + j->grain < j->count ? begin + j->grain : j->count;
        j->fn(j->user, begin, end, worker);
    }
}

static void mt_thread(unsigned int index, unsigned int max, void *arg)
{
    (void)max;
    mt_job *j = arg;
    mt_run(j, (int)index);
}

static int mt_workers(void *impl)
{
    (void)impl;
    unsigned int n = 1;
    if (!G.mt || G.mt->multiThreadNumCPUs(&n) != kOfxStatOK || n < 1) return 1;
    return n > 256 ? 256 : (int)n;
}

/* Threads pull chunks from one counter, so which thread computes a chunk never matters (the
 * nodes write disjoint output per item). The suite cannot be entered recursively: a nested call,
 * or a host without the suite, runs on the calling thread under that thread's own index, which
 * keeps worker indices unique among concurrent calls. If the host fails to launch threads, the
 * calling thread finishes whatever is left. */
static void mt_for(void *impl, int count, int grain, nprfx_range_fn fn, void *user)
{
    if (count <= 0) return;
    if (grain < 1) grain = 1;
    mt_job j;
    j.fn = fn;
    j.user = user;
    j.count = count;
    j.grain = grain;
    atomic_init(&j.next, 0);
    int chunks = (count - 1) / grain + 1;
    int n = mt_workers(impl);
    if (n > chunks) n = chunks;
    int worker = 0;
    if (G.mt && G.mt->multiThreadIsSpawnedThread()) {
        unsigned int index = 0;
        if (G.mt->multiThreadIndex(&index) == kOfxStatOK) worker = (int)index;
    } else if (G.mt && n > 1) {
        (void)G.mt->multiThread(mt_thread, (unsigned int)n, &j);
    }
    mt_run(&j, worker);
}

static const nprfx_executor host_executor = {sizeof(nprfx_executor), NULL, mt_workers, mt_for};

/* ---- host images ----------------------------------------------------------------------------- */

typedef struct ofx_img {
    OfxPropertySetHandle h; /* NULL: nothing fetched */
    char *data;             /* pixel (bounds.x1, bounds.y1) */
    int row_bytes;
    OfxRectI b;
    int ncomp;   /* 1 Alpha, 3 RGB, 4 RGBA */
    int bytes;   /* per component of data: 4 float, 2 unsigned short, 1 unsigned char */
    float *conv; /* an 8/16-bit input converted to float (data points here then) */
} ofx_img;

static void img_release(ofx_img *im)
{
    if (im->h) G.fx->clipReleaseImage(im->h);
    ofx_free(im->conv);
    memset(im, 0, sizeof *im);
}

static int depth_bytes(const char *depth)
{
    return !strcmp(depth, kOfxBitDepthFloat)   ? 4
           : !strcmp(depth, kOfxBitDepthShort) ? 2
           : !strcmp(depth, kOfxBitDepthByte)  ? 1
                                               : 0;
}

/* An 8/16-bit image as float in [0, 1]: the nodes read float only, and a host that gives
 * integers (MLT) gives display-referred video, for which that is the natural scale. */
static OfxStatus img_to_float(ofx_img *im)
{
    int w = im->b.x2 - im->b.x1, h = im->b.y2 - im->b.y1, n = w * im->ncomp;
    if (w <= 0 || h <= 0) return kOfxStatOK;
    float *f = ofx_alloc((size_t)n * (size_t)h * sizeof *f);
    if (!f) return kOfxStatErrMemory;
    for (int y = 0; y < h; y++) {
        const char *row = im->data + (ptrdiff_t)y * im->row_bytes;
        float *d = f + (size_t)y * (size_t)n;
        for (int i = 0; i < n; i++)
            d[i] = im->bytes == 2 ? ((const unsigned short *)row)[i] / 65535.0f
                                  : ((const unsigned char *)row)[i] / 255.0f;
    }
    im->conv = f;
    im->data = (char *)f;
    im->row_bytes = n * (int)sizeof *f;
    im->bytes = 4;
    return kOfxStatOK;
}

/* An image of clip at t. Inputs (convert = 1) always come out as float; the output keeps the
 * host's depth and is written with img_store. */
static OfxStatus img_fetch(OfxImageClipHandle clip, OfxTime t, int convert, ofx_img *im)
{
    memset(im, 0, sizeof *im);
    OfxPropertySetHandle h = NULL;
    OfxStatus st = G.fx->clipGetImage(clip, t, NULL, &h);
    if (st != kOfxStatOK) return st;
    if (!h) return kOfxStatFailed;
    im->h = h;
    void *data = NULL;
    char *depth = NULL, *comps = NULL;
    int b[4] = {0, 0, 0, 0};
    if (G.prop->propGetPointer(h, kOfxImagePropData, 0, &data) != kOfxStatOK ||
        G.prop->propGetInt(h, kOfxImagePropRowBytes, 0, &im->row_bytes) != kOfxStatOK ||
        G.prop->propGetIntN(h, kOfxImagePropBounds, 4, b) != kOfxStatOK ||
        G.prop->propGetString(h, kOfxImageEffectPropPixelDepth, 0, &depth) != kOfxStatOK ||
        G.prop->propGetString(h, kOfxImageEffectPropComponents, 0, &comps) != kOfxStatOK) {
        img_release(im);
        return kOfxStatErrBadHandle;
    }
    im->data = data;
    im->b.x1 = b[0], im->b.y1 = b[1], im->b.x2 = b[2], im->b.y2 = b[3];
    im->ncomp = !strcmp(comps, kOfxImageComponentRGBA)    ? 4
                : !strcmp(comps, kOfxImageComponentAlpha) ? 1
                : !strcmp(comps, kOfxImageComponentRGB)   ? 3
                                                          : 0;
    im->bytes = depth_bytes(depth);
    if (!im->bytes || !im->ncomp || im->row_bytes % im->bytes ||
        (!im->data && im->b.x2 > im->b.x1 && im->b.y2 > im->b.y1)) {
        img_release(im);
        return kOfxStatErrImageFormat;
    }
    if (convert && im->bytes != 4 && (st = img_to_float(im)) != kOfxStatOK) {
        img_release(im);
        return st;
    }
    return kOfxStatOK;
}

/* Write v into component c of pixel (x, y_up) of a host image of any depth (integers clamp to
 * [0, 1] and round; NaN becomes 0). */
static void img_store(const ofx_img *im, int x, int y, int c, float v)
{
    char *row = im->data + (ptrdiff_t)(y - im->b.y1) * im->row_bytes;
    ptrdiff_t i = (ptrdiff_t)(x - im->b.x1) * im->ncomp + c;
    if (im->bytes == 4) {
        ((float *)row)[i] = v;
        return;
    }
    float u = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; /* NaN fails v > 0 */
    if (im->bytes == 2)
        ((unsigned short *)row)[i] = (unsigned short)(u * 65535.0f + 0.5f);
    else
        ((unsigned char *)row)[i] = (unsigned char)(u * 255.0f + 0.5f);
}

/* Pixel (x, y_up) of a host image, component c of its own layout. */
static float *img_at(const ofx_img *im, int x, int y, int c)
{
    return (float *)(im->data + (ptrdiff_t)(y - im->b.y1) * im->row_bytes) +
           (ptrdiff_t)(x - im->b.x1) * im->ncomp + c;
}

static nprfx_rect flip_rect(OfxRectI b, int f)
{
    if (b.x2 <= b.x1 || b.y2 <= b.y1) return nprfx_rect_make(b.x1, 0, b.x1, 0);
    return nprfx_rect_make(b.x1, f - (b.y2 - 1), b.x2, f - b.y1 + 1);
}

/* Which host component holds RGBA component c (-1: the image has none). */
static int host_comp(const ofx_img *im, int c)
{
    if (im->ncomp == 4) return c;
    if (im->ncomp == 3) return c < 3 ? c : -1;
    return c == 3 ? 0 : -1;
}

static float dummy_pixel[4];

/* A view of `count` RGBA components from `first` (the selector's pick), flipped about f. It
 * shares the host's pixels when the image has those components; an Alpha image read for a single
 * channel gives its alpha whatever the pick (a matte in an Alpha-only clip is still the data the
 * user routed there); otherwise the components are copied into *scratch, missing ones 0 (1 for
 * the alpha of an RGB image, which is opaque). */
static nprfx_result img_view(const ofx_img *im, int f, int first, int count, nprfx_image *v,
                             float **scratch)
{
    memset(v, 0, sizeof *v);
    *scratch = NULL;
    v->bounds = flip_rect(im->b, f);
    v->channels = count;
    if (nprfx_rect_empty(v->bounds)) {
        v->data = dummy_pixel; /* connected, but no pixels: reads as outside its bounds */
        v->pixel_stride = count;
        return NPRFX_OK;
    }
    int c0 = host_comp(im, first), direct;
    if (im->ncomp == 1) {
        direct = count == 1;
        c0 = 0;
    } else {
        direct = c0 >= 0;
        for (int k = 1; k < count; k++)
            direct &= host_comp(im, first + k) == c0 + k;
    }
    if (direct) {
        v->data = img_at(im, im->b.x1, im->b.y2 - 1, c0);
        v->pixel_stride = im->ncomp;
        v->row_stride = -(ptrdiff_t)(im->row_bytes / (int)sizeof(float));
        return NPRFX_OK;
    }
    int w = im->b.x2 - im->b.x1, h = im->b.y2 - im->b.y1;
    float *px = ofx_alloc((size_t)w * (size_t)h * (size_t)count * sizeof(float));
    if (!px) return NPRFX_ERR_OUT_OF_MEMORY;
    for (int y = im->b.y1; y < im->b.y2; y++)
        for (int x = im->b.x1; x < im->b.x2; x++) {
            float *d = px + ((size_t)(f - y - v->bounds.y0) * (size_t)w + (size_t)(x - im->b.x1)) *
                                (size_t)count;
            for (int k = 0; k < count; k++) {
                int hc = host_comp(im, first + k);
                d[k] = hc >= 0 ? *img_at(im, x, y, hc)
                               : (im->ncomp == 3 && first + k == 3 ? 1.0f : 0.0f);
            }
        }
    v->data = px;
    v->pixel_stride = count;
    v->row_stride = (ptrdiff_t)w * count;
    *scratch = px;
    return NPRFX_OK;
}

/* ---- one render call ------------------------------------------------------------------------- */

#define RING (NPRFX_FETCH_KEEP * 2)

typedef struct fetched {
    ofx_img img;
    float *scratch;
} fetched;

#define FLOWS 4 /* flows kept during one render: a frame and its neighbours */

typedef struct flow_slot {
    int frame, used;
    nprfx_image im;
} flow_slot;

typedef struct render_call {
    ofx_instance *inst;
    nprfx_context *ctx;
    OfxTime time;
    int f; /* the frame's flip: y_down = f - y_up */
    nprfx_image *inputs;
    fetched *cur; /* per input, at the render time */
    int *first, *count;
    pthread_mutex_t lock; /* guards the ring: a node may fetch from several threads */
    fetched ring[RING];
    long nfetch;
    /* Footage (inst->derive, ofx_derive.c): Source whole at the render time, the flow node's
     * params (render scale applied), the frame, the shot the flow and the node see (from the
     * effect's restart without temporal access), the flows computed in this call and the derived
     * views handed out (copies, so a flow can be dropped while a view lives). dlock guards
     * those; a flow's own fetches take lock. */
    nprfx_image src;
    float *src_scratch;
    nprfx_value fvalues[NPRFX_OFX_DERIVE_MAX_PARAMS];
    double scale;
    nprfx_rect frame;
    int first_frame, last_frame;
    pthread_mutex_t dlock;
    flow_slot flows[FLOWS];
    long nflows;
    nprfx_image dcur[NPRFX_OFX_DERIVE_MAX_INPUTS];
    nprfx_image dring[RING];
    long ndring;
} render_call;

static void fetched_release(fetched *s)
{
    img_release(&s->img);
    ofx_free(s->scratch);
    s->scratch = NULL;
}

static int input_flip(const render_call *rc, int k, const ofx_img *im)
{
    if (rc->inst->desc->inputs[k].flags & NPRFX_INPUT_UNALIGNED) return im->b.y1 + im->b.y2 - 1;
    return rc->f;
}

/* nprfx_fetch_fn: clip k at another time. The current frame is served from the images already
 * held; other frames go into a ring, so a view stays valid for the next RING - 1 fetches, more
 * than NPRFX_FETCH_KEEP promises. */
static nprfx_result fetch_cb(void *user, int input, double time, nprfx_image *out)
{
    render_call *rc = user;
    const nprfx_node_desc *d = rc->inst->desc;
    if (input < 0 || input >= d->num_inputs)
        return nprfx_error(rc->ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: no input %d", d->id, input);
    if (!rc->inputs[input].data)
        return nprfx_error(rc->ctx, NPRFX_ERR_MISSING_INPUT, "%s: input '%s' is not connected",
                           d->id, d->inputs[input].name);
    if (time == rc->time) {
        *out = rc->inputs[input];
        return NPRFX_OK;
    }
    pthread_mutex_lock(&rc->lock);
    fetched *s = &rc->ring[rc->nfetch++ % RING];
    fetched_release(s);
    OfxStatus st = img_fetch(rc->inst->clips[input], time, 1, &s->img);
    nprfx_result r = NPRFX_OK;
    if (st != kOfxStatOK)
        r = nprfx_error(rc->ctx,
                        st == kOfxStatErrMemory ? NPRFX_ERR_OUT_OF_MEMORY : NPRFX_ERR_MISSING_INPUT,
                        "%s: the host gave no image of input '%s' at frame %g (OFX status %d)",
                        d->id, d->inputs[input].name, time, st);
    else if ((r = img_view(&s->img, input_flip(rc, input, &s->img), rc->first[input],
                           rc->count[input], out, &s->scratch)))
        r = nprfx_error(rc->ctx, r, "%s: out of memory", d->id);
    pthread_mutex_unlock(&rc->lock);
    return r;
}

/* ---- inputs derived from Source (footage in the Filter context, ofx_derive.c) ---------------- */

static int round_frame(double t)
{
    return (int)floor(t + 0.5);
}

/* Source whole (all the components the host image has) at frame t, for the flow: the render
 * time's image, another frame from the host, or, without temporal clip access, the previous
 * frame the instance kept. */
static nprfx_result source_at(render_call *rc, int t, nprfx_image *out)
{
    ofx_instance *inst = rc->inst;
    const nprfx_node_desc *d = inst->desc;
    if (t == round_frame(rc->time)) {
        *out = rc->src;
        return NPRFX_OK;
    }
    if (!G.temporal) {
        if (inst->kept && inst->kept_frame == t) {
            *out = inst->kept_src;
            return NPRFX_OK;
        }
        return nprfx_error(rc->ctx, NPRFX_ERR_MISSING_INPUT,
                           "%s: the Source clip at frame %d, while rendering frame %d: this host "
                           "gives no other frame (no temporal clip access), and the plug-in keeps "
                           "only the previous one (render in order)",
                           d->id, t, round_frame(rc->time));
    }
    int main = nprfx_ofx_main_input(d);
    pthread_mutex_lock(&rc->lock);
    fetched *s = &rc->ring[rc->nfetch++ % RING];
    fetched_release(s);
    OfxStatus st = img_fetch(inst->clips[main], t, 1, &s->img);
    nprfx_result r = NPRFX_OK;
    if (st != kOfxStatOK)
        r = nprfx_error(rc->ctx,
                        st == kOfxStatErrMemory ? NPRFX_ERR_OUT_OF_MEMORY : NPRFX_ERR_MISSING_INPUT,
                        "%s: the host gave no image of the Source clip at frame %d (OFX status %d)",
                        d->id, t, st);
    else if ((r = img_view(&s->img, input_flip(rc, main, &s->img), 0, s->img.ncomp, out,
                           &s->scratch)))
        r = nprfx_error(rc->ctx, r, "%s: out of memory", d->id);
    pthread_mutex_unlock(&rc->lock);
    return r;
}

/* The flow node's fetch: Source at its neighbouring frames. */
static nprfx_result flow_fetch(void *user, int input, double time, nprfx_image *out)
{
    (void)input;
    return source_at(user, round_frame(time), out);
}

/* The flow at frame t, computed by the flow node on Source as a graph would (held: dlock). */
static nprfx_result flow_at(render_call *rc, int t, const nprfx_image **out)
{
    ofx_instance *inst = rc->inst;
    for (int i = 0; i < FLOWS; i++)
        if (rc->flows[i].used && rc->flows[i].frame == t) {
            *out = &rc->flows[i].im;
            return NPRFX_OK;
        }
    if (!G.temporal && inst->kept && inst->kept_frame == t) {
        *out = &inst->kept_flow;
        return NPRFX_OK;
    }
    flow_slot *slot = &rc->flows[rc->nflows++ % FLOWS];
    nprfx_image_free(&slot->im);
    slot->used = 0;
    nprfx_image src;
    nprfx_result r = source_at(rc, t, &src);
    if (!r) r = nprfx_image_alloc(rc->ctx, rc->frame, inst->plan.channels, &slot->im);
    if (r) return r;
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = rc->ctx;
    a.node = inst->plan.flow;
    a.time = t;
    a.render_scale = rc->scale;
    a.frame = rc->frame;
    a.window = rc->frame;
    a.first_frame = rc->first_frame;
    a.last_frame = rc->last_frame;
    a.inputs = &src;
    a.params = rc->fvalues;
    a.output = &slot->im;
    a.fetch = flow_fetch;
    a.fetch_user = rc;
    a.state = &inst->flow_state;
    if ((r = nprfx_node_render(&a))) {
        nprfx_image_free(&slot->im);
        return r;
    }
    slot->frame = t;
    slot->used = 1;
    *out = &slot->im;
    return NPRFX_OK;
}

/* Input k's channels of a flow, copied into dst. */
static nprfx_result derived_copy(render_call *rc, const nprfx_image *flow, int k, nprfx_image *dst)
{
    const ofx_derive_plan *p = &rc->inst->plan;
    nprfx_result r = nprfx_image_alloc(rc->ctx, flow->bounds, p->count[k], dst);
    if (r) return r;
    for (int y = flow->bounds.y0; y < flow->bounds.y1; y++)
        for (int x = flow->bounds.x0; x < flow->bounds.x1; x++) {
            const float *s = nprfx_image_at(flow, x, y);
            float *o = nprfx_image_at(dst, x, y);
            for (int c = 0; c < p->count[k]; c++)
                o[c] = s[p->idx[k][c]];
        }
    return NPRFX_OK;
}

/* The node's fetch when inputs are derived: a derived input from the flow at that frame, the
 * main input fed by Source from the host (or, without temporal access, the kept frame). */
static nprfx_result derive_fetch(void *user, int input, double time, nprfx_image *out)
{
    render_call *rc = user;
    ofx_instance *inst = rc->inst;
    const nprfx_node_desc *d = inst->desc;
    if (input < 0 || input >= d->num_inputs)
        return nprfx_error(rc->ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: no input %d", d->id, input);
    int t = round_frame(time);
    if (t == round_frame(rc->time) || !rc->inputs[input].data) return fetch_cb(user, input, t, out);
    if (!inst->plan.count[input]) {
        if (G.temporal) return fetch_cb(user, input, time, out);
        const nprfx_image *k = &inst->kept_src;
        if (inst->kept && inst->kept_frame == t &&
            (k->channels == rc->count[input] ||
             (k->channels == 4 && rc->first[input] + rc->count[input] <= 4))) {
            *out =
                nprfx_image_channels(k, k->channels == 4 ? rc->first[input] : 0, rc->count[input]);
            return NPRFX_OK;
        }
        return nprfx_error(rc->ctx, NPRFX_ERR_MISSING_INPUT,
                           "%s: input '%s' (the Source clip) at frame %d, while rendering frame "
                           "%d: this host gives no other frame (no temporal clip access)",
                           d->id, d->inputs[input].name, t, round_frame(rc->time));
    }
    pthread_mutex_lock(&rc->dlock);
    const nprfx_image *flow = NULL;
    nprfx_result r = flow_at(rc, t, &flow);
    if (!r) {
        nprfx_image *slot = &rc->dring[rc->ndring++ % RING];
        nprfx_image_free(slot);
        if (!(r = derived_copy(rc, flow, input, slot))) *out = *slot;
    }
    pthread_mutex_unlock(&rc->dlock);
    return r;
}

/* Without temporal clip access, whether frame t continues what the instance kept (the frame
 * after it, or the same again); anything else (the first render, a jump, a change of size or
 * params) restarts the effect at t as at a cut: the node's cache and the kept frames go, and
 * the node and the flow see a shot that starts at t, so its first frame has zero motion and
 * zero confidence and nothing from before the jump shows. Held: inst->lock. */
static void derive_continue(render_call *rc, int t)
{
    ofx_instance *inst = rc->inst;
    int follows = inst->kept && (inst->kept_frame == t || inst->kept_frame == t - 1) &&
                  nprfx_rect_equal(inst->kept_src.bounds, rc->src.bounds) &&
                  inst->kept_src.channels == rc->src.channels;
    if (!follows) {
        if (inst->state && inst->desc->state_free) inst->desc->state_free(inst->state);
        inst->state = NULL;
        ofx_instance_forget_footage(inst);
        inst->seg_start = t;
    }
    if (inst->seg_start > rc->first_frame) rc->first_frame = inst->seg_start;
}

/* After a render without temporal access: keep Source and the flow at t for the next frame. */
static nprfx_result derive_keep(render_call *rc, int t)
{
    ofx_instance *inst = rc->inst;
    if (inst->kept && inst->kept_frame == t) return NPRFX_OK;
    const nprfx_image *flow = NULL;
    nprfx_image src, fl;
    memset(&src, 0, sizeof src);
    memset(&fl, 0, sizeof fl);
    nprfx_result r = flow_at(rc, t, &flow);
    if (!r) r = nprfx_image_alloc(rc->ctx, rc->src.bounds, rc->src.channels, &src);
    if (!r) r = nprfx_image_copy(rc->ctx, &rc->src, &src);
    if (!r) r = nprfx_image_alloc(rc->ctx, flow->bounds, flow->channels, &fl);
    if (!r) r = nprfx_image_copy(rc->ctx, flow, &fl);
    if (r) {
        nprfx_image_free(&src);
        nprfx_image_free(&fl);
        return r;
    }
    nprfx_image_free(&inst->kept_src);
    nprfx_image_free(&inst->kept_flow);
    inst->kept_src = src;
    inst->kept_flow = fl;
    inst->kept_frame = t;
    inst->kept = 1;
    return NPRFX_OK;
}

static void derive_release(render_call *rc)
{
    for (int i = 0; i < FLOWS; i++)
        nprfx_image_free(&rc->flows[i].im);
    for (int i = 0; i < RING; i++)
        nprfx_image_free(&rc->dring[i]);
    for (int k = 0; k < NPRFX_OFX_DERIVE_MAX_INPUTS; k++)
        nprfx_image_free(&rc->dcur[k]);
    ofx_free(rc->src_scratch);
}

/* ---- output ---------------------------------------------------------------------------------- */

/* The host component values for a result pixel with n channels (see clip preferences). */
static void result_rgba(const float *px, int n, float rgba[4])
{
    switch (n) {
    case 1:
        rgba[0] = rgba[1] = rgba[2] = px[0], rgba[3] = 1.0f;
        break;
    case 2:
        rgba[0] = px[0], rgba[1] = px[1], rgba[2] = 0.0f, rgba[3] = 1.0f;
        break;
    case 3:
        rgba[0] = px[0], rgba[1] = px[1], rgba[2] = px[2], rgba[3] = 1.0f;
        break;
    case 4:
        memcpy(rgba, px, 4 * sizeof(float));
        break;
    default: /* more than a host image holds: the colour, and the last channel as alpha */
        rgba[0] = px[0], rgba[1] = px[1], rgba[2] = px[2], rgba[3] = px[n - 1];
        break;
    }
}

typedef struct finish_job {
    const ofx_img *out;
    const nprfx_image *res, *src, *mask;
    nprfx_rect window; /* nprfx coordinates, inside the frame */
    int f, nout, mask_invert;
    double mix;
} finish_job;

/* Mix with the Source by mix * Mask, then write the host components the result does not
 * already fill in place. Rows are independent, so this runs on the executor too. */
static void finish_rows(void *user, int begin, int end, int worker)
{
    (void)worker;
    const finish_job *j = user;
    const int ncomp = j->out->ncomp;
    for (int y = j->window.y0 + begin; y < j->window.y0 + end; y++)
        for (int x = j->window.x0; x < j->window.x1; x++) {
            float *px = nprfx_image_at(j->res, x, y);
            if (j->mask || j->mix != 1.0) {
                double m = j->mix;
                if (j->mask) {
                    double mv = nprfx_rect_contains(j->mask->bounds, x, y)
                                    ? nprfx_image_at(j->mask, x, y)[0]
                                    : 0.0;
                    mv = mv > 0.0 ? (mv < 1.0 ? mv : 1.0) : 0.0;
                    m *= j->mask_invert ? 1.0 - mv : mv;
                }
                int nc = j->src && j->src->channels < j->nout ? j->src->channels : j->nout;
                const float *s = j->src && nprfx_rect_contains(j->src->bounds, x, y)
                                     ? nprfx_image_at(j->src, x, y)
                                     : NULL;
                for (int c = 0; j->src && c < nc; c++) {
                    double sv = s ? s[c] : 0.0;
                    px[c] = (float)(sv + ((double)px[c] - sv) * m);
                }
            }
            float rgba[4];
            result_rgba(px, j->nout, rgba);
            int yu = j->f - y;
            if (ncomp == 1)
                img_store(j->out, x, yu, 0, j->nout >= 4 ? rgba[3] : px[0]);
            else
                for (int c = 0; c < ncomp; c++)
                    img_store(j->out, x, yu, c, rgba[c]);
        }
}

/* ---- render ---------------------------------------------------------------------------------- */

static OfxRectI to_pixels(OfxRectD r, double sx, double sy, double par)
{
    OfxRectI p;
    p.x1 = (int)floor(r.x1 * sx / par + 1e-9);
    p.y1 = (int)floor(r.y1 * sy + 1e-9);
    p.x2 = (int)ceil(r.x2 * sx / par - 1e-9);
    p.y2 = (int)ceil(r.y2 * sy - 1e-9);
    return p;
}

OfxStatus ofx_render(ofx_instance *inst, OfxPropertySetHandle in_args)
{
    const nprfx_node_desc *d = inst->desc;
    const OfxPropertySuiteV1 *ps = G.prop;
    double time = 0, scale[2] = {1, 1};
    int win[4] = {0, 0, 0, 0};
    if (ps->propGetDouble(in_args, kOfxPropTime, 0, &time) != kOfxStatOK ||
        ps->propGetIntN(in_args, kOfxImageEffectPropRenderWindow, 4, win) != kOfxStatOK)
        return kOfxStatErrBadHandle;
    if (ps->propGetDoubleN(in_args, kOfxImageEffectPropRenderScale, 2, scale) != kOfxStatOK ||
        !(scale[0] > 0))
        scale[0] = scale[1] = 1;
    if (!(scale[1] > 0)) scale[1] = scale[0];

    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.executor = &host_executor;
    ci.data_dir = ofx_g.data_dir[0] ? ofx_g.data_dir : NULL;
    ci.flow = nprfx_flow_opencv(); /* the flow node's solver; NULL without OpenCV */
    render_call rc;
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
    if (G.fx->clipGetPropertySet(inst->output, &op) != kOfxStatOK ||
        ps->propGetDouble(op, kOfxImagePropPixelAspectRatio, 0, &par) != kOfxStatOK || !(par > 0))
        par = 1;
    OfxRectI fr = to_pixels(rod, scale[0], scale[1], par);
    rc.f = fr.y1 + fr.y2 - 1;
    nprfx_rect frame = flip_rect(fr, rc.f);
    OfxRectI wr = {win[0], win[1], win[2], win[3]};
    nprfx_rect host_window = flip_rect(wr, rc.f);

    if ((r = ofx_eval_params(inst, rc.ctx, time, 0, values, strings))) goto done;
    nprfx_node_apply_render_scale(d, values, scale[0]);

    for (int k = 0; k < d->num_inputs; k++) {
        if (!ofx_clip_connected(inst->clips[k])) continue;
        if (inst->derive && inst->plan.count[k]) continue; /* below */
        ofx_input_selection(inst, k, time, 0, &rc.first[k], &rc.count[k]);
        OfxStatus st = img_fetch(inst->clips[k], time, 1, &rc.cur[k].img);
        if (st == kOfxStatFailed) continue; /* no image at this time: as if not connected */
        if (st != kOfxStatOK) {
            r = nprfx_error(rc.ctx, NPRFX_ERR_MISSING_INPUT,
                            "%s: the host gave no usable image of input '%s' (OFX status %d)",
                            d->id, d->inputs[k].name, st);
            status = st;
            goto done;
        }
        if ((r = img_view(&rc.cur[k].img, input_flip(&rc, k, &rc.cur[k].img), rc.first[k],
                          rc.count[k], &rc.inputs[k], &rc.cur[k].scratch))) {
            status = kOfxStatErrMemory;
            goto done;
        }
        in_ch[k] = rc.count[k];
    }

    double first = 0, last = 0;
    ofx_shot_range(inst, &first, &last);
    rc.first_frame = round_frame(first);
    rc.last_frame = round_frame(last);
    /* A stateful node's cache, and the flow's and the kept frames of footage, are shared by the
     * renders of the instance. */
    if ((d->flags & NPRFX_NODE_STATEFUL) || inst->derive) {
        pthread_mutex_lock(&inst->lock);
        locked = 1;
    }
    if (inst->derive) {
        /* Footage: the derived inputs from the flow node run on Source (ofx_derive.c). */
        int main = nprfx_ofx_main_input(d);
        if (!ofx_clip_connected(inst->clips[main])) {
            r = nprfx_error(rc.ctx, NPRFX_ERR_MISSING_INPUT,
                            "%s: the Source clip is not connected: it is the footage this effect "
                            "computes its motion from",
                            d->id);
            goto done;
        }
        OfxStatus st = kOfxStatOK;
        if (!rc.cur[main].img.h) st = img_fetch(inst->clips[main], time, 1, &rc.cur[main].img);
        if (st != kOfxStatOK) {
            r = nprfx_error(rc.ctx, NPRFX_ERR_MISSING_INPUT,
                            "%s: the host gave no image of the Source clip at frame %g (OFX "
                            "status %d)",
                            d->id, time, st);
            status = st == kOfxStatErrMemory ? st : kOfxStatFailed;
            goto done;
        }
        const ofx_img *si = &rc.cur[main].img;
        if ((r = img_view(si, input_flip(&rc, main, si), 0, si->ncomp, &rc.src, &rc.src_scratch))) {
            status = kOfxStatErrMemory;
            goto done;
        }
        memcpy(rc.fvalues, inst->plan.values, sizeof rc.fvalues);
        nprfx_node_apply_render_scale(inst->plan.flow, rc.fvalues, scale[0]);
        rc.scale = scale[0];
        rc.frame = frame;
        if (!G.temporal) derive_continue(&rc, round_frame(time));
        const nprfx_image *flow = NULL;
        pthread_mutex_lock(&rc.dlock);
        r = flow_at(&rc, round_frame(time), &flow);
        for (int k = 0; !r && k < d->num_inputs; k++)
            if (inst->plan.count[k] && !(r = derived_copy(&rc, flow, k, &rc.dcur[k]))) {
                rc.inputs[k] = rc.dcur[k];
                in_ch[k] = rc.count[k] = inst->plan.count[k];
            }
        pthread_mutex_unlock(&rc.dlock);
        if (r) goto done;
    }

    nprfx_output_info oi;
    if ((r = nprfx_node_output_info(rc.ctx, d, values, in_ch, &oi))) goto done;
    int nout = oi.channels;
    OfxStatus st = img_fetch(inst->output, time, 0, &out);
    if (st != kOfxStatOK) {
        r = nprfx_error(rc.ctx, NPRFX_ERR_INTERNAL, "%s: the host gave no output image (%d)", d->id,
                        st);
        status = st;
        goto done;
    }
    host_window = nprfx_rect_intersect(host_window, flip_rect(out.b, rc.f));
    nprfx_rect window = nprfx_rect_intersect(host_window, frame);
    /* The result: in place where the host image holds the first nout components in order,
     * else in a scratch image covering the window. */
    if (out.bytes == 4 && (out.ncomp == 4 || out.ncomp == 3) && nout <= out.ncomp &&
        !nprfx_rect_empty(window)) {
        if ((r = img_view(&out, rc.f, 0, nout, &res, &res_scratch))) goto done;
    } else if (!nprfx_rect_empty(window)) {
        if ((r = nprfx_image_alloc(rc.ctx, window, nout, &res))) goto done;
        res_owned = 1;
    }

    int main = nprfx_ofx_main_input(d);
    finish_job fj;
    memset(&fj, 0, sizeof fj);
    fj.out = &out;
    fj.res = &res;
    fj.window = window;
    fj.f = rc.f;
    fj.nout = nout;
    fj.mix = 1.0;
    if (inst->mix) {
        double mix = 1.0;
        int inv = 0;
        if (G.param->paramGetValueAtTime(inst->mix, time, &mix) == kOfxStatOK) fj.mix = mix;
        if (inst->mask_invert &&
            G.param->paramGetValueAtTime(inst->mask_invert, time, &inv) == kOfxStatOK)
            fj.mask_invert = inv != 0;
        if (ofx_clip_connected(inst->mask) && img_fetch(inst->mask, time, 1, &mask) == kOfxStatOK) {
            if ((r = img_view(&mask, rc.f, mask.ncomp == 4 ? 3 : 0, 1, &mask_view, &mask_scratch)))
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
        a.render_scale = scale[0];
        a.frame = frame;
        a.window = window;
        a.first_frame = rc.first_frame;
        a.last_frame = rc.last_frame;
        a.inputs = rc.inputs;
        a.params = values;
        a.output = &res;
        /* Without temporal access the host would answer with the current frame: no fetch, and
         * a node that needs another frame says so. */
        a.fetch = inst->derive ? derive_fetch : G.temporal ? fetch_cb : NULL;
        a.fetch_user = &rc;
        a.state = &inst->state;
        r = nprfx_node_render(&a);
        if (!r && inst->derive && !G.temporal) r = derive_keep(&rc, round_frame(time));
        if (locked) pthread_mutex_unlock(&inst->lock);
        locked = 0;
        if (r) goto done;
        nprfx_parallel_for(&host_executor, nprfx_rect_height(window), 16, finish_rows, &fj);
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
                    img_store(&out, x, rc.f - y, c, 0.0f);
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
    derive_release(&rc);
    for (int i = 0; i < RING; i++)
        fetched_release(&rc.ring[i]);
    for (int k = 0; rc.cur && k < d->num_inputs; k++)
        fetched_release(&rc.cur[k]);
    img_release(&mask);
    ofx_free(mask_scratch);
    ofx_free(res_scratch);
    if (res_owned) nprfx_image_free(&res);
    img_release(&out);
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
