/* nprfx ivs — generate, write and check the compact IVS sequence file (nprfx/ivs.h).
 *
 * The core generates and encodes the sequence in memory; this command writes the bytes (through
 * a temporary name and a rename, nprfx_io_write_text) and, with --check, reads a file back,
 * decodes and validates it and measures its spacing. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine/engine_util.h"
#include "commands.h"
#include "io/io_write.h"
#include "nprfx/ivs.h"
#include "nprfx/nprfx.h"
#include "util/cli_util.h"

/* Exit status: 0 done (and, with --check, every spacing bound held), 1 a file or data error, or
 * a spacing bound failed, 2 usage error. */
enum { IVS_OK = 0, IVS_FAILED = 1, IVS_USAGE = 2 };

/* The most points -n takes: the generator needs ~150 bytes a point while it runs. */
#define IVS_MAX_COUNT (1 << 24)
/* r_i * sqrt(i) is reported for i past the bootstrap, as the design's bound is stated. */
#define IVS_WARMUP 16

static void usage(FILE *f)
{
    fprintf(f,
            "usage: nprfx ivs -n COUNT [--seed S] -o FILE\n"
            "       nprfx ivs --check FILE\n\n"
            "The stipple node's dot sequence: an incremental Voronoi set (IVS), a farthest-point\n"
            "sequence on the unit torus in which every prefix is evenly spread and point i\n"
            "(1-based) owns about 1/i of the torus (docs/design.md §3.3). The node generates\n"
            "it on first use; this command writes it as a compact file (6 bytes a point, 24-bit\n"
            "coordinates, with a checksum) and checks such files.\n\n"
            "options:\n"
            "  -n COUNT        points to generate, 1..%d (about 2.5 s per million)\n"
            "  --seed S        generator seed (default %llu, the node's sequence); the first m\n"
            "                  points do not depend on COUNT\n"
            "  -o FILE         where to write; written to a temporary name, then renamed\n"
            "  --check FILE    read FILE, verify header and checksum, print its count and seed,\n"
            "                  the range of r_i*sqrt(i) (r_i: distance from point i to the\n"
            "                  nearest earlier point, i > %d; expected within [0.7, 0.9]) and\n"
            "                  the normalised minimum distance d_min / sqrt(2 / (sqrt(3) n)) of\n"
            "                  prefixes of n = 64, 256, ... points (expected >= 0.7). Exit 1\n"
            "                  when the file is unreadable or corrupt or a bound fails.\n\n"
            "examples:\n"
            "  nprfx ivs -n 1048576 -o ivs_1m.bin\n"
            "  nprfx ivs --check ivs_1m.bin\n",
            IVS_MAX_COUNT, (unsigned long long)NPRFX_IVS_DEFAULT_SEED, IVS_WARMUP);
}

static int generate(nprfx_context *ctx, long long n, unsigned long long seed, const char *out)
{
    float *xy = malloc(sizeof(float) * 2 * (size_t)n);
    size_t size = nprfx_ivs_encoded_size((int)n);
    unsigned char *buf = malloc(size);
    int status = IVS_OK;
    if (!xy || !buf) {
        fprintf(stderr, "nprfx ivs: out of memory for %lld points\n", n);
        status = IVS_FAILED;
        goto done;
    }
    double t0 = engine_now();
    if (nprfx_ivs_generate(ctx, seed, (int)n, xy, NULL) != NPRFX_OK ||
        nprfx_ivs_encode(ctx, seed, (int)n, xy, buf, size) != NPRFX_OK ||
        nprfx_io_write_text(ctx, out, (const char *)buf, size) != NPRFX_OK) {
        fprintf(stderr, "nprfx ivs: %s\n", cli_message(ctx));
        status = IVS_FAILED;
        goto done;
    }
    printf("wrote %s: %lld points, seed %llu, %zu bytes (%.2f s)\n", out, n, seed, size,
           engine_now() - t0);
done:
    free(xy);
    free(buf);
    return status;
}

/* ---- --check: nearest earlier point of every point, on a uniform grid of the torus ---- */

typedef struct tgrid {
    int g;
    int *head, *next; /* per cell, the points inserted so far (a linked list) */
    const float *xy;
} tgrid;

