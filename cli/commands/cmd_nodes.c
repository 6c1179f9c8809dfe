/* nprfx list / help / docs — everything printed here is generated from the node descriptors. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "look_desc.h"
#include "nprfx/graph.h"
#include "nprfx/io_oiio.h"
#include "nprfx/nprfx.h"
#include "util/cli_util.h"

/* Print text wrapped at `width` columns, each line indented by `indent`; blank lines in the
 * text separate paragraphs; lines starting with two spaces are kept verbatim (formulas). */
static void print_wrapped(FILE *f, const char *text, int indent, int width)
{
    const char *s = text;
    while (*s) {
        const char *eol = strchr(s, '\n');
        size_t len = eol ? (size_t)(eol - s) : strlen(s);
        if (len == 0) {
            fputc('\n', f);
        } else if (len >= 2 && s[0] == ' ' && s[1] == ' ') {
            fprintf(f, "%*s%.*s\n", indent, "", (int)len, s);
        } else {
            int col = 0;
            const char *w = s, *end = s + len;
            while (w < end) {
                while (w < end && *w == ' ')
                    w++;
                const char *we = w;
                while (we < end && *we != ' ')
                    we++;
                int wl = (int)(we - w);
                if (wl == 0) break;
                if (col > 0 && col + 1 + wl > width - indent) {
                    fputc('\n', f);
                    col = 0;
                }
                if (col == 0)
                    fprintf(f, "%*s%.*s", indent, "", wl, w);
                else
                    fprintf(f, " %.*s", wl, w);
                col += (col ? 1 : 0) + wl;
                w = we;
            }
            fputc('\n', f);
        }
        s += len;
        if (*s == '\n') s++;
    }
}

/* Markdown table cell: '|' would end the cell, newlines the row. */
static void md_cell(FILE *f, const char *text)
{
    for (const char *c = text ? text : ""; *c; c++) {
        if (*c == '|')
            fputs("\\|", f);
        else if (*c == '\n')
            fputs("<br>", f);
        else
            fputc(*c, f);
    }
}

/* Markdown: paragraphs as they are, runs of verbatim lines (two leading spaces) fenced. */
static void print_markdown(FILE *f, const char *text)
{
    int in_code = 0;
    for (const char *s = text; *s;) {
        const char *eol = strchr(s, '\n');
        size_t len = eol ? (size_t)(eol - s) : strlen(s);
        int verbatim = len >= 2 && s[0] == ' ' && s[1] == ' ';
        if (verbatim != in_code) {
            fprintf(f, in_code ? "```\n" : "\n```\n");
            in_code = verbatim;
        }
        fprintf(f, "%.*s\n", (int)len, s);
        s += len;
        if (*s == '\n') s++;
    }
    if (in_code) fprintf(f, "```\n");
}

static void range_text(const nprfx_param_desc *p, char *buf, size_t n)
{
    buf[0] = 0;
    if (p->type == NPRFX_PARAM_DOUBLE || p->type == NPRFX_PARAM_INT ||
        p->type == NPRFX_PARAM_COLOR) {
        if (p->soft_min != p->hard_min || p->soft_max != p->hard_max)
            snprintf(buf, n, "range [%.10g, %.10g], sliders [%.10g, %.10g]", p->hard_min,
                     p->hard_max, p->soft_min, p->soft_max);
        else
            snprintf(buf, n, "range [%.10g, %.10g]", p->hard_min, p->hard_max);
    }
}

static void input_channels_text(const nprfx_input_desc *in, char *buf, size_t n)
{
    if (in->channels > 0)
        snprintf(buf, n, "%d channel%s", in->channels, in->channels > 1 ? "s" : "");
    else
        snprintf(buf, n, "1-4 channels");
}

