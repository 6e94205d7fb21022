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
 *   keys (p3d_cli.mesh.kernels.ForwardBuckets), with the other half's 32-bit prints, and every
 *   key for the open road.
 * - near_walk (at the end): `p3d repair`'s faces near new faces, the walk of its box tree
 *   (p3d_cli.repairs.near).
 * - print_groups, backward_block, split_groups, pick_sides (at the end): `p3d props`' open
 *   road, the groups of the forward keys and the prints (or of the other half of the keys
 *   beside the forward ones), and the boundary's sides.
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

/* The key of the side start -> end (distinct hashes): its edge hash with bit 0 the direction
 * (1: from the smaller hash), as p3d_cli.mesh.closed makes it. */
static inline uint64_t side_key(uint64_t start, uint64_t end) {
    return (edge_hash(start, end) & ~(uint64_t)1) | (uint64_t)(start < end);
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
    /* forward_block with prints: each backward side's print, the 32 key bits below its
     * bucket's (key >> (shift - 32)), dealt to buckets of the same shift and room;
     * print_overflow is set when one is full (its print is dropped). */
    uint32_t *prints;
    int64_t *print_fill;
    int print_overflow;
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

/* Bounds and the finite test of loaded corners. Selections, not branches (minsd and maxsd
 * take x exactly when x < lo, x > hi, as the tests did), and the exponent bits of every
 * coordinate or-ed together: all ones somewhere is a NaN or an infinity. */
static void bound(Pass *c, const double p[][9], Py_ssize_t n) {
    double lo0 = c->lo[0], lo1 = c->lo[1], lo2 = c->lo[2], hi0 = c->hi[0], hi1 = c->hi[1], hi2 = c->hi[2];
    uint64_t special = 0;
    const uint64_t ones = (uint64_t)0x7ff << 52;
    for (Py_ssize_t k = 0; k < n; k++)
        for (int v = 0; v < 3; v++) {
            double x = p[k][3 * v], y = p[k][3 * v + 1], z = p[k][3 * v + 2];
            uint64_t bx, by, bz;
            memcpy(&bx, &x, 8);
            memcpy(&by, &y, 8);
            memcpy(&bz, &z, 8);
            special |= ((bx & ones) == ones) | ((by & ones) == ones) | ((bz & ones) == ones);
            lo0 = x < lo0 ? x : lo0;
            lo1 = y < lo1 ? y : lo1;
            lo2 = z < lo2 ? z : lo2;
            hi0 = x > hi0 ? x : hi0;
            hi1 = y > hi1 ? y : hi1;
            hi2 = z > hi2 ? z : hi2;
        }
    c->lo[0] = lo0, c->lo[1] = lo1, c->lo[2] = lo2, c->hi[0] = hi0, c->hi[1] = hi1, c->hi[2] = hi2;
    if (special)
        c->finite = 0;
}

/* Edge keys of loaded triangles (p3d_cli.mesh.closed.column_edge_keys): for each side whose
 * ends hash apart, mix(min * GOLDEN + max) with bit 0 the direction (1: from the smaller). */
static void leaf_keys(const double p[][9], Py_ssize_t n, uint64_t h[3][LEAF], uint64_t keys[3][LEAF],
                      uint64_t g[3][LEAF]);
static void forward_keys(Pass *c, const uint64_t h[3][LEAF], const uint64_t keys[3][LEAF],
                         const uint64_t g[3][LEAF], Py_ssize_t n);

/* Edge keys of loaded triangles (p3d_cli.mesh.closed.column_edge_keys): for each side whose
 * ends hash apart, mix(min * GOLDEN + max) with bit 0 the direction (1: from the smaller).
 * The hashes of the leaf are made first, all at once (leaf_keys), then dealt in file order. */
static void edge_keys(Pass *c, const double p[][9], Py_ssize_t n) {
    uint64_t h[3][LEAF], all[3][LEAF], g[3][LEAF];
    leaf_keys(p, n, h, all, c->forward_only ? g : NULL);
    if (c->forward_only && c->fill) {
        forward_keys(c, (const uint64_t (*)[LEAF])h, (const uint64_t (*)[LEAF])all, (const uint64_t (*)[LEAF])g, n);
        return;
    }
    uint64_t *keys = c->fill ? c->keys : c->keys + c->written;
    Py_ssize_t w = 0;
    for (Py_ssize_t k = 0; k < n; k++) {
        for (int v = 0; v < 3; v++) {
            uint64_t start = h[v][k], end = h[v == 2 ? 0 : v + 1][k];
            if (start == end)
                continue; /* a side whose ends hash alike bounds nothing */
            uint64_t key = all[v][k];
            if (c->forward_only) {
                if (start > end) {
                    c->balance -= g[v][k];
                    c->backward++;
                    continue;
                }
                c->balance += g[v][k];
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

/* The block's pass: bounds, sums (pairwise, as numpy's) and edge keys, without the GIL. */
static void integrate(Pass *c, double *sums) {
    start_bounds(c);
    Py_BEGIN_ALLOW_THREADS
    memset(sums, 0, NSUMS * sizeof *sums);
    if (c->b->n)
        pairwise(c, 0, c->b->n, sums);
    /* numpy's reduction starts from the identity: 0.0 + sum (a sum of -0.0 is 0.0) */
    for (int r = 0; r < NSUMS; r++)
        sums[r] = 0.0 + sums[r];
    Py_END_ALLOW_THREADS
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
    integrate(&c, sums);
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
                keys[at] = side_key(start, end);
            }
        }
    }
    Py_END_ALLOW_THREADS
    release_block(&view, &b);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&mview);
    return PyLong_FromSsize_t(degenerate);
}

/* The answers of groups() as a scan finds them, edge by edge (groups and split_groups). */
typedef struct {
    uint64_t *unbalanced, *doubtful;
    Py_ssize_t nu, nd, cu, cd;
    long long edges, sides;
    int proven_open, failed;
} GroupScan;

/* Append x to a growing array (*a, *n, *cap); 0 when memory ran out. */
static int push_u64(uint64_t **a, Py_ssize_t *n, Py_ssize_t *cap, uint64_t x) {
    if (*n == *cap) {
        uint64_t *grown = realloc(*a, (*cap *= 2) * 8);
        if (!grown)
            return 0;
        *a = grown;
    }
    (*a)[(*n)++] = x;
    return 1;
}

/* A fresh scan; failed is set when its arrays cannot be had. */
static void scan_start(GroupScan *s) {
    s->nu = s->nd = 0;
    s->cu = s->cd = 64;
    s->edges = s->sides = 0;
    s->proven_open = 0;
    s->unbalanced = malloc(s->cu * 8);
    s->doubtful = malloc(s->cd * 8);
    s->failed = !s->unbalanced || !s->doubtful;
}

/* One edge's group: count sides, forward of them in direction 1. */
static void scan_edge(GroupScan *s, uint64_t edge, Py_ssize_t forward, Py_ssize_t count) {
    long long net = 2 * (long long)forward - count;
    if (net != 0) {
        if (!push_u64(&s->unbalanced, &s->nu, &s->cu, edge))
            s->failed = 1;
        s->edges += net < 0 ? -net : net;
        s->sides += count;
    }
    if (!(count == 2 && forward == 1) && !s->proven_open) {
        if (count < 4 || 2 * forward != count)
            s->proven_open = 1;
        else if (!push_u64(&s->doubtful, &s->nd, &s->cd, edge))
            s->failed = 1;
    }
}

/* groups()'s result tuple (or a MemoryError), and the scan's arrays freed. */
static PyObject *scan_result(GroupScan *s) {
    PyObject *result = NULL;
    if (s->failed)
        PyErr_NoMemory();
    else {
        PyObject *d = s->proven_open ? (Py_INCREF(Py_None), Py_None)
                                     : PyBytes_FromStringAndSize((const char *)s->doubtful, s->nd * 8);
        PyObject *u = PyBytes_FromStringAndSize((const char *)s->unbalanced, s->nu * 8);
        if (d && u)
            result = Py_BuildValue("OLLO", u, s->edges, s->sides, d);
        Py_XDECREF(d);
        Py_XDECREF(u);
    }
    free(s->unbalanced);
    free(s->doubtful);
    return result;
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
    Py_ssize_t n = kview.len / 8;
    GroupScan scan;
    scan_start(&scan);
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; i < n && !scan.failed;) {
        uint64_t edge = keys[i] >> 1;
        Py_ssize_t j = i, forward = 0;
        while (j < n && (keys[j] >> 1) == edge) {
            forward += keys[j] & 1;
            j++;
        }
        scan_edge(&scan, edge, forward, j - i);
        i = j;
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&kview);
    return scan_result(&scan);
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
static PyObject *py_unite(PyObject *self, PyObject *args);
static PyObject *py_flatten(PyObject *self, PyObject *args);
static PyObject *py_near_walk(PyObject *self, PyObject *args);
static PyObject *py_fan_cycles(PyObject *self, PyObject *args);
static PyObject *py_open_pairs(PyObject *self, PyObject *args);
static PyObject *py_fan_chains(PyObject *self, PyObject *args);
static PyObject *py_area_filter(PyObject *self, PyObject *args);
static PyObject *py_backward_block(PyObject *self, PyObject *args);
static PyObject *py_split_groups(PyObject *self, PyObject *args);
static PyObject *py_print_groups(PyObject *self, PyObject *args);
static PyObject *py_pick_sides(PyObject *self, PyObject *args);
static PyObject *py_populate(PyObject *self, PyObject *args);
static PyObject *py_ear_holds(PyObject *self, PyObject *args);
static PyObject *py_local_terms(PyObject *self, PyObject *args);
static PyObject *py_exact_bins(PyObject *self, PyObject *args);
/* ---- p3d check's self-intersection test (issue 29): the fans' certificate and the broad phase
 * (p3d_cli.mesh.stars, p3d_cli.mesh.broadphase through p3d_cli.mesh.kernels). ---- */

/* A C-contiguous buffer of one kind: 'd' float64, 'f' float32, 'i' int32 or int64, 'B' bytes,
 * 'Q' uint64, 'q' int64. */
static int get_array(PyObject *obj, Py_buffer *v, char kind, int writable, const char *who) {
    if (PyObject_GetBuffer(obj, v, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0)) < 0)
        return -1;
    const char *f = v->format ? v->format : "B";
    if (*f == '<' || *f == '=' || *f == '@')
        f++;
    int ok = 0;
    switch (kind) {
    case 'd': ok = f[0] == 'd' && v->itemsize == 8 && f[1] == 0; break;
    case 'f': ok = f[0] == 'f' && v->itemsize == 4 && f[1] == 0; break;
    case 'i': ok = int_format(v); break;
    case 'q': ok = (f[0] == 'l' || f[0] == 'q') && v->itemsize == 8 && f[1] == 0; break;
    case 'B': ok = v->itemsize == 1 && (f[0] == 'B' || f[0] == '?' || f[0] == 'b') && f[1] == 0; break;
    case 'Q': ok = (f[0] == 'L' || f[0] == 'Q') && v->itemsize == 8 && f[1] == 0; break;
    }
    if (!ok) {
        PyBuffer_Release(v);
        PyErr_Format(PyExc_TypeError, "%s: an array has the wrong dtype", who);
        return -1;
    }
    return 0;
}

static inline int64_t at_index(const Py_buffer *v, Py_ssize_t k) {
    return v->itemsize == 8 ? ((const int64_t *)v->buf)[k] : ((const int32_t *)v->buf)[k];
}

/* star_normals(points, faces, shift, step, normal): p3d_cli.mesh.stars.certified_vertices's
 * first pass: normal[v] += the sum, over the faces of each run of `step` faces, of the cross
 * products (b - a) x (c - a) of the points scaled by 2**shift, per corner in corner order from
 * 0.0 (numpy's bincount), added to normal once per run. points (m, 3) float64, faces (n, 3)
 * int32/int64, normal (m, 3) float64. */
static PyObject *py_star_normals(PyObject *self, PyObject *args) {
    PyObject *po, *fo, *no;
    int shift;
    Py_ssize_t step;
    if (!PyArg_ParseTuple(args, "OOinO", &po, &fo, &shift, &step, &no))
        return NULL;
    Py_buffer pv, fv, nv;
    if (get_array(po, &pv, 'd', 0, "star_normals") < 0)
        return NULL;
    if (get_array(fo, &fv, 'i', 0, "star_normals") < 0) {
        PyBuffer_Release(&pv);
        return NULL;
    }
    if (get_array(no, &nv, 'd', 1, "star_normals") < 0) {
        PyBuffer_Release(&pv);
        PyBuffer_Release(&fv);
        return NULL;
    }
    Py_ssize_t m = pv.len / 24, n = fv.len / fv.itemsize / 3;
    int bad = nv.len != pv.len || fv.len != 3 * n * fv.itemsize || step < 1;
    double *temp = NULL;
    uint8_t *mark = NULL;
    if (!bad) {
        temp = calloc(3 * (size_t)m + 1, sizeof(double));
        mark = calloc((size_t)m + 1, 1);
        if (!temp || !mark) {
            free(temp);
            free(mark);
            PyBuffer_Release(&pv);
            PyBuffer_Release(&fv);
            PyBuffer_Release(&nv);
            return PyErr_NoMemory();
        }
    }
    const double *P = pv.buf;
    double *normal = nv.buf;
    /* x * 2**shift is ldexp(x, shift), both correctly rounded, while 2**shift is a normal number. */
    int scaled = shift > -1000 && shift < 1000;
    double scale = scaled ? ldexp(1.0, shift) : 1.0;
    if (!bad) {
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t c = 0; c < 3 * n && !bad; c++) {
            int64_t v = at_index(&fv, c);
            if (v < 0 || v >= m)
                bad = 1;
        }
        for (Py_ssize_t s = 0; s < n && !bad; s += step) {
            Py_ssize_t e = n - s < step ? n : s + step;
            for (Py_ssize_t f = s; f < e; f++) {
                int64_t id[3];
                double q[3][3];
                for (int k = 0; k < 3; k++) {
                    id[k] = at_index(&fv, 3 * f + k);
                    for (int a = 0; a < 3; a++)
                        q[k][a] = scaled ? P[3 * id[k] + a] * scale : ldexp(P[3 * id[k] + a], shift);
                }
                double u0 = q[1][0] - q[0][0], u1 = q[1][1] - q[0][1], u2 = q[1][2] - q[0][2];
                double v0 = q[2][0] - q[0][0], v1 = q[2][1] - q[0][1], v2 = q[2][2] - q[0][2];
                double c0 = u1 * v2 - u2 * v1, c1 = u2 * v0 - u0 * v2, c2 = u0 * v1 - u1 * v0;
                for (int k = 0; k < 3; k++) {
                    double *t = temp + 3 * id[k];
                    t[0] += c0;
                    t[1] += c1;
                    t[2] += c2;
                }
            }
            for (Py_ssize_t c = 3 * s; c < 3 * e; c++) {
                int64_t v = at_index(&fv, c);
                if (!mark[v]) {
                    mark[v] = 1;
                    for (int a = 0; a < 3; a++)
                        normal[3 * v + a] += temp[3 * v + a];
                }
            }
            for (Py_ssize_t c = 3 * s; c < 3 * e; c++) {
                int64_t v = at_index(&fv, c);
                mark[v] = 0;
                temp[3 * v] = temp[3 * v + 1] = temp[3 * v + 2] = 0.0;
            }
        }
        Py_END_ALLOW_THREADS
    }
    free(temp);
    free(mark);
    PyBuffer_Release(&pv);
    PyBuffer_Release(&fv);
    PyBuffer_Release(&nv);
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "star_normals: the points, faces and normals do not match");
        return NULL;
    }
    Py_RETURN_NONE;
}

