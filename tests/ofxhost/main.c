/* nprfx-ofxtest — the OpenFX test host's command line: `nprfx-ofxtest run GRAPH.json --ofx BUNDLE
 * [options of nprfx run]` is the runner's own run command (cli/commands/cmd_run.c, from the
 * nprfx_runner library) with a render hook that drives every node through the plug-ins of BUNDLE,
 * so the two programs differ only in how nodes render (tests/cli/ofx.sh requires the same pixels).
 * A test program, kept out of the shipped runner and never installed. */
#include <stdio.h>
#include <string.h>

#include "commands/commands.h"
#include "ofx_host.h"
#include "ofx_host_internal.h"

typedef struct ofx_run {
    const char *bundle;  /* --ofx */
    const char *profile; /* --profile */
    int footage;         /* --footage */
    int analyze;         /* --analyze-shot */
    nprfx_ofx_host *host;
} ofx_run;

static int ofx_option(void *user, const char *arg, const char *next)
{
    ofx_run *o = user;
    if (!strcmp(arg, "--footage")) {
        o->footage = 1;
        return 1;
    }
    if (!strcmp(arg, "--analyze-shot")) {
        o->analyze = 1;
        return 1;
    }
    if (!next) return 0;
    if (!strcmp(arg, "--ofx"))
        o->bundle = next;
    else if (!strcmp(arg, "--profile"))
        o->profile = next;
    else
        return 0;
    return 2;
}

static nprfx_result ofx_open(void *user, nprfx_context *ctx, int quiet,
                             const nprfx_render_hook **hook)
{
    ofx_run *o = user;
    if (!o->bundle)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "--ofx BUNDLE is required (e.g. build/plugins/ofx/nprfx.ofx.bundle)");
    nprfx_result r = nprfx_ofx_host_open(ctx, o->bundle, o->profile, &o->host);
    if (r) return r;
    nprfx_ofx_host_set_footage(o->host, o->footage);
    nprfx_ofx_host_set_analyze(o->host, o->analyze);
    *hook = nprfx_ofx_host_hook(o->host);
    if (quiet) return NPRFX_OK;
    int n = nprfx_ofx_host_plugin_count(o->host);
    fprintf(stderr, "ofx: %d plug-ins in %s (profile %s)\n", n, o->bundle,
            nprfx_ofx_host_profile(o->host));
    /* Once here rather than at each node that uses one: a graph may not use it at all. */
    for (int i = 0; i < n; i++) {
        const char *reason = "", *id = nprfx_ofx_host_unavailable(o->host, i, &reason);
        if (id) fprintf(stderr, "ofx: %s is not available in this host: %s\n", id, reason);
    }
    return NPRFX_OK;
}

static void ofx_close(void *user)
{
    ofx_run *o = user;
    nprfx_ofx_host_close(o->host); /* the runner calls this after freeing the graph */
    o->host = NULL;
}

static void usage(FILE *f)
{
    fprintf(f,
            "nprfx-ofxtest — the nprfx runner with every node rendered through the plug-ins of "
            "an OpenFX\nbundle, in a minimal test host\n\n"
            "usage: nprfx-ofxtest run GRAPH.json --ofx BUNDLE [--profile NAME] [options of nprfx "
            "run]\n"
            "       nprfx-ofxtest look GRAPH.json --ofx BUNDLE [--profile NAME] [--frames SPEC] "
            "[--scramble] [--analyze-shot] [--shot SPEC] [--set NODE.PARAM=VALUE]\n"
            "       [--channels R,G,B] [-o DIR]\n"
            "       (the look plug-in of GRAPH, its clips fed with GRAPH's plates' AOVs)\n\n"
            "'nprfx-ofxtest run --help' lists the options.\n");
}

int main(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (!strcmp(argv[1], "look")) return internal_look_main(argc - 1, argv + 1);
    if (strcmp(argv[1], "run")) {
        fprintf(stderr, "nprfx-ofxtest: unknown command '%s' (run or look)\n", argv[1]);
        return 2;
    }
    ofx_run o = {NULL, NULL, 0, 0, NULL};
    const cli_run_extension ext = {
        "nprfx-ofxtest",
        "  --ofx BUNDLE        render every node through the OpenFX plug-ins of BUNDLE\n"
        "                      (nprfx.ofx.bundle) in a minimal test host; same pixels (required)\n"
        "  --profile NAME      behave as this host does (tests/ofxhost/profile.c): strict (the\n"
        "                      default), natron (Natron 2.5), mlt (MLT 7, 8-bit), mlt16 (16-bit)\n"
        "  --footage           a node whose motion/confidence inputs come from a flow node\n"
        "                      renders in the Filter context on the picture that flow node\n"
        "                      reads (the plug-in derives them: footage in a Filter host)\n",
        ofx_option,
        ofx_open,
        ofx_close,
        &o};
    return cli_cmd_run_extended(argc - 1, argv + 1, &ext);
}
