/* nprfx — the watercolor node: Bousseau, Kaplan, Thollot, Sillion, "Interactive watercolor
 * rendering with temporal coherence and abstraction" (NPAR 2006); docs/design.md §3.14.
 *
 * Every effect is a change of pigment density d applied to the colour C through the paper's
 * model (the blend node's pigment mode, core/looks/blend.c):
 *
 *   pigment(C, d) = C - (C - C^2)(d - 1)        (d = 1: unchanged; d > 1 darker; d < 1 lighter)
 *
 * Per pixel p, in this order:
 *
 *   1. wobbling edges   W(p) = C(p + o(p)), bilinear, clamped to the frame, with
 *                       o = wobble * G / max(|G|, N, 1e-5),  G = grad(blur(P, wobble_scale))
 *                       (central differences of the paper P low-passed by a Gaussian), and N the
 *                       root mean square of |G| over a (2r+1)^2 box, r = ceil(wobble_scale): the
 *                       offset is wobble px where the paper slopes as much as it does around it,
 *                       and falls smoothly to 0 at its flat spots (no tearing). No paper: o = 0.
 *                       With coverage K (also sampled at p + o), Q = K W + (1 - K) * 1: the
 *                       background is white paper, so silhouettes wobble and get dark edges too.
 *   2. edge darkening   B = Q blurred by a Gaussian of sigma = edge_width (sampled taps
 *                       w_k ~ exp(-k^2 / (2 sigma^2)), |k| <= ceil(3 sigma); 0: B = Q);
 *                       g = sqrt(sum_c |grad B_c|^2 / n) / (w_0 + w_1), grad by central
 *                       differences, n colour channels, so that a step of height h gives g = h/2
 *                       next to it whatever edge_width is (at edge_width 0, g = |grad Q|);
 *                       d = min(1 + edge_darkening * g, 2)  (2: C' = C^2, never below 0).
 *   3. turbulence       d = 1 + turbulence  * (T - 0.5)   (T: low-frequency coherent noise)
 *      dispersion       d = 1 + dispersion  * (D - 0.5)   (D: high-frequency coherent noise)
 *      paper            d = 1 + granulation * (P - 0.5)   (P: paper height, unwobbled)
 *
 * each applied in sequence: out = pigment(pigment(pigment(pigment(Q, d_edge), d_T), d_D), d_P).
 * A stage whose density is exactly 1 (amount 0, input not connected) is skipped, so with nothing
 * connected and edge_darkening = 0 the output is the input bit for bit. */
#ifndef NPRFX_WATERCOLOR_H
#define NPRFX_WATERCOLOR_H

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The node's params (its descriptor binds each one here by offset). Lengths are in pixels at the
 * render's scale. */
typedef struct nprfx_watercolor_params {
    double turbulence;     /* density amount of the turbulence texture T */
    double dispersion;     /* density amount of the dispersion texture D */
    double granulation;    /* density amount of the paper height P */
    double edge_darkening; /* density added per unit of colour gradient g, >= 0 */
    double edge_width;     /* sigma of the blur before the gradient, px, >= 0 */
    double wobble;         /* edge displacement, px, >= 0 */
    double wobble_scale;   /* sigma of the paper's low-pass for the wobble, px, >= 0 */
} nprfx_watercolor_params;

/* The node's inputs, in the descriptor's order (args->inputs); data NULL where not connected.
 * image is required (1 to 4 channels; with 4 the 4th is alpha and passes through untouched); the
 * others are read from channel 0 and must have 1 channel. */
enum {
    NPRFX_WATERCOLOR_IN_IMAGE = 0,
    NPRFX_WATERCOLOR_IN_TURBULENCE = 1, /* T in [0, 1] */
    NPRFX_WATERCOLOR_IN_DISPERSION = 2, /* D in [0, 1] */
    NPRFX_WATERCOLOR_IN_PAPER = 3,      /* P in [0, 1], screen space */
    NPRFX_WATERCOLOR_IN_COVERAGE = 4,   /* K in [0, 1], clamped */
    NPRFX_WATERCOLOR_IN_COUNT
};

/* Paint args->window of args->output (image's channel count). args->frame is the whole image
 * domain: every input is
 * read clamped to it and to its own data window (edges repeat), so every tile sees the same
 * neighbourhoods; an optional input with an empty data window counts as not connected. Runs on
 * ctx's executor; bit-identical for any thread count and window split. Errors name the input or
 * param. */
NPRFX_API nprfx_result nprfx_watercolor_render(const nprfx_render_args *args,
                                               const nprfx_watercolor_params *p);

#ifdef __cplusplus
}
#endif
#endif
