/* nprfx CLI — reading image files: whole plates, the channels a caller picks, a strip of rows at a
 * time, header facts and attributes (io_read.cpp, OpenImageIO). */
#ifndef NPRFX_CLI_IO_READ_H
#define NPRFX_CLI_IO_READ_H

#include "io.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Read a file's default part group: the first part of the default view and every other part
 * of that view with the same data and display windows, concatenated (repeated channel names get
 * the part's name as a prefix). Deep parts are refused; tiled and MIP-mapped parts are read at
 * level 0. */
nprfx_result cli_io_read(nprfx_context *ctx, const char *path, cli_plate *out);
/* The same with a part, a view and the channels wanted (opt NULL: as cli_io_read). */
nprfx_result cli_io_read_ex(nprfx_context *ctx, const char *path, const cli_read_options *opt,
                            cli_plate *out);

/* A plate a strip of rows at a time (EXR), for the runner's strip renders (docs/design.md §1
 * "Memory"): opened with the same options as cli_io_read_ex, *shape gets the plate's
 * description (everything but pixels); then any rows [y0, y1) of the data window, in any order,
 * are decoded into dst (shape's nchannels floats per pixel, rows of the window's width), a block
 * of whole chunks at a time, so the read never holds more than its block. The memory limit
 * counts the block, not the plate. Other formats: NPRFX_ERR_UNSUPPORTED. */
typedef struct cli_row_reader cli_row_reader;
nprfx_result cli_io_rows_open(nprfx_context *ctx, const char *path, const cli_read_options *opt,
                              cli_plate *shape, cli_row_reader **out);
nprfx_result cli_io_rows_read(nprfx_context *ctx, cli_row_reader *r, int y0, int y1, float *dst);
void cli_io_rows_close(cli_row_reader *r);

nprfx_result cli_io_info(nprfx_context *ctx, const char *path, cli_file_info *out);

/* The header attributes of a file's first subimage whose names begin with `prefix`, as text
 * (ints and floats printed, strings as they are); *names and *values are arrays of *count
 * strings, freed with cli_attributes_free. */
nprfx_result cli_io_read_attributes(nprfx_context *ctx, const char *path, const char *prefix,
                                    char ***names, char ***values, int *count);
void cli_attributes_free(char **names, char **values, int count);

#ifdef __cplusplus
}
#endif
#endif
