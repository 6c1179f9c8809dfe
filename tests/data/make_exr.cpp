/* nprfx-make-exr OUTDIR: the valid EXR layouts oiiotool cannot write, made with the OpenEXR
 * library itself (tests/data/make_valid.sh calls it; tests/cli/corpus_valid.sh reads them):
 *   uint_mixed.exr   half, float and uint channels in one part, ids up to 2^24, at an origin
 *   uint_big.exr     uint ids above 2^24, one apart (a float holds none but the first exactly)
 *   mv_exr.exr       single-part stereo (multiView left, right), OpenEXR names: diffuse.right.R
 *   mv_nuke.exr      the same with Nuke's names: right.diffuse.R
 *   rip_down.exr     600x400 half RGBA tiled 64x64 with RIPMAP levels rounded down (as
 *                    exrmaketiled -r writes it)
 *   rip_up.exr       37x23 tiled 8x8, RIPMAP levels rounded up (odd sizes, where rounding counts)
 *   mip_up.exr       37x23 tiled 8x8, MIPMAP levels rounded up
 *   tiled_typed_scanline.exr  a single-part 40x24 file tiled 16x16 whose optional "type"
 *                    attribute says "scanlineimage" (the tile description and the version
 *                    field say tiled, as OpenEXR reads it)
 *   unfinished.exr   4 scanline parts of which only parts 0 and 1 were written, as a render
 *                    killed mid-way leaves the file (the offsets of parts 2 and 3 stay 0)
 * nprfx-make-exr --uint-ids BASE [--merge] IN OUT: IN (one scanline part, a float channel "id"
 * of small object numbers, as `nprfx synth` writes) with "id" rewritten as uint: 0 stays 0 and
 * every other k becomes BASE + k (--merge: BASE + 1, one object); the other channels unchanged.
 * oiiotool scales the values it writes into uint channels and cannot write the multiView
 * attribute (OIIO 2.4), hence this program. The values are simple functions of (x, y, channel)
 * so a test can say what a reader must find. */
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfMultiView.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfTiledOutputFile.h>

#include <Imath/half.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <exception>
#include <string>
#include <vector>

namespace
{

struct channel {
    std::string name;
    Imf::PixelType type;
    double scale; /* value = scale * (x + 10 y) + offset (uint: rounded) */
    double offset;
};

/* Write one scanline part with the given channels over data window (x0, y0, w, h) inside
 * display window (0, 0, dw, dh). */
void write_file(const std::string &path, int x0, int y0, int w, int h, int dw, int dh,
                const std::vector<channel> &chans, const std::vector<std::string> &views)
{
    Imath::Box2i display(Imath::V2i(0, 0), Imath::V2i(dw - 1, dh - 1));
    Imath::Box2i data(Imath::V2i(x0, y0), Imath::V2i(x0 + w - 1, y0 + h - 1));
    Imf::Header header(display, data);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const channel &c : chans)
        header.channels().insert(c.name, Imf::Channel(c.type));
    if (!views.empty()) Imf::addMultiView(header, Imf::StringVector(views.begin(), views.end()));
    std::vector<std::vector<char>> store(chans.size());
    Imf::FrameBuffer fb;
    for (size_t k = 0; k < chans.size(); k++) {
        const channel &c = chans[k];
        size_t bytes = c.type == Imf::HALF ? 2 : 4;
        store[k].resize((size_t)w * h * bytes);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                double v = c.scale * (x + 10.0 * y) + c.offset;
                char *p = &store[k][((size_t)y * w + x) * bytes];
                if (c.type == Imf::UINT) {
                    uint32_t u = (uint32_t)(v + 0.5);
                    std::memcpy(p, &u, 4);
                } else if (c.type == Imf::HALF) {
                    half hv((float)v);
                    std::memcpy(p, &hv, 2);
                } else {
                    float f = (float)v;
                    std::memcpy(p, &f, 4);
                }
            }
        /* The slice's base points at pixel (0, 0) of the data window's coordinates. */
        char *base = store[k].data() - ((ptrdiff_t)y0 * w + x0) * (ptrdiff_t)bytes;
        fb.insert(c.name, Imf::Slice(c.type, base, bytes, bytes * (size_t)w));
    }
    Imf::OutputFile out(path.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(h);
}

/* A tiled half RGBA file of w x h at the origin with every level of its mode: level (lx, ly)
 * holds value(x, y, c) + 0.125 (lx + 2 ly), so a reader that takes another level than (0, 0)
 * shows it. */
