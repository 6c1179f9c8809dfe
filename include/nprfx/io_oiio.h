/* nprfx — libnprfx-io: images in files through OpenImageIO (EXR and every format it reads and
 * writes) and colour through OpenColorIO. nprfx_io_oiio() is the table the graph engine takes
 * (nprfx_graph_options.io); the functions behind it can be called directly. Link with
 * `pkg-config --libs nprfx-io`. Types and the memory bound: nprfx/io.h. */
#ifndef NPRFX_IO_OIIO_H
#define NPRFX_IO_OIIO_H

#include <stddef.h>

#include "nprfx/io.h"

#if defined(NPRFX_STATIC)
#define NPRFX_IO_API
#elif defined(__GNUC__) || defined(__clang__)
#define NPRFX_IO_API __attribute__((visibility("default")))
#else
#define NPRFX_IO_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* The table of the functions below, for nprfx_graph_options.io: static, never freed. */
NPRFX_IO_API const nprfx_io *nprfx_io_oiio(void);

/* Read a file's default part group: the first part of the default view and every other part
 * of that view with the same data and display windows, concatenated (repeated channel names get
 * the part's name as a prefix). Deep parts are refused; tiled and MIP-mapped parts are read at
 * level 0. */
NPRFX_IO_API nprfx_result nprfx_io_read(nprfx_context *ctx, const char *path, nprfx_plate *out);
/* The same with a part, a view and the channels wanted (opt NULL: as nprfx_io_read). */
NPRFX_IO_API nprfx_result nprfx_io_read_ex(nprfx_context *ctx, const char *path,
                                           const nprfx_read_options *opt, nprfx_plate *out);

/* A plate a strip of rows at a time (EXR), for the runner's strip renders (docs/design.md §1
 * "Memory"): opened with the same options as nprfx_io_read_ex, *shape gets the plate's
 * description (everything but pixels); then any rows [y0, y1) of the data window, in any order,
 * are decoded into dst (shape's nchannels floats per pixel, rows of the window's width), a block
 * of whole chunks at a time, so the read never holds more than its block. The memory limit
 * counts the block, not the plate. Other formats: NPRFX_ERR_UNSUPPORTED. */
NPRFX_IO_API nprfx_result nprfx_io_rows_open(nprfx_context *ctx, const char *path,
                                             const nprfx_read_options *opt, nprfx_plate *shape,
                                             nprfx_row_reader **out);
NPRFX_IO_API nprfx_result nprfx_io_rows_read(nprfx_context *ctx, nprfx_row_reader *r, int y0,
                                             int y1, float *dst);
NPRFX_IO_API void nprfx_io_rows_close(nprfx_row_reader *r);
/* The read's note after the rows read so far (nprfx_io.rows_note). */
NPRFX_IO_API nprfx_result nprfx_io_rows_note(nprfx_context *ctx, nprfx_row_reader *r, char **note,
                                             int *warning);

NPRFX_IO_API nprfx_result nprfx_io_info(nprfx_context *ctx, const char *path, nprfx_file_info *out);

/* The header attributes of a file's first subimage whose names begin with `prefix`, as text
 * (ints and floats printed, strings as they are); *names and *values are arrays of *count
 * strings, freed with nprfx_attributes_free. */
NPRFX_IO_API nprfx_result nprfx_io_read_attributes(nprfx_context *ctx, const char *path,
                                                   const char *prefix, char ***names,
                                                   char ***values, int *count);
NPRFX_IO_API void nprfx_attributes_free(char **names, char **values, int count);

/* Write an EXR (or any format OIIO knows, by extension) with the given channel names
 * (names may be NULL: default names by count). display: the display window (NULL = bounds). */
NPRFX_IO_API nprfx_result nprfx_io_write(nprfx_context *ctx, const char *path,
                                         const nprfx_image *im, const char *const *names,
                                         const nprfx_rect *display, const nprfx_write_options *opt);

/* An image written a strip of rows at a time, top to bottom: as nprfx_io_write (same header,
 * types and options, a temporary name beside path), but each nprfx_io_rows_write gives the next
 * rows (full width of bounds), and nprfx_io_rows_finish with keep renames the file into place
 * once every row is written; without keep (or on any error) the temporary file is removed. The
 * writer is freed by finish. */
NPRFX_IO_API nprfx_result nprfx_io_rows_create(nprfx_context *ctx, const char *path,
                                               nprfx_rect bounds, int channels,
                                               const char *const *names, const nprfx_rect *display,
                                               const nprfx_write_options *opt,
                                               nprfx_row_writer **out);
NPRFX_IO_API nprfx_result nprfx_io_rows_write(nprfx_context *ctx, nprfx_row_writer *w,
                                              const nprfx_image *rows);
NPRFX_IO_API nprfx_result nprfx_io_rows_finish(nprfx_context *ctx, nprfx_row_writer *w, int keep);

/* Write len bytes of text to path through a temporary name and a rename, creating missing
 * parent directories (vector exports: CSV, SVG). */
NPRFX_IO_API nprfx_result nprfx_io_write_text(nprfx_context *ctx, const char *path,
                                              const char *text, size_t len);

/* Write an 8-bit PNG preview of a scene-linear image. 1 channel: grey; 2: R,G (B = 0); 3: RGB;
 * 4: RGBA. With an OCIO config (ocio_config path, or $OCIO when NULL) the image goes from
 * `colorspace` (NULL: the config's scene_linear role) through display/view (NULL: the config's
 * defaults); with no config, the plain sRGB transfer function is applied. */
NPRFX_IO_API nprfx_result nprfx_io_write_preview(nprfx_context *ctx, const char *path,
                                                 const nprfx_image *im,
                                                 const nprfx_preview_options *opt);

/* Convert the first three channels of im in place from colour space `from` to `to` (names from
 * the OCIO config, or "linear"/"srgb" without one). Same names: no-op. */
NPRFX_IO_API nprfx_result nprfx_io_convert_colorspace(nprfx_context *ctx, nprfx_image *im,
                                                      const char *from, const char *to,
                                                      const char *ocio_config);

#ifdef __cplusplus
}
#endif
#endif
