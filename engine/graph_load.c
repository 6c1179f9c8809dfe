#define _DEFAULT_SOURCE /* realpath */
/* nprfx graph engine — node graphs: parsing (json.c) and validation against the descriptors,
 * overrides (--set, --shot, synthesized reads), the frames to render, and freeing a graph;
 * evaluation is in graph_eval.c, writing in graph_write.c.
 *
 * A graph is {"frames": "1-24", "nodes": {NAME: {...}, ...}}. Processing nodes are
 * {"node": ID, "inputs": {INPUT: REF}, "params": {PARAM: VALUE}}; the built-in I/O nodes are
 * read {"node": "read", "path": SEQ, "colorspace": CS, "vectors": CONVENTION, "aovs": PROFILE,
 * "part": PART, "view": VIEW},
 * synth {"node": "synth", "scene": NAME, "size": "WxH"} and
 * write {"node": "write", "inputs": {"image": REF}, "path": SEQ, "preview": SEQ}.
 * A REF is "name" or "name:channels" (nprfx/channels.h); on a plate, CHANNELS may be a canonical
 * AOV (nprfx/aov.h: "plate:depth") that its profile resolves.
 *
 * Evaluation pulls from the write nodes. Results are cached per (node, frame) under a byte bound
 * with least-recently-used eviction (graph_cache.c); temporal nodes fetch their inputs at other
 * frames through the same cache, and what a render call fetched stays pinned until it returns. */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "frame_pool.h"
#include "nprfx/graph.h"
#include "graph_cache.h"
#include "graph_cycles.h"
#include "graph_limits.h"
#include "aov_map.h"
#include "graph_model.h"
#include "graph_write_jobs.h"
#include "graph_read.h"
#include "graph_names.h"
#include "graph_knobs.h"
#include "nprfx/io.h"
#include "nprfx/nprfx.h"
#include "nprfx/seq.h"
#include "engine_util.h"
#include "json.h"
#include "nprfx/aov.h"
#include "graph_io.h"

/* ---------------------------------------------------------------- parsing ---- */

/* The JSON tests the loader makes (NULL is no value of any type). */
static int json_is(const internal_json *j, internal_json_type t)
{
    return j && j->type == t;
}
static int json_is_bool(const internal_json *j)
{
    return json_is(j, INTERNAL_JSON_TRUE) || json_is(j, INTERNAL_JSON_FALSE);
}
/* A number as an int, saturated at INT_MIN and INT_MAX ("frames": 1e12). */
static int json_int(const internal_json *j)
{
    return j->number >= (double)INT_MAX   ? INT_MAX
           : j->number <= (double)INT_MIN ? INT_MIN
                                          : (int)j->number;
}

static nprfx_result parse_ref(nprfx_graph *g, const char *node, const char *input,
                              const internal_json *j, gref *ref)
{
    if (!json_is(j, INTERNAL_JSON_STRING))
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                           "node '%s': input '%s' must be a string \"node\" or \"node:channels\"",
                           node, input);
    ref->text = engine_strdup(j->string);
    const char *colon = strchr(j->string, ':');
    if (colon) {
        ref->sel = engine_strdup(colon + 1);
        ref->text[colon - j->string] = 0; /* text holds the node name */
    }
    ref->src = -1;
    return NPRFX_OK;
}

static nprfx_result set_value_json(nprfx_graph *g, gnode *n, int pi, const internal_json *j)
{
    const nprfx_param_desc *p = &n->desc->params[pi];
    nprfx_value v = n->params[pi];
    if (json_is(j, INTERNAL_JSON_STRING)) {
        free(n->param_text[pi]);
        n->param_text[pi] = engine_strdup(j->string);
        nprfx_result r = nprfx_param_parse(n->ctx, n->desc, p, n->param_text[pi], &v);
        if (r) return r;
    } else if (json_is_bool(j)) {
        v.v[0] = json_is(j, INTERNAL_JSON_TRUE) ? 1 : 0;
    } else if (json_is(j, INTERNAL_JSON_NUMBER)) {
        if (p->type == NPRFX_PARAM_COLOR)
            v.v[0] = v.v[1] = v.v[2] = j->number, v.v[3] = 1;
        else
            v.v[0] = j->number;
    } else if (json_is(j, INTERNAL_JSON_ARRAY) && p->type == NPRFX_PARAM_COLOR) {
        int k = j->count;
        if (k != 3 && k != 4)
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                               "node '%s': %s.%s: a colour is an array of 3 or 4 numbers", n->name,
                               n->desc->id, p->name);
        v.v[3] = 1;
        const internal_json *e = j->child;
        for (int c = 0; c < k; c++, e = e->next) {
            if (!json_is(e, INTERNAL_JSON_NUMBER))
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                   "node '%s': %s.%s: colour components must be numbers", n->name,
                                   n->desc->id, p->name);
            v.v[c] = e->number;
        }
    } else {
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': %s.%s: unsupported value type",
                           n->name, n->desc->id, p->name);
    }
    if (p->type != NPRFX_PARAM_STRING && !json_is(j, INTERNAL_JSON_STRING)) {
        nprfx_result r = nprfx_param_check(n->ctx, n->desc, p, &v);
        if (r) return r;
    }
    n->params[pi] = v;
    return NPRFX_OK;
}

