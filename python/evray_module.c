/* evray._evray: the thin CPython binding of the C library (include/evray.h), in plain C against
 * the public headers only. The Python layer (python/evray/__init__.py) makes the API of it.
 *
 * Threads: a run (evr_sim_run) goes on a thread of its own, with the GIL released; the caller
 * waits for it in slices of WAIT_SLICE_NS, taking the GIL between them to let Python's signal
 * handlers run, so Ctrl-C raises KeyboardInterrupt at once and the run is cancelled
 * (evr_sim_cancel) and joined before the exception goes on. A stream's batches reach Python
 * through a hand-off of one batch: the library's sink (on a writer thread) waits until the
 * consumer has copied the batch into a bytearray, so a slow consumer holds the run back through
 * the library's own bounded queue (evr_sim_set_sink). */
#define PY_SSIZE_T_CLEAN
/* the stable ABI of Python 3.9 and later: one build of the module loads in any of them (the GPU
 * machine's Python is not this one's) */
#define Py_LIMITED_API 0x03090000
#include <Python.h>

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "evray.h"
#include "evray_experimental.h"

#define WAIT_SLICE_NS 50000000L /* 50 ms: how long Ctrl-C may wait to be seen */

/* The types, made at import from their specs (the stable ABI has no static types). */
static PyTypeObject *SceneType, *ConfigType, *RunType;

/* A heap type's instance freed, and its reference to the type dropped. */
static void free_object(PyObject *self)
{
    PyTypeObject *t = Py_TYPE(self);
    freefunc f = (freefunc)PyType_GetSlot(t, Py_tp_free);
    f(self);
    Py_DECREF(t);
}

/* ---- errors ---- */
static PyObject *raise_status(evr_status st, const evr_error *err)
{
    PyObject *type = PyExc_RuntimeError;
    if (st == EVR_ERR_ARG) type = PyExc_ValueError;
    else if (st == EVR_ERR_IO) type = PyExc_OSError;
    else if (st == EVR_ERR_NOMEM) type = PyExc_MemoryError;
    PyErr_SetString(type, err->msg[0] ? err->msg : "evray: unknown error");
    return NULL;
}

/* ---- scenes ---- */
typedef struct {
    PyObject_HEAD evr_scene *scene;
} SceneObject;

static void scene_dealloc(SceneObject *self)
{
    evr_scene_release(self->scene);
    free_object((PyObject *)self);
}

static PyObject *scene_describe(SceneObject *self, PyObject *unused)
{
    char *text = evr_scene_describe(self->scene);
    if (!text) return PyErr_NoMemory();
    PyObject *r = PyUnicode_DecodeUTF8(text, (Py_ssize_t)strlen(text), "replace");
    free(text);
    return r;
}

static PyObject *scene_warnings(SceneObject *self, PyObject *unused)
{
    return PyUnicode_DecodeUTF8(evr_scene_warnings(self->scene),
                                (Py_ssize_t)strlen(evr_scene_warnings(self->scene)), "replace");
}

static PyObject *scene_notice(SceneObject *self, PyObject *unused)
{
    const char *n = evr_scene_notice(self->scene);
    if (!n) Py_RETURN_NONE;
    return PyUnicode_DecodeUTF8(n, (Py_ssize_t)strlen(n), "replace");
}

static PyMethodDef scene_methods[] = {
    {"describe", (PyCFunction)scene_describe, METH_NOARGS, "The scene, described for a person."},
    {"warnings", (PyCFunction)scene_warnings, METH_NOARGS,
     "What evray does not render of the file as it is, one warning per line."},
    {"notice", (PyCFunction)scene_notice, METH_NOARGS, "The loader's note, or None."},
    {NULL, NULL, 0, NULL}};

static PyType_Slot scene_slots[] = {{Py_tp_dealloc, (void *)scene_dealloc},
                                    {Py_tp_doc, (void *)"A loaded scene (evray.load, evray.demo)."},
                                    {Py_tp_methods, scene_methods},
                                    {0, NULL}};
static PyType_Spec scene_spec = {"evray._evray.Scene", sizeof(SceneObject), 0, Py_TPFLAGS_DEFAULT,
                                 scene_slots};

