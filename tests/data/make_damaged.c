/* nprfx test data — a corpus of damaged EXRs, made from valid ones this program writes itself.
 * Nothing is copied from elsewhere: the bases are written with OpenEXRCore's encoder,
 * the crafted files byte by byte, and every damaged file is a base with a known defect.
 *
 *   nprfx_make_damaged OUTDIR [EXTRA.exr...]
 *
 * writes OUTDIR/base/NAME.exr (valid: scanline and tiled, none/rle/zips/zip/piz, half/float/uint,
 * mipmapped, multi-part) and OUTDIR/damaged/NAME.exr. A damaged file's name says what was done and
 * what a reader must do: "must-*" files cannot be read correctly and must be refused; "any-*"
 * files may still decode (a flipped byte in an unused attribute) and must be read correctly or
 * refused. Extra valid EXRs given after OUTDIR are damaged the same way (the test passes a
 * mipmapped one). tests/cli/corpus_damaged.sh runs nprfx on each; the fuzz targets use them as
 * seeds. */
#define _DEFAULT_SOURCE
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <OpenEXR/openexr.h>

static const char *outdir;
static int nwritten;

static void die(const char *what, const char *detail)
{
    fprintf(stderr, "make_damaged: %s: %s\n", what, detail);
    exit(1);
}

static void write_file(const char *dir, const char *name, const unsigned char *data, size_t n)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s/%s", outdir, dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || (n && fwrite(data, 1, n, f) != n) || fclose(f) != 0) die(path, strerror(errno));
    nwritten++;
}

static unsigned char *read_file(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) die(path, strerror(errno));
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *d = malloc((size_t)len + 1);
    if (!d || fread(d, 1, (size_t)len, f) != (size_t)len) die(path, "cannot read");
    fclose(f);
    *n = (size_t)len;
    return d;
}

/* ---- valid bases, through OpenEXRCore's encoder ------------------------------------------ */

typedef struct chan {
    const char *name;
    exr_pixel_type_t type;
} chan;

typedef struct part_desc {
    const char *name;
    const chan *channels;
    int nchannels;
    exr_compression_t compression;
    int tiled; /* 0 scanline; else tile size */
    exr_tile_level_mode_t levels;
} part_desc;

/* A deterministic, not too compressible pattern: channel c at (x, y) of level (lx, ly). */
static float pattern(int c, int x, int y, int l)
{
    return (float)((x * 7 + y * 13 + c * 5 + l * 3) % 23) * 0.25f - 1.0f;
}

static void check(exr_result_t rv, const char *what)
{
    if (rv != EXR_ERR_SUCCESS) die(what, exr_get_default_error_message(rv));
}

/* Encode one chunk of w x h pixels at (x, y) of level l for every channel of the part. */
static void encode_chunk(exr_context_t f, int p, const part_desc *pd, exr_chunk_info_t *ci,
                         exr_encode_pipeline_t *enc, int *inited, int x, int y, int w, int h, int l)
{
    float *fbuf = malloc((size_t)w * h * pd->nchannels * sizeof(float));
    uint32_t *ubuf = malloc((size_t)w * h * pd->nchannels * sizeof(uint32_t));
    if (!fbuf || !ubuf) die("encode", "out of memory");
    for (int c = 0; c < pd->nchannels; c++)
        for (int j = 0; j < h; j++)
            for (int i = 0; i < w; i++) {
                size_t k = ((size_t)c * h + j) * w + i;
                float v = pattern(c, x + i, y + j, l);
                fbuf[k] = v;
                ubuf[k] = (uint32_t)((x + i + 2 * (y + j) + c) % 9);
            }
    if (!*inited) {
        check(exr_encoding_initialize(f, p, ci, enc), "exr_encoding_initialize");
        *inited = 1;
    } else {
        check(exr_encoding_update(f, p, ci, enc), "exr_encoding_update");
    }
    /* The pipeline's channels are sorted by name; find each one's plane by name. */
    for (int k = 0; k < enc->channel_count; k++) {
        exr_coding_channel_info_t *cc = &enc->channels[k];
        int c = 0;
        while (c < pd->nchannels && strcmp(pd->channels[c].name, cc->channel_name))
            c++;
        if (c == pd->nchannels) die("encode", "channel not found");
        int is_uint = pd->channels[c].type == EXR_PIXEL_UINT;
        cc->user_pixel_stride = 4;
        cc->user_line_stride = 4 * w;
        cc->user_bytes_per_element = 4;
        cc->user_data_type = is_uint ? EXR_PIXEL_UINT : EXR_PIXEL_FLOAT;
        cc->encode_from_ptr = is_uint ? (const uint8_t *)(ubuf + (size_t)c * w * h)
                                      : (const uint8_t *)(fbuf + (size_t)c * w * h);
    }
    check(exr_encoding_choose_default_routines(f, p, enc), "choose routines");
    check(exr_encoding_run(f, p, enc), "exr_encoding_run");
    free(fbuf);
    free(ubuf);
}

