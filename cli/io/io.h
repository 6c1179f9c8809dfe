/* nprfx CLI — image file I/O behind a C header.
 *
 * The only C++ in the project lives behind this header (io_oiio.cpp: OpenImageIO for files,
 * OpenColorIO for colour). Every writer writes to a temporary name in the target directory and
 * renames it into place, so an interrupted or failed write never leaves a partial file and never
 * touches an input. Errors name the file, and the layer or channel when one is at fault. */
#ifndef NPRFX_CLI_IO_H
#define NPRFX_CLI_IO_H

#include "nprfx/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The pixel type a channel has in its file, so that a copy can write it back the same way. */
typedef enum nprfx_pixel_type {
    NPRFX_PIXEL_FLOAT = 0, /* float, or any non-EXR type (read as normalised float) */
    NPRFX_PIXEL_HALF = 1,
    NPRFX_PIXEL_UINT = 2 /* EXR uint (object ids): read as integers, exact up to 2^24 */
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
     * were used and which parts were not, uint values beyond float's exact range. */
    char *note;
    int note_is_warning; /* 1: parts were left out or values were rounded */
} nprfx_plate;

void nprfx_plate_free(nprfx_plate *p);
/* A view of channels [first, first+count) of the plate (shares pixels). */
nprfx_image nprfx_plate_view(const nprfx_plate *p, int first, int count);
/* Index of a channel by exact name, or -1. */
int nprfx_plate_channel(const nprfx_plate *p, const char *name);

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

/* Read a file's default part group: the first part of the default view and every other part
 * of that view with the same data and display windows, concatenated (repeated channel names get
 * the part's name as a prefix). Deep parts are refused; tiled and MIP-mapped parts are read at
 * level 0. */
nprfx_result nprfx_io_read(nprfx_context *ctx, const char *path, nprfx_plate *out);
/* The same with a part, a view and the channels wanted (opt NULL: as nprfx_io_read). */
nprfx_result nprfx_io_read_ex(nprfx_context *ctx, const char *path, const nprfx_read_options *opt,
                              nprfx_plate *out);

/* A plate a strip of rows at a time (EXR), for the runner's strip renders (docs/design.md §1
 * "Memory"): opened with the same options as nprfx_io_read_ex, *shape gets the plate's
 * description (everything but pixels); then any rows [y0, y1) of the data window, in any order,
 * are decoded into dst (shape's nchannels floats per pixel, rows of the window's width), a block
 * of whole chunks at a time, so the read never holds more than its block. The memory limit
 * counts the block, not the plate. Other formats: NPRFX_ERR_UNSUPPORTED. */
typedef struct nprfx_row_reader nprfx_row_reader;
nprfx_result nprfx_io_rows_open(nprfx_context *ctx, const char *path, const nprfx_read_options *opt,
                                nprfx_plate *shape, nprfx_row_reader **out);
nprfx_result nprfx_io_rows_read(nprfx_context *ctx, nprfx_row_reader *r, int y0, int y1,
                                float *dst);
void nprfx_io_rows_close(nprfx_row_reader *r);

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
} nprfx_file_info;
nprfx_result nprfx_io_info(nprfx_context *ctx, const char *path, nprfx_file_info *out);
void nprfx_file_info_free(nprfx_file_info *info);

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

/* The header attributes of a file's first subimage whose names begin with `prefix`, as text
 * (ints and floats printed, strings as they are); *names and *values are arrays of *count
 * strings, freed with nprfx_attributes_free. */
nprfx_result nprfx_io_read_attributes(nprfx_context *ctx, const char *path, const char *prefix,
                                      char ***names, char ***values, int *count);
void nprfx_attributes_free(char **names, char **values, int count);

/* Write an EXR (or any format OIIO knows, by extension) with the given channel names
 * (names may be NULL: default names by count). display: the display window (NULL = bounds). */
nprfx_result nprfx_io_write(nprfx_context *ctx, const char *path, const nprfx_image *im,
                            const char *const *names, const nprfx_rect *display,
                            const nprfx_write_options *opt);

/* An image written a strip of rows at a time, top to bottom: as nprfx_io_write (same header,
 * types and options, a temporary name beside path), but each nprfx_io_rows_write gives the next
 * rows (full width of bounds), and nprfx_io_rows_finish with keep renames the file into place
 * once every row is written; without keep (or on any error) the temporary file is removed. The
 * writer is freed by finish. */
typedef struct nprfx_row_writer nprfx_row_writer;
nprfx_result nprfx_io_rows_create(nprfx_context *ctx, const char *path, nprfx_rect bounds,
                                  int channels, const char *const *names, const nprfx_rect *display,
                                  const nprfx_write_options *opt, nprfx_row_writer **out);
nprfx_result nprfx_io_rows_write(nprfx_context *ctx, nprfx_row_writer *w, const nprfx_image *rows);
nprfx_result nprfx_io_rows_finish(nprfx_context *ctx, nprfx_row_writer *w, int keep);

/* Write an 8-bit PNG preview of a scene-linear image. 1 channel: grey; 2: R,G (B = 0); 3: RGB;
 * 4: RGBA. With an OCIO config (ocio_config path, or $OCIO when NULL) the image goes from
 * `colorspace` (NULL: the config's scene_linear role) through display/view (NULL: the config's
 * defaults); with no config, the plain sRGB transfer function is applied. */
typedef struct nprfx_preview_options {
    size_t size;
    const char *ocio_config;
    const char *colorspace;
    const char *display;
    const char *view;
    int raw; /* 1: no transform at all (data passes: noise, masks), values clamped to [0,1] */
} nprfx_preview_options;
nprfx_result nprfx_io_write_preview(nprfx_context *ctx, const char *path, const nprfx_image *im,
                                    const nprfx_preview_options *opt);

/* Write len bytes of text to path through a temporary name and a rename, creating missing
 * parent directories (vector exports: CSV, SVG). */
nprfx_result nprfx_io_write_text(nprfx_context *ctx, const char *path, const char *text,
                                 size_t len);

/* Convert the first three channels of im in place from colour space `from` to `to` (names from
 * the OCIO config, or "linear"/"srgb" without one). Same names: no-op. */
nprfx_result nprfx_io_convert_colorspace(nprfx_context *ctx, nprfx_image *im, const char *from,
                                         const char *to, const char *ocio_config);

#ifdef __cplusplus
}
#endif
#endif
