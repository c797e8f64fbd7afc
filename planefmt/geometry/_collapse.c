/* Dropping corners that carry no shape (planefmt/geometry/redundant.py says which and why the surface
 * stays where it is): half-edge collapses made one corner at a time, in passes over the corners.
 *
 * Each corner's checks must see every collapse made before it: two corners along a crease both pass
 * alone, not always one after the other.  numpy can only make collapses in rounds of corners far enough
 * apart not to interact; on box.STL's chains of straight corners that took 47 rounds of 10 to 20 ms
 * each.  These passes take 3 ms there (12 ms with the fans found before them).  redundant.py runs the
 * same rules in Python where this module was not built; the arithmetic is the same, operation for
 * operation, so the two drop the same corners (built with -ffp-contract=off: a fused multiply-add would
 * round otherwise).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define MAX_PASSES 64
#define MIN_SINE 1e-9

static int
typed_view(PyObject *obj, Py_buffer *view, int writable, char type, const char *name)
{
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0)
        return -1;
    const char *fmt = view->format ? view->format : "";
    if (*fmt == '<' || *fmt == '=')
        fmt++;
    int ok = view->itemsize == 8 && (type == 'd' ? !strcmp(fmt, "d") : (!strcmp(fmt, "q") || !strcmp(fmt, "l")));
    if (!ok) {
        PyErr_Format(PyExc_TypeError, "%s: expected a contiguous %s array", name, type == 'd' ? "float64" : "int64");
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

/* Whether triangle a, b, c seen along nrm turns counter-clockwise and is not too thin to have a side. */
static int
upright(const double *a, const double *b, const double *c, const double *nrm)
{
    double e1x = b[0] - a[0], e1y = b[1] - a[1], e1z = b[2] - a[2];
    double e2x = c[0] - a[0], e2y = c[1] - a[1], e2z = c[2] - a[2];
    double cx = e1y * e2z - e1z * e2y;
    double cy = e1z * e2x - e1x * e2z;
    double cz = e1x * e2y - e1y * e2x;
    double lhs = cx * nrm[0] + cy * nrm[1] + cz * nrm[2];
    double l1 = sqrt(e1x * e1x + e1y * e1y + e1z * e1z);
    double l2 = sqrt(e2x * e2x + e2y * e2y + e2z * e2z);
    return lhs > MIN_SINE * l1 * l2;
}

static double
squared(const double *p, int64_t a, int64_t b)
{
    double dx = p[3 * a] - p[3 * b], dy = p[3 * a + 1] - p[3 * b + 1], dz = p[3 * a + 2] - p[3 * b + 2];
    return dx * dx + dy * dy + dz * dz;
}

