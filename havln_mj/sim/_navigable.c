/*
 * Restricted navigation's per-step query, compiled: the navigable locations in a field of view.
 *
 * window(bearings, ring, location, heading, elevation, cos_half_hfov, half_width, ViewPoint)
 *     -> list
 *
 * bearings, ring: a viewpoint's neighbours with a bearing, sorted by it and repeated one turn
 *                 later (havln_mj.sim.navigation._Node): bearings[k] is ring[k][6], a row is
 *                 (order, viewpointId, ix, x, y, z, bearing, flat, elevation angle, distance).
 * location:       the agent's own location (index 0 of the answer).
 * heading:        in [0, 2 pi); half_width < pi (the caller sends other queries elsewhere).
 *
 * Returns [location] followed by the ViewPoints of the neighbours in the bisected window
 * [heading - half_width, heading + half_width] whose bearing relative to the heading has a
 * cosine of at least cos_half_hfov, sorted by the angle from the view centre
 * (hypot(rel_heading, rel_elevation)), ties by ix. The arithmetic is that of
 * NavTable.candidates' Python loop, operation for operation (libm's fmod and cos, as Python's
 * math module calls them), so the values agree float for float. The rank is libm's hypot,
 * where Python's math.hypot has its own; they may differ in the last bit, which orders two
 * neighbours differently only when their angles from the view centre agree to ~1e-16.
 * Build with -ffp-contract=off.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

#define ROW_FIELDS 10

/* First k in [0, n) with bearings[k] >= x (left) or > x (right): bisect's rule on floats. */
static Py_ssize_t bisect(PyObject *bearings, double x, int right)
{
    Py_ssize_t lo = 0, hi = PyList_GET_SIZE(bearings);
    while (lo < hi) {
        Py_ssize_t mid = (lo + hi) / 2;
        double b = PyFloat_AS_DOUBLE(PyList_GET_ITEM(bearings, mid));
        if (right ? x < b : !(b < x))
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* A record of `type` (a tuple subclass without instance fields) holding `items` (stolen). */
static PyObject *record(PyTypeObject *type, PyObject **items, Py_ssize_t n)
{
    PyObject *obj = type->tp_alloc(type, n);
    Py_ssize_t i;
    if (obj == NULL) {
        for (i = 0; i < n; ++i)
            Py_XDECREF(items[i]);
        return NULL;
    }
    for (i = 0; i < n; ++i)
        PyTuple_SET_ITEM(obj, i, items[i]);
    return obj;
}

typedef struct {
    double rank;
    long ix;
    PyObject *viewpoint;
} Found;

static PyObject *window(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    PyObject *bearings, *ring, *location, *out;
    PyTypeObject *type;
    double heading, elevation, c, w;
    Py_ssize_t lo, hi, k, n = 0, i;
    Found found[64], *all = found;
    (void)self;
    if (nargs != 8) {
        PyErr_SetString(PyExc_TypeError, "window takes 8 arguments");
        return NULL;
    }
    bearings = args[0], ring = args[1], location = args[2];
    type = (PyTypeObject *)args[7];
    if (!PyList_Check(bearings) || !PyList_Check(ring) || !PyType_Check(args[7]) ||
        !PyType_IsSubtype(type, &PyTuple_Type) ||
        PyList_GET_SIZE(bearings) != PyList_GET_SIZE(ring)) {
        PyErr_SetString(PyExc_TypeError,
                        "window(bearings list, ring list, location, heading, elevation, "
                        "cos_half_hfov, half_width, ViewPoint type)");
        return NULL;
    }
    heading = PyFloat_AsDouble(args[3]);
    elevation = PyFloat_AsDouble(args[4]);
    c = PyFloat_AsDouble(args[5]);
    w = PyFloat_AsDouble(args[6]);
    if (PyErr_Occurred())
        return NULL;
    lo = bisect(bearings, heading - w, 0);
    hi = bisect(bearings, heading + w, 1);
    if (hi - lo > 64 && (all = PyMem_Malloc((hi - lo) * sizeof(Found))) == NULL)
        return PyErr_NoMemory();
    for (k = lo; k < hi; ++k) {
        PyObject *row = PyList_GET_ITEM(ring, k), *items[8];
        double rel, rel_e;
        if (!PyTuple_Check(row) || PyTuple_GET_SIZE(row) != ROW_FIELDS) {
            PyErr_SetString(PyExc_TypeError, "a ring row is a 10-tuple");
            goto fail;
        }
        rel = PyFloat_AsDouble(PyTuple_GET_ITEM(row, 6)) - heading;
        if (rel > M_PI || rel <= -M_PI) {
            rel = fmod(rel + M_PI, 2.0 * M_PI);
            rel = rel > 0.0 ? rel - M_PI : rel + M_PI;
        }
        if (!(cos(rel) >= c))
            continue;
        rel_e = PyFloat_AsDouble(PyTuple_GET_ITEM(row, 8)) - elevation;
        for (i = 0; i < 5; ++i) { /* viewpointId, ix, x, y, z: the row's own objects */
            items[i] = PyTuple_GET_ITEM(row, i + 1);
            Py_INCREF(items[i]);
        }
        items[5] = PyFloat_FromDouble(rel);
        items[6] = PyFloat_FromDouble(rel_e);
        items[7] = PyTuple_GET_ITEM(row, 9);
        Py_INCREF(items[7]);
        if (items[5] == NULL || items[6] == NULL) {
            for (i = 0; i < 8; ++i)
                Py_XDECREF(items[i]);
            goto fail;
        }
        all[n].ix = PyLong_AsLong(items[1]);
        all[n].rank = hypot(rel, rel_e);
        if ((all[n].viewpoint = record(type, items, 8)) == NULL)
            goto fail;
        ++n;
    }
    /* Insertion sort: a field of view holds a handful of neighbours. */
    for (k = 1; k < n; ++k) {
        Found f = all[k];
        for (i = k; i > 0 && (all[i - 1].rank > f.rank ||
                              (all[i - 1].rank == f.rank && all[i - 1].ix > f.ix));
             --i)
            all[i] = all[i - 1];
        all[i] = f;
    }
    if ((out = PyList_New(n + 1)) == NULL)
        goto fail;
    Py_INCREF(location);
    PyList_SET_ITEM(out, 0, location);
    for (k = 0; k < n; ++k)
        PyList_SET_ITEM(out, k + 1, all[k].viewpoint);
    if (all != found)
        PyMem_Free(all);
    return out;
fail:
    for (k = 0; k < n; ++k)
        Py_DECREF(all[k].viewpoint);
    if (all != found)
        PyMem_Free(all);
    return NULL;
}

static PyMethodDef methods[] = {
    {"window", (PyCFunction)(void (*)(void))window, METH_FASTCALL,
     "window(bearings, ring, location, heading, elevation, cos_half_hfov, half_width, "
     "ViewPoint) -> list."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_navigable",
    "Restricted navigation's per-step query, compiled.", -1, methods,
};

PyMODINIT_FUNC PyInit__navigable(void) { return PyModule_Create(&module); }
