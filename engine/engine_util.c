/* nprfx graph engine — engine_util.h: the clocks, strdup and a parallel byte copy. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine_util.h"

double engine_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double engine_cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

char *engine_strdup(const char *s)
{
    if (!s) return NULL;
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

typedef struct bytes_job {
    const unsigned char *src; /* NULL: zero */
    unsigned char *dst;
    size_t bytes;
    int parts;
} bytes_job;

static void bytes_parts(void *user, int begin, int end, int worker)
{
    (void)worker;
    const bytes_job *j = user;
    for (int p = begin; p < end; p++) {
        size_t a = j->bytes * (size_t)p / (size_t)j->parts;
        size_t b = j->bytes * (size_t)(p + 1) / (size_t)j->parts;
        if (j->src)
            memcpy(j->dst + a, j->src + a, b - a);
        else
            memset(j->dst + a, 0, b - a);
    }
}

void engine_parallel_bytes(const nprfx_executor *ex, void *dst, const void *src, size_t bytes,
                           int parts)
{
    bytes_job j = {src, dst, bytes, parts > 0 ? parts : 1};
    if (j.parts == 1 || !ex) {
        bytes_parts(&j, 0, j.parts, 0);
        return;
    }
    nprfx_parallel_for(ex, j.parts, 1, bytes_parts, &j);
}

void engine_names_free(char **names, int n)
{
    if (!names) return;
    for (int i = 0; i < n; i++)
        free(names[i]);
    free(names);
}

char *engine_read_text(nprfx_context *ctx, const char *path, const char *what, long most)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        nprfx_error(ctx, NPRFX_ERR_IO, "cannot open %s '%s': %s", what, path, strerror(errno));
        return NULL;
    }
    char *text = NULL;
    long len = fseek(f, 0, SEEK_END) ? -1 : ftell(f);
    if (len >= 0 && len < most && !fseek(f, 0, SEEK_SET)) text = malloc((size_t)len + 1);
    if (!text || fread(text, 1, (size_t)len, f) != (size_t)len) {
        free(text);
        fclose(f);
        if (len >= most)
            nprfx_error(ctx, NPRFX_ERR_IO, "%s '%s' is %ld bytes: too large to be one", what, path,
                        len);
        else
            nprfx_error(ctx, NPRFX_ERR_IO, "cannot read %s '%s'", what, path);
        return NULL;
    }
    fclose(f);
    text[len] = 0;
    return text;
}
