/* The executor: every index exactly once for any thread count and grain, worker ids in range
 * and never shared by two running chunks, nested calls that do not deadlock, several callers
 * sharing one pool. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "check.h"
#include "nprfx/context.h"
#include "nprfx/exec.h"

#define MAX_COUNT 5000
#define MAX_WORKERS 64

typedef struct cover {
    atomic_int hits[MAX_COUNT];
    atomic_int busy[MAX_WORKERS]; /* 1 while a chunk runs on that worker id */
    atomic_int bad_worker;        /* out of range, or shared by two running chunks */
    atomic_int bad_range;
    int workers;
    int count;
    const nprfx_executor *ex; /* for nested calls; NULL: none */
    int nested_count;
    atomic_int nested_hits;
} cover;

static void count_fn(void *user, int begin, int end, int worker)
{
    cover *c = user;
    if (worker < 0 || worker >= c->workers || worker >= MAX_WORKERS) {
        atomic_fetch_add(&c->bad_worker, 1);
        return;
    }
    if (atomic_exchange(&c->busy[worker], 1) != 0) atomic_fetch_add(&c->bad_worker, 1);
    if (begin < 0 || end > c->count || begin >= end) atomic_fetch_add(&c->bad_range, 1);
    for (int i = begin; i < end && i < c->count; i++) {
        atomic_fetch_add(&c->hits[i], 1);
        /* burn a little time so chunks overlap across threads */
        volatile double x = 0;
        for (int k = 0; k < 50; k++)
            x += k;
    }
    atomic_store(&c->busy[worker], 0);
}

static void reset(cover *c, int count, int workers)
{
    for (int i = 0; i < MAX_COUNT; i++)
        atomic_store(&c->hits[i], 0);
    for (int i = 0; i < MAX_WORKERS; i++)
        atomic_store(&c->busy[i], 0);
    atomic_store(&c->bad_worker, 0);
    atomic_store(&c->bad_range, 0);
    atomic_store(&c->nested_hits, 0);
    c->count = count;
    c->workers = workers;
}

static int all_once(cover *c)
{
    for (int i = 0; i < c->count; i++)
        if (atomic_load(&c->hits[i]) != 1) return 0;
    return 1;
}

static void test_coverage(void)
{
    static cover c;
    const int threads[] = {1, 2, 3, 4, 8};
    const int grains[] = {1, 3, 7, 64, 1000, 0};
    const int counts[] = {0, 1, 5, 100, 1037, MAX_COUNT};
    for (int t = 0; t < 5; t++) {
        nprfx_pool *pool = NULL;
        CHECK_OK(nprfx_pool_create(threads[t], &pool));
        const nprfx_executor *ex = nprfx_pool_executor(pool);
        CHECK(nprfx_executor_workers(ex) == threads[t]);
        for (int g = 0; g < 6; g++)
            for (int n = 0; n < 6; n++) {
                reset(&c, counts[n], threads[t]);
                nprfx_parallel_for(ex, counts[n], grains[g], count_fn, &c);
                CHECK(all_once(&c));
                CHECK(atomic_load(&c.bad_worker) == 0);
                CHECK(atomic_load(&c.bad_range) == 0);
            }
        /* many small jobs in a row: wake-ups must not be lost */
        int ok = 1;
        for (int rep = 0; rep < 300; rep++) {
            reset(&c, 40, threads[t]);
            nprfx_parallel_for(ex, 40, 2, count_fn, &c);
            ok &= all_once(&c) && atomic_load(&c.bad_worker) == 0;
        }
        CHECK(ok);
        nprfx_pool_destroy(pool);
    }
    /* the serial fallbacks: a NULL executor and a context without one */
    reset(&c, 100, 1);
    nprfx_parallel_for(NULL, 100, 7, count_fn, &c);
    CHECK(all_once(&c));
    CHECK(nprfx_executor_workers(NULL) == 1);
    nprfx_context *ctx = NULL;
    CHECK_OK(nprfx_context_create(NULL, &ctx));
    const nprfx_executor *serial = nprfx_context_executor(ctx);
    CHECK(serial != NULL && nprfx_executor_workers(serial) == 1);
    reset(&c, 100, 1);
    nprfx_parallel_for(serial, 100, 7, count_fn, &c);
    CHECK(all_once(&c));
    nprfx_context_destroy(ctx);
    /* threads <= 0: one per online CPU, at least one */
    nprfx_pool *pool = NULL;
    CHECK_OK(nprfx_pool_create(0, &pool));
    CHECK(nprfx_executor_workers(nprfx_pool_executor(pool)) >= 1);
    nprfx_pool_destroy(pool);
    CHECK(nprfx_pool_create(2, NULL) == NPRFX_ERR_INVALID_ARGUMENT);
}

/* A chunk that issues its own parallel_for on the same executor. */
static void nested_inner(void *user, int begin, int end, int worker)
{
    cover *c = user;
    atomic_fetch_add(&c->nested_hits, end - begin);
}

static void nested_outer(void *user, int begin, int end, int worker)
{
    cover *c = user;
    count_fn(user, begin, end, worker);
    for (int i = begin; i < end; i++)
        nprfx_parallel_for(c->ex, c->nested_count, 3, nested_inner, c);
}

static void test_nested(void)
{
    static cover c;
    nprfx_pool *pool = NULL;
    CHECK_OK(nprfx_pool_create(4, &pool));
    c.ex = nprfx_pool_executor(pool);
    c.nested_count = 25;
    reset(&c, 200, 4);
    nprfx_parallel_for(c.ex, 200, 5, nested_outer, &c);
    CHECK(all_once(&c));
    CHECK(atomic_load(&c.nested_hits) == 200 * 25);
    CHECK(atomic_load(&c.bad_worker) == 0);
    nprfx_pool_destroy(pool);
}

/* Two application threads sharing one pool: jobs are serialised, none is lost. */
typedef struct caller_arg {
    const nprfx_executor *ex;
    cover *c;
    int ok;
} caller_arg;

static void *caller_main(void *arg)
{
    caller_arg *a = arg;
    a->ok = 1;
    for (int rep = 0; rep < 40; rep++) {
        /* each caller owns its cover, so it can check its own job's coverage */
        reset(a->c, 300, nprfx_executor_workers(a->ex));
        nprfx_parallel_for(a->ex, 300, 4, count_fn, a->c);
        a->ok &= all_once(a->c);
    }
    return NULL;
}

static void test_concurrent_callers(void)
{
    static cover c1, c2;
    nprfx_pool *pool = NULL;
    CHECK_OK(nprfx_pool_create(3, &pool));
    caller_arg a1 = {nprfx_pool_executor(pool), &c1, 0}, a2 = {nprfx_pool_executor(pool), &c2, 0};
    pthread_t t1, t2;
    CHECK(pthread_create(&t1, NULL, caller_main, &a1) == 0);
    CHECK(pthread_create(&t2, NULL, caller_main, &a2) == 0);
    pthread_join(t1, NULL);
    pthread_join(t2, NULL);
    CHECK(a1.ok && a2.ok);
    nprfx_pool_destroy(pool);
}

int main(void)
{
    test_coverage();
    test_nested();
    test_concurrent_callers();
    return check_finish();
}
