/* nprfx info --aovs — a plate seen through the graph engine. Every answer comes from the engine
 * settling a small graph on the file (nprfx_graph_settle): the profile, the channels an input
 * naming each canonical AOV gets, the fallbacks and decodings it announces, and for the sample
 * style graphs whether they settle. Nothing here knows a renderer's names. */
#define _DEFAULT_SOURCE /* realpath */
#include <dirent.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "info_aovs.h"
#include "nprfx/aov.h"
#include "nprfx/graph.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "util/cli_util.h"

/* The notices of one settling, joined. */
typedef struct heard {
    char text[4096];
} heard;

static void hear(void *user, const char *message)
{
    heard *h = user;
    size_t n = strlen(h->text);
    snprintf(h->text + n, sizeof h->text - n, "%s%s", n ? "\n" : "", message);
}

/* Load json (graph text, or a file when path), point its plate at file, settle it at its first
 * frame. The graph stays for the caller to ask (NULL when it did not load); *err gets the
 * message when settling failed. */
static nprfx_graph *settle(const char *json, const char *path, const char *file, heard *h,
                           char *err, size_t errn)
{
    nprfx_context *ctx = NULL;
    nprfx_graph *g = NULL;
    err[0] = 0;
    if (nprfx_context_create(NULL, &ctx)) return NULL;
    nprfx_graph_options opt;
    memset(&opt, 0, sizeof opt);
    opt.size = sizeof opt;
    opt.io = nprfx_io_oiio();
    opt.notice = hear;
    opt.notice_user = h;
    nprfx_result r =
        path ? nprfx_graph_load(ctx, path, &opt, &g) : nprfx_graph_parse(ctx, json, ".", &opt, &g);
    /* a style reading a synthetic plate has none to point at the file */
    nprfx_graph_node_info ni;
    memset(&ni, 0, sizeof ni);
    ni.size = sizeof ni;
    if (!r && (nprfx_graph_node(g, nprfx_graph_node_index(g, "plate"), &ni) ||
               ni.kind != NPRFX_GRAPH_READ)) {
        snprintf(err, errn, "its plate is not a read node");
        nprfx_context_destroy(ctx);
        return g;
    }
    char set[4200], abs[PATH_MAX];
    snprintf(set, sizeof set, "plate.path=%s", realpath(file, abs) ? abs : file);
    if (!r) r = nprfx_graph_set(g, set);
    int first = 1, last = 1;
    if (!r && nprfx_graph_shot(g, &first, &last)) first = 1;
    if (!r) r = nprfx_graph_settle(g, first);
    if (r && nprfx_context_last_error(ctx, err, errn) == NPRFX_OK && !err[0])
        snprintf(err, errn, "error %d", (int)r);
    nprfx_context_destroy(ctx);
    return g;
}

/* The last line of a notice that mentions aov ("... has no rest: uv stands in ..."). */
static const char *about(const heard *h, const char *what, char *buf, size_t n)
{
    const char *p = strstr(h->text, what);
    if (!p) return NULL;
    const char *start = p;
    while (start > h->text && start[-1] != '\n')
        start--;
    const char *end = strchr(p, '\n');
    size_t len = end ? (size_t)(end - start) : strlen(start);
    snprintf(buf, n, "%.*s", (int)(len < n ? len : n - 1), start);
    return buf;
}

