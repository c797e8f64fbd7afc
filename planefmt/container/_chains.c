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
#include <stdlib.h>
#include <string.h>

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


/* floor(num / den) for den > 0: C's division truncates toward zero. */
static int64_t
floor_div(int64_t num, int64_t den)
{
    int64_t q = num / den;
    return (num % den != 0 && num < 0) ? q - 1 : q;
}

/* The error of a pass over corners that stopped at corner bad (none where bad < 0): a resolved value
 * beyond limit, or a term not before the corner. */
static void
corner_error(Py_ssize_t bad, int beyond, long long limit)
{
    if (bad >= 0 && beyond)
        PyErr_Format(PyExc_OverflowError, "corner %zd resolves beyond %lld", bad, limit);
    else if (bad >= 0)
        PyErr_Format(PyExc_ValueError, "corner %zd is predicted from a corner not before it", bad);
}

static PyObject *
reflect(PyObject *self, PyObject *args)
{
    /* A kind 12 walk's explicit corners (spec/pln.md §9.16), in place and in corner order: value is
     * (V, 3) row-major, each corner's residuals on entry.  Where corner k's step sources chain
     * a = pointer[k], b = pointer[a], c = pointer[b] and the chain turns (D = d2.d2 > 0, every
     * component of d1 = v[b] - v[c] and d2 = v[a] - v[b] within turn), the prediction is
     * v[a] + floor((2N + D) / 2D), N = 2 (d1.d2) d2 - D d1; elsewhere resolve()'s rule (pointer,
     * plus, minus; -1 where unused; pointer -1: the residuals are the values).  With turn = 2^18 every
     * product is below 2^60, and every resolved magnitude is checked against limit as it is made. */
    PyObject *objs[4];
    static const char *names[4] = {"value", "pointer", "plus", "minus"};
    Py_buffer views[4];
    long long limit, turn;
    int held = 0;
    if (!PyArg_ParseTuple(args, "OOOOLL", &objs[0], &objs[1], &objs[2], &objs[3], &limit, &turn))
        return NULL;
    for (; held < 4; held++)
        if (int64_view(objs[held], &views[held], held == 0, names[held]) < 0)
            goto done;
    Py_ssize_t n = views[1].len / 8, bad = -1;
    if (views[0].len / 8 != 3 * n || views[2].len / 8 != n || views[3].len / 8 != n) {
        PyErr_SetString(PyExc_ValueError, "the corner arrays differ in length");
        goto done;
    }
    if (turn < 0 || turn > (1LL << 18)) {
        PyErr_SetString(PyExc_ValueError, "turn must be within 2^18");
        goto done;
    }
    int64_t *value = views[0].buf;
    const int64_t *pointer = views[1].buf, *plus = views[2].buf, *minus = views[3].buf;
    int beyond = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < n && bad < 0; k++) {
        int64_t a = pointer[k];
        if (a < 0)
            continue;
        int64_t p = plus[k], m = minus[k];
        if (a >= k || p >= k || m >= k) {
            bad = k;
            break;
        }
        int64_t b = pointer[a], c = b >= 0 ? pointer[b] : -1, x[3];
        int turns = b >= 0 && c >= 0 && b < a && c < b;
        int64_t d1[3], d2[3], dd = 0, dot = 0;
        for (int i = 0; turns && i < 3; i++) {
            d1[i] = value[3 * b + i] - value[3 * c + i];
            d2[i] = value[3 * a + i] - value[3 * b + i];
            turns = d1[i] >= -turn && d1[i] <= turn && d2[i] >= -turn && d2[i] <= turn;
        }
        if (turns) {
            for (int i = 0; i < 3; i++) {
                dd += d2[i] * d2[i];
                dot += d1[i] * d2[i];
            }
            turns = dd > 0;
        }
        for (int i = 0; i < 3; i++) {
            if (turns)
                x[i] = value[3 * k + i] + value[3 * a + i]
                       + floor_div(2 * (2 * dot * d2[i] - dd * d1[i]) + dd, 2 * dd);
            else
                x[i] = value[3 * k + i] + value[3 * a + i] + (p >= 0 ? value[3 * p + i] : 0)
                       - (m >= 0 ? value[3 * m + i] : 0);
            if (x[i] > limit || x[i] < -limit) {
                bad = k;
                beyond = 1;
            }
        }
        if (bad < 0)
            for (int i = 0; i < 3; i++)
                value[3 * k + i] = x[i];
    }
    Py_END_ALLOW_THREADS
    corner_error(bad, beyond, limit);
done:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&views[i]);
    if (PyErr_Occurred())
        return NULL;
    Py_RETURN_NONE;
}

/* A slot of an edge map: the directed edge (a, b), a < 0 for an empty slot, and what it maps to.  One
 * struct, not three arrays, so that a probe reads one cache line, not three (a walk of bun_zipper.ply's
 * 69,451 triangles makes 6 probes a triangle into a map of 12 MB). */
typedef struct {
    int64_t a, b, value;
} Slot;

/* Simple tabulation hashing of a directed edge (a, b): a table of 256 random words per byte of a and of
 * b, filled from a key the caller draws per decode (spec §9.13).  A fixed hash lets a file put every
 * edge into a few slots, and linear probing then costs a probe per edge already there (a kind 9 walk
 * of 100,000 such edges took 24 s); with keys the file cannot know, linear probing takes expected
 * constant time per operation (Patrascu and Thorup, "The power of simple tabulation hashing", 2011),
 * whatever the corners.  Only the bytes a corner below the caller's limit can have are hashed: the
 * others are zero in every key, so their tables would only xor a constant into every hash (a walk of
 * 65,536 corners or fewer looks up 4 words an edge, not 16). */
