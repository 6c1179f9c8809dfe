/* nprfx bench-graph — time a whole graph per frame on synthetic plates.
 *
 * `nprfx bench` times one node; a look is a graph, and what a farm pays is the graph's time and
 * memory per frame. Every read node becomes an in-memory `nprfx synth` scene at --size (the
 * generator `nprfx synth` writes files with), every synth node and "format" take that size, so a
 * graph is timed at 1080p or 4K without plates on disk. The time of the plates (synthesis standing
 * in for reads) and of writes (only with --write) is reported apart from the nodes' compute. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/engine_util.h"
#include "nprfx/io_oiio.h"
#include "bench_options.h"
#include "cmd_shared.h"
#include "commands.h"
#include "nprfx/graph.h"
#include "nprfx/io.h"
#include "util/cli_util.h"

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: nprfx bench-graph GRAPH.json [--size WxH] [--frames N] [--threads N]\n"
        "                        [--scene NAME] [--set N.P=VALUE ...] [--write DIR]\n"
        "                        [--mem-limit SIZE] [--no-pool] [--stats]\n\n"
        "Times a whole graph per frame on synthetic plates: every read node of a frame\n"
        "sequence becomes the synthetic scene NAME (default orbit, as nprfx synth makes it)\n"
        "at --size (default 1920x1080; a read of one file, such as a painterly art map, stays),\n"
        "and every synth node and \"format\" take that size, so the graph's\n"
        "references must name synth channels (Z, motion_prev, Pref, UV, id, diffuse, R,G,B,\n"
        "...) or rely on the inputs' AOV hints. The shot is frames 1 to N (default 8), rendered\n"
        "in order. Each frame evaluates every write node's input; with --write DIR the files\n"
        "are written under DIR and timed as output. Reports ms per frame and frames per second\n"
        "(all frames, and the first apart: it holds a temporal warm-up; then the frames after\n"
        "the first alone, a long shot's steady state), the time in the nodes\n"
        "(compute), in the plates (input: synthesis standing in for reads) and in writes\n"
        "(output), and the process's peak memory. --stats adds the per-node table of\n"
        "nprfx run --stats; --mem-limit and --no-pool are as for nprfx run.\n\n"
        "example:\n"
        "  nprfx bench-graph samples/bench/bench_six.json --size 3840x2160 --threads 2\n");
}

/* The graph's node seconds so far, by kind: compute, read, synth, write. */
static void seconds_by_kind(nprfx_graph *g, double sec[4])
{
    const nprfx_graph_node_stats *st;
    int n = nprfx_graph_stats(g, &st);
    for (int k = 0; k < 4; k++)
        sec[k] = 0.0;
    for (int i = 0; i < n; i++)
        sec[st[i].kind & 3] += st[i].seconds;
}

