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
#include "look_desc.h"
#include "ofx_names.h"

/* One look: its graph file and what it makes of it (look_desc.h: clips, knobs, outputs). */
typedef struct ofx_look {
    char path[4096];
    look_desc d;
    /* The minor version: a 16-bit hash of the graph file's bytes, so that a host that keys its
     * cached frames or saved projects on the plug-in's version sees an edited look as another
     * version (the major stays 1). */
    unsigned version;
} ofx_look;

/* Whether the look reads nothing but its Source picture: offered in the Filter context. */
static inline int ofx_look_filter(const ofx_look *lk, int planar)
{
    int clips = 0;
    for (int k = 0; k < lk->d.desc.num_inputs; k++)
        clips += look_desc_has_clip(&lk->d, k, planar);
    return clips == 1;
}

/* Find the looks: every graph file in the folders of NPRFX_LOOK_PATH (':' between them), then
 * in the bundle's Contents/Resources/looks; a name seen first wins, so a studio's look of the
 * same name replaces the shipped one. Graph files that cannot be looks are reported on stderr
 * and left out. At most max; returns how many. */
int ofx_looks_discover(int max);
const ofx_look *ofx_look_at(int i);

/* The actions of look i's plug-in. */
OfxStatus ofx_look_main(int i, const char *action, const void *handle, OfxPropertySetHandle in_args,
                        OfxPropertySetHandle out_args);

/* ofx_look_layers.c: the layer menus of multi-plane hosts (look_desc_layer_aov says which). */
/* Reset the menu's options to "auto" and the channels of Source (names, n) that could feed the
 * AOV: each channel for a one-channel AOV, else each layer's first channels, comma-separated;
 * its value the option equal to resolved (0: none is). */
OfxStatus ofx_look_layer_options(OfxParamHandle h, int aov, const char *const *names, int n,
                                 const char *resolved);
/* The AOV Layers text with the AOV's line replaced by AOV = channels (NULL: removed); malloc'd. */
char *ofx_look_layer_edit(const char *text, int aov, const char *channels);

/* ofx_look_render.c: instances and the render. */
OfxStatus ofx_look_create(const ofx_look *look, OfxImageEffectHandle fx);
OfxStatus ofx_look_instance_action(const ofx_look *look, const char *action,
                                   OfxImageEffectHandle fx, OfxPropertySetHandle in_args,
                                   OfxPropertySetHandle out_args);

#endif
