/* nprfx graph engine — the memory plan: consumer counts, temporal sources, the channels plates keep
 * (graph_plan.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_PLAN_H
#define NPRFX_CLI_GRAPH_PLAN_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* The consumer counts and temporal sources, made once. */
nprfx_result internal_graph_plan_build(nprfx_graph *g);

/* The channels of a plate (a read or synth node's result, names/nc) that its readers take, by
 * the selections they would make on it: keep[c] set for each, the count returned; -1 when a
 * reader's selection fails (the reader reports it) or the plate is evaluated for the caller of
 * nprfx_graph_eval, who sees all of it. Only a planned graph trims plates. */
int internal_graph_plate_channels(nprfx_graph *g, int node, const char *const *names, int nc,
                                  unsigned char *keep);

/* The channels read node `node` reads of a file whose whole read would deliver names (nc):
 * those its readers take (internal_graph_plate_channels on names with the motion channels
 * appended), the sources of its motion channels and its R,G,B when it converts colour, as
 * indices into names in file order into pick (room for nc); -1 to read them all: nothing to
 * leave out, no plan, or a selection that would come out otherwise on the channels read. */
int internal_graph_read_pick(nprfx_graph *g, int node, const char *const *names, int nc, int *pick);

/* The channels of plate node's result with names (nc) to keep: those its readers take, when
 * every reader then selects the very same channels from them; their indices in names, in
 * order, into map (room for nc), and their count; 0 to keep the plate whole. */
int internal_graph_plate_pick(nprfx_graph *g, int node, const char *const *names, int nc, int *map);

/* Keep only the channels of plate node's result (im, names, and meta's per-channel types when it
 * has them) that its readers take, when every reader then selects the very same channels
 * (internal_graph_plate_channels); whether it did. pooled: im is a frame of the pool (a synth
 * node's, a read's by rows), else the reader's own memory. */
int internal_graph_trim_plate(nprfx_graph *g, int node, nprfx_image *im, char ***names, gmeta *meta,
                              int pooled);

#endif