static PyObject *wrap_scene(evr_scene *s)
{
    SceneObject *o = PyObject_New(SceneObject, SceneType);
    if (!o) {
        evr_scene_release(s);
        return NULL;
    }
    o->scene = s;
    return (PyObject *)o;
}

static PyObject *mod_load(PyObject *mod, PyObject *args)
{
    const char *path, *animation = NULL;
    int strict = 0, external = 0;
    if (!PyArg_ParseTuple(args, "s|zpp", &path, &animation, &strict, &external)) return NULL;
    evr_load_options o;
    evr_load_options_defaults(&o);
    o.animation = animation;
    o.strict = strict;
    o.allow_external = external;
    evr_scene *s = NULL;
    evr_error err = {{0}};
    evr_status st;
    Py_BEGIN_ALLOW_THREADS st = evr_scene_load_with(path, &o, &s, &err);
    Py_END_ALLOW_THREADS if (st != EVR_OK) return raise_status(st, &err);
    return wrap_scene(s);
}

static PyObject *mod_demo(PyObject *mod, PyObject *args)
{
    const char *name;
    unsigned long long seed = 0;
    if (!PyArg_ParseTuple(args, "s|K", &name, &seed)) return NULL;
    evr_scene *s = NULL;
    evr_error err = {{0}};
    evr_status st;
    Py_BEGIN_ALLOW_THREADS st = evr_demo_load_variant(name, (uint64_t)seed, &s, &err);
    Py_END_ALLOW_THREADS if (st != EVR_OK) return raise_status(st, &err);
    return wrap_scene(s);
}

static PyObject *mod_demo_names(PyObject *mod, PyObject *unused)
{
    PyObject *l = PyList_New(0);
    for (const char *const *n = evr_demo_names(); l && *n; n++) {
        PyObject *s = PyUnicode_FromString(*n);
        if (!s || PyList_Append(l, s) < 0) {
            Py_XDECREF(s);
            Py_DECREF(l);
            return NULL;
        }
        Py_DECREF(s);
    }
    return l;
}

/* ---- configurations ---- */
/* An evr_config and the strings it points to (the setters keep strings, not copies). */
typedef struct {
    PyObject_HEAD evr_config cfg;
    char **strings;
    int num_strings;
} ConfigObject;

static void config_dealloc(ConfigObject *self)
{
    for (int i = 0; i < self->num_strings; i++) free(self->strings[i]);
    free(self->strings);
    free_object((PyObject *)self);
}

static PyType_Slot config_slots[] = {
    {Py_tp_dealloc, (void *)config_dealloc},
    {Py_tp_doc, (void *)"A checked evr_config (made by evray.Config)."},
    {0, NULL}};
static PyType_Spec config_spec = {"evray._evray.Config", sizeof(ConfigObject), 0,
                                  Py_TPFLAGS_DEFAULT, config_slots};

/* Applies the options (names[i], values[i], NULL: none) to c in order, as the evray program
 * does; *sensor is set to a --sensor's name. 0, or 1 with err set. */
static int apply_options(evr_config *c, const char *const *names, char *const *values, Py_ssize_t n,
                         const char **sensor, evr_error *err)
{
    for (Py_ssize_t i = 0; i < n; i++) {
        const char *used;
        const evr_config_option *o = evr_config_option_find(names[i], &used);
        if (!o || strchr(names[i], '=')) {
            snprintf(err->msg, sizeof err->msg, "unknown option '%s'", names[i]);
            return 1;
        }
        if (evr_config_option_takes_value(o) != (values[i] != NULL)) {
            snprintf(err->msg, sizeof err->msg,
                     values[i] ? "%s takes no value" : "%s needs a value", names[i]);
            return 1;
        }
        const char *before = c->sensor;
        if (evr_config_option_set(c, o, values[i], err) != EVR_OK) return 1;
        if (c->sensor != before) *sensor = c->sensor;
    }
    return 0;
}

