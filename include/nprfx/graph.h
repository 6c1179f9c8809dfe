/* nprfx — the graph engine: load a JSON graph of nodes (docs/graphs.md), validate it against
 * the node descriptors, and evaluate it frame by frame under a memory plan, with a bounded cache
 * of node results and strip renders. Plates are read and outputs written through the nprfx_io
 * the caller gives (nprfx/io.h; libnprfx-io's nprfx_io_oiio()). The runner (`nprfx run`), the
 * OpenFX test host and any binding share this one engine. */
#ifndef NPRFX_GRAPH_H
#define NPRFX_GRAPH_H

#include <stddef.h>
#include <stdint.h>

#include "nprfx/export.h"
#include "nprfx/io.h"
#include "nprfx/node.h"
#include "nprfx/seq.h"

#ifdef __cplusplus
extern "C" {
#endif

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

/* For a render hook, during its render: the node connected to input `input` of the node being
 * rendered (fetch_user is the render's args->fetch_user), with its params; NULL when the input is
 * not connected or comes from a read or synth. The OpenFX test host's --footage mode serves a
 * plug-in the picture a flow node reads instead of the flow (tests/ofxhost/render.c). */
NPRFX_API const nprfx_node_desc *nprfx_graph_hook_upstream(void *fetch_user, int input,
                                                           const nprfx_value **params);
/* Input `up_input` of that node at `frame`, with the channels that node reads: a view valid as
 * args->fetch's are (NPRFX_FETCH_KEEP further fetches). */
NPRFX_API nprfx_result nprfx_graph_hook_fetch_upstream(void *fetch_user, int input, int up_input,
                                                       int frame, nprfx_image *out);

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
    /* Appended. Non-zero: no frame-buffer pool and no memory plan: every frame is calloc'd and
     * freed, and results stay in the cache until evicted (--no-pool; the pixels must not
     * change). */
    int no_pool;
    /* Appended. Write nodes whose whole chain renders by rows (NPRFX_NODE_ROWS) are rendered a
     * strip of this many rows at a time, reading and writing only those rows (plus the margins
     * the footprints need): > 0 always, 0 only when whole frames would pass the memory limit
     * (nprfx_graph_plan chooses), < 0 never (--strip-rows). */
    int strip_rows;
    /* Appended: how the graph reads plates and writes outputs (NULL: it cannot; a read or write
     * fails saying so). The table is copied at load. */
    const nprfx_io *io;
} nprfx_graph_options;

/* What one node of a graph cost since it loaded (nprfx run --stats, bench-graph). */
typedef struct nprfx_graph_node_stats {
    const char *name, *type; /* type: the node's id, or "read", "synth", "write" */
    int kind;                /* 0 processing node, 1 read, 2 synth, 3 write */
    long long calls;         /* frames it rendered (a node re-rendered after eviction counts
                                again) */
    double seconds;          /* in its own render, read or write, not in nodes it fetched */
    size_t bytes;            /* frames it allocated: outputs and channel scratch */
    size_t fresh_bytes;      /* of those, the ones the pool had no buffer for */
} nprfx_graph_node_stats;

/* The graph's memory estimate for one frame (nprfx_graph_plan). */
typedef struct nprfx_graph_plan_info {
    uint64_t peak;         /* bytes of frames held at the most, the pool's idle ones included */
    uint64_t need;         /* of those, the most in use at once: what must fit the limit */
    uint64_t limit;        /* the memory limit (UINT64_MAX: none) */
    int width, height;     /* the frame size the estimate is for */
    const char *peak_node; /* the node whose output frame makes the peak */
    /* Appended: > 0 when the frames render a strip of this many rows at a time; need is then
     * what strips hold at once (whole_need: what whole frames would). */
    int strip_rows;
    uint64_t whole_need;
    /* Appended: of need, the bytes stateful nodes keep between frames (their caches, as
     * desc->state_bytes bounds them). */
    uint64_t state;
} nprfx_graph_plan_info;

/* Parse a graph file. Read paths are resolved relative to the graph file's directory; write
 * paths relative to the current directory (or output_dir). */
NPRFX_API nprfx_result nprfx_graph_load(nprfx_context *ctx, const char *path,
                                        const nprfx_graph_options *opt, nprfx_graph **out);
