/* nprfx diff — compare two images or two frame sequences with idiff's thresholds and exit codes.
 *
 * Modelled on OpenImageIO's idiff so golden-image tests read the same everywhere: a pixel's
 * error is the largest absolute difference over its channels; it "fails" above --fail and "warns"
 * above --warn; the result is FAILURE when more than --failpercent % of the pixels fail or any
 * pixel exceeds --hardfail, WARNING likewise with the warn thresholds, else PASS. Defaults are
 * idiff 2.4's: fail 1e-6, failpercent 0, hardfail inf, warn 1e-6, warnpercent 0, hardwarn inf.
 * Exit status: 0 pass, 1 warning, 2 failure, 3 size or channel mismatch, 4 file error. */
#define _POSIX_C_SOURCE 200809L /* open_memstream */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "io/io_write.h"
#include "nprfx/io.h"
#include "nprfx/seq.h"

enum { DIFF_PASS = 0, DIFF_WARN = 1, DIFF_FAIL = 2, DIFF_MISMATCH = 3, DIFF_FILE_ERROR = 4 };
#define DIFF_USAGE 2 /* as for the other commands; a usage error can never pass */

typedef struct diff_options {
    double fail, failpercent, hardfail;
    double warn, warnpercent, hardwarn;
    double scale;
    const char *out;      /* difference image path (may hold a frame pattern) */
    int out_nonzero_only; /* --od: write it only when some pixel differs */
    const char *channels; /* comma-separated names, NULL: all */
    const char *frames;   /* frame list for sequences, NULL: discover from A */
    int quiet;
} diff_options;

/* What one comparison found, beyond its status. */
typedef struct diff_summary {
    int status;
    double maxerr; /* largest pixel error (inf for a NaN/inf mismatch) */
    int maxx, maxy;
    char maxchan[128]; /* the channel where maxerr occurs ("" when none) */
    long npixels, nfail, nwarn;
} diff_summary;

typedef struct chan_stats {
    double max, sum, sumsq;
    int maxx, maxy;
} chan_stats;

static const char *status_word(int s)
{
    switch (s) {
    case DIFF_PASS:
        return "PASS";
    case DIFF_WARN:
        return "WARNING";
    case DIFF_FAIL:
        return "FAILURE";
    case DIFF_MISMATCH:
        return "MISMATCH";
    default:
        return "FILE ERROR";
    }
}

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: nprfx diff A B [options]\n\n"
        "Compare two images (all channels, matched by name) or two frame sequences, like\n"
        "OpenImageIO's idiff. A pixel's error is its largest absolute channel difference.\n\n"
        "  --fail T          a pixel fails when its error exceeds T (default 1e-06)\n"
        "  --failpercent P   FAILURE when more than P%% of pixels fail (default 0)\n"
        "  --hardfail T      FAILURE when any pixel's error exceeds T (default inf)\n"
        "  --warn T          a pixel warns when its error exceeds T (default 1e-06)\n"
        "  --warnpercent P   WARNING when more than P%% of pixels warn (default 0)\n"
        "  --hardwarn T      WARNING when any pixel's error exceeds T (default inf)\n"
        "  --out DIFF.exr    write |A - B| * K (sequences: a pattern, e.g. diff.####.exr)\n"
        "  --od              write --out only when the images differ\n"
        "  --scale K         scale of the difference image (default 1)\n"
        "  --channels a,b    compare only these channels (names as 'nprfx info' shows)\n"
        "  --frames LIST     frames for sequences: 1-24, 1-24x2, 1,3,5-7\n"
        "                    (default: every frame of A that exists)\n"
        "  -q, --quiet       print only the result\n\n"
        "Sequences: when A and B hold a frame pattern (#### = 4 digits, @ = one digit each,\n"
        "%%04d printf style), each frame is compared and the worst result is reported.\n"
        "Pixels outside a data window count as 0; NaN matches only NaN, inf only the same inf.\n\n"
        "Exit status (idiff's): 0 pass, 1 warning, 2 failure, 3 size or channel mismatch,\n"
        "4 file error (a missing or unreadable file or frame). Usage errors exit 2.\n");
}

