/* One RK4 step of the planar pendulum under a pivot acceleration, compiled for planners.swingup_fast.
 *
 * The same arithmetic, in the same order, as swingup_fast's pure-Python planar_rk4_py (which stays as the fallback when
 * this extension is not built). Built with -ffp-contract=off so that no fused multiply-add changes a rounding: the
 * results equal Python's to the last bit (tests/planners/test_swingup_fast.py). The swing-up search calls it three
 * times per 5 ms step of every candidate: a Python function call cost more than the arithmetic.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

/* rk4(theta, theta_dot, a0, a1, h, length, g) -> (theta, theta_dot) after h [s]; pivot acceleration a0 -> a1 */
static PyObject *rk4(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    double v[7];
    if (nargs != 7) {
        PyErr_SetString(PyExc_TypeError, "expected (theta, theta_dot, a0, a1, h, length, g)");
        return NULL;
    }
    for (int i = 0; i < 7; i++) {
        v[i] = PyFloat_AsDouble(args[i]);
        if (v[i] == -1.0 && PyErr_Occurred())
            return NULL;
    }
    double th = v[0], om = v[1], a0 = v[2], a1 = v[3], h = v[4], length = v[5], g = v[6];
    double il = 1.0 / length, gl = g / length;
    double am = 0.5 * (a0 + a1);
    double k1t = om, k1o = -a0 * il * cos(th) - gl * sin(th);
    double t2 = th + 0.5 * h * k1t, o2 = om + 0.5 * h * k1o;
    double k2t = o2, k2o = -am * il * cos(t2) - gl * sin(t2);
    double t3 = th + 0.5 * h * k2t, o3 = om + 0.5 * h * k2o;
    double k3t = o3, k3o = -am * il * cos(t3) - gl * sin(t3);
    double t4 = th + h * k3t, o4 = om + h * k3o;
    double k4t = o4, k4o = -a1 * il * cos(t4) - gl * sin(t4);
    return Py_BuildValue("(dd)", th + h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t),
                         om + h / 6.0 * (k1o + 2 * k2o + 2 * k3o + k4o));
}

static PyMethodDef methods[] = {
    {"rk4", (PyCFunction)(void (*)(void))rk4, METH_FASTCALL, "One RK4 step of the planar pendulum."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_planar", NULL, -1, methods};

PyMODINIT_FUNC PyInit__planar(void) { return PyModule_Create(&module); }
