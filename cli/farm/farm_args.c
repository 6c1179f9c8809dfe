/* What nprfx farm and nprfx farm check share: the graph loaded as every chunk loads it, checked
 * before anything is submitted, and the chunk command quoted for a shell. */
#define _DEFAULT_SOURCE /* realpath */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "nprfx/io_oiio.h"
#include "farm_args.h"
#include "nprfx/graph.h"
#include "util/cli_util.h"

void farm_job_free(farm_job *job)
{
    for (int i = 0; i < job->nchunks; i++)
        free(job->chunks[i]);
    free(job->chunks);
    free(job->frames);
    job->chunks = NULL;
    job->frames = NULL;
    job->nchunks = 0;
}

void farm_put_quoted(FILE *f, const char *s)
{
    int plain = *s != '\0';
    for (const char *p = s; *p && plain; p++)
        plain = strchr("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=./,:@%",
                       *p) != NULL;
    if (plain) {
        fputs(s, f);
        return;
    }
    /* Inside single quotes only the quote itself needs care: end, escaped quote, reopen. */
    fputc('\'', f);
    for (const char *p = s; *p; p++)
        if (*p == '\'')
            fputs("'\\''", f);
        else
            fputc(*p, f);
    fputc('\'', f);
}

void farm_put_graph_args(FILE *f, const farm_job *job)
{
    if (job->shot[0]) {
        fputs(" --shot ", f);
        farm_put_quoted(f, job->shot);
    }
    for (int i = 0; i < job->nsets; i++) {
        fputs(" --set ", f);
        farm_put_quoted(f, job->sets[i]);
    }
    if (job->output_dir) {
        fputs(" --output-dir ", f);
        farm_put_quoted(f, job->output_dir);
    }
}

static void put_command(FILE *f, const farm_job *job, const char *cmd)
{
    farm_put_quoted(f, job->nprfx);
    fprintf(f, " %s ", cmd);
    farm_put_quoted(f, job->graph);
    farm_put_graph_args(f, job);
    if (job->analysis[0]) {
        fputs(" --analysis ", f);
        farm_put_quoted(f, job->analysis);
    }
}

void farm_put_run(FILE *f, const farm_job *job)
{
    put_command(f, job, "run");
}

void farm_put_analyze(FILE *f, const farm_job *job)
{
    put_command(f, job, "analyze");
}

int farm_take_graph_arg(farm_graph_args *a, const char *arg, const char *next)
{
    if (!strcmp(arg, "--frames") && next)
        a->frames = next;
    else if (!strcmp(arg, "--shot") && next)
        a->shot = next;
    else if (!strcmp(arg, "--output-dir") && next)
        a->output_dir = next;
    else if (!strcmp(arg, "--set") && next && a->nsets < 256)
        a->sets[a->nsets++] = next;
    else if (arg[0] != '-' && !a->graph) {
        a->graph = arg;
        return 1;
    } else
        return 0;
    return 2;
}

char *farm_frames_spec(const int *frames, int count)
{
    /* At most 24 characters a frame ("-2147483648--2147483647,"). */
    char *s = malloc((size_t)count * 24 + 1), *p = s;
    if (!s) return NULL;
    *p = '\0';
    for (int i = 0; i < count;) {
        int j = i;
        while (j + 1 < count && frames[j] != 2147483647 && frames[j + 1] == frames[j] + 1)
            j++;
        p += sprintf(p, "%s%d", p == s ? "" : ",", frames[i]);
        if (j > i) p += sprintf(p, "-%d", frames[j]);
        i = j + 1;
    }
    return s;
}

/* Every read node's file for every frame: the first one missing, with how many frames lack one,
 * so a range the plates do not cover fails here and not in chunk 7 after hours on the farm. */
static int check_reads(nprfx_graph *g, nprfx_context *ctx, const char *cmd,
                       const nprfx_frame_list *fl, const char *spec)
{
    char **paths;
    const char **nodes;
    int n;
    if (nprfx_graph_read_patterns(g, &paths, &nodes, &n)) {
        fprintf(stderr, "nprfx %s: %s\n", cmd, cli_message(ctx));
        return 2;
    }
    int status = 0;
    for (int i = 0; i < n && !status; i++) {
        int missing = 0, first = 0, err = 0;
        char file[4096], first_file[4096] = "";
        int frames = nprfx_seq_has_pattern(paths[i]) ? fl->count : (fl->count > 0);
        for (int k = 0; k < frames; k++) {
            if (nprfx_seq_expand(ctx, paths[i], fl->frames[k], file, sizeof file)) {
                snprintf(file, sizeof file, "%s", paths[i]);
            }
            if (access(file, R_OK) == 0) continue;
            if (!missing++) {
                first = fl->frames[k];
                err = errno;
                snprintf(first_file, sizeof first_file, "%s", file);
            }
        }
        if (missing) {
            fprintf(stderr,
                    "nprfx %s: frames %s: read node '%s' cannot read '%s' (frame %d): %s; %d of "
                    "%d frames lack their file\n",
                    cmd, spec, nodes[i], first_file, first, strerror(err), missing, fl->count);
            status = 2;
        }
    }
    nprfx_graph_output_patterns_free(paths, n);
    free(nodes);
    return status;
}

