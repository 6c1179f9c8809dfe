/* nprfx OpenFX adapter — the render action (ofx_render.c). */
#ifndef NPRFX_OFX_RENDER_H
#define NPRFX_OFX_RENDER_H

#include "ofx_api.h"
#include "ofx_instance.h"

/* Render the window, time and scale in_args name into the output clip's image; on an error the
 * host gets a message on the effect and a failed status. */
OfxStatus ofx_render(ofx_instance *inst, OfxPropertySetHandle in_args);

#endif
