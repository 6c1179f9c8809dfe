/* nprfx — the matte node: object coverage (the cookbook's isBackground, antialiased) from
 * whatever a render has: an alpha, a depth whose background is far or infinite, an object id
 * whose background is a known value (docs/design.md §3.10). Styles put paper where it is 0. */
#ifndef NPRFX_MATTE_H
#define NPRFX_MATTE_H

#include "nprfx/context.h"
#include "nprfx/image.h"
#include "nprfx/node.h"
#include "nprfx/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The node's inputs, in the descriptor's order (args->inputs); each optional. */
enum {
    NPRFX_MATTE_IN_ALPHA = 0,
    NPRFX_MATTE_IN_DEPTH = 1,
    NPRFX_MATTE_IN_ID = 2,
    NPRFX_MATTE_IN_COUNT
};

/* The node's params (its descriptor binds each one here by offset). */
typedef struct nprfx_matte_params {
    double far;        /* depth >= far, not finite or <= 0: background */
    int background_id; /* an id equal to this (nprfx_id_to_uint): background; -1: none is */
    double soften;     /* Gaussian sigma in pixels over the hard depth/id matte (0: hard) */
    int invert;        /* output 1 - coverage (a background matte) */
} nprfx_matte_params;

/* Hard coverage of one pixel: alpha (clamped to [0, 1]; 1 when NULL) times [depth is an object]
 * times [id is an object], each factor only when its value is given (NULL: 1). */
NPRFX_API double nprfx_matte_pixel(const nprfx_matte_params *p, const float *alpha,
                                   const float *depth, const float *id);

/* Render args->window of the 1-channel matte args->output; at least one of the inputs alpha,
 * depth, id (NPRFX_MATTE_IN_*) must be connected. The
 * depth/id part is softened by a Gaussian of sigma p->soften (at most 2 px: the frame around the
 * window is read, so tiles agree with the whole frame); alpha, already antialiased, is not. */
NPRFX_API nprfx_result nprfx_matte_render(const nprfx_render_args *args,
                                          const nprfx_matte_params *p);

#ifdef __cplusplus
}
#endif
#endif