static void print_error(void *user, const nprfx_context *ctx, nprfx_result code,
                        const char *message)
{
    (void)user;
    (void)code;
    fprintf(stderr, "nprfx diff: %s\n", message);
}

/* Error between two samples: equal values (including equal infinities) and two NaNs match;
 * any other NaN or infinity is an unbounded error, so it always fails. */
static double sample_error(float a, float b)
{
    if (a == b) return 0.0;
    if (isnan(a) && isnan(b)) return 0.0;
    double e = fabs((double)a - (double)b);
    return isnan(e) ? INFINITY : e;
}

static int parse_list(const char *list, char ***out)
{
    int n = 1;
    for (const char *p = list; *p; p++)
        n += *p == ',';
    char **v = calloc((size_t)n, sizeof *v);
    if (!v) return -1;
    int k = 0;
    const char *s = list;
    for (;;) {
        const char *e = strchr(s, ',');
        size_t len = e ? (size_t)(e - s) : strlen(s);
        v[k] = malloc(len + 1);
        if (!v[k]) {
            for (int i = 0; i < k; i++)
                free(v[i]);
            free(v);
            return -1;
        }
        memcpy(v[k], s, len);
        v[k][len] = '\0';
        k++;
        if (!e) break;
        s = e + 1;
    }
    *out = v;
    return k;
}

static void free_list(char **v, int n)
{
    for (int i = 0; i < n; i++)
        free(v[i]);
    free(v);
}

/* Pick the channels to compare: idx_a[i] in A pairs with idx_b[i] in B. Returns the count, or -1
 * after printing why (a mismatch). */
static int match_channels(const nprfx_plate *a, const nprfx_plate *b, const char *pa,
                          const char *pb, const char *list, int *idx_a, int *idx_b, FILE *rep)
{
    if (list) {
        char **names;
        int n = parse_list(list, &names);
        if (n < 0) return -1;
        for (int i = 0; i < n; i++) {
            idx_a[i] = nprfx_plate_channel(a, names[i]);
            idx_b[i] = nprfx_plate_channel(b, names[i]);
            if (idx_a[i] < 0 || idx_b[i] < 0) {
                fprintf(stderr, "nprfx diff: channel '%s' is not in '%s'\n", names[i],
                        idx_a[i] < 0 ? pa : pb);
                free_list(names, n);
                return -1;
            }
        }
        free_list(names, n);
        return n;
    }
    if (a->nchannels != b->nchannels) {
        fprintf(stderr, "nprfx diff: '%s' has %d channels but '%s' has %d\n", pa, a->nchannels, pb,
                b->nchannels);
        return -1;
    }
    int by_name = 1;
    for (int i = 0; i < a->nchannels; i++) {
        idx_a[i] = i;
        idx_b[i] = nprfx_plate_channel(b, a->names[i]);
        if (idx_b[i] < 0) by_name = 0;
    }
    if (!by_name) {
        /* Different names, same count: compare by position, as idiff does, but say so. */
        for (int i = 0; i < a->nchannels; i++)
            idx_b[i] = i;
        fprintf(rep, "  note: channel names differ; comparing channels by position\n");
    }
    return a->nchannels;
}

/* Read pixel (x, y) channel c, 0 outside the data window (the EXR meaning of "no data"). */
static float sample(const nprfx_plate *p, int x, int y, int c)
{
    if (!nprfx_rect_contains(p->bounds, x, y)) return 0.0f;
    size_t w = (size_t)nprfx_rect_width(p->bounds);
    return p->pixels[((size_t)(y - p->bounds.y0) * w + (size_t)(x - p->bounds.x0)) *
                         (size_t)p->nchannels +
                     (size_t)c];
}

static nprfx_rect rect_union(nprfx_rect a, nprfx_rect b)
{
    nprfx_rect r = {a.x0 < b.x0 ? a.x0 : b.x0, a.y0 < b.y0 ? a.y0 : b.y0, a.x1 > b.x1 ? a.x1 : b.x1,
                    a.y1 > b.y1 ? a.y1 : b.y1};
    return r;
}

