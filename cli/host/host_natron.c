/* nprfx host-project --natron: the graph as a Natron 2 project (.ntp), a Boost XML archive laid
 * out as the projects NatronRenderer 2.5 loaded (samples/hosts/nprfx_crossing.ntp): every knob
 * with its value and default, choices by index and by label (Natron matches the label), inputs
 * by clip label. Boost numbers each serialized class the first time it appears (class_id), so
 * the writer tracks which classes it has written. */
#include <stdlib.h>
#include <string.h>

#include "host_natron.h"
#include "host_project.h"
#include "ofx_names.h"

/* The classes of the archive, numbered in order of first appearance. */
enum { C_NODE = 2, C_INPUTS, C_PAIR, C_USERCOMP, C_KNOB, C_VALUE, C_STRANIM, C_FORMATS = 9 };

/* Room for a formatted knob value (a file path at most). */
#define NTP_VAL 4224

typedef struct ntp {
    FILE *f;
    int seen[16];
} ntp;

/* ' class_id="N" tracking_level="0" version="V"' the first time class N is written, else "". */
static const char *cls(ntp *w, int id, int version)
{
    static char buf[96];
    if (w->seen[id]) return "";
    w->seen[id] = 1;
    snprintf(buf, sizeof buf, " class_id=\"%d\" tracking_level=\"0\" version=\"%d\"", id, version);
    return buf;
}

static void xml_text(FILE *f, const char *s)
{
    for (; *s; s++)
        if (*s == '<')
            fputs("&lt;", f);
        else if (*s == '>')
            fputs("&gt;", f);
        else if (*s == '&')
            fputs("&amp;", f);
        else if (*s == '"')
            fputs("&quot;", f);
        else
            fputc(*s, f);
}

/* A knob: `dims` values and defaults already formatted, a choice label or NULL. String-valued
 * knobs of the animating kinds (String, InputFile) carry an empty StringsAnimation. */
static void knob(ntp *w, const char *tabs, const char *name, const char *type, int secret, int dims,
                 char vals[][NTP_VAL], char defs[][NTP_VAL], const char *label)
{
    FILE *f = w->f;
    fprintf(f, "%s<item%s>\n", tabs, cls(w, C_KNOB, 14));
    fprintf(f, "%s\t<Name>%s</Name>\n%s\t<Type>%s</Type>\n", tabs, name, tabs, type);
    fprintf(f, "%s\t<Dimension>%d</Dimension>\n%s\t<Secret>%d</Secret>\n", tabs, dims, tabs,
            secret);
    fprintf(f, "%s\t<MasterIsAlias>0</MasterIsAlias>\n", tabs);
    for (int d = 0; d < dims; d++) {
        fprintf(f, "%s\t<item%s>\n", tabs, cls(w, C_VALUE, 7));
        fprintf(f, "%s\t\t<Enabled>1</Enabled>\n%s\t\t<HasAnimation>0</HasAnimation>\n", tabs,
                tabs);
        fprintf(f, "%s\t\t<Value>", tabs);
        xml_text(f, vals[d]);
        fprintf(f, "</Value>\n%s\t\t<Default>", tabs);
        xml_text(f, defs[d]);
        fprintf(f, "</Default>\n%s\t\t<HasMaster>0</HasMaster>\n", tabs);
        fprintf(f, "%s\t\t<Expression></Expression>\n%s\t\t<ExprHasRet>0</ExprHasRet>\n", tabs,
                tabs);
        fprintf(f, "%s\t</item>\n", tabs);
    }
    if (label) {
        fprintf(f, "%s\t<ChoiceLabel>", tabs);
        xml_text(f, label);
        fprintf(f, "</ChoiceLabel>\n");
    }
    if (!strcmp(type, "String") || !strcmp(type, "InputFile")) {
        fprintf(f, "%s\t<StringsAnimation%s>\n", tabs, cls(w, C_STRANIM, 0));
        fprintf(f, "%s\t\t<count>0</count>\n%s\t\t<item_version>0</item_version>\n", tabs, tabs);
        fprintf(f, "%s\t</StringsAnimation>\n", tabs);
    }
    fprintf(f, "%s\t<UserKnob>0</UserKnob>\n%s</item>\n", tabs, tabs);
}

