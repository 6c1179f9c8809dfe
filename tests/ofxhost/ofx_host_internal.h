/* nprfx OpenFX test host — what its files share, never used outside tests/ofxhost/: the objects
 * behind the handles, the host and the per-graph-node instance, and the functions one file
 * defines for the others (prefixed internal_). ofx_host.h is the host's interface; props.c has
 * the property sets, image_effect.c the objects and the image effect suite, params.c the
 * parameter suite, messages.c the message suites, host_suites.c the other suites, bundle.c the
 * loading and describing of the plug-ins, render.c the instances and the graph's render hook,
 * frames.c the frames-needed bookkeeping, pixels.c the pixel depths, profile.c the host
 * profiles, main.c the command line.
 *
 * Objects. Every handle the plug-in sees points at an hprops (a property set) or at a struct
 * that starts with one, tagged with a kind, so a wrong handle is caught instead of read as
 * garbage: effects (plug-in descriptors, context descriptors, instances) double as param sets,
 * and clips, params and images carry their own properties.
 *
 * Strictness. The host is lenient where hosts differ (unknown properties may be set) and strict
 * where a mistake in the adapter would go unnoticed in a real host: getting a property of the
 * wrong type, describing params that do not match the node descriptor, fetching a frame the
 * plug-in did not declare in getFramesNeeded, declaring frames it does not fetch (first render)
 * or frames on an unconnected clip, a region of definition other than the frame, an image not
 * released by the end of an action, or a failed action whose error message is empty all fail,
 * whatever the profile. */
#ifndef NPRFX_TESTS_OFX_HOST_INTERNAL_H
#define NPRFX_TESTS_OFX_HOST_INTERNAL_H

#include <pthread.h>
#include <stdint.h>

#include "ofx/ofx_api.h"
#include "ofx/ofx_derive.h"
#include "ofx_names.h"
#include "ofx_host.h"

/* ---- property sets (props.c) ----------------------------------------------------------------- */

typedef enum pkind { K_PLAIN = 1, K_EFFECT, K_CLIP, K_PARAM, K_IMAGE } pkind;
typedef enum ptype { PT_INT, PT_DOUBLE, PT_STRING, PT_POINTER } ptype;

typedef struct prop {
    char *name;
    ptype type;
    int dim;
    union {
        int *i;
        double *d;
        char **s;
        void **p;
    } v;
} prop;

#define PROPS_MAGIC 0x6e70f0f0u /* "np" and a pattern: tags every live object */
typedef struct hprops {
    uint32_t magic;
    pkind kind;
    prop *items;
    int count, cap;
} hprops;

void internal_props_init(hprops *p, pkind kind);
void internal_props_free(hprops *p); /* the values; not p itself */
/* The property set behind a handle, or NULL when it is none. */
hprops *internal_props_of(OfxPropertySetHandle h);
/* Copy every property of src into dst (dst's own values of the same names are replaced). */
OfxStatus internal_props_copy(hprops *dst, const hprops *src);

/* The property suite's functions, also called directly. */
OfxStatus internal_set_pointer(OfxPropertySetHandle h, const char *name, int i, void *v);
OfxStatus internal_set_string(OfxPropertySetHandle h, const char *name, int i, const char *v);
OfxStatus internal_set_double(OfxPropertySetHandle h, const char *name, int i, double v);
OfxStatus internal_set_int(OfxPropertySetHandle h, const char *name, int i, int v);
OfxStatus internal_set_double_n(OfxPropertySetHandle h, const char *name, int n, const double *v);
OfxStatus internal_set_int_n(OfxPropertySetHandle h, const char *name, int n, const int *v);
OfxStatus internal_get_string(OfxPropertySetHandle h, const char *name, int i, char **v);
OfxStatus internal_get_double(OfxPropertySetHandle h, const char *name, int i, double *v);
OfxStatus internal_get_int(OfxPropertySetHandle h, const char *name, int i, int *v);
OfxStatus internal_get_double_n(OfxPropertySetHandle h, const char *name, int n, double *v);

/* Value i of a property, or the fallback when it is absent or of another type; its dimension. */
const char *internal_pstr(hprops *p, const char *name, int i, const char *fallback);
int internal_pint(hprops *p, const char *name, int i, int fallback);
int internal_pdim(hprops *p, const char *name);

extern const OfxPropertySuiteV1 internal_property_suite;

/* ---- effects, clips, params, images (image_effect.c) ----------------------------------------- */

struct node_inst;
struct hplugin;

typedef struct hparam {
    hprops props; /* first: the param's handle is also its property set */
    char *name, *type;
    int i;
    double d[4];
    char *s;
} hparam;

typedef struct hclip {
    hprops props;
    char *name;
    struct heffect *fx;
    int input; /* node input index; -1 Output; -2 another clip (Mask) */
} hclip;

typedef struct heffect {
    hprops props; /* first: getPropertySet and the param set's property set */
    struct hplugin *pl;
    hclip **clips;
    int nclips;
    hparam **params;
    int nparams;
    struct node_inst *ni; /* instances only */
} heffect;

