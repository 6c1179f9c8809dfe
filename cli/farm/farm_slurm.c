/* nprfx farm's Slurm engine: an array job with one task a chunk, and a check job that runs once
 * every task has ended (failed ones too, so that it can name what they left missing). */
#define _DEFAULT_SOURCE /* realpath */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "farm_args.h"
#include "farm_slurm.h"

/* #SBATCH lines are split by Slurm's own reader, not a shell: a path there must be one word. */
static int sbatch_word(const char *what, const char *s)
{
    if (!strpbrk(s, " \t\n\"'\\")) return 1;
    fprintf(stderr,
            "nprfx farm: %s '%s' holds a space, quote or backslash, which #SBATCH lines cannot "
            "carry; use another directory\n",
            what, s);
    return 0;
}

/* s with '%' doubled: Slurm expands %-patterns in --output file names. */
static void put_sbatch_path(FILE *f, const char *s)
{
    for (; *s; s++) {
        if (*s == '%') fputc('%', f);
        fputc(*s, f);
    }
}

static void put_common(FILE *f, const farm_job *job, const farm_slurm *opt, const char *name,
                       int cpus)
{
    fprintf(f, "#!/bin/bash\n#SBATCH --job-name=%s\n#SBATCH --cpus-per-task=%d\n", name, cpus);
    if (opt->partition) fprintf(f, "#SBATCH --partition=%s\n", opt->partition);
    if (opt->time) fprintf(f, "#SBATCH --time=%s\n", opt->time);
    if (opt->mem) fprintf(f, "#SBATCH --mem=%s\n", opt->mem);
    fputs("#SBATCH --chdir=", f);
    put_sbatch_path(f, job->workdir);
    fputc('\n', f);
}

static int write_render(const char *path, const farm_job *job, const farm_slurm *opt,
                        const char *name, const char *logs)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    put_common(f, job, opt, name, opt->cpus);
    fprintf(f, "#SBATCH --array=0-%d\n#SBATCH --output=", job->nchunks - 1);
    put_sbatch_path(f, logs);
    /* append: a requeued or retried task adds to its chunk's log instead of replacing it */
    fputs("/chunk_%a.log\n#SBATCH --open-mode=append\n#SBATCH --requeue\n", f);
    fprintf(f,
            "# Written by nprfx farm: %s, frames %s (%d) in %d chunks of %d, one array task a\n"
            "# chunk. Each chunk renders its frames as one sequential run would (temporal nodes\n"
            "# warm up from the shot's start or their window), and writes every file under a\n"
            "# temporary name renamed into place, so a preempted task leaves no partial frame.\n"
            "# By hand, without Slurm: SLURM_ARRAY_TASK_ID=0 bash %s\n"
            "set -u\nchunks=(",
            job->graph, job->frames, job->nframes, job->nchunks, job->chunk, path);
    for (int c = 0; c < job->nchunks; c++) {
        fputs(c ? " " : "", f);
        farm_put_quoted(f, job->chunks[c]);
    }
    fputs(")\n"
          "task=${SLURM_ARRAY_TASK_ID:?not a Slurm array task: set SLURM_ARRAY_TASK_ID}\n"
          "frames=${chunks[$task]:?no chunk $task}\n"
          "cd ",
          f);
    farm_put_quoted(f, job->workdir);
    fputs(" || exit 1\n"
          "echo \"nprfx farm: chunk $task (frames $frames) on $(hostname), restart"
          " ${SLURM_RESTART_COUNT:-0}, $(date -u +%Y-%m-%dT%H:%M:%SZ)\"\n",
          f);
    fprintf(f, "tries=%d\nwhile :; do\n    ", opt->retries);
    farm_put_run(f, job);
    fputs(" --frames \"$frames\" --threads \"${SLURM_CPUS_PER_TASK:-1}\" --shared-lock && exit 0\n"
          "    status=$?\n"
          "    [ \"$tries\" -gt 0 ] || exit \"$status\"\n"
          "    tries=$((tries - 1))\n"
          "    echo \"nprfx farm: chunk $task failed (status $status); trying again\"\n"
          "done\n",
          f);
    return fclose(f) ? -1 : 0;
}

