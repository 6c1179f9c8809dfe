/* The image-file adapter behind io.h: OpenImageIO for files, OpenColorIO for colour.
 *
 * This is the only C++ in the project. Every entry point is extern "C", catches every exception
 * (a C caller cannot unwind through it) and reports through nprfx_error, naming the file and,
 * where one is at fault, the channel. */
#include "io.h"
#include "io_limits.h"
#include "io_validate.h"

extern "C" {
#include "channels.h"
}

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

/* ---- reading: parts and views ------------------------------------------------------------- */

/* One part (subimage) of a file, as its header describes it. */
struct part {
    int index = 0;
    ImageSpec spec;
    std::string name; /* oiio:subimagename, "" when unnamed */
    std::string view; /* the part's "view" attribute (multi-part stereo), "" when none */
    int miplevels = 1;
};

struct header {
    std::string format;
    std::vector<part> parts;
    std::vector<std::string> views; /* views[0] is the default view; empty: not multi-view */
};

/* A channel a read delivers: file channel c of part p under its final, plate-unique name. */
struct chan {
    const part *p;
    int c;
    std::string name;
    unsigned char type; /* nprfx_pixel_type */
};

/* What a read takes: parts of one data and display window, one view, and what to tell. */
struct choice {
    std::vector<const part *> group;
    std::vector<chan> chans;
    std::string view;
    std::string note;
    bool warn = false;
};

/* An error found while choosing: raised by the caller (nprfx info reports a file it cannot read
 * instead of failing). */
struct failure {
    nprfx_result code = NPRFX_OK;
    std::string message;
};

std::string part_label(const part &p)
{
    std::string s = "part " + std::to_string(p.index);
    if (!p.name.empty()) s += " '" + p.name + "'";
    return s;
}

/* oiiotool's geometry notation, WxH+X+Y, as nprfx info prints windows. */
std::string rect_text(nprfx_rect r)
{
    char buf[80];
    std::snprintf(buf, sizeof buf, "%dx%d%+d%+d", nprfx_rect_width(r), nprfx_rect_height(r), r.x0,
                  r.y0);
    return buf;
}

nprfx_rect data_rect(const ImageSpec &s)
{
    return nprfx_rect_make(s.x, s.y, s.x + s.width, s.y + s.height);
}

nprfx_rect display_rect(const ImageSpec &s)
{
    return nprfx_rect_make(s.full_x, s.full_y, s.full_x + s.full_width, s.full_y + s.full_height);
}

bool same_windows(const ImageSpec &a, const ImageSpec &b)
{
    return nprfx_rect_equal(data_rect(a), data_rect(b)) &&
           nprfx_rect_equal(display_rect(a), display_rect(b));
}

unsigned char pixel_type(const header &h, const ImageSpec &s, int c)
{
    if (h.format != "openexr") return NPRFX_PIXEL_FLOAT; /* other formats: normalised floats */
    TypeDesc t = s.channelformat(c);
    return t == TypeDesc::UINT   ? NPRFX_PIXEL_UINT
           : t == TypeDesc::HALF ? NPRFX_PIXEL_HALF
                                 : NPRFX_PIXEL_FLOAT;
}

/* Open path and describe every part: windows, name, view, MIP levels; and the file's views: the
 * multiView attribute (OpenEXR's single-part stereo), else the parts' "view" attributes in file
 * order. Nothing is refused here; what a read cannot take is refused when it is chosen. */
nprfx_result scan(nprfx_context *ctx, const char *path, std::unique_ptr<ImageInput> &in, header &h)
{
    in = ImageInput::open(path);
    if (!in) {
        std::string e = OIIO::geterror();
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read '%s': %s", path,
                           e.empty() ? "unknown error" : e.c_str());
    }
    h.format = in->format_name();
    for (int s = 0; in->seek_subimage(s, 0); s++) {
        part p;
        p.index = s;
        p.spec = in->spec();
        p.name = p.spec.get_string_attribute("oiio:subimagename");
        p.view = p.spec.get_string_attribute("view");
        while (p.miplevels < 64 && in->seek_subimage(s, p.miplevels))
            p.miplevels++;
        h.parts.push_back(std::move(p));
    }
    OIIO::geterror(); /* the failed seeks past the last subimage and level leave messages */
    in->geterror();
    if (h.parts.empty()) return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' holds no image", path);
    for (const part &p : h.parts) {
        const OIIO::ParamValue *mv = p.spec.find_attribute("multiView");
        if (!mv || mv->type().basetype != TypeDesc::STRING) continue;
        const OIIO::ustring *u = static_cast<const OIIO::ustring *>(mv->data());
        size_t n = (size_t)mv->type().numelements() * (size_t)mv->nvalues();
        for (size_t i = 0; i < n; i++)
            if (!u[i].empty()) h.views.push_back(u[i].string());
        if (!h.views.empty()) break;
    }
    if (h.views.empty())
        for (const part &p : h.parts)
            if (!p.view.empty() &&
                std::find(h.views.begin(), h.views.end(), p.view) == h.views.end())
                h.views.push_back(p.view);
    return NPRFX_OK;
}

