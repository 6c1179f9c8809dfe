/* nprfx Python module — contexts, errors, arrays, params and namespaces (internal_py.h). */
#include "internal_py.h"

#include <stdlib.h>
#include <string.h>

#include "flow_opencv.h"

PyObject *internal_py_error;

int internal_py_env_init(internal_py_env *env, int threads)
{
    memset(env, 0, sizeof *env);
    nprfx_context_init init = NPRFX_CONTEXT_INIT_DEFAULT;
    /* as the runner: the stipple sequence's folder from $NPRFX_DATA_DIR (else generated when
     * needed, the same numbers), OpenCV's flow solver when the build has it */
    const char *data = getenv("NPRFX_DATA_DIR");
    init.data_dir = data && *data ? data : NULL;
    init.flow = flow_opencv_provider();
    /* threads 0: $NPRFX_THREADS when it is a positive number (as the runner), else every core */
    const char *nt = getenv("NPRFX_THREADS");
    if (threads <= 0 && nt && atoi(nt) > 0) threads = atoi(nt);
    if (threads != 1) {
        if (nprfx_pool_create(threads, &env->pool)) {
            PyErr_SetString(internal_py_error, "cannot start worker threads");
            return -1;
        }
        init.executor = nprfx_pool_executor(env->pool);
    }
    if (nprfx_context_create(&init, &env->ctx)) {
        if (env->pool) nprfx_pool_destroy(env->pool);
        env->pool = NULL;
        PyErr_NoMemory();
        return -1;
    }
    return 0;
}

void internal_py_env_free(internal_py_env *env)
{
    if (env->ctx) nprfx_context_destroy(env->ctx);
    if (env->pool) nprfx_pool_destroy(env->pool);
    memset(env, 0, sizeof *env);
}

PyObject *internal_py_raise(const nprfx_context *ctx)
{
    char msg[4096];
    nprfx_context_last_error(ctx, msg, sizeof msg);
    PyErr_SetString(internal_py_error, msg);
    return NULL;
}

int internal_py_take_array(nprfx_context *ctx, const nprfx_node_desc *node, int input,
                           PyObject *obj, int *w, int *h, nprfx_image *out)
{
    const nprfx_input_desc *d = &node->inputs[input];
    Py_buffer v;
    if (PyObject_GetBuffer(obj, &v, PyBUF_RECORDS_RO)) {
        PyErr_Clear();
        PyErr_Format(internal_py_error,
                     "%s input '%s': an array of float32 (H x W or H x W x C) is needed, not %s",
                     node->id, d->name, Py_TYPE(obj)->tp_name);
        return -1;
    }
    const char *f = v.format ? v.format : "B";
    if (*f == '<' || *f == '=' || *f == '@') f++;
    const int ch = v.ndim == 3 ? (int)v.shape[2] : 1;
    char want[64] = "1 to 4 channels";
    if (d->channels > 0)
        snprintf(want, sizeof want, "%d channel%s", d->channels, d->channels > 1 ? "s" : "");
    const char *why =
        strcmp(f, "f") || v.itemsize != 4 ? "its items are not float32 (dtype=numpy.float32)"
        : v.ndim != 2 && v.ndim != 3      ? "it is not H x W or H x W x C"
        : v.shape[0] < 1 || v.shape[1] < 1 || v.shape[0] > 1 << 20 || v.shape[1] > 1 << 20
            ? "its size is outside 1 to 2^20"
        : (d->channels > 0 ? ch != d->channels : ch < 1 || ch > 4) ? "channels"
                                                                   : NULL;
    if (!why && *w >= 0 && (v.shape[1] != *w || v.shape[0] != *h)) why = "size";
    if (why) {
        if (!strcmp(why, "channels"))
            PyErr_Format(internal_py_error,
                         "%s input '%s': it has %d channel%s; the input takes %s", node->id,
                         d->name, ch, ch == 1 ? "" : "s", want);
        else if (!strcmp(why, "size"))
            PyErr_Format(internal_py_error,
                         "%s input '%s': it is %zd x %zd (W x H); the other inputs are %d x %d",
                         node->id, d->name, v.shape[1], v.shape[0], *w, *h);
        else
            PyErr_Format(internal_py_error, "%s input '%s' (%d dimensions, format '%s'): %s",
                         node->id, d->name, v.ndim, v.format ? v.format : "B", why);
        PyBuffer_Release(&v);
        return -1;
    }
    *h = (int)v.shape[0];
    *w = (int)v.shape[1];
    if (nprfx_image_alloc(ctx, nprfx_rect_make(0, 0, *w, *h), ch, out)) {
        PyBuffer_Release(&v);
        internal_py_raise(ctx);
        return -1;
    }
    const char *base = v.buf;
    const Py_ssize_t sc = v.ndim == 3 ? v.strides[2] : 0;
    for (int y = 0; y < *h; y++) {
        const char *row = base + y * v.strides[0];
        float *dst = nprfx_image_at(out, 0, y);
        for (int x = 0; x < *w; x++, dst += out->pixel_stride) {
            const char *p = row + x * v.strides[1];
            for (int c = 0; c < ch; c++)
                memcpy(&dst[c], p + c * sc, sizeof(float));
        }
    }
    PyBuffer_Release(&v);
    return 0;
}

