/* nprfx CLI — shared helpers. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "cli_util.h"
#include "flow_opencv.h"
#include "graph/graph.h"
#include "io/io_limits.h"

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

const char *nprfx_cli_data_dir(char *buf, size_t size)
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

int nprfx_cli_env_init(nprfx_cli_env *env, int threads)
{
    memset(env, 0, sizeof *env);
    if (nprfx_pool_create(nprfx_cli_threads(threads), &env->pool)) {
        fprintf(stderr, "nprfx: cannot start worker threads\n");
        return 1;
    }
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.executor = nprfx_pool_executor(env->pool);
    char dir[4096];
    init.data_dir = nprfx_cli_data_dir(dir, sizeof dir);
    init.flow = nprfx_flow_opencv(); /* NULL without OpenCV: the flow node says so */
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

const char *nprfx_cli_message(const nprfx_context *ctx)
{
    static _Thread_local char buf[2048];
    nprfx_context_last_error(ctx, buf, sizeof buf);
    return buf;
}

double nprfx_cli_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double nprfx_cli_peak_mib(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return (double)ru.ru_maxrss / 1024.0; /* Linux reports KiB */
}

int nprfx_cli_set_mem_limit(const char *prog, const char *cmd, const char *size)
{
    uint64_t bytes;
    if (nprfx_parse_size(size, &bytes)) {
        fprintf(stderr, "%s %s: --mem-limit '%s' is not a size (e.g. 8G, 512M, or 0 for none)\n",
                prog, cmd, size);
        return 1;
    }
    nprfx_mem_limit_set(bytes);
    return 0;
}

void nprfx_cli_print_stats(FILE *f, struct nprfx_graph *g, int frames,
                           const struct nprfx_graph_plan_info *plan)
{
    const nprfx_graph_node_stats *st;
    int n = nprfx_graph_stats(g, &st);
    int per = frames > 0 ? frames : 1;
    fprintf(f, "stats: %d frame%s\n", frames, frames == 1 ? "" : "s");
    fprintf(f, "  %-20s %-15s %7s %10s %12s %12s\n", "node", "type", "renders", "ms/frame",
            "MiB/frame", "new MiB");
    for (int i = 0; i < n; i++) {
        if (!st[i].calls) continue; /* not on the way to a write */
        fprintf(f, "  %-20s %-15s %7lld %10.2f %12.1f %12.1f\n", st[i].name, st[i].type,
                st[i].calls, st[i].seconds * 1e3 / per, (double)st[i].bytes / per / 1048576.0,
                (double)st[i].fresh_bytes / 1048576.0);
    }
    char peak[32], est[32], need[32], lim[32];
    nprfx_format_bytes(peak, sizeof peak, nprfx_graph_mem_peak(g));
    nprfx_format_bytes(est, sizeof est, plan ? plan->peak : 0);
    nprfx_format_bytes(need, sizeof need, plan ? plan->need : 0);
    if (!plan || plan->limit == UINT64_MAX)
        snprintf(lim, sizeof lim, "none");
    else
        nprfx_format_bytes(lim, sizeof lim, plan->limit);
    fprintf(
        f,
        "frames and caches held at most %s (estimate %s, %s in use at once; memory limit %s); peak "
        "resident %.0f MiB\n",
        peak, est, need, lim, nprfx_cli_peak_mib());
    if (plan && plan->state) {
        char kept[32];
        nprfx_format_bytes(kept, sizeof kept, plan->state);
        fprintf(f, "of the estimate, up to %s are caches nodes keep between frames\n", kept);
    }
    if (plan && plan->strip_rows > 0) {
        char whole[32];
        nprfx_format_bytes(whole, sizeof whole, plan->whole_need);
        fprintf(f, "rendered by strips of %d rows (whole frames: %s in use at once)\n",
                plan->strip_rows, whole);
    }
}
