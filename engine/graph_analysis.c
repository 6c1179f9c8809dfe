/* nprfx graph engine — shot statistics measured once (docs/design.md §1 "Shot statistics").
 *
 * A node that measures over the whole shot (tone's range) reads every frame of the shot before
 * its first render. A farm renders a shot in chunks, each a new process, so each chunk read the
 * whole shot again. `nprfx analyze` renders every such node once and stores what its state
 * measured (desc->state_save's text) in a small JSON sidecar; a run loads it and seeds the nodes'
 * states with it, so a chunk reads only its own frames.
 *
 * A seeded result is the measured one, bit for bit: the state checks the fingerprint of every
 * frame it renders and measures the shot again when it differs, and the sidecar records the shot
 * and each plate file's size and modification time over the shot, so a sidecar made for other
 * plates or another shot seeds nothing. Both give the caller a notice naming what changed.
 *
 * The file:
 *   {"nprfx_analysis": 1, "shot": [FIRST, LAST],
 *    "plates": [{"node": NAME, "path": PATTERN, "files": N, "fingerprint": HEX}, ...],
 *    "nodes": {NAME: {"node": TYPE, "measured": [LINE, ...]}, ...}} */
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "engine_util.h"
#include "graph_model.h"
#include "graph_names.h"
#include "json.h"
#include "nprfx/graph.h"
#include "nprfx/rng.h"
#include "nprfx/seq.h"

#define ANALYSIS_VERSION 1

/* What the files of `pattern` over the shot are: each frame's file's size and modification time
 * (a missing one counts as missing), hashed; *files gets how many exist. No pixel is read. */
static uint64_t plates_fingerprint(const nprfx_graph *g, const char *pattern, int *files)
{
    uint64_t h = NPRFX_FNV_INIT;
    int seq = nprfx_seq_has_pattern(pattern);
    int first = seq ? g->first_frame : 0, last = seq ? g->last_frame : 0;
    *files = 0;
    for (long long f = first; f <= last; f++) {
        char path[8192];
        if (seq) {
            if (nprfx_seq_expand(NULL, pattern, (int)f, path, sizeof path)) continue;
        } else {
            snprintf(path, sizeof path, "%s", pattern);
        }
        struct stat st;
        long long v[4] = {f, -1, 0, 0};
        if (!stat(path, &st)) {
            v[1] = (long long)st.st_size;
            v[2] = (long long)st.st_mtim.tv_sec;
            v[3] = (long long)st.st_mtim.tv_nsec;
            ++*files;
        }
        h = nprfx_fnv1a(h, v, sizeof v);
    }
    return h;
}

/* ---- measuring ------------------------------------------------------------------------------ */

static int measures(const gnode *n)
{
    return n->kind == GK_NODE && nprfx_node_measures_shot(n->desc);
}

nprfx_result nprfx_graph_analyze(nprfx_graph *g, int *measured)
{
    int first, last, count = 0;
    if (measured) *measured = 0;
    if (!nprfx_graph_shot(g, &first, &last))
        return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "the graph has no shot (\"frames\") to analyse: give one (--shot)");
    for (int i = 0; i < g->visible; i++) {
        gnode *n = &g->nodes[i];
        if (!measures(n)) continue;
        /* Rendering the node once measures what it measures over the shot: its first frame
         * fetches its inputs at every frame it needs. */
        nprfx_image im;
        nprfx_result r = nprfx_graph_eval(g, n->name, first, &im, NULL);
        if (r) return r;
        char *text = NULL;
        if ((r = nprfx_node_state_save(n->ctx, n->desc, n->state, &text))) return r;
        count += text != NULL;
        free(text);
    }
    if (measured) *measured = count;
    return NPRFX_OK;
}

/* ---- the sidecar ---------------------------------------------------------------------------- */

static void put_string_n(FILE *f, const char *s, size_t len)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; p < (const unsigned char *)s + len;
         p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

static void put_string(FILE *f, const char *s)
{
    put_string_n(f, s, strlen(s));
}

