/* nprfx graph engine — file patterns at a frame, the channels each input takes, motion conventions
 * (graph_resolve.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_RESOLVE_H
#define NPRFX_CLI_GRAPH_RESOLVE_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* Copies of n channel names (NULL names become "C"). */
char **internal_graph_names_dup(const char *const *names, int n);

/* pattern at frame, relative to dir unless absolute, into buf. */
void internal_graph_resolve_path(const nprfx_graph *g, const char *dir, const char *pattern,
                                 int frame, char *buf, size_t n);

/* The channels (indices into names, nc of them) input k of node n takes from its source: the
 * reference's selection, else the input's AOV hint, else all, checked against the input's
 * channel count; *count receives how many (idx has room for 256). */
nprfx_result internal_graph_input_channels(nprfx_graph *g, const gnode *n, int k,
                                           const char *const *names, int nc, int *idx, int *count);

/* input_channels's resolution, its error written to msg rather than raised. */
nprfx_result internal_graph_input_channels_quiet(const nprfx_graph *g, const gnode *n, int k,
                                                 const char *const *names, int nc, int *idx,
                                                 int *count, char *msg, size_t msgn);

/* The canonical AOV an item of a selection names ("beauty.RGB": beauty, components "RGB"), or
 * -1. */
int internal_graph_canonical_parse(const char *item, char *components, size_t n);
/* The profile a plate's channels are looked up in (its read's "aovs", else what its first
 * frame showed, else detected from names). */
int internal_graph_plate_profile(const gnode *src, const char *const *names, int nc);

/* Whether an input (flags: its NPRFX_INPUT_* flags, 0 for a write node's image) gets the count
 * channels idx of a source of src_channels packed into a frame of their own rather than read in
 * place: when they are not adjacent, or are a few out of a wide plate (nodes then stream through
 * memory instead of striding over the channels they do not use) unless the input gathers them
 * itself. The evaluation and the memory plan both ask this. */
int internal_graph_packs(int src_channels, const int *idx, int count, unsigned flags);

#endif
