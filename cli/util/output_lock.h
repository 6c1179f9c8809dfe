/* nprfx CLI — one run at a time per output sequence.
 *
 * Before its first frame a run takes an exclusive advisory lock (flock) on a lock file beside
 * each sequence it writes: ".<file pattern>.nprfx-lock" in the sequence's folder, the pattern's
 * frame tokens written as '#' runs (nprfx_seq_canonical), so "x.####.exr" and "x.%04d.exr" share
 * one lock. The file holds the holder's pid, host, graph and start time, for the message another
 * run gets. The OS drops the lock when the holder dies, even by kill -9, so a lock is never
 * stale; the next holder then removes the temporary files the dead run left for that sequence
 * (io_write.cpp's temp_path_for names) and nothing else. Locks are taken in the order of their
 * canonical paths, so runs that wait (--wait) for several sequences cannot deadlock.
 *
 * Limitation: flock is advisory and only as good as the file system's lock support. On Linux NFS
 * it maps to the NFS lock manager, so runs on different hosts exclude each other only when the
 * server supports locks (NFSv4, or v3 with lockd) and the mount does not say "nolock"; there, and
 * on file systems without locks, runs on different hosts are not kept apart. */
#ifndef NPRFX_CLI_OUTPUT_LOCK_H
#define NPRFX_CLI_OUTPUT_LOCK_H

#include "nprfx/context.h"

typedef struct cli_output_locks cli_output_locks;

/* Told what the run is doing while taking its locks: that it waits for another run, that it
 * removed a dead run's temporary files (one finished line of text, no newline). */
typedef void (*cli_output_lock_notice)(void *user, const char *message);

/* Lock every pattern ("out/x.####.exr"; repeats and spellings of one sequence are locked once),
 * creating missing folders. graph_path is recorded for other runs to name (may be NULL). wait 0:
 * a sequence another run holds is an error naming that run and the path; wait 1: block until it
 * is free. On error nothing stays locked and *out is NULL. */
nprfx_result cli_output_locks_take(nprfx_context *ctx, const char *const *patterns, int count,
                                   const char *graph_path, int wait, cli_output_lock_notice notice,
                                   void *user, cli_output_locks **out);

/* As cli_output_locks_take, but the locks are shared: runs that lock shared (nprfx farm's
 * chunk tasks, `run --shared-lock`, which write disjoint frames of one sequence) run together,
 * and a run locking exclusively still excludes them all, and they it. A shared holder removes no
 * temporary file, since another holder may be writing it: the next exclusive holder does (the
 * farm's check job, after the last chunk). */
nprfx_result cli_output_locks_take_shared(nprfx_context *ctx, const char *const *patterns,
                                          int count, const char *graph_path, int wait,
                                          cli_output_lock_notice notice, void *user,
                                          cli_output_locks **out);

/* Remove the lock files and release the locks (NULL: nothing). A shared holder removes a lock
 * file only when it is the last holder. */
void cli_output_locks_release(cli_output_locks *locks);

#endif
