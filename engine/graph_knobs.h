/* nprfx graph engine — a graph's knobs: the params worth turning its author lists (graph_knobs.c).
 * Never installed. */
#ifndef NPRFX_GRAPH_KNOBS_H
#define NPRFX_GRAPH_KNOBS_H

#include "graph_model.h"
#include "json.h"

/* The "knobs" entry (an array of "NODE.PARAM" strings, NODE may hold * wildcards), kept. */
nprfx_result internal_graph_knobs_parse(nprfx_graph *g, const internal_json *e);
/* Once the nodes are loaded: every knob names a param of at least one processing node. */
nprfx_result internal_graph_knobs_check(nprfx_graph *g);
void internal_graph_knobs_free(nprfx_graph *g);
/* Whether node name matches pattern (* matches any run of characters, nothing else is special). */
int internal_graph_name_matches(const char *pattern, const char *name);
/* Set key=value on every processing node whose name matches pattern (with a *) and that has the
 * param, as nprfx_graph_set does on one; refused when there is none. */
nprfx_result internal_graph_set_matching(nprfx_graph *g, const char *pattern, const char *key,
                                         const char *value);

#endif
