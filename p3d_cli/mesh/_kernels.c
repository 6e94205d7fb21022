/*
 * p3d_cli.mesh._kernels: the per-triangle work of `p3d props` and of `p3d check`'s fast path in
 * compiled loops (issue 32; docs/performance.md, "At the streaming floor"). Optional:
 * p3d_cli.mesh.kernels falls back to the numpy code when this module is not built (no
 * compiler), and the results are the same bits either way.
 *
 * - bounds, block: a block's bounds and finite test, edge keys (in order or dealt to buckets by
 *   their top bits) and the ten divergence-theorem sums with their rounding magnitudes
 *   (p3d_cli.mesh.analysis, integrals, closed);
 * - sort, finish: an in-place radix sort of uint64 keys, and the sort of bucketed keys;
 * - side_keys, groups: the open-mesh road's side keys and its scan of the key groups
 *   (p3d_cli.mesh.closed, boundary);
 * - paired_keys, pairs, confirm: `p3d check`'s fast path (p3d_cli.mesh.paired).
 * - forward_block, distinct, keys_block (at the end): `p3d props`' closed test on half the
 *   keys (p3d_cli.mesh.kernels.ForwardBuckets), and every key for the open road.
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
#ifdef __linux__
#include <sys/mman.h>
#include <unistd.h>
#endif

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

/* The corner hashes of one loaded triangle p[3 v + a] (p3d_cli.mesh.closed._column_hashes:
 * mix(mix(mix(x ^ GOLDEN) ^ y) ^ z) of the float64 bits, -0.0 read as 0.0). */
static inline void corner_hashes(const double p[9], uint64_t h[3]) {
    for (int v = 0; v < 3; v++) {
        uint64_t z = mix(bits_of(p[3 * v]) ^ GOLDEN);
        z = mix(z ^ bits_of(p[3 * v + 1]));
        h[v] = mix(z ^ bits_of(p[3 * v + 2]));
    }
}

/* The edge hash of the side start -> end (distinct hashes): mix(min * GOLDEN + max). */
static inline uint64_t edge_hash(uint64_t start, uint64_t end) {
    uint64_t lo = start < end ? start : end, hi = start < end ? end : start;
    return mix(lo * GOLDEN + hi);
}

/* A block of triangles: base pointer, byte strides (triangle, corner, axis), float32 or not;
 * or, indexed, the corners vertices[faces[t][v]]: base the vertices, st the row stride, sa
 * the axis stride, and the (k, 3) faces at ibase with strides (ist, isv), int32 or int64. */
typedef struct {
    const char *base;
    Py_ssize_t n, st, sv, sa;
    int f32;
    int indexed, i64;
    const char *ibase;
    Py_ssize_t ist, isv;
    Py_buffer iview;
} Block;

static int float_format(const Py_buffer *view) {
    const char *f = view->format ? view->format : "B";
    if (*f == '<' || *f == '=' || *f == '@')
        f++;
    return ((f[0] == 'f' && view->itemsize == 4) || (f[0] == 'd' && view->itemsize == 8)) && f[1] == 0;
}

static int int_format(const Py_buffer *view) {
    const char *f = view->format ? view->format : "B";
    if (*f == '<' || *f == '=' || *f == '@')
        f++;
    return ((f[0] == 'i' && view->itemsize == 4) || ((f[0] == 'l' || f[0] == 'q') && view->itemsize == 8)) &&
           f[1] == 0;
}

/* (vertices, faces): vertices (m, 3) float32 or float64, faces (k, 3) int32 or int64 with
 * every index in [0, m). */
static int get_indexed(PyObject *obj, Py_buffer *view, Block *b) {
    PyObject *vobj = PyTuple_GET_ITEM(obj, 0), *fobj = PyTuple_GET_ITEM(obj, 1);
    if (PyObject_GetBuffer(vobj, view, PyBUF_STRIDES | PyBUF_FORMAT) < 0)
        return -1;
    if (PyObject_GetBuffer(fobj, &b->iview, PyBUF_STRIDES | PyBUF_FORMAT) < 0) {
        PyBuffer_Release(view);
        return -1;
    }
    Py_buffer *f = &b->iview;
    int ok = view->ndim == 2 && view->shape[1] == 3 && float_format(view) && f->ndim == 2 && f->shape[1] == 3 &&
             int_format(f);
    Py_ssize_t m = ok ? view->shape[0] : 0;
    b->i64 = f->itemsize == 8;
    for (Py_ssize_t t = 0; ok && t < f->shape[0]; t++)
        for (int v = 0; v < 3; v++) {
            const char *q = (const char *)f->buf + t * f->strides[0] + v * f->strides[1];
            int64_t i;
            if (b->i64)
                memcpy(&i, q, 8);
            else {
                int32_t j;
                memcpy(&j, q, 4);
                i = j;
            }
            if (i < 0 || i >= m)
                ok = 0;
        }
    if (!ok) {
        PyBuffer_Release(view);
        PyBuffer_Release(&b->iview);
        PyErr_SetString(PyExc_TypeError, "expected (vertices (m, 3) float32 or float64, faces (k, 3) int32 or int64 "
                                         "in [0, m))");
        return -1;
    }
    b->indexed = 1;
    b->base = view->buf;
    b->st = view->strides[0];
    b->sv = 0;
    b->sa = view->strides[1];
    b->f32 = view->itemsize == 4;
    b->ibase = f->buf;
    b->n = f->shape[0];
    b->ist = f->strides[0];
    b->isv = f->strides[1];
    return 0;
}

static void release_block(Py_buffer *view, Block *b) {
    PyBuffer_Release(view);
    if (b->indexed)
        PyBuffer_Release(&b->iview);
}

