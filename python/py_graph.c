/* nprfx Python module — nprfx.Graph: a graph file (or dict) run by the library's graph engine,
 * the same calls `nprfx run` makes: load, overrides, the shot, the memory plan, the shot
 * statistics a previous `nprfx analyze` stored, then the frames with progress and costs. */
#include "internal_py.h"

#include <string.h>
#include <unistd.h>

#include "nprfx/graph.h"
#include "nprfx/io.h"
#include "nprfx/io_oiio.h"
#include "nprfx/seq.h"

typedef struct py_graph {
    PyObject_HEAD nprfx_graph *g;
    internal_py_env env;
    PyObject *path;     /* the graph file (None for a dict): its analysis file is found by it */
    PyObject *notices;  /* the engine's notes and warnings, in order */
    PyObject *progress; /* during run(): the callable, or NULL */
    PyObject *frames;   /* during run(): the per-frame records */
    int stopped;        /* during run(): the callable raised (or a record could not be made) */
    PyObject *exc[3];   /* during run(): that exception, until run() raises it */
    int busy;
} py_graph;

static void graph_dealloc(py_graph *s)
{
    nprfx_graph_free(s->g);
    internal_py_env_free(&s->env);
    Py_XDECREF(s->path);
    Py_XDECREF(s->notices);
    Py_TYPE(s)->tp_free((PyObject *)s);
}

/* The engine's notices (which part of a file a read took, ...): kept, in order. */
static void graph_notice(void *user, const char *message)
{
    py_graph *s = user;
    PyGILState_STATE gs = PyGILState_Ensure();
    PyObject *m = PyUnicode_FromString(message);
    if (!m || PyList_Append(s->notices, m)) PyErr_Clear();
    Py_XDECREF(m);
    PyGILState_Release(gs);
}

/* A new Graph from a file (path) or JSON text (json, base_dir). */
static PyObject *graph_make(PyTypeObject *type, const char *path, const char *json,
                            const char *base_dir, int threads, PyObject *mem_limit,
                            const char *output_dir)
{
    py_graph *s = (py_graph *)type->tp_alloc(type, 0);
    if (!s) return NULL;
    s->notices = PyList_New(0);
    if (!s->notices || internal_py_env_init(&s->env, threads)) goto fail;
    if (mem_limit && mem_limit != Py_None) {
        PyObject *t = PyObject_Str(mem_limit);
        const char *text = t ? PyUnicode_AsUTF8(t) : NULL;
        uint64_t bytes;
        if (!text || nprfx_parse_size(text, &bytes)) {
            if (text)
                PyErr_Format(internal_py_error,
                             "mem_limit '%s': give bytes or a size such as 4G, 512M", text);
            Py_XDECREF(t);
            goto fail;
        }
        Py_DECREF(t);
        nprfx_context_set_memory_limit(s->env.ctx, bytes, "mem_limit");
    }
    nprfx_graph_options opt;
    memset(&opt, 0, sizeof opt);
    opt.size = sizeof opt;
    opt.output_dir = output_dir;
    opt.io = nprfx_io_oiio();
    opt.notice = graph_notice;
    opt.notice_user = s;
    nprfx_result r;
    Py_BEGIN_ALLOW_THREADS;
    r = path ? nprfx_graph_load(s->env.ctx, path, &opt, &s->g)
             : nprfx_graph_parse(s->env.ctx, json, base_dir, &opt, &s->g);
    Py_END_ALLOW_THREADS;
    if (r) {
        internal_py_raise(s->env.ctx);
        goto fail;
    }
    s->path = path ? PyUnicode_FromString(path) : (Py_INCREF(Py_None), Py_None);
    if (!s->path) goto fail;
    return (PyObject *)s;
fail:
    Py_DECREF(s);
    return NULL;
}

static PyObject *graph_load(PyTypeObject *type, PyObject *args, PyObject *kw)
{
    static char *names[] = {"path", "threads", "mem_limit", "output_dir", NULL};
    const char *path, *output_dir = NULL;
    int threads = 0;
    PyObject *mem_limit = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "s|iOz", names, &path, &threads, &mem_limit,
                                     &output_dir))
        return NULL;
    return graph_make(type, path, NULL, NULL, threads, mem_limit, output_dir);
}

