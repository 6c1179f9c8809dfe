/* nprfx host-project --natron-script: the graph as a Natron 2 Python script that builds the
 * project in the running Natron (Natron -t SCRIPT, or the Script Editor). Natron runs scripts
 * without __file__, so the script finds its folder from __file__ when there is one, else from
 * $NPRFX_SAMPLES or the current folder, by looking for the script file itself (a plate path may
 * be absolute, and then says nothing of where the script is). Params are set by script name with
 * the graph's values; inputs are connected by clip label. Every node's variable is n_ and its
 * name, so that no node (a "base", a "folder") takes the name of the script's own variables. */
#include <string.h>

#include "host_natron_py.h"
#include "host_project.h"
#include "ofx_names.h"

static void py_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        if (*s == '"' || *s == '\\') fputc('\\', f);
        fputc(*s, f);
    }
    fputc('"', f);
}

/* The parent folder's and the script folder's names: where the script sits below the samples. */
static void folder_names(const char *out_file, char *parent, char *dir, size_t n)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", out_file);
    char *s = strrchr(buf, '/');
    snprintf(dir, n, ".");
    snprintf(parent, n, ".");
    if (!s) return;
    *s = 0;
    s = strrchr(buf, '/');
    snprintf(dir, n, "%s", s ? s + 1 : buf);
    if (!s) return;
    *s = 0;
    s = strrchr(buf, '/');
    snprintf(parent, n, "%s", s ? s + 1 : buf);
}

static const char prelude[] =
    "import os\n\n"
    "import NatronEngine  # noqa: F401  (provided by Natron)\n\n\n"
    "def here():\n"
    "    \"\"\"The folder paths below are relative to: this script's.\"\"\"\n"
    "    try:\n"
    "        return os.path.dirname(os.path.abspath(__file__))\n"
    "    except NameError:  # Natron runs scripts without __file__\n"
    "        pass\n"
    "    tries = []\n"
    "    if os.environ.get(\"NPRFX_SAMPLES\"):\n"
    "        tries.append(os.path.join(os.environ[\"NPRFX_SAMPLES\"], SCRIPT_DIR))\n"
    "    tries += [os.path.join(os.getcwd(), SAMPLES_DIR, SCRIPT_DIR),\n"
    "              os.path.join(os.getcwd(), SCRIPT_DIR), os.getcwd()]\n"
    "    for t in tries:\n"
    "        if os.path.exists(os.path.join(t, SCRIPT_FILE)):\n"
    "            return t\n"
    "    print(\"nprfx: %s not found in %s; paths are taken from the current folder (set \"\n"
    "          \"NPRFX_SAMPLES to the folder above the script's)\" % (SCRIPT_FILE, tries))\n"
    "    return os.getcwd()\n\n\n"
    "def choose(param, *labels):\n"
    "    \"\"\"Set a choice param to the first option called one of labels (or ending with\n"
    "    it).\"\"\"\n"
    "    options = [param.getOption(i) for i in range(param.getNumOptions())]\n"
    "    for label in labels:\n"
    "        for i, o in enumerate(options):\n"
    "            if o == label or o.endswith(\".\" + label):\n"
    "                param.setValue(i)\n"
    "                return\n"
    "    print(\"nprfx: %s has no option %s among %s\" % (param.getScriptName(), \" or "
    "\".join(labels),\n"
    "                                                 options))\n\n\n"
    "def connect(node, label, src):\n"
    "    \"\"\"Connect src to the input whose label is label (the clip's).\"\"\"\n"
    "    for i in range(node.getMaxInputCount()):\n"
    "        if node.getInputLabel(i) == label:\n"
    "            node.connectInput(i, src)\n"
    "            return\n"
    "    print(\"nprfx: %s has no input %s\" % (node.getScriptName(), label))\n\n\n"
    "def create(app, plugin, name):\n"
    "    node = app.createNode(plugin)\n"
    "    node.setScriptName(name)\n"
    "    return node\n\n\n";

