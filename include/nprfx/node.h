/* nprfx — node descriptors: a node is declared once, here-shaped, and everything else is derived.
 *
 * The CLI's `list`/`help`, its parameter parsing and graph validation, the OpenFX adapter's clips
 * and params, and the docs are all generated from an nprfx_node_desc. A param's name, default,
 * range or help is written in exactly one place: the descriptor in plugins/. */
#ifndef NPRFX_NODE_H
#define NPRFX_NODE_H

#include <stddef.h>

#include "nprfx/image.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum nprfx_param_type {
    NPRFX_PARAM_DOUBLE = 0,
    NPRFX_PARAM_INT = 1,
    NPRFX_PARAM_BOOL = 2,
    NPRFX_PARAM_CHOICE = 3,
    NPRFX_PARAM_COLOR = 4, /* RGBA, four doubles */
    NPRFX_PARAM_STRING = 5
} nprfx_param_type;

/* Param flags. */
#define NPRFX_PARAM_PIXELS 0x1u /* a length in pixels: multiplied by the host's render scale */
#define NPRFX_PARAM_AREA 0x2u   /* an area in pixels^2: multiplied by render scale squared */
/* The widest design width (the image width PIXELS/AREA params were set for) a graph or a host
 * node may state. */
#define NPRFX_DESIGN_WIDTH_MAX 1000000
#define NPRFX_PARAM_PATH 0x4u /* a STRING that names a file (sequence) path */
#define NPRFX_PARAM_EXPORT                                                                         \
    0x8u /* a PATH the caller writes desc->export_text's text to, per frame;                       \
            empty: no export */

typedef struct nprfx_param_desc {
    const char *name;  /* identifier used in graphs, --set and OFX ("sigma") */
    const char *label; /* shown in hosts ("Sigma") */
    const char *help;
    nprfx_param_type type;
    double def[4];                  /* default; CHOICE: index; COLOR: RGBA */
    double soft_min, soft_max;      /* slider range */
    double hard_min, hard_max;      /* values outside are refused */
    const char *const *choices;     /* CHOICE: NULL-terminated option names */
    const char *const *choice_help; /* CHOICE: optional, one line per option (formula, meaning) */
    const char *def_string;         /* STRING default */
    unsigned flags;
    /* Where the value goes in the node's typed params struct (desc->params_size bytes), which
     * nprfx_node_render fills, checked, before it calls the node: DOUBLE -> double, INT, BOOL
     * and CHOICE -> int, COLOR -> double[4] (RGBA), STRING -> const char * (never NULL). Write
     * it with NPRFX_FIELD(struct, member). */
    size_t offset;
} nprfx_param_desc;

/* In a param's initializer: the field of the node's typed params struct that receives it. */
#define NPRFX_FIELD(type, member) .offset = offsetof(type, member)

/* Input flags. */
#define NPRFX_INPUT_OPTIONAL 0x1u
#define NPRFX_INPUT_MAIN 0x2u     /* the image the node modifies (OFX "Source") */
#define NPRFX_INPUT_TEMPORAL 0x4u /* the node fetches this input at other frame times */
/* Not pixel-aligned with the frame (a threshold map, a palette): any size, exempt from the
 * same-bounds check of frame inputs, passed whole (its own data window) to render. */
#define NPRFX_INPUT_UNALIGNED 0x8u
/* Packing this input's channels gains the node nothing: it reads each pixel once (a per-pixel
 * operation streaming rows), gathers what it needs into its own buffers, or reads few pixels (a
 * value per splat). A runner then passes channels picked out of a wider frame (a plate's R,G,B
 * out of twenty AOVs) in place instead of copying them out first, which costs a pass over the
 * whole plate and a frame. Only where the picked channels are adjacent and in order; the node
 * honours pixel_stride. */
#define NPRFX_INPUT_IN_PLACE 0x10u

#define NPRFX_FETCH_UNBOUNDED (-1) /* fetch_before/after: any number of frames */

typedef struct nprfx_input_desc {
    const char *name;  /* "depth" */
    const char *label; /* "Depth" (OFX clip name is derived from it) */
    const char *help;
    /* Channel names looked for when a reference names no channels: alternatives separated by
     * '|', each a comma-separated channel list or a layer form ("Z|depth.Z|Depth.Z",
     * "Vector.XY"). NULL: take the source's channels as they are. */
    const char *aov;
    int channels; /* exact channel count required; 0: any count from 1 to 4 */
    unsigned flags;
    int fetch_before, fetch_after; /* TEMPORAL: how many frames back/forward it may fetch */
} nprfx_input_desc;

