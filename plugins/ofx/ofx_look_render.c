/* nprfx OpenFX adapter — a look plug-in's instance (declared in ofx_look.h): its graph, loaded
 * from the look's file with the knobs' values set into it, evaluated a whole frame at a time;
 * the plates the graph reads served from the host's clips through an nprfx_io (a plate's
 * channels are the connected clips' AOVs under the generic profile's names, so the engine reads
 * them as a render's files); and the questions the host asks before a render (region of
 * definition, frames needed, clip preferences) answered from the graph. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flow_opencv.h"
#include "nprfx/aov.h"
#include "nprfx/channels.h"
#include "ofx_executor.h"
#include "ofx_image.h"
#include "ofx_look.h"
#include "ofx_messages.h"
#include "ofx_suites.h"

/* Where the graph's reads point: the clips, never a file. */
#define LOOK_PLATES "/nprfx-ofx-look/"

typedef struct look_inst {
    const ofx_look *look;
    OfxImageEffectHandle fx;
    OfxImageClipHandle output;
    OfxImageClipHandle clips[LOOK_MAX_INPUTS]; /* NULL: not defined in this context */
    OfxParamHandle *knobs, output_choice, design;
    pthread_mutex_t lock; /* the graph and the render in flight */
    nprfx_context *ctx;
    nprfx_graph *g;
    char *settings; /* what the graph was loaded with (ofx_look_render.c, settings_at) */
    int out_node;   /* the graph node the Output shows */
    int planar;     /* a multi-plane host: the look's plates are Source's layers */
    int profile;    /* there, the renderer profile the layers are read with (0: detected) */
    OfxParamHandle renderer;
    OfxParamHandle analysis;   /* what Analyze Shot measured (NULL: the look measures nothing) */
    OfxParamHandle aov_layers; /* multi-plane: the user's layer for an AOV, lines AOV = CHANNELS */
    OfxParamHandle layer_menu[LOOK_MAX_INPUTS]; /* and a menu of them per AOV input */
    int persistent;
    /* the render in flight: its time, render scale and the frame in host pixels */
    double time, scale;
    OfxRectI frame;
} look_inst;

static look_inst *inst_of(OfxImageEffectHandle fx)
{
    OfxPropertySetHandle p;
    void *data = NULL;
    if (ofx_g.fx->getPropertySet(fx, &p) != kOfxStatOK ||
        ofx_g.prop->propGetPointer(p, kOfxPropInstanceData, 0, &data) != kOfxStatOK)
        return NULL;
    return data;
}

OfxStatus ofx_look_create(const ofx_look *look, OfxImageEffectHandle fx)
{
    look_inst *li = calloc(1, sizeof *li);
    if (!li) return kOfxStatErrMemory;
    li->knobs = calloc((size_t)look->d.desc.num_params + 1, sizeof *li->knobs);
    if (!li->knobs) {
        free(li);
        return kOfxStatErrMemory;
    }
    li->look = look;
    li->fx = fx;
    li->planar = ofx_g.multiplanar;
    (void)ofx_g.fx->clipGetHandle(fx, NPRFX_OFX_OUTPUT_CLIP, &li->output, NULL);
    for (int i = 0; i < look->d.desc.num_inputs; i++)
        if (ofx_g.fx->clipGetHandle(fx, look->d.clip[i], &li->clips[i], NULL) != kOfxStatOK)
            li->clips[i] = NULL;
    OfxParamSetHandle ps;
    if (ofx_g.fx->getParamSet(fx, &ps) == kOfxStatOK) {
        for (int i = 0; i < look->d.desc.num_params; i++)
            (void)ofx_g.param->paramGetHandle(ps, look->d.param_name[i], &li->knobs[i], NULL);
        if (look->d.noutputs > 1)
            (void)ofx_g.param->paramGetHandle(ps, look->d.param_name[look->d.output_param],
                                              &li->output_choice, NULL);
        (void)ofx_g.param->paramGetHandle(ps, "designWidth", &li->design, NULL);
        if (li->planar)
            (void)ofx_g.param->paramGetHandle(ps, LOOK_PARAM_RENDERER, &li->renderer, NULL);
        if (li->planar)
            (void)ofx_g.param->paramGetHandle(ps, LOOK_PARAM_AOV_LAYERS, &li->aov_layers, NULL);
        for (int k = 0; li->planar && k < look->d.desc.num_inputs; k++) {
            int aov = look_desc_layer_aov(&look->d, k);
            char name[64];
            if (aov < 0) continue;
            look_desc_layer_name(aov, name, sizeof name);
            (void)ofx_g.param->paramGetHandle(ps, name, &li->layer_menu[k], NULL);
        }
        char name[NPRFX_OFX_NAME_MAX];
        ofx_names_extra_param(&look->d.desc, "analysis", name, sizeof name);
        if (look->d.measures) (void)ofx_g.param->paramGetHandle(ps, name, &li->analysis, NULL);
    }
    pthread_mutex_init(&li->lock, NULL);
    OfxPropertySetHandle p;
    if (ofx_g.fx->getPropertySet(fx, &p) != kOfxStatOK ||
        ofx_g.prop->propSetPointer(p, kOfxPropInstanceData, 0, li) != kOfxStatOK) {
        pthread_mutex_destroy(&li->lock);
        free(li->knobs);
        free(li);
        return kOfxStatErrBadHandle;
    }
    return kOfxStatOK;
}

static void drop_graph(look_inst *li)
{
    nprfx_graph_free(li->g);
    li->g = NULL;
    nprfx_context_destroy(li->ctx);
    li->ctx = NULL;
    free(li->settings);
    li->settings = NULL;
}

/* ---- the plates: the clips as files ---------------------------------------------------------- */

/* The channel names AOV `aov` has in a plate served to the graph: the generic profile's. */
static const char *const *aov_channels(int aov, int *n)
{
    static const char *const beauty[] = {"R", "G", "B", "A"};
    static const char *const albedo[] = {"albedo.R", "albedo.G", "albedo.B"};
    static const char *const light[] = {"diffuse_light.R", "diffuse_light.G", "diffuse_light.B"};
    static const char *const depth[] = {"depth.Z"};
    static const char *const normal[] = {"N.X", "N.Y", "N.Z"};
    static const char *const position[] = {"P.X", "P.Y", "P.Z"};
    static const char *const rest[] = {"Pref.X", "Pref.Y", "Pref.Z"};
    static const char *const uv[] = {"UV.U", "UV.V"};
    static const char *const id[] = {"id"};
    static const char *const prev[] = {"motion_prev.X", "motion_prev.Y"};
    static const char *const next[] = {"motion_next.X", "motion_next.Y"};
    static const char *const *const names[NPRFX_AOV_COUNT] = {
        beauty, albedo, light, depth, normal, position, rest, uv, id, NULL, prev, next};
    *n = aov >= 0 && aov < NPRFX_AOV_COUNT && names[aov] ? nprfx_aov_channels(aov) : 0;
    return *n ? names[aov] : NULL;
}

/* "/nprfx-ofx-look/plate.0012.exr" -> read node index, frame (map: no frame, *frame the time). */
static int parse_plate(const look_inst *li, const char *path, int *node, int *frame)
{
    if (strncmp(path, LOOK_PLATES, strlen(LOOK_PLATES))) return 0;
    const char *name = path + strlen(LOOK_PLATES);
    const char *dot = strchr(name, '.');
    size_t len = dot ? (size_t)(dot - name) : strlen(name);
    *frame = (int)floor(li->time + 0.5);
    if (dot) *frame = (int)strtol(dot + 1, NULL, 10);
    for (int i = 0; i < li->look->d.desc.num_inputs; i++) {
        nprfx_graph_node_info ni = {sizeof ni};
        if (nprfx_graph_node(li->g, li->look->d.node[i], &ni)) continue;
        if (strlen(ni.name) == len && !strncmp(ni.name, name, len)) {
            *node = li->look->d.node[i];
            return 1;
        }
    }
    return 0;
}

