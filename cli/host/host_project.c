#define _DEFAULT_SOURCE /* realpath */
/* nprfx host-project: the host view of a graph (host_project.h), resolved exactly as `nprfx run`
 * resolves it: plate channels from the first frame's header through the runner's I/O layer, the
 * read node's motion-vector convention, each input's selection or AOV hint. */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/engine_util.h"
#include "nprfx/graph.h"
#include "host_project.h"
#include "nprfx/channels.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/io.h"
#include "ofx_names.h"
#include "util/cli_util.h"

char *host_double(double v, char *buf, size_t n)
{
    for (int prec = 1; prec <= 17; prec++) {
        snprintf(buf, n, "%.*g", prec, v);
        if (strtod(buf, NULL) == v) break;
    }
    /* plain decimals for everyday magnitudes: 10, not 1e+01 */
    if (strchr(buf, 'e') && fabs(v) >= 1e-4 && fabs(v) < 1e15)
        for (int dec = 0; dec <= 17; dec++) {
            snprintf(buf, n, "%.*f", dec, v);
            if (strtod(buf, NULL) == v) break;
        }
    return buf;
}

int host_design_width(const host_project *hp, const nprfx_node_desc *d)
{
    /* a look's design width is its graph's, the plug-in's default */
    if (!strncmp(d->id, NPRFX_OFX_LOOK_PREFIX, strlen(NPRFX_OFX_LOOK_PREFIX))) return 0;
    return ofx_names_has_pixel_params(d) ? hp->design_width : 0;
}

int host_param_changed(const nprfx_graph_node_info *n, int i)
{
    const nprfx_param_desc *p = &n->desc->params[i];
    const nprfx_value *v = &n->params[i];
    if (p->type == NPRFX_PARAM_STRING)
        return strcmp(v->s ? v->s : "", p->def_string ? p->def_string : "") != 0;
    int dims = p->type == NPRFX_PARAM_COLOR ? 4 : 1;
    for (int c = 0; c < dims; c++)
        if (v->v[c] != p->def[c]) return 1;
    return 0;
}

/* Copies of n channel names (NULL names become "C", as the engine names them). */
static char **names_dup(const char *const *names, int n)
{
    char **d = calloc((size_t)n + 1, sizeof *d);
    for (int c = 0; d && c < n; c++)
        if (!(d[c] = engine_strdup(names[c] ? names[c] : "C"))) {
            for (int k = 0; k < c; k++)
                free(d[k]);
            free(d);
            return NULL;
        }
    return d;
}

/* Host node names are Python identifiers (Natron script names): other characters become '_'. */
static void host_name(char *buf, size_t n, const char *a, const char *b)
{
    snprintf(buf, n, "%s%s%s", a, b ? "_" : "", b ? b : "");
    for (char *c = buf; *c; c++)
        if (!(isalnum((unsigned char)*c) || *c == '_')) *c = '_';
    if (isdigit((unsigned char)buf[0])) buf[0] = '_';
}

/* Channel names of graph node i as its consumers see them, and how many: a read node's plate
 * channels (plus the motion channels its "vectors" adds), an OpenFX node's output. */
typedef struct src_info {
    int done, nc;
    char **names;      /* nc names */
    int motion_idx[4]; /* read with vectors: plate channels of the motion channels */
    double motion_sign[4];
    int plate_nc; /* read: channels in the file */
    int *rank;    /* read: each plate channel's position, layer by layer */
} src_info;

typedef struct builder {
    nprfx_graph *g;
    host_project *hp;
    src_info *info;
    int *visiting;
} builder;

static nprfx_result oom(builder *b)
{
    return nprfx_error(nprfx_graph_context(b->g), NPRFX_ERR_OUT_OF_MEMORY, "out of memory");
}