static void write_base(const char *name, int width, int height, const part_desc *parts, int nparts)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/base/%s", outdir, name);
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t f;
    check(exr_start_write(&f, path, EXR_WRITE_FILE_DIRECTLY, &init), path);
    for (int p = 0; p < nparts; p++) {
        const part_desc *pd = &parts[p];
        int idx;
        check(exr_add_part(f, pd->name, pd->tiled ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE, &idx),
              "exr_add_part");
        check(exr_initialize_required_attr_simple(f, idx, width, height, pd->compression),
              "required attributes");
        for (int c = 0; c < pd->nchannels; c++)
            check(exr_add_channel(f, idx, pd->channels[c].name, pd->channels[c].type,
                                  EXR_PERCEPTUALLY_LINEAR, 1, 1),
                  "exr_add_channel");
        if (pd->tiled)
            check(exr_set_tile_descriptor(f, idx, (uint32_t)pd->tiled, (uint32_t)pd->tiled,
                                          pd->levels, EXR_TILE_ROUND_DOWN),
                  "tile descriptor");
        exr_attr_set_string(f, idx, "comments", "nprfx damaged-file corpus base");
    }
    check(exr_write_header(f), "exr_write_header");
    for (int p = 0; p < nparts; p++) {
        const part_desc *pd = &parts[p];
        exr_encode_pipeline_t enc;
        memset(&enc, 0, sizeof enc);
        int inited = 0;
        exr_chunk_info_t ci;
        if (!pd->tiled) {
            int32_t lpc;
            check(exr_get_scanlines_per_chunk(f, p, &lpc), "scanlines per chunk");
            for (int y = 0; y < height; y += lpc) {
                check(exr_write_scanline_chunk_info(f, p, y, &ci), "scanline chunk info");
                encode_chunk(f, p, pd, &ci, &enc, &inited, 0, y, width,
                             y + lpc > height ? height - y : lpc, 0);
            }
        } else {
            int32_t nlx, nly;
            check(exr_get_tile_levels(f, p, &nlx, &nly), "tile levels");
            for (int l = 0; l < nlx && l < nly; l++) {
                int32_t lw, lh;
                check(exr_get_level_sizes(f, p, l, l, &lw, &lh), "level sizes");
                int t = pd->tiled;
                for (int ty = 0; ty * t < lh; ty++)
                    for (int tx = 0; tx * t < lw; tx++) {
                        check(exr_write_tile_chunk_info(f, p, tx, ty, l, l, &ci), "tile info");
                        int w = tx * t + t > lw ? lw - tx * t : t;
                        int h = ty * t + t > lh ? lh - ty * t : t;
                        encode_chunk(f, p, pd, &ci, &enc, &inited, tx * t, ty * t, w, h, l);
                    }
            }
        }
        if (inited) exr_encoding_destroy(f, &enc);
    }
    check(exr_finish(&f), "exr_finish");
    nwritten++;
}

