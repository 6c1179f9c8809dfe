/* nprfx I/O (libnprfx-io) — the EXR checks of io_validate.h, on OpenEXRCore's C API.
 *
 * Everything here reads headers and the 8-20 byte chunk leaders, never pixel data, so a valid
 * 4K plate of 135 chunks costs 135 small reads. Messages name the file, the part and the chunk;
 * OpenEXRCore's own message is kept per thread by the error handler, which prints nothing. */
#define _DEFAULT_SOURCE
#include "io_validate.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <OpenEXR/openexr.h>

#include "nprfx/io.h"
#include "io_timeout.h"

/* Channels in one part. OpenImageIO refuses more than 1024 (its limits:channels); a damaged
 * channel list claims millions. */
enum { MAX_PART_CHANNELS = 1024, MAX_TOTAL_CHANNELS = 8192, MAX_PARTS = 4096 };
/* The longest channel name OpenEXR allows (with the long-names flag). */
enum { MAX_NAME_BYTES = 255 };

static _Thread_local char exr_message[256];

/* The broken parts of the last file checked on this thread (internal_io_broken_part). More than
 * MAX_BROKEN of them and the file is refused whole, as one damaged beyond reading. */
enum { MAX_BROKEN = 16 };
static _Thread_local struct {
    int count;
    int part[MAX_BROKEN];
    char why[MAX_BROKEN][400];
} broken;

const char *internal_io_broken_part(int part)
{
    for (int i = 0; i < broken.count; i++)
        if (broken.part[i] == part) return broken.why[i];
    return NULL;
}

void internal_io_broken_reset(void)
{
    broken.count = 0;
}

static void on_exr_error(exr_const_context_t c, exr_result_t code, const char *msg)
{
    (void)c;
    /* The first message is the cause; later ones are its consequences. */
    if (!exr_message[0])
        snprintf(exr_message, sizeof exr_message, "%s",
                 msg && *msg ? msg : exr_get_default_error_message(code));
}

/* OpenEXRCore's message for rv, or its generic text for the code. */
static const char *exr_why(exr_result_t rv)
{
    if (exr_message[0]) return exr_message;
    return exr_get_default_error_message(rv);
}

int internal_io_is_exr(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    unsigned char m[4] = {0};
    size_t n = fread(m, 1, 4, f);
    fclose(f);
    return n == 4 && m[0] == 0x76 && m[1] == 0x2f && m[2] == 0x31 && m[3] == 0x01;
}

/* Unpacked bytes one packed byte may become, per compression: beyond it a chunk's leader lies.
 * Measured on all-zero 4096x256 images (whole files, so a little under the chunk ratio): RLE 62,
 * ZIPS 634, ZIP 960, PXR24 1251, PIZ 400, B44A 10.7, DWAA 6584, DWAB 13888; deflate's ceiling is
 * 1032 and RLE's 64. The bounds leave twice that or more: they are there to refuse a 779-byte
 * file that declares gigabytes, not to judge encoders. DWA's fixed overhead per chunk makes its
 * ratio grow with the chunk, so its bound is loose. */
static double max_ratio(exr_compression_t c)
{
    switch (c) {
    case EXR_COMPRESSION_NONE:
        return 1.0;
    case EXR_COMPRESSION_RLE:
        return 128.0;
    case EXR_COMPRESSION_ZIPS:
    case EXR_COMPRESSION_ZIP:
    case EXR_COMPRESSION_PXR24:
        return 2048.0;
    case EXR_COMPRESSION_PIZ:
        return 1024.0;
    case EXR_COMPRESSION_B44:
    case EXR_COMPRESSION_B44A:
        return 32.0;
    default:
        return 262144.0;
    }
}

/* A channel name fit to print and select: 1-255 bytes of valid UTF-8 without control
 * characters. Damaged headers give names of raw bytes; the reader must never pass them on. */