/* One-dimensional knobs from plain values. */
static void knob1(ntp *w, const char *name, const char *type, int secret, const char *val,
                  const char *def, const char *label)
{
    char v[1][NTP_VAL], d[1][NTP_VAL];
    snprintf(v[0], sizeof v[0], "%s", val);
    snprintf(d[0], sizeof d[0], "%s", def);
    knob(w, "\t\t\t", name, type, secret, 1, v, d, label);
}

static void knob_int(ntp *w, const char *name, const char *type, int secret, int val, int def,
                     const char *label)
{
    char v[32], d[32];
    snprintf(v, sizeof v, "%d", val);
    snprintf(d, sizeof d, "%d", def);
    knob1(w, name, type, secret, v, d, label);
}

/* Doubles as Natron saves them: 17 significant digits, exponent form. */
static void fmt_double(char *buf, double v)
{
    snprintf(buf, NTP_VAL, "%.17e", v);
}

static void node_begin(ntp *w, const char *name, const char *plugin, int major, int minor,
                       int knobs)
{
    FILE *f = w->f;
    fprintf(f, "\t\t<item%s>\n", cls(w, C_NODE, 15));
    fprintf(f, "\t\t\t<Plugin_label>%s</Plugin_label>\n", name);
    fprintf(f, "\t\t\t<Plugin_script_name>%s</Plugin_script_name>\n", name);
    fprintf(f, "\t\t\t<Plugin_id>%s</Plugin_id>\n", plugin);
    fprintf(f, "\t\t\t<PythonModule></PythonModule>\n");
    fprintf(f, "\t\t\t<PythonModuleVersion>0</PythonModuleVersion>\n");
    fprintf(f, "\t\t\t<Plugin_major_version>%d</Plugin_major_version>\n", major);
    fprintf(f, "\t\t\t<Plugin_minor_version>%d</Plugin_minor_version>\n", minor);
    fprintf(f, "\t\t\t<KnobsCount>%d</KnobsCount>\n", knobs);
}

/* Inputs by label: labels[i] -> srcs[i] for the n connected ones. */
static void node_end(ntp *w, const char *name, const char *const *labels, const char *const *srcs,
                     int n, int knobs, int pages)
{
    FILE *f = w->f;
    fprintf(f, "\t\t\t<Inputs_map%s>\n", cls(w, C_INPUTS, 0));
    fprintf(f, "\t\t\t\t<count>%d</count>\n\t\t\t\t<item_version>0</item_version>\n", n);
    for (int i = 0; i < n; i++) {
        fprintf(f, "\t\t\t\t<item%s>\n", cls(w, C_PAIR, 0));
        fprintf(f, "\t\t\t\t\t<first>%s</first>\n\t\t\t\t\t<second>%s</second>\n", labels[i],
                srcs[i]);
        fprintf(f, "\t\t\t\t</item>\n");
    }
    fprintf(f, "\t\t\t</Inputs_map>\n\t\t\t<KnobsAge>%d</KnobsAge>\n", knobs);
    fprintf(f, "\t\t\t<MasterNode></MasterNode>\n\t\t\t<HasRotoContext>0</HasRotoContext>\n");
    fprintf(f, "\t\t\t<HasTrackerContext>0</HasTrackerContext>\n");
    fprintf(f, "\t\t\t<MultiInstanceParent></MultiInstanceParent>\n");
    fprintf(f, "\t\t\t<UserPagesCount>0</UserPagesCount>\n\t\t\t<PagesCount>%d</PagesCount>\n",
            pages ? 3 : 0);
    if (pages)
        fprintf(f,
                "\t\t\t<name>Controls</name>\n\t\t\t<name>Node</name>\n\t\t\t<name>Info</name>\n");
    fprintf(f, "\t\t\t<Children>0</Children>\n\t\t\t<UserComponents%s>\n", cls(w, C_USERCOMP, 0));
    fprintf(f, "\t\t\t\t<count>0</count>\n\t\t\t\t<item_version>2</item_version>\n");
    fprintf(f, "\t\t\t</UserComponents>\n\t\t\t<CacheID>%s</CacheID>\n\t\t</item>\n", name);
}