void write_tiled(const std::string &path, int w, int h, int tile, Imf::LevelMode mode,
                 Imf::LevelRoundingMode round)
{
    Imf::Header header(w, h);
    header.compression() = Imf::ZIP_COMPRESSION;
    const char *names[4] = {"R", "G", "B", "A"};
    for (const char *n : names)
        header.channels().insert(n, Imf::Channel(Imf::HALF));
    header.setTileDescription(Imf::TileDescription(tile, tile, mode, round));
    Imf::TiledOutputFile out(path.c_str(), header);
    for (int ly = 0; ly < out.numYLevels(); ly++)
        for (int lx = 0; lx < out.numXLevels(); lx++) {
            if (mode != Imf::RIPMAP_LEVELS && lx != ly) continue;
            const int lw = out.levelWidth(lx), lh = out.levelHeight(ly);
            std::vector<half> px((size_t)lw * lh * 4);
            for (int y = 0; y < lh; y++)
                for (int x = 0; x < lw; x++)
                    for (int c = 0; c < 4; c++)
                        px[((size_t)y * lw + x) * 4 + c] =
                            half((float)(0.001 * (x + 10.0 * y) + 0.1 * c + 0.125 * (lx + 2 * ly)));
            Imf::FrameBuffer fb;
            for (int c = 0; c < 4; c++)
                fb.insert(names[c], Imf::Slice(Imf::HALF, (char *)&px[c], 4 * sizeof(half),
                                               4 * sizeof(half) * (size_t)lw));
            out.setFrameBuffer(fb);
            out.writeTiles(0, out.numXTiles(lx) - 1, 0, out.numYTiles(ly) - 1, lx, ly);
        }
}

/* A single-part tiled file (ONE_LEVEL) whose "type" attribute, written as "tiledimage", is
 * rewritten to "scanlineimage": 3 bytes longer, so the chunk offsets after the header move by 3
 * too. */
void write_tiled_typed_scanline(const std::string &path)
{
    const std::string tmp = path + ".tmp";
    const int w = 40, h = 24, tile = 16;
    {
        Imf::Header header(w, h);
        header.compression() = Imf::ZIP_COMPRESSION;
        header.channels().insert("Y", Imf::Channel(Imf::HALF));
        header.setTileDescription(Imf::TileDescription(tile, tile, Imf::ONE_LEVEL));
        header.setType(Imf::TILEDIMAGE);
        Imf::TiledOutputFile out(tmp.c_str(), header);
        std::vector<half> px((size_t)w * h);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                px[(size_t)y * w + x] = half((float)(0.01 * (x + 10.0 * y)));
        Imf::FrameBuffer fb;
        fb.insert("Y", Imf::Slice(Imf::HALF, (char *)px.data(), sizeof(half), sizeof(half) * w));
        out.setFrameBuffer(fb);
        out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
    }
    std::FILE *f = std::fopen(tmp.c_str(), "rb");
    if (!f) throw std::runtime_error("cannot read " + tmp);
    std::vector<unsigned char> b;
    for (int c; (c = std::fgetc(f)) != EOF;)
        b.push_back((unsigned char)c);
    std::fclose(f);
    std::remove(tmp.c_str());
    static const char attr[] = "type\0string\0";
    const std::string from = "tiledimage", to = "scanlineimage";
    size_t at = 0;
    while (at + sizeof attr - 1 + 4 <= b.size() &&
           std::memcmp(&b[at], attr, sizeof attr - 1) != 0)
        at++;
    const size_t size_at = at + sizeof attr - 1, value_at = size_at + 4;
    if (value_at + from.size() > b.size() || std::memcmp(&b[value_at], from.data(), from.size()))
        throw std::runtime_error("no type attribute in " + tmp);
    /* the header ends at the first empty attribute name after it; the offset table follows */
    size_t end = value_at + from.size();
    while (end < b.size() && b[end] != 0) {
        while (end < b.size() && b[end]) end++; /* name */
        end++;
        while (end < b.size() && b[end]) end++; /* type */
        end++;
        int32_t n;
        std::memcpy(&n, &b[end], 4);
        end += 4 + (size_t)n;
    }
    const size_t table = end + 1, chunks = (size_t)((w + tile - 1) / tile) * ((h + tile - 1) / tile);
    const uint64_t delta = to.size() - from.size();
    for (size_t k = 0; k < chunks; k++) {
        uint64_t off;
        std::memcpy(&off, &b[table + 8 * k], 8);
        off += delta;
        std::memcpy(&b[table + 8 * k], &off, 8);
    }
    const int32_t n = (int32_t)to.size();
    std::memcpy(&b[size_at], &n, 4);
    b.erase(b.begin() + (ptrdiff_t)value_at, b.begin() + (ptrdiff_t)(value_at + from.size()));
    b.insert(b.begin() + (ptrdiff_t)value_at, to.begin(), to.end());
    f = std::fopen(path.c_str(), "wb");
    if (!f || std::fwrite(b.data(), 1, b.size(), f) != b.size() || std::fclose(f))
        throw std::runtime_error("cannot write " + path);
}

