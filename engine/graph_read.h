/* nprfx graph engine — read and synth nodes' plates, whole or by rows (graph_read.c). Never
 * installed. */
#ifndef NPRFX_CLI_GRAPH_READ_H
#define NPRFX_CLI_GRAPH_READ_H

#include "nprfx/graph.h"
#include "graph_model.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"

/* Read node `node` at frame into a plate (im, names, meta): the channels the graph uses, the
 * motion channels its convention appends, converted to scene-linear. *pooled: 1 when im is a
 * frame of the pool (EXR), 0 when it is the reader's own memory (adopted). */
nprfx_result internal_graph_read_plate(nprfx_graph *g, int node, int frame, nprfx_image *im,
                                       char ***names, gmeta *meta, int *pooled);

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