static PyObject *graph_from_dict(PyTypeObject *type, PyObject *args, PyObject *kw)
{
    static char *names[] = {"graph", "base_dir", "threads", "mem_limit", "output_dir", NULL};
    PyObject *d, *mem_limit = NULL;
    const char *base_dir = ".", *output_dir = NULL;
    int threads = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|siOz", names, &d, &base_dir, &threads, &mem_limit,
                                     &output_dir))
        return NULL;
    PyObject *json = PyImport_ImportModule("json");
    PyObject *text = json ? PyObject_CallMethod(json, "dumps", "O", d) : NULL;
    Py_XDECREF(json);
    const char *t = text ? PyUnicode_AsUTF8(text) : NULL;
    PyObject *g = t ? graph_make(type, NULL, t, base_dir, threads, mem_limit, output_dir) : NULL;
    Py_XDECREF(text);
    return g;
}

static int graph_ready(py_graph *s)
{
    if (!s->g) {
        PyErr_SetString(internal_py_error, "make a Graph with Graph.load or Graph.from_dict");
        return -1;
    }
    if (s->busy) {
        PyErr_SetString(internal_py_error, "the Graph is running on another thread");
        return -1;
    }
    return 0;
}

/* set("node.param", value): an override, as `nprfx run --set node.param=value`. */
static PyObject *graph_set(py_graph *s, PyObject *args)
{
    const char *what;
    PyObject *value;
    if (!PyArg_ParseTuple(args, "sO", &what, &value) || graph_ready(s)) return NULL;
    PyObject *text = internal_py_value_text(value);
    PyObject *a = text ? PyUnicode_FromFormat("%s=%U", what, text) : NULL;
    Py_XDECREF(text);
    const char *as = a ? PyUnicode_AsUTF8(a) : NULL;
    if (!as) {
        Py_XDECREF(a);
        return NULL;
    }
    nprfx_result r = nprfx_graph_set(s->g, as);
    Py_DECREF(a);
    if (r) return internal_py_raise(s->env.ctx);
    Py_RETURN_NONE;
}

/* The frames to render: `frames` (None: the graph's), after `shot` replaced the shot. */
static int graph_frames(py_graph *s, PyObject *frames, const char *shot, nprfx_frame_list *fl)
{
    if (shot && nprfx_graph_set_shot(s->g, shot)) {
        internal_py_raise(s->env.ctx);
        return -1;
    }
    PyObject *t = NULL;
    if (frames && frames != Py_None) {
        t = PyUnicode_Check(frames) ? (Py_INCREF(frames), frames) : internal_py_value_text(frames);
        if (!t) return -1;
    }
    const char *ft = t ? PyUnicode_AsUTF8(t) : NULL;
    nprfx_result r = nprfx_graph_frames(s->g, ft, fl);
    Py_XDECREF(t);
    if (r) {
        internal_py_raise(s->env.ctx);
        return -1;
    }
    return 0;
}

static PyObject *frame_list(const nprfx_frame_list *fl)
{
    PyObject *l = PyList_New(fl->count);
    for (int i = 0; l && i < fl->count; i++)
        PyList_SET_ITEM(l, i, PyLong_FromLong(fl->frames[i]));
    return l;
}

static PyObject *plan_info(const nprfx_graph_plan_info *p)
{
    return internal_py_namespace(Py_BuildValue(
        "{s:K,s:K,s:O,s:i,s:i,s:s,s:i,s:K}", "peak", (unsigned long long)p->peak, "need",
        (unsigned long long)p->need, "limit",
        p->limit == UINT64_MAX ? Py_None : PyLong_FromUnsignedLongLong(p->limit), "width", p->width,
        "height", p->height, "peak_node", p->peak_node ? p->peak_node : "", "strip_rows",
        p->strip_rows, "state", (unsigned long long)p->state));
}

/* The frames to render and the memory plan of the first, or -1 with the error raised: what
 * check() reports and run() does first (as `nprfx run` before it locks or renders anything). */
