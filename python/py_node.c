/* nprfx Python module — nprfx.Node: one node with its params and the state a temporal node
 * keeps between frames, rendered frame after frame on arrays. */
#include "internal_py.h"

#include <string.h>

/* The frames of inputs a node remembers for its fetches (those given to earlier renders). */
#define KEEP_FRAMES 8

typedef struct kept_frame {
    int frame;       /* valid when in != NULL */
    nprfx_image *in; /* num_inputs images, data NULL where not given */
} kept_frame;

typedef struct py_node {
    PyObject_HEAD const nprfx_node_desc *desc;
    internal_py_env env;
    nprfx_value *params;
    PyObject *keep;  /* the str objects STRING params point into */
    PyObject *fetch; /* a callable fetch(input, frame) -> array, or NULL */
    void *state;     /* the node's per-instance slot */
    int first, last; /* the shot (last < first: unknown) */
    kept_frame kept[KEEP_FRAMES];
    int next_kept;
    /* what the fetch callback answers from, during one render */
    nprfx_image fetched[NPRFX_FETCH_KEEP];
    int next_fetched;
    int busy;
    PyObject *channels; /* the last render's output channel names */
} py_node;

static void kept_clear(py_node *n, kept_frame *k)
{
    for (int i = 0; k->in && i < n->desc->num_inputs; i++)
        nprfx_image_free(&k->in[i]);
    PyMem_Free(k->in);
    k->in = NULL;
}

static void node_dealloc(py_node *n)
{
    for (int i = 0; i < KEEP_FRAMES; i++)
        kept_clear(n, &n->kept[i]);
    for (int i = 0; i < NPRFX_FETCH_KEEP; i++)
        nprfx_image_free(&n->fetched[i]);
    if (n->state && n->desc && n->desc->state_free) n->desc->state_free(n->state);
    internal_py_env_free(&n->env);
    PyMem_Free(n->params);
    Py_XDECREF(n->keep);
    Py_XDECREF(n->fetch);
    Py_XDECREF(n->channels);
    Py_TYPE(n)->tp_free((PyObject *)n);
}

static int parse_shot(PyObject *shot, int *first, int *last)
{
    *first = 0;
    *last = -1;
    if (!shot || shot == Py_None) return 0;
    if (!PyArg_ParseTuple(shot, "ii;shot: (first, last) frames", first, last)) return -1;
    if (*last < *first) {
        PyErr_Format(internal_py_error, "shot: (%d, %d) ends before it starts", *first, *last);
        return -1;
    }
    return 0;
}

static int node_init(py_node *n, PyObject *args, PyObject *kw)
{
    static char *names[] = {"node", "params", "threads", "shot", "fetch", NULL};
    const char *id;
    PyObject *params = NULL, *shot = NULL, *fetch = NULL;
    int threads = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "s|OiOO", names, &id, &params, &threads, &shot,
                                     &fetch))
        return -1;
    if (n->desc) {
        PyErr_SetString(internal_py_error, "a Node is made once");
        return -1;
    }
    n->desc = nprfx_node_find(id);
    if (!n->desc) {
        PyErr_Format(internal_py_error, "no node '%s' (nprfx.nodes() lists them)", id);
        return -1;
    }
    if (fetch && fetch != Py_None && !PyCallable_Check(fetch)) {
        PyErr_SetString(internal_py_error, "fetch: a callable fetch(input, frame) -> array");
        return -1;
    }
    if (parse_shot(shot, &n->first, &n->last)) return -1;
    n->params = PyMem_Calloc((size_t)n->desc->num_params + 1, sizeof *n->params);
    n->keep = PyList_New(0);
    if (!n->params || !n->keep) {
        PyErr_NoMemory();
        return -1;
    }
    if (internal_py_env_init(&n->env, threads)) return -1;
    nprfx_node_defaults(n->desc, n->params);
    if (internal_py_take_params(n->env.ctx, n->desc, params, n->params, n->keep)) return -1;
    if (fetch && fetch != Py_None) {
        Py_INCREF(fetch);
        n->fetch = fetch;
    }
    return 0;
}

/* The node's fetch: from the fetch callable (the GIL taken again), else from the inputs given
 * to earlier renders. */