/* A parameter's value at one time. CHOICE holds the option index in v[0], BOOL 0/1, INT an
 * integer, COLOR four components; STRING uses s (never NULL: "" when empty). */
typedef struct nprfx_value {
    double v[4];
    const char *s;
} nprfx_value;

/* What a node outputs for given params and connected input channel counts. */
typedef struct nprfx_output_info {
    int channels;
    const char *names[NPRFX_MAX_CHANNELS]; /* NULL entries get default names */
    /* When the callback fails: why, in words that name the input or param ("mode 'map' needs
     * the 'map' input"); NULL gives a generic message. */
    const char *problem;
} nprfx_output_info;

/* Fetch input `input` at frame `time`. The view stays valid until the render call returns or
 * until NPRFX_FETCH_KEEP further fetches have been made, whichever comes first (so a recursion
 * over many frames needs only bounded memory). An input that is not connected yields
 * NPRFX_ERR_MISSING_INPUT. */
#define NPRFX_FETCH_KEEP 16
typedef nprfx_result (*nprfx_fetch_fn)(void *fetch_user, int input, double time, nprfx_image *out);

typedef struct nprfx_node_desc nprfx_node_desc;

/* An inclusive range of frames. */
typedef struct nprfx_frame_range {
    int first, last;
} nprfx_frame_range;

/* The most ranges nprfx_node_frames_needed gives for one input. */
#define NPRFX_MAX_FRAME_RANGES 4

/* What rendering one frame reads: the question desc->frames_needed answers. */
typedef struct nprfx_frames_query {
    int time;                    /* the frame rendered */
    int first_frame, last_frame; /* the shot; last < first when unknown */
    const int *input_channels;   /* per input: its channel count, 0 when not connected */
    /* The instance's state (what nprfx_render_args.state holds; NULL: none, or not asked). A
     * node that keeps what earlier frames computed may answer with what it still has to read
     * (coherent-noise rendered in order: the new frame, not the recursion from its start), so a
     * host prepares no frame the render will not read. The caller keeps it from being freed or
     * rendered into meanwhile. */
    const void *state;
} nprfx_frames_query;

/* What a node keeps between calls depends on: the question desc->state_bytes answers. */
typedef struct nprfx_state_query {
    int width, height;           /* of the frames rendered (render scale applied) */
    int first_frame, last_frame; /* the shot; last < first when unknown */
    const int *input_channels;   /* per input: its channel count, 0 when not connected */
} nprfx_state_query;

typedef struct nprfx_render_args {
    size_t size; /* sizeof(nprfx_render_args) */
    nprfx_context *ctx;
    const nprfx_node_desc *node;
    double time;                 /* the frame being rendered */
    double render_scale;         /* this frame's pixels per pixel the params were set in: a host
                                    proxy gives e.g. 0.5, a graph run at twice its design width 2 */
    nprfx_rect frame;            /* the whole image domain at this scale */
    nprfx_rect window;           /* the pixels to write now; inside output->bounds and frame */
    int first_frame, last_frame; /* the shot's frame range, for temporal nodes */
    const nprfx_image *inputs;   /* one view per declared input; data == NULL: not connected */
    const nprfx_value *params;   /* one value per declared param, at `time`, scale applied */
    nprfx_image *output;
    nprfx_fetch_fn fetch; /* NULL when the caller cannot fetch other frames */
    void *fetch_user;
    void **state; /* per-instance slot, NULL at first; the node owns what it stores */
    /* NULL, or where a node that counts what it makes (desc->item_name) adds how many it made
     * for the window (stipples drawn, kernels splatted), for benchmarks and logs. Appended after
     * the first release: nprfx_node_render gives nodes NULL here when the caller's struct is
     * the shorter NPRFX_RENDER_ARGS_SIZE_V1 one. */
    long long *items;
    /* What pixel-valued inputs (motion vectors) are multiplied by to be in this frame's pixels:
     * a host's proxy render gives vectors in full-resolution pixels (render_scale), a graph run
     * at another size than its design width gives them in the plate's own pixels (1). 0, or a
     * caller's struct too short to hold it (it came after `items`): render_scale. */
    double vector_scale;
} nprfx_render_args;

/* Render args as the first release defined them, without `items`: callers built against that
 * header pass this size, and nprfx_node_render still accepts it. */