/* The plate's channels: per connected clip of the node, its AOV's channels; in a multi-plane
 * host, for the look's plates, the layers its Source carries: the colour plane as R, G, B, A and
 * each other layer's channels as LAYER.CHANNEL, the names the render's file gives them, so the
 * engine reads them as it reads the file (profile, conventions and all). */
typedef struct plate_chan {
    char name[160];
    int clip, comp;
    int plane; /* index into the planes present, -1: the clip's image */
} plate_chan;

typedef struct plate_planes {
    int n;
    char *plane[64]; /* the clip's planes present (the host's strings) */
} plate_planes;

/* A Natron layer "NatronOfxImageComponentsPlane_LAYER_Channel_X_Channel_Y": its name into layer,
 * its channels' names into ch; returns how many (0: not a layer). */
static int natron_layer(const char *plane, char *layer, size_t n, char ch[4][32])
{
    size_t pl = strlen(kNatronOfxImageComponentsPlane),
           sl = strlen(kNatronOfxImageComponentsPlaneChannel);
    if (strncmp(plane, kNatronOfxImageComponentsPlane, pl)) return 0;
    const char *s = plane + pl, *sep = strstr(s, kNatronOfxImageComponentsPlaneChannel);
    if (!sep) return 0;
    snprintf(layer, n, "%.*s", (int)(sep - s), s);
    int count = 0;
    while (sep && count < 4) {
        const char *c = sep + sl, *next = strstr(c, kNatronOfxImageComponentsPlaneChannel);
        size_t len = next ? (size_t)(next - c) : strlen(c);
        snprintf(ch[count++], sizeof ch[0], "%.*s", (int)(len < 31 ? len : 31), c);
        sep = next;
    }
    return count;
}

static int standard_components(const char *s)
{
    return !strcmp(s, kOfxImageComponentRGBA)    ? 4
           : !strcmp(s, kOfxImageComponentRGB)   ? 3
           : !strcmp(s, kOfxImageComponentAlpha) ? 1
                                                 : 0;
}

/* The planes Source carries (kFnOfxImageEffectPropComponentsPresent). */
static void planes_present(const look_inst *li, plate_planes *pp)
{
    pp->n = 0;
    OfxPropertySetHandle cp = ofx_clip_props(li->clips[li->look->d.source]);
    for (int i = 0; cp && i < 64; i++) {
        char *s = NULL;
        if (ofx_g.prop->propGetString(cp, kFnOfxImageEffectPropComponentsPresent, i, &s) !=
                kOfxStatOK ||
            !s)
            break;
        pp->plane[pp->n++] = s;
    }
}

static int plate_channels(const look_inst *li, int node, plate_chan *out, int max, plate_planes *pp)
{
    int n = 0;
    pp->n = 0;
    const ofx_look *lk = li->look;
    if (li->planar && node == lk->d.node[lk->d.source]) {
        planes_present(li, pp);
        int colour = 0;
        for (int p = 0; p < pp->n; p++) {
            char layer[128], ch[4][32];
            int count = standard_components(pp->plane[p]);
            if (count && colour) continue; /* the colour plane once */
            static const char *const rgba[] = {"R", "G", "B", "A"};
            int first = count == 1 ? 3 : 0;
            if (count) {
                colour = 1;
                for (int k = 0; k < count && n < max; k++, n++) {
                    snprintf(out[n].name, sizeof out[n].name, "%s", rgba[first + k]);
                    out[n].clip = lk->d.source, out[n].comp = k, out[n].plane = p;
                }
                continue;
            }
            count = natron_layer(pp->plane[p], layer, sizeof layer, ch);
            /* A file's channels without a layer but R, G, B, A (RenderMan's z and id, Karma's
             * and V-Ray's depth) are kept in a layer "other" (Nuke's name for it, other.depth):
             * they go by their own names again, as the renderer's profile looks for them. */
            int bare = !strcmp(layer, "other");
            for (int k = 0; k < count && n < max; k++, n++) {
                snprintf(out[n].name, sizeof out[n].name, "%s%s%s", bare ? "" : layer,
                         bare ? "" : ".", ch[k]);
                out[n].clip = lk->d.source, out[n].comp = k, out[n].plane = p;
            }
        }
        /* a host that lists nothing: its colour plane */
        if (!pp->n) {
            static const char *const rgba[] = {"R", "G", "B", "A"};
            for (int k = 0; k < 4 && n < max; k++, n++) {
                snprintf(out[n].name, sizeof out[n].name, "%s", rgba[k]);
                out[n].clip = lk->d.source, out[n].comp = k, out[n].plane = -1;
            }
        }
        return n;
    }
    for (int i = 0; i < lk->d.desc.num_inputs; i++) {
        if (lk->d.node[i] != node || !ofx_clip_connected(li->clips[i])) continue;
        int aov = lk->d.aov[i], count = 4;
        static const char *const rgba[] = {"R", "G", "B", "A"};
        const char *const *names = aov >= 0 ? aov_channels(aov, &count) : rgba;
        /* a picture the host calls opaque has no alpha to read (RGB footage): none, so the
         * graph falls back as on a plate without one */
        char *premult = NULL;
        OfxPropertySetHandle cp = ofx_clip_props(li->clips[i]);
        if (aov == NPRFX_AOV_BEAUTY && cp &&
            ofx_g.prop->propGetString(cp, kOfxImageEffectPropPreMultiplication, 0, &premult) ==
                kOfxStatOK &&
            premult && !strcmp(premult, kOfxImageOpaque))
            count = 3;
        for (int k = 0; names && k < count && n < max; k++, n++) {
            snprintf(out[n].name, sizeof out[n].name, "%s", names[k]);
            out[n].clip = i;
            out[n].comp = k;
            out[n].plane = -1;
        }
    }
    return n;
}

/* Source's layers as channel names (into ch and names, 64 at most; *n how many) and the profile
 * the look reads them with: the one chosen (Renderer), else the one the names tell. */
static int source_layers(const look_inst *li, plate_chan *ch, const char **names, int *n)
{
    plate_planes pp;
    *n = plate_channels(li, li->look->d.node[li->look->d.source], ch, 64, &pp);
    for (int i = 0; i < *n; i++)
        names[i] = ch[i].name;
    return li->profile > 0 ? li->profile - 1 : nprfx_aov_detect(names, *n, NULL, NULL, 0);
}

static OfxRectI to_pixels(OfxRectD r, double s)
{
    OfxRectI p;
    p.x1 = (int)floor(r.x1 * s + 1e-9);
    p.y1 = (int)floor(r.y1 * s + 1e-9);
    p.x2 = (int)ceil(r.x2 * s - 1e-9);
    p.y2 = (int)ceil(r.y2 * s - 1e-9);
    return p;
}

/* The plate's rectangle: the frame for the plates, a map clip's own region for a map. */
static nprfx_result plate_rect(nprfx_context *ctx, const look_inst *li, int node, int frame,
                               OfxRectI *r)
{
    for (int i = 0; i < li->look->d.desc.num_inputs; i++) {
        const look_desc *d = &li->look->d;
        if (d->node[i] != node) continue;
        if (d->aov[i] >= 0) {
            *r = li->frame;
            return NPRFX_OK;
        }
        OfxRectD rod;
        if (!ofx_clip_connected(li->clips[i]))
            return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                               "the %s clip is not connected: the look reads a map from it",
                               d->clip[i]);
        if (ofx_g.fx->clipGetRegionOfDefinition(li->clips[i], frame, &rod) != kOfxStatOK)
            return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                               "the host gives no region of definition for clip %s", d->clip[i]);
        *r = to_pixels(rod, li->scale);
        return NPRFX_OK;
    }
    *r = li->frame;
    return NPRFX_OK;
}

