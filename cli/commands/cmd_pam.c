/* nprfx pam — painterly art maps (nprfx/pam.h, docs/design.md §3.7): build one from brushstroke
 * samples, describe and check a built one, and paint procedural samples to build from.
 *
 * The core builds the strip in memory; this command reads the samples, writes the strip as an EXR
 * with the format's attributes (through nprfx/io_oiio.h) and reads them back for `info`. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine/engine_util.h"
#include "commands.h"
#include "nprfx/io.h"
#include "io/io_colour.h"
#include "nprfx/io_oiio.h"
#include "nprfx/io_oiio.h"
#include "io/io_write.h"
#include "nprfx/io.h"
#include "nprfx/pam.h"
#include "util/cli_util.h"

/* Exit status: 0 done, 1 a file or data error (a file that is not a valid PAM), 2 usage. */
enum { PAM_OK = 0, PAM_FAILED = 1, PAM_USAGE = 2 };

#define MAX_SAMPLES 64

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: nprfx pam build --sample FILE [--sample FILE ...] -o OUT.pam.exr [options]\n"
        "       nprfx pam info FILE...\n"
        "       nprfx pam samples -o DIR [--size N] [--seed S]\n\n"
        "A painterly art map (PAM; Yan et al., TVCG 2008): tileable tone maps, dark to light,\n"
        "whose strokes keep one orientation and layout from tone to tone (docs/design.md §3.7).\n\n"
        "build: one key map per sample by multiresolution patch-based synthesis; every key map\n"
        "follows the first sample's stroke layout (coherence search space); key maps sorted by\n"
        "mean intensity, with N = round(|mu_a - mu_b| * 255 / k) - 1 linear blends between\n"
        "adjacent ones (Eq. 7-8). Samples are turned so their strokes run vertically.\n"
        "  --sample FILE   a brushstroke sample (2 to %d; all of one size, RGB). PNG, JPEG and\n"
        "                  other 8-bit files are read as sRGB, EXR as linear (--colorspace)\n"
        "  -o FILE         the PAM, an EXR (name it NAME.pam.exr)\n"
        "  --k K           intensity step per map (Eq. 7; default 5, on a 0-255 scale)\n"
        "  --size S        map size in pixels (default 256)\n"
        "  --patch P       synthesis tile at the finest level (default 64; divides S)\n"
        "  --overlap O     overlap in pixels (default 16, P/4)\n"
        "  --levels L      pyramid levels (default 3; P must be a multiple of 2^(L-1))\n"
        "  --seed N        the first key map's random choices (default 2008)\n"
        "  --no-align      use the samples as they are (no rotation to vertical strokes)\n"
        "  --float         store 32-bit floats (default: half floats)\n"
        "  --colorspace C  auto (default), srgb or linear: how sample pixels are read\n"
        "  --threads N     worker threads (the result is the same for any N)\n\n"
        "The file: ONE RGB image, `count` square maps of S x S side by side, left to right, dark\n"
        "to light (width count*S, height S), scene-linear, EXR, with header attributes\n"
        "  nprfx:pam (int, format version 1), nprfx:pamCount (int), nprfx:pamKeys (string, key\n"
        "  map indices, e.g. \"0,4,9\"), nprfx:pamMeanY / pamMeanU / pamMeanV (strings, each\n"
        "  map's mean YUV, comma-separated; Y = 0.299 R + 0.587 G + 0.114 B, U = 0.492111 (B-Y),\n"
        "  V = 0.877283 (R-Y)).\n"
        "A reader derives count = width / height and may recompute the means from the pixels.\n\n"
        "info: print count, S, keys and means, checking the attributes against the pixels; exit\n"
        "1 for a file that is not a PAM (no nprfx:pam, width not a multiple of height, fewer\n"
        "than 2 maps, attributes that disagree with the pixels).\n\n"
        "samples: paint procedural brushstroke samples (the project ships no painting):\n"
        "DIR/strokes_1.png .. strokes_4.png, dark to light, strokes at different angles.\n"
        "  --size N        side in pixels (default 256)\n\n"
        "examples:\n"
        "  nprfx pam samples -o samples/pam\n"
        "  nprfx pam build --sample samples/pam/strokes_1.png --sample samples/pam/strokes_2.png "
        "\\\n"
        "      --sample samples/pam/strokes_3.png -o strokes.pam.exr\n"
        "  nprfx pam info strokes.pam.exr\n",
        MAX_SAMPLES);
}

