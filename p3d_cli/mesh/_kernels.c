/*
 * p3d_cli.mesh._kernels: the per-triangle work of `p3d props` in one pass, and an in-place
 * radix sort of 64-bit keys. Optional: p3d_cli.mesh.kernels falls back to the numpy code when
 * this module is not built (no compiler), and the results are the same bits either way.
 *
 * Bit for bit the numpy code's results:
 * - the same IEEE double operations in the same order (build with -ffp-contract=off, never
 *   -ffast-math: a fused multiply-add would round once where numpy rounds twice);
 * - the block sums replay numpy's pairwise summation (numpy/_core/src/umath/loops_utils.h.src,
 *   pairwise_sum: fewer than 8 terms summed in order from 0.0; up to 128 with 8 running sums
 *   combined as ((r0+r1)+(r2+r3))+((r4+r5)+(r6+r7)) and the rest added in order; above, split
 *   at n/2 rounded down to a multiple of 8). The terms of a leaf of up to 128 triangles are
 *   computed into a small buffer that stays in L1 and summed there.
 * - the corner hashes and edge keys are the splitmix64 ones of p3d_cli.mesh.closed.
 *
 * The functions take Python buffers (numpy arrays export them), so the build needs no numpy
 * headers.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define LEAF 128
#define NSUMS 14 /* 10 term rows, the magnitude, the 3 weighted magnitudes */

static const uint64_t M1 = 0xBF58476D1CE4E5B9ULL, M2 = 0x94D049BB133111EBULL, GOLDEN = 0x9E3779B97F4A7C15ULL;

static inline uint64_t mix(uint64_t z) {
    z ^= z >> 30;
    z *= M1;
    z ^= z >> 27;
    z *= M2;
    z ^= z >> 31;
    return z;
}

static inline uint64_t bits_of(double x) {
    uint64_t b;
    x += 0.0; /* -0.0 and 0.0 hash alike */
    memcpy(&b, &x, 8);
    return b;
}

/* A block of triangles: base pointer, byte strides (triangle, corner, axis), float32 or not. */
typedef struct {
    const char *base;
    Py_ssize_t n, st, sv, sa;
    int f32;
} Block;

static inline double coord(const Block *b, Py_ssize_t t, int v, int a) {
    const char *p = b->base + t * b->st + v * b->sv + a * b->sa;
    if (b->f32) {
        float f;
        memcpy(&f, p, 4);
        return (double)f;
    }
    double d;
    memcpy(&d, p, 8);
    return d;
}

static int get_block(PyObject *obj, Py_buffer *view, Block *b) {
    if (PyObject_GetBuffer(obj, view, PyBUF_STRIDES | PyBUF_FORMAT) < 0)
        return -1;
    const char *f = view->format ? view->format : "B";
    if (*f == '<' || *f == '=' || *f == '@')
        f++;
    if (view->ndim != 3 || view->shape[1] != 3 || view->shape[2] != 3 || !((f[0] == 'f' && view->itemsize == 4) ||
                                                                            (f[0] == 'd' && view->itemsize == 8))
        || f[1] != 0) {
        PyBuffer_Release(view);
        PyErr_SetString(PyExc_TypeError, "expected a (k, 3, 3) float32 or float64 array");
        return -1;
    }
    b->base = view->buf;
    b->n = view->shape[0];
    b->st = view->strides[0];
    b->sv = view->strides[1];
    b->sa = view->strides[2];
    b->f32 = view->itemsize == 4;
    return 0;
}

/* numpy's pairwise leaf: the sum of a[0..n) for n <= 128. */
static inline double leaf_sum(const double *a, Py_ssize_t n) {
    Py_ssize_t i;
    if (n < 8) {
        double res = 0.;
        for (i = 0; i < n; i++)
            res += a[i];
        return res;
    }
    double r0 = a[0], r1 = a[1], r2 = a[2], r3 = a[3], r4 = a[4], r5 = a[5], r6 = a[6], r7 = a[7];
    for (i = 8; i < n - (n % 8); i += 8) {
        r0 += a[i + 0];
        r1 += a[i + 1];
        r2 += a[i + 2];
        r3 += a[i + 3];
        r4 += a[i + 4];
        r5 += a[i + 5];
        r6 += a[i + 6];
        r7 += a[i + 7];
    }
    double res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7));
    for (; i < n; i++)
        res += a[i];
    return res;
}

typedef struct {
    const Block *b;
    double o[3];
} Terms;