static char *dup_s(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

static nprfx_result look_info(nprfx_context *ctx, const char *path, nprfx_file_info *out)
{
    look_inst *li = nprfx_context_front_end(ctx);
    memset(out, 0, sizeof *out);
    int node = -1, frame = 0;
    if (!li || !parse_plate(li, path, &node, &frame))
        return nprfx_error(ctx, NPRFX_ERR_IO, "'%s': a look reads its plates from its clips", path);
    plate_chan ch[64];
    plate_planes pp;
    int nc = plate_channels(li, node, ch, 64, &pp);
    OfxRectI r;
    nprfx_result res = plate_rect(ctx, li, node, frame, &r);
    if (res) return res;
    int f = r.y1 + r.y2 - 1;
    snprintf(out->format, sizeof out->format, "ofx");
    out->subimages = out->nparts = 1;
    out->bounds = out->display = ofx_flip_rect(r, f);
    out->nchannels = nc;
    out->names = calloc((size_t)nc + 1, sizeof *out->names);
    out->types = calloc((size_t)nc + 1, sizeof *out->types);
    out->parts = calloc(1, sizeof *out->parts);
    int ok = out->names && out->types && out->parts;
    if (ok) {
        nprfx_part_info *pt = &out->parts[0];
        pt->bounds = pt->display = out->bounds;
        pt->nchannels = nc;
        pt->names = calloc((size_t)nc + 1, sizeof *pt->names);
        pt->types = calloc((size_t)nc + 1, sizeof *pt->types);
        pt->miplevels = 1;
        pt->pixel_aspect = 1;
        pt->used = 1;
        ok = pt->names && pt->types;
        for (int c = 0; ok && c < nc; c++)
            ok = (out->names[c] = dup_s(ch[c].name)) && (out->types[c] = dup_s("float")) &&
                 (pt->names[c] = dup_s(ch[c].name)) && (pt->types[c] = dup_s("float"));
    }
    if (!ok) {
        nprfx_file_info_free(out);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    return NPRFX_OK;
}

static nprfx_result look_read(nprfx_context *ctx, const char *path, const nprfx_read_options *opt,
                              nprfx_plate *out)
{
    look_inst *li = nprfx_context_front_end(ctx);
    memset(out, 0, sizeof *out);
    int node = -1, frame = 0;
    if (!li || !parse_plate(li, path, &node, &frame))
        return nprfx_error(ctx, NPRFX_ERR_IO, "'%s': a look reads its plates from its clips", path);
    if (!ofx_g.temporal && frame != (int)floor(li->time + 0.5))
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "the look reads frame %d of its clips to render frame %g, and this "
                           "host gives no other frame (no temporal clip access)",
                           frame, li->time);
    plate_chan all[64];
    plate_planes pp;
    int na = plate_channels(li, node, all, 64, &pp);
    const char *names[64];
    for (int c = 0; c < na; c++)
        names[c] = all[c].name;
    /* the channels asked for, by name, in their order */
    int pick[64], np = 0;
    if (opt && opt->size >= offsetof(nprfx_read_options, pick) && opt->channels) {
        for (int i = 0; i < opt->nchannels && np < 64; i++)
            for (int c = 0; c < na; c++)
                if (!strcmp(opt->channels[i], names[c])) {
                    pick[np++] = c;
                    break;
                }
    } else if (opt && opt->size > offsetof(nprfx_read_options, pick) && opt->pick) {
        np = opt->pick(opt->pick_user, names, na, pick);
    }
    if (np <= 0)
        for (np = 0; np < na; np++)
            pick[np] = np;
    OfxRectI r;
    nprfx_result res = plate_rect(ctx, li, node, frame, &r);
    if (res) return res;
    int f = r.y1 + r.y2 - 1;
    nprfx_rect b = ofx_flip_rect(r, f);
    size_t w = (size_t)nprfx_rect_width(b), h = (size_t)nprfx_rect_height(b);
    out->bounds = out->display = b;
    out->nchannels = np;
    out->pixel_aspect = 1;
    out->names = calloc((size_t)np + 1, sizeof *out->names);
    out->types = calloc((size_t)np + 1, 1);
    out->pixels = calloc(w * h * (size_t)(np > 0 ? np : 1), sizeof *out->pixels);
    if (!out->names || !out->types || !out->pixels) {
        nprfx_plate_free(out);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory for a %zux%zu plate", w, h);
    }
    for (int c = 0; c < np; c++)
        if (!(out->names[c] = dup_s(names[pick[c]]))) {
            nprfx_plate_free(out);
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
        }
    /* each image once (a clip's, or a plane of Source), then its channels into the plate */
    int done[64] = {0};
    for (int c0 = 0; c0 < np; c0++) {
        if (done[c0]) continue;
        const plate_chan *src = &all[pick[c0]];
        const look_desc *ld = &li->look->d;
        int src_aov = ld->aov[src->clip];
        ofx_img img;
        OfxStatus st = src->plane >= 0 && pp.n
                           ? ofx_img_fetch_plane(li->clips[src->clip], frame,
                                                 standard_components(pp.plane[src->plane])
                                                     ? kFnOfxImagePlaneColour
                                                     : pp.plane[src->plane],
                                                 &img)
                           : ofx_img_fetch(li->clips[src->clip], frame, 1, &img);
        if (st != kOfxStatOK) {
            nprfx_plate_free(out);
            return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                               "the host gave no image of clip %s%s%s at frame %d (OFX status %d)",
                               ld->clip[src->clip], src->plane >= 0 ? ", layer of " : "",
                               src->plane >= 0 ? src->name : "", frame, st);
        }
        nprfx_image v;
        float *scratch = NULL;
        if ((res = ofx_img_view(&img, f, 0, img.ncomp, &v, &scratch))) {
            ofx_img_release(&img);
            nprfx_plate_free(out);
            return res;
        }
        /* an AOV clip's motion comes in pixels at full resolution */
        double k =
            src->plane < 0 && (src_aov == NPRFX_AOV_MOTION_PREV || src_aov == NPRFX_AOV_MOTION_NEXT)
                ? li->scale
                : 1.0;
        nprfx_rect in = nprfx_rect_intersect(b, v.bounds);
        for (int c = c0; c < np; c++) {
            const plate_chan *pc = &all[pick[c]];
            if (pc->clip != src->clip || pc->plane != src->plane) continue;
            done[c] = 1;
            int comp = v.channels == 1 ? 0 : pc->comp < v.channels ? pc->comp : -1;
            if (comp < 0) continue; /* an RGB image's alpha: none */
            for (int y = in.y0; y < in.y1; y++) {
                const float *s = nprfx_image_at(&v, in.x0, y) + comp;
                float *d = out->pixels +
                           ((size_t)(y - b.y0) * w + (size_t)(in.x0 - b.x0)) * (size_t)np + c;
                for (int x = in.x0; x < in.x1; x++, s += v.pixel_stride, d += np)
                    *d = k == 1.0 ? *s : (float)(*s * k);
            }
        }
        ofx_free(scratch);
        ofx_img_release(&img);
    }
    /* The read's other clips at this frame, though the graph takes no channel of them: OpenFX
     * has no way to declare a connected clip unneeded (the host prepares it at the frame), and
     * what a host prepared is fetched, as the frames needed said. */
    for (int i = 0; i < li->look->d.desc.num_inputs; i++) {
        int fetched = 0;
        for (int c = 0; c < np; c++)
            fetched |= all[pick[c]].clip == i;
        if (fetched || li->look->d.node[i] != node || !ofx_clip_connected(li->clips[i])) continue;
        ofx_img img;
        if (ofx_img_fetch(li->clips[i], frame, 0, &img) == kOfxStatOK) ofx_img_release(&img);
    }
    /* A render's own motion vectors among the layers are in pixels at full resolution: at a
     * render scale, the channels the read's convention takes them from are scaled with the
     * plate (the AOV clips' motion is, above). */
    int mv[4];
    double sign[4];
    if (li->planar && li->scale != 1.0 && pp.n && nprfx_graph_read_vectors(li->g, node) &&
        nprfx_graph_motion_sources(li->g, node, path, names, na, mv, sign) == NPRFX_OK)
        for (int c = 0; c < np; c++) {
            int motion = 0;
            for (int m = 0; m < 4; m++)
                motion |= mv[m] == pick[c];
            if (!motion) continue;
            for (size_t i = 0; i < w * h; i++)
                out->pixels[i * (size_t)np + (size_t)c] *= (float)li->scale;
        }
    return NPRFX_OK;
}

