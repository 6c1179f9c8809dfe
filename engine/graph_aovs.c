/* nprfx graph engine — what a graph's plates are. A graph names what it needs (depth, id, rest,
 * ...; nprfx/aov.h); each read node's first frame says under which names and conventions its
 * renderer wrote them. This settles, once and before anything renders, the plate's profile, the
 * motion convention it is read with, where its ids come from (an index pass or Cryptomatte) and
 * how its depth is stored, then checks that every input finds its channels, falling back where a
 * plate lacks an AOV and saying so once. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aov_map.h"
#include "engine_util.h"
#include "graph_aovs.h"
#include "graph_extras.h"
#include "graph_model.h"
#include "graph_resolve.h"
#include "nprfx/aov.h"
#include "nprfx/channels.h"
#include "nprfx/cryptomatte.h"
#include "nprfx/io.h"
#include "nprfx/synth.h"

/* What stands in for an AOV a plate lacks, in order of preference. optional_out: an optional
 * input goes without instead (tone divides its light by the albedo: the beauty there would make
 * the light a flat 1, while without one the light is the beauty's). */
static const struct {
    int aov;
    int with[2];
    int optional_out;
    const char *why;
} fallbacks[] = {
    {NPRFX_AOV_REST,
     {NPRFX_AOV_UV, NPRFX_AOV_POSITION},
     0,
     "patterns stick to the surface only as well as it does"},
    {NPRFX_AOV_ALBEDO, {NPRFX_AOV_BEAUTY, -1}, 1, "the colour carries its light"},
    {NPRFX_AOV_DIFFUSE_LIGHT, {NPRFX_AOV_BEAUTY, -1}, 0, "the light carries the colour"},
};

/* Whether a fallback stands in for aov. */
static int has_fallback(int aov)
{
    for (size_t f = 0; f < sizeof fallbacks / sizeof fallbacks[0]; f++)
        if (fallbacks[f].aov == aov) return 1;
    return 0;
}

/* The canonical AOV input k of n asks for: its selection's (the first item that has a fallback,
 * else the first canonical one: "rest" of "rest,coverage", its place in the selection in *at and
 * *len), else the first canonical alternative of its hint (*len 0); -1 when none. comp gets the
 * item's components. */
static int wanted_aov(const gnode *n, int k, char *comp, size_t size, size_t *at, size_t *len)
{
    const gref *ref = &n->inputs[k];
    comp[0] = 0;
    *at = *len = 0;
    if (ref->sel) {
        int found = -1;
        for (const char *item = ref->sel; *item;) {
            size_t l = strcspn(item, ",");
            char buf[128], c[8];
            if (l < sizeof buf) {
                memcpy(buf, item, l);
                buf[l] = 0;
                int aov = internal_graph_canonical_parse(buf, c, sizeof c);
                if (aov >= 0 && (found < 0 || (!has_fallback(found) && has_fallback(aov)))) {
                    found = aov;
                    *at = (size_t)(item - ref->sel);
                    *len = l;
                    snprintf(comp, size, "%s", c);
                }
            }
            item += l + (item[l] == ',');
        }
        return found;
    }
    if (n->kind != GK_NODE || !n->desc->inputs[k].aov) return -1;
    char buf[1024], c[8];
    snprintf(buf, sizeof buf, "%s", n->desc->inputs[k].aov);
    for (char *save = NULL, *alt = strtok_r(buf, "|", &save); alt;
         alt = strtok_r(NULL, "|", &save)) {
        int aov = internal_graph_canonical_parse(alt, c, sizeof c);
        if (aov >= 0) return aov;
    }
    return -1;
}

/* Whether some input reading plate i asks for `aov` (by its selection or its hint), or
 * `literal` appears in a selection. */
static int plate_needs(const nprfx_graph *g, int i, int aov)
{
    for (int j = 0; j < g->count; j++) {
        const gnode *n = &g->nodes[j];
        for (int k = 0; k < n->ninputs; k++) {
            if (n->inputs[k].src != i) continue;
            char comp[8];
            size_t at, len;
            if (wanted_aov(n, k, comp, sizeof comp, &at, &len) == aov) return 1;
            const char *text = n->inputs[k].sel     ? n->inputs[k].sel
                               : n->kind == GK_NODE ? n->desc->inputs[k].aov
                                                    : NULL;
            if (text && strstr(text, nprfx_aov_name(aov))) return 1;
        }
    }
    return 0;
}

