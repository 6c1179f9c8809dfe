/* nprfx graph engine — the hash index of node names (graph_names.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_NAMES_H
#define NPRFX_CLI_GRAPH_NAMES_H

#include "graph_model.h"

/* The index of the node called name, or -1. */
int internal_graph_find_node(const nprfx_graph *g, const char *name);

/* An empty name index with room for count nodes. */
nprfx_result internal_graph_names_init(nprfx_graph *g, int count);

/* Index node's name; when another node has it already, that node's index (else -1). */
int internal_graph_names_add(nprfx_graph *g, int node);

#endif
