/* nprfx — the command-line node runner: dispatches to one function per sub-command. */
#include <stdio.h>
#include <string.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "commands/commands.h"
#include "flow_opencv.h"
#include "nprfx/nprfx.h"

typedef struct command {
    const char *name;
    int (*fn)(int argc, char **argv);
    const char *summary;
} command;

static const command commands[] = {
    {"list", cli_cmd_list, "list the nodes (ids, groups, one-line help)"},
    {"help", cli_cmd_help, "document a node: inputs, expected AOVs, params, defaults, ranges"},
    {"run", cli_cmd_run, "render a JSON node graph over a frame range"},
    {"analyze", cli_cmd_analyze,
     "measure a graph's shot statistics (tone ranges) once, for every run and farm chunk"},
    {"info", cli_cmd_info, "print a plate's size, layers and channels (like iinfo)"},
    {"diff", cli_cmd_diff,
     "compare two images or sequences (idiff-style thresholds and exit codes)"},
    {"synth", cli_cmd_synth, "write analytic test plates with exact AOVs"},
    {"measure", cli_cmd_measure,
     "measure a look over its shot: warp error along the motion, background, tone curve"},
    {"bench", cli_cmd_bench, "time a node: Mpixel/s, ms per frame, peak memory"},
    {"bench-graph", cli_cmd_bench_graph,
     "time a whole graph per frame on synthetic plates: compute and I/O apart, peak memory"},
    {"docs", cli_cmd_docs, "write the node reference (Markdown) generated from the descriptors"},
    {"host-project", cli_cmd_host_project,
     "write a graph as a Natron project, Natron script and Nuke script (OpenFX nodes)"},
    {"ivs", cli_cmd_ivs, "generate or check the stipple node's dot sequence file (IVS)"},
    {"pam", cli_cmd_pam,
     "painterly art maps: build one from brushstroke samples, check one, paint samples"},
    {"farm", cli_cmd_farm,
     "render a shot in frame chunks on a farm (Slurm array job), check every frame arrived"},
};

static void usage(FILE *f)
{
    fprintf(f,
            "nprfx %s — temporally coherent non-photorealistic rendering as compositing nodes\n\n"
            "usage: nprfx COMMAND [options]\n\ncommands:\n",
            NPRFX_VERSION_STRING);
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(f, "  %-12s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "\n'nprfx COMMAND --help' explains a command; 'nprfx help NODE' a node.\n"
               "Example: nprfx run samples/graphs/threshold.json --frames 1-4\n");
}

/* Every frame of a shot makes the same allocations again: a node's scratch (Gabor's point
 * lists, its depth window, a strip's planes) is freed at the end of the frame and asked for
 * again at the next. glibc gives memory at the top of a heap back to the kernel once 128 KiB of
 * it are free, and serves blocks above its (adaptive) mmap threshold from fresh mappings, so
 * each frame paid its page faults again: a quarter of the six-node bench graph's compute time.
 * The runner keeps what it freed for the next frame instead: resident memory stays
 * at the shot's high-water mark, which is the peak it reports anyway. Frames themselves are
 * pooled (frame_pool.c); blocks above 64 MiB (8K planes) still get their own mappings. */
static void keep_freed_memory(void)
{
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 64 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

int main(int argc, char **argv)
{
    keep_freed_memory();
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (!strcmp(argv[1], "--version")) {
        printf("nprfx %s\n", NPRFX_VERSION_STRING);
        /* what the flow node computes with (tests skip footage without it) */
        const nprfx_flow_provider *fp = flow_opencv_provider();
        if (fp)
            printf("optical flow: %s\n", fp->name);
        else
            printf("optical flow: none (built without OpenCV: the flow node cannot render)\n");
        return 0;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name)) return commands[i].fn(argc - 1, argv + 1);
    fprintf(stderr, "nprfx: unknown command '%s' (try 'nprfx --help')\n", argv[1]);
    return 2;
}
