/*
 * The collision signal's inner loop, compiled: how close each person comes to a track.
 *
 * closest(rows, people, frames, axis, values, distance) -> (smallest, hits)
 *
 * rows:   the track's knots (t, x, y, ...), linear between rows, t non-decreasing.
 * people: person indices into frames.
 * frames: per person (fps, where simulated time 0 lies on the axis, the index of their
 *         first position on it).
 * axis:   the unrolled frame axis (float64, non-decreasing, by steps of at most 1 within a
 *         person's positions), values: x + iy there (complex128); see
 *         havln_mj.humans.tracks.PelvisTable.
 *
 * Returns the smallest horizontal distance from any of the people to the track over its
 * samples, and the people (a tuple, in the order given) that come within distance. The
 * samples and positions are computed with the arithmetic of the numpy path in
 * havln_mj/sim/proximity.py (_samples, then the table read), operation for operation:
 * evenly spaced times i * step + t0 at SAMPLE_HZ, the inner knots' times after them,
 * numpy.interp's rule for linear interpolation. Only |gap| is taken differently (the square
 * root of the smallest squared distance, where numpy takes each |x + iy|), so distances
 * agree to rounding and the flags agree. Build with -ffp-contract=off: a fused multiply-add
 * would round differently.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

#define SAMPLE_HZ 16.0 /* havln_mj.sim.proximity.SAMPLE_HZ */

/*
 * Largest j with xp[j] <= x, for xp[0] <= x < xp[n - 1]: a galloping search from *guess
 * (consecutive samples lie close together on the axis), which is left at the answer.
 */
