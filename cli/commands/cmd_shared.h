/* nprfx CLI — what several commands share: --mem-limit and the --stats table. */
#ifndef NPRFX_CLI_CMD_SHARED_H
#define NPRFX_CLI_CMD_SHARED_H

#include <stdio.h>

#include "nprfx/graph.h"

/* --mem-limit SIZE of command `cmd`: set the process's memory limit (io_limits.h), or say why
 * SIZE is not a size on stderr and return non-zero. */
int cli_set_mem_limit(const char *prog, const char *cmd, const char *size);

/* The --stats table of a graph after `frames` frames: per node its calls, ms per frame and
 * bytes allocated per frame, then the graph's peak of frames held, the plan's estimate and the
 * process's peak resident size. */
void cli_print_stats(FILE *f, nprfx_graph *g, int frames, const nprfx_graph_plan_info *plan);

#endif
