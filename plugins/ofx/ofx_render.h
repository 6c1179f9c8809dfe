/* nprfx OpenFX adapter — the render action (ofx_render.c). */
#ifndef NPRFX_OFX_RENDER_H
#define NPRFX_OFX_RENDER_H

#include "ofx_api.h"
#include "ofx_instance.h"

/* Render the window, time and scale in_args name into the output clip's image; on an error the
 * host gets a message on the effect and a failed status. */
OfxStatus ofx_render(ofx_instance *inst, OfxPropertySetHandle in_args);

/* The Analyze Shot button (instance changed): render the node once at the shot's first frame,
 * fetching its inputs at every frame it measures, and store what its state measured in the
 * instance's analysis param, which the host saves with the project. Renders then seed the state
 * from it and read only their own frame (a frame whose fingerprint differs measures again). */
OfxStatus ofx_analyze(ofx_instance *inst);
/* Whether an instance-changed action's in_args are the Analyze Shot button being pressed. */
int ofx_is_analyze(const ofx_instance *inst, OfxPropertySetHandle in_args);

/* The analysis param's text, when the instance has one that is not empty (NULL otherwise): the
 * host's string, valid until the param changes. */
const char *ofx_analysis_text(const ofx_instance *inst);

#endif