/* Fields of the built-in I/O nodes, by name: the same table serves JSON keys and --set. */
typedef struct io_field {
    const char *key;
    size_t offset; /* of a char* or int in gnode */
    int is_int;
    unsigned kinds; /* bit per gkind */
} io_field;
#define KB(k) (1u << (k))
static const io_field io_fields[] = {
    {"path", offsetof(gnode, path), 0, KB(GK_READ) | KB(GK_WRITE)},
    {"preview", offsetof(gnode, preview), 0, KB(GK_WRITE)},
    {"colorspace", offsetof(gnode, colorspace), 0, KB(GK_READ) | KB(GK_WRITE)},
    {"vectors", offsetof(gnode, vectors), 0, KB(GK_READ)},
    {"aovs", offsetof(gnode, aovs), 0, KB(GK_READ)},
    {"cryptomatte", offsetof(gnode, cryptomatte), 0, KB(GK_READ)},
    {"compression", offsetof(gnode, compression), 0, KB(GK_WRITE)},
    {"display", offsetof(gnode, display), 0, KB(GK_WRITE)},
    {"view", offsetof(gnode, view), 0, KB(GK_WRITE)},
    {"part", offsetof(gnode, part), 0, KB(GK_READ)},
    {"view", offsetof(gnode, read_view), 0, KB(GK_READ)},
    {"half", offsetof(gnode, half), 1, KB(GK_WRITE)},
    {"raw", offsetof(gnode, raw), 1, KB(GK_WRITE)},
    {"scene", offsetof(gnode, scene), 0, KB(GK_SYNTH)},
    {"size", 0, 2, KB(GK_SYNTH)},
};

static nprfx_result set_io_field(nprfx_graph *g, gnode *n, const char *key, const char *text,
                                 const internal_json *j)
{
    for (size_t i = 0; i < sizeof io_fields / sizeof io_fields[0]; i++) {
        const io_field *f = &io_fields[i];
        if (strcmp(f->key, key) || !(f->kinds & KB(n->kind))) continue;
        if (f->is_int == 2) { /* size "WxH" */
            const char *s = j ? (json_is(j, INTERNAL_JSON_STRING) ? j->string : NULL) : text;
            if (!s || sscanf(s, "%dx%d", &n->width, &n->height) != 2 || n->width < 1 ||
                n->height < 1 || n->width > 65536 || n->height > 65536)
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                   "node '%s': size must be \"WxH\", e.g. \"320x180\"", n->name);
            return NPRFX_OK;
        }
        if (f->is_int) {
            int *dst = (int *)((char *)n + f->offset);
            if (j && json_is_bool(j))
                *dst = json_is(j, INTERNAL_JSON_TRUE);
            else if (j && json_is(j, INTERNAL_JSON_NUMBER))
                *dst = json_int(j) != 0;
            else if (text && (!strcmp(text, "true") || !strcmp(text, "1") || !strcmp(text, "on")))
                *dst = 1;
            else if (text && (!strcmp(text, "false") || !strcmp(text, "0") || !strcmp(text, "off")))
                *dst = 0;
            else
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': %s must be true or false",
                                   n->name, key);
            return NPRFX_OK;
        }
        const char *s = j ? (json_is(j, INTERNAL_JSON_STRING) ? j->string : NULL) : text;
        if (!s)
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': %s must be a string", n->name,
                               key);
        if (!strcmp(key, "vectors") && strcmp(s, "auto") && strcmp(s, "none") &&
            !nprfx_aov_vectors_find(s)) {
            char list[256] = "none, auto";
            for (int v = 0; nprfx_aov_vectors_at(v); v++) {
                strcat(list, ", ");
                strcat(list, nprfx_aov_vectors_at(v)->name);
            }
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': vectors '%s' is not one of: %s",
                               n->name, s, list);
        }
        if (!strcmp(key, "aovs") && strcmp(s, "auto") && nprfx_aov_profile_find(s) < 0 &&
            !internal_aov_map_named(s)) {
            char list[256] = "auto";
            for (int p = 0; p < NPRFX_PROFILE_COUNT; p++) {
                strcat(list, ", ");
                strcat(list, nprfx_aov_profile_name(p));
            }
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                               "node '%s': aovs '%s' is not one of: %s, or a mapping file "
                               "(NAME.json)",
                               n->name, s, list);
        }
        char **dst = (char **)((char *)n + f->offset);
        free(*dst);
        /* an empty preview is none (--set out.preview= turns previews off) */
        *dst = !strcmp(key, "preview") && !*s ? NULL : engine_strdup(s);
        if (!strcmp(key, "aovs")) { /* a mapping file is read again when the plate settles */
            internal_aov_map_free(n->aov_map);
            n->aov_map = NULL;
        }
        return NPRFX_OK;
    }
    static const char *const kind_names[] = {"node", "read", "synth", "write"};
    return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM, "node '%s': '%s' is not a field of %s",
                       n->name, key, kind_names[n->kind]);
}