static int parse_int(const char *opt, const char *text, int lo, int hi, int *out)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (errno || end == text || *end || v < lo || v > hi) {
        fprintf(stderr, "nprfx pam: %s must be a whole number in [%d, %d], not '%s'\n", opt, lo, hi,
                text);
        return 0;
    }
    *out = (int)v;
    return 1;
}

/* ---- reading samples ---- */

/* The R, G, B channels of a plate (by name, else the first three). */
static int rgb_channels(const nprfx_plate *pl, int idx[3])
{
    static const char *const n[3] = {"R", "G", "B"};
    int found = 1;
    for (int c = 0; c < 3; c++)
        if ((idx[c] = nprfx_plate_channel(pl, n[c])) < 0) found = 0;
    if (found) return 1;
    if (pl->nchannels < 3) return 0;
    for (int c = 0; c < 3; c++)
        idx[c] = c;
    return 1;
}

/* Read a sample into a packed RGB image, linear. */
static int read_sample(nprfx_context *ctx, const char *path, const char *colorspace,
                       nprfx_image *out)
{
    nprfx_plate pl;
    if (nprfx_io_read(ctx, path, &pl) != NPRFX_OK) {
        fprintf(stderr, "nprfx pam build: %s\n", cli_message(ctx));
        return 0;
    }
    int idx[3];
    if (!rgb_channels(&pl, idx)) {
        fprintf(stderr, "nprfx pam build: '%s' has %d channel(s); a sample is an RGB image\n", path,
                pl.nchannels);
        nprfx_plate_free(&pl);
        return 0;
    }
    int ok = nprfx_image_alloc(ctx, pl.bounds, 3, out) == NPRFX_OK;
    if (ok) {
        size_t n = (size_t)nprfx_rect_width(pl.bounds) * (size_t)nprfx_rect_height(pl.bounds);
        for (size_t i = 0; i < n; i++)
            for (int c = 0; c < 3; c++)
                out->data[3 * i + c] = pl.pixels[i * (size_t)pl.nchannels + (size_t)idx[c]];
    }
    nprfx_plate_free(&pl);
    if (!ok) {
        fprintf(stderr, "nprfx pam build: %s\n", cli_message(ctx));
        return 0;
    }
    int srgb = !strcmp(colorspace, "srgb");
    if (!strcmp(colorspace, "auto")) {
        nprfx_file_info fi;
        if (nprfx_io_info(ctx, path, &fi) == NPRFX_OK) {
            /* Float files hold scene-linear light; 8- and 16-bit images are display-encoded. */
            srgb = strcmp(fi.format, "openexr") != 0;
            nprfx_file_info_free(&fi);
        }
    }
    if (srgb && nprfx_io_convert_colorspace(ctx, out, "srgb", "linear", NULL) != NPRFX_OK) {
        fprintf(stderr, "nprfx pam build: '%s': %s\n", path, cli_message(ctx));
        nprfx_image_free(out);
        return 0;
    }
    return 1;
}

/* ---- writing ---- */

/* "a,b,c" of count values (ints when `ints`), appended to a growing buffer. */
static char *join(const double *v, int stride, int count, int ints)
{
    size_t cap = (size_t)count * 24 + 1, len = 0;
    char *s = malloc(cap);
    if (!s) return NULL;
    s[0] = 0;
    for (int i = 0; i < count; i++) {
        int n = ints ? snprintf(s + len, cap - len, "%s%d", i ? "," : "", (int)v[i * stride])
                     : snprintf(s + len, cap - len, "%s%.6g", i ? "," : "", v[i * stride]);
        len += (size_t)n;
    }
    return s;
}

