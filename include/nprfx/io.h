/* nprfx — images in files, as the graph engine (nprfx/graph.h) reads and writes them: the types
 * plates and file descriptions have, the memory bound every image is checked against, and
 * nprfx_io, the table of functions through which the engine reaches files. libnprfx itself
 * reads and writes no image file: a front end passes an nprfx_io, e.g. libnprfx-io's
 * nprfx_io_oiio() (nprfx/io_oiio.h: OpenImageIO for files, OpenColorIO for colour). Every writer
 * writes to a temporary name in the target directory and renames it into place, so an
 * interrupted or failed write never leaves a partial file and never touches an input; errors
 * name the file, and the layer or channel when one is at fault. */
#ifndef NPRFX_IO_H
#define NPRFX_IO_H

#include <stddef.h>
#include <stdint.h>

#include "nprfx/export.h"
#include "nprfx/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The pixel type a channel has in its file, so that a copy can write it back the same way. */
typedef enum nprfx_pixel_type {
    NPRFX_PIXEL_FLOAT = 0, /* float, or any non-EXR type (read as normalised float) */
    NPRFX_PIXEL_HALF = 1,
    NPRFX_PIXEL_UINT = 2 /* EXR uint (object ids): read as ids, exactly (nprfx/objectid.h) */
} nprfx_pixel_type;

/* A decoded plate: the channels of one part of an image file (or of several parts with the same
 * data and display windows), interleaved. docs/design.md §2.3 says which parts a read takes. */
typedef struct nprfx_plate {
    nprfx_rect bounds;  /* data window */
    nprfx_rect display; /* display window */
    int nchannels;
    char **names;         /* nchannels full channel names ("ViewLayer.Vector.X") */
    float *pixels;        /* nchannels floats per pixel, rows of bounds' width, top row first */
    unsigned char *types; /* nchannels nprfx_pixel_type */
    float pixel_aspect;   /* the PixelAspectRatio attribute (1 when absent) */
    /* What a user should know about the read (malloc'd, NULL when nothing): which parts and view
     * were used and which parts were not. */
    char *note;
    int note_is_warning; /* 1: parts were left out */
} nprfx_plate;

/* Which part and view of a file a read takes. */
typedef struct nprfx_read_options {
    size_t size;      /* sizeof(nprfx_read_options) */
    const char *part; /* a part's name or index (NULL or "": the default, below) */
    const char *view; /* a view of a multi-view file (NULL or "": the file's default view) */
    /* Channel selections (channels.h syntax) the caller needs: without `part`, the read takes
     * the first group of parts (same data and display window) of the view that holds them all. */
    const char *const *want;
    int nwant;
    /* Appended (read when size covers them). The channels to read, by the names a whole read
     * gives them (nprfx_plate.names), in the order the plate should have them; NULL: all. Only
     * these are decoded into the plate (EXR: a block of whole chunks at a time, converting only
     * the span of a part's channels that holds them) and counted against the memory limit. */
    const char *const *channels;
    int nchannels;
    /* Without `channels`: chosen once the names are known, from the same look at the header.
     * Called with the n names a whole read would deliver, in order, before any pixel is read;
     * fills pick (room for n) with indices into names and returns how many, or 0 or less for
     * all of them. */
    int (*pick)(void *user, const char *const *names, int n, int *pick);
    void *pick_user;
} nprfx_read_options;

/* One part (subimage) of a file, for `nprfx info`. */
typedef struct nprfx_part_info {
    int index;
    char name[128]; /* "" when unnamed */
    char view[64];  /* the part's "view" attribute, "" when none */
    nprfx_rect bounds, display;
    int nchannels;
    char **names, **types;
    int deep;           /* 1: deep data (refused by reads) */
    int tile_w, tile_h; /* 0: scanlines */
    int miplevels;      /* 1: no MIP map */
    float pixel_aspect; /* PixelAspectRatio */
    int used;           /* 1: a read without "part" or "view" takes it */
    int broken;         /* 1: its pixels are missing or damaged (an unfinished render): reads
                           leave it out, and refuse to take it by "part" */
} nprfx_part_info;

