/* nprfx graph engine — frames handed out under the memory limit, and results freed once consumed
 * (graph_memory.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_MEMORY_H
#define NPRFX_CLI_GRAPH_MEMORY_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* A zeroed frame of bounds x channels for node (its output or a scratch), from the pool, after
 * checking it against the memory limit (evicting unpinned cached results first when the limit
 * would be passed); errors name `what` ("node 'x': output frame") and the sizes. */
nprfx_result internal_graph_frame_alloc(nprfx_graph *g, int node, const char *what,
                                        nprfx_rect bounds, int channels, nprfx_image *im);

/* The same frame, not cleared when it comes from the pool: for a caller that sets every pixel
 * before reading any (a node with NPRFX_NODE_WRITES_WINDOW, a channel packing). */
nprfx_result internal_graph_frame_alloc_unset(nprfx_graph *g, int node, const char *what,
                                              nprfx_rect bounds, int channels, nprfx_image *im);

/* A frame for work ahead (the next frame's plate), only when it fits under the limit beside what
 * the graph holds without dropping a cached result: NPRFX_ERR_OUT_OF_MEMORY, raised nowhere,
 * when it does not. Not cleared. */
nprfx_result internal_graph_frame_alloc_spare(nprfx_graph *g, int node, nprfx_rect bounds,
                                              int channels, nprfx_image *im);

/* One consumer at e's frame has used e: when none is left and no temporal node reads e's node
 * at other frames, e leaves the cache now (unless pinned) instead of waiting for eviction. */
void internal_graph_consumed(nprfx_graph *g, centry *e);

/* A pin on e let go: e leaves the cache as internal_graph_consumed would have let it. */
void internal_graph_unpin(nprfx_graph *g, centry *e);

/* After a frame: drop every unpinned result but a temporal source's within the window the next
 * frame is expected to read (the offsets touched in this one, moved on by the step between the
 * last two frames, +1 at first). */
void internal_graph_frame_sweep(nprfx_graph *g);

#endif
