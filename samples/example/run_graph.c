/* run_graph.c — run an nprfx graph file through the installed libraries, as `nprfx run` does:
 * the graph engine of libnprfx, with libnprfx-io reading the plates and writing the outputs.
 *
 *     cc run_graph.c $(pkg-config --cflags --libs nprfx-io) -o run_graph
 *     ./run_graph samples/graphs/main.json out 1-3
 *
 * Prints a line a frame from the progress callback and each node's time from the statistics
 * callback, then "ok" when every frame rendered. */
#include <stdio.h>

#include "nprfx/graph.h"
#include "nprfx/io_oiio.h"
#include "nprfx/nprfx.h"

static void on_error(void *user, const nprfx_context *ctx, nprfx_result code, const char *message)
{
    (void)user, (void)ctx;
    fprintf(stderr, "nprfx error (%s): %s\n", nprfx_result_name(code), message);
}

static int on_frame(void *user, const nprfx_graph_progress *p)
{
    (void)user;
    printf("frame %d (%d/%d): %s, %d file%s\n", p->frame, p->done, p->count,
           p->result ? "failed" : "done", p->written, p->written == 1 ? "" : "s");
    return 0; /* non-zero would stop the run */
}

static void on_stats(void *user, const nprfx_graph_node_stats *stats, int count)
{
    (void)user;
    for (int i = 0; i < count; i++)
        printf("  %-16s %-16s %lld call%s\n", stats[i].name, stats[i].type, stats[i].calls,
               stats[i].calls == 1 ? "" : "s");
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: %s GRAPH.json OUTPUT_DIR [FRAMES]\n", argv[0]);
        return 2;
    }
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.error_handler = on_error;
    nprfx_context *ctx = NULL;
    if (nprfx_context_create(&init, &ctx)) return 1;

    nprfx_graph_options opt = {.size = sizeof opt};
    opt.output_dir = argv[2];
    opt.io = nprfx_io_oiio(); /* the engine itself reads and writes no file */
    nprfx_graph *g = NULL;
    nprfx_frame_list frames = {NULL, 0};
    nprfx_graph_run_summary sum = {.rendered = 0};
    nprfx_graph_run_options run = {.size = sizeof run};
    run.progress = on_frame;
    run.stats = on_stats;
    int ok = nprfx_graph_load(ctx, argv[1], &opt, &g) == NPRFX_OK &&
             nprfx_graph_frames(g, argc > 3 ? argv[3] : NULL, &frames) == NPRFX_OK &&
             nprfx_graph_check(g, &frames, NULL) == NPRFX_OK &&
             nprfx_graph_run(g, &frames, &run, &sum) == NPRFX_OK;
    printf("%d frame%s rendered, %d failed, %d files\n", sum.rendered, sum.rendered == 1 ? "" : "s",
           sum.failed, sum.files);
    nprfx_seq_frames_free(&frames);
    nprfx_graph_free(g);
    nprfx_context_destroy(ctx);
    if (ok) printf("ok\n");
    return ok ? 0 : 1;
}
