/* nprfx — the analytic scene generator: plates with exact AOVs for tests and demos.
 *
 * Scenes are ray-cast analytically (spheres, planes, tori/boxes), so depth, motion, positions
 * and ids are exact, and the motion fields are computed by projecting the same surface point at
 * the neighbouring frames: that is the ground truth the coherence metrics are measured against. */
#ifndef NPRFX_SYNTH_H
#define NPRFX_SYNTH_H

#include "nprfx/image.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Channels of every synthetic plate, in this order (nprfx_synth_channel_names):
 *   R G B A             beauty (scene-linear, A = coverage of objects, 1 on the backdrop plane)
 *   Z                   camera distance along the view axis; background: 1e10 (no object)
 *   motion_prev.X/Y     pixels from this frame's position to the same surface point at frame-1
 *   motion_next.X/Y     likewise to frame+1
 *   P.X/Y/Z             world position        Pref.X/Y/Z  object-space (rest) position
 *   N.X/Y/Z             world normal          UV.U/V      surface parameterisation
 *   id                  object index (0 = background, 1.. objects)
 *   diffuse             the light's diffuse term: max(0, N.L) in [0,1] under the sun, I cos / d^2
 *                       under a point light (nprfx_synth_render_lit)
 *   coverage            1 where an object covers the pixel centre, 0 on background */
NPRFX_API int nprfx_synth_channel_count(void);
NPRFX_API const char *const *nprfx_synth_channel_names(void);

typedef struct nprfx_synth_scene_info {
    const char *name; /* "orbit" */
    const char *help; /* one line */
} nprfx_synth_scene_info;
NPRFX_API int nprfx_synth_scene_count(void);
NPRFX_API const nprfx_synth_scene_info *nprfx_synth_scene_at(int i);

/* Render frame `frame` of scene `name` into out, which must be width x height with
 * nprfx_synth_channel_count() channels (bounds from (0,0)). Parallel over rows through the
 * context's executor; deterministic. */
NPRFX_API nprfx_result nprfx_synth_render(nprfx_context *ctx, const char *name, int frame,
                                          nprfx_image *out);

/* The same frame with only some channels: out's channel c is channel channels[c] of the whole
 * plate (indices in nprfx_synth_channel_names order), bit for bit as nprfx_synth_render makes
 * it; out must have `count` channels. Motion that is not picked is not computed. */
NPRFX_API nprfx_result nprfx_synth_render_channels(nprfx_context *ctx, const char *name, int frame,
                                                   const int *channels, int count,
                                                   nprfx_image *out);

/* As nprfx_synth_render_channels, under a named light: "sun" (NULL or "" too: the default),
 * "point" (HDR highlights) or "lowkey" (see nprfx_synth_light_name). Only beauty and the diffuse
 * channel change with the light. */
NPRFX_API nprfx_result nprfx_synth_render_lit(nprfx_context *ctx, const char *name,
                                              const char *light, int frame, const int *channels,
                                              int count, nprfx_image *out);
/* The lights, 0 .. count-1: name, and in *help (may be NULL) one line on it; NULL outside. */
NPRFX_API int nprfx_synth_light_count(void);
NPRFX_API const char *nprfx_synth_light_name(int i, const char **help);

#ifdef __cplusplus
}
#endif
#endif
