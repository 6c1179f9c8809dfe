/* nprfx CLI — the options `nprfx bench` and `nprfx bench-graph` share. */
#ifndef NPRFX_CLI_BENCH_OPTIONS_H
#define NPRFX_CLI_BENCH_OPTIONS_H

#define CLI_BENCH_MAX_SETS 64
typedef struct cli_bench_options {
    const char *size, *scene, *mem_limit;
    const char *sets[CLI_BENCH_MAX_SETS];
    int nsets, frames, threads, no_pool;
} cli_bench_options;
/* Consume argv[*i] (and its value) when it is one of the shared options: --size, --frames,
 * --threads, --scene, --set, --mem-limit, --no-pool. 1 when taken. */
int cli_bench_option(int argc, char **argv, int *i, cli_bench_options *o);
/* Parse o->size into w, h; 2 (with the message) when it is not WxH within 65536. */
int cli_bench_size(const char *cmd, const cli_bench_options *o, int *w, int *h);

#endif
