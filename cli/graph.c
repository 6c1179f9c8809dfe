#define _DEFAULT_SOURCE /* realpath */
/* nprfx CLI — node graphs: parsing (cJSON), validation against the descriptors, evaluation.
 *
 * A graph is {"frames": "1-24", "nodes": {NAME: {...}, ...}}. Processing nodes are
 * {"node": ID, "inputs": {INPUT: REF}, "params": {PARAM: VALUE}}; the built-in I/O nodes are
 * read {"node": "read", "path": SEQ, "colorspace": CS, "vectors": CONVENTION},
 * synth {"node": "synth", "scene": NAME, "size": "WxH"} and
 * write {"node": "write", "inputs": {"image": REF}, "path": SEQ, "preview": SEQ}.
 * A REF is "name" or "name:channels" (see channels.h).
 *
 * Evaluation pulls from the write nodes. Results are cached per (node, frame) under a byte bound
 * with least-recently-used eviction; temporal nodes fetch their inputs at other frames through the
 * same cache, and what a render call fetched stays pinned until it returns. */
#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "channels.h"
#include "graph.h"
#include "io.h"
#include "nprfx/nprfx.h"
#include "seq.h"

typedef enum gkind { GK_NODE, GK_READ, GK_SYNTH, GK_WRITE } gkind;

typedef struct gref {
    int src;   /* node index, -1 when not connected */
    char *sel; /* channel selection, NULL: by the input's AOV hint */
    char *text;
} gref;

typedef struct gnode {
    char *name;
    gkind kind;
    const nprfx_node_desc *desc; /* GK_NODE */
    int ninputs;
    gref *inputs;
    nprfx_value *params;
    char **param_text; /* owned copies of STRING values */
    void *state;
    void *instance; /* the render hook's per-node slot */
    nprfx_context *ctx; /* raises through the graph's with "node 'NAME'" before the message */
    /* read / write / synth */
    char *path, *preview, *colorspace, *vectors, *compression, *scene;
    char *display, *view;
    int half, raw, width, height;
    int mark; /* cycle detection */
} gnode;

typedef struct centry {
    int node, frame;
    nprfx_image im;
    char **names;
    size_t bytes;
    int pins;
    struct centry *prev, *next; /* most recent first */
} centry;

struct nprfx_graph {
    nprfx_context *ctx;
    gnode *nodes;
    int count;
    char *frames_text;
    int first_frame, last_frame;
    char *base_dir, *out_dir, *ocio;
    char *fmt_text; /* "format": "WxH" for graphs without inputs */
    centry *head;
    size_t cache_bytes, cache_limit;
    int tile;
    double render_seconds;
    long long render_items; /* what nodes counted (nprfx_render_args.items) */
    nprfx_render_hook hook;
    int has_hook;
    nprfx_context *owned_ctx; /* ctx when the graph made it (the file's scope): freed with it */
};

static char *xstrdup(const char *s)
{
    if (!s) return NULL;
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int find_node(const nprfx_graph *g, const char *name)
{
    for (int i = 0; i < g->count; i++)
        if (!strcmp(g->nodes[i].name, name)) return i;
    return -1;
}

/* ---------------------------------------------------------------- parsing ---- */

static nprfx_result parse_ref(nprfx_graph *g, const char *node, const char *input, const cJSON *j,
                              gref *ref)
{
    if (!cJSON_IsString(j))
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                           "node '%s': input '%s' must be a string \"node\" or \"node:channels\"",
                           node, input);
    ref->text = xstrdup(j->valuestring);
    const char *colon = strchr(j->valuestring, ':');
    if (colon) {
        ref->sel = xstrdup(colon + 1);
        ref->text[colon - j->valuestring] = 0; /* text holds the node name */
    }
    ref->src = -1;
    return NPRFX_OK;
}

static nprfx_result set_value_json(nprfx_graph *g, gnode *n, int pi, const cJSON *j)
{
    const nprfx_param_desc *p = &n->desc->params[pi];
    nprfx_value v = n->params[pi];
    if (cJSON_IsString(j)) {
        free(n->param_text[pi]);
        n->param_text[pi] = xstrdup(j->valuestring);
        nprfx_result r = nprfx_param_parse(n->ctx, n->desc, p, n->param_text[pi], &v);
        if (r) return r;
    } else if (cJSON_IsBool(j)) {
        v.v[0] = cJSON_IsTrue(j) ? 1 : 0;
    } else if (cJSON_IsNumber(j)) {
        if (p->type == NPRFX_PARAM_COLOR)
            v.v[0] = v.v[1] = v.v[2] = j->valuedouble, v.v[3] = 1;
        else
            v.v[0] = j->valuedouble;
    } else if (cJSON_IsArray(j) && p->type == NPRFX_PARAM_COLOR) {
        int k = cJSON_GetArraySize(j);
        if (k != 3 && k != 4)
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                               "node '%s': %s.%s: a colour is an array of 3 or 4 numbers", n->name,
                               n->desc->id, p->name);
        v.v[3] = 1;
        for (int c = 0; c < k; c++) {
            const cJSON *e = cJSON_GetArrayItem(j, c);
            if (!cJSON_IsNumber(e))
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                   "node '%s': %s.%s: colour components must be numbers", n->name,
                                   n->desc->id, p->name);
            v.v[c] = e->valuedouble;
        }
    } else {
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': %s.%s: unsupported value type",
                           n->name, n->desc->id, p->name);
    }
    if (p->type != NPRFX_PARAM_STRING && !cJSON_IsString(j)) {
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
    {"compression", offsetof(gnode, compression), 0, KB(GK_WRITE)},
    {"display", offsetof(gnode, display), 0, KB(GK_WRITE)},
    {"view", offsetof(gnode, view), 0, KB(GK_WRITE)},
    {"half", offsetof(gnode, half), 1, KB(GK_WRITE)},
    {"raw", offsetof(gnode, raw), 1, KB(GK_WRITE)},
    {"scene", offsetof(gnode, scene), 0, KB(GK_SYNTH)},
    {"size", 0, 2, KB(GK_SYNTH)},
};