/* Four 16x8 float parts (beauty: R,G,B; aov: N.X; depth: Z; extra: Y), only the first two of
 * which get their pixels before the file is closed. */
void write_unfinished(const std::string &path)
{
    const char *names[4] = {"beauty", "aov", "depth", "extra"};
    const std::vector<std::vector<std::string>> chans = {{"R", "G", "B"}, {"N.X"}, {"Z"}, {"Y"}};
    const int w = 16, h = 8;
    std::vector<Imf::Header> headers;
    for (int p = 0; p < 4; p++) {
        Imf::Header hd(w, h);
        hd.compression() = Imf::ZIP_COMPRESSION;
        hd.setName(names[p]);
        hd.setType(Imf::SCANLINEIMAGE);
        for (const std::string &c : chans[p])
            hd.channels().insert(c, Imf::Channel(Imf::FLOAT));
        headers.push_back(hd);
    }
    Imf::MultiPartOutputFile out(path.c_str(), headers.data(), (int)headers.size());
    for (int p = 0; p < 2; p++) {
        const size_t nc = chans[p].size();
        std::vector<float> px((size_t)w * h * nc);
        for (size_t i = 0; i < px.size(); i++)
            px[i] = (float)(0.01 * (double)i + p);
        Imf::FrameBuffer fb;
        for (size_t c = 0; c < nc; c++)
            fb.insert(chans[p][c], Imf::Slice(Imf::FLOAT, (char *)&px[c], nc * sizeof(float),
                                              nc * sizeof(float) * (size_t)w));
        Imf::OutputPart part(out, p);
        part.setFrameBuffer(fb);
        part.writePixels(h);
    }
}

/* The --uint-ids copy (see the file comment). */
void write_uint_ids(const std::string &in_path, const std::string &out_path, uint32_t base,
                    bool merge)
{
    Imf::InputFile in(in_path.c_str());
    const Imf::Header &ih = in.header();
    const Imath::Box2i dw = ih.dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    if (!ih.channels().findChannel("id")) throw std::runtime_error(in_path + ": no channel 'id'");
    Imf::Header oh = ih;
    Imf::ChannelList out_chans;
    for (Imf::ChannelList::ConstIterator c = ih.channels().begin(); c != ih.channels().end(); ++c)
        out_chans.insert(c.name(),
                         std::string(c.name()) == "id" ? Imf::Channel(Imf::UINT) : c.channel());
    oh.channels() = out_chans;
    std::vector<std::vector<char>> store;
    std::vector<std::string> names;
    Imf::FrameBuffer fb;
    std::vector<float> ids((size_t)w * h);
    for (Imf::ChannelList::ConstIterator c = ih.channels().begin(); c != ih.channels().end(); ++c) {
        const bool is_id = std::string(c.name()) == "id";
        const Imf::PixelType t = is_id ? Imf::FLOAT : c.channel().type;
        const size_t bytes = t == Imf::HALF ? 2 : 4;
        store.emplace_back((size_t)w * h * bytes);
        names.push_back(c.name());
        char *buf = is_id ? (char *)ids.data() : store.back().data();
        char *b = buf - ((ptrdiff_t)dw.min.y * w + dw.min.x) * (ptrdiff_t)bytes;
        fb.insert(c.name(), Imf::Slice(t, b, bytes, bytes * (size_t)w));
    }
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    std::vector<uint32_t> uids(ids.size());
    for (size_t i = 0; i < ids.size(); i++) {
        const uint32_t k = (uint32_t)(ids[i] + 0.5f);
        uids[i] = k == 0 ? 0u : base + (merge ? 1u : k);
    }
    Imf::FrameBuffer ofb;
    size_t k = 0;
    for (Imf::ChannelList::ConstIterator c = ih.channels().begin(); c != ih.channels().end();
         ++c, ++k) {
        const bool is_id = names[k] == "id";
        const Imf::PixelType t = is_id ? Imf::UINT : c.channel().type;
        const size_t bytes = t == Imf::HALF ? 2 : 4;
        char *buf = is_id ? (char *)uids.data() : store[k].data();
        char *b = buf - ((ptrdiff_t)dw.min.y * w + dw.min.x) * (ptrdiff_t)bytes;
        ofb.insert(c.name(), Imf::Slice(t, b, bytes, bytes * (size_t)w));
    }
    Imf::OutputFile out(out_path.c_str(), oh);
    out.setFrameBuffer(ofb);
    out.writePixels(h);
}

} // namespace