static void aov_line(const char *file, const nprfx_file_info *info, int aov)
{
    const char *name = nprfx_aov_name(aov);
    char json[1024];
    snprintf(json, sizeof json,
             "{\"nodes\": {\"plate\": {\"node\": \"read\", \"path\": \"x\", \"vectors\": "
             "\"auto\"}, \"t\": {\"node\": \"time-offset\", \"inputs\": {\"image\": "
             "\"plate:%s\"}}, \"w\": {\"node\": \"write\", \"inputs\": {\"image\": \"t\"}, "
             "\"path\": \"x.exr\"}}}",
             name);
    heard h = {{0}};
    char err[2048], buf[1024], what[64];
    nprfx_graph *g = settle(json, NULL, file, &h, err, sizeof err);
    printf("  %-14s", name);
    if (!g || err[0]) {
        const char *looks = strstr(err, "looks for ");
        if (looks && !strncmp(looks, "looks for no fixed channel name", 31))
            printf("missing: the profile has no fixed name for it\n");
        else
            printf("missing%s%.*s\n", looks ? ": the profile " : "",
                   looks ? (int)strcspn(looks, ";") : 0, looks ? looks : "");
        nprfx_graph_free(g);
        return;
    }
    snprintf(what, sizeof what, "has no %s", name);
    if (aov == NPRFX_AOV_MOTION_PREV || aov == NPRFX_AOV_MOTION_NEXT)
        snprintf(what, sizeof what, "has no motion vectors");
    const char *fallback = about(&h, what, buf, sizeof buf);
    if (fallback) { /* what stands in: the words after "has no AOV: " */
        const char *says = strstr(strstr(fallback, what), ": ");
        if (says) fallback = says + 2;
    }
    int t = nprfx_graph_node_index(g, "t"), plate = nprfx_graph_node_index(g, "plate");
    nprfx_graph_node_info ni;
    memset(&ni, 0, sizeof ni);
    ni.size = sizeof ni;
    if (fallback && strstr(fallback, "optical flow")) {
        printf("optical flow on the beauty (no vectors)\n");
    } else if (!nprfx_graph_node(g, t, &ni) && ni.inputs[0].src == plate) {
        /* the plate's channels as the read delivers them, then the channels the input takes */
        const char *names[1100];
        int nc = info->nchannels < 1024 ? info->nchannels : 1024, idx[256], count = 0;
        for (int c = 0; c < nc; c++)
            names[c] = info->names[c];
        nc += nprfx_graph_read_extras(g, plate, names + nc, 64);
        if (!nprfx_graph_input_channels(g, t, 0, names, nc, idx, &count))
            for (int c = 0; c < count; c++)
                printf("%s%s", c ? " " : "", names[idx[c]]);
        if (fallback) printf("  (%s)", fallback);
        /* what the read decodes for it (Cryptomatte ids, a single motion vector) */
        for (const char *p = h.text; (p = strstr(p, "note: ")); p++) {
            const char *say = strstr(p, "): ");
            if (say && (!strchr(p, '\n') || say < strchr(p, '\n')))
                printf("  (%.*s)", (int)strcspn(say + 3, "\n"), say + 3);
        }
        printf("\n");
    } else {
        printf("left out (%s)\n", fallback ? fallback : "");
    }
    nprfx_graph_free(g);
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void styles(const char *file, const char *dir)
{
    char data[4096], path[4200];
    if (!dir) {
        if (!cli_data_dir(data, sizeof data)) {
            printf("styles: no data directory (share/nprfx) with graphs/ to try\n");
            return;
        }
        snprintf(path, sizeof path, "%s/graphs", data);
        dir = path;
    }
    DIR *d = opendir(dir);
    if (!d) {
        printf("styles: cannot open '%s'\n", dir);
        return;
    }
    char *list[256];
    int n = 0;
    for (struct dirent *e; (e = readdir(d)) && n < 256;) {
        size_t len = strlen(e->d_name);
        if (len > 5 && !strcmp(e->d_name + len - 5, ".json")) list[n++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(list, (size_t)n, sizeof *list, by_name);
    printf("styles in %s (plate.path set to this file):\n", dir);
    for (int i = 0; i < n; i++) {
        char graph[PATH_MAX + 300], err[2048];
        snprintf(graph, sizeof graph, "%s/%s", dir, list[i]);
        heard h = {{0}};
        nprfx_graph *g = settle(NULL, graph, file, &h, err, sizeof err);
        list[i][strlen(list[i]) - 5] = 0;
        printf("  %-22s", list[i]);
        if (g && !strcmp(err, "its plate is not a read node")) {
            printf("not tried: its plate is synthetic\n");
        } else if (!g || err[0]) {
            const char *m = strstr(err, ".json: ");
            printf("does not run: %s\n", m ? m + 7 : err);
        } else if (!strstr(h.text, "warning:")) {
            printf("runs as is\n");
        } else {
            printf("runs with fallbacks:");
            for (const char *p = h.text; (p = strstr(p, " has no ")); p += 8)
                printf(" %.*s", (int)strcspn(p + 8, ":( "), p + 8);
            printf("\n");
        }
        nprfx_graph_free(g);
        free(list[i]);
    }
}

int cli_info_aovs(nprfx_context *ctx, const char *file, const char *styles_dir)
{
    nprfx_file_info info;
    memset(&info, 0, sizeof info);
    if (nprfx_io_info(ctx, file, &info)) return 4;
    int profile = nprfx_aov_detect((const char *const *)info.names, info.nchannels,
                                   (const char *const *)info.attr_names,
                                   (const char *const *)info.attr_values, info.nattributes);
    printf("%s: %s profile (detected; a read's \"aovs\" or run --aovs overrides it)\n", file,
           nprfx_aov_profile_name(profile));
    for (int aov = 0; aov < NPRFX_AOV_COUNT; aov++)
        aov_line(file, &info, aov);
    nprfx_file_info_free(&info);
    styles(file, styles_dir);
    return 0;
}