static Py_ssize_t locate(const double *xp, Py_ssize_t n, double x, Py_ssize_t *guess)
{
    Py_ssize_t lo = *guess, hi, step = 1;
    if (lo < 0)
        lo = 0;
    if (lo > n - 2)
        lo = n - 2;
    if (xp[lo] <= x) { /* forward: xp[lo] <= x, find hi with xp[hi] > x */
        /* A few positions on (the usual step between samples), else galloping. */
        for (int k = 0; k < 4; ++k, ++lo) {
            if (xp[lo + 1] > x) {
                *guess = lo;
                return lo;
            }
        }
        hi = lo + 1;
        while (xp[hi] <= x) {
            lo = hi;
            hi = lo + step > n - 1 ? n - 1 : lo + step;
            step <<= 1;
        }
    }
    else { /* backward: xp[hi] > x, find lo with xp[lo] <= x */
        hi = lo;
        lo = hi - 1;
        while (xp[lo] > x) {
            hi = lo;
            lo = hi - step < 0 ? 0 : hi - step;
            step <<= 1;
        }
    }
    while (hi - lo > 1) { /* xp[lo] <= x < xp[hi] */
        Py_ssize_t mid = lo + ((hi - lo) >> 1);
        if (xp[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    *guess = lo;
    return lo;
}

/* One coordinate of numpy.interp between (xp[j], y0) and (xp[j + 1], y1). */
static double between(double slope, double x, double x0, double x1, double y0, double y1)
{
    double v = slope * (x - x0) + y0;
    if (isnan(v)) {
        v = slope * (x - x1) + y1;
        if (isnan(v) && y0 == y1)
            v = y0;
    }
    return v;
}

/* numpy.interp(x, xp, fp) for complex fp (pairs of doubles), n >= 2. */
static void interp(const double *xp, const double *fp, Py_ssize_t n, double x,
                   Py_ssize_t *guess, double *re, double *im)
{
    Py_ssize_t j;
    if (isnan(x)) {
        *re = x;
        *im = 0.0;
        return;
    }
    if (x < xp[0]) {
        *re = fp[0];
        *im = fp[1];
        return;
    }
    if (x >= xp[n - 1]) {
        *re = fp[2 * (n - 1)];
        *im = fp[2 * (n - 1) + 1];
        return;
    }
    j = locate(xp, n, x, guess);
    if (xp[j] == x) {
        *re = fp[2 * j];
        *im = fp[2 * j + 1];
        return;
    }
    {
        const double inv = 1.0 / (xp[j + 1] - xp[j]);
        const double *a = fp + 2 * j, *b = a + 2;
        *re = between((b[0] - a[0]) * inv, x, xp[j], xp[j + 1], a[0], b[0]);
        *im = between((b[1] - a[1]) * inv, x, xp[j], xp[j + 1], a[1], b[1]);
    }
}

/* Reads item i of a sequence as a float; -1 with an exception set on failure. */
static int row_item(PyObject *row, Py_ssize_t i, double *out)
{
    PyObject *item = PySequence_GetItem(row, i);
    if (item == NULL)
        return -1;
    *out = PyFloat_AsDouble(item);
    Py_DECREF(item);
    return (*out == -1.0 && PyErr_Occurred()) ? -1 : 0;
}

/* The track's knots as their times t[n] then their x + iy as pairs (3 * n doubles). */
static double *read_knots(PyObject *rows, Py_ssize_t *count)
{
    PyObject *seq = PySequence_Fast(rows, "rows must be a sequence of knots");
    Py_ssize_t n, i;
    double *out;
    if (seq == NULL)
        return NULL;
    n = PySequence_Fast_GET_SIZE(seq);
    if (n == 0) {
        PyErr_SetString(PyExc_ValueError, "a track needs at least one knot");
        Py_DECREF(seq);
        return NULL;
    }
    out = PyMem_Malloc(3 * n * sizeof(double));
    if (out == NULL) {
        Py_DECREF(seq);
        PyErr_NoMemory();
        return NULL;
    }
    for (i = 0; i < n; ++i) {
        PyObject *row = PySequence_Fast_GET_ITEM(seq, i);
        if (row_item(row, 0, out + i) || row_item(row, 1, out + n + 2 * i) ||
            row_item(row, 2, out + n + 2 * i + 1)) {
            PyMem_Free(out);
            Py_DECREF(seq);
            return NULL;
        }
    }
    Py_DECREF(seq);
    *count = n;
    return out;
}

/*
 * The track's sample times and x + iy there (as _samples gives them): 3 * m doubles
 * (times, x, y), m in *count.
 */
static double *sample(const double *knots, Py_ssize_t n_knots, Py_ssize_t *count)
{
    const double *kt = knots, *kxy = knots + n_knots;
    const double t0 = kt[0], t1 = kt[n_knots - 1];
    Py_ssize_t n, inner, m, i, guess = 0;
    double *out, step;
    if (n_knots == 1 || t1 <= t0) {
        out = PyMem_Malloc(3 * sizeof(double));
        if (out == NULL)
            return (double *)PyErr_NoMemory();
        out[0] = t1;
        out[1] = kxy[2 * (n_knots - 1)];
        out[2] = kxy[2 * (n_knots - 1) + 1];
        *count = 1;
        return out;
    }
    n = (Py_ssize_t)ceil((t1 - t0) * SAMPLE_HZ) + 1;
    if (n < 2)
        n = 2;
    inner = n_knots - 2;
    m = n + inner;
    out = PyMem_Malloc(3 * m * sizeof(double));
    if (out == NULL)
        return (double *)PyErr_NoMemory();
    step = (t1 - t0) / (double)(n - 1);
    for (i = 0; i < n; ++i)
        out[i] = (double)i * step + t0;
    out[n - 1] = t1;
    for (i = 0; i < inner; ++i)
        out[n + i] = kt[1 + i];
    for (i = 0; i < m; ++i)
        interp(kt, kxy, n_knots, out[i], &guess, out + m + i, out + 2 * m + i);
    *count = m;
    return out;
}

/*
 * The smallest distance from person (fps, at) to the sampled track. The search for the
 * first sample starts `f - axis[first]` positions past the person's first: the axis
 * advancing by at most 1 a position, the answer is there or a little after.
 */
static double person_closest(const double *samples, Py_ssize_t m, double fps, double at,
                             Py_ssize_t first, const double *axis, const double *values,
                             Py_ssize_t n_axis)
{
    const double *t = samples, *x = samples + m, *y = samples + 2 * m;
    double smallest = INFINITY, ahead = t[0] * fps + at - axis[first];
    Py_ssize_t i, guess = first;
    if (ahead > 0.0 && ahead < (double)n_axis)
        guess += (Py_ssize_t)ahead;
    for (i = 0; i < m; ++i) {
        double f = t[i] * fps, re, im, dx, dy, d2;
        f += at;
        interp(axis, values, n_axis, f, &guess, &re, &im);
        dx = re - x[i];
        dy = im - y[i];
        d2 = dx * dx + dy * dy;
        if (d2 < smallest)
            smallest = d2;
    }
    return sqrt(smallest);
}

/* Person k's (fps, at, first) from frames. */
static int read_frame(PyObject *frames, Py_ssize_t k, Py_ssize_t n_axis, double *fps,
                      double *at, Py_ssize_t *first)
{
    PyObject *row, *index;
    int bad;
    if (k < 0 || k >= PySequence_Size(frames)) {
        PyErr_Format(PyExc_IndexError, "person %zd is not in the table", k);
        return -1;
    }
    row = PySequence_GetItem(frames, k);
    if (row == NULL)
        return -1;
    bad = row_item(row, 0, fps) || row_item(row, 1, at);
    index = bad ? NULL : PySequence_GetItem(row, 2);
    Py_DECREF(row);
    if (index == NULL)
        return -1;
    *first = PyLong_AsSsize_t(index);
    Py_DECREF(index);
    if (*first == -1 && PyErr_Occurred())
        return -1;
    if (*first < 0 || *first >= n_axis) {
        PyErr_Format(PyExc_IndexError, "person %zd starts at %zd, off the axis", k, *first);
        return -1;
    }
    return 0;
}

static PyObject *closest(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    PyObject *people, *hits, *result = NULL;
    char *hit;
    Py_buffer axis, values;
    double *knots = NULL, *samples = NULL, distance, smallest = INFINITY;
    Py_ssize_t n_knots, m, n_axis, i, n_people, n_hits = 0;
    (void)self;
    if (nargs != 6) {
        PyErr_SetString(PyExc_TypeError,
                        "closest(rows, people, frames, axis, values, distance)");
        return NULL;
    }
    distance = PyFloat_AsDouble(args[5]);
    if (distance == -1.0 && PyErr_Occurred())
        return NULL;
    if (PyObject_GetBuffer(args[3], &axis, PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    if (PyObject_GetBuffer(args[4], &values, PyBUF_C_CONTIGUOUS) < 0) {
        PyBuffer_Release(&axis);
        return NULL;
    }
    n_axis = axis.len / (Py_ssize_t)sizeof(double);
    if (n_axis < 2 || values.len != 2 * axis.len) {
        PyErr_SetString(PyExc_ValueError,
                        "axis (float64) and values (complex128) must be equally long, >= 2");
        goto done;
    }
    people = PySequence_Fast(args[1], "people must be a sequence of indices");
    if (people == NULL)
        goto done;
    knots = read_knots(args[0], &n_knots);
    if (knots != NULL)
        samples = sample(knots, n_knots, &m);
    n_people = PySequence_Fast_GET_SIZE(people);
    hit = samples == NULL ? NULL : PyMem_Malloc(n_people + 1);
    if (samples != NULL && hit == NULL)
        PyErr_NoMemory();
    for (i = 0; hit != NULL && i < n_people; ++i) {
        double fps, at, d;
        Py_ssize_t first, k = PyLong_AsSsize_t(PySequence_Fast_GET_ITEM(people, i));
        if ((k == -1 && PyErr_Occurred()) ||
            read_frame(args[2], k, n_axis, &fps, &at, &first) < 0)
            break;
        d = person_closest(samples, m, fps, at, first, axis.buf, values.buf, n_axis);
        if (d < smallest)
            smallest = d;
        hit[i] = d <= distance;
        n_hits += hit[i];
    }
    if (hit != NULL && i == n_people && (hits = PyTuple_New(n_hits)) != NULL) {
        for (i = 0, n_hits = 0; i < n_people; ++i) {
            if (hit[i]) {
                PyObject *who = PySequence_Fast_GET_ITEM(people, i);
                Py_INCREF(who);
                PyTuple_SET_ITEM(hits, n_hits++, who);
            }
        }
        result = Py_BuildValue("(dN)", smallest, hits);
    }
    PyMem_Free(hit);
    Py_DECREF(people);
done:
    PyMem_Free(samples);
    PyMem_Free(knots);
    PyBuffer_Release(&values);
    PyBuffer_Release(&axis);
    return result;
}

static PyMethodDef methods[] = {
    {"closest", (PyCFunction)(void (*)(void))closest, METH_FASTCALL,
     "closest(rows, people, frames, axis, values, distance) -> (smallest, hits)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "_closest", "The collision signal's inner loop, compiled.", -1,
    methods,
};

PyMODINIT_FUNC PyInit__closest(void) { return PyModule_Create(&module); }
