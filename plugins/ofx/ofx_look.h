/* nprfx OpenFX adapter — look plug-ins: each graph file of a looks folder is one effect that
 * evaluates the graph with the engine `nprfx run` uses, its plates served from the host's clips
 * (ofx_look.c: the table and describe; ofx_look_render.c: instances, the plates, render and the
 * questions before it). Clips, knobs and defaults are derived from the graph file: the AOVs its
 * inputs read become clips, its "knobs" become params with the graph's values as defaults. */
#ifndef NPRFX_OFX_LOOK_H
#define NPRFX_OFX_LOOK_H

#include "nprfx/graph.h"
#include "nprfx/nprfx.h"
#include "ofx_api.h"
#include "ofx_names.h"

/* Where a look's clips come from: one AOV of a read node, or a map's whole file (aov -1). */
typedef struct look_clip {
    char name[64];
    int node; /* the read node's index in the graph */
    int aov;  /* nprfx_aov, -1: the whole file */
    int main; /* of the look's first frame sequence (Source and its AOVs) */
} look_clip;

/* One knob: a param of one or more graph nodes ("ink.width", "strokes*.radius"). */
typedef struct look_knob {
    char *name;                     /* as the graph gives it: what nprfx_graph_set takes */
    char param[NPRFX_OFX_NAME_MAX]; /* the OFX param's name */
    char *label, *help;
    const nprfx_param_desc *p; /* the node param's descriptor (the registry's) */
    nprfx_value def;           /* the graph's value */
    char *def_string;
} look_knob;

#define LOOK_MAX_CLIPS 32

typedef struct ofx_look {
    char path[4096];
    char id[NPRFX_OFX_NAME_MAX], label[NPRFX_OFX_NAME_MAX];
    char *comment;
    look_clip clips[LOOK_MAX_CLIPS];
    int nclips;
    int source; /* the Source clip's index in clips */
    look_knob *knobs;
    int nknobs;
    char **outputs;       /* the nodes its write nodes write, evaluated by the plug-in */
    char **output_labels; /* the write nodes' names */
    int noutputs;
    int temporal; /* a node reads other frames, or keeps state between them */
    int measures; /* nodes that measure over the shot (tone's range) */
    double design_width;
    int filter; /* reads nothing but its Source picture: offered in the Filter context */
} ofx_look;

/* Find the looks: every graph file in the folders of NPRFX_LOOK_PATH (':' between them), then
 * in the bundle's Contents/Resources/looks; a name seen first wins, so a studio's look of the
 * same name replaces the shipped one. Graph files that cannot be looks are reported on stderr
 * and left out. At most max; returns how many. */
int ofx_looks_discover(int max);
const ofx_look *ofx_look_at(int i);

/* The actions of look i's plug-in. */
OfxStatus ofx_look_main(int i, const char *action, const void *handle, OfxPropertySetHandle in_args,
                        OfxPropertySetHandle out_args);

/* ofx_look_render.c: instances and the render. */
OfxStatus ofx_look_create(const ofx_look *look, OfxImageEffectHandle fx);
OfxStatus ofx_look_instance_action(const ofx_look *look, const char *action,
                                   OfxImageEffectHandle fx, OfxPropertySetHandle in_args,
                                   OfxPropertySetHandle out_args);

#endif
