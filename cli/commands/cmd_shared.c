/* nprfx CLI — what several commands share: --mem-limit and the --stats table. */
#include <stdint.h>
#include <stdio.h>

#include "cmd_shared.h"
#include "nprfx/graph.h"
#include "nprfx/io.h"
#include "util/cli_util.h"

int cli_set_mem_limit(const char *prog, const char *cmd, const char *size)
{
    uint64_t bytes;
    if (nprfx_parse_size(size, &bytes)) {
        fprintf(stderr, "%s %s: --mem-limit '%s' is not a size (e.g. 8G, 512M, or 0 for none)\n",
                prog, cmd, size);
        return 1;
    }
    cli_env_mem_limit(bytes);
    return 0;
}

void cli_print_stats(FILE *f, nprfx_graph *g, int frames, const nprfx_graph_plan_info *plan)
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
    /* what each read takes of its files: a render of these passes alone reads faster */
    for (int i = 0; i < nprfx_graph_node_count(g); i++) {
        nprfx_graph_node_info info = {sizeof info};
        if (nprfx_graph_node(g, i, &info) || info.kind != NPRFX_GRAPH_READ || !info.read_channels)
            continue;
        int k = 1;
        for (const char *c = info.read_channels; *c; c++)
            k += *c == ',';
        fprintf(f, "read '%s' takes %d of its files' %d channels: %s\n", info.name, k,
                info.file_channels, info.read_channels);
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
        peak, est, need, lim, cli_peak_mib());
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
