/* nprfx OpenFX adapter — inputs derived from the Source clip with the flow node: coherent-noise
 * and advect applied to plain footage in a Filter context (Shotcut and Kdenlive through MLT, or
 * any host's Filter context) get the motion and confidence they take from the flow node run on
 * Source inside the plug-in, as `nprfx run` gets them from a flow node connected in a graph.
 *
 * Which inputs: those whose AOV hint names flow output channels (ofx_derive.h). Which flow
 * params: the flow node's defaults, with its output choice narrowed to the fewest channels that
 * cover the inputs' first alternatives the host can serve; a host without temporal clip access
 * can serve only flows to the previous frame, which the plug-in keeps (ofx_footage.c). This file
 * plans that and says which Source frames a render reads; ofx_footage.c computes it. */
#include <stdlib.h>
#include <string.h>

#include "ofx_derive.h"
#include "ofx_names.h"
#include "ofx_suites.h"

/* Whether flow params `v` read only the frame and the one before (what an in-order host without
 * temporal clip access lets the plug-in keep), asked of the flow node itself. */
static int served_without_temporal(const nprfx_node_desc *f, const nprfx_value *v)
{
    int ich[1] = {4};
    nprfx_frames_query q = {1000, 0, 2000, ich};
    nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES];
    int n = 0;
    if (nprfx_node_frames_needed(NULL, f, v, &q, 0, r, &n) != NPRFX_OK) return 0;
    for (int i = 0; i < n; i++)
        if (r[i].first < q.time - 1 || r[i].last > q.time) return 0;
    return 1;
}

/* The flow configurations tried: its defaults, then each option of each choice param in turn
 * (the output choice among them; nothing here names it). Candidate c into v; 0 past the last. */
static int candidate(const nprfx_node_desc *f, int c, nprfx_value *v)
{
    nprfx_node_defaults(f, v);
    if (c == 0) return 1;
    c--;
    for (int i = 0; i < f->num_params; i++) {
        const nprfx_param_desc *p = &f->params[i];
        if (p->type != NPRFX_PARAM_CHOICE) continue;
        int n = 0;
        while (p->choices && p->choices[n])
            n++;
        if (c < n) {
            v[i].v[0] = c;
            return 1;
        }
        c -= n;
    }
    return 0;
}

static int outputs(const nprfx_node_desc *f, const nprfx_value *v, nprfx_output_info *oi)
{
    int ich[1] = {4};
    return nprfx_node_output_info(NULL, f, v, ich, oi) == NPRFX_OK;
}

int ofx_derive_make_plan(const nprfx_node_desc *d, int temporal, ofx_derive_plan *plan)
{
    memset(plan, 0, sizeof *plan);
    const nprfx_node_desc *f = ofx_flow_node();
    if (!f || !ofx_g.flow || d == f || d->num_inputs > NPRFX_OFX_DERIVE_MAX_INPUTS) return 0;
    /* Per input, the first alternative of its hint some servable configuration outputs: the
     * runner's choice against a flow node's whole output where every configuration is
     * servable (temporal access), else the first one that needs no later frame. */
    const char *want[NPRFX_OFX_DERIVE_MAX_INPUTS][4];
    int nwant[NPRFX_OFX_DERIVE_MAX_INPUTS] = {0};
    nprfx_value v[NPRFX_OFX_DERIVE_MAX_PARAMS];
    nprfx_output_info oi;
    int idx[4];
    for (int k = 0; k < d->num_inputs; k++) {
        if (!ofx_derivable(d, k)) continue;
        for (int alt = 0; !nwant[k]; alt++) {
            int n = 0, more = 0;
            for (int c = 0; candidate(f, c, v) && n <= 0; c++) {
                if (!outputs(f, v, &oi)) continue;
                n = ofx_aov_match(&d->inputs[k], alt, &oi, idx);
                if (n >= 0) more = 1;
                if (n > 0 && !temporal && !served_without_temporal(f, v)) n = 0;
                for (int j = 0; j < n; j++)
                    want[k][j] = oi.names[idx[j]];
            }
            if (n > 0) nwant[k] = n;
            if (!more) break; /* no alternative left */
        }
    }
    /* The servable configuration with the fewest channels that outputs them all. */
    int best = -1, best_ch = 0;
    for (int c = 0; candidate(f, c, v); c++) {
        if (!outputs(f, v, &oi) || (!temporal && !served_without_temporal(f, v))) continue;
        int covers = 1;
        for (int k = 0; k < d->num_inputs && covers; k++)
            for (int j = 0; j < nwant[k] && covers; j++) {
                int found = 0;
                for (int i = 0; i < oi.channels && !found; i++)
                    found = oi.names[i] && !strcmp(oi.names[i], want[k][j]);
                covers = found;
            }
        if (covers && (best < 0 || oi.channels < best_ch)) best = c, best_ch = oi.channels;
    }
    if (best < 0) return 0;
    candidate(f, best, plan->values);
    outputs(f, plan->values, &oi);
    plan->flow = f;
    plan->channels = oi.channels;
    int any = 0, complete = 1, main = ofx_names_main_input(d);
    for (int k = 0; k < d->num_inputs; k++) {
        for (int j = 0; j < nwant[k]; j++)
            for (int i = 0; i < oi.channels; i++)
                if (oi.names[i] && !strcmp(oi.names[i], want[k][j])) plan->idx[k][j] = i;
        plan->count[k] = nwant[k];
        any |= nwant[k] > 0;
        /* Source feeds the main input when that is not derived; any other required input must
         * be derived, as the Filter context has no clip for it. */
        if (!nwant[k] && k != main && !(d->inputs[k].flags & NPRFX_INPUT_OPTIONAL)) complete = 0;
    }
    plan->any = any && complete;
    if (!plan->any) memset(plan, 0, sizeof *plan);
    return plan->any;
}