static int selects(const char *const *names, int nc, const char *hint)
{
    int idx[NPRFX_MAX_CHANNELS + 1];
    return hint && nprfx_channels_from_hint(names, nc, hint, idx, NPRFX_MAX_CHANNELS + 1) > 0;
}

void internal_graph_notice(nprfx_graph *g, const char *fmt, ...)
{
    if (!g->notice) return;
    char msg[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    g->notice(g->notice_user, msg);
}

/* Read node i's profile, motion, ids and depth from one header. */
static nprfx_result settle_read(nprfx_graph *g, int i, const nprfx_file_info *info,
                                const char *const *names, int nc)
{
    gnode *n = &g->nodes[i];
    if (internal_aov_map_named(n->aovs) && !n->aov_map) {
        char path[4096];
        if (n->aovs[0] == '/')
            snprintf(path, sizeof path, "%s", n->aovs);
        else
            snprintf(path, sizeof path, "%s/%s", g->base_dir, n->aovs);
        nprfx_result r =
            internal_aov_map_inline(n->aovs)
                ? internal_aov_map_parse(n->ctx, n->aovs, "the read's aovs", &n->aov_map)
                : internal_aov_map_load(n->ctx, path, &n->aov_map);
        if (r) return r;
    }
    const internal_aov_map *map = n->aov_map;
    n->profile = map ? map->base
                 : n->aovs && strcmp(n->aovs, "auto")
                     ? nprfx_aov_profile_find(n->aovs)
                     : nprfx_aov_detect(names, nc, (const char *const *)info->attr_names,
                                        (const char *const *)info->attr_values, info->nattributes);
    n->profile_known = 1;
    const char *profile = internal_graph_profile_label(n, n->profile);
    /* Motion: the convention "vectors" names; with "auto" the profile's, else the first whose
     * channels the plate has (as an explicit convention always reads them, whether or not a node
     * uses them: tools such as measure compare against the plate's motion); with none given, the
     * same, only when an input reads motion from the plate. A plate that has nprfx's own motion
     * channels is read as it is. */
    n->vec = NULL;
    if (n->vectors && strcmp(n->vectors, "auto"))
        n->vec = nprfx_aov_vectors_find(n->vectors); /* "none": NULL */
    else if (n->vectors || plate_needs(g, i, NPRFX_AOV_MOTION_PREV) ||
             plate_needs(g, i, NPRFX_AOV_MOTION_NEXT)) {
        if (!selects(names, nc, "motion_prev.X,motion_prev.Y")) {
            const nprfx_aov_vectors *v =
                map && map->vectors_given ? map->vec : nprfx_aov_profile_vectors(n->profile);
            if (v && selects(names, nc, v->channels)) n->vec = v;
            for (int k = 0;
                 !n->vec && n->profile == NPRFX_PROFILE_GENERIC && nprfx_aov_vectors_at(k); k++)
                if (selects(names, nc, nprfx_aov_vectors_at(k)->channels))
                    n->vec = nprfx_aov_vectors_at(k);
        }
        if (n->vec && n->vec->prev_from_next && plate_needs(g, i, NPRFX_AOV_MOTION_PREV))
            internal_graph_notice(
                g,
                "note: plate '%s' (%s): the renderer writes one motion vector, to the next "
                "frame; motion_prev is its opposite (vectors: %s)",
                n->name, profile, n->vec->name);
    }
    /* Ids: the profile's index pass, else a Cryptomatte layer ("cryptomatte" picks one). */
    free(n->crypto);
    n->crypto = NULL;
    int want_layer = n->cryptomatte && n->cryptomatte[0];
    if (want_layer || plate_needs(g, i, NPRFX_AOV_ID)) {
        int chosen = n->aovs && strcmp(n->aovs, "auto");
        int have_index =
            selects(names, nc, internal_aov_map_candidates(map, n->profile, NPRFX_AOV_ID)) ||
            (!chosen &&
             selects(names, nc, nprfx_aov_candidates(NPRFX_PROFILE_GENERIC, NPRFX_AOV_ID)));
        if (want_layer || !have_index) {
            nprfx_cryptomatte_layer layers[16];
            int nl = nprfx_cryptomatte_find(names, nc, (const char *const *)info->attr_names,
                                            (const char *const *)info->attr_values,
                                            info->nattributes, layers, 16);
            if (nl > 16) nl = 16;
            int pick = nprfx_cryptomatte_pick(layers, nl, want_layer ? n->cryptomatte : NULL);
            if (want_layer && pick < 0) {
                char list[1024] = "";
                for (int l = 0; l < nl; l++) {
                    if (l) strncat(list, ", ", sizeof list - strlen(list) - 1);
                    strncat(list, layers[l].name, sizeof list - strlen(list) - 1);
                }
                return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                                   "node '%s': plate has no Cryptomatte layer '%s' (it has: %s)",
                                   n->name, n->cryptomatte, nl ? list : "none");
            }
            if (pick >= 0) {
                char sel[1024];
                snprintf(sel, sizeof sel, "%s,%s", names[layers[pick].id0],
                         names[layers[pick].cov0]);
                n->crypto = engine_strdup(sel);
                internal_graph_notice(g,
                                      "note: plate '%s' (%s): object ids from Cryptomatte layer %s",
                                      n->name, profile, layers[pick].name);
            }
        }
    }
    /* "colorspace": "auto": integer files (PNG, JPEG, 8- and 16-bit TIFF) hold sRGB-encoded
     * colour, float and half files (EXR, HDR) scene-linear colour. */
    n->colour_from = NULL;
    if (n->colorspace && !strcmp(n->colorspace, "auto")) {
        int rgb[3], amb;
        char bad[64];
        if (nprfx_channels_select((const char *const *)info->names, info->nchannels, "R,G,B", rgb,
                                  3, bad, sizeof bad, &amb) == 3 &&
            info->types && info->types[rgb[0]] &&
            (!strcmp(info->types[rgb[0]], "uint8") || !strcmp(info->types[rgb[0]], "uint16")))
            n->colour_from = "srgb";
    }
    /* Depth stored as 1/z. */
    free(n->depth_inverse);
    n->depth_inverse = NULL;
    if ((map && map->depth >= 0 ? map->depth : nprfx_aov_profile_depth(n->profile)) ==
        NPRFX_DEPTH_INVERSE) {
        int idx[2];
        const char *cand = internal_aov_map_candidates(map, n->profile, NPRFX_AOV_DEPTH);
        if (cand && nprfx_channels_from_hint(names, nc, cand, idx, 2) == 1)
            n->depth_inverse = engine_strdup(names[idx[0]]);
    }
    /* No position, rest or uv, but depth: a camera-space position from depth stands in for them
     * (patterns then hold to the camera, as on footage, rather than to the surfaces). */
    free(n->position_from);
    n->position_from = NULL;
    if (plate_needs(g, i, NPRFX_AOV_REST) || plate_needs(g, i, NPRFX_AOV_UV) ||
        plate_needs(g, i, NPRFX_AOV_POSITION)) {
        int chosen = n->aovs && strcmp(n->aovs, "auto"), have = 0, idx[2];
        static const int anchors[] = {NPRFX_AOV_REST, NPRFX_AOV_UV, NPRFX_AOV_POSITION};
        for (int a = 0; a < 3 && !have; a++)
            have = selects(names, nc, internal_aov_map_candidates(map, n->profile, anchors[a])) ||
                   (!chosen &&
                    selects(names, nc, nprfx_aov_candidates(NPRFX_PROFILE_GENERIC, anchors[a])));
        const char *cand = internal_aov_map_candidates(map, n->profile, NPRFX_AOV_DEPTH);
        int d = cand ? nprfx_channels_from_hint(names, nc, cand, idx, 2) : -1;
        if (d != 1 && !chosen)
            d = nprfx_channels_from_hint(
                names, nc, nprfx_aov_candidates(NPRFX_PROFILE_GENERIC, NPRFX_AOV_DEPTH), idx, 2);
        if (!have && d == 1 && !n->depth_inverse) {
            n->position_from = engine_strdup(names[idx[0]]);
            internal_graph_notice(
                g,
                "warning: plate '%s' (%s profile) has no position, rest or uv: a camera-space "
                "position from its depth stands in (patterns hold to the camera, not to the "
                "surfaces)",
                n->name, profile);
        }
    }
    n->prepared = 1;
    return NPRFX_OK;
}