static nprfx_result node_fetch(void *user, int input, double time, nprfx_image *out)
{
    py_node *n = user;
    const int frame = (int)time;
    const char *name = n->desc->inputs[input].name;
    if (!n->fetch) {
        for (int i = 0; i < KEEP_FRAMES; i++) {
            kept_frame *k = &n->kept[i];
            if (k->in && k->frame == frame) {
                if (!k->in[input].data) break;
                *out = k->in[input];
                return NPRFX_OK;
            }
        }
        return nprfx_error(n->env.ctx, NPRFX_ERR_MISSING_INPUT,
                           "%s input '%s' at frame %d: not given to this Node (it remembers the "
                           "inputs of its last %d renders); render the frames in order, or give "
                           "the Node a fetch(input, frame) callable",
                           n->desc->id, name, frame, KEEP_FRAMES);
    }
    PyGILState_STATE gs = PyGILState_Ensure();
    nprfx_result r = NPRFX_OK;
    PyObject *a = PyObject_CallFunction(n->fetch, "si", name, frame);
    nprfx_image *slot = &n->fetched[n->next_fetched];
    n->next_fetched = (n->next_fetched + 1) % NPRFX_FETCH_KEEP;
    nprfx_image_free(slot);
    if (!a) {
        PyErr_Clear();
        r = nprfx_error(n->env.ctx, NPRFX_ERR_IO, "%s input '%s' at frame %d: fetch raised",
                        n->desc->id, name, frame);
    } else if (a == Py_None) {
        r = nprfx_error(n->env.ctx, NPRFX_ERR_MISSING_INPUT,
                        "%s input '%s' at frame %d: fetch gave None", n->desc->id, name, frame);
    } else {
        int w = -1, h = -1;
        if (internal_py_take_array(n->env.ctx, n->desc, input, a, &w, &h, slot)) {
            PyObject *t, *v, *tb;
            PyErr_Fetch(&t, &v, &tb);
            PyObject *s = v ? PyObject_Str(v) : NULL;
            r = nprfx_error(n->env.ctx, NPRFX_ERR_INVALID_ARGUMENT, "%s (from fetch, frame %d)",
                            s ? PyUnicode_AsUTF8(s) : "a bad array", frame);
            Py_XDECREF(s);
            Py_XDECREF(t);
            Py_XDECREF(v);
            Py_XDECREF(tb);
        } else {
            *out = *slot;
        }
    }
    Py_XDECREF(a);
    PyGILState_Release(gs);
    return r;
}