/* A node's text, one JSON string a line. */
static void put_lines(FILE *f, const char *text)
{
    for (int k = 0; *text; k++) {
        const char *nl = strchr(text, '\n');
        size_t len = nl ? (size_t)(nl - text) : strlen(text);
        fputs(k ? ",\n      " : "\n      ", f);
        put_string_n(f, text, len);
        text += len + (nl ? 1 : 0);
    }
}

nprfx_result nprfx_graph_analysis_save(nprfx_graph *g, const char *path)
{
    char **patterns = NULL;
    const char **names = NULL;
    int np = 0;
    nprfx_result r = nprfx_graph_read_patterns(g, &patterns, &names, &np);
    if (r) return r;
    char tmp[8192];
    if (snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid()) >= (int)sizeof tmp) {
        nprfx_graph_output_patterns_free(patterns, np);
        free(names);
        return nprfx_error(g->ctx, NPRFX_ERR_IO, "analysis path '%s' is too long", path);
    }
    FILE *f = fopen(tmp, "w");
    if (!f) {
        nprfx_graph_output_patterns_free(patterns, np);
        free(names);
        return nprfx_error(g->ctx, NPRFX_ERR_IO, "cannot write the analysis '%s'", tmp);
    }
    fprintf(f, "{\n  \"nprfx_analysis\": %d,\n  \"shot\": [%d, %d],\n  \"plates\": [",
            ANALYSIS_VERSION, g->first_frame, g->last_frame);
    for (int i = 0; i < np; i++) {
        int files;
        uint64_t h = plates_fingerprint(g, patterns[i], &files);
        fprintf(f, "%s\n    {\"node\": ", i ? "," : "");
        put_string(f, names[i]);
        fputs(", \"path\": ", f);
        put_string(f, patterns[i]);
        fprintf(f, ", \"files\": %d, \"fingerprint\": \"%016" PRIx64 "\"}", files, h);
    }
    nprfx_graph_output_patterns_free(patterns, np);
    free(names);
    fputs("\n  ],\n  \"nodes\": {", f);
    int k = 0;
    for (int i = 0; i < g->visible && !r; i++) {
        gnode *n = &g->nodes[i];
        char *text = NULL;
        if (!measures(n) || (r = nprfx_node_state_save(n->ctx, n->desc, n->state, &text)) || !text)
            continue;
        fputs(k++ ? ",\n    " : "\n    ", f);
        put_string(f, n->name);
        fputs(": {\"node\": ", f);
        put_string(f, n->desc->id);
        fputs(", \"measured\": [", f);
        put_lines(f, text);
        fputs("\n    ]}", f);
        free(text);
    }
    fputs("\n  }\n}\n", f);
    int bad = ferror(f);
    bad |= fclose(f) != 0;
    if (!r && bad) r = nprfx_error(g->ctx, NPRFX_ERR_IO, "cannot write the analysis '%s'", tmp);
    if (!r && rename(tmp, path))
        r = nprfx_error(g->ctx, NPRFX_ERR_IO, "cannot rename '%s' to '%s'", tmp, path);
    if (r) remove(tmp);
    return r;
}

void nprfx_graph_analysis_path(const nprfx_graph *g, const char *graph_path, char *buf, size_t n)
{
    /* beside the first write's output, named after the graph file: out/main/main.analysis.json */
    char **outs = NULL;
    int count = 0;
    char dir[4096] = ".";
    if (!nprfx_graph_output_patterns(g, &outs, &count) && count > 0) {
        const char *slash = strrchr(outs[0], '/');
        if (slash) snprintf(dir, sizeof dir, "%.*s", (int)(slash - outs[0]), outs[0]);
        if (slash == outs[0]) snprintf(dir, sizeof dir, "/");
    }
    nprfx_graph_output_patterns_free(outs, count);
    const char *base = strrchr(graph_path, '/');
    base = base ? base + 1 : graph_path;
    size_t len = strlen(base);
    if (len > 5 && !strcmp(base + len - 5, ".json")) len -= 5;
    snprintf(buf, n, "%s%s%.*s.analysis.json", dir, strcmp(dir, "/") ? "/" : "", (int)len, base);
}

/* ---- seeding a run -------------------------------------------------------------------------- */