static int graph_plan(py_graph *s, PyObject *frames, const char *shot, nprfx_frame_list *fl,
                      nprfx_graph_plan_info *plan)
{
    if (!nprfx_graph_write_count(s->g)) {
        PyErr_SetString(internal_py_error,
                        "the graph has no write node, so it would produce nothing");
        return -1;
    }
    if (graph_frames(s, frames, shot, fl)) return -1;
    memset(plan, 0, sizeof *plan);
    nprfx_result r;
    Py_BEGIN_ALLOW_THREADS;
    r = nprfx_graph_check(s->g, fl, plan);
    Py_END_ALLOW_THREADS;
    if (r) {
        internal_py_raise(s->env.ctx);
        nprfx_seq_frames_free(fl);
        return -1;
    }
    return 0;
}

/* check(frames=None, shot=None): what a run would refuse before a pixel is read (no write node,
 * a memory plan over the limit); the frames and the plan. */
static PyObject *graph_check(py_graph *s, PyObject *args, PyObject *kw)
{
    static char *names[] = {"frames", "shot", NULL};
    PyObject *frames = NULL;
    const char *shot = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "|Oz", names, &frames, &shot) || graph_ready(s))
        return NULL;
    nprfx_frame_list fl = {NULL, 0};
    nprfx_graph_plan_info plan;
    if (graph_plan(s, frames, shot, &fl, &plan)) return NULL;
    PyObject *out = internal_py_namespace(
        Py_BuildValue("{s:N,s:N}", "frames", frame_list(&fl), "plan", plan_info(&plan)));
    nprfx_seq_frames_free(&fl);
    return out;
}

/* The shot statistics `nprfx analyze` stored (analysis: a path, "off", or None: the graph
 * file's own when it is there), as `nprfx run` seeds them. */
static int graph_seed(py_graph *s, const char *analysis)
{
    if (!nprfx_graph_measuring_nodes(s->g) || (analysis && !strcmp(analysis, "off"))) return 0;
    char path[8192];
    if (analysis) {
        snprintf(path, sizeof path, "%s", analysis);
    } else {
        if (s->path == Py_None) return 0;
        nprfx_graph_analysis_path(s->g, PyUnicode_AsUTF8(s->path), path, sizeof path);
        if (access(path, F_OK)) return 0;
    }
    int seeded = 0;
    if (nprfx_graph_analysis_load(s->g, path, &seeded)) {
        char msg[4096], note[4200];
        nprfx_context_last_error(s->env.ctx, msg, sizeof msg);
        snprintf(note, sizeof note, "warning: %s: measuring the shot in this run", msg);
        graph_notice(s, note);
    } else if (seeded) { /* as the runner says it */
        char note[8400];
        snprintf(note, sizeof note, "note: the shot statistics of %d node%s from %s", seeded,
                 seeded == 1 ? "" : "s", path);
        graph_notice(s, note);
    }
    return 0;
}

static int run_progress(void *user, const nprfx_graph_progress *p)
{
    py_graph *s = user;
    if (s->stopped) return 1; /* a frame written in the background reports after the stop */
    PyGILState_STATE gs = PyGILState_Ensure();
    PyObject *err = Py_None;
    Py_INCREF(err);
    if (p->result) {
        char msg[4096];
        nprfx_context_last_error(s->env.ctx, msg, sizeof msg);
        Py_DECREF(err);
        err = PyUnicode_FromString(msg);
    }
    PyObject *rec =
        err ? internal_py_namespace(Py_BuildValue(
                  "{s:i,s:O,s:N,s:i,s:d,s:d,s:i,s:i}", "frame", p->frame, "ok",
                  p->result ? Py_False : Py_True, "error", err, "written", p->written, "seconds",
                  p->seconds, "elapsed", p->elapsed, "done", p->done, "count", p->count))
            : NULL;
    int stop = 0;
    if (!rec || PyList_Append(s->frames, rec)) {
        stop = s->stopped = 1;
    } else if (s->progress) {
        PyObject *r = PyObject_CallFunctionObjArgs(s->progress, rec, NULL);
        if (!r) stop = s->stopped = 1;
        Py_XDECREF(r);
    }
    /* kept for run() to raise: this may be a writer thread's state, not the caller's */
    if (stop && PyErr_Occurred()) PyErr_Fetch(&s->exc[0], &s->exc[1], &s->exc[2]);
    Py_XDECREF(rec);
    PyGILState_Release(gs);
    return stop;
}