static nprfx_result set_io_field(nprfx_graph *g, gnode *n, const char *key, const char *text,
                                 const cJSON *j)
{
    for (size_t i = 0; i < sizeof io_fields / sizeof io_fields[0]; i++) {
        const io_field *f = &io_fields[i];
        if (strcmp(f->key, key) || !(f->kinds & KB(n->kind))) continue;
        if (f->is_int == 2) { /* size "WxH" */
            const char *s = j ? (cJSON_IsString(j) ? j->valuestring : NULL) : text;
            if (!s || sscanf(s, "%dx%d", &n->width, &n->height) != 2 || n->width < 1 ||
                n->height < 1 || n->width > 65536 || n->height > 65536)
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                   "node '%s': size must be \"WxH\", e.g. \"320x180\"", n->name);
            return NPRFX_OK;
        }
        if (f->is_int) {
            int *dst = (int *)((char *)n + f->offset);
            if (j && cJSON_IsBool(j))
                *dst = cJSON_IsTrue(j);
            else if (j && cJSON_IsNumber(j))
                *dst = j->valueint != 0;
            else if (text && (!strcmp(text, "true") || !strcmp(text, "1") || !strcmp(text, "on")))
                *dst = 1;
            else if (text && (!strcmp(text, "false") || !strcmp(text, "0") || !strcmp(text, "off")))
                *dst = 0;
            else
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': %s must be true or false",
                                   n->name, key);
            return NPRFX_OK;
        }
        const char *s = j ? (cJSON_IsString(j) ? j->valuestring : NULL) : text;
        if (!s)
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s': %s must be a string", n->name,
                               key);
        char **dst = (char **)((char *)n + f->offset);
        free(*dst);
        *dst = xstrdup(s);
        return NPRFX_OK;
    }
    static const char *const kind_names[] = {"node", "read", "synth", "write"};
    return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM, "node '%s': '%s' is not a field of %s",
                       n->name, key, kind_names[n->kind]);
}

static nprfx_result parse_node(nprfx_graph *g, gnode *n, const cJSON *j)
{
    if (!cJSON_IsObject(j))
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE, "node '%s' must be a JSON object", n->name);
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(j, "node");
    if (!cJSON_IsString(type))
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                           "node '%s' has no \"node\": \"TYPE\" entry (nprfx list shows the types)",
                           n->name);
    const char *t = type->valuestring;
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
    for (const cJSON *e = j->child; e; e = e->next) {
        nprfx_result r = NPRFX_OK;
        if (!strcmp(e->string, "node") || !strcmp(e->string, "comment")) continue;
        if (!strcmp(e->string, "inputs")) {
            if (!cJSON_IsObject(e))
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                   "node '%s': \"inputs\" must be an object", n->name);
            for (const cJSON *in = e->child; in; in = in->next) {
                int idx = -1;
                if (n->kind == GK_NODE)
                    idx = nprfx_node_input_index(n->desc, in->string);
                else if (n->kind == GK_WRITE && !strcmp(in->string, "image"))
                    idx = 0;
                if (idx < 0) {
                    char list[512] = "";
                    for (int k = 0; n->kind == GK_NODE && k < n->desc->num_inputs; k++) {
                        if (k) strncat(list, ", ", sizeof list - strlen(list) - 1);
                        strncat(list, n->desc->inputs[k].name, sizeof list - strlen(list) - 1);
                    }
                    return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM,
                                       "node '%s': no input named '%s' (inputs: %s)", n->name,
                                       in->string, n->kind == GK_NODE ? list : "image");
                }
                if ((r = parse_ref(g, n->name, in->string, in, &n->inputs[idx]))) return r;
            }
        } else if (!strcmp(e->string, "params") && n->kind == GK_NODE) {
            if (!cJSON_IsObject(e))
                return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                   "node '%s': \"params\" must be an object", n->name);
            for (const cJSON *pv = e->child; pv; pv = pv->next) {
                int pi = nprfx_node_param_index(n->desc, pv->string);
                if (pi < 0)
                    return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM,
                                       "node '%s': %s has no param '%s' (nprfx help %s)", n->name,
                                       n->desc->id, pv->string, n->desc->id);
                if ((r = set_value_json(g, n, pi, pv))) return r;
            }
        } else if (n->kind != GK_NODE) {
            if ((r = set_io_field(g, n, e->string, NULL, e))) return r;
        } else {
            return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                               "node '%s': unexpected entry '%s' (use \"inputs\" and \"params\")",
                               n->name, e->string);
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

