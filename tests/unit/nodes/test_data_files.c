/* The data files nodes read (plugins/support/data_files.c): a file of the context's data
 * directory read whole or reported missing, its size limit, errors that name it; the stipple
 * node's shipped sequence preloaded from it, and a corrupt or foreign one refused with advice. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "nprfx/context.h"
#include "nprfx/ivs.h"
#include "nprfx/stipple.h"
#include "support/data_files.h"

static char dir[256];

static nprfx_context *context_for(const char *data_dir)
{
    nprfx_context_init ci = NPRFX_CONTEXT_INIT_DEFAULT;
    ci.data_dir = data_dir;
    nprfx_context *ctx = NULL;
    if (nprfx_context_create(&ci, &ctx) != NPRFX_OK) exit(2);
    return ctx;
}

static void write_file(const char *name, const void *data, size_t size)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0) {
        fprintf(stderr, "test: cannot write %s\n", path);
        exit(2);
    }
}

static void test_read(void)
{
    nprfx_data_file f;
    /* no data directory, or no such file: found missing, no error */
    nprfx_context *none = context_for(NULL);
    CHECK_OK(internal_data_file_read(none, "x.bin", 100, &f));
    CHECK(f.data == NULL && f.size == 0);
    nprfx_context_destroy(none);
    nprfx_context *ctx = context_for(dir);
    CHECK_OK(internal_data_file_read(ctx, "absent.bin", 100, &f));
    CHECK(f.data == NULL && strstr(f.path, "absent.bin") != NULL);

    /* a file: its bytes, up to and including the limit; one byte more is an error naming it */
    unsigned char bytes[300];
    for (int i = 0; i < 300; i++)
        bytes[i] = (unsigned char)(i * 7);
    write_file("some.bin", bytes, sizeof bytes);
    CHECK_OK(internal_data_file_read(ctx, "some.bin", 300, &f));
    CHECK(f.data && f.size == 300 && memcmp(f.data, bytes, 300) == 0);
    internal_data_file_free(&f);
    CHECK(f.data == NULL);
    CHECK(internal_data_file_read(ctx, "some.bin", 299, &f) == NPRFX_ERR_IO);
    CHECK(f.data == NULL);
    CHECK(strstr(th_error(ctx), "/some.bin: larger than 299 bytes") != NULL);
    write_file("empty.bin", "", 0);
    CHECK_OK(internal_data_file_read(ctx, "empty.bin", 10, &f));
    CHECK(f.data != NULL && f.size == 0); /* there, though empty */
    internal_data_file_free(&f);

    /* something there that cannot be read */
    char sub[512];
    snprintf(sub, sizeof sub, "%s/folder.bin", dir);
    CHECK(mkdir(sub, 0700) == 0);
    CHECK(internal_data_file_read(ctx, "folder.bin", 100, &f) == NPRFX_ERR_IO);
    CHECK(strstr(th_error(ctx), "/folder.bin: cannot read it") != NULL);
    rmdir(sub);
    printf("read: missing, whole, limit, empty, unreadable\n");
    nprfx_context_destroy(ctx);
}

/* An encoded sequence of n points all at (0.25, 0.75), of the given seed. */
static void write_ivs(uint64_t seed, int n)
{
    float *xy = malloc(sizeof(float) * 2 * (size_t)n);
    size_t size = nprfx_ivs_encoded_size(n);
    unsigned char *buf = malloc(size);
    if (!xy || !buf) exit(2);
    for (int i = 0; i < n; i++) {
        xy[2 * i] = 0.25f;
        xy[2 * i + 1] = 0.75f;
    }
    CHECK_OK(nprfx_ivs_encode(NULL, seed, n, xy, buf, size));
    write_file("ivs.bin", buf, size);
    free(xy);
    free(buf);
}