/* Compare two files; the detailed report goes to rep. out_path: difference image or NULL. */
static int compare_files(nprfx_context *ctx, const char *pa, const char *pb, const char *out_path,
                         const diff_options *o, FILE *rep, diff_summary *sum)
{
    memset(sum, 0, sizeof *sum);
    sum->status = DIFF_FILE_ERROR;
    nprfx_plate a, b;
    memset(&b, 0, sizeof b);
    if (nprfx_io_read(ctx, pa, &a)) return sum->status;
    if (nprfx_io_read(ctx, pb, &b)) {
        nprfx_plate_free(&a);
        return sum->status;
    }
    int *idx_a = NULL, *idx_b = NULL, n = -1;
    chan_stats *cs = NULL;
    nprfx_image diff;
    memset(&diff, 0, sizeof diff);
    int cap = (a.nchannels > b.nchannels ? a.nchannels : b.nchannels) + 1;
    if (o->channels) cap += (int)strlen(o->channels);
    idx_a = malloc((size_t)cap * sizeof *idx_a);
    idx_b = malloc((size_t)cap * sizeof *idx_b);
    if (!idx_a || !idx_b) goto oom;

    fprintf(rep, "Comparing \"%s\" and \"%s\"\n", pa, pb);
    sum->status = DIFF_MISMATCH;
    int wa = nprfx_rect_width(a.bounds), ha = nprfx_rect_height(a.bounds);
    int wb = nprfx_rect_width(b.bounds), hb = nprfx_rect_height(b.bounds);
    /* Different data windows are fine when both are crops of the same frame (equal display
     * windows); otherwise differently sized images are a mismatch, as in idiff. */
    if ((wa != wb || ha != hb) && !nprfx_rect_equal(a.display, b.display)) {
        fprintf(stderr, "nprfx diff: images do not match in size: '%s' is %dx%d, '%s' is %dx%d\n",
                pa, wa, ha, pb, wb, hb);
        goto done;
    }
    n = match_channels(&a, &b, pa, pb, o->channels, idx_a, idx_b, rep);
    if (n < 0) goto done;
    cs = calloc((size_t)n, sizeof *cs);
    if (!cs) goto oom;

    nprfx_rect r = rect_union(a.bounds, b.bounds);
    if (out_path && nprfx_image_alloc(ctx, r, n, &diff)) {
        sum->status = DIFF_FILE_ERROR;
        goto done;
    }
    sum->npixels = (long)nprfx_rect_width(r) * nprfx_rect_height(r);
    sum->maxx = r.x0;
    sum->maxy = r.y0;
    int maxc = 0;
    for (int y = r.y0; y < r.y1; y++)
        for (int x = r.x0; x < r.x1; x++) {
            double perr = 0.0;
            float *d = diff.data ? nprfx_image_at(&diff, x, y) : NULL;
            for (int i = 0; i < n; i++) {
                double e = sample_error(sample(&a, x, y, idx_a[i]), sample(&b, x, y, idx_b[i]));
                chan_stats *c = &cs[i];
                c->sum += e;
                c->sumsq += e * e;
                if (e > c->max) {
                    c->max = e;
                    c->maxx = x;
                    c->maxy = y;
                }
                if (e > perr) perr = e;
                if (e > sum->maxerr) {
                    sum->maxerr = e;
                    sum->maxx = x;
                    sum->maxy = y;
                    maxc = i;
                }
                if (d) d[i] = (float)(e * o->scale);
            }
            sum->nfail += perr > o->fail;
            sum->nwarn += perr > o->warn;
        }
    snprintf(sum->maxchan, sizeof sum->maxchan, "%s", a.names[idx_a[maxc]]);

    if (sum->nfail > o->failpercent / 100.0 * (double)sum->npixels || sum->maxerr > o->hardfail)
        sum->status = DIFF_FAIL;
    else if (sum->nwarn > o->warnpercent / 100.0 * (double)sum->npixels ||
             sum->maxerr > o->hardwarn)
        sum->status = DIFF_WARN;
    else
        sum->status = DIFF_PASS;

    /* The report: per channel, then idiff's summary lines. */
    int namew = 7;
    for (int i = 0; i < n; i++) {
        int l = (int)strlen(a.names[idx_a[i]]);
        if (l > namew) namew = l;
    }
    fprintf(rep, "  %dx%d, %d channel%s compared\n", nprfx_rect_width(r), nprfx_rect_height(r), n,
            n == 1 ? "" : "s");
    fprintf(rep, "  %-*s  %12s  %-12s  %12s  %12s\n", namew, "channel", "max error", "at (x, y)",
            "mean error", "RMS error");
    double tsum = 0, tsq = 0;
    for (int i = 0; i < n; i++) {
        char at[32];
        snprintf(at, sizeof at, "(%d, %d)", cs[i].maxx, cs[i].maxy);
        double np = sum->npixels ? (double)sum->npixels : 1.0;
        fprintf(rep, "  %-*s  %12.6g  %-12s  %12.6g  %12.6g\n", namew, a.names[idx_a[i]], cs[i].max,
                cs[i].max > 0 ? at : "-", cs[i].sum / np, sqrt(cs[i].sumsq / np));
        tsum += cs[i].sum;
        tsq += cs[i].sumsq;
    }
    double nv = (double)sum->npixels * n;
    if (nv <= 0) nv = 1;
    fprintf(rep, "  Mean error = %g\n  RMS error = %g\n", tsum / nv, sqrt(tsq / nv));
    if (sum->maxerr > 0) {
        int ca = idx_a[maxc], cb = idx_b[maxc];
        fprintf(rep, "  Max error  = %g @ (%d, %d, %s)  values are %.9g vs %.9g\n", sum->maxerr,
                sum->maxx, sum->maxy, a.names[ca], sample(&a, sum->maxx, sum->maxy, ca),
                sample(&b, sum->maxx, sum->maxy, cb));
    } else {
        fprintf(rep, "  Max error  = 0\n");
    }
    double pct = sum->npixels ? 100.0 * (double)sum->nfail / (double)sum->npixels : 0.0;
    fprintf(rep, "  %ld pixels (%.3g%%) over %g (fail)\n", sum->nfail, pct, o->fail);
    pct = sum->npixels ? 100.0 * (double)sum->nwarn / (double)sum->npixels : 0.0;
    fprintf(rep, "  %ld pixels (%.3g%%) over %g (warn)\n", sum->nwarn, pct, o->warn);

    if (diff.data && (!o->out_nonzero_only || sum->maxerr > 0)) {
        const char **names = malloc((size_t)n * sizeof *names);
        if (!names) goto oom;
        for (int i = 0; i < n; i++)
            names[i] = a.names[idx_a[i]];
        nprfx_write_options wo = {sizeof wo, "zip", 0};
        nprfx_result wr = nprfx_io_write(ctx, out_path, &diff, names, &a.display, &wo);
        free(names);
        if (wr) {
            sum->status = DIFF_FILE_ERROR;
            goto done;
        }
        fprintf(rep, "  difference image (x%g) written to %s\n", o->scale, out_path);
    }
    goto done;
oom:
    fprintf(stderr, "nprfx diff: out of memory comparing '%s' and '%s'\n", pa, pb);
    sum->status = DIFF_FILE_ERROR;
done:
    nprfx_image_free(&diff);
    free(cs);
    free(idx_a);
    free(idx_b);
    nprfx_plate_free(&a);
    nprfx_plate_free(&b);
    return sum->status;
}