/* Resolve references to node indices, check required inputs and cycles. */
static nprfx_result link_graph(nprfx_graph *g)
{
    for (int i = 0; i < g->count; i++) {
        gnode *n = &g->nodes[i];
        for (int k = 0; k < n->ninputs; k++) {
            gref *r = &n->inputs[k];
            const char *iname = n->kind == GK_NODE ? n->desc->inputs[k].name : "image";
            if (r->text) {
                r->src = find_node(g, r->text);
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
    /* cycles: iterative marking by depth-first search */
    for (int i = 0; i < g->count; i++)
        g->nodes[i].mark = 0;
    for (int i = 0; i < g->count; i++) {
        /* walk every path from i; with small graphs a simple bounded DFS per node suffices */
        int stack[256], depth = 0;
        stack[depth++] = i;
        int steps = 0;
        while (depth > 0) {
            int cur = stack[--depth];
            if (++steps > 100000) break;
            gnode *n = &g->nodes[cur];
            for (int k = 0; k < n->ninputs; k++) {
                int s = n->inputs[k].src;
                if (s < 0) continue;
                if (s == i)
                    return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                       "the graph has a cycle through node '%s'", g->nodes[i].name);
                if (depth < 256) stack[depth++] = s;
            }
        }
    }
    return NPRFX_OK;
}

nprfx_result nprfx_graph_parse(nprfx_context *ctx, const char *json, const char *base_dir,
                               const nprfx_graph_options *opt, nprfx_graph **out)
{
    *out = NULL;
    cJSON *root = cJSON_Parse(json);
    if (!root) {
        const char *at = cJSON_GetErrorPtr();
        int line = 1;
        for (const char *c = json; at && c < at; c++)
            line += *c == '\n';
        return nprfx_error(ctx, NPRFX_ERR_PARSE, "malformed JSON near line %d", line);
    }
    nprfx_graph *g = calloc(1, sizeof *g);
    if (!g) {
        cJSON_Delete(root);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    g->ctx = ctx;
    g->base_dir = xstrdup(base_dir ? base_dir : ".");
    g->cache_limit = (opt && opt->cache_bytes) ? opt->cache_bytes : (size_t)2 << 30;
    g->tile = opt ? opt->tile : 0;
    if (opt && opt->size >= sizeof *opt && opt->hook) {
        g->hook = *opt->hook;
        g->has_hook = 1;
    }
    g->out_dir = opt && opt->output_dir ? xstrdup(opt->output_dir) : NULL;
    g->first_frame = 1;
    g->last_frame = 1;
    nprfx_result r = NPRFX_OK;
    const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(root, "nodes");
    if (!cJSON_IsObject(root) || !cJSON_IsObject(nodes)) {
        r = nprfx_error(ctx, NPRFX_ERR_PARSE, "a graph is an object with a \"nodes\" object");
        goto done;
    }
    for (const cJSON *e = root->child; e; e = e->next) {
        if (!strcmp(e->string, "nodes") || !strcmp(e->string, "comment")) continue;
        if (!strcmp(e->string, "frames") && cJSON_IsString(e))
            g->frames_text = xstrdup(e->valuestring);
        else if (!strcmp(e->string, "frames") && cJSON_IsNumber(e)) {
            char buf[32];
            snprintf(buf, sizeof buf, "%d", e->valueint);
            g->frames_text = xstrdup(buf);
        } else if (!strcmp(e->string, "ocio") && cJSON_IsString(e))
            g->ocio = xstrdup(e->valuestring);
        else if (!strcmp(e->string, "format") && cJSON_IsString(e))
            g->fmt_text = xstrdup(e->valuestring);
        else {
            r = nprfx_error(ctx, NPRFX_ERR_PARSE,
                            "unexpected top-level entry '%s' (expected frames, nodes, ocio)",
                            e->string);
            goto done;
        }
    }
    g->count = cJSON_GetArraySize(nodes);
    g->nodes = calloc((size_t)(g->count ? g->count : 1), sizeof *g->nodes);
    if (!g->nodes) {
        r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        goto done;
    }
    int i = 0;
    for (const cJSON *e = nodes->child; e; e = e->next, i++) {
        g->nodes[i].name = xstrdup(e->string);
        char scope[512];
        snprintf(scope, sizeof scope, "node '%s'", e->string);
        if (nprfx_context_create_scoped(ctx, scope, &g->nodes[i].ctx)) {
            r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            goto done;
        }
        if ((r = parse_node(g, &g->nodes[i], e))) goto done;
    }
    if (g->frames_text) {
        nprfx_frame_list fl;
        if ((r = nprfx_seq_parse_frames(ctx, g->frames_text, &fl))) goto done;
        g->first_frame = INT_MAX;
        g->last_frame = INT_MIN;
        for (int k = 0; k < fl.count; k++) {
            if (fl.frames[k] < g->first_frame) g->first_frame = fl.frames[k];
            if (fl.frames[k] > g->last_frame) g->last_frame = fl.frames[k];
        }
        nprfx_seq_frames_free(&fl);
    }
    r = link_graph(g);
done:
    cJSON_Delete(root);
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
    FILE *f = fopen(path, "rb");
    if (!f)
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot open graph file '%s': %s", path,
                           strerror(errno));
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = len >= 0 ? malloc((size_t)len + 1) : NULL;
    if (!text || fread(text, 1, (size_t)len, f) != (size_t)len) {
        fclose(f);
        free(text);
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read graph file '%s'", path);
    }
    fclose(f);
    text[len] = 0;
    char *dir = xstrdup(path);
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

static void centry_free(centry *e)
{
    if (!e) return;
    for (int c = 0; e->names && c < e->im.channels; c++)
        free(e->names[c]);
    free(e->names);
    nprfx_image_free(&e->im);
    free(e);
}

void nprfx_graph_free(nprfx_graph *g)
{
    if (!g) return;
    for (centry *e = g->head, *next; e; e = next) {
        next = e->next;
        centry_free(e);
    }
    for (int i = 0; i < g->count; i++) {
        gnode *n = &g->nodes[i];
        if (n->state && n->desc && n->desc->state_free) n->desc->state_free(n->state);
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
        free(n->compression);
        free(n->scene);
        free(n->display);
        free(n->view);
    }
    free(g->nodes);
    nprfx_context_destroy(g->owned_ctx);
    free(g->frames_text);
    free(g->base_dir);
    free(g->out_dir);
    free(g->ocio);
    free(g->fmt_text);
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
    int i = find_node(g, name);
    if (i < 0)
        return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_NODE, "--set: the graph has no node '%s'",
                           name);
    gnode *n = &g->nodes[i];
    if (n->kind != GK_NODE) return set_io_field(g, n, key, eq + 1, NULL);
    int pi = nprfx_node_param_index(n->desc, key);
    if (pi < 0)
        return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_PARAM,
                           "--set: node '%s' (%s) has no param '%s' (nprfx help %s)", name,
                           n->desc->id, key, n->desc->id);
    cJSON *s = cJSON_CreateString(eq + 1);
    nprfx_result r = s ? set_value_json(g, n, pi, s) : NPRFX_ERR_OUT_OF_MEMORY;
    cJSON_Delete(s);
    if (n->state && n->desc->state_free) { /* a changed param invalidates any cache */
        n->desc->state_free(n->state);
        n->state = NULL;
    }
    return r;
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

/* ---------------------------------------------------------------- cache ---- */

static void cache_unlink(nprfx_graph *g, centry *e)
{
    if (e->prev)
        e->prev->next = e->next;
    else
        g->head = e->next;
    if (e->next) e->next->prev = e->prev;
    e->prev = e->next = NULL;
}

static void cache_push_front(nprfx_graph *g, centry *e)
{
    e->prev = NULL;
    e->next = g->head;
    if (g->head) g->head->prev = e;
    g->head = e;
}

static centry *cache_find(nprfx_graph *g, int node, int frame)
{
    for (centry *e = g->head; e; e = e->next)
        if (e->node == node && e->frame == frame) {
            cache_unlink(g, e);
            cache_push_front(g, e);
            return e;
        }
    return NULL;
}

static void cache_evict(nprfx_graph *g)
{
    centry *e = g->head;
    while (e && e->next)
        e = e->next; /* least recently used is last */
    while (e && g->cache_bytes > g->cache_limit) {
        centry *prev = e->prev;
        if (e->pins == 0 && e != g->head) {
            cache_unlink(g, e);
            g->cache_bytes -= e->bytes;
            centry_free(e);
        }
        e = prev;
    }
}

/* Take ownership of im and names (names: nc malloc'd strings). */
static centry *cache_insert(nprfx_graph *g, int node, int frame, nprfx_image *im, char **names)
{
    centry *e = calloc(1, sizeof *e);
    if (!e) return NULL;
    e->node = node;
    e->frame = frame;
    e->im = *im;
    e->names = names;
    e->bytes = (size_t)nprfx_rect_width(im->bounds) * (size_t)nprfx_rect_height(im->bounds) *
               (size_t)im->channels * sizeof(float);
    memset(im, 0, sizeof *im);
    cache_push_front(g, e);
    g->cache_bytes += e->bytes;
    cache_evict(g);
    return e;
}

/* ---------------------------------------------------------------- evaluation ---- */

static nprfx_result eval(nprfx_graph *g, int node, int frame, centry **out);

static char **names_dup(const char *const *names, int n)
{
    char **d = calloc((size_t)n, sizeof *d);
    for (int i = 0; d && i < n; i++)
        d[i] = xstrdup(names[i] ? names[i] : "C");
    return d;
}

static void resolve_path(const nprfx_graph *g, const char *dir, const char *pattern, int frame,
                         char *buf, size_t n)
{
    char expanded[4096];
    if (nprfx_seq_expand(NULL, pattern, frame, expanded, sizeof expanded))
        snprintf(expanded, sizeof expanded, "%s", pattern);
    if (expanded[0] == '/' || !dir || !dir[0] || !strcmp(dir, "."))
        snprintf(buf, n, "%s", expanded);
    else
        snprintf(buf, n, "%s/%s", dir, expanded);
    (void)g;
}

/* The motion-vector conventions a read node can map onto nprfx's (DESIGN.md §2: pixels, y down,
 * motion_prev points to where the surface point was at frame-1). */
typedef struct vec_convention {
    const char *name;
    const char *layer; /* channels to look for: prev.x, prev.y, next.x, next.y */
    double sign[4];    /* multipliers applied to those channels */
} vec_convention;
/* Blender's Vector pass (measured on the sample renders, see samples/plates/README.md), image y
 * up: (X, Y) = position at frame i-1 minus position at i; (Z, W) = position at i minus position
 * at i+1. So motion_prev = (X, -Y) and motion_next = (-Z, W). Nuke's backward/forward vectors
 * point from this frame to the previous/next one, y up. */
static const vec_convention vec_conventions[] = {
    {"blender", "Vector.X,Vector.Y,Vector.Z,Vector.W", {1, -1, -1, 1}},
    {"nuke", "backward.u,backward.v,forward.u,forward.v", {1, -1, 1, -1}},
};

static nprfx_result add_motion_channels(nprfx_graph *g, gnode *n, const char *file,
                                        nprfx_plate *plate)
{
    const vec_convention *vc = NULL;
    for (size_t i = 0; i < sizeof vec_conventions / sizeof vec_conventions[0]; i++)
        if (!strcmp(n->vectors, vec_conventions[i].name)) vc = &vec_conventions[i];
    if (!vc)
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "node '%s': vectors '%s' is not one of: none, blender, nuke", n->name,
                           n->vectors);
    int idx[4], amb;
    char bad[256];
    if (nprfx_channels_select((const char *const *)plate->names, plate->nchannels, vc->layer, idx,
                              4, bad, sizeof bad, &amb) != 4)
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                           "node '%s': %s has no %s channel '%s' for vectors=%s", n->name, file,
                           amb ? "unique" : "", bad, n->vectors);
    int nc = plate->nchannels, nn = nc + 4;
    size_t npix =
        (size_t)nprfx_rect_width(plate->bounds) * (size_t)nprfx_rect_height(plate->bounds);
    float *px = malloc(npix * (size_t)nn * sizeof(float));
    char **names = realloc(plate->names, (size_t)nn * sizeof *names);
    if (!px || !names) {
        free(px);
        if (names) plate->names = names;
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading %s", file);
    }
    plate->names = names;
    static const char *const mnames[4] = {"motion_prev.X", "motion_prev.Y", "motion_next.X",
                                          "motion_next.Y"};
    for (int k = 0; k < 4; k++)
        names[nc + k] = xstrdup(mnames[k]);
    for (size_t p = 0; p < npix; p++) {
        const float *s = plate->pixels + p * (size_t)nc;
        float *d = px + p * (size_t)nn;
        memcpy(d, s, (size_t)nc * sizeof(float));
        for (int k = 0; k < 4; k++) {
            float v = s[idx[k]] * (float)vc->sign[k];
            d[nc + k] = isfinite(v) ? v : 0.0f;
        }
    }
    free(plate->pixels);
    plate->pixels = px;
    plate->nchannels = nn;
    return NPRFX_OK;
}

