/* The quick acceptance of a joint command, compiled: the per-joint comparisons that BrakingEnvelope.admit and
 * CommandGuard.refuse_position make for every command of every FRI cycle before anything else.
 *
 * Also the supervision's per-message joint checks (within the position bound; the tracking error's largest joint).
 * Each function only answers "every joint passes the quick test" (True) or "look closer" (False); the Python code
 * (which stays as the fallback when this extension is not built) then runs its full per-joint loop, so a False never
 * changes a result and a True is given only where that loop would accept every joint at once. The arithmetic is
 * Python's, in the same order, built with -ffp-contract=off so that no fused multiply-add changes a rounding
 * (tests/trajectories/test_quick.py compares both on random and limit-grazing commands). Any value that is not a
 * float (or a sequence not of 7) answers False: the Python loop reports it.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <string.h>

static int number(PyObject *v, double *out)
{
    if (PyFloat_CheckExact(v)) {
        *out = PyFloat_AS_DOUBLE(v);
        return 0;
    }
    if (!PyFloat_Check(v) && !PyLong_Check(v))
        return -1;
    *out = PyFloat_AsDouble(v);
    if (*out == -1.0 && PyErr_Occurred()) {
        PyErr_Clear();
        return -1;
    }
    return 0;
}

/* 7 doubles from a sequence; -1 (no exception set) if it is not 7 numbers */
static int seven(PyObject *seq, double out[7])
{
    if (!PyList_Check(seq) && !PyTuple_Check(seq)) {
        /* e.g. a protobuf repeated field: its items one by one (no list built from an iteration) */
        Py_ssize_t n = PySequence_Size(seq);
        if (n != 7) {
            PyErr_Clear();
            return -1;
        }
        for (Py_ssize_t i = 0; i < 7; i++) {
            PyObject *v = PySequence_GetItem(seq, i);
            if (v == NULL) {
                PyErr_Clear();
                return -1;
            }
            int bad = number(v, &out[i]);
            Py_DECREF(v);
            if (bad)
                return -1;
        }
        return 0;
    }
    PyObject *fast = PySequence_Fast(seq, "");
    if (fast == NULL) {
        PyErr_Clear();
        return -1;
    }
    if (PySequence_Fast_GET_SIZE(fast) != 7) {
        Py_DECREF(fast);
        return -1;
    }
    PyObject **items = PySequence_Fast_ITEMS(fast);
    for (int i = 0; i < 7; i++) {
        if (number(items[i], &out[i])) {
            Py_DECREF(fast);
            return -1;
        }
    }
    Py_DECREF(fast);
    return 0;
}

/* n doubles packed in a bytes object (struct.pack of float64) */
static const double *packed(PyObject *b, Py_ssize_t n)
{
    if (!PyBytes_Check(b) || PyBytes_GET_SIZE(b) != n * (Py_ssize_t)sizeof(double))
        return NULL;
    return (const double *)PyBytes_AS_STRING(b);
}

/* admit(q, q1, q2, q3, bounds, floor, jerk, k, idt2, dt) -> bool
 * bounds: 35 packed doubles, per joint (A, JD, V, J2, free) as BrakingEnvelope._fast_bounds; floor: 7 packed doubles
 * [rad/s^3] or None; jerk: bool. True when every joint passes admit's inline test and lies within free. */