int cli_cmd_bench_graph(int argc, char **argv)
{
    const char *path = NULL, *write_dir = NULL;
    int stats = 0;
    cli_bench_options o = {.size = "1920x1080", .scene = "orbit", .frames = 8};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (cli_bench_option(argc, argv, &i, &o))
            continue;
        else if (!strcmp(a, "--write") && i + 1 < argc)
            write_dir = argv[++i];
        else if (!strcmp(a, "--stats"))
            stats = 1;
        else if (a[0] != '-' && !path)
            path = a;
        else {
            fprintf(stderr, "nprfx bench-graph: unexpected argument '%s'\n\n", a);
            usage(stderr);
            return 2;
        }
    }
    const char *scene = o.scene, *mem_limit = o.mem_limit;
    const char *const *sets = o.sets;
    const int nsets = o.nsets, frames = o.frames, threads = o.threads, no_pool = o.no_pool;
    if (!path || frames < 1) {
        usage(stderr);
        return 2;
    }
    int w, h;
    if (cli_bench_size("bench-graph", &o, &w, &h)) return 2;
    uint64_t limit_bytes = 0;
    if (mem_limit && nprfx_parse_size(mem_limit, &limit_bytes)) {
        fprintf(stderr,
                "nprfx bench-graph: --mem-limit '%s' is not a size (e.g. 8G, 512M, or 0 "
                "for none)\n",
                mem_limit);
        return 2;
    }
    cli_env env;
    if (cli_env_init(&env, threads)) return 1;
    int status = 0;
    nprfx_graph *g = NULL;
    nprfx_graph_options opt = {sizeof opt, 0, 0, write_dir, NULL};
    opt.io = nprfx_io_oiio();
    opt.no_pool = no_pool;
    char shot[64];
    snprintf(shot, sizeof shot, "1-%d", frames);
    nprfx_graph_plan_info plan;
    memset(&plan, 0, sizeof plan);
    /* The limit applies to the graph at --size, not at the size its file names. */
    if (nprfx_graph_load(env.ctx, path, &opt, &g) || nprfx_graph_set_shot(g, shot) ||
        (mem_limit && (nprfx_context_set_memory_limit(env.ctx, limit_bytes, "--mem-limit"), 0)) ||
        nprfx_graph_synthesize_reads(g, w, h, scene)) {
        fprintf(stderr, "nprfx bench-graph: %s\n", cli_message(env.ctx));
        status = 2;
        goto done;
    }
    for (int i = 0; i < nsets; i++)
        if (nprfx_graph_set(g, sets[i])) {
            fprintf(stderr, "nprfx bench-graph: %s\n", cli_message(env.ctx));
            status = 2;
            goto done;
        }
    if (!nprfx_graph_write_count(g)) {
        fprintf(stderr, "nprfx bench-graph: %s: the graph has no write node to time\n", path);
        status = 2;
        goto done;
    }
    if (nprfx_graph_plan(g, 1, &plan)) {
        fprintf(stderr, "nprfx bench-graph: %s\n", cli_message(env.ctx));
        status = 2;
        goto done;
    }
    /* seconds by kind: compute, read, synth, write; at1: as they stood after frame 1 */
    double t0 = engine_now(), first = 0, at1[4] = {0, 0, 0, 0};
    for (int f = 1; f <= frames; f++) {
        int written = 0;
        nprfx_result r =
            write_dir ? nprfx_graph_render_frame(g, f, &written) : nprfx_graph_compute_frame(g, f);
        if (r) {
            fprintf(stderr, "nprfx bench-graph: frame %d: %s\n", f, cli_message(env.ctx));
            status = 1;
            goto done;
        }
        if (f == 1) {
            first = engine_now() - t0;
            seconds_by_kind(g, at1);
        }
    }
    double total = engine_now() - t0, sec[4];
    seconds_by_kind(g, sec);
    int workers = nprfx_executor_workers(nprfx_context_executor(env.ctx));
    printf("%s %dx%d, %d frame%s, %d thread%s: %.1f ms/frame, %.2f frames/s (first frame %.1f "
           "ms); compute %.1f ms, input %.1f ms, output %.1f ms per frame; peak memory %.0f MiB\n",
           path, w, h, frames, frames == 1 ? "" : "s", workers, workers == 1 ? "" : "s",
           total * 1e3 / frames, frames / total, first * 1e3, sec[0] * 1e3 / frames,
           (sec[1] + sec[2]) * 1e3 / frames, sec[3] * 1e3 / frames, cli_peak_mib());
    if (frames > 1) {
        /* a shot's steady state: the first frame holds the temporal warm-up and the first
         * allocation of every buffer, which a long shot spreads over more frames */
        int m = frames - 1;
        double rest = total - first;
        printf("after the first frame: %.1f ms/frame, %.2f frames/s; compute %.1f ms, input %.1f "
               "ms, output %.1f ms per frame\n",
               rest * 1e3 / m, m / rest, (sec[0] - at1[0]) * 1e3 / m,
               (sec[1] + sec[2] - at1[1] - at1[2]) * 1e3 / m, (sec[3] - at1[3]) * 1e3 / m);
    }
    if (stats) cli_print_stats(stdout, g, frames, &plan);
done:
    nprfx_graph_free(g);
    cli_env_free(&env);
    return status;
}