/* One node's reference, as plain text (help) or Markdown (docs). */
static void print_node(FILE *f, const nprfx_node_desc *d, int md)
{
    char buf[512], rng[160], def[160];
    nprfx_value *defs = calloc((size_t)(d->num_params ? d->num_params : 1), sizeof *defs);
    if (defs) nprfx_node_defaults(d, defs);
    if (md)
        fprintf(f, "## %s — %s\n\n", d->id, d->label);
    else
        fprintf(f, "%s — %s (group %s)\n\n", d->id, d->label, d->group);
    if (md)
        print_markdown(f, d->help);
    else
        print_wrapped(f, d->help, 2, 96);
    /* NPRFX_NODE_ROWS: what lets `nprfx run` render a frame by strips (docs/design.md §1). */
    if (d->flags & NPRFX_NODE_ROWS) {
        const char *rows = "Renders by rows: the runner can render a frame through it a strip of "
                           "rows at a time, in bounded memory (`nprfx run --strip-rows`).";
        if (md) {
            fprintf(f, "\n%s\n", rows);
        } else {
            fputc('\n', f);
            print_wrapped(f, rows, 2, 96);
        }
    }
    fprintf(f, md ? "\n### Inputs\n\n| input | channels | looks for | |\n|---|---|---|---|\n"
                  : "\nInputs:\n");
    for (int i = 0; i < d->num_inputs; i++) {
        const nprfx_input_desc *in = &d->inputs[i];
        input_channels_text(in, buf, sizeof buf);
        const char *req = (in->flags & NPRFX_INPUT_OPTIONAL) ? "optional" : "required";
        if (md) {
            fprintf(f, "| `%s` | %s, %s%s | ", in->name, buf, req,
                    (in->flags & NPRFX_INPUT_TEMPORAL) ? ", other frames" : "");
            md_cell(f, in->aov ? in->aov : "(as connected)");
            fputs(" | ", f);
            md_cell(f, in->help);
            fputs(" |\n", f);
        } else {
            fprintf(f, "  %-12s %s, %s%s\n", in->name, buf, req,
                    (in->flags & NPRFX_INPUT_TEMPORAL) ? ", fetched at other frames" : "");
            if (in->aov) fprintf(f, "  %-12s looks for: %s\n", "", in->aov);
            if (in->help) print_wrapped(f, in->help, 15, 96);
        }
    }
    fprintf(f, md ? "\n### Params\n\n| param | type | default | range | |\n|---|---|---|---|---|\n"
                  : "\nParams:\n");
    for (int i = 0; i < d->num_params; i++) {
        const nprfx_param_desc *p = &d->params[i];
        range_text(p, rng, sizeof rng);
        nprfx_param_format(p, &defs[i], def, sizeof def);
        if (p->type == NPRFX_PARAM_CHOICE) {
            buf[0] = 0;
            for (int c = 0; p->choices[c]; c++) {
                if (c) strncat(buf, " | ", sizeof buf - strlen(buf) - 1);
                strncat(buf, p->choices[c], sizeof buf - strlen(buf) - 1);
            }
            snprintf(rng, sizeof rng, "%s", buf);
        }
        const char *unit = (p->flags & NPRFX_PARAM_PIXELS) ? " (pixels)"
                           : (p->flags & NPRFX_PARAM_AREA) ? " (pixels²)"
                                                           : "";
        if (md) {
            fprintf(f, "| `%s` | %s%s | `%s` | ", p->name, nprfx_param_type_name(p->type), unit,
                    def);
            md_cell(f, rng);
            fputs(" | ", f);
            md_cell(f, p->help);
            for (int c = 0; p->type == NPRFX_PARAM_CHOICE && p->choice_help && p->choices[c]; c++) {
                fprintf(f, "<br>`%s`: ", p->choices[c]);
                md_cell(f, p->choice_help[c]);
            }
            fprintf(f, " |\n");
        } else {
            fprintf(f, "  %-12s %s%s, default %s%s%s\n", p->name, nprfx_param_type_name(p->type),
                    unit, def, rng[0] ? "; " : "", rng);
            if (p->help) print_wrapped(f, p->help, 15, 96);
            for (int c = 0; p->type == NPRFX_PARAM_CHOICE && p->choice_help && p->choices[c]; c++) {
                fprintf(f, "%15s%s:\n", "", p->choices[c]);
                print_wrapped(f, p->choice_help[c], 19, 96);
            }
        }
    }
    fputc('\n', f);
    free(defs);
}

int cli_cmd_list(int argc, char **argv)
{
    if (argc > 1 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        printf("usage: nprfx list\n\nLists every node: id, group and the first line of its help.\n"
               "Graph files name nodes by id; 'nprfx help ID' documents one.\n");
        return 0;
    }
    for (int i = 0; i < nprfx_node_count(); i++) {
        const nprfx_node_desc *d = nprfx_node_at(i);
        const char *eol = strchr(d->help, '\n');
        int len = eol ? (int)(eol - d->help) : (int)strlen(d->help);
        const char *dot = memchr(d->help, '.', (size_t)len);
        if (dot) len = (int)(dot - d->help) + 1;
        printf("%-16s %-6s %.*s\n", d->id, d->group, len, d->help);
    }
    printf("%-16s %-6s %s\n", "read", "I/O", "Read an image sequence (graph files only).");
    printf("%-16s %-6s %s\n", "write", "I/O",
           "Write an EXR sequence and PNG previews (graph files only).");
    return 0;
}

/* A graph file's help: its comment, its shot, and its knobs (the params worth turning) with
 * their values there, types, ranges and help from the descriptors. */
