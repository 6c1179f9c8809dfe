/* nprfx I/O (libnprfx-io) — reading image files (OpenImageIO): whole plates, the channels a caller
 * picks, a strip of rows at a time, header facts for nprfx info and attributes. Every entry point
 * is extern "C", catches every exception (a C caller cannot unwind through it) and reports through
 * nprfx_error, naming the file and, where one is at fault, the channel. */
#include "nprfx/io_oiio.h"
#include "io_guard.h"
#include "nprfx/io.h"
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
#include <Imath/half.h>
#include <OpenImageIO/imageio.h>

namespace OCIO = OCIO_NAMESPACE;
using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

namespace io_internal
{

/* ---- reading ------------------------------------------------------------------------------ */

/* The options a caller passed, read as far as its struct's size reaches (size-versioned). */
static nprfx_read_options read_options(const nprfx_read_options *opt)
{
    nprfx_read_options o;
    std::memset(&o, 0, sizeof o);
    o.size = sizeof o;
    if (opt && opt->size >= sizeof(size_t))
        std::memcpy(&o, opt, opt->size < sizeof o ? opt->size : sizeof o);
    return o;
}

/* Rows an EXR part stores per chunk (a tile's height when tiled): reads in blocks of whole chunks
 * decode each chunk once. From the compression, as OpenEXR defines it. */
static int chunk_rows(const part &p)
{
    if (p.spec.tile_width > 0 && p.spec.tile_height > 0) return p.spec.tile_height;
    std::string c = p.spec.get_string_attribute("compression");
    c = c.substr(0, c.find(':'));
    if (c.empty() || c == "none" || c == "rle" || c == "zips") return 1;
    if (c == "zip" || c == "pxr24") return 16;
    if (c == "dwab") return 256;
    return 32; /* piz, b44, b44a, dwaa */
}

/* Rows a block read of part p decodes at once: at least 64 (fewer calls), whole chunks. */
static int block_rows(const part &p)
{
    int cr = chunk_rows(p);
    return cr >= 64 ? cr : (64 + cr - 1) / cr * cr;
}

/* An open read: the file, the parts and view chosen, and the channels it delivers. */
struct reading {
    std::string path;
    std::unique_ptr<ImageInput> in;
    header h;
    choice ch;
    std::vector<chan> sel; /* what the read delivers, in order: ch.chans or the caller's choice */
    bool chosen = false;   /* the caller named or picked the channels */
    /* EXR with chosen channels: decoded a block of whole chunks at a time, converting only the
     * span between a part's first and last delivered channel, so no more than the delivered
     * channels and one block is ever held; any rows can be read (strip renders). */
    bool blocks = false;
    std::vector<float> fbuf;
    std::vector<uint32_t> ubuf;
    std::vector<Imath::half> hbuf;
};

/* The spans [lo, hi] of the delivered float (or half) and uint channels of part p; -1: none. */
static void part_spans(const reading &rd, const part *p, int &flo, int &fhi, int &ulo, int &uhi)
{
    flo = fhi = ulo = uhi = -1;
    for (const chan &c : rd.sel) {
        if (c.p != p) continue;
        int &lo = c.type == NPRFX_PIXEL_UINT ? ulo : flo,
            &hi = c.type == NPRFX_PIXEL_UINT ? uhi : fhi;
        if (lo < 0 || c.c < lo) lo = c.c;
        if (hi < 0 || c.c > hi) hi = c.c;
    }
}

/* Guard, header, choice of parts and view, and the channels to deliver: everything but pixels. */
static nprfx_result open_reading(nprfx_context *ctx, const char *path, const nprfx_read_options &o,
                                 reading &rd, bool rows = false)
{
    rd.path = path;
    rd.chosen = o.channels || o.pick || rows;
    /* Damaged files are refused before OIIO allocates anything (io_validate.h). A read of chosen
     * channels is held to the memory limit by what it delivers, checked once they are known. */
    if (nprfx_result g =
            internal_io_guard(ctx, path, rd.chosen ? NPRFX_GUARD_READ_CHOSEN : NPRFX_GUARD_READ))
        return g;
    nprfx_result r = scan(ctx, path, rd.in, rd.h);
    if (r) return r;
    failure f = choose(path, rd.h, o, rd.ch);
    if (f.code) return nprfx_error(ctx, f.code, "%s", f.message.c_str());
    const std::string where = part_label(*rd.ch.group[0]) + " of '" + path + "'";
    rd.sel = rd.ch.chans;
    if (o.channels) {
        std::vector<chan> sel;
        std::set<std::string> seen;
        for (int i = 0; i < o.nchannels; i++) {
            const char *want = o.channels[i] ? o.channels[i] : "";
            auto it = std::find_if(rd.ch.chans.begin(), rd.ch.chans.end(),
                                   [&](const chan &c) { return c.name == want; });
            if (it == rd.ch.chans.end())
                return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "%s has no channel '%s'",
                                   where.c_str(), want);
            if (!seen.insert(want).second)
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "reading %s: channel '%s' is asked for twice", where.c_str(),
                                   want);
            sel.push_back(*it);
        }
        if (sel.empty())
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "reading %s: an empty list of channels", where.c_str());
        rd.sel = sel;
    } else if (o.pick) {
        std::vector<const char *> names;
        for (const chan &c : rd.ch.chans)
            names.push_back(c.name.c_str());
        std::vector<int> idx(names.size());
        int k = o.pick(o.pick_user, names.data(), (int)names.size(), idx.data());
        if (k > 0 && k <= (int)names.size()) {
            std::vector<char> used(names.size(), 0);
            std::vector<chan> sel;
            for (int i = 0; i < k; i++) {
                if (idx[i] < 0 || idx[i] >= (int)names.size() || used[(size_t)idx[i]])
                    return nprfx_error(ctx, NPRFX_ERR_INTERNAL,
                                       "reading %s: channel choice %d of %d is %d", where.c_str(),
                                       i, k, idx[i]);
                used[(size_t)idx[i]] = 1;
                sel.push_back(rd.ch.chans[(size_t)idx[i]]);
            }
            rd.sel = sel;
        }
    }
    const ImageSpec &first = rd.ch.group[0]->spec;
    const size_t nch = rd.sel.size();
    if ((size_t)first.width * (size_t)first.height == 0)
        return nprfx_error(ctx, NPRFX_ERR_IO, "%s holds an empty image (%dx%d, %zu channels)",
                           where.c_str(), first.width, first.height, nch);
    rd.blocks = rd.chosen && rd.h.format == "openexr";
    if (rows && !rd.blocks)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "'%s' is %s: only EXR files can be read a strip of rows at a time", path,
                           rd.h.format.c_str());
    if (rd.chosen) {
        /* What this read allocates: its channels, and one block per part (or the uint scratch
         * of a read by channel runs); a read by rows only the blocks (the caller holds its rows).
         */
        uint64_t scratch = 0;
        int block_h = 0, block_ch = 0;
        for (const part *p : rd.ch.group) {
            int flo, fhi, ulo, uhi;
            part_spans(rd, p, flo, fhi, ulo, uhi);
            int span = (flo < 0 ? 0 : fhi - flo + 1) + (ulo < 0 ? 0 : uhi - ulo + 1);
            int h = rd.blocks ? block_rows(*p) : (ulo < 0 ? 0 : first.height);
            uint64_t b = (uint64_t)h * (uint64_t)first.width * (uint64_t)span * 4u;
            if (b > scratch) {
                scratch = b;
                block_h = h;
                block_ch = span;
            }
        }
        std::string what =
            "'" + std::string(path) + (rows ? "': a block of rows" : "': data window");
        if ((r = rows
                     ? nprfx_image_limit_check(ctx, what.c_str(), first.width, block_h, block_ch, 0)
                     : nprfx_image_limit_check(ctx, what.c_str(), first.width, first.height,
                                               (int64_t)nch, scratch)))
            return r;
    }
    return NPRFX_OK;
}