typedef struct {
    int bytes;
    uint64_t t[16][256];
} EdgeHash;

static EdgeHash *
edge_hash_new(uint64_t key, int64_t limit)
{
    EdgeHash *e = malloc(sizeof(EdgeHash));
    if (!e)
        return NULL;
    e->bytes = 1;
    while (e->bytes < 8 && (uint64_t)(limit > 0 ? limit - 1 : 0) >> (8 * e->bytes))
        e->bytes++;
    for (int i = 0; i < 16; i++) {
        if (i % 8 >= e->bytes)
            continue;
        for (int j = 0; j < 256; j++) {
            /* splitmix64 */
            uint64_t z = (key += 0x9E3779B97F4A7C15ULL);
            z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
            z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
            e->t[i][j] = z ^ (z >> 31);
        }
    }
    return e;
}

/* Where directed edge (a, b), both in 0 .. limit - 1, starts probing in a table of mask + 1 slots. */
static int64_t
edge_hash(const EdgeHash *e, int64_t a, int64_t b, int64_t mask)
{
    uint64_t h = 0, x = (uint64_t)a, y = (uint64_t)b;
    for (int i = 0; i < e->bytes; i++, x >>= 8, y >>= 8)
        h ^= e->t[i][x & 0xFF] ^ e->t[8 + i][y & 0xFF];
    return (int64_t)(h & (uint64_t)mask);
}

static PyObject *
average(PyObject *self, PyObject *args)
{
    /* One axis of a kind 10 walk's explicit corners (spec/pln.md §9.14), in place and in corner
     * order: where corner k has parallelograms start[k] .. start[k + 1] - 1 (corners a, b, c each),
     * value[k] = offset[k] + floor((S + floor(n / 2)) / n), S the sum of value[a] + value[b] - value[c];
     * elsewhere resolve()'s rule (pointer, plus, minus; -1 where unused).  Every term is an earlier
     * corner and every resolved magnitude is checked against limit as it is made, so with terms within
     * 2^52 a sum of four parallelograms stays below 2^56. */
    PyObject *objs[9];
    static const char *names[9] = {"value", "pointer", "plus", "minus", "offset", "start", "a", "b", "c"};
    Py_buffer views[9];
    long long limit;
    int held = 0;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOL", &objs[0], &objs[1], &objs[2], &objs[3], &objs[4], &objs[5],
                          &objs[6], &objs[7], &objs[8], &limit))
        return NULL;
    for (; held < 9; held++)
        if (int64_view(objs[held], &views[held], held == 0, names[held]) < 0)
            goto done;
    Py_ssize_t n = views[0].len / 8, m = views[6].len / 8, bad = -1;
    for (int i = 1; i < 5; i++)
        if (views[i].len / 8 != n) {
            PyErr_SetString(PyExc_ValueError, "the corner arrays differ in length");
            goto done;
        }
    if (views[5].len / 8 != n + 1 || views[7].len / 8 != m || views[8].len / 8 != m) {
        PyErr_SetString(PyExc_ValueError, "the parallelogram arrays do not match");
        goto done;
    }
    int64_t *value = views[0].buf;
    const int64_t *pointer = views[1].buf, *plus = views[2].buf, *minus = views[3].buf, *offset = views[4].buf;
    const int64_t *start = views[5].buf, *pa = views[6].buf, *pb = views[7].buf, *pc = views[8].buf;
    int beyond = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < n; k++) {
        int64_t lo = start[k], hi = start[k + 1], x;
        if (lo < 0 || hi < lo || hi > m) {
            bad = k;
            break;
        }
        if (hi > lo) {
            int64_t sum = 0, count = hi - lo;
            for (int64_t q = lo; q < hi; q++) {
                if (pa[q] < 0 || pa[q] >= k || pb[q] < 0 || pb[q] >= k || pc[q] < 0 || pc[q] >= k) {
                    bad = k;
                    break;
                }
                sum += value[pa[q]] + value[pb[q]] - value[pc[q]];
            }
            if (bad >= 0)
                break;
            x = offset[k] + floor_div(sum + count / 2, count);
        } else if (pointer[k] >= 0) {
            int64_t p = pointer[k], a = plus[k], b = minus[k];
            if (p >= k || a >= k || b >= k) {
                bad = k;
                break;
            }
            x = offset[k] + value[p] + (a >= 0 ? value[a] : 0) - (b >= 0 ? value[b] : 0);
        } else {
            continue;
        }
        if (x > limit || x < -limit) {
            bad = k;
            beyond = 1;
            break;
        }
        value[k] = x;
    }
    Py_END_ALLOW_THREADS
    corner_error(bad, beyond, limit);
done:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&views[i]);
    if (PyErr_Occurred())
        return NULL;
    Py_RETURN_NONE;
}


