/* nprfx CLI — image file I/O: the types its C headers share (plates, file descriptions, read and
 * write options). The readers and writers (io_read.h, io_write.h, io_preview.h, io_colour.h; C++
 * behind C headers: OpenImageIO for files, OpenColorIO for colour) and plate.h declare the
 * functions. Every writer writes to a temporary name in the target directory and
 * renames it into place, so an interrupted or failed write never leaves a partial file and never
 * touches an input. Errors name the file, and the layer or channel when one is at fault. */
#ifndef NPRFX_CLI_IO_H
#define NPRFX_CLI_IO_H

#include "nprfx/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The pixel type a channel has in its file, so that a copy can write it back the same way. */
typedef enum cli_pixel_type {
    NPRFX_PIXEL_FLOAT = 0, /* float, or any non-EXR type (read as normalised float) */
    NPRFX_PIXEL_HALF = 1,
    NPRFX_PIXEL_UINT = 2 /* EXR uint (object ids): read as integers, exact up to 2^24 */
} cli_pixel_type;

/* A decoded plate: the channels of one part of an image file (or of several parts with the same
 * data and display windows), interleaved. docs/design.md §2.3 says which parts a read takes. */
typedef struct cli_plate {
    nprfx_rect bounds;  /* data window */
    nprfx_rect display; /* display window */
    int nchannels;
    char **names;         /* nchannels full channel names ("ViewLayer.Vector.X") */
    float *pixels;        /* nchannels floats per pixel, rows of bounds' width, top row first */
    unsigned char *types; /* nchannels cli_pixel_type */
    float pixel_aspect;   /* the PixelAspectRatio attribute (1 when absent) */
    /* What a user should know about the read (malloc'd, NULL when nothing): which parts and view
     * were used and which parts were not, uint values beyond float's exact range. */
    char *note;
    int note_is_warning; /* 1: parts were left out or values were rounded */
} cli_plate;

/* Which part and view of a file a read takes. */
typedef struct cli_read_options {
    size_t size;      /* sizeof(cli_read_options) */
    const char *part; /* a part's name or index (NULL or "": the default, below) */
    const char *view; /* a view of a multi-view file (NULL or "": the file's default view) */
    /* Channel selections (channels.h syntax) the caller needs: without `part`, the read takes
     * the first group of parts (same data and display window) of the view that holds them all. */
    const char *const *want;
    int nwant;
    /* Appended (read when size covers them). The channels to read, by the names a whole read
     * gives them (cli_plate.names), in the order the plate should have them; NULL: all. Only
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
} cli_read_options;

/* One part (subimage) of a file, for `nprfx info`. */
typedef struct cli_part_info {
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
} cli_part_info;

/* Header facts for `nprfx info`. */
typedef struct cli_file_info {
    char format[32]; /* "openexr" */
    int subimages;
    nprfx_rect bounds, display; /* what a default read delivers */
    int nchannels;              /* ditto */
    char **names;               /* nchannels */
    char **types;               /* nchannels: "half", "float", "uint8", ... */
    char compression[32];       /* "" when not applicable */
    int nparts;                 /* == subimages */
    cli_part_info *parts;
    int nviews; /* the multiView attribute, or the parts' views; views[0] is the default */
    char **views;
} cli_file_info;

/* A header attribute, given as text and stored with its type (EXR: int, float or string). */
typedef enum cli_attribute_type {
    NPRFX_ATTR_STRING = 0,
    NPRFX_ATTR_INT = 1,
    NPRFX_ATTR_FLOAT = 2
} cli_attribute_type;
typedef struct cli_attribute {
    const char *name; /* "nprfx:pamCount" */
    int type;         /* cli_attribute_type */
    const char *value;
} cli_attribute;

typedef struct cli_write_options {
    size_t size;                     /* sizeof(cli_write_options) */
    const char *compression;         /* EXR: "zip" (default), "piz", "none", "dwaa", ... */
    int half;                        /* 1: store EXR channels as half floats */
    const cli_attribute *attributes; /* extra header attributes (NULL: none) */
    int nattributes;
    /* Appended: read when size covers them. */
    const unsigned char *types; /* per channel cli_pixel_type (NULL: all float, or half);
                                   with `half`, float channels become half, uint stays uint */
    float pixel_aspect;         /* the PixelAspectRatio attribute (0: not written) */
} cli_write_options;

#ifdef __cplusplus
}
#endif
#endif
