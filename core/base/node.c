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

void nprfx_node_apply_render_scale(const nprfx_node_desc *node, nprfx_value *values,
                                   double render_scale)
{
    for (int i = 0; i < node->num_params; i++) {
        const nprfx_param_desc *p = &node->params[i];
        if (!(p->flags & (NPRFX_PARAM_PIXELS | NPRFX_PARAM_AREA))) continue;
        double v = values[i].v[0];
        int was_in_range = v >= p->hard_min && v <= p->hard_max;
        v *= (p->flags & NPRFX_PARAM_AREA) ? render_scale * render_scale : render_scale;
        /* A valid size stays valid at any scale: a proxy draws a fine paper thread at its
         * smallest size rather than refusing the frame (a value already out of range is left
         * for the check to name). */
        if (p->type == NPRFX_PARAM_INT) v = floor(v + 0.5);
        if (was_in_range) v = v < p->hard_min ? p->hard_min : v > p->hard_max ? p->hard_max : v;
        values[i].v[0] = v;
    }
}

/* ---- rendering through the descriptor ------------------------------------------------------- */

/* Typed params structs of every node fit here; a larger one is allocated. Aligned for doubles and
 * pointers, the widest fields a struct holds. */
#define BIND_INLINE_BYTES 1024
/* Inputs a node may declare (the checks keep their channel counts on the stack). */
#define NPRFX_MAX_INPUTS_CHECKED 32

/* Check every value and store it at its param's offset in `typed`. */
static nprfx_result bind_params(nprfx_context *ctx, const nprfx_node_desc *node,
                                const nprfx_value *values, void *typed)
{
    for (int i = 0; i < node->num_params; i++) {
        const nprfx_param_desc *p = &node->params[i];
        nprfx_result r = nprfx_param_check(ctx, node, p, &values[i]);
        if (r) return r;
        if (!typed) continue;
        unsigned char *field = (unsigned char *)typed + p->offset;
        switch (p->type) {
        case NPRFX_PARAM_DOUBLE:
            memcpy(field, &values[i].v[0], sizeof(double));
            break;
        case NPRFX_PARAM_INT:
        case NPRFX_PARAM_BOOL:
        case NPRFX_PARAM_CHOICE: {
            int k = (int)values[i].v[0]; /* whole and in range: checked above */
            memcpy(field, &k, sizeof k);
            break;
        }
        case NPRFX_PARAM_COLOR:
            memcpy(field, values[i].v, 4 * sizeof(double));
            break;
        case NPRFX_PARAM_STRING: {
            const char *s = values[i].s ? values[i].s : "";
            memcpy(field, &s, sizeof s);
            break;
        }
        }
    }
    return NPRFX_OK;
}

/* The shared checks of nprfx_node_render/export; on success *a is a full-size copy of args. A
 * text export writes no pixels: it needs no output image (when one is given it is checked). */
static nprfx_result check_args(const nprfx_render_args *args, nprfx_render_args *a, int need_output)
{
    if (!args) return NPRFX_ERR_INVALID_ARGUMENT;
    nprfx_context *ctx = args->ctx;
    if (args->size < NPRFX_RENDER_ARGS_SIZE_V1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "render arguments of %zu bytes are older than any nprfx release",
                           args->size);
    memset(a, 0, sizeof *a);
    memcpy(a, args, args->size < sizeof *a ? args->size : sizeof *a);
    if (args->size < NPRFX_RENDER_ARGS_SIZE_V2 + sizeof a->vector_scale || !(a->vector_scale > 0))
        a->vector_scale = a->render_scale;
    a->size = sizeof *a;
    const nprfx_node_desc *d = a->node;
    if (!d || !d->render)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "render arguments name no node");
    if (!need_output && (!a->output || !a->output->data)) a->output = NULL;
    if ((d->num_inputs > 0 && !a->inputs) || (d->num_params > 0 && !a->params) ||
        (need_output && (!a->output || !a->output->data)))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s: incomplete render arguments (inputs, params or output missing)",
                           d->id);
    /* Tiles at the edges may reach past the image: a node writes only what exists. */
    if (a->output) a->window = nprfx_rect_intersect(a->window, a->output->bounds);
    int ich[NPRFX_MAX_INPUTS_CHECKED];
    if (d->num_inputs > NPRFX_MAX_INPUTS_CHECKED)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: more than %d inputs", d->id,
                           NPRFX_MAX_INPUTS_CHECKED);
    for (int i = 0; i < d->num_inputs; i++) {
        const nprfx_input_desc *in = &d->inputs[i];
        const nprfx_image *im = &a->inputs[i];
        ich[i] = im->data ? im->channels : 0;
        if (!im->data) {
            if (!(in->flags & NPRFX_INPUT_OPTIONAL))
                return nprfx_error(ctx, NPRFX_ERR_MISSING_INPUT, "%s: input '%s' is not connected",
                                   d->id, in->name);
            continue;
        }
        if (in->channels > 0 && im->channels != in->channels)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "%s: input '%s' has %d channels, expected %d", d->id, in->name,
                               im->channels, in->channels);
    }
    nprfx_output_info oi;
    nprfx_result r = nprfx_node_output_info(ctx, d, a->params, ich, &oi);
    if (r) return r;
    if (a->output && a->output->channels != oi.channels)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s: output has %d channels, expected %d", d->id, a->output->channels,
                           oi.channels);
    return NPRFX_OK;
}

