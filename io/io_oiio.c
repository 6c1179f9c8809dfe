/* nprfx I/O — nprfx_io_oiio(): libnprfx-io's functions as the table the graph engine reads and
 * writes files through (nprfx/io.h). */
#include "nprfx/io_oiio.h"

static const nprfx_io table = {
    sizeof(nprfx_io),
    nprfx_io_read_ex,
    nprfx_io_rows_open,
    nprfx_io_rows_read,
    nprfx_io_rows_close,
    nprfx_io_info,
    nprfx_io_write,
    nprfx_io_rows_create,
    nprfx_io_rows_write,
    nprfx_io_rows_finish,
    nprfx_io_write_text,
    nprfx_io_write_preview,
    nprfx_io_convert_colorspace,
    nprfx_io_rows_note,
};

const nprfx_io *nprfx_io_oiio(void)
{
    return &table;
}