std::vector<std::string> split_dots(const std::string &s)
{
    std::vector<std::string> v;
    size_t b = 0;
    for (size_t e; (e = s.find('.', b)) != std::string::npos; b = e + 1)
        v.push_back(s.substr(b, e - b));
    v.push_back(s.substr(b));
    return v;
}

/* The view a channel belongs to, and its name without the view. A part's "view" attribute says
 * it for all its channels. Otherwise the view is a component of the name: OpenEXR's multi-view
 * rule puts it next to last ("diffuse.right.R"), Nuke writes it first ("right.diffuse.R"). A name
 * with no view component belongs to the default view (OpenEXR: "R" is the default view's). The
 * bare names of every view are then alike, so a graph's references work on any view. */
std::string channel_view(const header &h, const part &p, const std::string &name, std::string &bare)
{
    bare = name;
    std::vector<std::string> views = p.view.empty() ? h.views : std::vector<std::string>{p.view};
    if (views.empty()) return "";
    std::vector<std::string> c = split_dots(name);
    auto is_view = [&](const std::string &s) {
        return std::find(views.begin(), views.end(), s) != views.end();
    };
    size_t at = c.size();
    if (c.size() >= 2 && is_view(c[c.size() - 2]))
        at = c.size() - 2;
    else if (c.size() >= 2 && is_view(c[0]))
        at = 0;
    if (at == c.size()) return p.view.empty() ? h.views[0] : p.view;
    std::string view = c[at];
    c.erase(c.begin() + (long)at);
    bare.clear();
    for (size_t i = 0; i < c.size(); i++)
        bare += (i ? "." : "") + c[i];
    return view;
}

/* The channels a group of parts delivers for a view, with plate-unique names: multi-part files
 * often repeat bare names ("R" in every part), and a repeated name gets its part's name as a
 * layer prefix so every channel stays addressable. */
std::vector<chan> group_channels(const header &h, const std::vector<const part *> &group,
                                 const std::string &view)
{
    std::vector<chan> out;
    std::set<std::string> used;
    for (const part *p : group) {
        const ImageSpec &s = p->spec;
        std::string prefix = p->name.empty() ? "subimage" + std::to_string(p->index) : p->name;
        for (int c = 0; c < s.nchannels; c++) {
            std::string raw = c < (int)s.channelnames.size() ? s.channelnames[c] : "";
            if (raw.empty()) raw = "channel" + std::to_string(c);
            std::string n;
            std::string v = channel_view(h, *p, raw, n);
            if (!view.empty() && !v.empty() && v != view) continue;
            if (used.count(n)) {
                std::string prefixed = prefix + "." + n;
                for (int k = 2; used.count(prefixed); k++)
                    prefixed = prefix + "." + n + "." + std::to_string(k);
                n = prefixed;
            }
            used.insert(n);
            out.push_back({p, c, n, pixel_type(h, s, c)});
        }
    }
    return out;
}

bool holds_all(const std::vector<chan> &chans, const nprfx_read_options &o)
{
    std::vector<const char *> names;
    for (const chan &c : chans)
        names.push_back(c.name.c_str());
    std::vector<int> idx(chans.size() + 256);
    for (int i = 0; i < o.nwant; i++) {
        char bad[256];
        int amb = 0;
        if (!o.want[i] || !*o.want[i]) continue;
        if (nprfx_channels_select(names.data(), (int)names.size(), o.want[i], idx.data(),
                                  (int)idx.size(), bad, sizeof bad, &amb) < 0)
            return false;
    }
    return true;
}

