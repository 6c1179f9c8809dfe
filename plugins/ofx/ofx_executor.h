/* nprfx OpenFX adapter — the executor on the host's multithread suite (ofx_executor.c). */
#ifndef NPRFX_OFX_EXECUTOR_H
#define NPRFX_OFX_EXECUTOR_H

#include "nprfx/nprfx.h"

/* Given to every render context: workers are the host's CPUs (at most 256); a nested call, or a
 * host without the suite, runs on the calling thread. */
extern const nprfx_executor ofx_host_executor;

#endif