PyObject *internal_py_make_array(const nprfx_image *im)
{
    const int w = nprfx_rect_width(im->bounds), h = nprfx_rect_height(im->bounds);
    const int ch = im->channels;
    PyObject *numpy = PyImport_ImportModule("numpy");
    if (!numpy) return NULL;
    PyObject *a = PyObject_CallMethod(numpy, "empty", "((iii)s)", h, w, ch, "float32");
    Py_DECREF(numpy);
    if (!a) return NULL;
    Py_buffer v;
    if (PyObject_GetBuffer(a, &v, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE)) {
        Py_DECREF(a);
        return NULL;
    }
    float *dst = v.buf;
    for (int y = 0; y < h; y++) {
        const float *src = nprfx_image_at(im, im->bounds.x0, im->bounds.y0 + y);
        for (int x = 0; x < w; x++, src += im->pixel_stride, dst += ch)
            memcpy(dst, src, sizeof(float) * (size_t)ch);
    }
    PyBuffer_Release(&v);
    return a;
}

PyObject *internal_py_namespace(PyObject *kw)
{
    if (!kw) return NULL;
    PyObject *types = PyImport_ImportModule("types"), *ns = NULL;
    if (types) {
        PyObject *cls = PyObject_GetAttrString(types, "SimpleNamespace");
        PyObject *args = PyTuple_New(0);
        if (cls && args) ns = PyObject_Call(cls, args, kw);
        Py_XDECREF(args);
        Py_XDECREF(cls);
        Py_DECREF(types);
    }
    Py_DECREF(kw);
    return ns;
}

PyObject *internal_py_value_text(PyObject *value)
{
    if (PyBool_Check(value)) return PyUnicode_FromString(value == Py_True ? "true" : "false");
    if (!PyList_Check(value) && !PyTuple_Check(value)) return PyObject_Str(value);
    PyObject *sep = PyUnicode_FromString(","), *parts = PyList_New(0), *text = NULL;
    const Py_ssize_t n = PySequence_Size(value);
    for (Py_ssize_t i = 0; sep && parts && i < n; i++) {
        PyObject *item = PySequence_GetItem(value, i), *s = item ? PyObject_Str(item) : NULL;
        if (!s || PyList_Append(parts, s)) Py_CLEAR(parts);
        Py_XDECREF(s);
        Py_XDECREF(item);
    }
    if (sep && parts) text = PyUnicode_Join(sep, parts);
    Py_XDECREF(sep);
    Py_XDECREF(parts);
    return text;
}

int internal_py_take_params(nprfx_context *ctx, const nprfx_node_desc *node, PyObject *params,
                            nprfx_value *values, PyObject *keep)
{
    if (!params || params == Py_None) return 0;
    if (!PyDict_Check(params)) {
        PyErr_SetString(internal_py_error, "params: a dict {param name: value} is needed");
        return -1;
    }
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(params, &pos, &key, &value)) {
        const char *name = PyUnicode_Check(key) ? PyUnicode_AsUTF8(key) : NULL;
        if (!name) {
            PyErr_SetString(internal_py_error, "params: names must be strings");
            return -1;
        }
        const int k = nprfx_node_param_index(node, name);
        if (k < 0) {
            PyErr_Format(internal_py_error, "%s has no param '%s' (nprfx.nodes()['%s'].params)",
                         node->id, name, node->id);
            return -1;
        }
        PyObject *text = internal_py_value_text(value);
        if (!text || PyList_Append(keep, text)) {
            Py_XDECREF(text);
            return -1;
        }
        Py_DECREF(text); /* keep holds it: STRING values point into it */
        const char *s = PyUnicode_AsUTF8(text);
        if (!s) return -1;
        if (nprfx_param_parse(ctx, node, &node->params[k], s, &values[k])) {
            internal_py_raise(ctx);
            return -1;
        }
    }
    return 0;
}

PyObject *internal_py_param_value(const nprfx_param_desc *p, const nprfx_value *v)
{
    switch (p->type) {
    case NPRFX_PARAM_BOOL:
        return PyBool_FromLong(v->v[0] != 0.0);
    case NPRFX_PARAM_INT:
        return PyLong_FromDouble(v->v[0]);
    case NPRFX_PARAM_CHOICE: {
        int n = 0;
        while (p->choices && p->choices[n])
            n++;
        int c = (int)v->v[0];
        if (c >= 0 && c < n) return PyUnicode_FromString(p->choices[c]);
        Py_RETURN_NONE;
    }
    case NPRFX_PARAM_COLOR:
        return Py_BuildValue("(dddd)", v->v[0], v->v[1], v->v[2], v->v[3]);
    case NPRFX_PARAM_STRING:
        return PyUnicode_FromString(v->s ? v->s : "");
    default:
        return PyFloat_FromDouble(v->v[0]);
    }
}