/* A sign from Shewchuk's stage A filter: 2 where |det| <= bound * perm and perm != 0 (unsure). */
static inline int filtered(double det, double perm, double bound) {
    if (fabs(det) <= bound * perm && perm != 0)
        return 2;
    return (det > 0) - (det < 0);
}

/* star_signs(points, faces, normal, bound, g0, g1, good, count, deferred) -> deferred count, or
 * -1 when more corners than deferred holds were unsure.
 * p3d_cli.mesh.stars.certified_vertices's second pass, corner by corner: the sector sign
 * det[b - v, c - v, N] and the two turns det[b - v, R, N], det[R, c - v, N] with R = N x g0 (or
 * N x g1 where that is weak), each by the float filter of stars._sector and stars._turn; a
 * corner with a sign the filter leaves unsure is written to deferred (3 f + k) and left to the
 * caller's exact code, the others clear good[v] (a bad sign) and count the sectors holding R.
 * good (m,) bytes, count (m,) int64, deferred int64. */
static PyObject *py_star_signs(PyObject *self, PyObject *args) {
    PyObject *po, *fo, *no, *go, *co, *dobj;
    double bound, g0[3], g1[3];
    if (!PyArg_ParseTuple(args, "OOOd(ddd)(ddd)OOO", &po, &fo, &no, &bound, &g0[0], &g0[1], &g0[2], &g1[0], &g1[1],
                          &g1[2], &go, &co, &dobj))
        return NULL;
    Py_buffer v[6];
    const char kinds[6] = {'d', 'i', 'd', 'B', 'q', 'q'};
    PyObject *objs[6] = {po, fo, no, go, co, dobj};
    for (int k = 0; k < 6; k++)
        if (get_array(objs[k], &v[k], kinds[k], k >= 3, "star_signs") < 0) {
            while (k--)
                PyBuffer_Release(&v[k]);
            return NULL;
        }
    Py_ssize_t m = v[0].len / 24, n = v[1].len / v[1].itemsize / 3, cap = v[5].len / 8;
    int bad = v[2].len != v[0].len || v[1].len != 3 * n * v[1].itemsize || v[3].len != m || v[4].len != 8 * m;
    Py_ssize_t nd = 0;
    if (!bad) {
        const double *P = v[0].buf, *normal = v[2].buf;
        uint8_t *good = v[3].buf;
        int64_t *count = v[4].buf, *deferred = v[5].buf;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t f = 0; f < n && !bad && nd >= 0; f++) {
            int64_t id[3];
            for (int k = 0; k < 3; k++) {
                id[k] = at_index(&v[1], 3 * f + k);
                if (id[k] < 0 || id[k] >= m)
                    bad = 1;
            }
            if (bad)
                break;
            for (int k = 0; k < 3; k++) {
                int64_t w = id[k];
                const double *p = P + 3 * w, *b = P + 3 * id[(k + 1) % 3], *c = P + 3 * id[(k + 2) % 3];
                const double *N = normal + 3 * w;
                double r0 = N[1] * g0[2] - N[2] * g0[1], r1 = N[2] * g0[0] - N[0] * g0[2],
                       r2 = N[0] * g0[1] - N[1] * g0[0];
                if ((fabs(r0) + fabs(r1)) + fabs(r2) < 0.25 * ((fabs(N[0]) + fabs(N[1])) + fabs(N[2]))) {
                    r0 = N[1] * g1[2] - N[2] * g1[1];
                    r1 = N[2] * g1[0] - N[0] * g1[2];
                    r2 = N[0] * g1[1] - N[1] * g1[0];
                }
                double p0 = r1 * N[2], p1 = r2 * N[1], p2 = r2 * N[0], p3 = r0 * N[2], p4 = r0 * N[1], p5 = r1 * N[0];
                double M0 = p0 - p1, M1 = p2 - p3, M2 = p4 - p5;
                double A0 = fabs(p0) + fabs(p1), A1 = fabs(p2) + fabs(p3), A2 = fabs(p4) + fabs(p5);
                double x0 = b[0] - p[0], x1 = b[1] - p[1], x2 = b[2] - p[2];
                double y0 = c[0] - p[0], y1 = c[1] - p[1], y2 = c[2] - p[2];
                double q0 = x1 * y2, q1 = x2 * y1, q2 = x2 * y0, q3 = x0 * y2, q4 = x0 * y1, q5 = x1 * y0;
                double det = ((q0 - q1) * N[0] + (q2 - q3) * N[1]) + (q4 - q5) * N[2];
                double perm = ((fabs(q0) + fabs(q1)) * fabs(N[0]) + (fabs(q2) + fabs(q3)) * fabs(N[1])) +
                              (fabs(q4) + fabs(q5)) * fabs(N[2]);
                int sector = filtered(det, perm, bound);
                det = (x0 * M0 + x1 * M1) + x2 * M2;
                perm = (fabs(x0) * A0 + fabs(x1) * A1) + fabs(x2) * A2;
                int before = filtered(det, perm, bound);
                det = (y0 * M0 + y1 * M1) + y2 * M2;
                perm = (fabs(y0) * A0 + fabs(y1) * A1) + fabs(y2) * A2;
                int after = filtered(det, perm, bound);
                if (sector == 2 || before == 2 || after == 2) {
                    if (nd >= cap) {
                        nd = -1;
                        break;
                    }
                    deferred[nd++] = 3 * f + k;
                    continue;
                }
                after = -after;
                if (sector <= 0 || before == 0 || after == 0)
                    good[w] = 0;
                if (before > 0 && after > 0)
                    count[w]++;
            }
        }
        Py_END_ALLOW_THREADS
    }
    for (int k = 0; k < 6; k++)
        PyBuffer_Release(&v[k]);
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "star_signs: the points, faces and outputs do not match");
        return NULL;
    }
    return PyLong_FromSsize_t(nd);
}

/* The broad phase's grid of one level (p3d_cli.mesh.broadphase.compiled_pairs): every face of
 * the level entered once, in the cell of its box's lower corner, cells numbered
 * clip(floor((x - origin) / size), 0, 2**40) per axis (a size per axis), keys
 * (((z << by | y) << bx | x) << fbits) | box, sorted. */
typedef struct {
    double origin[3], size[3];
    int bits[3], fbits;
    int64_t span[3];
} Level;

static inline int64_t cell_of(double x, double origin, double size) {
    double t = floor((x - origin) / size);
    if (!(t >= 0))
        t = 0;
    if (t > 1099511627776.0)
        t = 1099511627776.0;
    return (int64_t)t;
}

static int parse_level(PyObject *tuple, Level *L) {
    if (!PyArg_ParseTuple(tuple, "(ddd)(ddd)(iii)i(LLL)", &L->origin[0], &L->origin[1], &L->origin[2], &L->size[0],
                          &L->size[1], &L->size[2], &L->bits[0], &L->bits[1], &L->bits[2], &L->fbits, &L->span[0],
                          &L->span[1], &L->span[2]))
        return 0;
    if (L->fbits < 1 || L->fbits > 62 || L->bits[0] < 1 || L->bits[1] < 1 || L->bits[2] < 1 ||
        L->bits[0] + L->bits[1] + L->bits[2] + L->fbits > 64 || L->span[0] < 0 || L->span[1] < 0 || L->span[2] < 0 ||
        !(L->size[0] > 0 && L->size[1] > 0 && L->size[2] > 0)) {
        PyErr_SetString(PyExc_ValueError, "grid: the level does not make 64-bit keys");
        return 0;
    }
    return 1;
}

static void release_all(Py_buffer *v, const int *got, int k) {
    for (int j = 0; j < k; j++)
        if (got[j])
            PyBuffer_Release(&v[j]);
}

/* The faces' boxes as p3d_cli.mesh.intersections._boxes makes them: the corners' least and
 * greatest coordinates, less the centre, scaled by 2**shift, rounded outwards to float32 and
 * moved one float32 step further out. */
typedef struct {
    const double *points;
    const Py_buffer *faces, *live;
    double centre[3], scale;
    int shift, scaled;
    Py_ssize_t m_points, nfaces, n;
} Frame;

static int parse_frame(PyObject *tuple, Frame *F) {
    if (!PyArg_ParseTuple(tuple, "(ddd)i", &F->centre[0], &F->centre[1], &F->centre[2], &F->shift))
        return 0;
    F->scaled = F->shift > -1000 && F->shift < 1000;
    F->scale = F->scaled ? ldexp(1.0, F->shift) : 1.0;
    return 1;
}

/* Whether every live number names a face and every corner of those a point. */
static int frame_valid(Frame *F) {
    for (Py_ssize_t e = 0; e < F->n; e++) {
        int64_t f = at_index(F->live, e);
        if (f < 0 || f >= F->nfaces)
            return 0;
        for (int k = 0; k < 3; k++) {
            int64_t v = at_index(F->faces, 3 * f + k);
            if (v < 0 || v >= F->m_points)
                return 0;
        }
    }
    return 1;
}

static inline void face_box(const Frame *F, int64_t box, float out[6]) {
    int64_t f = at_index(F->live, box);
    const double *a = F->points + 3 * at_index(F->faces, 3 * f), *b = F->points + 3 * at_index(F->faces, 3 * f + 1),
                 *c = F->points + 3 * at_index(F->faces, 3 * f + 2);
    for (int k = 0; k < 3; k++) {
        double low = a[k] < b[k] ? a[k] : b[k], high = a[k] > b[k] ? a[k] : b[k];
        low = c[k] < low ? c[k] : low;
        high = c[k] > high ? c[k] : high;
        low -= F->centre[k];
        high -= F->centre[k];
        low = F->scaled ? low * F->scale : ldexp(low, F->shift);
        high = F->scaled ? high * F->scale : ldexp(high, F->shift);
        float l = (float)low, h = (float)high;
        if ((double)l > low)
            l = nextafterf(l, -INFINITY);
        if ((double)h < high)
            h = nextafterf(h, INFINITY);
        out[k] = nextafterf(l, -INFINITY);
        out[3 + k] = nextafterf(h, INFINITY);
    }
}

enum { F_POINTS, F_FACES, F_LIVE, F_ARRAYS };

/* Points (m, 3) float64, faces (k, 3) int, live (n,) int: the frame's arrays, checked. */
static int get_frame(PyObject *po, PyObject *fo, PyObject *lo, PyObject *frame, Py_buffer *v, int *got, Frame *F,
                     const char *who) {
    PyObject *objs[F_ARRAYS] = {po, fo, lo};
    const char kinds[F_ARRAYS] = {'d', 'i', 'i'};
    for (int k = 0; k < F_ARRAYS; k++) {
        if (get_array(objs[k], &v[k], kinds[k], 0, who) < 0)
            return -1;
        got[k] = 1;
    }
    if (!parse_frame(frame, F))
        return -1;
    F->points = v[F_POINTS].buf;
    F->faces = &v[F_FACES];
    F->live = &v[F_LIVE];
    F->m_points = v[F_POINTS].len / 24;
    F->nfaces = v[F_FACES].len / v[F_FACES].itemsize / 3;
    F->n = v[F_LIVE].len / v[F_LIVE].itemsize;
    if (!frame_valid(F)) {
        PyErr_Format(PyExc_ValueError, "%s: the points, faces and live faces do not match", who);
        return -1;
    }
    return 0;
}

/* face_extents(points, faces, live, frame, extent) -> (least lower corner, greatest upper
 * corner): each live face's box (frame: (centre, shift)), its largest extent in float32 (as
 * numpy subtracts float32 corners), and the boxes' bounds. */
static PyObject *py_face_extents(PyObject *self, PyObject *args) {
    PyObject *po, *fo, *lo, *frame, *eo;
    if (!PyArg_ParseTuple(args, "OOOOO", &po, &fo, &lo, &frame, &eo))
        return NULL;
    Py_buffer v[F_ARRAYS + 1];
    int got[F_ARRAYS + 1] = {0};
    Frame F;
    if (get_frame(po, fo, lo, frame, v, got, &F, "face_extents") < 0 ||
        get_array(eo, &v[F_ARRAYS], 'f', 1, "face_extents") < 0) {
        release_all(v, got, F_ARRAYS + 1);
        return NULL;
    }
    got[F_ARRAYS] = 1;
    if (v[F_ARRAYS].len != 4 * F.n) {
        release_all(v, got, F_ARRAYS + 1);
        PyErr_SetString(PyExc_ValueError, "face_extents: the extents do not match the faces");
        return NULL;
    }
    float *extent = v[F_ARRAYS].buf;
    float least[3] = {INFINITY, INFINITY, INFINITY}, most[3] = {-INFINITY, -INFINITY, -INFINITY};
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t e = 0; e < F.n; e++) {
        float box[6];
        face_box(&F, e, box);
        float x = box[3] - box[0], y = box[4] - box[1], z = box[5] - box[2];
        float w = x > y ? x : y;
        extent[e] = w > z ? w : z;
        for (int k = 0; k < 3; k++) {
            least[k] = box[k] < least[k] ? box[k] : least[k];
            most[k] = box[3 + k] > most[k] ? box[3 + k] : most[k];
        }
    }
    Py_END_ALLOW_THREADS
    release_all(v, got, F_ARRAYS + 1);
    return Py_BuildValue("(ddd)(ddd)", (double)least[0], (double)least[1], (double)least[2], (double)most[0],
                         (double)most[1], (double)most[2]);
}

/* An entry of a level's grid: the box (lower corner, upper corner) and the face's three
 * vertex ids, a certified vertex's id stored as ~id (negative). In key order, scanning a run
 * of cells reads memory in order. */
typedef struct {
    float box[6];
    int32_t v[3];
} Entry;

/* grid_keys(points, faces, live, frame, members, level, keys) -> span: the keys of a level's
 * members (numbers into live; None: all, in order), each with the member's position in its low
 * fbits bits, in the members' order; and the most cells minus one a member's box spans along
 * each axis. */
static PyObject *py_grid_keys(PyObject *self, PyObject *args) {
    PyObject *po, *fo, *lo, *frame, *mo, *lev, *ko;
    if (!PyArg_ParseTuple(args, "OOOOOOO", &po, &fo, &lo, &frame, &mo, &lev, &ko))
        return NULL;
    Level L;
    if (!parse_level(lev, &L))
        return NULL;
    enum { MEMBERS = F_ARRAYS, KEYS, ARRAYS };
    Py_buffer v[ARRAYS];
    int got[ARRAYS] = {0};
    Frame F;
    if (get_frame(po, fo, lo, frame, v, got, &F, "grid_keys") < 0) {
        release_all(v, got, ARRAYS);
        return NULL;
    }
    const char kinds[ARRAYS] = {0, 0, 0, 'i', 'Q'};
    PyObject *objs[ARRAYS] = {NULL, NULL, NULL, mo, ko};
    for (int k = MEMBERS; k < ARRAYS; k++) {
        if (k == MEMBERS && mo == Py_None)
            continue;
        if (get_array(objs[k], &v[k], kinds[k], k == KEYS, "grid_keys") < 0) {
            release_all(v, got, ARRAYS);
            return NULL;
        }
        got[k] = 1;
    }
    const Py_buffer *members = got[MEMBERS] ? &v[MEMBERS] : NULL; /* None: every live face */
    Py_ssize_t k = members ? members->len / members->itemsize : F.n;
    int bad = v[KEYS].len != 8 * k || ((int64_t)1 << L.fbits) < k;
    int64_t span[3] = {0, 0, 0};
    if (!bad) {
        uint64_t *keys = v[KEYS].buf;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t e = 0; e < k && !bad; e++) {
            int64_t box = members ? at_index(members, e) : e;
            if (box < 0 || box >= F.n) {
                bad = 1;
                break;
            }
            float b[6];
            face_box(&F, box, b);
            uint64_t key = 0;
            for (int a = 2; a >= 0; a--) {
                int64_t c0 = cell_of(b[a], L.origin[a], L.size[a]), c1 = cell_of(b[3 + a], L.origin[a], L.size[a]);
                if (c1 - c0 > span[a])
                    span[a] = c1 - c0;
                if (c0 >> L.bits[a]) {
                    bad = 1;
                    break;
                }
                key = key << L.bits[a] | (uint64_t)c0;
            }
            keys[e] = key << L.fbits | (uint64_t)e;
        }
        Py_END_ALLOW_THREADS
    }
    release_all(v, got, ARRAYS);
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "grid_keys: the members, level and keys do not match");
        return NULL;
    }
    return Py_BuildValue("LLL", (long long)span[0], (long long)span[1], (long long)span[2]);
}

