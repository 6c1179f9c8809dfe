/* nprfx — the Python module: every node from its descriptor, rendered on NumPy float32 arrays.
 *
 * Written against CPython's C API and the buffer protocol alone: an input is any object that
 * exports float32 items (a NumPy array, any strides), so the module needs no NumPy headers; the
 * result is made by calling numpy.empty. Everything a node is (inputs, params, their help,
 * ranges and defaults) comes from its descriptor, as the runner's and the OpenFX plug-in's. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <string.h>

#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/image.h"
#include "nprfx/node.h"

static PyObject *nprfx_py_error; /* nprfx.Error */

/* ---- the node list ---------------------------------------------------------------------- */

/* types.SimpleNamespace(**kw), consuming kw */
static PyObject *make_namespace(PyObject *kw)
{
    if (!kw) return NULL;
    PyObject *types = PyImport_ImportModule("types"), *ns = NULL;
    if (types) {
        PyObject *cls = PyObject_GetAttrString(types, "SimpleNamespace");
        if (cls) {
            PyObject *args = PyTuple_New(0);
            if (args) ns = PyObject_Call(cls, args, kw);
            Py_XDECREF(args);
            Py_DECREF(cls);
        }
        Py_DECREF(types);
    }
    Py_DECREF(kw);
    return ns;
}

static PyObject *str_or_none(const char *s)
{
    if (s) return PyUnicode_FromString(s);
    Py_RETURN_NONE;
}

/* A param's default as Python sees it: a number, a bool, a choice's name, a colour's tuple, a
 * string. */
static PyObject *param_default(const nprfx_param_desc *p)
{
    switch (p->type) {
    case NPRFX_PARAM_BOOL:
        return PyBool_FromLong(p->def[0] != 0.0);
    case NPRFX_PARAM_INT:
        return PyLong_FromDouble(p->def[0]);
    case NPRFX_PARAM_CHOICE:
        return str_or_none(p->choices ? p->choices[(int)p->def[0]] : NULL);
    case NPRFX_PARAM_COLOR:
        return Py_BuildValue("(dddd)", p->def[0], p->def[1], p->def[2], p->def[3]);
    case NPRFX_PARAM_STRING:
        return PyUnicode_FromString(p->def_string ? p->def_string : "");
    default:
        return PyFloat_FromDouble(p->def[0]);
    }
}

static PyObject *param_info(const nprfx_param_desc *p)
{
    PyObject *choices = Py_None;
    Py_INCREF(Py_None);
    if (p->choices) {
        Py_DECREF(choices);
        choices = PyList_New(0);
        for (int i = 0; choices && p->choices[i]; i++) {
            PyObject *c = PyUnicode_FromString(p->choices[i]);
            if (!c || PyList_Append(choices, c)) Py_CLEAR(choices);
            Py_XDECREF(c);
        }
        if (!choices) return NULL;
    }
    return make_namespace(Py_BuildValue(
        "{s:s,s:N,s:N,s:s,s:N,s:d,s:d,s:d,s:d,s:N}", "name", p->name, "label",
        str_or_none(p->label), "help", str_or_none(p->help), "type", nprfx_param_type_name(p->type),
        "default", param_default(p), "min", p->hard_min, "max", p->hard_max, "soft_min",
        p->soft_min, "soft_max", p->soft_max, "choices", choices));
}

static PyObject *input_info(const nprfx_input_desc *in)
{
    return make_namespace(Py_BuildValue(
        "{s:s,s:N,s:N,s:N,s:i,s:O}", "name", in->name, "label", str_or_none(in->label), "help",
        str_or_none(in->help), "aov", str_or_none(in->aov), "channels", in->channels, "optional",
        (in->flags & NPRFX_INPUT_OPTIONAL) ? Py_True : Py_False));
}

