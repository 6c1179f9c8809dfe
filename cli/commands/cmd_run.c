/* nprfx run — render a node graph over a frame range, with progress. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "engine/engine_util.h"
#include "nprfx/io_oiio.h"
#include "cmd_shared.h"
#include "commands.h"
#include "nprfx/graph.h"
#include "util/output_lock.h"
#include "util/cli_util.h"

static void usage_analyze(FILE *f, const char *prog)
{
    fprintf(f,
            "usage: %s analyze GRAPH.json [GRAPH.json ...] [options]\n\n"
            "Measures once what a graph's nodes measure over the whole shot (the range of every\n"
            "tone node whose range is 'shot' or 'frame') and stores it in a small JSON file,\n"
            "by default beside the graph's first output, named after the graph\n"
            "(out/main/main.analysis.json). '%s run' and every farm chunk find it there and\n"
            "render their frames without reading the rest of the shot; the pixels are the same\n"
            "as without it. The file records the shot and each plate file's size and time: a run\n"
            "on other or changed plates, or another shot, measures again with a note, and so\n"
            "does a node whose rendered frame differs from what was measured.\n\n"
            "options (as for '%s run', with which it must agree):\n"
            "  --analysis PATH     where to write it (default: as above)\n"
            "  --shot SPEC, --set N.P=VALUE, --aovs PROFILE, --design-width W, --threads N,\n"
            "  --output-dir DIR, --cache-mb N, --mem-limit SIZE, --stats, --quiet\n",
            prog, prog, prog);
}

static void usage(FILE *f, const char *prog, const cli_run_extension *ext)
{
    /* The nodes that render by rows, from their descriptors. */
    char rows[512] = "";
    for (int i = 0, n = 0; i < nprfx_node_count(); i++) {
        const nprfx_node_desc *d = nprfx_node_at(i);
        if (!(d->flags & NPRFX_NODE_ROWS)) continue;
        size_t len = strlen(rows);
        snprintf(rows + len, sizeof rows - len, "%s%s", n++ ? ", " : "", d->id);
    }
    fprintf(
        f,
        "usage: %s run GRAPH.json [GRAPH.json ...] [options]\n\n"
        "Renders a node graph: every write node's sequence over the frames. Several graphs\n"
        "render one after the other with the same options (a --set applies to the graphs\n"
        "that have the node); the status is the worst of them.\n\n"
        "options:\n"
        "  --frames SPEC       frames to render: 12, 1-24, 1-24x2, 24-1, 1,5,9-12 (default:\n"
        "                      the graph's \"frames\"; temporal nodes still see the whole shot)\n"
        "  --shot SPEC         the shot: replaces the graph's \"frames\" (what temporal nodes\n"
        "                      see, and what is rendered without --frames), e.g. 1-100 for a\n"
        "                      longer shot than the graph was written for\n"
        "  --set N.P=VALUE     override param P of node N (repeatable), e.g. --set "
        "blend.opacity=0.5\n"
        "  --aovs PROFILE      the renderer every read node's plates come from, for the\n"
        "                      canonical AOVs graphs name (plate:depth): auto (detected from\n"
        "                      the header and channel names), generic, blender, arnold,\n"
        "                      renderman, karma, vray, redshift, nuke, or a studio's mapping\n"
        "                      file NAME.json (README); as --set READ.aovs=... on each read\n"
        "  --design-width W    the plate width in pixels the graph's params were set for\n"
        "                      (replaces its \"design_width\"): on a plate of another width,\n"
        "                      every length in pixels (stroke widths, dot areas, radii) is\n"
        "                      scaled by plate width / W, so a proxy draws the same look\n"
        "                      smaller; off: params in each plate's own pixels\n"
        "  --threads N         worker threads (default $NPRFX_THREADS, else all cores)\n"
        "  --output-dir DIR    put relative write paths under DIR\n"
        "  --cache-mb N        memory for cached node results and idle frame buffers\n"
        "                      (default 2048)\n"
        "  --mem-limit SIZE    the most memory the graph's frames may take, e.g. 8G, 512M\n"
        "                      (0: none; default $NPRFX_READ_LIMIT, else half the physical\n"
        "                      memory). A graph whose estimated peak is above it fails before\n"
        "                      the first frame, and every frame is checked before it is\n"
        "                      allocated; the message names the node and the sizes. The same\n"
        "                      limit refuses plates and synth sizes too large to hold\n"
        "  --stats             after the run, print per node ms/frame and bytes allocated,\n"
        "                      then the most frames and caches held, the plan's estimate and\n"
        "                      the process's peak resident size\n"
        "  --no-pool           no frame-buffer pool and no memory plan (every frame calloc'd\n"
        "                      and freed, plates whole, results kept until --cache-mb evicts\n"
        "                      them): the pixels are the same, for checking that\n"
        "  --strip-rows N      render a write whose whole chain renders by rows (EXR reads,\n"
        "                      and nodes %s) N rows at a time,\n"
        "                      reading and writing only those rows (plus the margins the\n"
        "                      filters need), so memory follows N, not the frame; the pixels\n"
        "                      are the same. 0 (default): by strips of 64 rows only when whole\n"
        "                      frames would pass --mem-limit; -1: never\n"
        "  --tile N            render nodes in NxN tiles (output is identical; for testing)\n"
        "  --keep-going        render the remaining frames after a failed one, exit 1\n"
        "  --wait              when another run is writing one of the graph's sequences,\n"
        "                      wait for it to finish (default: fail at once, naming it)\n"
        "  --analysis PATH     the shot statistics '%s analyze' stored (default: the graph's\n"
        "                      own beside its first output, when it is there); off: measure\n"
        "                      the shot in this run. Pixels are the same either way\n"
        "  --shared-lock       share the sequences' locks with other --shared-lock runs, which\n"
        "                      write other frames of them (nprfx farm's chunk tasks); a run\n"
        "                      without it still excludes them all\n"
        "%s"
        "  --no-previews       write no preview (PNG) of any write node\n"
        "  --serial            read, compute and write each frame before the next starts\n"
        "                      (default: the next frame's plates decode while a frame\n"
        "                      computes and, with 4 or more --threads, a frame's files are\n"
        "                      written while the next computes, progress then showing a\n"
        "                      frame once its files are written); less memory, same pixels\n"
        "  --quiet             no progress output\n"
        "  --check             check the graphs (JSON, nodes, params, references, cycles,\n"
        "                      frames, sizes, the memory plan against --mem-limit) and list\n"
        "                      what they would write; render nothing\n\n"
        "Graph files: {\"frames\": \"1-24\", \"nodes\": {NAME: {\"node\": TYPE, \"inputs\": "
        "{INPUT: REF}, \"params\": {PARAM: VALUE}}},\n"
        "         \"design_width\": 1280}  (optional: the plate width its pixel params are for)\n"
        "  read:  {\"node\": \"read\", \"path\": \"plates/shot.####.exr\", \"colorspace\": "
        "\"linear\", \"vectors\": \"blender\",\n"
        "         \"part\": \"rgba\", \"view\": \"left\"}  (part, view: of multi-part and stereo "
        "EXRs)\n"
        "  synth: {\"node\": \"synth\", \"scene\": \"orbit\", \"size\": \"256x256\"}\n"
        "  write: {\"node\": \"write\", \"inputs\": {\"image\": REF}, \"path\": "
        "\"out/x.####.exr\", \"preview\": \"out/x.####.png\"}\n"
        "  REF:   \"node\" or \"node:channels\", e.g. \"plate:Depth.Z\", \"plate:Vector.XY\"\n"
        "Write speed (one 1920x1080 RGBA frame on 2 cores): a write node's \"compression\"\n"
        "  zip (the default, lossless) ~370 ms, piz ~500 ms, dwaa (lossy) ~260 ms, none\n"
        "  ~50 ms (4x the disk); \"half\": true stores half floats (half the file, ~40%%\n"
        "  less time); a preview ~150 ms more, written beside the EXR on a second core.\n"
        "  With 4 or more --threads both are written while the next frame computes.\n"
        "  Set them in the graph or per run: --set out.compression=none, --set out.half=true,\n"
        "  --set out.preview= (none), or --no-previews for every write node.\n"
        "Node names are unique; a graph has at most 1,000,000 nodes, in any depth, and no\n"
        "cycles (an error names the nodes on one).\n"
        "Read paths are relative to the graph file, write paths to the current directory.\n"
        "Files are written under a temporary name and renamed, so a failed frame never leaves\n"
        "a partial file. A run locks every sequence it writes (a hidden .NAME.nprfx-lock file\n"
        "beside it; across hosts only where the file system supports locks, e.g. NFSv4) and\n"
        "removes what a killed run left there. See 'nprfx list' and 'nprfx help NODE' for the\n"
        "node types.\n",
        prog, rows, prog, ext && ext->options_usage ? ext->options_usage : "");
}