failure refuse_part(const char *path, const part &p)
{
    if (p.spec.deep)
        return {NPRFX_ERR_UNSUPPORTED,
                "'" + std::string(path) + "' " + part_label(p) +
                    " holds deep data (several samples per pixel), which nprfx cannot read: "
                    "flatten it first, e.g. oiiotool '" +
                    path + "' --flatten -o flat.exr"};
    if (p.spec.depth > 1)
        return {NPRFX_ERR_UNSUPPORTED, "'" + std::string(path) + "' " + part_label(p) +
                                           " is a volume (depth " + std::to_string(p.spec.depth) +
                                           "), which nprfx cannot read"};
    return {};
}

std::string list_text(const std::vector<std::string> &v)
{
    std::string s;
    for (const std::string &x : v)
        s += (s.empty() ? "" : ", ") + x;
    return s;
}

/* Choose the parts and view a read takes (docs/design.md §2.3). */
failure choose(const char *path, const header &h, const nprfx_read_options &o, choice &ch)
{
    const std::string file = "'" + std::string(path) + "'";
    const std::string want_view = o.view && *o.view ? o.view : "";
    if (!want_view.empty()) {
        if (h.views.empty())
            return {NPRFX_ERR_MISSING_INPUT,
                    file + " has no view '" + want_view +
                        "': it is not a multi-view file (no multiView attribute, no part with a "
                        "view)"};
        if (std::find(h.views.begin(), h.views.end(), want_view) == h.views.end())
            return {NPRFX_ERR_MISSING_INPUT,
                    file + " has no view '" + want_view + "' (views: " + list_text(h.views) + ")"};
    }
    ch.view = !want_view.empty() ? want_view : h.views.empty() ? "" : h.views[0];
    if (o.part && *o.part) {
        const part *found = nullptr;
        for (const part &p : h.parts)
            if (p.name == o.part) found = &p;
        char *end = nullptr;
        long i = std::strtol(o.part, &end, 10);
        if (!found && end != o.part && !*end && i >= 0 && i < (long)h.parts.size())
            found = &h.parts[(size_t)i];
        if (!found) {
            std::vector<std::string> labels;
            for (const part &p : h.parts)
                labels.push_back(p.name.empty() ? std::to_string(p.index)
                                                : std::to_string(p.index) + " '" + p.name + "'");
            return {NPRFX_ERR_MISSING_INPUT,
                    file + " has no part '" + o.part +
                        "' (parts, by index and name: " + list_text(labels) + ")"};
        }
        if (!found->view.empty()) {
            if (!want_view.empty() && found->view != want_view)
                return {NPRFX_ERR_MISSING_INPUT, file + " " + part_label(*found) + " is view '" +
                                                     found->view + "', not view '" + want_view +
                                                     "'"};
            ch.view = found->view;
        }
        failure f = refuse_part(path, *found);
        if (f.code) return f;
        ch.group = {found};
        ch.chans = group_channels(h, ch.group, ch.view);
    } else {
        /* Groups of same-window parts of the view, in file order: the first that holds every
         * channel the caller wants, else the first. */
        std::vector<std::vector<const part *>> groups;
        const part *refused = nullptr;
        for (const part &p : h.parts) {
            if (!p.view.empty() && p.view != ch.view) continue;
            if (refuse_part(path, p).code) {
                if (!refused) refused = &p;
                continue;
            }
            bool placed = false;
            for (auto &g : groups)
                if (same_windows(g[0]->spec, p.spec)) {
                    g.push_back(&p);
                    placed = true;
                    break;
                }
            if (!placed) groups.push_back({&p});
        }
        if (groups.empty()) {
            if (refused) return refuse_part(path, *refused);
            return {NPRFX_ERR_MISSING_INPUT, file + " has no part of view '" + ch.view + "'"};
        }
        size_t pick = 0;
        for (size_t g = 0; g < groups.size(); g++)
            if (holds_all(group_channels(h, groups[g], ch.view), o)) {
                pick = g;
                break;
            }
        ch.group = groups[pick];
        ch.chans = group_channels(h, ch.group, ch.view);
    }
    if (ch.chans.empty())
        return {NPRFX_ERR_MISSING_INPUT, file + " " + part_label(*ch.group[0]) +
                                             " has no channels of view '" + ch.view + "'"};
    if (h.parts.size() > 1 || !h.views.empty()) {
        std::string used, unused;
        for (const part *p : ch.group)
            used += (used.empty() ? "" : ", ") + part_label(*p);
        for (const part &p : h.parts) {
            if (std::find(ch.group.begin(), ch.group.end(), &p) != ch.group.end()) continue;
            std::string why;
            if (!p.view.empty() && p.view != ch.view)
                why = "view '" + p.view + "'";
            else if (p.spec.deep)
                why = "deep";
            else if (p.spec.depth > 1)
                why = "volume";
            else
                why = "data window " + rect_text(data_rect(p.spec)) + ", display window " +
                      rect_text(display_rect(p.spec));
            /* Parts of other views, or left out by the caller's own choice, are no surprise. */
            if (why.compare(0, 5, "view ") && !(o.part && *o.part)) ch.warn = true;
            unused += (unused.empty() ? "" : ", ") + part_label(p) + " (" + why + ")";
        }
        ch.note = file + ": read " + used;
        if (!ch.view.empty()) ch.note += ", view '" + ch.view + "'";
        if (!unused.empty())
            ch.note += "; not used: " + unused + (ch.warn ? " (set \"part\" to read another)" : "");
    }
    return {};
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

/* ---- reading ------------------------------------------------------------------------------ */

/* The options a caller passed, read as far as its struct's size reaches (size-versioned). */
nprfx_read_options read_options(const nprfx_read_options *opt)
{
    nprfx_read_options o;
    std::memset(&o, 0, sizeof o);
    o.size = sizeof o;
    if (opt && opt->size >= sizeof(size_t))
        std::memcpy(&o, opt, opt->size < sizeof o ? opt->size : sizeof o);
    return o;
}

/* The largest integer float32 holds exactly, with every integer below it. */
const uint32_t float_exact_max = 1u << 24;

/* Rows an EXR part stores per chunk (a tile's height when tiled): reads in blocks of whole chunks
 * decode each chunk once. From the compression, as OpenEXR defines it. */
int chunk_rows(const part &p)
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
int block_rows(const part &p)
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
    std::vector<uint32_t> umax; /* per delivered uint channel: the largest value read */
    std::vector<float> fbuf;
    std::vector<uint32_t> ubuf;
};