static void write_bases(void)
{
    static const chan rgba_half[] = {
        {"R", EXR_PIXEL_HALF}, {"G", EXR_PIXEL_HALF}, {"B", EXR_PIXEL_HALF}, {"A", EXR_PIXEL_HALF}};
    static const chan float_z[] = {{"R", EXR_PIXEL_FLOAT},
                                   {"G", EXR_PIXEL_FLOAT},
                                   {"B", EXR_PIXEL_FLOAT},
                                   {"Z", EXR_PIXEL_FLOAT}};
    static const chan with_id[] = {{"R", EXR_PIXEL_HALF},
                                   {"G", EXR_PIXEL_HALF},
                                   {"B", EXR_PIXEL_HALF},
                                   {"IndexOB.X", EXR_PIXEL_UINT}};
    static const chan mixed[] = {{"ViewLayer.Combined.R", EXR_PIXEL_HALF},
                                 {"ViewLayer.Depth.Z", EXR_PIXEL_FLOAT},
                                 {"ViewLayer.IndexOB.X", EXR_PIXEL_UINT},
                                 {"ViewLayer.Vector.X", EXR_PIXEL_HALF},
                                 {"ViewLayer.Vector.Y", EXR_PIXEL_HALF}};
    static const chan aov[] = {{"Z", EXR_PIXEL_FLOAT}, {"id", EXR_PIXEL_UINT}};
    part_desc p;
    p = (part_desc){"rgba", rgba_half, 4, EXR_COMPRESSION_ZIP, 0, EXR_TILE_ONE_LEVEL};
    write_base("scan_zip_half.exr", 37, 41, &p, 1);
    p = (part_desc){"rgbz", float_z, 4, EXR_COMPRESSION_PIZ, 0, EXR_TILE_ONE_LEVEL};
    write_base("scan_piz_float.exr", 40, 70, &p, 1);
    p = (part_desc){"id", with_id, 4, EXR_COMPRESSION_NONE, 0, EXR_TILE_ONE_LEVEL};
    write_base("scan_none_uint.exr", 23, 9, &p, 1);
    p = (part_desc){"mixed", mixed, 5, EXR_COMPRESSION_RLE, 0, EXR_TILE_ONE_LEVEL};
    write_base("scan_rle_mixed.exr", 30, 20, &p, 1);
    p = (part_desc){"zips", float_z, 4, EXR_COMPRESSION_ZIPS, 0, EXR_TILE_ONE_LEVEL};
    write_base("scan_zips_float.exr", 16, 12, &p, 1);
    p = (part_desc){"tiles", rgba_half, 4, EXR_COMPRESSION_ZIP, 16, EXR_TILE_ONE_LEVEL};
    write_base("tile_zip_half.exr", 50, 34, &p, 1);
    /* No mipmapped base here: OpenEXRCore 3.1's writer sizes the partial tiles of levels above
     * 0 as level 0's, which its own reader then refuses; the test adds one written by oiiotool
     * (-otex) as an extra base. */
    p = (part_desc){"none", mixed, 5, EXR_COMPRESSION_NONE, 8, EXR_TILE_ONE_LEVEL};
    write_base("tile_none_mixed.exr", 17, 11, &p, 1);
    part_desc mp[2] = {{"beauty", rgba_half, 4, EXR_COMPRESSION_ZIP, 0, EXR_TILE_ONE_LEVEL},
                       {"aov", aov, 2, EXR_COMPRESSION_RLE, 0, EXR_TILE_ONE_LEVEL}};
    write_base("multipart_zip_rle.exr", 33, 25, mp, 2);
    part_desc mt[2] = {{"beauty", rgba_half, 4, EXR_COMPRESSION_PIZ, 16, EXR_TILE_ONE_LEVEL},
                       {"aov", aov, 2, EXR_COMPRESSION_ZIP, 0, EXR_TILE_ONE_LEVEL}};
    write_base("multipart_tiled.exr", 40, 18, mt, 2);
}

/* ---- where things are in a base ---------------------------------------------------------- */

typedef struct attr {
    int part;
    char name[64], type[64];
    size_t value; /* offset of the value */
    uint32_t size;
} attr;

typedef struct layout {
    attr attrs[256];
    int nattrs;
    size_t header_end;    /* first byte after the header(s): the offset table */
    size_t table_end;     /* first chunk */
    size_t part0_end;     /* first byte after part 0's chunks (the file's size when single-part) */
    size_t part0_entries; /* part 0's entries in the offset table */
} layout;

static uint32_t rd32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void wr32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void wr64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static uint64_t rd64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--)
        v = v << 8 | p[i];
    return v;
}

static const attr *find_attr(const layout *L, int part, const char *name);

static void parse_layout(const unsigned char *d, size_t n, layout *L)
{
    memset(L, 0, sizeof *L);
    int multipart = (d[5] & 0x10) != 0; /* version flags, bit 12 */
    size_t o = 8;
    int part = 0;
    for (;;) {
        if (o >= n) die("layout", "header runs past the end");
        if (d[o] == 0) { /* end of a header */
            o++;
            if (!multipart) break;
            part++;
            if (o < n && d[o] == 0) { /* end of the header list */
                o++;
                break;
            }
            continue;
        }
        attr *a = &L->attrs[L->nattrs < 255 ? L->nattrs++ : 255];
        a->part = part;
        size_t k = 0;
        while (d[o] && k < 63)
            a->name[k++] = (char)d[o++];
        a->name[k] = 0;
        o++;
        k = 0;
        while (d[o] && k < 63)
            a->type[k++] = (char)d[o++];
        a->type[k] = 0;
        o++;
        a->size = rd32(d + o);
        o += 4;
        a->value = o;
        o += a->size;
    }
    L->header_end = o;
    /* The first chunk begins where the table ends: the smallest offset in it. */
    uint64_t first = n;
    for (size_t t = o; t + 8 <= n && t < first; t += 8) {
        uint64_t v = rd64(d + t);
        if (v > o && v < first) first = v;
    }
    L->table_end = (size_t)first;
    /* Part 0's chunks: those its offsets name (its entries lead the table), each a leader (part
     * number; y, or tile x, y and levels; packed size) and its packed bytes. */
    L->part0_end = n;
    L->part0_entries = (L->table_end - L->header_end) / 8;
    const attr *cc = find_attr(L, 0, "chunkCount");
    if (multipart && cc && cc->size == 4) {
        size_t count = rd32(d + cc->value), lead = find_attr(L, 0, "tiles") ? 20 : 8, end = 0;
        for (size_t e = 0; e < count && o + 8 * e + 8 <= n; e++) {
            uint64_t v = rd64(d + o + 8 * e);
            if (v + lead + 4 > n) continue;
            size_t stop = (size_t)v + lead + 4 + rd32(d + v + lead);
            if (stop > end) end = stop;
        }
        if (end > 0 && end <= n) L->part0_end = end;
        L->part0_entries = count;
    }
}