/* The earlier entry of e's object with e's key, or NULL. JSON leaves a key given twice to the
 * reader; a graph refuses it rather than keep one silently. Callers stop at the first unknown
 * key, so the scan stays within the few keys a node, its inputs or its params can have. */
static const internal_json *earlier_same_key(const internal_json *first, const internal_json *e)
{
    for (const internal_json *c = first; c && c != e; c = c->next)
        if (c->key && e->key && !strcmp(c->key, e->key)) return c;
    return NULL;
}

static nprfx_result parse_node(nprfx_graph *g, gnode *n, const internal_json *j)
{
    if (!json_is(j, INTERNAL_JSON_OBJECT))
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s' must be a JSON object", n->name);
    const internal_json *type = internal_json_member(j, "node");
    if (!json_is(type, INTERNAL_JSON_STRING))
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                           "node '%s' has no \"node\": \"TYPE\" entry (nprfx list shows the types)",
                           n->name);
    const char *t = type->string;
    if (!strcmp(t, "read"))
        n->kind = GK_READ;
    else if (!strcmp(t, "write"))
        n->kind = GK_WRITE;
    else if (!strcmp(t, "synth"))
        n->kind = GK_SYNTH;
    else {
        n->kind = GK_NODE;
        n->desc = nprfx_node_find(t);
        if (!n->desc)
            return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_NODE,
                               "node '%s': unknown node type '%s' (nprfx list shows the types)",
                               n->name, t);
    }
    n->ninputs = n->kind == GK_NODE ? n->desc->num_inputs : n->kind == GK_WRITE ? 1 : 0;
    if (n->ninputs) {
        n->inputs = calloc((size_t)n->ninputs, sizeof *n->inputs);
        if (!n->inputs) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        for (int i = 0; i < n->ninputs; i++)
            n->inputs[i].src = -1;
    }
    if (n->kind == GK_NODE) {
        n->params = calloc((size_t)n->desc->num_params + 1, sizeof *n->params);
        n->param_text = calloc((size_t)n->desc->num_params + 1, sizeof *n->param_text);
        if (!n->params || !n->param_text)
            return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        nprfx_node_defaults(n->desc, n->params);
    }
    n->half = 0;
    for (const internal_json *e = j->child; e; e = e->next) {
        nprfx_result r = NPRFX_OK;
        if (earlier_same_key(j->child, e))
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': entry '%s' is given twice",
                               n->name, e->key);
        if (!strcmp(e->key, "node") || !strcmp(e->key, "comment")) continue;
        if (!strcmp(e->key, "inputs")) {
            if (!json_is(e, INTERNAL_JSON_OBJECT))
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                   "node '%s': \"inputs\" must be an object", n->name);
            for (const internal_json *in = e->child; in; in = in->next) {
                int idx = -1;
                if (earlier_same_key(e->child, in))
                    return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                       "node '%s': input '%s' is given twice", n->name, in->key);
                if (n->kind == GK_NODE)
                    idx = nprfx_node_input_index(n->desc, in->key);
                else if (n->kind == GK_WRITE && !strcmp(in->key, "image"))
                    idx = 0;
                if (idx < 0) {
                    char list[512] = "";
                    for (int k = 0; n->kind == GK_NODE && k < n->desc->num_inputs; k++) {
                        if (k) strncat(list, ", ", sizeof list - strlen(list) - 1);
                        strncat(list, n->desc->inputs[k].name, sizeof list - strlen(list) - 1);
                    }
                    return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM,
                                       "node '%s': no input named '%s' (inputs: %s)", n->name,
                                       in->key, n->kind == GK_NODE ? list : "image");
                }
                if ((r = parse_ref(g, n->name, in->key, in, &n->inputs[idx]))) return r;
            }
        } else if (!strcmp(e->key, "params") && n->kind == GK_NODE) {
            if (!json_is(e, INTERNAL_JSON_OBJECT))
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                   "node '%s': \"params\" must be an object", n->name);
            for (const internal_json *pv = e->child; pv; pv = pv->next) {
                if (earlier_same_key(e->child, pv))
                    return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                       "node '%s': param '%s' is given twice", n->name, pv->key);
                int pi = nprfx_node_param_index(n->desc, pv->key);
                if (pi < 0)
                    return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM,
                                       "node '%s': %s has no param '%s' (nprfx help %s)", n->name,
                                       n->desc->id, pv->key, n->desc->id);
                if ((r = set_value_json(g, n, pi, pv))) return r;
            }
        } else if (n->kind != GK_NODE) {
            if ((r = set_io_field(g, n, e->key, NULL, e))) return r;
        } else {
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                               "node '%s': unexpected entry '%s' (use \"inputs\" and \"params\")",
                               n->name, e->key);
        }
    }
    if ((n->kind == GK_READ || n->kind == GK_WRITE) && !n->path)
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': %s needs a \"path\"", n->name,
                           n->kind == GK_READ ? "read" : "write");
    if (n->kind == GK_SYNTH && (!n->scene || !n->width))
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                           "node '%s': synth needs \"scene\" and \"size\" (e.g. \"256x256\")",
                           n->name);
    return NPRFX_OK;
}