static PyObject *
parallelograms(PyObject *self, PyObject *args)
{
    /* A kind 10 walk's parallelograms (spec/pln.md §9.14): triangles (3T), explicit (V, 0 or 1), and
     * out start (V + 1) and terms (at least 12V): corner k's are terms rows start[k] .. start[k + 1] - 1,
     * (a, b, c) each.  A directed edge's far corner comes from a map filled in triangle order, the first
     * triangle with an edge keeping it; one more pass over the triangles takes each corner's first four.
     * Returns the number of rows; ValueError for a corner outside 0 .. V - 1. */
    PyObject *objs[4];
    static const char *names[4] = {"triangles", "explicit", "start", "terms"};
    Py_buffer views[4];
    int held = 0;
    int64_t rows = 0;
    unsigned long long key;
    if (!PyArg_ParseTuple(args, "OOOOK", &objs[0], &objs[1], &objs[2], &objs[3], &key))
        return NULL;
    for (; held < 4; held++)
        if (int64_view(objs[held], &views[held], held >= 2, names[held]) < 0)
            goto done;
    int64_t cells = views[0].len / 8, t = cells / 3, v = views[1].len / 8;
    if (cells % 3 || views[2].len / 8 != v + 1 || views[3].len / 8 < 12 * v) {
        PyErr_SetString(PyExc_ValueError, "parallelograms: the arrays do not match");
        goto done;
    }
    const int64_t *tri = views[0].buf, *explicit = views[1].buf;
    int64_t *start = views[2].buf, *terms = views[3].buf;
    for (int64_t i = 0; i < cells; i++)
        if (tri[i] < 0 || tri[i] >= v) {
            PyErr_SetString(PyExc_ValueError, "parallelograms: a corner outside the corners");
            goto done;
        }
    int64_t size = 16;
    while (size < 2 * cells)
        size *= 2;
    Slot *slots = malloc(sizeof(Slot) * (size_t)size);
    int64_t *counts = calloc((size_t)(v > 0 ? v : 1), sizeof(int64_t));
    EdgeHash *hash = edge_hash_new(key, v);
    if (!slots || !counts || !hash) {
        free(slots);
        free(counts);
        free(hash);
        PyErr_NoMemory();
        goto done;
    }
    int64_t mask = size - 1;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t k = 0; k < size; k++)
        slots[k].a = -1;
    for (int64_t j = 0; j < t; j++)
        for (int s = 0; s < 3; s++) {
            int64_t a = tri[3 * j + s], b = tri[3 * j + (s + 1) % 3];
            int64_t k = edge_hash(hash, a, b, mask);
            while (slots[k].a >= 0 && (slots[k].a != a || slots[k].b != b))
                k = (k + 1) & mask;
            if (slots[k].a < 0) {
                slots[k].a = a;
                slots[k].b = b;
                slots[k].value = tri[3 * j + (s + 2) % 3];
            }
        }
    for (int64_t j = 0; j < t; j++)
        for (int s = 0; s < 3; s++) {
            int64_t k = tri[3 * j + s], a = tri[3 * j + (s + 1) % 3], b = tri[3 * j + (s + 2) % 3];
            if (counts[k] >= 4 || !explicit[k] || a >= k || b >= k || !explicit[a] || !explicit[b])
                continue;
            int64_t q = edge_hash(hash, b, a, mask);
            while (slots[q].a >= 0 && (slots[q].a != b || slots[q].b != a))
                q = (q + 1) & mask;
            if (slots[q].a < 0)
                continue;
            int64_t c = slots[q].value;
            if (c >= k || !explicit[c])
                continue;
            int64_t *row = terms + 3 * (4 * k + counts[k]++);
            row[0] = a;
            row[1] = b;
            row[2] = c;
        }
    start[0] = 0;
    for (int64_t k = 0; k < v; k++) {
        for (int64_t i = 0; i < 3 * counts[k]; i++)
            terms[3 * rows + i] = terms[12 * k + i];
        rows += counts[k];
        start[k + 1] = rows;
    }
    Py_END_ALLOW_THREADS
    free(slots);
    free(counts);
    free(hash);
done:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&views[i]);
    if (PyErr_Occurred())
        return NULL;
    return PyLong_FromLongLong(rows);
}

/* A shell walk's open edges (spec/pln.md §9.13): directed edges of the decoded surface that no
 * second triangle has closed yet.  Each entry sits on a stack of its directed edge and on two doubly
 * linked lists, of the entries starting and of those ending at a corner, newest first: entering,
 * closing, and the left and right queries take constant time (the map's expected, its hash keyed per
 * decode), so a walk is linear in its triangles whatever a file holds.  The map holds one slot per
 * undirected edge with the newest entry of each direction: entering (a, b) closes an entry of (b, a)
 * or else stacks one on (a, b), both in the slot one probe finds. */
typedef struct {
    int64_t lo, hi;    /* the edge's corners, lo < hi; lo < 0 for an empty slot */
    int64_t newest[2]; /* the newest entry of (lo, hi) and of (hi, lo), -1 for none */
} PairSlot;

typedef struct {
    int64_t corners, used, mask;
    int64_t *start, *end, *below, *in_next, *in_prev, *out_next, *out_prev, *in_head, *out_head;
    PairSlot *slots;
    EdgeHash *hash;
} Open;

static void
open_free(Open *o)
{
    free(o->start);
    free(o->slots);
    free(o->in_head);
    free(o->hash);
}