#define NPRFX_RENDER_ARGS_SIZE_V1 offsetof(nprfx_render_args, items)
/* Render args with `items` but without `vector_scale`. */
#define NPRFX_RENDER_ARGS_SIZE_V2 offsetof(nprfx_render_args, vector_scale)

/* A node's render function. nprfx_node_render calls it after the shared checks (see there), with
 * a full-size copy of the caller's args and `params`, the node's typed params struct filled from
 * args->params (NULL when the node declares no params_size). */
typedef nprfx_result (*nprfx_render_fn)(const nprfx_render_args *args, const void *params);

/* In a CHOICE param's initializer: the range of its n options, 0 .. n - 1, soft and hard alike. */
#define NPRFX_CHOICE_RANGE(n) .soft_min = 0, .soft_max = (n)-1, .hard_min = 0, .hard_max = (n)-1

/* Node flags. */
#define NPRFX_NODE_TEMPORAL 0x1u /* fetches inputs at other frames */
#define NPRFX_NODE_STATEFUL                                                                        \
    0x2u /* keeps a cache in *state between calls (results never depend                            \
            on it: it only saves work) */
/* TEMPORAL, and no params make it read only the frame itself (a recursion over frames, a time
 * shift): a host that cannot give other frames must not offer it, rather than show a wrong one. */
#define NPRFX_NODE_NEEDS_OTHER_FRAMES 0x4u
/* Renders any rows of a frame from its inputs' rows within its footprint (desc->footprint; params
 * whose footprint is -1 cannot, and render whole frames) of the window: it reads no input pixel
 * farther than that and computes nothing from a whole input (no statistics of the frame), so a
 * runner may render a frame a strip of rows at a time from inputs that hold only those rows, bit
 * for bit as the whole frame (docs/design.md §1 "Memory"). */
#define NPRFX_NODE_ROWS 0x8u
/* Its render sets every output channel of every pixel of the window, whatever its inputs and
 * params, and reads nothing of its output before setting it: a runner may hand it an output frame
 * it has not cleared (a reused buffer still holding an earlier frame's pixels), saving a pass over
 * the frame. Without it, the output arrives zeroed, as nprfx_image_alloc gives it. */
#define NPRFX_NODE_WRITES_WINDOW 0x10u
/* Its output depends on the render scale beyond its PIXELS and AREA params (e.g. texture
 * coordinates made from pixel positions): a host that scales params by a graph's design width
 * must give it the same scale (nprfx_render_args.render_scale). */
#define NPRFX_NODE_PIXEL_SCALED 0x20u