/* grid_fill(points, faces, live, frame, keys, fbits, members, certified, entries): the entries
 * (k, 36) bytes of keys (any k of a level's keys, in their order): the box and vertex ids of
 * the live face members[p], p the key's low fbits bits (members None: p itself). */
static PyObject *py_grid_fill(PyObject *self, PyObject *args) {
    PyObject *po, *fo, *lo, *frame, *ko, *mo, *cert_o, *eo;
    int fbits;
    if (!PyArg_ParseTuple(args, "OOOOOiOOO", &po, &fo, &lo, &frame, &ko, &fbits, &mo, &cert_o, &eo))
        return NULL;
    enum { KEYS = F_ARRAYS, MEMBERS, CERT, ENTRIES, ARRAYS };
    Py_buffer v[ARRAYS];
    int got[ARRAYS] = {0}, certify = cert_o != Py_None;
    Frame F;
    if (get_frame(po, fo, lo, frame, v, got, &F, "grid_fill") < 0) {
        release_all(v, got, ARRAYS);
        return NULL;
    }
    const char kinds[ARRAYS] = {0, 0, 0, 'Q', 'i', 'B', 'B'};
    PyObject *objs[ARRAYS] = {NULL, NULL, NULL, ko, mo, cert_o, eo};
    for (int k = KEYS; k < ARRAYS; k++) {
        if ((k == CERT && !certify) || (k == MEMBERS && mo == Py_None))
            continue;
        if (get_array(objs[k], &v[k], kinds[k], k == ENTRIES, "grid_fill") < 0) {
            release_all(v, got, ARRAYS);
            return NULL;
        }
        got[k] = 1;
    }
    const Py_buffer *members = got[MEMBERS] ? &v[MEMBERS] : NULL;
    Py_ssize_t k = v[KEYS].len / 8, count = members ? members->len / members->itemsize : F.n;
    int bad = v[ENTRIES].len != (Py_ssize_t)sizeof(Entry) * k || fbits < 1 || fbits > 62 ||
              F.m_points > 2147483647 || (certify && v[CERT].len != F.m_points);
    if (!bad) {
        const uint64_t *keys = v[KEYS].buf;
        const uint8_t *cert = certify ? v[CERT].buf : NULL;
        Entry *entries = v[ENTRIES].buf;
        uint64_t mask = ((uint64_t)1 << fbits) - 1;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t e = 0; e < k; e++) {
            Py_ssize_t p = (Py_ssize_t)(keys[e] & mask);
            int64_t box = p < count ? (members ? at_index(members, p) : p) : -1;
            if (box < 0 || box >= F.n) {
                bad = 1;
                break;
            }
            Entry *t = entries + e;
            face_box(&F, box, t->box);
            int64_t face = at_index(F.live, (Py_ssize_t)box);
            for (int c = 0; c < 3; c++) {
                int32_t id = (int32_t)at_index(F.faces, 3 * face + c);
                t->v[c] = cert && cert[id] ? ~id : id;
            }
        }
        Py_END_ALLOW_THREADS
    }
    release_all(v, got, ARRAYS);
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "grid_fill: the keys, members, faces and entries do not match");
        return NULL;
    }
    Py_RETURN_NONE;
}

