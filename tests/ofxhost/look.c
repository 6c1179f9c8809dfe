/* nprfx OpenFX test host — a look plug-in driven as a host drives it:
 * `nprfx-ofxtest look GRAPH.json --ofx BUNDLE [--profile NAME] [--frames SPEC] [--scramble]
 * [--shot SPEC] [--set KNOB=VALUE] [--render-scale S] [--channels R,G,B] [-o DIR]` renders the look
 * plug-in of GRAPH (found through NPRFX_LOOK_PATH, set to the graph's folder) frame by frame, its
 * clips fed with the AOVs of the graph's own plates as the engine reads them (nprfx_graph_eval_aov:
 * nprfx's conventions, what a compositor's shuffles would give), and writes its Output as
 * DIR/STEM.####.exr (RGBA float). tests/cli/ofx_looks.sh compares them with `nprfx run GRAPH`. The
 * look stands as a node of the render hook (render.c) whose inputs are the look's clips, so every
 * check of the hook holds: frames declared equal frames fetched on the first render, images
 * released, messages not empty. */
#define _POSIX_C_SOURCE 200809L /* setenv, strdup */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nprfx/aov.h"
#include "look_desc.h"
#include "nprfx/io_oiio.h"
#include "ofx_host_internal.h"

#define LOOK_INPUTS 32
#define LOOK_RING 16
#define LOOK_PARAMS LOOK_MAX_KNOBS

typedef struct look_run {
    nprfx_context *ctx;
    nprfx_graph *g;
    look_desc look; /* the look as the plug-in derives it (look_desc.h), after --set */
    /* the inputs this host has clips for: all of the look's, or (multi-plane) Source and maps */
    int n;
    int node[LOOK_INPUTS], aov[LOOK_INPUTS]; /* aov -1: a map's whole plate */
    nprfx_input_desc in[LOOK_INPUTS];
    nprfx_image ring[LOOK_RING]; /* fetched frames of this render */
    int nring;
    /* a multi-plane host (profile planes): the main read's file as layers */
    int planar, main_node;
    char *planes[64];
    int nplanes;
    nprfx_plate plate; /* the last frame read, and which */
    int plate_frame, have_plate;
    /* --render-scale: the plates are a proxy at this scale of the project's size; the host's
     * images carry motion vectors in pixels at full resolution, as a host's proxy does */
    double scale;
} look_run;

/* The main read's file at frame, every channel (a multi-plane host's Read gives them all). */
static nprfx_result main_plate(look_run *lr, int frame)
{
    if (lr->have_plate && lr->plate_frame == frame) return NPRFX_OK;
    nprfx_plate_free(&lr->plate);
    lr->have_plate = 0;
    nprfx_graph_node_info ni = {sizeof ni};
    nprfx_result r = nprfx_graph_node(lr->g, lr->main_node, &ni);
    if (r) return r;
    char file[4096];
    nprfx_graph_resolve_path(lr->g, nprfx_graph_base_dir(lr->g), ni.path, frame, file, sizeof file);
    if ((r = nprfx_io_oiio()->read(lr->ctx, file, NULL, &lr->plate))) return r;
    lr->plate_frame = frame;
    lr->have_plate = 1;
    return NPRFX_OK;
}

/* The layers of a plate as a multi-plane host names them: LAYER.CHANNEL channels grouped by
 * LAYER, up to 4 a plane; R, G, B, A without a layer are the colour plane's, and other channels
 * without one are put where Nuke puts them: Z in "depth", the rest in "other" (an Arnold render's
 * depth is a bare Z). plane[i] gets the plane string, chan[i] its channels' indices. Returns how
 * many. */