static const char *bad_name(const char *s, int len)
{
    if (len <= 0 || !s) return "it is empty";
    if (len > MAX_NAME_BYTES) return "it is longer than 255 bytes";
    const unsigned char *p = (const unsigned char *)s, *end = p + len;
    while (p < end) {
        unsigned c = *p;
        if (c == 0) return "it holds a NUL byte";
        if (c < 0x20 || c == 0x7f) return "it holds control characters";
        if (c < 0x80) {
            p++;
            continue;
        }
        int n = c >= 0xf0 && c <= 0xf4 ? 3 : c >= 0xe0 ? 2 : c >= 0xc2 && c < 0xe0 ? 1 : -1;
        if (c >= 0xf5) n = -1;
        if (n < 0 || end - p <= n) return "it is not valid UTF-8";
        for (int k = 1; k <= n; k++)
            if ((p[k] & 0xc0) != 0x80) return "it is not valid UTF-8";
        unsigned cp =
            n == 1   ? (c & 0x1f) << 6 | (p[1] & 0x3f)
            : n == 2 ? (c & 0x0f) << 12 | (p[1] & 0x3f) << 6 | (p[2] & 0x3f)
                     : (c & 0x07) << 18 | (p[1] & 0x3f) << 12 | (p[2] & 0x3f) << 6 | (p[3] & 0x3f);
        if ((n == 2 && cp < 0x800) || (n == 3 && (cp < 0x10000 || cp > 0x10ffff)) ||
            (cp >= 0xd800 && cp <= 0xdfff) || (cp >= 0x80 && cp < 0xa0))
            return "it is not valid UTF-8";
        p += n + 1;
    }
    return NULL;
}

/* The name as printable text: control and non-ASCII bytes escaped, at most ~40 bytes. */
static void escape_name(char *buf, size_t n, const char *s, int len)
{
    size_t o = 0;
    if (!s) len = 0;
    for (int i = 0; i < len && o + 8 < n && i < 40; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\')
            buf[o++] = (char)c;
        else
            o += (size_t)snprintf(buf + o, n - o, "\\x%02x", c);
    }
    if (len > 40 && o + 4 < n) o += (size_t)snprintf(buf + o, n - o, "...");
    buf[o < n ? o : n - 1] = 0;
}

/* ---- a raw walk over the header before OpenEXRCore parses it ----------------------------- */

/* OpenEXRCore inserts channels and attributes into sorted lists one at a time, so a damaged
 * header declaring 100000 channels costs it tens of seconds before any check of ours can run.
 * This walk reads only names, types and sizes, counts channels and attributes, and refuses
 * absurd counts first. */
enum { MAX_ATTRIBUTES = 4096 };

static int read_cstr(FILE *f, char *buf, int cap)
{
    for (int i = 0; i < cap; i++) {
        int c = fgetc(f);
        if (c == EOF) return -1;
        buf[i] = (char)c;
        if (!c) return i;
    }
    return -2; /* too long */
}

