/* Descriptor helpers: defaults, parsing and checking values, the output description. Everything a
 * front end (CLI, OFX adapter, docs) needs to know about a param comes from its descriptor. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nprfx/node.h"

int nprfx_node_param_index(const nprfx_node_desc *node, const char *name)
{
    for (int i = 0; node && name && i < node->num_params; i++)
        if (strcmp(node->params[i].name, name) == 0) return i;
    return -1;
}

int nprfx_node_input_index(const nprfx_node_desc *node, const char *name)
{
    for (int i = 0; node && name && i < node->num_inputs; i++)
        if (strcmp(node->inputs[i].name, name) == 0) return i;
    return -1;
}

void nprfx_node_defaults(const nprfx_node_desc *node, nprfx_value *values)
{
    for (int i = 0; i < node->num_params; i++) {
        const nprfx_param_desc *p = &node->params[i];
        memcpy(values[i].v, p->def, sizeof values[i].v);
        values[i].s = p->def_string ? p->def_string : "";
    }
}

const char *nprfx_param_type_name(nprfx_param_type t)
{
    switch (t) {
    case NPRFX_PARAM_DOUBLE:
        return "double";
    case NPRFX_PARAM_INT:
        return "int";
    case NPRFX_PARAM_BOOL:
        return "bool";
    case NPRFX_PARAM_CHOICE:
        return "choice";
    case NPRFX_PARAM_COLOR:
        return "colour";
    case NPRFX_PARAM_STRING:
        return "string";
    }
    return "?";
}

/* %g without trailing noise: enough digits to read back the same double. */
static void fmt_number(char *buf, size_t n, double v)
{
    snprintf(buf, n, "%.10g", v);
}

static int choice_count(const nprfx_param_desc *p)
{
    int n = 0;
    while (p->choices && p->choices[n])
        n++;
    return n;
}

nprfx_result nprfx_param_check(nprfx_context *ctx, const nprfx_node_desc *node,
                               const nprfx_param_desc *p, const nprfx_value *v)
{
    const char *nid = node ? node->id : "?";
    int comps = p->type == NPRFX_PARAM_COLOR ? 4 : 1;
    if (p->type == NPRFX_PARAM_STRING) return NPRFX_OK;
    for (int c = 0; c < comps; c++) {
        double x = v->v[c];
        if (!isfinite(x))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "%s.%s: value is not a finite number",
                               nid, p->name);
        if ((p->type == NPRFX_PARAM_INT || p->type == NPRFX_PARAM_CHOICE ||
             p->type == NPRFX_PARAM_BOOL) &&
            x != floor(x))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "%s.%s: %g is not a whole number", nid,
                               p->name, x);
        if (p->type == NPRFX_PARAM_CHOICE) {
            if (x < 0 || x >= choice_count(p))
                return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                                   "%s.%s: option index %g does not exist", nid, p->name, x);
            continue;
        }
        if (p->type == NPRFX_PARAM_BOOL) {
            if (x != 0 && x != 1)
                return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "%s.%s: %g is not a boolean", nid,
                                   p->name, x);
            continue;
        }
        if (x < p->hard_min || x > p->hard_max) {
            char lo[32], hi[32], val[32];
            fmt_number(lo, sizeof lo, p->hard_min);
            fmt_number(hi, sizeof hi, p->hard_max);
            fmt_number(val, sizeof val, x);
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE,
                               "%s.%s: %s is outside the range [%s, %s]", nid, p->name, val, lo,
                               hi);
        }
    }
    return NPRFX_OK;
}

static int parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    while (isspace((unsigned char)*s))
        s++;
    if (!*s) return 0;
    double v = strtod(s, &end);
    while (isspace((unsigned char)*end))
        end++;
    if (*end || errno == ERANGE) return 0;
    *out = v;
    return 1;
}