static nprfx_result eval_read(nprfx_graph *g, int node, int frame, nprfx_image *im, char ***names)
{
    gnode *n = &g->nodes[node];
    char file[4096];
    resolve_path(g, g->base_dir, n->path, frame, file, sizeof file);
    nprfx_plate plate;
    memset(&plate, 0, sizeof plate);
    nprfx_result r = nprfx_io_read(n->ctx, file, &plate);
    if (r) return r;
    if (n->vectors && strcmp(n->vectors, "none") && (r = add_motion_channels(g, n, file, &plate))) {
        nprfx_plate_free(&plate);
        return r;
    }
    if (n->colorspace) {
        int idx[3], amb;
        char bad[64];
        if (nprfx_channels_select((const char *const *)plate.names, plate.nchannels, "R,G,B", idx,
                                  3, bad, sizeof bad, &amb) == 3 &&
            idx[1] == idx[0] + 1 && idx[2] == idx[0] + 2) {
            nprfx_image rgb = nprfx_plate_view(&plate, idx[0], 3);
            nprfx_context *fctx = NULL; /* the file's name before what OCIO says */
            r = nprfx_context_create_scoped(n->ctx, file, &fctx);
            if (!r)
                r = nprfx_io_convert_colorspace(fctx, &rgb, n->colorspace, "scene_linear", g->ocio);
            nprfx_context_destroy(fctx);
            if (r) {
                nprfx_plate_free(&plate);
                return r;
            }
        }
    }
    im->data = plate.pixels;
    im->channels = plate.nchannels;
    im->pixel_stride = plate.nchannels;
    im->row_stride = (ptrdiff_t)nprfx_rect_width(plate.bounds) * plate.nchannels;
    im->bounds = plate.bounds;
    *names = plate.names;
    plate.pixels = NULL;
    plate.names = NULL;
    plate.nchannels = 0;
    nprfx_plate_free(&plate);
    return NPRFX_OK;
}