static nprfx_result prescan(nprfx_context *ctx, const char *path, uint64_t file_size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NPRFX_OK;
    unsigned char head[8];
    nprfx_result r = NPRFX_OK;
    if (fread(head, 1, 8, f) != 8) {
        fclose(f);
        return NPRFX_OK; /* OpenEXRCore says what is missing */
    }
    int multipart = (head[5] & 0x10) != 0;
    uint64_t pos = 8;
    char name[300], type[300];
    for (int part = 0; !r; part++) {
        if (part >= MAX_PARTS) {
            r = nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: it declares over %d parts", path,
                            MAX_PARTS);
            break;
        }
        int nattrs = 0, ended = 0;
        for (;;) {
            int nl = read_cstr(f, name, (int)sizeof name);
            if (nl < 0) { /* cut short or not text: OpenEXRCore words it */
                fclose(f);
                return NPRFX_OK;
            }
            pos += (uint64_t)nl + 1;
            if (nl == 0) {
                ended = 1;
                break;
            }
            int tl = read_cstr(f, type, (int)sizeof type);
            unsigned char sz[4];
            if (tl < 0 || fread(sz, 1, 4, f) != 4) {
                fclose(f);
                return NPRFX_OK;
            }
            pos += (uint64_t)tl + 1 + 4;
            uint32_t size = (uint32_t)sz[0] | (uint32_t)sz[1] << 8 | (uint32_t)sz[2] << 16 |
                            (uint32_t)sz[3] << 24;
            if ((int32_t)size < 0 || size > file_size - (pos < file_size ? pos : file_size)) {
                /* OpenEXRCore leaves an unknown attribute unread, but the OpenEXR library behind
                 * OIIO allocates and fills the declared size first: 1.9 GB and 10 s for a
                 * 2.7 KB file (a fuzz finding, tests/data/regressions/read/). */
                for (char *c = name; *c; c++)
                    if ((unsigned char)*c < 32 || (unsigned char)*c > 126) *c = '?';
                r = nprfx_error(ctx, NPRFX_ERR_IO,
                                "'%s' is damaged: header attribute '%s' of part %d declares %lld "
                                "bytes, past the end of the file (%llu bytes)",
                                path, name, part, (long long)(int32_t)size,
                                (unsigned long long)file_size);
                break;
            }
            if (++nattrs > MAX_ATTRIBUTES) {
                r = nprfx_error(ctx, NPRFX_ERR_IO,
                                "'%s' is damaged: part %d declares over %d header attributes", path,
                                part, MAX_ATTRIBUTES);
                break;
            }
            if (!strcmp(type, "chlist")) {
                /* Entries are a name, its NUL and 16 bytes; count them. */
                int nch = 0;
                uint32_t used = 0;
                while (used < size && nch <= MAX_PART_CHANNELS) {
                    int c = fgetc(f);
                    if (c == EOF) break;
                    used++;
                    if (c == 0) { /* the list's end, or an empty name */
                        if (used == size) break;
                    } else {
                        while (used < size && (c = fgetc(f)) != EOF && c != 0)
                            used++;
                        used++;
                    }
                    if (used + 16 > size) break;
                    if (fseek(f, 16, SEEK_CUR) != 0) break;
                    used += 16;
                    nch++;
                }
                if (nch > MAX_PART_CHANNELS) {
                    r = nprfx_error(ctx, NPRFX_ERR_IO,
                                    "'%s' is damaged: part %d declares over %d channels (1 to %d "
                                    "are readable)",
                                    path, part, MAX_PART_CHANNELS, MAX_PART_CHANNELS);
                    break;
                }
                if (fseek(f, (long)(pos + size), SEEK_SET) != 0) break;
            } else if (fseek(f, (long)size, SEEK_CUR) != 0) {
                break;
            }
            pos += size;
        }
        if (!ended || !multipart) break;
        int c = fgetc(f); /* a multi-part header list ends with an empty header */
        if (c == EOF || c == 0) break;
        ungetc(c, f);
    }
    fclose(f);
    return r;
}

typedef struct walk {
    nprfx_context *ctx;
    const char *path;
    exr_context_t f;
    int part;
    uint64_t file_size;
    double ratio;     /* 0: no ratio check (header mode) */
    double deadline;  /* 0: none */
    double timeout;   /* for the message */
    uint64_t visited; /* chunks checked so far, for the deadline's stride */
    int timed_out;    /* the walk stopped at the deadline, not at a damaged chunk */
} walk;