nprfx_result nprfx_param_parse(nprfx_context *ctx, const nprfx_node_desc *node,
                               const nprfx_param_desc *p, const char *text, nprfx_value *out)
{
    const char *nid = node ? node->id : "?";
    memcpy(out->v, p->def, sizeof out->v);
    out->s = p->def_string ? p->def_string : "";
    if (!text) return nprfx_error(ctx, NPRFX_ERR_PARSE, "%s.%s: no value given", nid, p->name);
    switch (p->type) {
    case NPRFX_PARAM_STRING:
        out->s = text;
        return NPRFX_OK;
    case NPRFX_PARAM_BOOL:
        if (!strcmp(text, "1") || !strcmp(text, "true") || !strcmp(text, "on") ||
            !strcmp(text, "yes"))
            out->v[0] = 1;
        else if (!strcmp(text, "0") || !strcmp(text, "false") || !strcmp(text, "off") ||
                 !strcmp(text, "no"))
            out->v[0] = 0;
        else
            return nprfx_error(ctx, NPRFX_ERR_PARSE,
                               "%s.%s: '%s' is not a boolean (use true/false, on/off, 1/0)", nid,
                               p->name, text);
        return NPRFX_OK;
    case NPRFX_PARAM_CHOICE: {
        int n = choice_count(p);
        for (int i = 0; i < n; i++)
            if (!strcmp(text, p->choices[i])) {
                out->v[0] = i;
                return NPRFX_OK;
            }
        char list[512] = "";
        for (int i = 0; i < n; i++) {
            if (i) strncat(list, ", ", sizeof list - strlen(list) - 1);
            strncat(list, p->choices[i], sizeof list - strlen(list) - 1);
        }
        return nprfx_error(ctx, NPRFX_ERR_OUT_OF_RANGE, "%s.%s: '%s' is not one of: %s", nid,
                           p->name, text, list);
    }
    case NPRFX_PARAM_COLOR: {
        double c[4];
        int n = 0;
        char buf[256];
        snprintf(buf, sizeof buf, "%s", text);
        for (char *tok = strtok(buf, ", \t"); tok; tok = strtok(NULL, ", \t")) {
            if (n == 4 || !parse_double(tok, &c[n]))
                return nprfx_error(ctx, NPRFX_ERR_PARSE,
                                   "%s.%s: '%s' is not a colour (1, 3 or 4 numbers)", nid, p->name,
                                   text);
            n++;
        }
        if (n == 1)
            c[1] = c[2] = c[0], c[3] = 1;
        else if (n == 3)
            c[3] = 1;
        else if (n != 4)
            return nprfx_error(ctx, NPRFX_ERR_PARSE,
                               "%s.%s: '%s' is not a colour (1, 3 or 4 numbers)", nid, p->name,
                               text);
        memcpy(out->v, c, sizeof c);
        break;
    }
    case NPRFX_PARAM_DOUBLE:
    case NPRFX_PARAM_INT:
        if (!parse_double(text, &out->v[0]))
            return nprfx_error(ctx, NPRFX_ERR_PARSE, "%s.%s: '%s' is not a number", nid, p->name,
                               text);
        break;
    }
    return nprfx_param_check(ctx, node, p, out);
}

char *nprfx_param_format(const nprfx_param_desc *p, const nprfx_value *v, char *buf, size_t n)
{
    char a[32], b[32], c[32], d[32];
    switch (p->type) {
    case NPRFX_PARAM_STRING:
        snprintf(buf, n, "%s", v->s ? v->s : "");
        break;
    case NPRFX_PARAM_BOOL:
        snprintf(buf, n, "%s", v->v[0] != 0 ? "true" : "false");
        break;
    case NPRFX_PARAM_CHOICE: {
        int i = (int)v->v[0];
        snprintf(buf, n, "%s", i >= 0 && i < choice_count(p) ? p->choices[i] : "?");
        break;
    }
    case NPRFX_PARAM_COLOR:
        fmt_number(a, sizeof a, v->v[0]);
        fmt_number(b, sizeof b, v->v[1]);
        fmt_number(c, sizeof c, v->v[2]);
        fmt_number(d, sizeof d, v->v[3]);
        snprintf(buf, n, "%s,%s,%s,%s", a, b, c, d);
        break;
    default:
        fmt_number(buf, n, v->v[0]);
        break;
    }
    return buf;
}

static const char *const default_names[4][4] = {
    {"Y"}, {"R", "G"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};

nprfx_result nprfx_node_output_info(nprfx_context *ctx, const nprfx_node_desc *node,
                                    const nprfx_value *params, const int *input_channels,
                                    nprfx_output_info *out)
{
    memset(out, 0, sizeof *out);
    if (node->output) {
        nprfx_result r = node->output(params, input_channels, out);
        if (r) return nprfx_error(ctx, r, "%s: cannot determine the output channels", node->id);
    } else if (node->output_channels > 0) {
        out->channels = node->output_channels;
    } else {
        out->channels = node->num_inputs > 0 ? input_channels[0] : 0;
    }
    if (out->channels < 1 || out->channels > NPRFX_MAX_CHANNELS)
        return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT,
                           "%s: the output would have %d channels (is input '%s' connected?)",
                           node->id, out->channels,
                           node->num_inputs > 0 ? node->inputs[0].name : "");
    for (int c = 0; c < out->channels; c++)
        if (!out->names[c])
            out->names[c] = out->channels <= 4 ? default_names[out->channels - 1][c] : "C";
    return NPRFX_OK;
}

void nprfx_node_apply_render_scale(const nprfx_node_desc *node, nprfx_value *values,
                                   double render_scale)
{
    for (int i = 0; i < node->num_params; i++) {
        if (node->params[i].flags & NPRFX_PARAM_PIXELS) values[i].v[0] *= render_scale;
        if (node->params[i].flags & NPRFX_PARAM_AREA) values[i].v[0] *= render_scale * render_scale;
    }
}
