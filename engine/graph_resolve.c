/* nprfx graph engine — resolving a graph's references: file patterns at a frame, the channels each
 * input takes from its source, and the motion-vector conventions of read nodes. The evaluation, the
 * memory plan, strip renders and host projects all resolve them the same way. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "nprfx/graph.h"
#include "aov_map.h"
#include "graph_model.h"
#include "graph_extras.h"
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

/* A component letter's position inside a canonical AOV: colour, vector and texture letters. */
static int component_index(char c)
{
    switch (c) {
    case 'R':
    case 'r':
    case 'X':
    case 'x':
    case 'U':
    case 'u':
        return 0;
    case 'G':
    case 'g':
    case 'Y':
    case 'y':
    case 'V':
    case 'v':
        return 1;
    case 'B':
    case 'b':
    case 'Z':
    case 'z':
        return 2;
    case 'A':
    case 'a':
    case 'W':
    case 'w':
        return 3;
    default:
        return -1;
    }
}

int internal_graph_canonical_parse(const char *item, char *components, size_t n)
{
    char name[64];
    const char *dot = strchr(item, '.');
    size_t len = dot ? (size_t)(dot - item) : strlen(item);
    if (len >= sizeof name) return -1;
    memcpy(name, item, len);
    name[len] = 0;
    int aov = nprfx_aov_find(name);
    if (aov < 0) return -1;
    const char *comp = dot ? dot + 1 : "";
    if (strlen(comp) >= n || strlen(comp) > 4) return -1;
    for (const char *c = comp; *c; c++)
        if (component_index(*c) < 0 || component_index(*c) >= nprfx_aov_channels(aov)) return -1;
    snprintf(components, n, "%s", comp);
    return aov;
}

const char *internal_graph_profile_label(const gnode *n, int profile)
{
    return n->aov_map ? n->aov_map->label : nprfx_aov_profile_name(profile);
}

int internal_graph_plate_profile(const gnode *src, const char *const *names, int nc)
{
    if (src->profile_known) return src->profile;
    if (src->aov_map) return src->aov_map->base;
    if (internal_aov_map_named(src->aovs)) return NPRFX_PROFILE_GENERIC;
    if (src->aovs && strcmp(src->aovs, "auto")) return nprfx_aov_profile_find(src->aovs);
    return nprfx_aov_detect(names, nc, NULL, NULL, 0);
}

/* A plate's channels for canonical AOV `aov` (nprfx/aov.h), through its read node's profile
 * ("aovs", else detected; the generic names after a detected profile's): the count, or -1 when
 * the plate has none of its channels. What the read derives comes first: motion in nprfx's
 * convention, ids decoded from Cryptomatte, depth from 1/z. Only plates (read, synth) are
 * resolved: a node's output is named by the node. */
static int canonical_channels(const gnode *src, int aov, const char *const *names, int nc, int *idx,
                              int max, int *profile)
{
    *profile = NPRFX_PROFILE_GENERIC;
    if (src->kind != GK_READ && src->kind != GK_SYNTH) return -1;
    *profile = internal_graph_plate_profile(src, names, nc);
    const char *derived = internal_graph_extra_for(src, aov);
    if (derived) return nprfx_channels_from_hint(names, nc, derived, idx, max);
    if (aov == NPRFX_AOV_MOTION_PREV || aov == NPRFX_AOV_MOTION_NEXT)
        /* A renderer's raw vectors would read with the wrong signs: only the read's own (above)
         * or a synth plate's, which are nprfx's convention already. */
        return src->kind == GK_SYNTH
                   ? nprfx_channels_from_hint(names, nc, nprfx_aov_name(aov), idx, max)
                   : -1;
    const char *cand = internal_aov_map_candidates(src->aov_map, *profile, aov);
    int count = cand ? nprfx_channels_from_hint(names, nc, cand, idx, max) : -1;
    /* a profile the graph names is its word; a detected one may miss a custom pass's name */
    int chosen = src->kind == GK_READ && src->aovs && strcmp(src->aovs, "auto");
    if (count < 0 && !chosen && *profile != NPRFX_PROFILE_GENERIC)
        count = nprfx_channels_from_hint(
            names, nc, nprfx_aov_candidates(NPRFX_PROFILE_GENERIC, aov), idx, max);
    /* a layer may carry more (Blender's Pref AOV has coverage in A): the AOV's own */
    return count > nprfx_aov_channels(aov) ? nprfx_aov_channels(aov) : count;
}

/* Whether a selection's items (sep ',') or a hint's alternatives (sep '|') name a canonical AOV
 * the read derives (Nuke's depth from its 1/z "depth" layer, ids from Cryptomatte, motion in
 * nprfx's convention): the derived channels come before a same-named layer holding the raw
 * numbers. */