static const attr *find_attr(const layout *L, int part, const char *name)
{
    for (int i = 0; i < L->nattrs; i++)
        if (L->attrs[i].part == part && !strcmp(L->attrs[i].name, name)) return &L->attrs[i];
    return NULL;
}

/* ---- damage ------------------------------------------------------------------------------- */

static unsigned char *copy_of(const unsigned char *d, size_t n)
{
    unsigned char *c = malloc(n ? n : 1);
    if (!c) die("copy", "out of memory");
    memcpy(c, d, n);
    return c;
}

static void emit(const char *kind, const char *base, const char *what, const unsigned char *d,
                 size_t n)
{
    char name[512];
    char stem[128];
    snprintf(stem, sizeof stem, "%s", base);
    char *dot = strrchr(stem, '.');
    if (dot) *dot = 0;
    snprintf(name, sizeof name, "%s-%s-%s.exr", kind, stem, what);
    write_file("damaged", name, d, n);
}

static void damage_truncate(const char *base, const unsigned char *d, size_t n, const layout *L)
{
    size_t cuts[256];
    int nc = 0;
    size_t fixed[] = {0, 1, 3, 4, 7, 8, 9, 12, 20};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        cuts[nc++] = fixed[i];
    for (size_t o = 16; o < L->header_end && nc < 80; o += 29)
        cuts[nc++] = o;
    size_t around[] = {L->header_end - 1,
                       L->header_end,
                       L->header_end + 1,
                       (L->header_end + L->table_end) / 2,
                       L->table_end - 1,
                       L->table_end,
                       L->table_end + 4,
                       L->table_end + 8,
                       n - 1};
    for (size_t i = 0; i < sizeof around / sizeof around[0]; i++)
        cuts[nc++] = around[i];
    for (int k = 1; k < 16; k++)
        cuts[nc++] = L->table_end + (n - L->table_end) * (size_t)k / 16;
    for (int i = 0; i < nc; i++) {
        if (cuts[i] >= n) continue;
        int dup = 0;
        for (int j = 0; j < i; j++)
            dup |= cuts[j] == cuts[i];
        if (dup) continue;
        char what[64];
        snprintf(what, sizeof what, "truncated-at-%zu", cuts[i]);
        /* Cut after part 0's chunks, a multi-part file is unfinished in its later parts: part 0
         * still reads (with a warning naming the others), or the file is refused. */
        emit(cuts[i] >= L->part0_end ? "any" : "must", base, what, d, cuts[i]);
    }
}

/* Flipped header bytes: every stride-th byte of the header, xor 0xff and xor 0x01 (a small
 * change keeps names printable and sizes plausible, which is the harder case). */
static void damage_flip(const char *base, const unsigned char *d, size_t n, const layout *L,
                        int stride)
{
    for (size_t o = 0; o < L->header_end; o += (size_t)stride) {
        for (int v = 0; v < 2; v++) {
            if (v && stride == 1 && (o & 1)) continue; /* the small change at every other byte */
            unsigned char *c = copy_of(d, n);
            c[o] ^= v ? 0x01 : 0xff;
            char what[64];
            snprintf(what, sizeof what, "flip%s-at-%zu", v ? "1" : "ff", o);
            /* The magic number and the version's low byte are checked by every reader. */
            emit(o < 5 ? "must" : "any", base, what, c, n);
            free(c);
        }
    }
}

static void damage_windows(const char *base, const unsigned char *d, size_t n, const layout *L)
{
    static const struct {
        const char *what, *kind;
        int32_t b[4];
    } wins[] = {
        {"window-2000000000x3", "must", {0, 0, 1999999999, 2}},
        {"window-3x2000000000", "must", {0, 0, 2, 1999999999}},
        {"window-65536x65536", "must", {0, 0, 65535, 65535}},
        {"window-100000x100000", "must", {0, 0, 99999, 99999}},
        {"window-full-int-range", "must", {INT32_MIN, INT32_MIN, INT32_MAX, INT32_MAX}},
        {"window-inverted", "must", {10, 10, 0, 0}},
        {"window-negative-huge", "must", {-2000000000, 0, 0, 7}},
        {"window-1x1", "any", {0, 0, 0, 0}},
        {"window-shifted", "any", {5, 5, 41, 45}},
    };
    for (int part = 0; part < 2; part++) {
        const char *names[] = {"dataWindow", "displayWindow"};
        for (int which = 0; which < 2; which++) {
            const attr *a = find_attr(L, part, names[which]);
            if (!a || a->size != 16) continue;
            for (size_t i = 0; i < sizeof wins / sizeof wins[0]; i++) {
                unsigned char *c = copy_of(d, n);
                for (int k = 0; k < 4; k++)
                    wr32(c + a->value + 4 * k, (uint32_t)wins[i].b[k]);
                char what[96];
                snprintf(what, sizeof what, "p%d-%s-%s", part, which ? "display" : "data",
                         wins[i].what);
                /* A display window is only metadata: any value that parses may be read. */
                const char *kind = which ? "any" : wins[i].kind;
                emit(kind, base, what, c, n);
                free(c);
            }
        }
    }
}