static const nprfx_io look_io = {sizeof(nprfx_io), look_read, NULL, NULL, NULL, look_info};

/* ---- the graph ------------------------------------------------------------------------------- */

static void append(char **buf, size_t *len, size_t *cap, const char *text)
{
    size_t n = strlen(text);
    if (!*buf && !(*buf = calloc(1, *cap = 1024))) return;
    if (*len + n + 2 > *cap) {
        size_t c = (*len + n + 2) * 2;
        char *g = realloc(*buf, c);
        if (!g) return;
        *buf = g;
        *cap = c;
    }
    memcpy(*buf + *len, text, n);
    *len += n;
    (*buf)[(*len)++] = '\n';
    (*buf)[*len] = 0;
}

/* A value as nprfx_graph_set takes it; doubles in full, so a value comes back bit for bit. */
static void format_value(const nprfx_param_desc *p, const nprfx_value *v, char *text, size_t n)
{
    if (p->type == NPRFX_PARAM_DOUBLE)
        snprintf(text, n, "%.17g", v->v[0]);
    else if (p->type == NPRFX_PARAM_COLOR)
        snprintf(text, n, "%.17g,%.17g,%.17g,%.17g", v->v[0], v->v[1], v->v[2], v->v[3]);
    else
        nprfx_param_format(p, v, text, n);
}

/* The knobs' values at time, as nprfx_graph_set assignments, then what else decides the graph:
 * the output, design width, render scale, shot and connected clips. */
static char *settings_at(const look_inst *li, double time, double scale)
{
    const ofx_look *lk = li->look;
    char *buf = NULL, line[4300];
    size_t len = 0, cap = 0;
    for (int i = 0; i < lk->d.desc.num_params; i++) {
        if (!lk->d.knob[i][0]) continue; /* the output choice: below */
        const nprfx_param_desc *kp = &lk->d.params[i];
        OfxParamHandle h = li->knobs[i];
        nprfx_value v = lk->d.values[i];
        char text[4096];
        int iv = 0;
        char *s = NULL;
        if (h) switch (kp->type) {
            case NPRFX_PARAM_DOUBLE:
                (void)ofx_g.param->paramGetValueAtTime(h, time, &v.v[0]);
                break;
            case NPRFX_PARAM_INT:
            case NPRFX_PARAM_BOOL:
            case NPRFX_PARAM_CHOICE:
                if (ofx_g.param->paramGetValueAtTime(h, time, &iv) == kOfxStatOK) v.v[0] = iv;
                break;
            case NPRFX_PARAM_COLOR:
                (void)ofx_g.param->paramGetValueAtTime(h, time, &v.v[0], &v.v[1], &v.v[2], &v.v[3]);
                break;
            case NPRFX_PARAM_STRING:
                if (ofx_g.param->paramGetValueAtTime(h, time, &s) == kOfxStatOK && s) v.s = s;
                break;
            }
        /* A knob at the graph's value sets nothing: a knob over several nodes ("pattern*.sigma")
         * shows the first one's value, and the others keep their own until it is turned. */
        char def[4096];
        format_value(kp, &v, text, sizeof text);
        format_value(kp, &lk->d.values[i], def, sizeof def);
        if (!strcmp(text, def)) continue;
        snprintf(line, sizeof line, "%s=%s", lk->d.knob[i], text);
        append(&buf, &len, &cap, line);
    }
    int out = 0;
    double design = lk->d.design_width;
    if (li->output_choice) (void)ofx_g.param->paramGetValue(li->output_choice, &out);
    if (li->design) (void)ofx_g.param->paramGetValue(li->design, &design);
    int renderer = 0;
    if (li->renderer) (void)ofx_g.param->paramGetValue(li->renderer, &renderer);
    double range[2] = {0, -1};
    OfxPropertySetHandle sp = ofx_clip_props(li->clips[lk->d.source]);
    if (!sp ||
        ofx_g.prop->propGetDoubleN(sp, kOfxImageEffectPropFrameRange, 2, range) != kOfxStatOK)
        range[0] = 0, range[1] = -1;
    unsigned long long connected = 0;
    for (int i = 0; i < lk->d.desc.num_inputs; i++)
        if (ofx_clip_connected(li->clips[i])) connected |= 1ull << i;
    /* in a multi-plane host, the layers Source carries; and what Analyze Shot measured */
    unsigned long long more = 1469598103934665603ull;
    if (li->planar) {
        plate_planes pp;
        planes_present(li, &pp);
        for (int i = 0; i < pp.n; i++)
            for (const char *c = pp.plane[i]; *c; c++)
                more = (more ^ (unsigned char)*c) * 1099511628211ull;
    }
    OfxParamHandle texts[2] = {li->analysis, li->aov_layers};
    for (int t = 0; t < 2; t++) {
        char *text = NULL;
        if (texts[t] && ofx_g.param->paramGetValue(texts[t], &text) == kOfxStatOK && text)
            for (const char *c = text; *c; c++)
                more = (more ^ (unsigned char)*c) * 1099511628211ull;
        more = (more ^ 0xff) * 1099511628211ull;
    }
    snprintf(line, sizeof line,
             "#output %d\n#design %.17g\n#scale %.17g\n#shot %d %d\n#clips %llx\n#renderer "
             "%d\n#layers %llx",
             out < 0 || out >= lk->d.noutputs ? 0 : out, design, scale, (int)floor(range[0] + 0.5),
             (int)floor(range[1] + 0.5), connected, renderer, more);
    append(&buf, &len, &cap, line);
    return buf;
}

static nprfx_result ensure_graph(look_inst *li, const char *settings, char *err, size_t errn);
static OfxStatus frame_rod(const look_inst *li, double time, OfxRectD *rod);
static OfxStatus fail(look_inst *li, const char *msg);

/* What Analyze Shot measured, into the graph's measuring nodes: "node NAME", the node's lines,
 * "end", for each. A node seeded so still measures again when its frame differs; text that does
 * not read is as none. */
static void seed_analysis(look_inst *li)
{
    char *text = NULL;
    if (!li->analysis || ofx_g.param->paramGetValue(li->analysis, &text) != kOfxStatOK || !text)
        return;
    const char *s = text;
    while (s && !strncmp(s, "node ", 5)) {
        const char *nl = strchr(s, '\n'), *end = strstr(s, "\nend\n");
        if (!nl || !end || end < nl) break;
        char name[256], *lines = NULL;
        snprintf(name, sizeof name, "%.*s", (int)(nl - s - 5 < 255 ? nl - s - 5 : 255), s + 5);
        size_t n = (size_t)(end - nl); /* the lines, with their last newline */
        if ((lines = malloc(n + 1))) {
            memcpy(lines, nl + 1, n);
            lines[n] = 0;
            int i = nprfx_graph_node_index(li->g, name);
            if (i >= 0) (void)nprfx_graph_node_seed(li->g, i, lines);
            free(lines);
        }
        s = end + 5;
    }
}

/* A button's action (Analyze Shot, Find AOV Layers) begins: the graph for the settings now, at the
 * action's time and full size, the instance locked (the caller unlocks). Else the failure,
 * posted. */
static OfxStatus button_begin(look_inst *li, OfxPropertySetHandle in_args, double *time)
{
    (void)ofx_g.prop->propGetDouble(in_args, kOfxPropTime, 0, time);
    OfxRectD rod;
    char msg[2048];
    if (frame_rod(li, *time, &rod) != kOfxStatOK) {
        snprintf(msg, sizeof msg, "%s: the Source clip is not connected", li->look->d.label);
        return fail(li, msg);
    }
    char *settings = settings_at(li, *time, 1);
    if (!settings) return kOfxStatErrMemory;
    pthread_mutex_lock(&li->lock);
    nprfx_result r = ensure_graph(li, settings, msg, sizeof msg);
    free(settings);
    if (r) {
        pthread_mutex_unlock(&li->lock);
        return fail(li, msg);
    }
    li->time = *time;
    li->scale = 1;
    li->frame = to_pixels(rod, 1);
    return kOfxStatOK;
}