/* Header facts for `nprfx info`. */
typedef struct nprfx_file_info {
    char format[32]; /* "openexr" */
    int subimages;
    nprfx_rect bounds, display; /* what a default read delivers */
    int nchannels;              /* ditto */
    char **names;               /* nchannels */
    char **types;               /* nchannels: "half", "float", "uint8", ... */
    char compression[32];       /* "" when not applicable */
    int nparts;                 /* == subimages */
    nprfx_part_info *parts;
    int nviews; /* the multiView attribute, or the parts' views; views[0] is the default */
    char **views;
    /* The header attributes of the part a default read takes first, as text (a renderer's
     * "arnold/version", Cryptomatte's "cryptomatte/KEY/manifest"): names and values. */
    int nattributes;
    char **attr_names, **attr_values;
} nprfx_file_info;

/* A header attribute, given as text and stored with its type (EXR: int, float or string). */
typedef enum nprfx_attribute_type {
    NPRFX_ATTR_STRING = 0,
    NPRFX_ATTR_INT = 1,
    NPRFX_ATTR_FLOAT = 2
} nprfx_attribute_type;
typedef struct nprfx_attribute {
    const char *name; /* "nprfx:pamCount" */
    int type;         /* nprfx_attribute_type */
    const char *value;
} nprfx_attribute;

typedef struct nprfx_write_options {
    size_t size;                       /* sizeof(nprfx_write_options) */
    const char *compression;           /* EXR: "zip" (default), "piz", "none", "dwaa", ... */
    int half;                          /* 1: store EXR channels as half floats */
    const nprfx_attribute *attributes; /* extra header attributes (NULL: none) */
    int nattributes;
    /* Appended: read when size covers them. */
    const unsigned char *types; /* per channel nprfx_pixel_type (NULL: all float, or half);
                                   with `half`, float channels become half, uint stays uint */
    float pixel_aspect;         /* the PixelAspectRatio attribute (0: not written) */
} nprfx_write_options;

/* ---- plates and file descriptions in memory ------------------------------------------------ */
NPRFX_API void nprfx_plate_free(nprfx_plate *p);
/* A view of channels [first, first+count) of the plate (shares pixels). */
NPRFX_API nprfx_image nprfx_plate_view(const nprfx_plate *p, int first, int count);
/* Index of a channel by exact name, or -1. */
NPRFX_API int nprfx_plate_channel(const nprfx_plate *p, const char *name);
/* Free what an nprfx_io's info filled in. */
NPRFX_API void nprfx_file_info_free(nprfx_file_info *info);

/* ---- the memory bound ---------------------------------------------------------------------
 * One bound covers the images held at once: every image made in one piece (a plate read from a
 * file, a synth frame, a node's output frame) is checked against it before anything is
 * allocated, so a damaged header that declares a 2000000000x3 window, or a graph asking for a
 * 16384x16384 frame of 27 channels, is refused with the size and the limit instead of failing
 * after gigabytes; and a graph's frames together are held under it. The bound is the context's
 * (nprfx_context_set_memory_limit), else NPRFX_READ_LIMIT ("4G", "512M", "1073741824"; "0": none),
 * else half the physical memory. */

/* The bound in bytes (UINT64_MAX: none). A malformed NPRFX_READ_LIMIT is an error. */
NPRFX_API nprfx_result nprfx_image_limit(nprfx_context *ctx, uint64_t *bytes);
/* What set the bound, for messages: the context's origin ("--mem-limit"), "NPRFX_READ_LIMIT" or
 * the default. */
NPRFX_API const char *nprfx_memory_limit_origin(const nprfx_context *ctx);
/* Parse a size: "4G", "512M", "1.5GiB", "1073741824"; "0" is no limit (UINT64_MAX).
 * NPRFX_ERR_INVALID_ARGUMENT (nothing raised) when text is not one. */
