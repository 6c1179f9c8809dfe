/* nprfx graph engine — a graph's knobs (nprfx/graph.h, "knobs"): the params worth turning, as the
 * graph's author lists them. Front ends derive what they show from them and the params'
 * descriptors (`nprfx help GRAPH`, the Python module, host projects), so a look's controls are
 * written once, in its graph file. A knob NODE.PARAM may name many nodes with * ("strokes*.radius":
 * every strokes layer, of the nodes it matches those that have the param): one control setting
 * all. An entry is the "NODE.PARAM" string, or
 * {"param": "NODE.PARAM", "help": "what it does in this look"}. */
#include "graph_knobs.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine_util.h"
#include "graph_names.h"

/* The most knobs a graph lists: a look's controls, not its every param. */
#define MAX_KNOBS 64

int internal_graph_name_matches(const char *pattern, const char *name)
{
    /* iterative glob with one backtrack point: linear enough for node names */
    const char *star = NULL, *retry = NULL;
    while (*name) {
        if (*pattern == '*') {
            star = pattern++;
            retry = name;
        } else if (*pattern == *name) {
            pattern++;
            name++;
        } else if (star) {
            pattern = star + 1;
            name = ++retry;
        } else {
            return 0;
        }
    }
    while (*pattern == '*')
        pattern++;
    return *pattern == 0;
}

nprfx_result internal_graph_knobs_parse(nprfx_graph *g, const internal_json *e)
{
    if (g->knobs)
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "top-level entry 'knobs' is given twice");
    if (!e || e->type != INTERNAL_JSON_ARRAY || e->count > MAX_KNOBS)
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                           "top-level entry 'knobs' must be a list of up to %d \"NODE.PARAM\" "
                           "strings (the params worth turning)",
                           MAX_KNOBS);
    g->knobs = calloc((size_t)e->count + 1, sizeof *g->knobs);
    g->knob_help = calloc((size_t)e->count + 1, sizeof *g->knob_help);
    if (!g->knobs || !g->knob_help)
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    for (const internal_json *k = e->child; k; k = k->next) {
        const internal_json *param = k, *help = NULL;
        if (k->type == INTERNAL_JSON_OBJECT) {
            param = internal_json_member(k, "param");
            help = internal_json_member(k, "help");
            for (const internal_json *m = k->child; m; m = m->next)
                if (strcmp(m->key, "param") && strcmp(m->key, "help"))
                    return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                       "knobs: entry %d: unexpected '%s' (expected param, help)",
                                       g->nknobs + 1, m->key);
            if (help && help->type != INTERNAL_JSON_STRING)
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "knobs: entry %d: help is not text",
                                   g->nknobs + 1);
        }
        if (!param || param->type != INTERNAL_JSON_STRING || !strchr(param->string, '.'))
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                               "knobs: entry %d is not \"NODE.PARAM\" or {\"param\": "
                               "\"NODE.PARAM\", \"help\": \"...\"}",
                               g->nknobs + 1);
        const int n = g->nknobs;
        if (!(g->knobs[n] = engine_strdup(param->string)))
            return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        g->nknobs++; /* freed with the graph from here on */
        if (help && !(g->knob_help[n] = engine_strdup(help->string)))
            return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    return NPRFX_OK;
}

/* The nodes knob k sets: how many, and the first (-1: none); *param its index there. */
static int knob_nodes(const nprfx_graph *g, const char *knob, int *first, int *param,
                      const char **missing)
{
    const char *dot = strrchr(knob, '.');
    char pattern[256];
    snprintf(pattern, sizeof pattern, "%.*s", (int)(dot - knob), knob);
    const int wild = strchr(pattern, '*') != NULL;
    int n = 0;
    *first = -1;
    *missing = NULL;
    for (int i = 0; i < g->visible; i++) {
        const gnode *nd = &g->nodes[i];
        if (nd->kind != GK_NODE || !internal_graph_name_matches(pattern, nd->name)) continue;
        int pi = nprfx_node_param_index(nd->desc, dot + 1);
        if (pi < 0 && wild) continue; /* a pattern sets the nodes that have the param */
        if (pi < 0) {
            *missing = nd->name;
            return -1;
        }
        if (*first < 0) {
            *first = i;
            *param = pi;
        }
        n++;
    }
    return n;
}

nprfx_result internal_graph_knobs_check(nprfx_graph *g)
{
    for (int k = 0; k < g->nknobs; k++) {
        int first, param;
        const char *missing;
        int n = knob_nodes(g, g->knobs[k], &first, &param, &missing);
        if (n < 0)
            return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM,
                               "knobs: '%s': node '%s' (%s) has no param '%s'", g->knobs[k],
                               missing, g->nodes[internal_graph_find_node(g, missing)].desc->id,
                               strrchr(g->knobs[k], '.') + 1);
        if (n == 0)
            return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_NODE,
                               "knobs: '%s' names no processing node of the graph with that "
                               "param",
                               g->knobs[k]);
    }
    return NPRFX_OK;
}

void internal_graph_knobs_free(nprfx_graph *g)
{
    for (int k = 0; g->knobs && k < g->nknobs; k++) {
        free(g->knobs[k]);
        free(g->knob_help[k]);
    }
    free(g->knobs);
    free(g->knob_help);
    g->knobs = g->knob_help = NULL;
    g->nknobs = 0;
}

nprfx_result internal_graph_set_matching(nprfx_graph *g, const char *pattern, const char *key,
                                         const char *value)
{
    int n = 0;
    for (int i = 0; i < g->visible; i++) {
        const gnode *nd = &g->nodes[i];
        if (nd->kind != GK_NODE || !internal_graph_name_matches(pattern, nd->name) ||
            nprfx_node_param_index(nd->desc, key) < 0)
            continue;
        char *a = malloc(strlen(nd->name) + strlen(key) + strlen(value) + 3);
        if (!a) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        sprintf(a, "%s.%s=%s", nd->name, key, value);
        nprfx_result r = nprfx_graph_set(g, a);
        free(a);
        if (r) return r;
        n++;
    }
    if (!n)
        return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_NODE,
                           "--set: no processing node of the graph matches '%s' and has a "
                           "param '%s'",
                           pattern, key);
    return NPRFX_OK;
}

const char *nprfx_graph_comment(const nprfx_graph *g)
{
    return g ? g->comment : NULL;
}

int nprfx_graph_knob_count(const nprfx_graph *g)
{
    return g ? g->nknobs : 0;
}

nprfx_result nprfx_graph_knob(const nprfx_graph *g, int i, nprfx_graph_knob_info *out)
{
    if (!g || !out || out->size < sizeof *out || i < 0 || i >= g->nknobs)
        return nprfx_error(g ? g->ctx : NULL, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_graph_knob: no knob %d", i);
    int first, param;
    const char *missing;
    int n = knob_nodes(g, g->knobs[i], &first, &param, &missing);
    if (n <= 0)
        return nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "knob '%s' names no node", g->knobs[i]);
    const gnode *nd = &g->nodes[first];
    memset(out, 0, sizeof *out);
    out->size = sizeof *out;
    out->name = g->knobs[i];
    out->help = g->knob_help[i];
    out->node = nd->name;
    out->desc = nd->desc;
    out->param = &nd->desc->params[param];
    out->value = &nd->params[param];
    out->nodes = n;
    return NPRFX_OK;
}