/* What `run` applies to every graph it renders. */
typedef struct run_opts {
    const char *prog, *frames, *shot;
    const char *const *sets;
    int nsets, keep_going, quiet, several, wait, stats, check, shared_lock;
    const char *aovs;         /* --aovs: every read node's profile */
    const char *design_width; /* --design-width */
    const char *analysis;     /* --analysis: PATH, "off", or NULL (the graph's own, if any) */
    int no_previews;          /* --no-previews */
    int serial;               /* --serial */
    int analyze;              /* `nprfx analyze`: measure and store, render nothing */
} run_opts;

/* Is --set "N.P=V" about a node of g? With several graphs a --set may name a node only some of
 * them have. */
static int graph_has_node_of(nprfx_graph *g, const char *assignment)
{
    const char *dot = strchr(assignment, '.');
    char name[256];
    if (!dot) return 1;
    snprintf(name, sizeof name, "%.*s", (int)(dot - assignment), assignment);
    return nprfx_graph_has_node(g, name);
}

static void lock_notice(void *user, const char *message)
{
    const run_opts *ro = user;
    if (!ro->quiet) fprintf(stderr, "%s: %s\n", ro->prog, message);
}

/* A read's note on the parts and views it took: warnings always, notes unless --quiet. */
static void graph_notice(void *user, const char *message)
{
    const run_opts *ro = user;
    if (!ro->quiet || !strncmp(message, "warning", 7))
        fprintf(stderr, "%s: %s\n", ro->prog, message);
}