static int
open_init(Open *o, int64_t triangles, int64_t corners, uint64_t key)
{
    int64_t records = 3 * triangles, size = 16;
    while (size < 2 * records)
        size *= 2;
    memset(o, 0, sizeof(*o));
    o->corners = corners;
    o->mask = size - 1;
    o->start = malloc(sizeof(int64_t) * 7 * (size_t)(records > 0 ? records : 1));
    o->slots = malloc(sizeof(PairSlot) * (size_t)size);
    o->in_head = malloc(sizeof(int64_t) * 2 * (size_t)(corners > 0 ? corners : 1));
    o->hash = edge_hash_new(key, corners);
    if (!o->start || !o->slots || !o->in_head || !o->hash) {
        open_free(o);
        return -1;
    }
    o->end = o->start + records;
    o->below = o->end + records;
    o->in_next = o->below + records;
    o->in_prev = o->in_next + records;
    o->out_next = o->in_prev + records;
    o->out_prev = o->out_next + records;
    o->out_head = o->in_head + corners;
    for (int64_t k = 0; k < size; k++)
        o->slots[k].lo = -1;
    for (int64_t k = 0; k < 2 * corners; k++)
        o->in_head[k] = -1;
    return 0;
}

static void
open_edge(Open *o, int64_t a, int64_t b)
{
    int64_t lo = a < b ? a : b, hi = a < b ? b : a;
    int d = a > b; /* the direction of (a, b) in its slot; 1 - d that of (b, a) */
    int64_t k = edge_hash(o->hash, lo, hi, o->mask);
    while (o->slots[k].lo >= 0 && (o->slots[k].lo != lo || o->slots[k].hi != hi))
        k = (k + 1) & o->mask;
    PairSlot *s = o->slots + k;
    if (s->lo < 0) {
        s->lo = lo;
        s->hi = hi;
        s->newest[0] = s->newest[1] = -1;
    } else if (s->newest[1 - d] >= 0) {
        /* (b, a) is open: (a, b) closes its newest entry */
        int64_t r = s->newest[1 - d];
        s->newest[1 - d] = o->below[r];
        if (o->out_prev[r] >= 0) o->out_next[o->out_prev[r]] = o->out_next[r]; else o->out_head[b] = o->out_next[r];
        if (o->out_next[r] >= 0) o->out_prev[o->out_next[r]] = o->out_prev[r];
        if (o->in_prev[r] >= 0) o->in_next[o->in_prev[r]] = o->in_next[r]; else o->in_head[a] = o->in_next[r];
        if (o->in_next[r] >= 0) o->in_prev[o->in_next[r]] = o->in_prev[r];
        return;
    }
    int64_t r = o->used++;
    o->start[r] = a;
    o->end[r] = b;
    o->out_prev[r] = -1;
    o->out_next[r] = o->out_head[a];
    if (o->out_head[a] >= 0) o->out_prev[o->out_head[a]] = r;
    o->out_head[a] = r;
    o->in_prev[r] = -1;
    o->in_next[r] = o->in_head[b];
    if (o->in_head[b] >= 0) o->in_prev[o->in_head[b]] = r;
    o->in_head[b] = r;
    o->below[r] = s->newest[d];
    s->newest[d] = r;
}

/* Left: the start of the newest open edge ending at i1, the second newest where that start is x. */
static int64_t
open_left(const Open *o, int64_t i1, int64_t x)
{
    int64_t r = o->in_head[i1];
    if (r >= 0 && o->start[r] == x)
        r = o->in_next[r];
    return r >= 0 ? o->start[r] : -1;
}

/* Right: the end of the newest open edge starting at i0, the second newest where that end is x. */
static int64_t
open_right(const Open *o, int64_t i0, int64_t x)
{
    int64_t r = o->out_head[i0];
    if (r >= 0 && o->end[r] == x)
        r = o->out_next[r];
    return r >= 0 ? o->end[r] : -1;
}

static void
open_triangle(Open *o, const int64_t *t)
{
    open_edge(o, t[0], t[1]);
    open_edge(o, t[1], t[2]);
    open_edge(o, t[2], t[0]);
}

/* The ordered lists of a root's and of an attached triangle's free edges (places in them), by length
 * then lexicographically: length, then the places. */
static const int8_t CHILDREN[16][4] = {
    {0}, {1, 0}, {1, 1}, {1, 2}, {2, 0, 1}, {2, 0, 2}, {2, 1, 0}, {2, 1, 2}, {2, 2, 0}, {2, 2, 1},
    {3, 0, 1, 2}, {3, 0, 2, 1}, {3, 1, 0, 2}, {3, 1, 2, 0}, {3, 2, 0, 1}, {3, 2, 1, 0},
};
static const int8_t ATTACHED[5][3] = {{0}, {1, 0}, {1, 1}, {2, 0, 1}, {2, 1, 0}};

static uint64_t
zigzag(int64_t v)
{
    return ((uint64_t)v << 1) ^ (uint64_t)(v >> 63);
}

static int64_t
unzigzag(uint64_t u)
{
    return (int64_t)(u >> 1) ^ -(int64_t)(u & 1);
}