static PyObject *stats_list(const nprfx_graph *g)
{
    const nprfx_graph_node_stats *st = NULL;
    const int n = nprfx_graph_stats(g, &st);
    PyObject *l = PyList_New(0);
    for (int i = 0; l && i < n; i++) {
        PyObject *rec = internal_py_namespace(Py_BuildValue(
            "{s:s,s:s,s:i,s:L,s:d,s:K,s:K}", "name", st[i].name, "type", st[i].type, "kind",
            st[i].kind, "calls", st[i].calls, "seconds", st[i].seconds, "bytes",
            (unsigned long long)st[i].bytes, "fresh_bytes", (unsigned long long)st[i].fresh_bytes));
        if (!rec || PyList_Append(l, rec)) Py_CLEAR(l);
        Py_XDECREF(rec);
    }
    return l;
}

/* run(frames=None, shot=None, progress=None, keep_going=False, serial=False, analysis=None):
 * render the frames in order, each frame's write nodes writing their files. progress(record)
 * after each frame (raising stops the run, and the exception reaches the caller). Returns the
 * frames' records and the costs (`nprfx run --stats`); a failed frame raises nprfx.Error with
 * its message unless keep_going. */
static PyObject *graph_run(py_graph *s, PyObject *args, PyObject *kw)
{
    static char *names[] = {"frames", "shot", "progress", "keep_going", "serial", "analysis", NULL};
    PyObject *frames = NULL, *progress = NULL;
    const char *shot = NULL, *analysis = NULL;
    int keep_going = 0, serial = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "|OzOppz", names, &frames, &shot, &progress,
                                     &keep_going, &serial, &analysis) ||
        graph_ready(s))
        return NULL;
    if (progress == Py_None) progress = NULL;
    if (progress && !PyCallable_Check(progress))
        return PyErr_Format(internal_py_error, "progress: a callable progress(record)");
    nprfx_frame_list fl = {NULL, 0};
    nprfx_graph_plan_info plan;
    if (graph_plan(s, frames, shot, &fl, &plan)) return NULL;
    PyObject *out = NULL;
    if (graph_seed(s, analysis)) goto done;
    s->frames = PyList_New(0);
    if (!s->frames) goto done;
    s->progress = progress;
    s->stopped = 0;
    s->busy = 1;
    nprfx_graph_run_options ro;
    memset(&ro, 0, sizeof ro);
    ro.size = sizeof ro;
    ro.keep_going = keep_going;
    ro.progress = run_progress;
    ro.user = s;
    ro.serial = serial;
    nprfx_graph_run_summary sum;
    memset(&sum, 0, sizeof sum);
    Py_BEGIN_ALLOW_THREADS;
    nprfx_graph_run(s->g, &fl, &ro, &sum);
    Py_END_ALLOW_THREADS;
    s->busy = 0;
    s->progress = NULL;
    if (s->exc[0]) {
        PyErr_Restore(s->exc[0], s->exc[1], s->exc[2]);
        s->exc[0] = s->exc[1] = s->exc[2] = NULL;
        goto done;
    }
    if (sum.failed && !keep_going) {
        /* the first failed frame's message */
        for (Py_ssize_t i = 0; i < PyList_GET_SIZE(s->frames); i++) {
            PyObject *e = PyObject_GetAttrString(PyList_GET_ITEM(s->frames, i), "error");
            if (e && e != Py_None) {
                PyErr_SetObject(internal_py_error, e);
                Py_DECREF(e);
                goto done;
            }
            Py_XDECREF(e);
        }
        PyErr_SetString(internal_py_error, "a frame failed");
        goto done;
    }
    out = internal_py_namespace(
        Py_BuildValue("{s:O,s:i,s:i,s:i,s:d,s:N,s:N,s:K,s:O}", "frames", s->frames, "rendered",
                      sum.rendered, "failed", sum.failed, "files", sum.files, "seconds",
                      sum.seconds, "stats", stats_list(s->g), "plan", plan_info(&plan), "mem_peak",
                      (unsigned long long)nprfx_graph_mem_peak(s->g), "notices", s->notices));