/* A typed params struct: on the stack when it fits, else allocated. */
typedef struct typed_buf {
    union {
        unsigned char bytes[BIND_INLINE_BYTES];
        double align_d;
        void *align_p;
        long long align_l;
    } inline_buf;
    void *typed; /* NULL when the node declares no params_size */
} typed_buf;

/* Check the values and bind them into b->typed; release with typed_release. */
static nprfx_result typed_bind(nprfx_context *ctx, const nprfx_node_desc *d,
                               const nprfx_value *values, typed_buf *b)
{
    b->typed = NULL;
    if (d->params_size > sizeof b->inline_buf) {
        if (!(b->typed = calloc(1, d->params_size)))
            return nprfx_error(ctx, NPRFX_ERR_OUT_OF_MEMORY, "%s: out of memory", d->id);
    } else if (d->params_size > 0) {
        memset(&b->inline_buf, 0, d->params_size);
        b->typed = &b->inline_buf;
    }
    return bind_params(ctx, d, values, b->typed);
}

static void typed_release(typed_buf *b)
{
    if (b->typed != (void *)&b->inline_buf) free(b->typed);
    b->typed = NULL;
}

static const char *const default_names[4][4] = {
    {"Y"}, {"R", "G"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};

nprfx_result nprfx_node_output_info(nprfx_context *ctx, const nprfx_node_desc *node,
                                    const nprfx_value *params, const int *input_channels,
                                    nprfx_output_info *out)
{
    memset(out, 0, sizeof *out);
    if (node->output) {
        /* the callback reads the typed params struct, bound (and checked) as for render */
        typed_buf b;
        nprfx_result r = typed_bind(ctx, node, params, &b);
        if (r) return r;
        r = node->output(b.typed, input_channels, out);
        typed_release(&b);
        if (r)
            return nprfx_error(ctx, r, "%s: %s", node->id,
                               out->problem ? out->problem
                                            : "cannot determine the output channels");
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

typedef nprfx_result (*bound_call)(const nprfx_render_args *a, const void *typed, void *user);

/* Check args, bind params into a typed struct and call `call`. */
static nprfx_result with_bound_params(const nprfx_render_args *args, int need_output,
                                      bound_call call, void *user)
{
    nprfx_render_args a;
    nprfx_result r = check_args(args, &a, need_output);
    if (r) return r;
    typed_buf b;
    r = typed_bind(a.ctx, a.node, a.params, &b);
    if (!r) r = call(&a, b.typed, user);
    typed_release(&b);
    return r;
}

static nprfx_result call_render(const nprfx_render_args *a, const void *typed, void *user)
{
    (void)user;
    if (nprfx_rect_empty(a->window)) return NPRFX_OK;
    return a->node->render(a, typed);
}

nprfx_result nprfx_node_render(const nprfx_render_args *args)
{
    return with_bound_params(args, 1, call_render, NULL);
}

typedef struct export_call {
    const char *path;
    char **text;
    size_t *len;
} export_call;

static nprfx_result call_export(const nprfx_render_args *a, const void *typed, void *user)
{
    export_call *e = user;
    return a->node->export_text(a, typed, e->path, e->text, e->len);
}

nprfx_result nprfx_node_export(const nprfx_render_args *args, const char *path, char **text,
                               size_t *len)
{
    if (!args || !text || !len) return NPRFX_ERR_INVALID_ARGUMENT;
    *text = NULL;
    *len = 0;
    if (args->node && !args->node->export_text)
        return nprfx_error(args->ctx, NPRFX_ERR_UNSUPPORTED, "%s: the node has no text export",
                           args->node->id);
    export_call e = {path, text, len};
    return with_bound_params(args, 0, call_export, &e);
}

/* ---- frames needed ------------------------------------------------------------------------ */

static int range_cmp(const void *a, const void *b)
{
    const nprfx_frame_range *x = a, *y = b;
    return (x->first > y->first) - (x->first < y->first);
}

/* The default rule: a TEMPORAL input of a TEMPORAL node within fetch_before/after (within the
 * shot when it is known), any other input the frame itself. */
static int default_frames(const nprfx_node_desc *d, const nprfx_frames_query *q, int input,
                          nprfx_frame_range *out)
{
    const nprfx_input_desc *in = &d->inputs[input];
    out->first = out->last = q->time;
    if (!(d->flags & NPRFX_NODE_TEMPORAL) || !(in->flags & NPRFX_INPUT_TEMPORAL)) return 1;
    int known = q->last_frame >= q->first_frame;
    long long lo = in->fetch_before == NPRFX_FETCH_UNBOUNDED
                       ? (known ? q->first_frame : q->time)
                       : (long long)q->time - in->fetch_before;
    long long hi = in->fetch_after == NPRFX_FETCH_UNBOUNDED ? (known ? q->last_frame : q->time)
                                                            : (long long)q->time + in->fetch_after;
    if (known && lo < q->first_frame) lo = q->first_frame;
    if (known && hi > q->last_frame) hi = q->last_frame;
    out->first = lo < q->time ? (int)lo : q->time;
    out->last = hi > q->time ? (int)hi : q->time;
    return 1;
}

nprfx_result nprfx_node_frames_needed(nprfx_context *ctx, const nprfx_node_desc *node,
                                      const nprfx_value *params, const nprfx_frames_query *q,
                                      int input, nprfx_frame_range *ranges, int *count)
{
    if (!count) return NPRFX_ERR_INVALID_ARGUMENT;
    *count = 0;
    if (!node || !q || !ranges || !q->input_channels || (node->num_params > 0 && !params) ||
        input < 0 || input >= node->num_inputs)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_node_frames_needed: no node, query, ranges or input %d", input);
    if (q->input_channels[input] <= 0) return NPRFX_OK;
    /* one slot more than a node may fill, for the frame itself */
    nprfx_frame_range r[NPRFX_MAX_FRAME_RANGES + 1];
    int n;
    int has_fn = node->size >= offsetof(nprfx_node_desc, frames_needed) + sizeof(void *) &&
                 node->frames_needed;
    if (has_fn) {
        typed_buf b;
        nprfx_result res = typed_bind(ctx, node, params, &b);
        n = res ? 0 : node->frames_needed(b.typed, q, input, r);
        typed_release(&b);
        if (res) return res;
        if (n < 0 || n > NPRFX_MAX_FRAME_RANGES)
            return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "%s: frames_needed gave %d ranges",
                               node->id, n);
    } else {
        n = default_frames(node, q, input, r);
    }
    /* The front ends hand every connected input over at the frame itself. */
    r[n].first = r[n].last = q->time;
    n++;
    for (int i = 0; i < n; i++)
        if (r[i].last < r[i].first) {
            int t = r[i].first;
            r[i].first = r[i].last;
            r[i].last = t;
        }
    qsort(r, (size_t)n, sizeof r[0], range_cmp);
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (m > 0 && (long long)r[i].first <= (long long)ranges[m - 1].last + 1) {
            if (r[i].last > ranges[m - 1].last) ranges[m - 1].last = r[i].last;
        } else if (m < NPRFX_MAX_FRAME_RANGES) {
            ranges[m++] = r[i];
        } else { /* more disjoint ranges than slots: widen the last (never miss a frame) */
            if (r[i].last > ranges[m - 1].last) ranges[m - 1].last = r[i].last;
        }
    }
    *count = m;
    return NPRFX_OK;
}

nprfx_result nprfx_node_footprint(nprfx_context *ctx, const nprfx_node_desc *node,
                                  const nprfx_value *params, int *radius)
{
    if (!radius) return NPRFX_ERR_INVALID_ARGUMENT;
    *radius = 0;
    if (!node || (node->num_params > 0 && !params))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_node_footprint: no node or params");
    if (node->size < offsetof(nprfx_node_desc, footprint) + sizeof(void *) || !node->footprint)
        return NPRFX_OK;
    typed_buf b;
    nprfx_result r = typed_bind(ctx, node, params, &b);
    if (!r) *radius = node->footprint(b.typed);
    typed_release(&b);
    if (!r && *radius < -1)
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "%s: footprint gave %d", node->id, *radius);
    return r;
}