static nprfx_result chunk_ok(walk *w, exr_result_t rv, const exr_chunk_info_t *ci, const char *at)
{
    if (rv != EXR_ERR_SUCCESS)
        return nprfx_error(w->ctx, NPRFX_ERR_IO,
                           "'%s' is damaged: part %d, chunk at %s: %s (a truncated file or a "
                           "damaged chunk table)",
                           w->path, w->part, at, exr_why(rv));
    if (ci->data_offset > w->file_size || ci->packed_size > w->file_size - ci->data_offset)
        return nprfx_error(w->ctx, NPRFX_ERR_IO,
                           "'%s' is damaged: part %d, chunk at %s: %llu bytes at offset %llu run "
                           "past the end of the file (%llu bytes)",
                           w->path, w->part, at, (unsigned long long)ci->packed_size,
                           (unsigned long long)ci->data_offset, (unsigned long long)w->file_size);
    if (w->ratio > 0 && (double)ci->unpacked_size > w->ratio * (double)ci->packed_size + 64.0)
        return nprfx_error(w->ctx, NPRFX_ERR_IO,
                           "'%s' is damaged: part %d, chunk at %s: %llu packed bytes cannot hold "
                           "the %llu bytes its pixels need with this compression",
                           w->path, w->part, at, (unsigned long long)ci->packed_size,
                           (unsigned long long)ci->unpacked_size);
    if ((++w->visited & 63) == 0 && w->deadline > 0 && internal_io_now() > w->deadline) {
        w->timed_out = 1;
        return nprfx_error(w->ctx, NPRFX_ERR_IO,
                           "'%s': reading took longer than %g s while checking its %llu-th chunk "
                           "(NPRFX_READ_TIMEOUT)",
                           w->path, w->timeout, (unsigned long long)w->visited);
    }
    return NPRFX_OK;
}

static nprfx_result walk_scanlines(walk *w, const exr_attr_box2i_t *dw)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(w->f, w->part, &lines);
    if (rv != EXR_ERR_SUCCESS || lines < 1)
        return nprfx_error(w->ctx, NPRFX_ERR_IO, "'%s' is damaged: part %d: %s", w->path, w->part,
                           rv ? exr_why(rv) : "no scanlines per chunk");
    for (int64_t y = dw->min.y; y <= dw->max.y; y += lines) {
        exr_chunk_info_t ci;
        exr_message[0] = 0;
        rv = exr_read_scanline_chunk_info(w->f, w->part, (int)y, &ci);
        char at[64];
        snprintf(at, sizeof at, "scanline %lld", (long long)y);
        nprfx_result r = chunk_ok(w, rv, &ci, at);
        if (r) return r;
    }
    return NPRFX_OK;
}

static nprfx_result walk_tiles(walk *w)
{
    uint32_t tw = 0, th = 0;
    exr_tile_level_mode_t mode;
    exr_tile_round_mode_t round;
    int32_t nlx = 0, nly = 0;
    exr_message[0] = 0;
    exr_result_t rv = exr_get_tile_descriptor(w->f, w->part, &tw, &th, &mode, &round);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_tile_levels(w->f, w->part, &nlx, &nly);
    if (rv != EXR_ERR_SUCCESS || tw < 1 || th < 1 || nlx < 1 || nly < 1 || nlx > 64 || nly > 64)
        return nprfx_error(w->ctx, NPRFX_ERR_IO,
                           "'%s' is damaged: part %d: bad tile description%s%s", w->path, w->part,
                           rv ? ": " : "", rv ? exr_why(rv) : "");
    for (int ly = 0; ly < nly; ly++)
        for (int lx = 0; lx < nlx; lx++) {
            /* Mipmaps have only the diagonal levels; ripmaps every pair. */
            if (mode != EXR_TILE_RIPMAP_LEVELS && lx != ly) continue;
            /* A rip-map's levels lie row by row (ly, then lx), but OpenEXR 3.1's core library
             * indexes a level above the first row as if the rows below held only the levels
             * left of lx, and so looks for its tiles in other levels' chunks (it refused every
             * valid rip-map). A read takes level 0 alone, whose chunks are checked with the
             * first row's; the levels above it are never decoded. */
            if (mode == EXR_TILE_RIPMAP_LEVELS && ly > 0) continue;
            int32_t lw = 0, lh = 0;
            exr_message[0] = 0;
            rv = exr_get_level_sizes(w->f, w->part, lx, ly, &lw, &lh);
            if (rv != EXR_ERR_SUCCESS || lw < 1 || lh < 1)
                return nprfx_error(w->ctx, NPRFX_ERR_IO,
                                   "'%s' is damaged: part %d: level %d,%d has no size%s%s", w->path,
                                   w->part, lx, ly, rv ? ": " : "", rv ? exr_why(rv) : "");
            int64_t nx = ((int64_t)lw + tw - 1) / tw, ny = ((int64_t)lh + th - 1) / th;
            for (int64_t ty = 0; ty < ny; ty++)
                for (int64_t tx = 0; tx < nx; tx++) {
                    exr_chunk_info_t ci;
                    exr_message[0] = 0;
                    rv = exr_read_tile_chunk_info(w->f, w->part, (int)tx, (int)ty, lx, ly, &ci);
                    char at[80];
                    snprintf(at, sizeof at, "tile %lld,%lld level %d,%d", (long long)tx,
                             (long long)ty, lx, ly);
                    nprfx_result r = chunk_ok(w, rv, &ci, at);
                    if (r) return r;
                }
        }
    return NPRFX_OK;
}

