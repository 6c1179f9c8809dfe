/* libFuzzer target: the image readers of cli/io/io_read.h on arbitrary bytes.
 *
 * Each input is written to a file (OpenImageIO reads paths) and given to nprfx_io_info and
 * nprfx_io_read, as `nprfx info` and a graph's read node do. Beyond the sanitizers' findings, a
 * read that succeeds with a channel name unfit to print is a finding: abort(). The memory bound
 * is lowered so that a refusal, not libFuzzer's -rss_limit_mb, decides large declared images.
 * See tests/fuzz/README.md. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "nprfx/io.h"

static nprfx_context *ctx;
static char path[256];

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    setenv("NPRFX_READ_LIMIT", "256M", 0);
    setenv("NPRFX_READ_TIMEOUT", "3", 0);
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT; /* no handler: messages are kept */
    if (nprfx_context_create(&init, &ctx)) abort();
    const char *dir = getenv("TMPDIR");
    snprintf(path, sizeof path, "%s/nprfx-fuzz-read-%ld.exr", dir && *dir ? dir : "/tmp",
             (long)getpid());
    return 0;
}

static void check_names(char **names, int n)
{
    for (int i = 0; i < n; i++) {
        const unsigned char *s = (const unsigned char *)names[i];
        if (!s || !*s) abort();
        for (; *s; s++)
            if (*s < 0x20 || *s == 0x7f) abort(); /* a garbage channel name was let through */
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f) abort();
    if (size && fwrite(data, 1, size, f) != size) abort();
    fclose(f);
    nprfx_file_info fi;
    if (nprfx_io_info(ctx, path, &fi) == NPRFX_OK) {
        check_names(fi.names, fi.nchannels);
        nprfx_file_info_free(&fi);
    }
    nprfx_plate pl;
    if (nprfx_io_read(ctx, path, &pl) == NPRFX_OK) {
        check_names(pl.names, pl.nchannels);
        nprfx_plate_free(&pl);
    }
    unlink(path);
    return 0;
}
