/* nprfx graph engine — what a graph's plates are (graph_aovs.c): profiles, conventions, decoded
 * ids and fallbacks, settled from the first frame before anything renders. Never installed. */
#ifndef NPRFX_ENGINE_GRAPH_AOVS_H
#define NPRFX_ENGINE_GRAPH_AOVS_H

#include "graph_model.h"

/* Settle every read node's plates from `frame`'s header (profile, motion convention, Cryptomatte
 * ids, 1/z depth), then give each input that reads a plate its channels, or a fallback announced
 * once (rest -> uv -> position, albedo and diffuse_light -> beauty, id -> none for an optional
 * input), or fail naming the AOV, the profile and the channels that would do. Once per graph: a
 * read whose header cannot be read yet is settled at a later frame. strict: a frame whose file
 * cannot be read is an error (the check before a run), else it waits for the frame's own read. */
nprfx_result internal_graph_prepare(nprfx_graph *g, int frame, int strict);

#endif
