/* The image-file adapter behind io.h: OpenImageIO for files, OpenColorIO for colour.
 *
 * This is the only C++ in the project. Every entry point is extern "C", catches every exception
 * (a C caller cannot unwind through it) and reports through nprfx_error, naming the file and,
 * where one is at fault, the channel. */
#include "io.h"
#include "io_validate.h"

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

namespace
{

/* OIIO keeps a per-thread error string; take it (and clear it) so it never leaks into a later,
 * unrelated message. */
std::string oiio_error(const ImageInput *in)
{
    std::string e = in ? in->geterror() : std::string();
    if (e.empty()) e = OIIO::geterror();
    return e.empty() ? std::string("unknown error") : e;
}

std::string oiio_error(const ImageOutput *out)
{
    std::string e = out ? out->geterror() : std::string();
    if (e.empty()) e = OIIO::geterror();
    return e.empty() ? std::string("unknown error") : e;
}

/* One subimage that takes part in a read: the specs of all parts whose data window matches the
 * first one's are concatenated; parts of another resolution (e.g. a proxy) are skipped. */
struct part {
    int index;
    ImageSpec spec;
    std::vector<std::string> names; /* final, file-unique channel names */
};

struct header {
    std::string format;
    int subimages = 0;
    std::vector<part> parts;
};

bool same_window(const ImageSpec &a, const ImageSpec &b)
{
    return a.x == b.x && a.y == b.y && a.width == b.width && a.height == b.height;
}

/* Open path and collect the parts a read will deliver, with unique channel names. Multi-part
 * EXRs often repeat bare names ("R" in every part); a repeated name gets its part's name as a
 * layer prefix so every channel stays addressable. */
nprfx_result scan(nprfx_context *ctx, const char *path, std::unique_ptr<ImageInput> &in, header &h)
{
    in = ImageInput::open(path);
    if (!in) {
        std::string e = OIIO::geterror();
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path,
                           e.empty() ? "unknown error" : e.c_str());
    }
    h.format = in->format_name();
    std::set<std::string> used;
    for (int s = 0; in->seek_subimage(s, 0); s++) {
        h.subimages++;
        ImageSpec spec = in->spec();
        if (spec.deep)
            return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                               "'%s' subimage %d holds deep pixels, which nprfx cannot read", path,
                               s);
        if (spec.depth > 1)
            return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                               "'%s' subimage %d is a volume (depth %d), which nprfx cannot read",
                               path, s, spec.depth);
        if (!h.parts.empty() && !same_window(spec, h.parts[0].spec)) continue;
        part p;
        p.index = s;
        std::string partname = spec.get_string_attribute("oiio:subimagename");
        for (int c = 0; c < spec.nchannels; c++) {
            std::string n = c < (int)spec.channelnames.size() ? spec.channelnames[c] : "";
            if (n.empty()) n = "channel" + std::to_string(c);
            if (used.count(n)) {
                std::string prefixed =
                    (partname.empty() ? "subimage" + std::to_string(s) : partname) + "." + n;
                for (int k = 2; used.count(prefixed); k++)
                    prefixed = (partname.empty() ? "subimage" + std::to_string(s) : partname) +
                               "." + n + "." + std::to_string(k);
                n = prefixed;
            }
            used.insert(n);
            p.names.push_back(n);
        }
        p.spec = spec;
        h.parts.push_back(std::move(p));
    }
    OIIO::geterror(); /* the failed seek past the last subimage leaves a message behind */
    in->geterror();
    if (h.parts.empty()) return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' holds no image", path);
    return NPRFX_OK;
}

nprfx_rect data_rect(const ImageSpec &s)
{
    return nprfx_rect_make(s.x, s.y, s.x + s.width, s.y + s.height);
}

nprfx_rect display_rect(const ImageSpec &s)
{
    return nprfx_rect_make(s.full_x, s.full_y, s.full_x + s.full_width, s.full_y + s.full_height);
}

char *dup_cstr(const std::string &s)
{
    char *r = static_cast<char *>(std::malloc(s.size() + 1));
    if (r) std::memcpy(r, s.c_str(), s.size() + 1);
    return r;
}