static int
uint64_view(PyObject *obj, Py_buffer *view, int writable, const char *name)
{
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0)
        return -1;
    if (view->itemsize != 8) {
        PyErr_Format(PyExc_TypeError, "%s: expected a contiguous 64-bit array", name);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

/* Reasons a walk fails (spec §9.13), as walk() returns them. */
enum { WALK_OK, WALK_SYMBOL, WALK_ESCAPES, WALK_CORNER, WALK_OPEN, WALK_TWICE, WALK_STACK, WALK_LEFT_OVER,
       WALK_CORNERS, WALK_MEMORY };

static PyObject *
walk(PyObject *self, PyObject *args)
{
    /* symbols (T, uint64), escapes (X, uint64), corners V, triangles out (3T int64), links out (T int64),
     * key, and optionally fresh out (3T bytes): decodes the walk in place and returns (reason, triangle),
     * reason 0 for none.  fresh gets one byte per entry of the corner code stream (a root's three
     * corners, an attached triangle's third; spec §9.11), 1 where it names a corner anew: what a reader
     * otherwise finds again from the triangles in a dozen passes (shellfields.code_stream). */
    PyObject *objs[4], *fresh_obj = NULL;
    long long corners;
    unsigned long long key;
    Py_buffer views[4], fresh_view;
    int held = 0, reason = WALK_OK, has_fresh = 0;
    int64_t at = -1;
    if (!PyArg_ParseTuple(args, "OOLOOK|O", &objs[0], &objs[1], &corners, &objs[2], &objs[3], &key, &fresh_obj))
        return NULL;
    for (; held < 4; held++)
        if (uint64_view(objs[held], &views[held], held >= 2, "walk") < 0)
            goto done;
    int64_t t = views[0].len / 8, x = views[1].len / 8;
    if (fresh_obj != NULL && fresh_obj != Py_None) {
        if (PyObject_GetBuffer(fresh_obj, &fresh_view, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE) < 0)
            goto done;
        has_fresh = 1;
        if (fresh_view.len < 3 * t) {
            PyErr_SetString(PyExc_ValueError, "walk: fresh needs three bytes a triangle");
            goto done;
        }
    }
    if (views[2].len / 8 != 3 * t || views[3].len / 8 != t || corners < 0) {
        PyErr_SetString(PyExc_ValueError, "walk: the arrays do not match the triangles");
        goto done;
    }
    const uint64_t *sym = views[0].buf, *esc = views[1].buf;
    int64_t *tri = views[2].buf, *links = views[3].buf;
    uint8_t *fresh = has_fresh ? fresh_view.buf : NULL;
    int64_t s_at = 0;
    Open o;
    int64_t *stack = malloc(sizeof(int64_t) * (size_t)(3 * t + 1));
    if (!stack || open_init(&o, t, corners, key) < 0) {
        free(stack);
        reason = WALK_MEMORY;
        goto done;
    }
    Py_BEGIN_ALLOW_THREADS
    int64_t top = 0, n = 0, e_at = 0;
    for (int64_t j = 0; j < t && reason == WALK_OK; j++) {
        int64_t *c = tri + 3 * j;
        const int8_t *list;
        int first;
        at = j;
        if (top == 0) {
            if (sym[j] >= 16) { reason = WALK_SYMBOL; break; }
            if (e_at + 3 > x) { reason = WALK_ESCAPES; break; }
            for (int k = 0; k < 3; k++) {
                uint64_t code = esc[e_at++];
                if (code == 0 && n >= corners) { reason = WALK_CORNERS; break; }
                if (code == 0) c[k] = n++;
                else if (code > (uint64_t)n) { reason = WALK_CORNER; break; }
                else c[k] = n - (int64_t)code;
                if (fresh) fresh[s_at++] = code == 0;
            }
            if (reason) break;
            links[j] = 0;
            list = CHILDREN[sym[j]];
            first = 0;
        } else {
            int64_t slot = stack[--top], p = slot / 3, e = slot % 3;
            const int64_t *q = tri + 3 * p;
            if (sym[j] >= 20) { reason = WALK_SYMBOL; break; }
            uint64_t code = sym[j] % 4;
            c[0] = q[(e + 1) % 3];
            c[1] = q[e];
            int64_t opp = q[(e + 2) % 3];
            if (code == 3) {
                if (e_at >= x) { reason = WALK_ESCAPES; break; }
                /* Corners are fewer than 2^61: a larger step names none, and is not added (overflow). */
                if (esc[e_at] >> 62) { reason = WALK_CORNER; break; }
                int64_t w = c[1] + unzigzag(esc[e_at++]);
                if (w < 0 || w >= n) { reason = WALK_CORNER; break; }
                c[2] = w;
            } else if (code == 0) {
                if (n >= corners) { reason = WALK_CORNERS; break; }
                c[2] = n++;
            } else {
                c[2] = code == 1 ? open_left(&o, c[1], opp) : open_right(&o, c[0], opp);
                if (c[2] < 0) { reason = WALK_OPEN; break; }
            }
            if (fresh) fresh[s_at++] = code == 0;
            links[j] = 3 * (j - p - 1) + e + 1;
            list = ATTACHED[sym[j] / 4];
            first = 1;
        }
        if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) { reason = WALK_TWICE; break; }
        open_triangle(&o, c);
        for (int k = list[0]; k >= 1; k--)
            stack[top++] = 3 * j + list[k] + first;
    }
    if (reason == WALK_OK) {
        at = t;
        if (top != 0) reason = WALK_STACK;
        else if (e_at != x) reason = WALK_LEFT_OVER;
        else if (n != corners) reason = WALK_CORNERS;
    }
    Py_END_ALLOW_THREADS
    free(stack);
    open_free(&o);
done:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&views[i]);
    if (has_fresh)
        PyBuffer_Release(&fresh_view);
    if (PyErr_Occurred())
        return NULL;
    return Py_BuildValue("(iL)", reason, (long long)at);
}

