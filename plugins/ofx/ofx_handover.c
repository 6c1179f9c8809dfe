/* nprfx OpenFX adapter — what a footage instance keeps between renders, handed to the next
 * instance of the same effect (declared in ofx_handover.h). A host without temporal clip access
 * that makes a new instance for every frame (melt: Shotcut, Kdenlive) would otherwise restart
 * the effect at every frame, as at a cut: each frame a different answer, silently. An instance
 * destroyed while it keeps a frame leaves what it kept here; a fresh instance whose first frame
 * follows it takes it back. Several effects of one look in one process are told apart by their
 * params and Source's size; two that agree in both are refused, with the reason, rather than
 * mixed. A few are held at a time, and freed when the host unloads the bundle. */
#include <pthread.h>
#include <stdint.h>
#include <string.h>

#include "ofx_handover.h"

#define HANDOVER_SLOTS 8

typedef struct handover {
    int used;
    unsigned long long key, age;
    const nprfx_node_desc *desc, *flow;
    int kept_frame, seg_start;
    unsigned long long src_hash; /* the kept Source frame's pixels */
    nprfx_image kept_src, kept_flow;
    void *state, *flow_state;
} handover;

static handover slots[HANDOVER_SLOTS];
static unsigned long long ages;
static pthread_mutex_t slots_lock = PTHREAD_MUTEX_INITIALIZER;

static void slot_free(handover *h)
{
    nprfx_image_free(&h->kept_src);
    nprfx_image_free(&h->kept_flow);
    if (h->state && h->desc && h->desc->state_free) h->desc->state_free(h->state);
    if (h->flow_state && h->flow && h->flow->state_free) h->flow->state_free(h->flow_state);
    memset(h, 0, sizeof *h);
}

static unsigned long long mix(unsigned long long h, const void *p, size_t n)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++)
        h = (h ^ b[i]) * 1099511628211ull;
    return h;
}

/* A Source frame's pixels, to know the same frame of the same footage again. */
static unsigned long long pixels_hash(const nprfx_image *im)
{
    unsigned long long h = 1469598103934665603ull;
    for (int y = im->bounds.y0; im->data && y < im->bounds.y1; y++)
        for (int x = im->bounds.x0; x < im->bounds.x1; x++)
            h = mix(h, nprfx_image_at(im, x, y), sizeof(float) * (size_t)im->channels);
    return h;
}

unsigned long long ofx_handover_key(const nprfx_node_desc *d, const nprfx_value *values,
                                    const nprfx_image *src)
{
    unsigned long long h = 1469598103934665603ull;
    h = mix(h, d->id, strlen(d->id));
    for (int i = 0; i < d->num_params; i++) {
        h = mix(h, values[i].v, sizeof values[i].v);
        if (d->params[i].type == NPRFX_PARAM_STRING && values[i].s)
            h = mix(h, values[i].s, strlen(values[i].s));
    }
    h = mix(h, &src->bounds, sizeof src->bounds);
    return mix(h, &src->channels, sizeof src->channels);
}

void ofx_handover_leave(ofx_instance *inst)
{
    if (!inst->kept || !inst->footage_key) return;
    pthread_mutex_lock(&slots_lock);
    handover *h = NULL;
    for (int i = 0; i < HANDOVER_SLOTS && !h; i++)
        if (!slots[i].used) h = &slots[i];
    if (!h) { /* full: the oldest goes */
        h = &slots[0];
        for (int i = 1; i < HANDOVER_SLOTS; i++)
            if (slots[i].age < h->age) h = &slots[i];
        slot_free(h);
    }
    h->used = 1;
    h->age = ++ages;
    h->key = inst->footage_key;
    h->desc = inst->desc;
    h->flow = inst->plan.flow;
    h->kept_frame = inst->kept_frame;
    h->seg_start = inst->seg_start;
    h->src_hash = pixels_hash(&inst->kept_src);
    h->kept_src = inst->kept_src;
    h->kept_flow = inst->kept_flow;
    h->state = inst->state;
    h->flow_state = inst->flow_state;
    memset(&inst->kept_src, 0, sizeof inst->kept_src);
    memset(&inst->kept_flow, 0, sizeof inst->kept_flow);
    inst->state = inst->flow_state = NULL;
    inst->kept = 0;
    pthread_mutex_unlock(&slots_lock);
}

int ofx_handover_take(ofx_instance *inst, unsigned long long key, int t, const nprfx_image *src)
{
    pthread_mutex_lock(&slots_lock);
    /* The same frame again (a host re-rendering it) is known by its pixels: the footage's own.
     * The frame after is known only by the key: more than one such is ambiguous. */
    int found = -1, count = 0, have_hash = 0;
    unsigned long long sh = 0;
    for (int i = 0; i < HANDOVER_SLOTS && found < 0; i++) {
        const handover *h = &slots[i];
        if (!h->used || h->desc != inst->desc || h->key != key || h->kept_frame != t) continue;
        if (!have_hash) sh = pixels_hash(src), have_hash = 1;
        if (h->src_hash == sh) found = i, count = 1;
    }
    if (found < 0)
        for (int i = 0; i < HANDOVER_SLOTS; i++)
            if (slots[i].used && slots[i].desc == inst->desc && slots[i].key == key &&
                slots[i].kept_frame == t - 1) {
                found = i;
                count++;
            }
    if (count == 1) {
        handover *h = &slots[found];
        if (inst->state && inst->desc->state_free) inst->desc->state_free(inst->state);
        ofx_instance_forget_footage(inst);
        inst->kept_src = h->kept_src;
        inst->kept_flow = h->kept_flow;
        inst->kept_frame = h->kept_frame;
        inst->seg_start = h->seg_start;
        inst->state = h->state;
        inst->flow_state = h->flow_state;
        inst->kept = 1;
        memset(h, 0, sizeof *h);
    }
    pthread_mutex_unlock(&slots_lock);
    return count;
}

#if defined(__GNUC__)
__attribute__((destructor))
#endif
static void
handover_free_all(void)
{
    for (int i = 0; i < HANDOVER_SLOTS; i++)
        if (slots[i].used) slot_free(&slots[i]);
}
