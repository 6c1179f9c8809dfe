/* libFuzzer target: the graph loader (cli/graph/graph_load.c and the name, cycle and reference
 * checks it calls) on arbitrary text, without rendering: parse, the frame list, the outputs'
 * description and free. Seeds: tests/graphs/ and samples/graphs/. See tests/fuzz/README.md. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/io_oiio.h"
#include "nprfx/graph.h"

static nprfx_context *ctx;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!ctx) {
        nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
        if (nprfx_context_create(&init, &ctx)) abort();
    }
    char *text = malloc(size + 1);
    if (!text) return 0;
    memcpy(text, data, size);
    text[size] = 0;
    nprfx_graph *g = NULL;
    nprfx_graph_options opt = {sizeof opt};
    opt.io = nprfx_io_oiio();
    opt.output_dir = "/nonexistent-nprfx-fuzz"; /* nothing is written: no frame is rendered */
    if (nprfx_graph_parse(ctx, text, "/nonexistent-nprfx-fuzz", &opt, &g) == NPRFX_OK) {
        nprfx_frame_list frames = {NULL, 0};
        if (nprfx_graph_frames(g, NULL, &frames) == NPRFX_OK) nprfx_seq_frames_free(&frames);
        char buf[512];
        nprfx_graph_describe_outputs(g, buf, sizeof buf);
        nprfx_graph_free(g);
    }
    free(text);
    return 0;
}