/* The rest of the GUI state, as in the projects Natron saves (one viewer, the default panes);
 * the viewer's frame bounds are the project's. */
static const char gui_tail[] =
    "\t<Gui_Layout class_id=\"15\" tracking_level=\"0\" version=\"2\">\n"
    "\t\t<NbWindows>1</NbWindows>\n"
    "\t\t<Window class_id=\"16\" tracking_level=\"0\" version=\"1\">\n"
    "\t\t\t<ChildType>0</ChildType>\n"
    "\t\t\t<Child class_id=\"17\" tracking_level=\"1\" version=\"1\" object_id=\"_0\">\n"
    "\t\t\t\t<Sizes>893 481</Sizes>\n"
    "\t\t\t\t<Orientation>1</Orientation>\n"
    "\t\t\t\t<ChildIsSplitter>1</ChildIsSplitter>\n"
    "\t\t\t\t<Child object_id=\"_1\">\n"
    "\t\t\t\t\t<Sizes>497 497</Sizes>\n"
    "\t\t\t\t\t<Orientation>2</Orientation>\n"
    "\t\t\t\t\t<ChildIsSplitter>0</ChildIsSplitter>\n"
    "\t\t\t\t\t<Child class_id=\"18\" tracking_level=\"1\" version=\"5\" object_id=\"_2\">\n"
    "\t\t\t\t\t\t<Tabs class_id=\"19\" tracking_level=\"0\" version=\"0\">\n"
    "\t\t\t\t\t\t\t<count>1</count>\n"
    "\t\t\t\t\t\t\t<item_version>0</item_version>\n"
    "\t\t\t\t\t\t\t<item>Viewer1</item>\n"
    "\t\t\t\t\t\t</Tabs>\n"
    "\t\t\t\t\t\t<Index>0</Index>\n"
    "\t\t\t\t\t\t<Name>pane1</Name>\n"
    "\t\t\t\t\t\t<IsAnchor>1</IsAnchor>\n"
    "\t\t\t\t\t</Child>\n"
    "\t\t\t\t\t<ChildIsSplitter>0</ChildIsSplitter>\n"
    "\t\t\t\t\t<Child object_id=\"_3\">\n"
    "\t\t\t\t\t\t<Tabs>\n"
    "\t\t\t\t\t\t\t<count>3</count>\n"
    "\t\t\t\t\t\t\t<item_version>0</item_version>\n"
    "\t\t\t\t\t\t\t<item>nodeGraph</item>\n"
    "\t\t\t\t\t\t\t<item>curveEditor</item>\n"
    "\t\t\t\t\t\t\t<item>dopeSheetEditor</item>\n"
    "\t\t\t\t\t\t</Tabs>\n"
    "\t\t\t\t\t\t<Index>0</Index>\n"
    "\t\t\t\t\t\t<Name>pane3</Name>\n"
    "\t\t\t\t\t\t<IsAnchor>0</IsAnchor>\n"
    "\t\t\t\t\t</Child>\n"
    "\t\t\t\t</Child>\n"
    "\t\t\t\t<ChildIsSplitter>0</ChildIsSplitter>\n"
    "\t\t\t\t<Child object_id=\"_4\">\n"
    "\t\t\t\t\t<Tabs>\n"
    "\t\t\t\t\t\t<count>1</count>\n"
    "\t\t\t\t\t\t<item_version>0</item_version>\n"
    "\t\t\t\t\t\t<item>properties</item>\n"
    "\t\t\t\t\t</Tabs>\n"
    "\t\t\t\t\t<Index>0</Index>\n"
    "\t\t\t\t\t<Name>pane2</Name>\n"
    "\t\t\t\t\t<IsAnchor>0</IsAnchor>\n"
    "\t\t\t\t</Child>\n"
    "\t\t\t</Child>\n"
    "\t\t\t<MainWindow>1</MainWindow>\n"
    "\t\t\t<x>52</x>\n"
    "\t\t\t<y>25</y>\n"
    "\t\t\t<w>1410</w>\n"
    "\t\t\t<h>997</h>\n"
    "\t\t</Window>\n"
    "\t</Gui_Layout>\n"
    "\t<ViewersData class_id=\"20\" tracking_level=\"0\" version=\"0\">\n"
    "\t\t<count>1</count>\n"
    "\t\t<item_version>0</item_version>\n"
    "\t\t<item class_id=\"21\" tracking_level=\"0\" version=\"0\">\n"
    "\t\t\t<first>Viewer1</first>\n"
    "\t\t\t<second class_id=\"22\" tracking_level=\"0\" version=\"14\">\n"
    "\t\t\t\t<zoomLeft>-2.00000000000000000e+02</zoomLeft>\n"
    "\t\t\t\t<zoomBottom>-1.00000000000000000e+02</zoomBottom>\n"
    "\t\t\t\t<zoomFactor>1.50000000000000000e+00</zoomFactor>\n"
    "\t\t\t\t<UserRoIEnabled>0</UserRoIEnabled>\n"
    "\t\t\t\t<UserRoI class_id=\"23\" tracking_level=\"0\" version=\"0\">\n"
    "\t\t\t\t\t<Left>8.00000000000000000e+01</Left>\n"
    "\t\t\t\t\t<Bottom>4.50000000000000000e+01</Bottom>\n"
    "\t\t\t\t\t<Right>2.40000000000000000e+02</Right>\n"
    "\t\t\t\t\t<Top>1.35000000000000000e+02</Top>\n"
    "\t\t\t\t</UserRoI>\n"
    "\t\t\t\t<ClippedToProject>0</ClippedToProject>\n"
    "\t\t\t\t<AutoContrast>0</AutoContrast>\n"
    "\t\t\t\t<Gain>1.00000000000000000e+00</Gain>\n"
    "\t\t\t\t<Gain>1.00000000000000000e+00</Gain>\n"
    "\t\t\t\t<ColorSpace>sRGB</ColorSpace>\n"
    "\t\t\t\t<Layer>Color.RGBA</Layer>\n"
    "\t\t\t\t<AlphaLayer>Color.A</AlphaLayer>\n"
    "\t\t\t\t<Channels>RGB</Channels>\n"
    "\t\t\t\t<RenderScaleActivated>0</RenderScaleActivated>\n"
    "\t\t\t\t<MipMapLevel>0</MipMapLevel>\n"
    "\t\t\t\t<ZoomOrPanSinceFit>0</ZoomOrPanSinceFit>\n"
    "\t\t\t\t<CompositingOP>0</CompositingOP>\n"
    "\t\t\t\t<LeftBound>%d</LeftBound>\n"
    "\t\t\t\t<RightBound>%d</RightBound>\n"
    "\t\t\t\t<LeftToolbarVisible>1</LeftToolbarVisible>\n"
    "\t\t\t\t<RightToolbarVisible>1</RightToolbarVisible>\n"
    "\t\t\t\t<TopToolbarVisible>1</TopToolbarVisible>\n"
    "\t\t\t\t<PlayerVisible>1</PlayerVisible>\n"
    "\t\t\t\t<TimelineVisible>1</TimelineVisible>\n"
    "\t\t\t\t<InfobarVisible>1</InfobarVisible>\n"
    "\t\t\t\t<isInputAPaused>0</isInputAPaused>\n"
    "\t\t\t\t<isInputBPaused>0</isInputBPaused>\n"
    "\t\t\t\t<CheckerboardEnabled>0</CheckerboardEnabled>\n"
    "\t\t\t\t<Fps>2.40000000000000000e+01</Fps>\n"
    "\t\t\t\t<FpsLocked>1</FpsLocked>\n"
    "\t\t\t\t<aInput>0</aInput>\n"
    "\t\t\t\t<bInput>0</bInput>\n"
    "\t\t\t\t<fullFrame>0</fullFrame>\n"
    "\t\t\t</second>\n"
    "\t\t</item>\n"
    "\t</ViewersData>\n"
    "\t<Histograms>\n"
    "\t\t<count>0</count>\n"
    "\t\t<item_version>0</item_version>\n"
    "\t</Histograms>\n"
    "\t<OpenedPanels>\n"
    "\t\t<count>0</count>\n"
    "\t\t<item_version>0</item_version>\n"
    "\t</OpenedPanels>\n"
    "\t<ScriptEditorInput></ScriptEditorInput>\n"
    "\t<NumPyPanels>0</NumPyPanels>\n"
    "</ProjectGui>\n"
    "</boost_serialization>\n";

