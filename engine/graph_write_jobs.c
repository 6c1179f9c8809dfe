/* nprfx graph engine — a write node's files at one frame, written now or in the background.
 *
 * A steady frame of a look was its compute, then its writes (zlib in the EXR and the PNG,
 * about half a second at 1080p), with the compute's workers idle through the writes. In a run
 * (nprfx_graph_run) the writes of a frame go to threads of their own and the next frame
 * computes meanwhile: the result written stays pinned in the cache (counted in the graph's
 * memory, so a frame that needs the room waits for the writes instead of failing), and the run
 * reports a frame once its files are written. The pixels written are the same either way. */
#include <stdlib.h>
#include <string.h>

#include "engine_util.h"
#include "graph_frames.h"
#include "graph_memory.h"
#include "graph_write_jobs.h"
#include "nprfx/exec.h"

static void write_item(write_job *j, int i, nprfx_context *ctx)
{
    nprfx_graph *g = j->g;
    const gnode *n = &g->nodes[j->node];
    if (i == 0) {
        j->r[0] = g->io.write(ctx, j->path, &j->view, j->names, j->has_display ? &j->display : NULL,
                              &j->wo);
    } else {
        nprfx_preview_options po = {sizeof po, g->ocio, n->colorspace, n->display, n->view, n->raw};
        j->r[1] = g->io.write_preview(ctx, j->ppath, &j->pv, &po);
    }
}

/* The job's memory back to the graph (graph thread): the pinned result, the selection's
 * frame, the preview's copy; and its time in node's --stats. */
static void release(nprfx_graph *g, write_job *j)
{
    internal_graph_frame_release(g, &j->scratch);
    free(j->pv.data);
    j->pv.data = NULL;
    free(j->sel_names);
    j->sel_names = NULL;
    internal_graph_unpin(g, j->e);
    g->stats[j->node].seconds += j->end - j->started;
    g->stats[j->node].calls++;
}

static void now_items(void *user, int begin, int end, int worker)
{
    (void)worker;
    write_job *j = user;
    for (int i = begin; i < end; i++)
        write_item(j, i, j->g->nodes[j->node].ctx);
}

static void *thread_item(write_job *j, int i)
{
    write_item(j, i, j->ctx[i]);
    return NULL;
}

static void *thread_exr(void *user)
{
    return thread_item(user, 0);
}

static void *thread_preview(void *user)
{
    return thread_item(user, 1);
}

static void join(write_job *j)
{
    for (int i = 0; i < j->threads; i++)
        pthread_join(j->thread[i], NULL);
    j->end = engine_now();
    j->joined = 1;
}

nprfx_result internal_graph_write_job_start(nprfx_graph *g, write_job *job)
{
    job->g = g;
    job->wo.types = job->wo.types ? job->types : NULL;
    int items = job->preview ? 2 : 1;
    if (!g->background_writes) {
        nprfx_parallel_for(nprfx_context_executor(g->ctx), items, 1, now_items, job);
        job->end = engine_now();
        nprfx_result r = job->r[0] ? job->r[0] : job->r[1];
        release(g, job);
        free(job);
        return r;
    }
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    for (int i = 0; i < items; i++) {
        int failed = nprfx_context_create(&ci, &job->ctx[i]) != NPRFX_OK;
        if (!failed) { /* the io may reach its front end's data through it */
            nprfx_context_set_front_end(job->ctx[i], nprfx_context_front_end(g->ctx));
            failed = pthread_create(&job->thread[i], NULL, i ? thread_preview : thread_exr, job);
        }
        if (failed) {
            int frame = job->frame;
            join(job);
            for (int k = 0; k < 2; k++)
                nprfx_context_destroy(job->ctx[k]);
            release(g, job);
            free(job);
            return nprfx_error(g->ctx, NPRFX_ERR_OUT_OF_MEMORY,
                               "cannot start a thread to write frame %d's files", frame);
        }
        job->threads++;
    }
    job->next = g->write_jobs;
    g->write_jobs = job;
    return NPRFX_OK;
}

int internal_graph_write_jobs_wait(nprfx_graph *g)
{
    int any = 0;
    for (write_job *j = g->write_jobs; j; j = j->next) {
        if (j->joined) continue;
        join(j);
        release(g, j);
        any = 1;
    }
    return any;
}

nprfx_result internal_graph_write_jobs_reap(nprfx_graph *g, int frame, int *failed, double *end)
{
    nprfx_result first = NPRFX_OK;
    *failed = 0;
    *end = 0;
    for (write_job **link = &g->write_jobs, *j; (j = *link);) {
        if (j->frame != frame) {
            link = &j->next;
            continue;
        }
        if (!j->joined) {
            join(j);
            release(g, j);
        }
        if (j->end > *end) *end = j->end;
        int bad = 0;
        for (int i = 0; i < 2; i++) {
            if (!j->r[i]) continue;
            char msg[2048];
            nprfx_context_last_error(j->ctx[i], msg, sizeof msg);
            /* raised on the node's context, as a write done at once raises it */
            nprfx_result r = nprfx_error(g->nodes[j->node].ctx, j->r[i], "%s", msg);
            if (!first) first = r;
            bad = 1;
        }
        *failed += bad;
        for (int i = 0; i < 2; i++)
            nprfx_context_destroy(j->ctx[i]);
        *link = j->next;
        free(j);
    }
    return first;
}