char **dup_names(const std::vector<std::string> &v)
{
    char **r = static_cast<char **>(std::calloc(v.size() ? v.size() : 1, sizeof(char *)));
    if (!r) return nullptr;
    for (size_t i = 0; i < v.size(); i++) {
        r[i] = dup_cstr(v[i]);
        if (!r[i]) {
            for (size_t j = 0; j < i; j++)
                std::free(r[j]);
            std::free(r);
            return nullptr;
        }
    }
    return r;
}

void copy_field(char *dst, size_t n, const std::string &s)
{
    std::snprintf(dst, n, "%s", s.c_str());
}

/* ---- writing ---------------------------------------------------------------------------- */

std::atomic<unsigned> temp_counter{0};

/* ".name.tmp-<pid>-<n>.ext" beside the target: same file system, so rename() is atomic, and the
 * extension is kept for anyone who inspects a leftover. The counter separates threads. */
std::string temp_path_for(const std::filesystem::path &target)
{
    std::string stem = target.stem().string(), ext = target.extension().string();
    std::string name = "." + stem + ".tmp-" + std::to_string((long)getpid()) + "-" +
                       std::to_string(temp_counter++) + ext;
    return (target.parent_path() / name).string();
}

bool valid_exr_compression(const std::string &c)
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
    if (target.has_parent_path()) {
        fs::create_directories(target.parent_path(), ec);
        if (ec)
            return nprfx_error(ctx, NPRFX_ERR_IO, "cannot create directory '%s' for '%s': %s",
                               target.parent_path().string().c_str(), path, ec.message().c_str());
    }
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

std::vector<std::string> default_names(int n)
{
    static const char *const rgba[] = {"R", "G", "B", "A"};
    std::vector<std::string> v;
    if (n == 1) return {"Y"}; /* OpenEXR's name for a single grey channel */
    for (int c = 0; c < n; c++)
        v.push_back(c < 4 ? rgba[c] : "channel" + std::to_string(c));
    return v;
}

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
float srgb_encode(float v)
{
    return v < 0.0f ? -srgb_oetf(-v) : srgb_oetf(v);
}

float srgb_decode(float v)
{
    float a = std::fabs(v);
    float r = a <= 0.04045f ? a / 12.92f : std::pow((a + 0.055f) / 1.055f, 2.4f);
    return v < 0.0f ? -r : r;
}

enum builtin_space { SPACE_UNKNOWN, SPACE_LINEAR, SPACE_SRGB };

builtin_space builtin_named(const char *n)
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

} // namespace

/* ---- reading ------------------------------------------------------------------------------ */