/* Lock every sequence g writes before its first frame (output_lock.h). */
static nprfx_result lock_outputs(nprfx_context *ctx, nprfx_graph *g, const char *graph_path,
                                 const run_opts *ro, cli_output_locks **locks)
{
    char **paths;
    int n;
    nprfx_result r = nprfx_graph_output_patterns(g, &paths, &n);
    if (r) return r;
    r = (ro->shared_lock ? cli_output_locks_take_shared : cli_output_locks_take)(
        ctx, (const char *const *)paths, n, graph_path, ro->wait, lock_notice, (void *)ro, locks);
    nprfx_graph_output_patterns_free(paths, n);
    return r;
}

/* What `nprfx run` shows of a run: a progress line a frame (one line rewritten on a terminal),
 * each failed frame's message, and a warning once the measured pace says hours. */
typedef struct run_progress {
    const char *prog;
    nprfx_context *ctx;
    int tty, quiet, warned_eta;
} run_progress;

static int show_progress(void *user, const nprfx_graph_progress *p)
{
    run_progress *rp = user;
    int k = p->done - 1;
    if (p->result) {
        if (rp->tty) fputc('\n', stderr);
        fprintf(stderr, "%s: frame %d failed: %s\n", rp->prog, p->frame, cli_message(rp->ctx));
        return 0;
    }
    double el = p->elapsed, fps = (k + 1) / (el > 0 ? el : 1e-9);
    double eta = (p->count - k - 1) / fps;
    /* Measured, after the first frames (the first alone includes a temporal warm-up). */
    if (!rp->warned_eta && k == (p->count > 2 ? 1 : 0) && eta > 3600.0) {
        rp->warned_eta = 1;
        if (rp->tty) fputc('\n', stderr);
        fprintf(stderr,
                "%s: warning: %.2f s a frame so far: the remaining %d frames take about "
                "%.1f hours\n",
                rp->prog, el / (k + 1), p->count - k - 1, eta / 3600.0);
    }
    if (rp->tty)
        fprintf(stderr, "\r[%d/%d] frame %d  %.2f fps  ETA %.0f s   ", k + 1, p->count, p->frame,
                fps, eta);
    else if (!rp->quiet)
        fprintf(stderr, "frame %d (%d/%d) %.3f s\n", p->frame, k + 1, p->count, p->seconds);
    return 0;
}

