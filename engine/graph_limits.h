/* nprfx graph engine — synth sizes and "format" against the image memory bound (graph_limits.c). Never
 * installed. */
#ifndef NPRFX_CLI_GRAPH_LIMITS_H
#define NPRFX_CLI_GRAPH_LIMITS_H

#include "graph_model.h"

/* Synth sizes and "format" against the image memory bound. */
nprfx_result internal_graph_check_limits(nprfx_graph *g);

#endif