/* Where a node sits in the node graph and how it is drawn. */
typedef struct gui_node {
    const char *name;
    double x, y;
    const char *rgb; /* Natron's default colour of the node's kind */
    int tall, preview;
} gui_node;

static const char *const rgb_plain = "6.999923587e-01 6.999923587e-01 6.999923587e-01";
static const char *const rgb_shuffle = "6.000000238e-01 2.399939001e-01 3.900053501e-01";
static const char *const rgb_math = "4.800030589e-01 6.599984765e-01 1.000000000e+00";
static const char *const rgb_write = "7.499961853e-01 7.499961853e-01 0.000000000e+00";

static void param_knob(ntp *w, const nprfx_graph_node_info *n, int i)
{
    const nprfx_param_desc *p = &n->desc->params[i];
    const nprfx_value *v = &n->params[i];
    char vals[4][NTP_VAL], defs[4][NTP_VAL];
    const char *type = "Double", *label = NULL;
    int dims = 1;
    switch (p->type) {
    case NPRFX_PARAM_DOUBLE:
        fmt_double(vals[0], v->v[0]);
        fmt_double(defs[0], p->def[0]);
        break;
    case NPRFX_PARAM_INT:
    case NPRFX_PARAM_BOOL:
    case NPRFX_PARAM_CHOICE:
        type = p->type == NPRFX_PARAM_INT ? "Int" : p->type == NPRFX_PARAM_BOOL ? "Bool" : "Choice";
        snprintf(vals[0], NTP_VAL, "%d", (int)v->v[0]);
        snprintf(defs[0], NTP_VAL, "%d", (int)p->def[0]);
        if (p->type == NPRFX_PARAM_CHOICE) label = p->choices[(int)v->v[0]];
        break;
    case NPRFX_PARAM_COLOR:
        type = "Color";
        dims = 4;
        for (int c = 0; c < 4; c++) {
            fmt_double(vals[c], v->v[c]);
            fmt_double(defs[c], p->def[c]);
        }
        break;
    case NPRFX_PARAM_STRING:
        type = (p->flags & NPRFX_PARAM_EXPORT) ? "OutputFile"
               : (p->flags & NPRFX_PARAM_PATH) ? "InputFile"
                                               : "String";
        snprintf(vals[0], NTP_VAL, "%s", v->s ? v->s : "");
        snprintf(defs[0], NTP_VAL, "%s", p->def_string ? p->def_string : "");
        break;
    }
    knob(w, "\t\t\t", p->name, type, 0, dims, vals, defs, label);
}