/* `nprfx analyze`: measure the shot once and store it; the exit status. */
static int analyze_graph(nprfx_context *ctx, nprfx_graph *g, const char *graph_path,
                         const run_opts *ro, const nprfx_frame_list *fl,
                         const nprfx_graph_plan_info *plan)
{
    char path[8192];
    if (ro->analysis && strcmp(ro->analysis, "off"))
        snprintf(path, sizeof path, "%s", ro->analysis);
    else
        nprfx_graph_analysis_path(g, graph_path, path, sizeof path);
    double t0 = engine_now();
    int measured = 0;
    char dir[8192];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash && slash != dir) *slash = 0;
    if (slash && slash != dir && cli_make_dirs(dir)) {
        fprintf(stderr, "%s: cannot create the directory '%s' for %s\n", ro->prog, dir, path);
        return 2;
    }
    if (nprfx_graph_analyze(g, &measured) || nprfx_graph_analysis_save(g, path)) {
        fprintf(stderr, "%s: %s\n", ro->prog, cli_message(ctx));
        return 2;
    }
    int first = 0, last = 0;
    nprfx_graph_shot(g, &first, &last);
    if (!ro->quiet)
        printf("%s: measured %d node%s over frames %d-%d in %.1f s: %s\n", graph_path, measured,
               measured == 1 ? "" : "s", first, last, engine_now() - t0, path);
    if (ro->stats) cli_print_stats(stdout, g, fl->count, plan);
    return 0;
}

/* Seed g's measuring nodes from --analysis or the graph's own analysis when it is there. A
 * missing or broken file costs a measurement, never the run: a warning, and 0. */
static int seed_graph(nprfx_context *ctx, nprfx_graph *g, const char *graph_path,
                      const run_opts *ro)
{
    char path[8192];
    if (!nprfx_graph_measuring_nodes(g) || (ro->analysis && !strcmp(ro->analysis, "off"))) return 0;
    if (ro->analysis)
        snprintf(path, sizeof path, "%s", ro->analysis);
    else {
        nprfx_graph_analysis_path(g, graph_path, path, sizeof path);
        if (access(path, F_OK)) return 0;
    }
    int seeded = 0;
    if (nprfx_graph_analysis_load(g, path, &seeded))
        fprintf(stderr, "%s: warning: %s: measuring the shot in this run\n", ro->prog,
                cli_message(ctx));
    else if (seeded && !ro->quiet)
        fprintf(stderr, "%s: note: the shot statistics of %d node%s from %s\n", ro->prog, seeded,
                seeded == 1 ? "" : "s", path);
    return 0;
}

