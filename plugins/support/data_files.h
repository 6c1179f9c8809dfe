/* The data files nodes read from the context's data directory (plugins/support/data_files.c,
 * library nprfx_nodes): finding one and reading it whole, and the stipple node's dot sequence
 * ivs.bin. Core reads no files: it gets the bytes (nprfx_ivs_decode) or what they decode to. */
#ifndef NPRFX_SUPPORT_DATA_FILES_H
#define NPRFX_SUPPORT_DATA_FILES_H

#include <stddef.h>

#include "nprfx/context.h"
#include "nprfx/stipple.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A data file read whole. */
typedef struct nprfx_data_file {
    unsigned char *data; /* malloc'd; NULL: no data directory, or no such file in it */
    size_t size;
    char path[4096]; /* where it was looked for: "" without a data directory */
} nprfx_data_file;

/* Read the file `name` of nprfx_context_data_dir(ctx) whole, at most max_size bytes. NPRFX_OK
 * with out->data NULL when there is no data directory or the file does not exist there: the
 * caller does without it. A file that is there but cannot be opened or read, or is larger than
 * max_size, is an NPRFX_ERR_IO error whose message starts with its path. Free with
 * internal_data_file_free. */
nprfx_result internal_data_file_read(nprfx_context *ctx, const char *name, size_t max_size,
                                  nprfx_data_file *out);
void internal_data_file_free(nprfx_data_file *f);

/* The stipple node's dot sequence: an nprfx_stipple_sequence preloaded from the shipped
 * DATA_DIR/ivs.bin (written by `nprfx ivs`), which saves generating it (seconds per million
 * points) and keeps the dots the same whatever compiler built this. No data directory or no
 * file: an empty sequence, generated when used, with the same pixels. A file that is there but
 * unreadable, corrupt or of another seed is an error that names it and says to rebuild it with
 * `nprfx ivs` or remove it: a broken install should not pass silently. */
nprfx_result internal_stipple_shipped_sequence(nprfx_context *ctx, nprfx_stipple_sequence **out);
/* The sequence above is made once per data file (its path and what stat says of it) and shared
 * by every caller in the process, each getting a reference of its own: the file is read, indexed
 * and each tone curve measured once, whatever the number of instances. This drops the process's
 * own references (an OpenFX host unloading the plug-in); users keep theirs. */
void internal_stipple_shipped_release(void);

#ifdef __cplusplus
}
#endif
#endif
