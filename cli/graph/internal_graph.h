/* nprfx CLI — what the graph's files share: the parsed graph (nodes, references, the result
 * cache) and the helpers that parsing (graph_load.c), evaluation (graph_eval.c) and writing
 * (graph_write.c) all use. Never installed. */
#ifndef NPRFX_CLI_INTERNAL_GRAPH_H
#define NPRFX_CLI_INTERNAL_GRAPH_H

#include <stdint.h>

#include "frame_pool.h"
#include "graph.h"
#include "io/io.h"
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
    int state_counted;  /* its caches are in the graph's state_bytes (from its first render) */
    void *instance;     /* the render hook's per-node slot */
    nprfx_context *ctx; /* raises through the graph's with "node 'NAME'" before the message */
    /* read / write / synth */
    char *path, *preview, *colorspace, *vectors, *compression, *scene;
    char *display, *view;
    char *part, *read_view; /* read: the file's part and view ("view" of a write is OCIO's) */
    int half, raw, width, height;
    int noted; /* read: its note on parts and views was given (once per run) */
    /* read: the channels the graph asks of it by name (references' selections, the vectors
     * convention), gathered for all reads at the first one; they pick the default part. */
    char **wants;
    int nwants, wants_known;
} gnode;

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
    /* The memory plan (graph_plan.c): consumers at this frame that have not yet used it; and
     * the frame generation that last touched it (the sweep keeps a temporal source's entries
     * touched by the last frame, the window its temporal readers work in). */
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
    char *base_dir, *out_dir, *ocio;
    char *fmt_text;  /* "format": "WxH" for graphs without inputs */
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
    /* Memory (graph_plan.c): frame buffers come from the pool and go back to it; the
     * plan frees each result once its consumers at the frame have run, unless a temporal node
     * reads its node at other frames. no_pool: neither (plain calloc/free and the cache alone,
     * to check that pooling never changes a pixel). */
    nprfx_frame_pool *pool;
    int no_pool;
    /* Strip renders (graph_strips.c): the option (nprfx_graph_options.strip_rows), and the rows
     * per strip the plan chose (0: whole frames). */
    int strip_option, strip_rows;
    int plan_ready;
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
    nprfx_context *owned_ctx; /* ctx when the graph made it (the file's scope): freed with it */
};

/* The index of the node called name, or -1 (graph_names.c). */
int internal_graph_find_node(const nprfx_graph *g, const char *name);
/* An empty name index with room for count nodes. */
nprfx_result internal_graph_names_init(nprfx_graph *g, int count);
/* Index node's name; when another node has it already, that node's index (else -1). */
int internal_graph_names_add(nprfx_graph *g, int node);
/* An error naming the nodes of a cycle, if the linked graph has one (graph_cycles.c). */
nprfx_result internal_graph_check_cycles(nprfx_graph *g);
/* Synth sizes and "format" against the image memory bound (graph_limits.c). */
nprfx_result internal_graph_check_limits(nprfx_graph *g);
/* The memory plan (graph_plan.c): the consumer counts and temporal sources, made once. */
nprfx_result internal_graph_plan_build(nprfx_graph *g);
/* A zeroed frame of bounds x channels for node (its output or a scratch), from the pool, after
 * checking it against the memory limit (evicting unpinned cached results first when the limit
 * would be passed); errors name `what` ("node 'x': output frame") and the sizes. */
nprfx_result internal_graph_frame_alloc(nprfx_graph *g, int node, const char *what,
                                        nprfx_rect bounds, int channels, nprfx_image *im);
/* The same frame, not cleared when it comes from the pool: for a caller that sets every pixel
 * before reading any (a node with NPRFX_NODE_WRITES_WINDOW, a channel packing). */
nprfx_result internal_graph_frame_alloc_unset(nprfx_graph *g, int node, const char *what,
                                              nprfx_rect bounds, int channels, nprfx_image *im);