/* The chunks: `chunk` frames of the list each, in its order. */
static int make_chunks(farm_job *job, const nprfx_frame_list *fl, int chunk)
{
    job->nchunks = (fl->count + chunk - 1) / chunk;
    job->chunks = calloc((size_t)(job->nchunks > 0 ? job->nchunks : 1), sizeof *job->chunks);
    if (!job->chunks) return -1;
    for (int c = 0; c < job->nchunks; c++) {
        int lo = c * chunk, n = fl->count - lo < chunk ? fl->count - lo : chunk;
        if (!(job->chunks[c] = farm_frames_spec(fl->frames + lo, n))) return -1;
    }
    return 0;
}

int farm_prepare(cli_env *env, const char *cmd, const farm_graph_args *a, int chunk,
                 int check_inputs, farm_job *job, nprfx_graph **gout)
{
    nprfx_context *ctx = env->ctx;
    nprfx_graph *g = NULL;
    nprfx_frame_list fl = {NULL, 0};
    int status = 2;
    memset(job, 0, sizeof *job);
    job->sets = a->sets;
    job->nsets = a->nsets;
    job->output_dir = a->output_dir;
    job->chunk = chunk;
    ssize_t len = readlink("/proc/self/exe", job->nprfx, sizeof job->nprfx - 1);
    if (len <= 0) {
        fprintf(stderr, "nprfx %s: cannot find the nprfx executable (/proc/self/exe): %s\n", cmd,
                strerror(errno));
        return 2;
    }
    job->nprfx[len] = '\0';
    if (!realpath(a->graph, job->graph)) {
        fprintf(stderr, "nprfx %s: cannot open graph '%s': %s\n", cmd, a->graph, strerror(errno));
        return 2;
    }
    if (!getcwd(job->workdir, sizeof job->workdir)) {
        fprintf(stderr, "nprfx %s: cannot name the current directory: %s\n", cmd, strerror(errno));
        return 2;
    }
    nprfx_graph_options opt = {sizeof opt, (size_t)64 << 20, 0, a->output_dir, NULL};
    opt.io = nprfx_io_oiio();
    if (nprfx_graph_load(ctx, a->graph, &opt, &g)) {
        fprintf(stderr, "nprfx %s: %s\n", cmd, cli_message(ctx));
        goto done;
    }
    if (!nprfx_graph_write_count(g)) {
        fprintf(stderr, "nprfx %s: %s: the graph has no write node, so it would produce nothing\n",
                cmd, a->graph);
        goto done;
    }
    if (a->shot && nprfx_graph_set_shot(g, a->shot)) goto fail;
    for (int i = 0; i < a->nsets; i++)
        if (nprfx_graph_set(g, a->sets[i])) goto fail;
    int first, last, declared = nprfx_graph_shot(g, &first, &last);
    if (nprfx_graph_frames(g, a->frames, &fl)) goto fail;
    if (fl.count == 0) {
        fprintf(stderr, "nprfx %s: %s: no frames to render\n", cmd, a->graph);
        goto done;
    }
    if (a->shot)
        snprintf(job->shot, sizeof job->shot, "%s", a->shot);
    else if (!declared) {
        first = last = fl.frames[0];
        for (int k = 1; k < fl.count; k++) {
            if (fl.frames[k] < first) first = fl.frames[k];
            if (fl.frames[k] > last) last = fl.frames[k];
        }
        snprintf(job->shot, sizeof job->shot, "%d-%d", first, last);
    }
    /* Shot statistics: the analysis job measures them once, every chunk reads them. */
    job->analysis[0] = 0;
    if (nprfx_graph_measuring_nodes(g)) {
        char path[4096];
        nprfx_graph_analysis_path(g, job->graph, path, sizeof path);
        snprintf(job->analysis, sizeof job->analysis, "%s%s%s", path[0] == '/' ? "" : job->workdir,
                 path[0] == '/' ? "" : "/", path);
    }
    job->nframes = fl.count;
    if (!(job->frames = farm_frames_spec(fl.frames, fl.count)) ||
        (chunk > 0 && make_chunks(job, &fl, chunk))) {
        fprintf(stderr, "nprfx %s: out of memory\n", cmd);
        goto done;
    }
    status = 0;
    if (!check_inputs) goto done;
    /* What `run --check` refuses before the first frame: the memory plan (plate headers). */
    status = 2;
    nprfx_graph_plan_info plan;
    memset(&plan, 0, sizeof plan);
    if (nprfx_graph_plan(g, fl.frames[0], &plan)) goto fail;
    status = check_reads(g, ctx, cmd, &fl, job->frames);
    goto done;
fail:
    fprintf(stderr, "nprfx %s: %s: %s\n", cmd, a->graph, cli_message(ctx));
done:
    nprfx_seq_frames_free(&fl);
    if (status) {
        farm_job_free(job);
        nprfx_graph_free(g);
    } else if (gout)
        *gout = g;
    else
        nprfx_graph_free(g);
    return status;
}