static PyObject *node_info(const nprfx_node_desc *d)
{
    PyObject *inputs = PyDict_New(), *params = PyDict_New();
    for (int i = 0; inputs && i < d->num_inputs; i++) {
        PyObject *v = input_info(&d->inputs[i]);
        if (!v || PyDict_SetItemString(inputs, d->inputs[i].name, v)) Py_CLEAR(inputs);
        Py_XDECREF(v);
    }
    for (int i = 0; params && i < d->num_params; i++) {
        PyObject *v = param_info(&d->params[i]);
        if (!v || PyDict_SetItemString(params, d->params[i].name, v)) Py_CLEAR(params);
        Py_XDECREF(v);
    }
    if (!inputs || !params) {
        Py_XDECREF(inputs);
        Py_XDECREF(params);
        return NULL;
    }
    return make_namespace(Py_BuildValue("{s:s,s:N,s:N,s:N,s:N,s:i}", "id", d->id, "label",
                                        str_or_none(d->label), "help", str_or_none(d->help),
                                        "inputs", inputs, "params", params, "output_channels",
                                        d->output_channels));
}

static PyObject *py_nodes(PyObject *self, PyObject *noargs)
{
    (void)self;
    (void)noargs;
    PyObject *all = PyDict_New();
    for (int i = 0; all && i < nprfx_node_count(); i++) {
        const nprfx_node_desc *d = nprfx_node_at(i);
        PyObject *v = node_info(d);
        if (!v || PyDict_SetItemString(all, d->id, v)) Py_CLEAR(all);
        Py_XDECREF(v);
    }
    return all;
}

/* ---- render ------------------------------------------------------------------------------- */

/* What one render holds, freed by render_free whatever happened. */
typedef struct render_job {
    const nprfx_node_desc *node;
    nprfx_context *ctx;
    nprfx_pool *pool;
    nprfx_image in[64];
    int in_channels[64];
    nprfx_value params[256];
    PyObject *texts; /* the str objects STRING params point into */
    nprfx_image out;
} render_job;

static void render_free(render_job *j)
{
    for (int i = 0; i < 64; i++)
        nprfx_image_free(&j->in[i]);
    nprfx_image_free(&j->out);
    if (j->ctx) nprfx_context_destroy(j->ctx);
    if (j->pool) nprfx_pool_destroy(j->pool);
    Py_XDECREF(j->texts);
}

static PyObject *raise_context(render_job *j)
{
    char msg[2048];
    nprfx_context_last_error(j->ctx, msg, sizeof msg);
    PyErr_SetString(nprfx_py_error, msg);
    return NULL;
}

/* Input `name` from obj: float32 items, H x W or H x W x C (any strides), copied into an
 * image; every input of one render has the same H x W. */
static int take_input(render_job *j, const char *name, PyObject *obj, int *w, int *h)
{
    int k = nprfx_node_input_index(j->node, name);
    if (k < 0) {
        PyErr_Format(nprfx_py_error, "%s has no input '%s'", j->node->id, name);
        return -1;
    }
    Py_buffer v;
    if (PyObject_GetBuffer(obj, &v, PyBUF_RECORDS_RO)) {
        PyErr_Clear();
        PyErr_Format(nprfx_py_error,
                     "%s input '%s': an array of float32 (H x W or H x W x C) is needed, not %s",
                     j->node->id, name, Py_TYPE(obj)->tp_name);
        return -1;
    }
    const char *f = v.format ? v.format : "B";
    if (*f == '<' || *f == '=' || *f == '@') f++;
    int ch = v.ndim == 3 ? (int)v.shape[2] : 1;
    const nprfx_input_desc *d = &j->node->inputs[k];
    const char *why = strcmp(f, "f") || v.itemsize != 4  ? "its items are not float32"
                      : v.ndim != 2 && v.ndim != 3       ? "it is not H x W or H x W x C"
                      : v.shape[0] < 1 || v.shape[1] < 1 ? "it is empty"
                      : d->channels > 0 && ch != d->channels
                          ? "its channel count is not the input's"
                      : d->channels == 0 && (ch < 1 || ch > 4) ? "it has not 1 to 4 channels"
                                                               : NULL;
    if (!why && *w >= 0 && (v.shape[1] != *w || v.shape[0] != *h))
        why = "its size is not the others'";
    if (why) {
        PyErr_Format(nprfx_py_error, "%s input '%s' (%d dimensions, format '%s'): %s", j->node->id,
                     name, v.ndim, v.format ? v.format : "B", why);
        PyBuffer_Release(&v);
        return -1;
    }
    *h = (int)v.shape[0];
    *w = (int)v.shape[1];
    if (nprfx_image_alloc(j->ctx, nprfx_rect_make(0, 0, *w, *h), ch, &j->in[k])) {
        PyBuffer_Release(&v);
        raise_context(j);
        return -1;
    }
    const char *base = v.buf;
    for (int y = 0; y < *h; y++)
        for (int x = 0; x < *w; x++) {
            float *dst = nprfx_image_at(&j->in[k], x, y);
            for (int c = 0; c < ch; c++) {
                const char *p = base + y * v.strides[0] + x * v.strides[1] +
                                (v.ndim == 3 ? c * v.strides[2] : 0);
                memcpy(&dst[c], p, sizeof(float));
            }
        }
    j->in_channels[k] = ch;
    PyBuffer_Release(&v);
    return 0;
}