static int names_derived(const gnode *src, const char *list, char sep)
{
    for (const char *p = list; p && *p;) {
        const char *e = strchr(p, sep);
        size_t len = e ? (size_t)(e - p) : strlen(p);
        char item[64], comp[8];
        if (len < sizeof item) {
            memcpy(item, p, len);
            item[len] = 0;
            int aov = internal_graph_canonical_parse(item, comp, sizeof comp);
            if (aov >= 0 && internal_graph_extra_for(src, aov)) return 1;
        }
        p = e ? e + 1 : NULL;
    }
    return 0;
}

/* One item of a selection that names a canonical AOV, with components ("beauty.RGB",
 * "normal.ZX"): the count, or -1. *aovp gets the AOV (-1: the item names none). */
static int canonical_item(const gnode *src, const char *item, const char *const *names, int nc,
                          int *idx, int max, int *profile, int *aovp)
{
    char comp[8];
    int aov = internal_graph_canonical_parse(item, comp, sizeof comp);
    *aovp = aov;
    *profile = NPRFX_PROFILE_GENERIC;
    if (aov < 0) return -1;
    int all[NPRFX_MAX_CHANNELS + 1];
    int count = canonical_channels(src, aov, names, nc, all, NPRFX_MAX_CHANNELS + 1, profile);
    if (count < 0) return -1;
    if (!comp[0]) {
        if (count > max) return -1;
        memcpy(idx, all, (size_t)count * sizeof *idx);
        return count;
    }
    int m = 0;
    for (const char *c = comp; *c; c++) {
        int k = component_index(*c);
        if (k >= count || m >= max) return -1;
        idx[m++] = all[k];
    }
    return m;
}

/* A selection of canonical AOVs and channel names, ',' between items ("rest,coverage",
 * "beauty.RGB"): the count, or -1 with *failed the first canonical item that has no channels
 * (-1 when an item is neither a channel nor canonical). */
static int canonical_select(const gnode *src, const char *sel, const char *const *names, int nc,
                            int *idx, int max, int *profile, int *failed, int *single)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", sel);
    int m = 0, items = 0, any = 0;
    *failed = -1;
    *profile = NPRFX_PROFILE_GENERIC;
    for (char *save = NULL, *item = strtok_r(buf, ",", &save); item;
         item = strtok_r(NULL, ",", &save)) {
        items++;
        int amb, aov, k;
        char bad[64];
        k = names_derived(src, item, ',')
                ? -1
                : nprfx_channels_select(names, nc, item, idx + m, max - m, bad, sizeof bad, &amb);
        if (k < 0) {
            k = canonical_item(src, item, names, nc, idx + m, max - m, profile, &aov);
            if (aov >= 0) any = 1;
            if (k < 0) {
                *failed = aov;
                return -1;
            }
        }
        m += k;
    }
    *single = items == 1;
    return any ? m : -1;
}

/* The hint's alternatives that are canonical AOVs, tried through the plate's profile after its
 * literal names found nothing. */
static int canonical_from_hint(const gnode *src, const char *hint, const char *const *names, int nc,
                               int *idx, int max)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", hint);
    for (char *save = NULL, *alt = strtok_r(buf, "|", &save); alt;
         alt = strtok_r(NULL, "|", &save)) {
        int profile, aov, k = canonical_item(src, alt, names, nc, idx, max, &profile, &aov);
        if (k > 0) return k;
    }
    return -1;
}

/* The resolution of internal_graph_input_channels, its error as text in msg instead of raised:
 * the plan tries inputs against plates before it knows which fallback they need. */
