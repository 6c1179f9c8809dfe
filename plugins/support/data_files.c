/* The data files nodes read, outside core: a file of the context's data directory found and read
 * whole with a size limit and errors that name it, and the stipple node's shipped dot sequence
 * (ivs.bin) read, decoded by core (nprfx_ivs_decode) and preloaded into a sequence that the
 * whole process shares. */
#include <errno.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "support/data_files.h"

nprfx_result internal_data_file_read(nprfx_context *ctx, const char *name, size_t max_size,
                                  nprfx_data_file *out)
{
    if (!out || !name || !*name)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "data file: no name or no output");
    memset(out, 0, sizeof *out);
    const char *dir = nprfx_context_data_dir(ctx);
    if (!dir || !*dir) return NPRFX_OK;
    int n = snprintf(out->path, sizeof out->path, "%s/%s", dir, name);
    if (n < 0 || (size_t)n >= sizeof out->path)
        return nprfx_error(ctx, NPRFX_ERR_IO,
                           "%s: the data directory's path is too long (the file's path would "
                           "exceed %zu bytes)",
                           name, sizeof out->path - 1);
    FILE *f = fopen(out->path, "rb");
    if (!f) {
        if (errno == ENOENT || errno == ENOTDIR) return NPRFX_OK; /* not there: do without */
        return nprfx_error(ctx, NPRFX_ERR_IO, "%s: cannot open it: %s", out->path, strerror(errno));
    }
    if (max_size > SIZE_MAX / 2) max_size = SIZE_MAX / 2;
    unsigned char *buf = NULL;
    size_t size = 0, cap = 0;
    nprfx_result r = NPRFX_OK;
    for (;;) {
        if (size == cap) {
            if (cap > max_size) {
                r = nprfx_error(ctx, NPRFX_ERR_IO,
                                "%s: larger than %zu bytes, the most it may hold", out->path,
                                max_size);
                break;
            }
            /* one byte past the limit tells a file of max_size bytes from a longer one */
            size_t ncap = cap ? 2 * cap : (size_t)8 << 20;
            if (ncap > max_size + 1) ncap = max_size + 1;
            unsigned char *nb = realloc(buf, ncap);
            if (!nb) {
                r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "%s: out of memory reading it",
                                out->path);
                break;
            }
            buf = nb;
            cap = ncap;
        }
        errno = 0;
        size_t got = fread(buf + size, 1, cap - size, f);
        size += got;
        if (got == 0) break;
    }
    if (r == NPRFX_OK && ferror(f))
        r = nprfx_error(ctx, NPRFX_ERR_IO, "%s: cannot read it: %s", out->path,
                        errno ? strerror(errno) : "read error");
    fclose(f);
    if (r != NPRFX_OK) {
        free(buf);
        return r;
    }
    out->data = buf;
    out->size = size;
    return NPRFX_OK;
}

void internal_data_file_free(nprfx_data_file *f)
{
    if (!f) return;
    free(f->data);
    f->data = NULL;
    f->size = 0;
}

/* ---- the stipple node's dot sequence ---- */

#define IVS_FILE_NAME "ivs.bin"
/* The longest sequence `nprfx ivs` writes (2^24 points, about 100 MB). */
#define IVS_FILE_MAX_POINTS (1 << 24)
#define IVS_FILE_ADVICE "rebuild it with `nprfx ivs`, or remove it"

/* Preload seq from the shipped file, when there is one. */
static nprfx_result preload_shipped(nprfx_context *ctx, nprfx_stipple_sequence *seq)
{
    const char *dir = nprfx_context_data_dir(ctx);
    if (!dir || !*dir) return NPRFX_OK;
    /* Read and decode on a private context (with the caller's data directory), so that the
     * caller's handler hears one message that says which file and what to do, not the reader's
     * or the decoder's alone. */
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.data_dir = dir;
    nprfx_context *quiet = NULL;
    nprfx_result r = nprfx_context_create(&ci, &quiet);
    if (r != NPRFX_OK) return nprfx_error(ctx, r, "stipple: out of memory");
    nprfx_data_file file;
    uint64_t seed = 0;
    int n = 0;
    float *xy = NULL;
    char why[512];
    r = internal_data_file_read(quiet, IVS_FILE_NAME, nprfx_ivs_encoded_size(IVS_FILE_MAX_POINTS),
                             &file);
    if (r != NPRFX_OK) { /* the reader's message starts with the path */
        nprfx_context_last_error(quiet, why, sizeof why);
        r = nprfx_error(ctx, r, "stipple: %s (" IVS_FILE_ADVICE ")", why);
    } else if (file.data) {
        r = nprfx_ivs_decode(quiet, file.data, file.size, &seed, &n, &xy);
        if (r != NPRFX_OK) {
            nprfx_context_last_error(quiet, why, sizeof why);
            r = nprfx_error(ctx, r, "stipple: %s: %s (" IVS_FILE_ADVICE ")", file.path, why);
        } else if (seed != NPRFX_IVS_DEFAULT_SEED) {
            r = nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                            "stipple: %s holds the sequence of seed %llu, not the node's %u "
                            "(" IVS_FILE_ADVICE ")",
                            file.path, (unsigned long long)seed, NPRFX_IVS_DEFAULT_SEED);
        } else {
            r = nprfx_stipple_sequence_preload(ctx, seq, xy, n);
        }
    }
    free(xy);
    internal_data_file_free(&file);
    nprfx_context_destroy(quiet);
    return r;
}

