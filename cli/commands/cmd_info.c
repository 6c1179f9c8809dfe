/* nprfx info — a plate's format, size, windows, subimages, compression and channels by layer.
 *
 * Compact like `iinfo -v`: one header line per file, then one line per layer, so a Blender
 * multilayer EXR with fifty channels still fits on a screen. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "nprfx/io.h"
#include "io/io_colour.h"
#include "nprfx/io_oiio.h"
#include "nprfx/io_oiio.h"
#include "io/io_write.h"
#include "nprfx/io.h"
#include "info_aovs.h"
#include "io_check.h"

/* Exit codes follow idiff: a file that cannot be read is 4. */
enum { INFO_OK = 0, INFO_USAGE = 2, INFO_FILE_ERROR = 4 };

static void usage(FILE *f)
{
    fprintf(f, "usage: nprfx info FILE...\n"
               "       nprfx info --aovs FILE... [--styles DIR]\n\n"
               "Print each image's format, size, data and display windows, subimages,\n"
               "compression and channels grouped by layer with their pixel types, e.g.\n"
               "  ViewLayer.Vector: X Y Z W (half)\n"
               "The first lines describe what a read node takes by default; then the views of a\n"
               "stereo file, tiles, MIP levels, pixel aspect and deep data, and each part of a\n"
               "multi-part file with its windows and channels.\n\n"
               "With --aovs: the renderer profile the plate is read with, each canonical AOV\n"
               "(beauty, depth, id, motion_prev, ...) with the channels a read gives it, what\n"
               "stands in for one it lacks (uv for rest, optical flow for motion, ...) or that\n"
               "it is missing; then every sample style graph (share/nprfx/graphs, or DIR) with\n"
               "its plate pointed at the file: runs as is, runs with fallbacks, or does not run\n"
               "and why. Nothing is rendered.\n\n"
               "Exit status: 0 all files read, 2 usage error, 4 a file could not be read.\n");
}

static void print_error(void *user, const nprfx_context *ctx, nprfx_result code,
                        const char *message)
{
    (void)code;
    fprintf(stderr, "nprfx %s: %s\n", (const char *)user, message);
}

/* Length of the layer part of a channel name ("ViewLayer.Vector.X" -> 16; "R" -> 0). */
static size_t layer_len(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot ? (size_t)(dot - name) : 0;
}

static int same_layer(const char *a, const char *b)
{
    size_t la = layer_len(a), lb = layer_len(b);
    return la == lb && !strncmp(a, b, la);
}

static void print_rect(const char *label, nprfx_rect r)
{
    /* oiiotool's geometry notation: WxH+X+Y (the origin signed, as it may be negative). */
    printf("%s %dx%d%+d%+d", label, nprfx_rect_width(r), nprfx_rect_height(r), r.x0, r.y0);
}

/* Channels grouped by layer in order of first appearance; a layer's channels need not be
 * adjacent in the file (multi-part files can split a layer). */
static void print_channels(char **names, char **types, int n, const char *indent)
{
    char *done = calloc((size_t)n + 1, 1);
    if (!done) return;
    for (int i = 0; i < n; i++) {
        if (done[i]) continue;
        size_t ll = layer_len(names[i]);
        int uniform = 1;
        for (int j = i; j < n; j++)
            if (!done[j] && same_layer(names[i], names[j]) && strcmp(types[i], types[j]))
                uniform = 0;
        printf("%s", indent);
        if (ll) printf("%.*s:", (int)ll, names[i]);
        for (int j = i; j < n; j++) {
            if (done[j] || !same_layer(names[i], names[j])) continue;
            done[j] = 1;
            const char *short_name = names[j] + (ll ? ll + 1 : 0);
            if (j != i || ll) printf(" ");
            if (uniform)
                printf("%s", short_name);
            else
                printf("%s:%s", short_name, types[j]);
        }
        if (uniform) printf(" (%s)", types[i]);
        printf("\n");
    }
    free(done);
}

