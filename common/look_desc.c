/* nprfx — a graph file as one OpenFX effect (declared in look_desc.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "look_desc.h"
#include "nprfx/aov.h"

static char *copy(const char *s)
{
    if (!s) return NULL;
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

void look_desc_free(look_desc *l)
{
    for (int i = 0; i < LOOK_MAX_KNOBS; i++)
        free(l->knob_help[i]);
    free(l->comment);
    memset(l, 0, sizeof *l);
}

void look_desc_values(look_desc *l, const nprfx_graph *g)
{
    for (int p = 0, i = 0; p < l->desc.num_params; p++) {
        if (!l->knob[p][0]) continue; /* the output choice */
        nprfx_graph_knob_info k = {sizeof k};
        if (nprfx_graph_knob(g, i++, &k)) continue;
        l->values[p] = *k.value;
        if (k.value->s) {
            snprintf(l->value_text[p], sizeof l->value_text[p], "%s", k.value->s);
            l->values[p].s = l->value_text[p];
        }
    }
}

nprfx_result look_desc_build(nprfx_graph *g, const char *stem, look_desc *l, char *why, size_t n)
{
    memset(l, 0, sizeof *l);
    ofx_names_look_id(stem, l->id, sizeof l->id);
    /* "cross_hatching" -> "Cross hatching" */
    snprintf(l->label, sizeof l->label, "%.100s", stem);
    for (char *c = l->label; *c; c++)
        if (*c == '_' || *c == '-') *c = ' ';
    if (l->label[0] >= 'a' && l->label[0] <= 'z') l->label[0] = (char)(l->label[0] - 'a' + 'A');
    int nsrc = nprfx_graph_source_count(g), ni = 0, main_node = -1;
    l->source = -1;
    for (int i = 0; i < nsrc; i++) {
        nprfx_graph_source_info s = {sizeof s};
        if (nprfx_graph_source(g, i, &s)) continue;
        if (s.raw) {
            snprintf(why, n,
                     "read node '%s' is read by channel names ('%s'), which only the renderer's "
                     "own files have: name the AOV instead (docs/graphs.md)",
                     s.name, s.raw);
            return NPRFX_ERR_UNSUPPORTED;
        }
        int is_main = s.sequence && main_node < 0;
        if (is_main) main_node = s.node;
        /* a sequence's AOVs but coverage (Source's alpha), or a map's whole file */
        for (int aov = s.sequence ? 0 : -1; aov < (s.sequence ? NPRFX_AOV_COUNT : 0); aov++) {
            if (aov >= 0 && (!(s.aovs & (1u << aov)) || aov == NPRFX_AOV_COVERAGE)) continue;
            if (ni == LOOK_MAX_INPUTS) break;
            int k = ni++;
            ofx_names_look_clip(s.name, is_main, aov >= 0 ? nprfx_aov_name(aov) : NULL, l->clip[k],
                                sizeof l->clip[k]);
            l->node[k] = s.node;
            l->aov[k] = aov;
            l->main[k] = is_main;
            l->in[k].name = l->clip[k];
            l->in[k].label = l->clip[k];
            l->in[k].flags = NPRFX_INPUT_OPTIONAL | (aov < 0 ? NPRFX_INPUT_UNALIGNED : 0);
            l->in[k].channels = aov >= 0 ? nprfx_aov_channels(aov) : 0;
            if (is_main && aov == NPRFX_AOV_BEAUTY) {
                l->in[k].flags = NPRFX_INPUT_MAIN;
                l->source = k;
            }
        }
    }
    if (l->source < 0) {
        snprintf(why, n, "it reads no frame sequence (a look's Source is the render's plates)");
        return NPRFX_ERR_UNSUPPORTED;
    }
    int count = nprfx_graph_node_count(g);
    for (int i = 0; i < count; i++) {
        nprfx_graph_node_info info = {sizeof info};
        if (nprfx_graph_node(g, i, &info)) continue;
        if (info.kind == NPRFX_GRAPH_NODE && info.desc &&
            (info.desc->flags & (NPRFX_NODE_TEMPORAL | NPRFX_NODE_STATEFUL)))
            l->temporal = 1;
        if (info.kind == NPRFX_GRAPH_WRITE && info.ninputs > 0 && info.inputs[0].src >= 0 &&
            l->noutputs < LOOK_MAX_OUTPUTS) {
            snprintf(l->output[l->noutputs], sizeof l->output[0], "%s", info.inputs[0].text);
            snprintf(l->output_label[l->noutputs], sizeof l->output_label[0], "%s", info.name);
            l->noutputs++;
        }
    }
    if (!l->noutputs) {
        snprintf(why, n, "it has no write node (the image a look makes is what its write writes)");
        return NPRFX_ERR_UNSUPPORTED;
    }
    l->measures = nprfx_graph_measuring_nodes(g);
    l->design_width = nprfx_graph_design_width(g);
    int nk = nprfx_graph_knob_count(g), np = 0;
    for (int i = 0; i < nk && np < LOOK_MAX_KNOBS; i++) {
        nprfx_graph_knob_info k = {sizeof k};
        if (nprfx_graph_knob(g, i, &k)) continue;
        int p = np++;
        snprintf(l->knob[p], sizeof l->knob[p], "%s", k.name);
        ofx_names_look_knob(k.name, l->param_name[p], sizeof l->param_name[p]);
        /* "ink.width" reads "ink width": the node's name says which of its kind it is */
        snprintf(l->param_label[p], sizeof l->param_label[p], "%s", k.name);
        for (char *c = l->param_label[p]; *c; c++)
            if (*c == '.' || *c == '_') *c = ' ';
        l->knob_help[p] = copy(k.help);
        l->params[p] = *k.param;
        l->params[p].name = l->param_name[p];
        l->params[p].label = l->param_label[p];
        l->values[p] = *k.value;
        if (k.value->s) {
            snprintf(l->value_text[p], sizeof l->value_text[p], "%s", k.value->s);
            l->values[p].s = l->value_text[p];
        }
        /* the graph's value is the default a host shows and resets to */
        memcpy(l->params[p].def, k.value->v, sizeof l->params[p].def);
        if (k.param->type == NPRFX_PARAM_STRING) l->params[p].def_string = l->values[p].s;
    }
    /* several write nodes: which one's image the effect shows */
    l->output_param = -1;
    if (l->noutputs > 1 && np < LOOK_MAX_KNOBS) {
        int p = l->output_param = np++;
        for (int o = 0; o < l->noutputs; o++)
            l->output_choices[o] = l->output_label[o];
        nprfx_param_desc *d = &l->params[p];
        snprintf(l->param_name[p], sizeof l->param_name[p], "output");
        snprintf(l->param_label[p], sizeof l->param_label[p], "Output");
        d->name = l->param_name[p];
        d->label = l->param_label[p];
        d->help = "Which of the graph's write nodes' images the effect shows.";
        d->type = NPRFX_PARAM_CHOICE;
        d->choices = l->output_choices;
        d->hard_max = d->soft_max = l->noutputs - 1;
    }
    l->desc.size = sizeof l->desc;
    l->desc.id = l->id;
    l->desc.label = l->label;
    l->comment = copy(nprfx_graph_comment(g));
    l->desc.help = l->comment;
    l->desc.group = "Looks";
    l->desc.version_major = 1;
    l->desc.version_minor = 0;
    l->desc.flags = l->temporal ? NPRFX_NODE_TEMPORAL : 0;
    l->desc.num_inputs = ni;
    l->desc.inputs = l->in;
    l->desc.num_params = np;
    l->desc.params = l->params;
    return NPRFX_OK;
}

int look_desc_layer_aov(const look_desc *l, int k)
{
    int aov = l->aov[k];
    if (!l->main[k] || aov < 0 || aov == NPRFX_AOV_MOTION_PREV || aov == NPRFX_AOV_MOTION_NEXT)
        return -1;
    return aov;
}

void look_desc_layer_name(int aov, char *buf, size_t n)
{
    snprintf(buf, n, "layer_%s", nprfx_aov_name(aov));
}

void look_desc_layer_label(int aov, char *buf, size_t n)
{
    snprintf(buf, n, "%s layer", nprfx_aov_name(aov));
    if (buf[0] >= 'a' && buf[0] <= 'z') buf[0] = (char)(buf[0] - 'a' + 'A');
    for (char *c = buf; *c; c++)
        if (*c == '_') *c = ' ';
}
