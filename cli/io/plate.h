/* nprfx CLI — plates and file descriptions in memory: freeing them, channel views and lookups. */
#ifndef NPRFX_CLI_PLATE_H
#define NPRFX_CLI_PLATE_H

#include "io.h"

#ifdef __cplusplus
extern "C" {
#endif

void cli_plate_free(cli_plate *p);
/* A view of channels [first, first+count) of the plate (shares pixels). */
nprfx_image cli_plate_view(const cli_plate *p, int first, int count);
/* Index of a channel by exact name, or -1. */
int cli_plate_channel(const cli_plate *p, const char *name);

/* Free what cli_io_info filled in. */
void cli_file_info_free(cli_file_info *info);

#ifdef __cplusplus
}
#endif
#endif