/* After the graph's nodes, a flow node per read node ("READ:flow", a name no reference can give),
 * with its defaults and no input: neither planned nor rendered unless the plates' settling wires
 * it in for a plate that has no motion vectors (graph_aovs.c), as the footage graphs use it. */
static nprfx_result add_fallback_flows(nprfx_graph *g)
{
    if (!nprfx_node_find("flow")) return NPRFX_OK;
    internal_json *j = NULL;
    nprfx_result r = internal_json_parse(g->ctx, "{\"node\": \"flow\"}", &j);
    for (int i = 0, visible = g->count; !r && i < visible; i++) {
        g->nodes[i].flow = -1;
        if (g->nodes[i].kind != GK_READ) continue;
        gnode *f = &g->nodes[g->count];
        char name[600];
        snprintf(name, sizeof name, "%s:flow", g->nodes[i].name);
        f->name = engine_strdup(name);
        if (!f->name) r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        if (r || internal_graph_names_add(g, g->count) >= 0) {
            free(f->name);
            f->name = NULL;
            continue; /* a node of the graph already has the name (written with an escape) */
        }
        g->count++; /* what nprfx_graph_free releases */
        char scope[700];
        snprintf(scope, sizeof scope, "node '%s'", name);
        if (nprfx_context_create_scoped(g->ctx, scope, &f->ctx))
            r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        if (!r) r = parse_node(g, f, j);
        f->flow = -1;
        g->nodes[i].flow = g->count - 1;
    }
    internal_json_free(j);
    return r;
}