/* Order of plate channels as hosts list them: by layer, then by component inside the layer. */
static int plate_before(const char *x, const char *y)
{
    const char *dx = strrchr(x, '.'), *dy = strrchr(y, '.');
    size_t lx = dx ? (size_t)(dx - x) : 0, ly = dy ? (size_t)(dy - y) : 0;
    size_t l = lx < ly ? lx : ly;
    int c = strncmp(x, y, l);
    if (c || lx != ly) return c ? c < 0 : lx < ly;
    int rx = nprfx_channels_component_rank(dx ? dx + 1 : x);
    int ry = nprfx_channels_component_rank(dy ? dy + 1 : y);
    return rx != ry ? rx < ry : strcmp(x, y) < 0;
}

int host_color_component(const char *channel)
{
    static const char *const rgba[4] = {"R", "G", "B", "A"};
    for (int c = 0; c < 4; c++)
        if (!strcmp(channel, rgba[c])) return c;
    return -1;
}

void host_natron_option(const char *channel, char *out, size_t n)
{
    static const char *const rgba[4] = {"A.r", "A.g", "A.b", "A.a"};
    int c = host_color_component(channel);
    if (c >= 0)
        snprintf(out, n, "%s", rgba[c]);
    else
        snprintf(out, n, "A.%s", channel);
}

/* Each channel's place among the plate's layered channels (the colour plane's R, G, B, A are
 * the host's own RGBA, listed apart, so they take no place). */
static void plate_ranks(char **names, int nc, int *rank)
{
    for (int i = 0; i < nc; i++) {
        rank[i] = 0;
        for (int j = 0; j < nc; j++)
            rank[i] +=
                j != i && host_color_component(names[j]) < 0 && plate_before(names[j], names[i]);
    }
}

static nprfx_result read_info(builder *b, int gi, src_info *s)
{
    nprfx_graph *g = b->g;
    const nprfx_graph_node_info *n = &b->hp->info[gi];
    char file[4096];
    nprfx_graph_resolve_path(g, nprfx_graph_base_dir(g), n->path, b->hp->first_frame, file,
                             sizeof file);
    nprfx_file_info fi;
    memset(&fi, 0, sizeof fi);
    nprfx_result r = nprfx_io_info(n->ctx, file, &fi);
    if (r) return r;
    int extra = nprfx_graph_read_vectors(g, gi) ? 4 : 0;
    if (nprfx_graph_read_decodes(g, gi)) {
        nprfx_file_info_free(&fi);
        return nprfx_error(n->ctx, NPRFX_ERR_UNSUPPORTED,
                           "%s: its ids come from Cryptomatte or its depth from 1/z, which a "
                           "host project does not decode yet; render it with nprfx run",
                           file);
    }
    s->names = calloc((size_t)fi.nchannels + 4, sizeof *s->names);
    s->rank = calloc((size_t)fi.nchannels + 1, sizeof *s->rank);
    if (!s->names || !s->rank) {
        nprfx_file_info_free(&fi);
        return oom(b);
    }
    for (int c = 0; c < fi.nchannels; c++)
        s->names[c] = engine_strdup(fi.names[c]);
    s->plate_nc = s->nc = fi.nchannels;
    plate_ranks(s->names, s->nc, s->rank);
    if (!b->hp->width) {
        b->hp->width = nprfx_rect_width(fi.bounds);
        b->hp->height = nprfx_rect_height(fi.bounds);
    }
    nprfx_file_info_free(&fi);
    if (extra) {
        r = nprfx_graph_motion_sources(g, gi, file, (const char *const *)s->names, s->nc,
                                       s->motion_idx, s->motion_sign);
        if (r) return r;
        for (int k = 0; k < 4; k++)
            s->names[s->nc++] = engine_strdup(nprfx_graph_motion_name(k));
    }
    return NPRFX_OK;
}

