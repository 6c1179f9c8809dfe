/* Output sequence locks (see output_lock.h): flock on ".<pattern>.nprfx-lock" beside each
 * sequence, the holder described inside, stale temporary files removed by the next holder. */
#define _DEFAULT_SOURCE /* flock, gethostname, realpath */
#include "cli_util.h"
#include "output_lock.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "nprfx/seq.h"

typedef struct lock_entry {
    char pattern[4096];          /* as the graph names it, for messages */
    char dir[4096];              /* the sequence's folder as given ("." when none) */
    char base[1024];             /* the pattern's file name */
    char path[4096 + 1024 + 16]; /* the lock file, beside the sequence */
    char key[PATH_MAX + 1100];   /* the lock file under the folder's real path: sorts, dedups */
    int fd;
} lock_entry;

struct cli_output_locks {
    lock_entry *entries;
    int count;
    int shared; /* LOCK_SH: other shared holders may hold the same files */
};

static nprfx_result entry_init(nprfx_context *ctx, const char *pattern, lock_entry *e)
{
    const char *slash = strrchr(pattern, '/');
    const char *base = slash ? slash + 1 : pattern;
    char canon[1024], real[PATH_MAX];
    e->fd = -1;
    snprintf(e->pattern, sizeof e->pattern, "%s", pattern);
    if (!base[0] || strlen(pattern) >= sizeof e->dir || strlen(base) >= sizeof e->base)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "cannot lock '%s': not a file name",
                           pattern);
    snprintf(e->base, sizeof e->base, "%s", base);
    if (!slash)
        snprintf(e->dir, sizeof e->dir, ".");
    else if (slash == pattern)
        snprintf(e->dir, sizeof e->dir, "/");
    else
        snprintf(e->dir, sizeof e->dir, "%.*s", (int)(slash - pattern), pattern);
    nprfx_result r = nprfx_seq_canonical(ctx, base, canon, sizeof canon);
    if (r) return r;
    if (cli_make_dirs(e->dir) || !realpath(e->dir, real))
        return nprfx_error(ctx, NPRFX_ERR_IO, "cannot create directory '%s' for '%s': %s", e->dir,
                           pattern, strerror(errno));
    snprintf(e->path, sizeof e->path, "%s/.%s.nprfx-lock", e->dir, canon);
    snprintf(e->key, sizeof e->key, "%s/.%s.nprfx-lock", real, canon);
    return NPRFX_OK;
}

static int cmp_key(const void *a, const void *b)
{
    return strcmp(((const lock_entry *)a)->key, ((const lock_entry *)b)->key);
}

/* The value of "name=" in the lock file's text, or "?" (buf receives it). */
static const char *field(const char *text, const char *name, char *buf, size_t n)
{
    size_t len = strlen(name);
    for (const char *line = text; *line;) {
        const char *end = strchr(line, '\n');
        size_t ll = end ? (size_t)(end - line) : strlen(line);
        if (ll > len && !strncmp(line, name, len) && line[len] == '=') {
            snprintf(buf, n, "%.*s", (int)(ll - len - 1), line + len + 1);
            return buf;
        }
        line += ll + (end != NULL);
    }
    return "?";
}

/* "pid 12 on host h, graph g.json, since T" from the lock file another run holds. The holder
 * writes it just after locking, so an empty file is given a moment to fill. */