/* Resolve references to node indices, check required inputs and cycles. */
static nprfx_result link_graph(nprfx_graph *g)
{
    for (int i = 0; i < g->count; i++) {
        gnode *n = &g->nodes[i];
        for (int k = 0; k < n->ninputs; k++) {
            gref *r = &n->inputs[k];
            const char *iname = n->kind == GK_NODE ? n->desc->inputs[k].name : "image";
            if (r->text) {
                r->src = internal_graph_find_node(g, r->text);
                if (r->src < 0)
                    return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                       "node '%s': input '%s' refers to '%s', which is not a node "
                                       "of this graph",
                                       n->name, iname, r->text);
                if (g->nodes[r->src].kind == GK_WRITE)
                    return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                       "node '%s': input '%s' refers to write node '%s'", n->name,
                                       iname, r->text);
            } else if (n->kind == GK_WRITE || !(n->desc->inputs[k].flags & NPRFX_INPUT_OPTIONAL)) {
                return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                                   "node '%s': required input '%s' is not connected", n->name,
                                   iname);
            }
        }
    }
    return internal_graph_check_cycles(g);
}

/* first_frame and last_frame from frames_text: the shot temporal nodes see. */
static nprfx_result shot_range(nprfx_graph *g)
{
    nprfx_frame_list fl;
    nprfx_result r = nprfx_seq_parse_frames(g->ctx, g->frames_text, &fl);
    if (r) return r;
    g->first_frame = INT_MAX;
    g->last_frame = INT_MIN;
    for (int k = 0; k < fl.count; k++) {
        if (fl.frames[k] < g->first_frame) g->first_frame = fl.frames[k];
        if (fl.frames[k] > g->last_frame) g->last_frame = fl.frames[k];
    }
    nprfx_seq_frames_free(&fl);
    return NPRFX_OK;
}

