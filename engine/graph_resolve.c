/* nprfx graph engine — resolving a graph's references: file patterns at a frame, the channels each input
 * takes from its source, and the motion-vector conventions of read nodes. The evaluation, the
 * memory plan, strip renders and host projects all resolve them the same way. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "nprfx/graph.h"
#include "graph_model.h"
#include "graph_resolve.h"
#include "nprfx/aov.h"
#include "nprfx/channels.h"
#include "engine_util.h"

char **internal_graph_names_dup(const char *const *names, int n)
{
    char **d = calloc((size_t)n, sizeof *d);
    for (int i = 0; d && i < n; i++)
        d[i] = engine_strdup(names[i] ? names[i] : "C");
    return d;
}

void internal_graph_resolve_path(const nprfx_graph *g, const char *dir, const char *pattern,
                                 int frame, char *buf, size_t n)
{
    char expanded[4096];
    if (nprfx_seq_expand(NULL, pattern, frame, expanded, sizeof expanded))
        snprintf(expanded, sizeof expanded, "%s", pattern);
    if (expanded[0] == '/' || !dir || !dir[0] || !strcmp(dir, "."))
        snprintf(buf, n, "%s", expanded);
    else
        snprintf(buf, n, "%s/%s", dir, expanded);
    (void)g;
}

/* The motion-vector conventions a read node can map onto nprfx's (docs/design.md §2: pixels, y
 * down, motion_prev points to where the surface point was at frame-1). */
typedef struct vec_convention {
    const char *name;
    const char *layer; /* channels to look for: prev.x, prev.y, next.x, next.y */
    double sign[4];    /* multipliers applied to those channels */
} vec_convention;
/* Blender's Vector pass (measured on the sample renders, see samples/plates/README.md), image y
 * up: (X, Y) = position at frame i-1 minus position at i; (Z, W) = position at i minus position
 * at i+1. So motion_prev = (X, -Y) and motion_next = (-Z, W). Nuke's backward/forward vectors
 * point from this frame to the previous/next one, y up. */
const char *const internal_graph_motion_names[4] = {"motion_prev.X", "motion_prev.Y",
                                                    "motion_next.X", "motion_next.Y"};

static const vec_convention vec_conventions[] = {
    {"blender", "Vector.X,Vector.Y,Vector.Z,Vector.W", {1, -1, -1, 1}},
    {"nuke", "backward.u,backward.v,forward.u,forward.v", {1, -1, 1, -1}},
};

const char *internal_graph_motion_layer(const char *vectors)
{
    for (size_t i = 0; i < sizeof vec_conventions / sizeof vec_conventions[0]; i++)
        if (!strcmp(vectors, vec_conventions[i].name)) return vec_conventions[i].layer;
    return NULL;
}

nprfx_result internal_graph_motion_sources(nprfx_graph *g, const gnode *n, const char *file,
                                           const char *const *names, int nc, int *idx, double *sign)
{
    const vec_convention *vc = NULL;
    for (size_t i = 0; i < sizeof vec_conventions / sizeof vec_conventions[0]; i++)
        if (!strcmp(n->vectors, vec_conventions[i].name)) vc = &vec_conventions[i];
    if (!vc)
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "node '%s': vectors '%s' is not one of: none, blender, nuke", n->name,
                           n->vectors);
    int amb;
    char bad[256];
    if (nprfx_channels_select(names, nc, vc->layer, idx, 4, bad, sizeof bad, &amb) != 4)
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                           "node '%s': %s has no %s channel '%s' for vectors=%s", n->name, file,
                           amb ? "unique" : "", bad, n->vectors);
    for (int k = 0; k < 4; k++)
        sign[k] = vc->sign[k];
    return NPRFX_OK;
}

/* Which channels of a source with `names` input k of node n takes (its reference's selection,
 * else its AOV hint, else all), checked against the input's channel count. */
/* A plate's channels for canonical AOV `name` (nprfx/aov.h), through its read node's profile
 * ("aovs"; detected from the channel names when unset or "auto", the generic names after the
 * detected profile's): the count, or -1 when name is no canonical AOV or the plate has none of
 * its channels. Motion is left to the read node's vector convention, which turns a renderer's
 * vectors into nprfx's; its raw channels would have the wrong signs. *profile gets the profile
 * looked in. Only plates (read, synth) are resolved: a node's output is named by the node. */
static int canonical_channels(const gnode *src, const char *name, const char *const *names,
                              int nc, int *idx, int max, int *profile)
{
    int aov = nprfx_aov_find(name);
    *profile = NPRFX_PROFILE_GENERIC;
    if (aov < 0 || aov == NPRFX_AOV_MOTION_PREV || aov == NPRFX_AOV_MOTION_NEXT) return -1;
    if (src->kind != GK_READ && src->kind != GK_SYNTH) return -1;
    int chosen = src->aovs && strcmp(src->aovs, "auto");
    *profile = chosen ? nprfx_aov_profile_find(src->aovs)
                      : nprfx_aov_detect(names, nc, NULL, NULL, 0);
    const char *cand = nprfx_aov_candidates(*profile, aov);
    int count = cand ? nprfx_channels_from_hint(names, nc, cand, idx, max) : -1;
    if (count < 0 && !chosen && *profile != NPRFX_PROFILE_GENERIC)
        count = nprfx_channels_from_hint(names, nc,
                                         nprfx_aov_candidates(NPRFX_PROFILE_GENERIC, aov), idx,
                                         max);
    return count;
}

