/* nprfx graph engine — the graph engine's bottom: the parsed graph (nodes, references, the result
 * cache's entries, the memory plan's and the statistics' fields) that every file of the engine
 * shares. Never installed. */
#ifndef NPRFX_CLI_GRAPH_MODEL_H
#define NPRFX_CLI_GRAPH_MODEL_H

#include <stdint.h>
#include <string.h>

#include "nprfx/graph.h"
#include "nprfx/aov.h"
#include "nprfx/io.h"
#include "nprfx/nprfx.h"

typedef enum gkind {
    GK_NODE = NPRFX_GRAPH_NODE,
    GK_READ = NPRFX_GRAPH_READ,
    GK_SYNTH = NPRFX_GRAPH_SYNTH,
    GK_WRITE = NPRFX_GRAPH_WRITE
} gkind;

/* An input's reference (nprfx/graph.h). */
typedef nprfx_graph_ref gref;

typedef struct gnode {
    char *name;
    gkind kind;
    const nprfx_node_desc *desc; /* GK_NODE */
    int ninputs;
    gref *inputs;
    nprfx_value *params;
    char **param_text; /* owned copies of STRING values */
    void *state;
    char *seeded;       /* the measurement an analysis seeded state with (graph_analysis.c) */
    int state_counted;  /* its caches are in the graph's state_bytes (from its first render) */
    void *instance;     /* the render hook's per-node slot */
    nprfx_context *ctx; /* raises through the graph's with "node 'NAME'" before the message */
    /* read / write / synth */
    char *path, *preview, *colorspace, *vectors, *compression, *scene;
    char *display, *view;
    char *part, *read_view; /* read: the file's part and view ("view" of a write is OCIO's) */
    char *aovs;             /* read: its renderer profile (nprfx/aov.h); NULL or "auto": detected */
    int half, raw, width, height;
    int noted; /* read: its note on parts and views was given (once per run) */
    /* read: the channels its last read took ("a,b,c"; graph_read.c) of the file's count */
    char *read_channels;
    int file_channels;
    /* read: the channels the graph asks of it by name (references' selections, the vectors
     * convention), gathered for all reads at the first one; they pick the default part. */
    char **wants;
    int nwants, wants_known;
    /* read: what its plates are, from the first frame's header (graph_aovs.c): the profile, the
     * motion convention the read applies (NULL: none), the Cryptomatte channels its ids are
     * decoded from ("crypto_object00.R,crypto_object00.G") and the 1/z channel its depth is made
     * of (NULL: none), and the layer the graph asks for ("cryptomatte"). */
    int prepared, profile_known, profile;
    const nprfx_aov_vectors *vec;
    int flow; /* read: its fallback flow node, -1 when none */
    char *crypto, *depth_inverse, *cryptomatte;
    /* read: the depth channel a camera-space position is made of, for a plate with no position
     * (and no rest or uv to stand in for it); NULL: none */
    char *position_from;
    /* read with "colorspace": "auto": what its plates' R,G,B are, from the first frame's header
     * ("srgb" for 8- and 16-bit integer files; NULL: scene-linear, left as they are) */
    const char *colour_from;
    /* read: the studio's mapping file its "aovs" names (aov_map.h), loaded when it settles */
    struct internal_aov_map *aov_map;
} gnode;

/* A read's profile as messages name it: the renderer's, or the mapping file's name. */
const char *internal_graph_profile_label(const gnode *n, int profile);

/* The colour space a read converts its R,G,B from (NULL: none). */
static inline const char *internal_graph_colorspace(const gnode *n)
{
    if (!n->colorspace || !n->colorspace[0]) return NULL;
    return strcmp(n->colorspace, "auto") ? n->colorspace : n->colour_from;
}

/* What a result carries besides pixels: the display window and pixel aspect a write puts back,
 * and, for a plate as read, each channel's file type (so a copy writes uint ids as uint). */
typedef struct gmeta {
    nprfx_rect display;
    float pixel_aspect;
    unsigned char *types; /* NULL: float results of a node */
} gmeta;

typedef struct centry {
    int node, frame;
    nprfx_image im;
    char **names;
    gmeta meta;
    size_t bytes;
    int pins;
    /* The memory plan (graph_plan.c, graph_memory.c): consumers at this frame that have not yet
     * used it; and the frame generation that last touched it (the sweep keeps a temporal source's
     * entries touched by the last frame, the window its temporal readers work in). */
    int uses;
    unsigned gen;
    int from_reader; /* im is the reader's own buffer: back to the system, not to the pool */
    struct centry *prev, *next; /* most recent first */
    struct centry *hnext;       /* the next entry in the same hash slot */
} centry;

/* The most nodes a graph may have: generous, and still a graph whose bookkeeping (names, scoped
 * contexts, parsed params) fits in memory. README and `nprfx run --help` say it. */
#define NPRFX_GRAPH_MAX_NODES 1000000
/* Cached results kept besides the byte bound: graphs of many tiny frames would otherwise keep
 * every node's result with its bookkeeping. */
#define NPRFX_GRAPH_CACHE_ENTRIES 16384
/* How deep renders may nest through temporal fetches (a temporal node fetching another frame of
 * an input that is itself temporal, and so on): each level is a render call on the C stack,
 * which the evaluation's own work stack cannot replace. */
#define NPRFX_GRAPH_MAX_FETCH_DEPTH 64

