/* The gabor-splat node's render: the params its descriptor binds (plugins/gabor_splat.c) hold
 * nprfx_gabor_render's, completed here, with the checks only this node can make. */
#include <string.h>

#include "nprfx/gabor.h"

nprfx_result nprfx_gabor_splat_render(const nprfx_render_args *args,
                                      const nprfx_gabor_splat_params *np)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    const nprfx_gabor_inputs in = {sizeof in,
                                   nprfx_render_input(args, NPRFX_GABOR_SPLAT_IN_ANCHOR),
                                   nprfx_render_input(args, NPRFX_GABOR_SPLAT_IN_DEPTH),
                                   nprfx_render_input(args, NPRFX_GABOR_SPLAT_IN_ID),
                                   nprfx_render_input(args, NPRFX_GABOR_SPLAT_IN_ORIENTATION),
                                   nprfx_render_input(args, NPRFX_GABOR_SPLAT_IN_FREQUENCY)};
    nprfx_image *out = args->output;
    if (!np || !in.anchor || !in.depth || !out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor-splat: params, anchor, depth or output missing");
    int space = np->anchor_space;
    if (space < 0 || space >= NPRFX_GABOR_SPACE_COUNT)
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "gabor-splat.anchor_space: no anchor space with index %d", space);
    int uv = space == NPRFX_GABOR_SPACE_UV;
    int dims = uv ? 2 : 3;
    int ach = in.anchor->channels;
    if (ach < dims || ach > dims + 1)
        return nprfx_error(
            ctx, NPRFX_ERR_INVALID_ARGUMENT,
            "gabor-splat: input 'anchor' has %d channels; this anchor_space needs %d "
            "(or %d with coverage), e.g. %s",
            ach, dims, dims + 1, uv ? "plate:UV.U,UV.V" : "plate:Pref");
    if (in.orientation && in.orientation->channels > 2)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "gabor-splat: input 'orientation' has %d channels; 1 (angle) or 2 "
                           "(direction) are supported",
                           in.orientation->channels);

    /* the bound algorithm params, completed with what the node derives */
    nprfx_gabor_params p = np->gabor;
    p.size = sizeof p;
    p.anchor_dims = dims;
    /* radius is scaled by the host (a PIXELS param); the frequency by the core's rule */
    p.frequency = nprfx_gabor_frequency_at_scale(np->gabor.frequency, args->render_scale);
    p.isotropic = p.isotropic != 0;
    p.seed = (uint64_t)np->seed;
    p.points = p.points != 0;

    /* args of the first release end before items */
    long long *kernels = args->size > NPRFX_RENDER_ARGS_SIZE_V1 ? args->items : NULL;
    nprfx_gabor_stats stats;
    nprfx_result r = nprfx_gabor_render(ctx, &p, &in, args->window, out, kernels ? &stats : NULL);
    if (r) return r; /* core's message names the node ("gabor: ...") */
    if (kernels) *kernels += stats.kernels;
    return NPRFX_OK;
}