static nprfx_result channels_error(nprfx_context *ctx, const reading &rd, const chan &a,
                                   const chan &b)
{
    std::string e = oiio_error(rd.in.get());
    return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read channels %s..%s of %s of '%s': %s",
                       a.name.c_str(), b.name.c_str(), part_label(*a.p).c_str(), rd.path.c_str(),
                       e.c_str());
}

/* Rows [y0, y1) of the delivered channels into dst (all of them per pixel, rows of the data
 * window's width, row y0 first), part by part, a block of whole chunks at a time. */
static nprfx_result read_blocks(nprfx_context *ctx, reading &rd, int y0, int y1, float *dst)
{
    const ImageSpec &first = rd.ch.group[0]->spec;
    const size_t w = (size_t)first.width, nsel = rd.sel.size();
    for (const part *p : rd.ch.group) {
        int flo, fhi, ulo, uhi;
        part_spans(rd, p, flo, fhi, ulo, uhi);
        if (flo < 0 && ulo < 0) continue;
        const int step = block_rows(*p), py0 = p->spec.y, py1 = p->spec.y + p->spec.height;
        for (int by = py0 + (y0 - py0) / step * step; by < y1; by += step) {
            const int be = std::min(by + step, py1), r0 = std::max(by, y0), r1 = std::min(be, y1);
            for (int as_uint = 0; as_uint < 2; as_uint++) {
                const int lo = as_uint ? ulo : flo, hi = as_uint ? uhi : fhi, n = hi - lo + 1;
                if (lo < 0) continue;
                const size_t count = (size_t)(be - by) * w * (size_t)n;
                /* A span of channels of one type is read as it is stored (TypeDesc::UNKNOWN)
                 * and widened here: asked for a type, or for a subset of the channels, OIIO
                 * converts through a buffer of its own, tens of megabytes allocated (and their
                 * pages faulted in) at every call. A span of mixed types is converted by OIIO.
                 * EXR uint channels (object ids) are read as integers and turned into ids
                 * (nprfx/objectid.h), since a float read would normalise them to [0,1]. */
                const TypeDesc want = as_uint ? TypeDesc::UINT : TypeDesc::FLOAT;
                const TypeDesc stored = p->spec.channelformat(lo);
                bool uniform = true;
                for (int c = lo + 1; uniform && c <= hi; c++)
                    uniform = p->spec.channelformat(c) == stored;
                const bool half = uniform && !as_uint && stored == TypeDesc::HALF;
                const bool native = half || (uniform && stored == want);
                void *buf;
                if (as_uint) {
                    rd.ubuf.resize(count);
                    buf = rd.ubuf.data();
                } else if (half) {
                    rd.hbuf.resize(count);
                    buf = rd.hbuf.data();
                } else {
                    rd.fbuf.resize(count);
                    buf = rd.fbuf.data();
                }
                const TypeDesc type = native ? TypeDesc::UNKNOWN : want;
                bool ok =
                    p->spec.tile_width > 0
                        ? rd.in->read_tiles(p->index, 0, p->spec.x, p->spec.x + p->spec.width, by,
                                            be, 0, 1, lo, hi + 1, type, buf)
                        : rd.in->read_scanlines(p->index, 0, by, be, 0, lo, hi + 1, type, buf);
                if (internal_io_deadline_passed()) {
                    oiio_error(rd.in.get());
                    return internal_io_deadline_error(ctx, rd.path.c_str());
                }
                const chan *a = nullptr, *b = nullptr;
                for (const chan &c : rd.sel)
                    if (c.p == p && (c.type == NPRFX_PIXEL_UINT) == (as_uint != 0)) {
                        if (!a) a = &c;
                        b = &c;
                    }
                if (!ok) return channels_error(ctx, rd, *a, *b);
                for (size_t k = 0; k < nsel; k++) {
                    const chan &c = rd.sel[k];
                    if (c.p != p || (c.type == NPRFX_PIXEL_UINT) != (as_uint != 0)) continue;
                    for (int y = r0; y < r1; y++) {
                        const size_t src = ((size_t)(y - by) * w) * (size_t)n + (size_t)(c.c - lo);
                        float *d = dst + (size_t)(y - y0) * w * nsel + k;
                        if (as_uint) {
                            const uint32_t *s = rd.ubuf.data() + src;
                            for (size_t x = 0; x < w; x++)
                                d[x * nsel] = nprfx_id_from_uint(s[x * (size_t)n]);
                        } else if (half) {
                            const Imath::half *s = rd.hbuf.data() + src;
                            for (size_t x = 0; x < w; x++)
                                d[x * nsel] = (float)s[x * (size_t)n];
                        } else {
                            const float *s = rd.fbuf.data() + src;
                            for (size_t x = 0; x < w; x++)
                                d[x * nsel] = s[x * (size_t)n];
                        }
                    }
                }
            }
        }
    }
    return NPRFX_OK;
}