static int write_pam(nprfx_context *ctx, const char *path, const nprfx_image *strip,
                     const nprfx_pam_info *info, int half)
{
    double keys[NPRFX_PAM_MAX_MAPS];
    int nk = 0;
    for (int m = 0; m < info->count; m++)
        if (info->key[m]) keys[nk++] = m;
    char version[16], count[16];
    snprintf(version, sizeof version, "%d", NPRFX_PAM_FORMAT_VERSION);
    snprintf(count, sizeof count, "%d", info->count);
    char *k = join(keys, 1, nk, 1);
    char *my = join(&info->mean_yuv[0][0], 3, info->count, 0);
    char *mu = join(&info->mean_yuv[0][1], 3, info->count, 0);
    char *mv = join(&info->mean_yuv[0][2], 3, info->count, 0);
    int ok = k && my && mu && mv;
    if (ok) {
        nprfx_attribute attrs[6] = {
            {NPRFX_PAM_ATTR_VERSION, NPRFX_ATTR_INT, version},
            {NPRFX_PAM_ATTR_COUNT, NPRFX_ATTR_INT, count},
            {NPRFX_PAM_ATTR_KEYS, NPRFX_ATTR_STRING, k},
            {NPRFX_PAM_ATTR_MEAN_Y, NPRFX_ATTR_STRING, my},
            {NPRFX_PAM_ATTR_MEAN_U, NPRFX_ATTR_STRING, mu},
            {NPRFX_PAM_ATTR_MEAN_V, NPRFX_ATTR_STRING, mv},
        };
        static const char *const names[3] = {"R", "G", "B"};
        nprfx_write_options wo = {sizeof wo, "zip", half, attrs, 6};
        ok = nprfx_io_write(ctx, path, strip, names, NULL, &wo) == NPRFX_OK;
        if (!ok) fprintf(stderr, "nprfx pam build: %s\n", cli_message(ctx));
    } else {
        fprintf(stderr, "nprfx pam build: out of memory\n");
    }
    free(k);
    free(my);
    free(mu);
    free(mv);
    return ok;
}

static int has_suffix(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && !strcmp(s + a - b, suffix);
}

