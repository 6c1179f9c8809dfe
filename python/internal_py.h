/* nprfx Python module — what its files share: the exception, contexts with worker threads,
 * arrays to images and back, namespaces. Never installed. */
#ifndef NPRFX_INTERNAL_PY_H
#define NPRFX_INTERNAL_PY_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include "nprfx/context.h"
#include "nprfx/exec.h"
#include "nprfx/image.h"
#include "nprfx/node.h"

/* nprfx.Error */
extern PyObject *internal_py_error;

/* A context and the pool of worker threads it runs on (threads <= 0: every core). */
typedef struct internal_py_env {
    nprfx_context *ctx;
    nprfx_pool *pool;
} internal_py_env;

int internal_py_env_init(internal_py_env *env, int threads);
void internal_py_env_free(internal_py_env *env);

/* Raise nprfx.Error with ctx's last message; returns NULL. */
PyObject *internal_py_raise(const nprfx_context *ctx);

/* An array for input `name` of `node`: float32 items, H x W or H x W x C, any strides, copied
 * into *out at the origin. *w, *h: the size every input of one render shares (-1 before the
 * first); the channel count is checked against the input's. 0, or -1 with the error raised. */
int internal_py_take_array(nprfx_context *ctx, const nprfx_node_desc *node, int input,
                           PyObject *obj, int *w, int *h, nprfx_image *out);

/* A new H x W x C numpy.float32 array with im's pixels (its bounds, top row first). */
PyObject *internal_py_make_array(const nprfx_image *im);

/* types.SimpleNamespace(**kw), kw consumed (NULL: the error stays raised). */
PyObject *internal_py_namespace(PyObject *kw);

/* Params from a dict {name: value} into values (defaults already there), each through the
 * text the runner's --set parses; the str objects STRING values point into are kept in keep. */
int internal_py_take_params(nprfx_context *ctx, const nprfx_node_desc *node, PyObject *params,
                            nprfx_value *values, PyObject *keep);

/* The text a Python value stands for in an assignment: bools as true/false, sequences joined
 * by commas, anything else as str() gives it. New reference, NULL with the error raised. */
PyObject *internal_py_value_text(PyObject *value);

/* A param's value as Python sees it: a number, a bool, a choice's name, a colour's tuple, a
 * string. */
PyObject *internal_py_param_value(const nprfx_param_desc *p, const nprfx_value *v);
/* A param's description from its descriptor (nodes()'s params): name, label, help, type,
 * default, min, max, soft_min, soft_max, choices. */
PyObject *internal_py_param_info(const nprfx_param_desc *p);

/* Module parts. */
extern PyTypeObject internal_py_node_type;
extern PyTypeObject internal_py_graph_type;
PyObject *internal_py_nodes(PyObject *self, PyObject *noargs);

#endif
