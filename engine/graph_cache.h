/* nprfx graph engine — the per-(node, frame) result cache with its bounds and least-recently-used eviction
 * (graph_cache.c). Never installed. */
#ifndef NPRFX_CLI_GRAPH_CACHE_H
#define NPRFX_CLI_GRAPH_CACHE_H

#include "nprfx/graph.h"
#include "graph_model.h"

/* Remove entry e (unpinned) from the cache and release its frame. */
void internal_graph_cache_drop(nprfx_graph *g, centry *e);

/* The entry of (node, frame), made the most recent, or NULL. */
centry *internal_graph_cache_find(nprfx_graph *g, int node, int frame);

/* Add a result (taking im, names and meta's types), evicting unpinned old ones over the bounds;
 * NULL: no memory. */
centry *internal_graph_cache_insert(nprfx_graph *g, int node, int frame, nprfx_image *im,
                                    char **names, gmeta *meta);

/* Evict unpinned entries, oldest first, until the cache is within its bounds. */
void internal_graph_cache_evict(nprfx_graph *g);

/* Free every entry. */
void internal_graph_cache_clear(nprfx_graph *g);

#endif
