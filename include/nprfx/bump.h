/* nprfx — bump shading: an image lit as if embossed by a height field, for the brush-fibre
 * relief of painterly styles (Hertzmann, "Fast Paint Texture", NPAR 2002) and the grain of
 * watercolour paper (docs/design.md §3.13).
 *
 * The normal comes from the height's gradient by central differences (reads clamped to the
 * frame), n = normalize(-s dh/dx, -s dh/dy, 1) with s = strength. The light l points from the
 * surface towards the light: azimuth a in the image plane, counter-clockwise as seen on screen
 * from +x (0: from the right, 90: from the top of the image; y grows downward, so its y
 * component is -cos(e) sin(a)), elevation e above the image plane:
 *     l = (cos e cos a, -cos e sin a, sin e).
 * The shade is normalised by the flat surface's, shade = max(0, n . l) / l_z, so a flat height
 * leaves the image exactly unchanged, and
 *     out = image * (1 + amount * (shade - 1)) + specular * max(0, (n . H)^shininess -
 * H_z^shininess) on the colour channels, with H = normalize(l + (0, 0, 1)) (Blinn's half vector for
 * a viewer straight above): the highlight is what a slope catches beyond what the flat surface
 * would. A 4-channel image keeps its alpha. */
#ifndef NPRFX_BUMP_H
#define NPRFX_BUMP_H

#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The node's inputs, in the descriptor's order (args->inputs). */
enum { NPRFX_BUMP_IN_IMAGE = 0, NPRFX_BUMP_IN_HEIGHT = 1, NPRFX_BUMP_IN_COUNT };

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_bump_params {
    double strength;  /* s, in pixels (the render scale applied), [0, 1e4] */
    double azimuth;   /* degrees, [-360, 360] */
    double elevation; /* degrees, [1, 90] */
    double amount;    /* mix between no shading (0) and the full shade (1), [0, 4] */
    double specular;  /* highlight added, [0, 4]; 0: none */
    double shininess; /* the highlight's exponent, [1, 1e4] */
} nprfx_bump_params;

/* Shade args->window of args->output (which has image's channels) by the gradient of input
 * NPRFX_BUMP_IN_HEIGHT (channel 0), the image NPRFX_BUMP_IN_IMAGE, over args->frame.
 * s multiplies a slope per pixel, so it is a length in pixels: scaled with the render scale, a
 * proxy shades like the full image. Height reads clamp to the frame and the height's data
 * window, the same for every tile; outside its data window the image reads as 0. Runs on ctx's
 * executor; bit-identical for any thread count and window split. */
NPRFX_API nprfx_result nprfx_bump_render(const nprfx_render_args *args, const nprfx_bump_params *p);

#ifdef __cplusplus
}
#endif
#endif