static int write_analyze(const char *path, const farm_job *job, const farm_slurm *opt,
                         const char *name, const char *logs)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    put_common(f, job, opt, name, opt->cpus);
    fputs("#SBATCH --output=", f);
    put_sbatch_path(f, logs);
    fputs("/analyze.log\n#SBATCH --open-mode=append\n#SBATCH --requeue\n", f);
    fprintf(f,
            "# Written by nprfx farm: measures the shot statistics of %s (tone ranges) once,\n"
            "# over frames %s, into the file every chunk of render.sbatch reads (submit.sh:\n"
            "# the chunks start after it succeeded, --dependency=afterok), so no chunk reads\n"
            "# the rest of the shot. By hand, without Slurm: bash %s\n"
            "cd ",
            job->graph, job->shot[0] ? job->shot : "of the graph", path);
    farm_put_quoted(f, job->workdir);
    fputs(" || exit 1\nexec ", f);
    farm_put_analyze(f, job);
    fputs(" --threads \"${SLURM_CPUS_PER_TASK:-1}\"\n", f);
    return fclose(f) ? -1 : 0;
}

static int write_check(const char *path, const farm_job *job, const farm_slurm *opt,
                       const char *name, const char *logs)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    farm_slurm one = *opt;
    put_common(f, job, &one, name, 1);
    fputs("#SBATCH --output=", f);
    put_sbatch_path(f, logs);
    fputs("/check.log\n", f);
    fprintf(f, "# Written by nprfx farm: runs after every task of render.sbatch has ended, failed\n"
               "# ones too (submit.sh: --dependency=afterany), and lists each missing or damaged\n"
               "# frame with the command that renders it again; it fails when there is one.\n"
               "cd ");
    farm_put_quoted(f, job->workdir);
    fputs(" || exit 1\nexec ", f);
    farm_put_quoted(f, job->nprfx);
    fputs(" farm check ", f);
    farm_put_quoted(f, job->graph);
    fputs(" --frames ", f);
    farm_put_quoted(f, job->frames);
    farm_put_graph_args(f, job);
    fputc('\n', f);
    return fclose(f) ? -1 : 0;
}

static int write_submit(const char *path, const char *analyze, const char *render,
                        const char *check, const farm_job *job, const char *logs)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fputs("#!/bin/sh\n"
          "# Written by nprfx farm: submits the analysis job when the graph measures its shot,\n"
          "# the render array to start once it succeeded, then the check job to run after all\n"
          "# of the array's tasks, whatever their outcome.\n"
          "set -eu\n",
          f);
    if (analyze) {
        fputs("analyze=$(sbatch --parsable ", f);
        farm_put_quoted(f, analyze);
        fputs(")\nanalyze=${analyze%%;*}\nrender=$(sbatch --parsable "
              "--dependency=afterok:\"$analyze\" ",
              f);
    } else
        fputs("render=$(sbatch --parsable ", f);
    farm_put_quoted(f, render);
    fputs(")\nrender=${render%%;*}\n"
          "check=$(sbatch --parsable --dependency=afterany:\"$render\" ",
          f);
    farm_put_quoted(f, check);
    fputs(")\ncheck=${check%%;*}\n", f);
    if (analyze) fputs("echo \"analysis job: $analyze\"\n", f);
    fprintf(f,
            "echo \"render job: $render (%d chunks)\"\necho \"check job: $check\"\n"
            "echo \"logs: %s\"\n",
            job->nchunks, logs);
    if (fclose(f)) return -1;
    return chmod(path, 0755);
}

