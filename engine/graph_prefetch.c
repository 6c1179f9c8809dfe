/* nprfx graph engine — the next frame's plates decoded while the current frame computes.
 *
 * A steady frame of a look at 1080p was the plate's decoding, then the nodes, then the writes,
 * one after the other, with a core idle through most of the read and the writes. When the
 * runner says which frame it renders next (nprfx_graph_run), a read node's plate at that frame
 * starts decoding on a thread of its own as soon as the read at the current frame is done: the
 * frame from the pool is taken on the graph's thread (under the memory limit, beside what the
 * graph holds; when it does not fit there is simply no decoding ahead), and the thread only
 * fills its pixels (graph_read.c, internal_graph_pooled_fill). The next frame's read takes the
 * frame when it is the one asked for; anything else (another frame, a failed decode) is dropped
 * and read as before, so the pixels never depend on it. One decode ahead per read node. */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "graph_model.h"
#include "graph_read.h"

typedef struct internal_prefetch {
    pthread_t thread;
    int running;
    pooled_read p;
    nprfx_context *ctx; /* the decode's own: its errors are nobody's until the frame's read */
} internal_prefetch;

static void *fill_main(void *user)
{
    internal_prefetch *f = user;
    internal_graph_pooled_fill(&f->p, f->ctx);
    return NULL;
}

/* Wait for node's decode, if one runs. */
static void join(internal_prefetch *f)
{
    if (!f->running) return;
    pthread_join(f->thread, NULL);
    f->running = 0;
    nprfx_context_destroy(f->ctx);
    f->ctx = NULL;
}

nprfx_result internal_graph_prefetched(nprfx_graph *g, int node, int frame, pooled_read *p, int *ok)
{
    *ok = 0;
    if (!g->prefetch) return NPRFX_OK;
    internal_prefetch *f = &g->prefetch[node];
    /* a decode of another frame (this is a temporal fetch) goes on */
    if (!f->running || f->p.frame != frame) return NPRFX_OK;
    join(f);
    if (!f->p.r) {
        *p = f->p;
        memset(&f->p, 0, sizeof f->p);
        *ok = 1;
    } else {
        internal_graph_pooled_drop(g, &f->p);
    }
    return NPRFX_OK;
}

void internal_graph_prefetch_next(nprfx_graph *g, int node, int frame)
{
    /* only for the frame being rendered: a temporal node's fetch of another frame is not what
     * the next frame reads */
    if (!g->has_next || frame != g->cur_frame || g->next_frame == frame) return;
    if (!g->prefetch) {
        g->prefetch = calloc((size_t)g->count, sizeof *g->prefetch);
        if (!g->prefetch) return;
    }
    internal_prefetch *f = &g->prefetch[node];
    if (f->running) return;
    int ok = 0;
    if (internal_graph_pooled_open(g, node, g->next_frame, 1, &f->p, &ok) || !ok) return;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    if (!nprfx_context_create(&ci, &f->ctx))
        nprfx_context_set_front_end(f->ctx, nprfx_context_front_end(g->ctx)); /* for the io */
    if (!f->ctx || pthread_create(&f->thread, NULL, fill_main, f)) {
        nprfx_context_destroy(f->ctx);
        f->ctx = NULL;
        internal_graph_pooled_drop(g, &f->p);
        return;
    }
    f->running = 1;
}

void internal_graph_prefetch_stop(nprfx_graph *g)
{
    if (!g->prefetch) return;
    for (int i = 0; i < g->count; i++) {
        internal_prefetch *f = &g->prefetch[i];
        int had = f->running;
        join(f);
        if (had) internal_graph_pooled_drop(g, &f->p);
    }
}