static void damage_table(const char *base, const unsigned char *d, size_t n, const layout *L)
{
    size_t t0 = L->header_end, t1 = L->table_end;
    size_t entries = (t1 - t0) / 8;
    if (entries < 1) return;
    static const struct {
        const char *what;
        int mode;
        uint64_t v;
    } edits[] = {
        {"offset0-zero", 0, 0},
        {"offset0-past-end", 0, 1u << 20},
        {"offset0-2p63", 0, (uint64_t)1 << 63},
        {"offset0-max", 0, UINT64_MAX},
        {"offset0-into-header", 0, 8},
        {"offset0-into-table", 0, 1},
        {"offsetlast-past-end", 1, 1u << 20},
        {"offsetlast-minus1", 2, 0},
        {"all-offsets-first", 3, 0},
        {"offsets-reversed", 4, 0},
        {"offsets-zero", 5, 0},
        {"offset0-plus4", 6, 0},
    };
    for (size_t i = 0; i < sizeof edits / sizeof edits[0]; i++) {
        unsigned char *c = copy_of(d, n);
        size_t last = t0 + (entries - 1) * 8;
        switch (edits[i].mode) {
        case 0:
            wr64(c + t0, edits[i].mode == 0 && edits[i].v == 1 ? t0 + 4 : edits[i].v);
            break;
        case 1:
            wr64(c + last, n + edits[i].v);
            break;
        case 2:
            wr64(c + last, rd64(c + last) - 1);
            break;
        case 3:
            for (size_t e = 0; e < entries; e++)
                wr64(c + t0 + 8 * e, rd64(d + t0));
            break;
        case 4:
            for (size_t e = 0; e < entries; e++)
                wr64(c + t0 + 8 * e, rd64(d + t0 + 8 * (entries - 1 - e)));
            break;
        case 5:
            memset(c + t0, 0, t1 - t0);
            break;
        case 6:
            wr64(c + t0, rd64(d + t0) + 4);
            break;
        }
        /* Reversed offsets of a one-chunk part are the same table. The last entry of a
         * multi-part file belongs to its last part: part 0 still reads, or the file is refused. */
        int same = memcmp(c, d, n) == 0;
        int later = (edits[i].mode == 1 || edits[i].mode == 2) && entries > L->part0_entries;
        if (!same) emit(later ? "any" : "must", base, edits[i].what, c, n);
        free(c);
    }
    /* A chunk leader claiming a huge packed size, and one claiming the wrong scanline. */
    unsigned char *c = copy_of(d, n);
    uint64_t first = rd64(d + t0);
    int tiled = (d[5] & 0x02) != 0 || find_attr(L, 0, "tiles") != NULL;
    size_t size_at = (size_t)first + (tiled ? 16 : 4) + (((d[5] & 0x10) != 0) ? 4 : 0);
    if (size_at + 4 <= n) {
        wr32(c + size_at, 0x7fffffff);
        emit("must", base, "chunk0-size-2g", c, n);
        memcpy(c, d, n);
        wr32(c + size_at, 0);
        emit("must", base, "chunk0-size-0", c, n);
        memcpy(c, d, n);
        wr32(c + size_at - 4, rd32(d + size_at - 4) + 1000);
        emit("must", base, "chunk0-coordinate-wrong", c, n);
    }
    free(c);
}

/* Multi-part headers carry chunkCount; a single-part one does not. */
static void damage_chunk_count(const char *base, const unsigned char *d, size_t n, const layout *L)
{
    static const struct {
        const char *what;
        int64_t delta;
        int32_t abs;
    } cc[] = {{"chunkcount-0", 0, 0},           {"chunkcount-minus1", 0, -1},
              {"chunkcount-2g", 0, 0x7fffffff}, {"chunkcount-1m", 0, 1000000},
              {"chunkcount-plus1", 1, 0},       {"chunkcount-less1", -1, 0}};
    for (int part = 0; part < 2; part++) {
        const attr *a = find_attr(L, part, "chunkCount");
        if (!a || a->size != 4) continue;
        for (size_t i = 0; i < sizeof cc / sizeof cc[0]; i++) {
            unsigned char *c = copy_of(d, n);
            int32_t v =
                cc[i].delta ? (int32_t)rd32(d + a->value) + (int32_t)cc[i].delta : cc[i].abs;
            wr32(c + a->value, (uint32_t)v);
            char what[64];
            snprintf(what, sizeof what, "p%d-%s", part, cc[i].what);
            /* Both OpenEXR libraries count chunks from the window and ignore the attribute, so
             * such a file still decodes as it was written. */
            emit("any", base, what, c, n);
            free(c);
        }
    }
}