static PyObject *
tree_terms(PyObject *self, PyObject *args)
{
    /* A shell tree's corner predictors (spec/pln.md §9.11, §9.12, §9.17), as shellfields._tree_predictors
     * makes them in numpy: links (T int64), triangles (3T int64), explicit (V bytes), fresh (the corner
     * code stream's entries, bytes: 1 where one names a corner anew, V of them), parallelogram, later,
     * and terms out (3V int64): each corner's (p, a, b), -1 where absent.  The caller has checked the
     * tree (parents before their children, V fresh entries); an index outside the arrays is ValueError. */
    PyObject *objs[5];
    static const char *names[5] = {"links", "triangles", "explicit", "fresh", "terms"};
    Py_buffer views[5];
    int held = 0, parallelogram, later, bad = 0;
    if (!PyArg_ParseTuple(args, "OOOOppO", &objs[0], &objs[1], &objs[2], &objs[3], &parallelogram, &later,
                          &objs[4]))
        return NULL;
    for (; held < 5; held++) {
        int flags = PyBUF_C_CONTIGUOUS | (held == 4 ? PyBUF_WRITABLE : 0);
        if ((held == 2 || held == 3) ? PyObject_GetBuffer(objs[held], &views[held], flags) < 0
                                     : int64_view(objs[held], &views[held], held == 4, names[held]) < 0)
            goto done;
    }
    int64_t t = views[0].len / 8, v = views[2].len, stream = views[3].len;
    if (views[1].len / 8 != 3 * t || views[4].len / 8 != 3 * v) {
        PyErr_SetString(PyExc_ValueError, "tree_terms: the arrays do not match");
        goto done;
    }
    const int64_t *links = views[0].buf, *tri = views[1].buf;
    const uint8_t *explicit = views[2].buf, *fresh = views[3].buf;
    int64_t *out = views[4].buf;
    Py_BEGIN_ALLOW_THREADS
    int64_t k = 0, s_at = 0, previous = -1;
    for (int64_t j = 0; j < t && !bad; j++) {
        int64_t per = links[j] == 0 ? 3 : 1;
        for (int64_t q = 0; q < per && !bad; q++, s_at++) {
            if (s_at >= stream) { bad = 1; break; }
            if (!fresh[s_at])
                continue;
            if (k >= v) { bad = 1; break; }
            int64_t gate = tri[3 * j], second = tri[3 * j + 1];
            if (later && second > gate) {
                int64_t swap = gate;
                gate = second;
                second = swap;
            }
            if (gate < 0 || gate >= v || second < 0 || second >= v) { bad = 1; break; }
            int attached = links[j] != 0;
            int64_t *row = out + 3 * k;
            row[0] = attached && explicit[gate] ? gate : previous;
            row[1] = row[2] = -1;
            if (parallelogram && attached) {
                int64_t link = links[j], parent = j - (link - 1) / 3 - 1, edge = (link - 1) % 3;
                if (link < 0 || parent < 0) { bad = 1; break; }
                int64_t opposite = tri[3 * parent + (edge + 2) % 3];
                if (opposite < 0 || opposite >= v) { bad = 1; break; }
                if (explicit[gate] && explicit[second] && explicit[opposite]) {
                    row[1] = second;
                    row[2] = opposite;
                }
            }
            if (explicit[k])
                previous = k;
            k++;
        }
    }
    if (k != v)
        bad = 1;
    Py_END_ALLOW_THREADS
    if (bad)
        PyErr_SetString(PyExc_ValueError, "tree_terms: the tree does not match its corners");
done:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&views[i]);
    if (PyErr_Occurred())
        return NULL;
    Py_RETURN_NONE;
}

static PyObject *
walk_codes(PyObject *self, PyObject *args)
{
    /* triangles (3T int64, a shell tree's, corners numbered by first use), links (T int64), corners V,
     * codes out (T int64): each attached triangle's corner code of spec §9.13 (0 new, 1 left, 2 right,
     * 3 + zigzag(i2 - i1) otherwise); roots' entries are left as they are. */
    PyObject *objs[3];
    long long corners;
    unsigned long long key;
    Py_buffer views[3];
    int held = 0;
    if (!PyArg_ParseTuple(args, "OOLOK", &objs[0], &objs[1], &corners, &objs[2], &key))
        return NULL;
    for (; held < 3; held++)
        if (uint64_view(objs[held], &views[held], held == 2, "walk_codes") < 0)
            goto done;
    int64_t t = views[1].len / 8;
    if (views[0].len / 8 != 3 * t || views[2].len / 8 != t) {
        PyErr_SetString(PyExc_ValueError, "walk_codes: the arrays do not match the triangles");
        goto done;
    }
    const int64_t *tri = views[0].buf, *links = views[1].buf;
    int64_t *codes = views[2].buf;
    Open o;
    if (open_init(&o, t, corners, key) < 0) {
        PyErr_NoMemory();
        goto done;
    }
    Py_BEGIN_ALLOW_THREADS
    int64_t n = 0;
    for (int64_t j = 0; j < t; j++) {
        const int64_t *c = tri + 3 * j;
        if (links[j] == 0) {
            for (int k = 0; k < 3; k++)
                n += c[k] == n;
        } else {
            int64_t p = j - (links[j] - 1) / 3 - 1, e = (links[j] - 1) % 3;
            int64_t opp = tri[3 * p + (e + 2) % 3];
            if (c[2] == n) { codes[j] = 0; n++; }
            else if (open_left(&o, c[1], opp) == c[2]) codes[j] = 1;
            else if (open_right(&o, c[0], opp) == c[2]) codes[j] = 2;
            else codes[j] = 3 + (int64_t)zigzag(c[2] - c[1]);
        }
        open_triangle(&o, c);
    }
    Py_END_ALLOW_THREADS
    open_free(&o);
done:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&views[i]);
    if (PyErr_Occurred())
        return NULL;
    Py_RETURN_NONE;
}