/* make_config([(option, value or None), ...], no_event_files=False): the defaults, then a --sensor's preset, then every
 * option in order (the preset first, wherever --sensor is, as the evray program does); the
 * values are the object's own copies. ValueError with the library's message for a bad one. */
static PyObject *mod_make_config(PyObject *mod, PyObject *args)
{
    PyObject *items;
    int no_files = 0;
    if (!PyArg_ParseTuple(args, "O!|p", &PyList_Type, &items, &no_files)) return NULL;
    Py_ssize_t n = PyList_Size(items);
    ConfigObject *o = PyObject_New(ConfigObject, ConfigType);
    if (!o) return NULL;
    o->strings = calloc((size_t)n + 1, sizeof *o->strings);
    o->num_strings = o->strings ? (int)n : 0;
    const char **names = calloc((size_t)n + 1, sizeof *names);
    if (!o->strings || !names) {
        free(names);
        Py_DECREF(o);
        return PyErr_NoMemory();
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *it = PyList_GetItem(items, i);
        const char *value = NULL;
        if (!PyArg_ParseTuple(it, "sz", &names[i], &value)) {
            free(names);
            Py_DECREF(o);
            return NULL;
        }
        if (value && !(o->strings[i] = strdup(value))) {
            free(names);
            Py_DECREF(o);
            return PyErr_NoMemory();
        }
    }
    evr_config c;
    evr_error err = {{0}};
    const char *sensor = NULL;
    evr_config_defaults(&c);
    int r = apply_options(&c, names, o->strings, n, &sensor, &err);
    if (r == 0 && sensor) { /* again over the preset */
        evr_config_defaults(&c);
        r = evr_config_sensor(&c, sensor, &err) != EVR_OK ||
            apply_options(&c, names, o->strings, n, &sensor, &err);
        c.sensor = sensor;
    }
    free(names);                 /* the names were the tuples', used only here */
    if (no_files) c.formats = 0; /* a stream's alone (evr_sim_set_sink) */
    if (!r) r = evr_config_validate(&c, NULL, &err) != EVR_OK; /* the scene's checks: later */
    if (r) {
        Py_DECREF(o);
        PyErr_SetString(PyExc_ValueError, err.msg);
        return NULL;
    }
    o->cfg = c;
    return (PyObject *)o;
}

/* validate(scene, config): every value against the scene (evr_config_validate). */
static PyObject *mod_validate(PyObject *mod, PyObject *args)
{
    SceneObject *s;
    ConfigObject *c;
    if (!PyArg_ParseTuple(args, "O!O!", SceneType, &s, ConfigType, &c)) return NULL;
    evr_error err = {{0}};
    evr_status st = evr_config_validate(&c->cfg, s->scene, &err);
    if (st != EVR_OK) return raise_status(st, &err);
    Py_RETURN_NONE;
}

static PyObject *mod_options(PyObject *mod, PyObject *unused)
{
    PyObject *l = PyList_New(0);
    const char *name, *help;
    int takes;
    for (int i = 0; l && (name = evr_config_option_name(i, &takes, &help)); i++) {
        PyObject *t = Py_BuildValue("(sOs)", name, takes ? Py_True : Py_False, help);
        if (!t || PyList_Append(l, t) < 0) {
            Py_XDECREF(t);
            Py_DECREF(l);
            return NULL;
        }
        Py_DECREF(t);
    }
    return l;
}

static PyObject *mod_options_help(PyObject *mod, PyObject *unused)
{
    char *h = evr_config_options_help();
    if (!h) return PyErr_NoMemory();
    PyObject *r = PyUnicode_FromString(h);
    free(h);
    return r;
}

/* ---- runs ---- */
typedef struct {
    PyObject_HEAD PyObject *scene_obj, *config_obj;
    evr_sim *sim;
    pthread_t thread;
    int started, joined;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    /* the hand-off: the sink's batch while full; done when evr_sim_run returned */
    const evr_event *batch;
    size_t batch_n;
    int full, done, gone; /* gone: the consumer stopped (the sink returns non-zero) */
    evr_status status;
    evr_error err;
} RunObject;

