/* nprfx measure — how a look behaves over its shot, in numbers: whether its patterns follow the
 * motion (the warp error between each frame and the previous one carried along the plate's
 * motion vectors), what it puts on the background, and whether its tone follows the light.
 *
 * A look is compared with two baselines of the same graph (graph_variant.c): 'shower-door',
 * patterns stuck to the screen, and 'white', patterns drawn anew every frame. A coherent look has
 * a warp error well below both. docs/design.md §4 gives the thresholds the tests use. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/io_oiio.h"
#include "cmd_measure_flow.h"
#include "commands.h"
#include "nprfx/graph.h"
#include "nprfx/channels.h"
#include "nprfx/metrics.h"
#include "util/cli_util.h"

enum { MEASURE_OK = 0, MEASURE_FAILED = 1, MEASURE_USAGE = 2, MEASURE_BINS = 10 };

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: nprfx measure GRAPH.json --node NAME [--plate NAME] [--frames SPEC] [--shot SPEC]\n"
        "                     [--variant coherent|shower-door|white] [--matte NAME]\n"
        "                     [--paper NAME] [--margin PX] [--light NODE[:CHANNELS]]\n"
        "                     [--inset PX] [--moving PX]\n"
        "                     [--set N.P=V ...]\n"
        "                     [--threads N]\n\n"
        "Measures a look (node NAME of the graph) over its shot and prints one 'key value'\n"
        "line per measure:\n"
        "  warp_rms, warp_corr  the RMS difference and correlation between each frame's\n"
        "                       luminance and the previous frame's carried along the plate's\n"
        "                       motion vectors (motion_prev: the read node needs \"vectors\"),\n"
        "                       averaged over the frames after the first. Patterns that follow\n"
        "                       the scene keep it low; flicker and sliding raise it.\n"
        "  background_max_diff  with --paper and --matte: the largest difference between the\n"
        "                       look and the paper where the matte is 0 (the background).\n"
        "  tone_curve, tone_monotone\n"
        "                       with --light: the look's mean luminance in ten equal steps of\n"
        "                       the light (covered pixels only, with --matte), and 1 when it\n"
        "                       never falls by more than 0.04 as the light rises.\n\n"
        "options:\n"
        "  --plate NAME     the read or synth node with the motion (default: the only one)\n"
        "  --frames SPEC    frames to measure, e.g. 1-24 (default: the graph's)\n"
        "  --shot SPEC      the shot, replacing the graph's \"frames\" (as in nprfx run)\n"
        "  --variant V      coherent: the graph as it is (default); shower-door: the plate's\n"
        "                   motion zeroed and its anchors (Pref, UV, P) replaced by screen\n"
        "                   position, so patterns stick to the screen; white: every 'seed'\n"
        "                   param changed each frame, so patterns are drawn anew. The warp\n"
        "                   always uses the plate's true motion.\n"
        "  --moving PX      the warp error only where the motion is over PX pixels a frame\n"
        "                   (static pixels are alike in every variant and dilute it)\n"
        "  --margin PX      background_max_diff looks only at pixels at least PX from any\n"
        "                   covered pixel (for looks whose edges wobble or bleed on purpose)\n"
        "  --inset PX       the tone curve looks only at pixels at least PX inside an object\n"
        "                   (with --matte), away from silhouettes where a look mixes in paper\n"
        "  --set N.P=V      override a param, as in nprfx run\n"
        "  --threads N      worker threads\n\n"
        "nprfx measure flow ESTIMATE TRUTH --frames SPEC: an optical flow sequence against a\n"
        "synthetic plate's exact motion (nprfx measure flow --help).\n\n"
        "example:\n"
        "  nprfx measure samples/graphs/hatching.json --node ink --matte matte --paper paper \\\n"
        "      --light plate:DiffDir.G --variant shower-door\n");
}

/* Luminance of a pixel of c channels (Rec. 709 for RGB(A), else the first channel). */
static double lum(const float *p, int c)
{
    return c >= 3 ? 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] : p[0];
}