static double torus_d2(double ax, double ay, double bx, double by)
{
    double dx = ax - bx, dy = ay - by;
    dx -= floor(dx + 0.5);
    dy -= floor(dy + 0.5);
    return dx * dx + dy * dy;
}

static int cell(double v, int g)
{
    int c = (int)floor(v * g);
    return c < 0 ? 0 : c >= g ? g - 1 : c;
}

static double visit_cell(const tgrid *t, int cx, int cy, double x, double y, double best)
{
    int g = t->g, c = ((cy % g + g) % g) * g + ((cx % g + g) % g);
    for (int j = t->head[c]; j >= 0; j = t->next[j]) {
        double d2 = torus_d2(x, y, t->xy[2 * j], t->xy[2 * j + 1]);
        if (d2 < best) best = d2;
    }
    return best;
}

/* Distance from point k to the nearest point already in the grid: rings of cells around it
 * until a ring lies farther than the best found, or the rings have covered the torus. */
static double nearest(const tgrid *t, int k)
{
    int g = t->g;
    double x = t->xy[2 * k], y = t->xy[2 * k + 1];
    int cx = cell(x, g), cy = cell(y, g);
    double best = visit_cell(t, cx, cy, x, y, 1e30);
    for (int ring = 1; 2 * ring - 1 < g; ring++) {
        if (ring >= 2 && (ring - 1) * (1.0 / g) > sqrt(best)) break;
        for (int dx = -ring; dx <= ring; dx++) { /* top and bottom rows */
            best = visit_cell(t, cx + dx, cy - ring, x, y, best);
            best = visit_cell(t, cx + dx, cy + ring, x, y, best);
        }
        for (int dy = -ring + 1; dy <= ring - 1; dy++) { /* left and right columns */
            best = visit_cell(t, cx - ring, cy + dy, x, y, best);
            best = visit_cell(t, cx + ring, cy + dy, x, y, best);
        }
    }
    return sqrt(best);
}

static int check(nprfx_context *ctx, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "nprfx ivs: cannot open '%s': %s\n", path, strerror(errno));
        return IVS_FAILED;
    }
    size_t cap = 1 << 20, size = 0;
    unsigned char *buf = malloc(cap);
    for (;;) {
        if (!buf) break;
        size += fread(buf + size, 1, cap - size, f);
        if (size < cap) break;
        unsigned char *nb = realloc(buf, cap * 2);
        if (!nb) {
            free(buf);
            buf = NULL;
            break;
        }
        buf = nb;
        cap *= 2;
    }
    int read_error = ferror(f);
    fclose(f);
    if (!buf || read_error) {
        fprintf(stderr, "nprfx ivs: cannot read '%s': %s\n", path,
                buf ? "read error" : "out of memory");
        free(buf);
        return IVS_FAILED;
    }
    uint64_t seed = 0;
    int n = 0;
    float *xy = NULL;
    nprfx_result r = nprfx_ivs_decode(ctx, buf, size, &seed, &n, &xy);
    free(buf);
    if (r != NPRFX_OK) {
        fprintf(stderr, "nprfx ivs: %s: %s\n", path, cli_message(ctx));
        return IVS_FAILED;
    }
    printf("%s: %d points, seed %llu, %zu bytes, checksum ok\n", path, n, (unsigned long long)seed,
           size);

    tgrid t;
    t.g = (int)floor(sqrt(n / 2.0));
    if (t.g < 1) t.g = 1;
    t.xy = xy;
    t.head = malloc(sizeof(int) * (size_t)t.g * (size_t)t.g);
    t.next = malloc(sizeof(int) * (size_t)n);
    if (!t.head || !t.next) {
        fprintf(stderr, "nprfx ivs: out of memory checking %d points\n", n);
        free(t.head);
        free(t.next);
        free(xy);
        return IVS_FAILED;
    }
    for (int c = 0; c < t.g * t.g; c++)
        t.head[c] = -1;
    double lo = INFINITY, hi = -INFINITY, dmin = INFINITY;
    int lo_i = 0, hi_i = 0, status = IVS_OK;
    long long next_prefix = 64;
    printf("normalised minimum distance d_min / sqrt(2 / (sqrt(3) n)) of the first n points:\n");
    for (int k = 0; k < n; k++) {
        if (k > 0) {
            double d = nearest(&t, k);
            if (d < dmin) dmin = d;
            int i = k + 1; /* 1-based */
            double rs = d * sqrt((double)i);
            if (i > IVS_WARMUP) {
                if (rs < lo) lo = rs, lo_i = i;
                if (rs > hi) hi = rs, hi_i = i;
            }
        }
        int c = cell(xy[2 * k + 1], t.g) * t.g + cell(xy[2 * k], t.g);
        t.next[k] = t.head[c];
        t.head[c] = k;
        long long m = k + 1;
        if (m == next_prefix || (m == n && m >= 64)) {
            double norm = dmin / sqrt(2.0 / (sqrt(3.0) * (double)m));
            int ok = norm >= 0.7;
            printf("  n = %-9lld %.3f%s\n", m, norm, ok ? "" : "  FAIL (< 0.7)");
            if (!ok) status = IVS_FAILED;
            if (m == next_prefix) next_prefix *= 4;
        }
    }
    if (n > IVS_WARMUP) {
        int ok = lo >= 0.7 && hi <= 0.9;
        printf("r_i * sqrt(i) for i = %d..%d: min %.3f (i = %d), max %.3f (i = %d)%s\n",
               IVS_WARMUP + 1, n, lo, lo_i, hi, hi_i, ok ? "" : "  FAIL (outside [0.7, 0.9])");
        if (!ok) status = IVS_FAILED;
    } else {
        printf("r_i * sqrt(i): too few points (the bound is for i > %d)\n", IVS_WARMUP);
    }
    printf("%s\n", status == IVS_OK ? "ok" : "FAILED: the sequence is not evenly spread");
    free(t.head);
    free(t.next);
    free(xy);
    return status;
}