static int sink(void *user, const evr_event *ev, size_t n)
{
    RunObject *r = user;
    pthread_mutex_lock(&r->mu);
    r->batch = ev;
    r->batch_n = n;
    r->full = 1;
    pthread_cond_broadcast(&r->cv);
    while (r->full && !r->gone) pthread_cond_wait(&r->cv, &r->mu);
    int stop = r->gone;
    r->full = 0;
    pthread_mutex_unlock(&r->mu);
    return stop;
}

static void *run_main(void *arg)
{
    RunObject *r = arg;
    evr_error err = {{0}};
    evr_status st = evr_sim_run(r->sim, NULL, NULL, &err);
    pthread_mutex_lock(&r->mu);
    r->status = st;
    r->err = err;
    r->done = 1;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
    return NULL;
}

/* Stops the run (if going) and waits for its thread, with the GIL released. */
static void run_stop_join(RunObject *r)
{
    if (!r->started || r->joined) return;
    pthread_mutex_lock(&r->mu);
    r->gone = 1;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
    evr_sim_cancel(r->sim);
    Py_BEGIN_ALLOW_THREADS pthread_join(r->thread, NULL);
    Py_END_ALLOW_THREADS r->joined = 1;
}

static void run_dealloc(RunObject *self)
{
    run_stop_join(self);
    evr_sim_release(self->sim);
    pthread_mutex_destroy(&self->mu);
    pthread_cond_destroy(&self->cv);
    Py_XDECREF(self->scene_obj);
    Py_XDECREF(self->config_obj);
    free_object((PyObject *)self);
}

/* Waits (GIL released, in slices) until pred holds or a signal handler raised; 0 or -1. */
static int wait_for(RunObject *r, int want_batch)
{
    for (;;) {
        int ready;
        Py_BEGIN_ALLOW_THREADS pthread_mutex_lock(&r->mu);
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += WAIT_SLICE_NS;
        if (ts.tv_nsec >= 1000000000L) {
            ts.tv_sec++;
            ts.tv_nsec -= 1000000000L;
        }
        if (!((want_batch && r->full) || r->done)) pthread_cond_timedwait(&r->cv, &r->mu, &ts);
        ready = (want_batch && r->full) || r->done;
        pthread_mutex_unlock(&r->mu);
        Py_END_ALLOW_THREADS if (ready) return 0;
        if (PyErr_CheckSignals() < 0) return -1; /* KeyboardInterrupt: the caller stops the run */
    }
}

static PyObject *run_start(RunObject *r, int stream)
{
    if (r->started) {
        PyErr_SetString(PyExc_RuntimeError, "this run has started already");
        return NULL;
    }
    evr_error err = {{0}};
    evr_status st;
    if (stream && (st = evr_sim_set_sink(r->sim, sink, r, &err)) != EVR_OK)
        return raise_status(st, &err);
    if (pthread_create(&r->thread, NULL, run_main, r) != 0) {
        PyErr_SetString(PyExc_RuntimeError, "cannot start the simulation thread");
        return NULL;
    }
    r->started = 1;
    Py_RETURN_NONE;
}

static PyObject *run_start_stream(RunObject *r, PyObject *unused) { return run_start(r, 1); }
static PyObject *run_start_files(RunObject *r, PyObject *unused) { return run_start(r, 0); }

/* next_batch(): the next batch as a bytearray of evr_event records, or None at the end. */
static PyObject *run_next_batch(RunObject *r, PyObject *unused)
{
    if (!r->started || r->joined) Py_RETURN_NONE;
    if (wait_for(r, 1) < 0) return NULL;
    pthread_mutex_lock(&r->mu);
    int full = r->full;
    const evr_event *ev = r->batch;
    size_t n = r->batch_n;
    pthread_mutex_unlock(&r->mu);
    if (!full) Py_RETURN_NONE; /* done */
    /* the sink waits while full: ev stays valid until the hand-back below */
    PyObject *b = PyByteArray_FromStringAndSize(NULL, (Py_ssize_t)(n * sizeof *ev));
    if (b) memcpy(PyByteArray_AsString(b), ev, n * sizeof *ev);
    pthread_mutex_lock(&r->mu);
    r->full = 0;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
    return b;
}

