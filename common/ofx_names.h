/* nprfx — how a node descriptor maps onto OpenFX names: plug-in identifiers, clip names,
 * channel-selector params and their options. Everything is derived from the descriptor, never
 * written a second time; the adapter (plugins/ofx/) and the test host (tests/ofxhost/) include
 * this one header so both sides agree on the derivation. */
#ifndef NPRFX_OFX_NAMES_H
#define NPRFX_OFX_NAMES_H

#include <ctype.h>
#include <stdio.h>
#include <string.h>

#include "nprfx/node.h"

#define NPRFX_OFX_ID_PREFIX "org.nprfx."
#define NPRFX_OFX_OUTPUT_CLIP "Output"
#define NPRFX_OFX_SOURCE_CLIP "Source"
#define NPRFX_OFX_MASK_CLIP "Mask"
#define NPRFX_OFX_NAME_MAX 128

/* "coherent-noise" -> "org.nprfx.CoherentNoise". */
static inline void ofx_names_plugin_id(const nprfx_node_desc *d, char *buf, size_t n)
{
    size_t k = (size_t)snprintf(buf, n, "%s", NPRFX_OFX_ID_PREFIX);
    int up = 1;
    for (const char *s = d->id; *s && k + 1 < n; s++) {
        if (!isalnum((unsigned char)*s)) {
            up = 1;
            continue;
        }
        buf[k++] = up ? (char)toupper((unsigned char)*s) : *s;
        up = 0;
    }
    buf[k < n ? k : n - 1] = 0;
}

/* The input OFX calls "Source": the one flagged NPRFX_INPUT_MAIN, else the one labelled
 * "Source" (coherent-noise's clip to make coherent), else the first; -1 without inputs. */
static inline int ofx_names_main_input(const nprfx_node_desc *d)
{
    for (int k = 0; k < d->num_inputs; k++)
        if (d->inputs[k].flags & NPRFX_INPUT_MAIN) return k;
    for (int k = 0; k < d->num_inputs; k++)
        if (d->inputs[k].label && !strcmp(d->inputs[k].label, NPRFX_OFX_SOURCE_CLIP)) return k;
    return d->num_inputs > 0 ? 0 : -1;
}

/* Only a node that modifies an image (NPRFX_INPUT_MAIN) gets the Mask clip and mix params. */
static inline int ofx_names_maskable(const nprfx_node_desc *d)
{
    for (int k = 0; k < d->num_inputs; k++)
        if (d->inputs[k].flags & NPRFX_INPUT_MAIN) return 1;
    return 0;
}

static inline int ofx_names_reserved_clip(const char *s)
{
    return !strcmp(s, NPRFX_OFX_OUTPUT_CLIP) || !strcmp(s, NPRFX_OFX_SOURCE_CLIP) ||
           !strcmp(s, NPRFX_OFX_MASK_CLIP);
}

/* Clip name of input k: "Source" for the main input, else its label without spaces or
 * punctuation ("Z Velocity" -> "ZVelocity"); a clash with a reserved name gets the input's
 * name appended, so every clip name stays unique. */
static inline void ofx_names_clip_name(const nprfx_node_desc *d, int k, char *buf, size_t n)
{
    if (k == ofx_names_main_input(d)) {
        snprintf(buf, n, "%s", NPRFX_OFX_SOURCE_CLIP);
        return;
    }
    const char *label = d->inputs[k].label ? d->inputs[k].label : d->inputs[k].name;
    size_t j = 0;
    int up = 1;
    for (const char *s = label; *s && j + 1 < n; s++) {
        if (!isalnum((unsigned char)*s)) {
            up = 1;
            continue;
        }
        buf[j++] = up ? (char)toupper((unsigned char)*s) : *s;
        up = 0;
    }
    buf[j] = 0;
    if (!j || ofx_names_reserved_clip(buf)) {
        size_t len = strlen(buf);
        snprintf(buf + len, n - len, "_%s", d->inputs[k].name);
    }
}