static int plate_layers(const nprfx_plate *p, char **plane, int (*chan)[4], int *nch, int max)
{
    int n = 0;
    for (int c = 0; c < p->nchannels; c++) {
        const char *name = p->names[c], *dot = strrchr(name, '.');
        const char *layer = name, *channel = dot ? dot + 1 : name;
        size_t len = dot ? (size_t)(dot - name) : 0;
        if (!dot && strlen(name) == 1 && strchr("RGBA", name[0])) continue;
        if (!dot) {
            layer = strcmp(name, "Z") ? "other" : "depth";
            len = strlen(layer);
        }
        int found = -1;
        size_t pl = strlen(kNatronOfxImageComponentsPlane);
        for (int i = 0; i < n && found < 0; i++)
            if (nch[i] < 4 && !strncmp(plane[i] + pl, layer, len) &&
                !strncmp(plane[i] + pl + len, kNatronOfxImageComponentsPlaneChannel,
                         strlen(kNatronOfxImageComponentsPlaneChannel)))
                found = i;
        if (found < 0) {
            if (n == max) break;
            found = n++;
            nch[found] = 0;
            if (plane) {
                plane[found] = calloc(1, 1024);
                if (!plane[found]) return -1;
                snprintf(plane[found], 1024, "%s%.*s", kNatronOfxImageComponentsPlane, (int)len,
                         layer);
            }
        }
        chan[found][nch[found]++] = c;
        size_t at = strlen(plane[found]);
        snprintf(plane[found] + at, 1024 - at, "%s%s", kNatronOfxImageComponentsPlaneChannel,
                 channel);
    }
    return n;
}

/* The plane source of the test host: one layer of the main read's file at time. */
static nprfx_result look_plane(void *user, double time, const char *plane, nprfx_image *out)
{
    look_run *lr = user;
    int frame = (int)(time >= 0 ? time + 0.5 : time - 0.5);
    nprfx_result r = main_plate(lr, frame);
    if (r) return r;
    char *names[64];
    int chan[64][4], nch[64];
    int n = plate_layers(&lr->plate, names, chan, nch, 64);
    int found = -1;
    for (int i = 0; i < n; i++) {
        if (found < 0 && !strcmp(names[i], plane)) found = i;
    }
    if (found >= 0 && lr->nring == LOOK_RING) {
        nprfx_image_free(&lr->ring[0]);
        memmove(lr->ring, lr->ring + 1, (LOOK_RING - 1) * sizeof *lr->ring);
        lr->nring--;
    }
    if (found >= 0 &&
        !(r = nprfx_image_alloc(lr->ctx, lr->plate.bounds, nch[found], &lr->ring[lr->nring]))) {
        /* the plate's channels interleaved, rows of its width (more than a view may have) */
        const nprfx_plate *pl = &lr->plate;
        double k[4] = {1, 1, 1, 1};
        int mv[4];
        double sign[4];
        if (lr->scale != 1.0 && nprfx_graph_read_vectors(lr->g, lr->main_node) &&
            nprfx_graph_motion_sources(lr->g, lr->main_node, "the plate",
                                       (const char *const *)pl->names, pl->nchannels, mv,
                                       sign) == NPRFX_OK)
            for (int c = 0; c < nch[found]; c++)
                for (int m = 0; m < 4; m++)
                    if (mv[m] == chan[found][c]) k[c] = 1.0 / lr->scale;
        size_t w = (size_t)nprfx_rect_width(pl->bounds), nc = (size_t)pl->nchannels;
        nprfx_image *im = &lr->ring[lr->nring++];
        for (int y = im->bounds.y0; y < im->bounds.y1; y++)
            for (int x = im->bounds.x0; x < im->bounds.x1; x++) {
                const float *s =
                    pl->pixels +
                    ((size_t)(y - pl->bounds.y0) * w + (size_t)(x - pl->bounds.x0)) * nc;
                for (int c = 0; c < nch[found]; c++)
                    nprfx_image_at(im, x, y)[c] = (float)(s[chan[found][c]] * k[c]);
            }
        *out = *im;
    }
    for (int i = 0; i < n; i++)
        free(names[i]);
    if (!r && found < 0) r = nprfx_error(lr->ctx, NPRFX_ERR_MISSING_INPUT, "no plane %s", plane);
    return r;
}

