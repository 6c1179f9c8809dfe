/* nprfx — a graph file as one OpenFX effect, a "look" (look_desc.c): the clips its plates come
 * through (Source, one per AOV its inputs read, one per map), its knobs as params under their
 * OpenFX names with the graph's values as defaults, its outputs. Derived from the graph alone,
 * once: the bundle's look plug-ins (plugins/ofx/ofx_look.c), the host projects that place one
 * (nprfx host-project --look) and the test host that drives one (tests/ofxhost/look.c) all take
 * it from here, so the three agree on every name. The inputs and params are those of a node
 * descriptor (nprfx_node_desc) for the front ends that handle nodes. */
#ifndef NPRFX_LOOK_DESC_H
#define NPRFX_LOOK_DESC_H

#include "nprfx/graph.h"
#include "nprfx/node.h"
#include "ofx_names.h"

#define LOOK_MAX_INPUTS 32
#define LOOK_MAX_KNOBS 48
#define LOOK_MAX_OUTPUTS 8

typedef struct look_desc {
    nprfx_node_desc desc; /* id: the plug-in identifier; inputs: the clips; params: the knobs */
    char id[NPRFX_OFX_NAME_MAX], label[NPRFX_OFX_NAME_MAX];
    /* per input (clip) */
    nprfx_input_desc in[LOOK_MAX_INPUTS];
    char clip[LOOK_MAX_INPUTS][64];
    int node[LOOK_MAX_INPUTS]; /* the read node's index in the graph */
    int aov[LOOK_MAX_INPUTS];  /* nprfx_aov; -1: a map's whole file */
    int main[LOOK_MAX_INPUTS]; /* of the look's first frame sequence: Source and its AOVs */
    int source;                /* Source's input index */
    /* per param (knob) */
    nprfx_param_desc params[LOOK_MAX_KNOBS];
    char param_name[LOOK_MAX_KNOBS][NPRFX_OFX_NAME_MAX];  /* ink_width */
    char param_label[LOOK_MAX_KNOBS][NPRFX_OFX_NAME_MAX]; /* ink width */
    char knob[LOOK_MAX_KNOBS][NPRFX_OFX_NAME_MAX]; /* ink.width: what nprfx_graph_set takes */
    char *knob_help[LOOK_MAX_KNOBS];               /* the graph's words on it, or NULL */
    nprfx_value values[LOOK_MAX_KNOBS];            /* the graph's values */
    char value_text[LOOK_MAX_KNOBS][256];          /* STRING values' text */
    /* the images it makes: the nodes its write nodes write, and the write nodes' names */
    char output[LOOK_MAX_OUTPUTS][128], output_label[LOOK_MAX_OUTPUTS][128];
    int noutputs;
    /* with several outputs, the last param is "output", a choice among the write nodes (its
     * knob[] is empty: no graph param), and this is its index; else -1 */
    int output_param;
    const char *output_choices[LOOK_MAX_OUTPUTS + 1];
    int temporal;        /* a node reads other frames or keeps state between them */
    int measures;        /* nodes that measure over the shot (tone's range) */
    double design_width; /* the graph's "design_width" (0: none) */
    char *comment;       /* the graph's "comment" (desc.help) */
} look_desc;

/* The look of graph g, whose file is named stem ("toon" from toon.json). A graph that cannot be
 * one (no frame sequence read, no write node, an input naming a renderer's own channels)
 * returns NPRFX_ERR_UNSUPPORTED with the reason in why. out owns copies of what it takes from g
 * (g may go), and points into itself: do not copy it. Free with look_desc_free. */
nprfx_result look_desc_build(nprfx_graph *g, const char *stem, look_desc *out, char *why, size_t n);
void look_desc_free(look_desc *l);
/* Take the knobs' values from g again (after nprfx_graph_set: what a user turned), leaving the
 * defaults at what the graph file says. g is the graph l was built from. */
void look_desc_values(look_desc *l, const nprfx_graph *g);

/* The params a look has in multi-plane hosts beside its knobs: whose names it finds the AOVs
 * under, the button that lists Source's layers, the text of the user's layer for an AOV, and a
 * menu per AOV read from Source (look_desc_layer_name). */
#define LOOK_PARAM_RENDERER "renderer"
#define LOOK_PARAM_FIND_LAYERS "findLayers"
#define LOOK_PARAM_AOV_LAYERS "aovLayers"
/* The AOV input k reads from Source with a layer menu of its own; -1 when none (motion follows
 * the renderer's convention, a map is its own clip). */
int look_desc_layer_aov(const look_desc *l, int k);
/* The layer menu's param name ("layer_depth") and label ("Depth layer"). */
void look_desc_layer_name(int aov, char *buf, size_t n);
void look_desc_layer_label(int aov, char *buf, size_t n);

/* Whether input k is a clip in a host of that kind: a multi-plane host carries the main read's
 * AOVs as layers of Source, so only Source and the maps are clips there. */
static inline int look_desc_has_clip(const look_desc *l, int k, int planar)
{
    return !planar || !l->main[k] || k == l->source;
}

#endif