nprfx_result nprfx_node_state_bytes(nprfx_context *ctx, const nprfx_node_desc *node,
                                    const nprfx_value *params, const nprfx_state_query *q,
                                    double *bytes)
{
    if (!bytes) return NPRFX_ERR_INVALID_ARGUMENT;
    *bytes = 0;
    if (!node || !q || (node->num_params > 0 && !params))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "nprfx_node_state_bytes: no node, query or params");
    if (node->size < offsetof(nprfx_node_desc, state_bytes) + sizeof(void *) || !node->state_bytes)
        return NPRFX_OK;
    typed_buf b;
    nprfx_result r = typed_bind(ctx, node, params, &b);
    if (!r) *bytes = node->state_bytes(b.typed, q);
    typed_release(&b);
    if (!r && !(*bytes >= 0))
        return nprfx_error(ctx, NPRFX_ERR_INTERNAL, "%s: state_bytes gave %g", node->id, *bytes);
    return r;
}

/* ---- shot-wide measurements ----------------------------------------------------------------- */

int nprfx_node_measures_shot(const nprfx_node_desc *node)
{
    return node && node->size >= offsetof(nprfx_node_desc, state_load) + sizeof(void *) &&
           node->state_save && node->state_load;
}

nprfx_result nprfx_node_state_save(nprfx_context *ctx, const nprfx_node_desc *node,
                                   const void *state, char **text)
{
    if (!text) return NPRFX_ERR_INVALID_ARGUMENT;
    *text = NULL;
    if (!nprfx_node_measures_shot(node))
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED, "%s: measures nothing over the shot",
                           node ? node->id : "(no node)");
    return state ? node->state_save(ctx, state, text) : NPRFX_OK;
}