/* Input k at frame: an AOV of a plate, or a map's plate; allocated. */
static nprfx_result look_image(look_run *lr, int k, int frame, nprfx_image *out)
{
    memset(out, 0, sizeof *out);
    if (lr->aov[k] >= 0) {
        nprfx_result r = nprfx_graph_eval_aov(lr->g, lr->node[k], lr->aov[k], frame, out);
        /* a proxy's motion clip: in pixels at full resolution */
        if (!r && lr->scale != 1.0 &&
            (lr->aov[k] == NPRFX_AOV_MOTION_PREV || lr->aov[k] == NPRFX_AOV_MOTION_NEXT))
            for (int y = out->bounds.y0; y < out->bounds.y1; y++)
                for (int x = out->bounds.x0; x < out->bounds.x1; x++)
                    for (int c = 0; c < out->channels; c++)
                        nprfx_image_at(out, x, y)[c] =
                            (float)(nprfx_image_at(out, x, y)[c] / lr->scale);
        return r;
    }
    nprfx_graph_node_info ni = {sizeof ni};
    nprfx_image v;
    nprfx_result r = nprfx_graph_node(lr->g, lr->node[k], &ni);
    if (!r) r = nprfx_graph_eval(lr->g, ni.name, frame, &v, NULL);
    if (!r) r = nprfx_image_alloc(lr->ctx, v.bounds, v.channels < 4 ? v.channels : 4, out);
    if (!r) r = nprfx_image_copy(lr->ctx, &v, out);
    return r;
}

static nprfx_result look_fetch(void *user, int input, double time, nprfx_image *out)
{
    look_run *lr = user;
    if (lr->nring == LOOK_RING) {
        nprfx_image_free(&lr->ring[0]);
        memmove(lr->ring, lr->ring + 1, (LOOK_RING - 1) * sizeof *lr->ring);
        lr->nring--;
    }
    nprfx_image *im = &lr->ring[lr->nring];
    nprfx_result r = look_image(lr, input, (int)(time >= 0 ? time + 0.5 : time - 0.5), im);
    if (r) return r;
    lr->nring++;
    *out = *im;
    return NPRFX_OK;
}

static void usage(void)
{
    fprintf(stderr, "usage: nprfx-ofxtest look GRAPH.json --ofx BUNDLE [--profile NAME] [--frames "
                    "SPEC] [--scramble] [--analyze-shot] [--shot SPEC] [--set NODE.PARAM=VALUE] "
                    "[--param NAME=VALUE] [--press NAME] [--choose NAME=OPTION] [--render-scale S] "
                    "[--outputs all] [--channels R,G,B[;...]] [-o DIR]\n");
}

/* What the command line asks, shared by every output's render. */
typedef struct look_args {
    const char *graph, *bundle, *profile, *frames, *dir, *shot, *stem, *channels;
    const char *sets[16], *params[16], *presses[16], *chooses[16];
    int nsets, nparams, npresses, nchooses;
    int scramble, analyze, all_outputs;
    double scale;
} look_args;

/* One look node of the project: an instance of the look plug-in with its Output choice, its own
 * clips' server (look_run) and its own thread under --outputs all, as a host renders the trees
 * of several writers at once. */
typedef struct look_out {
    look_run lr;
    nprfx_pool *pool;
    nprfx_node_desc desc;
    void *slot;
    int main_input, output; /* output: the Output choice's index, -1 without one */
    char channels[256], file_stem[512];
    double render_seconds;
    nprfx_result r;
    /* shared */
    const look_args *A;
    nprfx_ofx_host *h;
    const nprfx_frame_list *list;
    const char *id;
} look_out;

