/* nprfx OpenFX test host — the remaining suites and the host's fetchSuite: multithreading on the
 * runner's executor (so --threads N reaches the plug-ins) and memory; fetchSuite hands out every
 * suite, version 1, and the message suite's version 2 where the profile has it (messages.c), to
 * the host's own property set only. */
#define _POSIX_C_SOURCE 200809L /* posix_memalign */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ofx_host_internal.h"

/* ---- multithread suite: the runner's executor ------------------------------------------------ */

static _Thread_local int mt_spawned;
static _Thread_local unsigned int mt_index;

typedef struct mt_call {
    OfxThreadFunctionV1 *fn;
    unsigned int n;
    void *arg;
} mt_call;

/* One executor item per OFX thread. The pool may run fewer items at once than asked, which is
 * allowed: the spec only promises that all nThreads calls have returned when multiThread does. */
static void mt_items(void *user, int begin, int end, int worker)
{
    (void)worker;
    const mt_call *c = user;
    for (int i = begin; i < end; i++) {
        mt_spawned = 1;
        mt_index = (unsigned int)i;
        c->fn((unsigned int)i, c->n, c->arg);
        mt_spawned = 0;
        mt_index = 0;
    }
}

static OfxStatus mt_multi_thread(OfxThreadFunctionV1 fn, unsigned int n, void *arg)
{
    if (!fn) return kOfxStatFailed;
    if (mt_spawned) return kOfxStatErrExists; /* the suite is not re-entrant */
    if (n == 0) return kOfxStatOK;
    mt_call c = {fn, n, arg};
    nprfx_parallel_for(internal_g_host ? internal_g_host->exec : NULL, (int)n, 1, mt_items, &c);
    return kOfxStatOK;
}

static OfxStatus mt_num_cpus(unsigned int *n)
{
    if (!n) return kOfxStatFailed;
    *n = (unsigned int)nprfx_executor_workers(internal_g_host ? internal_g_host->exec : NULL);
    return kOfxStatOK;
}

static OfxStatus mt_thread_index(unsigned int *index)
{
    if (!index) return kOfxStatFailed;
    *index = mt_spawned ? mt_index : 0;
    return kOfxStatOK;
}

static int mt_is_spawned(void)
{
    return mt_spawned;
}

static OfxStatus mt_mutex_create(OfxMutexHandle *out, int lock_count)
{
    pthread_mutex_t *m = malloc(sizeof *m);
    pthread_mutexattr_t at;
    if (!m || !out) {
        free(m);
        return kOfxStatErrMemory;
    }
    pthread_mutexattr_init(&at);
    pthread_mutexattr_settype(&at, PTHREAD_MUTEX_RECURSIVE);
    pthread_mutex_init(m, &at);
    pthread_mutexattr_destroy(&at);
    for (int i = 0; i < lock_count; i++)
        pthread_mutex_lock(m);
    *out = (OfxMutexHandle)m;
    return kOfxStatOK;
}
static OfxStatus mt_mutex_destroy(const OfxMutexHandle h)
{
    if (!h) return kOfxStatErrBadHandle;
    pthread_mutex_destroy((pthread_mutex_t *)h);
    free(h);
    return kOfxStatOK;
}
static OfxStatus mt_mutex_lock(const OfxMutexHandle h)
{
    return h && !pthread_mutex_lock((pthread_mutex_t *)h) ? kOfxStatOK : kOfxStatErrBadHandle;
}
static OfxStatus mt_mutex_unlock(const OfxMutexHandle h)
{
    return h && !pthread_mutex_unlock((pthread_mutex_t *)h) ? kOfxStatOK : kOfxStatErrBadHandle;
}
static OfxStatus mt_mutex_try_lock(const OfxMutexHandle h)
{
    if (!h) return kOfxStatErrBadHandle;
    return pthread_mutex_trylock((pthread_mutex_t *)h) ? kOfxStatFailed : kOfxStatOK;
}

static const OfxMultiThreadSuiteV1 multithread_suite = {
    mt_multi_thread,  mt_num_cpus,   mt_thread_index, mt_is_spawned,    mt_mutex_create,
    mt_mutex_destroy, mt_mutex_lock, mt_mutex_unlock, mt_mutex_try_lock};

/* ---- memory suite ---------------------------------------------------------------------------- */

static OfxStatus mem_alloc(void *handle, size_t n, void **out)
{
    (void)handle;
    if (!out) return kOfxStatErrBadHandle;
    *out = NULL;
    return posix_memalign(out, 16, n ? n : 1) ? kOfxStatErrMemory : kOfxStatOK;
}
static OfxStatus mem_free(void *p)
{
    free(p);
    return kOfxStatOK;
}
static const OfxMemorySuiteV1 memory_suite = {mem_alloc, mem_free};

const void *internal_fetch_suite(OfxPropertySetHandle host, const char *name, int version)
{
    if (!internal_g_host || internal_props_of(host) != &internal_g_host->props || !name)
        return NULL;
    if (!strcmp(name, kOfxMessageSuite))
        return internal_message_suite(internal_g_host->profile, version);
    if (version != 1) return NULL;
    if (!strcmp(name, kOfxPropertySuite)) return &internal_property_suite;
    if (!strcmp(name, kOfxImageEffectSuite)) return &internal_image_effect_suite;
    if (!strcmp(name, kOfxParameterSuite)) return &internal_parameter_suite;
    if (!strcmp(name, kOfxMultiThreadSuite)) return &multithread_suite;
    if (!strcmp(name, kOfxMemorySuite)) return &memory_suite;
    if (!strcmp(name, kFnOfxImageEffectPlaneSuite) && internal_g_host->profile->planes)
        return &internal_plane_suite;
    return NULL;
}
