/* nprfx host-project — the Nuke script writer (host_nuke.c). */
#ifndef NPRFX_CLI_HOST_NUKE_H
#define NPRFX_CLI_HOST_NUKE_H

#include <stdio.h>

#include "host_project.h"

/* Write hp as a Nuke script (.nk) to f: 0 on success, else an error raised on hp->g's context. */
nprfx_result host_write_nuke(const host_project *hp, FILE *f);

#endif