/* Parse a graph from JSON text (base_dir resolves relative read paths). */
NPRFX_API nprfx_result nprfx_graph_parse(nprfx_context *ctx, const char *json, const char *base_dir,
                                         const nprfx_graph_options *opt, nprfx_graph **out);
NPRFX_API void nprfx_graph_free(nprfx_graph *g);

/* Override a value: "node.param=value" (params of processing nodes, or path/preview/... of read
 * and write nodes). */
NPRFX_API nprfx_result nprfx_graph_set(nprfx_graph *g, const char *assignment);

/* Replace the graph's "frames" (the shot temporal nodes see, and the frames rendered by
 * default), e.g. for a shot longer or shorter than the graph was written for (--shot). */
NPRFX_API nprfx_result nprfx_graph_set_shot(nprfx_graph *g, const char *frames);
/* The plate width in pixels the graph's pixel params were set for ("design_width"): on a plate
 * W pixels wide every PIXELS param is multiplied by W / width and every AREA param by its square
 * (0: none, the params are in each plate's own pixels). Refused outside 0 .. 1000000. */
NPRFX_API nprfx_result nprfx_graph_set_design_width(nprfx_graph *g, double width);
NPRFX_API double nprfx_graph_design_width(const nprfx_graph *g);
/* The shot's frames from the graph's "frames" entry (or `override`, e.g. from --frames, which
 * must lie inside the shot when the graph declares one). Free with nprfx_seq_frames_free. */
NPRFX_API nprfx_result nprfx_graph_frames(nprfx_graph *g, const char *override,
                                          nprfx_frame_list *out);

/* Evaluate every write node at `frame`; *written receives the number of files written. */
NPRFX_API nprfx_result nprfx_graph_render_frame(nprfx_graph *g, int frame, int *written);

/* As nprfx_graph_render_frame, but the write nodes only evaluate their inputs: nothing is
 * written (bench-graph times the compute apart from the file I/O). */
NPRFX_API nprfx_result nprfx_graph_compute_frame(nprfx_graph *g, int frame);

/* Describe the write nodes' outputs ("out/x.####.exr (preview out/x.####.png)"), one per line. */
NPRFX_API void nprfx_graph_describe_outputs(const nprfx_graph *g, char *buf, size_t n);

/* Every file pattern the graph writes: write nodes' paths and previews and the export params of
 * processing nodes, placed under the output directory as their frames' files are, frame tokens
 * kept ("out/x.####.exr"); in graph order, possibly repeated. Free with
 * nprfx_graph_output_patterns_free. */
NPRFX_API nprfx_result nprfx_graph_output_patterns(const nprfx_graph *g, char ***paths, int *count);
NPRFX_API void nprfx_graph_output_patterns_free(char **paths, int count);

/* Every read node's file pattern, resolved as a render resolves it (relative to the graph file),
 * frame tokens kept; *nodes (may be NULL) receives the read nodes' names (the graph's own strings,
 * valid while it lives). In graph order. Free the paths with nprfx_graph_output_patterns_free and
 * *nodes with free. */
NPRFX_API nprfx_result nprfx_graph_read_patterns(const nprfx_graph *g, char ***paths,
                                                 const char ***nodes, int *count);

/* Whether the graph has a shot of its own ("frames", or --shot through nprfx_graph_set_shot);
 * *first and *last receive the shot's first and last frame (its frames' range) when it has. */
NPRFX_API int nprfx_graph_shot(const nprfx_graph *g, int *first, int *last);

/* Warnings, one a line into buf, when rendering `frames` frames of g would take hours: many frames,
 * or a node whose footprint (nprfx_node_footprint) makes every pixel read a huge area. Before a
 * single pixel is read, so it knows no frame size: counts, not seconds. Returns how many. */
NPRFX_API int nprfx_graph_cost_warnings(nprfx_graph *g, int frames, char *buf, size_t n);

/* Whether the graph has a node called name. */
NPRFX_API int nprfx_graph_has_node(const nprfx_graph *g, const char *name);
/* Number of write nodes (a graph to run needs at least one). */
NPRFX_API int nprfx_graph_write_count(const nprfx_graph *g);

