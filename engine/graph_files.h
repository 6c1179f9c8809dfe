/* nprfx graph engine — the files a graph reads and writes (graph_files.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_FILES_H
#define NPRFX_CLI_GRAPH_FILES_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* Write node w would overwrite one of the graph's inputs at frame with out: the error. */
nprfx_result internal_graph_check_not_input(nprfx_graph *g, const gnode *w, const char *out,
                                            int frame);

#endif