/* A report buffer: single comparisons print it; sequences keep only the worst frame's. */
typedef struct report {
    char *text;
    size_t len;
    FILE *f;
} report;

static FILE *report_open(report *r)
{
    r->text = NULL;
    r->len = 0;
    r->f = open_memstream(&r->text, &r->len);
    return r->f ? r->f : stdout; /* no memory stream: report straight away */
}

static void report_close(report *r)
{
    if (r->f) fclose(r->f);
    r->f = NULL;
}

/* Worse result: higher status, then larger error. */
static int worse(const diff_summary *x, const diff_summary *y)
{
    if (x->status != y->status) return x->status > y->status;
    return x->maxerr > y->maxerr;
}

static int compare_sequence(nprfx_context *ctx, const char *pa, const char *pb,
                            const diff_options *o)
{
    nprfx_frame_list frames = {NULL, 0};
    if (o->frames) {
        if (nprfx_seq_parse_frames(ctx, o->frames, &frames)) return DIFF_USAGE;
    } else {
        if (nprfx_seq_list(ctx, pa, &frames)) return DIFF_FILE_ERROR;
        if (!frames.count) {
            fprintf(stderr, "nprfx diff: no frames of '%s' exist\n", pa);
            return DIFF_FILE_ERROR;
        }
    }
    if (o->out && !nprfx_seq_has_pattern(o->out) && frames.count > 1) {
        fprintf(stderr,
                "nprfx diff: --out '%s' needs a frame pattern (e.g. diff.####.exr) for a "
                "sequence\n",
                o->out);
        nprfx_seq_frames_free(&frames);
        return DIFF_USAGE;
    }
    int counts[5] = {0};
    diff_summary worst;
    memset(&worst, 0, sizeof worst);
    worst.status = -1;
    int worst_frame = 0;
    char *worst_text = NULL;
    char fa[4096], fb[4096], fo[4096];
    for (int i = 0; i < frames.count; i++) {
        int f = frames.frames[i];
        diff_summary s;
        report rep;
        if (nprfx_seq_expand(ctx, pa, f, fa, sizeof fa) ||
            nprfx_seq_expand(ctx, pb, f, fb, sizeof fb) ||
            (o->out && nprfx_seq_expand(ctx, o->out, f, fo, sizeof fo))) {
            nprfx_seq_frames_free(&frames);
            free(worst_text);
            return DIFF_USAGE;
        }
        FILE *rf = report_open(&rep);
        compare_files(ctx, fa, fb, o->out ? fo : NULL, o, rf, &s);
        report_close(&rep);
        counts[s.status]++;
        if (!o->quiet) {
            printf("frame %d: %-10s", f, status_word(s.status));
            if (s.status <= DIFF_FAIL && s.maxerr > 0)
                printf(" max error %g @ (%d, %d, %s), %ld pixels over fail", s.maxerr, s.maxx,
                       s.maxy, s.maxchan, s.nfail);
            else if (s.status <= DIFF_FAIL)
                printf(" identical");
            printf("\n");
        }
        if (worse(&s, &worst)) {
            worst = s;
            worst_frame = f;
            free(worst_text);
            worst_text = rep.text;
        } else {
            free(rep.text);
        }
    }
    if (!o->quiet) {
        printf("%d frames: %d pass, %d warning, %d failure, %d mismatch, %d file error\n",
               frames.count, counts[0], counts[1], counts[2], counts[3], counts[4]);
        if (worst.status > DIFF_PASS && worst_text && worst_text[0]) {
            printf("worst frame %d:\n%s", worst_frame, worst_text);
        }
    }
    printf("%s\n", status_word(worst.status));
    free(worst_text);
    nprfx_seq_frames_free(&frames);
    return worst.status;
}