/* The spans [lo, hi] of the delivered float (or half) and uint channels of part p; -1: none. */
void part_spans(const reading &rd, const part *p, int &flo, int &fhi, int &ulo, int &uhi)
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
nprfx_result open_reading(nprfx_context *ctx, const char *path, const nprfx_read_options &o,
                          reading &rd, bool rows = false)
{
    rd.path = path;
    rd.chosen = o.channels || o.pick || rows;
    /* Damaged files are refused before OIIO allocates anything (io_validate.h). A read of chosen
     * channels is held to the memory limit by what it delivers, checked once they are known. */
    if (nprfx_result g =
            nprfx_io_guard(ctx, path, rd.chosen ? NPRFX_GUARD_READ_CHOSEN : NPRFX_GUARD_READ))
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
    rd.umax.assign(nch, 0);
    return NPRFX_OK;
}

nprfx_result channels_error(nprfx_context *ctx, const reading &rd, const chan &a, const chan &b)
{
    std::string e = oiio_error(rd.in.get());
    return nprfx_error(ctx, NPRFX_ERR_IO, "cannot read channels %s..%s of %s of '%s': %s",
                       a.name.c_str(), b.name.c_str(), part_label(*a.p).c_str(), rd.path.c_str(),
                       e.c_str());
}

/* Rows [y0, y1) of the delivered channels into dst (all of them per pixel, rows of the data
 * window's width, row y0 first), part by part, a block of whole chunks at a time. */
nprfx_result read_blocks(nprfx_context *ctx, reading &rd, int y0, int y1, float *dst)
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
                void *buf;
                if (as_uint) {
                    rd.ubuf.resize(count);
                    buf = rd.ubuf.data();
                } else {
                    rd.fbuf.resize(count);
                    buf = rd.fbuf.data();
                }
                /* EXR uint channels (object ids) are read as integers and cast, since a float
                 * read would normalise them to [0,1]. */
                const TypeDesc type = as_uint ? TypeDesc::UINT : TypeDesc::FLOAT;
                bool ok =
                    p->spec.tile_width > 0
                        ? rd.in->read_tiles(p->index, 0, p->spec.x, p->spec.x + p->spec.width, by,
                                            be, 0, 1, lo, hi + 1, type, buf)
                        : rd.in->read_scanlines(p->index, 0, by, be, 0, lo, hi + 1, type, buf);
                if (nprfx_io_deadline_passed()) {
                    oiio_error(rd.in.get());
                    return nprfx_io_deadline_error(ctx, rd.path.c_str());
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
                    uint32_t most = rd.umax[k];
                    for (int y = r0; y < r1; y++) {
                        const size_t src = ((size_t)(y - by) * w) * (size_t)n + (size_t)(c.c - lo);
                        float *d = dst + (size_t)(y - y0) * w * nsel + k;
                        if (as_uint) {
                            const uint32_t *s = rd.ubuf.data() + src;
                            for (size_t x = 0; x < w; x++) {
                                uint32_t v = s[x * (size_t)n];
                                d[x * nsel] = (float)v;
                                if (v > most) most = v;
                            }
                        } else {
                            const float *s = rd.fbuf.data() + src;
                            for (size_t x = 0; x < w; x++)
                                d[x * nsel] = s[x * (size_t)n];
                        }
                    }
                    rd.umax[k] = most;
                }
            }
        }
    }
    return NPRFX_OK;
}

