/* Internal: the anchored-point scatter (docs/design.md §3.2), never installed. It is the first
 * phase of gabor-splat's render, shared with pam-splat (§3.7): points anchored on the surfaces
 * through an anchor AOV, at a constant screen density with the continuous level of detail, each
 * emitted once by the pixel that owns it, with the depth and id its splat is tested against.
 *
 * Its configuration is gabor's (gconf, set from an nprfx_gabor_params) and its points are gabor's
 * (gpoint): the Gabor kernel's start values come with every point, a node that splats something
 * else ignores them. Keeping one struct keeps gabor-splat's pixels exactly what they were. */
#ifndef NPRFX_INTERNAL_SCATTER_H
#define NPRFX_INTERNAL_SCATTER_H

#include "internal_gabor.h"
#include "nprfx/context.h"

#if GABOR_X86
static inline int internal_scatter_cpu_avx512(void)
{
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
           __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq");
}

static inline int internal_scatter_cpu_avx2(void)
{
    return __builtin_cpu_supports("avx2");
}
#endif

/* a / b rounded towards minus infinity (b > 0): the block of a pixel */
static inline int internal_scatter_floor_div(int a, int b)
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/* The configuration for params p (already checked: nprfx_gabor_render's rules) and inputs in:
 * sources, density, level-of-detail tables, kernel constants and the emission path. */
void internal_scatter_conf_init(gconf *G, const nprfx_gabor_params *p,
                                const nprfx_gabor_inputs *in);

/* Set up J for a render of `window` (not empty) whose splats reach `reach` pixels from their
 * owner: the grid of emission blocks covering the window grown by reach. Allocates nothing. */
void internal_scatter_job_init(gjob *J, const gconf *G, nprfx_rect window, int reach,
                               nprfx_image *out);

/* Emission: fills J->blocks (the points of every block, in emission order), J->zwin and
 * J->idwin (the window's depth and id as the visibility tests read them) and leaves J->scratch
 * an array of J->nworkers NULL slots for the caller's own per-worker buffers. Errors (out of
 * memory) go to ctx prefixed by `who` ("gabor"). */
nprfx_result internal_scatter_emit(nprfx_context *ctx, gjob *J, const char *who);

/* Free what internal_scatter_emit allocated (the scratch array, not what its slots point to). */
void internal_scatter_job_free(gjob *J);

#endif
