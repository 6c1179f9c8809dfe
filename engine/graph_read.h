/* nprfx graph engine — read and synth nodes' plates, whole or by rows (graph_read.c). Never
 * installed. */
#ifndef NPRFX_CLI_GRAPH_READ_H
#define NPRFX_CLI_GRAPH_READ_H

#include "nprfx/graph.h"
#include "graph_model.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "graph_extras.h"

/* Read node `node` at frame into a plate (im, names, meta): the channels the graph uses, the
 * motion channels its convention appends, converted to scene-linear. *pooled: 1 when im is a
 * frame of the pool (EXR), 0 when it is the reader's own memory (adopted). */
nprfx_result internal_graph_read_plate(nprfx_graph *g, int node, int frame, nprfx_image *im,
                                       char ***names, gmeta *meta, int *pooled);

/* An EXR plate read into a frame of the pool in three steps (graph_read.c): open on the graph's
 * thread (header, appended channels, the frame), fill on any thread (every pixel; touches nothing
 * of the graph, errors on its own ctx), finish on the graph's thread (names, note, colour). */
typedef struct pooled_read {
    int node, frame;
    char file[4096];
    nprfx_io io;
    nprfx_plate shape; /* names, types, windows; no pixels */
    nprfx_row_reader *rr;
    gextra x;
    int nc, nn; /* the file's channels, and with the appended ones */
    nprfx_image im;
    char *note; /* the note after the rows (NULL: the shape's) */
    int warning;
    nprfx_result r; /* the fill's */
} pooled_read;

/* *ok 0 (and NPRFX_OK) when the file is not read by rows (not EXR) or, with spare, when anything
 * fails or the frame does not fit beside what the graph holds: a spare read says nothing. */
nprfx_result internal_graph_pooled_open(nprfx_graph *g, int node, int frame, int spare,
                                        pooled_read *p, int *ok);
void internal_graph_pooled_fill(pooled_read *p, nprfx_context *ctx);
/* Hands the frame to *im (or, on error, drops it); p is empty after. */
nprfx_result internal_graph_pooled_finish(nprfx_graph *g, pooled_read *p, nprfx_image *im,
                                          char ***names, gmeta *meta);
void internal_graph_pooled_drop(nprfx_graph *g, pooled_read *p);

/* The next frame's plates decoded while the current frame computes (graph_prefetch.c), when the
 * runner said which frame comes next (nprfx_graph_run). internal_graph_prefetched: *ok 1 and
 * *p filled when node's plate at frame was decoded ahead (a failed one is dropped: the frame's
 * own read says why); internal_graph_prefetch_next: after node's read at the frame being
 * rendered, start decoding its plate at the next; internal_graph_prefetch_stop: wait for every
 * decode and drop what was not taken. */
nprfx_result internal_graph_prefetched(nprfx_graph *g, int node, int frame, pooled_read *p,
                                       int *ok);
void internal_graph_prefetch_next(nprfx_graph *g, int node, int frame);
void internal_graph_prefetch_stop(nprfx_graph *g);

/* Synth node `node` at frame: the channels its readers take of its scene. */
nprfx_result internal_graph_synth_plate(nprfx_graph *g, int node, int frame, nprfx_image *im,
                                        char ***names, gmeta *meta);

/* Read node `node`'s file at frame (its path into file, n bytes)
 * opened for rows with the channels internal_graph_read_plate would read; *shape describes the
 * plate. */
nprfx_result internal_graph_read_rows_open(nprfx_graph *g, int node, int frame, char *file,
                                           size_t n, nprfx_plate *shape, nprfx_row_reader **rr);

/* Rows [y0, y1) of it as a plate of their own (malloc'd), with the motion channels and the
 * colour conversion internal_graph_read_plate applies to a whole plate. */
nprfx_result internal_graph_read_rows(nprfx_graph *g, int node, const char *file,
                                      nprfx_row_reader *rr, const nprfx_plate *shape, int y0,
                                      int y1, nprfx_plate *out);

#endif