struct nprfx_node_desc {
    size_t size;       /* sizeof(nprfx_node_desc) */
    const char *id;    /* "threshold-map": graph files, CLI */
    const char *label; /* "Threshold Map": hosts */
    const char *group; /* "NPR" */
    const char *help;  /* paragraphs separated by blank lines */
    const nprfx_input_desc *inputs;
    int num_inputs;
    const nprfx_param_desc *params;
    int num_params;
    /* Output channel count when `output` is NULL; 0 means "as many as the first input". */
    int output_channels;
    /* Optional: compute output channels and names from params and input channel counts
     * (input_channels[i] is 0 for an unconnected input). `params` is the node's typed params
     * struct, bound and checked as for render (NULL when the node declares no params_size).
     * Called through nprfx_node_output_info. */
    nprfx_result (*output)(const void *params, const int *input_channels, nprfx_output_info *out);
    unsigned flags;
    nprfx_render_fn render;
    void (*state_free)(void *state);
    /* Optional: a vector/text export of the frame (e.g. stipples as CSV or SVG). Called by the
     * front end after the whole frame rendered, with the same args (window = frame) and `path`,
     * the NPRFX_PARAM_EXPORT param's value expanded for this frame, whose extension picks the
     * format. *text is malloc'd; the caller writes it (the library does no file I/O). Called
     * through nprfx_node_export, which binds `params` as for render. */
    nprfx_result (*export_text)(const nprfx_render_args *args, const void *params, const char *path,
                                char **text, size_t *len);
    /* Optional: what the node counts into args->items, a plural noun ("stipples"). */
    const char *item_name;
    /* Size of the node's typed params struct (0: the node reads args->params itself). */
    size_t params_size;
    /* The node's version, major.minor: hosts see it as the OpenFX plug-in version. The minor
     * number goes up when the node's pixels change for the same params, the major one when a
     * param or input is removed or changes meaning (a host then keeps the old one apart). */
    int version_major, version_minor;
    /* Optional, for TEMPORAL nodes: the frames input `input` is read at when frame q->time is
     * rendered with these params (the typed struct render gets) and an empty cache, as up to
     * NPRFX_MAX_FRAME_RANGES ranges; returns how many. A host prepares exactly these before the
     * render (OpenFX getFramesNeeded), so they must cover every fetch and ask for nothing the
     * node does not read. Called through nprfx_node_frames_needed. Without it: a TEMPORAL input
     * every frame within fetch_before/fetch_after of the time (within the shot), the others the
     * frame itself. Appended after the first release: read it only when `size` covers it. */
    int (*frames_needed)(const void *params, const nprfx_frames_query *q, int input,
                         nprfx_frame_range *ranges);
    /* Optional: how far from an output pixel, in pixels at render scale 1, the input pixels it
     * depends on may lie with these params (a filter's radius, both passes of a composite
     * filter); -1: anywhere in the frame (a warp by an input's values). Without it: 0, the
     * pixel itself. It bounds where a NaN or infinite input pixel may show in the output
     * (docs/design.md §2.2, tests/unit/test_nan.c) and how much work a pixel costs (the
     * runner's warning before hours of work). Called through nprfx_node_footprint. Appended:
     * read it only when `size` covers it. */
    int (*footprint)(const void *params);
    /* Optional, for STATEFUL nodes: the most bytes the node's *state holds between calls while
     * it renders the frames of q with these params (its caches at their fullest: a frame-state
     * cache's bound, a solved pair of frames, a texture window). A runner counts them with the
     * frames it holds, so a memory limit covers them. Without it: 0. Called through
     * nprfx_node_state_bytes. Appended: read it only when `size` covers it. */
    double (*state_bytes)(const void *params, const nprfx_state_query *q);
    /* Optional, for STATEFUL nodes whose state holds what they measured over the whole shot (the
     * tone node's range): that measurement as text, lines of "key value ..." (*text malloc'd;
     * NULL while nothing is measured), and the state rebuilt from such text. A
     * runner measures a shot once (`nprfx analyze`), stores the text and seeds every later run
     * and farm chunk with it. A seeded state still checks what it can see (the rendered frame's
     * own fingerprint) and measures again when that differs, so a result never depends on
     * whether the state was seeded. Called through nprfx_node_state_save / _load. Appended: read
     * them only when `size` covers them. */
    nprfx_result (*state_save)(nprfx_context *ctx, const void *state, char **text);
    nprfx_result (*state_load)(nprfx_context *ctx, void **state, const char *text);
};

/* Input i of a render call, or NULL when it is not connected (for nodes' optional inputs). */
static inline const nprfx_image *nprfx_render_input(const nprfx_render_args *args, int i)
{
    return args->inputs && args->inputs[i].data ? &args->inputs[i] : NULL;
}

/* ---- rendering through the descriptor (core/base/node.c) ---- */

/* Render args->window of a node: the one way front ends (runner, OpenFX adapter, tests, library
 * users) run a node. Before the node sees them it checks, once for every node:
 *  - args: args->size at least NPRFX_RENDER_ARGS_SIZE_V1 (older, shorter structs are accepted:
 *    the fields they lack read as 0/NULL), node, inputs, params and output present;
 *  - the window is cut to the output's bounds (an empty one renders nothing);
 *  - every input without NPRFX_INPUT_OPTIONAL is connected, and an input that declares a channel
 *    count has it;
 *  - the output has the channels nprfx_node_output_info gives for these params and inputs;
 *  - every param value has its type and lies in its hard range;
 * and fills the node's typed params struct. Errors name the node, input or param. */
NPRFX_API nprfx_result nprfx_node_render(const nprfx_render_args *args);

/* The node's text export of a whole frame (desc->export_text), with the same checks and binding
 * as nprfx_node_render, except that it needs no output image (args->output may be NULL).
 * NPRFX_ERR_UNSUPPORTED when the node has none. */
NPRFX_API nprfx_result nprfx_node_export(const nprfx_render_args *args, const char *path,
                                         char **text, size_t *len);

/* The frames input `input` is read at when frame q->time renders with these params: the
 * node's own answer (desc->frames_needed) or the fetch_before/after rule, sorted and merged, the
 * frame itself always included. *count is 0 for an input that is not connected. Params are
 * checked as for render (errors name the param). */
NPRFX_API nprfx_result nprfx_node_frames_needed(nprfx_context *ctx, const nprfx_node_desc *node,
                                                const nprfx_value *params,
                                                const nprfx_frames_query *q, int input,
                                                nprfx_frame_range *ranges, int *count);

