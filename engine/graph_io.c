/* nprfx graph engine — graph_io.h: the caller's nprfx_io, completed. */
#include "graph_io.h"

#include <stddef.h>
#include <string.h>

#define NO_IO(ctx, what)                                                                           \
    nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,                                                        \
                "no image I/O to " what ": the graph was loaded without an nprfx_io that can "     \
                "(nprfx_graph_options.io; libnprfx-io's nprfx_io_oiio() reads and writes files)")

static nprfx_result no_read(nprfx_context *ctx, const char *path, const nprfx_read_options *opt,
                            nprfx_plate *out)
{
    return NO_IO(ctx, "read a file");
}
static nprfx_result no_rows_open(nprfx_context *ctx, const char *path,
                                 const nprfx_read_options *opt, nprfx_plate *shape,
                                 nprfx_row_reader **out)
{
    return NO_IO(ctx, "read a file by rows");
}
static nprfx_result no_rows_read(nprfx_context *ctx, nprfx_row_reader *r, int y0, int y1,
                                 float *dst)
{
    return NO_IO(ctx, "read a file by rows");
}
static void no_rows_close(nprfx_row_reader *r) {}
static nprfx_result no_info(nprfx_context *ctx, const char *path, nprfx_file_info *out)
{
    return NO_IO(ctx, "read a file's header");
}
static nprfx_result no_write(nprfx_context *ctx, const char *path, const nprfx_image *im,
                             const char *const *names, const nprfx_rect *display,
                             const nprfx_write_options *opt)
{
    return NO_IO(ctx, "write a file");
}
static nprfx_result no_rows_create(nprfx_context *ctx, const char *path, nprfx_rect bounds,
                                   int channels, const char *const *names,
                                   const nprfx_rect *display, const nprfx_write_options *opt,
                                   nprfx_row_writer **out)
{
    return NO_IO(ctx, "write a file by rows");
}
static nprfx_result no_rows_write(nprfx_context *ctx, nprfx_row_writer *w, const nprfx_image *rows)
{
    return NO_IO(ctx, "write a file by rows");
}
static nprfx_result no_rows_finish(nprfx_context *ctx, nprfx_row_writer *w, int keep)
{
    return keep ? NO_IO(ctx, "write a file by rows") : NPRFX_OK;
}
static nprfx_result no_write_text(nprfx_context *ctx, const char *path, const char *text,
                                  size_t len)
{
    return NO_IO(ctx, "write a text file");
}
static nprfx_result no_write_preview(nprfx_context *ctx, const char *path, const nprfx_image *im,
                                     const nprfx_preview_options *opt)
{
    return NO_IO(ctx, "write a preview");
}
static nprfx_result no_rows_note(nprfx_context *ctx, nprfx_row_reader *r, char **note, int *warning)
{
    *note = NULL; /* the shape's note stands */
    *warning = 0;
    return NPRFX_OK;
}
static nprfx_result no_convert_colorspace(nprfx_context *ctx, nprfx_image *im, const char *from,
                                          const char *to, const char *ocio_config)
{
    return NO_IO(ctx, "convert colour spaces");
}

/* Take member m of io when io's size covers it and it is set. */
#define TAKE(m)                                                                                    \
    if (io && io->size >= offsetof(nprfx_io, m) + sizeof io->m && io->m) out->m = io->m

void internal_graph_io_init(nprfx_io *out, const nprfx_io *io)
{
    const nprfx_io none = {sizeof(nprfx_io),      no_read,        no_rows_open,  no_rows_read,
                           no_rows_close,         no_info,        no_write,      no_rows_create,
                           no_rows_write,         no_rows_finish, no_write_text, no_write_preview,
                           no_convert_colorspace, no_rows_note};
    *out = none;
    TAKE(read);
    TAKE(rows_open);
    TAKE(rows_read);
    TAKE(rows_close);
    TAKE(info);
    TAKE(write);
    TAKE(rows_create);
    TAKE(rows_write);
    TAKE(rows_finish);
    TAKE(write_text);
    TAKE(write_preview);
    TAKE(convert_colorspace);
    TAKE(rows_note);
}