static void test_shipped_sequence(void)
{
    nprfx_context *ctx = context_for(dir);
    nprfx_stipple_sequence *seq = NULL;
    const nprfx_ivs_index *index = NULL;
    float xy[2];

    /* no file: an empty sequence, generated when used */
    CHECK_OK(internal_stipple_shipped_sequence(ctx, &seq));
    CHECK(seq != NULL);
    CHECK_OK(nprfx_stipple_sequence_index(ctx, seq, 16, &index));
    if (index) nprfx_ivs_index_point(index, 0, xy);
    CHECK(index && !(xy[0] == 0.25f && xy[1] == 0.75f));
    nprfx_stipple_sequence_destroy(seq);

    /* a file of the default seed: its points are the sequence's (this one's are all alike, which
     * no generated sequence is) */
    const int n = 1 << 16; /* the shortest prefix a sequence builds */
    write_ivs(NPRFX_IVS_DEFAULT_SEED, n);
    CHECK_OK(internal_stipple_shipped_sequence(ctx, &seq));
    CHECK_OK(nprfx_stipple_sequence_index(ctx, seq, 16, &index));
    if (index) nprfx_ivs_index_point(index, 12345, xy);
    CHECK(index && xy[0] == 0.25f && xy[1] == 0.75f);
    /* the process shares one sequence per file: a second instance gets the same one, already
     * indexed, and keeps it after the first lets go */
    nprfx_stipple_sequence *seq2 = NULL;
    CHECK_OK(internal_stipple_shipped_sequence(ctx, &seq2));
    CHECK(seq2 == seq);
    nprfx_stipple_sequence_destroy(seq);
    const nprfx_ivs_index *index2 = NULL;
    CHECK_OK(nprfx_stipple_sequence_index(ctx, seq2, 16, &index2));
    CHECK(index2 == index);
    /* a file rebuilt (another size) is read again; the old sequence lives on in its users */
    write_ivs(NPRFX_IVS_DEFAULT_SEED, n + 1);
    CHECK_OK(internal_stipple_shipped_sequence(ctx, &seq));
    CHECK(seq != seq2);
    CHECK_OK(nprfx_stipple_sequence_index(ctx, seq2, 16, &index2));
    if (index2) nprfx_ivs_index_point(index2, 12345, xy);
    CHECK(index2 && xy[0] == 0.25f && xy[1] == 0.75f);
    nprfx_stipple_sequence_destroy(seq2);
    nprfx_stipple_sequence_destroy(seq);
    internal_stipple_shipped_release();

    /* another seed, or a corrupt file: an error naming the file, with what to do */
    write_ivs(5, 100);
    seq = NULL;
    CHECK(internal_stipple_shipped_sequence(ctx, &seq) == NPRFX_ERR_INVALID_ARGUMENT && !seq);
    CHECK(strstr(th_error(ctx), "/ivs.bin holds the sequence of seed 5") != NULL);
    CHECK(strstr(th_error(ctx), "rebuild it with `nprfx ivs`, or remove it") != NULL);
    write_file("ivs.bin", "NPRFXIVS but not much else", 26);
    CHECK(internal_stipple_shipped_sequence(ctx, &seq) == NPRFX_ERR_PARSE && !seq);
    CHECK(strncmp(th_error(ctx), "stipple: ", 9) == 0 && strstr(th_error(ctx), "/ivs.bin: ivs: "));
    CHECK(strstr(th_error(ctx), "rebuild it with `nprfx ivs`, or remove it") != NULL);
    printf("shipped sequence: %s\n", th_error(ctx));
    nprfx_context_destroy(ctx);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/nprfx_data_files_XXXXXX");
    if (!mkdtemp(dir)) {
        fprintf(stderr, "test: cannot make a temporary directory\n");
        return 2;
    }
    test_read();
    test_shipped_sequence();
    const char *names[] = {"some.bin", "empty.bin", "ivs.bin"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        remove(path);
    }
    rmdir(dir);
    return check_finish();
}