/* Node i's kind (nprfx_graph_node_kind), -1 when there is none. */
static int node_kind(const nprfx_graph *g, int i)
{
    nprfx_graph_node_info info = {sizeof info};
    return nprfx_graph_node(g, i, &info) ? -1 : info.kind;
}
static const char *node_name(const nprfx_graph *g, int i)
{
    nprfx_graph_node_info info = {sizeof info};
    return nprfx_graph_node(g, i, &info) ? "" : info.name;
}
/* Whether node i is a read or synth node. */
static int is_plate(const nprfx_graph *g, int i)
{
    int k = node_kind(g, i);
    return k == NPRFX_GRAPH_READ || k == NPRFX_GRAPH_SYNTH;
}

/* Evaluate "NODE" or "NODE:CHANNELS" of g at frame into an owned copy (channels as selected; with
 * want_lum, one channel of luminance). */
static nprfx_result take(nprfx_graph *g, const char *spec, int frame, int want_lum,
                         nprfx_image *out)
{
    char name[256];
    const char *colon = strchr(spec, ':');
    snprintf(name, sizeof name, "%.*s", colon ? (int)(colon - spec) : (int)strlen(spec), spec);
    nprfx_context *ctx = nprfx_graph_context(g);
    int kind = node_kind(g, nprfx_graph_node_index(g, name));
    if (kind < 0 || kind == NPRFX_GRAPH_WRITE)
        return nprfx_error(ctx, NPRFX_ERR_UNKNOWN_NODE, "the graph has no node '%s' to measure",
                           name);
    nprfx_image im;
    const char *const *names;
    nprfx_result r = nprfx_graph_eval(g, name, frame, &im, &names);
    if (r) return r;
    int idx[NPRFX_MAX_CHANNELS], n = im.channels < NPRFX_MAX_CHANNELS ? im.channels : 4;
    for (int c = 0; c < n; c++)
        idx[c] = c;
    if (colon) {
        char bad[128];
        int amb = 0;
        n = nprfx_channels_select(names, im.channels, colon + 1, idx, NPRFX_MAX_CHANNELS, bad,
                                  sizeof bad, &amb);
        if (n < 1)
            return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "'%s': '%s' %s in node '%s'", spec,
                               bad, amb ? "matches several channels" : "is not a channel", name);
    }
    if ((r = nprfx_image_alloc(ctx, im.bounds, want_lum ? 1 : n, out))) return r;
    for (int y = out->bounds.y0; y < out->bounds.y1; y++)
        for (int x = out->bounds.x0; x < out->bounds.x1; x++) {
            const float *s = nprfx_image_at(&im, x, y);
            float *d = nprfx_image_at(out, x, y), v[NPRFX_MAX_CHANNELS];
            for (int c = 0; c < n; c++)
                v[c] = s[idx[c]];
            if (want_lum)
                d[0] = (float)lum(v, n);
            else
                memcpy(d, v, sizeof(float) * (size_t)n);
        }
    return NPRFX_OK;
}

/* The only read or synth node of the graph, or -1. */
static int only_plate(const nprfx_graph *g)
{
    int found = -1;
    for (int i = 0; i < nprfx_graph_node_count(g); i++)
        if (is_plate(g, i)) {
            if (found >= 0) return -1;
            found = i;
        }
    return found;
}

typedef struct measure_opts {
    const char *graph, *node, *plate, *frames, *shot, *matte, *paper, *light;
    const char *sets[64];
    int nsets, variant, threads, margin, inset;
    double moving; /* > 0: the warp error only where the motion exceeds this many pixels */
} measure_opts;

/* Is (x, y) well inside an object: the matte at least 0.999 at every pixel within `inset`? The
 * tone curve leaves out the silhouettes, where a look mixes in the paper. */
static int interior(const nprfx_image *matte, int x, int y, int inset)
{
    for (int dy = -inset; dy <= inset; dy++)
        for (int dx = -inset; dx <= inset; dx++) {
            int xx = x + dx, yy = y + dy;
            if (!nprfx_rect_contains(matte->bounds, xx, yy)) continue;
            if (!(nprfx_image_at(matte, xx, yy)[0] >= 0.999f)) return 0;
        }
    return 1;
}

