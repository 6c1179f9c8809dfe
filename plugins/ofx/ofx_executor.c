/* nprfx OpenFX adapter — the executor the nodes split their work with, on the host's
 * multithread suite (declared in ofx_executor.h). */
#include <stdatomic.h>

#include "ofx_executor.h"
#include "ofx_suites.h"

typedef struct mt_job {
    nprfx_range_fn fn;
    void *user;
    int count, grain;
    atomic_int next;
} mt_job;

static void mt_run(mt_job *j, int worker)
{
    for (;;) {
        int begin = atomic_fetch_add(&j->next, j->grain);
        if (begin >= j->count) break;
        int end = begin + j->grain < j->count ? begin + j->grain : j->count;
        j->fn(j->user, begin, end, worker);
    }
}

static void mt_thread(unsigned int index, unsigned int max, void *arg)
{
    (void)max;
    mt_job *j = arg;
    mt_run(j, (int)index);
}

static int mt_workers(void *impl)
{
    (void)impl;
    unsigned int n = 1;
    if (!ofx_g.mt || ofx_g.mt->multiThreadNumCPUs(&n) != kOfxStatOK || n < 1) return 1;
    return n > 256 ? 256 : (int)n;
}

/* Threads pull chunks from one counter, so which thread computes a chunk never matters (the
 * nodes write disjoint output per item). The suite cannot be entered recursively: a nested call,
 * or a host without the suite, runs on the calling thread under that thread's own index, which
 * keeps worker indices unique among concurrent calls. If the host fails to launch threads, the
 * calling thread finishes whatever is left. */
static void mt_for(void *impl, int count, int grain, nprfx_range_fn fn, void *user)
{
    if (count <= 0) return;
    if (grain < 1) grain = 1;
    mt_job j;
    j.fn = fn;
    j.user = user;
    j.count = count;
    j.grain = grain;
    atomic_init(&j.next, 0);
    int chunks = (count - 1) / grain + 1;
    int n = mt_workers(impl);
    if (n > chunks) n = chunks;
    int worker = 0;
    if (ofx_g.mt && ofx_g.mt->multiThreadIsSpawnedThread()) {
        unsigned int index = 0;
        if (ofx_g.mt->multiThreadIndex(&index) == kOfxStatOK) worker = (int)index;
    } else if (ofx_g.mt && n > 1) {
        (void)ofx_g.mt->multiThread(mt_thread, (unsigned int)n, &j);
    }
    mt_run(&j, worker);
}

const nprfx_executor ofx_host_executor = {sizeof(nprfx_executor), NULL, mt_workers, mt_for};
