/* nprfx CLI — what the graph's files share: the parsed graph (nodes, references, the result
 * cache) and the helpers that parsing (graph_load.c), evaluation (graph_eval.c) and writing
 * (graph_write.c) all use. Never installed. */
#ifndef NPRFX_CLI_INTERNAL_GRAPH_H
#define NPRFX_CLI_INTERNAL_GRAPH_H

#include "graph.h"
#include "nprfx/nprfx.h"

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
    void *instance;     /* the render hook's per-node slot */
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
    int variant;              /* nprfx_graph_variant */
    nprfx_context *owned_ctx; /* ctx when the graph made it (the file's scope): freed with it */
};

char *internal_graph_strdup(const char *s);
double internal_graph_now(void);
/* The index of the node called name, or -1. */
int internal_graph_find_node(const nprfx_graph *g, const char *name);
void internal_graph_centry_free(centry *e);
/* Copies of n channel names (NULL names become "C"). */
char **internal_graph_names_dup(const char *const *names, int n);
/* pattern at frame, relative to dir unless absolute, into buf. */
void internal_graph_resolve_path(const nprfx_graph *g, const char *dir, const char *pattern,
                                 int frame, char *buf, size_t n);
/* The channels (indices into names, nc of them) input k of node n takes from its source: the
 * reference's selection, else the input's AOV hint, else all, checked against the input's
 * channel count; *count receives how many (idx has room for 256). */
nprfx_result internal_graph_input_channels(nprfx_graph *g, const gnode *n, int k,
                                           const char *const *names, int nc, int *idx, int *count);
/* The names of the 4 channels a read node with "vectors" appends to its plates. */
extern const char *const internal_graph_motion_names[4];
/* Read node n's motion convention ("vectors"): the plate channels (indices into names) the 4
 * appended channels are made of, and the factor each is multiplied by. */
nprfx_result internal_graph_motion_sources(nprfx_graph *g, const gnode *n, const char *file,
                                           const char *const *names, int nc, int *idx,
                                           double *sign);
/* The view of the channels of entry e that input k of node n uses: e's pixels when they are
 * adjacent, else *scratch (malloc'd, the caller frees). */
nprfx_result internal_graph_select_input(nprfx_graph *g, const gnode *n, int k, const centry *e,
                                         nprfx_image *view, float **scratch);
/* NPRFX_VARIANT_SHOWER_DOOR: alter a plate just read (graph_variant.c). */
void internal_graph_variant_plate(const nprfx_graph *g, nprfx_image *im, char **names);
/* NPRFX_VARIANT_WHITE: the params node n renders frame with (its own, or *copy altered). */
const nprfx_value *internal_graph_variant_params(const nprfx_graph *g, const gnode *n, int frame,
                                                 nprfx_value *copy);
/* The cache entry of node at frame, evaluated (and its inputs) when not cached. */
nprfx_result internal_graph_eval(nprfx_graph *g, int node, int frame, centry **out);

#endif