static void damage_fields(const char *base, const unsigned char *d, size_t n, const layout *L)
{
    const attr *a = find_attr(L, 0, "compression");
    if (a && a->size == 1)
        for (int v = 0; v < 12; v++) {
            if (v == d[a->value]) continue;
            unsigned char *c = copy_of(d, n);
            c[a->value] = (unsigned char)(v == 11 ? 255 : v);
            char what[64];
            snprintf(what, sizeof what, "compression-%d", c[a->value]);
            /* Another codec on these chunks: garbage or an error, unless it is a twin. */
            emit("any", base, what, c, n);
            free(c);
        }
    a = find_attr(L, 0, "tiles");
    if (a && a->size == 9) {
        static const uint32_t sizes[][2] = {
            {0x7fffffff, 0x7fffffff}, {0, 16}, {1, 1}, {65536, 65536}, {1, 0x40000000}};
        for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
            unsigned char *c = copy_of(d, n);
            wr32(c + a->value, sizes[i][0]);
            wr32(c + a->value + 4, sizes[i][1]);
            char what[64];
            snprintf(what, sizeof what, "tiles-%ux%u", sizes[i][0], sizes[i][1]);
            emit("must", base, what, c, n);
            free(c);
        }
        for (int lm = 1; lm < 4; lm++) {
            unsigned char *c = copy_of(d, n);
            c[a->value + 8] = (unsigned char)(lm == 3 ? 0x7f : lm);
            if (c[a->value + 8] != d[a->value + 8]) {
                char what[64];
                snprintf(what, sizeof what, "tile-levels-%d", c[a->value + 8]);
                emit("must", base, what, c, n);
            }
            free(c);
        }
    }
    /* Version flags: tiled, long names, deep, multi-part bits set or cleared, version 1 and 3. */
    static const struct {
        const char *what;
        int byte;
        unsigned char xor_;
    } flags[] = {{"version-flag-tiled", 5, 0x02}, {"version-flag-longnames", 5, 0x04},
                 {"version-flag-deep", 5, 0x08},  {"version-flag-multipart", 5, 0x10},
                 {"version-number-3", 4, 0x01},   {"version-number-0", 4, 0x02}};
    for (size_t i = 0; i < sizeof flags / sizeof flags[0]; i++) {
        unsigned char *c = copy_of(d, n);
        c[flags[i].byte] ^= flags[i].xor_;
        emit(!strcmp(flags[i].what, "version-flag-longnames") ? "any" : "must", base, flags[i].what,
             c, n);
        free(c);
    }
    /* The channel list with a huge declared size, and with its end marker gone. */
    a = find_attr(L, 0, "channels");
    if (a) {
        unsigned char *c = copy_of(d, n);
        wr32(c + a->value - 4, 0x7ffffff0);
        emit("must", base, "chlist-size-2g", c, n);
        memcpy(c, d, n);
        c[a->value + a->size - 1] = 'x';
        emit("must", base, "chlist-no-end", c, n);
        memcpy(c, d, n);
        /* The first channel's type: 3 is no pixel type. */
        size_t t = a->value + strlen((const char *)d + a->value) + 1;
        wr32(c + t, 3);
        emit("must", base, "channel-type-3", c, n);
        memcpy(c, d, n);
        wr32(c + t + 8, 0); /* x sampling 0 */
        emit("must", base, "channel-xsampling-0", c, n);
        memcpy(c, d, n);
        wr32(c + t + 8, 0x40000000);
        emit("must", base, "channel-xsampling-huge", c, n);
        free(c);
    }
}

/* ---- crafted files: a NONE scanline header written byte by byte --------------------------- */

typedef struct buf {
    unsigned char *d;
    size_t n, cap;
} buf;

static void put(buf *b, const void *p, size_t n)
{
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2 + 1024;
        b->d = realloc(b->d, b->cap);
        if (!b->d) die("craft", "out of memory");
    }
    memcpy(b->d + b->n, p, n);
    b->n += n;
}

static void put32(buf *b, uint32_t v)
{
    unsigned char t[4];
    wr32(t, v);
    put(b, t, 4);
}

static void put_attr_head(buf *b, const char *name, const char *type, uint32_t size)
{
    put(b, name, strlen(name) + 1);
    put(b, type, strlen(type) + 1);
    put32(b, size);
}

/* A width x height NONE scanline file with the given channels (names as raw bytes of the given
 * lengths, all half), complete with its table and chunks. */
