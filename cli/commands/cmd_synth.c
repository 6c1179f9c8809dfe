/* nprfx synth — write analytic test plates: one multi-channel EXR per frame with exact AOVs.
 *
 * The scenes and channels are the core's (nprfx/synth.h); this command only parses options,
 * renders each frame through a pthread pool and writes it through the OIIO adapter. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "nprfx/io.h"
#include "nprfx/io.h"
#include "io/io_write.h"
#include "nprfx/seq.h"
#include "util/cli_util.h"

/* Exit status: 0 written, 1 render or write error, 2 usage error. */
enum { SYNTH_OK = 0, SYNTH_FAILED = 1, SYNTH_USAGE = 2 };

static void list_scenes(FILE *f)
{
    for (int i = 0; i < nprfx_synth_scene_count(); i++) {
        const nprfx_synth_scene_info *s = nprfx_synth_scene_at(i);
        fprintf(f, "  %-10s %s\n", s->name, s->help);
    }
}

/* --layout blender: the channels as Blender's multilayer EXR names them (layer ViewLayer), so a
 * graph written for Blender plates runs on a synthetic plate with only the read path changed.
 * Each output channel is a synth channel times a sign; Vector packs the motion in Blender's
 * convention (docs/design.md §2.1: motion_prev = (X, -Y), motion_next = (-Z, W)). */
typedef struct layout_channel {
    const char *name, *src;
    float sign;
} layout_channel;
static const layout_channel blender_layout[] = {
    {"ViewLayer.Combined.R", "R", 1},
    {"ViewLayer.Combined.G", "G", 1},
    {"ViewLayer.Combined.B", "B", 1},
    {"ViewLayer.Combined.A", "A", 1},
    {"ViewLayer.Depth.Z", "Z", 1},
    {"ViewLayer.DiffCol.R", "albedo.R", 1},
    {"ViewLayer.DiffCol.G", "albedo.G", 1},
    {"ViewLayer.DiffCol.B", "albedo.B", 1},
    {"ViewLayer.DiffDir.R", "diffuse", 1},
    {"ViewLayer.DiffDir.G", "diffuse", 1},
    {"ViewLayer.DiffDir.B", "diffuse", 1},
    {"ViewLayer.IndexOB.X", "id", 1},
    {"ViewLayer.Normal.X", "N.X", 1},
    {"ViewLayer.Normal.Y", "N.Y", 1},
    {"ViewLayer.Normal.Z", "N.Z", 1},
    {"ViewLayer.Position.X", "P.X", 1},
    {"ViewLayer.Position.Y", "P.Y", 1},
    {"ViewLayer.Position.Z", "P.Z", 1},
    {"ViewLayer.Pref.R", "Pref.X", 1},
    {"ViewLayer.Pref.G", "Pref.Y", 1},
    {"ViewLayer.Pref.B", "Pref.Z", 1},
    {"ViewLayer.Pref.A", "coverage", 1},
    {"ViewLayer.UV.U", "UV.U", 1},
    {"ViewLayer.UV.V", "UV.V", 1},
    {"ViewLayer.Vector.X", "motion_prev.X", 1},
    {"ViewLayer.Vector.Y", "motion_prev.Y", -1},
    {"ViewLayer.Vector.Z", "motion_next.X", -1},
    {"ViewLayer.Vector.W", "motion_next.Y", 1},
};
enum { BLENDER_CHANNELS = (int)(sizeof blender_layout / sizeof blender_layout[0]) };

static int synth_index(const char *name)
{
    const char *const *n = nprfx_synth_channel_names();
    for (int i = 0; n[i]; i++)
        if (!strcmp(n[i], name)) return i;
    return -1;
}