/* Param `name` from a Python value, through the text the runner's --set parses. */
static int take_param(render_job *j, const char *name, PyObject *value)
{
    int k = nprfx_node_param_index(j->node, name);
    if (k < 0) {
        PyErr_Format(nprfx_py_error, "%s has no param '%s'", j->node->id, name);
        return -1;
    }
    PyObject *text;
    if (PyBool_Check(value)) {
        text = PyUnicode_FromString(value == Py_True ? "true" : "false");
    } else if (PyList_Check(value) || PyTuple_Check(value)) {
        PyObject *sep = PyUnicode_FromString(","), *parts = PyList_New(0);
        for (Py_ssize_t i = 0; sep && parts && i < PySequence_Size(value); i++) {
            PyObject *item = PySequence_GetItem(value, i), *s = item ? PyObject_Str(item) : NULL;
            if (!s || PyList_Append(parts, s)) Py_CLEAR(parts);
            Py_XDECREF(s);
            Py_XDECREF(item);
        }
        text = sep && parts ? PyUnicode_Join(sep, parts) : NULL;
        Py_XDECREF(sep);
        Py_XDECREF(parts);
    } else {
        text = PyObject_Str(value);
    }
    if (!text || PyList_Append(j->texts, text)) {
        Py_XDECREF(text);
        return -1;
    }
    Py_DECREF(text);
    const char *s = PyUnicode_AsUTF8(text); /* kept alive by j->texts */
    if (!s) return -1;
    if (nprfx_param_parse(j->ctx, j->node, &j->node->params[k], s, &j->params[k])) {
        raise_context(j);
        return -1;
    }
    return 0;
}

PyDoc_STRVAR(render_doc,
             "render(node, inputs={}, params={}, frame=1, threads=0) -> numpy.ndarray\n\n"
             "Render one node (an id of nprfx.nodes()) at one frame on float32 arrays (H x W or\n"
             "H x W x C, any strides), returning a new H x W x C float32 array. params take\n"
             "what the runner's --set takes (numbers, bools, choice names, colours as\n"
             "sequences). threads: worker threads (0: every core). The GIL is released while\n"
             "the node computes. Errors raise nprfx.Error with the runner's words.");