/* The output's graph and look, after --set and --shot; its clips once the host is open. */
static nprfx_result out_open(look_out *o, const look_args *A, int output)
{
    look_run *lr = &o->lr;
    lr->scale = A->scale;
    o->A = A;
    o->output = output;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    nprfx_result r = nprfx_pool_create(2, &o->pool);
    if (!r) {
        ci.executor = nprfx_pool_executor(o->pool);
        r = nprfx_context_create(&ci, &lr->ctx);
    }
    if (r) return r;
    nprfx_graph_options opt;
    memset(&opt, 0, sizeof opt);
    opt.size = sizeof opt;
    opt.io = nprfx_io_oiio();
    if ((r = nprfx_graph_load(lr->ctx, A->graph, &opt, &lr->g))) return r;
    /* the look as the plug-in derives it from the file; the knobs' values after --set, which the
     * host sets each param to, as a user turning it */
    char why[1024] = "";
    if ((r = look_desc_build(lr->g, A->stem, &lr->look, why, sizeof why)))
        return nprfx_error(lr->ctx, r, "%s is no look: %s", A->graph, why);
    for (int i = 0; i < A->nsets && !r; i++)
        r = nprfx_graph_set(lr->g, A->sets[i]);
    if (!r) look_desc_values(&lr->look, lr->g);
    if (!r && output >= 0 && lr->look.output_param >= 0)
        lr->look.values[lr->look.output_param].v[0] = output;
    if (!r && A->shot) r = nprfx_graph_set_shot(lr->g, A->shot); /* the host's frame range */
    return r;
}