static int get_block(PyObject *obj, Py_buffer *view, Block *b) {
    b->indexed = 0;
    if (PyTuple_Check(obj) && PyTuple_GET_SIZE(obj) == 2)
        return get_indexed(obj, view, b);
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

/* The state of one block's pass: its origin, where its keys go, its bounds so far. */
typedef struct {
    const Block *b;
    double o[3];
    uint64_t *keys; /* NULL: no keys wanted */
    Py_ssize_t written;
    /* Bucketed keys: key k goes to bucket k >> shift, at keys[b * cap + fill[b]]; NULL fill:
     * one after the other from keys[0]. A full bucket sets overflow (its key is dropped). */
    int64_t *fill;
    Py_ssize_t cap;
    int shift, overflow;
    double lo[3], hi[3];
    int finite;
    /* forward_block: only the keys of sides running from the smaller corner hash are kept;
     * balance sums +g(edge) over those and -g(edge) over the others, mod 2^64. */
    int forward_only;
    uint64_t balance;
    Py_ssize_t backward;
} Pass;

/* Corners of triangles [t0, t0 + n) widened to float64: p[k][3 v + a]. */
static void load(const Block *b, Py_ssize_t t0, Py_ssize_t n, double p[][9]) {
    for (Py_ssize_t k = 0; k < n; k++) {
        const char *tri = b->base + (t0 + k) * b->st;
        for (int v = 0; v < 3; v++) {
            const char *corner = tri + v * b->sv;
            if (b->indexed) {
                const char *q = b->ibase + (t0 + k) * b->ist + v * b->isv;
                int64_t i;
                if (b->i64)
                    memcpy(&i, q, 8);
                else {
                    int32_t j;
                    memcpy(&j, q, 4);
                    i = j;
                }
                corner = b->base + i * b->st;
            }
            for (int a = 0; a < 3; a++) {
                const char *q = corner + a * b->sa;
                if (b->f32) {
                    float f;
                    memcpy(&f, q, 4);
                    p[k][3 * v + a] = (double)f;
                } else
                    memcpy(&p[k][3 * v + a], q, 8);
            }
        }
    }
}

/* Bounds and the finite test of loaded corners. */
static void bound(Pass *c, const double p[][9], Py_ssize_t n) {
    for (Py_ssize_t k = 0; k < n; k++)
        for (int i = 0; i < 9; i++) {
            double x = p[k][i];
            int a = i % 3;
            if (!isfinite(x))
                c->finite = 0;
            if (x < c->lo[a])
                c->lo[a] = x;
            if (x > c->hi[a])
                c->hi[a] = x;
        }
}

/* Edge keys of loaded triangles (p3d_cli.mesh.closed.column_edge_keys): for each side whose
 * ends hash apart, mix(min * GOLDEN + max) with bit 0 the direction (1: from the smaller). */
static void edge_keys(Pass *c, const double p[][9], Py_ssize_t n) {
    uint64_t *keys = c->fill ? c->keys : c->keys + c->written;
    Py_ssize_t w = 0;
    for (Py_ssize_t k = 0; k < n; k++) {
        uint64_t h[3];
        corner_hashes(p[k], h);
        for (int v = 0; v < 3; v++) {
            uint64_t start = h[v], end = h[v == 2 ? 0 : v + 1];
            if (start == end)
                continue; /* a side whose ends hash alike bounds nothing */
            uint64_t key = (edge_hash(start, end) & ~(uint64_t)1) | (uint64_t)(start < end);
            if (c->forward_only) {
                uint64_t g = mix(key | 1);
                if (start > end) {
                    c->balance -= g;
                    c->backward++;
                    continue;
                }
                c->balance += g;
            }
            if (c->fill) {
                uint64_t b = key >> c->shift;
                if (c->fill[b] == c->cap) {
                    c->overflow = 1;
                    continue;
                }
                keys[b * c->cap + c->fill[b]++] = key;
                w++;
            } else
                keys[w++] = key;
        }
    }
    c->written += w;
}

/* The terms' loop runs over the triangles of a leaf in columns (one array per coordinate), so
 * that the compiler vectorises it; on x86-64 with GCC a copy for AVX2 is also built and chosen
 * at run time. Vector lanes round each operation exactly as scalar code does, and no FMA is
 * enabled, so every copy gives the same bits. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CLONES
#endif

CLONES
static void leaf_terms(const double (*P)[LEAF], Py_ssize_t n, double (*buf)[LEAF]) {
    const double *x1 = P[0], *y1 = P[1], *z1 = P[2], *x2 = P[3], *y2 = P[4], *z2 = P[5], *x3 = P[6], *y3 = P[7],
                 *z3 = P[8];
    for (Py_ssize_t k = 0; k < n; k++) {
        double ex1 = x2[k] - x1[k], ey1 = y2[k] - y1[k], ez1 = z2[k] - z1[k];
        double ex2 = x3[k] - x1[k], ey2 = y3[k] - y1[k], ez2 = z3[k] - z1[k];
        /* D = p1 . ((p2 - p1) x (p3 - p1)), in the order of integrals.determinants */
        double t0 = ey1 * ez2, u0 = ez1 * ey2;
        double t1 = ez1 * ex2, u1 = ex1 * ez2;
        double t2 = ex1 * ey2, u2 = ey1 * ex2;
        double det = 0.0;
        det += (t0 - u0) * x1[k];
        det += (t1 - u1) * y1[k];
        det += (t2 - u2) * z1[k];
        double mag = 0.0;
        mag += (fabs(t0) + fabs(u0)) * fabs(x1[k]);
        mag += (fabs(t1) + fabs(u1)) * fabs(y1[k]);
        mag += (fabs(t2) + fabs(u2)) * fabs(z1[k]);
        double sx = (x1[k] + x2[k]) + x3[k], sy = (y1[k] + y2[k]) + y3[k], sz = (z1[k] + z2[k]) + z3[k];
        buf[0][k] = det;
        buf[1][k] = det * sx;
        buf[2][k] = det * sy;
        buf[3][k] = det * sz;
        double qxx = x1[k] * x1[k], qyy = y1[k] * y1[k], qzz = z1[k] * z1[k];
        double qxy = x1[k] * y1[k], qxz = x1[k] * z1[k], qyz = y1[k] * z1[k];
        qxx += x2[k] * x2[k];
        qyy += y2[k] * y2[k];
        qzz += z2[k] * z2[k];
        qxy += x2[k] * y2[k];
        qxz += x2[k] * z2[k];
        qyz += y2[k] * z2[k];
        qxx += x3[k] * x3[k];
        qyy += y3[k] * y3[k];
        qzz += z3[k] * z3[k];
        qxy += x3[k] * y3[k];
        qxz += x3[k] * z3[k];
        qyz += y3[k] * z3[k];
        qxx += sx * sx;
        qyy += sy * sy;
        qzz += sz * sz;
        qxy += sx * sy;
        qxz += sx * sz;
        qyz += sy * sz;
        buf[4][k] = qxx * det;
        buf[5][k] = qyy * det;
        buf[6][k] = qzz * det;
        buf[7][k] = qxy * det;
        buf[8][k] = qxz * det;
        buf[9][k] = qyz * det;
        buf[10][k] = mag;
        buf[11][k] = mag * qxx;
        buf[12][k] = mag * qyy;
        buf[13][k] = mag * qzz;
    }
}