/* The hint's alternatives that are canonical AOVs, tried through the plate's profile after its
 * literal names found nothing. */
static int canonical_from_hint(const gnode *src, const char *hint, const char *const *names,
                               int nc, int *idx, int max)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", hint);
    for (char *save = NULL, *alt = strtok_r(buf, "|", &save); alt;
         alt = strtok_r(NULL, "|", &save)) {
        int profile, k = canonical_channels(src, alt, names, nc, idx, max, &profile);
        if (k > 0) return k;
    }
    return -1;
}

nprfx_result internal_graph_input_channels(nprfx_graph *g, const gnode *n, int k,
                                           const char *const *names, int nc, int *idx, int *countp)
{
    const gref *ref = &n->inputs[k];
    const nprfx_input_desc *in = n->kind == GK_NODE ? &n->desc->inputs[k] : NULL;
    const char *iname = in ? in->name : "image";
    const char *src = g->nodes[ref->src].name;
    int count = -1;
    char bad[256];
    int amb = 0;
    const gnode *srcn = &g->nodes[ref->src];
    if (ref->sel) {
        count = nprfx_channels_select(names, nc, ref->sel, idx, 256, bad, sizeof bad, &amb);
        int profile = NPRFX_PROFILE_GENERIC;
        if (count < 0 && !amb) {
            int k = canonical_channels(srcn, ref->sel, names, nc, idx, 256, &profile);
            if (k > 0) count = k;
        }
        if (count < 0 && nprfx_aov_find(ref->sel) >= 0 &&
            (srcn->kind == GK_READ || srcn->kind == GK_SYNTH)) {
            int aov = nprfx_aov_find(ref->sel);
            const char *cand = nprfx_aov_candidates(profile, aov);
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s': plate '%s' has no %s: its %s profile "
                               "looks for %s; name the channels (\"%s:CHANNELS\"), or the "
                               "profile (\"aovs\" on the read node)",
                               n->name, iname, src, ref->sel, nprfx_aov_profile_name(profile),
                               aov == NPRFX_AOV_MOTION_PREV || aov == NPRFX_AOV_MOTION_NEXT
                                   ? "the vectors its \"vectors\" convention makes"
                                   : (cand ? cand : "no fixed channel name"),
                               src);
        }
        if (count < 0) {
            char list[1024] = "";
            for (int c = 0; c < nc && strlen(list) < 900; c++) {
                if (c) strcat(list, " ");
                strncat(list, names[c], sizeof list - strlen(list) - 1);
            }
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s': '%s' %s in '%s' (channels: %s)", n->name,
                               iname, bad, amb ? "matches several channels" : "is not a channel",
                               src, list);
        }
    } else if (in && in->aov) {
        count = nprfx_channels_from_hint(names, nc, in->aov, idx, NPRFX_MAX_CHANNELS + 1);
        if (count < 0)
            count = canonical_from_hint(srcn, in->aov, names, nc, idx, NPRFX_MAX_CHANNELS + 1);
        if (count < 0 && nc <= 4 && (in->channels == 0 || in->channels == nc)) {
            count = nc;
            for (int c = 0; c < nc; c++)
                idx[c] = c;
        }
        if (count < 0)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s': '%s' has no channel matching %s; name the "
                               "channels, e.g. \"%s:CHANNELS\"",
                               n->name, iname, src, in->aov, src);
    } else if (nc <= 4 || !in) {
        count = nc < 256 ? nc : 256; /* a write takes everything */
        for (int c = 0; c < count; c++)
            idx[c] = c;
    } else {
        count = nprfx_channels_from_hint(names, nc, "R,G,B,A|R,G,B|Combined.RGBA|Combined.RGB", idx,
                                         NPRFX_MAX_CHANNELS + 1);
        if (count < 0)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s': '%s' has %d channels and no R,G,B; name "
                               "the channels to use, e.g. \"%s:R,G,B\"",
                               n->name, iname, src, nc, src);
    }
    if (in) {
        if (in->channels > 0 && count != in->channels)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s' needs %d channel%s, '%s%s%s' gives %d",
                               n->name, iname, in->channels, in->channels > 1 ? "s" : "", src,
                               ref->sel ? ":" : "", ref->sel ? ref->sel : "", count);
        if (in->channels == 0 && count > 4)
            return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                               "node '%s': input '%s' takes 1 to 4 channels, '%s%s%s' gives %d",
                               n->name, iname, src, ref->sel ? ":" : "", ref->sel ? ref->sel : "",
                               count);
    }
    if (count < 1)
        return nprfx_error(g->ctx, NPRFX_ERR_MISSING_INPUT,
                           "node '%s': input '%s' selects no channels", n->name, iname);
    *countp = count;
    return NPRFX_OK;
}

int internal_graph_packs(int src_channels, const int *idx, int count, unsigned flags)
{
    int contiguous = 1;
    for (int c = 1; c < count; c++)
        contiguous &= idx[c] == idx[0] + c;
    if (!contiguous) return 1;
    return src_channels > 2 * count && !(flags & NPRFX_INPUT_IN_PLACE);
}