static int cmd_build(int argc, char **argv)
{
    const char *files[MAX_SAMPLES], *out = NULL, *colorspace = "auto";
    int nfiles = 0, threads = 0, half = 1;
    nprfx_pam_build_params p = NPRFX_PAM_BUILD_PARAMS_DEFAULT;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return PAM_OK;
        } else if (!strcmp(a, "--sample") && has) {
            if (nfiles == MAX_SAMPLES) {
                fprintf(stderr, "nprfx pam build: at most %d samples\n", MAX_SAMPLES);
                return PAM_USAGE;
            }
            files[nfiles++] = argv[++i];
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has) {
            out = argv[++i];
        } else if (!strcmp(a, "--k") && has) {
            char *end = NULL;
            const char *t = argv[++i];
            p.k = strtod(t, &end);
            if (end == t || *end || !(p.k > 0) || !isfinite(p.k)) {
                fprintf(stderr, "nprfx pam build: --k must be a positive number, not '%s'\n", t);
                return PAM_USAGE;
            }
        } else if (!strcmp(a, "--size") && has) {
            if (!parse_int(a, argv[++i], 8, 8192, &p.map_size)) return PAM_USAGE;
        } else if (!strcmp(a, "--patch") && has) {
            if (!parse_int(a, argv[++i], 2, 4096, &p.patch)) return PAM_USAGE;
        } else if (!strcmp(a, "--overlap") && has) {
            if (!parse_int(a, argv[++i], 1, 2048, &p.overlap)) return PAM_USAGE;
        } else if (!strcmp(a, "--levels") && has) {
            if (!parse_int(a, argv[++i], 1, 5, &p.levels)) return PAM_USAGE;
        } else if (!strcmp(a, "--seed") && has) {
            char *end = NULL;
            const char *t = argv[++i];
            errno = 0;
            p.seed = strtoull(t, &end, 0);
            if (errno || end == t || *end || t[0] == '-') {
                fprintf(stderr, "nprfx pam build: --seed must be a non-negative integer\n");
                return PAM_USAGE;
            }
        } else if (!strcmp(a, "--no-align")) {
            p.align = 0;
        } else if (!strcmp(a, "--float")) {
            half = 0;
        } else if (!strcmp(a, "--colorspace") && has) {
            colorspace = argv[++i];
            if (strcmp(colorspace, "auto") && strcmp(colorspace, "srgb") &&
                strcmp(colorspace, "linear")) {
                fprintf(stderr, "nprfx pam build: --colorspace is auto, srgb or linear\n");
                return PAM_USAGE;
            }
        } else if (!strcmp(a, "--threads") && has) {
            if (!parse_int(a, argv[++i], 1, 1024, &threads)) return PAM_USAGE;
        } else {
            fprintf(stderr, "nprfx pam build: unexpected argument '%s'%s\n\n", a,
                    a[0] == '-' && !has ? " (it needs a value)" : "");
            usage(stderr);
            return PAM_USAGE;
        }
    }
    if (nfiles < 2 || !out) {
        fprintf(stderr, "nprfx pam build: give two or more --sample FILE and -o OUT.pam.exr\n\n");
        usage(stderr);
        return PAM_USAGE;
    }
    if (!has_suffix(out, ".exr")) {
        fprintf(stderr,
                "nprfx pam build: the PAM is an EXR (its attributes need one): name it "
                "NAME.pam.exr, not '%s'\n",
                out);
        return PAM_USAGE;
    }
    cli_env env;
    if (cli_env_init(&env, threads)) return PAM_FAILED;
    nprfx_image samples[MAX_SAMPLES];
    memset(samples, 0, sizeof samples);
    int status = PAM_FAILED, n = 0;
    for (; n < nfiles; n++)
        if (!read_sample(env.ctx, files[n], colorspace, &samples[n])) goto done;
    /* Name the files in the checks the core can only make by index. */
    for (int s = 0; s < nfiles; s++) {
        int w = nprfx_rect_width(samples[s].bounds), h = nprfx_rect_height(samples[s].bounds);
        int w0 = nprfx_rect_width(samples[0].bounds), h0 = nprfx_rect_height(samples[0].bounds);
        if (w != w0 || h != h0) {
            fprintf(stderr,
                    "nprfx pam build: '%s' is %dx%d but '%s' is %dx%d (all samples must have "
                    "one size, so their strokes have one scale)\n",
                    files[s], w, h, files[0], w0, h0);
            goto done;
        }
        int b = p.patch + p.overlap;
        if (w < b || h < b) {
            fprintf(stderr,
                    "nprfx pam build: '%s' (%dx%d) is smaller than a patch with its overlap "
                    "(%dx%d); use a larger sample or a smaller --patch\n",
                    files[s], w, h, b, b);
            goto done;
        }
    }
    double t0 = engine_now();
    nprfx_image strip;
    nprfx_pam_info info;
    memset(&info, 0, sizeof info);
    info.size = sizeof info;
    if (nprfx_pam_build(env.ctx, &p, samples, nfiles, &strip, &info) != NPRFX_OK) {
        const char *msg = cli_message(env.ctx);
        fprintf(stderr, "nprfx pam build: %s\n", msg);
        int idx;
        if (sscanf(strstr(msg, "sample ") ? strstr(msg, "sample ") : "", "sample %d", &idx) == 1 &&
            idx >= 0 && idx < nfiles)
            fprintf(stderr, "nprfx pam build: (sample %d is '%s')\n", idx, files[idx]);
        goto done;
    }
    double t1 = engine_now();
    if (write_pam(env.ctx, out, &strip, &info, half)) {
        int nk = 0;
        for (int m = 0; m < info.count; m++)
            nk += info.key[m];
        printf("wrote %s: %d maps of %dx%d (%d key maps), built in %.2f s\n", out, info.count,
               info.map_size, info.map_size, nk, t1 - t0);
        status = PAM_OK;
    }
    nprfx_image_free(&strip);
done:
    for (int s = 0; s < n; s++)
        nprfx_image_free(&samples[s]);
    cli_env_free(&env);
    return status;
}

/* ---- info ---- */

static const char *attr(char **names, char **values, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(names[i], name)) return values[i];
    return NULL;
}

/* Parse a comma-separated list of count numbers; 1 on success. */
static int parse_list(const char *s, double *v, int count)
{
    for (int i = 0; i < count; i++) {
        char *end = NULL;
        v[i] = strtod(s, &end);
        if (end == s) return 0;
        s = end;
        if (i + 1 < count) {
            if (*s != ',') return 0;
            s++;
        }
    }
    return *s == 0;
}