/* A part's layout beyond its channels: tiles, MIP levels, pixel aspect, deep data. */
static void print_layout(const nprfx_part_info *p, const char *sep)
{
    if (p->tile_w > 0) printf("%stiled %dx%d", sep, p->tile_w, p->tile_h), sep = ", ";
    if (p->miplevels > 1)
        printf("%s%d MIP levels (reads take level 0)", sep, p->miplevels), sep = ", ";
    if (p->pixel_aspect != 1.0f) printf("%spixel aspect %g", sep, p->pixel_aspect), sep = ", ";
    if (p->deep) printf("%sdeep (reads refuse it: flatten it first)", sep);
}

/* Views, and every part of a multi-part file with what a read without "part" takes; a single
 * part's layout on one line. */
static void print_parts(const nprfx_file_info *fi)
{
    if (fi->nviews > 0) {
        printf("    views:");
        for (int v = 0; v < fi->nviews; v++)
            printf("%s %s%s", v ? "," : "", fi->views[v], v == 0 ? " (default)" : "");
        printf("\n");
    }
    if (fi->nparts == 1) {
        const nprfx_part_info *p = &fi->parts[0];
        if (p->tile_w > 0 || p->miplevels > 1 || p->pixel_aspect != 1.0f || p->deep) {
            printf("    layout: ");
            print_layout(p, "");
            printf("\n");
        }
        return;
    }
    for (int i = 0; i < fi->nparts; i++) {
        const nprfx_part_info *p = &fi->parts[i];
        printf("    part %d", p->index);
        if (p->name[0]) printf(" '%s'", p->name);
        if (p->view[0]) printf(", view %s", p->view);
        print_rect(": data window", p->bounds);
        print_rect(", display window", p->display);
        print_layout(p, ", ");
        printf(", %s\n", p->broken ? "unfinished or damaged (its pixels are missing): not read"
                         : p->used ? "read by default"
                         : p->view[0] && fi->nviews && strcmp(p->view, fi->views[0])
                             ? "read with \"view\" or \"part\""
                             : "read with \"part\"");
        print_channels(p->names, p->types, p->nchannels, "        ");
    }
}

static int info_file(nprfx_context *ctx, const char *path)
{
    nprfx_file_info fi;
    if (nprfx_io_info(ctx, path, &fi)) return INFO_FILE_ERROR;
    printf("%s: %s %dx%d, %d channel%s, %d subimage%s", path, fi.format,
           nprfx_rect_width(fi.bounds), nprfx_rect_height(fi.bounds), fi.nchannels,
           fi.nchannels == 1 ? "" : "s", fi.subimages, fi.subimages == 1 ? "" : "s");
    if (fi.compression[0]) printf(", compression %s", fi.compression);
    printf("\n");
    print_rect("    data window", fi.bounds);
    print_rect(", display window", fi.display);
    printf("\n");
    print_channels(fi.names, fi.types, fi.nchannels, "    ");
    print_parts(&fi);
    nprfx_file_info_free(&fi);
    return INFO_OK;
}

/* ---- test mode -----------------------------------------------------------------------------
 * `nprfx info --io-test OP ...` drives the I/O functions that no other command reaches yet, for
 * tests/cli/io.sh, which then checks the files with oiiotool as an independent reader. Not part
 * of the documented interface.
 *   write IN OUT [--half] [--compression C]          read IN, write all its channels to OUT
 *   preview IN OUT [--raw] [--ocio CFG] [--colorspace CS] [--display D] [--view V]
 *   convert IN OUT FROM TO [--ocio CFG]               convert the first 3 channels, write EXR
 *   channel IN NAME                                   print the channel's index (-1: absent)
 *   view IN FIRST COUNT                               print a plate view's shape, or "absent"
 *   damaged LIST                                      a verdict for each file (io_check.c)
 *   channels IN OUT A,B,...                           read only channels A, B, ... (in that
 *                                                     order), write them with their file types
 *   rows IN OUT N                                     the same, all channels, N rows at a time
 *                                                     in both (nprfx_io_rows_*) */
