/* nprfx CLI — writing image files, whole or a strip of rows at a time, and text files, through a
 * temporary name and a rename (io_write.cpp, OpenImageIO). */
#ifndef NPRFX_CLI_IO_WRITE_H
#define NPRFX_CLI_IO_WRITE_H

#include "io.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Write an EXR (or any format OIIO knows, by extension) with the given channel names
 * (names may be NULL: default names by count). display: the display window (NULL = bounds). */
nprfx_result cli_io_write(nprfx_context *ctx, const char *path, const nprfx_image *im,
                          const char *const *names, const nprfx_rect *display,
                          const cli_write_options *opt);

/* An image written a strip of rows at a time, top to bottom: as cli_io_write (same header,
 * types and options, a temporary name beside path), but each cli_io_rows_write gives the next
 * rows (full width of bounds), and cli_io_rows_finish with keep renames the file into place
 * once every row is written; without keep (or on any error) the temporary file is removed. The
 * writer is freed by finish. */
typedef struct cli_row_writer cli_row_writer;
nprfx_result cli_io_rows_create(nprfx_context *ctx, const char *path, nprfx_rect bounds,
                                int channels, const char *const *names, const nprfx_rect *display,
                                const cli_write_options *opt, cli_row_writer **out);
nprfx_result cli_io_rows_write(nprfx_context *ctx, cli_row_writer *w, const nprfx_image *rows);
nprfx_result cli_io_rows_finish(nprfx_context *ctx, cli_row_writer *w, int keep);

/* Write len bytes of text to path through a temporary name and a rename, creating missing
 * parent directories (vector exports: CSV, SVG). */
nprfx_result cli_io_write_text(nprfx_context *ctx, const char *path, const char *text, size_t len);

#ifdef __cplusplus
}

#include <OpenImageIO/imageio.h>

/* What previews share of the writer (C++ only). */
namespace cli_io
{

/* Write pixels described by spec (data in `type`, with byte strides) to path through a temporary
 * name beside it and a rename, creating missing parent directories. */
nprfx_result write_atomic(nprfx_context *ctx, const char *path, OIIO::ImageSpec spec,
                          OIIO::TypeDesc type, const void *data, OIIO::stride_t xstride,
                          OIIO::stride_t ystride);

} // namespace cli_io
#endif
#endif
