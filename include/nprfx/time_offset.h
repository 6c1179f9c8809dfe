/* nprfx — the time-offset node: an input as it is at another frame, out_i = image_{i + offset},
 * held at the shot's first and last frames (Nuke's TimeOffset; docs/design.md §3.8). */
#ifndef NPRFX_TIME_OFFSET_H
#define NPRFX_TIME_OFFSET_H

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The node's inputs, in the descriptor's order (args->inputs and args->fetch use them). */
enum { NPRFX_TIME_OFFSET_IN_IMAGE = 0, NPRFX_TIME_OFFSET_IN_COUNT };

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_time_offset_params {
    int offset; /* frames to shift by: -1 is the previous frame */
} nprfx_time_offset_params;

/* The frame shown at `time`: time + offset, clamped to [first_frame, last_frame] when
 * first_frame <= last_frame (so frame 1 of a "previous frame" graph does not ask for a frame 0
 * that was never rendered). */
NPRFX_API double nprfx_time_offset_frame(double time, int offset, int first_frame, int last_frame);

/* Render args->window of out = args->output at frame args->time of the shot
 * [args->first_frame, args->last_frame]. Offset 0 copies the input NPRFX_TIME_OFFSET_IN_IMAGE (at
 * args->time; the overlap of its data window and out's bounds). Otherwise the input at
 * nprfx_time_offset_frame(...) comes from args->fetch(args->fetch_user,
 * NPRFX_TIME_OFFSET_IN_IMAGE, frame, &view) (NULL: NPRFX_ERR_UNSUPPORTED) and must have out's
 * channels; the window reads 0 outside its data window, as EXR readers do. */
NPRFX_API nprfx_result nprfx_time_offset_render(const nprfx_render_args *args,
                                                const nprfx_time_offset_params *p);

#ifdef __cplusplus
}
#endif
#endif
