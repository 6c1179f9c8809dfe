/* The options `nprfx bench` and `nprfx bench-graph` share, parsed in one place: the size of the
 * synthetic plates, frames, threads, scene, param overrides, the memory limit and the pool. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_options.h"

int cli_bench_option(int argc, char **argv, int *i, cli_bench_options *o)
{
    const char *a = argv[*i];
    const int has = *i + 1 < argc;
    if (!strcmp(a, "--size") && has)
        o->size = argv[++*i];
    else if (!strcmp(a, "--frames") && has)
        o->frames = atoi(argv[++*i]);
    else if (!strcmp(a, "--threads") && has)
        o->threads = atoi(argv[++*i]);
    else if (!strcmp(a, "--scene") && has)
        o->scene = argv[++*i];
    else if (!strcmp(a, "--set") && has && o->nsets < CLI_BENCH_MAX_SETS)
        o->sets[o->nsets++] = argv[++*i];
    else if (!strcmp(a, "--mem-limit") && has)
        o->mem_limit = argv[++*i];
    else if (!strcmp(a, "--no-pool"))
        o->no_pool = 1;
    else
        return 0;
    return 1;
}

int cli_bench_size(const char *cmd, const cli_bench_options *o, int *w, int *h)
{
    if (sscanf(o->size, "%dx%d", w, h) != 2 || *w < 1 || *h < 1 || *w > 65536 || *h > 65536) {
        fprintf(stderr, "nprfx %s: --size must be WxH, e.g. 1920x1080\n", cmd);
        return 2;
    }
    return 0;
}
