/* nprfx — procedural paper and canvas: the background a stylised image is laid on (the style
 * cookbook's last step, docs/design.md §3.12).
 *
 * Real paper does not move with the scene, so the texture is fixed in screen space: a function of
 * the pixel position and the params only, the same at every frame. It is built from periodic
 * lattice noise, so with a tile of T pixels out(x + T, y) = out(x, y + T) = out(x, y) exactly,
 * and a paper rendered at one size can be repeated over a larger one without a seam.
 *
 * The height h(x, y) lies in [0, 1] with a mean of about 0.5 (1: the tops of the grain). The
 * colour output is
 *     color * (1 - shade * (1 - h)) * max(0, n . l) / l_z
 * on R, G and B, color's alpha on A. The first factor makes the param colour that of the highest
 * points, the valleys (where less light reaches) darker by up to `shade`. The second is the bump
 * node's shade (nprfx/bump.h) under a fixed light from the upper left (azimuth 135 degrees,
 * elevation 45), n = normalize(-s dh/dx, -s dh/dy, 1) with s = relief: the relief lit as paper
 * on a desk is; it is 1 where the paper is flat and is left out when relief is 0. */
#ifndef NPRFX_PAPER_H
#define NPRFX_PAPER_H

#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The surfaces, in the order of the node's `kind` choice. */
typedef enum nprfx_paper_kind {
    /* Drawing paper: fine multi-octave grain, a faint cloudy formation, and a few thin fibres
     * (short straight or curved strokes of any orientation, lighter or darker). */
    NPRFX_PAPER_DRAWING = 0,
    /* Cold-press watercolour paper: rounded bumps (a cellular pattern) of 6 x and 3 x scale,
     * roughened with coarse multi-octave noise. */
    NPRFX_PAPER_WATERCOLOR = 1,
    /* Canvas: a plain weave of horizontal and vertical threads of period `thread`, each going
     * over and under the crossing ones in turn, with wobbling threads of varying thickness and a
     * grain along each thread. */
    NPRFX_PAPER_CANVAS = 2,
    NPRFX_PAPER_KIND_COUNT
} nprfx_paper_kind;

/* What the node outputs, in the order of its `output` choice. */
typedef enum nprfx_paper_output {
    NPRFX_PAPER_COLOR = 0,  /* RGBA: the colour above, alpha = color's */
    NPRFX_PAPER_HEIGHT = 1, /* 1 channel: h in [0, 1], mean about 0.5 */
    NPRFX_PAPER_OUTPUT_COUNT
} nprfx_paper_output;

/* The node's params (its descriptor binds each one here by offset). Lengths are in pixels of
 * the image rendered (a host's render scale already applied). */
typedef struct nprfx_paper_params {
    int kind;        /* nprfx_paper_kind */
    double scale;    /* grain size in pixels, (0, 1024] */
    double grain;    /* amount of grain (noise, bumps) in [0, 4] */
    double fibres;   /* amount of fibres (drawing paper) in [0, 4] */
    double weave;    /* amount of the weave's relief (canvas) in [0, 4] */
    double thread;   /* canvas thread period in pixels, [1, 4096] */
    double color[4]; /* RGBA of the highest points (scene-linear) */
    double shade;    /* how much the valleys darken the colour, [0, 1] */
    double relief;   /* s of the colour's built-in light, in pixels, [0, 1e4]; 0: none */
    double tile;     /* period in pixels (rounded to an integer); 0: not periodic */
    int seed;        /* which paper: any seed gives another sheet of the same kind */
    int output;      /* nprfx_paper_output */
} nprfx_paper_params;

/* The channel count of the output for these params: 4 for color, 1 for height. */
NPRFX_API int nprfx_paper_output_channels(const nprfx_paper_params *p);

/* Write `window` of out (nprfx_paper_output_channels channels) with the texture at absolute
 * pixel positions: the result depends on neither the frame nor the time, only on (x, y) and the
 * params. Periods that must fit the tile (the noise lattices, the canvas threads, two per
 * over-under repeat) are rounded to a whole number per tile, so scale and thread may change
 * slightly when tile is set. Runs on ctx's executor; bit-identical for any thread count and
 * window split. */
NPRFX_API nprfx_result nprfx_paper_texture(nprfx_context *ctx, const nprfx_paper_params *p,
                                           nprfx_rect window, nprfx_image *out);

/* nprfx_paper_texture through a per-instance cache in *state (the node's render args' state slot;
 * NULL: no cache): the last window rendered is kept, and a window inside it with the same params
 * is copied from it, the same pixels. Free the state with nprfx_paper_state_free. */
NPRFX_API nprfx_result nprfx_paper_render_cached(nprfx_context *ctx, const nprfx_paper_params *p,
                                                 nprfx_rect window, nprfx_image *out, void **state);
NPRFX_API void nprfx_paper_state_free(void *state);

/* The node's inputs, in the descriptor's order (args->inputs): the image only gives the frame's
 * size, no pixel of it is read. */
enum { NPRFX_PAPER_IN_IMAGE = 0, NPRFX_PAPER_IN_COUNT };

/* Render args->window of args->output: nprfx_paper_render_cached with args->state. */
NPRFX_API nprfx_result nprfx_paper_render(const nprfx_render_args *args,
                                          const nprfx_paper_params *p);
/* The most bytes that state holds for frames of width x height: one window of the output. */
NPRFX_API double nprfx_paper_state_bytes(const nprfx_paper_params *p, int width, int height);

#ifdef __cplusplus
}
#endif
#endif
