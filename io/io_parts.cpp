/* nprfx I/O (libnprfx-io) — what a file holds and what a read takes of it (OpenImageIO): its parts,
 * views and windows, the channels a group of parts delivers under plate-unique names, and the
 * choice of parts and view (docs/design.md §2.3). */
#include "io_parts.h"
#include "io_validate.h"

extern "C" {
#include "nprfx/channels.h"
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

namespace io_internal
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

std::string part_label(const part &p)
{
    std::string s = "part " + std::to_string(p.index);
    if (!p.name.empty()) s += " '" + p.name + "'";
    return s;
}

/* oiiotool's geometry notation, WxH+X+Y, as nprfx info prints windows. */
static std::string rect_text(nprfx_rect r)
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

static bool same_windows(const ImageSpec &a, const ImageSpec &b)
{
    return nprfx_rect_equal(data_rect(a), data_rect(b)) &&
           nprfx_rect_equal(display_rect(a), display_rect(b));
}

static unsigned char pixel_type(const header &h, const ImageSpec &s, int c)
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

static std::vector<std::string> split_dots(const std::string &s)
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
static std::string channel_view(const header &h, const part &p, const std::string &name,
                                std::string &bare)
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
static std::vector<chan> group_channels(const header &h, const std::vector<const part *> &group,
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

static bool holds_all(const std::vector<chan> &chans, const nprfx_read_options &o)
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

static failure refuse_part(const char *path, const part &p)
{
    if (const char *why = internal_io_broken_part(p.index)) return {NPRFX_ERR_IO, why};
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

static std::string list_text(const std::vector<std::string> &v)
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
            /* A broken part is left out of its group, unless it is the first part a read
             * would take: then the read is refused, never moved to parts the caller did not
             * mean (a file damaged at its first chunk must not read as its second part). */
            bool broken = internal_io_broken_part(p.index) != nullptr;
            if (broken && groups.empty()) return refuse_part(path, p);
            if (refuse_part(path, p).code) {
                if (!refused && !broken) refused = &p;
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
            const bool broken = internal_io_broken_part(p.index) != nullptr;
            if (broken)
                why = "unfinished or damaged: its pixels are missing";
            else if (!p.view.empty() && p.view != ch.view)
                why = "view '" + p.view + "'";
            else if (p.spec.deep)
                why = "deep";
            else if (p.spec.depth > 1)
                why = "volume";
            else
                why = "data window " + rect_text(data_rect(p.spec)) + ", display window " +
                      rect_text(display_rect(p.spec));
            /* Parts of other views, or left out by the caller's own choice, are no surprise;
             * a broken part always is. */
            if (broken || (why.compare(0, 5, "view ") && !(o.part && *o.part))) ch.warn = true;
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

} // namespace io_internal

using namespace io_internal;
