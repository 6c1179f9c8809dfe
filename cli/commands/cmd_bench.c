/* nprfx bench — time one node on synthetic plates: Mpixel/s, ms per frame, peak memory.
 *
 * The node's inputs are fed from the analytic "orbit" scene at the requested size (each input
 * takes the channels its AOV hint names, colour inputs R,G,B,A), so a benchmark needs no files
 * and excludes file I/O: only time inside the node's render function is counted. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/io_oiio.h"
#include "bench_floor.h"
#include "bench_options.h"
#include "cmd_shared.h"
#include "commands.h"
#include "nprfx/graph.h"
#include "util/cli_util.h"

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: nprfx bench NODE [--size WxH] [--frames N] [--set PARAM=VALUE ...]\n"
        "                  [--connect INPUT[=CHANNELS] ...] [--threads N] [--scene NAME]\n"
        "                  [--mem-limit SIZE] [--no-pool]\n\n"
        "Times NODE on synthetic plates (nprfx synth scenes, default orbit, 1920x1080,\n"
        "10 frames after one warm-up frame). Required inputs are connected to the plate by\n"
        "their AOV names; one without names takes motion_prev.X,Y when it needs 2 channels\n"
        "(warp's offset), diffuse when it needs 1. --connect adds an optional one (CHANNELS\n"
        "picks synth channels, e.g. --connect alpha=diffuse). Reports ms per frame (mean and best, "
        "and the CPU time of all\n"
        "threads: on a busy machine, the node's cost apart from waiting), Mpixel/s and the\n"
        "process's peak memory, and for nodes that count what they make (stipple: dots\n"
        "drawn) that count per frame and per second. File I/O and plate synthesis are not\n"
        "timed. Frames come from the runner's frame pool (--no-pool: calloc'd afresh, as\n"
        "before); --mem-limit is as for nprfx run. Then the node's memory floor: the bytes of\n"
        "frames it reads and writes, at this machine's memcpy speed on as many threads, and how\n"
        "many times that the node takes. 'nprfx bench-graph' times whole graphs.\n\n"
        "example:\n"
        "  nprfx bench stipple --size 1920x1080 --connect uv=UV.U,UV.V --connect id=id \\\n"
        "      --set mode=radius\n");
}

int cli_cmd_bench(int argc, char **argv)
{
    const char *node_id = NULL, *connects[32];
    int nconn = 0;
    cli_bench_options o = {.size = "1920x1080", .scene = "orbit", .frames = 10};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (cli_bench_option(argc, argv, &i, &o))
            continue;
        else if (!strcmp(a, "--connect") && i + 1 < argc && nconn < 32)
            connects[nconn++] = argv[++i];
        else if (a[0] != '-' && !node_id)
            node_id = a;
        else {
            fprintf(stderr, "nprfx bench: unexpected argument '%s'\n\n", a);
            usage(stderr);
            return 2;
        }
    }
    const char *scene = o.scene, *mem_limit = o.mem_limit;
    const char *const *sets = o.sets;
    const int nsets = o.nsets, frames = o.frames, threads = o.threads, no_pool = o.no_pool;
    if (!node_id || frames < 1) {
        usage(stderr);
        return 2;
    }
    const nprfx_node_desc *d = nprfx_node_find(node_id);
    if (!d) {
        fprintf(stderr, "nprfx bench: unknown node '%s' (nprfx list shows the nodes)\n", node_id);
        return 2;
    }
    int w, h;
    if (cli_bench_size("bench", &o, &w, &h)) return 2;
    /* Build the graph as JSON text, so bench exercises exactly the runner's wiring. */
    char json[8192];
    int len = snprintf(json, sizeof json,
                       "{\"frames\": \"1-%d\", \"nodes\": {\"plate\": {\"node\": \"synth\", "
                       "\"scene\": \"%s\", \"size\": \"%dx%d\"}, \"bench\": {\"node\": \"%s\", "
                       "\"inputs\": {",
                       frames + 1, scene, w, h, node_id);
    int first = 1;
    for (int k = 0; k < d->num_inputs; k++) {
        const char *sel = NULL;
        int connect = !(d->inputs[k].flags & NPRFX_INPUT_OPTIONAL);
        for (int c = 0; c < nconn; c++) {
            size_t nl = strlen(d->inputs[k].name);
            if (!strncmp(connects[c], d->inputs[k].name, nl) &&
                (connects[c][nl] == 0 || connects[c][nl] == '=')) {
                connect = 1;
                sel = connects[c][nl] ? connects[c] + nl + 1 : NULL;
            }
        }
        if (!connect) continue;
        /* An input that names no AOV takes the plate as it is unless it needs an exact count of
         * channels: then channels of the synth plate that fit (warp's offset: the motion). */
        if (!sel && !d->inputs[k].aov && d->inputs[k].channels == 2)
            sel = "motion_prev.X,motion_prev.Y";
        else if (!sel && !d->inputs[k].aov && d->inputs[k].channels == 1)
            sel = "diffuse";
        len += snprintf(json + len, sizeof json - (size_t)len, "%s\"%s\": \"plate%s%s\"",
                        first ? "" : ", ", d->inputs[k].name, sel ? ":" : "", sel ? sel : "");
        first = 0;
    }
    /* The write is never run (bench evaluates the node itself): it makes the node the graph's
     * output, so the plan sizes its frame and the plate's channels against --mem-limit. */
    snprintf(json + len, sizeof json - (size_t)len,
             "}}, \"out\": {\"node\": \"write\", \"inputs\": {\"image\": \"bench\"}, "
             "\"path\": \"bench.####.exr\"}}}");

    if (mem_limit && cli_set_mem_limit("nprfx", "bench", mem_limit)) return 2;
    cli_env env;
    if (cli_env_init(&env, threads)) return 1;
    int status = 0;
    nprfx_graph *g = NULL;
    nprfx_graph_options opt = {sizeof opt, (size_t)512 << 20, 0, NULL, NULL}; /* plates are big */
    opt.io = nprfx_io_oiio();
    opt.no_pool = no_pool;
    if (nprfx_graph_parse(env.ctx, json, ".", &opt, &g)) {
        fprintf(stderr, "nprfx bench: %s\n", cli_message(env.ctx));
        status = 2;
        goto done;
    }
    for (int i = 0; i < nsets; i++) {
        char buf[512];
        snprintf(buf, sizeof buf, "bench.%s", sets[i]);
        if (nprfx_graph_set(g, buf)) {
            fprintf(stderr, "nprfx bench: %s\n", cli_message(env.ctx));
            status = 2;
            goto done;
        }
    }
    nprfx_graph_plan_info plan;
    if (nprfx_graph_plan(g, 1, &plan)) { /* a bench beyond --mem-limit fails before it starts */
        fprintf(stderr, "nprfx bench: %s\n", cli_message(env.ctx));
        status = 2;
        goto done;
    }
    double total = 0, best = 1e30, cpu = 0, traffic = 0;
    long long items = 0;
    nprfx_image out;
    for (int f = 0; f <= frames; f++) { /* frame 0 warms caches and page tables */
        nprfx_graph_take_render_seconds(g);
        nprfx_graph_take_render_cpu_seconds(g);
        nprfx_graph_take_render_items(g);
        nprfx_graph_take_render_bytes(g);
        if (nprfx_graph_eval(g, "bench", 1 + f, &out, NULL)) {
            fprintf(stderr, "nprfx bench: %s\n", cli_message(env.ctx));
            status = 1;
            goto done;
        }
        double s = nprfx_graph_take_render_seconds(g);
        cpu += nprfx_graph_take_render_cpu_seconds(g) * (f > 0);
        traffic += nprfx_graph_take_render_bytes(g) * (f > 0);
        long long n = nprfx_graph_take_render_items(g);
        if (f == 0) continue;
        items += n;
        total += s;
        if (s < best) best = s;
    }
    double mean = total / frames;
    /* the CPU time over all threads: on a shared machine, the node's cost apart from waiting */
    printf("%s %dx%d, %d frame%s, %d thread%s: %.2f ms/frame (best %.2f; CPU %.2f), %.1f "
           "Mpixel/s, peak memory %.0f MiB\n",
           node_id, w, h, frames, frames == 1 ? "" : "s",
           nprfx_executor_workers(nprfx_context_executor(env.ctx)),
           nprfx_executor_workers(nprfx_context_executor(env.ctx)) == 1 ? "" : "s", mean * 1e3,
           best * 1e3, cpu / frames * 1e3, (double)w * h / mean * 1e-6, cli_peak_mib());
    /* the floor: the frames' bytes the node must read and write, at this machine's copy speed */
    double per_frame = traffic / frames;
    double bw = cli_copy_bandwidth(nprfx_context_executor(env.ctx), (size_t)per_frame);
    if (bw > 0 && per_frame > 0)
        printf("memory floor: %.2f ms/frame (%.0f MB of frames read and written at %.1f GB/s "
               "memcpy); the node takes %.1fx that\n",
               per_frame / bw * 1e3, per_frame * 1e-6, bw * 1e-9, mean / (per_frame / bw));
    if (d->item_name && items > 0) /* what the node counts: e.g. stipples drawn */
        printf("%s: %.0f %s/frame, %.2f M %s/s\n", node_id, (double)items / frames, d->item_name,
               (double)items / total * 1e-6, d->item_name);
done:
    nprfx_graph_free(g);
    cli_env_free(&env);
    return status;
}