/* The first position in keys[lo, hi) whose key is >= target. */
static inline Py_ssize_t lower_bound(const uint64_t *keys, Py_ssize_t lo, Py_ssize_t hi, uint64_t target) {
    while (lo < hi) {
        Py_ssize_t mid = lo + (hi - lo) / 2;
        if (keys[mid] < target)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

typedef struct {
    int64_t *out_i, *out_j;
    Py_ssize_t cap, count;
    const Py_buffer *live, *members;
    uint64_t mask;
} Emit;

static inline int32_t vertex_id(int32_t x) { return x < 0 ? ~x : x; }

/* Whether entries A and B have boxes that overlap (closed) and share no certified vertex
 * (p3d_cli.mesh.triangle_pairs.uncertified): then their faces are written, the smaller first.
 * 0: done; -1: no room. */
static inline int emit(Emit *E, const Entry *A, int64_t fa, const Entry *B, uint64_t key) {
    const float *a = A->box, *b = B->box;
    if (!(a[0] <= b[3] && b[0] <= a[3] && a[1] <= b[4] && b[1] <= a[4] && a[2] <= b[5] && b[2] <= a[5]))
        return 0;
    int32_t w0 = vertex_id(B->v[0]), w1 = vertex_id(B->v[1]), w2 = vertex_id(B->v[2]);
    for (int k = 0; k < 3; k++)
        if (A->v[k] < 0) {
            int32_t u = ~A->v[k];
            if (u == w0 || u == w1 || u == w2)
                return 0;
        }
    if (E->count >= E->cap)
        return -1;
    Py_ssize_t at = (Py_ssize_t)(key & E->mask);
    int64_t fb = at_index(E->live, E->members ? (Py_ssize_t)at_index(E->members, at) : at);
    E->out_i[E->count] = fa < fb ? fa : fb;
    E->out_j[E->count] = fa < fb ? fb : fa;
    E->count++;
    return 0;
}

/* grid_pairs(keys, entries, window, members, live, level, query_keys, queries, query_members, at,
 *            start, stop, out_i, out_j) -> (next, written)
 * The pairs of faces whose boxes overlap (closed) and that share no certified vertex, between
 * queries and the level's entries (sorted keys, grid_keys with the level's span; their entries,
 * grid_entries), as face numbers, smaller first, in out_i/out_j (int64), from query `start`
 * on, before query `stop` (faces live[members[p]], the positions p in the keys' low bits;
 * members None: all the live faces, in order). entries are those of keys[window:]; the
 * entries a scan needs beyond them raise ValueError. next: the first query not done; written -1 when one query's pairs do not fit in the
 * outputs (make them larger).
 * queries None: the level's own pairs, each once (an entry keeps the entries after it in key
 * order, found by a cursor per row that moves forward only, as the queries' cells do); else
 * the entries (of a finer level, with their keys) at positions `at` (int array), each paired with every level
 * entry whose box meets its own (a binary search per row).
 * Why it finds every pair: if boxes a and b overlap, b's lower corner is at most a's upper
 * corner and b's upper corner at least a's lower corner, along each axis; cells are monotone
 * in the coordinates, so b's lower-corner cell lies between a's lower-corner cell minus the
 * level's span and a's upper-corner cell. */
static PyObject *py_grid_pairs(PyObject *self, PyObject *args) {
    PyObject *ko, *eo, *mo, *live_o, *lev, *qko, *qo, *qmo, *ato, *io, *jo;
    Py_ssize_t start, stop, window;
    if (!PyArg_ParseTuple(args, "OOnOOOOOOOnnOO", &ko, &eo, &window, &mo, &live_o, &lev, &qko, &qo, &qmo, &ato,
                          &start, &stop, &io, &jo))
        return NULL;
    Level L;
    if (!parse_level(lev, &L))
        return NULL;
    int cross = qo != Py_None;
    enum { KEYS, ENTRIES, MEMBERS, LIVE, OUT_I, OUT_J, QKEYS, QUERIES, QMEMBERS, AT, ARRAYS };
    Py_buffer v[ARRAYS];
    const char kinds[ARRAYS] = {'Q', 'B', 'i', 'i', 'q', 'q', 'Q', 'B', 'i', 'i'};
    PyObject *objs[ARRAYS] = {ko, eo, mo, live_o, io, jo, qko, qo, qmo, ato};
    int got[ARRAYS] = {0};
    for (int k = 0; k < ARRAYS; k++) {
        if ((k >= QKEYS && !cross) || ((k == MEMBERS || k == QMEMBERS) && objs[k] == Py_None))
            continue;
        if (get_array(objs[k], &v[k], kinds[k], k == OUT_I || k == OUT_J, "grid_pairs") < 0) {
            release_all(v, got, ARRAYS);
            return NULL;
        }
        got[k] = 1;
    }
    Py_ssize_t nk = v[KEYS].len / 8, nq = cross ? v[AT].len / v[AT].itemsize : nk;
    Py_ssize_t nent = v[ENTRIES].len / (Py_ssize_t)sizeof(Entry);
    if (stop < nq)
        nq = stop;
    Py_ssize_t nqe = cross ? v[QKEYS].len / 8 : nk, n = v[LIVE].len / v[LIVE].itemsize;
    uint64_t fmask = ((uint64_t)1 << L.fbits) - 1;
    int bad = v[ENTRIES].len != nent * (Py_ssize_t)sizeof(Entry) || window < 0 || window + nent > nk ||
              (cross && (window != 0 || nent != nk)) || v[OUT_I].len != v[OUT_J].len || start < 0 ||
              (!cross && start < nq && start < window) ||
              (cross && v[QUERIES].len != nqe * (Py_ssize_t)sizeof(Entry));
    for (Py_ssize_t e = 0; cross && e < nq && !bad; e++) {
        int64_t q = at_index(&v[AT], e);
        bad = q < 0 || q >= nqe;
    }
    /* Every key's position must name a member, and every member a live face. */
    for (int w = 0; w < (cross ? 2 : 1) && !bad; w++) {
        const uint64_t *k = v[w ? QKEYS : KEYS].buf;
        const Py_buffer *mem = got[w ? QMEMBERS : MEMBERS] ? &v[w ? QMEMBERS : MEMBERS] : NULL;
        Py_ssize_t count = mem ? mem->len / mem->itemsize : n;
        for (Py_ssize_t e = 0, end = w ? nqe : nk; e < end && !bad; e++)
            bad = (Py_ssize_t)(k[e] & fmask) >= count;
        for (Py_ssize_t e = 0; mem && e < count && !bad; e++) {
            int64_t b = at_index(mem, e);
            bad = b < 0 || b >= n;
        }
    }
    if (bad) {
        release_all(v, got, ARRAYS);
        PyErr_SetString(PyExc_ValueError, "grid_pairs: the keys, entries, queries and outputs do not match");
        return NULL;
    }
    int64_t sx = L.span[0], sy = L.span[1], sz = L.span[2];
    Py_ssize_t rows = (Py_ssize_t)(sy + sz * (2 * sy + 1));
    Py_ssize_t *cursor = calloc((size_t)rows + 1, sizeof(Py_ssize_t));
    if (!cursor) {
        release_all(v, got, ARRAYS);
        return PyErr_NoMemory();
    }
    Emit E = {v[OUT_I].buf, v[OUT_J].buf, v[OUT_I].len / 8, 0, &v[LIVE], got[MEMBERS] ? &v[MEMBERS] : NULL, fmask};
    const Py_buffer *qmembers = got[cross ? QMEMBERS : MEMBERS] ? &v[cross ? QMEMBERS : MEMBERS] : NULL;
    const uint64_t *keys = v[KEYS].buf;
    const Entry *entries = v[ENTRIES].buf, *queries = cross ? v[QUERIES].buf : entries;
    const uint64_t *qkeys = cross ? v[QKEYS].buf : keys;
    int bx = L.bits[0], by = L.bits[1], fb = L.fbits;
    int64_t xmax = ((int64_t)1 << bx) - 1, ymax = ((int64_t)1 << by) - 1, zmax = ((int64_t)1 << L.bits[2]) - 1;
    Py_ssize_t next = start < nq ? start : nq, written = 0, end = window + nent;
    int short_window = 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t q = start; q < nq; q++) {
        Py_ssize_t before = E.count;
        Py_ssize_t qa = cross ? (Py_ssize_t)at_index(&v[AT], q) : q;
        if (!cross && qa >= end) {
            short_window = 1;
            break;
        }
        const Entry *A = cross ? queries + qa : entries + (qa - window);
        Py_ssize_t qp = (Py_ssize_t)(qkeys[qa] & fmask);
        int64_t fa = at_index(&v[LIVE], qmembers ? (Py_ssize_t)at_index(qmembers, qp) : qp);
        int64_t c0[3], c1[3];
        for (int d = 0; d < 3; d++) {
            c0[d] = cell_of(A->box[d], L.origin[d], L.size[d]);
            c1[d] = cell_of(A->box[3 + d], L.origin[d], L.size[d]);
        }
        int64_t x0 = c0[0] - sx < 0 ? 0 : c0[0] - sx, x1 = c1[0] < xmax ? c1[0] : xmax;
        int full = 0;
        if (cross) {
            int64_t z0 = c0[2] - sz < 0 ? 0 : c0[2] - sz, z1 = c1[2] < zmax ? c1[2] : zmax;
            int64_t y0 = c0[1] - sy < 0 ? 0 : c0[1] - sy, y1 = c1[1] < ymax ? c1[1] : ymax;
            for (int64_t z = z0; z <= z1 && !full && x0 <= x1; z++)
                for (int64_t y = y0; y <= y1 && !full; y++) {
                    uint64_t row = ((uint64_t)z << by | (uint64_t)y) << bx;
                    uint64_t first = (row | (uint64_t)x0) << fb, last = (row | (uint64_t)x1) << fb | fmask;
                    for (Py_ssize_t e = lower_bound(keys, 0, nk, first); e < nk && keys[e] <= last; e++)
                        if (emit(&E, A, fa, entries + e, keys[e]) < 0) {
                            full = 1;
                            break;
                        }
                }
        } else {
            /* The query's own row after it, then the rows after that row, each from its
             * cursor: the first entry at or after the row's first cell, which only moves
             * forward as the queries' cells do (galloping, then a binary search). */
            Py_ssize_t r = 0;
            for (int64_t dz = 0; dz <= sz && !full; dz++)
                for (int64_t dy = dz ? -sy : 0; dy <= sy && !full; dy++) {
                    int64_t z = c0[2] + dz, y = c0[1] + dy;
                    int outside = y < 0 || y > ymax || z > zmax;
                    uint64_t row = outside ? 0 : ((uint64_t)z << by | (uint64_t)y) << bx;
                    Py_ssize_t e;
                    if (dz == 0 && dy == 0) {
                        e = q + 1;
                    } else {
                        Py_ssize_t *c = cursor + r++;
                        if (outside)
                            continue;
                        uint64_t first = (row | (uint64_t)x0) << fb;
                        Py_ssize_t s = *c, step = 1;
                        while (s + step < nk && keys[s + step] < first) {
                            s += step;
                            step <<= 1;
                        }
                        e = *c = lower_bound(keys, s, s + step < nk ? s + step + 1 : nk, first);
                    }
                    if (outside || x0 > x1)
                        continue;
                    uint64_t last = (row | (uint64_t)x1) << fb | fmask;
                    for (; e < nk && keys[e] <= last; e++) {
                        if (e >= end) {
                            short_window = full = 1;
                            break;
                        }
                        if (emit(&E, A, fa, entries + (e - window), keys[e]) < 0) {
                            full = 1;
                            break;
                        }
                    }
                }
        }
        if (short_window)
            break;
        if (full) {
            E.count = before;
            written = before ? before : -1;
            next = q;
            break;
        }
        next = q + 1;
        written = E.count;
    }
    Py_END_ALLOW_THREADS
    free(cursor);
    release_all(v, got, ARRAYS);
    if (short_window) {
        PyErr_SetString(PyExc_ValueError, "grid_pairs: the entries do not reach the rows the queries scan");
        return NULL;
    }
    return Py_BuildValue("nn", next, written);
}

static PyMethodDef methods[] = {
    {"paired_keys", py_paired_keys, METH_VARARGS,
     "paired_keys(block, bits, first_face, keys, fill, cap, shift) -> (degenerate, s1, s2, written)"},
    {"pairs", py_pairs, METH_VARARGS, "pairs(keys, bits, pi) -> whether the sorted side keys pair up"},
    {"open_pairs", py_open_pairs, METH_VARARGS, "open_pairs(keys, bits, pi) -> (boundary sides, other sides)"},
    {"fan_chains", py_fan_chains, METH_VARARGS, "fan_chains(pi, first) -> number of fans (chains and cycles)"},
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
     "forward_block(block, ox, oy, oz, keys, fill, cap, shift[, prints, pfill]) -> block()'s results, balance, "
     "backward sides, prints whole"},
    {"keys_block", py_keys_block, METH_VARARGS, "keys_block(block, keys, fill, cap, shift) -> keys written (-1: overflow)"},
    {"unite", py_unite, METH_VARARGS, "unite(parent, a, b): join nodes a[i] and b[i] (int64), smallest node the root"},
    {"flatten", py_flatten, METH_VARARGS, "flatten(parent): every node pointed at its root"},
    {"star_normals", py_star_normals, METH_VARARGS, "star_normals(points, faces, shift, step, normal)"},
    {"star_signs", py_star_signs, METH_VARARGS,
     "star_signs(points, faces, normal, bound, g0, g1, good, count, deferred) -> deferred count (-1: too many)"},
    {"face_extents", py_face_extents, METH_VARARGS,
     "face_extents(points, faces, live, frame, extent) -> (least lower corner, greatest upper corner)"},
    {"grid_keys", py_grid_keys, METH_VARARGS, "grid_keys(points, faces, live, frame, members, level, keys) -> span"},
    {"grid_fill", py_grid_fill, METH_VARARGS,
     "grid_fill(points, faces, live, frame, keys, fbits, members, certified, entries)"},
    {"grid_pairs", py_grid_pairs, METH_VARARGS,
     "grid_pairs(keys, entries, window, members, live, level, query_keys, queries, query_members, at, start, stop, "
     "out_i, out_j) -> (next, written)"},
    {"near_walk", py_near_walk, METH_VARARGS,
     "near_walk(triangles, node_lo, node_hi, node_label, offsets, face_lo, face_hi, face_label, mine, margin, leaf, "
     "start, out_tri, out_face) -> (next, written)"},
    {"fan_cycles", py_fan_cycles, METH_VARARGS,
     "fan_cycles(pi, first) -> fans: pi overwritten with each corner's fan (numbered by smallest corner)"},
    {"area_filter", py_area_filter, METH_VARARGS,
     "area_filter(block, undecided) -> count: the faces no plane certifies as of non-zero area"},
    {"backward_block", py_backward_block, METH_VARARGS,
     "backward_block(block, keys, fill, cap, shift) -> keys written (-1: overflow): the other half of the keys"},
    {"split_groups", py_split_groups, METH_VARARGS,
     "split_groups(fkeys, ffill, bkeys, bfill, cap, shift) -> groups(...) of both halves' keys together"},
    {"print_groups", py_print_groups, METH_VARARGS,
     "print_groups(fkeys, ffill, prints, pfill, cap, shift) -> groups(...) by print id of forward keys and backward prints"},
    {"populate", py_populate, METH_VARARGS,
     "populate(keys, fill, cap, shift, sure) -> whether each bucket's first `sure` slots' pages were made at once"},
    {"pick_sides", py_pick_sides, METH_VARARGS,
     "pick_sides(block, ids, table, shift, starts, start_shift, out[, low, keys]) -> sides written: those whose edge "
     "id (key >> low) is in ids"},
    {"ear_holds", py_ear_holds, METH_VARARGS,
     "ear_holds(plane, order, alive, sign, bound, u, v, w, first, last) -> 1, 0 or -1 (undecided): whether a "
     "corner lies in the ear"},
    {"local_terms", py_local_terms, METH_VARARGS,
     "local_terms(u, v, frame, scale, parts, q_high, mag, big_t, big_w, low_sums, r_sum) -> sides that may have "
     "lost bits to underflow (-1: u - frame inexact): Locals.add's terms of one batch of sides"},
    {"exact_bins", py_exact_bins, METH_VARARGS,
     "exact_bins(values, offsets, high, low): ExactSum.add's binning of values (k, m) into the float bins"},
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


/* The print buckets (forward_block's prints, print_groups'): prints uint32 writable and
 * contiguous with room for `buckets` buckets of `cap`, fill int64 of `buckets` counts within
 * [0, cap], and a shift that leaves 32 bits of key below the buckets' bits and above bit 0. */
static int get_prints(PyObject *printobj, PyObject *fillobj, Py_ssize_t buckets, Py_ssize_t cap, int shift,
                      Py_buffer *pview, Py_buffer *fview) {
    if (PyObject_GetBuffer(printobj, pview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0)
        return -1;
    if (PyObject_GetBuffer(fillobj, fview, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) < 0) {
        PyBuffer_Release(pview);
        return -1;
    }
    const int64_t *fill = (const int64_t *)fview->buf;
    int bad = pview->itemsize != 4 || fview->itemsize != 8 || shift < 33 || fview->len / 8 != buckets ||
              pview->len / 4 < buckets * cap;
    for (Py_ssize_t b = 0; !bad && b < buckets; b++)
        bad = fill[b] < 0 || fill[b] > cap;
    if (bad) {
        PyBuffer_Release(pview);
        PyBuffer_Release(fview);
        PyErr_SetString(PyExc_ValueError, "the print buckets do not fit the key buckets");
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

/* forward_block(block, ox, oy, oz, keys, fill, cap, shift[, prints, pfill]) ->
 *   ((lo0, lo1, lo2, hi0, hi1, hi2), finite, (10 sums), magnitude sum, (3 weighted), keys written,
 *    balance, backward sides, prints whole)
 * block(..., keys, 0, fill, cap, shift) keeping only the keys with bit 0 set (the sides that
 * run from the smaller corner hash to the larger: half the sides), dealt to buckets; balance is
 * the sum mod 2^64 of g = mix(key | 1) over those sides minus g over the others, backward the
 * number of the others. The mesh is closed (keys_pair_up over all the keys) exactly when no
 * kept key is there twice (distinct), the two counts agree and the balance is
 * zero, barring a 64-bit coincidence of the balance: with no forward key twice, an edge used
 * other than once each way is used unequally often in the two directions, and weighs g(edge)
 * times a nonzero count in the balance (p3d_cli.mesh.analysis).
 * With prints (uint32) and pfill (int64, one count a bucket): each backward side's print, the
 * 32 key bits below its bucket's (key >> (shift - 32), truncated), dealt to buckets of the same
 * shift and room, for print_groups; prints whole is False when one did not fit (or none were
 * asked for). */
static PyObject *py_forward_block(PyObject *self, PyObject *args) {
    PyObject *obj, *keyobj, *fillobj, *printobj = Py_None, *pfillobj = Py_None;
    double o[3];
    Py_ssize_t cap;
    int shift;
    if (!PyArg_ParseTuple(args, "OdddOOni|OO", &obj, &o[0], &o[1], &o[2], &keyobj, &fillobj, &cap, &shift,
                          &printobj, &pfillobj))
        return NULL;
    Py_buffer view, kview, fview, pview, pfview;
    Block b;
    int prints = printobj != Py_None;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    if (get_buckets(keyobj, fillobj, cap, shift, 1, &kview, &fview) < 0) {
        release_block(&view, &b);
        return NULL;
    }
    if (prints && get_prints(printobj, pfillobj, fview.len / 8, cap, shift, &pview, &pfview) < 0) {
        release_block(&view, &b);
        PyBuffer_Release(&kview);
        PyBuffer_Release(&fview);
        return NULL;
    }
    double sums[NSUMS];
    Pass c = {&b, {o[0], o[1], o[2]}, (uint64_t *)kview.buf, 0, (int64_t *)fview.buf, cap, shift, 0};
    c.forward_only = 1;
    if (prints) {
        c.prints = (uint32_t *)pview.buf;
        c.print_fill = (int64_t *)pfview.buf;
    }
    integrate(&c, sums);
    release_block(&view, &b);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&fview);
    if (prints) {
        PyBuffer_Release(&pview);
        PyBuffer_Release(&pfview);
    }
    if (c.overflow)
        c.written = -1;
    return Py_BuildValue("(dddddd)O(dddddddddd)d(ddd)nKnO", c.lo[0], c.lo[1], c.lo[2], c.hi[0], c.hi[1], c.hi[2],
                         c.finite ? Py_True : Py_False, sums[0], sums[1], sums[2], sums[3], sums[4], sums[5],
                         sums[6], sums[7], sums[8], sums[9], sums[10], sums[11], sums[12], sums[13], c.written,
                         (unsigned long long)c.balance, c.backward, prints && !c.print_overflow ? Py_True : Py_False);
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

/* Connected components (p3d_cli.mesh.shells.chunked_roots): a union-find whose every root is
 * the smallest node of its component, so the result is that of the numpy rounds whatever the
 * order of the unions. parent[x] <= x always holds (roots are linked under smaller roots, path
 * halving only moves a node to an ancestor), so one ascending pass (flatten) points every node
 * at its root. */
static inline int64_t uf_root(int64_t *parent, int64_t x) {
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

static PyObject *py_unite(PyObject *self, PyObject *args) {
    PyObject *pobj, *aobj, *bobj;
    if (!PyArg_ParseTuple(args, "OOO", &pobj, &aobj, &bobj))
        return NULL;
    Py_buffer pv, av, bv;
    if (PyObject_GetBuffer(pobj, &pv, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return NULL;
    if (PyObject_GetBuffer(aobj, &av, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyBuffer_Release(&pv);
        return NULL;
    }
    if (PyObject_GetBuffer(bobj, &bv, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyBuffer_Release(&pv);
        PyBuffer_Release(&av);
        return NULL;
    }
    int ok = pv.itemsize == 8 && av.itemsize == 8 && bv.itemsize == 8 && av.len == bv.len &&
             strchr("lq", pv.format[0]) && strchr("lq", av.format[0]) && strchr("lq", bv.format[0]);
    int64_t *parent = (int64_t *)pv.buf;
    const int64_t *a = (const int64_t *)av.buf, *b = (const int64_t *)bv.buf;
    Py_ssize_t size = pv.len / 8, m = av.len / 8;
    for (Py_ssize_t i = 0; ok && i < m; i++)
        ok = a[i] >= 0 && a[i] < size && b[i] >= 0 && b[i] < size;
    /* parent is arange's or unite's (parent[x] <= x: its roots are reached); not checked
     * here, which would cost a pass over all the nodes for every piece of the arcs */
    if (ok) {
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < m; i++) {
            int64_t ra = uf_root(parent, a[i]), rb = uf_root(parent, b[i]);
            if (ra < rb)
                parent[rb] = ra;
            else if (rb < ra)
                parent[ra] = rb;
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&pv);
    PyBuffer_Release(&av);
    PyBuffer_Release(&bv);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "unite: int64 parent (parent[x] <= x) and equal int64 a, b within it");
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyObject *py_flatten(PyObject *self, PyObject *args) {
    PyObject *pobj;
    if (!PyArg_ParseTuple(args, "O", &pobj))
        return NULL;
    Py_buffer pv;
    if (PyObject_GetBuffer(pobj, &pv, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        return NULL;
    int ok = pv.itemsize == 8 && strchr("lq", pv.format[0]);
    int64_t *parent = (int64_t *)pv.buf;
    Py_ssize_t size = pv.len / 8;
    for (Py_ssize_t i = 0; ok && i < size; i++)
        ok = parent[i] >= 0 && parent[i] <= i;
    if (ok)
        for (Py_ssize_t i = 0; i < size; i++)
            parent[i] = parent[parent[i]];
    PyBuffer_Release(&pv);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "flatten: int64 parent with parent[x] <= x");
        return NULL;
    }
    Py_RETURN_NONE;
}

/* ---- the faces near new faces: the box tree's walk (p3d_cli.repairs.near) ------------------ */

/* Whether triangle `c` (3 corners, x y z) may meet the box lo..hi grown by `margin`:
 * p3d_cli.repairs.near._meets for one pair, the same IEEE operations in the same order. The
 * triangle's own box first; then the separating-axis test, where numpy's "the least of the three
 * projections > r" (NaN spreading through the least, so False) is "all three > r" here, which is
 * False on a NaN too. */
static int near_meets(const double *c, const double *lo, const double *hi, double margin) {
    for (int a = 0; a < 3; a++) {
        double low = c[a], high = c[a];
        for (int k = 1; k < 3; k++) {
            double x = c[3 * k + a];
            low = x < low ? x : low;
            high = x > high ? x : high;
        }
        if (!(low - margin <= hi[a] && lo[a] <= high + margin))
            return 0;
    }
    double h[3], x[3][3], e[3][3];
    for (int a = 0; a < 3; a++) {
        double centre = (lo[a] + hi[a]) / 2;
        h[a] = (hi[a] - lo[a]) / 2 + margin;
        for (int k = 0; k < 3; k++)
            x[k][a] = c[3 * k + a] - centre;
        if ((x[0][a] > h[a] && x[1][a] > h[a] && x[2][a] > h[a]) ||
            (x[0][a] < -h[a] && x[1][a] < -h[a] && x[2][a] < -h[a]))
            return 0;
    }
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++)
            e[k][a] = x[(k + 1) % 3][a] - x[k][a];
    double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                   e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    double p[3], r = fabs(n[0]) * h[0] + fabs(n[1]) * h[1] + fabs(n[2]) * h[2];
    for (int k = 0; k < 3; k++)
        p[k] = n[0] * x[k][0] + n[1] * x[k][1] + n[2] * x[k][2];
    if ((p[0] > r && p[1] > r && p[2] > r) || (p[0] < -r && p[1] < -r && p[2] < -r))
        return 0;
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) {
            int b = (a + 1) % 3, d = (a + 2) % 3;
            const double *edge = e[k];
            for (int q = 0; q < 3; q++)
                p[q] = edge[d] * x[q][b] - edge[b] * x[q][d];
            r = fabs(edge[d]) * h[b] + fabs(edge[b]) * h[d];
            if ((p[0] > r && p[1] > r && p[2] > r) || (p[0] < -r && p[1] < -r && p[2] < -r))
                return 0;
        }
    return 1;
}

/* near_walk(triangles, node_lo, node_hi, node_label, offsets, face_lo, face_hi, face_label, mine,
 * margin, leaf, start, out_tri, out_face) -> (next, written): p3d_cli.repairs.near._tree_query's
 * walk, one triangle at a time, depth first. The tree's levels are rows offsets[l] ..
 * offsets[l + 1] of the node arrays, the root first; node i of a level has children 2i and
 * 2i + 1 of the next (those that exist); node i of the last level holds the faces leaf * i ..
 * leaf * i + leaf - 1 (those that exist) of the face arrays. A node or face whose label is the
 * triangle's `mine` is passed over (but the root). The pairs (triangle, face position) that
 * meet are written from triangles start on; next: the first triangle not done (when the outputs
 * are full; its pairs are not written), written: the pairs written. */
static PyObject *py_near_walk(PyObject *self, PyObject *args) {
    PyObject *objs[12];
    double margin;
    Py_ssize_t leaf, start;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOdnnOO", &objs[0], &objs[1], &objs[2], &objs[3], &objs[4], &objs[5], &objs[6],
                          &objs[7], &objs[8], &margin, &leaf, &start, &objs[9], &objs[10]))
        return NULL;
    enum { TRI, NLO, NHI, NLAB, OFF, FLO, FHI, FLAB, MINE, OUT_T, OUT_F, ARRAYS };
    Py_buffer v[ARRAYS];
    int got[ARRAYS] = {0};
    const char kinds[ARRAYS] = {'d', 'd', 'd', 'q', 'q', 'd', 'd', 'q', 'q', 'q', 'q'};
    for (int k = 0; k < ARRAYS; k++) {
        if (get_array(objs[k], &v[k], kinds[k], k == OUT_T || k == OUT_F, "near_walk") < 0) {
            release_all(v, got, ARRAYS);
            return NULL;
        }
        got[k] = 1;
    }
    Py_ssize_t nt = v[TRI].len / 72, nn = v[NLO].len / 24, nlev = v[OFF].len / 8 - 1, nf = v[FLO].len / 24;
    Py_ssize_t cap = v[OUT_T].len / 8;
    const int64_t *off = v[OFF].buf;
    int bad = v[TRI].len != nt * 72 || v[NHI].len != nn * 24 || v[NLAB].len != nn * 8 || v[FHI].len != nf * 24 ||
              v[FLAB].len != nf * 8 || v[MINE].len != nt * 8 || v[OUT_F].len != cap * 8 || nlev < 1 || nlev > 64 ||
              leaf < 1 || start < 0 || off[0] != 0 || off[nlev] != nn || off[1] != 1;
    for (Py_ssize_t l = 0; l < nlev && !bad; l++)
        bad = off[l + 1] <= off[l] || (l > 0 && off[l + 1] - off[l] > 2 * (off[l] - off[l - 1]));
    if (!bad)
        bad = (off[nlev] - off[nlev - 1]) * leaf < nf || (off[nlev] - off[nlev - 1] - 1) * leaf >= nf;
    if (bad) {
        release_all(v, got, ARRAYS);
        PyErr_SetString(PyExc_ValueError, "near_walk: the tree, triangles and outputs do not match");
        return NULL;
    }
    const double *tri = v[TRI].buf, *nlo = v[NLO].buf, *nhi = v[NHI].buf, *flo = v[FLO].buf, *fhi = v[FHI].buf;
    const int64_t *nlab = v[NLAB].buf, *flab = v[FLAB].buf, *mine = v[MINE].buf;
    int64_t *out_t = v[OUT_T].buf, *out_f = v[OUT_F].buf;
    Py_ssize_t next = start < nt ? start : nt, written = 0;
    Py_BEGIN_ALLOW_THREADS
    Py_ssize_t stack[2 * 64 + 2][2];
    for (; next < nt; next++) {
        const double *c = tri + 9 * next;
        Py_ssize_t before = written;
        int full = 0;
        if (!near_meets(c, nlo, nhi, margin))
            continue;
        int top = 0;
        stack[top][0] = 0, stack[top][1] = 0, top++;
        while (top > 0 && !full) {
            top--;
            Py_ssize_t l = stack[top][0], i = stack[top][1];
            if (l == nlev - 1) {
                for (Py_ssize_t f = i * leaf; f < (i + 1) * leaf && f < nf; f++) {
                    if (flab[f] == mine[next] || !near_meets(c, flo + 3 * f, fhi + 3 * f, margin))
                        continue;
                    if (written == cap) {
                        full = 1;
                        break;
                    }
                    out_t[written] = next, out_f[written] = f, written++;
                }
                continue;
            }
            Py_ssize_t width = off[l + 2] - off[l + 1];
            for (int s = 1; s >= 0; s--) {
                Py_ssize_t child = 2 * i + s, row = off[l + 1] + child;
                if (child >= width || nlab[row] == mine[next] || !near_meets(c, nlo + 3 * row, nhi + 3 * row, margin))
                    continue;
                stack[top][0] = l + 1, stack[top][1] = child, top++;
            }
        }
        if (full) {
            written = before;
            break;
        }
    }
    Py_END_ALLOW_THREADS
    release_all(v, got, ARRAYS);
    return Py_BuildValue("nn", next, written);
}

/* ---- p3d check's fast path: the fans, the cycles of the corner permutation
 * (p3d_cli.mesh.paired._fan_ids) --------------------------------------------------------- */

/* fan_cycles(pi, first) -> count: pi (int32 or int64) a permutation of the corners; each of
 * its cycles is a fan. Overwrites pi with the fan number of every corner, the fans numbered
 * by their smallest corner (the numpy code's pointer doubling labels each cycle with its
 * smallest corner and numbers the labels in order: the same numbers), and sets first[c]
 * (bytes) where c is its fan's smallest corner. The cycles are found in ascending order of
 * their smallest corner, each walked once; a visited corner holds -(fan + 1) until the last
 * pass. -1 when pi is not a permutation (an index out of range, or two corners leading to
 * one; pi is then left partly overwritten). */
#define FAN_CYCLES(T)                                                                              \
    static Py_ssize_t fan_cycles_##T(T *pi, unsigned char *first, Py_ssize_t size) {             \
        Py_ssize_t count = 0;                                                                      \
        for (Py_ssize_t c = 0; c < size; c++)                                                      \
            if (pi[c] < 0 || pi[c] >= size)                                                        \
                return -1;                                                                         \
        for (Py_ssize_t c = 0; c < size; c++) {                                                    \
            if (pi[c] < 0) {                                                                       \
                first[c] = 0;                                                                      \
                continue;                                                                          \
            }                                                                                      \
            first[c] = 1;                                                                          \
            T mark = (T)(-(count + 1));                                                            \
            Py_ssize_t x = c;                                                                      \
            while (pi[x] >= 0) {                                                                   \
                Py_ssize_t next = (Py_ssize_t)pi[x];                                               \
                if (next >= size)                                                                  \
                    return -1;                                                                     \
                pi[x] = mark;                                                                      \
                x = next;                                                                          \
            }                                                                                      \
            if (x != c)                                                                            \
                return -1; /* met another cycle: not a permutation */                             \
            count++;                                                                               \
        }                                                                                          \
        for (Py_ssize_t c = 0; c < size; c++)                                                      \
            pi[c] = (T)(-pi[c] - 1);                                                               \
        return count;                                                                              \
    }
FAN_CYCLES(int32_t)
FAN_CYCLES(int64_t)

static PyObject *py_fan_cycles(PyObject *self, PyObject *args) {
    PyObject *piobj, *fobj;
    if (!PyArg_ParseTuple(args, "OO", &piobj, &fobj))
        return NULL;
    Py_buffer pv, fv;
    if (get_array(piobj, &pv, 'i', 1, "fan_cycles") < 0)
        return NULL;
    if (get_array(fobj, &fv, 'B', 1, "fan_cycles") < 0) {
        PyBuffer_Release(&pv);
        return NULL;
    }
    Py_ssize_t size = pv.len / pv.itemsize, count = -1;
    if (fv.len == size) {
        Py_BEGIN_ALLOW_THREADS
        count = pv.itemsize == 4 ? fan_cycles_int32_t((int32_t *)pv.buf, (unsigned char *)fv.buf, size)
                                 : fan_cycles_int64_t((int64_t *)pv.buf, (unsigned char *)fv.buf, size);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&pv);
    PyBuffer_Release(&fv);
    if (count < 0) {
        PyErr_SetString(PyExc_ValueError, "fan_cycles: pi must be a permutation and first as long");
        return NULL;
    }
    return PyLong_FromSsize_t(count);
}

/* ---- p3d check's zero-area faces: the float filter (p3d_cli.mesh.faces.zero_area_faces) ---- */

/* area_filter(block, undecided) -> count: the faces of a (k, 3, 3) block (any strides, float32
 * widened) that no coordinate plane certifies as of non-zero area, ascending in undecided
 * (int64, at least k long). Plane (i, j) certifies a face when |left - right| > bound, with
 * left = (a_i - c_i)(b_j - c_j), right = (a_j - c_j)(b_i - c_i) and bound = (3 + 16 eps) eps
 * (|left| + |right|) + 2^-1060: the numpy filter's IEEE operations in the same order, so the
 * same faces are left to its exact test (a NaN or an overflow certifies nothing). */
static PyObject *py_area_filter(PyObject *self, PyObject *args) {
    PyObject *obj, *uobj;
    if (!PyArg_ParseTuple(args, "OO", &obj, &uobj))
        return NULL;
    Py_buffer view, uv;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    if (b.indexed || get_array(uobj, &uv, 'q', 1, "area_filter") < 0) {
        if (b.indexed)
            PyErr_SetString(PyExc_TypeError, "area_filter: a (k, 3, 3) block");
        release_block(&view, &b);
        return NULL;
    }
    Py_ssize_t count = -1;
    if (uv.len / 8 >= b.n) {
        const double eps = 0x1p-53, bound_factor = (3.0 + 16.0 * eps) * eps, underflow = 0x1p-1060;
        static const int planes[3][2] = {{0, 1}, {1, 2}, {2, 0}};
        int64_t *undecided = (int64_t *)uv.buf;
        count = 0;
        Py_BEGIN_ALLOW_THREADS
        double p[128][9];
        for (Py_ssize_t t0 = 0; t0 < b.n; t0 += 128) {
            Py_ssize_t m = b.n - t0 < 128 ? b.n - t0 : 128;
            load(&b, t0, m, p);
            for (Py_ssize_t k = 0; k < m; k++) {
                const double *a = p[k], *bb = p[k] + 3, *c = p[k] + 6;
                int certain = 0;
                for (int q = 0; q < 3 && !certain; q++) {
                    int i = planes[q][0], j = planes[q][1];
                    double left = (a[i] - c[i]) * (bb[j] - c[j]);
                    double right = (a[j] - c[j]) * (bb[i] - c[i]);
                    double bound = bound_factor * (fabs(left) + fabs(right)) + underflow;
                    certain = fabs(left - right) > bound;
                }
                if (!certain)
                    undecided[count++] = t0 + k;
            }
        }
        Py_END_ALLOW_THREADS
    }
    release_block(&view, &b);
    PyBuffer_Release(&uv);
    if (count < 0) {
        PyErr_SetString(PyExc_ValueError, "area_filter: undecided shorter than the block");
        return NULL;
    }
    return PyLong_FromSsize_t(count);
}

/* ---- props on an open mesh without making every key again (issue 32) ---------------------- */

/* backward_block(block, keys, fill, cap, shift) -> keys written, -1 when a bucket overflowed:
 * the keys forward_block leaves out (the sides running from the larger corner hash to the
 * smaller: bit 0 clear), dealt to buckets of the same shift as its own. With its buckets they
 * are every key of keys_block, so that split_groups finds the key groups of a mesh
 * forward_block did not prove closed from one more pass that stores half the keys. */
static PyObject *py_backward_block(PyObject *self, PyObject *args) {
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
    uint64_t *keys = kview.buf;
    int64_t *fill = fview.buf;
    Py_ssize_t written = 0;
    int overflow = 0;
    Py_BEGIN_ALLOW_THREADS
    double raw[LEAF][9];
    uint64_t h[3][LEAF], all[3][LEAF], scratch = 0;
    for (Py_ssize_t t0 = 0; t0 < b.n; t0 += LEAF) {
        Py_ssize_t m = b.n - t0 < LEAF ? b.n - t0 : LEAF;
        load(&b, t0, m, raw);
        leaf_keys((const double (*)[9])raw, m, h, all, NULL);
        for (Py_ssize_t k = 0; k < m; k++) {
            for (int v = 0; v < 3; v++) {
                /* a backward side: its ends hash apart, the larger first (key bit 0 clear); the
                 * others' keys go to a scratch word, by a mask rather than a coin-toss branch */
                uint64_t key = all[v][k], back = h[v][k] > h[v == 2 ? 0 : v + 1][k], at = key >> shift;
                int64_t f = fill[at];
                if (f == cap) { /* rare: predicted */
                    overflow |= (int)back;
                    continue;
                }
                uintptr_t keep = (uintptr_t)0 - (uintptr_t)back;
                uint64_t *slot = (uint64_t *)(((uintptr_t)(keys + at * cap + f) & keep) | ((uintptr_t)&scratch & ~keep));
                *slot = key;
                fill[at] = f + (int64_t)back;
                written += (Py_ssize_t)back;
            }
        }
    }
    Py_END_ALLOW_THREADS
    release_block(&view, &b);
    PyBuffer_Release(&kview);
    PyBuffer_Release(&fview);
    return PyLong_FromSsize_t(overflow ? -1 : written);
}

/* split_groups(fkeys, ffill, bkeys, bfill, cap, shift) ->
 *   (unbalanced ids, net boundary edges, their sides, doubtful ids or None)
 * groups() of every key, given as forward_block's buckets (bit 0 set) and backward_block's
 * (bit 0 clear) of the same shift: each bucket of both is sorted and the two are merged by
 * edge (key >> 1) as they are scanned, bucket by bucket, so that the keys are never moved
 * together. The same answers as groups() over all the keys sorted.
 *
 * Most edges of an open mesh are used once each way, and only the groups of the others are
 * answers (unless no group is unbalanced: then the balanced groups of four or more sides are,
 * the doubtful ids). So each bucket is first cut by its next bits into sub-buckets of a few
 * keys, each given the sum of g = mix(key | 1), the same for both directions of an edge, over
 * its forward keys less that over its backward ones, mod 2^64, and its count of forward less
 * backward keys: a sub-bucket whose two are zero has every edge used as often each way (else
 * the nonzero differences would cancel by a 64-bit coincidence, the closed test's argument,
 * ForwardBuckets), and only the keys of the other sub-buckets are sorted and scanned. If no
 * group then proves the mesh open (no unbalanced edge), the doubtful ids in the skipped
 * sub-buckets are wanted too: every bucket is then sorted whole, as before. */
static void group_bucket(GroupScan *scan, uint64_t *f, Py_ssize_t nf, uint64_t *g, Py_ssize_t ng, int shift,
                         uint64_t *tmp, int low) {
    Py_ssize_t i = 0, j = 0;
    msd(f, nf, shift, tmp);
    msd(g, ng, shift, tmp);
    while ((i < nf || j < ng) && !scan->failed) {
        uint64_t ef = i < nf ? f[i] >> low : UINT64_MAX, eg = j < ng ? g[j] >> low : UINT64_MAX;
        uint64_t edge = ef < eg ? ef : eg;
        Py_ssize_t forward = 0, count = 0;
        while (i < nf && (f[i] >> low) == edge)
            i++, forward++;
        count = forward;
        while (j < ng && (g[j] >> low) == edge)
            j++, count++;
        scan_edge(scan, edge, forward, count);
    }
}

#define SUB_MAX_BITS 14

/* The keys of f[0..nf) and g[0..ng) in sub-buckets whose uses are not balanced (see
 * split_groups), copied to kf and kg; returns 0 when more than half the keys are there (then
 * the caller sorts the whole bucket). sig, cnt: 2^SUB_MAX_BITS entries of scratch. Keys are
 * compared above bit `low` (1: the edge ids; print_groups: the prints). */
static int unbalanced_part(const uint64_t *f, Py_ssize_t nf, const uint64_t *g, Py_ssize_t ng, int shift,
                           uint64_t *sig, int64_t *cnt, uint64_t *kf, Py_ssize_t *mf, uint64_t *kg, Py_ssize_t *mg,
                           int low) {
    const uint64_t above = ~(((uint64_t)1 << low) - 1); /* the compared bits */
    int bits = 4;
    while (bits < SUB_MAX_BITS && ((Py_ssize_t)8 << bits) < nf + ng)
        bits++;
    if (bits > shift - 1)
        bits = shift - 1;
    if (bits < 1)
        return 0;
    const int s = shift - bits;
    const uint64_t mask = ((uint64_t)1 << bits) - 1;
    memset(sig, 0, (mask + 1) * sizeof *sig);
    memset(cnt, 0, (mask + 1) * sizeof *cnt);
    for (Py_ssize_t i = 0; i < nf; i++) {
        uint64_t x = f[i], at = (x >> s) & mask;
        sig[at] += mix((x & above) | 1);
        cnt[at]++;
    }
    for (Py_ssize_t j = 0; j < ng; j++) {
        uint64_t x = g[j], at = (x >> s) & mask;
        sig[at] -= mix((x & above) | 1);
        cnt[at]--;
    }
    for (uint64_t at = 0; at <= mask; at++)
        cnt[at] = sig[at] != 0 || cnt[at] != 0; /* 1: sort this sub-bucket's keys */
    Py_ssize_t a = 0, b = 0;
    for (Py_ssize_t i = 0; i < nf; i++) {
        uint64_t x = f[i];
        kf[a] = x;
        a += cnt[(x >> s) & mask];
    }
    for (Py_ssize_t j = 0; j < ng; j++) {
        uint64_t x = g[j];
        kg[b] = x;
        b += cnt[(x >> s) & mask];
    }
    *mf = a;
    *mg = b;
    return 2 * (a + b) <= nf + ng;
}

/* split_groups' scan of forward keys fa (buckets of cap) and the other direction's, given as
 * keys ba (uint64) or, when prints is not NULL, as forward_block's prints (uint32, each bucket's
 * made into keys of the bucket in a buffer): groups of the keys compared above bit `low`. */
static PyObject *scan_buckets(uint64_t *fa, const int64_t *ffill, uint64_t *ba, const uint32_t *prints,
                              const int64_t *bfill, Py_ssize_t buckets, Py_ssize_t cap, int shift, int low) {
    GroupScan scan;
    scan_start(&scan);
    uint64_t *tmp = malloc((cap < SMALL ? cap : SMALL) * sizeof(uint64_t) + 8);
    /* the filter's scratch and the kept keys of one bucket, both directions */
    uint64_t *sig = malloc(((Py_ssize_t)1 << SUB_MAX_BITS) * sizeof(uint64_t));
    int64_t *cnt = malloc(((Py_ssize_t)1 << SUB_MAX_BITS) * sizeof(int64_t));
    uint64_t *kept = malloc((2 * cap + 2) * sizeof(uint64_t));
    uint64_t *made = prints ? malloc((cap + 1) * sizeof(uint64_t)) : NULL;
    scan.failed |= !tmp || !sig || !cnt || !kept || (prints && !made);
    Py_BEGIN_ALLOW_THREADS
    int whole = 0; /* every bucket sorted whole: the filtered scan proved nothing */
    for (int round = 0; round < 2 && !scan.failed; round++) {
        for (Py_ssize_t bucket = 0; bucket < buckets && !scan.failed; bucket++) {
            uint64_t *f = fa + bucket * cap, *g, *kf = kept, *kg = kept + cap + 1;
            Py_ssize_t nf = ffill[bucket], ng = bfill[bucket], mf, mg;
            if (prints) {
                const uint32_t *p = prints + bucket * cap;
                const uint64_t top = (uint64_t)bucket << shift;
                for (Py_ssize_t k = 0; k < ng; k++)
                    made[k] = top | (uint64_t)p[k] << low;
                g = made;
            } else
                g = ba + bucket * cap;
            if (!whole && unbalanced_part(f, nf, g, ng, shift, sig, cnt, kf, &mf, kg, &mg, low))
                group_bucket(&scan, kf, mf, kg, mg, shift, tmp, low);
            else
                group_bucket(&scan, f, nf, g, ng, shift, tmp, low);
        }
        if (whole || scan.proven_open || scan.failed)
            break;
        /* no unbalanced edge: the doubtful ids of the skipped sub-buckets are wanted too */
        free(scan.unbalanced);
        free(scan.doubtful);
        scan_start(&scan);
        whole = 1;
    }
    Py_END_ALLOW_THREADS
    free(tmp);
    free(sig);
    free(cnt);
    free(kept);
    free(made);
    return scan_result(&scan);
}

static PyObject *py_split_groups(PyObject *self, PyObject *args) {
    PyObject *fobj, *ffobj, *bobj, *bfobj;
    Py_ssize_t cap;
    int shift;
    if (!PyArg_ParseTuple(args, "OOOOni", &fobj, &ffobj, &bobj, &bfobj, &cap, &shift))
        return NULL;
    Py_buffer fk, ff, bk, bf;
    if (get_buckets(fobj, ffobj, cap, shift, 1, &fk, &ff) < 0)
        return NULL;
    if (get_buckets(bobj, bfobj, cap, shift, 1, &bk, &bf) < 0) {
        PyBuffer_Release(&fk);
        PyBuffer_Release(&ff);
        return NULL;
    }
    PyObject *result = NULL;
    if (bf.len != ff.len)
        PyErr_SetString(PyExc_ValueError, "split_groups: the two buckets differ in number");
    else
        result = scan_buckets(fk.buf, ff.buf, bk.buf, NULL, bf.buf, ff.len / 8, cap, shift, 1);
    PyBuffer_Release(&fk);
    PyBuffer_Release(&ff);
    PyBuffer_Release(&bk);
    PyBuffer_Release(&bf);
    return result;
}

/* print_groups(fkeys, ffill, prints, pfill, cap, shift) ->
 *   (unbalanced prints, net boundary edges, their sides, doubtful prints or None)
 * split_groups with the backward sides given by forward_block's prints (the 32 key bits below
 * a bucket's: four bytes a side, made in the first pass) instead of their keys: the groups of
 * every side by its print id, key >> (shift - 32), the bucket's bits and the print. An edge's
 * sides share a print id, so every unbalanced edge is in an unbalanced print group unless
 * another unbalanced edge shares its print id and cancels it (a 32-bit coincidence, which the
 * caller rules out by the balance: p3d_cli.mesh.analysis); two edges sharing one add sides,
 * never lose any. The ids come ascending, as uint64 bytes. */
static PyObject *py_print_groups(PyObject *self, PyObject *args) {
    PyObject *fobj, *ffobj, *pobj, *pfobj;
    Py_ssize_t cap;
    int shift;
    if (!PyArg_ParseTuple(args, "OOOOni", &fobj, &ffobj, &pobj, &pfobj, &cap, &shift))
        return NULL;
    Py_buffer fk, ff, pk, pf;
    if (get_buckets(fobj, ffobj, cap, shift, 1, &fk, &ff) < 0)
        return NULL;
    if (get_prints(pobj, pfobj, ff.len / 8, cap, shift, &pk, &pf) < 0) {
        PyBuffer_Release(&fk);
        PyBuffer_Release(&ff);
        return NULL;
    }
    PyObject *result = scan_buckets(fk.buf, ff.buf, NULL, pk.buf, pf.buf, ff.len / 8, cap, shift, shift - 32);
    PyBuffer_Release(&fk);
    PyBuffer_Release(&ff);
    PyBuffer_Release(&pk);
    PyBuffer_Release(&pf);
    return result;
}

/* pick_sides(block, ids, table, shift, starts, start_shift, out) -> sides written.
 * The sides of a block whose edge id (key >> 1) is in the sorted ids (uint64), in the order of
 * p3d_cli.mesh.boundary.unbalanced_sides (slot, then face; sides whose ends hash alike left
 * out): out[i] = (start x, y, z, end x, y, z) in float64, -0.0 read as 0.0. table is a bit
 * set of the ids' top bits (bit id >> shift set for every id, little-endian bit order within
 * its bytes, as numpy.packbits(..., bitorder="little")), small enough to stay in cache, which
 * turns most sides away; starts (int64) indexes the ids by their top bits,
 * starts[j] = the first id >= j << start_shift, so that an id that passes the table is looked
 * for among the few ids of its slot, not by a binary search of all of them (a cache miss a
 * step). out holds 3 k rows.
 * With `low` (default 1) the ids are key >> low instead (print_groups' print ids: low =
 * shift - 32); with `keys` (uint64, 3 k long, or None) each written side's key goes to keys[i]. */
static PyObject *py_pick_sides(PyObject *self, PyObject *args) {
    PyObject *obj, *idobj, *tabobj, *startobj, *outobj, *keyobj = Py_None;
    int tshift, sshift, low = 1;
    if (!PyArg_ParseTuple(args, "OOOiOiO|iO", &obj, &idobj, &tabobj, &tshift, &startobj, &sshift, &outobj, &low,
                          &keyobj))
        return NULL;
    if (low < 1 || low > 62) {
        PyErr_SetString(PyExc_ValueError, "pick_sides: low outside [1, 62]");
        return NULL;
    }
    Py_buffer view, iv, tv, sv, ov;
    Block b;
    if (get_block(obj, &view, &b) < 0)
        return NULL;
    int got[5] = {0, 0, 0, 0, 0};
    Py_buffer kv;
    Py_buffer *vs[5] = {&iv, &tv, &sv, &ov, &kv};
    const uint64_t width = UINT64_MAX >> low; /* the largest id */
    int ok = PyObject_GetBuffer(idobj, &iv, PyBUF_C_CONTIGUOUS) == 0 && (got[0] = 1) &&
             PyObject_GetBuffer(tabobj, &tv, PyBUF_C_CONTIGUOUS) == 0 && (got[1] = 1) &&
             PyObject_GetBuffer(startobj, &sv, PyBUF_C_CONTIGUOUS) == 0 && (got[2] = 1) &&
             PyObject_GetBuffer(outobj, &ov, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) == 0 && (got[3] = 1) &&
             (keyobj == Py_None || (PyObject_GetBuffer(keyobj, &kv, PyBUF_WRITABLE | PyBUF_C_CONTIGUOUS) == 0 &&
                                    (got[4] = 1)));
    if (ok && (iv.itemsize != 8 || tv.itemsize != 1 || sv.itemsize != 8 || ov.itemsize != 8 ||
               ov.len / 48 < 3 * b.n || tshift < 0 || tshift > 60 ||
               tv.len < (Py_ssize_t)((width >> tshift) >> 3) + 1 || sshift < 0 || sshift > 62 ||
               sv.len / 8 != (Py_ssize_t)(width >> sshift) + 2 ||
               (got[4] && (kv.itemsize != 8 || kv.len / 8 < 3 * b.n)))) {
        PyErr_SetString(PyExc_ValueError, "pick_sides: the ids, table, starts, output or keys do not fit");
        ok = 0;
    }
    const uint64_t *ids = ok ? iv.buf : NULL;
    const int64_t *starts = ok ? sv.buf : NULL;
    Py_ssize_t nid = ok ? iv.len / 8 : 0;
    if (!ok) {
        for (int i = 0; i < 5; i++)
            if (got[i])
                PyBuffer_Release(vs[i]);
        release_block(&view, &b);
        return NULL;
    }
    const uint8_t *table = tv.buf;
    double *out = ov.buf;
    uint64_t *keys_out = got[4] ? kv.buf : NULL;
    Py_ssize_t k = b.n, written = 0, n[3] = {0, 0, 0}, room[3] = {64, 64, 64};
    /* The faces of the hit sides, one list a slot (each in face order as found). */
    Py_ssize_t *hit[3] = {malloc(64 * sizeof(Py_ssize_t)), malloc(64 * sizeof(Py_ssize_t)),
                          malloc(64 * sizeof(Py_ssize_t))};
    int failed = !hit[0] || !hit[1] || !hit[2];
    Py_BEGIN_ALLOW_THREADS
    double raw[LEAF][9];
    uint64_t h[3][LEAF], all[3][LEAF];
    for (Py_ssize_t t0 = 0; t0 < k && !failed; t0 += LEAF) {
        Py_ssize_t m = k - t0 < LEAF ? k - t0 : LEAF;
        load(&b, t0, m, raw);
        leaf_keys((const double (*)[9])raw, m, h, all, NULL);
        for (Py_ssize_t j = 0; j < m && !failed; j++) {
            for (int v = 0; v < 3; v++) {
                if (h[v][j] == h[v == 2 ? 0 : v + 1][j])
                    continue; /* a side whose ends hash alike bounds nothing */
                uint64_t e = all[v][j] >> low, top = e >> tshift;
                if (!(table[top >> 3] >> (top & 7) & 1))
                    continue;
                Py_ssize_t at = starts[e >> sshift], stop = starts[(e >> sshift) + 1];
                if (at < 0)
                    at = 0;
                if (stop > nid)
                    stop = nid; /* (an index that is not one finds less, never reads beyond) */
                while (at < stop && ids[at] < e)
                    at++;
                if (at == stop || ids[at] != e)
                    continue;
                if (n[v] == room[v]) {
                    Py_ssize_t *grown = realloc(hit[v], (room[v] *= 2) * sizeof(Py_ssize_t));
                    if (!grown) {
                        failed = 1;
                        break;
                    }
                    hit[v] = grown;
                }
                hit[v][n[v]++] = t0 + j;
            }
        }
    }
    /* The hit sides' end points, slot by slot (and their keys, made again from them). */
    for (int v = 0; v < 3 && !failed; v++)
        for (Py_ssize_t i = 0; i < n[v]; i++) {
            double p[1][9];
            load(&b, hit[v][i], 1, p);
            int w = v == 2 ? 0 : v + 1;
            for (int a = 0; a < 3; a++) {
                out[6 * written + a] = p[0][3 * v + a] + 0.0;
                out[6 * written + 3 + a] = p[0][3 * w + a] + 0.0;
            }
            if (keys_out) {
                uint64_t hc[3];
                corner_hashes(p[0], hc);
                keys_out[written] = side_key(hc[v], hc[w]);
            }
            written++;
        }
    Py_END_ALLOW_THREADS
    for (int v = 0; v < 3; v++)
        free(hit[v]);
    for (int i = 0; i < 5; i++)
        if (got[i])
            PyBuffer_Release(vs[i]);
    release_block(&view, &b);
    if (failed)
        return PyErr_NoMemory();
    return PyLong_FromSsize_t(written);
}

/* ---- p3d check's fast path with boundary edges (p3d_cli.mesh.paired, open meshes) ---- */

/* open_pairs(keys, bits, pi) -> (boundary sides, other sides): pairs(keys, bits, pi) for a soup
 * whose edges may also be used once. In the sorted side keys, a group (keys equal above the
 * direction bit) of one side is a boundary side: pi[side] = -1; a group of two sides running
 * opposite ways is linked as pairs links it; the sides of any other group (two sides the same
 * way, or three or more: colliding hashes, or a non-manifold or misoriented edge) get
 * pi = -2, for p3d_cli.mesh.paired to sort out by their exact end points. pi: int32 or int64,
 * as long as the keys. */
#define OPEN_PAIRS(T)                                                                              \
    static Py_ssize_t open_pairs_##T(const uint64_t *keys, Py_ssize_t n, int bits, T *pi,        \
                                     Py_ssize_t *other) {                                          \
        const uint64_t mask = ((uint64_t)1 << bits) - 1;                                           \
        Py_ssize_t i = 0, boundary = 0;                                                            \
        while (i < n) {                                                                            \
            uint64_t a = keys[i], edge = a >> (bits + 1);                                          \
            int64_t sa = (int64_t)(a & mask);                                                      \
            if (i + 1 < n && keys[i + 1] >> (bits + 1) == edge) {                                  \
                uint64_t b = keys[i + 1];                                                          \
                if (((a ^ b) >> bits) != 1 || (i + 2 < n && keys[i + 2] >> (bits + 1) == edge)) { \
                    for (; i < n && keys[i] >> (bits + 1) == edge; i++, (*other)++)                \
                        pi[keys[i] & mask] = -2;                                                   \
                    continue;                                                                      \
                }                                                                                  \
                int64_t sb = (int64_t)(b & mask);                                                  \
                pi[sa] = (T)(sb % 3 == 2 ? sb - 2 : sb + 1);                                       \
                pi[sb] = (T)(sa % 3 == 2 ? sa - 2 : sa + 1);                                       \
                i += 2;                                                                            \
            } else {                                                                               \
                pi[sa] = -1;                                                                       \
                boundary++;                                                                        \
                i++;                                                                               \
            }                                                                                      \
        }                                                                                          \
        return boundary;                                                                           \
    }
OPEN_PAIRS(int32_t)
OPEN_PAIRS(int64_t)

static PyObject *py_open_pairs(PyObject *self, PyObject *args) {
    PyObject *keyobj, *piobj;
    int bits;
    if (!PyArg_ParseTuple(args, "OiO", &keyobj, &bits, &piobj))
        return NULL;
    Py_buffer kv, pv;
    if (get_array(keyobj, &kv, 'Q', 0, "open_pairs") < 0)
        return NULL;
    if (get_array(piobj, &pv, 'i', 1, "open_pairs") < 0) {
        PyBuffer_Release(&kv);
        return NULL;
    }
    Py_ssize_t n = kv.len / 8, found = -1, other = 0;
    int wide = pv.itemsize == 8;
    if (pv.len / pv.itemsize == n && bits >= 1 && bits <= 62 && (wide || n <= 2147483647)) {
        Py_BEGIN_ALLOW_THREADS
        found = wide ? open_pairs_int64_t((const uint64_t *)kv.buf, n, bits, (int64_t *)pv.buf, &other)
                     : open_pairs_int32_t((const uint64_t *)kv.buf, n, bits, (int32_t *)pv.buf, &other);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&kv);
    PyBuffer_Release(&pv);
    if (found < 0) {
        PyErr_SetString(PyExc_ValueError, "open_pairs: keys and pi do not match");
        return NULL;
    }
    return Py_BuildValue("nn", found, other);
}

/* fan_chains(pi, first) -> number of fans: fan_cycles for a map with open ends. pi[c] is the
 * next corner of c's fan, or -1 where c's side is a boundary side (the fan is an open chain
 * there); pi must be one-to-one. Overwrites pi with the fan number of every corner, the fans
 * (cycles and chains) numbered by their smallest corner, and sets first[c] where c is its fan's
 * smallest corner: from each corner not yet seen, in ascending order, the walk goes back to its
 * chain's start (or round its cycle) and then forward, numbering. -1 when pi is not one-to-one
 * or out of range, -2 when out of memory. */
#define FAN_CHAINS(T)                                                                              \
    static Py_ssize_t fan_chains_##T(T *pi, unsigned char *first, Py_ssize_t size) {             \
        T *back = malloc((size_t)(size > 0 ? size : 1) * sizeof(T));                               \
        if (!back)                                                                                 \
            return -2;                                                                             \
        for (Py_ssize_t c = 0; c < size; c++)                                                      \
            back[c] = -1;                                                                          \
        for (Py_ssize_t c = 0; c < size; c++) {                                                    \
            T to = pi[c];                                                                          \
            if (to < -1 || to >= size || (to >= 0 && back[to] >= 0)) {                            \
                free(back);                                                                        \
                return -1;                                                                         \
            }                                                                                      \
            if (to >= 0)                                                                           \
                back[to] = (T)c;                                                                   \
        }                                                                                          \
        Py_ssize_t count = 0;                                                                      \
        for (Py_ssize_t c = 0; c < size; c++) {                                                    \
            if (pi[c] <= -2) {                                                                     \
                first[c] = 0;                                                                      \
                continue;                                                                          \
            }                                                                                      \
            first[c] = 1;                                                                          \
            Py_ssize_t start = c;                                                                  \
            while (back[start] >= 0 && back[start] != c)                                           \
                start = back[start];                                                               \
            T mark = (T)(-(count + 2));                                                            \
            Py_ssize_t x = start;                                                                  \
            for (;;) {                                                                             \
                T next = pi[x];                                                                    \
                if (next <= -2) {                                                                  \
                    free(back);                                                                    \
                    return -1;                                                                     \
                }                                                                                  \
                pi[x] = mark;                                                                      \
                if (next == -1 || next == start)                                                   \
                    break;                                                                         \
                x = next;                                                                          \
            }                                                                                      \
            count++;                                                                               \
        }                                                                                          \
        free(back);                                                                                \
        for (Py_ssize_t c = 0; c < size; c++)                                                      \
            pi[c] = (T)(-pi[c] - 2);                                                               \
        return count;                                                                              \
    }
FAN_CHAINS(int32_t)
FAN_CHAINS(int64_t)

static PyObject *py_fan_chains(PyObject *self, PyObject *args) {
    PyObject *piobj, *fobj;
    if (!PyArg_ParseTuple(args, "OO", &piobj, &fobj))
        return NULL;
    Py_buffer pv, fv;
    if (get_array(piobj, &pv, 'i', 1, "fan_chains") < 0)
        return NULL;
    if (get_array(fobj, &fv, 'B', 1, "fan_chains") < 0) {
        PyBuffer_Release(&pv);
        return NULL;
    }
    Py_ssize_t size = pv.len / pv.itemsize, count = -1;
    if (fv.len == size) {
        Py_BEGIN_ALLOW_THREADS
        count = pv.itemsize == 4 ? fan_chains_int32_t((int32_t *)pv.buf, (unsigned char *)fv.buf, size)
                                 : fan_chains_int64_t((int64_t *)pv.buf, (unsigned char *)fv.buf, size);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&pv);
    PyBuffer_Release(&fv);
    if (count == -2)
        return PyErr_NoMemory();
    if (count < 0) {
        PyErr_SetString(PyExc_ValueError, "fan_chains: pi must be one-to-one and first as long");
        return NULL;
    }
    return PyLong_FromSsize_t(count);
}

/* ---- the edge keys of a leaf, all at once (issue 32) ---------------------------------------- */

/* The keys of edge_keys for the triangles of a leaf (n <= LEAF): h[v][k] the hash of corner v
 * of triangle k (corner_hashes), keys[v][k] the key of its side v -> v + 1 (as edge_keys makes
 * it; meaningless where the two ends hash alike) and, when g is not NULL, g[v][k] =
 * mix(keys[v][k] | 1). The same integer operations as corner_hashes and edge_hash, but
 * arranged as loops over the leaf's triangles, whose iterations do not depend on each other:
 * the processor overlaps many triangles' mixes instead of waiting on one triangle's chain of
 * multiplications, and a build for AVX-512 (whose vectors multiply 64-bit integers) or AVX2 is
 * chosen at run time where the processor has it. Integer arithmetic: every copy gives the same
 * bits. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && __GNUC__ >= 11
#define KEY_CLONES __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#elif defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define KEY_CLONES __attribute__((target_clones("avx2", "default"))) /* no x86-64-v4 before GCC 11 */
#else
#define KEY_CLONES
#endif

KEY_CLONES
static void leaf_keys(const double p[][9], Py_ssize_t n, uint64_t h[3][LEAF], uint64_t keys[3][LEAF],
                      uint64_t g[3][LEAF]) {
    uint64_t bits[9][LEAF];
    for (Py_ssize_t k = 0; k < n; k++)
        for (int i = 0; i < 9; i++)
            bits[i][k] = bits_of(p[k][i]);
    for (int v = 0; v < 3; v++) {
        const uint64_t *x = bits[3 * v], *y = bits[3 * v + 1], *z = bits[3 * v + 2];
        uint64_t *hv = h[v];
        for (Py_ssize_t k = 0; k < n; k++)
            hv[k] = mix(mix(mix(x[k] ^ GOLDEN) ^ y[k]) ^ z[k]);
    }
    for (int v = 0; v < 3; v++) {
        const uint64_t *s = h[v], *e = h[v == 2 ? 0 : v + 1];
        uint64_t *out = keys[v];
        for (Py_ssize_t k = 0; k < n; k++) {
            uint64_t a = s[k], b = e[k], lo = a < b ? a : b, hi = a < b ? b : a;
            out[k] = (mix(lo * GOLDEN + hi) & ~(uint64_t)1) | (uint64_t)(a < b);
        }
        if (g) {
            uint64_t *gv = g[v];
            for (Py_ssize_t k = 0; k < n; k++)
                gv[k] = mix(out[k] | 1);
        }
    }
}

/* edge_keys' deal for forward_block (forward_only, bucketed) from leaf_keys' arrays: the same
 * keys dealt to the same buckets in the same order, the same balance and backward count, and
 * the backward sides' prints when asked. Whether a side runs forward is a coin toss for hashed
 * corners, so a branch on it would be mispredicted half the time: here the direction picks the
 * sign of g and which of two lists of the leaf's keys grows by arithmetic, and each list is then
 * dealt by a loop of its own. */
static void forward_keys(Pass *c, const uint64_t h[3][LEAF], const uint64_t keys[3][LEAF],
                         const uint64_t g[3][LEAF], Py_ssize_t n) {
    uint64_t *out = c->keys, balance = c->balance, fk[3 * LEAF], bk[3 * LEAF];
    int64_t *fill = c->fill;
    const Py_ssize_t cap = c->cap;
    const int shift = c->shift;
    Py_ssize_t backward = 0, nf = 0, nb = 0;
    /* The leaf's forward keys and backward keys, each in file order, apart: both written,
     * each count moved by the direction (arithmetic, not a branch). */
    for (Py_ssize_t k = 0; k < n; k++) {
        for (int v = 0; v < 3; v++) {
            uint64_t start = h[v][k], end = h[v == 2 ? 0 : v + 1][k];
            if (start == end)
                continue; /* a side whose ends hash alike bounds nothing (rare: predicted) */
            uint64_t key = keys[v][k], fwd = key & 1, back = fwd ^ 1;
            uint64_t sign = (uint64_t)0 - back;             /* all ones for a backward side */
            balance += (g[v][k] ^ sign) + back;             /* +g or -g, mod 2^64 */
            fk[nf] = key;
            bk[nb] = key;
            nf += (Py_ssize_t)fwd;
            nb += (Py_ssize_t)back;
        }
    }
    backward = nb;
    Py_ssize_t w = 0;
    for (Py_ssize_t i = 0; i < nf; i++) {
        uint64_t key = fk[i], b = key >> shift;
        int64_t f = fill[b];
        if (f == cap) { /* rare: predicted */
            c->overflow = 1;
            continue;
        }
        out[b * cap + f] = key;
        fill[b] = f + 1;
        w++;
    }
    if (c->prints) {
        /* the backward sides' prints: the 32 key bits below the bucket's */
        uint32_t *prints = c->prints;
        int64_t *pfill = c->print_fill;
        const int low = shift - 32;
        for (Py_ssize_t i = 0; i < nb; i++) {
            uint64_t key = bk[i], b = key >> shift;
            int64_t q = pfill[b];
            if (q == cap) { /* rare: predicted */
                c->print_overflow = 1;
                continue;
            }
            prints[b * cap + q] = (uint32_t)(key >> low);
            pfill[b] = q + 1;
        }
    }
    c->balance = balance;
    c->backward += backward;
    c->written += w;
}

/* ---- the bucket pages every mesh fills, made at once (issue 32) ---------------------------- */

/* populate(keys, fill, cap, shift, sure) -> whether it was done: asks the kernel for the whole pages
 * of the first `sure` slots of every bucket of forward_block's buffer in one call per bucket
 * (MADV_POPULATE_WRITE, Linux 5.14 on), instead of one page fault per page as the keys reach
 * them (a fifth of the pass's system time at 16M triangles). `sure` is a count every bucket
 * of a mesh's keys reaches (the mean less eight standard deviations), so the pages are those
 * the keys write anyway: no more resident memory. False, and nothing done, elsewhere. */
static PyObject *py_populate(PyObject *self, PyObject *args) {
    PyObject *keyobj, *fillobj;
    Py_ssize_t cap, sure;
    int shift, done = 0;
    if (!PyArg_ParseTuple(args, "OOnin", &keyobj, &fillobj, &cap, &shift, &sure))
        return NULL;
    Py_buffer kview, fview;
    if (get_buckets(keyobj, fillobj, cap, shift, 0, &kview, &fview) < 0)
        return NULL;
    Py_ssize_t buckets = fview.len / 8;
    if (sure > cap)
        sure = cap;
#if defined(__linux__)
#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23
#endif
    uintptr_t page = (uintptr_t)sysconf(_SC_PAGESIZE);
    done = page > 1 && sure > 0;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t b = 0; done && b < buckets; b++) {
        uintptr_t lo = (uintptr_t)((uint64_t *)kview.buf + b * cap), hi = lo + (uintptr_t)sure * 8;
        lo = (lo + page - 1) / page * page;
        hi = hi / page * page;
        if (hi > lo && madvise((void *)lo, hi - lo, MADV_POPULATE_WRITE) != 0)
            done = 0; /* an older kernel: the keys fault their pages in as before */
    }
    Py_END_ALLOW_THREADS
#endif
    PyBuffer_Release(&kview);
    PyBuffer_Release(&fview);
    return PyBool_FromLong(done);
}

/* ---- ear clipping's corner test (p3d_cli.repairs.fill) ------------------------------------ */

/* orient2d_about's float filter (p3d_cli.geometry.predicates): the sign of
 * (ax - cx)(by - cy) - (ay - cy)(bx - cx), the same operations in the same order, decided when
 * |det| > bound * perm or perm == 0 (Shewchuk's stage-A bound); *sure is cleared otherwise. */
static inline int ear_turn(const double *p, int64_t a, int64_t b, int64_t c, double bound, int *sure) {
    double left = (p[2 * a] - p[2 * c]) * (p[2 * b + 1] - p[2 * c + 1]);
    double right = (p[2 * a + 1] - p[2 * c + 1]) * (p[2 * b] - p[2 * c]);
    double det = left - right;
    double perm = fabs(left) + fabs(right);
    if (fabs(det) <= bound * perm && perm != 0) {
        *sure = 0;
        return 0;
    }
    return (det > 0) - (det < 0);
}

/* ear_holds(plane, order, alive, sign, bound, u, v, w, first, last): whether an alive corner c
 * of order[first:last] other than u, v, w, with y within u v w's, lies in the closed triangle
 * u v w (sign times each of orient(u, v, c), orient(v, w, c), orient(w, u, c) >= 0): 1 when one
 * certainly does, 0 when none does, -1 when the filter leaves a corner undecided and none is
 * certainly in (the caller decides exactly). plane (k, 2) float64, order (k,) int64, alive (k,)
 * bool. */
static PyObject *py_ear_holds(PyObject *self, PyObject *args) {
    PyObject *po, *oo, *ao;
    int sign;
    double bound;
    Py_ssize_t u, v, w, first, last;
    if (!PyArg_ParseTuple(args, "OOOidnnnnn", &po, &oo, &ao, &sign, &bound, &u, &v, &w, &first, &last))
        return NULL;
    Py_buffer b[3];
    int got[3] = {0};
    PyObject *objs[3] = {po, oo, ao};
    const char kinds[3] = {'d', 'q', 'B'};
    for (int k = 0; k < 3; k++) {
        if (get_array(objs[k], &b[k], kinds[k], 0, "ear_holds") < 0) {
            release_all(b, got, 3);
            return NULL;
        }
        got[k] = 1;
    }
    Py_ssize_t n = b[2].len;
    if (b[0].len != 16 * n || b[1].len != 8 * n || u < 0 || v < 0 || w < 0 || u >= n || v >= n || w >= n ||
        first < 0 || last > n || (sign != 1 && sign != -1)) {
        release_all(b, got, 3);
        PyErr_SetString(PyExc_ValueError, "ear_holds: the corners, order and indices do not match");
        return NULL;
    }
    const double *p = b[0].buf;
    const int64_t *order = b[1].buf;
    const unsigned char *alive = b[2].buf;
    double lo = p[2 * u + 1], hi = lo;
    if (p[2 * v + 1] < lo) lo = p[2 * v + 1];
    if (p[2 * w + 1] < lo) lo = p[2 * w + 1];
    if (p[2 * v + 1] > hi) hi = p[2 * v + 1];
    if (p[2 * w + 1] > hi) hi = p[2 * w + 1];
    int found = 0, open = 0, bad = 0;
    for (Py_ssize_t i = first; i < last; i++) {
        int64_t c = order[i];
        if (c < 0 || c >= n) {
            bad = 1;
            break;
        }
        if (!alive[c] || c == u || c == v || c == w || !(p[2 * c + 1] >= lo && p[2 * c + 1] <= hi))
            continue;
        int sure = 1, outside = 0;
        int64_t ends[3][2] = {{u, v}, {v, w}, {w, u}};
        for (int e = 0; e < 3 && !outside; e++) {
            int s = 1;
            int t = ear_turn(p, ends[e][0], ends[e][1], c, bound, &s);
            if (!s)
                sure = 0;
            else if (t * sign < 0)
                outside = 1;
        }
        if (outside)
            continue;
        if (sure) {
            found = 1;
            break;
        }
        open = 1;
    }
    release_all(b, got, 3);
    if (bad) {
        PyErr_SetString(PyExc_ValueError, "ear_holds: an order entry is out of range");
        return NULL;
    }
    return PyLong_FromLong(found ? 1 : (open ? -1 : 0));
}

/* ---- an open mesh's boundary terms (p3d_cli.mesh.boundary_terms.Locals.add) -------------- */

static inline void two_sum_d(double a, double b, double *s, double *e) {
    double x = a + b, bb = x - a;
    *s = x;
    *e = (a - (x - bb)) + (b - bb);
}

static inline void split_d(double a, double *hi, double *lo) {
    double c = 134217729.0 * a; /* Veltkamp: 2**27 + 1 */
    double h = c - (c - a);
    *hi = h;
    *lo = a - h;
}

/* expansions.product_of_splits: p = fl(a b), p + e = a b exactly (barring underflow) */
static inline void product_d(double a, double ah, double al, double b, double bh, double bl, double *p, double *e) {
    double x = a * b;
    *p = x;
    *e = ((ah * bh - x) + ah * bl + al * bh) + al * bl;
}

/* numpy's sum of a contiguous row: 0.0 + its pairwise sum (leaves of 128, halves rounded down
 * to a multiple of 8). */
static double pairwise_row(const double *a, Py_ssize_t n) {
    if (n <= LEAF)
        return leaf_sum(a, n);
    Py_ssize_t n2 = n / 2;
    n2 -= n2 % 8;
    return pairwise_row(a, n2) + pairwise_row(a + n2, n - n2);
}

static inline double numpy_sum(const double *a, Py_ssize_t n) { return 0.0 + pairwise_row(a, n); }

/* boundary_terms._dd_product: (xh + xl)(yh + yl) as an exact high part p and a rounded low
 * part e (xl yl dropped), given the splits of xh and yh */
static inline void dd_product_d(double xh, double xhh, double xhl, double xl, double yh, double yhh, double yhl,
                                double yl, double *p, double *e) {
    product_d(xh, xhh, xhl, yh, yhh, yhl, p, e);
    *e = *e + (xh * yl + xl * yh);
}

/* local_terms(u, v, frame, scale, parts, q_high, mag, big_t, big_w, low_sums, r_sum) ->
 *   underflow count, or -1 when some u - frame is not exact (InexactLocal)
 * Locals.add's numbers for the sides u -> v ((3, n) float64 world coordinates, rows x, y, z)
 * with scaled local end points a = (u - frame) 2**-scale, b likewise (local_coordinates), by the
 * same IEEE operations in the same order as the numpy code of
 * p3d_cli.mesh.boundary_terms (_cross, _dd_product, _w, expansions.cascaded_sums, numpy's
 * pairwise row sums): parts (12, n) the cross products' exact parts (row 4k + part), q_high
 * (9, n) Q's exact high parts (row 3k + i), low_sums (27) Q's and R's low parts summed per row
 * (R's with the cascade's errors added), r_sum (18) the cascade's high sums, and the bound's
 * inputs mag = |X_k| (3, n), big_t = |a| + |b| (3, n), big_w (6, n). Returns the sides whose
 * cross products may have lost bits to underflow. */
static const int CROSS_I[3] = {1, 2, 0}, CROSS_J[3] = {2, 0, 1};
static const int PAIR_I[6] = {0, 1, 2, 0, 0, 1}, PAIR_J[6] = {0, 1, 2, 1, 2, 2};

static PyObject *py_local_terms(PyObject *self, PyObject *args) {
    PyObject *obj[9];
    double frame[3];
    int scale;
    if (!PyArg_ParseTuple(args, "OO(ddd)iOOOOOOO", &obj[0], &obj[1], &frame[0], &frame[1], &frame[2], &scale, &obj[2],
                          &obj[3], &obj[4], &obj[5], &obj[6], &obj[7], &obj[8]))
        return NULL;
    Py_buffer v[9];
    int got[9] = {0};
    for (int i = 0; i < 9; i++) {
        if (get_array(obj[i], &v[i], 'd', i >= 2, "local_terms") < 0) {
            release_all(v, got, 9);
            return NULL;
        }
        got[i] = 1;
    }
    Py_ssize_t n = v[0].len / 24;
    static const Py_ssize_t rows[9] = {3, 3, 12, 9, 3, 3, 6, 27, 18};
    int fits = v[0].len == 24 * n;
    for (int i = 0; i < 9; i++)
        fits &= v[i].len == rows[i] * (i >= 7 ? 1 : n) * 8;
    if (!fits) {
        release_all(v, got, 9);
        PyErr_SetString(PyExc_ValueError, "local_terms: the arrays' shapes do not fit");
        return NULL;
    }
    const double *u = v[0].buf, *w = v[1].buf;
    double *parts = v[2].buf, *q_high = v[3].buf, *mag = v[4].buf, *big_t = v[5].buf, *big_w = v[6].buf;
    double *low_sums = v[7].buf, *r_sum = v[8].buf;
    /* a, b (3 n each), q_low (9 n), r_low (18 n), r_high (18 (n + 1)), the cascade's errors (n / 2 + 1) */
    double *work = n ? malloc((6 * n + 9 * n + 18 * n + 18 * (n + 1) + n / 2 + 1) * sizeof(double)) : NULL;
    if (n && !work) {
        release_all(v, got, 9);
        return PyErr_NoMemory();
    }
    Py_ssize_t underflow = 0;
    int inexact = 0;
    Py_BEGIN_ALLOW_THREADS
    double *a = work, *b = a + 3 * n, *q_low = b + 3 * n, *r_low = q_low + 9 * n, *r_high = r_low + 18 * n,
           *error = r_high + 18 * (n + 1);
    /* boundary_terms.local_coordinates: a = (u - frame) 2**-scale, checked exact (two_sum's
     * error zero, the scaling undone gives the difference back) */
    for (int i = 0; i < 3; i++)
        for (Py_ssize_t s = 0; s < n; s++) {
            double d, e, x, y;
            two_sum_d(u[i * n + s], -frame[i], &d, &e);
            two_sum_d(w[i * n + s], -frame[i], &x, &y);
            a[i * n + s] = ldexp(d, -scale);
            b[i * n + s] = ldexp(x, -scale);
            inexact |= e != 0.0 || y != 0.0 || ldexp(a[i * n + s], scale) != d || ldexp(b[i * n + s], scale) != x;
        }
    for (Py_ssize_t s = 0; s < n && !inexact; s++) {
        double A[3], B[3], ah[3], al[3], bh[3], bl[3], xh[3], xl[3], th[3], tl[3], thh[3], thl[3];
        double xhh[3], xhl[3], wh[6], wl[6], whh[6], whl[6];
        int small = 0;
        for (int i = 0; i < 3; i++) {
            A[i] = a[i * n + s];
            B[i] = b[i * n + s];
            split_d(A[i], &ah[i], &al[i]);
            split_d(B[i], &bh[i], &bl[i]);
        }
        for (int k = 0; k < 3; k++) { /* _cross */
            int i = CROSS_I[k], j = CROSS_J[k];
            double p1, e1, p2, e2, S, T, F, G, H, C, D;
            product_d(A[i], ah[i], al[i], B[j], bh[j], bl[j], &p1, &e1);
            product_d(A[j], ah[j], al[j], B[i], bh[i], bl[i], &p2, &e2);
            small |= (p1 != 0.0 && fabs(p1) < 0x1p-968) || (p2 != 0.0 && fabs(p2) < 0x1p-968);
            two_sum_d(p1, -p2, &S, &T);
            two_sum_d(e1, -e2, &F, &G);
            two_sum_d(T, F, &H, &C);
            two_sum_d(S, H, &xh[k], &D);
            xl[k] = D + (C + G);
            parts[(4 * k) * n + s] = xh[k];
            parts[(4 * k + 1) * n + s] = D;
            parts[(4 * k + 2) * n + s] = C;
            parts[(4 * k + 3) * n + s] = G;
        }
        underflow += small;
        for (int i = 0; i < 3; i++) {
            two_sum_d(A[i], B[i], &th[i], &tl[i]);
            split_d(th[i], &thh[i], &thl[i]);
            split_d(xh[i], &xhh[i], &xhl[i]);
        }
        for (int k = 0; k < 3; k++) /* Q: _dd_product */
            for (int i = 0; i < 3; i++)
                dd_product_d(xh[k], xhh[k], xhl[k], xl[k], th[i], thh[i], thl[i], tl[i], &q_high[(3 * k + i) * n + s],
                             &q_low[(3 * k + i) * n + s]);
        for (int r = 0; r < 6; r++) { /* _w */
            int i = PAIR_I[r], j = PAIR_J[r];
            double x1, y1, x2, y2, x3, y3, h, l2, l3;
            product_d(A[i], ah[i], al[i], A[j], ah[j], al[j], &x1, &y1);
            product_d(B[i], bh[i], bl[i], B[j], bh[j], bl[j], &x2, &y2);
            product_d(th[i], thh[i], thl[i], th[j], thh[j], thl[j], &x3, &y3);
            y3 = y3 + (th[i] * tl[j] + tl[i] * th[j]);
            two_sum_d(x1, x2, &h, &l2);
            two_sum_d(h, x3, &h, &l3);
            two_sum_d(h, ((y1 + y2) + y3) + (l2 + l3), &wh[r], &wl[r]);
            split_d(wh[r], &whh[r], &whl[r]);
        }
        for (int k = 0; k < 3; k++) /* R: _dd_product */
            for (int r = 0; r < 6; r++)
                dd_product_d(xh[k], xhh[k], xhl[k], xl[k], wh[r], whh[r], whl[r], wl[r],
                             &r_high[(6 * k + r) * (n + 1) + s], &r_low[(6 * k + r) * n + s]);
        /* the bound's inputs (Locals._bound) */
        double aa[3], bb[3], tt[3];
        for (int i = 0; i < 3; i++) {
            aa[i] = fabs(A[i]);
            bb[i] = fabs(B[i]);
            tt[i] = aa[i] + bb[i];
            mag[i * n + s] = fabs(xh[i]);
            big_t[i * n + s] = tt[i];
        }
        for (int r = 0; r < 6; r++) {
            int i = PAIR_I[r], j = PAIR_J[r];
            big_w[r * n + s] = aa[i] * aa[j] + bb[i] * bb[j] + tt[i] * tt[j];
        }
    }
    for (int r = 0; r < 9 && !inexact; r++)
        low_sums[r] = numpy_sum(q_low + r * n, n);
    for (int r = 0; r < 18 && !inexact; r++) {
        /* cascaded_sums: halves added by two_sum level by level (a zero pads an odd row), each
         * level's errors summed as numpy sums a row and added to low */
        double *x = r_high + r * (n + 1), low = 0.0;
        Py_ssize_t m = n;
        while (m > 1) {
            if (m % 2)
                x[m++] = 0.0;
            Py_ssize_t half = m / 2;
            for (Py_ssize_t i = 0; i < half; i++)
                two_sum_d(x[i], x[i + half], &x[i], &error[i]);
            low = low + numpy_sum(error, half);
            m = half;
        }
        r_sum[r] = x[0];
        low_sums[9 + r] = numpy_sum(r_low + r * n, n) + low;
    }
    Py_END_ALLOW_THREADS
    free(work);
    release_all(v, got, 9);
    return PyLong_FromSsize_t(inexact ? -1 : underflow);
}

/* exact_bins(values, offsets, high, low): p3d_cli.geometry.expansions.ExactSum.add's binning.
 * Each value of row r of values ((k, m) float64, finite) is f 2**e (frexp), f 2**27 split into
 * its floor, added to high[offsets[r] + e], and the rest, added to low[offsets[r] + e]
 * (offsets: k int64). Every bin's sum is exact (the caller moves the bins into integers before
 * any can leave float64's integers), so the order of the additions does not matter: the same
 * bins as numpy's bincount. */
static PyObject *py_exact_bins(PyObject *self, PyObject *args) {
    PyObject *obj[4];
    if (!PyArg_ParseTuple(args, "OOOO", &obj[0], &obj[1], &obj[2], &obj[3]))
        return NULL;
    Py_buffer v[4];
    int got[4] = {0};
    static const char kinds[4] = {'d', 'q', 'd', 'd'};
    for (int i = 0; i < 4; i++) {
        if (get_array(obj[i], &v[i], kinds[i], i >= 2, "exact_bins") < 0) {
            release_all(v, got, 4);
            return NULL;
        }
        got[i] = 1;
    }
    Py_ssize_t k = v[1].len / 8, m = k ? v[0].len / 8 / k : 0, size = v[2].len / 8;
    const int64_t *offsets = v[1].buf;
    int bad = (k ? v[0].len != 8 * k * m : v[0].len != 0) || v[3].len != v[2].len;
    for (Py_ssize_t r = 0; r < k && !bad; r++)
        bad = offsets[r] - 1073 < 0 || offsets[r] + 1024 >= size;
    if (bad) {
        release_all(v, got, 4);
        PyErr_SetString(PyExc_ValueError, "exact_bins: the arrays do not fit");
        return NULL;
    }
    const double *values = v[0].buf;
    double *high = v[2].buf, *low = v[3].buf;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t r = 0; r < k; r++) {
        const double *row = values + r * m;
        const int64_t offset = offsets[r];
        for (Py_ssize_t i = 0; i < m; i++) {
            int e;
            double f = frexp(row[i], &e) * 134217728.0; /* 2**27 */
            double h = floor(f);
            Py_ssize_t bin = offset + e;
            high[bin] += h;
            low[bin] += f - h;
        }
    }
    Py_END_ALLOW_THREADS
    release_all(v, got, 4);
    Py_RETURN_NONE;
}