/* The set of plate channels idx[0..count) of read node gi, added when new. */
static nprfx_result add_set(builder *b, int gi, const src_info *s, const int *idx, int count,
                            const host_chanset **out)
{
    host_project *hp = b->hp;
    host_chanset cs;
    memset(&cs, 0, sizeof cs);
    cs.read = gi;
    cs.count = count;
    for (int c = 0; c < count; c++) {
        int k = idx[c], plate = k;
        cs.sign[c] = 1;
        if (k >= s->plate_nc) { /* a motion channel: a plate channel times the convention's sign */
            plate = s->motion_idx[k - s->plate_nc];
            cs.sign[c] = s->motion_sign[k - s->plate_nc];
        }
        snprintf(cs.want[c], sizeof cs.want[c], "%s", s->names[k]);
        snprintf(cs.chan[c], sizeof cs.chan[c], "%s", s->names[plate]);
        cs.rank[c] = s->rank[plate];
        const char *dot = strrchr(s->names[plate], '.');
        size_t ll = dot ? (size_t)(dot - s->names[plate]) : 0;
        for (int j = 0; j < s->plate_nc; j++)
            cs.layer_pos[c] += s->rank[j] < s->rank[plate] &&
                               !strncmp(s->names[j], s->names[plate], ll) &&
                               strrchr(s->names[j], '.') == s->names[j] + ll;
        cs.has_sign |= cs.sign[c] != 1;
    }
    for (int i = 0; i < hp->nsets; i++) {
        const host_chanset *o = &hp->sets[i];
        int same = o->read == gi && o->count == count;
        for (int c = 0; same && c < count; c++)
            same = !strcmp(o->want[c], cs.want[c]);
        if (same) {
            *out = o;
            return NPRFX_OK;
        }
    }
    /* Named after the channels the runner reads: "plate_Depth_Z", "plate_motion_prev_XY". */
    char layer[128] = "", letters[8] = "";
    const char *last = strrchr(cs.want[0], '.');
    if (last) {
        const char *start = last;
        while (start > cs.want[0] && start[-1] != '.')
            start--;
        snprintf(layer, sizeof layer, "%.*s", (int)(last - start), start);
    }
    for (int c = 0; c < count; c++) {
        const char *d = strrchr(cs.want[c], '.');
        letters[c] = d ? d[1] : cs.want[c][0];
    }
    char base[256];
    snprintf(base, sizeof base, "%s%s%s", layer, layer[0] ? "_" : "", letters);
    host_name(cs.shuffle, sizeof cs.shuffle, b->hp->info[gi].name, base);
    if (cs.has_sign) {
        snprintf(cs.multiply, sizeof cs.multiply, "%s", cs.shuffle);
        size_t len = strlen(cs.shuffle);
        snprintf(cs.shuffle + len, sizeof cs.shuffle - len, "_plate");
    }
    host_chanset *sets = realloc(hp->sets, sizeof *sets * (size_t)(hp->nsets + 1));
    if (!sets) return oom(b);
    hp->sets = sets;
    sets[hp->nsets] = cs;
    *out = &sets[hp->nsets++];
    return NPRFX_OK;
}

static nprfx_result visit(builder *b, int gi);

/* Input k of OpenFX node hn: resolve its channels and link it to a Shuffle or an OpenFX node. */
static nprfx_result link_input(builder *b, host_node *hn, int k)
{
    nprfx_graph *g = b->g;
    nprfx_context *ctx = nprfx_graph_context(g);
    const nprfx_graph_node_info *n = hn->n;
    int gi = (int)(n - b->hp->info);
    const nprfx_input_desc *in = &n->desc->inputs[k];
    host_link *l = &hn->links[k];
    int src = n->inputs[k].src;
    if (src < 0) return NPRFX_OK;
    nprfx_result r = visit(b, src);
    if (r) return r;
    src_info *s = &b->info[src];
    int idx[256], count = 0;
    if ((r = nprfx_graph_input_channels(g, gi, k, (const char *const *)s->names, s->nc, idx,
                                        &count)))
        return r;
    if (count > 4)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "node '%s': input '%s' takes %d channels; host clips carry 4 at most",
                           n->name, in->name, count);
    int first = 0;
    if (b->hp->info[src].kind == NPRFX_GRAPH_READ) {
        const host_chanset *cs;
        if ((r = add_set(b, src, s, idx, count, &cs))) return r;
        l->src = cs->has_sign ? cs->multiply : cs->shuffle;
    } else {
        for (int c = 1; c < count; c++)
            if (idx[c] != idx[0] + c)
                return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                                   "node '%s': input '%s' takes channels of '%s' that are not "
                                   "adjacent; a host selector picks a run of R, G, B, A",
                                   n->name, in->name, b->hp->info[src].name);
        first = idx[0];
        for (int i = 0; i < b->hp->nnodes; i++)
            if (b->hp->nodes[i].n == &b->hp->info[src]) l->src = b->hp->nodes[i].name;
    }
    l->option = ofx_names_selector_find(in, first, count);
    if (l->option < 0)
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                           "node '%s': input '%s' has no channel selector option for %d "
                           "channel%s from component %d",
                           n->name, in->name, count, count > 1 ? "s" : "", first);
    int opts[NPRFX_OFX_CHAN_OPTIONS];
    ofx_names_selector_options(in, opts);
    l->label = ofx_names_chan_options[opts[l->option]].label;
    return NPRFX_OK;
}

