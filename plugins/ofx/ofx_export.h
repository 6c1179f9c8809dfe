/* nprfx OpenFX adapter — a node's text export written from a host (ofx_export.c). */
#ifndef NPRFX_OFX_EXPORT_H
#define NPRFX_OFX_EXPORT_H

#include "nprfx/nprfx.h"
#include "ofx_instance.h"

/* Write the node's text export of the frame a render made (render args with window = frame),
 * when its export param is set; once per frame and params (tiles do not repeat it). */
nprfx_result ofx_export(ofx_instance *inst, const nprfx_render_args *a);

#endif