typedef struct { int64_t j, r, p, k; } Step;

static PyObject *
spanning(PyObject *self, PyObject *args)
{
    /* twin (3T int64: the directed half-edge across each triangle edge, -1 for none), faces (T int64),
     * walk, rotation, links (T int64 each, out), defer (int): the encoder's depth-first walk
     * (groups/shells.py, spanning_walk), a neighbour on the same face popped first; with defer, a
     * neighbour on another face (not FREE, -1) is left until the walk has run out, then taken last
     * left first: as a child of the triangle that left it where that triangle is on the path from the
     * last triangle walked to its root (its subtree then follows all walked), else as a root. */
    PyObject *objs[5];
    Py_buffer views[5];
    int held = 0, defer = 0;
    if (!PyArg_ParseTuple(args, "OOOOOi", &objs[0], &objs[1], &objs[2], &objs[3], &objs[4], &defer))
        return NULL;
    for (; held < 5; held++)
        if (int64_view(objs[held], &views[held], held >= 2, "spanning") < 0)
            goto done;
    int64_t t = views[1].len / 8;
    if (views[0].len / 8 != 3 * t || views[2].len / 8 != t || views[3].len / 8 != t || views[4].len / 8 != t) {
        PyErr_SetString(PyExc_ValueError, "spanning: the arrays do not match the triangles");
        goto done;
    }
    const int64_t *twin = views[0].buf, *face = views[1].buf;
    int64_t *walk_out = views[2].buf, *rot = views[3].buf, *links = views[4].buf;
    unsigned char *seen = calloc(t ? t : 1, 1), *on_path = calloc(t ? t : 1, 1);
    int64_t *position = malloc((t ? t : 1) * sizeof(int64_t)), *parent = malloc((t ? t : 1) * sizeof(int64_t));
    /* Each triangle pushes or leaves at most three steps, each start one. */
    Step *stack = malloc((4 * t + 1) * sizeof(Step));
    Step *left = malloc((3 * t + 1) * sizeof(Step));
    if (!seen || !on_path || !position || !parent || !stack || !left) {
        free(seen);
        free(on_path);
        free(position);
        free(parent);
        free(stack);
        free(left);
        PyErr_NoMemory();
        goto done;
    }
    Py_BEGIN_ALLOW_THREADS
    int64_t n = 0, top = 0, kept = 0, start = 0;
    for (;;) {
        while (kept && seen[left[kept - 1].j])
            kept--;
        int64_t anchor = -1;
        if (kept) {
            Step d = left[--kept];
            if (on_path[d.p]) {
                anchor = d.p;
                stack[top++] = d;
            } else {
                stack[top++] = (Step){d.j, d.r, -1, 0};
            }
        } else {
            while (start < t && seen[start])
                start++;
            if (start == t)
                break;
            stack[top++] = (Step){start++, 0, -1, 0};
        }
        /* The path from the last triangle walked up to the anchor leaves the rightmost path (all of it
         * for a root); each triangle joins and leaves it once, so the walk stays linear. */
        for (int64_t m = n - 1; m >= 0 && m != anchor; m = parent[m])
            on_path[m] = 0;
        while (top) {
            Step e = stack[--top];
            if (seen[e.j])
                continue;
            seen[e.j] = 1;
            position[e.j] = n;
            walk_out[n] = e.j;
            rot[n] = e.r;
            parent[n] = e.p;
            links[n] = e.p < 0 ? 0 : 3 * (n - e.p - 1) + e.k + 1;
            n++;
            static const int64_t root_edges[3] = {2, 1, 0}, edges[2] = {2, 1};
            const int64_t *ks = e.p < 0 ? root_edges : edges;
            int count = e.p < 0 ? 3 : 2;
            /* Other faces first, then the same face: the stack pops the last pushed first. */
            for (int same = 0; same < 2; same++)
                for (int i = 0; i < count; i++) {
                    int64_t w = twin[3 * e.j + (e.r + ks[i]) % 3];
                    if (w < 0 || seen[w / 3] || (face[w / 3] == face[e.j]) != same)
                        continue;
                    Step s = {w / 3, w % 3, position[e.j], ks[i]};
                    if (defer && !same && face[w / 3] != -1)
                        left[kept++] = s;
                    else
                        stack[top++] = s;
                }
        }
        for (int64_t m = n - 1; m >= 0 && !on_path[m]; m = parent[m])
            on_path[m] = 1;
    }
    Py_END_ALLOW_THREADS
    free(seen);
    free(on_path);
    free(position);
    free(parent);
    free(stack);
    free(left);
done:
    for (int i = 0; i < held; i++)
        PyBuffer_Release(&views[i]);
    if (PyErr_Occurred())
        return NULL;
    Py_RETURN_NONE;
}