/* The whole plate of the delivered channels into dst, a read_image per run of adjacent file
 * channels of one part and kind (any format; tiled and MIP-mapped parts at level 0). */
nprfx_result read_runs(nprfx_context *ctx, reading &rd, float *dst)
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
                                   OIIO::AutoStride, nprfx_io_read_progress, nullptr);
        } else {
            rd.ubuf.resize(npix * (size_t)n);
            ok = rd.in->read_image(a.p->index, 0, c0, c1, TypeDesc::UINT, rd.ubuf.data(),
                                   OIIO::AutoStride, OIIO::AutoStride, OIIO::AutoStride,
                                   nprfx_io_read_progress, nullptr);
            for (size_t i = 0; ok && i < npix; i++)
                for (int j = 0; j < n; j++) {
                    uint32_t v = rd.ubuf[i * n + j];
                    d[i * nch + j] = (float)v;
                    if (v > rd.umax[k0 + j]) rd.umax[k0 + j] = v;
                }
        }
        if (nprfx_io_deadline_passed()) {
            oiio_error(rd.in.get());
            return nprfx_io_deadline_error(ctx, rd.path.c_str());
        }
        if (!ok) return channels_error(ctx, rd, rd.sel[k0], rd.sel[k1 - 1]);
        k0 = k1;
    }
    return NPRFX_OK;
}

/* out's description of the plate (everything but pixels) and the read's note: which parts and
 * view, and uint values float cannot hold (once the pixels are read). */
nprfx_result describe(nprfx_context *ctx, const reading &rd, nprfx_plate *out)
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

nprfx_result set_note(nprfx_context *ctx, const reading &rd, nprfx_plate *out)
{
    std::string note = rd.ch.note, rounded;
    bool warn = rd.ch.warn;
    for (size_t k = 0; k < rd.sel.size(); k++)
        if (rd.umax[k] > float_exact_max)
            rounded += (rounded.empty() ? "" : ", ") + std::string("'") + rd.sel[k].name +
                       "' (up to " + std::to_string(rd.umax[k]) + ")";
    if (!rounded.empty()) {
        note += (note.empty() ? "'" + rd.path + "': " : "; ") + "uint channels " + rounded +
                " hold integers above 2^24 = 16777216, which float pixels cannot all hold: "
                "they are rounded to the nearest float (distinct ids may merge)";
        warn = true;
    }
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

} // namespace

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
    if (nprfx_result g = nprfx_io_guard(ctx, path, NPRFX_GUARD_HEADER)) return g;
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
        out->parts =
            static_cast<nprfx_part_info *>(std::calloc(h.parts.size(), sizeof(nprfx_part_info)));
        bool ok = out->names && out->types && out->views && out->parts;
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

namespace
{

/* The options a caller passed, read as far as its struct's size reaches (size-versioned). */
nprfx_result write_options(nprfx_context *ctx, const char *path, const nprfx_write_options *opt,
                           nprfx_write_options &o)
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
nprfx_result write_spec(nprfx_context *ctx, const char *path, nprfx_rect bounds, int channels,
                        const char *const *names, const nprfx_rect *display,
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

/* im's pixels in the channels' native types (formats), packed: uint takes the float's integer
 * value; anything else in a uint channel is rounded. */
void pack_native(const nprfx_image *im, const std::vector<TypeDesc> &formats,
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
                    uint32_t u = !(v > 0.0f)          ? 0u
                                 : v >= 4294967295.0f ? 4294967295u
                                                      : (uint32_t)std::lrint(v);
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

} // namespace

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

/* ---- colour ------------------------------------------------------------------------------- */

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

extern "C" void nprfx_io_rows_close(nprfx_row_reader *r)
{
    if (r && r->rd.in) r->rd.in->close();
    delete r;
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