/* The whole plate of the delivered channels into dst, a read_image per run of adjacent file
 * channels of one part and kind (any format; tiled and MIP-mapped parts at level 0). */
static nprfx_result read_runs(nprfx_context *ctx, reading &rd, float *dst)
{
    const ImageSpec &first = rd.ch.group[0]->spec;
    const size_t nch = rd.sel.size(), npix = (size_t)first.width * (size_t)first.height;
    const OIIO::stride_t xstride = (OIIO::stride_t)(nch * sizeof(float));
    const OIIO::stride_t ystride = xstride * first.width;
    for (size_t k0 = 0; k0 < nch;) {
        const chan &a = rd.sel[k0];
        const bool as_uint = a.type == NPRFX_PIXEL_UINT;
        size_t k1 = k0 + 1;
        while (k1 < nch && rd.sel[k1].p == a.p && rd.sel[k1].c == a.c + (int)(k1 - k0) &&
               (rd.sel[k1].type == NPRFX_PIXEL_UINT) == as_uint)
            k1++;
        const int c0 = a.c, c1 = a.c + (int)(k1 - k0), n = c1 - c0;
        float *d = dst + k0;
        bool ok;
        if (!as_uint) {
            /* The read deadline (NPRFX_READ_TIMEOUT) stops OIIO between strips of rows. */
            ok = rd.in->read_image(a.p->index, 0, c0, c1, TypeDesc::FLOAT, d, xstride, ystride,
                                   OIIO::AutoStride, internal_io_read_progress, nullptr);
        } else {
            rd.ubuf.resize(npix * (size_t)n);
            ok = rd.in->read_image(a.p->index, 0, c0, c1, TypeDesc::UINT, rd.ubuf.data(),
                                   OIIO::AutoStride, OIIO::AutoStride, OIIO::AutoStride,
                                   internal_io_read_progress, nullptr);
            for (size_t i = 0; ok && i < npix; i++)
                for (int j = 0; j < n; j++)
                    d[i * nch + j] = nprfx_id_from_uint(rd.ubuf[i * n + j]);
        }
        if (internal_io_deadline_passed()) {
            oiio_error(rd.in.get());
            return internal_io_deadline_error(ctx, rd.path.c_str());
        }
        if (!ok) return channels_error(ctx, rd, rd.sel[k0], rd.sel[k1 - 1]);
        k0 = k1;
    }
    return NPRFX_OK;
}