nprfx_result nprfx_graph_parse(nprfx_context *ctx, const char *json, const char *base_dir,
                               const nprfx_graph_options *opt, nprfx_graph **out)
{
    *out = NULL;
    internal_json *root = NULL;
    nprfx_result pr = internal_json_parse(ctx, json, &root);
    if (pr) return pr;
    nprfx_graph *g = calloc(1, sizeof *g);
    if (!g) {
        internal_json_free(root);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    g->ctx = ctx;
    g->base_dir = engine_strdup(base_dir ? base_dir : ".");
    g->cache_limit = (opt && opt->cache_bytes) ? opt->cache_bytes : (size_t)2 << 30;
    g->cache_entry_limit = NPRFX_GRAPH_CACHE_ENTRIES;
    g->tile = opt ? opt->tile : 0;
    if (opt && opt->size >= offsetof(nprfx_graph_options, hook) + sizeof opt->hook && opt->hook) {
        g->hook = *opt->hook;
        g->has_hook = 1;
    }
    if (opt && opt->size >= offsetof(nprfx_graph_options, variant) + sizeof opt->variant)
        g->variant = opt->variant;
    if (opt && opt->size >= offsetof(nprfx_graph_options, progress) + sizeof opt->progress)
        g->progress = opt->progress;
    if (opt && opt->size >= offsetof(nprfx_graph_options, notice_user) + sizeof opt->notice_user) {
        g->notice = opt->notice;
        g->notice_user = opt->notice_user;
    }
    if (opt && opt->size >= offsetof(nprfx_graph_options, no_pool) + sizeof opt->no_pool)
        g->no_pool = opt->no_pool;
    if (opt && opt->size >= offsetof(nprfx_graph_options, strip_rows) + sizeof opt->strip_rows)
        g->strip_option = opt->strip_rows;
    g->strip_rows = g->strip_option > 0 ? g->strip_option : 0;
    internal_graph_io_init(
        &g->io,
        opt && opt->size >= offsetof(nprfx_graph_options, io) + sizeof opt->io ? opt->io : NULL);
    g->pool = frame_pool_create(g->no_pool);
    /* tests: pixels a node leaves unset in a reused frame show as NaN (docs/design.md §1) */
    if (g->pool && getenv("NPRFX_POOL_POISON")) frame_pool_poison(g->pool, 1);
    if (!g->pool) {
        internal_json_free(root);
        free(g->base_dir);
        free(g);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    g->out_dir = opt && opt->output_dir ? engine_strdup(opt->output_dir) : NULL;
    g->first_frame = 1;
    g->last_frame = 1;
    nprfx_result r = NPRFX_OK;
    const internal_json *nodes = internal_json_member(root, "nodes");
    if (!json_is(root, INTERNAL_JSON_OBJECT) || !json_is(nodes, INTERNAL_JSON_OBJECT)) {
        r = nprfx_error(ctx, NPRFX_ERR_PARSE, "a graph is an object with a \"nodes\" object");
        goto done;
    }
    for (const internal_json *e = root->child; e; e = e->next) {
        if (!strcmp(e->key, "nodes") && e != nodes) {
            r = nprfx_error(ctx, NPRFX_ERR_PARSE, "top-level entry 'nodes' is given twice");
            goto done;
        }
        if (!strcmp(e->key, "comment") && json_is(e, INTERNAL_JSON_STRING) && !g->comment &&
            !(g->comment = engine_strdup(e->string))) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            goto done;
        }
        if (!strcmp(e->key, "nodes") || !strcmp(e->key, "comment")) continue;
        /* A key given twice is ambiguous (JSON leaves it to the reader): refuse it rather than
         * take one silently. */
        if ((!strcmp(e->key, "frames") && g->frames_text) || (!strcmp(e->key, "ocio") && g->ocio) ||
            (!strcmp(e->key, "format") && g->fmt_text) ||
            (!strcmp(e->key, "design_width") && g->design_width > 0)) {
            r = nprfx_error(ctx, NPRFX_ERR_PARSE, "top-level entry '%s' is given twice", e->key);
            goto done;
        }
        if (!strcmp(e->key, "frames") && json_is(e, INTERNAL_JSON_STRING))
            g->frames_text = engine_strdup(e->string);
        else if (!strcmp(e->key, "frames") && json_is(e, INTERNAL_JSON_NUMBER)) {
            char buf[32];
            snprintf(buf, sizeof buf, "%d", json_int(e));
            g->frames_text = engine_strdup(buf);
        } else if (!strcmp(e->key, "ocio") && json_is(e, INTERNAL_JSON_STRING))
            g->ocio = engine_strdup(e->string);
        else if (!strcmp(e->key, "format") && json_is(e, INTERNAL_JSON_STRING))
            g->fmt_text = engine_strdup(e->string);
        else if (!strcmp(e->key, "design_width")) {
            if (!json_is(e, INTERNAL_JSON_NUMBER) || !(e->number >= 1) ||
                e->number > NPRFX_DESIGN_WIDTH_MAX) {
                r = nprfx_error(ctx, NPRFX_ERR_PARSE,
                                "top-level entry 'design_width' must be the plate width in "
                                "pixels the params were set for (a number, 1 to %d)",
                                NPRFX_DESIGN_WIDTH_MAX);
                goto done;
            }
            g->design_width = e->number;
        } else if (!strcmp(e->key, "knobs")) {
            if ((r = internal_graph_knobs_parse(g, e))) goto done;
        } else {
            r = nprfx_error(ctx, NPRFX_ERR_PARSE,
                            "unexpected top-level entry '%s' (expected frames, nodes, ocio, "
                            "format, design_width, knobs)",
                            e->key);
            goto done;
        }
    }
    int count = nodes->count;
    if (count > NPRFX_GRAPH_MAX_NODES) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                        "the graph has %d nodes; at most %d are allowed", count,
                        NPRFX_GRAPH_MAX_NODES);
        goto done;
    }
    /* room for a fallback flow node per read node (add_fallback_flows) */
    int reads = 0;
    for (const internal_json *e = nodes->child; e; e = e->next) {
        const internal_json *t = internal_json_member(e, "node");
        reads += json_is(t, INTERNAL_JSON_STRING) && !strcmp(t->string, "read");
    }
    g->nodes = calloc((size_t)(count + reads ? count + reads : 1), sizeof *g->nodes);
    if (!g->nodes) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        goto done;
    }
    if ((r = internal_graph_names_init(g, count + reads))) goto done;
    g->stats = calloc((size_t)(count + reads ? count + reads : 1), sizeof *g->stats);
    if (!g->stats) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        goto done;
    }
    int i = 0;
    for (const internal_json *e = nodes->child; e; e = e->next, i++) {
        g->count = i + 1; /* what nprfx_graph_free releases */
        g->nodes[i].name = engine_strdup(e->key);
        if (!g->nodes[i].name) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            goto done;
        }
        if (internal_graph_names_add(g, i) >= 0) {
            r = nprfx_error(ctx, NPRFX_ERR_PARSE,
                            "node name '%s' is given twice in \"nodes\" (names must be unique)",
                            e->key);
            goto done;
        }
        char scope[512];
        snprintf(scope, sizeof scope, "node '%s'", e->key);
        if (nprfx_context_create_scoped(ctx, scope, &g->nodes[i].ctx)) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            goto done;
        }
        if ((r = parse_node(g, &g->nodes[i], e))) goto done;
    }
    if (g->frames_text && (r = shot_range(g))) goto done;
    r = link_graph(g);
    if (!r) r = internal_graph_check_limits(g);
    if (!r) r = nprfx_image_limit(ctx, &g->mem_limit);
    g->visible = g->count;
    if (!r) r = internal_graph_knobs_check(g);
    if (!r) r = add_fallback_flows(g);