/* Load and render one graph; the exit status: 0 ok, 1 frames failed, 2 not rendered. */
static int run_graph(cli_env *envp, const nprfx_graph_options *optp, const char *graph_path,
                     const run_opts *ro)
{
    cli_env env = *envp;
    nprfx_graph_options opt = *optp;
    const char *prog = ro->prog, *frames = ro->frames, *shot = ro->shot;
    const char *const *sets = ro->sets;
    int nsets = ro->nsets, keep_going = ro->keep_going, quiet = ro->quiet;
    nprfx_graph *g = NULL;
    nprfx_frame_list fl = {NULL, 0};
    cli_output_locks *locks = NULL;
    int status = 0;
    if (nprfx_graph_load(env.ctx, graph_path, &opt, &g)) {
        fprintf(stderr, "%s: %s\n", prog, cli_message(env.ctx));
        status = 2;
        goto done;
    }
    if (!nprfx_graph_write_count(g)) {
        fprintf(stderr, "%s: %s: the graph has no write node, so it would produce nothing\n", prog,
                graph_path);
        status = 2;
        goto done;
    }
    if (shot && nprfx_graph_set_shot(g, shot)) {
        fprintf(stderr, "%s: --shot: %s\n", prog, cli_message(env.ctx));
        status = 2;
        goto done;
    }
    if (ro->design_width) {
        char *end = NULL;
        double w = !strcmp(ro->design_width, "off") ? 0 : strtod(ro->design_width, &end);
        if ((end && (end == ro->design_width || *end)) || nprfx_graph_set_design_width(g, w)) {
            fprintf(stderr,
                    "%s: --design-width '%s': give the plate width the params were set for "
                    "(e.g. 1920), or off for the plate's own pixels\n",
                    prog, ro->design_width);
            status = 2;
            goto done;
        }
    }
    for (int i = 0; ro->aovs && i < nprfx_graph_node_count(g); i++) {
        nprfx_graph_node_info info = {sizeof info};
        char set[512];
        if (nprfx_graph_node(g, i, &info) || info.kind != NPRFX_GRAPH_READ) continue;
        snprintf(set, sizeof set, "%s.aovs=%s", info.name, ro->aovs);
        if (nprfx_graph_set(g, set)) {
            fprintf(stderr, "%s: --aovs: %s\n", prog, cli_message(env.ctx));
            status = 2;
            goto done;
        }
    }
    for (int i = 0; ro->no_previews && i < nprfx_graph_node_count(g); i++) {
        nprfx_graph_node_info info = {sizeof info};
        char set[512];
        if (nprfx_graph_node(g, i, &info) || info.kind != NPRFX_GRAPH_WRITE) continue;
        snprintf(set, sizeof set, "%s.preview=", info.name);
        if (nprfx_graph_set(g, set)) {
            fprintf(stderr, "%s: --no-previews: %s\n", prog, cli_message(env.ctx));
            status = 2;
            goto done;
        }
    }
    for (int i = 0; i < nsets; i++)
        if ((!ro->several || graph_has_node_of(g, sets[i])) && nprfx_graph_set(g, sets[i])) {
            fprintf(stderr, "%s: %s\n", prog, cli_message(env.ctx));
            status = 2;
            goto done;
        }
    if (nprfx_graph_frames(g, frames, &fl)) {
        fprintf(stderr, "%s: %s\n", prog, cli_message(env.ctx));
        status = 2;
        goto done;
    }
    /* The memory plan's estimate, before anything is locked or rendered: a graph that cannot
     * fit fails here with the node and the sizes, never in the OOM killer at frame 40. */
    nprfx_graph_plan_info plan;
    memset(&plan, 0, sizeof plan);
    if (nprfx_graph_check(g, &fl, &plan)) {
        fprintf(stderr, "%s: %s\n", prog, cli_message(env.ctx));
        status = 2;
        goto done;
    }
    if (ro->analyze) {
        status = analyze_graph(env.ctx, g, graph_path, ro, &fl, &plan);
        goto done;
    }
    if (seed_graph(env.ctx, g, graph_path, ro)) {
        status = 2;
        goto done;
    }
    if (ro->check) {
        /* --check: everything a render would refuse up front (the memory plan above reads
         * plate headers, no pixel, and allocates no frame), and nothing read or written. */
        char buf[4096];
        nprfx_graph_describe_outputs(g, buf, sizeof buf);
        printf("%s: ok: %d frame%s would write:\n%s", graph_path, fl.count,
               fl.count == 1 ? "" : "s", buf);
        goto done;
    }
    if (lock_outputs(env.ctx, g, graph_path, ro, &locks)) {
        fprintf(stderr, "%s: %s\n", prog, cli_message(env.ctx));
        status = 2;
        goto done;
    }
    {
        char why[2048];
        if (nprfx_graph_cost_warnings(g, fl.count, why, sizeof why) > 0)
            fprintf(stderr, "%s: warning: %s: this may take hours:\n%s", prog, graph_path, why);
    }
    run_progress rp = {prog, env.ctx, isatty(STDERR_FILENO) && !quiet, quiet, 0};
    nprfx_graph_run_options runo = {sizeof runo, keep_going, show_progress, NULL, &rp};
    runo.serial = ro->serial;
    nprfx_graph_run_summary sum;
    nprfx_graph_run(g, &fl, &runo, &sum);
    int tty = rp.tty, failed = sum.failed, files = sum.files;
    if (tty) fputc('\n', stderr);
    if (failed) {
        status = 1;
        fprintf(stderr, "%s: %d of %d frames failed\n", prog, failed, fl.count);
    }
    if (files && !quiet) {
        char buf[4096];
        nprfx_graph_describe_outputs(g, buf, sizeof buf);
        printf("wrote %d frame%s in %.1f s:\n%s", fl.count - failed,
               fl.count - failed == 1 ? "" : "s", sum.seconds, buf);
    }
    if (ro->stats) cli_print_stats(stdout, g, fl.count, &plan);
done:
    cli_output_locks_release(locks);
    nprfx_seq_frames_free(&fl);
    nprfx_graph_free(g);
    return status;
}

