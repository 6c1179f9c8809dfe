/* nprfx CLI — 8-bit PNG previews of scene-linear images (io_preview.cpp). */
#ifndef NPRFX_CLI_IO_PREVIEW_H
#define NPRFX_CLI_IO_PREVIEW_H

#include <stddef.h>

#include "nprfx/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Write an 8-bit PNG preview of a scene-linear image. 1 channel: grey; 2: R,G (B = 0); 3: RGB;
 * 4: RGBA. With an OCIO config (ocio_config path, or $OCIO when NULL) the image goes from
 * `colorspace` (NULL: the config's scene_linear role) through display/view (NULL: the config's
 * defaults); with no config, the plain sRGB transfer function is applied. */
typedef struct cli_preview_options {
    size_t size;
    const char *ocio_config;
    const char *colorspace;
    const char *display;
    const char *view;
    int raw; /* 1: no transform at all (data passes: noise, masks), values clamped to [0,1] */
} cli_preview_options;
nprfx_result cli_io_write_preview(nprfx_context *ctx, const char *path, const nprfx_image *im,
                                  const cli_preview_options *opt);

#ifdef __cplusplus
}
#endif
#endif