int farm_slurm_emit(const farm_job *job, const farm_slurm *opt, const char *dir)
{
    char real[PATH_MAX], logs[PATH_MAX + 8], render[PATH_MAX + 16], check[PATH_MAX + 16],
        submit[PATH_MAX + 16], analyze[PATH_MAX + 16], name[256];
    char logs_given[4200];
    snprintf(logs_given, sizeof logs_given, "%s/logs", dir);
    if (cli_make_dirs(logs_given) || !realpath(dir, real)) {
        fprintf(stderr, "nprfx farm: cannot create '%s': %s\n", logs_given, strerror(errno));
        return 1;
    }
    snprintf(logs, sizeof logs, "%s/logs", real);
    if (!sbatch_word("the log directory", logs) || !sbatch_word("the directory", job->workdir))
        return 1;
    snprintf(render, sizeof render, "%s/render.sbatch", real);
    snprintf(check, sizeof check, "%s/check.sbatch", real);
    snprintf(submit, sizeof submit, "%s/submit.sh", real);
    snprintf(analyze, sizeof analyze, "%s/analyze.sbatch", real);
    if (opt->name)
        snprintf(name, sizeof name, "%s", opt->name);
    else {
        /* nprfx-STEM from the graph's file name, in characters a job name takes as they are */
        const char *base = strrchr(job->graph, '/');
        base = base ? base + 1 : job->graph;
        size_t n = strcspn(base, ".");
        snprintf(name, sizeof name, "nprfx-%.*s", (int)(n < 200 ? n : 200), base);
        for (char *p = name; *p; p++)
            if (!strchr("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.", *p))
                *p = '_';
    }
    if (!sbatch_word("--name", name)) return 1;
    char check_name[300], analyze_name[300];
    snprintf(check_name, sizeof check_name, "%s-check", name);
    snprintf(analyze_name, sizeof analyze_name, "%s-analyze", name);
    int analysis = job->analysis[0] != 0;
    if (!analysis) remove(analyze); /* a previous farm of another graph may have left one */
    if ((analysis && write_analyze(analyze, job, opt, analyze_name, logs)) ||
        write_render(render, job, opt, name, logs) ||
        write_check(check, job, opt, check_name, logs) ||
        write_submit(submit, analysis ? analyze : NULL, render, check, job, logs)) {
        fprintf(stderr, "nprfx farm: cannot write the job files in '%s': %s\n", real,
                strerror(errno));
        return 1;
    }
    if (analysis) printf("wrote %s (the shot statistics, into %s)\n", analyze, job->analysis);
    printf("wrote %s (%d chunk%s of %d frames), %s, %s; logs in %s\n", render, job->nchunks,
           job->nchunks == 1 ? "" : "s", job->chunk, check, submit, logs);
    return 0;
}

/* Run `sbatch --parsable ARGS` and put the job id it prints into id; 0 or -1. */
static int sbatch(const char *kind, const char *dependency, const char *script, char *id, size_t n)
{
    char *cmd = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&cmd, &len);
    if (!f) return -1;
    fputs("sbatch --parsable ", f);
    if (dependency) fprintf(f, "--dependency=%s:%s ", kind, dependency);
    farm_put_quoted(f, script);
    fclose(f);
    FILE *p = popen(cmd, "r");
    free(cmd);
    if (!p) return -1;
    char line[64] = "";
    if (!fgets(line, sizeof line, p)) line[0] = '\0';
    int rc = pclose(p);
    line[strcspn(line, ";\n")] = '\0'; /* --parsable: "ID" or "ID;CLUSTER" */
    if (rc != 0 || !line[0] || strspn(line, "0123456789") != strlen(line)) return -1;
    snprintf(id, n, "%s", line);
    return 0;
}

int farm_slurm_submit(const farm_job *job, const char *dir)
{
    char real[PATH_MAX], render[PATH_MAX + 16], check[PATH_MAX + 16], analyze[PATH_MAX + 16];
    char aid[64] = "", rid[64], cid[64];
    if (!realpath(dir, real)) {
        fprintf(stderr, "nprfx farm: '%s': %s\n", dir, strerror(errno));
        return 1;
    }
    snprintf(render, sizeof render, "%s/render.sbatch", real);
    snprintf(check, sizeof check, "%s/check.sbatch", real);
    snprintf(analyze, sizeof analyze, "%s/analyze.sbatch", real);
    if (job->analysis[0] && sbatch(NULL, NULL, analyze, aid, sizeof aid)) {
        fprintf(stderr, "nprfx farm: sbatch refused '%s' (its message is above)\n", analyze);
        return 1;
    }
    if (sbatch("afterok", aid[0] ? aid : NULL, render, rid, sizeof rid)) {
        fprintf(stderr, "nprfx farm: sbatch refused '%s' (its message is above)%s%s%s\n", render,
                aid[0] ? "; the analysis job " : "", aid, aid[0] ? " is queued: 'scancel' it" : "");
        return 1;
    }
    if (sbatch("afterany", rid, check, cid, sizeof cid)) {
        fprintf(stderr,
                "nprfx farm: sbatch refused '%s' (its message is above); the render job %s is "
                "queued: cancel it with 'scancel %s' or check by hand with 'nprfx farm check'\n",
                check, rid, rid);
        return 1;
    }
    if (aid[0]) printf("analysis job: %s\n", aid);
    printf("render job: %s (%d chunks)\ncheck job: %s\nlogs: %s/logs\n", rid, job->nchunks, cid,
           real);
    return 0;
}
