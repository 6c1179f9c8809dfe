/* Frame lists and frame-numbered path patterns (see seq.h for the syntax). */
#define _POSIX_C_SOURCE 200809L /* opendir, strtol ranges */
#include "nprfx/seq.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A runaway spec ("1-2000000000") should be an error, not an allocation of gigabytes. */
#define SEQ_MAX_FRAMES 1000000

void nprfx_seq_frames_free(nprfx_frame_list *list)
{
    if (!list) return;
    free(list->frames);
    list->frames = NULL;
    list->count = 0;
}

static int push_frame(nprfx_frame_list *l, int *cap, int frame)
{
    if (l->count == *cap) {
        int ncap = *cap ? *cap * 2 : 16;
        int *nf = realloc(l->frames, (size_t)ncap * sizeof *nf);
        if (!nf) return 0;
        l->frames = nf;
        *cap = ncap;
    }
    l->frames[l->count++] = frame;
    return 1;
}

/* Parse an optionally negative integer at *p, advancing *p; 0 on failure. */
static int parse_int(const char **p, long *v)
{
    const char *s = *p;
    if (!(isdigit((unsigned char)s[0]) || (s[0] == '-' && isdigit((unsigned char)s[1])))) return 0;
    char *end;
    errno = 0;
    long x = strtol(s, &end, 10);
    if (errno || x < INT_MIN || x > INT_MAX) return 0;
    *v = x;
    *p = end;
    return 1;
}

nprfx_result nprfx_seq_parse_frames(nprfx_context *ctx, const char *spec, nprfx_frame_list *out)
{
    out->frames = NULL;
    out->count = 0;
    if (!spec || !*spec)
        return nprfx_error(ctx, NPRFX_ERR_PARSE, "empty frame range (expected e.g. 1-24)");
    int cap = 0;
    const char *p = spec;
    for (;;) {
        const char *item = p;
        while (*p == ' ')
            p++;
        long a, b, step = 1;
        if (!parse_int(&p, &a)) goto bad;
        b = a;
        if (*p == '-') {
            p++;
            if (!parse_int(&p, &b)) goto bad;
            if (*p == 'x' || *p == ':') {
                p++;
                if (!parse_int(&p, &step) || step <= 0) goto bad;
            }
        }
        while (*p == ' ')
            p++;
        if (*p != ',' && *p != '\0') goto bad;
        if (a < NPRFX_FRAME_MIN || a > NPRFX_FRAME_MAX || b < NPRFX_FRAME_MIN ||
            b > NPRFX_FRAME_MAX) {
            nprfx_seq_frames_free(out);
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                               "frame %ld in '%s' is outside the frames nprfx renders (%d to %d)",
                               a < NPRFX_FRAME_MIN || a > NPRFX_FRAME_MAX ? a : b, spec,
                               NPRFX_FRAME_MIN, NPRFX_FRAME_MAX);
        }
        long n = (a <= b ? b - a : a - b) / step + 1;
        if (n > SEQ_MAX_FRAMES - out->count) {
            nprfx_seq_frames_free(out);
            return nprfx_error(ctx, NPRFX_ERR_PARSE, "frame range '%s' has more than %d frames",
                               spec, SEQ_MAX_FRAMES);
        }
        for (long i = 0; i < n; i++) {
            long f = a <= b ? a + i * step : a - i * step;
            if (!push_frame(out, &cap, (int)f)) {
                nprfx_seq_frames_free(out);
                return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory for frame list");
            }
        }
        if (*p == '\0') break;
        p++; /* ',' */
        continue;
    bad:
        nprfx_seq_frames_free(out);
        return nprfx_error(ctx, NPRFX_ERR_PARSE,
                           "bad frame range '%s' near '%s' (expected e.g. 1-24, 1-24x2 or 1,3,5-7)",
                           spec, item);
    }
    return NPRFX_OK;
}

/* Kinds of what token_at finds at a position of the file name. */
enum { TOK_NONE, TOK_PERCENT_LITERAL, TOK_FRAME };

/* Examine s: a frame token (its length, width and printf flavour), a "%%" escape, or neither. */
static int token_at(const char *s, int *len, int *width, char *pad)
{
    if (*s == '#' || *s == '@') {
        int n = 0;
        while (s[n] == s[0])
            n++;
        *len = n;
        *width = n;
        *pad = '0';
        return TOK_FRAME;
    }
    if (*s != '%') return TOK_NONE;
    if (s[1] == '%') {
        *len = 2;
        return TOK_PERCENT_LITERAL;
    }
    int i = 1, w = 0;
    char pd = ' ';
    if (s[i] == '0') {
        pd = '0';
        i++;
    }
    while (isdigit((unsigned char)s[i]) && w < 1000)
        w = w * 10 + (s[i++] - '0');
    if (s[i] != 'd') return TOK_NONE;
    *len = i + 1;
    *width = w;
    *pad = pd;
    return TOK_FRAME;
}

static const char *basename_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

int nprfx_seq_has_pattern(const char *path)
{
    int len, width;
    char pad;
    for (const char *s = basename_of(path); *s;) {
        int t = token_at(s, &len, &width, &pad);
        if (t == TOK_FRAME) return 1;
        s += t == TOK_NONE ? 1 : len;
    }
    return 0;
}