static nprfx_result eval_synth(nprfx_graph *g, int node, int frame, nprfx_image *im, char ***names)
{
    gnode *n = &g->nodes[node];
    int nc = nprfx_synth_channel_count();
    nprfx_result r = nprfx_image_alloc(g->ctx, nprfx_rect_make(0, 0, n->width, n->height), nc, im);
    if (r) return r;
    if ((r = nprfx_synth_render(n->ctx, n->scene, frame, im))) {
        nprfx_image_free(im);
        return r;
    }
    *names = names_dup(nprfx_synth_channel_names(), nc);
    return *names ? NPRFX_OK : nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
}

/* Pick the channels of entry e that input k of node n uses; the view shares e's pixels when
 * they are adjacent, else points into *scratch (malloc'd, caller frees). */
static nprfx_result select_input(nprfx_graph *g, const gnode *n, int k, const centry *e,
                                 nprfx_image *view, float **scratch)
{
    const gref *ref = &n->inputs[k];
    const nprfx_input_desc *in = n->kind == GK_NODE ? &n->desc->inputs[k] : NULL;
    const char *iname = in ? in->name : "image";
    const char *src = g->nodes[ref->src].name;
    const char *const *names = (const char *const *)e->names;
    int nc = e->im.channels, idx[256], count = -1;
    char bad[256];
    int amb = 0;
    if (ref->sel) {
        count = nprfx_channels_select(names, nc, ref->sel, idx, 256, bad, sizeof bad, &amb);
        if (count < 0) {
            char list[1024] = "";
            for (int c = 0; c < nc && strlen(list) < 900; c++) {
                if (c) strcat(list, " ");
                strncat(list, names[c], sizeof list - strlen(list) - 1);
            }
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s': '%s' %s in '%s' (channels: %s)", n->name,
                               iname, bad, amb ? "matches several channels" : "is not a channel",
                               src, list);
        }
    } else if (in && in->aov) {
        count = nprfx_channels_from_hint(names, nc, in->aov, idx, NPRFX_MAX_CHANNELS + 1);
        if (count < 0 && nc <= 4 && (in->channels == 0 || in->channels == nc)) {
            count = nc;
            for (int c = 0; c < nc; c++)
                idx[c] = c;
        }
        if (count < 0)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s': '%s' has no channel matching %s; name the "
                               "channels, e.g. \"%s:CHANNELS\"",
                               n->name, iname, src, in->aov, src);
    } else if (nc <= 4 || !in) {
        count = nc < 256 ? nc : 256; /* a write takes everything */
        for (int c = 0; c < count; c++)
            idx[c] = c;
    } else {
        count = nprfx_channels_from_hint(names, nc, "R,G,B,A|R,G,B|Combined.RGBA|Combined.RGB", idx,
                                         NPRFX_MAX_CHANNELS + 1);
        if (count < 0)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s': '%s' has %d channels and no R,G,B; name "
                               "the channels to use, e.g. \"%s:R,G,B\"",
                               n->name, iname, src, nc, src);
    }
    if (in) {
        if (in->channels > 0 && count != in->channels)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s' needs %d channel%s, '%s%s%s' gives %d",
                               n->name, iname, in->channels, in->channels > 1 ? "s" : "", src,
                               ref->sel ? ":" : "", ref->sel ? ref->sel : "", count);
        if (in->channels == 0 && count > 4)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s' takes 1 to 4 channels, '%s%s%s' gives %d",
                               n->name, iname, src, ref->sel ? ":" : "", ref->sel ? ref->sel : "",
                               count);
    }
    if (count < 1)
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                           "node '%s': input '%s' selects no channels", n->name, iname);
    int contiguous = 1;
    for (int c = 1; c < count; c++)
        contiguous &= idx[c] == idx[0] + c;
    /* A few channels out of a wide plate are packed anyway: nodes then stream through memory
     * instead of striding over the channels they do not use. */
    if (contiguous && nc <= 2 * count) {
        *view = nprfx_image_channels(&e->im, idx[0], count);
        return NPRFX_OK;
    }
    nprfx_image tmp;
    nprfx_result r = nprfx_image_alloc(g->ctx, e->im.bounds, count, &tmp);
    if (r) return r;
    for (int y = tmp.bounds.y0; y < tmp.bounds.y1; y++)
        for (int x = tmp.bounds.x0; x < tmp.bounds.x1; x++) {
            const float *s = nprfx_image_at(&e->im, x, y);
            float *d = nprfx_image_at(&tmp, x, y);
            for (int c = 0; c < count; c++)
                d[c] = s[idx[c]];
        }
    *scratch = tmp.data;
    *view = tmp;
    return NPRFX_OK;
}

