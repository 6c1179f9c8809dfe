/* nprfx farm — the Slurm engine (farm_slurm.c): job files that render a shot in chunks. */
#ifndef NPRFX_CLI_FARM_SLURM_H
#define NPRFX_CLI_FARM_SLURM_H

#include "farm_args.h"

typedef struct farm_slurm {
    const char *name, *partition, *time, *mem;
    int cpus, retries;
} farm_slurm;
/* Write DIR/render.sbatch (the array job, one task a chunk), DIR/check.sbatch (nprfx farm check)
 * and DIR/submit.sh (both, the check after the array); DIR/logs/ receives the logs. 0 or 1. */
int farm_slurm_emit(const farm_job *job, const farm_slurm *opt, const char *dir);
/* Submit what farm_slurm_emit wrote to dir through sbatch and print the job ids. 0 or 1. */
int farm_slurm_submit(const farm_job *job, const char *dir);

#endif
