/* nprfx CLI — shared helpers. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "cli_util.h"

int nprfx_cli_threads(int requested)
{
    if (requested > 0) return requested;
    const char *env = getenv("NPRFX_THREADS");
    if (env && *env) {
        int n = atoi(env);
        if (n > 0) return n;
        fprintf(stderr, "nprfx: ignoring NPRFX_THREADS='%s' (not a positive number)\n", env);
    }
    return 0; /* all cores */
}

int nprfx_cli_env_init(nprfx_cli_env *env, int threads)
{
    memset(env, 0, sizeof *env);
    if (nprfx_pool_create(nprfx_cli_threads(threads), &env->pool)) {
        fprintf(stderr, "nprfx: cannot start worker threads\n");
        return 1;
    }
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.executor = nprfx_pool_executor(env->pool);
    if (nprfx_context_create(&init, &env->ctx)) {
        nprfx_pool_destroy(env->pool);
        fprintf(stderr, "nprfx: out of memory\n");
        return 1;
    }
    return 0;
}

void nprfx_cli_env_free(nprfx_cli_env *env)
{
    nprfx_context_destroy(env->ctx);
    nprfx_pool_destroy(env->pool);
    memset(env, 0, sizeof *env);
}

double nprfx_cli_peak_mib(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return (double)ru.ru_maxrss / 1024.0; /* Linux reports KiB */
}