/* Per-render bookkeeping. The node's own inputs at the current frame stay pinned for the whole
 * render call; frames it fetches go into a ring of NPRFX_FETCH_KEEP * 2 slots, so a long
 * recursion can fetch any number of frames while the most recent ones stay valid. */
typedef struct pin_slot {
    centry *e;
    float *scratch;
} pin_slot;
#define RING (NPRFX_FETCH_KEEP * 2)
typedef struct render_frame {
    nprfx_graph *g;
    int node;
    pin_slot base[32];
    int nbase;
    pin_slot ring[RING];
    long nfetch;
} render_frame;

static void slot_release(pin_slot *s)
{
    if (s->e) s->e->pins--;
    free(s->scratch);
    s->e = NULL;
    s->scratch = NULL;
}

static void render_frame_release(render_frame *rf)
{
    for (int i = 0; i < rf->nbase; i++)
        slot_release(&rf->base[i]);
    for (int i = 0; i < RING; i++)
        slot_release(&rf->ring[i]);
    rf->nbase = 0;
    cache_evict(rf->g);
}

static nprfx_result fetch_input(render_frame *rf, int k, int frame, int base, nprfx_image *out)
{
    nprfx_graph *g = rf->g;
    const gnode *n = &g->nodes[rf->node];
    if (k < 0 || k >= n->ninputs || n->inputs[k].src < 0)
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                           "node '%s': input '%s' is not connected", n->name,
                           k >= 0 && k < n->ninputs ? n->desc->inputs[k].name : "?");
    pin_slot *slot = base ? &rf->base[rf->nbase++] : &rf->ring[rf->nfetch++ % RING];
    slot_release(slot);
    centry *e;
    nprfx_result r = eval(g, n->inputs[k].src, frame, &e);
    if (r) return r;
    e->pins++;
    slot->e = e;
    return select_input(g, n, k, e, out, &slot->scratch);
}

static nprfx_result fetch_cb(void *user, int input, double time, nprfx_image *out)
{
    return fetch_input(user, input, (int)(time < 0 ? time - 0.5 : time + 0.5), 0, out);
}

/* Write the node's per-frame export (NPRFX_PARAM_EXPORT param set, desc->export_text given),
 * relative to the output directory like write nodes, through a temporary name. */
static nprfx_result export_node(nprfx_graph *g, const gnode *n, nprfx_render_args *a, int frame)
{
    const nprfx_node_desc *d = n->desc;
    if (!d->export_text) return NPRFX_OK;
    for (int i = 0; i < d->num_params; i++) {
        if (!(d->params[i].flags & NPRFX_PARAM_EXPORT) || !n->params[i].s || !n->params[i].s[0])
            continue;
        char path[4096];
        resolve_path(g, g->out_dir, n->params[i].s, frame, path, sizeof path);
        char *text = NULL;
        size_t len = 0;
        a->window = a->frame;
        char what[4200];
        snprintf(what, sizeof what, "export to %s", path);
        nprfx_context *ectx = NULL;
        nprfx_result r = nprfx_context_create_scoped(n->ctx, what, &ectx);
        if (!r) {
            a->ctx = ectx;
            r = nprfx_node_export(a, path, &text, &len);
            a->ctx = n->ctx;
        }
        if (!r) r = nprfx_io_write_text(ectx, path, text, len);
        nprfx_context_destroy(ectx);
        free(text);
        if (r) return r;
    }
    return NPRFX_OK;
}