static int io_test_channels(nprfx_context *ctx, const char *in, const char *out, const char *list,
                            int rows)
{
    char buf[4096], *names[256];
    int n = 0;
    snprintf(buf, sizeof buf, "%s", list ? list : "");
    for (char *t = strtok(buf, ","); t && n < 256; t = strtok(NULL, ","))
        names[n++] = t;
    nprfx_read_options ro;
    memset(&ro, 0, sizeof ro);
    ro.size = sizeof ro;
    ro.channels = list ? (const char *const *)names : NULL;
    ro.nchannels = n;
    nprfx_plate plate;
    nprfx_result r;
    if (!rows) {
        if ((r = nprfx_io_read_ex(ctx, in, &ro, &plate))) return INFO_FILE_ERROR;
        nprfx_image all = {plate.pixels, plate.nchannels,
                           (ptrdiff_t)nprfx_rect_width(plate.bounds) * plate.nchannels,
                           plate.nchannels, plate.bounds};
        nprfx_write_options wo = {sizeof wo, NULL, 0};
        wo.types = plate.types;
        wo.pixel_aspect = plate.pixel_aspect;
        r = nprfx_io_write(ctx, out, &all, (const char *const *)plate.names, &plate.display, &wo);
        nprfx_plate_free(&plate);
        return r ? INFO_FILE_ERROR : INFO_OK;
    }
    nprfx_row_reader *rr = NULL;
    nprfx_row_writer *w = NULL;
    if (nprfx_io_rows_open(ctx, in, &ro, &plate, &rr)) return INFO_FILE_ERROR;
    nprfx_write_options wo = {sizeof wo, NULL, 0};
    wo.types = plate.types;
    wo.pixel_aspect = plate.pixel_aspect;
    const int width = nprfx_rect_width(plate.bounds), nc = plate.nchannels;
    float *px = malloc((size_t)width * (size_t)rows * (size_t)nc * sizeof(float));
    r = px ? nprfx_io_rows_create(ctx, out, plate.bounds, nc, (const char *const *)plate.names,
                                  &plate.display, &wo, &w)
           : NPRFX_ERR_OUT_OF_MEMORY;
    for (int y = plate.bounds.y0; !r && y < plate.bounds.y1; y += rows) {
        int y1 = y + rows < plate.bounds.y1 ? y + rows : plate.bounds.y1;
        nprfx_image im = {px, nc, (ptrdiff_t)width * nc, nc,
                          nprfx_rect_make(plate.bounds.x0, y, plate.bounds.x1, y1)};
        r = nprfx_io_rows_read(ctx, rr, y, y1, px);
        if (!r) r = nprfx_io_rows_write(ctx, w, &im);
    }
    nprfx_result f = nprfx_io_rows_finish(ctx, w, !r);
    free(px);
    nprfx_io_rows_close(rr);
    nprfx_plate_free(&plate);
    return r || f ? INFO_FILE_ERROR : INFO_OK;
}