typedef struct himage {
    hprops props;
    void *pixels;         /* owned; NULL for the output image, which points into its node's */
    struct node_inst *ni; /* whose render handed it out */
} himage;

/* The object behind a handle, or NULL when it is none or of another kind. */
heffect *internal_effect_of(const void *h);
hparam *internal_param_of(const void *h);

heffect *internal_effect_new(struct hplugin *pl, const char *type);
void internal_effect_free(heffect *e); /* with its clips and params; NULL is ignored */
/* The clip or param of that name, or NULL. */
hclip *internal_effect_clip(const heffect *e, const char *name);
hparam *internal_effect_param(const heffect *e, const char *name);
/* A new clip or param of the effect (NULL: out of memory). */
hclip *internal_clip_add(heffect *e, const char *name);
hparam *internal_param_add(heffect *e, const char *type, const char *name);

/* OFX pixel rectangle of an nprfx rectangle, flipped with y_up = f - y_down. */
OfxRectI internal_ofx_rect(nprfx_rect r, int f);

extern const OfxImageEffectSuiteV1 internal_image_effect_suite;
extern const FnOfxImageEffectPlaneSuiteV1 internal_plane_suite;

/* ---- parameter suite (params.c) -------------------------------------------------------------- */

/* Whether the param has OFX type t (kOfxParamType...). */
int internal_type_is(const hparam *p, const char *t);
/* Number of values (0: strings, pages, groups, buttons); *is_int: they are ints. */
int internal_param_dims(const hparam *p, int *is_int);

extern const OfxParameterSuiteV1 internal_parameter_suite;

/* ---- the host (bundle.c) --------------------------------------------------------------------- */

/* ---- host profiles (profile.c) --------------------------------------------------------------- */

typedef enum hdepth { HD_FLOAT, HD_BYTE, HD_SHORT } hdepth;

/* What a real host does that the adapter must cope with (nprfx-ofxtest run --profile NAME). */
typedef struct hprofile {
    const char *name, *like; /* --profile NAME; the host it imitates, for messages */
    int general, filter;     /* the contexts the host instantiates plug-ins in */
    int temporal;            /* kOfxImageEffectPropTemporalClipAccess: fetches at other times */
    int multires;            /* render scales other than 1 */
    int alpha;               /* Alpha images; else every image is RGBA */
    hdepth depth;            /* every image handed out has this depth, whatever the plug-in asked */
    int message_v2;          /* offers kOfxMessageSuite version 2 */
    int lossy_messages;      /* formats messages without their arguments (Natron 2.5) */
    int planes;              /* multi-plane: the plane suite, clips carrying several layers */
    int instance_per_frame;  /* an instance made for each render and destroyed after it (melt) */
} hprofile;

/* The profile called name, or NULL; the names, for messages ("strict, natron, ..."). */
const hprofile *internal_profile_find(const char *name);
const char *internal_profile_names(void);
/* The host's property set as the profile's host describes itself. */
void internal_profile_host_props(const hprofile *pf, OfxPropertySetHandle p);

/* ---- the host (bundle.c) --------------------------------------------------------------------- */

#define HMSG 1024

typedef struct hplugin {
    OfxPlugin *p;
    const nprfx_node_desc *desc; /* the node of this binary with the same identifier, or NULL */
    int loaded;
    heffect *descriptor, *general, *filter;
    /* Not usable in this host: it refused to load (kOfxStatErrMissingHostFeature from an action
     * of loading or describing), or offers no context the host supports; reason says why, as
     * the plug-in posted it while loading, or as the host found it. */
    int unavailable;
    char reason[HMSG];
} hplugin;

struct nprfx_ofx_host {
    nprfx_context *ctx;
    const nprfx_executor *exec;
    const hprofile *profile;
    char *bundle, *binary;
    void *dl;
    int nplugins;
    hplugin *plugins;
    hplugin *loading; /* the plug-in being loaded and described: its messages are its reason */
    hprops props;
    OfxHost ofx;
    nprfx_render_hook hook;
    pthread_mutex_t lock; /* clip image requests and messages: the runner's fetch is not
                             thread-safe */
    char message[HMSG];   /* the last message posted with no instance handle (NULL handle) */
    unsigned message_seq; /* counts those, so a render knows whether one came during it */
    int instances;
    /* --footage: a node whose flow-derivable inputs come from a flow node is rendered in the
     * Filter context on the flow node's picture (render.c). */
    int footage;
    int analyze; /* --analyze-shot (render.c) */
    /* Multi-plane (profile planes): the layers a main input carries, as the plane strings a
     * clip lists (kFnOfxImageEffectPropComponentsPresent), and how to serve one at a time
     * (look.c sets both; NULL: the clip carries its colour plane only), user being the render's
     * fetch_user (each look node serves its own). */
    char **planes;
    int nplanes;
    nprfx_result (*plane_fetch)(void *user, double time, const char *plane, nprfx_image *out);
    /* look.c's --param NAME=VALUE and --press NAME: set and pressed before the first render */
    const char *const *param_sets;
    int nparam_sets;
    const char *const *presses;
    int npresses;
    /* look.c --choose NAME=OPTION: a choice set to an option by its text after the presses */
    const char *const *chooses;
    int nchooses;
    double serve_seconds; /* spent serving clip images (image_effect.c) */
};