static nprfx_result eval_node(nprfx_graph *g, int node, int frame, nprfx_image *im, char ***names)
{
    gnode *n = &g->nodes[node];
    const nprfx_node_desc *d = n->desc;
    render_frame rf;
    memset(&rf, 0, sizeof rf);
    rf.g = g;
    rf.node = node;
    nprfx_image inputs[32];
    int in_ch[32];
    memset(inputs, 0, sizeof inputs);
    memset(in_ch, 0, sizeof in_ch);
    nprfx_result r = NPRFX_OK;
    if (d->num_inputs > 32) return nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "too many inputs");
    nprfx_rect frame_rect = {0, 0, 0, 0};
    int have_rect = 0, first_input = -1;
    for (int k = 0; k < d->num_inputs; k++) {
        if (n->inputs[k].src < 0) continue;
        if ((r = fetch_input(&rf, k, frame, 1, &inputs[k]))) goto done;
        in_ch[k] = inputs[k].channels;
        if (d->inputs[k].flags & NPRFX_INPUT_UNALIGNED) continue; /* e.g. a lookup map */
        if (!have_rect) {
            frame_rect = inputs[k].bounds;
            have_rect = 1;
            first_input = k;
        } else if (!nprfx_rect_equal(frame_rect, inputs[k].bounds)) {
            r = nprfx_error(g->ctx, NPRFX_ERR_SIZE_MISMATCH,
                            "node '%s': input '%s' is %dx%d but input '%s' is %dx%d at frame %d",
                            n->name, d->inputs[k].name, nprfx_rect_width(inputs[k].bounds),
                            nprfx_rect_height(inputs[k].bounds), d->inputs[first_input].name,
                            nprfx_rect_width(frame_rect), nprfx_rect_height(frame_rect), frame);
            goto done;
        }
    }
    if (!have_rect) {
        int w = 0, h = 0;
        if (!g->fmt_text || sscanf(g->fmt_text, "%dx%d", &w, &h) != 2) {
            r = nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                            "node '%s' has no input connected: give the graph a \"format\": "
                            "\"WxH\"",
                            n->name);
            goto done;
        }
        frame_rect = nprfx_rect_make(0, 0, w, h);
    }
    nprfx_output_info oi;
    if ((r = nprfx_node_output_info(n->ctx, d, n->params, in_ch, &oi))) goto done;
    if ((r = nprfx_image_alloc(g->ctx, frame_rect, oi.channels, im))) goto done;
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = n->ctx;
    a.node = d;
    a.time = frame;
    a.render_scale = 1.0;
    a.frame = frame_rect;
    a.first_frame = g->first_frame;
    a.last_frame = g->last_frame;
    a.inputs = inputs;
    a.params = n->params;
    a.output = im;
    a.fetch = fetch_cb;
    a.fetch_user = &rf;
    a.state = &n->state;
    a.items = &g->render_items;
    int tile = g->tile > 0 ? g->tile : 1 << 30;
    double t0 = now_seconds();
    for (int ty = frame_rect.y0; ty < frame_rect.y1 && !r; ty += tile)
        for (int tx = frame_rect.x0; tx < frame_rect.x1 && !r; tx += tile) {
            a.window = nprfx_rect_intersect(
                frame_rect, nprfx_rect_make(tx, ty, tx + (tile < (1 << 29) ? tile : frame_rect.x1),
                                            ty + (tile < (1 << 29) ? tile : frame_rect.y1)));
            r = g->has_hook ? g->hook.render(g->hook.user, &a, &n->instance) : nprfx_node_render(&a);
        }
    g->render_seconds += now_seconds() - t0;
    if (!r) r = export_node(g, n, &a, frame);
    if (r) { /* the message went out through n->ctx, naming the node */
        nprfx_image_free(im);
        goto done;
    }
    *names = names_dup(oi.names, oi.channels);
done:
    render_frame_release(&rf);
    return r;
}

static nprfx_result eval(nprfx_graph *g, int node, int frame, centry **out)
{
    centry *e = cache_find(g, node, frame);
    if (e) {
        *out = e;
        return NPRFX_OK;
    }
    nprfx_image im;
    memset(&im, 0, sizeof im);
    char **names = NULL;
    nprfx_result r;
    switch (g->nodes[node].kind) {
    case GK_READ:
        r = eval_read(g, node, frame, &im, &names);
        break;
    case GK_SYNTH:
        r = eval_synth(g, node, frame, &im, &names);
        break;
    case GK_NODE:
        r = eval_node(g, node, frame, &im, &names);
        break;
    default:
        r = nprfx_error(g->ctx, NPRFX_ERR_INTERNAL, "write nodes have no output");
        break;
    }
    if (r) return r;
    e = cache_insert(g, node, frame, &im, names);
    if (!e) return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    *out = e;
    return NPRFX_OK;
}