/* Analyze Shot: the look's measuring nodes rendered once at the shot's first frame (each reads
 * the frames it measures), and what they measured kept in the hidden param. */
static OfxStatus analyze(look_inst *li, OfxPropertySetHandle in_args)
{
    double time = 0;
    /* measured afresh: what the param held goes first */
    if (ofx_g.param->paramSetValue(li->analysis, "") != kOfxStatOK) return kOfxStatFailed;
    OfxStatus st = button_begin(li, in_args, &time);
    if (st != kOfxStatOK) return st;
    char msg[2048];
    char *text = NULL;
    size_t len = 0, cap = 0;
    nprfx_result r = NPRFX_OK;
    {
        int measured = 0;
        if ((r = nprfx_graph_analyze(li->g, &measured))) {
            char e[1500];
            nprfx_context_last_error(li->ctx, e, sizeof e);
            snprintf(msg, sizeof msg, "%s: Analyze Shot: %s", li->look->d.label, e);
        }
        for (int i = 0; !r && i < nprfx_graph_node_count(li->g); i++) {
            nprfx_graph_node_info ni = {sizeof ni};
            char *t = NULL, line[300];
            if (nprfx_graph_node(li->g, i, &ni) || ni.kind != NPRFX_GRAPH_NODE ||
                !nprfx_node_measures_shot(ni.desc) || nprfx_graph_node_measured(li->g, i, &t) || !t)
                continue;
            snprintf(line, sizeof line, "node %s", ni.name);
            append(&text, &len, &cap, line);
            size_t tl = strlen(t);
            if (tl && t[tl - 1] == '\n') t[tl - 1] = 0; /* append ends each with one */
            append(&text, &len, &cap, t);
            append(&text, &len, &cap, "end");
            free(t);
        }
    }
    pthread_mutex_unlock(&li->lock);
    if (r) return fail(li, msg);
    st = ofx_g.param->paramSetValue(li->analysis, text ? text : "");
    free(text);
    /* the graph reloads with the measurement on the next render (the settings changed) */
    return st == kOfxStatOK ? kOfxStatOK : kOfxStatFailed;
}

/* AOV Layers as the read's "aovs" mapping (engine/aov_map.h, inline): the renderer's profile
 * (chosen, or found from Source's layer names) for what the lines leave alone, and each line's
 * AOV = CHANNELS. *json NULL when the param is empty; an error (in err) names a bad line. */
static nprfx_result layers_map(look_inst *li, char **json, char *err, size_t errn)
{
    *json = NULL;
    err[0] = 0;
    char *text = NULL;
    if (!li->aov_layers || ofx_g.param->paramGetValue(li->aov_layers, &text) != kOfxStatOK || !text)
        return NPRFX_OK;
    char *buf = NULL;
    size_t len = 0, cap = 0;
    int lines = 0, lineno = 0;
    for (const char *s = text; s && *s;) {
        const char *e = strchr(s, '\n');
        size_t n = e ? (size_t)(e - s) : strlen(s);
        char line[1024], aov[64], sel[900];
        snprintf(line, sizeof line, "%.*s", (int)(n < sizeof line - 1 ? n : sizeof line - 1), s);
        s = e ? e + 1 : NULL;
        lineno++;
        char *eq = strchr(line, '=');
        int blank = strspn(line, " \t\r") == strlen(line);
        if (blank || line[strspn(line, " \t")] == '#') continue; /* Find's "# depth: not ..." */
        if (!eq || sscanf(line, " %63[a-z_]", aov) != 1 || nprfx_aov_find(aov) < 0 ||
            sscanf(eq + 1, " %899[^\r]", sel) != 1) {
            snprintf(err, errn,
                     "%s: AOV Layers, line %d ('%s'): expected AOV = CHANNELS with one of the "
                     "AOVs beauty, albedo, diffuse_light, depth, normal, position, rest, uv, id, "
                     "coverage",
                     li->look->d.label, lineno, line);
            free(buf);
            return NPRFX_ERR_PARSE;
        }
        for (size_t k = strlen(sel); k > 0 && (sel[k - 1] == ' ' || sel[k - 1] == '\t'); k--)
            sel[k - 1] = 0;
        char item[1100];
        snprintf(item, sizeof item, "%s\"%s\": \"", lines ? ", " : "", aov);
        size_t at = strlen(item);
        for (const char *c = sel; *c && at + 3 < sizeof item; c++) {
            if (*c == '"' || *c == '\\') item[at++] = '\\';
            item[at++] = *c;
        }
        snprintf(item + at, sizeof item - at, "\"");
        /* append without the newline append() adds */
        if (!buf && !(buf = calloc(1, cap = 4096))) return NPRFX_ERR_OUT_OF_MEMORY;
        if (len + strlen(item) + 1 > cap) {
            char *g = realloc(buf, cap = (len + strlen(item) + 1) * 2);
            if (!g) {
                free(buf);
                return NPRFX_ERR_OUT_OF_MEMORY;
            }
            buf = g;
        }
        memcpy(buf + len, item, strlen(item) + 1);
        len += strlen(item);
        lines++;
    }
    if (!lines) {
        free(buf);
        return NPRFX_OK;
    }
    /* the profile for the rest: the chosen one, else the one the layer names tell */
    plate_chan ch[64];
    const char *names[64];
    int n, profile = source_layers(li, ch, names, &n);
    size_t jn = len + 256;
    char *j = malloc(jn);
    if (j)
        snprintf(j, jn, "{\"profile\": \"%s\", \"aovs\": {%s}}", nprfx_aov_profile_name(profile),
                 buf);
    free(buf);
    if (!j) return NPRFX_ERR_OUT_OF_MEMORY;
    *json = j;
    return NPRFX_OK;
}

/* Find AOV Layers: the channels the look reads each of its AOVs from among Source's layers now,
 * written into AOV Layers (a line each), for the user to check or change. */
static OfxStatus find_layers(look_inst *li, OfxPropertySetHandle in_args)
{
    double time = 0;
    OfxStatus st = button_begin(li, in_args, &time);
    if (st != kOfxStatOK) return st;
    char msg[2048];
    char *text = NULL;
    size_t len = 0, cap = 0;
    const look_desc *d = &li->look->d;
    int node = d->node[d->source];
    nprfx_result r = NPRFX_OK;
    {
        if ((r = nprfx_graph_settle(li->g, (int)floor(time + 0.5)))) {
            char e[1500];
            nprfx_context_last_error(li->ctx, e, sizeof e);
            snprintf(msg, sizeof msg, "%s: Find AOV Layers: %s", d->label, e);
        }
    }
    plate_chan ch[64];
    plate_planes pp;
    int n = r ? 0 : plate_channels(li, node, ch, 64, &pp);
    /* Source's channels, then those the read makes from them (ids from Cryptomatte, depth from
     * 1/z): an AOV found among the latter is the read's work, not a layer to pick */
    const char *names[96];
    for (int i = 0; i < n; i++)
        names[i] = ch[i].name;
    int all = n + (r ? 0 : nprfx_graph_read_extras(li->g, node, names + n, 96 - n));
    if (all > 96) all = 96;
    for (int k = 0; !r && k < d->desc.num_inputs; k++) {
        int aov = look_desc_layer_aov(d, k);
        if (aov < 0) continue;
        int idx[256], count = 0, made = 0;
        char line[1200];
        const char *eq = NULL;
        int found =
            !nprfx_graph_aov_channels(li->g, node, aov, names, all, idx, &count) && count > 0;
        for (int c = 0; found && c < count; c++)
            made |= idx[c] >= n;
        if (made) {
            snprintf(line, sizeof line, "# %s: made by the read from Source's layers (%s)",
                     nprfx_aov_name(aov), names[idx[0]]);
        } else if (!found) {
            snprintf(line, sizeof line, "# %s: not among the layers", nprfx_aov_name(aov));
        } else {
            snprintf(line, sizeof line, "%s = ", nprfx_aov_name(aov));
            eq = line + strlen(line);
            for (int c = 0; c < count && idx[c] < n; c++)
                snprintf(line + strlen(line), sizeof line - strlen(line), "%s%s", c ? "," : "",
                         names[idx[c]]);
        }
        append(&text, &len, &cap, line);
        /* the menu: Source's layers, showing the one found */
        if (li->layer_menu[k]) (void)ofx_look_layer_options(li->layer_menu[k], aov, names, n, eq);
    }
    pthread_mutex_unlock(&li->lock);
    if (r) {
        free(text);
        return fail(li, msg);
    }
    st = ofx_g.param->paramSetValue(li->aov_layers, text ? text : "");
    free(text);
    return st == kOfxStatOK ? kOfxStatOK : kOfxStatFailed;
}