static void craft(const char *what, const char *kind, int width, int height, int nch,
                  const char *const *names, const int *lens, int long_names)
{
    buf b = {0};
    unsigned char magic[8] = {0x76, 0x2f, 0x31, 0x01, 2, (unsigned char)(long_names ? 4 : 0), 0, 0};
    put(&b, magic, 8);
    size_t chsize = 1;
    for (int c = 0; c < nch; c++)
        chsize += (size_t)lens[c] + 1 + 16;
    put_attr_head(&b, "channels", "chlist", (uint32_t)chsize);
    for (int c = 0; c < nch; c++) {
        put(&b, names[c], (size_t)lens[c]);
        put(&b, "", 1);
        put32(&b, 1); /* half */
        put32(&b, 0); /* pLinear + reserved */
        put32(&b, 1);
        put32(&b, 1);
    }
    put(&b, "", 1);
    put_attr_head(&b, "compression", "compression", 1);
    put(&b, "", 1); /* NONE */
    for (int w = 0; w < 2; w++) {
        put_attr_head(&b, w ? "displayWindow" : "dataWindow", "box2i", 16);
        put32(&b, 0);
        put32(&b, 0);
        put32(&b, (uint32_t)(width - 1));
        put32(&b, (uint32_t)(height - 1));
    }
    put_attr_head(&b, "lineOrder", "lineOrder", 1);
    put(&b, "", 1);
    float one = 1.0f, zero[2] = {0, 0};
    put_attr_head(&b, "pixelAspectRatio", "float", 4);
    put(&b, &one, 4);
    put_attr_head(&b, "screenWindowCenter", "v2f", 8);
    put(&b, zero, 8);
    put_attr_head(&b, "screenWindowWidth", "float", 4);
    put(&b, &one, 4);
    put(&b, "", 1);
    size_t table = b.n;
    size_t line_bytes = (size_t)width * 2 * (size_t)nch;
    for (int y = 0; y < height; y++) {
        unsigned char o[8];
        wr64(o, table + (size_t)height * 8 + (size_t)y * (8 + line_bytes));
        put(&b, o, 8);
    }
    unsigned char *line = calloc(line_bytes ? line_bytes : 1, 1);
    for (size_t i = 0; i + 1 < line_bytes; i += 2)
        line[i + 1] = 0x3c; /* half 1.0 */
    for (int y = 0; y < height; y++) {
        put32(&b, (uint32_t)y);
        put32(&b, (uint32_t)line_bytes);
        put(&b, line, line_bytes);
    }
    free(line);
    emit(kind, "crafted", what, b.d, b.n);
    free(b.d);
}

static void crafted(void)
{
    /* Control characters, invalid UTF-8, a long name, an empty one, DEL, a newline. */
    static const struct {
        const char *what, *kind;
        const char *name;
        int len;
    } bad[] = {
        {"name-control", "must", "R\x01G", 3},
        {"name-invalid-utf8", "must", "\xff\xfe\xfd", 3},
        {"name-overlong-utf8", "must", "\xc0\xaf", 2},
        {"name-newline", "must", "A\nB", 3},
        {"name-del", "must", "R\x7f", 2},
        {"name-escape", "must", "\x1b[31mred", 8},
        {"name-utf8-ok", "any", "d\xc3\xa9j\xc3\xa0", 7},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        const char *names[2] = {"A", bad[i].name};
        int lens[2] = {1, bad[i].len};
        craft(bad[i].what, bad[i].kind, 4, 2, 2, names, lens, 0);
    }
    {
        const char *names[1] = {""};
        int lens[1] = {0};
        craft("name-empty", "must", 4, 2, 1, names, lens, 0);
    }
    {
        static char longname[300];
        memset(longname, 'L', sizeof longname);
        const char *names[1] = {longname};
        int lens[1] = {300};
        craft("name-300-bytes", "must", 4, 2, 1, names, lens, 1);
    }
    {
        const char *names[2] = {"R", "R"};
        int lens[2] = {1, 1};
        craft("name-twice", "any", 4, 2, 2, names, lens, 0);
    }
    /* Channel counts past what a reader takes: a complete 1x1 file each. */
    static const int counts[] = {1025, 5000, 100000};
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
        int n = counts[i];
        char **names = malloc((size_t)n * sizeof *names);
        int *lens = malloc((size_t)n * sizeof *lens);
        for (int c = 0; c < n; c++) {
            names[c] = malloc(16);
            lens[c] = snprintf(names[c], 16, "c%06d", c);
        }
        char what[64];
        snprintf(what, sizeof what, "channels-%d", n);
        craft(what, "must", 1, 1, n, (const char *const *)names, lens, 0);
        for (int c = 0; c < n; c++)
            free(names[c]);
        free(names);
        free(lens);
    }
    /* A valid crafted file, so the crafted writer is known to be right. */
    {
        const char *names[3] = {"B", "G", "R"};
        int lens[3] = {1, 1, 1};
        craft("valid", "any", 5, 3, 3, names, lens, 0);
    }
    /* Tiny and empty files. */
    static const unsigned char head[] = {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0, 'c', 'h'};
    write_file("damaged", "must-crafted-empty.exr", head, 0);
    write_file("damaged", "must-crafted-magic-only.exr", head, 4);
    write_file("damaged", "must-crafted-magic-version.exr", head, 8);
    write_file("damaged", "must-crafted-attr-name-cut.exr", head, 10);
}

