/* nprfx — threshold functions and X-toon threshold maps (style cookbook §3).
 *
 * A threshold turns a pattern value p (noise mapped to [0,1]) into a stroke value. Three forms:
 *
 *   erf      threshold(p, sigma, mu) = (erf(sigma * (p - mu)) + 1) / 2
 *            a sigmoid centred on mu; sigma sets its sharpness (the cookbook uses 25, 0.5).
 *   map      an X-toon map T(u, v) (Barla, Thollot, Markosian, NPAR 2006): a 2D image looked up
 *            bilinearly at u = pattern, v = tone (e.g. diffuse intensity).
 *   builtin  the erf threshold with its position following the tone:
 *            builtin(p, tone, sigma) = threshold(p, sigma, mu(tone, sigma)), where mu is the
 *            position that makes the mean over a uniform pattern equal the tone:
 *                integral over p in [0,1] of threshold(p, sigma, mu) dp = tone.
 *            Away from the ends (tone in [6 / sigma, 1 - 6 / sigma]) that is simply mu = 1 - tone
 *            (to double precision); near the ends mu moves outside [0,1] so that tone 0 gives 0
 *            and tone 1 gives 1 everywhere. So with pattern = uniform noise the picture keeps its
 * tone on average, dark tones getting more ink (output near 0), light tones more paper (1).
 *
 * Map orientation (X-toon, OpenGL texture convention): u runs left to right along the map's
 * columns, v bottom to top along its rows. u = 0 is the centre of the leftmost column, u = 1 of
 * the rightmost; v = 0 the centre of the bottom row, v = 1 of the top row (core images store
 * the top row first, y growing downward, so v = 0 is the row y = bounds.y1 - 1). Coordinates
 * outside [0,1] are clamped to the edge. */
#ifndef NPRFX_THRESHOLD_H
#define NPRFX_THRESHOLD_H

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The cookbook's threshold: (erf(sigma * (p - mu)) + 1) / 2. */
NPRFX_API double nprfx_threshold_erf(double p, double sigma, double mu);

/* Mean of nprfx_threshold_erf(p, sigma, mu) over p uniform in [0,1] (closed form). */
NPRFX_API double nprfx_threshold_erf_mean(double sigma, double mu);

/* The position mu for which nprfx_threshold_erf_mean(sigma, mu) == tone (tone clamped to [0,1];
 * sigma > 0). Exact to about 1e-12 in the mean; tones at or beyond 0 / 1 give a position far
 * enough outside [0,1] that the threshold is 0 / 1 in single precision. */
NPRFX_API double nprfx_threshold_builtin_mu(double tone, double sigma);

/* builtin(p, tone, sigma) = nprfx_threshold_erf(p, sigma, nprfx_threshold_builtin_mu(tone,
 * sigma)). */
NPRFX_API double nprfx_threshold_builtin(double p, double tone, double sigma);

/* Quantise a tone in [0,1] to `steps` levels 0, 1/(steps-1), ..., 1 (nearest level); steps < 2
 * returns the tone unchanged (clamped to [0,1]). */
NPRFX_API double nprfx_threshold_quantize(double tone, int steps);

/* Bilinear lookup of every channel of the map at (u, v) with the orientation above. out
 * receives map->channels floats. The map must be non-empty. */
NPRFX_API void nprfx_threshold_map_lookup(const nprfx_image *map, double u, double v, float *out);

/* ---- the threshold-map node over an image ---- */

typedef enum nprfx_threshold_mode {
    NPRFX_THRESHOLD_ERF = 0,
    NPRFX_THRESHOLD_MAP = 1,
    NPRFX_THRESHOLD_BUILTIN = 2,
    NPRFX_THRESHOLD_MODE_COUNT
} nprfx_threshold_mode;

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_threshold_params {
    int mode;         /* nprfx_threshold_mode */
    double sigma, mu; /* erf, builtin: sharpness (> 0) and position */
    double tone;      /* map, builtin: used when there is no tone image */
    double tone_gain; /* map, builtin: tone multiplier before the clamp to [0,1] */
    int steps;        /* map, builtin: >= 2 quantises the tone to that many levels */
    int invert;       /* output 1 - value */
} nprfx_threshold_params;

/* Channels of the output: the pattern's, or the map's when a map of more than one channel is
 * applied to a 1-channel pattern. NPRFX_ERR_MISSING_INPUT when map mode has no map (map_channels
 * 0), NPRFX_ERR_INVALID_ARGUMENT for a many-channel map on a many-channel pattern. */
NPRFX_API nprfx_result nprfx_threshold_output_channels(int mode, int pattern_channels,
                                                       int map_channels, int *channels);

/* Threshold `window` of the pattern into out (which has the channels above). tone and map may be
 * NULL (map mode needs a non-empty map). Inputs read as 0 outside their data windows. Runs on
 * ctx's executor; bit-identical for any thread count and window split. */
NPRFX_API nprfx_result nprfx_threshold_render(nprfx_context *ctx, const nprfx_threshold_params *p,
                                              const nprfx_image *pattern, const nprfx_image *tone,
                                              const nprfx_image *map, nprfx_rect window,
                                              nprfx_image *out);
/* nprfx_threshold_render with a per-instance cache in *state (NULL at first; free it with
 * nprfx_threshold_state_free): the builtin mode's step table is built once per sigma instead of
 * at every call. The same pixels either way. */
NPRFX_API nprfx_result nprfx_threshold_render_cached(nprfx_context *ctx,
                                                     const nprfx_threshold_params *p,
                                                     const nprfx_image *pattern,
                                                     const nprfx_image *tone,
                                                     const nprfx_image *map, nprfx_rect window,
                                                     nprfx_image *out, void **state);
NPRFX_API void nprfx_threshold_state_free(void *state);

/* The threshold-map node's inputs, in the descriptor's order (args->inputs). */
enum {
    NPRFX_THRESHOLD_MAP_IN_PATTERN = 0,
    NPRFX_THRESHOLD_MAP_IN_TONE = 1, /* optional */
    NPRFX_THRESHOLD_MAP_IN_MAP = 2,  /* optional; mode map needs it */
    NPRFX_THRESHOLD_MAP_IN_COUNT
};

/* The threshold-map node: nprfx_threshold_render_cached of args->window into args->output, with
 * args->state as the cache. */
NPRFX_API nprfx_result nprfx_threshold_map_render(const nprfx_render_args *args,
                                                  const nprfx_threshold_params *p);
/* The bytes that state holds (one table). */
NPRFX_API double nprfx_threshold_state_bytes(void);

#ifdef __cplusplus
}
#endif
#endif