/* Param names the adapter adds beside the descriptor's own; a clash with a descriptor param
 * (whose names are snake_case) gets an "ofx" prefix. */
static inline void ofx_names_extra_param(const nprfx_node_desc *d, const char *want, char *buf,
                                         size_t n)
{
    int len = nprfx_node_param_index(d, want) < 0
                  ? snprintf(buf, n, "%s", want)
                  : snprintf(buf, n, "ofx%c%s", toupper((unsigned char)want[0]), want + 1);
    if (len < 0 || (size_t)len >= n) buf[n - 1] = 0; /* names this long do not occur */
}

/* Whether the node has params in pixels (PIXELS or AREA) or is otherwise scaled with the image
 * (NPRFX_NODE_PIXEL_SCALED): the adapter adds a "designWidth" param to it (the plate width those
 * params were set for, as a graph's "design_width"). */
static inline int ofx_names_has_pixel_params(const nprfx_node_desc *d)
{
    if (d->flags & NPRFX_NODE_PIXEL_SCALED) return 1;
    for (int i = 0; i < d->num_params; i++)
        if (d->params[i].flags & (NPRFX_PARAM_PIXELS | NPRFX_PARAM_AREA)) return 1;
    return 0;
}

/* The channel selector of input k: the input's own name in lowerCamel case, then "Channels"
 * ("depth" -> "depthChannels", "motion_prev" -> "motionPrevChannels", "uv" -> "uvChannels",
 * "object_id" -> "objectIdChannels"). The input's name, not its clip's: the main clip is
 * always "Source", and a knob called sourceChannels under a clip labelled Tone reads oddly. */
static inline void ofx_names_selector_name(const nprfx_node_desc *d, int k, char *buf, size_t n)
{
    char want[NPRFX_OFX_NAME_MAX];
    size_t j = 0;
    int up = 0;
    for (const char *s = d->inputs[k].name; *s && j + 1 < sizeof want - 8; s++) {
        if (!isalnum((unsigned char)*s)) {
            up = j > 0;
            continue;
        }
        want[j++] = up ? (char)toupper((unsigned char)*s) : (char)tolower((unsigned char)*s);
        up = 0;
    }
    snprintf(want + j, sizeof want - j, "Channels");
    ofx_names_extra_param(d, want, buf, n);
}

/* Host images carry RGBA or Alpha only, so an input's channels are a contiguous run of the
 * RGBA components, picked by its selector (openfx-misc style). */
typedef struct ofx_names_chan_option {
    const char *label;
    int first, count; /* components first .. first+count-1 of R,G,B,A */
} ofx_names_chan_option;

static const ofx_names_chan_option ofx_names_chan_options[] = {
    {"RGBA", 0, 4}, {"RGB", 0, 3}, {"GBA", 1, 3}, {"RG", 0, 2}, {"GB", 1, 2},
    {"BA", 2, 2},   {"R", 0, 1},   {"G", 1, 1},   {"B", 2, 1},  {"A", 3, 1},
};
#define NPRFX_OFX_CHAN_OPTIONS                                                                     \
    ((int)(sizeof ofx_names_chan_options / sizeof ofx_names_chan_options[0]))

/* The selector's options for an input (indices into ofx_names_chan_options): those with the
 * input's exact channel count, or all of them for "any count from 1 to 4". Returns how many. */
static inline int ofx_names_selector_options(const nprfx_input_desc *in, int *opts)
{
    int n = 0;
    for (int i = 0; i < NPRFX_OFX_CHAN_OPTIONS; i++)
        if (in->channels <= 0 || ofx_names_chan_options[i].count == in->channels) opts[n++] = i;
    return n;
}

/* Position among the input's options of (first, count); -1 when it has none such. */
static inline int ofx_names_selector_find(const nprfx_input_desc *in, int first, int count)
{
    int opts[NPRFX_OFX_CHAN_OPTIONS];
    int n = ofx_names_selector_options(in, opts);
    for (int i = 0; i < n; i++)
        if (ofx_names_chan_options[opts[i]].first == first &&
            ofx_names_chan_options[opts[i]].count == count)
            return i;
    return -1;
}

