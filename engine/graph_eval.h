/* nprfx graph engine — evaluating a node at a frame (graph_eval.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_EVAL_H
#define NPRFX_CLI_GRAPH_EVAL_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* The view of the channels of entry e that input k of node n uses: e's pixels when they are
 * adjacent, else *scratch (a frame from internal_graph_frame_alloc, the caller releases it with
 * internal_graph_frame_release; left empty when not needed). */
nprfx_result internal_graph_select_input(nprfx_graph *g, const gnode *n, int k, const centry *e,
                                         nprfx_image *view, nprfx_image *scratch);

/* The render arguments every render of node n at `frame` shares, whole frames or strips alike:
 * its context, descriptor, time, the frame, the shot, its params at that frame (varied: room
 * for 64, used when the params vary), state and item counter; the caller sets inputs, output,
 * window and fetch. */
void internal_graph_render_args(nprfx_graph *g, gnode *n, int frame, nprfx_rect frame_rect,
                                nprfx_rect display,
                                nprfx_value *varied, nprfx_render_args *a);

/* The cache entry of node at frame, evaluated (and its inputs) when not cached. */
nprfx_result internal_graph_eval(nprfx_graph *g, int node, int frame, centry **out);

#endif
