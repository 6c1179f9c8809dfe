/* nprfx info --aovs: what a plate holds in canonical AOVs, and which styles run on it. */
#ifndef NPRFX_CLI_INFO_AOVS_H
#define NPRFX_CLI_INFO_AOVS_H

#include "nprfx/context.h"

/* Print the plate's profile, each canonical AOV with the channels the read gives it (or what
 * stands in, or what is missing), and for every graph in styles_dir (NULL: the data directory's
 * graphs/) whether it runs on the plate as is, with fallbacks, or not. 0, or 4 when the file
 * cannot be read. */
int cli_info_aovs(nprfx_context *ctx, const char *file, const char *styles_dir);

#endif