static int run_main(int argc, char **argv, const cli_run_extension *ext, int analyze);

int cli_cmd_run(int argc, char **argv)
{
    return run_main(argc, argv, NULL, 0);
}

int cli_cmd_run_extended(int argc, char **argv, const cli_run_extension *ext)
{
    return run_main(argc, argv, ext, 0);
}

int cli_cmd_analyze(int argc, char **argv)
{
    return run_main(argc, argv, NULL, 1);
}

static int run_main(int argc, char **argv, const cli_run_extension *ext, int analyze)
{
    const char *prog = ext && ext->program ? ext->program : "nprfx";
    char label[256]; /* "nprfx run": what messages start with */
    snprintf(label, sizeof label, "%s %s", prog, analyze ? "analyze" : "run");
    const char *graphs[64], *frames = NULL, *outdir = NULL, *shot = NULL;
    int ngraphs = 0;
    const char *sets[256];
    int nsets = 0, threads = 0, tile = 0, keep_going = 0, quiet = 0, wait = 0, stats = 0;
    int no_pool = 0, check = 0, shared_lock = 0, strip_rows = 0, no_previews = 0, serial = 0;
    const char *mem_limit = NULL, *aovs = NULL, *design_width = NULL, *analysis = NULL;
    char aovs_path[8192];
    long cache_mb = 2048;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has = i + 1 < argc, took = 0;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            if (analyze)
                usage_analyze(stdout, prog);
            else
                usage(stdout, prog, ext);
            return 0;
        } else if (!strcmp(a, "--frames") && has)
            frames = argv[++i];
        else if (!strcmp(a, "--shot") && has)
            shot = argv[++i];
        else if (!strcmp(a, "--aovs") && has) {
            aovs = argv[++i];
            /* a mapping file named here is relative to where the command runs, not to the
             * graph file as a read's own "aovs" is */
            size_t n = strlen(aovs);
            if (n > 5 && !strcmp(aovs + n - 5, ".json") && aovs[0] != '/') {
                char cwd[4096];
                if (!getcwd(cwd, sizeof cwd) || snprintf(aovs_path, sizeof aovs_path, "%s/%s", cwd,
                                                         aovs) >= (int)sizeof aovs_path) {
                    fprintf(stderr, "%s: --aovs: the path '%s' is too long\n", label, aovs);
                    return 2;
                }
                aovs = aovs_path;
            }
        } else if (!strcmp(a, "--analysis") && has)
            analysis = argv[++i];
        else if (!strcmp(a, "--design-width") && has)
            design_width = argv[++i];
        else if (!strcmp(a, "--set") && has && nsets < 256)
            sets[nsets++] = argv[++i];
        else if (!strcmp(a, "--threads") && has)
            threads = atoi(argv[++i]);
        else if (!strcmp(a, "--tile") && has)
            tile = atoi(argv[++i]);
        else if (!strcmp(a, "--strip-rows") && has)
            strip_rows = atoi(argv[++i]);
        else if (!strcmp(a, "--cache-mb") && has)
            cache_mb = atol(argv[++i]);
        else if (!strcmp(a, "--output-dir") && has)
            outdir = argv[++i];
        else if (!strcmp(a, "--mem-limit") && has)
            mem_limit = argv[++i];
        else if (!strcmp(a, "--stats"))
            stats = 1;
        else if (!strcmp(a, "--no-previews"))
            no_previews = 1;
        else if (!strcmp(a, "--serial"))
            serial = 1;
        else if (!strcmp(a, "--no-pool"))
            no_pool = 1;
        else if (!strcmp(a, "--keep-going"))
            keep_going = 1;
        else if (!strcmp(a, "--wait"))
            wait = 1;
        else if (!strcmp(a, "--check"))
            check = 1;
        else if (!strcmp(a, "--shared-lock"))
            shared_lock = 1;
        else if (!strcmp(a, "--quiet") || !strcmp(a, "-q"))
            quiet = 1;
        else if (a[0] != '-' && ngraphs < 64)
            graphs[ngraphs++] = a;
        else if (ext && ext->option &&
                 (took = ext->option(ext->user, a, has ? argv[i + 1] : NULL)) > 0)
            i += took - 1;
        else {
            fprintf(stderr, "%s: unexpected argument '%s'\n\n", label, a);
            if (analyze)
                usage_analyze(stderr, prog);
            else
                usage(stderr, prog, ext);
            return 2;
        }
    }
    if (!ngraphs) {
        if (analyze)
            usage_analyze(stderr, prog);
        else
            usage(stderr, prog, ext);
        return 2;
    }
    if (cache_mb < 16) cache_mb = 16;
    if (mem_limit && cli_set_mem_limit(prog, analyze ? "analyze" : "run", mem_limit)) return 2;
    if (analyze && (frames || check || keep_going)) {
        fprintf(stderr, "%s: %s: it measures the whole shot and renders nothing (give --shot)\n",
                label,
                frames  ? "--frames"
                : check ? "--check"
                        : "--keep-going");
        return 2;
    }
    cli_env env;
    if (cli_env_init(&env, threads)) return 1;
    nprfx_graph_options opt = {sizeof opt, (size_t)cache_mb << 20, tile, outdir, NULL};
    opt.io = nprfx_io_oiio();
    opt.progress = !quiet;
    opt.no_pool = no_pool;
    opt.strip_rows = strip_rows;
    int status = 0;
    run_opts ro = {label, frames,       shot,     sets,        nsets,  keep_going,
                   quiet, ngraphs > 1,  wait,     stats,       check,  shared_lock,
                   aovs,  design_width, analysis, no_previews, serial, analyze};
    opt.notice = graph_notice;
    opt.notice_user = &ro;
    if (ext && ext->open && ext->open(ext->user, env.ctx, quiet, &opt.hook)) {
        fprintf(stderr, "%s: %s\n", label, cli_message(env.ctx));
        status = 2;
        goto done;
    }
    for (int i = 0; i < ngraphs; i++) {
        int st = run_graph(&env, &opt, graphs[i], &ro);
        if (st > status) status = st;
        if (st == 2 && ngraphs > 1)
            fprintf(stderr, "%s: %s: not %s\n", label, graphs[i],
                    analyze ? "analysed" : "rendered");
    }
done:
    if (ext && ext->close) ext->close(ext->user); /* after the graph, which releases the hook */
    cli_env_free(&env);
    return status;
}
