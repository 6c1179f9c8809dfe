/* A graph's design width (docs/design.md §3.6, "Design width"): its pixel params were set for
 * plates that many pixels wide. On a plate W wide the runner multiplies every length in pixels by W
 * / design and every area by its square, so a quarter-size proxy draws what the full-size render
 * draws, a quarter the size. Motion vectors are left alone: a plate's vectors are in its own
 * pixels. */
#include "graph_scale.h"

#include <string.h>

double internal_graph_param_scale(const nprfx_graph *g, nprfx_rect display)
{
    int w = nprfx_rect_width(display);
    if (!(g->design_width > 0) || w <= 0) return 1.0;
    return w / g->design_width;
}

const nprfx_value *internal_graph_scale_params(const gnode *n, const nprfx_value *params,
                                               double scale, nprfx_value *copy)
{
    if (scale == 1.0 || n->kind != GK_NODE || !n->desc) return params;
    if (copy != params) memcpy(copy, params, sizeof *copy * (size_t)n->desc->num_params);
    nprfx_node_apply_render_scale(n->desc, copy, scale);
    return copy;
}

nprfx_result nprfx_graph_set_design_width(nprfx_graph *g, double width)
{
    if (!(width >= 0) || width > NPRFX_DESIGN_WIDTH_MAX)
        return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_RANGE,
                           "design width %g: give the plate width in pixels the graph's params "
                           "were set for (1 to %d), or 0 for the plate's own pixels",
                           width, NPRFX_DESIGN_WIDTH_MAX);
    g->design_width = width;
    g->plan_ready = 0;
    return NPRFX_OK;
}

double nprfx_graph_design_width(const nprfx_graph *g)
{
    return g->design_width;
}