/* The 14 sums of triangles [t0, t0 + n), n <= 128, as p3d_cli.mesh.integrals.tetra_terms
 * computes each term (same operations, same order). */
static void leaf_terms(const Terms *c, Py_ssize_t t0, Py_ssize_t n, double out[NSUMS]) {
    double buf[NSUMS][LEAF];
    static const int PI[6] = {0, 1, 2, 0, 0, 1}, PJ[6] = {0, 1, 2, 1, 2, 2};
    for (Py_ssize_t k = 0; k < n; k++) {
        double p[3][3];
        for (int v = 0; v < 3; v++)
            for (int a = 0; a < 3; a++)
                p[v][a] = coord(c->b, t0 + k, v, a) - c->o[a];
        double e1[3], e2[3];
        for (int a = 0; a < 3; a++) {
            e1[a] = p[1][a] - p[0][a];
            e2[a] = p[2][a] - p[0][a];
        }
        double det = 0.0, mag = 0.0;
        static const int I[3] = {0, 1, 2}, J[3] = {1, 2, 0}, K[3] = {2, 0, 1};
        for (int r = 0; r < 3; r++) {
            double t = e1[J[r]] * e2[K[r]];
            double u = e1[K[r]] * e2[J[r]];
            double cross = (t - u) * p[0][I[r]];
            det += cross;
            double m = (fabs(t) + fabs(u)) * fabs(p[0][I[r]]);
            mag += m;
        }
        double s[3];
        for (int a = 0; a < 3; a++)
            s[a] = (p[0][a] + p[1][a]) + p[2][a];
        buf[0][k] = det;
        for (int a = 0; a < 3; a++)
            buf[1 + a][k] = det * s[a];
        for (int r = 0; r < 6; r++) {
            int i = PI[r], j = PJ[r];
            double q = p[0][i] * p[0][j];
            q += p[1][i] * p[1][j];
            q += p[2][i] * p[2][j];
            q += s[i] * s[j];
            if (i == j)
                buf[11 + i][k] = mag * q;
            buf[4 + r][k] = q * det;
        }
        buf[10][k] = mag;
    }
    for (int r = 0; r < NSUMS; r++)
        out[r] = leaf_sum(buf[r], n);
}

static void pairwise_terms(const Terms *c, Py_ssize_t t0, Py_ssize_t n, double out[NSUMS]) {
    if (n <= LEAF) {
        leaf_terms(c, t0, n, out);
        return;
    }
    Py_ssize_t n2 = n / 2;
    n2 -= n2 % 8;
    double right[NSUMS];
    pairwise_terms(c, t0, n2, out);
    pairwise_terms(c, t0 + n2, n - n2, right);
    for (int r = 0; r < NSUMS; r++)
        out[r] = out[r] + right[r];
}

/* bounds(block) -> (lo0, lo1, lo2, hi0, hi1, hi2, finite) over the widened coordinates. */
static int bounds_of(const Block *b, double lo[3], double hi[3]) {
    int finite = 1;
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    for (Py_ssize_t t = 0; t < b->n; t++)
        for (int v = 0; v < 3; v++)
            for (int a = 0; a < 3; a++) {
                double x = coord(b, t, v, a);
                if (!isfinite(x))
                    finite = 0;
                if (x < lo[a])
                    lo[a] = x;
                if (x > hi[a])
                    hi[a] = x;
            }
    return finite;
}

static PyObject *py_bounds(PyObject *self, PyObject *args) {
    PyObject *obj;
    if (!PyArg_ParseTuple(args, "O", &obj))
        return NULL;
    Py_buffer view;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    double lo[3], hi[3];
    int finite;
    Py_BEGIN_ALLOW_THREADS
    finite = bounds_of(&b, lo, hi);
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    return Py_BuildValue("(dddddd)O", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], finite ? Py_True : Py_False);
}

/* Edge keys of the block's sides into keys[offset...]: returns how many were written. */
static Py_ssize_t edge_keys(const Block *b, uint64_t *keys) {
    Py_ssize_t w = 0;
    for (Py_ssize_t t = 0; t < b->n; t++) {
        uint64_t h[3];
        for (int v = 0; v < 3; v++) {
            uint64_t z = mix(bits_of(coord(b, t, v, 0)) ^ GOLDEN);
            z = mix(z ^ bits_of(coord(b, t, v, 1)));
            h[v] = mix(z ^ bits_of(coord(b, t, v, 2)));
        }
        for (int v = 0; v < 3; v++) {
            uint64_t start = h[v], end = h[(v + 1) % 3];
            if (start == end)
                continue; /* a side whose ends hash alike bounds nothing */
            uint64_t lo = start < end ? start : end, hi = start < end ? end : start;
            uint64_t key = mix(lo * GOLDEN + hi);
            keys[w++] = (key & ~(uint64_t)1) | (uint64_t)(start < end);
        }
    }
    return w;
}

