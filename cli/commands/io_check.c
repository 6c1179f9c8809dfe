/* nprfx CLI — `nprfx info --io-test damaged LIST`: reads every file named in LIST (one path a
 * line) with nprfx_io_info and nprfx_io_read in one process and prints one verdict a file, for
 * tests/cli/corpus_damaged.sh. One process for a corpus of thousands: the runner's libraries take
 * half a second to load, a file's refusal a millisecond. Peak memory is the process's, which only
 * grows, so a file that made it jump shows it on its own line.
 *
 * Each line: VERDICT \t SECONDS \t PEAK_MIB \t PATH \t DETAIL, where VERDICT is
 *   refused   both calls failed, each message naming the file
 *   read      the read worked and every channel name is printable and unique
 *   unnamed   a call failed with a message that does not name the file
 *   garbage   a call worked but gave a channel name unfit to print, or twice the same name
 *   mixed     info worked and read failed, or the other way (allowed: info checks less)
 * SECONDS is the time of both calls together. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/engine_util.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/io.h"
#include "io_check.h"
#include "util/cli_util.h"

/* Printable ASCII or UTF-8 bytes at or above 0x80; no control characters. */
static int printable(const char *s)
{
    if (!s || !*s) return 0;
    for (const unsigned char *p = (const unsigned char *)s; *p; p++)
        if (*p < 0x20 || *p == 0x7f) return 0;
    return strlen(s) <= 1024;
}

static const char *names_fault(char **names, int n)
{
    for (int i = 0; i < n; i++) {
        if (!printable(names[i])) return "unprintable channel name";
        for (int j = 0; j < i; j++)
            if (!strcmp(names[i], names[j])) return "a channel name twice";
    }
    return NULL;
}

/* The message with tabs and newlines flattened, for one line of output. */
static void flat(char *s)
{
    for (; *s; s++)
        if (*s == '\t' || *s == '\n' || *s == '\r') *s = ' ';
}

int nprfx_io_check_damaged(const char *list)
{
    FILE *f = strcmp(list, "-") ? fopen(list, "r") : stdin;
    if (!f) {
        fprintf(stderr, "nprfx info: cannot open '%s'\n", list);
        return 4;
    }
    nprfx_context *ctx = NULL;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    if (nprfx_context_create(&init, &ctx)) return 4;
    char path[4096];
    while (fgets(path, sizeof path, f)) {
        path[strcspn(path, "\n")] = 0;
        if (!*path) continue;
        char msg_info[1024] = "", msg_read[1024] = "";
        double t0 = engine_now();
        nprfx_file_info fi;
        nprfx_result ri = nprfx_io_info(ctx, path, &fi);
        const char *fault = NULL;
        if (ri)
            nprfx_context_last_error(ctx, msg_info, sizeof msg_info);
        else {
            fault = names_fault(fi.names, fi.nchannels);
            nprfx_file_info_free(&fi);
        }
        nprfx_plate pl;
        nprfx_result rr = nprfx_io_read(ctx, path, &pl);
        char detail[1200] = "";
        if (rr) {
            nprfx_context_last_error(ctx, msg_read, sizeof msg_read);
        } else {
            if (!fault) fault = names_fault(pl.names, pl.nchannels);
            snprintf(detail, sizeof detail, "%dx%d, %d channels", nprfx_rect_width(pl.bounds),
                     nprfx_rect_height(pl.bounds), pl.nchannels);
            nprfx_plate_free(&pl);
        }
        double dt = engine_now() - t0;
        const char *verdict;
        if (fault) {
            verdict = "garbage";
            snprintf(detail, sizeof detail, "%s", fault);
        } else if ((ri && !strstr(msg_info, path)) || (rr && !strstr(msg_read, path))) {
            verdict = "unnamed";
            snprintf(detail, sizeof detail, "%s",
                     ri && !strstr(msg_info, path) ? msg_info : msg_read);
        } else if (ri && rr) {
            verdict = "refused";
            snprintf(detail, sizeof detail, "%s", msg_read);
        } else if (!ri && !rr) {
            verdict = "read";
        } else {
            verdict = "mixed";
            snprintf(detail, sizeof detail, "%s", ri ? msg_info : msg_read);
        }
        flat(detail);
        printf("%s\t%.4f\t%.0f\t%s\t%s\n", verdict, dt, cli_peak_mib(), path, detail);
        fflush(stdout);
    }
    if (f != stdin) fclose(f);
    nprfx_context_destroy(ctx);
    return 0;
}