static PyObject *admit(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 10) {
        PyErr_SetString(PyExc_TypeError, "expected (q, q1, q2, q3, bounds, floor, jerk, k, idt2, dt)");
        return NULL;
    }
    double q[7], q1[7], q2[7], q3[7];
    const double *b = packed(args[4], 35);
    const double *fl = args[5] == Py_None ? NULL : packed(args[5], 7);
    int jerk = PyObject_IsTrue(args[6]);
    double k = PyFloat_AsDouble(args[7]), idt2 = PyFloat_AsDouble(args[8]), dt = PyFloat_AsDouble(args[9]);
    if (PyErr_Occurred() || jerk < 0) {
        PyErr_Clear();
        Py_RETURN_FALSE;
    }
    if (b == NULL || (args[5] != Py_None && fl == NULL) || seven(args[0], q) || seven(args[1], q1) ||
        seven(args[2], q2) || seven(args[3], q3))
        Py_RETURN_FALSE;
    for (int j = 0; j < 7; j++) {
        double A = b[5 * j], JD = b[5 * j + 1], V = b[5 * j + 2], J2 = b[5 * j + 3], free_ = b[5 * j + 4];
        double x = q[j], p1 = q1[j], p2 = q2[j], p3 = q3[j];
        double jf = (jerk && fl != NULL) ? fl[j] : 0.0;
        if (jf * k > JD)
            JD = jf * k;
        double a = (x - 2.0 * p1 + p2) * idt2;
        double v1 = (p1 - p2) / dt;
        if (!(-A <= a && a <= A))
            Py_RETURN_FALSE;
        if (jerk) {
            double da = a - (p1 - 2.0 * p2 + p3) * idt2;
            if (!(-JD <= da && da <= JD))
                Py_RETURN_FALSE;
        }
        double v = v1 + a * dt;
        double v_c = v + 0.5 * a * dt;
        double peak = v_c + a * fabs(a) / J2;
        if (!(-V <= v && v <= V && -V <= v_c && v_c <= V && -V <= peak && peak <= V))
            Py_RETURN_FALSE;
        if (!(-free_ <= x && x <= free_))
            Py_RETURN_FALSE;
    }
    Py_RETURN_TRUE;
}

/* steps(q, prev, prev2, bounds) -> bool
 * bounds: 21 packed doubles, per joint (free, max_step, max_second) as CommandGuard.refuse_position reads them. True
 * when every joint passes its chained comparison (within free, the step and the second difference within bounds). */
static PyObject *steps(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 4) {
        PyErr_SetString(PyExc_TypeError, "expected (q, prev, prev2, bounds)");
        return NULL;
    }
    double q[7], p1[7], p2[7];
    const double *b = packed(args[3], 21);
    if (b == NULL || seven(args[0], q) || seven(args[1], p1) || seven(args[2], p2))
        Py_RETURN_FALSE;
    for (int j = 0; j < 7; j++) {
        double free_ = b[3 * j], max_step = b[3 * j + 1], max_second = b[3 * j + 2];
        double x = q[j];
        double step = x - p1[j];
        double second = step - (p1[j] - p2[j]);
        if (!(-free_ <= x && x <= free_ && -max_step <= step && step <= max_step && -max_second <= second &&
              second <= max_second))
            Py_RETURN_FALSE;
    }
    Py_RETURN_TRUE;
}

/* within(values, bound) -> bool: 7 values with |value| <= bound (7 numbers); NaN, inf beyond it and anything not 7
 * numbers answer False (as supervision.within, whose Python this replaces when built) */
static PyObject *within(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 2) {
        PyErr_SetString(PyExc_TypeError, "expected (values, bound)");
        return NULL;
    }
    double v[7], b[7];
    if (seven(args[0], v) || seven(args[1], b))
        Py_RETURN_FALSE;
    for (int j = 0; j < 7; j++)
        if (!(fabs(v[j]) <= b[j]))
            Py_RETURN_FALSE;
    Py_RETURN_TRUE;
}

/* worst(measured, command, bound) -> float: the largest |measured - command| when every joint's is <= bound (all
 * 7 numbers), else -1.0 (a joint beyond its bound, NaN, or not 7 numbers: the Python check says which) */
static PyObject *worst(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "expected (measured, command, bound)");
        return NULL;
    }
    double m[7], c[7], b[7];
    if (seven(args[0], m) || seven(args[1], c) || seven(args[2], b))
        return PyFloat_FromDouble(-1.0);
    double w = 0.0;
    for (int j = 0; j < 7; j++) {
        double e = fabs(m[j] - c[j]);
        if (!(e <= b[j]))
            return PyFloat_FromDouble(-1.0);
        if (e > w)
            w = e;
    }
    return PyFloat_FromDouble(w);
}

static PyMethodDef methods[] = {
    {"within", (PyCFunction)(void (*)(void))within, METH_FASTCALL, "supervision.within, compiled."},
    {"worst", (PyCFunction)(void (*)(void))worst, METH_FASTCALL, "Supervisor.tracking's largest error, compiled."},
    {"admit", (PyCFunction)(void (*)(void))admit, METH_FASTCALL, "BrakingEnvelope.admit's quick acceptance."},
    {"steps", (PyCFunction)(void (*)(void))steps, METH_FASTCALL, "CommandGuard.refuse_position's quick acceptance."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_quick", "Quick acceptance of joint commands.", -1,
                                    methods};

PyMODINIT_FUNC PyInit__quick(void) { return PyModule_Create(&module); }