/* The graph for these settings: the one loaded when they are the same, else loaded afresh from
 * the look's file (a change of any knob forgets every cached frame and state). */
static nprfx_result ensure_graph(look_inst *li, const char *settings, char *err, size_t errn)
{
    err[0] = 0;
    if (li->g && li->settings && !strcmp(li->settings, settings)) return NPRFX_OK;
    drop_graph(li);
    const ofx_look *lk = li->look;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.executor = &ofx_host_executor;
    ci.data_dir = ofx_g.data_dir[0] ? ofx_g.data_dir : NULL;
    ci.flow = flow_opencv_provider();
    if (nprfx_context_create(&ci, &li->ctx) != NPRFX_OK) {
        snprintf(err, errn, "%s: out of memory", lk->d.label);
        return NPRFX_ERR_OUT_OF_MEMORY;
    }
    nprfx_context_set_front_end(li->ctx, li);
    nprfx_graph_options opt;
    memset(&opt, 0, sizeof opt);
    opt.size = sizeof opt;
    opt.cache_bytes = (size_t)2 << 30;
    opt.strip_rows = -1; /* whole frames: the clips come whole */
    opt.no_pool = 0;
    opt.io = &look_io;
    nprfx_result r = nprfx_graph_load(li->ctx, lk->path, &opt, &li->g);
    char line[4400];
    const char *rs = strstr(settings, "#renderer ");
    li->profile = rs ? atoi(rs + strlen("#renderer ")) : 0;
    for (int i = 0; !r && i < lk->d.desc.num_inputs; i++) {
        nprfx_graph_node_info ni = {sizeof ni};
        if ((r = nprfx_graph_node(li->g, lk->d.node[i], &ni))) break;
        const char *name = ni.name;
        if (lk->d.aov[i] < 0) {
            snprintf(line, sizeof line, "%s.path=" LOOK_PLATES "%s", name, name);
            r = nprfx_graph_set(li->g, line);
            continue;
        }
        snprintf(line, sizeof line, "%s.path=" LOOK_PLATES "%s.####.exr", name, name);
        if (!r) r = nprfx_graph_set(li->g, line);
        if (li->planar && lk->d.main[i]) {
            /* the render's own layers: its profile as detected (or as the user names it), and
             * the graph's motion convention; AOV Layers maps an AOV to other channels */
            char *map = NULL;
            if (!r && (r = layers_map(li, &map, err, errn)) == NPRFX_OK && map) {
                size_t n = strlen(name) + strlen(map) + 8;
                char *set = malloc(n);
                if (set) {
                    snprintf(set, n, "%s.aovs=%s", name, map);
                    r = nprfx_graph_set(li->g, set);
                    free(set);
                }
                free(map);
            } else if (!r && li->profile > 0) {
                snprintf(line, sizeof line, "%s.aovs=%s", name,
                         nprfx_aov_profile_name(li->profile - 1));
                r = nprfx_graph_set(li->g, line);
            }
            if (r && err[0]) {
                drop_graph(li);
                return r;
            }
        } else {
            snprintf(line, sizeof line, "%s.aovs=generic", name);
            if (!r) r = nprfx_graph_set(li->g, line);
            snprintf(line, sizeof line, "%s.vectors=auto", name);
            if (!r) r = nprfx_graph_set(li->g, line);
        }
        snprintf(line, sizeof line, "%s.colorspace=", name); /* the host's pictures are linear */
        if (!r) r = nprfx_graph_set(li->g, line);
    }
    const char *s = settings;
    int first = 0, last = -1, out = 0;
    double design = 0;
    while (!r && s && *s) {
        const char *e = strchr(s, '\n');
        size_t n = e ? (size_t)(e - s) : strlen(s);
        snprintf(line, sizeof line, "%.*s", (int)n, s);
        if (line[0] != '#')
            r = nprfx_graph_set(li->g, line);
        else if (sscanf(line, "#shot %d %d", &first, &last) == 2 ||
                 sscanf(line, "#output %d", &out) == 1)
            ;
        else if (sscanf(line, "#design %lf", &design) == 1)
            r = nprfx_graph_set_design_width(li->g, design);
        s = e ? e + 1 : NULL;
    }
    if (!r && last >= first) {
        snprintf(line, sizeof line, "%d-%d", first, last);
        r = nprfx_graph_set_shot(li->g, line);
    }
    li->out_node = nprfx_graph_node_index(li->g, lk->d.output[out < lk->d.noutputs ? out : 0]);
    if (!r) seed_analysis(li);
    if (r) {
        char msg[1024];
        nprfx_context_last_error(li->ctx, msg, sizeof msg);
        snprintf(err, errn, "%s (%.600s): %.1000s", lk->d.label, lk->path, msg);
        drop_graph(li);
        return r;
    }
    li->settings = dup_s(settings);
    return NPRFX_OK;
}

/* The frame in host pixels at the render scale: Source's region of definition. */
static OfxStatus frame_rod(const look_inst *li, double time, OfxRectD *rod)
{
    OfxImageClipHandle src = li->clips[li->look->d.source];
    if (!ofx_clip_connected(src)) return kOfxStatFailed;
    return ofx_g.fx->clipGetRegionOfDefinition(src, time, rod);
}

static OfxStatus fail(look_inst *li, const char *msg)
{
    ofx_post_error_on(li->fx, &li->persistent, msg);
    return kOfxStatFailed;
}