/* A plate's channel names as its readers see them: the header's and what the read appends. */
typedef struct plate_names {
    char **names;
    int n;
} plate_names;

static void plate_names_free(plate_names *p)
{
    engine_names_free(p->names, p->n);
    memset(p, 0, sizeof *p);
}

/* Whether what happened to a plate's AOV (a bit: stood in for, replaced by flow, left out) is
 * news: each is said once per plate and AOV. */
static int announce(unsigned char *said, int bit)
{
    int news = !(*said & bit);
    *said |= (unsigned char)bit;
    return news;
}

/* Give input k of node j its channels, or a fallback, or fail. */
static nprfx_result settle_input(nprfx_graph *g, int j, int k, const plate_names *plates,
                                 unsigned char (*announced)[NPRFX_AOV_COUNT])
{
    gnode *n = &g->nodes[j];
    gref *ref = &n->inputs[k];
    const gnode *src = &g->nodes[ref->src];
    const plate_names *p = &plates[ref->src];
    const char *const *names = (const char *const *)p->names;
    int idx[256], count;
    char msg[2048], comp[8];
    nprfx_result r =
        internal_graph_input_channels_quiet(g, n, k, names, p->n, idx, &count, msg, sizeof msg);
    if (!r) return NPRFX_OK;
    size_t at, len;
    int aov = wanted_aov(n, k, comp, sizeof comp, &at, &len);
    const char *profile =
        internal_graph_profile_label(src, internal_graph_plate_profile(src, names, p->n));
    int optional = n->kind == GK_NODE && (n->desc->inputs[k].flags & NPRFX_INPUT_OPTIONAL);
    for (size_t f = 0; aov >= 0 && f < sizeof fallbacks / sizeof fallbacks[0]; f++) {
        if (fallbacks[f].aov != aov || (optional && fallbacks[f].optional_out)) continue;
        for (int w = 0; w < 2 && fallbacks[f].with[w] >= 0; w++) {
            /* the item replaced in the selection ("rest,coverage" -> "uv,coverage") */
            char sel[1100];
            const char *whole = ref->sel ? ref->sel : "";
            snprintf(sel, sizeof sel, "%.*s%s%s%s%s", (int)at, whole,
                     nprfx_aov_name(fallbacks[f].with[w]), comp[0] ? "." : "", comp,
                     len ? whole + at + len : "");
            char *old = ref->sel;
            ref->sel = engine_strdup(sel);
            char tried[2048];
            if (!internal_graph_input_channels_quiet(g, n, k, names, p->n, idx, &count, tried,
                                                     sizeof tried)) {
                free(old);
                if (announce(&announced[ref->src][aov], 1)) {
                    char what[300];
                    snprintf(what, sizeof what, "'%s' (%s profile) has no %s", src->name, profile,
                             nprfx_aov_name(aov));
                    internal_graph_notice(g, "warning: plate %s: %s stands in for it (%s)", what,
                                          nprfx_aov_name(fallbacks[f].with[w]), fallbacks[f].why);
                }
                return NPRFX_OK;
            }
            free(ref->sel);
            ref->sel = old;
        }
    }
    /* No motion vectors: optical flow on the beauty, as for footage (the read's fallback flow
     * node, graph_load.c), with its confidence where the node takes one and has none. */
    if ((aov == NPRFX_AOV_MOTION_PREV || aov == NPRFX_AOV_MOTION_NEXT) && src->kind == GK_READ &&
        src->flow >= 0) {
        int fi = src->flow, si = ref->src;
        gref *fin = &g->nodes[fi].inputs[0];
        if (fin->src < 0) {
            fin->src = si;
            fin->sel = engine_strdup("beauty.RGB");
            fin->text = engine_strdup(g->nodes[si].name);
            g->flows_wired = 1;
        }
        if (announce(&announced[si][aov], 2))
            internal_graph_notice(
                g,
                "warning: plate '%s' (%s profile) has no motion vectors: optical flow on its "
                "beauty stands in (node '%s', as for footage: slower, and it restarts the "
                "pattern where the flow is unsure)",
                g->nodes[si].name, profile, g->nodes[fi].name);
        free(ref->sel);
        ref->sel = NULL;
        ref->src = fi;
        free(ref->text);
        ref->text = engine_strdup(g->nodes[fi].name);
        for (int c = 0; c < n->ninputs; c++) {
            gref *conf = &n->inputs[c];
            if (conf->src >= 0 || n->kind != GK_NODE ||
                strcmp(n->desc->inputs[c].name, "confidence"))
                continue;
            conf->src = fi;
            free(conf->text);
            conf->text = engine_strdup(g->nodes[fi].name);
        }
        return NPRFX_OK;
    }
    /* An AOV an input can do without (an id, a normal: lines and mattes then cut where what
     * they still have jumps) is left out, unless the node would be left with no input at all. */
    int others = 0;
    for (int c = 0; c < n->ninputs; c++)
        others += c != k && n->inputs[c].src >= 0;
    if (aov >= 0 && others && optional) {
        if (announce(&announced[ref->src][aov], 4))
            internal_graph_notice(
                g,
                "warning: plate '%s' (%s profile) has no %s: the inputs that take it are left "
                "unconnected",
                src->name, profile, nprfx_aov_name(aov));
        free(ref->sel);
        ref->sel = NULL;
        ref->src = -1;
        return NPRFX_OK;
    }
    return nprfx_error(g->ctx, r, "%s", msg);
}