static void param_line(FILE *f, const nprfx_graph_node_info *n, const char *var, int i)
{
    const nprfx_param_desc *p = &n->desc->params[i];
    const nprfx_value *v = &n->params[i];
    char a[64], b[64], c[64], d[64];
    fprintf(f, "    ");
    switch (p->type) {
    case NPRFX_PARAM_DOUBLE:
        /* a float literal for a double param, also for whole numbers */
        host_double(v->v[0], a, sizeof a);
        if (!strpbrk(a, ".eni")) strcat(a, ".0");
        fprintf(f, "n_%s.getParam(\"%s\").setValue(%s)\n", var, p->name, a);
        break;
    case NPRFX_PARAM_INT:
        fprintf(f, "n_%s.getParam(\"%s\").setValue(%d)\n", var, p->name, (int)v->v[0]);
        break;
    case NPRFX_PARAM_BOOL:
        fprintf(f, "n_%s.getParam(\"%s\").setValue(%s)\n", var, p->name,
                v->v[0] != 0 ? "True" : "False");
        break;
    case NPRFX_PARAM_CHOICE:
        fprintf(f, "choose(n_%s.getParam(\"%s\"), \"%s\")\n", var, p->name,
                p->choices[(int)v->v[0]]);
        break;
    case NPRFX_PARAM_COLOR:
        fprintf(f, "n_%s.getParam(\"%s\").set(%s, %s, %s, %s)\n", var, p->name,
                host_double(v->v[0], a, sizeof a), host_double(v->v[1], b, sizeof b),
                host_double(v->v[2], c, sizeof c), host_double(v->v[3], d, sizeof d));
        break;
    case NPRFX_PARAM_STRING:
        fprintf(f, "n_%s.getParam(\"%s\").setValue(", var, p->name);
        py_string(f, v->s ? v->s : "");
        fprintf(f, ")\n");
        break;
    }
}