static void ofx_node(ntp *w, const host_project *hp, const host_node *hn)
{
    const nprfx_graph_node_info *n = hn->n;
    const nprfx_node_desc *d = n->desc;
    int design = host_design_width(hp, d);
    int knobs = design > 0;
    for (int i = 0; i < d->num_params; i++)
        knobs += host_param_changed(n, i);
    for (int k = 0; k < d->num_inputs && !hn->look; k++) /* a look's clips: no selectors */
        knobs += hn->links[k].src != NULL;
    node_begin(w, hn->name, hn->plugin_id, d->version_major, d->version_minor, knobs);
    for (int i = 0; i < d->num_params; i++)
        if (host_param_changed(n, i)) param_knob(w, n, i);
    if (design > 0) {
        char name[NPRFX_OFX_NAME_MAX];
        ofx_names_extra_param(d, "designWidth", name, sizeof name);
        knob_int(w, name, "Int", 0, design, 0, NULL);
    }
    const char *labels[32], *srcs[32];
    char clip[32][NPRFX_OFX_NAME_MAX];
    int nin = 0;
    for (int c = 0; c < hn->nclips; c++) {
        int k = hn->clips[c];
        if (!hn->links[k].src) continue;
        char sel[NPRFX_OFX_NAME_MAX];
        ofx_names_selector_name(d, k, sel, sizeof sel);
        if (!hn->look)
            knob_int(w, sel, "Choice", 0, hn->links[k].option,
                     ofx_names_selector_default(&d->inputs[k]), hn->links[k].label);
        /* Natron names inputs after the clip's label, which the adapter takes from the input */
        ofx_names_clip_name(d, k, clip[nin], sizeof clip[nin]);
        labels[nin] = d->inputs[k].label ? d->inputs[k].label : clip[nin];
        srcs[nin++] = hn->links[k].src;
    }
    node_end(w, hn->name, labels, srcs, nin, knobs, 1);
}

