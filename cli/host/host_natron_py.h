/* nprfx host-project — the Natron Python script writer (host_natron_py.c). */
#ifndef NPRFX_CLI_HOST_NATRON_PY_H
#define NPRFX_CLI_HOST_NATRON_PY_H

#include <stdio.h>

#include "host_project.h"

/* Write hp as a Natron Python script to f: 0 on success, else an error raised on hp->g's
 * context. out_file: the script's path, whose folder names it looks for when Natron gives no
 * __file__. */
nprfx_result host_write_natron_py(const host_project *hp, FILE *f, const char *out_file);

#endif
