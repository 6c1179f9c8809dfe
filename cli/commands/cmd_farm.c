/* nprfx farm — a shot split into frame chunks for a render manager (Slurm), and the check that
 * every frame arrived (nprfx farm check, farm_check.c). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "commands.h"
#include "farm/farm_args.h"
#include "farm/farm_check.h"
#include "farm/farm_slurm.h"
#include "util/cli_util.h"

static const char *const engines[] = {"slurm"};

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: nprfx farm GRAPH.json [--frames SPEC] --chunk N [--engine slurm]\n"
        "                  (--submit | --emit DIR | --submit --emit DIR) [options]\n"
        "       nprfx farm check GRAPH.json [--frames SPEC] [--shot SPEC] [--set N.P=V ...]\n\n"
        "Renders a shot on a farm: splits its frames into chunks of N and writes (--emit) or\n"
        "submits (--submit, through sbatch) a Slurm array job with one task a chunk, each\n"
        "running 'nprfx run GRAPH --frames CHUNK' with the same --shot, --set and --output-dir,\n"
        "its threads from the allocation (SLURM_CPUS_PER_TASK), its log in DIR/logs/chunk_N.log;\n"
        "then a check job, which runs once every chunk has ended (failed ones too) and lists\n"
        "each missing or damaged frame with the command that renders it again.\n\n"
        "A frame is the same, bit for bit, whatever chunk renders it: a chunk that starts\n"
        "mid-shot warms its temporal nodes up from the shot's start or their window, as one\n"
        "sequential run does. Frames are written under a temporary name and renamed, so a\n"
        "preempted or retried task never leaves a partial frame; chunks lock the sequences\n"
        "shared ('run --shared-lock'), so they run together and a plain run waits for them.\n"
        "Before anything is written, the graph is checked as 'run --check' does, and every\n"
        "read node's file must exist for every frame.\n\n"
        "options:\n"
        "  --frames SPEC      the frames: 1-2000, 1-100x2, 1,5,9-12 (default: the graph's)\n"
        "  --chunk N          frames per chunk (default 10)\n"
        "  --engine E         the render manager: slurm (the only one for now)\n"
        "  --emit DIR         write DIR/render.sbatch, DIR/check.sbatch and DIR/submit.sh (which\n"
        "                     submits both); with --submit, where the files go\n"
        "  --submit           submit through sbatch and print the job ids (files in --emit DIR,\n"
        "                     default ./nprfx-farm.STEM for GRAPH STEM.json)\n"
        "  --shot SPEC        the shot temporal nodes see (run --shot); when the graph has no\n"
        "                     \"frames\", the chunks get the range of --frames as their shot\n"
        "  --set N.P=VALUE    override a param in every chunk (repeatable)\n"
        "  --output-dir DIR   put relative write paths under DIR (run --output-dir)\n"
        "  --cpus N           CPUs per task (--cpus-per-task; default 1): the chunk's threads\n"
        "  --partition P, --time T, --mem M\n"
        "                     passed to sbatch for every task (#SBATCH --partition etc.)\n"
        "  --name NAME        the job name (default nprfx-STEM; the check job adds -check)\n"
        "  --retries N        run a failed chunk again up to N times in its task (default 0);\n"
        "                     tasks are also requeued when their node fails or is preempted\n\n"
        "Write paths are relative to the directory farm runs in (the jobs run there), read\n"
        "paths to the graph file. Exit status: 0 written or submitted, 1 writing or sbatch\n"
        "failed, 2 a bad request or graph (unknown engine, chunk <= 0, frames the graph cannot\n"
        "read, sbatch missing for --submit).\n\n"
        "example:\n"
        "  nprfx farm shot.json --frames 1-2000 --chunk 25 --cpus 8 --submit\n"
        "  nprfx farm shot.json --frames 1-2000 --chunk 25 --emit farm/shot && "
        "farm/shot/submit.sh\n"
        "  nprfx farm check shot.json --frames 1-2000\n");
}

/* Whether an executable called name is on PATH. */
static int on_path(const char *name)
{
    const char *path = getenv("PATH");
    if (!path) return 0;
    while (*path) {
        size_t n = strcspn(path, ":");
        char file[4096];
        snprintf(file, sizeof file, "%.*s/%s", (int)(n ? n : 1), n ? path : ".", name);
        if (access(file, X_OK) == 0) return 1;
        path += n + (path[n] == ':');
    }
    return 0;
}