/* out's description of the plate (everything but pixels) and the read's note: which parts and
 * view, and uint values float cannot hold (once the pixels are read). */
static nprfx_result describe(nprfx_context *ctx, const reading &rd, nprfx_plate *out)
{
    const ImageSpec &first = rd.ch.group[0]->spec;
    std::vector<std::string> names;
    for (const chan &c : rd.sel)
        names.push_back(c.name);
    const size_t nch = names.size();
    out->types = static_cast<unsigned char *>(std::malloc(nch));
    out->names = dup_names(names);
    out->nchannels = out->names ? (int)nch : 0;
    if (!out->names || !out->types) {
        nprfx_plate_free(out);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading '%s'",
                           rd.path.c_str());
    }
    out->bounds = data_rect(first);
    out->display = display_rect(first);
    out->pixel_aspect = first.get_float_attribute("PixelAspectRatio", 1.0f);
    for (size_t k = 0; k < nch; k++)
        out->types[k] = rd.sel[k].type;
    return NPRFX_OK;
}

static nprfx_result set_note(nprfx_context *ctx, const reading &rd, nprfx_plate *out)
{
    const std::string &note = rd.ch.note;
    const bool warn = rd.ch.warn;
    std::free(out->note);
    out->note = nullptr;
    if (!note.empty()) {
        out->note = dup_cstr(note);
        if (!out->note)
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory reading '%s'",
                               rd.path.c_str());
        out->note_is_warning = warn;
    }
    return NPRFX_OK;
}

} // namespace io_internal

using namespace io_internal;