/* Depth first, so every node comes after the nodes it reads. */
static nprfx_result visit(builder *b, int gi)
{
    nprfx_graph *g = b->g;
    nprfx_context *ctx = nprfx_graph_context(g);
    const nprfx_graph_node_info *n = &b->hp->info[gi];
    src_info *s = &b->info[gi];
    if (s->done) return NPRFX_OK;
    if (b->visiting[gi])
        return nprfx_error(ctx, NPRFX_ERR_PARSE, "the graph has a cycle through node '%s'",
                           n->name);
    b->visiting[gi] = 1;
    nprfx_result r = NPRFX_OK;
    if (n->kind == NPRFX_GRAPH_SYNTH) {
        r = nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                        "node '%s': synth plates exist in the runner only; render them with "
                        "'nprfx synth' and read the files",
                        n->name);
    } else if (n->kind == NPRFX_GRAPH_READ) {
        r = read_info(b, gi, s);
    } else if (n->kind == NPRFX_GRAPH_NODE) {
        const nprfx_node_desc *d = n->desc;
        host_node hn;
        memset(&hn, 0, sizeof hn);
        hn.n = n;
        ofx_names_plugin_id(d, hn.plugin_id, sizeof hn.plugin_id);
        host_name(hn.name, sizeof hn.name, n->name, NULL);
        hn.links = calloc((size_t)d->num_inputs + 1, sizeof *hn.links);
        if (!hn.links) return oom(b);
        int main_in = ofx_names_main_input(d), ch[64] = {0};
        if (main_in >= 0) hn.clips[hn.nclips++] = main_in;
        for (int k = 0; k < d->num_inputs && hn.nclips < 32; k++)
            if (k != main_in) hn.clips[hn.nclips++] = k;
        for (int k = 0; k < d->num_inputs && !r; k++) {
            r = link_input(b, &hn, k);
            if (!r && n->inputs[k].src >= 0) {
                int idx[256], count = 0;
                src_info *si = &b->info[n->inputs[k].src];
                nprfx_graph_input_channels(g, gi, k, (const char *const *)si->names, si->nc, idx,
                                           &count);
                ch[k] = count;
            }
        }
        nprfx_output_info oi;
        memset(&oi, 0, sizeof oi);
        if (!r) r = nprfx_node_output_info(n->ctx, d, n->params, ch, &oi);
        if (!r && oi.channels > 4)
            r = nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                            "node '%s': %s outputs %d channels; host images carry 4 at most",
                            n->name, d->id, oi.channels);
        if (!r) {
            s->nc = oi.channels;
            s->names = names_dup(oi.names, oi.channels);
            host_project *hp = b->hp;
            host_node *nodes = realloc(hp->nodes, sizeof *nodes * (size_t)(hp->nnodes + 1));
            if (!nodes || !s->names) {
                free(hn.links);
                return oom(b);
            }
            hp->nodes = nodes;
            nodes[hp->nnodes++] = hn;
        } else {
            free(hn.links);
        }
    }
    b->visiting[gi] = 0;
    s->done = !r;
    return r;
}

