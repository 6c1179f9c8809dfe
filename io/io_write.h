/* nprfx I/O (libnprfx-io) — writing image files, whole or a strip of rows at a time, and text files, through a
 * temporary name and a rename (io_write.cpp, OpenImageIO). */
#ifndef NPRFX_CLI_IO_WRITE_H
#define NPRFX_CLI_IO_WRITE_H

#include "nprfx/io_oiio.h"

#ifdef __cplusplus

#include <OpenImageIO/imageio.h>

/* What previews share of the writer (C++ only). */
namespace io_internal
{

/* Write pixels described by spec (data in `type`, with byte strides) to path through a temporary
 * name beside it and a rename, creating missing parent directories. */
nprfx_result write_atomic(nprfx_context *ctx, const char *path, OIIO::ImageSpec spec,
                          OIIO::TypeDesc type, const void *data, OIIO::stride_t xstride,
                          OIIO::stride_t ystride);

} // namespace io_internal
#endif
#endif
