/* The damped pendulum's classical Runge-Kutta integration for tracking.model_look, compiled.
 *
 * The same arithmetic, in the same order, as model_look's pure-Python integrate() and trajectory() (which stay as
 * the fallback when this extension is not built): theta'' = -w2 sin(theta) - c theta', and for trajectory() its four
 * variational equations (the sensitivities by theta0, theta'0, w2, c). Built with -ffp-contract=off so that no
 * fused multiply-add changes a rounding: the results equal Python's to the last bit (tests/tracking/test_model_look.py).
 * Each function returns a bytearray of float64 values that the Python side views as a numpy array (no numpy headers
 * needed to build).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

static int parse(PyObject *const *args, Py_ssize_t n, double v[5], Py_ssize_t *steps)
{
    if (n != 6) {
        PyErr_SetString(PyExc_TypeError, "expected (theta, rate, w2, c, dt, steps)");
        return -1;
    }
    for (int i = 0; i < 5; i++) {
        v[i] = PyFloat_AsDouble(args[i]);
        if (v[i] == -1.0 && PyErr_Occurred())
            return -1;
    }
    *steps = PyNumber_AsSsize_t(args[5], PyExc_OverflowError);
    if (*steps == -1 && PyErr_Occurred())
        return -1;
    if (*steps < 0 || *steps > 100000000) {
        PyErr_SetString(PyExc_ValueError, "steps must be 0..1e8");
        return -1;
    }
    return 0;
}

/* integrate(theta, rate, w2, c, dt, steps) -> bytearray of steps + 1 float64: theta at 0, dt, ..., steps dt */
static PyObject *integrate(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    double v[5];
    Py_ssize_t steps;
    if (parse(args, nargs, v, &steps) < 0)
        return NULL;
    PyObject *buf = PyByteArray_FromStringAndSize(NULL, (steps + 1) * (Py_ssize_t)sizeof(double));
    if (buf == NULL)
        return NULL;
    double *out = (double *)PyByteArray_AS_STRING(buf);
    double y = v[0], z = v[1], w2 = v[2], c = v[3], dt = v[4];
    out[0] = y;
    for (Py_ssize_t i = 0; i < steps; i++) {
        double k1y = z, k1z = -w2 * sin(y) - c * z;
        double y2 = y + 0.5 * dt * k1y, z2 = z + 0.5 * dt * k1z;
        double k2y = z2, k2z = -w2 * sin(y2) - c * z2;
        double y3 = y + 0.5 * dt * k2y, z3 = z + 0.5 * dt * k2z;
        double k3y = z3, k3z = -w2 * sin(y3) - c * z3;
        double y4 = y + dt * k3y, z4 = z + dt * k3z;
        double k4y = z4, k4z = -w2 * sin(y4) - c * z4;
        y += dt / 6.0 * (k1y + 2 * k2y + 2 * k3y + k4y);
        z += dt / 6.0 * (k1z + 2 * k2z + 2 * k3z + k4z);
        out[i + 1] = y;
    }
    return buf;
}

/* the rates of (theta, theta', a0, b0, ..., a3, b3) at state x (10 values), as model_look's first stage and _stage */
static void rates(const double x[10], double w2, double c, double k[10])
{
    double s = sin(x[0]), m = -w2 * cos(x[0]);
    k[0] = x[1];
    k[1] = -w2 * s - c * x[1];
    k[2] = x[3];
    k[3] = m * x[2] - c * x[3];
    k[4] = x[5];
    k[5] = m * x[4] - c * x[5];
    k[6] = x[7];
    k[7] = m * x[6] - c * x[7] - s;
    k[8] = x[9];
    k[9] = m * x[8] - c * x[9] - x[1];
}

/* trajectory(theta, rate, w2, c, dt, steps) -> bytearray of (steps + 1) x 5 float64: theta and its derivatives by
 * (theta0, theta'0, w2, c) at 0, dt, ..., steps dt */
static PyObject *trajectory(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    double v[5];
    Py_ssize_t steps;
    if (parse(args, nargs, v, &steps) < 0)
        return NULL;
    PyObject *buf = PyByteArray_FromStringAndSize(NULL, (steps + 1) * 5 * (Py_ssize_t)sizeof(double));
    if (buf == NULL)
        return NULL;
    double *out = (double *)PyByteArray_AS_STRING(buf);
    double w2 = v[2], c = v[3], dt = v[4], h2 = 0.5 * dt, h6 = dt / 6.0;
    double x[10] = {v[0], v[1], 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0};
    double p[10], q[10], r[10], t[10], s[10];
    out[0] = v[0], out[1] = 1.0, out[2] = 0.0, out[3] = 0.0, out[4] = 0.0;
    for (Py_ssize_t i = 0; i < steps; i++) {
        rates(x, w2, c, p);
        for (int j = 0; j < 10; j++)
            s[j] = x[j] + h2 * p[j];
        rates(s, w2, c, q);
        for (int j = 0; j < 10; j++)
            s[j] = x[j] + h2 * q[j];
        rates(s, w2, c, r);
        for (int j = 0; j < 10; j++)
            s[j] = x[j] + dt * r[j];
        rates(s, w2, c, t);
        for (int j = 0; j < 10; j++)
            x[j] += h6 * (p[j] + 2.0 * q[j] + 2.0 * r[j] + t[j]);
        double *row = out + 5 * (i + 1);
        row[0] = x[0], row[1] = x[2], row[2] = x[4], row[3] = x[6], row[4] = x[8];
    }
    return buf;
}

static PyMethodDef methods[] = {
    {"integrate", (PyCFunction)(void (*)(void))integrate, METH_FASTCALL, "theta [rad] at 0, dt, ..., steps dt."},
    {"trajectory", (PyCFunction)(void (*)(void))trajectory, METH_FASTCALL,
     "(steps + 1) x 5: theta [rad] and its derivatives by (theta0, theta'0, w2, c)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_rk4", "The damped pendulum's RK4, compiled.", -1, methods};

PyMODINIT_FUNC PyInit__rk4(void) { return PyModule_Create(&module); }