/* Repack a synth frame into the Blender layout. */
static void to_blender(const nprfx_image *src, nprfx_image *dst)
{
    int idx[BLENDER_CHANNELS];
    for (int c = 0; c < BLENDER_CHANNELS; c++)
        idx[c] = synth_index(blender_layout[c].src);
    for (int y = dst->bounds.y0; y < dst->bounds.y1; y++)
        for (int x = dst->bounds.x0; x < dst->bounds.x1; x++) {
            const float *s = nprfx_image_at(src, x, y);
            float *d = nprfx_image_at(dst, x, y);
            for (int c = 0; c < BLENDER_CHANNELS; c++)
                d[c] = s[idx[c]] * blender_layout[c].sign;
        }
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: nprfx synth SCENE -o PATH [--frames LIST] [--size WxH] [--half]\n"
            "                   [--layout synth|blender] [--compression C] [--threads N]\n"
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
            "  --layout L       channel names: synth (below, the default) or blender (Blender's\n"
            "                   multilayer names and Vector convention, as samples/plates has:\n"
            "                   a graph written for Blender plates runs with only its read\n"
            "                   path changed; the read node needs \"vectors\": \"blender\")\n"
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

int cli_cmd_synth(int argc, char **argv)
{
    const char *scene = NULL, *out = NULL, *frames_spec = "1", *size = "256x256";
    const char *compression = NULL;
    int half = 0, threads = 0, blender = 0;
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
        } else if (!strcmp(a, "--layout") && has) {
            const char *l = argv[++i];
            if (strcmp(l, "synth") && strcmp(l, "blender")) {
                fprintf(stderr, "nprfx synth: --layout must be synth or blender, not '%s'\n", l);
                return SYNTH_USAGE;
            }
            blender = !strcmp(l, "blender");
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

    cli_env env;
    if (cli_env_init(&env, threads)) return SYNTH_FAILED;
    /* Refused before anything is allocated, with the size and the limit (NPRFX_READ_LIMIT). */
    if (nprfx_image_limit_check(env.ctx, "nprfx synth: --size", w, h,
                                nprfx_synth_channel_count() + (blender ? BLENDER_CHANNELS : 0),
                                0)) {
        fprintf(stderr, "%s\n", cli_message(env.ctx));
        cli_env_free(&env);
        return SYNTH_USAGE;
    }
    nprfx_frame_list frames = {NULL, 0};
    nprfx_image im = {0}, packed = {0};
    const char *bnames[BLENDER_CHANNELS + 1];
    for (int c = 0; c < BLENDER_CHANNELS; c++)
        bnames[c] = blender_layout[c].name;
    bnames[BLENDER_CHANNELS] = NULL;
    int status = SYNTH_OK;
    if (nprfx_seq_parse_frames(env.ctx, frames_spec, &frames) != NPRFX_OK) {
        fprintf(stderr, "nprfx synth: --frames: %s\n", cli_message(env.ctx));
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
        fprintf(stderr, "nprfx synth: %s\n", cli_message(env.ctx));
        status = SYNTH_FAILED;
        goto done;
    }
    if (blender && nprfx_image_alloc(env.ctx, im.bounds, BLENDER_CHANNELS, &packed) != NPRFX_OK) {
        fprintf(stderr, "nprfx synth: %s\n", cli_message(env.ctx));
        status = SYNTH_FAILED;
        goto done;
    }
    const nprfx_image *written = blender ? &packed : &im;
    const char *const *names = blender ? bnames : nprfx_synth_channel_names();
    nprfx_write_options opt = {sizeof opt, compression, half};
    for (int i = 0; i < frames.count; i++) {
        int frame = frames.frames[i];
        char path[4096];
        if (nprfx_seq_expand(env.ctx, out, frame, path, sizeof path) != NPRFX_OK ||
            nprfx_synth_render(env.ctx, scene, frame, &im) != NPRFX_OK ||
            (blender && (to_blender(&im, &packed), 0)) ||
            nprfx_io_write(env.ctx, path, written, names, NULL, &opt) != NPRFX_OK) {
            fprintf(stderr, "nprfx synth: frame %d: %s\n", frame, cli_message(env.ctx));
            status = SYNTH_FAILED;
            goto done;
        }
        printf("wrote %s (%s frame %d, %dx%d, %d channels%s)\n", path, scene, frame, w, h,
               written->channels, half ? ", half" : "");
        fflush(stdout);
    }
done:
    nprfx_image_free(&im);
    nprfx_image_free(&packed);
    nprfx_seq_frames_free(&frames);
    cli_env_free(&env);
    return status;
}
