/* nprfx CLI — plates and file descriptions in memory: freeing them, channel views and lookups. */
#ifndef NPRFX_CLI_PLATE_H
#define NPRFX_CLI_PLATE_H

#include "io.h"

#ifdef __cplusplus
extern "C" {
#endif

void nprfx_plate_free(nprfx_plate *p);
/* A view of channels [first, first+count) of the plate (shares pixels). */
nprfx_image nprfx_plate_view(const nprfx_plate *p, int first, int count);
/* Index of a channel by exact name, or -1. */
int nprfx_plate_channel(const nprfx_plate *p, const char *name);

/* Free what nprfx_io_info filled in. */
void nprfx_file_info_free(nprfx_file_info *info);

#ifdef __cplusplus
}
#endif
#endif