/* Suite functions get no user pointer: they reach the host through this, and one host per
 * process keeps that unambiguous. */
extern nprfx_ofx_host *internal_g_host; /* bundle.c */

/* ---- frames needed and fetched (frames.c) ---------------------------------------------------- */

/* One input clip's frames: the [lo, hi] pairs getFramesNeeded declared for the render in flight
 * (several pairs may be given) and the integer frames fetched since the counts were reset. */
typedef struct hframes {
    double *decl;
    int ndecl;
    int *fetched;
    int nfetched, cap;
} hframes;

void internal_frames_free(hframes *f);
/* Replace the declared pairs (n values: lo, hi, lo, hi...); 0 pairs declare the frame itself. */
int internal_frames_declare(hframes *f, const double *v, int n, double time);
/* Whether time lies in a declared pair. */
int internal_frames_allows(const hframes *f, double time);
/* Record a fetch at time (rounded to a frame); 0: out of memory. */
int internal_frames_fetched(hframes *f, double time);
/* Declared set == fetched set; else writes "declared 1-3, fetched 1" into why. */
int internal_frames_match(const hframes *f, char *why, size_t n);

/* Per graph node: the instance and what the render in flight needs. */
typedef struct node_inst {
    nprfx_ofx_host *h;
    hplugin *pl;
    heffect *fx;
    const nprfx_node_desc *desc;
    const nprfx_render_args *args; /* set while the runner renders this node */
    int frame_flip;                /* y_up = frame_flip - y_down for frame-aligned images */
    int filter;                    /* instantiated in the Filter context */
    int footage;                   /* --footage: Source is the picture a flow node reads */
    hframes *frames;               /* per input: frames declared and fetched (frames.c) */
    int began;                     /* beginSequenceRender sent */
    int *in_comps;                 /* per input clip: 4 RGBA, 1 Alpha */
    int out_comps;                 /* Output clip components: 4 RGBA, 1 Alpha */
    void *out_pixels;              /* the output image of the render in flight, host depth */
    OfxRectI out_bounds;
    int out_row_bytes;
    int images; /* images handed out and not yet released */
    /* Messages the plug-in posted with this instance's handle: the last one during the render
     * in flight (posted: how many), and the persistent one until cleared; the host's own
     * complaint about a request of this render (a frame it refused to serve). */
    char posted[HMSG];
    int nposted;
    char persistent[HMSG];
    char host_error[HMSG];
    unsigned message_seq; /* the host's message_seq when the render began */

    int analyzing; /* in the Analyze Shot action: a clip may be fetched at any frame */
} node_inst;

/* Send an action to a plug-in. */
OfxStatus internal_call(hplugin *pl, const char *action, const void *handle, hprops *in,
                        hprops *out);

/* ---- suites (host_suites.c) and the render hook (render.c) ----------------------------------- */

/* The host's fetchSuite. */
const void *internal_fetch_suite(OfxPropertySetHandle host, const char *name, int version);

/* Host image memory and depth conversion (pixels.c): bytes per component of a depth, its OFX
 * name, and components stored and loaded as floats (byte: v * 255 rounded and clamped, short:
 * v * 65535 likewise, float: as is). */
size_t internal_depth_size(hdepth d);
const char *internal_depth_name(hdepth d);
void internal_depth_store(hdepth d, void *dst, size_t i, float v);
float internal_depth_load(hdepth d, const void *src, size_t i);

/* The message suites (messages.c): version 1, and 2 where the profile offers it. */
const void *internal_message_suite(const hprofile *pf, int version);
/* The error of a failed action of ni (what: "render failed (OFX status 1)"): the plug-in's
 * message, with the host's complaint when it has one; a loud error when the plug-in's message
 * is empty or none came. */
nprfx_result internal_failure(node_inst *ni, nprfx_context *ctx, const char *what);
/* Forget the messages of the previous action (before a render). */
void internal_messages_reset(node_inst *ni);

/* The hook's functions (nprfx_render_hook): render a window of a graph node through its plug-in
 * instance, created at its first render; destroy the instance. */
nprfx_result internal_hook_render(void *user, const nprfx_render_args *a, void **slot);
void internal_hook_release(void *user, const nprfx_node_desc *node, void *instance);

/* `nprfx-ofxtest look ...` (look.c): argv[0] is "look". Returns the exit status. */
int internal_look_main(int argc, char **argv);

/* The host's render scale for the runner's args: a proxy's (vector_scale); render_scale also
 * holds a graph's design scale, which the host passes as the designWidth param instead. */
static inline double internal_host_scale(const nprfx_render_args *a)
{
    return a->vector_scale > 0 ? a->vector_scale : a->render_scale;
}

#endif