/* The most bytes the node keeps in its state between calls for these params and frames
 * (desc->state_bytes; 0 without one) into *bytes. Params are checked as for render. */
NPRFX_API nprfx_result nprfx_node_state_bytes(nprfx_context *ctx, const nprfx_node_desc *node,
                                              const nprfx_value *params, const nprfx_state_query *q,
                                              double *bytes);

/* The shot-wide measurement in a node's state as text (desc->state_save): NPRFX_ERR_UNSUPPORTED
 * when the node keeps none; *text NULL while nothing is measured. */
NPRFX_API nprfx_result nprfx_node_state_save(nprfx_context *ctx, const nprfx_node_desc *node,
                                             const void *state, char **text);
/* Seed *state (freed and replaced when set) from text nprfx_node_state_save gave; errors name
 * the node and the line. */
NPRFX_API nprfx_result nprfx_node_state_load(nprfx_context *ctx, const nprfx_node_desc *node,
                                             void **state, const char *text);
/* Whether the node measures over the shot (has desc->state_save and desc->state_load). */
NPRFX_API int nprfx_node_measures_shot(const nprfx_node_desc *node);

/* The node's footprint for these params (desc->footprint; 0 without one) into *radius: pixels
 * at render scale 1, -1 for anywhere in the frame. Params are checked as for render. */
NPRFX_API nprfx_result nprfx_node_footprint(nprfx_context *ctx, const nprfx_node_desc *node,
                                            const nprfx_value *params, int *radius);

/* Check a descriptor for mistakes a compiler cannot see: names unique and well formed, help and
 * labels present, defaults inside the hard range and the soft range inside it, choice lists that
 * match their range, typed fields inside params_size and not overlapping. The first problem is
 * raised on ctx. */
NPRFX_API nprfx_result nprfx_node_lint(nprfx_context *ctx, const nprfx_node_desc *node);

/* ---- descriptor helpers (core/base/node.c) ---- */

NPRFX_API int nprfx_node_param_index(const nprfx_node_desc *node, const char *name);
NPRFX_API int nprfx_node_input_index(const nprfx_node_desc *node, const char *name);

/* Fill values[num_params] with the defaults. */
NPRFX_API void nprfx_node_defaults(const nprfx_node_desc *node, nprfx_value *values);

/* Parse text into a value for param p of node, checking type, choice names and hard range.
 * Errors name the node and param ("blend.opacity: 1.5 is outside [0, 1]"). STRING values point
 * into `text`, which must outlive the value. Colours take 1, 3 or 4 numbers separated by ',' or
 * spaces. */
NPRFX_API nprfx_result nprfx_param_parse(nprfx_context *ctx, const nprfx_node_desc *node,
                                         const nprfx_param_desc *p, const char *text,
                                         nprfx_value *out);
/* Check a value (e.g. from a JSON number) against the param's type and hard range. */
NPRFX_API nprfx_result nprfx_param_check(nprfx_context *ctx, const nprfx_node_desc *node,
                                         const nprfx_param_desc *p, const nprfx_value *v);
/* Format a value as nprfx_param_parse reads it. Returns buf. */
NPRFX_API char *nprfx_param_format(const nprfx_param_desc *p, const nprfx_value *v, char *buf,
                                   size_t n);
NPRFX_API const char *nprfx_param_type_name(nprfx_param_type t);

/* Output description for params/inputs, applying the output_channels rule and default names
 * (1: Y; 2: R,G; 3: R,G,B; 4: R,G,B,A). A node's desc->output gets the params bound into its
 * typed struct, checked as for render (errors name the param). */
NPRFX_API nprfx_result nprfx_node_output_info(nprfx_context *ctx, const nprfx_node_desc *node,
                                              const nprfx_value *params, const int *input_channels,
                                              nprfx_output_info *out);

/* Scale pixel/area params by the render scale (OFX proxies, a graph's design width), in place
 * on values; a value inside its hard range stays inside it (clamped to its ends). */
NPRFX_API void nprfx_node_apply_render_scale(const nprfx_node_desc *node, nprfx_value *values,
                                             double render_scale);

/* ---- the registry (plugins/, generated list) ---- */

NPRFX_API int nprfx_node_count(void);
NPRFX_API const nprfx_node_desc *nprfx_node_at(int index);
NPRFX_API const nprfx_node_desc *nprfx_node_find(const char *id);

#ifdef __cplusplus
}
#endif
#endif
