/* nprfx I/O (libnprfx-io) — 8-bit PNG previews of scene-linear images, through an OCIO display and
 * view or the sRGB transfer function. */
#include "nprfx/io_oiio.h"
#include "io_colour.h"
#include "io_write.h"

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

using namespace io_internal;

extern "C" nprfx_result nprfx_io_write_preview(nprfx_context *ctx, const char *path,
                                               const nprfx_image *im,
                                               const nprfx_preview_options *opt)
{
    if (!path || !im || !im->data || im->channels < 1 || nprfx_rect_empty(im->bounds))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "cannot write preview '%s': no image",
                           path ? path : "(null)");
    nprfx_preview_options o;
    std::memset(&o, 0, sizeof o);
    o.size = sizeof o;
    if (opt) {
        if (opt->size < sizeof(size_t) || opt->size > sizeof o)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "cannot write preview '%s': bad nprfx_preview_options size %zu",
                               path, opt->size);
        std::memcpy(&o, opt, opt->size);
    }
    try {
        const int w = nprfx_rect_width(im->bounds), h = nprfx_rect_height(im->bounds);
        const size_t npix = (size_t)w * (size_t)h;
        const int inch = im->channels > 4 ? 4 : im->channels; /* more than 4: the first four */
        const int outch = inch == 2 ? 3 : inch;
        const bool alpha = inch == 4;

        /* Gather RGB (grey replicated; B = 0 for two channels) and alpha, packed. Colour is
         * un-premultiplied while still linear: PNG stores unassociated alpha. */
        std::vector<float> rgb(npix * 3), a(alpha ? npix : 0);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                const float *p = nprfx_image_at(im, im->bounds.x0 + x, im->bounds.y0 + y);
                float *q = &rgb[((size_t)y * w + x) * 3];
                if (inch == 1) {
                    q[0] = q[1] = q[2] = p[0];
                } else {
                    q[0] = p[0];
                    q[1] = p[1];
                    q[2] = inch >= 3 ? p[2] : 0.0f;
                }
                if (alpha) {
                    float av = p[3];
                    a[(size_t)y * w + x] = av;
                    if (!o.raw && av > 0.0f && av != 1.0f)
                        for (int c = 0; c < 3; c++)
                            q[c] /= av;
                }
            }

        const char *cfg_path = o.raw ? "" : config_path_or_env(o.ocio_config);
        if (o.raw) {
            /* data passes through unchanged, only clamped below */
        } else if (*cfg_path) {
            OCIO::ConstConfigRcPtr config;
            nprfx_result r = load_config(ctx, cfg_path, config);
            if (r) return r;
            const char *cs = o.colorspace ? o.colorspace : OCIO::ROLE_SCENE_LINEAR;
            const char *disp = o.display ? o.display : config->getDefaultDisplay();
            const char *view = o.view ? o.view : config->getDefaultView(disp);
            OCIO::ConstCPUProcessorRcPtr cpu;
            try {
                cpu = config->getProcessor(cs, disp, view, OCIO::TRANSFORM_DIR_FORWARD)
                          ->getDefaultCPUProcessor();
            } catch (const std::exception &e) {
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "cannot write preview '%s': OCIO config '%s' cannot go from "
                                   "colour space '%s' to display '%s' view '%s': %s",
                                   path, cfg_path, cs, disp, view, e.what());
            }
            OCIO::PackedImageDesc desc(rgb.data(), w, h, 3);
            cpu->apply(desc);
        } else {
            for (float &v : rgb)
                v = srgb_oetf(v);
        }

        std::vector<uint8_t> px(npix * (size_t)outch);
        for (size_t i = 0; i < npix; i++) {
            uint8_t *q = &px[i * outch];
            const float *c = &rgb[i * 3];
            if (outch == 1) {
                q[0] = quantize((c[0] + c[1] + c[2]) * (1.0f / 3.0f));
            } else {
                q[0] = quantize(c[0]);
                q[1] = quantize(c[1]);
                q[2] = quantize(c[2]);
                if (alpha) q[3] = quantize(a[i]); /* alpha stays linear */
            }
        }
        ImageSpec spec(w, h, outch, TypeDesc::UINT8);
        spec.alpha_channel = alpha ? 3 : -1;
        /* Already unassociated (or raw data): stop OIIO from un-premultiplying a second time. */
        spec.attribute("oiio:UnassociatedAlpha", 1);
        /* zlib's fastest level: a preview is for looking at, and at the default level (6) its
         * compression took most of a frame's write (the coloured pencil's 1080p RGBA preview:
         * 4.45 MB instead of 4.25, in about half the time) */
        spec.attribute("png:compressionLevel", 1);
        if (!o.raw && !*cfg_path) spec.attribute("oiio:ColorSpace", "sRGB");
        return write_atomic(ctx, path, spec, TypeDesc::UINT8, px.data(), OIIO::AutoStride,
                            OIIO::AutoStride);
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write preview '%s': %s", path, e.what());
    }
}