static int print_graph(const char *path)
{
    cli_env env;
    if (cli_env_init(&env, 1)) return 1;
    nprfx_graph_options opt = {sizeof opt, 0, 0, NULL, NULL};
    opt.io = nprfx_io_oiio();
    nprfx_graph *g = NULL;
    if (nprfx_graph_load(env.ctx, path, &opt, &g)) {
        fprintf(stderr, "nprfx help: %s\n", cli_message(env.ctx));
        cli_env_free(&env);
        return 2;
    }
    printf("%s\n", path);
    const char *comment = nprfx_graph_comment(g);
    if (comment) print_wrapped(stdout, comment, 2, 96);
    int first, last;
    if (nprfx_graph_shot(g, &first, &last)) printf("\nShot: frames %d-%d", first, last);
    if (nprfx_graph_design_width(g) > 0)
        printf("; params set for plates %g pixels wide", nprfx_graph_design_width(g));
    printf("\n\nKnobs (set with 'nprfx run %s --set KNOB=VALUE'):\n", path);
    if (!nprfx_graph_knob_count(g)) printf("  none listed (\"knobs\" in the graph file)\n");
    for (int i = 0; i < nprfx_graph_knob_count(g); i++) {
        nprfx_graph_knob_info k = {sizeof k};
        if (nprfx_graph_knob(g, i, &k)) continue;
        char val[256], rng[256];
        nprfx_param_format(k.param, k.value, val, sizeof val);
        range_text(k.param, rng, sizeof rng);
        printf("  %-24s %s, %s%s%s", k.name, nprfx_param_type_name(k.param->type), val,
               rng[0] ? "; " : "", rng);
        if (k.nodes > 1) printf(" (%d nodes)", k.nodes);
        printf("\n");
        if (k.help) print_wrapped(stdout, k.help, 27, 96);
        if (k.param->help) print_wrapped(stdout, k.param->help, 27, 96);
    }
    /* the same graph as one effect in compositing hosts (look_desc.h) */
    char stem[256], why[1024] = "";
    const char *leaf = strrchr(path, '/');
    snprintf(stem, sizeof stem, "%s", leaf ? leaf + 1 : path);
    if (strlen(stem) > 5) stem[strlen(stem) - 5] = 0; /* ".json" */
    look_desc *ld = calloc(1, sizeof *ld);
    if (ld && look_desc_build(g, stem, ld, why, sizeof why) == NPRFX_OK) {
        printf("\nIn compositing hosts: NPR/Looks > %s (%s), one node:\n    clips:", ld->label,
               ld->id);
        for (int k = 0; k < ld->desc.num_inputs; k++)
            printf(" %s%s", ld->clip[k], look_desc_has_clip(ld, k, 1) ? "" : "*");
        printf("\n    (* a clip only in hosts without layers; with layers, Source carries it)\n"
               "    params:");
        for (int p = 0; p < ld->desc.num_params; p++)
            printf(" %s", ld->params[p].name);
        /* what multi-plane hosts add: which layer feeds each AOV */
        printf("\n    with layers also: %s %s %s", LOOK_PARAM_RENDERER, LOOK_PARAM_FIND_LAYERS,
               LOOK_PARAM_AOV_LAYERS);
        for (int k = 0; k < ld->desc.num_inputs; k++) {
            char name[64];
            if (look_desc_layer_aov(ld, k) < 0) continue;
            look_desc_layer_name(look_desc_layer_aov(ld, k), name, sizeof name);
            printf(" %s", name);
        }
        printf("\n");
    } else if (ld) {
        printf("\nNot a look for compositing hosts: %s\n", why);
    }
    if (ld) look_desc_free(ld);
    free(ld);
    nprfx_graph_free(g);
    cli_env_free(&env);
    return 0;
}

int cli_cmd_help(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        printf("usage: nprfx help NODE\n       nprfx help GRAPH.json\n\nDocuments a node: what "
               "it does, its inputs with the AOV channels it looks for, and every param with its "
               "type, default and range ('nprfx list' lists the nodes). Or a graph file: what it "
               "makes, its shot, and its knobs, the params worth turning, with their values "
               "there and their ranges.\n");
        return argc < 2 ? 2 : 0;
    }
    const nprfx_node_desc *d = nprfx_node_find(argv[1]);
    size_t len = strlen(argv[1]);
    if (!d && len > 5 && !strcmp(argv[1] + len - 5, ".json")) return print_graph(argv[1]);
    if (!d) {
        fprintf(stderr, "nprfx help: unknown node '%s' (nprfx list shows the nodes)\n", argv[1]);
        return 2;
    }
    print_node(stdout, d, 0);
    return 0;
}

int cli_cmd_docs(int argc, char **argv)
{
    const char *out = NULL;
    for (int i = 1; i < argc; i++) {
        if ((!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) && i + 1 < argc)
            out = argv[++i];
        else {
            printf("usage: nprfx docs [-o FILE]\n\nWrites the node reference in Markdown, "
                   "generated from the node descriptors (docs/nodes.md is made this way).\n");
            return strcmp(argv[i], "--help") ? 2 : 0;
        }
    }
    FILE *f = out ? fopen(out, "w") : stdout;
    if (!f) {
        fprintf(stderr, "nprfx docs: cannot write '%s'\n", out);
        return 4;
    }
    fprintf(f, "# nprfx node reference\n\nGenerated by `nprfx docs -o docs/nodes.md` from the node "
               "descriptors in plugins/; do not edit by hand.\n\n");
    for (int i = 0; i < nprfx_node_count(); i++)
        print_node(f, nprfx_node_at(i), 1);
    if (out && fclose(f) != 0) {
        fprintf(stderr, "nprfx docs: error writing '%s'\n", out);
        return 4;
    }
    return 0;
}
