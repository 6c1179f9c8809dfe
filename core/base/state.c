/* The per-instance caches of nodes (core/base/internal_state.h). */
#include <pthread.h>
#include <stdlib.h>

#include "internal_state.h"

void *internal_state_get(void **slot, size_t size)
{
    void *c = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
    if (c) return c;
    pthread_mutex_t *mine = calloc(1, size < sizeof *mine ? sizeof *mine : size);
    if (!mine) return NULL;
    if (pthread_mutex_init(mine, NULL) != 0) {
        free(mine);
        return NULL;
    }
    void *expected = NULL;
    if (__atomic_compare_exchange_n(slot, &expected, (void *)mine, 0, __ATOMIC_ACQ_REL,
                                    __ATOMIC_ACQUIRE))
        return mine;
    pthread_mutex_destroy(mine);
    free(mine);
    return expected;
}

void internal_state_free(void *state)
{
    if (!state) return;
    pthread_mutex_destroy((pthread_mutex_t *)state);
    free(state);
}
