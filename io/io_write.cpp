/* nprfx I/O (libnprfx-io) — writing image files (OpenImageIO): whole images and a strip of rows at
 * a time in the channels' own types, and text files; always through a temporary name beside the
 * target and a rename. Every entry point is extern "C", catches every exception and reports through
 * nprfx_error. */
#include "io_write.h"
#include "io_parts.h"
#include "nprfx/objectid.h"

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

/* ---- writing ---------------------------------------------------------------------------- */

static std::atomic<unsigned> temp_counter{0};

/* The folders above target (path as the caller named it, for the message), made when missing. */
static nprfx_result make_parent_dirs(nprfx_context *ctx, const std::filesystem::path &target,
                                     const char *path)
{
    std::error_code ec;
    if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path(), ec);
    if (ec)
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot create directory '%s' for '%s': %s",
                           target.parent_path().string().c_str(), path, ec.message().c_str());
    return NPRFX_OK;
}

/* ".name.tmp-<pid>-<n>.ext" beside the target: same file system, so rename() is atomic, and the
 * extension is kept for anyone who inspects a leftover. The counter separates threads. */
static std::string temp_path_for(const std::filesystem::path &target)
{
    std::string stem = target.stem().string(), ext = target.extension().string();
    std::string name = "." + stem + ".tmp-" + std::to_string((long)getpid()) + "-" +
                       std::to_string(temp_counter++) + ext;
    return (target.parent_path() / name).string();
}

static bool valid_exr_compression(const std::string &c)
{
    static const char *const known[] = {"none",  "rle", "zips", "zip",  "piz",
                                        "pxr24", "b44", "b44a", "dwaa", "dwab"};
    std::string base = c.substr(0, c.find(':'));
    for (const char *k : known)
        if (base == k) return true;
    return false;
}

/* Write pixels described by spec (data in `type`, with byte strides) to path through a
 * temporary file and rename(); the target is untouched unless the whole write succeeded. */
nprfx_result write_atomic(nprfx_context *ctx, const char *path, ImageSpec spec, TypeDesc type,
                          const void *data, OIIO::stride_t xstride, OIIO::stride_t ystride)
{
    namespace fs = std::filesystem;
    fs::path target(path);
    if (target.filename().empty())
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "cannot write '%s': not a file name",
                           path);
    std::error_code ec;
    if (nprfx_result r = make_parent_dirs(ctx, target, path)) return r;
    /* The format follows the target's extension, not the temporary name's. */
    std::unique_ptr<ImageOutput> out = ImageOutput::create(path);
    if (!out) {
        std::string e = OIIO::geterror();
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path,
                           e.empty() ? "no image format for this file extension" : e.c_str());
    }
    if (!out->supports("origin")) {
        spec.x = spec.y = 0;
    }
    if (!out->supports("displaywindow")) {
        spec.full_x = spec.x;
        spec.full_y = spec.y;
        spec.full_width = spec.width;
        spec.full_height = spec.height;
    }
    std::string tmp = temp_path_for(target);
    bool ok = out->open(tmp, spec) && out->write_image(type, data, xstride, ystride);
    std::string err = ok ? std::string() : oiio_error(out.get());
    bool closed = out->close();
    if (ok && !closed) {
        ok = false;
        err = oiio_error(out.get());
    }
    out.reset();
    if (ok && std::rename(tmp.c_str(), path) != 0) {
        ok = false;
        err = std::string("cannot rename the temporary file into place: ") + std::strerror(errno);
    }
    if (!ok) {
        fs::remove(tmp, ec);
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path, err.c_str());
    }
    return NPRFX_OK;
}

static std::vector<std::string> default_names(int n)
{
    static const char *const rgba[] = {"R", "G", "B", "A"};
    std::vector<std::string> v;
    if (n == 1) return {"Y"}; /* OpenEXR's name for a single grey channel */
    for (int c = 0; c < n; c++)
        v.push_back(c < 4 ? rgba[c] : "channel" + std::to_string(c));
    return v;
}

/* The options a caller passed, read as far as its struct's size reaches (size-versioned). */
static nprfx_result write_options(nprfx_context *ctx, const char *path,
                                  const nprfx_write_options *opt, nprfx_write_options &o)
{
    o = {sizeof o, "zip", 0, nullptr, 0, nullptr, 0.0f};
    if (opt) {
        if (opt->size < offsetof(nprfx_write_options, compression) + sizeof(const char *) ||
            opt->size > sizeof o)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "cannot write '%s': bad nprfx_write_options size %zu", path,
                               opt->size);
        std::memcpy(&o, opt, opt->size);
        if (!o.compression || !*o.compression) o.compression = "zip";
    }
    return NPRFX_OK;
}

