/* nprfx graph engine — the graph variants that nprfx measure compares a look with (graph.h): the same
 * graph with its patterns stuck to the screen (shower door), or drawn anew every frame (white).
 * Only the plates and the seeds change, so any graph gets its baselines without editing it. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/graph.h"
#include "graph_model.h"
#include "graph_variant.h"

/* The layer of a channel name ("ViewLayer.Pref.R" -> "Pref") and its last component ("R"). */
static void split_name(const char *name, char *layer, size_t n, const char **comp)
{
    const char *last = strrchr(name, '.');
    *comp = last ? last + 1 : name;
    layer[0] = 0;
    if (!last) return;
    const char *start = last;
    while (start > name && start[-1] != '.')
        start--;
    size_t len = (size_t)(last - start);
    if (len >= n) len = n - 1;
    memcpy(layer, start, len);
    layer[len] = 0;
}

static int in_list(const char *s, const char *const *list)
{
    for (int i = 0; list[i]; i++)
        if (!strcmp(s, list[i])) return 1;
    return 0;
}

void internal_graph_variant_plate(const nprfx_graph *g, nprfx_image *im, char **names)
{
    if (g->variant != NPRFX_VARIANT_SHOWER_DOOR || !names) return;
    static const char *const motion[] = {"Vector", "motion_prev", "motion_next", "motion", NULL};
    static const char *const anchors[] = {"Pref", "rest", "UV", "uv", "P", "Position", NULL};
    /* per channel: -1 keep, 0 zero, 1 x / width, 2 y / width */
    int role[256];
    int nc = im->channels < 256 ? im->channels : 256, any = 0;
    for (int c = 0; c < nc; c++) {
        char layer[64];
        const char *comp;
        split_name(names[c] ? names[c] : "", layer, sizeof layer, &comp);
        role[c] = -1;
        if (in_list(layer, motion)) {
            role[c] = 0;
        } else if (in_list(layer, anchors)) {
            if (!strcmp(comp, "X") || !strcmp(comp, "R") || !strcmp(comp, "U"))
                role[c] = 1;
            else if (!strcmp(comp, "Y") || !strcmp(comp, "G") || !strcmp(comp, "V"))
                role[c] = 2;
            else if (!strcmp(comp, "Z") || !strcmp(comp, "B"))
                role[c] = 0;
        }
        any |= role[c] >= 0;
    }
    if (!any) return;
    double w = nprfx_rect_width(im->bounds) > 0 ? nprfx_rect_width(im->bounds) : 1;
    for (int y = im->bounds.y0; y < im->bounds.y1; y++)
        for (int x = im->bounds.x0; x < im->bounds.x1; x++) {
            float *p = nprfx_image_at(im, x, y);
            for (int c = 0; c < nc; c++)
                if (role[c] == 0)
                    p[c] = 0.0f;
                else if (role[c] == 1)
                    p[c] = (float)(x / w);
                else if (role[c] == 2)
                    p[c] = (float)(y / w);
        }
}

const nprfx_value *internal_graph_variant_params(const nprfx_graph *g, const gnode *n, int frame,
                                                 nprfx_value *copy)
{
    if (g->variant != NPRFX_VARIANT_WHITE) return n->params;
    int si = nprfx_node_param_index(n->desc, "seed");
    if (si < 0) return n->params;
    const nprfx_param_desc *p = &n->desc->params[si];
    memcpy(copy, n->params, sizeof *copy * (size_t)n->desc->num_params);
    /* a new seed every frame, inside the param's range */
    uint64_t h = (uint64_t)(int64_t)frame * 0x9e3779b97f4a7c15ull + (uint64_t)copy[si].v[0];
    h ^= h >> 29;
    double span = p->hard_max - p->hard_min;
    if (span > 1e9) span = 1e9;
    copy[si].v[0] = p->hard_min + (double)(h % (uint64_t)(span + 1));
    return copy;
}
