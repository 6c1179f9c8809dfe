/* nprfx farm check — after a farm render: every frame of every file the graph writes exists and
 * reads back whole; for each one that does not, the file, why, and the command that renders its
 * frame again. The farm's check job runs it once every chunk has ended. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "farm_args.h"
#include "farm_check.h"
#include "nprfx/graph.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "util/output_lock.h"
#include "nprfx/io.h"
#include "util/cli_util.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: nprfx farm check GRAPH.json [--frames SPEC] [--shot SPEC] [--set N.P=V ...]\n"
            "                        [--output-dir DIR] [--quiet]\n\n"
            "Checks that a render of GRAPH over the frames is complete: every file its write\n"
            "nodes write (images, previews, exports) exists for every frame, and every image\n"
            "reads back whole (an EXR's every chunk decodes). Each missing or damaged file is\n"
            "listed with its frame, the reason and the 'nprfx run ... --frames F-F' command that\n"
            "renders it again; then one command for all of them. It also removes the temporary\n"
            "files that preempted or killed chunks left (it locks the sequences as a run does,\n"
            "so it waits for nothing: a chunk still running is reported). Run it where the\n"
            "chunks ran (write paths are relative to it); nprfx farm's check job does so.\n\n"
            "  --frames, --shot, --set, --output-dir   as given to nprfx farm\n"
            "  --quiet                                 print only the problems\n\n"
            "Exit status: 0 every frame complete, 1 a frame missing or damaged, 2 a bad request\n"
            "or graph.\n\n"
            "example: nprfx farm check shot.json --frames 1-2000\n");
}

static void lock_notice(void *user, const char *message)
{
    (void)user;
    fprintf(stderr, "nprfx farm check: %s\n", message);
}

/* Whether path names an image file (read back whole) rather than a text export (exists). */
static int is_image(const char *path)
{
    static const char *const exts[] = {".exr", ".png", ".tif", ".tiff", ".jpg", ".jpeg"};
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash)) return 0;
    for (size_t i = 0; i < sizeof exts / sizeof exts[0]; i++)
        if (!strcasecmp(dot, exts[i])) return 1;
    return 0;
}

/* NULL when the file is complete, else why not (into why). */
static const char *fault(nprfx_context *ctx, const char *path, char *why, size_t n)
{
    struct stat st;
    if (stat(path, &st)) return "missing";
    if (!S_ISREG(st.st_mode)) return "not a plain file";
    if (!is_image(path)) return NULL;
    nprfx_plate pl;
    if (nprfx_io_read(ctx, path, &pl)) {
        snprintf(why, n, "damaged: %s", cli_message(ctx));
        return why;
    }
    nprfx_plate_free(&pl);
    return NULL;
}

static void put_rerender(const farm_job *job, const char *frames)
{
    fputs("cd ", stdout);
    farm_put_quoted(stdout, job->workdir);
    fputs(" && ", stdout);
    farm_put_run(stdout, job);
    fputs(" --frames ", stdout);
    farm_put_quoted(stdout, frames);
    fputc('\n', stdout);
}

int farm_check(int argc, char **argv)
{
    farm_graph_args ga;
    memset(&ga, 0, sizeof ga);
    int quiet = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int took;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--quiet") || !strcmp(a, "-q"))
            quiet = 1;
        else if ((took = farm_take_graph_arg(&ga, a, i + 1 < argc ? argv[i + 1] : NULL)))
            i += took - 1;
        else {
            fprintf(stderr, "nprfx farm check: unexpected argument '%s'\n\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!ga.graph) {
        usage(stderr);
        return 2;
    }
    cli_env env;
    if (cli_env_init(&env, 0)) return 1;
    farm_job job;
    nprfx_graph *g = NULL;
    nprfx_frame_list fl = {NULL, 0};
    char **patterns = NULL;
    int npatterns = 0, status = farm_prepare(&env, "farm check", &ga, 0, 0, &job, &g);
    if (status) goto done;
    if (nprfx_graph_frames(g, ga.frames, &fl) ||
        nprfx_graph_output_patterns(g, &patterns, &npatterns)) {
        fprintf(stderr, "nprfx farm check: %s: %s\n", ga.graph, cli_message(env.ctx));
        status = 2;
        goto done;
    }
    /* The lock a plain run takes: it clears what killed chunks left, and a chunk still running
     * keeps it from doing so (then its frames are likely missing too, and listed below). */
    cli_output_locks *locks = NULL;
    if (cli_output_locks_take(env.ctx, (const char *const *)patterns, npatterns, job.graph, 0,
                              lock_notice, NULL, &locks))
        fprintf(stderr, "nprfx farm check: warning: temporary files not cleared: %s\n",
                cli_message(env.ctx));
    cli_output_locks_release(locks);
    int *bad = malloc((size_t)fl.count * sizeof *bad), nbad = 0, files = 0;
    if (!bad) {
        fprintf(stderr, "nprfx farm check: out of memory\n");
        status = 2;
        goto done;
    }
    for (int k = 0; k < fl.count; k++) {
        int frame_bad = 0;
        for (int p = 0; p < npatterns; p++) {
            char path[4096], why[2048], single[32];
            /* a pattern without a frame token is one file, checked once */
            if (!nprfx_seq_has_pattern(patterns[p]) && k > 0) continue;
            if (nprfx_seq_expand(env.ctx, patterns[p], fl.frames[k], path, sizeof path))
                snprintf(path, sizeof path, "%s", patterns[p]);
            files++;
            const char *f = fault(env.ctx, path, why, sizeof why);
            if (!f) continue;
            printf("frame %d: %s: %s\n  re-render: ", fl.frames[k], path, f);
            snprintf(single, sizeof single, "%d-%d", fl.frames[k], fl.frames[k]);
            put_rerender(&job, single);
            frame_bad = 1;
        }
        if (frame_bad) bad[nbad++] = fl.frames[k];
    }
    if (nbad) {
        char *spec = farm_frames_spec(bad, nbad);
        printf("nprfx farm check: %d of %d frames missing or damaged (%s); to render them all "
               "again:\n  ",
               nbad, fl.count, spec ? spec : "?");
        if (spec) put_rerender(&job, spec);
        free(spec);
        status = 1;
    } else if (!quiet)
        printf("nprfx farm check: %s: all %d frames complete (%d files read back)\n", ga.graph,
               fl.count, files);
    free(bad);
done:
    nprfx_graph_output_patterns_free(patterns, npatterns);
    nprfx_seq_frames_free(&fl);
    nprfx_graph_free(g);
    farm_job_free(&job); /* after farm_prepare, even a failed one: idempotent */
    cli_env_free(&env);
    return status;
}
