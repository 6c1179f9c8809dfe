/* nprfx graph engine — how measure's variants alter plates and params (graph_variant.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_VARIANT_H
#define NPRFX_CLI_GRAPH_VARIANT_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* NPRFX_VARIANT_SHOWER_DOOR: alter a plate just read. */
void internal_graph_variant_plate(const nprfx_graph *g, nprfx_image *im, char **names);

/* NPRFX_VARIANT_WHITE: the params node n renders frame with (its own, or *copy altered). */
const nprfx_value *internal_graph_variant_params(const nprfx_graph *g, const gnode *n, int frame,
                                                 nprfx_value *copy);

#endif