/* ---- one shipped sequence per file, for the whole process ----
 *
 * Every stipple instance (a graph's nodes, a host's instances, the tone-curve measurements) wants
 * the same points. Decoding the file, indexing it and measuring a tone curve took ~0.3-0.8 s of
 * each instance's first frame, so the sequence is made once per data file and shared: it is
 * thread-safe and only ever grows by immutable versions (nprfx/stipple.h), and the curves it
 * keeps are deterministic, so sharing never changes a pixel. The file is known by its path and
 * what stat says of it, so a file rebuilt with `nprfx ivs` (or removed) is read again. This is
 * the nodes' library, not core, which keeps no process-wide state. */

typedef struct shared_seq {
    char path[4096]; /* the data file's path, "" without a data directory */
    int exists;
    dev_t dev;
    ino_t ino;
    off_t size;
    struct timespec mtime;
    nprfx_stipple_sequence *seq; /* the registry's reference */
    struct shared_seq *next;
} shared_seq;

static pthread_mutex_t shared_lock = PTHREAD_MUTEX_INITIALIZER;
static shared_seq *shared_list;

/* What identifies the file at `path` now. */
static void file_key(const char *path, shared_seq *k)
{
    memset(k, 0, sizeof *k);
    snprintf(k->path, sizeof k->path, "%s", path);
    struct stat st;
    if (*path && stat(path, &st) == 0) {
        k->exists = 1;
        k->dev = st.st_dev;
        k->ino = st.st_ino;
        k->size = st.st_size;
        k->mtime = st.st_mtim;
    }
}

static int same_file(const shared_seq *a, const shared_seq *b)
{
    return !strcmp(a->path, b->path) && a->exists == b->exists && a->dev == b->dev &&
           a->ino == b->ino && a->size == b->size && a->mtime.tv_sec == b->mtime.tv_sec &&
           a->mtime.tv_nsec == b->mtime.tv_nsec;
}

/* A new sequence preloaded from the file (when there is one). */
static nprfx_result make_shipped(nprfx_context *ctx, nprfx_stipple_sequence **out)
{
    nprfx_stipple_sequence *seq = NULL;
    nprfx_result r = nprfx_stipple_sequence_create(ctx, &seq);
    if (r == NPRFX_OK) r = preload_shipped(ctx, seq);
    if (r != NPRFX_OK) {
        nprfx_stipple_sequence_destroy(seq);
        return r;
    }
    *out = seq;
    return NPRFX_OK;
}

nprfx_result internal_stipple_shipped_sequence(nprfx_context *ctx, nprfx_stipple_sequence **out)
{
    if (!out) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "stipple: NULL output");
    *out = NULL;
    const char *dir = nprfx_context_data_dir(ctx);
    char path[4096] = "";
    if (dir && *dir) snprintf(path, sizeof path, "%s/" IVS_FILE_NAME, dir);
    shared_seq *key = malloc(sizeof *key);
    if (!key) return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "stipple: out of memory");
    file_key(path, key);
    nprfx_result r = NPRFX_OK;
    /* read under the lock: a second instance waits for the first one's file instead of
     * reading it too */
    pthread_mutex_lock(&shared_lock);
    shared_seq **at = &shared_list;
    while (*at && strcmp((*at)->path, key->path))
        at = &(*at)->next;
    if (*at && same_file(*at, key)) {
        *out = nprfx_stipple_sequence_retain((*at)->seq);
        free(key);
    } else {
        nprfx_stipple_sequence *seq = NULL;
        r = make_shipped(ctx, &seq);
        if (r == NPRFX_OK) {
            if (*at) { /* the file changed: the old sequence lives on in its users */
                shared_seq *old = *at;
                *at = old->next;
                nprfx_stipple_sequence_destroy(old->seq);
                free(old);
            }
            key->seq = seq;
            key->next = shared_list;
            shared_list = key;
            *out = nprfx_stipple_sequence_retain(seq);
        } else {
            free(key); /* a broken file is not kept: each use reports it */
        }
    }
    pthread_mutex_unlock(&shared_lock);
    return r;
}

void internal_stipple_shipped_release(void)
{
    pthread_mutex_lock(&shared_lock);
    while (shared_list) {
        shared_seq *s = shared_list;
        shared_list = s->next;
        nprfx_stipple_sequence_destroy(s->seq);
        free(s);
    }
    pthread_mutex_unlock(&shared_lock);
}