int main(int argc, char **argv)
{
    if (argc >= 5 && std::string(argv[1]) == "--uint-ids") {
        const bool merge = argc == 6 && std::string(argv[3]) == "--merge";
        if (argc != (merge ? 6 : 5)) {
            std::fprintf(stderr, "usage: nprfx-make-exr --uint-ids BASE [--merge] IN OUT\n");
            return 2;
        }
        try {
            write_uint_ids(argv[argc - 2], argv[argc - 1],
                           (uint32_t)std::strtoul(argv[2], nullptr, 0), merge);
        } catch (const std::exception &e) {
            std::fprintf(stderr, "nprfx-make-exr: %s\n", e.what());
            return 1;
        }
        return 0;
    }
    if (argc != 2) {
        std::fprintf(stderr, "usage: nprfx-make-exr OUTDIR\n");
        return 2;
    }
    const std::string dir = argv[1];
    try {
        /* ids count down from 2^24 = 16777216, the largest uint float32 pixels hold with all
         * the integers below it. */
        write_file(dir + "/uint_mixed.exr", -3, 2, 16, 8, 12, 12,
                   {{"R", Imf::HALF, 0.25, 0.5},
                    {"G", Imf::FLOAT, 0.001, -0.3},
                    {"B", Imf::HALF, -0.5, 2.0},
                    {"id", Imf::UINT, -1021.0, 16777216.0}},
                   {});
        /* 16777217 (2^24 + 1) and up, each id one more than its left neighbour: pairs of them
         * round to one float. */
        write_file(dir + "/uint_big.exr", 0, 0, 4, 4, 4, 4,
                   {{"R", Imf::FLOAT, 0.1, 0.0}, {"id", Imf::UINT, 1.0, 16777217.0}}, {});
        /* Stereo in one part: the default view's channels bare, the other view's named. */
        write_file(dir + "/mv_exr.exr", 0, 0, 8, 6, 8, 6,
                   {{"R", Imf::FLOAT, 0.01, 0.1},
                    {"G", Imf::FLOAT, 0.01, 0.2},
                    {"B", Imf::FLOAT, 0.01, 0.3},
                    {"diffuse.R", Imf::HALF, 0.01, 0.4},
                    {"right.R", Imf::FLOAT, 0.02, 1.1},
                    {"right.G", Imf::FLOAT, 0.02, 1.2},
                    {"right.B", Imf::FLOAT, 0.02, 1.3},
                    {"diffuse.right.R", Imf::HALF, 0.02, 1.4}},
                   {"left", "right"});
        write_file(dir + "/mv_nuke.exr", 0, 0, 8, 6, 8, 6,
                   {{"R", Imf::FLOAT, 0.01, 0.1},
                    {"G", Imf::FLOAT, 0.01, 0.2},
                    {"B", Imf::FLOAT, 0.01, 0.3},
                    {"diffuse.R", Imf::HALF, 0.01, 0.4},
                    {"right.R", Imf::FLOAT, 0.02, 1.1},
                    {"right.G", Imf::FLOAT, 0.02, 1.2},
                    {"right.B", Imf::FLOAT, 0.02, 1.3},
                    {"right.diffuse.R", Imf::HALF, 0.02, 1.4}},
                   {"left", "right"});
        write_tiled(dir + "/rip_down.exr", 600, 400, 64, Imf::RIPMAP_LEVELS, Imf::ROUND_DOWN);
        write_tiled(dir + "/rip_up.exr", 37, 23, 8, Imf::RIPMAP_LEVELS, Imf::ROUND_UP);
        write_tiled(dir + "/mip_up.exr", 37, 23, 8, Imf::MIPMAP_LEVELS, Imf::ROUND_UP);
        write_unfinished(dir + "/unfinished.exr");
        write_tiled_typed_scanline(dir + "/tiled_typed_scanline.exr");
    } catch (const std::exception &e) {
        std::fprintf(stderr, "nprfx-make-exr: %s\n", e.what());
        return 1;
    }
    return 0;
}