extern "C" nprfx_result nprfx_io_read_ex(nprfx_context *ctx, const char *path,
                                         const nprfx_read_options *opt, nprfx_plate *out)
{
    if (!out || !path)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_read: NULL argument");
    std::memset(out, 0, sizeof *out);
    const nprfx_read_options o = read_options(opt);
    try {
        reading rd;
        nprfx_result r = open_reading(ctx, path, o, rd);
        if (r) return r;
        const ImageSpec &first = rd.ch.group[0]->spec;
        const size_t nch = rd.sel.size(), npix = (size_t)first.width * (size_t)first.height;
        const std::string where = part_label(*rd.ch.group[0]) + " of '" + path + "'";
        if (npix > SIZE_MAX / sizeof(float) / nch)
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "%s is too large to read",
                               where.c_str());
        if ((r = describe(ctx, rd, out))) return r;
        out->pixels = static_cast<float *>(std::malloc(npix * nch * sizeof(float)));
        if (!out->pixels) {
            nprfx_plate_free(out);
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY,
                               "out of memory reading %s (%dx%d, %zu channels)", where.c_str(),
                               first.width, first.height, nch);
        }
        r = rd.blocks ? read_blocks(ctx, rd, out->bounds.y0, out->bounds.y1, out->pixels)
                      : read_runs(ctx, rd, out->pixels);
        if (!r) r = set_note(ctx, rd, out);
        if (r) {
            nprfx_plate_free(out);
            return r;
        }
        rd.in->close();
        return NPRFX_OK;
    } catch (const std::exception &e) {
        nprfx_plate_free(out);
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path, e.what());
    }
}

extern "C" nprfx_result nprfx_io_read(nprfx_context *ctx, const char *path, nprfx_plate *out)
{
    return nprfx_io_read_ex(ctx, path, nullptr, out);
}