static int io_test(nprfx_context *ctx, int argc, char **argv)
{
    if (argc < 3) return INFO_USAGE;
    const char *op = argv[1], *in = argv[2];
    if (!strcmp(op, "damaged")) return nprfx_io_check_damaged(in);
    if (!strcmp(op, "channels") && argc >= 5) return io_test_channels(ctx, in, argv[3], argv[4], 0);
    if (!strcmp(op, "rows") && argc >= 5)
        return atoi(argv[4]) > 0 ? io_test_channels(ctx, in, argv[3], NULL, atoi(argv[4]))
                                 : INFO_USAGE;
    nprfx_plate plate;
    if (nprfx_io_read(ctx, in, &plate)) return INFO_FILE_ERROR;
    /* The whole plate as one view (may exceed NPRFX_MAX_CHANNELS, which the writer allows). */
    nprfx_image all = {plate.pixels, plate.nchannels,
                       (ptrdiff_t)nprfx_rect_width(plate.bounds) * plate.nchannels, plate.nchannels,
                       plate.bounds};
    int rc = INFO_USAGE;
    if (!strcmp(op, "write") && argc >= 4) {
        nprfx_write_options wo = {sizeof wo, NULL, 0};
        for (int i = 4; i < argc; i++) {
            if (!strcmp(argv[i], "--half"))
                wo.half = 1;
            else if (!strcmp(argv[i], "--compression") && i + 1 < argc)
                wo.compression = argv[++i];
        }
        rc = nprfx_io_write(ctx, argv[3], &all, (const char *const *)plate.names, &plate.display,
                            &wo)
                 ? INFO_FILE_ERROR
                 : INFO_OK;
    } else if (!strcmp(op, "preview") && argc >= 4) {
        nprfx_preview_options po;
        memset(&po, 0, sizeof po);
        po.size = sizeof po;
        for (int i = 4; i < argc; i++) {
            const char *next = i + 1 < argc ? argv[i + 1] : NULL;
            if (!strcmp(argv[i], "--raw"))
                po.raw = 1;
            else if (!strcmp(argv[i], "--ocio") && next)
                po.ocio_config = argv[++i];
            else if (!strcmp(argv[i], "--colorspace") && next)
                po.colorspace = argv[++i];
            else if (!strcmp(argv[i], "--display") && next)
                po.display = argv[++i];
            else if (!strcmp(argv[i], "--view") && next)
                po.view = argv[++i];
        }
        rc = nprfx_io_write_preview(ctx, argv[3], &all, &po) ? INFO_FILE_ERROR : INFO_OK;
    } else if (!strcmp(op, "convert") && argc >= 6) {
        const char *cfg = argc >= 8 && !strcmp(argv[6], "--ocio") ? argv[7] : NULL;
        rc = INFO_FILE_ERROR;
        if (!nprfx_io_convert_colorspace(ctx, &all, argv[4], argv[5], cfg) &&
            !nprfx_io_write(ctx, argv[3], &all, (const char *const *)plate.names, &plate.display,
                            NULL))
            rc = INFO_OK;
    } else if (!strcmp(op, "channel") && argc >= 4) {
        printf("%d\n", nprfx_plate_channel(&plate, argv[3]));
        rc = INFO_OK;
    } else if (!strcmp(op, "view") && argc >= 5) {
        nprfx_image v = nprfx_plate_view(&plate, atoi(argv[3]), atoi(argv[4]));
        if (!v.data)
            printf("absent\n");
        else
            printf("channels %d pixel_stride %td row_stride %td first %g\n", v.channels,
                   v.pixel_stride, v.row_stride, v.data[0]);
        rc = INFO_OK;
    }
    nprfx_plate_free(&plate);
    return rc;
}

int cli_cmd_info(int argc, char **argv)
{
    nprfx_context *ctx = NULL;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.error_handler = print_error;
    init.error_user = (void *)"info";
    if (nprfx_context_create(&init, &ctx)) {
        fprintf(stderr, "nprfx info: cannot create a context\n");
        return INFO_USAGE;
    }
    int rc = INFO_OK, nfiles = 0, opts_done = 0, aovs = 0;
    const char *styles = NULL;
    if (argc >= 2 && !strcmp(argv[1], "--io-test")) {
        rc = io_test(ctx, argc - 1, argv + 1);
        if (rc == INFO_USAGE) fprintf(stderr, "nprfx info: bad --io-test arguments\n");
        nprfx_context_destroy(ctx);
        return rc;
    }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!opts_done && (!strcmp(a, "--help") || !strcmp(a, "-h"))) {
            usage(stdout);
            nprfx_context_destroy(ctx);
            return INFO_OK;
        }
        if (!opts_done && !strcmp(a, "--")) {
            opts_done = 1;
            continue;
        }
        if (!opts_done && !strcmp(a, "--aovs")) {
            aovs = 1;
            continue;
        }
        if (!opts_done && !strcmp(a, "--styles") && i + 1 < argc) {
            styles = argv[++i];
            continue;
        }
        if (!opts_done && a[0] == '-' && a[1]) {
            fprintf(stderr, "nprfx info: unknown option '%s'\n", a);
            usage(stderr);
            nprfx_context_destroy(ctx);
            return INFO_USAGE;
        }
    }
    opts_done = 0;
    for (int i = 1; i < argc; i++) {
        if (!opts_done && !strcmp(argv[i], "--")) {
            opts_done = 1;
            continue;
        }
        if (!opts_done && !strcmp(argv[i], "--aovs")) continue;
        if (!opts_done && !strcmp(argv[i], "--styles")) {
            i++;
            continue;
        }
        nfiles++;
        /* Keep going after a bad file so one run reports on every file given. */
        if ((aovs ? cli_info_aovs(ctx, argv[i], styles) : info_file(ctx, argv[i])) != INFO_OK)
            rc = INFO_FILE_ERROR;
    }
    if (!nfiles) {
        usage(stderr);
        rc = INFO_USAGE;
    }
    nprfx_context_destroy(ctx);
    return rc;
}