/* Evaluate node `name` at `frame` without writing; the view (and *names, its channels' names,
 * when names is not NULL) stays valid until the next call into the graph. */
NPRFX_API nprfx_result nprfx_graph_eval(nprfx_graph *g, const char *name, int frame,
                                        nprfx_image *out, const char *const **names);

/* ---- shot statistics: measured once, stored beside the outputs (docs/design.md §1) ---- */

/* Render once every node that measures over the shot (nprfx_node_measures_shot: tone's range),
 * at the shot's first frame, so that each state holds its measurement; *measured (may be NULL)
 * receives how many hold one. The graph needs a shot ("frames" or nprfx_graph_set_shot). */
NPRFX_API nprfx_result nprfx_graph_analyze(nprfx_graph *g, int *measured);
/* One measuring node's measurement, for a front end that keeps it elsewhere than in a file (a
 * plug-in's hidden param): its state as text (*text malloc'd; NULL while it has measured
 * nothing), and a node seeded from such text, which still measures again when its rendered frame
 * differs. Errors: a node that measures nothing, unreadable text. */
NPRFX_API nprfx_result nprfx_graph_node_measured(nprfx_graph *g, int node, char **text);
NPRFX_API nprfx_result nprfx_graph_node_seed(nprfx_graph *g, int node, const char *text);
/* How many of the graph's nodes measure over the shot (nprfx_node_measures_shot): 0 means an
 * analysis has nothing to store or seed. */
NPRFX_API int nprfx_graph_measuring_nodes(const nprfx_graph *g);
/* Write what those states hold to `path` (JSON, under a temporary name then renamed), with the
 * shot and a fingerprint of every read node's files over it (sizes and times; no pixel). */
NPRFX_API nprfx_result nprfx_graph_analysis_save(nprfx_graph *g, const char *path);
/* Seed the measuring nodes' states from an analysis file; *seeded (may be NULL) receives how
 * many. A file measured for another shot or other plates (or plates changed since) seeds
 * nothing and gives a notice (nprfx_graph_options.notice); a seeded node whose rendered frame
 * differs from what was measured measures again, with a notice, so the pixels never depend on
 * the file. Errors: an unreadable or malformed file (the caller may go on without it). */
NPRFX_API nprfx_result nprfx_graph_analysis_load(nprfx_graph *g, const char *path, int *seeded);
/* Seeded nodes that found their frame differ from the analysis and measured again so far. */
NPRFX_API int nprfx_graph_analysis_stale(const nprfx_graph *g);
/* Where a graph loaded from graph_path keeps its analysis by default: beside its first write
 * node's output, named after the graph file ("out/main/main.analysis.json"). */
NPRFX_API void nprfx_graph_analysis_path(const nprfx_graph *g, const char *graph_path, char *buf,
                                         size_t n);

/* Estimate the memory that evaluating `frame` needs from the graph and the frame size alone
 * (plates' headers, synth sizes, "format"; no pixel is read), as the memory plan runs it: each
 * result freed after its last consumer, a temporal source's frames kept one frame longer, freed
 * buffers idle in the pool until reused. NPRFX_ERR_OUT_OF_MEMORY, naming the node and the sizes,
 * when the frames in use at once (need; idle buffers are given up under the limit) exceed the
 * memory limit; any other problem (a missing file, a bad channel name) is left to the render, which
 * reports it as it always has, and gives NPRFX_OK with out->peak 0. */
NPRFX_API nprfx_result nprfx_graph_plan(nprfx_graph *g, int frame, nprfx_graph_plan_info *out);

/* Per-node costs since the graph loaded: *stats gets g's count entries (valid while g lives). */
NPRFX_API int nprfx_graph_stats(const nprfx_graph *g, const nprfx_graph_node_stats **stats);
/* The most bytes the graph's frames held at once (cached, in use and idle in the pool). */
NPRFX_API size_t nprfx_graph_mem_peak(const nprfx_graph *g);

/* Make every read node of a frame sequence a synth node of `scene` at w x h (a read of one file,
 * a texture such as a painterly art map, stays), and every synth node and "format" that
 * size (bench-graph: a graph timed without its plates). */
NPRFX_API nprfx_result nprfx_graph_synthesize_reads(nprfx_graph *g, int w, int h,
                                                    const char *scene);