/* The 'memory DOS' shape: a file of a few hundred bytes whose header declares a window of
 * gigabytes, with a one-chunk table that is consistent with it. */
static void memory_dos(void)
{
    const char *names[1] = {"Y"};
    int lens[1] = {1};
    (void)names;
    (void)lens;
    buf b = {0};
    unsigned char magic[8] = {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0};
    put(&b, magic, 8);
    put_attr_head(&b, "channels", "chlist", 2 + 16 + 1);
    put(&b, "Y", 2);
    put32(&b, 2); /* float */
    put32(&b, 0);
    put32(&b, 1);
    put32(&b, 1);
    put(&b, "", 1);
    put_attr_head(&b, "compression", "compression", 1);
    unsigned char zip = 3;
    put(&b, &zip, 1);
    for (int w = 0; w < 2; w++) {
        put_attr_head(&b, w ? "displayWindow" : "dataWindow", "box2i", 16);
        put32(&b, 0);
        put32(&b, 0);
        put32(&b, 200000000 - 1); /* 2e8 x 16 floats: 12 GiB in one chunk */
        put32(&b, 15);
    }
    put_attr_head(&b, "lineOrder", "lineOrder", 1);
    put(&b, "", 1);
    float one = 1.0f, zero[2] = {0, 0};
    put_attr_head(&b, "pixelAspectRatio", "float", 4);
    put(&b, &one, 4);
    put_attr_head(&b, "screenWindowCenter", "v2f", 8);
    put(&b, zero, 8);
    put_attr_head(&b, "screenWindowWidth", "float", 4);
    put(&b, &one, 4);
    put(&b, "", 1);
    unsigned char o[8];
    wr64(o, b.n + 8);
    put(&b, o, 8);
    put32(&b, 0);
    put32(&b, 64);
    unsigned char junk[64];
    for (int i = 0; i < 64; i++)
        junk[i] = (unsigned char)(i * 37 + 11);
    put(&b, junk, 64);
    emit("must", "crafted", "memory-dos-12gib-window", b.d, b.n);
    /* The same window at 2e6 wide (122 MiB): under the memory bound, refused by the ratio. */
    for (size_t k = 0; k + 8 <= b.n; k++)
        if (!memcmp(b.d + k, "dataWindow", 10)) {
            wr32(b.d + k + 11 + 6 + 4 + 8, 2000000 - 1);
            break;
        }
    emit("must", "crafted", "ratio-122mib-from-64-bytes", b.d, b.n);
    free(b.d);
}

static void mkdir_or_die(const char *path)
{
    if (mkdir(path, 0777) != 0 && errno != EEXIST) die(path, strerror(errno));
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: nprfx_make_damaged OUTDIR [EXTRA.exr...]\n");
        return 2;
    }
    outdir = argv[1];
    char path[4096];
    mkdir_or_die(outdir);
    snprintf(path, sizeof path, "%s/base", outdir);
    mkdir_or_die(path);
    snprintf(path, sizeof path, "%s/damaged", outdir);
    mkdir_or_die(path);
    write_bases();
    static const char *const bases[] = {
        "scan_zip_half.exr",   "scan_piz_float.exr",    "scan_none_uint.exr",
        "scan_rle_mixed.exr",  "scan_zips_float.exr",   "tile_zip_half.exr",
        "tile_none_mixed.exr", "multipart_zip_rle.exr", "multipart_tiled.exr"};
    const int nbases = (int)(sizeof bases / sizeof bases[0]);
    for (int i = 0; i < nbases + argc - 2; i++) {
        const char *name = i < nbases ? bases[i] : strrchr(argv[2 + i - nbases], '/');
        name = name ? name + (i >= nbases) : argv[2 + i - nbases];
        if (i < nbases)
            snprintf(path, sizeof path, "%s/base/%s", outdir, bases[i]);
        else
            snprintf(path, sizeof path, "%s", argv[2 + i - nbases]);
        size_t n;
        unsigned char *d = read_file(path, &n);
        layout L;
        parse_layout(d, n, &L);
        damage_truncate(name, d, n, &L);
        /* Every header byte of two bases, fewer of the others: the header fields repeat. */
        damage_flip(name, d, n, &L, i == 0 || i == 5 || i == 7 ? 1 : 17);
        damage_windows(name, d, n, &L);
        damage_table(name, d, n, &L);
        damage_chunk_count(name, d, n, &L);
        damage_fields(name, d, n, &L);
        free(d);
    }
    crafted();
    memory_dos();
    printf("make_damaged: %d files in %s\n", nwritten, outdir);
    return 0;
}
