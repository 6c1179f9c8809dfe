/* nprfx graph engine — a write node's files at one frame as a job: written at once on the
 * graph's executor, or in the background on threads of their own while the next frame computes
 * (nprfx_graph_run). */
#ifndef NPRFX_GRAPH_WRITE_JOBS_H
#define NPRFX_GRAPH_WRITE_JOBS_H

#include <pthread.h>

#include "graph_cache.h"
#include "graph_model.h"
#include "nprfx/io.h"

typedef struct write_job {
    int node, frame;
    centry *e;           /* the result written: pinned until its files are */
    nprfx_image view;    /* e's pixels, or the selected channels' copy in scratch */
    nprfx_image scratch; /* a pool frame (a selection's copy), released when written */
    char **sel_names;    /* the selection's channel names (owned; NULL: e's names) */
    const char *const *names;
    char path[4096], ppath[4096];
    int preview;
    nprfx_image pv; /* the preview's channels (owned) */
    nprfx_write_options wo;
    unsigned char types[256];
    nprfx_rect display;
    int has_display;
    double started; /* when the job was handed out */
    /* the files: item 0 the EXR, item 1 the preview */
    nprfx_graph *g;
    nprfx_context *ctx[2]; /* the background's own contexts (errors raised when reaped) */
    pthread_t thread[2];
    int threads, joined;
    nprfx_result r[2];
    double end; /* when its last file was written */
    struct write_job *next;
} write_job;

/* Write the job's files. Without g->background_writes: now, side by side on the executor; the
 * job is released and the result is the files'. With it: on threads of their own; the job joins
 * the graph's list and NPRFX_OK (or the reason no thread started, the job released). */
nprfx_result internal_graph_write_job_start(nprfx_graph *g, write_job *job);

/* Wait for every write in the background (a frame needs their memory; the run ends): their
 * results stay for internal_graph_write_jobs_reap. Whether there were any. */
int internal_graph_write_jobs_wait(nprfx_graph *g);

/* Frame's writes in the background, waited for and released: the first failure's code (its
 * message raised on its node's context), how many failed, and when the last was done (0: there
 * were none). */
nprfx_result internal_graph_write_jobs_reap(nprfx_graph *g, int frame, int *failed, double *end);

#endif