/* The header of a write of `channels` channels over bounds, and the channels' own types when
 * they differ (formats empty: all float, or all half). */
static nprfx_result write_spec(nprfx_context *ctx, const char *path, nprfx_rect bounds,
                               int channels, const char *const *names, const nprfx_rect *display,
                               const nprfx_write_options &o, ImageSpec &spec,
                               std::vector<TypeDesc> &formats)
{
    std::vector<std::string> cn;
    if (names) {
        std::set<std::string> seen;
        for (int c = 0; c < channels; c++) {
            if (!names[c] || !*names[c])
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "cannot write '%s': channel %d has no name", path, c);
            if (!seen.insert(names[c]).second)
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "cannot write '%s': channel name '%s' appears twice", path,
                                   names[c]);
            cn.push_back(names[c]);
        }
    } else {
        cn = default_names(channels);
    }
    const int w = nprfx_rect_width(bounds), h = nprfx_rect_height(bounds);
    spec = ImageSpec(w, h, channels, o.half ? TypeDesc::HALF : TypeDesc::FLOAT);
    spec.x = bounds.x0;
    spec.y = bounds.y0;
    nprfx_rect d = display ? *display : bounds;
    spec.full_x = d.x0;
    spec.full_y = d.y0;
    spec.full_width = nprfx_rect_width(d);
    spec.full_height = nprfx_rect_height(d);
    spec.channelnames = cn;
    spec.alpha_channel = -1;
    for (int c = 0; c < channels; c++)
        if (cn[c] == "A" || cn[c] == "Alpha") spec.alpha_channel = c;
    std::string lower = std::filesystem::path(path).extension().string();
    for (char &ch : lower)
        ch = (char)std::tolower((unsigned char)ch);
    if (lower == ".exr" && !valid_exr_compression(o.compression))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "cannot write '%s': unknown EXR compression '%s' (none, rle, zips, "
                           "zip, piz, pxr24, b44, b44a, dwaa, dwab)",
                           path, o.compression);
    spec.attribute("compression", o.compression);
    for (int i = 0; o.attributes && i < o.nattributes; i++) {
        const nprfx_attribute &a = o.attributes[i];
        if (!a.name || !*a.name || !a.value)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "cannot write '%s': attribute %d has no name or value", path, i);
        char *end = nullptr;
        if (a.type == NPRFX_ATTR_INT) {
            long v = std::strtol(a.value, &end, 10);
            if (end == a.value || *end)
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "cannot write '%s': attribute %s: '%s' is not an integer", path,
                                   a.name, a.value);
            spec.attribute(a.name, (int)v);
        } else if (a.type == NPRFX_ATTR_FLOAT) {
            float v = std::strtof(a.value, &end);
            if (end == a.value || *end)
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "cannot write '%s': attribute %s: '%s' is not a number", path,
                                   a.name, a.value);
            spec.attribute(a.name, v);
        } else {
            spec.attribute(a.name, a.value);
        }
    }
    if (o.pixel_aspect > 0.0f) spec.attribute("PixelAspectRatio", o.pixel_aspect);
    bool mixed = false;
    for (int c = 0; o.types && c < channels; c++)
        mixed |= o.types[c] != NPRFX_PIXEL_FLOAT;
    formats.clear();
    if (!mixed) return NPRFX_OK;
    /* Channels of their own types (a copy keeps each channel's file type): the pixels go out in
     * those native types, since OIIO would scale floats into the full uint range. */
    for (int c = 0; c < channels; c++)
        formats.push_back(o.types[c] == NPRFX_PIXEL_UINT             ? TypeDesc::UINT
                          : o.types[c] == NPRFX_PIXEL_HALF || o.half ? TypeDesc::HALF
                                                                     : TypeDesc::FLOAT);
    spec.set_format(TypeDesc::FLOAT); /* the header's default; channelformats rule */
    spec.channelformats = formats;
    return NPRFX_OK;
}

/* im's pixels in the channels' native types (formats), packed: a uint channel holds ids, written
 * back as the uints they were read from (nprfx_id_to_uint). */