/* wait(): until the run ends (Ctrl-C raises after stopping it). */
static PyObject *run_wait(RunObject *r, PyObject *unused)
{
    if (!r->started) {
        PyErr_SetString(PyExc_RuntimeError, "this run has not started");
        return NULL;
    }
    if (!r->joined && wait_for(r, 0) < 0) return NULL;
    Py_RETURN_NONE;
}

/* finish(): stops and joins the run; raises its error unless it ran to the end or was stopped
 * (returns True when interrupted). */
static PyObject *run_finish(RunObject *r, PyObject *unused)
{
    run_stop_join(r);
    if (!r->started) Py_RETURN_NONE;
    if (r->status != EVR_OK && r->status != EVR_ERR_INTERRUPTED)
        return raise_status(r->status, &r->err);
    return PyBool_FromLong(r->status == EVR_ERR_INTERRUPTED);
}

static PyObject *run_stats(RunObject *r, PyObject *unused)
{
    /* read while the run goes: the counters are the last finished segment's */
    const evr_stats *s = evr_sim_stats(r->sim);
    return Py_BuildValue(
        "{sKsKsKsKsKsKsKsdsdsdsdsdsisisisdsisdsdsdsdsdsdsssssssd}", "events_on",
        (unsigned long long)s->events_on, "events_off", (unsigned long long)s->events_off,
        "unique_timestamps", (unsigned long long)s->unique_timestamps, "samples",
        (unsigned long long)s->samples, "rays", (unsigned long long)s->rays, "samples_traced",
        (unsigned long long)s->samples_traced, "pixels_skipped",
        (unsigned long long)s->pixels_skipped, "sim_time", s->sim_time, "wall_time", s->wall_time,
        "samples_per_second", s->samples_per_second, "rays_per_second", s->rays_per_second,
        "realtime_factor", s->realtime_factor, "segments_done", s->segments_done, "segments_total",
        s->segments_total, "interrupted", s->interrupted, "complete_until", s->complete_until,
        "outputs_kept", s->outputs_kept, "time_setup", s->time_setup, "time_render", s->time_render,
        "time_device", s->time_device, "time_sort", s->time_sort, "time_copy", s->time_copy,
        "time_write", s->time_write, "backend", s->backend, "device", s->device, "notice",
        s->notice, "time_photons", s->time_photons);
}

static PyMethodDef run_methods[] = {
    {"start_stream", (PyCFunction)run_start_stream, METH_NOARGS, NULL},
    {"start_files", (PyCFunction)run_start_files, METH_NOARGS, NULL},
    {"next_batch", (PyCFunction)run_next_batch, METH_NOARGS, NULL},
    {"wait", (PyCFunction)run_wait, METH_NOARGS, NULL},
    {"finish", (PyCFunction)run_finish, METH_NOARGS, NULL},
    {"stats", (PyCFunction)run_stats, METH_NOARGS, NULL},
    {NULL, NULL, 0, NULL}};

static PyType_Slot run_slots[] = {
    {Py_tp_dealloc, (void *)run_dealloc},
    {Py_tp_doc, (void *)"One run of a simulation (evr_sim), driven by evray.Simulator."},
    {Py_tp_methods, run_methods},
    {0, NULL}};
static PyType_Spec run_spec = {"evray._evray.Run", sizeof(RunObject), 0, Py_TPFLAGS_DEFAULT,
                               run_slots};

/* new_run(scene, config): evr_sim_new (the run folder prepared), GIL released. */
static PyObject *mod_new_run(PyObject *mod, PyObject *args)
{
    SceneObject *s;
    ConfigObject *c;
    if (!PyArg_ParseTuple(args, "O!O!", SceneType, &s, ConfigType, &c)) return NULL;
    evr_sim *sim = NULL;
    evr_error err = {{0}};
    evr_status st;
    Py_BEGIN_ALLOW_THREADS st = evr_sim_new(s->scene, &c->cfg, &sim, &err);
    Py_END_ALLOW_THREADS if (st != EVR_OK) return raise_status(st, &err);
    RunObject *r = PyObject_New(RunObject, RunType);
    if (!r) {
        evr_sim_release(sim);
        return NULL;
    }
    memset((char *)r + sizeof(PyObject), 0, sizeof *r - sizeof(PyObject));
    r->sim = sim;
    pthread_mutex_init(&r->mu, NULL);
    pthread_cond_init(&r->cv, NULL);
    Py_INCREF(s);
    Py_INCREF(c);
    r->scene_obj = (PyObject *)s;
    r->config_obj = (PyObject *)c;
    return (PyObject *)r;
}

