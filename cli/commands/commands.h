/* nprfx CLI — one function per sub-command; each returns the process exit status. */
#ifndef NPRFX_CLI_COMMANDS_H
#define NPRFX_CLI_COMMANDS_H

#include "nprfx/graph.h"

#ifdef __cplusplus
extern "C" {
#endif

/* argv[0] is the sub-command name ("run"), options follow. */
int cli_cmd_list(int argc, char **argv);
int cli_cmd_help(int argc, char **argv);
int cli_cmd_run(int argc, char **argv);
int cli_cmd_analyze(int argc, char **argv);
int cli_cmd_info(int argc, char **argv);
int cli_cmd_diff(int argc, char **argv);
int cli_cmd_synth(int argc, char **argv);
int cli_cmd_bench(int argc, char **argv);
int cli_cmd_bench_graph(int argc, char **argv);
int cli_cmd_docs(int argc, char **argv);
int cli_cmd_ivs(int argc, char **argv);
int cli_cmd_measure(int argc, char **argv);
int cli_cmd_host_project(int argc, char **argv);
int cli_cmd_pam(int argc, char **argv);
int cli_cmd_farm(int argc, char **argv);

/* What a program built on the runner adds to `run` (the OpenFX test host of tests/ofxhost/ gives
 * every node a render hook that drives the plug-ins): options of its own and a render hook for
 * the graph. Members may be NULL. */
typedef struct cli_run_extension {
    const char *program;       /* names the command in usage and messages (NULL: "nprfx") */
    const char *options_usage; /* lines added to the options of --help */
    /* Offered each argument `run` does not take, with the next one (NULL: none); returns how many
     * of the two it consumed (0: not its own, an error). */
    int (*option)(void *user, const char *arg, const char *next);
    /* Before the graph loads, with the run's context (whose executor has the --threads workers):
     * may set *hook. An error (raised in ctx) ends the run with status 2. */
    nprfx_result (*open)(void *user, nprfx_context *ctx, int quiet, const nprfx_render_hook **hook);
    /* At the end of a run that got as far as its context, after the graph is freed (which
     * releases the hook's instances); also when open failed. */
    void (*close)(void *user);
    void *user;
} cli_run_extension;

/* `run` with an extension (NULL: cli_cmd_run). */
int cli_cmd_run_extended(int argc, char **argv, const cli_run_extension *ext);

#ifdef __cplusplus
}
#endif
#endif