/* Default option: the first R/G/B/A single-letter alternative of the input's AOV hint (a
 * coverage input that looks for "coverage|Coverage|A" reads A), else the first option. */
static inline int ofx_names_selector_default(const nprfx_input_desc *in)
{
    const char *s = in->aov;
    while (s && *s) {
        const char *e = strchr(s, '|');
        size_t len = e ? (size_t)(e - s) : strlen(s);
        if (len == 1 && strchr("RGBA", *s)) {
            int i = ofx_names_selector_find(in, (int)(strchr("RGBA", *s) - "RGBA"), 1);
            if (i >= 0) return i;
        }
        s = e ? e + 1 : NULL;
    }
    return 0;
}

/* ---- look plug-ins: a graph file as one effect ---------------------------------------------- */

#define NPRFX_OFX_LOOK_PREFIX NPRFX_OFX_ID_PREFIX "look."

/* Words joined in CamelCase: "cross_hatching" -> "CrossHatching", "motion_prev" -> "MotionPrev". */
static inline void ofx_names_camel(const char *s, char *buf, size_t n)
{
    size_t j = 0;
    int up = 1;
    for (; s && *s && j + 1 < n; s++) {
        if (!isalnum((unsigned char)*s)) {
            up = 1;
            continue;
        }
        buf[j++] = up ? (char)toupper((unsigned char)*s) : *s;
        up = 0;
    }
    if (n) buf[j] = 0;
}

/* A look's identifier from its graph file's name without ".json": "toon" -> "org.nprfx.look.Toon".
 */
static inline void ofx_names_look_id(const char *stem, char *buf, size_t n)
{
    char camel[NPRFX_OFX_NAME_MAX];
    ofx_names_camel(stem, camel, sizeof camel);
    snprintf(buf, n, "%s%.100s", NPRFX_OFX_LOOK_PREFIX, camel);
}

/* The clip that carries AOV `aov` (nprfx_aov_name's name, NULL: the whole file of a map) of read
 * node `read`: for the look's first frame sequence ("main"), Source for the picture and the
 * AOV's name in CamelCase for the others ("Depth", "MotionPrev"); for another read, its name in
 * CamelCase before it ("Pam", "EnvDepth"). Coverage travels as Source's alpha. */
static inline void ofx_names_look_clip(const char *read, int main, const char *aov, char *buf,
                                       size_t n)
{
    char a[64] = "", r[64] = "";
    int beauty = aov && !strcmp(aov, "beauty");
    if (aov && !beauty) ofx_names_camel(aov, a, sizeof a);
    if (!strcmp(a, "Uv")) snprintf(a, sizeof a, "UV");
    if (!strcmp(a, "Id")) snprintf(a, sizeof a, "ID");
    if (main) {
        snprintf(buf, n, "%s", beauty ? NPRFX_OFX_SOURCE_CLIP : a);
        return;
    }
    ofx_names_camel(read, r, sizeof r);
    if (ofx_names_reserved_clip(r)) snprintf(r + strlen(r), sizeof r - strlen(r), "Map");
    snprintf(buf, n, "%s%s", r, a);
}

/* A knob's param name: the graph's NODE.PARAM with every other character an underscore
 * ("ink.width" -> "ink_width", "strokes*.radius" -> "strokes_radius"). */
static inline void ofx_names_look_knob(const char *knob, char *buf, size_t n)
{
    size_t j = 0;
    for (const char *s = knob; *s && j + 1 < n; s++) {
        char c = isalnum((unsigned char)*s) ? *s : '_';
        if (c == '_' && (j == 0 || buf[j - 1] == '_')) continue;
        buf[j++] = c;
    }
    while (j > 0 && buf[j - 1] == '_')
        j--;
    if (n) buf[j] = 0;
}

#endif