/* Split a real path into its components (in place); returns how many. */
static int components(char *path, char **parts, int max)
{
    int n = 0;
    for (char *save = NULL, *c = strtok_r(path, "/", &save); c && n < max;
         c = strtok_r(NULL, "/", &save))
        parts[n++] = c;
    return n;
}

/* target relative to the folder `from`, through real paths (so "samples/graphs/../plates" from
 * samples/hosts is "../plates"); target itself when a folder does not exist. */
static void relative_to(const char *from, const char *target, char *buf, size_t n)
{
    char a[PATH_MAX], t[PATH_MAX], dir[4096];
    snprintf(dir, sizeof dir, "%s", target);
    char *slash = strrchr(dir, '/');
    const char *leaf = slash ? target + (slash - dir) + 1 : target;
    if (slash)
        *slash = 0;
    else
        snprintf(dir, sizeof dir, ".");
    if (!realpath(from, a) || !realpath(dir, t)) {
        snprintf(buf, n, "%s", target);
        return;
    }
    char *pa[256], *pt[256];
    int na = components(a, pa, 256), nt = components(t, pt, 256), common = 0;
    while (common < na && common < nt && !strcmp(pa[common], pt[common]))
        common++;
    size_t k = 0;
    buf[0] = 0;
    for (int i = common; i < na && k < n; i++)
        k += (size_t)snprintf(buf + k, n - k, "../");
    for (int i = common; i < nt && k < n; i++)
        k += (size_t)snprintf(buf + k, n - k, "%s/", pt[i]);
    if (k < n) snprintf(buf + k, n - k, "%s", leaf);
}

/* The look's nodes, one per output: clips linked to the reads (Source whole where planar) or to
 * Shuffles of their AOVs; then the write nodes. */
static nprfx_result build_look(builder *b, const look_desc *look, int planar)
{
    host_project *hp = b->hp;
    nprfx_graph *g = b->g;
    const nprfx_node_desc *d = &look->desc;
    int np = d->num_params, ni = d->num_inputs;
    int set_of[LOOK_MAX_INPUTS];
    nprfx_result r = NPRFX_OK;
    hp->look_nodes = calloc((size_t)look->noutputs + 1, sizeof *hp->look_nodes);
    hp->look_values = calloc((size_t)(look->noutputs * (np + 1)) + 1, sizeof *hp->look_values);
    hp->nodes = calloc((size_t)look->noutputs + 1, sizeof *hp->nodes);
    if (!hp->look_nodes || !hp->look_values || !hp->nodes) return oom(b);
    for (int k = 0; k < ni && !r; k++) {
        set_of[k] = -1;
        if (!look_desc_has_clip(look, k, planar)) continue;
        if ((r = visit(b, look->node[k]))) break;
        if (look->aov[k] < 0 || (planar && k == look->source)) continue; /* the read whole */
        src_info *s = &b->info[look->node[k]];
        int idx[256], count = 0;
        const host_chanset *cs;
        if ((r = nprfx_graph_aov_channels(g, look->node[k], look->aov[k],
                                          (const char *const *)s->names, s->nc, idx, &count)) ||
            (r = add_set(b, look->node[k], s, idx, count, &cs)))
            break;
        set_of[k] = (int)(cs - hp->sets);
    }
    for (int i = 0; i < hp->nsets; i++)
        hp->sets[i].out = hp->sets[i].has_sign ? hp->sets[i].multiply : hp->sets[i].shuffle;
    for (int o = 0; o < look->noutputs && !r; o++) {
        nprfx_graph_node_info *n = &hp->look_nodes[o];
        nprfx_value *values = hp->look_values + (size_t)o * (size_t)(np + 1);
        memcpy(values, look->values, sizeof *values * (size_t)np);
        if (look->output_param >= 0) values[look->output_param].v[0] = o;
        n->size = sizeof *n;
        n->name = look->output_label[o];
        n->kind = NPRFX_GRAPH_NODE;
        n->desc = d;
        n->params = values;
        host_node *hn = &hp->nodes[hp->nnodes++];
        hn->n = n;
        hn->look = 1;
        snprintf(hn->plugin_id, sizeof hn->plugin_id, "%.90s", look->id);
        host_name(hn->name, sizeof hn->name, look->label,
                  look->noutputs > 1 ? look->output_label[o] : NULL);
        if (!(hn->links = calloc((size_t)ni + 1, sizeof *hn->links))) return oom(b);
        hn->clips[hn->nclips++] = look->source;
        for (int k = 0; k < ni && hn->nclips < 32; k++)
            if (k != look->source && look_desc_has_clip(look, k, planar))
                hn->clips[hn->nclips++] = k;
        for (int k = 0; k < ni; k++) {
            if (!look_desc_has_clip(look, k, planar)) continue;
            if (set_of[k] >= 0) {
                hn->links[k].src = hp->sets[set_of[k]].out;
                continue;
            }
            for (int i = 0; i < hp->nreads; i++)
                if (hp->reads[i].n == &hp->info[look->node[k]])
                    hn->links[k].src = hp->reads[i].name;
        }
        /* the write of this output */
        for (int i = 0; i < nprfx_graph_node_count(g); i++) {
            const nprfx_graph_node_info *w = &hp->info[i];
            if (w->kind != NPRFX_GRAPH_WRITE || strcmp(w->name, look->output_label[o])) continue;
            host_write *hw = &hp->writes[hp->nwrites++];
            hw->n = w;
            hw->path = w->path;
            host_name(hw->name, sizeof hw->name, w->name, NULL);
            hw->src = hn->name;
        }
    }
    return r;
}

