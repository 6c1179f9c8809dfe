/* nprfx I/O (libnprfx-io) — colour-space conversion (io_colour.cpp, OpenColorIO). */
#ifndef NPRFX_CLI_IO_COLOUR_H
#define NPRFX_CLI_IO_COLOUR_H

#include "nprfx/io_oiio.h"

#ifdef __cplusplus

#include <cstdint>

#include <OpenColorIO/OpenColorIO.h>

namespace OCIO = OCIO_NAMESPACE;

/* What previews share of the colour code (C++ only). */
namespace io_internal
{

/* The config at config_path, loaded once per path and reused (a preview per frame). */
nprfx_result load_config(nprfx_context *ctx, const char *config_path,
                         OCIO::ConstConfigRcPtr &config);
/* The config to use: the explicit one, else $OCIO, else none (""). */
const char *config_path_or_env(const char *explicit_path);
/* The sRGB transfer function (display encoding) of a linear value in [0, 1]. */
float srgb_oetf(float v);
/* A value in [0, 1] as an 8-bit code, rounded. */
uint8_t quantize(float v);

} // namespace io_internal
#endif
#endif