/* The "measured" lines joined into the node's text. */
static char *joined(const internal_json *lines)
{
    size_t n = 1;
    for (const internal_json *l = lines->child; l; l = l->next) {
        if (l->type != INTERNAL_JSON_STRING) return NULL;
        n += strlen(l->string) + 1;
    }
    char *s = malloc(n), *p = s;
    if (!s) return NULL;
    for (const internal_json *l = lines->child; l; l = l->next) {
        size_t m = strlen(l->string);
        memcpy(p, l->string, m);
        p += m;
        *p++ = '\n';
    }
    *p = 0;
    return s;
}

/* Whether the plates the sidecar was measured on are the graph's, unchanged; a notice names the
 * first that is not. */
static int plates_match(nprfx_graph *g, const char *path, const internal_json *plates)
{
    char **patterns = NULL;
    const char **names = NULL;
    int np = 0, ok = 1;
    if (nprfx_graph_read_patterns(g, &patterns, &names, &np)) return 0;
    int listed = plates && plates->type == INTERNAL_JSON_ARRAY ? plates->count : -1;
    if (listed != np) {
        internal_graph_notice(
            g,
            "note: %s was measured on %d plate sequence%s, this graph reads %d: measuring "
            "the shot again",
            path, listed, listed == 1 ? "" : "s", np);
        ok = 0;
    }
    const internal_json *e = ok ? plates->child : NULL;
    for (int i = 0; ok && i < np; i++, e = e->next) {
        const internal_json *node = internal_json_member(e, "node");
        const internal_json *fp = internal_json_member(e, "fingerprint");
        int files;
        char hex[32];
        snprintf(hex, sizeof hex, "%016" PRIx64, plates_fingerprint(g, patterns[i], &files));
        /* the same files may be named otherwise (a relative path from elsewhere): the
         * fingerprint decides */
        if (!node || node->type != INTERNAL_JSON_STRING || strcmp(node->string, names[i])) {
            internal_graph_notice(
                g,
                "note: %s was measured on other plates than read node '%s' reads (%s): "
                "measuring the shot again",
                path, names[i], patterns[i]);
            ok = 0;
        } else if (!fp || fp->type != INTERNAL_JSON_STRING || strcmp(fp->string, hex)) {
            internal_graph_notice(
                g,
                "note: %s: plates %s changed since they were measured (a file's size or "
                "time differs): measuring the shot again",
                path, patterns[i]);
            ok = 0;
        }
    }
    nprfx_graph_output_patterns_free(patterns, np);
    free(names);
    return ok;
}

