/* nprfx graph engine — what a graph's plates are (graph_aovs.c): profiles, conventions, decoded
 * ids and fallbacks, settled from the first frame before anything renders. Never installed. */
#ifndef NPRFX_ENGINE_GRAPH_AOVS_H
#define NPRFX_ENGINE_GRAPH_AOVS_H

#include "graph_model.h"

/* Settle every read node's plates from `frame`'s header (profile, motion convention, Cryptomatte
 * ids, 1/z depth, a position from depth), then give each input that reads a plate its channels,
 * or a fallback announced once (rest -> uv -> position, albedo and diffuse_light -> beauty,
 * motion -> optical flow, an optional input's AOV -> left out), or fail naming the AOV, the
 * profile and the channels that would do. Once per graph: a read whose header cannot be read
 * yet (a missing first frame) is settled at a later frame, its read reporting the file. */
nprfx_result internal_graph_prepare(nprfx_graph *g, int frame);

#endif