/* The channels of a plate (a read or synth node's result, names/nc) that its readers take, by
 * the selections they would make on it: keep[c] set for each, the count returned; -1 when a
 * reader's selection fails (the reader reports it) or the plate is evaluated for the caller of
 * nprfx_graph_eval, who sees all of it. Only a planned graph trims plates. */
int internal_graph_plate_channels(nprfx_graph *g, int node, const char *const *names, int nc,
                                  unsigned char *keep);
/* The channels read node `node` reads of a file whose whole read would deliver names (nc):
 * those its readers take (internal_graph_plate_channels on names with the motion channels
 * appended), the sources of its motion channels and its R,G,B when it converts colour, as
 * indices into names in file order into pick (room for nc); -1 to read them all: nothing to
 * leave out, no plan, or a selection that would come out otherwise on the channels read. */
int internal_graph_read_pick(nprfx_graph *g, int node, const char *const *names, int nc, int *pick);
/* The channels of plate node's result with names (nc) to keep: those its readers take, when
 * every reader then selects the very same channels from them; their indices in names, in
 * order, into map (room for nc), and their count; 0 to keep the plate whole. */
int internal_graph_plate_pick(nprfx_graph *g, int node, const char *const *names, int nc, int *map);
/* Keep only the channels of plate node's result (im, names, and meta's per-channel types when it
 * has them) that its readers take, when every reader then selects the very same channels
 * (internal_graph_plate_channels); whether it did. */
int internal_graph_trim_plate(nprfx_graph *g, int node, nprfx_image *im, char ***names,
                              gmeta *meta);
/* After node's first render (frame size w x h, its inputs' channel counts in_ch, the params it
 * rendered with): count the caches it keeps between frames from then on (desc->state_bytes) in
 * g->state_bytes, so that later frames are checked against the memory limit with them. */
void internal_graph_count_state(nprfx_graph *g, gnode *n, int w, int h, const int *in_ch,
                                const nprfx_value *params);
/* Count a frame made elsewhere (a plate from the reader) as held. */
void internal_graph_frame_adopt(nprfx_graph *g, int node, const nprfx_image *im);
/* Give a frame from internal_graph_frame_alloc (or adopted) back to the pool. */
void internal_graph_frame_release(nprfx_graph *g, nprfx_image *im);
/* One consumer at e's frame has used e: when none is left and no temporal node reads e's node
 * at other frames, e leaves the cache now (unless pinned) instead of waiting for eviction. */
void internal_graph_consumed(nprfx_graph *g, centry *e);
/* Begin evaluating frame (after the previous frame's sweep). */
void internal_graph_frame_begin(nprfx_graph *g, int frame);
/* Entry e was found or made: a temporal source's frame widens the window. */
void internal_graph_touch(nprfx_graph *g, centry *e);
/* After a frame: drop every unpinned result but a temporal source's within the window the next
 * frame is expected to read (the offsets touched in this one, moved on by the step between the
 * last two frames, +1 at first). */
void internal_graph_frame_sweep(nprfx_graph *g);
/* Remove entry e (unpinned) from the cache and release its frame. */
void internal_graph_cache_drop(nprfx_graph *g, centry *e);
/* The result cache (graph_cache.c): the entry of (node, frame), made the most recent, or NULL. */
centry *internal_graph_cache_find(nprfx_graph *g, int node, int frame);
/* Add a result (taking im, names and meta's types), evicting unpinned old ones over the bounds;
 * NULL: no memory. */
centry *internal_graph_cache_insert(nprfx_graph *g, int node, int frame, nprfx_image *im,
                                    char **names, gmeta *meta);
/* Evict unpinned entries, oldest first, until the cache is within its bounds. */
void internal_graph_cache_evict(nprfx_graph *g);
/* Free every entry. */
void internal_graph_cache_clear(nprfx_graph *g);
void internal_graph_centry_free(nprfx_graph *g, centry *e);
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
/* Whether an input (flags: its NPRFX_INPUT_* flags, 0 for a write node's image) gets the count
 * channels idx of a source of src_channels packed into a frame of their own rather than read in
 * place: when they are not adjacent, or are a few out of a wide plate (nodes then stream through
 * memory instead of striding over the channels they do not use) unless the input gathers them
 * itself. The evaluation and the memory plan both ask this. */