extern "C" nprfx_result nprfx_io_info(nprfx_context *ctx, const char *path, nprfx_file_info *out)
{
    if (!out || !path)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_info: NULL argument");
    std::memset(out, 0, sizeof *out);
    if (nprfx_result g = internal_io_guard(ctx, path, NPRFX_GUARD_HEADER)) return g;
    try {
        std::unique_ptr<ImageInput> in;
        header h;
        nprfx_result r = scan(ctx, path, in, h);
        if (r) return r;
        /* What a default read takes; a file no read can take (deep only) is still described,
         * from its first part. */
        choice ch;
        const nprfx_read_options o = read_options(nullptr);
        if (choose(path, h, o, ch).code) {
            ch.group = {&h.parts[0]};
            ch.chans.clear();
            for (int c = 0; c < h.parts[0].spec.nchannels; c++)
                ch.chans.push_back({&h.parts[0], c,
                                    c < (int)h.parts[0].spec.channelnames.size()
                                        ? h.parts[0].spec.channelnames[c]
                                        : "channel" + std::to_string(c),
                                    0});
            ch.group.clear();
        }
        const ImageSpec &first = ch.chans.empty() ? h.parts[0].spec : ch.chans[0].p->spec;
        std::vector<std::string> names, types;
        for (const chan &c : ch.chans) {
            names.push_back(c.name);
            types.push_back(c.p->spec.channelformat(c.c).c_str());
        }
        copy_field(out->format, sizeof out->format, h.format);
        copy_field(out->compression, sizeof out->compression,
                   first.get_string_attribute("compression"));
        out->subimages = (int)h.parts.size();
        out->bounds = data_rect(first);
        out->display = display_rect(first);
        out->names = dup_names(names);
        out->types = dup_names(types);
        out->nchannels = (int)names.size();
        out->views = dup_names(h.views);
        out->nviews = out->views ? (int)h.views.size() : 0;
        std::vector<std::string> an, av;
        for (const OIIO::ParamValue &pv : first.extra_attribs) {
            an.push_back(pv.name().string());
            av.push_back(pv.type() == TypeDesc::STRING ? std::string(pv.get_ustring().string())
                                                       : pv.get_string());
        }
        out->attr_names = dup_names(an);
        out->attr_values = dup_names(av);
        out->nattributes = (int)an.size();
        out->parts =
            static_cast<nprfx_part_info *>(std::calloc(h.parts.size(), sizeof(nprfx_part_info)));
        bool ok = out->names && out->types && out->views && out->parts && out->attr_names &&
                  out->attr_values;
        for (size_t i = 0; ok && i < h.parts.size(); i++) {
            const part &p = h.parts[i];
            nprfx_part_info &pi = out->parts[i];
            out->nparts = (int)i + 1;
            pi.index = p.index;
            copy_field(pi.name, sizeof pi.name, p.name);
            copy_field(pi.view, sizeof pi.view, p.view);
            pi.bounds = data_rect(p.spec);
            pi.display = display_rect(p.spec);
            pi.deep = p.spec.deep ? 1 : 0;
            pi.tile_w = p.spec.tile_width;
            pi.tile_h = p.spec.tile_height;
            pi.miplevels = p.miplevels;
            pi.pixel_aspect = p.spec.get_float_attribute("PixelAspectRatio", 1.0f);
            pi.used = std::find(ch.group.begin(), ch.group.end(), &p) != ch.group.end();
            pi.broken = internal_io_broken_part(p.index) ? 1 : 0;
            std::vector<std::string> pn, pt;
            for (int c = 0; c < p.spec.nchannels; c++) {
                pn.push_back(c < (int)p.spec.channelnames.size() ? p.spec.channelnames[c]
                                                                 : "channel" + std::to_string(c));
                pt.push_back(p.spec.channelformat(c).c_str());
            }
            pi.names = dup_names(pn);
            pi.types = dup_names(pt);
            pi.nchannels = p.spec.nchannels;
            ok = pi.names && pi.types;
        }
        if (!ok) {
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
                                                 const char *prefix, char ***names, char ***values,
                                                 int *count)
{
    if (!path || !names || !values || !count)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_io_read_attributes: NULL argument");
    *names = *values = nullptr;
    *count = 0;
    if (nprfx_result g = internal_io_guard(ctx, path, NPRFX_GUARD_HEADER)) return g;
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

/* ---- rows: strip renders ----------------------------------------------------------------- */

struct nprfx_row_reader {
    reading rd;
};

extern "C" nprfx_result nprfx_io_rows_open(nprfx_context *ctx, const char *path,
                                           const nprfx_read_options *opt, nprfx_plate *shape,
                                           nprfx_row_reader **out)
{
    if (!path || !shape || !out)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_rows_open: NULL argument");
    std::memset(shape, 0, sizeof *shape);
    *out = nullptr;
    const nprfx_read_options o = read_options(opt);
    try {
        std::unique_ptr<nprfx_row_reader> r(new nprfx_row_reader);
        nprfx_result e = open_reading(ctx, path, o, r->rd, true);
        if (!e) e = describe(ctx, r->rd, shape);
        if (!e) e = set_note(ctx, r->rd, shape);
        if (e) {
            nprfx_plate_free(shape);
            return e;
        }
        *out = r.release();
        return NPRFX_OK;
    } catch (const std::exception &e) {
        nprfx_plate_free(shape);
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path, e.what());
    }
}

extern "C" nprfx_result nprfx_io_rows_read(nprfx_context *ctx, nprfx_row_reader *r, int y0, int y1,
                                           float *dst)
{
    if (!r || !dst)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_rows_read: NULL argument");
    const ImageSpec &first = r->rd.ch.group[0]->spec;
    if (y0 < first.y || y1 > first.y + first.height || y0 >= y1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "'%s': rows %d..%d are not inside the data window's rows %d..%d",
                           r->rd.path.c_str(), y0, y1, first.y, first.y + first.height);
    try {
        return read_blocks(ctx, r->rd, y0, y1, dst);
    } catch (const std::exception &e) {
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", r->rd.path.c_str(), e.what());
    }
}

extern "C" nprfx_result nprfx_io_rows_note(nprfx_context *ctx, nprfx_row_reader *r, char **note,
                                           int *warning)
{
    if (!r || !note || !warning)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_io_rows_note: NULL argument");
    nprfx_plate p;
    std::memset(&p, 0, sizeof p);
    nprfx_result e = set_note(ctx, r->rd, &p);
    *note = p.note;
    *warning = p.note_is_warning;
    return e;
}

extern "C" void nprfx_io_rows_close(nprfx_row_reader *r)
{
    if (r && r->rd.in) r->rd.in->close();
    delete r;
}