static OfxStatus render(look_inst *li, OfxPropertySetHandle in_args)
{
    double time, scale[2];
    int win[4];
    OfxStatus rq = ofx_render_request(in_args, &time, scale, win);
    if (rq != kOfxStatOK) return rq;
    char msg[2048];
    OfxRectD rod;
    if (frame_rod(li, time, &rod) != kOfxStatOK) {
        snprintf(msg, sizeof msg,
                 "%s: the Source clip is not connected: it is the render's picture",
                 li->look->d.label);
        return fail(li, msg);
    }
    char *settings = settings_at(li, time, scale[0]);
    if (!settings) return kOfxStatErrMemory;
    pthread_mutex_lock(&li->lock);
    nprfx_result r = ensure_graph(li, settings, msg, sizeof msg);
    free(settings);
    ofx_img out;
    memset(&out, 0, sizeof out);
    OfxStatus status = kOfxStatFailed;
    if (r) goto done;
    li->time = time;
    li->scale = scale[0];
    li->frame = to_pixels(rod, scale[0]);
    int f = li->frame.y1 + li->frame.y2 - 1;
    int frame = (int)floor(time + 0.5);
    nprfx_image im;
    const char *const *names = NULL;
    nprfx_graph_node_info ni = {sizeof ni};
    if (li->out_node < 0 || nprfx_graph_node(li->g, li->out_node, &ni)) {
        snprintf(msg, sizeof msg, "%s: the graph has no output node", li->look->d.label);
        r = NPRFX_ERR_INTERNAL;
        goto done;
    }
    if ((r = nprfx_graph_eval(li->g, ni.name, frame, &im, &names))) {
        char e[1500];
        nprfx_context_last_error(li->ctx, e, sizeof e);
        snprintf(msg, sizeof msg, "%s: %s", li->look->d.label, e);
        goto done;
    }
    OfxStatus st = ofx_img_fetch(li->output, time, 0, &out);
    if (st != kOfxStatOK) {
        snprintf(msg, sizeof msg, "%s: the host gave no output image (%d)", li->look->d.label, st);
        r = NPRFX_ERR_INTERNAL;
        status = st;
        goto done;
    }
    /* the window, from the look's image: grey for one channel, opaque where it has no alpha */
    int nc = im.channels;
    for (int y = win[1]; y < win[3]; y++)
        for (int x = win[0]; x < win[2]; x++) {
            if (x < out.b.x1 || x >= out.b.x2 || y < out.b.y1 || y >= out.b.y2) continue;
            int yd = f - y;
            float px[4] = {0, 0, 0, 0};
            if (nprfx_rect_contains(im.bounds, x, yd)) {
                const float *s = nprfx_image_at(&im, x, yd);
                if (nc == 1)
                    px[0] = px[1] = px[2] = s[0], px[3] = 1;
                else
                    for (int c = 0; c < 4; c++)
                        px[c] = c < nc ? s[c] : c == 3 ? 1.0f : 0.0f;
            }
            for (int c = 0; c < out.ncomp && c < 4; c++)
                ofx_img_store(&out, x, y, out.ncomp == 1 ? 3 : c, px[out.ncomp == 1 ? 3 : c]);
        }
    status = kOfxStatOK;
    ofx_clear_error_on(li->fx, &li->persistent);
done:
    pthread_mutex_unlock(&li->lock);
    ofx_img_release(&out);
    if (r) {
        ofx_post_error_on(li->fx, &li->persistent, msg);
        if (status == kOfxStatOK) status = kOfxStatFailed;
    }
    return status;
}

/* ---- the questions before a render ----------------------------------------------------------- */

static void set_clip_prop(OfxPropertySetHandle out, const char *prefix, const char *clip, int n,
                          const double *v)
{
    char name[256];
    snprintf(name, sizeof name, "%s%s", prefix, clip);
    (void)ofx_g.prop->propSetDoubleN(out, name, n, v);
}

/* In a multi-plane host, the AOVs Source's layers hold (bits), under the profile the look reads
 * them with: what the graph's fallbacks need not stand in for. */
static unsigned planar_present(const look_inst *li)
{
    plate_chan ch[64];
    const char *names[64];
    int n, profile = source_layers(li, ch, names, &n);
    unsigned bits = 0;
    int idx[NPRFX_MAX_CHANNELS + 1];
    for (int aov = 0; aov < NPRFX_AOV_COUNT; aov++) {
        const char *cand = nprfx_aov_candidates(profile, aov);
        if (aov == NPRFX_AOV_MOTION_PREV || aov == NPRFX_AOV_MOTION_NEXT) {
            const nprfx_aov_vectors *v = nprfx_aov_profile_vectors(profile);
            cand = v ? v->channels : NULL;
            if (nprfx_channels_from_hint(names, n,
                                         aov == NPRFX_AOV_MOTION_PREV
                                             ? "motion_prev.X,motion_prev.Y"
                                             : "motion_next.X,motion_next.Y",
                                         idx, NPRFX_MAX_CHANNELS + 1) > 0)
                bits |= 1u << aov;
        }
        if (cand && nprfx_channels_from_hint(names, n, cand, idx, NPRFX_MAX_CHANNELS + 1) > 0)
            bits |= 1u << aov;
    }
    return bits;
}

static OfxStatus frames_needed(look_inst *li, OfxPropertySetHandle in_args,
                               OfxPropertySetHandle out_args)
{
    double time = 0;
    (void)ofx_g.prop->propGetDouble(in_args, kOfxPropTime, 0, &time);
    const ofx_look *lk = li->look;
    int frame = (int)floor(time + 0.5);
    char *settings = settings_at(li, time, li->scale > 0 ? li->scale : 1);
    char msg[1024];
    /* The graph's nodes' own answers through the graph, from the states a render left; a
     * render holding the graph (it may be fetching through the host on another thread) leaves
     * the whole shot declared, as for a fresh instance. */
    int locked = settings && pthread_mutex_trylock(&li->lock) == 0;
    int ok = locked && ensure_graph(li, settings, msg, sizeof msg) == NPRFX_OK;
    free(settings);
    unsigned present[LOOK_MAX_INPUTS];
    memset(present, 0, sizeof present);
    unsigned planar_aovs = li->planar ? planar_present(li) : 0;
    for (int i = 0; i < lk->d.desc.num_inputs; i++)
        if (li->planar && lk->d.main[i]) present[i] = planar_aovs;
    for (int i = 0; i < lk->d.desc.num_inputs; i++)
        for (int j = 0; j < lk->d.desc.num_inputs && !(li->planar && lk->d.main[i]); j++)
            if (lk->d.node[j] == lk->d.node[i] && lk->d.aov[j] >= 0 &&
                ofx_clip_connected(li->clips[j])) {
                present[i] |= 1u << lk->d.aov[j];
                if (lk->d.aov[j] == NPRFX_AOV_BEAUTY) present[i] |= 1u << NPRFX_AOV_COVERAGE;
            }
    for (int i = 0; i < lk->d.desc.num_inputs; i++) {
        if (!ofx_clip_connected(li->clips[i])) continue;
        double v[2 * 8];
        int n = 0;
        if (!ofx_g.temporal || !lk->d.temporal || lk->d.aov[i] < 0) {
            v[0] = v[1] = time;
            n = 1;
        } else if (ok) {
            nprfx_frame_range r[8];
            /* a plate is read whole (every AOV the graph wants) at each frame any is read */
            if (nprfx_graph_frames_read(li->g, li->out_node, frame, lk->d.node[i], -1, present[i],
                                        r, 8, &n) != NPRFX_OK)
                n = 0;
            for (int k = 0; k < n; k++)
                v[2 * k] = r[k].first, v[2 * k + 1] = r[k].last;
            if (!n) continue; /* the look does not read this clip at this frame */
        } else {
            double range[2] = {time, time};
            OfxPropertySetHandle sp = ofx_clip_props(li->clips[i]);
            if (sp) (void)ofx_g.prop->propGetDoubleN(sp, kOfxImageEffectPropFrameRange, 2, range);
            v[0] = range[0] < time ? range[0] : time;
            v[1] = range[1] > time ? range[1] : time;
            n = 1;
        }
        set_clip_prop(out_args, kOfxImageClipPropFrameRangePrefix, lk->d.clip[i], 2 * n, v);
    }
    if (locked) pthread_mutex_unlock(&li->lock);
    return kOfxStatOK;
}

static void set_clip_str(OfxPropertySetHandle out, const char *prefix, const char *clip,
                         const char *v)
{
    char name[256];
    snprintf(name, sizeof name, "%s%s", prefix, clip);
    (void)ofx_g.prop->propSetString(out, name, 0, v);
}

/* A multi-plane host asks which planes the look reads: every layer Source carries (the graph
 * picks its AOVs among them), RGBA of a map, and RGBA out; nothing passes through. */
static OfxStatus clip_components(look_inst *li, OfxPropertySetHandle out_args)
{
    const ofx_look *lk = li->look;
    char name[256];
    for (int i = 0; i < lk->d.desc.num_inputs; i++) {
        if (!li->clips[i]) continue;
        snprintf(name, sizeof name, "%s%s", kFnOfxImageEffectActionGetClipComponentsPropString,
                 lk->d.clip[i]);
        plate_planes pp = {0};
        if (i == lk->d.source) planes_present(li, &pp);
        if (!pp.n) {
            (void)ofx_g.prop->propSetString(out_args, name, 0, kOfxImageComponentRGBA);
            continue;
        }
        for (int p = 0; p < pp.n; p++)
            (void)ofx_g.prop->propSetString(out_args, name, p, pp.plane[p]);
    }
    snprintf(name, sizeof name, "%s%s", kFnOfxImageEffectActionGetClipComponentsPropString,
             NPRFX_OFX_OUTPUT_CLIP);
    (void)ofx_g.prop->propSetString(out_args, name, 0, kOfxImageComponentRGBA);
    (void)ofx_g.prop->propSetString(out_args, kFnOfxImageEffectPropPassThroughClip, 0, "");
    return kOfxStatOK;
}