NPRFX_API nprfx_result nprfx_parse_size(const char *text, uint64_t *bytes);
/* "44.7 GiB", "512 MiB", "900 bytes": sizes in messages. */
NPRFX_API void nprfx_format_bytes(char *buf, size_t n, uint64_t bytes);
/* Refuse an image of w x h pixels and `channels` float channels (plus extra_bytes of scratch)
 * when it would exceed the bound: "WHAT WxH with N channels needs 27.0 GiB, above the 4 GiB
 * memory limit (NPRFX_READ_LIMIT)". what names the file, node or option and what the size is
 * ("'a.exr': data window", "synth --size"). */
NPRFX_API nprfx_result nprfx_image_limit_check(nprfx_context *ctx, const char *what, int64_t w,
                                               int64_t h, int64_t channels, uint64_t extra_bytes);

/* ---- the engine's way to files --------------------------------------------------------------
 * Every function reports errors through ctx, naming the file. A table may leave functions NULL:
 * what needs one then fails with a message naming it. */
typedef struct nprfx_row_reader nprfx_row_reader;
typedef struct nprfx_row_writer nprfx_row_writer;
typedef struct nprfx_preview_options {
    size_t size; /* sizeof(nprfx_preview_options) */
    const char *ocio_config;
    const char *colorspace;
    const char *display;
    const char *view;
    int raw; /* 1: no transform at all (data passes: noise, masks), values clamped to [0,1] */
} nprfx_preview_options;

typedef struct nprfx_io {
    size_t size; /* sizeof(nprfx_io) */
    /* Decode a plate (opt may be NULL: the default part, every channel). */
    nprfx_result (*read)(nprfx_context *ctx, const char *path, const nprfx_read_options *opt,
                         nprfx_plate *out);
    /* Read a plate by rows: *shape gets everything but pixels; rows [y0, y1) of the data
     * window go to dst (shape's channels interleaved, its width per row). */
    nprfx_result (*rows_open)(nprfx_context *ctx, const char *path, const nprfx_read_options *opt,
                              nprfx_plate *shape, nprfx_row_reader **out);
    nprfx_result (*rows_read)(nprfx_context *ctx, nprfx_row_reader *r, int y0, int y1, float *dst);
    void (*rows_close)(nprfx_row_reader *r);
    /* Header facts of every part, no pixel read. */
    nprfx_result (*info)(nprfx_context *ctx, const char *path, nprfx_file_info *out);
    /* Write an image with its channel names (display NULL: the data window). */
    nprfx_result (*write)(nprfx_context *ctx, const char *path, const nprfx_image *im,
                          const char *const *names, const nprfx_rect *display,
                          const nprfx_write_options *opt);
    /* Write by rows: rows_write takes the next rows in order; rows_finish renames the file into
     * place (keep 0: removes it). */
    nprfx_result (*rows_create)(nprfx_context *ctx, const char *path, nprfx_rect bounds,
                                int channels, const char *const *names, const nprfx_rect *display,
                                const nprfx_write_options *opt, nprfx_row_writer **out);
    nprfx_result (*rows_write)(nprfx_context *ctx, nprfx_row_writer *w, const nprfx_image *rows);
    nprfx_result (*rows_finish)(nprfx_context *ctx, nprfx_row_writer *w, int keep);
    /* A text file (exports), written as images are: temporary name, then rename. */
    nprfx_result (*write_text)(nprfx_context *ctx, const char *path, const char *text, size_t len);
    /* An 8-bit display preview (PNG, JPEG) of a scene-linear image. */
    nprfx_result (*write_preview)(nprfx_context *ctx, const char *path, const nprfx_image *im,
                                  const nprfx_preview_options *opt);
    /* Convert im's colour channels in place between two colour spaces of the OCIO config
     * (NULL: $OCIO, else the built-in one). */
    nprfx_result (*convert_colorspace)(nprfx_context *ctx, nprfx_image *im, const char *from,
                                       const char *to, const char *ocio_config);
    /* Appended (read when size covers it): the read's note on parts and views, as the shape
     * has it; *note malloc'd, NULL when there is none. */
    nprfx_result (*rows_note)(nprfx_context *ctx, nprfx_row_reader *r, char **note, int *warning);
} nprfx_io;

#ifdef __cplusplus
}
#endif
#endif