static int info_one(nprfx_context *ctx, const char *path)
{
    char **names = NULL, **values = NULL;
    int na = 0, status = PAM_FAILED;
    nprfx_plate pl;
    memset(&pl, 0, sizeof pl);
    if (nprfx_io_read_attributes(ctx, path, "nprfx:", &names, &values, &na) != NPRFX_OK ||
        nprfx_io_read(ctx, path, &pl) != NPRFX_OK) {
        fprintf(stderr, "nprfx pam info: %s\n", cli_message(ctx));
        goto done;
    }
    const char *ver = attr(names, values, na, NPRFX_PAM_ATTR_VERSION);
    if (!ver) {
        fprintf(stderr, "nprfx pam info: '%s' is not a PAM: it has no %s attribute\n", path,
                NPRFX_PAM_ATTR_VERSION);
        goto done;
    }
    if (atoi(ver) != NPRFX_PAM_FORMAT_VERSION) {
        fprintf(stderr, "nprfx pam info: '%s' is a PAM of format version %s; this nprfx reads %d\n",
                path, ver, NPRFX_PAM_FORMAT_VERSION);
        goto done;
    }
    int idx[3];
    if (!rgb_channels(&pl, idx)) {
        fprintf(stderr, "nprfx pam info: '%s' has %d channel(s); a PAM is RGB\n", path,
                pl.nchannels);
        goto done;
    }
    nprfx_image rgb = nprfx_plate_view(&pl, 0, pl.nchannels);
    rgb.data = pl.pixels + idx[0];
    if (idx[1] != idx[0] + 1 || idx[2] != idx[0] + 2) {
        fprintf(stderr, "nprfx pam info: '%s': R, G, B are not adjacent channels\n", path);
        goto done;
    }
    rgb.channels = 3;
    nprfx_pam_info info;
    memset(&info, 0, sizeof info);
    info.size = sizeof info;
    if (nprfx_pam_describe(ctx, &rgb, &info) != NPRFX_OK) {
        fprintf(stderr, "nprfx pam info: '%s': %s\n", path, cli_message(ctx));
        goto done;
    }
    const char *cnt = attr(names, values, na, NPRFX_PAM_ATTR_COUNT);
    if (!cnt || atoi(cnt) != info.count) {
        fprintf(stderr, "nprfx pam info: '%s': %s is %s but the image holds %d maps\n", path,
                NPRFX_PAM_ATTR_COUNT, cnt ? cnt : "missing", info.count);
        goto done;
    }
    const char *keys = attr(names, values, na, NPRFX_PAM_ATTR_KEYS);
    if (keys) { /* ascending indices inside the strip */
        const char *s = keys;
        int last = -1;
        while (*s) {
            char *end = NULL;
            long k = strtol(s, &end, 10);
            if (end == s || k <= last || k >= info.count || (*end && *end != ',')) {
                fprintf(stderr,
                        "nprfx pam info: '%s': %s '%s' is not an ascending list of map indices "
                        "below %d\n",
                        path, NPRFX_PAM_ATTR_KEYS, keys, info.count);
                goto done;
            }
            info.key[k] = 1;
            last = (int)k;
            s = *end ? end + 1 : end;
        }
    }
    static const char *const mean_names[3] = {NPRFX_PAM_ATTR_MEAN_Y, NPRFX_PAM_ATTR_MEAN_U,
                                              NPRFX_PAM_ATTR_MEAN_V};
    for (int c = 0; c < 3; c++) {
        const char *m = attr(names, values, na, mean_names[c]);
        if (!m) continue; /* informative only: a reader recomputes them */
        double v[NPRFX_PAM_MAX_MAPS];
        if (!parse_list(m, v, info.count)) {
            fprintf(stderr, "nprfx pam info: '%s': %s is not a list of %d numbers\n", path,
                    mean_names[c], info.count);
            goto done;
        }
        for (int i = 0; i < info.count; i++)
            /* The attributes are the means before the pixels were stored as half floats. */
            if (fabs(v[i] - info.mean_yuv[i][c]) > 1e-3 + 2e-3 * fabs(v[i])) {
                fprintf(stderr,
                        "nprfx pam info: '%s': %s of map %d is %.6g but its pixels give %.6g\n",
                        path, mean_names[c], i, v[i], info.mean_yuv[i][c]);
                goto done;
            }
    }
    printf("%s: PAM version %d, %d maps of %dx%d (image %dx%d)\n", path, NPRFX_PAM_FORMAT_VERSION,
           info.count, info.map_size, info.map_size, info.count * info.map_size, info.map_size);
    printf("keys: %s\n", keys ? keys : "(not recorded)");
    printf("map  key   mean Y     mean U     mean V\n");
    for (int i = 0; i < info.count; i++)
        printf("%3d  %s  %9.6f  %9.6f  %9.6f\n", i, info.key[i] ? "key" : "   ",
               info.mean_yuv[i][0], info.mean_yuv[i][1], info.mean_yuv[i][2]);
    status = PAM_OK;
done:
    nprfx_attributes_free(names, values, na);
    nprfx_plate_free(&pl);
    return status;
}

