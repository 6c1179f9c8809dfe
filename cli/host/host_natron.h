/* nprfx host-project — the Natron project writer (host_natron.c). */
#ifndef NPRFX_CLI_HOST_NATRON_H
#define NPRFX_CLI_HOST_NATRON_H

#include <stdio.h>

#include "host_project.h"

/* Write hp as a Natron project (.ntp) to f: 0 on success, else an error raised on hp->g's
 * context. */
nprfx_result host_write_natron(const host_project *hp, FILE *f);

#endif
