/* nprfx graph engine — the check that a linked graph has no cycle (graph_cycles.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_CYCLES_H
#define NPRFX_CLI_GRAPH_CYCLES_H

#include "graph_model.h"

/* An error naming the nodes of a cycle, if the linked graph has one. */
nprfx_result internal_graph_check_cycles(nprfx_graph *g);

#endif
