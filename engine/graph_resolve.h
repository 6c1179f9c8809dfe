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

/* The names of the 4 channels a read node with "vectors" appends to its plates. */
extern const char *const internal_graph_motion_names[4];

/* The channels motion convention `vectors` ("blender", "nuke") reads, as a selection
 * ("Vector.X,Vector.Y,Vector.Z,Vector.W"); NULL for an unknown convention. */
const char *internal_graph_motion_layer(const char *vectors);
/* Read node n's motion convention ("vectors"): the plate channels (indices into names) the 4
 * appended channels are made of, and the factor each is multiplied by. */
nprfx_result internal_graph_motion_sources(nprfx_graph *g, const gnode *n, const char *file,
                                           const char *const *names, int nc, int *idx,
                                           double *sign);

/* Whether an input (flags: its NPRFX_INPUT_* flags, 0 for a write node's image) gets the count
 * channels idx of a source of src_channels packed into a frame of their own rather than read in
 * place: when they are not adjacent, or are a few out of a wide plate (nodes then stream through
 * memory instead of striding over the channels they do not use) unless the input gathers them
 * itself. The evaluation and the memory plan both ask this. */
int internal_graph_packs(int src_channels, const int *idx, int count, unsigned flags);

#endif