/* Seconds spent inside node render functions since the last call (for bench); resets. */
NPRFX_API double nprfx_graph_take_render_seconds(nprfx_graph *g);
/* The process's CPU seconds (all threads) over the same spans: on a loaded machine, what the
 * renders cost rather than how long they waited for a core; resets. */
NPRFX_API double nprfx_graph_take_render_cpu_seconds(nprfx_graph *g);
/* The bytes of frames the renders read (each input once) and wrote (the output once) since the
 * last call: the memory traffic no implementation can avoid (bench's floor); resets. */
NPRFX_API double nprfx_graph_take_render_bytes(nprfx_graph *g);
/* Items the nodes counted since the last call (nprfx_render_args.items; for bench); resets. */
NPRFX_API long long nprfx_graph_take_render_items(nprfx_graph *g);

/* ---- what a graph holds, for front ends that translate it (host projects, measurements) ---- */

/* A reference from an input to the node it reads ("plate:Vector.XY"). */
typedef struct nprfx_graph_ref {
    int src;    /* node index, -1 when not connected */
    char *sel;  /* channel selection (nprfx/channels.h), NULL: by the input's AOV hint */
    char *text; /* the referenced node's name */
} nprfx_graph_ref;

typedef enum nprfx_graph_node_kind {
    NPRFX_GRAPH_NODE = 0, /* a processing node (desc) */
    NPRFX_GRAPH_READ = 1,
    NPRFX_GRAPH_SYNTH = 2,
    NPRFX_GRAPH_WRITE = 3
} nprfx_graph_node_kind;

/* One node as the graph holds it; every pointer is the graph's, valid while it lives and until
 * nprfx_graph_set changes the node. */
typedef struct nprfx_graph_node_info {
    size_t size; /* sizeof(nprfx_graph_node_info), set by the caller */
    const char *name;
    int kind;                    /* nprfx_graph_node_kind */
    const nprfx_node_desc *desc; /* NPRFX_GRAPH_NODE, else NULL */
    int ninputs;
    const nprfx_graph_ref *inputs;
    const nprfx_value *params;     /* desc->nparams values */
    const char *const *param_text; /* STRING params' text, per param (NULL elsewhere) */
    nprfx_context *ctx;            /* raises with "node 'NAME': " before the message */
    /* read, synth and write nodes' fields as the graph gives them (NULL or 0 when absent) */
    const char *path, *preview, *colorspace, *vectors, *compression, *scene, *display, *view;
    const char *part, *read_view;
    int half, raw, width, height;
    /* Appended. A read node after its first read: the channels it reads of its files (only
     * those its readers use, and what its motion channels are made of), comma-separated, and
     * how many its files have; NULL and 0 before. */
    const char *read_channels;
    int file_channels;
} nprfx_graph_node_info;

/* One of the graph's knobs: the params worth turning its author lists ("knobs": ["light.out_low",
 * "strokes*.orientation", ...]; * matches any part of node names, and one knob sets every node it
 * matches). Pointers are the graph's, valid while it lives and until nprfx_graph_set. */
typedef struct nprfx_graph_knob_info {
    size_t size;                   /* sizeof(nprfx_graph_knob_info), set by the caller */
    const char *name;              /* as the graph gives it: "strokes*.orientation" */
    const char *help;              /* the graph's words on what it does in this look, or NULL */
    const char *node;              /* the first node it sets */
    const nprfx_node_desc *desc;   /* that node's descriptor */
    const nprfx_param_desc *param; /* the param's descriptor: type, ranges, help */
    const nprfx_value *value;      /* its value on that node */
    int nodes;                     /* how many nodes it sets */
} nprfx_graph_knob_info;

/* The graph file's "comment" (what it makes, how to use it), or NULL. */
NPRFX_API const char *nprfx_graph_comment(const nprfx_graph *g);
NPRFX_API int nprfx_graph_knob_count(const nprfx_graph *g);
NPRFX_API nprfx_result nprfx_graph_knob(const nprfx_graph *g, int i, nprfx_graph_knob_info *out);

