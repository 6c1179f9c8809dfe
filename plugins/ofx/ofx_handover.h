/* nprfx OpenFX adapter — a footage instance's kept frames handed to the next instance of the
 * same effect, for hosts that make one instance per frame (ofx_handover.c). */
#ifndef NPRFX_OFX_HANDOVER_H
#define NPRFX_OFX_HANDOVER_H

#include "ofx_instance.h"

/* What tells one effect's instances from another's: the node, its params, Source's size and
 * components (0 is never a key). */
unsigned long long ofx_handover_key(const nprfx_node_desc *d, const nprfx_value *values,
                                    const nprfx_image *src);

/* An instance that goes (destroy) leaves what it keeps (the last Source frame, its flow, the
 * node's and the flow's state), under inst->footage_key; the instance keeps nothing after. */
void ofx_handover_leave(ofx_instance *inst);

/* A fresh instance about to render frame t (its Source src) takes what another of the same key
 * left: at t with the same Source pixels (a frame rendered again), else at t - 1. Returns how
 * many were left so: 1 taken, 0 none (the effect starts at t), more: the effects cannot be told
 * apart, none taken (the caller refuses). */
int ofx_handover_take(ofx_instance *inst, unsigned long long key, int t, const nprfx_image *src);

#endif