nprfx_result host_project_build(nprfx_graph *g, const char *graph_path, const char *out_dir,
                                const char *out_file, const look_desc *look, int planar,
                                host_project *hp)
{
    memset(hp, 0, sizeof *hp);
    hp->g = g;
    hp->graph_path = graph_path;
    nprfx_frame_list fl = {NULL, 0};
    nprfx_result r = nprfx_graph_frames(g, NULL, &fl);
    if (r) return r;
    hp->first_frame = hp->last_frame = 1;
    hp->design_width = (int)(nprfx_graph_design_width(g) + 0.5);
    if (!nprfx_graph_shot(g, &hp->first_frame, &hp->last_frame) && fl.count)
        hp->first_frame = hp->last_frame = fl.frames[0];
    nprfx_seq_frames_free(&fl);
    /* the reads' plates as the runner would read them (profiles, conventions, fallbacks) */
    nprfx_result sr = nprfx_graph_settle(g, hp->first_frame);
    if (sr) return sr;
    /* the project format's name: the output file's, without folder and extension */
    const char *leaf = strrchr(out_file, '/');
    char stem[64];
    snprintf(stem, sizeof stem, "%s", leaf ? leaf + 1 : out_file);
    char *dot = strrchr(stem, '.');
    if (dot && dot != stem) *dot = 0;
    host_name(hp->format_name, sizeof hp->format_name, stem, NULL);

    int count = nprfx_graph_node_count(g);
    nprfx_context *ctx = nprfx_graph_context(g);
    const char *base_dir = nprfx_graph_base_dir(g);
    builder b = {g, hp, calloc((size_t)count + 1, sizeof(src_info)),
                 calloc((size_t)count + 1, sizeof(int))};
    hp->info = calloc((size_t)count + 1, sizeof *hp->info);
    hp->reads = calloc((size_t)count + 1, sizeof *hp->reads);
    hp->writes = calloc((size_t)count + 1, sizeof *hp->writes);
    if (!b.info || !b.visiting || !hp->info || !hp->reads || !hp->writes) {
        r = oom(&b);
        goto done;
    }
    for (int i = 0; i < count; i++) {
        hp->info[i].size = sizeof hp->info[i];
        nprfx_graph_node(g, i, &hp->info[i]);
    }
    for (int i = 0; i < count; i++) {
        const nprfx_graph_node_info *n = &hp->info[i];
        if (n->kind != NPRFX_GRAPH_READ) continue;
        host_read *rd = &hp->reads[hp->nreads++];
        rd->n = n;
        host_name(rd->name, sizeof rd->name, n->name, NULL);
        char full[4096];
        if (n->path[0] == '/' || !strcmp(base_dir, "."))
            snprintf(full, sizeof full, "%s", n->path);
        else
            snprintf(full, sizeof full, "%s/%s", base_dir, n->path);
        if (full[0] == '/')
            snprintf(rd->path, sizeof rd->path, "%s", full);
        else
            relative_to(out_dir, full, rd->path, sizeof rd->path);
    }
    if (look) {
        r = build_look(&b, look, planar);
        goto done;
    }
    for (int i = 0; i < count && !r; i++) {
        const nprfx_graph_node_info *n = &hp->info[i];
        if (n->kind != NPRFX_GRAPH_WRITE) {
            r = visit(&b, i);
            continue;
        }
        int src = n->inputs[0].src;
        if ((r = visit(&b, src))) break;
        host_write *w = &hp->writes[hp->nwrites++];
        w->n = n;
        w->path = n->path;
        host_name(w->name, sizeof w->name, n->name, NULL);
        if (hp->info[src].kind != NPRFX_GRAPH_NODE || n->inputs[0].sel)
            r = nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                            "node '%s': a write in a host project takes a whole nprfx node's "
                            "output (\"image\": \"NODE\"), not '%s%s%s'",
                            n->name, n->inputs[0].text, n->inputs[0].sel ? ":" : "",
                            n->inputs[0].sel ? n->inputs[0].sel : "");
        for (int k = 0; k < hp->nnodes; k++)
            if (hp->nodes[k].n == &hp->info[src]) w->src = hp->nodes[k].name;
    }
    if (!r && !hp->nreads)
        r = nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED,
                        "the graph has no read node, so a host project would have no format");
    /* set .out once the set array no longer moves */
    for (int i = 0; i < hp->nsets; i++)
        hp->sets[i].out = hp->sets[i].has_sign ? hp->sets[i].multiply : hp->sets[i].shuffle;
    /* links point at set names inside the array that realloc may have moved: point them again */
    for (int i = 0; i < hp->nnodes && !r; i++) {
        host_node *hn = &hp->nodes[i];
        for (int k = 0; k < hn->n->desc->num_inputs; k++) {
            int src = hn->n->inputs[k].src;
            if (src < 0) continue;
            if (hp->info[src].kind == NPRFX_GRAPH_NODE) {
                for (int j = 0; j < hp->nnodes; j++)
                    if (hp->nodes[j].n == &hp->info[src]) hn->links[k].src = hp->nodes[j].name;
                continue;
            }
            src_info *s = &b.info[src];
            int idx[256], count = 0;
            const host_chanset *cs = NULL;
            nprfx_graph_input_channels(g, (int)(hn->n - hp->info), k, (const char *const *)s->names,
                                       s->nc, idx, &count);
            if (!(r = add_set(&b, src, s, idx, count, &cs))) hn->links[k].src = cs->out;
        }
    }
    for (int i = 0; i < hp->nwrites; i++)
        for (int k = 0; k < hp->nnodes; k++)
            if (hp->nodes[k].n == &hp->info[hp->writes[i].n->inputs[0].src])
                hp->writes[i].src = hp->nodes[k].name;
done:
    for (int i = 0; b.info && i < count; i++) {
        for (int c = 0; c < b.info[i].nc; c++)
            free(b.info[i].names[c]);
        free(b.info[i].names);
        free(b.info[i].rank);
    }
    free(b.info);
    free(b.visiting);
    if (r) host_project_free(hp);
    return r;
}

void host_project_free(host_project *hp)
{
    free(hp->look_nodes);
    free(hp->look_values);
    for (int i = 0; i < hp->nnodes; i++)
        free(hp->nodes[i].links);
    free(hp->nodes);
    free(hp->sets);
    free(hp->reads);
    free(hp->writes);
    free(hp->info);
    memset(hp, 0, sizeof *hp);
}
