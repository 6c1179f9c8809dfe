/* nprfx I/O (libnprfx-io) — colour (OpenColorIO): conversions between colour spaces of a config, or the
 * built-in linear and sRGB without one, and the transfer functions previews use. */
#include "io_colour.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <strings.h>
#include <unistd.h>

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/imageio.h>

namespace OCIO = OCIO_NAMESPACE;
using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

namespace io_internal
{

enum builtin_space { SPACE_UNKNOWN, SPACE_LINEAR, SPACE_SRGB };

/* ---- colour ----------------------------------------------------------------------------- */

/* The config is loaded once per path and reused: the runner writes a preview per frame. */
nprfx_result load_config(nprfx_context *ctx, const char *config_path,
                         OCIO::ConstConfigRcPtr &config)
{
    static std::mutex lock;
    static std::string cached_path;
    static OCIO::ConstConfigRcPtr cached;
    std::lock_guard<std::mutex> guard(lock);
    if (cached && cached_path == config_path) {
        config = cached;
        return NPRFX_OK;
    }
    try {
        config = OCIO::Config::CreateFromFile(config_path);
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot load OCIO config '%s': %s", config_path,
                           e.what());
    }
    cached_path = config_path;
    cached = config;
    return NPRFX_OK;
}

/* The config to use: the explicit one, else $OCIO, else none (""). */
const char *config_path_or_env(const char *explicit_path)
{
    if (explicit_path && *explicit_path) return explicit_path;
    const char *env = std::getenv("OCIO");
    return env && *env ? env : "";
}

float srgb_oetf(float v)
{
    if (!(v > 0.0f)) return 0.0f; /* negatives and NaN: black */
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

/* Sign-symmetric transfer functions for conversion, so negative values survive a round trip
 * instead of turning into NaN. */
static float srgb_encode(float v)
{
    return v < 0.0f ? -srgb_oetf(-v) : srgb_oetf(v);
}

static float srgb_decode(float v)
{
    float a = std::fabs(v);
    float r = a <= 0.04045f ? a / 12.92f : std::pow((a + 0.055f) / 1.055f, 2.4f);
    return v < 0.0f ? -r : r;
}

static builtin_space builtin_named(const char *n)
{
    if (!strcasecmp(n, "linear") || !strcasecmp(n, "scene_linear")) return SPACE_LINEAR;
    if (!strcasecmp(n, "srgb")) return SPACE_SRGB;
    return SPACE_UNKNOWN;
}

uint8_t quantize(float v)
{
    if (!(v > 0.0f)) return 0;
    if (v >= 1.0f) return 255;
    return (uint8_t)std::lrintf(v * 255.0f);
}

} // namespace io_internal

using namespace io_internal;

extern "C" nprfx_result nprfx_io_convert_colorspace(nprfx_context *ctx, nprfx_image *im,
                                                    const char *from, const char *to,
                                                    const char *ocio_config)
{
    if (!im || !from || !to)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_io_convert_colorspace: NULL argument");
    if (!strcmp(from, to) || !im->data || nprfx_rect_empty(im->bounds)) return NPRFX_OK;
    try {
        const int w = nprfx_rect_width(im->bounds);
        const int nc = im->channels >= 3 ? 3 : im->channels;
        const char *cfg_path = config_path_or_env(ocio_config);
        if (!*cfg_path) {
            builtin_space f = builtin_named(from), t = builtin_named(to);
            if (f == SPACE_UNKNOWN || t == SPACE_UNKNOWN)
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "unknown colour space '%s' (without an OCIO config only "
                                   "'linear' and 'srgb' are known; give a config or set $OCIO)",
                                   f == SPACE_UNKNOWN ? from : to);
            if (f == t) return NPRFX_OK;
            for (int y = im->bounds.y0; y < im->bounds.y1; y++)
                for (int x = im->bounds.x0; x < im->bounds.x1; x++) {
                    float *p = nprfx_image_at(im, x, y);
                    for (int c = 0; c < nc; c++)
                        p[c] = f == SPACE_LINEAR ? srgb_encode(p[c]) : srgb_decode(p[c]);
                }
            return NPRFX_OK;
        }
        OCIO::ConstConfigRcPtr config;
        nprfx_result r = load_config(ctx, cfg_path, config);
        if (r) return r;
        for (const char *n : {from, to})
            if (!config->getColorSpace(n))
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "unknown colour space '%s' in OCIO config '%s'", n, cfg_path);
        OCIO::ConstCPUProcessorRcPtr cpu;
        try {
            cpu = config->getProcessor(from, to)->getDefaultCPUProcessor();
        } catch (const std::exception &e) {
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "OCIO config '%s' cannot convert '%s' to '%s': %s", cfg_path, from,
                               to, e.what());
        }
        /* Packed copy per row: the view may be strided or bottom-up. One channel is treated as
         * grey (replicated), two as R, G with B = 0; only the image's own channels are kept. */
        std::vector<float> row((size_t)w * 3);
        for (int y = im->bounds.y0; y < im->bounds.y1; y++) {
            for (int x = 0; x < w; x++) {
                const float *p = nprfx_image_at(im, im->bounds.x0 + x, y);
                for (int c = 0; c < 3; c++)
                    row[(size_t)x * 3 + c] = c < nc ? p[c] : nc == 1 ? p[0] : 0.0f;
            }
            OCIO::PackedImageDesc desc(row.data(), w, 1, 3);
            cpu->apply(desc);
            for (int x = 0; x < w; x++) {
                float *p = nprfx_image_at(im, im->bounds.x0 + x, y);
                for (int c = 0; c < nc; c++)
                    p[c] = row[(size_t)x * 3 + c];
            }
        }
        return NPRFX_OK;
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "colour conversion '%s' -> '%s' failed: %s",
                           from, to, e.what());
    }
}