/* Is (x, y) background with a margin: the matte 0 at every pixel within `margin` (a square)?
 * Looks whose edges wobble or bleed (watercolor) reach past the silhouette on purpose. */
static int far_background(const nprfx_image *matte, int x, int y, int margin)
{
    for (int dy = -margin; dy <= margin; dy++)
        for (int dx = -margin; dx <= margin; dx++) {
            int xx = x + dx, yy = y + dy;
            if (!nprfx_rect_contains(matte->bounds, xx, yy)) continue;
            if (nprfx_image_at(matte, xx, yy)[0] != 0.0f) return 0;
        }
    return 1;
}

static nprfx_result load(nprfx_context *ctx, const measure_opts *o, int variant, nprfx_graph **g)
{
    nprfx_graph_options opt;
    memset(&opt, 0, sizeof opt);
    opt.size = sizeof opt;
    opt.cache_bytes = (size_t)1 << 30;
    opt.variant = variant;
    opt.io = nprfx_io_oiio();
    nprfx_result r = nprfx_graph_load(ctx, o->graph, &opt, g);
    if (!r && o->shot) r = nprfx_graph_set_shot(*g, o->shot);
    for (int i = 0; !r && i < o->nsets; i++)
        r = nprfx_graph_set(*g, o->sets[i]);
    return r;
}

typedef struct tone_bins {
    double lo, hi; /* the light's range over the shot */
    double sum[MEASURE_BINS];
    long long count[MEASURE_BINS];
} tone_bins;