static PyObject *
passes(PyObject *self, PyObject *args)
{
    /* p (3n float64), f (3m int64, in place), label (m), normal (3m float64), distance (m float64),
     * manifold (n int64), cap, alive (m int64, in place): returns (dropped, offset). */
    PyObject *objs[8];
    static const char *names[8] = {"p", "f", "label", "normal", "distance", "manifold", "cap", "alive"};
    static const char types[8] = {'d', 'q', 'q', 'd', 'd', 'q', 0, 'q'};
    Py_buffer views[8];
    int held[8] = {0};
    double cap;
    PyObject *result = NULL;
    int64_t *head = NULL, *next = NULL, *mark = NULL, *mark2 = NULL, *fs = NULL, *nbx = NULL, *nbt = NULL;
    int64_t *nbc = NULL, *slot_of = NULL, *targets = NULL;
    char *gone = NULL;
    if (!PyArg_ParseTuple(args, "OOOOOOdO", &objs[0], &objs[1], &objs[2], &objs[3], &objs[4], &objs[5], &cap,
                          &objs[7]))
        return NULL;
    for (int i = 0; i < 8; i++) {
        if (i == 6)
            continue;
        if (typed_view(objs[i], &views[i], i == 1 || i == 7, types[i], names[i]) < 0)
            goto done;
        held[i] = 1;
    }
    const double *p = views[0].buf, *normal = views[3].buf, *distance = views[4].buf;
    int64_t *f = views[1].buf, *alive = views[7].buf;
    const int64_t *label = views[2].buf, *manifold = views[5].buf;
    Py_ssize_t n = views[0].len / 24, m = views[1].len / 24;
    if (views[2].len / 8 != m || views[3].len / 24 != m || views[4].len / 8 != m || views[5].len / 8 != n
        || views[7].len / 8 != m || views[0].len % 24 || views[1].len % 24) {
        PyErr_SetString(PyExc_ValueError, "the arrays differ in length");
        goto done;
    }
    for (Py_ssize_t s = 0; s < 3 * m; s++)
        if (f[s] < 0 || f[s] >= n) {
            PyErr_SetString(PyExc_ValueError, "a corner index is outside the vertices");
            goto done;
        }
    Py_ssize_t cells = n + 1, slots = 3 * m + 1;
    head = malloc(cells * sizeof *head);
    mark = calloc(cells, sizeof *mark);
    mark2 = calloc(cells, sizeof *mark2);
    slot_of = malloc(cells * sizeof *slot_of);
    gone = calloc(cells, 1);
    next = malloc(slots * sizeof *next);
    fs = malloc(slots * sizeof *fs);
    nbx = malloc(2 * slots * sizeof *nbx);
    nbt = malloc(4 * slots * sizeof *nbt);
    nbc = malloc(2 * slots * sizeof *nbc);
    targets = malloc(2 * slots * sizeof *targets);
    if (!head || !mark || !mark2 || !slot_of || !gone || !next || !fs || !nbx || !nbt || !nbc || !targets) {
        PyErr_NoMemory();
        goto done;
    }
    for (Py_ssize_t v = 0; v < n; v++)
        head[v] = -1;
    /* Each triangle's slot s (its corner s % 3) sits in the list of the corner f[s]; a slot moves to u's
     * list when its corner v collapses into u.  Slots of collapsed triangles stay behind, skipped. */
    for (Py_ssize_t s = 3 * m - 1; s >= 0; s--) {
        next[s] = head[f[s]];
        head[f[s]] = s;
    }
    for (Py_ssize_t t = 0; t < m; t++)
        alive[t] = 1;
    int64_t stamp = 0, stamp2 = 0, dropped = 0;
    double offset = 0.0;
    for (int pass = 0; pass < MAX_PASSES; pass++) {
        int64_t made = 0;
        for (Py_ssize_t v = 0; v < n; v++) {
            if (gone[v] || !manifold[v])
                continue;
            Py_ssize_t k = 0;
            int64_t lo = INT64_MAX, hi = INT64_MIN;
            for (int64_t s = head[v]; s >= 0; s = next[s])
                if (alive[s / 3])
                    fs[k++] = s;
            if (k == 0)
                continue;
            double d = 0.0;
            int bad = 0;
            for (Py_ssize_t i = 0; i < k && !bad; i++) {
                int64_t t = fs[i] / 3;
                if (label[t] < lo)
                    lo = label[t];
                if (label[t] > hi)
                    hi = label[t];
                if (distance[t] > d)
                    d = distance[t];
                if (!upright(p + 3 * f[3 * t], p + 3 * f[3 * t + 1], p + 3 * f[3 * t + 2], normal + 3 * t))
                    bad = 1;
            }
            if (bad || lo < 0)
                continue;
            for (Py_ssize_t i = 0; i < k && !bad; i++)
                if (label[fs[i] / 3] != lo && label[fs[i] / 3] != hi)
                    bad = 1;
            if (bad)
                continue;
            /* The neighbours of v, each with the (two) triangles at v it is a corner of. */
            stamp++;
            Py_ssize_t nn = 0;
            for (Py_ssize_t i = 0; i < k; i++) {
                int64_t t = fs[i] / 3;
                for (int c = 0; c < 3; c++) {
                    int64_t x = f[3 * t + c];
                    if (x == v)
                        continue;
                    if (mark[x] != stamp) {
                        mark[x] = stamp;
                        slot_of[x] = nn;
                        nbx[nn] = x;
                        nbc[nn] = 0;
                        nn++;
                    }
                    Py_ssize_t j = slot_of[x];
                    if (nbc[j] < 2)
                        nbt[2 * j + nbc[j]] = t;
                    nbc[j]++;
                }
            }
            Py_ssize_t nt = 0;
            double bound;
            if (lo == hi) {
                for (Py_ssize_t j = 0; j < nn; j++)
                    targets[nt++] = nbx[j];
                bound = 2.0 * d;
            } else {
                int64_t t1 = -1, t2 = -1;
                for (Py_ssize_t j = 0; j < nn; j++)
                    if (nbc[j] == 2 && label[nbt[2 * j]] != label[nbt[2 * j + 1]]) {
                        if (nt < 2) {
                            t1 = nbt[2 * j];
                            t2 = nbt[2 * j + 1];
                        }
                        targets[nt++] = nbx[j];
                    }
                if (nt != 2)
                    continue;
                const double *pv = p + 3 * v, *p1 = p + 3 * targets[0], *p2 = p + 3 * targets[1];
                if ((p1[0] - pv[0]) * (p2[0] - pv[0]) + (p1[1] - pv[1]) * (p2[1] - pv[1])
                    + (p1[2] - pv[2]) * (p2[2] - pv[2]) >= 0.0)
                    continue;
                const double *n1 = normal + 3 * t1, *n2 = normal + 3 * t2;
                double cosine = n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2];
                cosine = cosine > 1.0 ? 1.0 : (cosine < -1.0 ? -1.0 : cosine);
                double half = acos(cosine) / 2.0;
                double s = sin(half) < cos(half) ? sin(half) : cos(half);
                if (!(s > 0.0))
                    continue;
                bound = 2.0 * d + 2.0 * d / s;
            }
            if (!(bound <= cap))
                continue;
            /* Farthest first, then the lower index. */
            for (Py_ssize_t i = 1; i < nt; i++) {
                int64_t x = targets[i];
                double dx = squared(p, x, v);
                Py_ssize_t j = i;
                while (j > 0) {
                    double dy = squared(p, targets[j - 1], v);
                    if (dy > dx || (dy == dx && targets[j - 1] < x))
                        break;
                    targets[j] = targets[j - 1];
                    j--;
                }
                targets[j] = x;
            }
            for (Py_ssize_t i = 0; i < nt; i++) {
                int64_t u = targets[i];
                if (!manifold[u])
                    continue;
                stamp2++;
                int64_t common = 0;
                for (int64_t s = head[u]; s >= 0; s = next[s]) {
                    if (!alive[s / 3])
                        continue;
                    int64_t t = s / 3;
                    for (int c = 0; c < 3; c++) {
                        int64_t x = f[3 * t + c];
                        if (x != u && x != v && mark[x] == stamp && mark2[x] != stamp2) {
                            mark2[x] = stamp2;
                            common++;
                        }
                    }
                }
                if (common != 2)
                    continue;
                int fold = 0;
                for (Py_ssize_t q = 0; q < k && !fold; q++) {
                    int64_t t = fs[q] / 3;
                    const double *c3[3];
                    int has_u = 0;
                    for (int c = 0; c < 3; c++) {
                        int64_t x = f[3 * t + c];
                        has_u |= x == u;
                        c3[c] = p + 3 * (x == v ? u : x);
                    }
                    if (!has_u && !upright(c3[0], c3[1], c3[2], normal + 3 * t))
                        fold = 1;
                }
                if (fold)
                    continue;
                for (Py_ssize_t q = 0; q < k; q++) {
                    int64_t s = fs[q], t = s / 3;
                    if (f[3 * t] == u || f[3 * t + 1] == u || f[3 * t + 2] == u) {
                        alive[t] = 0;
                    } else {
                        f[s] = u;
                        next[s] = head[u];
                        head[u] = s;
                    }
                }
                head[v] = -1;
                gone[v] = 1;
                if (bound > offset)
                    offset = bound;
                dropped++;
                made++;
                break;
            }
        }
        if (!made)
            break;
    }
    result = Py_BuildValue("Ld", (long long)dropped, offset);
done:
    for (int i = 0; i < 8; i++)
        if (held[i])
            PyBuffer_Release(&views[i]);
    free(head);
    free(mark);
    free(mark2);
    free(slot_of);
    free(gone);
    free(next);
    free(fs);
    free(nbx);
    free(nbt);
    free(nbc);
    free(targets);
    return result;
}

static PyMethodDef methods[] = {
    {"passes", passes, METH_VARARGS,
     "passes(p, f, label, normal, distance, manifold, cap, alive): collapse flat and straight corners "
     "(planefmt/geometry/redundant.py) in place in f and alive; returns (dropped, offset)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_collapse", NULL, -1, methods};

PyMODINIT_FUNC
PyInit__collapse(void)
{
    return PyModule_Create(&module);
}