nprfx_result nprfx_node_state_load(nprfx_context *ctx, const nprfx_node_desc *node, void **state,
                                   const char *text)
{
    if (!state || !text) return NPRFX_ERR_INVALID_ARGUMENT;
    if (!nprfx_node_measures_shot(node))
        return nprfx_error(ctx, NPRFX_ERR_UNSUPPORTED, "%s: measures nothing over the shot",
                           node ? node->id : "(no node)");
    return node->state_load(ctx, state, text);
}

/* ---- descriptor lint ------------------------------------------------------------------------ */

/* Identifiers are what graphs, --set and OFX use: lower-case letters, digits, '_' ('-' in node
 * ids), starting with a letter. */
static int good_name(const char *s, int dash)
{
    if (!s || !(*s >= 'a' && *s <= 'z')) return 0;
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= '0' && *s <= '9') || *s == '_' ||
              (dash && *s == '-')))
            return 0;
    return 1;
}

static int has_text(const char *s)
{
    return s && *s;
}

static size_t field_size(nprfx_param_type t)
{
    switch (t) {
    case NPRFX_PARAM_DOUBLE:
        return sizeof(double);
    case NPRFX_PARAM_COLOR:
        return 4 * sizeof(double);
    case NPRFX_PARAM_STRING:
        return sizeof(const char *);
    default:
        return sizeof(int);
    }
}

static size_t field_align(nprfx_param_type t)
{
    switch (t) {
    case NPRFX_PARAM_DOUBLE:
    case NPRFX_PARAM_COLOR:
        return _Alignof(double);
    case NPRFX_PARAM_STRING:
        return _Alignof(const char *);
    default:
        return _Alignof(int);
    }
}