NPRFX_API int nprfx_graph_node_count(const nprfx_graph *g);
/* The index of node `name`, or -1. */
NPRFX_API int nprfx_graph_node_index(const nprfx_graph *g, const char *name);
/* Node i (0 <= i < nprfx_graph_node_count) into *out, as far as out->size covers. */
NPRFX_API nprfx_result nprfx_graph_node(const nprfx_graph *g, int i, nprfx_graph_node_info *out);
/* The context the graph raises its errors through, and the folder relative reads resolve in. */
NPRFX_API nprfx_context *nprfx_graph_context(const nprfx_graph *g);
NPRFX_API const char *nprfx_graph_base_dir(const nprfx_graph *g);
/* A frame-numbered pattern at `frame`, relative to dir unless absolute, into buf. */
NPRFX_API void nprfx_graph_resolve_path(const nprfx_graph *g, const char *dir, const char *pattern,
                                        int frame, char *buf, size_t n);
/* The channels (indices into names, nc of them) input k of node `node` takes from its source:
 * the reference's selection, else the input's AOV hint, else all, checked against the input's
 * channel count; *count receives how many (idx has room for 256). */
NPRFX_API nprfx_result nprfx_graph_input_channels(nprfx_graph *g, int node, int k,
                                                  const char *const *names, int nc, int *idx,
                                                  int *count);
/* Settle what the read nodes' plates are, from `frame`'s headers: each one's renderer profile,
 * motion convention, decoded ids and depth, and the fallbacks inputs take for AOVs a plate lacks
 * (announced through the notice callback). nprfx_graph_check does it; a front end that
 * translates a graph calls it before asking about reads. */
NPRFX_API nprfx_result nprfx_graph_settle(nprfx_graph *g, int frame);
/* The motion convention read node `node` applies, as settled ("blender", "nuke", ...); NULL:
 * none. */
NPRFX_API const char *nprfx_graph_read_vectors(const nprfx_graph *g, int node);
/* How many channels read node `node` decodes beyond motion (object ids from Cryptomatte, depth
 * from 1/z): what a translation to another host would have to rebuild. */
NPRFX_API int nprfx_graph_read_decodes(const nprfx_graph *g, int node);
/* The names of the channels read node `node` appends to its plates as settled (motion first,
 * then decoded ids and depth), at most max of them into names; returns how many there are. */
NPRFX_API int nprfx_graph_read_extras(const nprfx_graph *g, int node, const char **names, int max);
/* Name k (0..3) of the channels a read node with "vectors" appends to its plates
 * ("motion_prev.X", ...). */
NPRFX_API const char *nprfx_graph_motion_name(int k);
/* Read node `node`'s motion convention: the plate channels (indices into names) its 4 appended
 * channels are made of, and the factor each is multiplied by. file names the plate in
 * messages. */
NPRFX_API nprfx_result nprfx_graph_motion_sources(nprfx_graph *g, int node, const char *file,
                                                  const char *const *names, int nc, int *idx,
                                                  double *sign);

/* ---- feeding a graph from elsewhere (a host's clips as its plates) -------------------------- */

/* One read node and what the graph takes from it. */
typedef struct nprfx_graph_source_info {
    size_t size;      /* sizeof(nprfx_graph_source_info), set by the caller */
    int node;         /* the read node's index */
    const char *name; /* its name (the graph's string) */
    int sequence;     /* 1: its path has frame tokens (the render's plates); 0: one file (a map) */
    /* A bit (1u << aov) for every canonical AOV (nprfx/aov.h) the graph's inputs read from it,
     * by selection ("plate:depth", "plate:beauty.RGB") or by their AOV hint; for a sequence also
     * what stands in for a missing one (beauty always; uv and position for rest, position for
     * uv, depth for all three). An input that takes the whole plate counts as beauty. */
    unsigned aovs;
    /* The first selection that names plate channels rather than an AOV ("plate:Vector.XY"):
     * what only the renderer's own files can give; NULL when none. */
    const char *raw;
} nprfx_graph_source_info;

/* The graph's read nodes, in graph order. */
NPRFX_API int nprfx_graph_source_count(const nprfx_graph *g);
NPRFX_API nprfx_result nprfx_graph_source(const nprfx_graph *g, int i,
                                          nprfx_graph_source_info *out);
