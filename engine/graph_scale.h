/* nprfx graph engine — a graph's design width: the scale of its pixel params (graph_scale.c).
 * Never installed. */
#ifndef NPRFX_ENGINE_GRAPH_SCALE_H
#define NPRFX_ENGINE_GRAPH_SCALE_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* The frame's pixels per pixel of the graph's params: display width / design width, 1 when the
 * graph declares no design width (its params are in the plate's own pixels). */
double internal_graph_param_scale(const nprfx_graph *g, nprfx_rect display);

/* params (node n's, num_params of them) at `scale`: themselves at 1, else *copy holding them with
 * every PIXELS param multiplied by scale and every AREA param by its square. copy may be params;
 * it holds at least n->desc->num_params values. */
const nprfx_value *internal_graph_scale_params(const gnode *n, const nprfx_value *params,
                                               double scale, nprfx_value *copy);

#endif