static nprfx_result lint_param(nprfx_context *ctx, const nprfx_node_desc *d, int i)
{
    const nprfx_param_desc *p = &d->params[i];
    const char *id = d->id;
    if (!good_name(p->name, 0))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: param %d has a bad name '%s'", id,
                           i, p->name ? p->name : "(null)");
    for (int k = 0; k < i; k++)
        if (!strcmp(d->params[k].name, p->name))
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: two params named '%s'", id,
                               p->name);
    if (!has_text(p->label) || !has_text(p->help))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s.%s: label or help missing", id,
                           p->name);
    if ((unsigned)p->type > NPRFX_PARAM_STRING)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s.%s: unknown type %d", id, p->name,
                           (int)p->type);
    if (p->type == NPRFX_PARAM_CHOICE) {
        int n = choice_count(p);
        if (n < 1)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s.%s: a choice without options",
                               id, p->name);
        if (p->hard_min != 0 || p->hard_max != n - 1 || p->soft_min != 0 || p->soft_max != n - 1)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "%s.%s: %d options but the range is [%g, %g] (use "
                               "NPRFX_CHOICE_RANGE)",
                               id, p->name, n, p->hard_min, p->hard_max);
        for (int k = 0; p->choice_help && k < n; k++)
            if (!has_text(p->choice_help[k]))
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "%s.%s: option '%s' has no help line", id, p->name,
                                   p->choices[k]);
        for (int k = 0; k < n; k++)
            for (int m = 0; m < k; m++)
                if (!strcmp(p->choices[k], p->choices[m]))
                    return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                       "%s.%s: two options named '%s'", id, p->name, p->choices[k]);
    } else if (p->choices) {
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s.%s: options on a non-choice param",
                           id, p->name);
    }
    if (p->type != NPRFX_PARAM_STRING && p->type != NPRFX_PARAM_CHOICE &&
        p->type != NPRFX_PARAM_BOOL) {
        if (!(p->hard_min <= p->soft_min && p->soft_min <= p->soft_max &&
              p->soft_max <= p->hard_max))
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "%s.%s: ranges out of order (hard [%g, %g], soft [%g, %g])", id,
                               p->name, p->hard_min, p->hard_max, p->soft_min, p->soft_max);
    }
    if (p->type == NPRFX_PARAM_STRING && (p->flags & NPRFX_PARAM_EXPORT) && !d->export_text)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s.%s: an export param on a node without export_text", id, p->name);
    nprfx_value v;
    memcpy(v.v, p->def, sizeof v.v);
    v.s = p->def_string ? p->def_string : "";
    if (nprfx_param_check(NULL, d, p, &v) != NPRFX_OK)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s.%s: the default is outside the param's range or type", id, p->name);
    if (d->params_size > 0) {
        size_t sz = field_size(p->type), al = field_align(p->type);
        if (p->offset + sz > d->params_size || p->offset % al)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "%s.%s: field at offset %zu does not fit a %s in a %zu-byte struct",
                               id, p->name, p->offset, nprfx_param_type_name(p->type),
                               d->params_size);
        for (int k = 0; k < i; k++) {
            const nprfx_param_desc *q = &d->params[k];
            size_t qs = field_size(q->type);
            if (p->offset < q->offset + qs && q->offset < p->offset + sz)
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                                   "%s: params '%s' and '%s' share bytes of the typed struct", id,
                                   q->name, p->name);
        }
    }
    return NPRFX_OK;
}

nprfx_result nprfx_node_lint(nprfx_context *ctx, const nprfx_node_desc *d)
{
    if (!d) return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "no descriptor");
    if (d->size != sizeof *d)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: size is %zu, not %zu",
                           d->id ? d->id : "?", d->size, sizeof *d);
    if (!good_name(d->id, 1))
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "a node has a bad id '%s'",
                           d->id ? d->id : "(null)");
    if (!has_text(d->label) || !has_text(d->group) || !has_text(d->help) || !d->render)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s: label, group, help or render missing", d->id);
    if (d->version_major < 1 || d->version_minor < 0)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: version %d.%d (starts at 1.0)",
                           d->id, d->version_major, d->version_minor);
    if (d->num_inputs < 0 || d->num_inputs > NPRFX_MAX_INPUTS_CHECKED || d->num_params < 0)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: %d inputs, %d params", d->id,
                           d->num_inputs, d->num_params);
    int mains = 0;
    for (int i = 0; i < d->num_inputs; i++) {
        const nprfx_input_desc *in = &d->inputs[i];
        if (!good_name(in->name, 0) || !has_text(in->label) || !has_text(in->help))
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "%s: input %d: bad name, or label or help missing", d->id, i);
        for (int k = 0; k < i; k++)
            if (!strcmp(d->inputs[k].name, in->name))
                return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: two inputs named '%s'",
                                   d->id, in->name);
        if (in->channels < 0 || in->channels > NPRFX_MAX_CHANNELS)
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: input '%s' wants %d channels",
                               d->id, in->name, in->channels);
        if ((in->flags & NPRFX_INPUT_TEMPORAL) && !(d->flags & NPRFX_NODE_TEMPORAL))
            return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                               "%s: input '%s' is temporal but the node is not", d->id, in->name);
        mains += (in->flags & NPRFX_INPUT_MAIN) != 0;
    }
    if (mains > 1)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s: %d main inputs (at most one)",
                           d->id, mains);
    if (d->num_params > 0 && !d->params_size)
        return nprfx_error(ctx, NPRFX_ERR_INVALID_ARGUMENT,
                           "%s: params without a typed struct (params_size)", d->id);
    for (int i = 0; i < d->num_params; i++) {
        nprfx_result r = lint_param(ctx, d, i);
        if (r) return r;
    }
    return NPRFX_OK;
}
