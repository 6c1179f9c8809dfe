/* The stipple node over its render arguments: its bound params into core's (the pen tones
 * parsed), the per-instance cache (the dot sequence, which keeps the tone-correction curves)
 * in the instance slot, then nprfx_stipple_draw or nprfx_stipple_collect. No file I/O: the
 * params' make_sequence, which the descriptor fills, brings a shipped sequence. See
 * nprfx/stipple.h. */
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/node.h"
#include "nprfx/stipple.h"

/* ---- the per-instance cache: the dot sequence (which keeps the tone-correction curves) ---- */

typedef struct node_state {
    nprfx_stipple_sequence *seq; /* grown on demand, thread-safe on its own; may be shared */
} node_state;

void nprfx_stipple_state_free(void *state)
{
    node_state *s = state;
    if (!s) return;
    nprfx_stipple_sequence_destroy(s->seq);
    free(s);
}

/* The instance state, created on first use; NULL when the caller gives no state slot (then
 * each call builds what it needs). Hosts may render tiles of one instance on several threads
 * at once: a fresh state is installed with a compare-and-swap, the loser frees its own. */
static nprfx_result get_state(const nprfx_render_args *args,
                              nprfx_stipple_sequence_fn make_sequence, node_state **out)
{
    *out = NULL;
    if (!args->state) return NPRFX_OK;
    _Atomic(void *) *slot = (_Atomic(void *) *)args->state;
    node_state *s = atomic_load(slot);
    if (!s) {
        node_state *fresh = calloc(1, sizeof *fresh);
        if (!fresh)
            return nprfx_error(args->ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory");
        nprfx_result r = make_sequence ? make_sequence(args->ctx, &fresh->seq)
                                       : nprfx_stipple_sequence_create(args->ctx, &fresh->seq);
        if (r != NPRFX_OK) {
            nprfx_stipple_sequence_destroy(fresh->seq);
            free(fresh);
            return r;
        }
        void *expected = NULL;
        if (atomic_compare_exchange_strong(slot, &expected, fresh)) {
            s = fresh;
        } else {
            nprfx_stipple_state_free(fresh);
            s = expected;
        }
    }
    *out = s;
    return NPRFX_OK;
}

/* ---- node params to core params ---- */

/* Core params for the node's (the render scale is already applied to the areas): the bound ones
 * completed with what the node derives, the instance's sequence and the tone curve when the
 * params ask for it (curve: the caller's storage). */
static nprfx_result core_params(const nprfx_render_args *args, const nprfx_stipple_node_params *np,
                                nprfx_stipple_params *p, float *curve)
{
    nprfx_stipple_params def;
    nprfx_stipple_params_default(&def);
    *p = np->stipple;
    p->size = sizeof *p;
    p->num_tones = def.num_tones; /* the default pens until multitone parses the node's */
    memcpy(p->tones, def.tones, sizeof p->tones);
    p->tone_curve = NULL;
    p->sequence = NULL;
    p->count = NULL;
    double scale = args->render_scale > 0 ? args->render_scale : 1.0;
    p->plane_scale = NPRFX_STIPPLE_PLANE_PIXELS * scale;
    for (int c = 0; c < 4; c++) {
        p->ink[c] = (float)np->ink[c];
        p->paper[c] = (float)np->paper[c];
    }
    p->seed = (uint64_t)np->seed;
    p->coverage_channel = p->coverage_channel != 0;
    nprfx_result r = NPRFX_OK;
    if (p->mode == NPRFX_STIPPLE_MULTITONE) r = nprfx_stipple_parse_tones(args->ctx, np->tones, p);
    node_state *s = NULL;
    if (r == NPRFX_OK) r = get_state(args, np->make_sequence, &s);
    if (r != NPRFX_OK) return r;
    p->sequence = s ? s->seq : NULL;
    if (np->tone_correction) {
        r = nprfx_stipple_sequence_tone_curve(args->ctx, s ? s->seq : NULL, p, curve);
        p->tone_curve = curve;
    }
    return r;
}

static nprfx_stipple_inputs node_inputs(const nprfx_render_args *args)
{
    nprfx_stipple_inputs in;
    in.tone = &args->inputs[NPRFX_STIPPLE_IN_TONE];
    in.uv = nprfx_render_input(args, NPRFX_STIPPLE_IN_UV);
    in.id = nprfx_render_input(args, NPRFX_STIPPLE_IN_ID);
    in.frame = args->frame;
    return in;
}

nprfx_result nprfx_stipple_render(const nprfx_render_args *args,
                                  const nprfx_stipple_node_params *np)
{
    if (!args || !np || !args->inputs || !args->output)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple: incomplete render arguments");
    nprfx_stipple_params p;
    float curve[NPRFX_STIPPLE_CURVE_SIZE];
    nprfx_result r = core_params(args, np, &p, curve);
    if (r != NPRFX_OK) return r;
    nprfx_stipple_inputs in = node_inputs(args);
    p.count = args->items;
    return nprfx_stipple_draw(args->ctx, &p, &in, args->window, args->output);
}

nprfx_result nprfx_stipple_node_collect(const nprfx_render_args *args,
                                        const nprfx_stipple_node_params *np, nprfx_stipple **list,
                                        size_t *count)
{
    if (!args || !np || !args->inputs)
        return nprfx_error(args ? args->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "stipple: incomplete render arguments");
    nprfx_stipple_params p;
    float curve[NPRFX_STIPPLE_CURVE_SIZE];
    nprfx_result r = core_params(args, np, &p, curve);
    if (r != NPRFX_OK) return r;
    nprfx_stipple_inputs in = node_inputs(args);
    return nprfx_stipple_collect(args->ctx, &p, &in, args->frame, list, count);
}
