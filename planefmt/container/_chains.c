/* Resolving a shell tree's chains in one forward pass (spec/pln.md §9.11).
 *
 * A chain entry either holds a value or points to an earlier entry plus an offset.  Because every
 * pointer goes backwards, one pass in entry order resolves them all: O(n) with no rounds.  numpy has
 * no primitive for this recurrence (its pointer-jumping form in shellfields.py takes log(depth)
 * rounds of fancy indexing, 4 ms for torus.STL's 26,100 entries; this pass takes about 30 us), and it
 * is the one sequential step of decoding a shell tree.  Kind 8's parallelograms (a + b - c) add a
 * second and a third pointer, which pointer jumping cannot follow at all.  shellfields.py falls back to pointer jumping
 * where this module was not built.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>

static int
int64_view(PyObject *obj, Py_buffer *view, int writable, const char *name)
{
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0)
        return -1;
    if (view->itemsize != 8 || view->format == NULL || (strcmp(view->format, "q") && strcmp(view->format, "l")
                                                        && strcmp(view->format, "<q") && strcmp(view->format, "<l")
                                                        && strcmp(view->format, "=q") && strcmp(view->format, "=l"))) {
        PyErr_Format(PyExc_TypeError, "%s: expected a contiguous int64 array", name);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

static PyObject *
resolve(PyObject *self, PyObject *args)
{
    /* value, pointer, offset, then optionally plus and minus (None or arrays): a second pointer added
     * and a third subtracted (a parallelogram's a + b - c, spec §9.12), -1 where unused; and a limit on
     * every resolved magnitude, checked as each is made (0: none).  With entries and offsets within
     * 2^52 (the spec's bound) no sum leaves int64: a value past the limit stops the pass before a
     * doubling chain of parallelograms could wrap around. */
    PyObject *objs[5] = {NULL, NULL, NULL, Py_None, Py_None};
    static const char *names[5] = {"value", "pointer", "offset", "plus", "minus"};
    Py_buffer views[5];
    long long limit = 0;
    int held = 0;
    if (!PyArg_ParseTuple(args, "OOO|OOL", &objs[0], &objs[1], &objs[2], &objs[3], &objs[4], &limit))
        return NULL;
    if ((objs[3] == Py_None) != (objs[4] == Py_None)) {
        PyErr_SetString(PyExc_TypeError, "plus and minus come together");
        return NULL;
    }
    int count = objs[3] == Py_None ? 3 : 5;
    for (; held < count; held++)
        if (int64_view(objs[held], &views[held], held == 0, names[held]) < 0)
            goto done;
    Py_ssize_t n = views[0].len / 8, bad = -1;
    for (int i = 1; i < count; i++)
        if (views[i].len / 8 != n) {
            PyErr_SetString(PyExc_ValueError, "the arrays differ in length");
            goto done;
        }
    int64_t *value = views[0].buf;
    const int64_t *pointer = views[1].buf, *offset = views[2].buf;
    const int64_t *plus = count == 5 ? views[3].buf : NULL, *minus = count == 5 ? views[4].buf : NULL;
    int64_t culprit = 0, beyond = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < n; k++) {
        int64_t p = pointer[k];
        if (p < 0)
            continue;
        int64_t a = plus ? plus[k] : -1, b = minus ? minus[k] : -1;
        if (p >= k || a >= k || b >= k) {
            bad = k;
            culprit = p >= k ? p : a >= k ? a : b;
            break;
        }
        int64_t x = offset[k] + value[p] + (a >= 0 ? value[a] : 0) - (b >= 0 ? value[b] : 0);
        if (limit > 0 && (x > limit || x < -limit)) {
            bad = k;
            beyond = 1;
            break;
        }
        value[k] = x;
    }
    Py_END_ALLOW_THREADS
    if (bad >= 0 && beyond)
        PyErr_Format(PyExc_OverflowError, "entry %zd resolves beyond %lld", bad, limit);
    else if (bad >= 0)
        PyErr_Format(PyExc_ValueError, "entry %zd points to %lld, not an earlier entry", bad, (long long)culprit);
done:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&views[i]);
    if (PyErr_Occurred())
        return NULL;
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"resolve", resolve, METH_VARARGS,
     "resolve(value, pointer, offset[, plus, minus[, limit]]): in place, value[k] = offset[k] + "
     "value[pointer[k]] (+ value[plus[k]] - value[minus[k]] where those are >= 0) wherever pointer[k] >= 0, "
     "in entry order (int64 arrays; every pointer must go to an earlier entry; OverflowError past limit)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_chains", NULL, -1, methods};

PyMODINIT_FUNC
PyInit__chains(void)
{
    return PyModule_Create(&module);
}
