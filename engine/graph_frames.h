/* nprfx graph engine — the frames a graph holds, counted against the memory limit, and the temporal
 * window (graph_frames.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_FRAMES_H
#define NPRFX_CLI_GRAPH_FRAMES_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* The bytes of im's pixels. */
size_t internal_graph_image_bytes(const nprfx_image *im);

/* Note the frames held now (held, state and the pool's idle buffers) in the peak. */
void internal_graph_note_peak(nprfx_graph *g);

/* The bytes node n keeps between the graph's frames of w x h, its inputs selecting in_ch
 * channels (desc->state_bytes); 0 when it cannot be told (the render reports why). */
uint64_t internal_graph_query_state(nprfx_graph *g, const gnode *n, const nprfx_value *params,
                                    int w, int h, const int *in_ch);

/* After node's first render (frame size w x h, its inputs' channel counts in_ch, the params it
 * rendered with): count the caches it keeps between frames from then on (desc->state_bytes) in
 * g->state_bytes, so that later frames are checked against the memory limit with them. */
void internal_graph_count_state(nprfx_graph *g, gnode *n, int w, int h, const int *in_ch,
                                const nprfx_value *params);

/* Count a frame made elsewhere (a plate from the reader) as held. */
void internal_graph_frame_adopt(nprfx_graph *g, int node, const nprfx_image *im);

/* Give a frame from internal_graph_frame_alloc (or adopted) back to the pool. */
void internal_graph_frame_release(nprfx_graph *g, nprfx_image *im);

/* NPRFX_OK when frame is one nprfx renders (NPRFX_FRAME_MIN..MAX), else an error on g's context. */
nprfx_result internal_graph_frame_ok(nprfx_graph *g, int frame);

/* Begin evaluating frame (after the previous frame's sweep). */
void internal_graph_frame_begin(nprfx_graph *g, int frame);

/* Entry e was found or made: a temporal source's frame widens the window. */
void internal_graph_touch(nprfx_graph *g, centry *e);

#endif
