/* The pthread pool behind nprfx_executor.
 *
 * One job runs at a time: the calling thread takes part as worker 0, pool threads are workers
 * 1..n-1, and items are handed out in chunks through an atomic counter. Which worker computes a
 * chunk varies between runs, so callers must write disjoint output per item (they do), and the
 * result is the same whatever the thread count. A parallel_for issued from inside a job runs
 * serially on its caller, which keeps nested use deadlock-free. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <unistd.h>

#include "nprfx/exec.h"

struct nprfx_pool {
    nprfx_executor exec;
    int nthreads; /* including the caller */
    pthread_t *threads;
    pthread_mutex_t job_lock; /* one job at a time */
    pthread_mutex_t lock;
    pthread_cond_t wake, done;
    /* current job */
    nprfx_range_fn fn;
    void *user;
    int count, chunk;
    atomic_int next;
    int active;          /* pool threads still working on the current job */
    unsigned long epoch; /* bumped per job so sleeping threads know there is new work */
    int quit;
};

static _Thread_local int in_pool_job; /* set while this thread runs a chunk of a job */

static void run_chunks(struct nprfx_pool *p, int worker)
{
    in_pool_job = 1;
    for (;;) {
        int begin = atomic_fetch_add(&p->next, p->chunk);
        if (begin >= p->count) break;
        int end = begin + p->chunk < p->count ? begin + p->chunk : p->count;
        p->fn(p->user, begin, end, worker);
    }
    in_pool_job = 0;
}

struct worker_arg {
    struct nprfx_pool *pool;
    int index;
};

static void *worker_main(void *arg)
{
    struct worker_arg *wa = arg;
    struct nprfx_pool *p = wa->pool;
    int index = wa->index;
    free(wa);
    unsigned long seen = 0;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        while (!p->quit && p->epoch == seen)
            pthread_cond_wait(&p->wake, &p->lock);
        if (p->quit) break;
        seen = p->epoch;
        pthread_mutex_unlock(&p->lock);
        run_chunks(p, index);
        pthread_mutex_lock(&p->lock);
        if (--p->active == 0) pthread_cond_signal(&p->done);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

static int pool_workers(void *impl)
{
    return ((struct nprfx_pool *)impl)->nthreads;
}

static void pool_for(void *impl, int count, int grain, nprfx_range_fn fn, void *user)
{
    struct nprfx_pool *p = impl;
    if (count <= 0) return;
    if (grain < 1) grain = 1;
    if (p->nthreads == 1 || in_pool_job || count <= grain) {
        fn(user, 0, count, 0);
        return;
    }
    pthread_mutex_lock(&p->job_lock);
    pthread_mutex_lock(&p->lock);
    p->fn = fn;
    p->user = user;
    p->count = count;
    p->chunk = grain;
    atomic_store(&p->next, 0);
    p->active = p->nthreads - 1;
    p->epoch++;
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);
    run_chunks(p, 0);
    pthread_mutex_lock(&p->lock);
    while (p->active > 0)
        pthread_cond_wait(&p->done, &p->lock);
    pthread_mutex_unlock(&p->lock);
    pthread_mutex_unlock(&p->job_lock);
}

nprfx_result nprfx_pool_create(int threads, nprfx_pool **out)
{
    if (!out) return NPRFX_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (threads <= 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        threads = n > 0 ? (int)n : 1;
    }
    if (threads > 256) threads = 256;
    struct nprfx_pool *p = calloc(1, sizeof *p);
    if (!p) return NPRFX_ERR_OUT_OF_MEMORY;
    p->exec.size = sizeof p->exec;
    p->exec.impl = p;
    p->exec.num_workers = pool_workers;
    p->exec.parallel_for = pool_for;
    p->nthreads = threads;
    pthread_mutex_init(&p->job_lock, NULL);
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->wake, NULL);
    pthread_cond_init(&p->done, NULL);
    p->threads = calloc((size_t)threads, sizeof *p->threads);
    if (!p->threads) {
        nprfx_pool_destroy(p);
        return NPRFX_ERR_OUT_OF_MEMORY;
    }
    for (int i = 1; i < threads; i++) {
        struct worker_arg *wa = malloc(sizeof *wa);
        if (!wa || (wa->pool = p, wa->index = i,
                    pthread_create(&p->threads[i], NULL, worker_main, wa) != 0)) {
            free(wa);
            p->nthreads = i; /* threads 1..i-1 exist */
            nprfx_pool_destroy(p);
            return NPRFX_ERR_OUT_OF_MEMORY;
        }
    }
    *out = p;
    return NPRFX_OK;
}

void nprfx_pool_destroy(nprfx_pool *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    p->quit = 1;
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);
    for (int i = 1; p->threads && i < p->nthreads; i++)
        pthread_join(p->threads[i], NULL);
    free(p->threads);
    pthread_cond_destroy(&p->wake);
    pthread_cond_destroy(&p->done);
    pthread_mutex_destroy(&p->lock);
    pthread_mutex_destroy(&p->job_lock);
    free(p);
}

const nprfx_executor *nprfx_pool_executor(nprfx_pool *pool)
{
    return pool ? &pool->exec : NULL;
}

void nprfx_parallel_for(const nprfx_executor *ex, int count, int grain, nprfx_range_fn fn,
                        void *user)
{
    if (count <= 0) return;
    if (!ex || !ex->parallel_for)
        fn(user, 0, count, 0);
    else
        ex->parallel_for(ex->impl, count, grain, fn, user);
}

int nprfx_executor_workers(const nprfx_executor *ex)
{
    return ex && ex->num_workers ? ex->num_workers(ex->impl) : 1;
}