/* A whole number >= 1 (and < 1e9), or -1. */
static int positive(const char *s)
{
    char *end;
    long v = strtol(s, &end, 10);
    return *s && !*end && v >= 1 && v < 1000000000 ? (int)v : -1;
}

int cli_cmd_farm(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "check")) return farm_check(argc - 1, argv + 1);
    farm_graph_args ga;
    memset(&ga, 0, sizeof ga);
    farm_slurm so = {NULL, NULL, NULL, NULL, 1, 0};
    const char *engine = "slurm", *emit = NULL, *chunk_text = "10";
    int submit = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *next = i + 1 < argc ? argv[i + 1] : NULL;
        int took;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--submit"))
            submit = 1;
        else if ((took = farm_take_graph_arg(&ga, a, next)) > 0)
            i += took - 1;
        else if (!next) {
            fprintf(stderr, "nprfx farm: unexpected argument '%s'\n\n", a);
            usage(stderr);
            return 2;
        } else if (!strcmp(a, "--chunk"))
            chunk_text = argv[++i];
        else if (!strcmp(a, "--engine"))
            engine = argv[++i];
        else if (!strcmp(a, "--emit"))
            emit = argv[++i];
        else if (!strcmp(a, "--partition"))
            so.partition = argv[++i];
        else if (!strcmp(a, "--time"))
            so.time = argv[++i];
        else if (!strcmp(a, "--mem"))
            so.mem = argv[++i];
        else if (!strcmp(a, "--name"))
            so.name = argv[++i];
        else if (!strcmp(a, "--cpus")) {
            if ((so.cpus = positive(argv[++i])) < 0) {
                fprintf(stderr, "nprfx farm: --cpus must be a whole number >= 1, not '%s'\n",
                        argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--retries")) {
            char *end;
            long v = strtol(argv[++i], &end, 10);
            if (!*argv[i] || *end || v < 0 || v > 100) {
                fprintf(stderr, "nprfx farm: --retries must be a whole number 0-100, not '%s'\n",
                        argv[i]);
                return 2;
            }
            so.retries = (int)v;
        } else {
            fprintf(stderr, "nprfx farm: unexpected argument '%s'\n\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!ga.graph) {
        usage(stderr);
        return 2;
    }
    /* The request first, then the graph: every error before anything is written or submitted. */
    size_t e = 0, ne = sizeof engines / sizeof engines[0];
    while (e < ne && strcmp(engines[e], engine))
        e++;
    if (e == ne) {
        fprintf(stderr, "nprfx farm: unknown engine '%s' (known: slurm)\n", engine);
        return 2;
    }
    int chunk = positive(chunk_text);
    if (chunk < 0) {
        fprintf(stderr, "nprfx farm: --chunk must be a whole number of frames >= 1, not '%s'\n",
                chunk_text);
        return 2;
    }
    if (!submit && !emit) {
        fprintf(stderr, "nprfx farm: say --submit (submit through sbatch) or --emit DIR (write "
                        "the job files)\n");
        return 2;
    }
    if (submit && !on_path("sbatch")) {
        fprintf(stderr, "nprfx farm: --submit: sbatch is not on PATH: install Slurm's client "
                        "(Debian: slurm-client) or write the job files with --emit DIR and "
                        "submit them where Slurm is\n");
        return 2;
    }
    cli_env env;
    if (cli_env_init(&env, 1)) return 1;
    farm_job job;
    int status = farm_prepare(&env, "farm", &ga, chunk, 1, &job, NULL);
    cli_env_free(&env);
    if (status) return status;
    if (job.nchunks > 1000)
        fprintf(stderr,
                "nprfx farm: warning: %d chunks: Slurm's default MaxArraySize (1001) refuses "
                "arrays of more than 1001 tasks; a larger --chunk makes fewer\n",
                job.nchunks);
    char dir[4200];
    if (emit)
        snprintf(dir, sizeof dir, "%s", emit);
    else {
        const char *base = strrchr(job.graph, '/');
        base = base ? base + 1 : job.graph;
        snprintf(dir, sizeof dir, "nprfx-farm.%.*s", (int)strcspn(base, "."), base);
    }
    status = farm_slurm_emit(&job, &so, dir);
    if (!status && submit) status = farm_slurm_submit(&job, dir);
    farm_job_free(&job);
    return status;
}