/* Width or height of a box, or -1 when it is empty or beyond int (OpenImageIO's sizes). */
static int64_t box_extent(int32_t lo, int32_t hi)
{
    int64_t e = (int64_t)hi - (int64_t)lo + 1;
    return e >= 1 && e <= 0x7fffffff ? e : -1;
}

static nprfx_result validate_open(nprfx_context *ctx, const char *path, int mode, double deadline,
                                  double timeout, uint64_t file_size, exr_context_t f)
{
    int nparts = 0;
    exr_message[0] = 0;
    exr_result_t rv = exr_get_count(f, &nparts);
    if (rv != EXR_ERR_SUCCESS || nparts < 1 || nparts > MAX_PARTS)
        return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: %d parts%s%s", path, nparts,
                           rv ? ": " : "", rv ? exr_why(rv) : "");
    uint64_t limit;
    nprfx_result r = nprfx_image_limit(ctx, &limit);
    if (r) return r;
    int64_t total_channels = 0, x0 = 0, y0 = 0, x1 = 0, y1 = 0, uint_scratch = 0;
    int seen = 0;          /* pixel parts whose windows are in x0..y1 (deep parts are not) */
    uint64_t tile_row = 0; /* the largest row of tiles the reader decodes at once, in bytes */
    uint64_t table_bytes = 0;
    for (int p = 0; p < nparts; p++) {
        exr_storage_t st;
        exr_message[0] = 0;
        if ((rv = exr_get_storage(f, p, &st)) != EXR_ERR_SUCCESS)
            return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: part %d: %s", path, p,
                               exr_why(rv));
        /* Deep parts are never decoded: the reader skips them, or refuses a read that needs
         * one with a message that says how to flatten it, and `info` shows them. */
        if (st == EXR_STORAGE_DEEP_SCANLINE || st == EXR_STORAGE_DEEP_TILED) continue;
        if (st != EXR_STORAGE_SCANLINE && st != EXR_STORAGE_TILED)
            return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: part %d has no known storage",
                               path, p);
        exr_attr_box2i_t dw, disp;
        exr_message[0] = 0;
        if ((rv = exr_get_data_window(f, p, &dw)) != EXR_ERR_SUCCESS ||
            (rv = exr_get_display_window(f, p, &disp)) != EXR_ERR_SUCCESS)
            return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: part %d: %s", path, p,
                               exr_why(rv));
        int64_t w = box_extent(dw.min.x, dw.max.x), h = box_extent(dw.min.y, dw.max.y);
        if (w < 0 || h < 0)
            return nprfx_error(ctx, NPRFX_ERR_IO,
                               "'%s' is damaged: part %d: data window (%d,%d)-(%d,%d) is empty or "
                               "wider than 2^31",
                               path, p, dw.min.x, dw.min.y, dw.max.x, dw.max.y);
        if (box_extent(disp.min.x, disp.max.x) < 0 || box_extent(disp.min.y, disp.max.y) < 0)
            return nprfx_error(ctx, NPRFX_ERR_IO,
                               "'%s' is damaged: part %d: display window (%d,%d)-(%d,%d) is empty "
                               "or wider than 2^31",
                               path, p, disp.min.x, disp.min.y, disp.max.x, disp.max.y);
        const exr_attr_chlist_t *ch = NULL;
        exr_message[0] = 0;
        if ((rv = exr_get_channels(f, p, &ch)) != EXR_ERR_SUCCESS || !ch)
            return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: part %d: no channel list%s%s",
                               path, p, rv ? ": " : "", rv ? exr_why(rv) : "");
        if (ch->num_channels < 1 || ch->num_channels > MAX_PART_CHANNELS)
            return nprfx_error(ctx, NPRFX_ERR_IO,
                               "'%s' is damaged: part %d declares %d channels (1 to %d are "
                               "readable)",
                               path, p, ch->num_channels, MAX_PART_CHANNELS);
        int nuint = 0;
        for (int c = 0; c < ch->num_channels; c++) {
            const exr_attr_chlist_entry_t *e = &ch->entries[c];
            const char *why = bad_name(e->name.str, e->name.length);
            if (why) {
                char esc[200];
                escape_name(esc, sizeof esc, e->name.str, e->name.length);
                return nprfx_error(ctx, NPRFX_ERR_IO,
                                   "'%s' is damaged: part %d, channel %d has the name \"%s\": %s",
                                   path, p, c, esc, why);
            }
            if (e->x_sampling < 1 || e->y_sampling < 1)
                return nprfx_error(ctx, NPRFX_ERR_IO,
                                   "'%s' is damaged: part %d, channel '%s' has sampling %d,%d",
                                   path, p, e->name.str, e->x_sampling, e->y_sampling);
            if (e->pixel_type == EXR_PIXEL_UINT) nuint++;
        }
        /* Every chunk is stored in the file, so a part cannot decode to more than the file's
         * bytes times its compression's largest ratio. Checked in header mode too: opening a part
         * makes OpenEXR allocate its decoder for the declared window (2 GB for a one-byte flip
         * that widened a 6 KB file to 16 million pixels), before any pixel is read. */
        {
            exr_compression_t comp = EXR_COMPRESSION_NONE;
            exr_message[0] = 0;
            if ((rv = exr_get_compression(f, p, &comp)) != EXR_ERR_SUCCESS)
                return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: part %d: %s", path, p,
                                   exr_why(rv));
            double decoded = 0.0;
            for (int c = 0; c < ch->num_channels; c++) {
                const exr_attr_chlist_entry_t *e = &ch->entries[c];
                double bytes = e->pixel_type == EXR_PIXEL_HALF ? 2.0 : 4.0;
                decoded +=
                    bytes * ceil((double)w / e->x_sampling) * ceil((double)h / e->y_sampling);
            }
            double most = max_ratio(comp) * (double)file_size + 65536.0;
            /* A read that would pass the memory limit is worded by the limit check below, which
             * says which bound to raise (--mem-limit or NPRFX_READ_LIMIT). */
            double plate = (double)w * (double)h * (double)ch->num_channels * 4.0;
            int over_limit = mode == NPRFX_GUARD_READ && plate > (double)limit;
            if (decoded > most && !over_limit) {
                char need[32], have[32];
                nprfx_format_bytes(need, sizeof need, (uint64_t)decoded);
                nprfx_format_bytes(have, sizeof have, file_size);
                return nprfx_error(ctx, NPRFX_ERR_IO,
                                   "'%s' is damaged: part %d declares a %lldx%lld data window of "
                                   "%d channels (%s of pixels), more than a file of %s can hold",
                                   path, p, (long long)w, (long long)h, ch->num_channels, need,
                                   have);
            }
        }
        total_channels += ch->num_channels;
        if (total_channels > MAX_TOTAL_CHANNELS)
            return nprfx_error(ctx, NPRFX_ERR_IO,
                               "'%s' is damaged: its parts declare over %d channels", path,
                               MAX_TOTAL_CHANNELS);
        int32_t chunks = 0;
        exr_message[0] = 0;
        if ((rv = exr_get_chunk_count(f, p, &chunks)) != EXR_ERR_SUCCESS || chunks < 1)
            return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: part %d: %d chunks%s%s", path,
                               p, chunks, rv ? ": " : "", rv ? exr_why(rv) : "");
        /* Every chunk has an 8-byte entry in the offset table: a table larger than the file is
         * a damaged header, whatever the chunks hold. */
        table_bytes += (uint64_t)chunks * 8u;
        if (table_bytes > file_size)
            return nprfx_error(ctx, NPRFX_ERR_IO,
                               "'%s' is damaged: part %d declares %d chunks, a chunk table of "
                               "%llu bytes in a file of %llu bytes",
                               path, p, chunks, (unsigned long long)table_bytes,
                               (unsigned long long)file_size);
        if (st == EXR_STORAGE_TILED) {
            uint32_t tw = 0, th = 0;
            exr_tile_level_mode_t lm;
            exr_tile_round_mode_t rm;
            exr_message[0] = 0;
            if ((rv = exr_get_tile_descriptor(f, p, &tw, &th, &lm, &rm)) != EXR_ERR_SUCCESS ||
                tw < 1 || th < 1)
                return nprfx_error(ctx, NPRFX_ERR_IO,
                                   "'%s' is damaged: part %d: bad tile description%s%s", path, p,
                                   rv ? ": " : "", rv ? exr_why(rv) : "");
            /* OpenImageIO decodes a whole row of full tiles at a time, whatever the window: a
             * damaged tile height of 16 million makes it allocate gigabytes for a 50x34 image.
             * No writer makes tiles that much larger than the image. */
            double row = (double)th * (double)((w + tw - 1) / tw) * (double)tw *
                         (double)ch->num_channels * 4.0;
            double plate = (double)w * (double)h * (double)ch->num_channels * 4.0;
            if (row > 4.0 * plate && row > 64.0 * 1024 * 1024)
                return nprfx_error(ctx, NPRFX_ERR_IO,
                                   "'%s' is damaged: part %d: tiles of %ux%u for a %lldx%lld data "
                                   "window",
                                   path, p, tw, th, (long long)w, (long long)h);
            if (row > (double)tile_row) tile_row = (uint64_t)row;
        }
        if (!seen || dw.min.x < x0) x0 = dw.min.x;
        if (!seen || dw.min.y < y0) y0 = dw.min.y;
        if (!seen || (int64_t)dw.max.x + 1 > x1) x1 = (int64_t)dw.max.x + 1;
        if (!seen || (int64_t)dw.max.y + 1 > y1) y1 = (int64_t)dw.max.y + 1;
        seen = 1;
        /* UINT channels are read into a scratch buffer of their own before the cast. */
        if ((int64_t)nuint * w * h > uint_scratch) uint_scratch = (int64_t)nuint * w * h;
    }
    /* NPRFX_GUARD_READ_CHOSEN: the reader checks the channels it delivers itself. */
    if (mode == NPRFX_GUARD_READ) {
        /* What the read allocates: one float per channel per pixel of all parts' windows, and
         * the scratch of UINT channels and of a row of tiles. */
        char what[4200];
        snprintf(what, sizeof what, "'%s': data window", path);
        double scratch = (double)uint_scratch * 4.0 + (double)tile_row;
        if ((r = nprfx_image_limit_check(ctx, what, x1 - x0, y1 - y0, total_channels,
                                         scratch > 1.8e19 ? UINT64_MAX : (uint64_t)scratch)))
            return r;
    }
    /* The chunks are walked on a context of their own: a broken part is a finding to keep, not
     * an error to raise through the caller's (whose handler may print it at once). */
    nprfx_context *wctx = NULL;
    nprfx_context_init wi = NPRFX_CONTEXT_INIT_DEFAULT;
    if (nprfx_context_create(&wi, &wctx))
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "'%s': out of memory", path);
    walk wk = {wctx, path, f, 0, file_size, 0.0, deadline, timeout, 0, 0};
    int whole = 0; /* pixel parts whose chunks are all in place */
    for (int p = 0; p < nparts; p++) {
        exr_storage_t st;
        exr_compression_t comp = EXR_COMPRESSION_NONE;
        exr_attr_box2i_t dw;
        exr_message[0] = 0;
        if ((rv = exr_get_storage(f, p, &st)) != EXR_ERR_SUCCESS ||
            (rv = exr_get_compression(f, p, &comp)) != EXR_ERR_SUCCESS ||
            (rv = exr_get_data_window(f, p, &dw)) != EXR_ERR_SUCCESS) {
            nprfx_context_destroy(wctx);
            return nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: part %d: %s", path, p,
                               exr_why(rv));
        }
        if (st == EXR_STORAGE_DEEP_SCANLINE || st == EXR_STORAGE_DEEP_TILED) continue;
        wk.part = p;
        wk.ratio = mode != NPRFX_GUARD_HEADER ? max_ratio(comp) : 0.0;
        r = st == EXR_STORAGE_TILED ? walk_tiles(&wk) : walk_scanlines(&wk, &dw);
        if (r && !wk.timed_out && broken.count < MAX_BROKEN) {
            /* A part's chunks are its own: the others may still be whole (checked on). */
            broken.part[broken.count] = p;
            nprfx_context_last_error(wctx, broken.why[broken.count], sizeof broken.why[0]);
            broken.count++;
            continue;
        }
        if (r) {
            char why[600];
            nprfx_context_last_error(wctx, why, sizeof why);
            nprfx_context_destroy(wctx);
            return nprfx_error(ctx, r, "%s", why);
        }
        whole++;
    }
    nprfx_context_destroy(wctx);
    if (broken.count && !whole) /* nothing to read: the first part's reason */
        return nprfx_error(ctx, NPRFX_ERR_IO, "%s", broken.why[0]);
    if (deadline > 0 && internal_io_now() > deadline)
        return nprfx_error(ctx, NPRFX_ERR_IO,
                           "'%s': reading took longer than %g s while checking its %llu chunks "
                           "(NPRFX_READ_TIMEOUT)",
                           path, timeout, (unsigned long long)wk.visited);
    return NPRFX_OK;
}

nprfx_result internal_io_validate_exr(nprfx_context *ctx, const char *path, int mode,
                                      double deadline)
{
    struct stat sb;
    if (stat(path, &sb) != 0 || !S_ISREG(sb.st_mode))
        return NPRFX_OK; /* the reader reports a missing or special file in its own words */
    double timeout = 0;
    nprfx_result r = internal_io_read_timeout(ctx, &timeout);
    if (r || (r = prescan(ctx, path, (uint64_t)sb.st_size))) return r;
    broken.count = 0;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    /* A damaged offset table is refused, never rebuilt by scanning the whole file (what made
     * some damaged files take seconds in OpenImageIO). */
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    exr_context_t f = NULL;
    exr_message[0] = 0;
    exr_result_t rv = exr_start_read(&f, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        r = nprfx_error(ctx, NPRFX_ERR_IO, "'%s' is damaged: its header cannot be read: %s", path,
                        exr_why(rv));
        exr_finish(&f);
        return r;
    }
    r = validate_open(ctx, path, mode, deadline, timeout, (uint64_t)sb.st_size, f);
    exr_finish(&f);
    return r;
}