/* block(tri, ox, oy, oz, keys or None, offset) ->
 *   ((lo0, lo1, lo2, hi0, hi1, hi2), finite, (10 sums), magnitude sum, (3 weighted), keys written)
 * The sums are those of p3d_cli.mesh.integrals.MomentSums.add_columns about the origin o;
 * nothing is summed (zeros) when a coordinate is not finite. */
static PyObject *py_block(PyObject *self, PyObject *args) {
    PyObject *obj, *keyobj;
    double o[3];
    Py_ssize_t offset;
    if (!PyArg_ParseTuple(args, "OdddOn", &obj, &o[0], &o[1], &o[2], &keyobj, &offset))
        return NULL;
    Py_buffer view, kview;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    uint64_t *keys = NULL;
    int have_keys = keyobj != Py_None;
    if (have_keys) {
        if (PyObject_GetBuffer(keyobj, &kview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
            PyBuffer_Release(&view);
            return NULL;
        }
        if (kview.itemsize != 8 || offset < 0 || kview.len / 8 - offset < 3 * b.n) {
            PyBuffer_Release(&view);
            PyBuffer_Release(&kview);
            PyErr_SetString(PyExc_ValueError, "the keys buffer is too small");
            return NULL;
        }
        keys = (uint64_t *)kview.buf + offset;
    }
    double lo[3], hi[3], sums[NSUMS];
    int finite;
    Py_ssize_t written = 0;
    Py_BEGIN_ALLOW_THREADS
    finite = bounds_of(&b, lo, hi);
    memset(sums, 0, sizeof sums);
    if (finite) {
        if (keys)
            written = edge_keys(&b, keys);
        Terms c = {&b, {o[0], o[1], o[2]}};
        if (b.n)
            pairwise_terms(&c, 0, b.n, sums);
        /* numpy's reduction starts from the identity: 0.0 + sum (a sum of -0.0 is 0.0) */
        for (int r = 0; r < NSUMS; r++)
            sums[r] = 0.0 + sums[r];
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    if (have_keys)
        PyBuffer_Release(&kview);
    return Py_BuildValue("(dddddd)O(dddddddddd)d(ddd)n", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
                         finite ? Py_True : Py_False, sums[0], sums[1], sums[2], sums[3], sums[4], sums[5], sums[6],
                         sums[7], sums[8], sums[9], sums[10], sums[11], sums[12], sums[13], written);
}

/* ---- sorting ------------------------------------------------------------------------------ */

static void insertion(uint64_t *a, Py_ssize_t n) {
    for (Py_ssize_t i = 1; i < n; i++) {
        uint64_t x = a[i];
        Py_ssize_t j = i;
        while (j > 0 && a[j - 1] > x) {
            a[j] = a[j - 1];
            j--;
        }
        a[j] = x;
    }
}

static int cmp_u64(const void *x, const void *y) {
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

#define DIGIT 11
#define RADIX (1 << DIGIT)
/* Buckets up to this many keys are finished by LSD passes in a buffer of their size (it and
 * the bucket stay in the 1 MB L2 cache); bigger ones are split again by the next digit. */
#define SMALL (1 << 15)

/* LSD radix sort of a[0..n) on the bits below `shift` (the bits above are common to all),
 * using tmp[0..n). */
static void lsd(uint64_t *a, uint64_t *tmp, Py_ssize_t n, int shift) {
    int low = shift - 3 * DIGIT;
    if (low < 0)
        low = 0;
    uint64_t *src = a, *dst = tmp;
    Py_ssize_t count[RADIX];
    for (int s = low; s < shift; s += DIGIT) {
        int width = shift - s < DIGIT ? shift - s : DIGIT;
        uint64_t mask = ((uint64_t)1 << width) - 1;
        memset(count, 0, sizeof(Py_ssize_t) << width);
        for (Py_ssize_t i = 0; i < n; i++)
            count[(src[i] >> s) & mask]++;
        if (count[(src[0] >> s) & mask] == n)
            continue; /* one value of this digit: nothing to move */
        Py_ssize_t total = 0;
        for (Py_ssize_t d = 0; d <= (Py_ssize_t)mask; d++) {
            Py_ssize_t c = count[d];
            count[d] = total;
            total += c;
        }
        for (Py_ssize_t i = 0; i < n; i++)
            dst[count[(src[i] >> s) & mask]++] = src[i];
        uint64_t *t = src;
        src = dst;
        dst = t;
    }
    if (src != a)
        memcpy(a, src, n * sizeof(uint64_t));
    if (low > 0) {
        /* Ties in the bits sorted so far are in file order: insertion sort finishes them, in
         * about one pass when the keys are hashes; it falls back to qsort past a budget. */
        Py_ssize_t moves = 0, budget = 8 * n + 64;
        for (Py_ssize_t i = 1; i < n; i++) {
            uint64_t x = a[i];
            Py_ssize_t j = i;
            while (j > 0 && a[j - 1] > x) {
                a[j] = a[j - 1];
                j--;
            }
            a[j] = x;
            moves += i - j;
            if (moves > budget) {
                qsort(a, n, sizeof(uint64_t), cmp_u64);
                return;
            }
        }
    }
}

/* Sort a[0..n) whose bits at and above `shift` are common to all: MSD by the next digit (in
 * place, American flag), then each bucket on its own. */
static void msd(uint64_t *a, Py_ssize_t n, int shift, uint64_t *tmp) {
    if (n <= 32) {
        insertion(a, n);
        return;
    }
    if (n <= SMALL || shift <= DIGIT) {
        lsd(a, tmp, n, shift);
        return;
    }
    int s = shift - DIGIT;
    Py_ssize_t *count = calloc(RADIX, sizeof(Py_ssize_t)), *next = malloc(RADIX * sizeof(Py_ssize_t)),
               *end = malloc(RADIX * sizeof(Py_ssize_t));
    if (!count || !next || !end) {
        free(count);
        free(next);
        free(end);
        qsort(a, n, sizeof(uint64_t), cmp_u64);
        return;
    }
    for (Py_ssize_t i = 0; i < n; i++)
        count[(a[i] >> s) & (RADIX - 1)]++;
    Py_ssize_t total = 0;
    for (int d = 0; d < RADIX; d++) {
        next[d] = total;
        total += count[d];
        end[d] = total;
    }
    for (int d = 0; d < RADIX; d++) {
        while (next[d] < end[d]) {
            uint64_t x = a[next[d]];
            int e = (int)((x >> s) & (RADIX - 1));
            while (e != d) {
                uint64_t y = a[next[e]];
                a[next[e]++] = x;
                x = y;
                e = (int)((x >> s) & (RADIX - 1));
            }
            a[next[d]++] = x;
        }
    }
    Py_ssize_t start = 0;
    for (int d = 0; d < RADIX; d++) {
        if (count[d] > 1)
            msd(a + start, count[d], s, tmp);
        start += count[d];
    }
    free(count);
    free(next);
    free(end);
}

/* sort(keys): sorts a C-contiguous uint64 buffer in place (ascending). */
static PyObject *py_sort(PyObject *self, PyObject *args) {
    PyObject *obj;
    if (!PyArg_ParseTuple(args, "O", &obj))
        return NULL;
    Py_buffer view;
    if (PyObject_GetBuffer(obj, &view, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    if (view.itemsize != 8) {
        PyBuffer_Release(&view);
        PyErr_SetString(PyExc_TypeError, "expected 64-bit keys");
        return NULL;
    }
    Py_ssize_t n = view.len / 8;
    uint64_t *tmp = malloc((n < SMALL ? n : SMALL) * sizeof(uint64_t) + 8);
    if (!tmp) {
        PyBuffer_Release(&view);
        return PyErr_NoMemory();
    }
    Py_BEGIN_ALLOW_THREADS
    msd((uint64_t *)view.buf, n, 64, tmp);
    Py_END_ALLOW_THREADS
    free(tmp);
    PyBuffer_Release(&view);
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"bounds", py_bounds, METH_VARARGS, "bounds(block) -> ((lo, hi) 6 floats, finite)"},
    {"block", py_block, METH_VARARGS, "block(block, ox, oy, oz, keys, offset) -> bounds, finite, sums, keys written"},
    {"sort", py_sort, METH_VARARGS, "sort(keys): in-place ascending sort of uint64 keys"},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_kernels", NULL, -1, methods};

PyMODINIT_FUNC PyInit__kernels(void) { return PyModule_Create(&module); }
