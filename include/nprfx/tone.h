/* nprfx — the tone node: a shading AOV mapped into the [0, 1] tone the threshold and the styles
 * expect (the cookbook's "diffuseIntensity": 0 darkest, 1 lightest), with a range measured once
 * over the whole shot or on a reference frame, never per frame, so it cannot flicker
 * (docs/design.md §3.9). */
#ifndef NPRFX_TONE_H
#define NPRFX_TONE_H

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where the range [lo, hi] that maps to [0, 1] comes from. */
typedef enum nprfx_tone_range {
    NPRFX_TONE_RANGE_SHOT = 0,   /* percentiles of every frame of the shot together */
    NPRFX_TONE_RANGE_FRAME = 1,  /* percentiles of one reference frame */
    NPRFX_TONE_RANGE_MANUAL = 2, /* lo = black, hi = white as given */
    NPRFX_TONE_RANGE_COUNT
} nprfx_tone_range;

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_tone_params {
    int range;                /* nprfx_tone_range */
    double low, high;         /* percentiles (0-100) of the covered pixels that map to 0 and 1 */
    int reference_frame;      /* RANGE_FRAME: the frame measured */
    double black, white;      /* RANGE_MANUAL: the values that map to 0 and 1 */
    double exposure;          /* stops, applied after the range: t * 2^exposure */
    double gamma;             /* t^(1/gamma) */
    int bands;                /* >= 2: the tone cut into this many flat levels (toon) */
    double band_softness;     /* width of the ramp between levels, in levels (0: a hard step) */
    double out_low, out_high; /* the output spans [out_low, out_high] */
    double background;        /* output where coverage is 0 */
    double solid_blacks;      /* tones t below it fade to 0 (solid ink); 0: off */
} nprfx_tone_params;

/* The scalar the node maps: one channel as it is, RGB(A) as Rec. 709 luminance
 * 0.2126 R + 0.7152 G + 0.0722 B, two channels: the first. */
NPRFX_API double nprfx_tone_value(const float *px, int channels);

/* Below this albedo luminance a surface counts as black (light 0). */
#define NPRFX_TONE_MIN_ALBEDO 1e-4

/* The light on a surface: its shading divided by its albedo (Blender's Combined / DiffCol is the
 * direct plus the ambient light), 0 where the albedo is black. */
NPRFX_API double nprfx_tone_light(double tone, double albedo);

/* The mapping of one value v with the range [lo, hi] (hi <= lo: a step at lo):
 *   t = clamp((v - lo) / (hi - lo) * 2^exposure, 0, 1)^(1 / gamma)
 *   with bands n >= 2: x = t n, k = floor(x), f = x - k, s = band_softness,
 *     t = min(k + clamp((f - 1 + s) / s, 0, 1), n - 1) / (n - 1)   (s = 0: the step f >= 1)
 *   out = out_low + (out_high - out_low) t,
 *   with solid_blacks b > 0 and t < b: out = out * t / b (0, solid ink, at t = 0),
 * and where coverage c < 1, out = c out + (1 - c) background. NaN v maps as lo. */
NPRFX_API double nprfx_tone_map(const nprfx_tone_params *p, double lo, double hi, double v,
                                double coverage);

/* The toon quantisation of t in [0, 1] into `bands` levels (see nprfx_tone_map). */
NPRFX_API double nprfx_tone_band(double t, int bands, double softness);

/* The q-th percentile (0-100) of n values, linear between order statistics; values is
 * reordered. n == 0 gives 0. */
NPRFX_API double nprfx_tone_percentile(float *values, size_t n, double q);

/* The samples a frame contributes to a measured range: the value (tone, or tone / albedo when an
 * albedo is given) at every s-th pixel in x and y of the tone's data window (s = the smallest
 * integer with (w / s)(h / s) <= 65536, so every frame weighs about the same whatever its size;
 * a long shot takes fewer per frame so that it holds at most 4M), where coverage (when given) is
 * at least 0.5 and the value is finite. *values is malloc'd (free it); *hash fingerprints them. */
NPRFX_API nprfx_result nprfx_tone_samples(nprfx_context *ctx, const nprfx_image *tone,
                                          const nprfx_image *albedo, const nprfx_image *coverage,
                                          float **values, size_t *n, unsigned long long *hash);

/* The frames every connected input is read at to render frame q->time with an empty cache:
 * the shot (range 'shot'), the reference frame ('frame') or none besides the frame itself
 * ('manual'). One range; the node's desc->frames_needed. */
NPRFX_API int nprfx_tone_frames(const nprfx_tone_params *p, const nprfx_frames_query *q,
                                nprfx_frame_range *ranges);

/* The node's inputs, in the descriptor's order (args->inputs and args->fetch use them). */
enum {
    NPRFX_TONE_IN_TONE = 0,
    NPRFX_TONE_IN_ALBEDO = 1,   /* optional */
    NPRFX_TONE_IN_COVERAGE = 2, /* optional */
    NPRFX_TONE_IN_COUNT
};

/* Render args->window of the tone node at frame args->time of the shot [args->first_frame,
 * args->last_frame]: measures [lo, hi] as p->range says (fetching the inputs NPRFX_TONE_IN_* at
 * other frames through args->fetch; without fetch only the current frame can be measured),
 * keeping what it measured in *args->state (freed by nprfx_tone_state_free; state NULL: nothing
 * kept) so that a shot is measured once, then maps every pixel. albedo and coverage need not be
 * connected. Output: one channel. */
NPRFX_API nprfx_result nprfx_tone_render(const nprfx_render_args *args, const nprfx_tone_params *p);

/* The range the last render used (for tests and logs); 0 when none was measured yet. */
NPRFX_API int nprfx_tone_state_range(const void *state, double *lo, double *hi);

NPRFX_API void nprfx_tone_state_free(void *state);

/* The measured range as text (tone_state.c documents the lines; *text NULL while nothing is
 * measured, or with range 'manual'), and a state seeded from it: the tone descriptor's
 * state_save and state_load. */
NPRFX_API nprfx_result nprfx_tone_state_save(nprfx_context *ctx, const void *state, char **text);
NPRFX_API nprfx_result nprfx_tone_state_load(nprfx_context *ctx, void **state, const char *text);

#ifdef __cplusplus
}
#endif
#endif
