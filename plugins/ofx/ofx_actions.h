/* nprfx OpenFX adapter — the image effect actions that answer the host about a render before
 * it is made (ofx_actions.c). Each returns the action's status with its answer in out_args. */
#ifndef NPRFX_OFX_ACTIONS_H
#define NPRFX_OFX_ACTIONS_H

#include "ofx_api.h"
#include "ofx_instance.h"

/* getRegionOfDefinition: the effect's frame (ofx_frame_rod); the host's default without one. */
OfxStatus ofx_region_of_definition(ofx_instance *inst, OfxPropertySetHandle in_args,
                                   OfxPropertySetHandle out_args);
/* getRegionsOfInterest: inputs whole, the mask where the output is asked for. */
OfxStatus ofx_regions_of_interest(ofx_instance *inst, OfxPropertySetHandle in_args,
                                  OfxPropertySetHandle out_args);
/* getFramesNeeded: exactly the frames the node reads, per connected clip. */
OfxStatus ofx_frames_needed(ofx_instance *inst, OfxPropertySetHandle in_args,
                            OfxPropertySetHandle out_args);
/* getClipPreferences: float everywhere, the output's components and premultiplication from the
 * channels the node will output, frame varying. */
OfxStatus ofx_clip_preferences(ofx_instance *inst, OfxPropertySetHandle out_args);

#endif
