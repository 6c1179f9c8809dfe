/* nprfx OpenFX adapter — what an instance reads back from the host at a time (ofx_params.c):
 * param values, input channels, the effect's frame, the shot's frame range. */
#ifndef NPRFX_OFX_PARAMS_H
#define NPRFX_OFX_PARAMS_H

#include "nprfx/nprfx.h"
#include "ofx_api.h"
#include "ofx_instance.h"

/* Param values at `time` (or the current ones), checked as the runner checks them; STRING
 * values are copied into strings[i] (free each with free()). Errors name the param. */
nprfx_result ofx_eval_params(const ofx_instance *inst, nprfx_context *ctx, OfxTime time,
                             int current, nprfx_value *values, char **strings);

/* The channels input k reads at `time`: its selector's option, or the only option. */
void ofx_input_selection(const ofx_instance *inst, int k, OfxTime time, int current, int *first,
                         int *count);

/* The channel count each input gives at `time` (0 where its clip is not connected). */
void ofx_input_channels(const ofx_instance *inst, OfxTime time, int current, int *channels);

/* The effect's frame (whole image domain) in canonical coordinates at `time`: the region of
 * definition of the first connected input that is aligned with the frame (as the runner takes
 * the first connected input's bounds), else the project. */
OfxStatus ofx_frame_rod(const ofx_instance *inst, OfxTime time, OfxRectD *rod);

/* The shot's first and last frame: the output clip's frame range; last < first when unknown
 * (the host gives none, or no temporal clip access). */
void ofx_shot_range(const ofx_instance *inst, double *first, double *last);

#endif