/* The 14 sums of triangles [t0, t0 + n), n <= 128, each term as
 * p3d_cli.mesh.integrals.tetra_terms computes it (same operations, same order); also their
 * bounds and edge keys, from the same loaded corners. */
static void leaf(Pass *c, Py_ssize_t t0, Py_ssize_t n, double out[NSUMS]) {
    double buf[NSUMS][LEAF];
    double raw[LEAF][9];
    double P[9][LEAF];
    load(c->b, t0, n, raw);
    bound(c, raw, n);
    if (c->keys)
        edge_keys(c, raw, n);
    for (int i = 0; i < 9; i++) {
        double o = c->o[i % 3];
        for (Py_ssize_t k = 0; k < n; k++)
            P[i][k] = raw[k][i] - o;
    }
    leaf_terms((const double (*)[LEAF])P, n, buf);
    for (int r = 0; r < NSUMS; r++)
        out[r] = leaf_sum(buf[r], n);
}

/* numpy's pairwise recursion over the block, leaf by leaf in file order. */
static void pairwise(Pass *c, Py_ssize_t t0, Py_ssize_t n, double out[NSUMS]) {
    if (n <= LEAF) {
        leaf(c, t0, n, out);
        return;
    }
    Py_ssize_t n2 = n / 2;
    n2 -= n2 % 8;
    double right[NSUMS];
    pairwise(c, t0, n2, out);
    pairwise(c, t0 + n2, n - n2, right);
    for (int r = 0; r < NSUMS; r++)
        out[r] = out[r] + right[r];
}

static void start_bounds(Pass *c) {
    c->finite = 1;
    for (int a = 0; a < 3; a++) {
        c->lo[a] = INFINITY;
        c->hi[a] = -INFINITY;
    }
}

/* bounds(block) -> ((lo0, lo1, lo2, hi0, hi1, hi2), finite) over the widened coordinates. */
static PyObject *py_bounds(PyObject *self, PyObject *args) {
    PyObject *obj;
    if (!PyArg_ParseTuple(args, "O", &obj))
        return NULL;
    Py_buffer view;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    Pass c = {&b};
    start_bounds(&c);
    Py_BEGIN_ALLOW_THREADS
    double raw[LEAF][9];
    for (Py_ssize_t t0 = 0; t0 < b.n; t0 += LEAF) {
        Py_ssize_t k = b.n - t0 < LEAF ? b.n - t0 : LEAF;
        load(&b, t0, k, raw);
        bound(&c, raw, k);
    }
    Py_END_ALLOW_THREADS
    release_block(&view, &b);
    return Py_BuildValue("(dddddd)O", c.lo[0], c.lo[1], c.lo[2], c.hi[0], c.hi[1], c.hi[2],
                         c.finite ? Py_True : Py_False);
}

/* block(tri, ox, oy, oz, keys or None, offset) ->
 *   ((lo0, lo1, lo2, hi0, hi1, hi2), finite, (10 sums), magnitude sum, (3 weighted), keys written)
 * The sums are those of p3d_cli.mesh.integrals.MomentSums.add_columns about the origin o, the
 * keys those of p3d_cli.mesh.closed.column_edge_keys (in another order). When a coordinate is
 * not finite, the other results mean nothing (the numpy code then words the error). */