/* Render frame on inputs (a dict {input name: array}); the result a new array. */
static PyObject *node_render(py_node *n, PyObject *args, PyObject *kw)
{
    static char *names[] = {"frame", "inputs", NULL};
    int frame;
    PyObject *inputs = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "i|O", names, &frame, &inputs)) return NULL;
    if (!n->desc) return PyErr_Format(internal_py_error, "the Node was not made");
    if (n->busy)
        return PyErr_Format(internal_py_error,
                            "%s: this Node is rendering on another thread (one frame at a time; "
                            "make a Node per thread)",
                            n->desc->id);
    const int ni = n->desc->num_inputs;
    kept_frame cur = {frame, PyMem_Calloc((size_t)ni + 1, sizeof(nprfx_image))};
    int *chans = PyMem_Calloc((size_t)ni + 1, sizeof(int));
    nprfx_image out;
    memset(&out, 0, sizeof out);
    PyObject *result = NULL;
    if (!cur.in || !chans) {
        PyErr_NoMemory();
        goto done;
    }
    int w = -1, h = -1;
    if (inputs && inputs != Py_None) {
        if (!PyDict_Check(inputs)) {
            PyErr_SetString(internal_py_error, "inputs: a dict {input name: array} is needed");
            goto done;
        }
        PyObject *key, *value;
        Py_ssize_t pos = 0;
        while (PyDict_Next(inputs, &pos, &key, &value)) {
            const char *name = PyUnicode_Check(key) ? PyUnicode_AsUTF8(key) : NULL;
            const int k = name ? nprfx_node_input_index(n->desc, name) : -1;
            if (k < 0) {
                PyErr_Format(internal_py_error, "%s has no input '%s' (nprfx.nodes()['%s'].inputs)",
                             n->desc->id, name ? name : "?", n->desc->id);
                goto done;
            }
            if (internal_py_take_array(n->env.ctx, n->desc, k, value, &w, &h, &cur.in[k]))
                goto done;
            chans[k] = cur.in[k].channels;
        }
    }
    if (w < 0) {
        PyErr_Format(internal_py_error, "%s: give at least one input (its size is the output's)",
                     n->desc->id);
        goto done;
    }
    nprfx_output_info oi;
    const nprfx_rect rect = nprfx_rect_make(0, 0, w, h);
    if (nprfx_node_output_info(n->env.ctx, n->desc, n->params, chans, &oi) ||
        nprfx_image_alloc(n->env.ctx, rect, oi.channels, &out)) {
        internal_py_raise(n->env.ctx);
        goto done;
    }
    nprfx_render_args a;
    memset(&a, 0, sizeof a);
    a.size = sizeof a;
    a.ctx = n->env.ctx;
    a.node = n->desc;
    a.time = frame;
    a.render_scale = 1;
    a.frame = rect;
    a.window = rect;
    a.first_frame = n->first;
    a.last_frame = n->last;
    a.inputs = cur.in;
    a.params = n->params;
    a.output = &out;
    a.fetch = node_fetch;
    a.fetch_user = n;
    a.state = &n->state;
    /* this frame's inputs are what a later frame fetches of it */
    kept_frame *slot = &n->kept[n->next_kept];
    kept_clear(n, slot);
    *slot = cur;
    cur.in = NULL;
    n->next_kept = (n->next_kept + 1) % KEEP_FRAMES;
    nprfx_result r;
    n->busy = 1;
    Py_BEGIN_ALLOW_THREADS;
    r = nprfx_node_render(&a);
    Py_END_ALLOW_THREADS;
    n->busy = 0;
    if (r) {
        internal_py_raise(n->env.ctx);
        goto done;
    }
    result = internal_py_make_array(&out);
    PyObject *out_names = result ? PyTuple_New(oi.channels) : NULL;
    for (int c = 0; out_names && c < oi.channels; c++) {
        PyObject *s = PyUnicode_FromString(oi.names[c] ? oi.names[c] : "");
        if (!s)
            Py_CLEAR(out_names);
        else
            PyTuple_SET_ITEM(out_names, c, s);
    }
    if (!out_names) {
        Py_CLEAR(result);
        goto done;
    }
    Py_XSETREF(n->channels, out_names);
done:
    if (cur.in) kept_clear(n, &cur);
    PyMem_Free(chans);
    nprfx_image_free(&out);
    return result;
}

static PyMethodDef node_methods[] = {
    {"render", (PyCFunction)(void (*)(void))node_render, METH_VARARGS | METH_KEYWORDS,
     "render(frame, inputs) -> numpy.ndarray: the node at frame on inputs {name: float32 array}; "
     "a temporal node fetches earlier frames from the inputs given to this Node's earlier "
     "renders (or from its fetch callable), and keeps its state from frame to frame."},
    {NULL, NULL, 0, NULL}};

static PyObject *node_get_id(py_node *n, void *closure)
{
    (void)closure;
    if (!n->desc) Py_RETURN_NONE;
    return PyUnicode_FromString(n->desc->id);
}

static PyObject *node_get_channels(py_node *n, void *closure)
{
    (void)closure;
    if (!n->channels) Py_RETURN_NONE;
    Py_INCREF(n->channels);
    return n->channels;
}

static PyGetSetDef node_getset[] = {
    {"id", (getter)node_get_id, NULL, "the node's id", NULL},
    {"channels", (getter)node_get_channels, NULL,
     "the names of the last render's output channels (as the runner writes them), or None", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

PyTypeObject internal_py_node_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "nprfx.Node",
    .tp_basicsize = sizeof(py_node),
    .tp_dealloc = (destructor)node_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Node(node, params={}, threads=0, shot=None, fetch=None): one node of "
              "nprfx.nodes() with its params; render(frame, inputs) frame after frame. shot: "
              "(first, last), the frames temporal nodes see as the shot (None: unknown). "
              "fetch(input, frame) -> array: where a temporal node gets other frames' inputs "
              "(None: the inputs given to this Node's last renders).",
    .tp_methods = node_methods,
    .tp_getset = node_getset,
    .tp_init = (initproc)node_init,
    .tp_new = PyType_GenericNew,
};