done:
    Py_CLEAR(s->frames);
    nprfx_seq_frames_free(&fl);
    return out;
}

/* knobs(): the graph's knobs (its "knobs": the params worth turning), with the graph's words on
 * each, the param's description and its value in the graph. */
static PyObject *graph_knobs(py_graph *s, PyObject *noargs)
{
    (void)noargs;
    if (graph_ready(s)) return NULL;
    PyObject *l = PyList_New(0);
    for (int i = 0; l && i < nprfx_graph_knob_count(s->g); i++) {
        nprfx_graph_knob_info k = {sizeof k};
        if (nprfx_graph_knob(s->g, i, &k)) {
            Py_DECREF(l);
            return internal_py_raise(s->env.ctx);
        }
        PyObject *help = k.help ? PyUnicode_FromString(k.help) : (Py_INCREF(Py_None), Py_None);
        PyObject *rec = internal_py_namespace(Py_BuildValue(
            "{s:s,s:N,s:s,s:s,s:i,s:N,s:N}", "name", k.name, "help", help, "node", k.node, "type",
            k.desc->id, "nodes", k.nodes, "param", internal_py_param_info(k.param), "value",
            internal_py_param_value(k.param, k.value)));
        if (!rec || PyList_Append(l, rec)) Py_CLEAR(l);
        Py_XDECREF(rec);
    }
    return l;
}

/* eval(node, frame): a node's result at frame, as an array, nothing written. */
static PyObject *graph_eval(py_graph *s, PyObject *args)
{
    const char *name;
    int frame;
    if (!PyArg_ParseTuple(args, "si", &name, &frame) || graph_ready(s)) return NULL;
    nprfx_image im;
    memset(&im, 0, sizeof im);
    nprfx_result r;
    s->busy = 1;
    Py_BEGIN_ALLOW_THREADS;
    r = nprfx_graph_eval(s->g, name, frame, &im, NULL);
    Py_END_ALLOW_THREADS;
    s->busy = 0;
    if (r) return internal_py_raise(s->env.ctx);
    return internal_py_make_array(&im);
}

static PyMethodDef graph_methods[] = {
    {"load", (PyCFunction)(void (*)(void))graph_load, METH_VARARGS | METH_KEYWORDS | METH_CLASS,
     "Graph.load(path, threads=0, mem_limit=None, output_dir=None): a graph file (read paths "
     "relative to it, write paths to output_dir or the current directory)."},
    {"from_dict", (PyCFunction)(void (*)(void))graph_from_dict,
     METH_VARARGS | METH_KEYWORDS | METH_CLASS,
     "Graph.from_dict(graph, base_dir='.', threads=0, mem_limit=None, output_dir=None): a graph "
     "given as the dict a graph file holds."},
    {"set", (PyCFunction)graph_set, METH_VARARGS,
     "set('node.param', value): override a param (or a read's or write's field), as --set."},
    {"check", (PyCFunction)(void (*)(void))graph_check, METH_VARARGS | METH_KEYWORDS,
     "check(frames=None, shot=None): what a run would refuse before reading a pixel; returns the "
     "frames and the memory plan."},
    {"run", (PyCFunction)(void (*)(void))graph_run, METH_VARARGS | METH_KEYWORDS,
     "run(frames=None, shot=None, progress=None, keep_going=False, serial=False, analysis=None):"
     " render the frames as `nprfx run` does; returns per-frame records and the costs."},
    {"knobs", (PyCFunction)graph_knobs, METH_NOARGS,
     "knobs() -> list: the graph's knobs, the params worth turning (name as set() takes it, the "
     "graph's help, the first node it sets and how many, the param's description, its value)."},
    {"eval", (PyCFunction)graph_eval, METH_VARARGS,
     "eval(node, frame) -> numpy.ndarray: a node's result at frame, nothing written."},
    {NULL, NULL, 0, NULL}};

PyTypeObject internal_py_graph_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "nprfx.Graph",
    .tp_basicsize = sizeof(py_graph),
    .tp_dealloc = (destructor)graph_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A node graph (a graph file, or the dict one holds) run by the engine of `nprfx "
              "run`: Graph.load(path) or Graph.from_dict(d), then set, check, run, eval.",
    .tp_methods = graph_methods,
};