static PyObject *py_block(PyObject *self, PyObject *args) {
    PyObject *obj, *keyobj;
    double o[3];
    Py_ssize_t offset;
    PyObject *fillobj = Py_None;
    Py_ssize_t cap = 0;
    int shift = 0;
    if (!PyArg_ParseTuple(args, "OdddOn|Oni", &obj, &o[0], &o[1], &o[2], &keyobj, &offset, &fillobj, &cap, &shift))
        return NULL;
    Py_buffer view, kview, fview;
    int64_t *fill = NULL;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    uint64_t *keys = NULL;
    int have_keys = keyobj != Py_None;
    if (have_keys) {
        if (PyObject_GetBuffer(keyobj, &kview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
            release_block(&view, &b);
            return NULL;
        }
        if (fillobj != Py_None) {
            if (PyObject_GetBuffer(fillobj, &fview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
                release_block(&view, &b);
                PyBuffer_Release(&kview);
                return NULL;
            }
            fill = (int64_t *)fview.buf;
            if (fview.itemsize != 8 || shift < 1 || shift > 63 || cap < 0 ||
                (fview.len / 8) != ((Py_ssize_t)1 << (64 - shift)) || kview.len / 8 < (fview.len / 8) * cap) {
                release_block(&view, &b);
                PyBuffer_Release(&kview);
                PyBuffer_Release(&fview);
                PyErr_SetString(PyExc_ValueError, "the key buckets do not fit the buffer");
                return NULL;
            }
        } else if (kview.itemsize != 8 || offset < 0 || kview.len / 8 - offset < 3 * b.n) {
            release_block(&view, &b);
            PyBuffer_Release(&kview);
            PyErr_SetString(PyExc_ValueError, "the keys buffer is too small");
            return NULL;
        }
        keys = (uint64_t *)kview.buf + (fill ? 0 : offset);
    }
    double sums[NSUMS];
    Pass c = {&b, {o[0], o[1], o[2]}, keys, 0, fill, cap, shift, 0};
    start_bounds(&c);
    Py_BEGIN_ALLOW_THREADS
    memset(sums, 0, sizeof sums);
    if (b.n)
        pairwise(&c, 0, b.n, sums);
    /* numpy's reduction starts from the identity: 0.0 + sum (a sum of -0.0 is 0.0) */
    for (int r = 0; r < NSUMS; r++)
        sums[r] = 0.0 + sums[r];
    Py_END_ALLOW_THREADS
    release_block(&view, &b);
    if (have_keys)
        PyBuffer_Release(&kview);
    if (fill)
        PyBuffer_Release(&fview);
    if (c.overflow)
        c.written = -1;
    return Py_BuildValue("(dddddd)O(dddddddddd)d(ddd)n", c.lo[0], c.lo[1], c.lo[2], c.hi[0], c.hi[1], c.hi[2],
                         c.finite ? Py_True : Py_False, sums[0], sums[1], sums[2], sums[3], sums[4], sums[5],
                         sums[6], sums[7], sums[8], sums[9], sums[10], sums[11], sums[12], sums[13], c.written);
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

/* Buckets up to SMALL keys are finished by LSD passes in a buffer of their size (it and the
 * bucket stay in the 1 MB L2 cache); bigger ones are split by their next digit, in place. */
#define SMALL (1 << 18)
#define LSD_BITS 11
#define LSD_PASSES 2
/* The widest MSD digit: 256 buckets, whose heads stay in L1 while keys are dealt to them. */
#define MSD_BITS 8

/* LSD radix sort of a[0..n) on the LSD_PASSES * LSD_BITS bits below `shift` (the bits at and
 * above it are common to all), through tmp[0..n), one counting pass for all digits; then an
 * insertion sort finishes the ties in the lower bits (about one pass for hashed keys, whose
 * ties are the two sides of an edge; past a budget, qsort does it). */
static void lsd(uint64_t *a, uint64_t *tmp, Py_ssize_t n, int shift) {
    int low = shift - LSD_PASSES * LSD_BITS;
    if (low < 0)
        low = 0;
    int passes = (shift - low + LSD_BITS - 1) / LSD_BITS;
    Py_ssize_t count[LSD_PASSES][1 << LSD_BITS];
    const uint64_t mask = (1 << LSD_BITS) - 1;
    memset(count, 0, sizeof count);
    for (Py_ssize_t i = 0; i < n; i++) {
        uint64_t x = a[i] >> low;
        for (int p = 0; p < passes; p++)
            count[p][(x >> (p * LSD_BITS)) & mask]++;
    }
    uint64_t *src = a, *dst = tmp;
    for (int p = 0; p < passes; p++) {
        int s = low + p * LSD_BITS;
        Py_ssize_t *c = count[p];
        if (c[(src[0] >> s) & mask] == n)
            continue; /* one value of this digit: nothing to move */
        Py_ssize_t total = 0;
        for (int d = 0; d <= (int)mask; d++) {
            Py_ssize_t k = c[d];
            c[d] = total;
            total += k;
        }
        for (Py_ssize_t i = 0; i < n; i++) {
            uint64_t x = src[i];
            dst[c[(x >> s) & mask]++] = x;
        }
        uint64_t *t = src;
        src = dst;
        dst = t;
    }
    if (src != a)
        memcpy(a, src, n * sizeof(uint64_t));
    if (low > 0) {
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
 * place, American flag; wide enough that the buckets come out near SMALL / 4 keys when the
 * keys are hashes), then each bucket on its own. */
static void msd(uint64_t *a, Py_ssize_t n, int shift, uint64_t *tmp) {
    if (n <= 32) {
        insertion(a, n);
        return;
    }
    if (shift == 0)
        return; /* all equal */
    if (n <= SMALL) {
        lsd(a, tmp, n, shift);
        return;
    }
    int width = 4;
    while (width < MSD_BITS && (n >> width) > SMALL / 4)
        width++;
    if (width > shift)
        width = shift;
    int s = shift - width;
    Py_ssize_t radix = (Py_ssize_t)1 << width, dmask = radix - 1;
    Py_ssize_t *count = calloc(radix, sizeof(Py_ssize_t)), *next = malloc(radix * sizeof(Py_ssize_t)),
               *end = malloc(radix * sizeof(Py_ssize_t));
    if (!count || !next || !end) {
        free(count);
        free(next);
        free(end);
        qsort(a, n, sizeof(uint64_t), cmp_u64);
        return;
    }
    for (Py_ssize_t i = 0; i < n; i++)
        count[(a[i] >> s) & dmask]++;
    Py_ssize_t total = 0;
    for (Py_ssize_t d = 0; d < radix; d++) {
        next[d] = total;
        total += count[d];
        end[d] = total;
    }
    for (Py_ssize_t d = 0; d < radix; d++) {
        while (next[d] < end[d]) {
            uint64_t x = a[next[d]];
            Py_ssize_t e = (Py_ssize_t)((x >> s) & dmask);
            while (e != d) {
                uint64_t y = a[next[e]];
                a[next[e]++] = x;
                x = y;
                e = (Py_ssize_t)((x >> s) & dmask);
            }
            a[next[d]++] = x;
        }
    }
    Py_ssize_t start = 0;
    for (Py_ssize_t d = 0; d < radix; d++) {
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

/* finish(keys, fill, cap, shift) -> count: sorts each bucket of bucketed keys (block(...,
 * fill, cap, shift)) in place and moves them together, ascending, to keys[0..count). */
static PyObject *py_finish(PyObject *self, PyObject *args) {
    PyObject *keyobj, *fillobj;
    Py_ssize_t cap;
    int shift;
    if (!PyArg_ParseTuple(args, "OOni", &keyobj, &fillobj, &cap, &shift))
        return NULL;
    Py_buffer kview, fview;
    if (PyObject_GetBuffer(keyobj, &kview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    if (PyObject_GetBuffer(fillobj, &fview, PyBUF_C_CONTIGUOUS) < 0) {
        PyBuffer_Release(&kview);
        return NULL;
    }
    Py_ssize_t buckets = fview.len / 8;
    const int64_t *fill = (const int64_t *)fview.buf;
    int bad = kview.itemsize != 8 || fview.itemsize != 8 || shift < 1 || shift > 63 ||
              buckets != ((Py_ssize_t)1 << (64 - shift)) || kview.len / 8 < buckets * cap;
    for (Py_ssize_t b = 0; !bad && b < buckets; b++)
        bad = fill[b] < 0 || fill[b] > cap;
    if (bad) {
        PyBuffer_Release(&kview);
        PyBuffer_Release(&fview);
        PyErr_SetString(PyExc_ValueError, "the key buckets do not fit the buffer");
        return NULL;
    }
    uint64_t *a = kview.buf, *tmp = malloc((cap < SMALL ? cap : SMALL) * sizeof(uint64_t) + 8);
    if (!tmp) {
        PyBuffer_Release(&kview);
        PyBuffer_Release(&fview);
        return PyErr_NoMemory();
    }
    Py_ssize_t total = 0;
#ifdef __linux__
    uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE);
#endif
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t b = 0; b < buckets; b++) {
        uint64_t *bucket = a + b * cap;
        msd(bucket, fill[b], shift, tmp);
        if (total != b * cap)
            memmove(a + total, bucket, fill[b] * sizeof(uint64_t));
        total += fill[b];
#ifdef __linux__
        /* The bucket's old place above the keys moved so far is dead: give its whole pages
         * back, so that moving the buckets together (over the slack pages of the buckets
         * before, never touched until now) does not grow the resident memory. */
        uintptr_t lo = (uintptr_t)(a + (total > b * cap ? total : b * cap)), hi = (uintptr_t)(bucket + fill[b]);
        lo = (lo + page - 1) / page * page;
        hi = hi / page * page;
        if (page > 1 && hi > lo)
            madvise((void *)lo, hi - lo, MADV_DONTNEED);
#endif
    }
    Py_END_ALLOW_THREADS
    free(tmp);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&fview);
    return PyLong_FromSsize_t(total);
}

/* side_keys(block, keys, keep) -> sides whose ends hash alike. Writes the key of side `slot`
 * (corner slot to slot + 1) of face f at keys[slot * k + f] and whether the side has two
 * distinct ends at keep[slot * k + f]: the layout of p3d_cli.mesh.closed._side_keys before it
 * drops the degenerate sides. */
static PyObject *py_side_keys(PyObject *self, PyObject *args) {
    PyObject *obj, *keyobj, *keepobj;
    if (!PyArg_ParseTuple(args, "OOO", &obj, &keyobj, &keepobj))
        return NULL;
    Py_buffer view, kview, mview;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    if (PyObject_GetBuffer(keyobj, &kview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
        release_block(&view, &b);
        return NULL;
    }
    if (PyObject_GetBuffer(keepobj, &mview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
        release_block(&view, &b);
        PyBuffer_Release(&kview);
        return NULL;
    }
    Py_ssize_t k = b.n, degenerate = 0;
    if (kview.itemsize != 8 || kview.len / 8 < 3 * k || mview.itemsize != 1 || mview.len < 3 * k) {
        release_block(&view, &b);
        PyBuffer_Release(&kview);
        PyBuffer_Release(&mview);
        PyErr_SetString(PyExc_ValueError, "the keys or keep buffer is too small");
        return NULL;
    }
    uint64_t *keys = kview.buf;
    uint8_t *keep = mview.buf;
    Py_BEGIN_ALLOW_THREADS
    double raw[LEAF][9];
    for (Py_ssize_t t0 = 0; t0 < k; t0 += LEAF) {
        Py_ssize_t m = k - t0 < LEAF ? k - t0 : LEAF;
        load(&b, t0, m, raw);
        for (Py_ssize_t j = 0; j < m; j++) {
            uint64_t h[3];
            corner_hashes(raw[j], h);
            for (int v = 0; v < 3; v++) {
                uint64_t start = h[v], end = h[v == 2 ? 0 : v + 1];
                Py_ssize_t at = v * k + t0 + j;
                keep[at] = start != end;
                if (start == end) {
                    degenerate++;
                    keys[at] = 0;
                    continue;
                }
                keys[at] = (edge_hash(start, end) & ~(uint64_t)1) | (uint64_t)(start < end);
            }
        }
    }
    Py_END_ALLOW_THREADS
    release_block(&view, &b);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&mview);
    return PyLong_FromSsize_t(degenerate);
}

/* groups(keys) -> (unbalanced ids, net boundary edges, their sides, doubtful ids or None).
 * One scan of sorted side keys, grouped by edge (key >> 1), with the answers of
 * p3d_cli.mesh.boundary.unbalanced_groups (groups whose directions are used unequally often:
 * their ids, the sum of |forward - backward|, their sides) and p3d_cli.mesh.closed.doubtful_edges
 * (the balanced groups of 4 or more sides, or None when some group other than one use each way
 * is not such: proven open). The ids come as bytes of uint64, ascending. */
static PyObject *py_groups(PyObject *self, PyObject *args) {
    PyObject *keyobj;
    if (!PyArg_ParseTuple(args, "O", &keyobj))
        return NULL;
    Py_buffer kview;
    if (PyObject_GetBuffer(keyobj, &kview, PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    if (kview.itemsize != 8) {
        PyBuffer_Release(&kview);
        PyErr_SetString(PyExc_TypeError, "expected 64-bit keys");
        return NULL;
    }
    const uint64_t *keys = kview.buf;
    Py_ssize_t n = kview.len / 8, nu = 0, nd = 0, cu = 64, cd = 64;
    long long edges = 0, sides = 0;
    int proven_open = 0;
    uint64_t *unbalanced = malloc(cu * 8), *doubtful = malloc(cd * 8);
    int failed = !unbalanced || !doubtful;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; i < n && !failed;) {
        uint64_t edge = keys[i] >> 1;
        Py_ssize_t j = i, forward = 0;
        while (j < n && (keys[j] >> 1) == edge) {
            forward += keys[j] & 1;
            j++;
        }
        Py_ssize_t count = j - i;
        long long net = 2 * (long long)forward - count;
        if (net != 0) {
            if (nu == cu) {
                uint64_t *grown = realloc(unbalanced, (cu *= 2) * 8);
                if (!grown) {
                    failed = 1;
                    break;
                }
                unbalanced = grown;
            }
            unbalanced[nu++] = edge;
            edges += net < 0 ? -net : net;
            sides += count;
        }
        if (!(count == 2 && forward == 1) && !proven_open) {
            if (count < 4 || 2 * forward != count)
                proven_open = 1;
            else {
                if (nd == cd) {
                    uint64_t *grown = realloc(doubtful, (cd *= 2) * 8);
                    if (!grown) {
                        failed = 1;
                        break;
                    }
                    doubtful = grown;
                }
                doubtful[nd++] = edge;
            }
        }
        i = j;
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&kview);
    PyObject *result = NULL;
    if (failed)
        PyErr_NoMemory();
    else {
        PyObject *d = proven_open ? (Py_INCREF(Py_None), Py_None)
                                  : PyBytes_FromStringAndSize((const char *)doubtful, nd * 8);
        PyObject *u = PyBytes_FromStringAndSize((const char *)unbalanced, nu * 8);
        if (d && u)
            result = Py_BuildValue("OLLO", u, edges, sides, d);
        Py_XDECREF(d);
        Py_XDECREF(u);
    }
    free(unbalanced);
    free(doubtful);
    return result;
}

/* pairs(keys, bits, pi) -> whether the sorted side keys of p3d check's fast path pair up.
 * Keys are (edge hash) | direction << bits | side; a clean mesh's sorted keys come in pairs
 * (direction 0, direction 1) of one edge. For each pair (a, b) of sides it sets
 * pi[a] = next(b) and pi[b] = next(a), next(3 f + k) = 3 f + (k + 1) % 3, as
 * p3d_cli.mesh.paired._orbit_map does; False (pi partly written) when some pair is not one
 * edge each way. pi: int32 or int64, as long as the keys. */
static PyObject *py_pairs(PyObject *self, PyObject *args) {
    PyObject *keyobj, *piobj;
    int bits;
    if (!PyArg_ParseTuple(args, "OiO", &keyobj, &bits, &piobj))
        return NULL;
    Py_buffer kview, pview;
    if (PyObject_GetBuffer(keyobj, &kview, PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    if (PyObject_GetBuffer(piobj, &pview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
        PyBuffer_Release(&kview);
        return NULL;
    }
    Py_ssize_t n = kview.len / 8;
    int wide = pview.itemsize == 8;
    if (kview.itemsize != 8 || !(pview.itemsize == 4 || wide) || pview.len / pview.itemsize != n || bits < 1 ||
        bits > 62 || (!wide && n > 2147483647)) {
        PyBuffer_Release(&kview);
        PyBuffer_Release(&pview);
        PyErr_SetString(PyExc_ValueError, "pairs: keys and pi do not match");
        return NULL;
    }
    const uint64_t *keys = kview.buf, mask = ((uint64_t)1 << bits) - 1;
    int clean = n % 2 == 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; clean && i < n; i += 2) {
        uint64_t a = keys[i], b = keys[i + 1];
        if (((a ^ b) >> bits) != 1) {
            clean = 0;
            break;
        }
        int64_t sa = (int64_t)(a & mask), sb = (int64_t)(b & mask);
        int64_t na = sa % 3 == 2 ? sa - 2 : sa + 1, nb = sb % 3 == 2 ? sb - 2 : sb + 1;
        if (wide) {
            ((int64_t *)pview.buf)[sa] = nb;
            ((int64_t *)pview.buf)[sb] = na;
        } else {
            ((int32_t *)pview.buf)[sa] = (int32_t)nb;
            ((int32_t *)pview.buf)[sb] = (int32_t)na;
        }
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&kview);
    PyBuffer_Release(&pview);
    if (clean)
        Py_RETURN_TRUE;
    Py_RETURN_FALSE;
}

/* confirm(block, fan, first, axes) -> whether every corner of the block equals its fan's first
 * corner (p3d_cli.mesh.paired._confirm, one block): fan and first are the block's corners'
 * fan numbers (int32 or int64) and first-corner flags (bytes), in corner order 3 f + k;
 * axes is (3, fans) float64, the fans' coordinates, set from their first corners here. Values
 * compare as numbers (-0.0 equals 0.0). */
static PyObject *py_confirm(PyObject *self, PyObject *args) {
    PyObject *obj, *fanobj, *firstobj, *axesobj;
    if (!PyArg_ParseTuple(args, "OOOO", &obj, &fanobj, &firstobj, &axesobj))
        return NULL;
    Py_buffer view, fview, mview, aview;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    if (PyObject_GetBuffer(fanobj, &fview, PyBUF_C_CONTIGUOUS) < 0) {
        release_block(&view, &b);
        return NULL;
    }
    if (PyObject_GetBuffer(firstobj, &mview, PyBUF_C_CONTIGUOUS) < 0) {
        release_block(&view, &b);
        PyBuffer_Release(&fview);
        return NULL;
    }
    if (PyObject_GetBuffer(axesobj, &aview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
        release_block(&view, &b);
        PyBuffer_Release(&fview);
        PyBuffer_Release(&mview);
        return NULL;
    }
    Py_ssize_t corners = 3 * b.n, fans = aview.len / 24;
    int wide = fview.itemsize == 8, same = 1, bad = 0;
    if (!(fview.itemsize == 4 || wide) || fview.len / fview.itemsize != corners || mview.itemsize != 1 ||
        mview.len != corners || aview.itemsize != 8 || aview.len != 24 * fans)
        bad = 1;
    double *axes = aview.buf;
    if (!bad) {
        Py_BEGIN_ALLOW_THREADS
        double raw[LEAF][9];
        const uint8_t *first = mview.buf;
        /* A fan's first corner is its earliest, in this block or before: set them first. */
        for (int pass = 0; pass < 2 && same && !bad; pass++)
            for (Py_ssize_t t0 = 0; t0 < b.n && same && !bad; t0 += LEAF) {
                Py_ssize_t m = b.n - t0 < LEAF ? b.n - t0 : LEAF;
                load(&b, t0, m, raw);
                for (Py_ssize_t j = 0; j < m && same; j++)
                    for (int v = 0; v < 3; v++) {
                        Py_ssize_t c = 3 * (t0 + j) + v;
                        int64_t f = wide ? ((const int64_t *)fview.buf)[c] : ((const int32_t *)fview.buf)[c];
                        if (f < 0 || f >= fans) {
                            bad = 1;
                            break;
                        }
                        if (pass == 0) {
                            if (first[c])
                                for (int a = 0; a < 3; a++)
                                    axes[a * fans + f] = raw[j][3 * v + a];
                        } else if (axes[f] != raw[j][3 * v] || axes[fans + f] != raw[j][3 * v + 1] ||
                                   axes[2 * fans + f] != raw[j][3 * v + 2]) {
                            same = 0;
                            break;
                        }
                    }
            }
        Py_END_ALLOW_THREADS
    }
    release_block(&view, &b);
    PyBuffer_Release(&fview);
    PyBuffer_Release(&mview);
    PyBuffer_Release(&aview);
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "confirm: the block, fans and axes do not match");
        return NULL;
    }
    if (same)
        Py_RETURN_TRUE;
    Py_RETURN_FALSE;
}

/* paired_keys(block, bits, first_face, keys, fill, cap, shift) -> (degenerate, s1, s2, written)
 * The side keys of p3d check's fast path (p3d_cli.mesh.paired._keyed_pass): for side k of face
 * f, (edge hash with its low bits + 1 bits cleared) | direction << bits | 3 f + k, dealt to
 * buckets by their top bits (as block(..., fill, cap, shift)); s1 = sum of the cleared hashes
 * of the sides running forward and s2 = sum of all of them, mod 2^64 (the balance test).
 * degenerate: a side whose ends hash alike was met (nothing else means anything then);
 * written -1: a bucket overflowed. */
static PyObject *py_paired_keys(PyObject *self, PyObject *args) {
    PyObject *obj, *keyobj, *fillobj;
    int bits, shift;
    Py_ssize_t first, cap;
    if (!PyArg_ParseTuple(args, "OinOOni", &obj, &bits, &first, &keyobj, &fillobj, &cap, &shift))
        return NULL;
    Py_buffer view, kview, fview;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    if (PyObject_GetBuffer(keyobj, &kview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
        release_block(&view, &b);
        return NULL;
    }
    if (PyObject_GetBuffer(fillobj, &fview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
        release_block(&view, &b);
        PyBuffer_Release(&kview);
        return NULL;
    }
    Py_ssize_t buckets = fview.len / 8;
    if (kview.itemsize != 8 || fview.itemsize != 8 || shift < 1 || shift > 63 || cap < 0 || bits < 1 ||
        bits > 62 || first < 0 || buckets != ((Py_ssize_t)1 << (64 - shift)) || kview.len / 8 < buckets * cap ||
        (uint64_t)(3 * (first + b.n)) > ((uint64_t)1 << bits)) {
        release_block(&view, &b);
        PyBuffer_Release(&kview);
        PyBuffer_Release(&fview);
        PyErr_SetString(PyExc_ValueError, "paired_keys: the buffers do not fit");
        return NULL;
    }
    uint64_t *keys = kview.buf, s1 = 0, s2 = 0, low = ((uint64_t)1 << (bits + 1)) - 1;
    int64_t *fill = fview.buf;
    int degenerate = 0, overflow = 0;
    Py_ssize_t written = 0;
    Py_BEGIN_ALLOW_THREADS
    double raw[LEAF][9];
    for (Py_ssize_t t0 = 0; t0 < b.n && !degenerate; t0 += LEAF) {
        Py_ssize_t m = b.n - t0 < LEAF ? b.n - t0 : LEAF;
        load(&b, t0, m, raw);
        for (Py_ssize_t j = 0; j < m && !degenerate; j++) {
            uint64_t h[3];
            corner_hashes(raw[j], h);
            for (int v = 0; v < 3; v++) {
                uint64_t start = h[v], end = h[v == 2 ? 0 : v + 1];
                if (start == end) {
                    degenerate = 1;
                    break;
                }
                uint64_t key = edge_hash(start, end) & ~low, forward = start < end;
                s1 += key * forward;
                s2 += key;
                key |= forward << bits;
                key += 3 * (uint64_t)(first + t0 + j) + v;
                uint64_t bucket = key >> shift;
                if (fill[bucket] == cap) {
                    overflow = 1;
                    continue;
                }
                keys[bucket * cap + fill[bucket]++] = key;
                written++;
            }
        }
    }
    Py_END_ALLOW_THREADS
    release_block(&view, &b);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&fview);
    return Py_BuildValue("OKKn", degenerate ? Py_True : Py_False, (unsigned long long)s1, (unsigned long long)s2,
                         overflow ? (Py_ssize_t)-1 : written);
}

/* Below the module's table (issue 32's closed test on half the keys). */
static PyObject *py_distinct(PyObject *self, PyObject *args);
static PyObject *py_forward_block(PyObject *self, PyObject *args);
static PyObject *py_keys_block(PyObject *self, PyObject *args);

static PyMethodDef methods[] = {
    {"paired_keys", py_paired_keys, METH_VARARGS,
     "paired_keys(block, bits, first_face, keys, fill, cap, shift) -> (degenerate, s1, s2, written)"},
    {"pairs", py_pairs, METH_VARARGS, "pairs(keys, bits, pi) -> whether the sorted side keys pair up"},
    {"confirm", py_confirm, METH_VARARGS, "confirm(block, fan, first, axes) -> whether every corner is its fan's"},
    {"side_keys", py_side_keys, METH_VARARGS, "side_keys(block, keys, keep) -> sides whose ends hash alike"},
    {"groups", py_groups, METH_VARARGS, "groups(sorted keys) -> (unbalanced ids, edges, sides, doubtful ids or None)"},
    {"finish", py_finish, METH_VARARGS, "finish(keys, fill, cap, shift) -> count: sort bucketed keys together"},
    {"bounds", py_bounds, METH_VARARGS, "bounds(block) -> ((lo, hi) 6 floats, finite)"},
    {"block", py_block, METH_VARARGS,
     "block(block, ox, oy, oz, keys, offset[, fill, cap, shift]) -> bounds, finite, sums, keys written (-1: a bucket "
     "overflowed)"},
    {"sort", py_sort, METH_VARARGS, "sort(keys): in-place ascending sort of uint64 keys"},
    {"distinct", py_distinct, METH_VARARGS, "distinct(keys, fill, cap, shift) -> whether no bucketed key is there twice"},
    {"forward_block", py_forward_block, METH_VARARGS,
     "forward_block(block, ox, oy, oz, keys, fill, cap, shift) -> block()'s results, balance, backward sides"},
    {"keys_block", py_keys_block, METH_VARARGS, "keys_block(block, keys, fill, cap, shift) -> keys written (-1: overflow)"},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_kernels", NULL, -1, methods};

PyMODINIT_FUNC PyInit__kernels(void) { return PyModule_Create(&module); }

/* ---- the closed test on half the keys, without moving them (issue 32) --------------------- */

/* The key buckets' buffers (keys, fill: block(..., fill, cap, shift)'s), both writable and
 * contiguous, checked to fit each other (and, with `counts`, each fill within [0, cap]); on
 * failure -1 with the exception set and nothing held. */
static int get_buckets(PyObject *keyobj, PyObject *fillobj, Py_ssize_t cap, int shift, int counts, Py_buffer *kview,
                       Py_buffer *fview) {
    if (PyObject_GetBuffer(keyobj, kview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        return -1;
    if (PyObject_GetBuffer(fillobj, fview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
        PyBuffer_Release(kview);
        return -1;
    }
    Py_ssize_t buckets = fview->len / 8;
    const int64_t *fill = (const int64_t *)fview->buf;
    int bad = kview->itemsize != 8 || fview->itemsize != 8 || shift < 1 || shift > 63 || cap < 0 ||
              buckets != ((Py_ssize_t)1 << (64 - shift)) || kview->len / 8 < buckets * cap;
    for (Py_ssize_t b = 0; counts && !bad && b < buckets; b++)
        bad = fill[b] < 0 || fill[b] > cap;
    if (bad) {
        PyBuffer_Release(kview);
        PyBuffer_Release(fview);
        PyErr_SetString(PyExc_ValueError, "the key buckets do not fit the buffer");
        return -1;
    }
    return 0;
}


/* distinct(keys, fill, cap, shift) -> whether no key is there twice among bucketed keys
 * (forward_block's), and there is at least one. Each bucket is sorted in place and checked
 * while it is in cache; the buckets are never moved together (that would touch every key's
 * page a second time). Stops at the first bucket with a key twice. */
static PyObject *py_distinct(PyObject *self, PyObject *args) {
    PyObject *keyobj, *fillobj;
    Py_ssize_t cap;
    int shift;
    if (!PyArg_ParseTuple(args, "OOni", &keyobj, &fillobj, &cap, &shift))
        return NULL;
    Py_buffer kview, fview;
    if (get_buckets(keyobj, fillobj, cap, shift, 1, &kview, &fview) < 0)
        return NULL;
    Py_ssize_t buckets = fview.len / 8;
    const int64_t *fill = (const int64_t *)fview.buf;
    uint64_t *a = kview.buf, *tmp = malloc((cap < SMALL ? cap : SMALL) * sizeof(uint64_t) + 8);
    if (!tmp) {
        PyBuffer_Release(&kview);
        PyBuffer_Release(&fview);
        return PyErr_NoMemory();
    }
    Py_ssize_t total = 0;
    int distinct = 1;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t b = 0; distinct && b < buckets; b++) {
        uint64_t *bucket = a + b * cap;
        Py_ssize_t n = fill[b];
        msd(bucket, n, shift, tmp);
        for (Py_ssize_t i = 1; i < n; i++)
            if (bucket[i] == bucket[i - 1]) {
                distinct = 0;
                break;
            }
        total += n;
    }
    Py_END_ALLOW_THREADS
    free(tmp);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&fview);
    if (distinct && total > 0)
        Py_RETURN_TRUE;
    Py_RETURN_FALSE;
}

/* forward_block(block, ox, oy, oz, keys, fill, cap, shift) ->
 *   ((lo0, lo1, lo2, hi0, hi1, hi2), finite, (10 sums), magnitude sum, (3 weighted), keys written,
 *    balance, backward sides)
 * block(..., keys, 0, fill, cap, shift) keeping only the keys with bit 0 set (the sides that
 * run from the smaller corner hash to the larger: half the sides), dealt to buckets; balance is
 * the sum mod 2^64 of g = mix(key | 1) over those sides minus g over the others, backward the
 * number of the others. The mesh is closed (keys_pair_up over all the keys) exactly when no
 * kept key is there twice (distinct), the two counts agree and the balance is
 * zero, barring a 64-bit coincidence of the balance: with no forward key twice, an edge used
 * other than once each way is used unequally often in the two directions, and weighs g(edge)
 * times a nonzero count in the balance (p3d_cli.mesh.analysis). */
static PyObject *py_forward_block(PyObject *self, PyObject *args) {
    PyObject *obj, *keyobj, *fillobj;
    double o[3];
    Py_ssize_t cap;
    int shift;
    if (!PyArg_ParseTuple(args, "OdddOOni", &obj, &o[0], &o[1], &o[2], &keyobj, &fillobj, &cap, &shift))
        return NULL;
    Py_buffer view, kview, fview;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    if (get_buckets(keyobj, fillobj, cap, shift, 1, &kview, &fview) < 0) {
        release_block(&view, &b);
        return NULL;
    }
    double sums[NSUMS];
    Pass c = {&b, {o[0], o[1], o[2]}, (uint64_t *)kview.buf, 0, (int64_t *)fview.buf, cap, shift, 0};
    c.forward_only = 1;
    start_bounds(&c);
    Py_BEGIN_ALLOW_THREADS
    memset(sums, 0, sizeof sums);
    if (b.n)
        pairwise(&c, 0, b.n, sums);
    for (int r = 0; r < NSUMS; r++)
        sums[r] = 0.0 + sums[r];
    Py_END_ALLOW_THREADS
    release_block(&view, &b);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&fview);
    if (c.overflow)
        c.written = -1;
    return Py_BuildValue("(dddddd)O(dddddddddd)d(ddd)nKn", c.lo[0], c.lo[1], c.lo[2], c.hi[0], c.hi[1], c.hi[2],
                         c.finite ? Py_True : Py_False, sums[0], sums[1], sums[2], sums[3], sums[4], sums[5],
                         sums[6], sums[7], sums[8], sums[9], sums[10], sums[11], sums[12], sums[13], c.written,
                         (unsigned long long)c.balance, c.backward);
}


/* keys_block(block, keys, fill, cap, shift) -> keys written, -1 when a bucket overflowed:
 * block(..., keys, 0, fill, cap, shift)'s edge keys alone (no bounds, no sums), for the open
 * road's pass that makes every key after forward_block's did not prove the mesh closed. */
static PyObject *py_keys_block(PyObject *self, PyObject *args) {
    PyObject *obj, *keyobj, *fillobj;
    Py_ssize_t cap;
    int shift;
    if (!PyArg_ParseTuple(args, "OOOni", &obj, &keyobj, &fillobj, &cap, &shift))
        return NULL;
    Py_buffer view, kview, fview;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    if (get_buckets(keyobj, fillobj, cap, shift, 1, &kview, &fview) < 0) {
        release_block(&view, &b);
        return NULL;
    }
    Pass c = {&b, {0.0, 0.0, 0.0}, (uint64_t *)kview.buf, 0, (int64_t *)fview.buf, cap, shift, 0};
    Py_BEGIN_ALLOW_THREADS
    double raw[LEAF][9];
    for (Py_ssize_t t0 = 0; t0 < b.n; t0 += LEAF) {
        Py_ssize_t m = b.n - t0 < LEAF ? b.n - t0 : LEAF;
        load(&b, t0, m, raw);
        edge_keys(&c, raw, m);
    }
    Py_END_ALLOW_THREADS
    release_block(&view, &b);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&fview);
    return PyLong_FromSsize_t(c.overflow ? -1 : c.written);
}