/* The channels (indices into names, nc of them: a plate of read node `node` with the channels
 * its read appends) that AOV `aov` is read from, as an input selecting it by name takes them;
 * *count receives how many (idx has room for 256). An error names the AOV and the profile. */
NPRFX_API nprfx_result nprfx_graph_aov_channels(nprfx_graph *g, int node, int aov,
                                                const char *const *names, int nc, int *idx,
                                                int *count);
/* AOV `aov` of read node `node`'s plate at `frame`, as an input that selects it by name receives
 * it: in nprfx's conventions (motion in pixels, y down; ids decoded; depth as z), fallbacks
 * applied. *out is allocated (free with nprfx_image_free). */
NPRFX_API nprfx_result nprfx_graph_eval_aov(nprfx_graph *g, int node, int aov, int frame,
                                            nprfx_image *out);

/* The frames of AOV `aov` of read node `source` (-1: of any AOV: a read decodes every channel
 * the graph wants of its file at each frame it reads) that evaluating node `node` at `frame`
 * reads, as
 * runs of frames within the shot (at most max; a last run covers what did not fit): each
 * node's nprfx_node_frames_needed at each frame it is evaluated at, through the graph, with
 * what the nodes' states already hold. `present`: the AOVs (bits) the source has; what an absent
 * one is made of is read instead (the picture for albedo, light and motion: optical flow reads
 * the neighbouring frame; depth for rest, uv and position). A front end that serves the plates
 * declares these frames to its host (the OpenFX look plug-ins' frames needed). */
NPRFX_API nprfx_result nprfx_graph_frames_read(nprfx_graph *g, int node, int frame, int source,
                                               int aov, unsigned present, nprfx_frame_range *ranges,
                                               int max, int *count);

/* ---- checking and running a shot ------------------------------------------------------------ */

/* Everything a render of `frames` would refuse before a pixel is read: a graph without a write
 * node, and the memory plan of its first frame (nprfx_graph_plan; plan may be NULL). Reads plate
 * headers only and allocates no frame. */
NPRFX_API nprfx_result nprfx_graph_check(nprfx_graph *g, const nprfx_frame_list *frames,
                                         nprfx_graph_plan_info *plan);

/* What nprfx_graph_run reports after each frame. */
typedef struct nprfx_graph_progress {
    int done, count;     /* frames rendered or failed so far (this one included), of count */
    int frame;           /* the frame just finished */
    nprfx_result result; /* NPRFX_OK, or the frame's error (its message raised through ctx) */
    int written;         /* files the frame wrote */
    double seconds;      /* the frame's wall time */
    double elapsed;      /* since the run began */
} nprfx_graph_progress;

typedef struct nprfx_graph_run_options {
    size_t size;    /* sizeof(nprfx_graph_run_options) */
    int keep_going; /* non-zero: a failed frame does not stop the run */
    /* After each frame, rendered or failed (NULL: none); a non-zero return stops the run there
     * (a user's cancel), which is no error. */
    int (*progress)(void *user, const nprfx_graph_progress *p);
    /* At the end of the run: every node's costs since the graph loaded (NULL: none). */
    void (*stats)(void *user, const nprfx_graph_node_stats *stats, int count);
    void *user;
    /* 0: the next frame's plates decode while a frame computes and, when the context's
     * executor has 4 or more workers, a frame's files are written while the next computes
     * (progress then comes once a frame's files are written, a frame behind); non-zero: each
     * frame read, computed and written before the next starts (less memory, the same pixels) */
    int serial;
} nprfx_graph_run_options;

/* What a run did. */
typedef struct nprfx_graph_run_summary {
    int rendered, failed; /* frames */
    int files;            /* files written */
    double seconds;
} nprfx_graph_run_summary;

/* Render `frames` in order: each frame's write nodes write their files (a failed frame writes
 * none and leaves the others' alone). NPRFX_OK when every frame rendered; otherwise the first
 * failed frame's code. summary may be NULL. */
NPRFX_API nprfx_result nprfx_graph_run(nprfx_graph *g, const nprfx_frame_list *frames,
                                       const nprfx_graph_run_options *opt,
                                       nprfx_graph_run_summary *summary);

#ifdef __cplusplus
}
#endif
#endif
