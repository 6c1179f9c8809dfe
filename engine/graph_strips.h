/* nprfx graph engine — rendering write nodes a strip of rows at a time (graph_strips.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_STRIPS_H
#define NPRFX_CLI_GRAPH_STRIPS_H

#include "graph_model.h"

/* Whether write node `node` can be rendered a strip of rows at a time: every
 * node it depends on is a read of an EXR or a node with NPRFX_NODE_ROWS and a footprint >= 0,
 * none temporal; no preview. When not, why names the node in the way. */
int internal_graph_strips_possible(nprfx_graph *g, int node, char *why, size_t n);

/* Render write nodes writes[0..nw) (a strip group, internal_graph_strip_group) at frame by
 * strips of g->strip_rows rows, each node of their chains once a strip. */
nprfx_result internal_graph_write_strips(nprfx_graph *g, const int *writes, int nw, int frame);

/* The writes that render by strips together with write node `write` (their chains share nodes,
 * directly or through others; it included), in node order, into group (room for g->count);
 * their count. Shared nodes then render each strip once for all of them. */
int internal_graph_strip_group(nprfx_graph *g, int write, int *group);

/* The bytes a strip render of write node `write` (with its strip group) at frame holds at most with
 * strips of `rows` rows (the plates' headers are read); *err: why it cannot be told (raised on g's
 * context), a plate's block of rows above the memory limit (NPRFX_ERR_OUT_OF_MEMORY) among them. */
uint64_t internal_graph_strip_need(nprfx_graph *g, int write, int frame, int rows,
                                   nprfx_result *err);

#endif