done:
    internal_json_free(root);
    if (r) {
        nprfx_graph_free(g);
        return r;
    }
    *out = g;
    return NPRFX_OK;
}

nprfx_result nprfx_graph_load(nprfx_context *ctx, const char *path, const nprfx_graph_options *opt,
                              nprfx_graph **out)
{
    *out = NULL;
    /* a graph file of a million nodes is tens of megabytes: a gigabyte is not one */
    char *text = engine_read_text(ctx, path, "graph file", 1L << 30);
    if (!text) return NPRFX_ERR_IO;
    char *dir = engine_strdup(path);
    char *slash = strrchr(dir, '/');
    if (slash)
        *slash = 0;
    else
        strcpy(dir, ".");
    /* Every message of this graph, at load and at render, names its file first. */
    nprfx_context *gctx = NULL;
    nprfx_result r = nprfx_context_create_scoped(ctx, path, &gctx);
    if (!r) r = nprfx_graph_parse(gctx, text, dir, opt, out);
    if (!r)
        (*out)->owned_ctx = gctx;
    else
        nprfx_context_destroy(gctx);
    free(dir);
    free(text);
    return r;
}

void nprfx_graph_free(nprfx_graph *g)
{
    if (!g) return;
    internal_graph_prefetch_stop(g); /* its frames go back to the pool first */
    for (int failed; g->write_jobs;) {
        double end;
        internal_graph_write_jobs_reap(g, g->write_jobs->frame, &failed, &end);
    }
    free(g->prefetch);
    internal_graph_cache_clear(g);
    frame_pool_destroy(g->pool);
    free(g->plan_uses);
    free(g->plan_temporal);
    free(g->plan_first);
    free(g->plan_readers);
    free(g->stats);
    for (int i = 0; i < g->count; i++) {
        gnode *n = &g->nodes[i];
        if (n->state && n->desc && n->desc->state_free) n->desc->state_free(n->state);
        free(n->seeded);
        free(n->read_channels);
        if (n->instance && g->has_hook && g->hook.release)
            g->hook.release(g->hook.user, n->desc, n->instance);
        for (int k = 0; k < n->ninputs; k++) {
            free(n->inputs[k].sel);
            free(n->inputs[k].text);
        }
        free(n->inputs);
        for (int k = 0; n->param_text && k < n->desc->num_params; k++)
            free(n->param_text[k]);
        free(n->param_text);
        free(n->params);
        free(n->name);
        nprfx_context_destroy(n->ctx);
        free(n->path);
        free(n->preview);
        free(n->colorspace);
        free(n->vectors);
        free(n->aovs);
        internal_aov_map_free(n->aov_map);
        free(n->cryptomatte);
        free(n->crypto);
        free(n->depth_inverse);
        free(n->position_from);
        free(n->compression);
        free(n->scene);
        free(n->display);
        free(n->view);
        free(n->part);
        free(n->read_view);
        free(n->wants); /* the strings belong to references and tables */
    }
    free(g->nodes);
    free(g->analysis_path);
    free(g->name_slots);
    nprfx_context_destroy(g->owned_ctx);
    free(g->frames_text);
    free(g->base_dir);
    free(g->out_dir);
    free(g->ocio);
    free(g->fmt_text);
    free(g->comment);
    internal_graph_knobs_free(g);
    free(g);
}