static void describe_holder(int fd, char *out, size_t n)
{
    char text[8192];
    ssize_t got = 0;
    for (int tries = 0; tries < 50; tries++) {
        got = pread(fd, text, sizeof text - 1, 0);
        if (got > 0 && memchr(text, '\n', (size_t)got)) break;
        struct timespec ts = {0, 10 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
    text[got > 0 ? got : 0] = '\0';
    char pid[64], host[256], graph[4096], since[64];
    snprintf(out, n, "pid %s on host %s, graph %s, since %s", field(text, "pid", pid, sizeof pid),
             field(text, "host", host, sizeof host), field(text, "graph", graph, sizeof graph),
             field(text, "started", since, sizeof since));
}

static void write_holder(int fd, const char *graph_path)
{
    char host[256] = "?", graph[PATH_MAX], started[64] = "?", text[8192];
    if (gethostname(host, sizeof host)) snprintf(host, sizeof host, "?");
    host[sizeof host - 1] = '\0';
    if (!graph_path)
        snprintf(graph, sizeof graph, "(none)");
    else if (!realpath(graph_path, graph))
        snprintf(graph, sizeof graph, "%s", graph_path);
    time_t now = time(NULL);
    struct tm tm;
    if (gmtime_r(&now, &tm)) strftime(started, sizeof started, "%Y-%m-%dT%H:%M:%SZ", &tm);
    int len = snprintf(text, sizeof text, "pid=%ld\nhost=%s\ngraph=%s\nstarted=%s\n",
                       (long)getpid(), host, graph, started);
    /* Only a description for other runs' messages (the lock is what excludes them), so a failed
     * write is not an error. */
    ssize_t put = ftruncate(fd, 0) == 0 ? pwrite(fd, text, (size_t)len, 0) : -1;
    (void)put;
}

/* Lock e: on return e->fd holds the lock on the file now at e->path. The inode check matters
 * because a releasing run unlinks its lock file: a run that opened the old file and got its
 * lock after the release holds a lock nobody else can see, so it opens the path again. */
static nprfx_result acquire(nprfx_context *ctx, lock_entry *e, const char *graph_path, int wait,
                            int shared, cli_output_lock_notice notice, void *user)
{
    int told = 0, transient = 0, how = shared ? LOCK_SH : LOCK_EX;
    for (;;) {
        int fd = open(e->path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd < 0)
            return nprfx_error(ctx, NPRFX_ERR_IO, "cannot lock '%s': cannot open '%s': %s",
                               e->pattern, e->path, strerror(errno));
        int rc = flock(fd, how | LOCK_NB);
        if (rc && errno == EWOULDBLOCK && shared && transient < 100) {
            /* The last shared holder makes its lock exclusive for a moment to remove the file
             * (cli_output_locks_release): try again before calling it another run's. */
            close(fd);
            transient++;
            struct timespec ts = {0, 10 * 1000 * 1000};
            nanosleep(&ts, NULL);
            continue;
        }
        if (rc && errno == EWOULDBLOCK) {
            char who[8192], msg[16384];
            describe_holder(fd, who, sizeof who);
            if (!wait) {
                close(fd);
                return nprfx_error(ctx, NPRFX_ERR_IO,
                                   "'%s' is being written by another run (%s; lock file '%s'); "
                                   "run with --wait to wait for it",
                                   e->pattern, who, e->path);
            }
            if (notice && !told) {
                snprintf(msg, sizeof msg, "waiting for another run writing '%s' (%s)", e->pattern,
                         who);
                notice(user, msg);
                told = 1;
            }
            while ((rc = flock(fd, how)) && errno == EINTR)
                ;
        }
        if (rc) {
            int err = errno;
            close(fd);
            return nprfx_error(ctx, NPRFX_ERR_IO,
                               "cannot lock '%s' (lock file '%s'): %s; the file system may not "
                               "support locks",
                               e->pattern, e->path, strerror(err));
        }
        struct stat held, now;
        if (fstat(fd, &held) == 0 && stat(e->path, &now) == 0 && held.st_dev == now.st_dev &&
            held.st_ino == now.st_ino) {
            e->fd = fd;
            write_holder(fd, graph_path);
            return NPRFX_OK;
        }
        close(fd); /* released and removed meanwhile: lock the file now at the path */
    }
}

/* Whether name is a temporary file io_write.cpp's temp_path_for makes for some frame of pattern
 * base: "." + stem + ".tmp-" + pid + "-" + counter + extension, where stem and extension are
 * the frame file's as std::filesystem splits them (extension from the last '.', none when the
 * only '.' leads the name). */
static int is_temp_of(const char *base, const char *name)
{
    if (name[0] != '.') return 0;
    for (const char *t = strstr(name + 1, ".tmp-"); t; t = strstr(t + 1, ".tmp-")) {
        const char *p = t + 5, *ext;
        if (*p < '0' || *p > '9') continue;
        while (*p >= '0' && *p <= '9')
            p++;
        if (*p++ != '-' || *p < '0' || *p > '9') continue;
        while (*p >= '0' && *p <= '9')
            p++;
        ext = p;
        if (*ext && (*ext != '.' || strchr(ext + 1, '.'))) continue;
        char target[4096];
        size_t stem = (size_t)(t - (name + 1));
        if (stem + strlen(ext) + 1 > sizeof target || stem == 0) continue;
        snprintf(target, sizeof target, "%.*s%s", (int)stem, name + 1, ext);
        const char *dot = strrchr(target, '.');
        int has_ext = dot && dot != target && strcmp(target, "..");
        /* the split of target must give back this stem and extension */
        if (*ext ? dot != target + stem : has_ext) continue;
        if (nprfx_seq_match(base, target, NULL)) return 1;
    }
    return 0;
}

/* Remove what a killed run left of e's sequence (only its temporary names, only plain files):
 * while the lock is held no other run writes them. */
static void remove_stale_temps(const lock_entry *e, cli_output_lock_notice notice, void *user)
{
    DIR *d = opendir(e->dir);
    if (!d) return;
    int removed = 0;
    struct dirent *de;
    while ((de = readdir(d))) {
        char path[8192];
        struct stat st;
        if (!is_temp_of(e->base, de->d_name)) continue;
        snprintf(path, sizeof path, "%s/%s", e->dir, de->d_name);
        if (lstat(path, &st) == 0 && S_ISREG(st.st_mode) && unlink(path) == 0) removed++;
    }
    closedir(d);
    if (removed && notice) {
        char msg[8192];
        snprintf(msg, sizeof msg, "removed %d temporary file%s of '%s' left by an interrupted run",
                 removed, removed == 1 ? "" : "s", e->pattern);
        notice(user, msg);
    }
}

static nprfx_result take(nprfx_context *ctx, const char *const *patterns, int count,
                         const char *graph_path, int wait, int shared,
                         cli_output_lock_notice notice, void *user, cli_output_locks **out)
{
    *out = NULL;
    cli_output_locks *l = calloc(1, sizeof *l);
    lock_entry *es = calloc((size_t)(count > 0 ? count : 1), sizeof *es);
    if (!l || !es) {
        free(l);
        free(es);
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory for output locks");
    }
    l->entries = es;
    l->shared = shared;
    nprfx_result r = NPRFX_OK;
    for (int i = 0; !r && i < count; i++)
        r = entry_init(ctx, patterns[i], &es[i]);
    if (!r) {
        /* One global order: two runs each waiting for the other's lock cannot happen. */
        qsort(es, (size_t)count, sizeof *es, cmp_key);
        for (int i = 0; i < count; i++)
            if (!l->count || strcmp(es[l->count - 1].key, es[i].key)) es[l->count++] = es[i];
    }
    for (int i = 0; !r && i < l->count; i++) {
        r = acquire(ctx, &es[i], graph_path, wait, shared, notice, user);
        if (r) {
            l->count = i; /* release the ones taken */
            cli_output_locks_release(l);
            return r;
        }
    }
    if (r) {
        l->count = 0;
        cli_output_locks_release(l);
        return r;
    }
    for (int i = 0; !shared && i < l->count; i++)
        remove_stale_temps(&es[i], notice, user);
    *out = l;
    return NPRFX_OK;
}

nprfx_result cli_output_locks_take(nprfx_context *ctx, const char *const *patterns, int count,
                                   const char *graph_path, int wait, cli_output_lock_notice notice,
                                   void *user, cli_output_locks **out)
{
    return take(ctx, patterns, count, graph_path, wait, 0, notice, user, out);
}

nprfx_result cli_output_locks_take_shared(nprfx_context *ctx, const char *const *patterns,
                                          int count, const char *graph_path, int wait,
                                          cli_output_lock_notice notice, void *user,
                                          cli_output_locks **out)
{
    return take(ctx, patterns, count, graph_path, wait, 1, notice, user, out);
}

void cli_output_locks_release(cli_output_locks *l)
{
    if (!l) return;
    for (int i = l->count - 1; i >= 0; i--) {
        /* Unlinked while still held, so no run can lock this file after it is released (the
         * inode check in acquire sends a run that opened it to the new one). A shared holder
         * unlinks only when it can make its lock exclusive, i.e. when it is the last: unlinking
         * under other holders would let an exclusive run lock a new file beside them. */
        if (!l->shared || flock(l->entries[i].fd, LOCK_EX | LOCK_NB) == 0)
            unlink(l->entries[i].path);
        close(l->entries[i].fd);
    }
    free(l->entries);
    free(l);
}