static int cmd_info(int argc, char **argv)
{
    int nfiles = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return PAM_OK;
        }
        if (argv[i][0] == '-') {
            fprintf(stderr, "nprfx pam info: unexpected option '%s'\n", argv[i]);
            return PAM_USAGE;
        }
        nfiles++;
    }
    if (!nfiles) {
        fprintf(stderr, "nprfx pam info: give one or more PAM files\n");
        return PAM_USAGE;
    }
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    if (nprfx_context_create(&ci, &ctx) != NPRFX_OK) return PAM_FAILED;
    int status = PAM_OK;
    for (int i = 1; i < argc; i++)
        if (info_one(ctx, argv[i]) != PAM_OK) status = PAM_FAILED;
    nprfx_context_destroy(ctx);
    return status;
}

/* ---- samples ---- */

static int cmd_samples(int argc, char **argv)
{
    const char *dir = NULL;
    int size = 256;
    unsigned long long seed = 14;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return PAM_OK;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has) {
            dir = argv[++i];
        } else if (!strcmp(a, "--size") && has) {
            if (!parse_int(a, argv[++i], 16, 4096, &size)) return PAM_USAGE;
        } else if (!strcmp(a, "--seed") && has) {
            seed = strtoull(argv[++i], NULL, 0);
        } else {
            fprintf(stderr, "nprfx pam samples: unexpected argument '%s'\n", a);
            return PAM_USAGE;
        }
    }
    if (!dir) {
        fprintf(stderr, "nprfx pam samples: give -o DIR\n");
        return PAM_USAGE;
    }
    /* Tones dark to light, strokes at four angles (the builder turns them upright). */
    static const double tones[4] = {0.12, 0.38, 0.62, 0.9}, angles[4] = {80, 65, 110, 95};
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    if (nprfx_context_create(&ci, &ctx) != NPRFX_OK) return PAM_FAILED;
    int status = PAM_OK;
    for (int i = 0; i < 4 && status == PAM_OK; i++) {
        nprfx_image im;
        char path[4096];
        snprintf(path, sizeof path, "%s/strokes_%d.png", dir, i + 1);
        nprfx_preview_options po = {sizeof po, NULL, NULL, NULL, NULL, 0};
        po.ocio_config = "";
        if (nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, size, size), 3, &im) ||
            nprfx_pam_sample_strokes(ctx, tones[i], angles[i], seed + (unsigned)i, &im) ||
            nprfx_io_write_preview(ctx, path, &im, &po)) {
            fprintf(stderr, "nprfx pam samples: %s\n", cli_message(ctx));
            status = PAM_FAILED;
        } else {
            printf("wrote %s (tone %.2f, strokes at %.0f degrees)\n", path, tones[i], angles[i]);
        }
        nprfx_image_free(&im);
    }
    nprfx_context_destroy(ctx);
    return status;
}

int cli_cmd_pam(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? PAM_USAGE : PAM_OK;
    }
    if (!strcmp(argv[1], "build")) return cmd_build(argc - 1, argv + 1);
    if (!strcmp(argv[1], "info")) return cmd_info(argc - 1, argv + 1);
    if (!strcmp(argv[1], "samples")) return cmd_samples(argc - 1, argv + 1);
    fprintf(stderr, "nprfx pam: unknown sub-command '%s' (build, info or samples)\n", argv[1]);
    return PAM_USAGE;
}