int cli_cmd_ivs(int argc, char **argv)
{
    const char *out = NULL, *check_path = NULL, *count_text = NULL, *seed_text = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return IVS_OK;
        } else if ((!strcmp(a, "-n") || !strcmp(a, "--count")) && has) {
            count_text = argv[++i];
        } else if (!strcmp(a, "--seed") && has) {
            seed_text = argv[++i];
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has) {
            out = argv[++i];
        } else if (!strcmp(a, "--check") && has) {
            check_path = argv[++i];
        } else {
            fprintf(stderr, "nprfx ivs: unexpected argument '%s'%s\n\n", a,
                    a[0] == '-' && !has ? " (it needs a value)" : "");
            usage(stderr);
            return IVS_USAGE;
        }
    }
    if (check_path && (out || count_text || seed_text)) {
        fprintf(stderr, "nprfx ivs: --check takes no other option\n\n");
        usage(stderr);
        return IVS_USAGE;
    }
    long long n = 0;
    unsigned long long seed = NPRFX_IVS_DEFAULT_SEED;
    if (!check_path) {
        char *end = NULL;
        if (!count_text || !out) {
            fprintf(stderr, "nprfx ivs: give -n COUNT and -o FILE, or --check FILE\n\n");
            usage(stderr);
            return IVS_USAGE;
        }
        errno = 0;
        n = strtoll(count_text, &end, 10);
        if (errno || end == count_text || *end || n < 1 || n > IVS_MAX_COUNT) {
            fprintf(stderr, "nprfx ivs: -n must be a whole number from 1 to %d, not '%s'\n",
                    IVS_MAX_COUNT, count_text);
            return IVS_USAGE;
        }
        if (seed_text) {
            errno = 0;
            seed = strtoull(seed_text, &end, 0);
            if (errno || end == seed_text || *end || seed_text[0] == '-') {
                fprintf(stderr, "nprfx ivs: --seed must be a non-negative integer, not '%s'\n",
                        seed_text);
                return IVS_USAGE;
            }
        }
    }
    nprfx_context *ctx = NULL;
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    if (nprfx_context_create(&ci, &ctx) != NPRFX_OK) {
        fprintf(stderr, "nprfx ivs: cannot create a context\n");
        return IVS_FAILED;
    }
    int status = check_path ? check(ctx, check_path) : generate(ctx, n, seed, out);
    nprfx_context_destroy(ctx);
    return status;
}
