/* The gabor-splat node's render: from the params its descriptor binds (plugins/gabor_splat.c) to
 * nprfx_gabor_render's, with the checks only this node can make. */
#include <string.h>

#include "nprfx/gabor.h"

nprfx_result nprfx_gabor_node_render(nprfx_context *ctx, const nprfx_gabor_node_params *np,
                                     const nprfx_gabor_inputs *in, double render_scale,
                                     nprfx_rect window, nprfx_image *out, long long *kernels)
{
    if (!np || !in || !in->anchor || !in->depth || !out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor-splat: params, anchor, depth or output missing");
    int space = np->anchor_space;
    if (space < 0 || space >= NPRFX_GABOR_SPACE_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "gabor-splat.anchor_space: no anchor space with index %d", space);
    int uv = space == NPRFX_GABOR_SPACE_UV;
    int dims = uv ? 2 : 3;
    int ach = in->anchor->channels;
    if (ach < dims || ach > dims + 1)
        return nprfx_error(
            ctx, NPRFX_ERR_INVALID_ARGUMENT,
            "gabor-splat: input 'anchor' has %d channels; this anchor_space needs %d "
            "(or %d with coverage), e.g. %s",
            ach, dims, dims + 1, uv ? "plate:UV.U,UV.V" : "plate:Pref");
    if (in->orientation && in->orientation->channels > 2)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor-splat: input 'orientation' has %d channels; 1 (angle) or 2 "
                           "(direction) are supported",
                           in->orientation->channels);

    nprfx_gabor_params p;
    nprfx_gabor_params_default(&p);
    p.anchor_dims = dims;
    /* radius is scaled by the host (a PIXELS param); the frequency by the core's rule */
    p.frequency = nprfx_gabor_frequency_at_scale(np->frequency, render_scale);
    p.orientation = np->orientation;
    p.isotropic = np->isotropic != 0;
    p.radius = np->radius;
    p.n0 = np->n0;
    p.amplitude = np->amplitude;
    p.seed = (uint64_t)np->seed;
    p.cell = np->cell;
    p.lod_levels = np->lod_levels;
    p.fade = np->fade;
    p.depth_test = np->depth_test;
    p.depth_tolerance = np->depth_tolerance;
    p.supersample = np->supersample;
    p.output = np->output;
    p.contrast = np->contrast;
    p.points = np->points != 0;

    nprfx_gabor_inputs gi = *in;
    gi.size = sizeof gi;
    nprfx_gabor_stats stats;
    nprfx_result r = nprfx_gabor_render(ctx, &p, &gi, window, out, kernels ? &stats : NULL);
    if (r) return r; /* core's message names the node ("gabor: ...") */
    if (kernels) *kernels += stats.kernels;
    return NPRFX_OK;
}
