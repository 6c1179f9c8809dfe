/* nprfx host-project — write a graph as compositing-host files (a Natron project, a Natron
 * script, a Nuke script) from the graph itself, so they say what `nprfx run` renders. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/io_oiio.h"
#include "commands.h"
#include "nprfx/graph.h"
#include "host/host_natron.h"
#include "host/host_natron_py.h"
#include "host/host_nuke.h"
#include "host/host_project.h"
#include "util/cli_util.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: nprfx host-project GRAPH.json [--natron OUT.ntp] [--natron-script OUT.py]\n"
            "                          [--nuke OUT.nk] [--set NODE.PARAM=VALUE ...]\n"
            "                          [--look | --look-clips]\n\n"
            "Writes the graph for compositing hosts, built from the nprfx OpenFX plug-ins:\n"
            "  --natron OUT.ntp         a Natron 2 project\n"
            "  --natron-script OUT.py   a Natron 2 Python script that builds the same project\n"
            "                           (Natron -t OUT.py; it finds its folder without __file__\n"
            "                           through $NPRFX_SAMPLES or the current folder)\n"
            "  --nuke OUT.nk            a Nuke script\n"
            "  --set NODE.PARAM=VALUE   change a param first, as 'nprfx run --set' does\n"
            "  --look                   the graph as its look plug-in (NPR/Looks: one effect per\n"
            "                           graph file in the bundle's looks or NPRFX_LOOK_PATH):\n"
            "                           a Read of the multilayer plates into the look's Source\n"
            "                           and one look node per write node, its knobs set where\n"
            "                           --set changed them (hosts with layers: Natron, Nuke)\n"
            "  --look-clips             the same for hosts without layers: a Shuffle of each AOV\n"
            "                           the look reads into its own clip\n\n"
            "The graph is read as 'nprfx run' reads it, and each plate's first frame header\n"
            "gives its channels: every node input becomes a Shuffle of the exact channels the\n"
            "runner reads into RGBA (then a Multiply where the read node's \"vectors\" flips\n"
            "signs), connected to the node's clip with its <input>Channels selector set; every\n"
            "param that differs from its default is set to the graph's value; the project's\n"
            "frames are the graph's and its format the first plate's size. Read paths are\n"
            "written relative to the output file, write paths as in the graph (from the\n"
            "project's folder). PNG previews are left to the runner.\n\n"
            "Hosts cannot express synth plates, inputs or outputs of more than 4 channels, or\n"
            "channels a selector cannot pick: those are errors naming the node.\n\n"
            "Example (the samples in samples/hosts are written so):\n"
            "  nprfx host-project samples/graphs/main.json --natron "
            "samples/hosts/nprfx_crossing.ntp \\\n"
            "      --natron-script samples/hosts/nprfx_crossing_natron.py \\\n"
            "      --nuke samples/hosts/nprfx_crossing.nk\n");
}

typedef enum { OUT_NATRON, OUT_NATRON_PY, OUT_NUKE } out_kind;

/* Write one host file through a temporary name and a rename: never a half-written file. */
static int write_one(nprfx_graph *g, const char *graph, out_kind kind, const char *path,
                     const look_desc *look, int planar, cli_env *env)
{
    char dir[4096], tmp[4200];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash)
        *slash = 0;
    else
        snprintf(dir, sizeof dir, ".");
    host_project hp;
    if (host_project_build(g, graph, dir, path, look, planar, &hp)) {
        fprintf(stderr, "nprfx host-project: %s\n", cli_message(env->ctx));
        return 2;
    }
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f) {
        fprintf(stderr, "nprfx host-project: cannot write %s\n", tmp);
        host_project_free(&hp);
        return 2;
    }
    nprfx_result r = kind == OUT_NATRON      ? host_write_natron(&hp, f)
                     : kind == OUT_NATRON_PY ? host_write_natron_py(&hp, f, path)
                                             : host_write_nuke(&hp, f);
    host_project_free(&hp);
    if (fclose(f) || r || rename(tmp, path)) {
        if (r)
            fprintf(stderr, "nprfx host-project: %s\n", cli_message(env->ctx));
        else
            fprintf(stderr, "nprfx host-project: cannot write %s\n", path);
        remove(tmp);
        return 2;
    }
    return 0;
}

int cli_cmd_host_project(int argc, char **argv)
{
    const char *graph = NULL, *outs[3] = {NULL, NULL, NULL};
    const char *sets[256];
    int nsets = 0, look = 0, planar = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--natron") && has)
            outs[OUT_NATRON] = argv[++i];
        else if (!strcmp(a, "--natron-script") && has)
            outs[OUT_NATRON_PY] = argv[++i];
        else if (!strcmp(a, "--nuke") && has)
            outs[OUT_NUKE] = argv[++i];
        else if (!strcmp(a, "--set") && has && nsets < 256)
            sets[nsets++] = argv[++i];
        else if (!strcmp(a, "--look"))
            look = planar = 1;
        else if (!strcmp(a, "--look-clips"))
            look = 1, planar = 0;
        else if (a[0] != '-' && !graph)
            graph = a;
        else {
            fprintf(stderr, "nprfx host-project: unexpected argument '%s'\n\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!graph || (!outs[0] && !outs[1] && !outs[2])) {
        fprintf(stderr, "nprfx host-project: %s\n\n",
                graph ? "name at least one output (--natron, --natron-script, --nuke)"
                      : "which graph?");
        usage(stderr);
        return 2;
    }
    cli_env env;
    if (cli_env_init(&env, 1)) return 1;
    nprfx_graph_options opt = {sizeof opt, 0, 0, NULL, NULL};
    opt.io = nprfx_io_oiio();
    nprfx_graph *g = NULL;
    int status = 0;
    if (nprfx_graph_load(env.ctx, graph, &opt, &g)) {
        fprintf(stderr, "nprfx host-project: %s\n", cli_message(env.ctx));
        status = 2;
    }
    /* the look: the graph file's (its defaults), before --set changes the knobs' values */
    look_desc *ld = look ? calloc(1, sizeof *ld) : NULL;
    if (look && !status) {
        char stem[256], why[1024] = "";
        const char *leaf = strrchr(graph, '/');
        snprintf(stem, sizeof stem, "%s", leaf ? leaf + 1 : graph);
        char *dot = strrchr(stem, '.');
        if (dot && !strcmp(dot, ".json")) *dot = 0;
        if (!ld || look_desc_build(g, stem, ld, why, sizeof why)) {
            fprintf(stderr, "nprfx host-project: %s is no look: %s\n", graph,
                    ld ? why : "out of memory");
            status = 2;
        }
    }
    for (int i = 0; !status && i < nsets; i++)
        if (nprfx_graph_set(g, sets[i])) {
            fprintf(stderr, "nprfx host-project: %s\n", cli_message(env.ctx));
            status = 2;
        }
    if (ld && !status) look_desc_values(ld, g);
    for (int k = 0; !status && k < 3; k++)
        if (outs[k]) status = write_one(g, graph, (out_kind)k, outs[k], ld, planar, &env);
    if (ld) look_desc_free(ld);
    free(ld);
    nprfx_graph_free(g);
    cli_env_free(&env);
    return status;
}