static int measure(nprfx_context *ctx, const measure_opts *o)
{
    nprfx_graph *g = NULL, *truth = NULL;
    nprfx_frame_list frames = {NULL, 0};
    nprfx_image cur = {0}, prev = {0}, motion = {0}, matte = {0}, paper = {0}, full = {0};
    nprfx_image light = {0};
    int status = MEASURE_FAILED;
    double rms_sum = 0, corr_sum = 0, bg_max = 0;
    long long bg_count = 0;
    int pairs = 0, corr_pairs = 0;
    float *lights = NULL, *looks = NULL;
    size_t nl = 0, cap = 0;
    nprfx_result r = load(ctx, o, o->variant, &g);
    if (!r && o->variant != NPRFX_VARIANT_NONE) r = load(ctx, o, NPRFX_VARIANT_NONE, &truth);
    if (!truth) truth = g;
    if (!r) r = nprfx_graph_frames(g, o->frames, &frames);
    if (r) {
        fprintf(stderr, "nprfx measure: %s\n", cli_message(ctx));
        status = MEASURE_USAGE;
        goto done;
    }
    int plate = o->plate ? nprfx_graph_node_index(g, o->plate) : only_plate(g);
    if (!is_plate(g, plate)) {
        fprintf(stderr, "nprfx measure: %s\n",
                o->plate ? "--plate does not name a read or synth node"
                         : "the graph has several plates: name the one with the motion, --plate");
        status = MEASURE_USAGE;
        goto done;
    }
    char motion_spec[300];
    snprintf(motion_spec, sizeof motion_spec, "%s:motion_prev.X,motion_prev.Y",
             node_name(g, plate));
    for (int i = 0; i < frames.count; i++) {
        int f = frames.frames[i];
        if ((r = take(g, o->node, f, 1, &cur))) break;
        if (i > 0) {
            if ((r = take(truth, motion_spec, f, 0, &motion))) {
                fprintf(stderr,
                        "nprfx measure: plate '%s' has no motion_prev channels (a read node "
                        "needs \"vectors\", e.g. \"blender\")\n",
                        node_name(g, plate));
                break;
            }
            nprfx_warp_error we;
            nprfx_image mask = {0};
            if (o->moving > 0) { /* where things move: static pixels are equal in every variant */
                if ((r = nprfx_image_alloc(ctx, motion.bounds, 1, &mask))) break;
                for (int y = mask.bounds.y0; y < mask.bounds.y1; y++)
                    for (int x = mask.bounds.x0; x < mask.bounds.x1; x++) {
                        const float *m = nprfx_image_at(&motion, x, y);
                        nprfx_image_at(&mask, x, y)[0] =
                            m[0] * m[0] + m[1] * m[1] > o->moving * o->moving ? 1.0f : 0.0f;
                    }
            }
            r = nprfx_warp_compare(ctx, &cur, &prev, 0, &motion, o->moving > 0 ? &mask : NULL, &we);
            nprfx_image_free(&mask);
            if (r) break;
            rms_sum += we.rms;
            pairs++;
            if (we.correlation == we.correlation) {
                corr_sum += we.correlation;
                corr_pairs++;
            }
            nprfx_image_free(&motion);
        }
        if (o->matte && (r = take(g, o->matte, f, 1, &matte))) break;
        if (o->paper && o->matte) {
            if ((r = take(g, o->paper, f, 0, &paper))) break;
            if ((r = take(g, o->node, f, 0, &full))) break;
            int nc = paper.channels < full.channels ? paper.channels : full.channels;
            for (int y = full.bounds.y0; y < full.bounds.y1; y++)
                for (int x = full.bounds.x0; x < full.bounds.x1; x++) {
                    if (!far_background(&matte, x, y, o->margin)) continue;
                    const float *a = nprfx_image_at(&full, x, y), *b = nprfx_image_at(&paper, x, y);
                    for (int c = 0; c < nc; c++) {
                        double d = fabs((double)a[c] - b[c]);
                        if (!(d <= bg_max)) bg_max = d; /* NaN counts as the largest */
                    }
                    bg_count++;
                }
            nprfx_image_free(&paper);
            nprfx_image_free(&full);
        }
        if (o->light) {
            if ((r = take(g, o->light, f, 1, &light))) break;
            size_t np =
                (size_t)nprfx_rect_width(cur.bounds) * (size_t)nprfx_rect_height(cur.bounds);
            if (nl + np > cap) {
                size_t nc = (nl + np) * 2;
                float *a = realloc(lights, nc * sizeof *a),
                      *b = a ? realloc(looks, nc * sizeof *b) : NULL;
                if (a) lights = a;
                if (b) looks = b;
                if (!a || !b) {
                    r = nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
                    break;
                }
                cap = nc;
            }
            for (int y = cur.bounds.y0; y < cur.bounds.y1; y++)
                for (int x = cur.bounds.x0; x < cur.bounds.x1; x++) {
                    if (o->matte && !interior(&matte, x, y, o->inset)) continue;
                    float l = nprfx_image_at(&light, x, y)[0];
                    if (!isfinite(l)) continue;
                    lights[nl] = l;
                    looks[nl++] = nprfx_image_at(&cur, x, y)[0];
                }
            nprfx_image_free(&light);
        }
        nprfx_image_free(&matte);
        nprfx_image_free(&prev);
        prev = cur;
        memset(&cur, 0, sizeof cur);
        fprintf(stderr, "\rmeasured frame %d (%d/%d)", f, i + 1, frames.count);
    }
    fprintf(stderr, "\n");
    if (r) {
        fprintf(stderr, "nprfx measure: %s\n", cli_message(ctx));
        goto done;
    }
    printf("frames %d\n", frames.count);
    if (pairs) {
        printf("warp_rms %.6f\n", rms_sum / pairs);
        printf("warp_corr %.6f\n", corr_pairs ? corr_sum / corr_pairs : NAN);
    }
    if (o->paper && o->matte)
        printf("background_max_diff %.6g\nbackground_pixels %lld\n", bg_max, bg_count);
    if (o->light && nl > 0) {
        tone_bins b;
        memset(&b, 0, sizeof b);
        b.lo = b.hi = lights[0];
        for (size_t k = 0; k < nl; k++) {
            if (lights[k] < b.lo) b.lo = lights[k];
            if (lights[k] > b.hi) b.hi = lights[k];
        }
        double span = b.hi > b.lo ? b.hi - b.lo : 1;
        for (size_t k = 0; k < nl; k++) {
            int i = (int)((lights[k] - b.lo) / span * MEASURE_BINS);
            if (i >= MEASURE_BINS) i = MEASURE_BINS - 1;
            b.sum[i] += looks[k];
            b.count[i]++;
        }
        /* Steps with few pixels say little: a step is judged when it has 0.5% of them. */
        long long least = (long long)(nl / 200) + 1;
        int monotone = 1;
        double last = -INFINITY;
        printf("tone_curve");
        for (int i = 0; i < MEASURE_BINS; i++) {
            if (b.count[i] < least) {
                printf(" -");
                continue;
            }
            double m = b.sum[i] / b.count[i];
            printf(" %.4f", m);
            if (m < last - 0.04) monotone = 0;
            if (m > last) last = m;
        }
        printf("\ntone_monotone %d\n", monotone);
    }
    status = MEASURE_OK;
done:
    free(lights);
    free(looks);
    nprfx_image_free(&cur);
    nprfx_image_free(&prev);
    nprfx_image_free(&motion);
    nprfx_image_free(&matte);
    nprfx_image_free(&paper);
    nprfx_image_free(&full);
    nprfx_image_free(&light);
    nprfx_seq_frames_free(&frames);
    if (truth != g) nprfx_graph_free(truth);
    nprfx_graph_free(g);
    return status;
}