/* ---- event files ---- */
/* read(path): (bytearray of evr_event records, width, height). */
static PyObject *mod_read(PyObject *mod, PyObject *args)
{
    const char *path;
    if (!PyArg_ParseTuple(args, "s", &path)) return NULL;
    evr_event *ev = NULL;
    size_t n = 0;
    int w = 0, h = 0;
    evr_error err = {{0}};
    evr_status st;
    Py_BEGIN_ALLOW_THREADS st = evr_events_read(path, &ev, &n, &w, &h, &err);
    Py_END_ALLOW_THREADS if (st != EVR_OK) return raise_status(st, &err);
    PyObject *b = PyByteArray_FromStringAndSize((const char *)ev, (Py_ssize_t)(n * sizeof *ev));
    free(ev);
    if (!b) return NULL;
    return Py_BuildValue("(Nii)", b, w, h);
}

static PyObject *mod_version(PyObject *mod, PyObject *unused)
{
    return PyUnicode_FromString(evr_version());
}

static PyMethodDef module_methods[] = {
    {"load", mod_load, METH_VARARGS, "load(path, animation, strict, allow_external) -> Scene"},
    {"demo", mod_demo, METH_VARARGS, "demo(name, seed=0) -> Scene"},
    {"demo_names", mod_demo_names, METH_NOARGS, "The built-in scenes' names."},
    {"make_config", mod_make_config, METH_VARARGS, "make_config([(option, value), ...])"},
    {"validate", mod_validate, METH_VARARGS, "validate(scene, config)"},
    {"options", mod_options, METH_NOARGS, "[(option, takes_value, help), ...]"},
    {"options_help", mod_options_help, METH_NOARGS, "The options' help text."},
    {"new_run", mod_new_run, METH_VARARGS, "new_run(scene, config) -> Run"},
    {"read", mod_read, METH_VARARGS, "read(path) -> (bytearray, width, height)"},
    {"version", mod_version, METH_NOARGS, "The library's version."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_evray",
                                    "The C library's binding (use the evray package).", -1,
                                    module_methods};

PyMODINIT_FUNC PyInit__evray(void); /* the one symbol Python looks for */
PyMODINIT_FUNC PyInit__evray(void)
{
    if (!(SceneType = (PyTypeObject *)PyType_FromSpec(&scene_spec)) ||
        !(ConfigType = (PyTypeObject *)PyType_FromSpec(&config_spec)) ||
        !(RunType = (PyTypeObject *)PyType_FromSpec(&run_spec)))
        return NULL;
    PyObject *m = PyModule_Create(&module);
    if (!m) return NULL;
    Py_INCREF(SceneType);
    if (PyModule_AddObject(m, "Scene", (PyObject *)SceneType) < 0) {
        Py_DECREF(SceneType);
        Py_DECREF(m);
        return NULL;
    }
    if (PyModule_AddIntConstant(m, "EVENT_SIZE", (long)sizeof(evr_event)) < 0 ||
        PyModule_AddIntConstant(m, "OFFSET_T", (long)offsetof(evr_event, t)) < 0 ||
        PyModule_AddIntConstant(m, "OFFSET_X", (long)offsetof(evr_event, x)) < 0 ||
        PyModule_AddIntConstant(m, "OFFSET_Y", (long)offsetof(evr_event, y)) < 0 ||
        PyModule_AddIntConstant(m, "OFFSET_P", (long)offsetof(evr_event, p)) < 0 ||
        PyModule_AddIntConstant(m, "OFFSET_ID", (long)offsetof(evr_event, id)) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