/* Add [a, b] to the sorted, merged list r of n ranges; returns the new count. A list already
 * full merges the new range into its nearest neighbour (a wider declaration, never a narrower
 * one). */
static int add_range(nprfx_frame_range *r, int n, int a, int b)
{
    nprfx_frame_range all[NPRFX_MAX_FRAME_RANGES + 1];
    int m = 0, placed = 0;
    for (int i = 0; i <= n; i++) {
        nprfx_frame_range x;
        if (i < n && (placed || r[i].first <= a)) {
            x = r[i];
        } else if (!placed) {
            x.first = a, x.last = b;
            placed = 1;
            i--;
        } else {
            break;
        }
        if (m && x.first <= all[m - 1].last + 1) {
            if (x.last > all[m - 1].last) all[m - 1].last = x.last;
        } else {
            all[m++] = x;
        }
    }
    while (m > NPRFX_MAX_FRAME_RANGES) { /* join the closest pair */
        int j = 0;
        for (int i = 1; i + 1 < m; i++)
            if (all[i + 1].first - all[i].last < all[j + 1].first - all[j].last) j = i;
        all[j].last = all[j + 1].last;
        memmove(&all[j + 1], &all[j + 2], (size_t)(m - j - 2) * sizeof all[0]);
        m--;
    }
    memcpy(r, all, (size_t)m * sizeof all[0]);
    return m;
}

int ofx_derive_frames(const nprfx_node_desc *d, const ofx_derive_plan *plan,
                      const nprfx_value *values, const nprfx_frames_query *q, int main_fed,
                      nprfx_frame_range *r)
{
    int n = 0, main = ofx_names_main_input(d);
    int src_ch[1] = {4};
    for (int k = 0; k < d->num_inputs; k++) {
        nprfx_frame_range nr[NPRFX_MAX_FRAME_RANGES];
        int m = 0;
        int fed = plan->count[k] > 0 || (k == main && main_fed);
        if (!fed || nprfx_node_frames_needed(NULL, d, values, q, k, nr, &m) != NPRFX_OK) continue;
        for (int i = 0; i < m; i++) {
            if (!plan->count[k]) { /* the main input itself, read from Source */
                n = add_range(r, n, nr[i].first, nr[i].last);
                continue;
            }
            /* The flow at a frame reads a span around it; over [first, last] that is the span
             * at first widened to the one at last. */
            nprfx_frame_range fa[NPRFX_MAX_FRAME_RANGES], fb[NPRFX_MAX_FRAME_RANGES];
            int na = 0, nb = 0;
            nprfx_frames_query qa = {nr[i].first, q->first_frame, q->last_frame, src_ch};
            nprfx_frames_query qb = {nr[i].last, q->first_frame, q->last_frame, src_ch};
            if (nprfx_node_frames_needed(NULL, plan->flow, plan->values, &qa, 0, fa, &na) ||
                nprfx_node_frames_needed(NULL, plan->flow, plan->values, &qb, 0, fb, &nb) || !na ||
                !nb)
                continue;
            n = add_range(r, n, fa[0].first, fb[nb - 1].last);
        }
    }
    return n;
}