nprfx_result nprfx_graph_analysis_load(nprfx_graph *g, const char *path, int *seeded)
{
    if (seeded) *seeded = 0;
    /* a long shot's fingerprints are 17 bytes a frame and node: a 100,000-frame shot fits */
    char *text = engine_read_text(g->ctx, path, "analysis", 64L << 20);
    if (!text) return NPRFX_ERR_IO;
    internal_json *root = NULL;
    nprfx_context *fctx = NULL;
    nprfx_result r = nprfx_context_create_scoped(g->ctx, path, &fctx);
    if (!r) r = internal_json_parse(fctx, text, &root);
    nprfx_context_destroy(fctx);
    free(text);
    if (r) return r;
    const internal_json *ver = internal_json_member(root, "nprfx_analysis");
    const internal_json *shot = internal_json_member(root, "shot");
    const internal_json *nodes = internal_json_member(root, "nodes");
    if (!ver || ver->type != INTERNAL_JSON_NUMBER || ver->number != ANALYSIS_VERSION || !shot ||
        shot->type != INTERNAL_JSON_ARRAY || shot->count != 2 ||
        shot->child->type != INTERNAL_JSON_NUMBER ||
        shot->child->next->type != INTERNAL_JSON_NUMBER || !nodes ||
        nodes->type != INTERNAL_JSON_OBJECT) {
        internal_json_free(root);
        return nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                           "'%s' is not an analysis nprfx analyze wrote (version %d: "
                           "\"nprfx_analysis\", \"shot\", \"plates\", \"nodes\")",
                           path, ANALYSIS_VERSION);
    }
    int first = (int)shot->child->number, last = (int)shot->child->next->number;
    int count = 0;
    if (first != g->first_frame || last != g->last_frame) {
        internal_graph_notice(
            g, "note: %s measured the shot %d-%d, this run's shot is %d-%d: measuring it again",
            path, first, last, g->first_frame, g->last_frame);
    } else if (plates_match(g, path, internal_json_member(root, "plates"))) {
        for (const internal_json *m = nodes->child; m && !r; m = m->next) {
            int i = internal_graph_find_node(g, m->key);
            const internal_json *type = internal_json_member(m, "node");
            const internal_json *lines = internal_json_member(m, "measured");
            gnode *n = i >= 0 ? &g->nodes[i] : NULL;
            if (!n || !measures(n) || !type || type->type != INTERNAL_JSON_STRING ||
                strcmp(type->string, n->desc->id)) {
                internal_graph_notice(
                    g, "note: %s measured a node '%s' this graph has not: left alone", path,
                    m->key);
                continue;
            }
            char *t = lines && lines->type == INTERNAL_JSON_ARRAY ? joined(lines) : NULL;
            if (!t) {
                r = nprfx_error(g->ctx, NPRFX_ERR_PARSE,
                                "%s: node '%s': \"measured\" is not an array of lines", path,
                                m->key);
                break;
            }
            r = nprfx_node_state_load(n->ctx, n->desc, &n->state, t);
            free(t);
            /* what the state says of itself now: the text a render that changes nothing
             * leaves unchanged */
            char *canon = NULL;
            if (!r) r = nprfx_node_state_save(n->ctx, n->desc, n->state, &canon);
            if (!r) {
                free(n->seeded);
                n->seeded = canon;
                count++;
            }
        }
    }
    internal_json_free(root);
    if (r) return r;
    free(g->analysis_path);
    g->analysis_path = engine_strdup(path);
    if (seeded) *seeded = count;
    return NPRFX_OK;
}

nprfx_result nprfx_graph_node_measured(nprfx_graph *g, int node, char **text)
{
    *text = NULL;
    if (node < 0 || node >= g->count || !measures(&g->nodes[node]))
        return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "node %d measures nothing over the shot", node);
    gnode *n = &g->nodes[node];
    return nprfx_node_state_save(n->ctx, n->desc, n->state, text);
}

nprfx_result nprfx_graph_node_seed(nprfx_graph *g, int node, const char *text)
{
    if (node < 0 || node >= g->count || !measures(&g->nodes[node]))
        return nprfx_error(g->ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "node %d measures nothing over the shot", node);
    gnode *n = &g->nodes[node];
    nprfx_result r = nprfx_node_state_load(n->ctx, n->desc, &n->state, text);
    /* what the state says of itself: the text a render that changes nothing leaves alone, and
     * which a render that finds its frame otherwise measures again (internal_graph_analysis_check)
     */
    char *canon = NULL;
    if (!r) r = nprfx_node_state_save(n->ctx, n->desc, n->state, &canon);
    if (!r) {
        free(n->seeded);
        n->seeded = canon;
    }
    return r;
}

void internal_graph_analysis_check(nprfx_graph *g, gnode *n, int frame)
{
    if (!n->seeded) return;
    char *now = NULL;
    if (nprfx_node_state_save(n->ctx, n->desc, n->state, &now) || !now || strcmp(now, n->seeded)) {
        internal_graph_notice(
            g,
            "note: node '%s': frame %d differs from what %s measured: the shot was "
            "measured again",
            n->name, frame, g->analysis_path ? g->analysis_path : "the analysis");
        free(n->seeded);
        n->seeded = NULL;
        g->analysis_stale++;
    }
    free(now);
}

int nprfx_graph_analysis_stale(const nprfx_graph *g)
{
    return g->analysis_stale;
}

int nprfx_graph_measuring_nodes(const nprfx_graph *g)
{
    int n = 0;
    for (int i = 0; g && i < g->visible; i++)
        n += g->nodes[i].kind == GK_NODE && nprfx_node_measures_shot(g->nodes[i].desc);
    return n;
}
