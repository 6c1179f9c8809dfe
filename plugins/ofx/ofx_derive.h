/* nprfx OpenFX adapter — inputs of a node derived from the Source clip with the flow node, so
 * that coherent-noise and advect work on plain footage in the Filter context (one clip, no
 * hand-wired flow; docs/design.md "OpenFX", "Footage in a Filter context").
 *
 * The inline half says which inputs are derivable: those with an alternative of their AOV hint
 * that names channels the flow node outputs, the same rule the runner applies when a graph
 * connects the input to a flow node, so nothing here lists a node's inputs or the flow's channels
 * a second time. The adapter (plugins/ofx/) and the test host (tests/ofxhost/) include this one
 * header, as they do ofx_names.h. The declared half is the adapter's plan of how it derives them
 * in a given host (ofx_derive.c); the test host does not use it. */
#ifndef NPRFX_OFX_DERIVE_H
#define NPRFX_OFX_DERIVE_H

#include <string.h>

#include "nprfx/channels.h"

#include "nprfx/node.h"

/* The node whose output derived inputs come from. */
#define NPRFX_OFX_FLOW_NODE "flow"
/* Bounds of the fixed arrays that hold the flow node's param values and a node's inputs. */
#define NPRFX_OFX_DERIVE_MAX_PARAMS 32
#define NPRFX_OFX_DERIVE_MAX_INPUTS 16

/* The flow node's descriptor; NULL where the registry has none of a shape these arrays hold. */
static inline const nprfx_node_desc *ofx_flow_node(void)
{
    const nprfx_node_desc *f = nprfx_node_find(NPRFX_OFX_FLOW_NODE);
    return f && f->num_inputs == 1 && f->num_params <= NPRFX_OFX_DERIVE_MAX_PARAMS ? f : NULL;
}

/* Alternative `alt` (0-based, '|'-separated) of the input's AOV hint as channels of an output
 * whose channel names `src` gives: their indices into idx (at most 4), and how many. 0 when the
 * alternative names a channel src lacks, is a layer form (no channel of that exact name), or has
 * another count than the input takes; -1 when the hint has no alternative `alt`. */
static inline int ofx_aov_match(const nprfx_input_desc *in, int alt, const nprfx_output_info *src,
                                int *idx)
{
    const char *s = in->aov;
    for (int i = 0; s && i < alt; i++)
        if ((s = strchr(s, '|'))) s++;
    if (!s) return -1;
    const char *end = strchr(s, '|');
    if (!end) end = s + strlen(s);
    /* the alternative as a channel selection (exact names, or a layer: "motion_prev") */
    char sel[256], bad[64];
    size_t len = (size_t)(end - s);
    if (len >= sizeof sel) return 0;
    memcpy(sel, s, len);
    sel[len] = 0;
    const char *names[NPRFX_MAX_CHANNELS];
    int nc = src->channels < NPRFX_MAX_CHANNELS ? src->channels : NPRFX_MAX_CHANNELS, amb = 0;
    for (int j = 0; j < nc; j++)
        names[j] = src->names[j] ? src->names[j] : "";
    int n = nprfx_channels_select(names, nc, sel, idx, 4, bad, sizeof bad, &amb);
    if (n < 0) return 0;
    if (!n || (in->channels > 0 && n != in->channels)) return 0;
    return n;
}

/* Whether input k of d names channels of the flow node's whole output (its default params).
 * Whether the adapter derives it in a given host also depends on that host (ofx_derive.c: the
 * flow provider, temporal clip access). */
static inline int ofx_derivable(const nprfx_node_desc *d, int k)
{
    const nprfx_node_desc *f = ofx_flow_node();
    if (!f || d == f || k < 0 || k >= d->num_inputs || !d->inputs[k].aov) return 0;
    nprfx_value v[NPRFX_OFX_DERIVE_MAX_PARAMS];
    int ich[1] = {4}, idx[4];
    nprfx_output_info oi;
    nprfx_node_defaults(f, v);
    if (nprfx_node_output_info(NULL, f, v, ich, &oi) != NPRFX_OK) return 0;
    for (int alt = 0;; alt++) {
        int n = ofx_aov_match(&d->inputs[k], alt, &oi, idx);
        if (n) return n > 0;
    }
}

/* How a node's inputs are derived from the Source clip with the flow node (ofx_derive.c): the
 * flow's param values (its defaults, with the output choice that covers what the inputs take and
 * that the host can serve), how many channels it then outputs, and per input the flow channels
 * it takes (count 0: not derived). */
typedef struct ofx_derive_plan {
    const nprfx_node_desc *flow;
    nprfx_value values[NPRFX_OFX_DERIVE_MAX_PARAMS];
    int channels;
    int count[NPRFX_OFX_DERIVE_MAX_INPUTS];
    int idx[NPRFX_OFX_DERIVE_MAX_INPUTS][4];
    int any; /* some input is derived and every required one is (or is the main input) */
} ofx_derive_plan;

/* The plan for node d in a host with (1) or without (0) temporal clip access; returns plan->any.
 * Without a flow provider (ofx_g.flow), or for a node without derivable inputs, nothing is
 * derived. */
int ofx_derive_make_plan(const nprfx_node_desc *d, int temporal, ofx_derive_plan *plan);

/* The frames of the Source clip a derived render of q->time reads: the frames the node reads its
 * derived inputs at, each widened by the frames the flow node reads to compute it, and the
 * frames it reads the main input at when Source feeds that too (main_fed). Up to
 * NPRFX_MAX_FRAME_RANGES merged ranges into r; returns how many. */
int ofx_derive_frames(const nprfx_node_desc *d, const ofx_derive_plan *plan,
                      const nprfx_value *values, const nprfx_frames_query *q, int main_fed,
                      nprfx_frame_range *r);

#endif