extern "C" nprfx_result nprfx_io_read(nprfx_context *ctx, const char *path, nprfx_plate *out)
{
    if (!out || !path)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_read: NULL argument");
    std::memset(out, 0, sizeof *out);
    /* Damaged files are refused before OIIO allocates anything (io_validate.h). */
    if (nprfx_result g = nprfx_io_guard(ctx, path, NPRFX_GUARD_READ)) return g;
    try {
        std::unique_ptr<ImageInput> in;
        header h;
        nprfx_result r = scan(ctx, path, in, h);
        if (r) return r;
        const ImageSpec &first = h.parts[0].spec;
        std::vector<std::string> names;
        for (const part &p : h.parts)
            names.insert(names.end(), p.names.begin(), p.names.end());
        size_t nch = names.size();
        size_t npix = (size_t)first.width * (size_t)first.height;
        if (nch == 0 || npix == 0)
            return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' holds an empty image (%dx%d, %zu channels)",
                               path, first.width, first.height, nch);
        if (npix > SIZE_MAX / sizeof(float) / nch)
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "'%s' is too large to read", path);
        float *pixels = static_cast<float *>(std::malloc(npix * nch * sizeof(float)));
        char **cnames = dup_names(names);
        if (!pixels || !cnames) {
            std::free(pixels);
            if (cnames)
                for (size_t i = 0; i < nch; i++)
                    std::free(cnames[i]);
            std::free(cnames);
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY,
                               "out of memory reading '%s' (%dx%d, %zu channels)", path,
                               first.width, first.height, nch);
        }
        out->bounds = data_rect(first);
        out->display = display_rect(first);
        out->nchannels = (int)nch;
        out->names = cnames;
        out->pixels = pixels;

        const OIIO::stride_t xstride = (OIIO::stride_t)(nch * sizeof(float));
        const OIIO::stride_t ystride = xstride * first.width;
        const bool exr = h.format == "openexr";
        std::vector<uint32_t> ubuf;
        size_t offset = 0;
        for (const part &p : h.parts) {
            const ImageSpec &s = p.spec;
            /* Runs of channels read in one call. EXR UINT channels (object ids) are read as
             * integers and cast, since a float read would normalise them to [0,1]. */
            for (int c0 = 0; c0 < s.nchannels;) {
                bool as_uint = exr && s.channelformat(c0) == TypeDesc::UINT;
                int c1 = c0 + 1;
                while (c1 < s.nchannels &&
                       (exr && s.channelformat(c1) == TypeDesc::UINT) == as_uint)
                    c1++;
                float *dst = pixels + offset + c0;
                bool ok;
                /* The read deadline (NPRFX_READ_TIMEOUT) stops OIIO between strips of rows. */
                if (!as_uint) {
                    ok = in->read_image(p.index, 0, c0, c1, TypeDesc::FLOAT, dst, xstride, ystride,
                                        OIIO::AutoStride, nprfx_io_read_progress, nullptr);
                } else {
                    int n = c1 - c0;
                    ubuf.resize(npix * (size_t)n);
                    ok = in->read_image(p.index, 0, c0, c1, TypeDesc::UINT, ubuf.data(),
                                        OIIO::AutoStride, OIIO::AutoStride, OIIO::AutoStride,
                                        nprfx_io_read_progress, nullptr);
                    for (size_t i = 0; ok && i < npix; i++)
                        for (int k = 0; k < n; k++)
                            dst[i * nch + k] = (float)ubuf[i * n + k];
                }
                if (nprfx_io_deadline_passed()) {
                    oiio_error(in.get());
                    nprfx_plate_free(out);
                    return nprfx_io_deadline_error(ctx, path);
                }
                if (!ok) {
                    std::string e = oiio_error(in.get());
                    nprfx_plate_free(out);
                    return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read channels %s..%s of '%s': %s",
                                       p.names[c0].c_str(), p.names[c1 - 1].c_str(), path,
                                       e.c_str());
                }
                c0 = c1;
            }
            offset += (size_t)s.nchannels;
        }
        in->close();
        return NPRFX_OK;
    } catch (const std::exception &e) {
        nprfx_plate_free(out);
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path, e.what());
    }
}

extern "C" nprfx_result nprfx_io_info(nprfx_context *ctx, const char *path, nprfx_file_info *out)
{
    if (!out || !path)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_info: NULL argument");
    std::memset(out, 0, sizeof *out);
    if (nprfx_result g = nprfx_io_guard(ctx, path, NPRFX_GUARD_HEADER)) return g;
    try {
        std::unique_ptr<ImageInput> in;
        header h;
        nprfx_result r = scan(ctx, path, in, h);
        if (r) return r;
        const ImageSpec &first = h.parts[0].spec;
        std::vector<std::string> names, types;
        for (const part &p : h.parts)
            for (int c = 0; c < p.spec.nchannels; c++) {
                names.push_back(p.names[c]);
                types.push_back(p.spec.channelformat(c).c_str());
            }
        copy_field(out->format, sizeof out->format, h.format);
        copy_field(out->compression, sizeof out->compression,
                   first.get_string_attribute("compression"));
        out->subimages = h.subimages;
        out->bounds = data_rect(first);
        out->display = display_rect(first);
        out->names = dup_names(names);
        out->types = dup_names(types);
        out->nchannels = (int)names.size();
        if (!out->names || !out->types) {
            nprfx_file_info_free(out);
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading '%s'", path);
        }
        in->close();
        return NPRFX_OK;
    } catch (const std::exception &e) {
        nprfx_file_info_free(out);
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path, e.what());
    }
}

