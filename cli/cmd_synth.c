/* nprfx synth — write analytic test plates: one multi-channel EXR per frame with exact AOVs.
 *
 * The scenes and channels are the core's (nprfx/synth.h); this command only parses options,
 * renders each frame through a pthread pool and writes it through the OIIO adapter. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "commands.h"
#include "io.h"
#include "seq.h"

/* Exit status: 0 written, 1 render or write error, 2 usage error. */
enum { SYNTH_OK = 0, SYNTH_FAILED = 1, SYNTH_USAGE = 2 };

static void list_scenes(FILE *f)
{
    for (int i = 0; i < nprfx_synth_scene_count(); i++) {
        const nprfx_synth_scene_info *s = nprfx_synth_scene_at(i);
        fprintf(f, "  %-10s %s\n", s->name, s->help);
    }
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: nprfx synth SCENE -o PATH [--frames LIST] [--size WxH] [--half]\n"
            "                   [--compression C] [--threads N]\n"
            "       nprfx synth --list\n\n"
            "Ray-casts an analytic scene and writes one multi-channel EXR per frame with exact\n"
            "AOVs: ground truth for the coherence metrics and plates for trying the nodes.\n\n"
            "options:\n"
            "  -o PATH          output; with several frames it needs a frame token in the file\n"
            "                   name: '####' (zero padded to 4), '@@@', '%%04d'\n"
            "  --frames LIST    frames to write, e.g. 1-48, 1-48x2, 7, 1,5,9 (default 1); any\n"
            "                   integer frame, negative too, is defined (time = frame)\n"
            "  --size WxH       image size (default 256x256); the composition is the same at\n"
            "                   any size, so motion in pixels scales with the width\n"
            "  --half           store channels as half floats (Z's 1e10 background becomes inf)\n"
            "  --compression C  EXR compression: zip (default), piz, none, dwaa, ...\n"
            "  --threads N      worker threads (default $NPRFX_THREADS, else all cores)\n"
            "  --list           list the scenes\n\n"
            "scenes (motion figures for 256 pixels wide):\n");
    list_scenes(f);
    fprintf(f, "\nchannels:");
    const char *const *names = nprfx_synth_channel_names();
    for (int i = 0; i < nprfx_synth_channel_count(); i++)
        fprintf(f, " %s", names[i]);
    fprintf(f,
            "\n  motion_prev/next: pixels to the same surface point at frame-1/+1; Z: view depth\n"
            "  (background 1e10); P world, Pref object-space rest position; id 0 = background.\n"
            "  Camera: pinhole, 45 degree horizontal field of view, pixel centres at integer\n"
            "  coordinates, y down.\n\n"
            "example: nprfx synth orbit --frames 1-48 --size 512x512 -o plates/orbit.####.exr\n");
}

int nprfx_cmd_synth(int argc, char **argv)
{
    const char *scene = NULL, *out = NULL, *frames_spec = "1", *size = "256x256";
    const char *compression = NULL;
    int half = 0, threads = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return SYNTH_OK;
        } else if (!strcmp(a, "--list")) {
            list_scenes(stdout);
            return SYNTH_OK;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has) {
            out = argv[++i];
        } else if (!strcmp(a, "--frames") && has) {
            frames_spec = argv[++i];
        } else if (!strcmp(a, "--size") && has) {
            size = argv[++i];
        } else if (!strcmp(a, "--threads") && has) {
            threads = atoi(argv[++i]);
        } else if (!strcmp(a, "--compression") && has) {
            compression = argv[++i];
        } else if (!strcmp(a, "--half")) {
            half = 1;
        } else if (a[0] != '-' && !scene) {
            scene = a;
        } else {
            fprintf(stderr, "nprfx synth: unexpected argument '%s' (nprfx synth --help)\n", a);
            return SYNTH_USAGE;
        }
    }
    if (!scene || !out) {
        fprintf(stderr, "nprfx synth: %s\n\n", !scene ? "name a scene" : "-o PATH is required");
        usage(stderr);
        return SYNTH_USAGE;
    }
    int known = 0;
    for (int i = 0; i < nprfx_synth_scene_count(); i++)
        if (!strcmp(nprfx_synth_scene_at(i)->name, scene)) known = 1;
    if (!known) {
        fprintf(stderr, "nprfx synth: unknown scene '%s'; the scenes are:\n", scene);
        list_scenes(stderr);
        return SYNTH_USAGE;
    }
    int w = 0, h = 0;
    char tail;
    if (sscanf(size, "%dx%d%c", &w, &h, &tail) != 2 || w < 1 || h < 1 || w > 65536 || h > 65536) {
        fprintf(stderr, "nprfx synth: --size must be WxH with positive sizes, e.g. 256x256\n");
        return SYNTH_USAGE;
    }
    if (threads < 0) {
        fprintf(stderr, "nprfx synth: --threads must be a positive number\n");
        return SYNTH_USAGE;
    }

    nprfx_cli_env env;
    if (nprfx_cli_env_init(&env, threads)) return SYNTH_FAILED;
    nprfx_frame_list frames = {NULL, 0};
    nprfx_image im = {0};
    int status = SYNTH_OK;
    if (nprfx_seq_parse_frames(env.ctx, frames_spec, &frames) != NPRFX_OK) {
        fprintf(stderr, "nprfx synth: --frames: %s\n", nprfx_cli_message(env.ctx));
        status = SYNTH_USAGE;
        goto done;
    }
    if (frames.count > 1 && !nprfx_seq_has_pattern(out)) {
        fprintf(stderr,
                "nprfx synth: %d frames but '%s' has no frame token; use e.g. "
                "name.####.exr\n",
                frames.count, out);
        status = SYNTH_USAGE;
        goto done;
    }
    if (nprfx_image_alloc(env.ctx, nprfx_rect_make(0, 0, w, h), nprfx_synth_channel_count(), &im) !=
        NPRFX_OK) {
        fprintf(stderr, "nprfx synth: %s\n", nprfx_cli_message(env.ctx));
        status = SYNTH_FAILED;
        goto done;
    }
    nprfx_write_options opt = {sizeof opt, compression, half};
    for (int i = 0; i < frames.count; i++) {
        int frame = frames.frames[i];
        char path[4096];
        if (nprfx_seq_expand(env.ctx, out, frame, path, sizeof path) != NPRFX_OK ||
            nprfx_synth_render(env.ctx, scene, frame, &im) != NPRFX_OK ||
            nprfx_io_write(env.ctx, path, &im, nprfx_synth_channel_names(), NULL, &opt) !=
                NPRFX_OK) {
            fprintf(stderr, "nprfx synth: frame %d: %s\n", frame, nprfx_cli_message(env.ctx));
            status = SYNTH_FAILED;
            goto done;
        }
        printf("wrote %s (%s frame %d, %dx%d, %d channels%s)\n", path, scene, frame, w, h,
               nprfx_synth_channel_count(), half ? ", half" : "");
        fflush(stdout);
    }
done:
    nprfx_image_free(&im);
    nprfx_seq_frames_free(&frames);
    nprfx_cli_env_free(&env);
    return status;
}