nprfx_result host_write_natron(const host_project *hp, FILE *f)
{
    ntp w = {f, {0}};
    int total = 1 + hp->nreads + hp->nnodes + hp->nwrites;
    for (int i = 0; i < hp->nsets; i++)
        total += 1 + hp->sets[i].has_sign;
    gui_node *gui = calloc((size_t)total, sizeof *gui);
    if (!gui)
        return nprfx_error(nprfx_graph_context(hp->g), NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
    int ng = 0;
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\" ?>\n"
               "<!DOCTYPE boost_serialization>\n"
               "<boost_serialization signature=\"serialization::archive\" version=\"16\">\n"
               "<Background_project>0</Background_project>\n"
               "<Project class_id=\"0\" tracking_level=\"0\" version=\"6\">\n"
               "\t<VersionMajor>2</VersionMajor>\n\t<VersionMinor>3</VersionMinor>\n"
               "\t<VersionRev>12</VersionRev>\n\t<GitBranch>nprfx-host-project</GitBranch>\n"
               "\t<GitCommit></GitCommit>\n\t<OS>Linux</OS>\n\t<Bits>64</Bits>\n"
               "\t<NodesCollection class_id=\"1\" tracking_level=\"0\" version=\"1\">\n");
    fprintf(f, "\t\t<NodesCount>%d</NodesCount>\n", total);

    /* Viewer1 on the first write's image */
    node_begin(&w, "Viewer1", "fr.inria.built-in.Viewer", 1, 0, 0);
    const char *one = "1", *vsrc = hp->nwrites ? hp->writes[0].src : NULL;
    node_end(&w, "Viewer1", &one, &vsrc, vsrc != NULL, 0, 0);
    gui[ng++] = (gui_node){"Viewer1", 0, 0, rgb_plain, 0, 0};

    char first[16], last[16];
    snprintf(first, sizeof first, "%d", hp->first_frame);
    snprintf(last, sizeof last, "%d", hp->last_frame);
    for (int i = 0; i < hp->nreads; i++) {
        const host_read *rd = &hp->reads[i];
        char file[4200];
        snprintf(file, sizeof file, "%s%s", rd->path[0] == '/' ? "" : "[Project]/", rd->path);
        node_begin(&w, rd->name, "fr.inria.built-in.Read", 1, 0, 6);
        knob1(&w, "decodingPluginID", "String", 1, "fr.inria.openfx.ReadOIIO", "", NULL);
        knob1(&w, "filename", "InputFile", 0, file, "", NULL);
        knob_int(&w, "firstFrame", "Int", 0, hp->first_frame, 0, NULL);
        knob_int(&w, "lastFrame", "Int", 0, hp->last_frame, 0, NULL);
        knob_int(&w, "startingTime", "Int", 0, hp->first_frame, 0, NULL);
        knob_int(&w, "ParamExistingInstance", "Bool", 1, 1, 0, NULL);
        node_end(&w, rd->name, NULL, NULL, 0, 8, 1);
        gui[ng++] = (gui_node){rd->name, 200.0 * i, 0, rgb_plain, 1, 1};
    }
    for (int i = 0; i < hp->nsets; i++) {
        const host_chanset *cs = &hp->sets[i];
        const char *rname = NULL;
        for (int r = 0; r < hp->nreads; r++)
            if (hp->reads[r].n == &hp->info[cs->read]) rname = hp->reads[r].name;
        node_begin(&w, cs->shuffle, "net.sf.openfx.ShufflePlugin", 2, 0, cs->count);
        static const char *const outs[4] = {"outputR", "outputG", "outputB", "outputA"};
        for (int c = 0; c < cs->count; c++) {
            /* Options: the 10 of the A and B inputs' RGBA ("A.r" first) and the constants,
             * then the plate's layered channels layer by layer, labelled "A.<channel>" */
            char label[160];
            int rgba = host_color_component(cs->chan[c]);
            host_natron_option(cs->chan[c], label, sizeof label);
            knob_int(&w, outs[c], "Choice", 0, rgba >= 0 ? rgba : 10 + cs->rank[c], c, label);
        }
        const char *a = "A";
        node_end(&w, cs->shuffle, &a, &rname, 1, cs->count, 1);
        gui[ng++] = (gui_node){cs->shuffle, 140.0 * i - 200, 160, rgb_shuffle, 0, 0};
        if (!cs->has_sign) continue;
        /* The runner's vector convention (engine/graph_resolve.c, vec_conventions): each motion
         * channel is a plate channel times a sign, here per component after the Shuffle. */
        int alpha = cs->count > 3 && cs->sign[3] != 1;
        node_begin(&w, cs->multiply, "net.sf.openfx.MultiplyPlugin", 2, 0, 1 + alpha);
        char vals[4][NTP_VAL], defs[4][NTP_VAL];
        for (int c = 0; c < 4; c++) {
            fmt_double(vals[c], c < cs->count ? cs->sign[c] : 1);
            fmt_double(defs[c], 1);
        }
        knob(&w, "\t\t\t", "value", "Color", 0, 4, vals, defs, NULL);
        if (alpha) knob_int(&w, "a", "Bool", 0, 1, 0, NULL); /* Multiply leaves alpha by default */
        const char *src = "Source", *shuffle = cs->shuffle;
        node_end(&w, cs->multiply, &src, &shuffle, 1, 1 + alpha, 1);
        gui[ng++] = (gui_node){cs->multiply, 140.0 * i - 200, 240, rgb_math, 0, 0};
    }
    for (int i = 0; i < hp->nnodes; i++) {
        ofx_node(&w, hp, &hp->nodes[i]);
        gui[ng++] =
            (gui_node){hp->nodes[i].name, 160.0 * (i % 4) - 150, 340 + 100.0 * i, rgb_plain, 0, 0};
    }
    for (int i = 0; i < hp->nwrites; i++) {
        const host_write *wr = &hp->writes[i];
        char file[4200];
        snprintf(file, sizeof file, "%s%s", wr->path[0] == '/' ? "" : "[Project]/", wr->path);
        node_begin(&w, wr->name, "fr.inria.built-in.Write", 1, 0, 4);
        knob1(&w, "encodingPluginID", "String", 1, "fr.inria.openfx.WriteOIIO", "", NULL);
        knob1(&w, "filename", "OutputFile", 0, file, "", NULL);
        /* The input's format (the plates'), whatever the project's: the image, no more */
        knob_int(&w, "formatType", "Choice", 0, 0, 1, "Input Stream Format");
        knob_int(&w, "ParamExistingInstance", "Bool", 1, 1, 0, NULL);
        const char *src = "Source";
        node_end(&w, wr->name, &src, &wr->src, 1, 4, 1);
        gui[ng++] =
            (gui_node){wr->name, 200.0 * i + 300, 340 + 100.0 * hp->nnodes, rgb_write, 2, 0};
    }
    /* the previews (PNG through the display transform) are left to the runner */
    fprintf(f, "\t</NodesCollection>\n\t<ProjectKnobsCount>2</ProjectKnobsCount>\n");
    {
        char v[2][NTP_VAL], d[2][NTP_VAL];
        snprintf(v[0], NTP_VAL, "%d", hp->first_frame);
        snprintf(v[1], NTP_VAL, "%d", hp->last_frame);
        snprintf(d[0], NTP_VAL, "1");
        snprintf(d[1], NTP_VAL, "250");
        knob(&w, "\t", "frameRange", "Int", 0, 2, v, d, NULL);
        char label[160];
        snprintf(label, sizeof label, "%s %dx%d", hp->format_name, hp->width, hp->height);
        /* the project's own format, after Natron's built-in ones: Natron finds it by label */
        snprintf(v[0], NTP_VAL, "0");
        snprintf(d[0], NTP_VAL, "0");
        knob(&w, "\t", "outputFormat", "Choice", 0, 1, v, d, label);
    }
    fprintf(f, "\t<AdditionalFormats%s>\n", cls(&w, C_FORMATS, 0));
    fprintf(f, "\t\t<count>1</count>\n\t\t<item_version>3</item_version>\n");
    fprintf(f, "\t\t<item class_id=\"10\" tracking_level=\"0\" version=\"3\">\n");
    fprintf(f, "\t\t\t<RectI class_id=\"11\" tracking_level=\"0\" version=\"0\">\n");
    fprintf(f, "\t\t\t\t<Left>0</Left>\n\t\t\t\t<Bottom>0</Bottom>\n");
    fprintf(f, "\t\t\t\t<Right>%d</Right>\n\t\t\t\t<Top>%d</Top>\n", hp->width, hp->height);
    fprintf(f, "\t\t\t</RectI>\n\t\t\t<Pixel_aspect_ratio>1.00000000000000000e+00"
               "</Pixel_aspect_ratio>\n");
    fprintf(f, "\t\t\t<Name>%s</Name>\n\t\t</item>\n\t</AdditionalFormats>\n", hp->format_name);
    fprintf(f, "\t<Timeline_current_time>%d</Timeline_current_time>\n", hp->first_frame);
    fprintf(f, "\t<CreationDate>1735689600000</CreationDate>\n</Project>\n");

    fprintf(f, "<ProjectGui class_id=\"12\" tracking_level=\"0\" version=\"11\">\n");
    fprintf(f, "\t<NodesGui class_id=\"13\" tracking_level=\"0\" version=\"0\">\n");
    fprintf(f, "\t\t<count>%d</count>\n", ng);
    gui[0].x = 300;
    gui[0].y = 440 + 100.0 * hp->nnodes;
    for (int i = 0; i < ng; i++) {
        const gui_node *gn = &gui[i];
        double r, g, b;
        sscanf(gn->rgb, "%lf %lf %lf", &r, &g, &b);
        fprintf(f, "\t\t<item%s>\n",
                i ? "" : " class_id=\"14\" tracking_level=\"0\" version=\"6\"");
        fprintf(f, "\t\t\t<Name>%s</Name>\n", gn->name);
        fprintf(f, "\t\t\t<X_position>%.17e</X_position>\n", gn->x);
        fprintf(f, "\t\t\t<Y_position>%.17e</Y_position>\n", gn->y);
        fprintf(f, "\t\t\t<Preview_enabled>%d</Preview_enabled>\n", gn->preview);
        fprintf(f, "\t\t\t<r>%.9e</r>\n\t\t\t<g>%.9e</g>\n\t\t\t<b>%.9e</b>\n", r, g, b);
        fprintf(f, "\t\t\t<Selected>0</Selected>\n");
        fprintf(f, "\t\t\t<Width>%.17e</Width>\n", gn->tall == 1 ? 128.0 : 104.0);
        fprintf(f, "\t\t\t<Height>%.17e</Height>\n",
                gn->tall == 1   ? 78.0
                : gn->tall == 2 ? 43.0
                                : 30.0);
        fprintf(f, "\t\t\t<HasOverlayColor>0</HasOverlayColor>\n\t\t\t<Children>0</Children>\n");
        fprintf(f, "\t\t</item>\n");
    }
    fprintf(f, "\t</NodesGui>\n");
    fprintf(f, gui_tail, hp->first_frame, hp->last_frame);
    free(gui);
    return ferror(f) ? nprfx_error(nprfx_graph_context(hp->g), NPRFX_ERR_IO, "write error")
                     : NPRFX_OK;
}
