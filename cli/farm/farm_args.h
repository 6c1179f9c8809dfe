/* nprfx farm — a shot rendered in frame chunks by a render manager.
 *
 * cmd_farm.c checks the request and the graph and splits the frames into chunks; an engine
 * (farm_slurm.c) writes the job files that run `nprfx run GRAPH --frames CHUNK` once per chunk and
 * then `nprfx farm check` (farm_check.c) once all chunks have ended. farm_args.c holds what they
 * share: the graph loaded as every chunk loads it, and the chunk command, quoted for a shell; this
 * header declares them. */
#ifndef NPRFX_CLI_FARM_ARGS_H
#define NPRFX_CLI_FARM_ARGS_H

#include <stdio.h>

#include "nprfx/graph.h"
#include "util/cli_util.h"

/* What every chunk's `nprfx run` gets besides its frames, and the shot as a whole. */
typedef struct farm_job {
    char nprfx[4096];   /* the nprfx executable, absolute */
    char graph[4096];   /* the graph file, absolute */
    char workdir[4096]; /* where write paths are relative to: the directory farm ran in */
    /* --shot for every chunk: the user's, or the frames' range when the graph declares no shot
     * (a chunk would otherwise take its own frames for the shot and start its noise there);
     * "" when the graph's own shot applies. */
    char shot[256];
    /* The shot statistics file (absolute) the analysis job writes and every chunk reads; ""
     * when the graph measures nothing over its shot (no analysis job). */
    char analysis[8200];
    const char *output_dir; /* --output-dir as given (NULL: none) */
    const char *const *sets;
    int nsets;
    char *frames;  /* every frame, as one frame-list spec (malloc'd) */
    char **chunks; /* nchunks frame-list specs (malloc'd) */
    int nchunks, chunk, nframes;
} farm_job;

void farm_job_free(farm_job *job);

/* s quoted for a POSIX shell: as is when it needs no quoting, else in single quotes. */
void farm_put_quoted(FILE *f, const char *s);

/* The graph's arguments every command of the job repeats: --shot, each --set, --output-dir. */
void farm_put_graph_args(FILE *f, const farm_job *job);
/* "'NPRFX' run 'GRAPH' [--shot S] [--set ...] [--output-dir D] [--analysis A]": the chunk
 * command without its frames. */
void farm_put_run(FILE *f, const farm_job *job);
/* "'NPRFX' analyze 'GRAPH' [--shot S] [--set ...] [--output-dir D] --analysis A": the analysis
 * job's command. */
void farm_put_analyze(FILE *f, const farm_job *job);

/* The options farm and farm check share (argv[i], with the next argument): 1 or 2 when taken, 0
 * when not one of them. */
typedef struct farm_graph_args {
    const char *graph, *frames, *shot, *output_dir;
    const char *sets[256];
    int nsets;
} farm_graph_args;
int farm_take_graph_arg(farm_graph_args *a, const char *arg, const char *next);

/* Load the graph as every chunk will (--shot, --set, --frames), fill job's paths, shot and frames
 * (chunks of `chunk` frames; 0: none), and check what a chunk would refuse before its first
 * frame: the graph, the frames against its shot, and with check_inputs the memory plan and every
 * read node's file for every frame. Errors are printed naming the file ("nprfx farm: ..."); returns
 * 0 or 2. On success *g holds the graph (free with nprfx_graph_free) when g is not NULL. */
int farm_prepare(cli_env *env, const char *cmd, const farm_graph_args *a, int chunk,
                 int check_inputs, farm_job *job, nprfx_graph **g);

/* A frame list as one spec: ascending runs as "A-B", joined by ','; malloc'd. */
char *farm_frames_spec(const int *frames, int count);

#endif
