/* nprfx CLI — one function per sub-command; each returns the process exit status. */
#ifndef NPRFX_CLI_COMMANDS_H
#define NPRFX_CLI_COMMANDS_H

#ifdef __cplusplus
extern "C" {
#endif

/* argv[0] is the sub-command name ("run"), options follow. */
int nprfx_cmd_list(int argc, char **argv);
int nprfx_cmd_help(int argc, char **argv);
int nprfx_cmd_run(int argc, char **argv);
int nprfx_cmd_info(int argc, char **argv);
int nprfx_cmd_diff(int argc, char **argv);
int nprfx_cmd_synth(int argc, char **argv);
int nprfx_cmd_bench(int argc, char **argv);
int nprfx_cmd_docs(int argc, char **argv);
int nprfx_cmd_ivs(int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