nprfx_result internal_graph_input_channels_quiet(const nprfx_graph *g, const gnode *n, int k,
                                                 const char *const *names, int nc, int *idx,
                                                 int *countp, char *msg, size_t msgn)
{
    const gref *ref = &n->inputs[k];
    const nprfx_input_desc *in = n->kind == GK_NODE ? &n->desc->inputs[k] : NULL;
    const char *iname = in ? in->name : "image";
    const char *src = g->nodes[ref->src].name;
    int count = -1, canonical_one = 0;
    char bad[256];
    int amb = 0;
    const gnode *srcn = &g->nodes[ref->src];
    if (ref->sel) {
        count = names_derived(srcn, ref->sel, ',')
                    ? -1
                    : nprfx_channels_select(names, nc, ref->sel, idx, 256, bad, sizeof bad, &amb);
        int profile = NPRFX_PROFILE_GENERIC, failed = -1;
        if (count < 0 && !amb) {
            int k2 = canonical_select(srcn, ref->sel, names, nc, idx, 256, &profile, &failed,
                                      &canonical_one);
            if (k2 > 0) count = k2;
        }
        if (count < 0 && failed >= 0) {
            const char *cand = internal_aov_map_candidates(srcn->aov_map, profile, failed);
            int motion = failed == NPRFX_AOV_MOTION_PREV || failed == NPRFX_AOV_MOTION_NEXT;
            snprintf(msg, msgn,
                     "node '%s': input '%s': plate '%s' has no %s: its %s profile looks for %s; "
                     "name the channels (\"%s:CHANNELS\"), or the profile (\"aovs\" on the read "
                     "node)",
                     n->name, iname, src, nprfx_aov_name(failed),
                     internal_graph_profile_label(srcn, profile),
                     motion ? "the vectors of its \"vectors\" convention"
                            : (cand ? cand : "no fixed channel name"),
                     src);
            return NPRFX_ERR_MISSING_INPUT;
        }
        if (count < 0) {
            char list[1024] = "";
            for (int c = 0; c < nc && strlen(list) < 900; c++) {
                if (c) strcat(list, " ");
                strncat(list, names[c], sizeof list - strlen(list) - 1);
            }
            snprintf(msg, msgn, "node '%s': input '%s': '%s' %s in '%s' (channels: %s)", n->name,
                     iname, bad, amb ? "matches several channels" : "is not a channel", src, list);
            return NPRFX_ERR_MISSING_INPUT;
        }
    } else if (in && in->aov) {
        count = names_derived(srcn, in->aov, '|')
                    ? -1
                    : nprfx_channels_from_hint(names, nc, in->aov, idx, NPRFX_MAX_CHANNELS + 1);
        if (count < 0) {
            count = canonical_from_hint(srcn, in->aov, names, nc, idx, NPRFX_MAX_CHANNELS + 1);
            canonical_one = count > 0;
        }
        if (count < 0 && nc <= 4 && (in->channels == 0 || in->channels == nc)) {
            count = nc;
            for (int c = 0; c < nc; c++)
                idx[c] = c;
        }
        if (count < 0) {
            snprintf(msg, msgn,
                     "node '%s': input '%s': '%s' has no channel matching %s; name the channels, "
                     "e.g. \"%s:CHANNELS\"",
                     n->name, iname, src, in->aov, src);
            return NPRFX_ERR_MISSING_INPUT;
        }
    } else if (nc <= 4 || !in) {
        count = nc < 256 ? nc : 256; /* a write takes everything */
        for (int c = 0; c < count; c++)
            idx[c] = c;
    } else {
        count = nprfx_channels_from_hint(names, nc, "R,G,B,A|R,G,B|Combined.RGBA|Combined.RGB", idx,
                                         NPRFX_MAX_CHANNELS + 1);
        if (count < 0) {
            snprintf(msg, msgn,
                     "node '%s': input '%s': '%s' has %d channels and no R,G,B; name the channels "
                     "to use, e.g. \"%s:R,G,B\"",
                     n->name, iname, src, nc, src);
            return NPRFX_ERR_MISSING_INPUT;
        }
    }
    if (in) {
        /* One canonical colour AOV for an input of fewer channels: its first ones ("beauty" for
         * an RGB input is its R,G,B). */
        if (canonical_one && in->channels > 0 && count > in->channels) count = in->channels;
        if (in->channels > 0 && count != in->channels) {
            snprintf(msg, msgn, "node '%s': input '%s' needs %d channel%s, '%s%s%s' gives %d",
                     n->name, iname, in->channels, in->channels > 1 ? "s" : "", src,
                     ref->sel ? ":" : "", ref->sel ? ref->sel : "", count);
            return NPRFX_ERR_MISSING_INPUT;
        }
        if (in->channels == 0 && count > 4) {
            snprintf(msg, msgn, "node '%s': input '%s' takes 1 to 4 channels, '%s%s%s' gives %d",
                     n->name, iname, src, ref->sel ? ":" : "", ref->sel ? ref->sel : "", count);
            return NPRFX_ERR_MISSING_INPUT;
        }
    }
    if (count < 1) {
        snprintf(msg, msgn, "node '%s': input '%s' selects no channels", n->name, iname);
        return NPRFX_ERR_MISSING_INPUT;
    }
    *countp = count;
    return NPRFX_OK;
}

nprfx_result internal_graph_input_channels(nprfx_graph *g, const gnode *n, int k,
                                           const char *const *names, int nc, int *idx, int *countp)
{
    char msg[2048];
    nprfx_result r =
        internal_graph_input_channels_quiet(g, n, k, names, nc, idx, countp, msg, sizeof msg);
    return r ? nprfx_error(g->ctx, r, "%s", msg) : NPRFX_OK;
}

int internal_graph_packs(int src_channels, const int *idx, int count, unsigned flags)
{
    int contiguous = 1;
    for (int c = 1; c < count; c++)
        contiguous &= idx[c] == idx[0] + c;
    if (!contiguous) return 1;
    return src_channels > 2 * count && !(flags & NPRFX_INPUT_IN_PLACE);
}