/* A number option: finite (or "inf" for the hard limits) and not negative. */
static int parse_number(const char *opt, const char *s, double *v)
{
    char *end;
    errno = 0;
    double x = strtod(s, &end);
    if (!*s || *end || errno || isnan(x) || x < 0) {
        fprintf(stderr, "nprfx diff: %s needs a non-negative number, not '%s'\n", opt, s);
        return 0;
    }
    *v = x;
    return 1;
}

int cli_cmd_diff(int argc, char **argv)
{
    diff_options o = {1e-6, 0.0, INFINITY, 1e-6, 0.0, INFINITY, 1.0, NULL, 0, NULL, NULL, 0};
    const char *files[2];
    int nfiles = 0, opts_done = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (opts_done || a[0] != '-' || !a[1]) {
            if (nfiles == 2) {
                fprintf(stderr, "nprfx diff: too many files ('%s'); give exactly two\n", a);
                return DIFF_USAGE;
            }
            files[nfiles++] = a;
            continue;
        }
        if (!strcmp(a, "--")) {
            opts_done = 1;
            continue;
        }
        /* Accept idiff's single-dash spellings and --opt=value as well. */
        char name[64];
        const char *val = NULL;
        snprintf(name, sizeof name, "%s", a[1] == '-' ? a + 2 : a + 1);
        char *eq = strchr(name, '=');
        if (eq) {
            *eq = '\0';
            val = a + (a[1] == '-' ? 2 : 1) + (eq - name) + 1;
        }
        if (!strcmp(name, "help") || !strcmp(name, "h")) {
            usage(stdout);
            return DIFF_PASS;
        }
        if (!strcmp(name, "q") || !strcmp(name, "quiet")) {
            o.quiet = 1;
            continue;
        }
        if (!strcmp(name, "od")) {
            o.out_nonzero_only = 1;
            continue;
        }
        static const char *const valued[] = {"fail",        "failpercent", "hardfail", "warn",
                                             "warnpercent", "hardwarn",    "scale",    "out",
                                             "o",           "channels",    "frames"};
        int known = 0;
        for (size_t k = 0; k < sizeof valued / sizeof valued[0]; k++)
            known |= !strcmp(name, valued[k]);
        if (!known) {
            fprintf(stderr, "nprfx diff: unknown option '%s' (try 'nprfx diff --help')\n", a);
            return DIFF_USAGE;
        }
        if (!val) {
            if (i + 1 >= argc) {
                fprintf(stderr, "nprfx diff: %s needs a value\n", a);
                return DIFF_USAGE;
            }
            val = argv[++i];
        }
        int ok = 1;
        if (!strcmp(name, "fail"))
            ok = parse_number(a, val, &o.fail);
        else if (!strcmp(name, "failpercent"))
            ok = parse_number(a, val, &o.failpercent);
        else if (!strcmp(name, "hardfail"))
            ok = parse_number(a, val, &o.hardfail);
        else if (!strcmp(name, "warn"))
            ok = parse_number(a, val, &o.warn);
        else if (!strcmp(name, "warnpercent"))
            ok = parse_number(a, val, &o.warnpercent);
        else if (!strcmp(name, "hardwarn"))
            ok = parse_number(a, val, &o.hardwarn);
        else if (!strcmp(name, "scale"))
            ok = parse_number(a, val, &o.scale);
        else if (!strcmp(name, "out") || !strcmp(name, "o"))
            o.out = val;
        else if (!strcmp(name, "channels"))
            o.channels = *val ? val : NULL;
        else
            o.frames = val;
        if (!ok) return DIFF_USAGE;
    }
    if (nfiles != 2) {
        usage(stderr);
        return DIFF_USAGE;
    }

    nprfx_context *ctx = NULL;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    init.error_handler = print_error;
    if (nprfx_context_create(&init, &ctx)) {
        fprintf(stderr, "nprfx diff: cannot create a context\n");
        return DIFF_FILE_ERROR;
    }
    int rc;
    int seq_a = nprfx_seq_has_pattern(files[0]), seq_b = nprfx_seq_has_pattern(files[1]);
    if (seq_a != seq_b) {
        fprintf(stderr,
                "nprfx diff: '%s' is %sa frame pattern but '%s' is %s; give two files or two "
                "sequences\n",
                files[0], seq_a ? "" : "not ", files[1], seq_b ? "one" : "not");
        rc = DIFF_USAGE;
    } else if (seq_a) {
        rc = compare_sequence(ctx, files[0], files[1], &o);
    } else if (o.frames) {
        fprintf(stderr, "nprfx diff: --frames needs frame patterns in A and B (e.g. a.####.exr)\n");
        rc = DIFF_USAGE;
    } else {
        diff_summary s;
        report rep;
        FILE *rf = o.quiet ? report_open(&rep) : stdout;
        rc = compare_files(ctx, files[0], files[1], o.out, &o, rf, &s);
        if (o.quiet) {
            report_close(&rep);
            free(rep.text);
        }
        if (rc <= DIFF_FAIL || !o.quiet) printf("%s\n", status_word(rc));
    }
    nprfx_context_destroy(ctx);
    return rc;
}
