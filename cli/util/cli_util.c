/* nprfx CLI — the runner's lowest layer: the context commands run with and peak memory (the
 * clocks, strdup and the parallel copy are the engine's: engine/engine_util.h). Includes nothing of
 * the runner's other folders. */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli_util.h"
#include "flow_opencv.h"

/* Threads from --threads (when > 0), else $NPRFX_THREADS, else all cores. */
static int cli_threads(int requested)
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

/* The data directory (the stipple node's ivs.bin): $NPRFX_DATA_DIR when set (empty: none), else
 * share/nprfx beside the executable (the build tree) or ../share/nprfx (an install), the first
 * holding ivs.bin; NULL when there is none (the data is then generated when needed). */
const char *cli_data_dir(char *buf, size_t size)
{
    const char *env = getenv("NPRFX_DATA_DIR");
    if (env) {
        if (!*env || strlen(env) >= size) return NULL;
        memcpy(buf, env, strlen(env) + 1);
        return buf;
    }
    char exe[4096];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0) return NULL;
    exe[n] = 0;
    char *slash = strrchr(exe, '/');
    if (!slash) return NULL;
    *slash = 0;
    static const char *const rel[] = {"/share/nprfx", "/../share/nprfx"};
    for (size_t i = 0; i < sizeof rel / sizeof rel[0]; i++) {
        char file[4200];
        snprintf(file, sizeof file, "%s%s/ivs.bin", exe, rel[i]);
        if (access(file, R_OK) == 0 && (size_t)snprintf(buf, size, "%s%s", exe, rel[i]) < size)
            return buf;
    }
    return NULL;
}

/* --mem-limit, parsed before the command's context exists: every context cli_env_init makes
 * afterwards carries it (one limit per process, as the option says). */
static int have_mem_limit;
static uint64_t mem_limit;

void cli_env_mem_limit(uint64_t bytes)
{
    have_mem_limit = 1;
    mem_limit = bytes;
}

int cli_env_init(cli_env *env, int threads)
{
    memset(env, 0, sizeof *env);
    if (nprfx_pool_create(cli_threads(threads), &env->pool)) {
        fprintf(stderr, "nprfx: cannot start worker threads\n");
        return 1;
    }
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.executor = nprfx_pool_executor(env->pool);
    char dir[4096];
    init.data_dir = cli_data_dir(dir, sizeof dir);
    init.flow = flow_opencv_provider(); /* NULL without OpenCV: the flow node says so */
    if (nprfx_context_create(&init, &env->ctx)) {
        nprfx_pool_destroy(env->pool);
        fprintf(stderr, "nprfx: out of memory\n");
        return 1;
    }
    if (have_mem_limit) nprfx_context_set_memory_limit(env->ctx, mem_limit, "--mem-limit");
    return 0;
}

void cli_env_free(cli_env *env)
{
    nprfx_context_destroy(env->ctx);
    nprfx_pool_destroy(env->pool);
    memset(env, 0, sizeof *env);
}

const char *cli_message(const nprfx_context *ctx)
{
    static _Thread_local char buf[2048];
    nprfx_context_last_error(ctx, buf, sizeof buf);
    return buf;
}

double cli_peak_mib(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return (double)ru.ru_maxrss / 1024.0; /* Linux reports KiB */
}

int cli_make_dirs(const char *dir)
{
    char buf[8192];
    snprintf(buf, sizeof buf, "%s", dir);
    for (char *p = buf + 1; *p; p++) {
        if (*p != '/') continue;
        *p = '\0';
        if (mkdir(buf, 0777) && errno != EEXIST) return -1;
        *p = '/';
    }
    return mkdir(buf, 0777) && errno != EEXIST ? -1 : 0;
}