static OfxStatus clip_preferences(look_inst *li, OfxPropertySetHandle out_args)
{
    set_clip_str(out_args, kOfxImageClipPropComponentsPrefix, NPRFX_OFX_OUTPUT_CLIP,
                 kOfxImageComponentRGBA);
    set_clip_str(out_args, kOfxImageClipPropDepthPrefix, NPRFX_OFX_OUTPUT_CLIP, kOfxBitDepthFloat);
    for (int i = 0; i < li->look->d.desc.num_inputs; i++)
        if (li->clips[i])
            set_clip_str(out_args, kOfxImageClipPropDepthPrefix, li->look->d.clip[i],
                         kOfxBitDepthFloat);
    (void)ofx_g.prop->propSetString(out_args, kOfxImageEffectPropPreMultiplication, 0,
                                    kOfxImageUnPreMultiplied);
    (void)ofx_g.prop->propSetInt(out_args, kOfxImageEffectFrameVarying, 0, 1);
    return kOfxStatOK;
}

static OfxStatus regions_of_interest(look_inst *li, OfxPropertySetHandle in_args,
                                     OfxPropertySetHandle out_args)
{
    double t = 0;
    (void)ofx_g.prop->propGetDouble(in_args, kOfxPropTime, 0, &t);
    for (int i = 0; i < li->look->d.desc.num_inputs; i++) {
        OfxRectD rod;
        if (!ofx_clip_connected(li->clips[i]) ||
            ofx_g.fx->clipGetRegionOfDefinition(li->clips[i], t, &rod) != kOfxStatOK)
            continue;
        double v[4] = {rod.x1, rod.y1, rod.x2, rod.y2};
        set_clip_prop(out_args, kOfxImageClipPropRoIPrefix, li->look->d.clip[i], 4, v);
    }
    return kOfxStatOK;
}

/* Whether an instance-changed action is that of the param the look calls `want` (the Analyze Shot
 * and Find AOV Layers buttons). */
static int is_param(const look_inst *li, OfxPropertySetHandle in_args, const char *want)
{
    char *type = NULL, *name = NULL, param[NPRFX_OFX_NAME_MAX];
    if (ofx_g.prop->propGetString(in_args, kOfxPropType, 0, &type) != kOfxStatOK ||
        ofx_g.prop->propGetString(in_args, kOfxPropName, 0, &name) != kOfxStatOK || !type ||
        !name || strcmp(type, kOfxTypeParameter))
        return 0;
    if (!strcmp(want, "analyze"))
        ofx_names_extra_param(&li->look->d.desc, want, param, sizeof param);
    else
        snprintf(param, sizeof param, "%s", want);
    return !strcmp(name, param);
}

/* A layer menu turned: its AOV's line of AOV Layers becomes the option (auto: no line). The
 * plug-in's own setting of it (Find AOV Layers showing the layer) changes nothing. */
static OfxStatus layer_chosen(look_inst *li, int k, OfxPropertySetHandle in_args)
{
    char *reason = NULL;
    if (ofx_g.prop->propGetString(in_args, kOfxPropChangeReason, 0, &reason) == kOfxStatOK &&
        reason && !strcmp(reason, kOfxChangePluginEdited))
        return kOfxStatOK;
    int pick = 0;
    char *option = NULL, *text = NULL;
    OfxPropertySetHandle p;
    if (ofx_g.param->paramGetValue(li->layer_menu[k], &pick) != kOfxStatOK ||
        ofx_g.param->paramGetPropertySet(li->layer_menu[k], &p) != kOfxStatOK)
        return kOfxStatFailed;
    if (pick > 0 &&
        (ofx_g.prop->propGetString(p, kOfxParamPropChoiceOption, pick, &option) != kOfxStatOK ||
         !option))
        return kOfxStatOK; /* a saved choice whose options are not listed yet: the text holds */
    if (ofx_g.param->paramGetValue(li->aov_layers, &text) != kOfxStatOK) text = NULL;
    char *edited = ofx_look_layer_edit(text, li->look->d.aov[k], pick > 0 ? option : NULL);
    if (!edited) return kOfxStatErrMemory;
    OfxStatus st = ofx_g.param->paramSetValue(li->aov_layers, edited);
    free(edited);
    return st == kOfxStatOK ? kOfxStatOK : kOfxStatFailed;
}

OfxStatus ofx_look_instance_action(const ofx_look *look, const char *action,
                                   OfxImageEffectHandle fx, OfxPropertySetHandle in_args,
                                   OfxPropertySetHandle out_args)
{
    (void)look;
    look_inst *li = inst_of(fx);
    if (!li) return kOfxStatErrBadHandle;
    if (!strcmp(action, kOfxActionDestroyInstance)) {
        OfxPropertySetHandle p;
        if (ofx_g.fx->getPropertySet(fx, &p) == kOfxStatOK)
            (void)ofx_g.prop->propSetPointer(p, kOfxPropInstanceData, 0, NULL);
        drop_graph(li);
        pthread_mutex_destroy(&li->lock);
        free(li->knobs);
        free(li);
        return kOfxStatOK;
    }
    if (!strcmp(action, kOfxImageEffectActionRender)) return render(li, in_args);
    if (!strcmp(action, kOfxImageEffectActionGetRegionOfDefinition)) {
        double t = 0;
        (void)ofx_g.prop->propGetDouble(in_args, kOfxPropTime, 0, &t);
        OfxRectD rod;
        if (frame_rod(li, t, &rod) != kOfxStatOK) return kOfxStatReplyDefault;
        double v[4] = {rod.x1, rod.y1, rod.x2, rod.y2};
        return ofx_g.prop->propSetDoubleN(out_args, kOfxImageEffectPropRegionOfDefinition, 4, v);
    }
    if (!strcmp(action, kOfxImageEffectActionGetRegionsOfInterest))
        return regions_of_interest(li, in_args, out_args);
    if (!strcmp(action, kOfxImageEffectActionGetFramesNeeded))
        return frames_needed(li, in_args, out_args);
    if (!strcmp(action, kOfxImageEffectActionGetClipPreferences))
        return clip_preferences(li, out_args);
    if (!strcmp(action, kFnOfxImageEffectActionGetClipComponents))
        return li->planar ? clip_components(li, out_args) : kOfxStatReplyDefault;
    if (!strcmp(action, kOfxActionPurgeCaches)) {
        pthread_mutex_lock(&li->lock);
        drop_graph(li);
        pthread_mutex_unlock(&li->lock);
        return kOfxStatOK;
    }
    if (!strcmp(action, kOfxActionInstanceChanged) && li->analysis &&
        is_param(li, in_args, "analyze"))
        return analyze(li, in_args);
    if (!strcmp(action, kOfxActionInstanceChanged) && li->aov_layers &&
        is_param(li, in_args, LOOK_PARAM_FIND_LAYERS))
        return find_layers(li, in_args);
    for (int k = 0; !strcmp(action, kOfxActionInstanceChanged) && k < LOOK_MAX_INPUTS; k++) {
        char name[64];
        if (!li->layer_menu[k]) continue;
        look_desc_layer_name(li->look->d.aov[k], name, sizeof name);
        if (is_param(li, in_args, name)) return layer_chosen(li, k, in_args);
    }
    if (!strcmp(action, kOfxActionInstanceChanged) ||
        !strcmp(action, kOfxImageEffectActionBeginSequenceRender) ||
        !strcmp(action, kOfxImageEffectActionEndSequenceRender) ||
        !strcmp(action, kOfxActionBeginInstanceChanged) ||
        !strcmp(action, kOfxActionEndInstanceChanged))
        return kOfxStatOK; /* a change shows in the settings the next render reads */
    return kOfxStatReplyDefault;
}
