/* nprfx CLI — node graphs: load a JSON graph file, validate it against the node descriptors,
 * and evaluate it frame by frame with a memory-bounded cache of node results. */
#ifndef NPRFX_CLI_GRAPH_H
#define NPRFX_CLI_GRAPH_H

#include <stddef.h>

#include "nprfx/node.h"
#include "seq.h"

typedef struct nprfx_graph nprfx_graph;

/* Renders one window of one node instead of calling desc->render directly: the OpenFX test
 * host uses it to drive the nodes through the plugin bundle. `instance` is a per-graph-node slot
 * (NULL at first) the hook may keep a plugin instance in; it is released with `release`. */
typedef struct nprfx_render_hook {
    nprfx_result (*render)(void *user, const nprfx_render_args *args, void **instance);
    void (*release)(void *user, const nprfx_node_desc *node, void *instance);
    void *user;
    /* Non-zero: the hook's renders write the nodes' exports (NPRFX_PARAM_EXPORT) themselves, as
     * a plug-in in a host must, so the runner does not write them too: a file that appears is
     * then the plug-in's. */
    int exports;
} nprfx_render_hook;

/* How the graph's plates and seeds are altered, for measuring a look against its baselines
 * (nprfx measure). */
typedef enum nprfx_graph_variant {
    NPRFX_VARIANT_NONE = 0, /* the graph as it is */
    /* Patterns stuck to the screen: the plates' motion vectors are zeroed and their anchors
     * (Pref, rest, UV, P, Position) replaced by screen position, x / width and y / width. */
    NPRFX_VARIANT_SHOWER_DOOR = 1,
    /* Patterns drawn anew every frame: every node's 'seed' param is changed each frame. */
    NPRFX_VARIANT_WHITE = 2
} nprfx_graph_variant;

typedef struct nprfx_graph_options {
    size_t size;                   /* sizeof(nprfx_graph_options) */
    size_t cache_bytes;            /* bound on cached node results (0: 2 GiB) */
    int tile;                      /* > 0: render nodes in tiles of this size (tests invariance) */
    const char *output_dir;        /* prefix for relative write paths (NULL: current directory) */
    const nprfx_render_hook *hook; /* NULL: call the node's render function */
    int variant;                   /* nprfx_graph_variant (appended: read when size covers it) */
    /* Non-zero: a temporal node whose render fetches many other frames (a recursion's warm-up)
     * reports them on stderr once it has taken a second, about once a second (appended). */
    int progress;
    /* Appended: what a user should know but that is no error, e.g. which part of a multi-part
     * file a read took and which parts it left out; once per read node (NULL: silent). */
    void (*notice)(void *user, const char *message);
    void *notice_user;
} nprfx_graph_options;

/* Parse a graph file. Read paths are resolved relative to the graph file's directory; write
 * paths relative to the current directory (or output_dir). */
nprfx_result nprfx_graph_load(nprfx_context *ctx, const char *path, const nprfx_graph_options *opt,
                              nprfx_graph **out);
/* Parse a graph from JSON text (base_dir resolves relative read paths). */
nprfx_result nprfx_graph_parse(nprfx_context *ctx, const char *json, const char *base_dir,
                               const nprfx_graph_options *opt, nprfx_graph **out);
void nprfx_graph_free(nprfx_graph *g);

/* Override a value: "node.param=value" (params of processing nodes, or path/preview/... of read
 * and write nodes). */
nprfx_result nprfx_graph_set(nprfx_graph *g, const char *assignment);

/* Replace the graph's "frames" (the shot temporal nodes see, and the frames rendered by
 * default), e.g. for a shot longer or shorter than the graph was written for (--shot). */
nprfx_result nprfx_graph_set_shot(nprfx_graph *g, const char *frames);
/* The shot's frames from the graph's "frames" entry (or `override`, e.g. from --frames, which
 * must lie inside the shot when the graph declares one). Free with nprfx_seq_frames_free. */
nprfx_result nprfx_graph_frames(nprfx_graph *g, const char *override, nprfx_frame_list *out);

/* Evaluate every write node at `frame`; *written receives the number of files written. */
nprfx_result nprfx_graph_render_frame(nprfx_graph *g, int frame, int *written);

/* Describe the write nodes' outputs ("out/x.####.exr (preview out/x.####.png)"), one per line. */
void nprfx_graph_describe_outputs(const nprfx_graph *g, char *buf, size_t n);

/* Every file pattern the graph writes: write nodes' paths and previews and the export params of
 * processing nodes, placed under the output directory as their frames' files are, frame tokens
 * kept ("out/x.####.exr"); in graph order, possibly repeated. Free with
 * nprfx_graph_output_patterns_free. */
nprfx_result nprfx_graph_output_patterns(const nprfx_graph *g, char ***paths, int *count);
void nprfx_graph_output_patterns_free(char **paths, int count);

/* Warnings, one a line into buf, when rendering `frames` frames of g would take hours: many frames,
 * or a node whose footprint (nprfx_node_footprint) makes every pixel read a huge area. Before a
 * single pixel is read, so it knows no frame size: counts, not seconds. Returns how many. */
int nprfx_graph_cost_warnings(nprfx_graph *g, int frames, char *buf, size_t n);

/* Whether the graph has a node called name. */
int nprfx_graph_has_node(const nprfx_graph *g, const char *name);
/* Number of write nodes (a graph to run needs at least one). */
int nprfx_graph_write_count(const nprfx_graph *g);

/* Evaluate node `name` at `frame` without writing; the view stays valid until the next call
 * into the graph. */
nprfx_result nprfx_graph_eval(nprfx_graph *g, const char *name, int frame, nprfx_image *out);

/* Seconds spent inside node render functions since the last call (for bench); resets. */
double nprfx_graph_take_render_seconds(nprfx_graph *g);
/* Items the nodes counted since the last call (nprfx_render_args.items; for bench); resets. */
long long nprfx_graph_take_render_items(nprfx_graph *g);

#endif