static PyObject *
varints(PyObject *self, PyObject *args)
{
    /* values (contiguous 64-bit array, read as unsigned): their LEB128 varints, concatenated (spec §2.2). */
    PyObject *obj;
    Py_buffer view;
    if (!PyArg_ParseTuple(args, "O", &obj) || uint64_view(obj, &view, 0, "varints") < 0)
        return NULL;
    int64_t n = view.len / 8;
    const uint64_t *v = view.buf;
    /* At most 10 bytes a value. */
    PyObject *out = PyBytes_FromStringAndSize(NULL, 10 * n);
    if (out == NULL) {
        PyBuffer_Release(&view);
        return NULL;
    }
    unsigned char *b = (unsigned char *)PyBytes_AS_STRING(out), *p = b;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t i = 0; i < n; i++) {
        uint64_t x = v[i];
        while (x >= 0x80) {
            *p++ = (unsigned char)(x & 0x7F) | 0x80;
            x >>= 7;
        }
        *p++ = (unsigned char)x;
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    if (_PyBytes_Resize(&out, p - b) < 0)
        return NULL;
    return out;
}

static PyObject *
unvarints(PyObject *self, PyObject *args)
{
    /* data (bytes-like), out (contiguous 64-bit array of count entries): the first count varints of data
     * into out; returns the bytes they took, or -1 where they are not count valid varints (the caller
     * then finds which rule they break, spec §2.2). */
    PyObject *data_obj, *out_obj;
    Py_buffer data, out;
    if (!PyArg_ParseTuple(args, "OO", &data_obj, &out_obj))
        return NULL;
    if (PyObject_GetBuffer(data_obj, &data, PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    if (uint64_view(out_obj, &out, 1, "unvarints") < 0) {
        PyBuffer_Release(&data);
        return NULL;
    }
    const unsigned char *b = data.buf;
    Py_ssize_t size = data.len, pos = 0;
    int64_t n = out.len / 8;
    uint64_t *v = out.buf;
    int bad = 0;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t i = 0; i < n && !bad; i++) {
        uint64_t x = 0;
        int k = 0;
        for (;;) {
            if (pos >= size || k == 10) {
                bad = 1;
                break;
            }
            unsigned char c = b[pos++];
            x |= (uint64_t)(c & 0x7F) << (7 * k);
            k++;
            if (c < 0x80) {
                /* Not minimal (a final zero group), or past 2^64 - 1 (a tenth byte above 1). */
                if ((k > 1 && c == 0) || (k == 10 && c > 1))
                    bad = 1;
                break;
            }
        }
        v[i] = x;
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&data);
    PyBuffer_Release(&out);
    return PyLong_FromSsize_t(bad ? -1 : pos);
}

static PyMethodDef methods[] = {
    {"resolve", resolve, METH_VARARGS,
     "resolve(value, pointer, offset[, plus, minus[, limit]]): in place, value[k] = offset[k] + "
     "value[pointer[k]] (+ value[plus[k]] - value[minus[k]] where those are >= 0) wherever pointer[k] >= 0, "
     "in entry order (int64 arrays; every pointer must go to an earlier entry; OverflowError past limit)."},
    {"average", average, METH_VARARGS,
     "average(value, pointer, plus, minus, offset, start, a, b, c, limit): one axis of a kind 10 walk's "
     "corners (spec §9.14) in place: the floor average of parallelograms a + b - c where a corner has "
     "some, resolve()'s rule elsewhere (OverflowError past limit, ValueError for a term not before)."},
    {"reflect", reflect, METH_VARARGS,
     "reflect(value, pointer, plus, minus, limit, turn): a kind 12 walk's corners (spec §9.16) in place, "
     "value (V, 3) row-major: a turning chain of step sources predicts by reflection, resolve()'s rule "
     "elsewhere (OverflowError past limit, ValueError for a term not before)."},
    {"parallelograms", parallelograms, METH_VARARGS,
     "parallelograms(triangles, explicit, start, terms, key): a kind 10 walk's parallelograms (spec §9.14) into "
     "start (V + 1) and terms (rows a, b, c; at least 12V entries); returns the number of rows."},
    {"walk", walk, METH_VARARGS,
     "walk(symbols, escapes, corners, triangles, links, key[, fresh]): decode a shell walk (spec §9.13) into "
     "triangles (3T int64) and links (T int64) in place, and into fresh (3T bytes) which corner code stream "
     "entries name a corner anew; returns (reason, triangle), reason 0 where the walk is valid."},
    {"spanning", spanning, METH_VARARGS,
     "spanning(twin, faces, walk, rotation, links, defer): the encoder's depth-first walk over shared edges, "
     "a neighbour on the same face first (with defer, one on another face, not -1, left until the walk has "
     "run out), "
     "into walk, rotation and links (int64, in place)."},
    {"varints", varints, METH_VARARGS,
     "varints(values): the unsigned LEB128 varints of a 64-bit array, concatenated (spec §2.2)."},
    {"unvarints", unvarints, METH_VARARGS,
     "unvarints(data, out): the first len(out) LEB128 varints of data into out (64-bit); returns the bytes "
     "they took, or -1 where they are not that many valid varints (spec §2.2)."},
    {"tree_terms", tree_terms, METH_VARARGS,
     "tree_terms(links, triangles, explicit, fresh, parallelogram, later, terms): a shell tree's corner "
     "predictors (p, a, b) into terms (3V int64), as shellfields._tree_predictors makes them."},
    {"walk_codes", walk_codes, METH_VARARGS,
     "walk_codes(triangles, links, corners, codes, key): each attached triangle's corner code of spec §9.13."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_chains", NULL, -1, methods};

PyMODINIT_FUNC
PyInit__chains(void)
{
    return PyModule_Create(&module);
}
