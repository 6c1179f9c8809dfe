/* nprfx graph engine — the cache of node results, one entry per (node, frame): a hash table to find an
 * entry in constant time, whatever the graph's size, and a list in least-recently-used order with
 * a tail pointer, so that eviction starts at the oldest entry without walking the list. Bounded by
 * bytes (the frames) and by entries (graphs of many tiny frames: the bookkeeping of 100,000 4x4
 * results would otherwise outweigh the pixels). Pinned entries are never evicted. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "frame_pool.h"
#include "nprfx/graph.h"
#include "graph_cache.h"
#include "graph_frames.h"
#include "graph_model.h"

/* Free entry e (out of the cache already) and give its frame back. */
static void centry_free(nprfx_graph *g, centry *e)
{
    if (!e) return;
    for (int c = 0; e->names && c < e->im.channels; c++)
        free(e->names[c]);
    free(e->names);
    free(e->meta.types);
    if (e->from_reader) { /* the reader never takes a buffer from the pool */
        size_t bytes = e->bytes < g->held_bytes ? e->bytes : g->held_bytes;
        g->held_bytes -= bytes;
        nprfx_image_free(&e->im);
    } else {
        internal_graph_frame_release(g, &e->im);
    }
    free(e);
}

static size_t slot_of(const nprfx_graph *g, int node, int frame)
{
    uint64_t h = (uint64_t)(uint32_t)node * 0x9e3779b97f4a7c15ull ^ (uint64_t)(uint32_t)frame;
    h ^= h >> 31;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 29;
    return (size_t)h & (g->cache_nslots - 1);
}

/* Grow the table to keep chains short: a slot per entry at most, doubling. */
static int table_fit(nprfx_graph *g)
{
    if (g->cache_slots && g->cache_entries < g->cache_nslots) return 1;
    size_t n = g->cache_nslots ? g->cache_nslots * 2 : 256;
    centry **slots = calloc(n, sizeof *slots);
    if (!slots) return 0;
    centry **old = g->cache_slots;
    size_t oldn = g->cache_nslots;
    g->cache_slots = slots;
    g->cache_nslots = n;
    for (size_t s = 0; s < oldn; s++)
        for (centry *e = old[s], *next; e; e = next) {
            next = e->hnext;
            size_t t = slot_of(g, e->node, e->frame);
            e->hnext = slots[t];
            slots[t] = e;
        }
    free(old);
    return 1;
}

static void list_unlink(nprfx_graph *g, centry *e)
{
    if (e->prev)
        e->prev->next = e->next;
    else
        g->head = e->next;
    if (e->next)
        e->next->prev = e->prev;
    else
        g->tail = e->prev;
    e->prev = e->next = NULL;
}

static void list_push_front(nprfx_graph *g, centry *e)
{
    e->prev = NULL;
    e->next = g->head;
    if (g->head)
        g->head->prev = e;
    else
        g->tail = e;
    g->head = e;
}

static void table_remove(nprfx_graph *g, centry *e)
{
    for (centry **p = &g->cache_slots[slot_of(g, e->node, e->frame)]; *p; p = &(*p)->hnext)
        if (*p == e) {
            *p = e->hnext;
            break;
        }
}

centry *internal_graph_cache_find(nprfx_graph *g, int node, int frame)
{
    if (!g->cache_slots) return NULL;
    for (centry *e = g->cache_slots[slot_of(g, node, frame)]; e; e = e->hnext)
        if (e->node == node && e->frame == frame) {
            list_unlink(g, e);
            list_push_front(g, e);
            e->gen = g->gen;
            internal_graph_touch(g, e);
            return e;
        }
    return NULL;
}

void internal_graph_cache_drop(nprfx_graph *g, centry *e)
{
    list_unlink(g, e);
    table_remove(g, e);
    g->cache_bytes -= e->bytes;
    g->cache_entries--;
    centry_free(g, e);
}

void internal_graph_cache_evict(nprfx_graph *g)
{
    /* The byte bound covers the pool's idle buffers too, so that pooling keeps what --cache-mb
     * promised; they go first, as they only save page faults while a result saves a render. */
    size_t idle = frame_pool_idle_bytes(g->pool);
    if (idle && g->cache_bytes + idle > g->cache_limit)
        frame_pool_trim(g->pool,
                        g->cache_limit > g->cache_bytes ? g->cache_limit - g->cache_bytes : 0);
    /* Oldest first; the newest entry stays, as it is about to be used. */
    for (centry *e = g->tail, *prev; e && e != g->head; e = prev) {
        if (g->cache_bytes <= g->cache_limit && g->cache_entries <= g->cache_entry_limit) break;
        prev = e->prev;
        if (e->pins) continue;
        internal_graph_cache_drop(g, e);
    }
}

centry *internal_graph_cache_insert(nprfx_graph *g, int node, int frame, nprfx_image *im,
                                    char **names, gmeta *meta)
{
    if (!table_fit(g)) return NULL;
    centry *e = calloc(1, sizeof *e);
    if (!e) return NULL;
    e->node = node;
    e->frame = frame;
    e->im = *im;
    e->names = names;
    e->meta = *meta;
    memset(meta, 0, sizeof *meta);
    e->gen = g->gen;
    internal_graph_touch(g, e);
    e->uses = g->plan_ready && node >= 0 && node < g->count ? g->plan_uses[node] : 0;
    e->bytes = (size_t)nprfx_rect_width(im->bounds) * (size_t)nprfx_rect_height(im->bounds) *
               (size_t)im->channels * sizeof(float);
    memset(im, 0, sizeof *im);
    list_push_front(g, e);
    size_t s = slot_of(g, node, frame);
    e->hnext = g->cache_slots[s];
    g->cache_slots[s] = e;
    g->cache_bytes += e->bytes;
    g->cache_entries++;
    internal_graph_cache_evict(g);
    return e;
}

void internal_graph_cache_clear(nprfx_graph *g)
{
    for (centry *e = g->head, *next; e; e = next) {
        next = e->next;
        centry_free(g, e);
    }
    free(g->cache_slots);
    g->cache_slots = NULL;
    g->cache_nslots = 0;
    g->head = g->tail = NULL;
    g->cache_bytes = 0;
    g->cache_entries = 0;
}
