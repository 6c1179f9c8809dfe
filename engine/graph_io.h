/* nprfx graph engine — the files a graph reads and writes go through the nprfx_io its caller gave
 * (nprfx_graph_options.io, nprfx/io.h); what it left out fails with a message saying so. */
#ifndef NPRFX_ENGINE_GRAPH_IO_H
#define NPRFX_ENGINE_GRAPH_IO_H

#include "nprfx/io.h"

/* Copy io (NULL: none) into *out, every function it lacks (or that its size does not cover)
 * replaced by one that raises "no image I/O ...". */
void internal_graph_io_init(nprfx_io *out, const nprfx_io *io);

#endif
