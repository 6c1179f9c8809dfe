/* nprfx graph engine — checking and running a shot (nprfx_graph_check, nprfx_graph_run): the
 * frame loop every front end shares, with its progress and statistics reported to the caller. */
#include <stddef.h>
#include <string.h>

#include "engine_util.h"
#include "graph_aovs.h"
#include "graph_model.h"
#include "graph_read.h"
#include "graph_write_jobs.h"
#include "nprfx/exec.h"
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

/* A frame rendered whose writes may still run in the background. */
typedef struct pending {
    int index, frame, written;
    nprfx_result r;
    double rendered; /* when its compute was done */
} pending;

/* Report a rendered frame once its files are written: its time runs from the previous frame's
 * report (the run's start for the first), so the frames' times add up to the run's. Whether the
 * run stops there. */
static int report(nprfx_graph *g, const nprfx_graph_run_options *o, const pending *f, int count,
                  double t0, double *last, nprfx_graph_run_summary *sum, nprfx_result *first)
{
    int failed;
    double end;
    nprfx_result r = internal_graph_write_jobs_reap(g, f->frame, &failed, &end);
    if (f->r) r = f->r;
    int written = f->written - failed;
    if (end < f->rendered) end = f->rendered;
    if (r) {
        sum->failed++;
        if (!*first) *first = r;
    } else {
        sum->rendered++;
    }
    sum->files += written > 0 ? written : 0;
    nprfx_graph_progress p = {f->index + 1, count, f->frame, r, written, end - *last, end - t0};
    *last = end;
    if (o->progress && o->progress(o->user, &p)) return 1;
    return r && !o->keep_going;
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
    double t0 = engine_now(), last = t0;
    int count = frames ? frames->count : 0, stop = 0, have = 0;
    pending prev;
    /* Writes in the background pay where the compute's workers leave cores idle while a frame
     * is written; on two cores every phase already keeps both busy, and the run measured the
     * same wall time with 200 MB more held, so there a frame writes before the next. */
    g->background_writes = !o.serial && nprfx_executor_workers(nprfx_context_executor(g->ctx)) >= 4;
    g->wait_writes = internal_graph_write_jobs_wait;
    for (int k = 0; k < count && !stop; k++) {
        int written = 0;
        /* the next frame's plates decode while this one computes */
        g->has_next = !o.serial && k + 1 < count;
        g->next_frame = g->has_next ? frames->frames[k + 1] : 0;
        nprfx_result r = nprfx_graph_render_frame(g, frames->frames[k], &written);
        pending cur = {k, frames->frames[k], written, r, engine_now()};
        /* the frame before wrote its files while this one computed */
        if (have) stop = report(g, &o, &prev, count, t0, &last, &sum, &first);
        prev = cur;
        have = 1;
        if (r && !o.keep_going) break;
    }
    /* a frame rendered is reported even when the run stops before it */
    if (have) report(g, &o, &prev, count, t0, &last, &sum, &first);
    g->has_next = 0;
    g->background_writes = 0;
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