static nprfx_result out_clips(look_out *o, nprfx_ofx_host *h, int first_frame, int own_planes)
{
    look_run *lr = &o->lr;
    lr->planar = h->profile->planes;
    o->main_input = -1;
    for (int k = 0; k < lr->look.desc.num_inputs; k++) {
        if (!look_desc_has_clip(&lr->look, k, lr->planar)) continue;
        int i = lr->n++;
        lr->in[i] = lr->look.in[k];
        lr->node[i] = lr->look.node[k];
        lr->aov[i] = lr->look.aov[k];
        if (k == lr->look.source) o->main_input = i;
    }
    o->desc = lr->look.desc;
    o->desc.num_inputs = lr->n;
    o->desc.inputs = lr->in;
    o->desc.flags = NPRFX_NODE_TEMPORAL;
    if (!lr->planar) return NPRFX_OK;
    /* Source carries the colour plane and every layer of the file, served from this output's
     * look_run (the render's fetch_user) */
    lr->main_node = lr->look.node[lr->look.source];
    h->plane_fetch = look_plane;
    if (!own_planes) return NPRFX_OK;
    nprfx_result r = main_plate(lr, first_frame);
    if (r) return r;
    int chan[63][4], nch[63];
    lr->planes[0] = strdup(kOfxImageComponentRGBA);
    int n = plate_layers(&lr->plate, lr->planes + 1, chan, nch, 63);
    if (n < 0 || !lr->planes[0])
        return nprfx_error(lr->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    lr->nplanes = 1 + n;
    h->planes = lr->planes;
    h->nplanes = lr->nplanes;
    return NPRFX_OK;
}

/* The output's frames, rendered in the order asked and written as DIR/STEM.####.exr. */
static void *out_render(void *user)
{
    look_out *o = user;
    look_run *lr = &o->lr;
    const look_args *A = o->A;
    const nprfx_frame_list *list = o->list;
    nprfx_result r = NPRFX_OK;
    int first = list->frames[0], last = list->frames[list->count - 1];
    (void)nprfx_graph_shot(lr->g, &first, &last);
    for (int fi = 0; fi < list->count && !r; fi++) {
        /* --scramble: the frames in an order no host promises (odd ones first, then even) */
        int idx = fi;
        if (A->scramble)
            idx = fi < (list->count + 1) / 2 ? 2 * fi : 2 * (fi - (list->count + 1) / 2) + 1;
        int frame = list->frames[idx];
        nprfx_image inputs[LOOK_INPUTS], out;
        memset(inputs, 0, sizeof inputs);
        memset(&out, 0, sizeof out);
        for (int k = 0; k < lr->n && !r; k++) {
            r = look_image(lr, k, frame, &inputs[k]);
            /* the clip's channel count, from the first frame: RGBA or fewer (RGB footage) */
            if (!r && fi == 0) lr->in[k].channels = inputs[k].channels;
        }
        nprfx_render_args a;
        memset(&a, 0, sizeof a);
        nprfx_value scaled[LOOK_PARAMS];
        if (o->desc.num_params > LOOK_PARAMS)
            r = nprfx_error(lr->ctx, NPRFX_ERR_UNSUPPORTED, "more than %d params", LOOK_PARAMS);
        else
            memcpy(scaled, lr->look.values, (size_t)o->desc.num_params * sizeof *scaled);
        if (!r) r = nprfx_image_alloc(lr->ctx, inputs[o->main_input].bounds, 4, &out);
        if (!r) {
            a.size = sizeof a;
            a.ctx = lr->ctx;
            a.node = &o->desc;
            a.time = frame;
            /* the host's render scale; the look's knobs are the graph's (design pixels): the
             * hook takes the runner's values, with the render scale applied */
            a.render_scale = a.vector_scale = A->scale;
            if (A->scale != 1.0)
                for (int i = 0; i < o->desc.num_params; i++) {
                    if (o->desc.params[i].flags & NPRFX_PARAM_PIXELS) scaled[i].v[0] *= A->scale;
                    if (o->desc.params[i].flags & NPRFX_PARAM_AREA)
                        scaled[i].v[0] *= A->scale * A->scale;
                }
            a.frame = a.window = inputs[o->main_input].bounds;
            a.first_frame = first;
            a.last_frame = last;
            a.inputs = inputs;
            a.params = scaled;
            a.output = &out;
            a.fetch = look_fetch;
            a.fetch_user = lr;
            struct timespec t0, t1;
            clock_gettime(CLOCK_MONOTONIC, &t0);
            r = internal_hook_render(o->h, &a, &o->slot);
            clock_gettime(CLOCK_MONOTONIC, &t1);
            o->render_seconds +=
                (double)(t1.tv_sec - t0.tv_sec) + (double)(t1.tv_nsec - t0.tv_nsec) * 1e-9;
        }
        if (!r) {
            char path[4400];
            snprintf(path, sizeof path, "%s/%s.%04d.exr", A->dir, o->file_stem, frame);
            /* --channels: the first channels of the Output, under the names the runner's file
             * has; what the plug-in fills beyond a look's channels is checked here: grey
             * (G = B = R) for one channel, opaque (A = 1) for up to three */
            char names_buf[256];
            const char *names[4];
            int nn = 0;
            snprintf(names_buf, sizeof names_buf, "%s", o->channels);
            char *save = NULL;
            for (char *t = strtok_r(names_buf, ",", &save); t && nn < 4;
                 t = strtok_r(NULL, ",", &save))
                names[nn++] = t;
            for (int y = out.bounds.y0; y < out.bounds.y1 && !r; y++)
                for (int x = out.bounds.x0; x < out.bounds.x1 && !r; x++) {
                    const float *p = nprfx_image_at(&out, x, y);
                    if ((nn == 1 && (p[1] != p[0] || p[2] != p[0])) || (nn < 4 && p[3] != 1.0f))
                        r = nprfx_error(lr->ctx, NPRFX_ERR_INTERNAL,
                                        "frame %d: pixel (%d, %d) of the Output is (%g, %g, %g, "
                                        "%g): a look of %d channels fills it otherwise",
                                        frame, x, y, p[0], p[1], p[2], p[3], nn);
                }
            nprfx_image first_n = nprfx_image_channels(&out, 0, nn);
            nprfx_write_options wo;
            memset(&wo, 0, sizeof wo);
            wo.size = sizeof wo;
            if (!r) r = nprfx_io_oiio()->write(lr->ctx, path, &first_n, names, NULL, &wo);
            if (!r) fprintf(stderr, "look %s: frame %d -> %s\n", o->id, frame, path);
        }
        for (int k = 0; k < lr->n; k++)
            nprfx_image_free(&inputs[k]);
        for (int k = 0; k < lr->nring; k++)
            nprfx_image_free(&lr->ring[k]);
        lr->nring = 0;
        nprfx_image_free(&out);
    }
    o->r = r;
    return NULL;
}

static void out_close(look_out *o)
{
    look_run *lr = &o->lr;
    if (o->slot) internal_hook_release(o->h, &o->desc, o->slot);
    for (int i = 0; i < lr->nplanes; i++)
        free(lr->planes[i]);
    nprfx_plate_free(&lr->plate);
    look_desc_free(&lr->look);
    nprfx_graph_free(lr->g);
    nprfx_context_destroy(lr->ctx);
    nprfx_pool_destroy(o->pool);
}

int internal_look_main(int argc, char **argv)
{
    look_args A;
    memset(&A, 0, sizeof A);
    A.dir = ".";
    A.channels = "R,G,B,A";
    A.scale = 1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--scramble"))
            A.scramble = 1;
        else if (!strcmp(a, "--analyze-shot"))
            A.analyze = 1;
        else if (next && !strcmp(a, "--ofx"))
            A.bundle = argv[++i];
        else if (next && !strcmp(a, "--profile"))
            A.profile = argv[++i];
        else if (next && !strcmp(a, "--frames"))
            A.frames = argv[++i];
        else if (next && !strcmp(a, "--shot"))
            A.shot = argv[++i];
        else if (next && !strcmp(a, "--set") && A.nsets < 16)
            A.sets[A.nsets++] = argv[++i];
        else if (next && !strcmp(a, "--param") && A.nparams < 16)
            A.params[A.nparams++] = argv[++i];
        else if (next && !strcmp(a, "--press") && A.npresses < 16)
            A.presses[A.npresses++] = argv[++i];
        else if (next && !strcmp(a, "--choose") && A.nchooses < 16)
            A.chooses[A.nchooses++] = argv[++i];
        else if (next && !strcmp(a, "--render-scale"))
            A.scale = atof(argv[++i]);
        else if (next && !strcmp(a, "--outputs") && !strcmp(next, "all"))
            A.all_outputs = 1, i++;
        else if (next && !strcmp(a, "--channels"))
            A.channels = argv[++i];
        else if (next && !strcmp(a, "-o"))
            A.dir = argv[++i];
        else if (!A.graph && a[0] != '-')
            A.graph = a;
        else {
            usage();
            return 2;
        }
    }
    if (!A.graph || !A.bundle || !(A.scale > 0 && A.scale <= 1)) {
        usage();
        return 2;
    }
    /* the look plug-in of this graph file: its folder first among the looks */
    char folder[4096], stem[256];
    snprintf(folder, sizeof folder, "%s", A.graph);
    char *slash = strrchr(folder, '/');
    const char *base = slash ? slash + 1 : A.graph;
    snprintf(stem, sizeof stem, "%s", base);
    if (strlen(stem) > 5 && !strcmp(stem + strlen(stem) - 5, ".json")) stem[strlen(stem) - 5] = 0;
    if (slash)
        *slash = 0;
    else
        snprintf(folder, sizeof folder, ".");
    setenv("NPRFX_LOOK_PATH", folder, 1);
    A.stem = stem;
    char id[NPRFX_OFX_NAME_MAX];
    ofx_names_look_id(stem, id, sizeof id);

    look_out outs[LOOK_MAX_OUTPUTS];
    memset(outs, 0, sizeof outs);
    int nouts = 1, status = 1;
    nprfx_ofx_host *h = NULL;
    nprfx_frame_list list = {0};
    /* the first output: the look's default Output, or every output with --outputs all */
    nprfx_result r = out_open(&outs[0], &A, -1);
    nprfx_context *ctx = outs[0].lr.ctx;
    if (!ctx) {
        fprintf(stderr, "nprfx-ofxtest: out of memory\n");
        return 1;
    }
    if (!r && A.all_outputs && outs[0].lr.look.noutputs > 1) {
        nouts = outs[0].lr.look.noutputs;
        outs[0].lr.look.values[outs[0].lr.look.output_param].v[0] = 0;
        outs[0].output = 0;
        for (int i = 1; i < nouts && !r; i++)
            outs[i].r = r = out_open(&outs[i], &A, i);
    }
    if (r || (r = nprfx_graph_frames(outs[0].lr.g, A.frames, &list))) goto done;
    if (list.count < 1) {
        r = nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "no frames to render");
        goto done;
    }
    if ((r = nprfx_ofx_host_open(ctx, A.bundle, A.profile, &h))) goto done;
    nprfx_ofx_host_set_analyze(h, A.analyze); /* Analyze Shot pressed before the first render */
    h->param_sets = A.params; /* the look's own params (AOV Layers), set as a project holds them */
    h->nparam_sets = A.nparams;
    h->presses = A.presses;
    h->npresses = A.npresses;
    h->chooses = A.chooses;
    h->nchooses = A.nchooses;
    for (int i = 0; i < h->nplugins; i++)
        if (h->plugins[i].p->pluginIdentifier && !strcmp(h->plugins[i].p->pluginIdentifier, id))
            fprintf(stderr, "look %s: version %u.%u\n", id, h->plugins[i].p->pluginVersionMajor,
                    h->plugins[i].p->pluginVersionMinor);
    /* --channels: one list per output, ';' between them */
    const char *ch = A.channels;
    for (int i = 0; i < nouts && !r; i++) {
        look_out *o = &outs[i];
        o->h = h;
        o->list = &list;
        o->id = id;
        const char *end = strchr(ch, ';');
        snprintf(o->channels, sizeof o->channels, "%.*s", end ? (int)(end - ch) : (int)strlen(ch),
                 ch);
        if (end) ch = end + 1;
        if (nouts > 1)
            snprintf(o->file_stem, sizeof o->file_stem, "%s.%s", stem, o->lr.look.output_label[i]);
        else
            snprintf(o->file_stem, sizeof o->file_stem, "%s", stem);
        r = out_clips(o, h, list.frames[0], i == 0);
    }
    if (r) goto done;
    /* every output's frames at once, one thread each, as a host renders several writers */
    pthread_t threads[LOOK_MAX_OUTPUTS];
    int started = 0;
    for (int i = 1; i < nouts; i++) {
        if (pthread_create(&threads[i], NULL, out_render, &outs[i])) break;
        started = i;
    }
    out_render(&outs[0]);
    for (int i = 1; i <= started; i++)
        pthread_join(threads[i], NULL);
    for (int i = 0; i < nouts && !r; i++)
        if (outs[i].r || i > started) r = outs[i].r ? outs[i].r : NPRFX_ERR_INTERNAL;
    for (int i = 0; i < nouts && !r; i++)
        /* what the frames cost: the host's render calls, of which serving the clips (the host's
         * own work: a real host's Read and Shuffles do it) */
        fprintf(stderr,
                "look %s: %d frames, %.2f s in render (%.1f ms a frame), %.2f s of it serving "
                "clips\n",
                id, list.count, outs[i].render_seconds,
                1000.0 * outs[i].render_seconds / list.count, h->serve_seconds);
    if (!r) status = 0;
done:
    if (r) {
        char msg[2048];
        int bad = 0;
        for (int i = 0; i < nouts; i++)
            if (outs[i].r) bad = i;
        nprfx_context_last_error(outs[bad].lr.ctx ? outs[bad].lr.ctx : ctx, msg, sizeof msg);
        fprintf(stderr, "nprfx-ofxtest look: %s\n", msg);
    }
    for (int i = nouts - 1; i >= 0; i--)
        if (i > 0) out_close(&outs[i]);
    if (outs[0].slot) internal_hook_release(h, &outs[0].desc, outs[0].slot);
    outs[0].slot = NULL;
    nprfx_seq_frames_free(&list);
    nprfx_ofx_host_close(h);
    out_close(&outs[0]); /* its context last: the host was opened on it */
    return status;
}
