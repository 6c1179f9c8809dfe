/* nprfx Python module — `import nprfx`: the node list from the descriptors, render() of one
 * node, and the Node and Graph types (py_node.c, py_graph.c).
 *
 * Written against CPython's C API and the buffer protocol alone: an input is any object that
 * exports float32 items (a NumPy array, any strides), so the module needs no NumPy headers; a
 * result is made by numpy.empty. Everything a node is (inputs, params, their help, ranges and
 * defaults) comes from its descriptor, as for the runner and the OpenFX plug-in. */
#include "internal_py.h"

#include <string.h>

/* ---- the node list ---------------------------------------------------------------------- */

static PyObject *str_or_none(const char *s)
{
    if (s) return PyUnicode_FromString(s);
    Py_RETURN_NONE;
}

static PyObject *param_default(const nprfx_param_desc *p)
{
    nprfx_value v;
    memset(&v, 0, sizeof v);
    memcpy(v.v, p->def, sizeof v.v);
    v.s = p->def_string ? p->def_string : "";
    return internal_py_param_value(p, &v);
}

PyObject *internal_py_param_info(const nprfx_param_desc *p)
{
    PyObject *choices = NULL;
    if (p->choices) {
        choices = PyList_New(0);
        for (int i = 0; choices && p->choices[i]; i++) {
            PyObject *c = PyUnicode_FromString(p->choices[i]);
            if (!c || PyList_Append(choices, c)) Py_CLEAR(choices);
            Py_XDECREF(c);
        }
        if (!choices) return NULL;
    } else {
        choices = Py_None;
        Py_INCREF(choices);
    }
    return internal_py_namespace(Py_BuildValue(
        "{s:s,s:N,s:N,s:s,s:N,s:d,s:d,s:d,s:d,s:N}", "name", p->name, "label",
        str_or_none(p->label), "help", str_or_none(p->help), "type", nprfx_param_type_name(p->type),
        "default", param_default(p), "min", p->hard_min, "max", p->hard_max, "soft_min",
        p->soft_min, "soft_max", p->soft_max, "choices", choices));
}

static PyObject *input_info(const nprfx_input_desc *in)
{
    return internal_py_namespace(Py_BuildValue(
        "{s:s,s:N,s:N,s:N,s:i,s:O,s:O}", "name", in->name, "label", str_or_none(in->label), "help",
        str_or_none(in->help), "aov", str_or_none(in->aov), "channels", in->channels, "optional",
        (in->flags & NPRFX_INPUT_OPTIONAL) ? Py_True : Py_False, "temporal",
        (in->flags & NPRFX_INPUT_TEMPORAL) ? Py_True : Py_False));
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
        PyObject *v = internal_py_param_info(&d->params[i]);
        if (!v || PyDict_SetItemString(params, d->params[i].name, v)) Py_CLEAR(params);
        Py_XDECREF(v);
    }
    if (!inputs || !params) {
        Py_XDECREF(inputs);
        Py_XDECREF(params);
        return NULL;
    }
    return internal_py_namespace(Py_BuildValue(
        "{s:s,s:N,s:N,s:N,s:N,s:i,s:O}", "id", d->id, "label", str_or_none(d->label), "help",
        str_or_none(d->help), "inputs", inputs, "params", params, "output_channels",
        d->output_channels, "temporal", (d->flags & NPRFX_NODE_TEMPORAL) ? Py_True : Py_False));
}

PyObject *internal_py_nodes(PyObject *self, PyObject *noargs)
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

/* ---- render: a Node made for one frame ---------------------------------------------------- */

static PyObject *py_render(PyObject *self, PyObject *args, PyObject *kw)
{
    (void)self;
    static char *names[] = {"node", "inputs", "params", "frame", "threads", NULL};
    const char *id;
    PyObject *inputs = NULL, *params = NULL;
    int frame = 1, threads = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "s|OOii", names, &id, &inputs, &params, &frame,
                                     &threads))
        return NULL;
    PyObject *n = PyObject_CallFunction((PyObject *)&internal_py_node_type, "sOi", id,
                                        params ? params : Py_None, threads);
    if (!n) return NULL;
    PyObject *r = PyObject_CallMethod(n, "render", "iO", frame, inputs ? inputs : Py_None);
    Py_DECREF(n);
    return r;
}

/* The render docstring: its usage, then the node list with each node's first sentence. */
static char *render_doc(void)
{
    static const char head[] =
        "render(node, inputs={}, params={}, frame=1, threads=0) -> numpy.ndarray\n\n"
        "Render one node at one frame on float32 arrays (H x W or H x W x C, any strides),\n"
        "returning a new H x W x C float32 array. params take what the runner's --set takes\n"
        "(numbers, bools, choice names, colours as sequences); threads: worker threads (0:\n"
        "every core). The GIL is released while the node computes. Errors raise nprfx.Error\n"
        "with the runner's words. For a temporal node over a sequence, use nprfx.Node.\n\n"
        "Nodes (nprfx.nodes() gives their inputs and params):\n";
    size_t n = sizeof head;
    for (int i = 0; i < nprfx_node_count(); i++)
        n += 100;
    char *doc = PyMem_Malloc(n), *p = doc;
    if (!doc) return NULL;
    p += snprintf(p, n, "%s", head);
    for (int i = 0; i < nprfx_node_count(); i++) {
        const nprfx_node_desc *d = nprfx_node_at(i);
        const char *h = d->help ? d->help : "";
        size_t len = strcspn(h, ".\n");
        if (len > 70) len = 67;
        p += snprintf(p, (size_t)(doc + n - p), "  %-15s %.*s%s\n", d->id, (int)len, h,
                      len == 67 ? "..." : "");
    }
    return doc;
}

static PyMethodDef methods[] = {
    {"nodes", internal_py_nodes, METH_NOARGS,
     "nodes() -> dict: every node by id (inputs, params with type, default, range and help, "
     "from its descriptor)."},
    {"render", (PyCFunction)(void (*)(void))py_render, METH_VARARGS | METH_KEYWORDS, NULL},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "nprfx",
    "nprfx: temporally coherent non-photorealistic rendering nodes on NumPy arrays.\n\n"
    "nodes(), render() and Node for single nodes; Graph for graph files, run by the same\n"
    "engine as `nprfx run`; Error for everything refused.",
    -1, methods};

PyMODINIT_FUNC PyInit_nprfx(void)
{
    static char *doc;
    if (!doc) doc = render_doc();
    methods[1].ml_doc = doc;
    if (PyType_Ready(&internal_py_node_type) || PyType_Ready(&internal_py_graph_type)) return NULL;
    PyObject *m = PyModule_Create(&module);
    if (!m) return NULL;
    internal_py_error = PyErr_NewExceptionWithDoc(
        "nprfx.Error", "A node or graph refused its input; the message names what and why.", NULL,
        NULL);
    if (!internal_py_error || PyModule_AddObjectRef(m, "Error", internal_py_error) ||
        PyModule_AddObjectRef(m, "Node", (PyObject *)&internal_py_node_type) ||
        PyModule_AddObjectRef(m, "Graph", (PyObject *)&internal_py_graph_type)) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
