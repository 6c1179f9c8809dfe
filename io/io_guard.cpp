/* nprfx I/O (libnprfx-io) — the guard every reader calls first (io_guard.h): EXRs through the
 * OpenEXRCore checks of io_validate.c, other formats by their header's size through OpenImageIO,
 * and the per-thread read deadline. C++ only because OpenImageIO is; like the readers and writers,
 * every entry point is extern "C" and catches every exception. */
#include "io_guard.h"
#include "io_validate.h"
#include "io_timeout.h"

#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>

#include <OpenImageIO/imageio.h>

#include "nprfx/io.h"

namespace
{

thread_local double read_deadline = 0; /* internal_io_now() time; 0: none */

/* OpenImageIO's own bounds, so that anything reaching it past the guard still meets a limit:
 * limits:imagesize_MB from NPRFX_READ_LIMIT (it counts native bytes, at most the float bytes the
 * guard bounds), limits:channels as the EXR check has it. */
void set_oiio_limits(uint64_t limit)
{
    static std::once_flag once;
    std::call_once(once, [limit] {
        if (limit != UINT64_MAX) {
            uint64_t mb = limit >> 20;
            OIIO::attribute("limits:imagesize_MB", (int)(mb > 0x7fffffff ? 0x7fffffff : mb));
        }
        OIIO::attribute("limits:channels", 1024);
    });
}

nprfx_result guard_other(nprfx_context *ctx, const char *path)
{
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) {
        OIIO::geterror(); /* the reader opens it again and reports in its own words */
        return NPRFX_OK;
    }
    /* What nprfx_io_read allocates: the float plate of every subimage of the first one's size
     * (the larger of that and any one subimage, so a huge later one is caught too). */
    int64_t w0 = 0, h0 = 0, channels = 0;
    for (int s = 0; s < 4096 && in->seek_subimage(s, 0); s++) {
        const OIIO::ImageSpec &spec = in->spec();
        if (s == 0) {
            w0 = spec.width;
            h0 = spec.height;
        }
        if (spec.width == w0 && spec.height == h0) {
            channels += spec.nchannels;
        } else {
            std::string what = std::string("'") + path + "': subimage " + std::to_string(s);
            nprfx_result r = nprfx_image_limit_check(
                ctx, what.c_str(), spec.width, spec.height,
                (int64_t)spec.nchannels * (spec.depth > 1 ? spec.depth : 1), 0);
            if (r) return r;
        }
    }
    OIIO::geterror();
    in->geterror();
    in->close();
    std::string what = std::string("'") + path + "': image";
    return nprfx_image_limit_check(ctx, what.c_str(), w0, h0, channels, 0);
}

} // namespace

extern "C" nprfx_result internal_io_guard(nprfx_context *ctx, const char *path, int mode)
{
    try {
        uint64_t limit;
        double timeout;
        nprfx_result r = nprfx_image_limit(ctx, &limit);
        if (!r) r = internal_io_read_timeout(ctx, &timeout);
        if (r) return r;
        set_oiio_limits(limit);
        double now = internal_io_now();
        read_deadline = timeout > 0 ? now + timeout : 0;
        internal_io_broken_reset();
        if (internal_io_is_exr(path))
            return internal_io_validate_exr(ctx, path, mode, read_deadline);
        /* Other formats decode every channel whatever a read keeps: all of them count. */
        if (mode != NPRFX_GUARD_HEADER) return guard_other(ctx, path);
        return NPRFX_OK;
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path, e.what());
    }
}

extern "C" int internal_io_deadline_passed(void)
{
    return read_deadline > 0 && internal_io_now() > read_deadline;
}

extern "C" bool internal_io_read_progress(void *user, float done)
{
    (void)user;
    (void)done;
    return internal_io_deadline_passed() != 0;
}

extern "C" nprfx_result internal_io_deadline_error(nprfx_context *ctx, const char *path)
{
    double timeout = 0;
    internal_io_read_timeout(nullptr, &timeout);
    return nprfx_error(ctx, NPRFX_ERR_IO,
                       "'%s': reading took longer than %g s and was stopped (NPRFX_READ_TIMEOUT)",
                       path, timeout);
}