int internal_graph_packs(int src_channels, const int *idx, int count, unsigned flags);
/* The view of the channels of entry e that input k of node n uses: e's pixels when they are
 * adjacent, else *scratch (a frame from internal_graph_frame_alloc, the caller releases it with
 * internal_graph_frame_release; left empty when not needed). */
nprfx_result internal_graph_select_input(nprfx_graph *g, const gnode *n, int k, const centry *e,
                                         nprfx_image *view, nprfx_image *scratch);
/* NPRFX_VARIANT_SHOWER_DOOR: alter a plate just read (graph_variant.c). */
void internal_graph_variant_plate(const nprfx_graph *g, nprfx_image *im, char **names);
/* NPRFX_VARIANT_WHITE: the params node n renders frame with (its own, or *copy altered). */
/* The render arguments every render of node n at `frame` shares, whole frames or strips alike:
 * its context, descriptor, time, the frame, the shot, its params at that frame (varied: room
 * for 64, used when the params vary), state and item counter; the caller sets inputs, output,
 * window and fetch. */
void internal_graph_render_args(nprfx_graph *g, gnode *n, int frame, nprfx_rect frame_rect,
                                nprfx_value *varied, nprfx_render_args *a);
const nprfx_value *internal_graph_variant_params(const nprfx_graph *g, const gnode *n, int frame,
                                                 nprfx_value *copy);
/* Strip renders (graph_strips.c): read node `node`'s file at frame (its path into file, n bytes)
 * opened for rows with the channels eval_read would read; *shape describes the plate. */
nprfx_result internal_graph_read_rows_open(nprfx_graph *g, int node, int frame, char *file,
                                           size_t n, nprfx_plate *shape, nprfx_row_reader **rr);
/* Rows [y0, y1) of it as a plate of their own (malloc'd), with the motion channels and the
 * colour conversion eval_read applies to a whole plate. */
nprfx_result internal_graph_read_rows(nprfx_graph *g, int node, const char *file,
                                      nprfx_row_reader *rr, const nprfx_plate *shape, int y0,
                                      int y1, nprfx_plate *out);
/* Write node w would overwrite one of the graph's inputs at frame with out: the error. */
nprfx_result internal_graph_check_not_input(nprfx_graph *g, const gnode *w, const char *out,
                                            int frame);
/* Whether write node `node` can be rendered a strip of rows at a time (graph_strips.c): every
 * node it depends on is a read of an EXR or a node with NPRFX_NODE_ROWS and a footprint >= 0,
 * none temporal; no preview. When not, why names the node in the way. */
int internal_graph_strips_possible(nprfx_graph *g, int node, char *why, size_t n);
/* Render write nodes writes[0..nw) (a strip group, internal_graph_strip_group) at frame by
 * strips of g->strip_rows rows, each node of their chains once a strip (graph_strips.c). */
nprfx_result internal_graph_write_strips(nprfx_graph *g, const int *writes, int nw, int frame);
/* The writes that render by strips together with write node `write` (their chains share nodes,
 * directly or through others; it included), in node order, into group (room for g->count);
 * their count. Shared nodes then render each strip once for all of them. */
int internal_graph_strip_group(nprfx_graph *g, int write, int *group);
/* The bytes a strip render of write node `write` (with its strip group) at frame holds at most with
 * strips of `rows` rows (the plates' headers are read); *err: why it cannot be told (raised on g's
 * context), a plate's block of rows above the memory limit (NPRFX_ERR_OUT_OF_MEMORY) among them. */
uint64_t internal_graph_strip_need(nprfx_graph *g, int write, int frame, int rows,
                                   nprfx_result *err);

/* The cache entry of node at frame, evaluated (and its inputs) when not cached. */
nprfx_result internal_graph_eval(nprfx_graph *g, int node, int frame, centry **out);

#endif