struct nprfx_graph {
    nprfx_context *ctx;
    gnode *nodes;
    int count;
    char *frames_text;
    int first_frame, last_frame;
    /* the display window of the last node render: the params' scale a question about the next
     * frames assumes (nprfx_graph_frames_read); have_display 0 before any render */
    nprfx_rect last_display;
    int have_display;
    char *base_dir, *out_dir, *ocio;
    char *fmt_text;      /* "format": "WxH" for graphs without inputs */
    double design_width; /* "design_width": the plate width its pixel params are for; 0: none */
    char *comment;       /* "comment": what the graph makes, for help texts; NULL: none */
    char **knobs;        /* "knobs": the params worth turning, "NODE.PARAM" (graph_knobs.c) */
    char **knob_help;    /* per knob: the graph's words on it, or NULL */
    int nknobs;
    int *name_slots; /* hash index of node names (graph_names.c) */
    size_t name_nslots;
    centry *head, *tail;
    centry **cache_slots; /* hash table of the entries (graph_cache.c) */
    size_t cache_nslots, cache_entries, cache_entry_limit;
    size_t cache_bytes, cache_limit;
    int fetch_depth; /* evaluations in progress, one per nested temporal fetch */
    int tile;
    double render_seconds;
    double render_cpu_seconds; /* the process's CPU time (all threads) over the same spans */
    long long render_items;    /* what nodes counted (nprfx_render_args.items) */
    double render_bytes;       /* the frames' bytes the renders read (inputs) and wrote (output) */
    /* Memory (graph_frames.c, graph_memory.c): frame buffers come from the pool and go back to it;
     * the plan frees each result once its consumers at the frame have run, unless a temporal node
     * reads its node at other frames. no_pool: neither (plain calloc/free and the cache alone,
     * to check that pooling never changes a pixel). */
    struct frame_pool *pool;
    int no_pool;
    /* Strip renders (graph_strips.c): the option (nprfx_graph_options.strip_rows), and the rows
     * per strip the plan chose (0: whole frames). */
    int strip_option, strip_rows;
    int plan_ready;
    int plates_settled; /* graph_aovs.c: the read nodes' plates are known, every input resolved */
    /* The nodes the graph file names come first (visible of them); after them, one flow node per
     * read node, unconnected until a plate without motion vectors needs it (graph_aovs.c). Front
     * ends see the visible ones, and the flows once one is wired in (flows_wired). */
    int visible, flows_wired;
    int *plan_uses;               /* per node: inputs reading it at the same frame */
    unsigned char *plan_temporal; /* per node: some temporal node reads it at other frames */
    /* per node, its readers: (node, input) pairs plan_readers[plan_first[i] .. plan_first[i+1]) */
    int *plan_first, (*plan_readers)[2];
    int external; /* nprfx_graph_eval is evaluating a plate for its caller */
    unsigned gen; /* frames begun (nprfx_graph_render_frame, nprfx_graph_eval) */
    /* The frame begun last and the one before (have_prev), and the offsets from it of the
     * temporal sources' frames touched since: the window the sweep keeps, moved on by a step. */
    int cur_frame, prev_frame, have_prev, win_lo, win_hi, have_win;
    uint64_t mem_limit;            /* bytes the graph's frames may take (UINT64_MAX: none) */
    size_t held_bytes;             /* frames handed out: cached results, outputs being rendered,
                                      channel scratch; the pool's idle buffers come on top */
    size_t state_bytes;            /* the caches stateful nodes keep between frames, counted at
                                      each one's first render (desc->state_bytes) */
    size_t mem_peak;               /* the most held_bytes + state_bytes + idle ever was */
    double child_seconds;          /* evaluations nested in the one being timed (stats) */
    nprfx_graph_node_stats *stats; /* per node */
    nprfx_render_hook hook;
    int has_hook;
    int variant;  /* nprfx_graph_variant */
    int progress; /* nprfx_graph_options.progress */
    void (*notice)(void *user, const char *message);
    void *notice_user;
    nprfx_io io;              /* nprfx_graph_options.io, completed (graph_io.h) */
    nprfx_context *owned_ctx; /* ctx when the graph made it (the file's scope): freed with it */
    char *analysis_path;      /* the analysis that seeded nodes' states (graph_analysis.c) */
    /* The frame nprfx_graph_run renders next (has_next), whose plates decode ahead, one per
     * read node (graph_prefetch.c). */
    int has_next, next_frame;
    struct internal_prefetch *prefetch;
    /* nprfx_graph_run's frames write their files in the background while the next computes;
     * the writes not yet reported, newest first (graph_write_jobs.c) */
    int background_writes;
    struct write_job *write_jobs;
    /* waits for them when a frame needs their memory (a pointer: the writes come after the
     * memory they use in the layers, graph_write_jobs.c above graph_memory.c) */
    int (*wait_writes)(nprfx_graph *g);
    int analysis_stale; /* seeded nodes that measured the shot again */
};

/* A note or warning for the caller (nprfx_graph_options.notice), printf-style; nothing without
 * a notice callback (graph_aovs.c). */
void internal_graph_notice(nprfx_graph *g, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* After node n rendered `frame`: when an analysis seeded its state and the state now says
 * otherwise (its input differs from what was measured), a notice, once (graph_analysis.c). */
void internal_graph_analysis_check(nprfx_graph *g, gnode *n, int frame);

#endif