/* Index list of the channels a preview shows: R,G,B,A when present, else the first <= 4. */
static nprfx_result preview_view(nprfx_graph *g, const nprfx_image *im, char **names,
                                 nprfx_image *view, float **scratch)
{
    int idx[4];
    int k = nprfx_channels_from_hint((const char *const *)names, im->channels,
                                     "R,G,B,A|R,G,B|Combined.RGBA|Combined.RGB", idx, 4);
    if (k < 0) {
        k = im->channels < 4 ? im->channels : 3;
        for (int c = 0; c < k; c++)
            idx[c] = c;
    }
    nprfx_result r = nprfx_image_alloc(g->ctx, im->bounds, k, view);
    if (r) return r;
    for (int y = im->bounds.y0; y < im->bounds.y1; y++)
        for (int x = im->bounds.x0; x < im->bounds.x1; x++) {
            const float *s = nprfx_image_at(im, x, y);
            float *d = nprfx_image_at(view, x, y);
            for (int c = 0; c < k; c++)
                d[c] = s[idx[c]];
        }
    *scratch = view->data;
    return NPRFX_OK;
}

/* Refuse to write over a file some read node of the graph takes as input at this frame: inputs
 * are never overwritten, even by a graph that names the same sequence twice. */
static nprfx_result check_not_input(nprfx_graph *g, const gnode *w, const char *out, int frame)
{
    char in[4096], rin[PATH_MAX], rout[PATH_MAX];
    if (!realpath(out, rout)) return NPRFX_OK; /* does not exist yet: cannot be an input */
    for (int i = 0; i < g->count; i++) {
        if (g->nodes[i].kind != GK_READ) continue;
        resolve_path(g, g->base_dir, g->nodes[i].path, frame, in, sizeof in);
        if (realpath(in, rin) && !strcmp(rin, rout))
            return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "node '%s': refusing to overwrite '%s', the input of read node '%s'",
                               w->name, out, g->nodes[i].name);
    }
    return NPRFX_OK;
}

static nprfx_result write_node(nprfx_graph *g, int node, int frame)
{
    gnode *n = &g->nodes[node];
    centry *e;
    nprfx_result r = eval(g, n->inputs[0].src, frame, &e);
    if (r) return r;
    e->pins++;
    nprfx_image view;
    float *scratch = NULL;
    r = select_input(g, n, 0, e, &view, &scratch);
    char **names = e->names;
    char **sel_names = NULL;
    if (!r && n->inputs[0].sel) {
        /* names of the selected channels, in selection order */
        int idx[256], amb;
        char bad[64];
        int k = nprfx_channels_select((const char *const *)e->names, e->im.channels,
                                      n->inputs[0].sel, idx, 256, bad, sizeof bad, &amb);
        sel_names = calloc((size_t)(k > 0 ? k : 1), sizeof *sel_names);
        for (int c = 0; sel_names && c < k; c++)
            sel_names[c] = e->names[idx[c]];
        names = sel_names;
    }
    char path[4096];
    if (!r) {
        resolve_path(g, g->out_dir, n->path, frame, path, sizeof path);
        r = check_not_input(g, n, path, frame);
    }
    if (!r) {
        nprfx_write_options wo = {sizeof wo, n->compression ? n->compression : "zip", n->half};
        r = nprfx_io_write(n->ctx, path, &view, (const char *const *)names, NULL, &wo);
    }
    if (!r && n->preview) {
        nprfx_image pv;
        float *pscratch = NULL;
        resolve_path(g, g->out_dir, n->preview, frame, path, sizeof path);
        r = check_not_input(g, n, path, frame);
        if (!r) r = preview_view(g, &view, names, &pv, &pscratch);
        if (!r) {
            nprfx_preview_options po = {sizeof po,  g->ocio, n->colorspace,
                                        n->display, n->view, n->raw};
            r = nprfx_io_write_preview(n->ctx, path, &pv, &po);
        }
        free(pscratch);
    }
    free(sel_names);
    free(scratch);
    e->pins--;
    return r;
}

nprfx_result nprfx_graph_render_frame(nprfx_graph *g, int frame, int *written)
{
    *written = 0;
    for (int i = 0; i < g->count; i++) {
        if (g->nodes[i].kind != GK_WRITE) continue;
        nprfx_result r = write_node(g, i, frame);
        if (r) return r;
        (*written)++;
    }
    return NPRFX_OK;
}

void nprfx_graph_describe_outputs(const nprfx_graph *g, char *buf, size_t n)
{
    buf[0] = 0;
    for (int i = 0; i < g->count; i++) {
        const gnode *w = &g->nodes[i];
        if (w->kind != GK_WRITE) continue;
        size_t len = strlen(buf);
        const char *dir = g->out_dir ? g->out_dir : "";
        const char *sep = dir[0] ? "/" : "";
        if (w->preview)
            snprintf(buf + len, n - len, "  %s%s%s  (previews %s%s%s)\n", dir, sep, w->path, dir,
                     sep, w->preview);
        else
            snprintf(buf + len, n - len, "  %s%s%s\n", dir, sep, w->path);
    }
}

long long nprfx_graph_take_render_items(nprfx_graph *g)
{
    long long n = g->render_items;
    g->render_items = 0;
    return n;
}

double nprfx_graph_take_render_seconds(nprfx_graph *g)
{
    double s = g->render_seconds;
    g->render_seconds = 0;
    return s;
}

int nprfx_graph_write_count(const nprfx_graph *g)
{
    int writes = 0;
    for (int i = 0; i < g->count; i++)
        writes += g->nodes[i].kind == GK_WRITE;
    return writes;
}

nprfx_result nprfx_graph_eval(nprfx_graph *g, const char *name, int frame, nprfx_image *out)
{
    int i = find_node(g, name);
    if (i < 0 || g->nodes[i].kind == GK_WRITE)
        return nprfx_error(g->ctx, NPRFX_ERR_UNKNOWN_NODE, "the graph has no node '%s' to evaluate",
                           name);
    centry *e;
    nprfx_result r = eval(g, i, frame, &e);
    if (!r) *out = e->im;
    return r;
}