/* Expand pattern into out; with stop_at_token, stop before the first frame token of the file name
 * (giving the literal prefix a matching name must start with). */
static int expand(const char *pattern, int frame, int stop_at_token, char *out, size_t size)
{
    const char *base = basename_of(pattern);
    size_t o = 0;
#define PUT(ch)                                                                                    \
    do {                                                                                           \
        if (o + 1 >= size) return 0;                                                               \
        out[o++] = (ch);                                                                           \
    } while (0)
    for (const char *s = pattern; s < base; s++)
        PUT(*s);
    int len, width;
    char pad;
    for (const char *s = base; *s;) {
        int t = token_at(s, &len, &width, &pad);
        if (t == TOK_NONE) {
            PUT(*s);
            s++;
        } else if (t == TOK_PERCENT_LITERAL) {
            PUT('%');
            s += len;
        } else {
            if (stop_at_token) break;
            char num[1100];
            snprintf(num, sizeof num, pad == '0' ? "%0*d" : "%*d", width, frame);
            for (const char *n = num; *n; n++)
                PUT(*n);
            s += len;
        }
    }
#undef PUT
    out[o] = '\0';
    return 1;
}

nprfx_result nprfx_seq_expand(nprfx_context *ctx, const char *pattern, int frame, char *out,
                              size_t size)
{
    if (!pattern || !out || !size)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "nprfx_seq_expand: NULL argument");
    if (!expand(pattern, frame, 0, out, size))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "path '%s' for frame %d is longer than %zu bytes", pattern, frame,
                           size - 1);
    return NPRFX_OK;
}

static int cmp_int(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

int nprfx_seq_match(const char *pattern, const char *name, int *frame)
{
    const char *base = basename_of(pattern);
    char prefix[4096], again[4096];
    if (!nprfx_seq_has_pattern(base)) return !strcmp(base, name);
    if (!expand(base, 0, 1, prefix, sizeof prefix)) return 0;
    size_t plen = strlen(prefix);
    if (strncmp(name, prefix, plen)) return 0;
    const char *p = name + plen;
    while (*p == ' ')
        p++; /* "%4d" pads with spaces */
    long f;
    if (!parse_int(&p, &f)) return 0;
    /* Only an exact re-expansion counts: rejects wrong padding and other suffixes. */
    if (!expand(base, (int)f, 0, again, sizeof again) || strcmp(again, name)) return 0;
    if (frame) *frame = (int)f;
    return 1;
}

nprfx_result nprfx_seq_canonical(nprfx_context *ctx, const char *pattern, char *out, size_t size)
{
    size_t o = 0;
    int len, width;
    char pad;
    for (const char *s = basename_of(pattern); *s; s += len) {
        int t = token_at(s, &len, &width, &pad);
        const char *piece = s;
        size_t n = 1, hashes = 0;
        if (t == TOK_NONE)
            len = 1;
        else if (t == TOK_PERCENT_LITERAL)
            piece = "%";
        else if (pad == '0' || width <= 1) /* "%d" prints what "#" prints */
            hashes = width > 1 ? (size_t)width : 1;
        else
            n = (size_t)len; /* space padded: kept as written */
        if (hashes) n = hashes;
        if (o + n + 1 > size)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "path '%s' is too long", pattern);
        if (hashes)
            memset(out + o, '#', n);
        else
            memcpy(out + o, piece, n);
        o += n;
    }
    out[o] = '\0';
    return NPRFX_OK;
}

nprfx_result nprfx_seq_list(nprfx_context *ctx, const char *pattern, nprfx_frame_list *out)
{
    out->frames = NULL;
    out->count = 0;
    if (!nprfx_seq_has_pattern(pattern))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "'%s' has no frame number pattern (####, @, %%04d)", pattern);
    const char *base = basename_of(pattern);
    size_t dirlen = (size_t)(base - pattern);
    char dir[4096], prefix[4096];
    if (dirlen + 2 > sizeof dir || strlen(base) + 1 > sizeof prefix)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "path '%s' is too long", pattern);
    if (dirlen) {
        memcpy(dir, pattern, dirlen);
        dir[dirlen] = '\0';
    } else {
        strcpy(dir, ".");
    }
    expand(base, 0, 1, prefix, sizeof prefix);
    size_t plen = strlen(prefix);

    DIR *d = opendir(dir);
    if (!d)
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot list directory '%s' for '%s': %s", dir,
                           pattern, strerror(errno));
    int cap = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        int f;
        if (strncmp(e->d_name, prefix, plen) || !nprfx_seq_match(base, e->d_name, &f)) continue;
        if (!push_frame(out, &cap, f)) {
            closedir(d);
            nprfx_seq_frames_free(out);
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory listing '%s'", pattern);
        }
    }
    closedir(d);
    if (out->count) qsort(out->frames, (size_t)out->count, sizeof *out->frames, cmp_int);
    int n = 0;
    for (int i = 0; i < out->count; i++)
        if (!n || out->frames[n - 1] != out->frames[i]) out->frames[n++] = out->frames[i];
    out->count = n;
    return NPRFX_OK;
}
