/* nprfx CLI — colour-space conversion (io_colour.cpp, OpenColorIO). */
#ifndef NPRFX_CLI_IO_COLOUR_H
#define NPRFX_CLI_IO_COLOUR_H

#include "io.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Convert the first three channels of im in place from colour space `from` to `to` (names from
 * the OCIO config, or "linear"/"srgb" without one). Same names: no-op. */
nprfx_result cli_io_convert_colorspace(nprfx_context *ctx, nprfx_image *im, const char *from,
                                       const char *to, const char *ocio_config);

#ifdef __cplusplus
}

#include <cstdint>

#include <OpenColorIO/OpenColorIO.h>

namespace OCIO = OCIO_NAMESPACE;

/* What previews share of the colour code (C++ only). */
namespace cli_io
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

} // namespace cli_io
#endif
#endif