nprfx_result internal_graph_prepare(nprfx_graph *g, int frame)
{
    if (g->plates_settled) return NPRFX_OK;
    plate_names *plates = calloc((size_t)g->count, sizeof *plates);
    unsigned char(*announced)[NPRFX_AOV_COUNT] = calloc((size_t)g->count, sizeof *announced);
    if (!plates || !announced) {
        free(plates);
        free(announced);
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    }
    nprfx_result r = NPRFX_OK;
    int waiting = 0;
    for (int i = 0; i < g->count && !r; i++) {
        gnode *n = &g->nodes[i];
        plate_names *p = &plates[i];
        if (n->kind == GK_SYNTH) {
            p->n = nprfx_synth_channel_count();
            p->names = internal_graph_names_dup(nprfx_synth_channel_names(), p->n);
            continue;
        }
        if (n->kind != GK_READ) continue;
        char file[4096];
        internal_graph_resolve_path(g, g->base_dir, n->path, frame, file, sizeof file);
        nprfx_file_info info;
        memset(&info, 0, sizeof info);
        nprfx_context *quiet = NULL;
        /* a header that cannot be read yet is the frame's read's to report */
        if (nprfx_context_create(NULL, &quiet)) {
            r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            break;
        }
        /* the io may serve plates from its front end's data (a plug-in's clips) */
        nprfx_context_set_front_end(quiet, nprfx_context_front_end(g->ctx));
        nprfx_result e = g->io.info(quiet, file, &info);
        nprfx_context_destroy(quiet);
        if (e) {
            waiting = 1;
            continue;
        }
        /* The channels the read can deliver: without "part", those of every part of the default
         * view, since the read takes the parts that hold what the graph names. */
        int extra_room = GRAPH_EXTRA_MAX, nc = 0;
        int total = info.nchannels;
        for (int q = 0; q < info.nparts; q++)
            total += info.parts[q].nchannels;
        p->names = calloc((size_t)(total + extra_room), sizeof *p->names);
        if (!p->names) {
            nprfx_file_info_free(&info);
            r = nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
            break;
        }
        for (int c = 0; c < info.nchannels; c++)
            p->names[nc++] = engine_strdup(info.names[c]);
        const char *view = info.nviews ? info.views[0] : "";
        for (int q = 0; info.nparts > 1 && !(n->part && n->part[0]) && q < info.nparts; q++) {
            const nprfx_part_info *part = &info.parts[q];
            if (part->deep || (part->view[0] && strcmp(part->view, view))) continue;
            for (int c = 0; c < part->nchannels; c++) {
                int seen = 0;
                for (int o = 0; o < nc && !seen; o++)
                    seen = !strcmp(p->names[o], part->names[c]);
                if (!seen) p->names[nc++] = engine_strdup(part->names[c]);
            }
        }
        p->n = nc;
        if (!n->prepared && (r = settle_read(g, i, &info, (const char *const *)p->names, nc))) {
            nprfx_file_info_free(&info);
            break;
        }
        for (int c = 0; c < internal_graph_extra_count(n) && c < extra_room; c++)
            p->names[p->n++] = engine_strdup(internal_graph_extra_name(n, c));
        nprfx_file_info_free(&info);
    }
    /* Every input that reads a plate, once all plates are known. */
    for (int j = 0; j < g->count && !r && !waiting; j++)
        for (int k = 0; k < g->nodes[j].ninputs && !r; k++) {
            int s = g->nodes[j].inputs[k].src;
            if (s < 0 || (g->nodes[s].kind != GK_READ && g->nodes[s].kind != GK_SYNTH)) continue;
            r = settle_input(g, j, k, plates, announced);
        }
    if (!r && !waiting) {
        g->plates_settled = 1;
        /* the plan and the reads' wants follow the inputs as settled */
        g->plan_ready = 0;
        for (int i = 0; i < g->count; i++) {
            free(g->nodes[i].wants);
            g->nodes[i].wants = NULL;
            g->nodes[i].nwants = 0;
            g->nodes[i].wants_known = 0;
        }
    }
    for (int i = 0; i < g->count; i++)
        plate_names_free(&plates[i]);
    free(plates);
    free(announced);
    return r;
}