static PyObject *py_render(PyObject *self, PyObject *args, PyObject *kw)
{
    (void)self;
    static char *names[] = {"node", "inputs", "params", "frame", "threads", NULL};
    const char *node_id;
    PyObject *inputs = NULL, *params = NULL;
    int frame = 1, threads = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "s|OOii", names, &node_id, &inputs, &params, &frame,
                                     &threads))
        return NULL;
    render_job j;
    memset(&j, 0, sizeof j);
    j.node = nprfx_node_find(node_id);
    if (!j.node)
        return PyErr_Format(nprfx_py_error, "no node '%s' (nprfx.nodes() lists them)", node_id);
    if (j.node->num_inputs > 64 || j.node->num_params > 256)
        return PyErr_Format(nprfx_py_error, "%s: too many inputs or params", node_id);
    PyObject *result = NULL;
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    if (threads != 1 && nprfx_pool_create(threads, &j.pool) == NPRFX_OK)
        init.executor = nprfx_pool_executor(j.pool);
    if (nprfx_context_create(&init, &j.ctx)) {
        PyErr_SetString(nprfx_py_error, "out of memory creating a context");
        goto done;
    }
    j.texts = PyList_New(0);
    if (!j.texts) goto done;
    nprfx_node_defaults(j.node, j.params);
    int w = -1, h = -1;
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    if (inputs && inputs != Py_None) {
        if (!PyDict_Check(inputs)) {
            PyErr_SetString(nprfx_py_error, "inputs: a dict {input name: array} is needed");
            goto done;
        }
        while (PyDict_Next(inputs, &pos, &key, &value)) {
            const char *name = PyUnicode_Check(key) ? PyUnicode_AsUTF8(key) : NULL;
            if (!name) {
                PyErr_SetString(nprfx_py_error, "inputs: names must be strings");
                goto done;
            }
            if (take_input(&j, name, value, &w, &h)) goto done;
        }
    }
    if (w < 0) {
        PyErr_Format(nprfx_py_error, "%s: connect at least one input (its size is the output's)",
                     node_id);
        goto done;
    }
    pos = 0;
    if (params && params != Py_None) {
        if (!PyDict_Check(params)) {
            PyErr_SetString(nprfx_py_error, "params: a dict {param name: value} is needed");
            goto done;
        }
        while (PyDict_Next(params, &pos, &key, &value)) {
            const char *name = PyUnicode_Check(key) ? PyUnicode_AsUTF8(key) : NULL;
            if (!name) {
                PyErr_SetString(nprfx_py_error, "params: names must be strings");
                goto done;
            }
            if (take_param(&j, name, value)) goto done;
        }
    }
    nprfx_output_info oi;
    if (nprfx_node_output_info(j.ctx, j.node, j.params, j.in_channels, &oi)) {
        raise_context(&j);
        goto done;
    }
    nprfx_rect frame_rect = nprfx_rect_make(0, 0, w, h);
    if (nprfx_image_alloc(j.ctx, frame_rect, oi.channels, &j.out)) {
        raise_context(&j);
        goto done;
    }
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = j.ctx;
    a.node = j.node;
    a.time = frame;
    a.render_scale = 1;
    a.frame = frame_rect;
    a.window = frame_rect;
    a.first_frame = a.last_frame = frame;
    a.inputs = j.in;
    a.params = j.params;
    a.output = &j.out;
    nprfx_result r;
    Py_BEGIN_ALLOW_THREADS r = nprfx_node_render(&a);
    Py_END_ALLOW_THREADS if (r)
    {
        raise_context(&j);
        goto done;
    }
    PyObject *numpy = PyImport_ImportModule("numpy");
    if (!numpy) goto done;
    result = PyObject_CallMethod(numpy, "empty", "((iii)s)", h, w, oi.channels, "float32");
    Py_DECREF(numpy);
    if (!result) goto done;
    Py_buffer v;
    if (PyObject_GetBuffer(result, &v, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE)) {
        Py_CLEAR(result);
        goto done;
    }
    float *dst = v.buf;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            memcpy(dst + ((size_t)y * w + x) * oi.channels, nprfx_image_at(&j.out, x, y),
                   sizeof(float) * oi.channels);
    PyBuffer_Release(&v);
done:
    render_free(&j);
    return result;
}

static PyMethodDef methods[] = {
    {"nodes", py_nodes, METH_NOARGS,
     "nodes() -> dict: every node by id, with its inputs and params (type, default, range, help) "
     "from its descriptor."},
    {"render", (PyCFunction)(void (*)(void))py_render, METH_VARARGS | METH_KEYWORDS, render_doc},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "nprfx",
                                    "nprfx: temporally coherent NPR nodes on NumPy arrays.", -1,
                                    methods};

PyMODINIT_FUNC PyInit_nprfx(void)
{
    PyObject *m = PyModule_Create(&module);
    if (!m) return NULL;
    nprfx_py_error = PyErr_NewExceptionWithDoc(
        "nprfx.Error", "A node or graph refused its input; the message names what and why.", NULL,
        NULL);
    if (!nprfx_py_error || PyModule_AddObject(m, "Error", nprfx_py_error)) {
        Py_XDECREF(nprfx_py_error);
        Py_DECREF(m);
        return NULL;
    }
    Py_INCREF(nprfx_py_error);
    return m;
}
