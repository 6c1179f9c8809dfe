/* nprfx graph engine — a graph's frames against the image memory bound (io_limits.h), checked when the
 * graph is loaded: a synth node or a "format" asking for a frame larger than NPRFX_READ_LIMIT
 * allows is refused before the first frame instead of failing in calloc after gigabytes. Frames
 * whose size comes from a file are checked when the file is read (io_validate.h), and every
 * node's output frame once more before it is allocated (graph_memory.c). */
#include <stdio.h>

#include "nprfx/graph.h"
#include "graph_limits.h"
#include "graph_model.h"
#include "nprfx/io.h"

nprfx_result internal_graph_check_limits(nprfx_graph *g)
{
    for (int i = 0; i < g->count; i++) {
        const gnode *n = &g->nodes[i];
        if (n->kind != GK_SYNTH) continue;
        char what[600];
        snprintf(what, sizeof what, "node '%s': synth size", n->name);
        /* One channel: a graph's synth makes only the channels its readers take
         * (internal_graph_synth_plate), which are known once the graph is planned; the frame is
         * checked again with them before it is allocated. This refuses the sizes no plate could
         * have. */
        nprfx_result r = nprfx_image_limit_check(g->ctx, what, n->width, n->height, 1, 0);
        if (r) return r;
    }
    int w = 0, h = 0;
    if (g->fmt_text && sscanf(g->fmt_text, "%dx%d", &w, &h) == 2 && w > 0 && h > 0)
        return nprfx_image_limit_check(g->ctx, "\"format\"", w, h, 1, 0);
    return NPRFX_OK;
}