int cli_cmd_measure(int argc, char **argv)
{
    /* `nprfx measure flow`: an optical flow sequence against exact motion (cmd_measure_flow.c). */
    if (argc > 1 && !strcmp(argv[1], "flow")) return cli_cmd_measure_flow(argc - 1, argv + 1);
    measure_opts o;
    memset(&o, 0, sizeof o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return MEASURE_OK;
        } else if (!strcmp(a, "--node") && has) {
            o.node = argv[++i];
        } else if (!strcmp(a, "--plate") && has) {
            o.plate = argv[++i];
        } else if (!strcmp(a, "--frames") && has) {
            o.frames = argv[++i];
        } else if (!strcmp(a, "--shot") && has) {
            o.shot = argv[++i];
        } else if (!strcmp(a, "--matte") && has) {
            o.matte = argv[++i];
        } else if (!strcmp(a, "--margin") && has) {
            o.margin = atoi(argv[++i]);
        } else if (!strcmp(a, "--moving") && has) {
            o.moving = atof(argv[++i]);
        } else if (!strcmp(a, "--inset") && has) {
            o.inset = atoi(argv[++i]);
        } else if (!strcmp(a, "--paper") && has) {
            o.paper = argv[++i];
        } else if (!strcmp(a, "--light") && has) {
            o.light = argv[++i];
        } else if (!strcmp(a, "--threads") && has) {
            o.threads = atoi(argv[++i]);
        } else if (!strcmp(a, "--set") && has && o.nsets < 64) {
            o.sets[o.nsets++] = argv[++i];
        } else if (!strcmp(a, "--variant") && has) {
            const char *v = argv[++i];
            if (!strcmp(v, "coherent"))
                o.variant = NPRFX_VARIANT_NONE;
            else if (!strcmp(v, "shower-door"))
                o.variant = NPRFX_VARIANT_SHOWER_DOOR;
            else if (!strcmp(v, "white"))
                o.variant = NPRFX_VARIANT_WHITE;
            else {
                fprintf(stderr,
                        "nprfx measure: --variant must be coherent, shower-door or white, not "
                        "'%s'\n",
                        v);
                return MEASURE_USAGE;
            }
        } else if (a[0] != '-' && !o.graph) {
            o.graph = a;
        } else {
            fprintf(stderr, "nprfx measure: unexpected argument '%s' (nprfx measure --help)\n", a);
            return MEASURE_USAGE;
        }
    }
    if (!o.graph || !o.node) {
        fprintf(stderr, "nprfx measure: %s\n\n", !o.graph ? "name a graph" : "--node is required");
        usage(stderr);
        return MEASURE_USAGE;
    }
    if (!!o.paper != !!o.matte && o.paper) {
        fprintf(stderr, "nprfx measure: --paper needs --matte (where the background is)\n");
        return MEASURE_USAGE;
    }
    cli_env env;
    if (cli_env_init(&env, o.threads)) return MEASURE_FAILED;
    int status = measure(env.ctx, &o);
    cli_env_free(&env);
    return status;
}
