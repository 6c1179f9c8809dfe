/* nprfx graph engine — checking and running a shot (nprfx_graph_check, nprfx_graph_run): the
 * frame loop every front end shares, with its progress and statistics reported to the caller. */
#include <stddef.h>
#include <string.h>

#include "engine_util.h"
#include "graph_aovs.h"
#include "graph_model.h"
#include "graph_read.h"
#include "nprfx/graph.h"

nprfx_result nprfx_graph_check(nprfx_graph *g, const nprfx_frame_list *frames,
                               nprfx_graph_plan_info *plan)
{
    nprfx_graph_plan_info local;
    if (!plan) plan = &local;
    memset(plan, 0, sizeof *plan);
    if (!nprfx_graph_write_count(g))
        return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "the graph has no write node, so it would produce nothing");
    if (!frames || frames->count <= 0) return NPRFX_OK;
    nprfx_result r = internal_graph_prepare(g, frames->frames[0]);
    return r ? r : nprfx_graph_plan(g, frames->frames[0], plan);
}

nprfx_result nprfx_graph_run(nprfx_graph *g, const nprfx_frame_list *frames,
                             const nprfx_graph_run_options *opt, nprfx_graph_run_summary *summary)
{
    nprfx_graph_run_options o;
    memset(&o, 0, sizeof o);
    if (opt) memcpy(&o, opt, opt->size < sizeof o ? opt->size : sizeof o);
    nprfx_graph_run_summary sum;
    memset(&sum, 0, sizeof sum);
    nprfx_result first = NPRFX_OK;
    double t0 = engine_now();
    int count = frames ? frames->count : 0;
    for (int k = 0; k < count; k++) {
        double tf = engine_now();
        int written = 0;
        /* the next frame's plates decode while this one computes */
        g->has_next = k + 1 < count;
        g->next_frame = g->has_next ? frames->frames[k + 1] : 0;
        nprfx_result r = nprfx_graph_render_frame(g, frames->frames[k], &written);
        if (r) {
            sum.failed++;
            if (!first) first = r;
        } else {
            sum.rendered++;
            sum.files += written;
        }
        double now = engine_now();
        nprfx_graph_progress p = {k + 1, count, frames->frames[k], r, written, now - tf, now - t0};
        if (o.progress && o.progress(o.user, &p)) break;
        if (r && !o.keep_going) break;
    }
    g->has_next = 0;
    internal_graph_prefetch_stop(g);
    sum.seconds = engine_now() - t0;
    if (o.stats) {
        const nprfx_graph_node_stats *st;
        int n = nprfx_graph_stats(g, &st);
        o.stats(o.user, st, n);
    }
    if (summary) *summary = sum;
    return first;
}