static void pack_native(const nprfx_image *im, const std::vector<TypeDesc> &formats,
                        std::vector<unsigned char> &buf)
{
    size_t bytes = 0;
    for (const TypeDesc &t : formats)
        bytes += t.size();
    buf.resize((size_t)nprfx_rect_width(im->bounds) * (size_t)nprfx_rect_height(im->bounds) *
               bytes);
    unsigned char *q = buf.data();
    for (int y = im->bounds.y0; y < im->bounds.y1; y++)
        for (int x = im->bounds.x0; x < im->bounds.x1; x++) {
            const float *p = nprfx_image_at(im, x, y);
            for (int c = 0; c < im->channels; c++) {
                float v = p[c];
                if (formats[c] == TypeDesc::UINT) {
                    uint32_t u = nprfx_id_to_uint(v);
                    std::memcpy(q, &u, 4);
                    q += 4;
                } else if (formats[c] == TypeDesc::HALF) {
                    OIIO::convert_pixel_values(TypeDesc::FLOAT, &v, TypeDesc::HALF, q, 1);
                    q += 2;
                } else {
                    std::memcpy(q, &v, 4);
                    q += 4;
                }
            }
        }
}

} // namespace io_internal

using namespace io_internal;

extern "C" nprfx_result nprfx_io_write(nprfx_context *ctx, const char *path, const nprfx_image *im,
                                       const char *const *names, const nprfx_rect *display,
                                       const nprfx_write_options *opt)
{
    if (!path || !im || !im->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "cannot write '%s': no image",
                           path ? path : "(null)");
    if (im->channels < 1 || nprfx_rect_empty(im->bounds))
        return nprfx_error(
            ctx, NPRFX_ERR_INVALID_ARGUMENT, "cannot write '%s': empty image (%dx%d, %d channels)",
            path, nprfx_rect_width(im->bounds), nprfx_rect_height(im->bounds), im->channels);
    nprfx_write_options o;
    if (nprfx_result r = write_options(ctx, path, opt, o)) return r;
    try {
        ImageSpec spec;
        std::vector<TypeDesc> formats;
        nprfx_result r =
            write_spec(ctx, path, im->bounds, im->channels, names, display, o, spec, formats);
        if (r) return r;
        if (formats.empty())
            return write_atomic(ctx, path, spec, TypeDesc::FLOAT, im->data,
                                (OIIO::stride_t)(im->pixel_stride * (ptrdiff_t)sizeof(float)),
                                (OIIO::stride_t)(im->row_stride * (ptrdiff_t)sizeof(float)));
        std::vector<unsigned char> buf;
        pack_native(im, formats, buf);
        return write_atomic(ctx, path, spec, TypeDesc::UNKNOWN, buf.data(), OIIO::AutoStride,
                            OIIO::AutoStride);
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path, e.what());
    }
}

struct nprfx_row_writer {
    std::string path, tmp;
    std::unique_ptr<ImageOutput> out;
    std::vector<TypeDesc> formats;
    std::vector<unsigned char> buf;
    nprfx_rect bounds;
    int next_y = 0,
        dy = 0; /* the next row to write; file row = row + dy (formats without origin) */
};

namespace
{

void rows_discard(nprfx_row_writer *w)
{
    if (w->out) w->out->close();
    w->out.reset();
    std::error_code ec;
    std::filesystem::remove(w->tmp, ec);
    delete w;
}

} // namespace

extern "C" nprfx_result nprfx_io_rows_create(nprfx_context *ctx, const char *path,
                                             nprfx_rect bounds, int channels,
                                             const char *const *names, const nprfx_rect *display,
                                             const nprfx_write_options *opt, nprfx_row_writer **out)
{
    namespace fs = std::filesystem;
    if (!path || !out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_rows_create: NULL argument");
    *out = nullptr;
    if (channels < 1 || nprfx_rect_empty(bounds))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "cannot write '%s': empty image (%dx%d, %d channels)", path,
                           nprfx_rect_width(bounds), nprfx_rect_height(bounds), channels);
    nprfx_write_options o;
    if (nprfx_result r = write_options(ctx, path, opt, o)) return r;
    try {
        std::unique_ptr<nprfx_row_writer> w(new nprfx_row_writer);
        ImageSpec spec;
        nprfx_result r =
            write_spec(ctx, path, bounds, channels, names, display, o, spec, w->formats);
        if (r) return r;
        fs::path target(path);
        if (target.filename().empty())
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "cannot write '%s': not a file name", path);
        if (nprfx_result r = make_parent_dirs(ctx, target, path)) return r;
        w->out = ImageOutput::create(path);
        if (!w->out) {
            std::string e = OIIO::geterror();
            return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path,
                               e.empty() ? "no image format for this file extension" : e.c_str());
        }
        if (!w->out->supports("origin")) spec.x = spec.y = 0;
        if (!w->out->supports("displaywindow")) {
            spec.full_x = spec.x;
            spec.full_y = spec.y;
            spec.full_width = spec.width;
            spec.full_height = spec.height;
        }
        w->path = path;
        w->tmp = temp_path_for(target);
        w->bounds = bounds;
        w->next_y = bounds.y0;
        w->dy = spec.y - bounds.y0;
        /* Written under a temporary name, renamed by nprfx_io_rows_finish (as every write). */
        if (!w->out->open(w->tmp, spec)) {
            std::string e = oiio_error(w->out.get());
            rows_discard(w.release());
            return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path, e.c_str());
        }
        *out = w.release();
        return NPRFX_OK;
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path, e.what());
    }
}