extern "C" nprfx_result nprfx_io_read_attributes(nprfx_context *ctx, const char *path,
                                                 const char *prefix, char ***names,
                                                 char ***values, int *count)
{
    if (!path || !names || !values || !count)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_io_read_attributes: NULL argument");
    *names = *values = nullptr;
    *count = 0;
    if (nprfx_result g = nprfx_io_guard(ctx, path, NPRFX_GUARD_HEADER)) return g;
    try {
        std::unique_ptr<ImageInput> in = ImageInput::open(path);
        if (!in) {
            std::string e = OIIO::geterror();
            return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path,
                               e.empty() ? "unknown error" : e.c_str());
        }
        const ImageSpec &spec = in->spec();
        std::string pre = prefix ? prefix : "";
        std::vector<std::string> n, v;
        for (const OIIO::ParamValue &p : spec.extra_attribs) {
            std::string name = p.name().string();
            if (name.compare(0, pre.size(), pre) != 0) continue;
            n.push_back(name);
            v.push_back(spec.metadata_val(p)); /* strings come back quoted */
            std::string &s = v.back();
            if (p.type() == TypeDesc::STRING && s.size() >= 2 && s.front() == '"' &&
                s.back() == '"')
                s = s.substr(1, s.size() - 2);
        }
        in->close();
        *names = dup_names(n);
        *values = dup_names(v);
        if (!*names || !*values) {
            nprfx_attributes_free(*names, *values, (int)n.size());
            *names = *values = nullptr;
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading '%s'", path);
        }
        *count = (int)n.size();
        return NPRFX_OK;
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path, e.what());
    }
}

extern "C" void nprfx_attributes_free(char **names, char **values, int count)
{
    for (int i = 0; i < count; i++) {
        if (names) std::free(names[i]);
        if (values) std::free(values[i]);
    }
    std::free(names);
    std::free(values);
}

/* ---- writing ------------------------------------------------------------------------------ */

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
    /* Read only the option fields the caller's struct has (size-versioned). */
    nprfx_write_options o = {sizeof o, "zip", 0, nullptr, 0};
    if (opt) {
        if (opt->size < offsetof(nprfx_write_options, compression) + sizeof(const char *) ||
            opt->size > sizeof o)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "cannot write '%s': bad nprfx_write_options size %zu", path,
                               opt->size);
        std::memcpy(&o, opt, opt->size);
        if (!o.compression || !*o.compression) o.compression = "zip";
    }
    try {
        std::vector<std::string> cn;
        if (names) {
            std::set<std::string> seen;
            for (int c = 0; c < im->channels; c++) {
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
            cn = default_names(im->channels);
        }
        const int w = nprfx_rect_width(im->bounds), h = nprfx_rect_height(im->bounds);
        ImageSpec spec(w, h, im->channels, o.half ? TypeDesc::HALF : TypeDesc::FLOAT);
        spec.x = im->bounds.x0;
        spec.y = im->bounds.y0;
        nprfx_rect d = display ? *display : im->bounds;
        spec.full_x = d.x0;
        spec.full_y = d.y0;
        spec.full_width = nprfx_rect_width(d);
        spec.full_height = nprfx_rect_height(d);
        spec.channelnames = cn;
        spec.alpha_channel = -1;
        for (int c = 0; c < im->channels; c++)
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
                                       "cannot write '%s': attribute %s: '%s' is not an integer",
                                       path, a.name, a.value);
                spec.attribute(a.name, (int)v);
            } else if (a.type == NPRFX_ATTR_FLOAT) {
                float v = std::strtof(a.value, &end);
                if (end == a.value || *end)
                    return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                       "cannot write '%s': attribute %s: '%s' is not a number",
                                       path, a.name, a.value);
                spec.attribute(a.name, v);
            } else {
                spec.attribute(a.name, a.value);
            }
        }
        return write_atomic(ctx, path, spec, TypeDesc::FLOAT, im->data,
                            (OIIO::stride_t)(im->pixel_stride * (ptrdiff_t)sizeof(float)),
                            (OIIO::stride_t)(im->row_stride * (ptrdiff_t)sizeof(float)));
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write '%s': %s", path, e.what());
    }
}

/* ---- colour ------------------------------------------------------------------------------- */

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
        if (!o.raw && !*cfg_path) spec.attribute("oiio:ColorSpace", "sRGB");
        return write_atomic(ctx, path, spec, TypeDesc::UINT8, px.data(), OIIO::AutoStride,
                            OIIO::AutoStride);
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot write preview '%s': %s", path, e.what());
    }
}

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

extern "C" nprfx_result nprfx_io_write_text(nprfx_context *ctx, const char *path, const char *text,
                                            size_t len)
{
    namespace fs = std::filesystem;
    try {
        fs::path target(path);
        std::error_code ec;
        if (target.has_parent_path()) {
            fs::create_directories(target.parent_path(), ec);
            if (ec)
                return nprfx_error(ctx, NPRFX_ERR_IO, "cannot create directory '%s' for '%s': %s",
                                   target.parent_path().string().c_str(), path,
                                   ec.message().c_str());
        }
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