nprfx_result nprfx_graph_set(nprfx_graph *g, const char *assignment)
{
    const char *eq = strchr(assignment, '=');
    const char *dot = strchr(assignment, '.');
    if (!eq || !dot || dot > eq)
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                           "--set '%s': expected NODE.PARAM=VALUE (e.g. blend.opacity=0.5)",
                           assignment);
    char name[256], key[256];
    snprintf(name, sizeof name, "%.*s", (int)(dot - assignment), assignment);
    snprintf(key, sizeof key, "%.*s", (int)(eq - dot - 1), dot + 1);
    /* NODE with * (a knob such as strokes*.radius): every processing node it matches */
    if (strchr(name, '*')) return internal_graph_set_matching(g, name, key, eq + 1);
    int i = internal_graph_find_node(g, name);
    if (i < 0)
        return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_NODE, "--set: the graph has no node '%s'",
                           name);
    gnode *n = &g->nodes[i];
    g->plan_ready = 0; /* params decide which inputs are read at other frames */
    if (n->kind != GK_NODE) {
        /* the plates are settled again from what the read now points at */
        g->plates_settled = 0;
        n->prepared = 0;
        return set_io_field(g, n, key, eq + 1, NULL);
    }
    int pi = nprfx_node_param_index(n->desc, key);
    if (pi < 0)
        return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM,
                           "--set: node '%s' (%s) has no param '%s' (nprfx help %s)", name,
                           n->desc->id, key, n->desc->id);
    /* The value as a JSON string would give it: params parse their text as in a graph file. */
    internal_json s = {INTERNAL_JSON_STRING};
    s.string = (char *)(eq + 1);
    nprfx_result r = set_value_json(g, n, pi, &s);
    if (n->state && n->desc->state_free) { /* a changed param invalidates any cache */
        n->desc->state_free(n->state);
        n->state = NULL;
    }
    return r;
}

nprfx_result nprfx_graph_set_shot(nprfx_graph *g, const char *frames)
{
    char *old = g->frames_text;
    int first = g->first_frame, last = g->last_frame;
    g->frames_text = engine_strdup(frames);
    if (!g->frames_text) {
        g->frames_text = old;
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    nprfx_result r = shot_range(g);
    if (r) {
        free(g->frames_text);
        g->frames_text = old;
        g->first_frame = first;
        g->last_frame = last;
        return r;
    }
    free(old);
    /* temporal nodes' caches hold results for the old shot (a tone range, noise states) */
    for (int i = 0; i < g->count; i++) {
        gnode *n = &g->nodes[i];
        if (n->state && n->desc && n->desc->state_free) n->desc->state_free(n->state);
        free(n->seeded);
        n->state = NULL;
    }
    return NPRFX_OK;
}

nprfx_result nprfx_graph_frames(nprfx_graph *g, const char *override, nprfx_frame_list *out)
{
    const char *text = override ? override : g->frames_text ? g->frames_text : "1";
    nprfx_result r = nprfx_seq_parse_frames(g->ctx, text, out);
    if (r) return r;
    if (!g->frames_text && out->count > 0) {
        /* No shot range in the graph: the frames asked for are the shot temporal nodes see. */
        g->first_frame = g->last_frame = out->frames[0];
        for (int k = 1; k < out->count; k++) {
            if (out->frames[k] < g->first_frame) g->first_frame = out->frames[k];
            if (out->frames[k] > g->last_frame) g->last_frame = out->frames[k];
        }
    }
    if (override && g->frames_text)
        for (int k = 0; k < out->count; k++)
            if (out->frames[k] < g->first_frame || out->frames[k] > g->last_frame) {
                int f = out->frames[k];
                nprfx_seq_frames_free(out);
                return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_RANGE,
                                   "frame %d is outside the graph's frames %s", f, g->frames_text);
            }
    return NPRFX_OK;
}

nprfx_result nprfx_graph_synthesize_reads(nprfx_graph *g, int w, int h, const char *scene)
{
    for (int i = 0; i < g->count; i++) {
        gnode *n = &g->nodes[i];
        if (n->kind != GK_READ && n->kind != GK_SYNTH) continue;
        /* a read of one file, not a sequence, is a texture the look paints with (a painterly
         * art map), not a render's plate: it stays */
        if (n->kind == GK_READ && n->path && !nprfx_seq_has_pattern(n->path)) continue;
        if (n->kind == GK_READ) {
            char *s = engine_strdup(scene);
            if (!s) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            free(n->scene);
            n->scene = s;
            n->kind = GK_SYNTH;
        }
        n->width = w;
        n->height = h;
    }
    if (g->fmt_text) {
        char buf[64];
        snprintf(buf, sizeof buf, "%dx%d", w, h);
        char *s = engine_strdup(buf);
        if (!s) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        free(g->fmt_text);
        g->fmt_text = s;
    }
    internal_graph_cache_clear(g);
    g->plan_ready = 0;
    nprfx_result r = nprfx_image_limit(g->ctx, &g->mem_limit);
    return r ? r : internal_graph_check_limits(g);
}