extern "C" nprfx_result nprfx_io_rows_write(nprfx_context *ctx, nprfx_row_writer *w,
                                            const nprfx_image *rows)
{
    if (!w || !rows || !rows->data)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_rows_write: NULL argument");
    const nprfx_rect b = rows->bounds;
    if (b.x0 != w->bounds.x0 || b.x1 != w->bounds.x1 || b.y0 != w->next_y || b.y1 > w->bounds.y1 ||
        b.y1 <= b.y0)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "cannot write '%s': rows %d..%d of x %d..%d come out of order (next: "
                           "row %d of x %d..%d)",
                           w->path.c_str(), b.y0, b.y1, b.x0, b.x1, w->next_y, w->bounds.x0,
                           w->bounds.x1);
    try {
        bool ok;
        if (w->formats.empty()) {
            ok = w->out->write_scanlines(
                b.y0 + w->dy, b.y1 + w->dy, 0, TypeDesc::FLOAT, nprfx_image_at(rows, b.x0, b.y0),
                (OIIO::stride_t)(rows->pixel_stride * (ptrdiff_t)sizeof(float)),
                (OIIO::stride_t)(rows->row_stride * (ptrdiff_t)sizeof(float)));
        } else {
            pack_native(rows, w->formats, w->buf);
            ok = w->out->write_scanlines(b.y0 + w->dy, b.y1 + w->dy, 0, TypeDesc::UNKNOWN,
                                         w->buf.data());
        }
        if (!ok)
            return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", w->path.c_str(),
                               oiio_error(w->out.get()).c_str());
        w->next_y = b.y1;
        return NPRFX_OK;
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", w->path.c_str(), e.what());
    }
}

extern "C" nprfx_result nprfx_io_rows_finish(nprfx_context *ctx, nprfx_row_writer *w, int keep)
{
    if (!w) return NPRFX_OK;
    if (!keep || w->next_y != w->bounds.y1) {
        rows_discard(w);
        return keep
                   ? nprfx_error(ctx, NPRFX_ERR_INTERNAL, "a strip write ended before its last row")
                   : NPRFX_OK;
    }
    std::string path = w->path, err;
    try {
        bool ok = w->out->close();
        if (!ok) err = oiio_error(w->out.get());
        w->out.reset();
        if (ok && std::rename(w->tmp.c_str(), path.c_str()) != 0)
            err =
                std::string("cannot rename the temporary file into place: ") + std::strerror(errno);
    } catch (const std::exception &e) {
        err = e.what();
    }
    if (err.empty()) {
        delete w;
        return NPRFX_OK;
    }
    rows_discard(w);
    return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path.c_str(), err.c_str());
}

extern "C" nprfx_result nprfx_io_write_text(nprfx_context *ctx, const char *path, const char *text,
                                            size_t len)
{
    namespace fs = std::filesystem;
    try {
        fs::path target(path);
        std::error_code ec;
        if (nprfx_result r = make_parent_dirs(ctx, target, path)) return r;
        std::string tmp = temp_path_for(target);
        FILE *f = std::fopen(tmp.c_str(), "wb");
        bool ok = f && std::fwrite(text, 1, len, f) == len;
        if (f && std::fclose(f) != 0) ok = false;
        if (ok && std::rename(tmp.c_str(), path) != 0) ok = false;
        if (!ok) {
            std::string err = std::strerror(errno);
            fs::remove(tmp, ec);
            return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path, err.c_str());
        }
        return NPRFX_OK;
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path, e.what());
    }
}