nprfx_result host_write_natron_py(const host_project *hp, FILE *f, const char *out_file)
{
    char parent[4096], dir[4096];
    folder_names(out_file, parent, dir, sizeof dir);
    const char *script_file = strrchr(out_file, '/') ? strrchr(out_file, '/') + 1 : out_file;
    fprintf(f, "# Generated by `nprfx host-project %s` from the graph: do not edit, regenerate.\n",
            hp->graph_path);
    fprintf(f,
            "# Builds the graph in Natron 2 from the nprfx OpenFX plug-ins:\n"
            "#   OFX_PLUGIN_PATH=build/plugins/ofx Natron -t %s\n",
            out_file);
    if (!hp->look_nodes)
        fprintf(f, "# OpenFX clips carry RGBA only: each set of plate channels a node reads is "
                   "shuffled\n# into RGBA and the node's <input>Channels selector picks them.\n");
    else if (hp->nsets)
        fprintf(f, "# Each AOV a look reads comes through its own clip, shuffled from the Read "
                   "into RGBA.\n");
    else
        fprintf(f, "# Each look takes the Read whole on its Source and finds the layers it "
                   "reads (its layer\n# menus show which, after Find AOV Layers).\n");
    fprintf(f, "\n");
    /* Natron 2.5's renderer can stall at 0 % CPU with several writers at once, its threads in
     * waitForImageBeingRenderedElsewhere (the host's own: seen with stock nodes alone, Natron
     * issues 248 and 811); each writer alone renders. */
    if (hp->nwrites > 1) {
        fprintf(f, "# Render one writer at a time (NatronRenderer 2.5 can stall with several at "
                   "once):\n");
        for (int i = 0; i < hp->nwrites; i++)
            fprintf(f, "#   NatronRenderer -w %s %d-%d PROJECT.ntp\n", hp->writes[i].name,
                    hp->first_frame, hp->last_frame);
        fprintf(f, "\n");
    }
    fprintf(f, "SAMPLES_DIR = ");
    py_string(f, parent);
    fprintf(f, "\nSCRIPT_DIR = ");
    py_string(f, dir);
    fprintf(f, "\nSCRIPT_FILE = ");
    py_string(f, script_file);
    fprintf(f, "\n\n%s", prelude);
    fprintf(f, "def build(app):\n    folder = here()\n");
    fprintf(f, "    app.getProjectParam(\"frameRange\").set(%d, %d)\n", hp->first_frame,
            hp->last_frame);
    fprintf(f, "    app.addFormat(\"%s %dx%d 1\")\n", hp->format_name, hp->width, hp->height);
    fprintf(f, "    choose(app.getProjectParam(\"outputFormat\"), \"%s\")\n", hp->format_name);
    for (int i = 0; i < hp->nreads; i++) {
        fprintf(f, "    n_%s = app.createReader(os.path.join(folder, ", hp->reads[i].name);
        py_string(f, hp->reads[i].path);
        fprintf(f, "))\n    n_%s.setScriptName(\"%s\")\n", hp->reads[i].name, hp->reads[i].name);
    }
    for (int i = 0; i < hp->nsets; i++) {
        const host_chanset *cs = &hp->sets[i];
        const char *rname = NULL;
        for (int r = 0; r < hp->nreads; r++)
            if (hp->reads[r].n == &hp->info[cs->read]) rname = hp->reads[r].name;
        fprintf(f, "    n_%s = create(app, \"net.sf.openfx.ShufflePlugin\", \"%s\")\n", cs->shuffle,
                cs->shuffle);
        fprintf(f, "    n_%s.connectInput(0, n_%s)\n", cs->shuffle, rname);
        static const char *const outs[4] = {"outputR", "outputG", "outputB", "outputA"};
        for (int c = 0; c < cs->count; c++) {
            char option[160];
            host_natron_option(cs->chan[c], option, sizeof option);
            /* the A input's option by its full name ("A.r" is not "B.r"), else by suffix */
            fprintf(f, "    choose(n_%s.getParam(\"%s\"), \"%s\", \"%s\")\n", cs->shuffle, outs[c],
                    option, cs->chan[c]);
        }
        if (!cs->has_sign) continue;
        char s[4][64];
        for (int c = 0; c < 4; c++)
            host_double(c < cs->count ? cs->sign[c] : 1, s[c], sizeof s[c]);
        fprintf(f, "    # the runner's vectors convention: ");
        for (int c = 0; c < cs->count; c++)
            fprintf(f, "%s%s = %s * %s", c ? ", " : "", cs->want[c], s[c], cs->chan[c]);
        fprintf(f, "\n    n_%s = create(app, \"net.sf.openfx.MultiplyPlugin\", \"%s\")\n",
                cs->multiply, cs->multiply);
        fprintf(f, "    n_%s.connectInput(0, n_%s)\n", cs->multiply, cs->shuffle);
        fprintf(f, "    n_%s.getParam(\"value\").set(%s, %s, %s, %s)\n", cs->multiply, s[0], s[1],
                s[2], s[3]);
        if (cs->count > 3 && cs->sign[3] != 1)
            fprintf(f, "    n_%s.getParam(\"a\").setValue(True)\n", cs->multiply);
    }
    for (int i = 0; i < hp->nnodes; i++) {
        const host_node *hn = &hp->nodes[i];
        const nprfx_graph_node_info *n = hn->n;
        const nprfx_node_desc *d = n->desc;
        fprintf(f, "    n_%s = create(app, \"%s\", \"%s\")\n", hn->name, hn->plugin_id, hn->name);
        for (int c = 0; c < hn->nclips; c++) {
            int k = hn->clips[c];
            if (!hn->links[k].src) continue;
            char clip[NPRFX_OFX_NAME_MAX], sel[NPRFX_OFX_NAME_MAX];
            ofx_names_clip_name(d, k, clip, sizeof clip);
            ofx_names_selector_name(d, k, sel, sizeof sel);
            fprintf(f, "    connect(n_%s, \"%s\", n_%s)\n", hn->name,
                    d->inputs[k].label ? d->inputs[k].label : clip, hn->links[k].src);
            if (!hn->look) /* a look's clips carry their AOVs whole */
                fprintf(f, "    choose(n_%s.getParam(\"%s\"), \"%s\")\n", hn->name, sel,
                        hn->links[k].label);
        }
        for (int p = 0; p < d->num_params; p++)
            if (host_param_changed(n, p)) param_line(f, n, hn->name, p);
        if (host_design_width(hp, d) > 0) {
            char name[NPRFX_OFX_NAME_MAX];
            ofx_names_extra_param(d, "designWidth", name, sizeof name);
            fprintf(f, "    n_%s.getParam(\"%s\").setValue(%d)\n", hn->name, name,
                    host_design_width(hp, d));
        }
    }
    for (int i = 0; i < hp->nwrites; i++) {
        const host_write *w = &hp->writes[i];
        fprintf(f, "    n_%s = app.createWriter(", w->name);
        if (w->path[0] == '/')
            py_string(f, w->path);
        else {
            fprintf(f, "os.path.join(folder, ");
            py_string(f, w->path);
            fprintf(f, ")");
        }
        fprintf(f, ")\n    n_%s.setScriptName(\"%s\")\n", w->name, w->name);
        fprintf(f, "    n_%s.connectInput(0, n_%s)\n", w->name, w->src);
        /* Natron 2.5 names the option "input", earlier versions by its label */
        fprintf(f,
                "    choose(n_%s.getParam(\"formatType\"), \"input\", \"Input Stream Format\")\n",
                w->name);
    }
    fprintf(f, "    # PNG previews are left to the runner (nprfx run): they go through its display "
               "transform\n\n\n");
    fprintf(f, "build(app)  # noqa: F821  (`app` is the project Natron runs the script in)\n");
    return ferror(f) ? nprfx_error(nprfx_graph_context(hp->g), NPRFX_ERR_IO, "write error")
                     : NPRFX_OK;
}
