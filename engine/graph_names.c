/* nprfx graph engine — the graph's node names: a hash index built while parsing, so references resolve in
 * constant time (a linear search per reference made validation quadratic: minutes for a 30,000-node
 * chain) and a name given twice is found as it is added. the JSON reader keeps every duplicate key
 * of an object, so without this check the second node of a name would silently be unreachable. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/graph.h"
#include "graph_names.h"

static uint64_t name_hash(const char *s)
{
    uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a */
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 0x100000001b3ull;
    return h;
}

nprfx_result internal_graph_names_init(nprfx_graph *g, int count)
{
    size_t n = 16;
    while (n < (size_t)count * 2)
        n *= 2;
    g->name_slots = malloc(n * sizeof *g->name_slots);
    if (!g->name_slots) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    for (size_t i = 0; i < n; i++)
        g->name_slots[i] = -1;
    g->name_nslots = n;
    return NPRFX_OK;
}

/* The slot that holds name, or the empty one where it would go (open addressing; the table is at
 * most half full, so a probe always ends). */
static size_t name_slot(const nprfx_graph *g, const char *name)
{
    size_t mask = g->name_nslots - 1;
    size_t s = (size_t)name_hash(name) & mask;
    while (g->name_slots[s] >= 0 && strcmp(g->nodes[g->name_slots[s]].name, name))
        s = (s + 1) & mask;
    return s;
}

int internal_graph_names_add(nprfx_graph *g, int node)
{
    size_t s = name_slot(g, g->nodes[node].name);
    if (g->name_slots[s] >= 0) return g->name_slots[s];
    g->name_slots[s] = node;
    return -1;
}

int internal_graph_find_node(const nprfx_graph *g, const char *name)
{
    if (!g->name_slots) return -1;
    return g->name_slots[name_slot(g, name)];
}
