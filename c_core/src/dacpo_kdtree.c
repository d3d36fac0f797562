/* SPDX-License-Identifier: BSD-3-Clause */
/* Built-in exact k-nearest-neighbour search in 3-D (stage 0 of the pipeline,
 * ALGORITHM.md §0: "the core also has its own search so it runs and tests
 * without PCL"; also used by later stages on block-local point sets).
 *
 * Input:  n points (3n doubles, copied). Output: a read-only tree.
 * Layout: the points are permuted into tree order (leaves are contiguous runs)
 * and the nodes live in one array; the children of a node are adjacent.
 * Build:  median split by COUNT (quickselect on (coordinate, index)) along the
 *         widest axis of the node's bounding box, until a node holds at most
 *         KD_LEAF points. Splitting by count keeps the depth at ceil(log2(n/8))
 *         even when all points coincide. O(n log n) time, no extra memory
 *         beyond the copy and the node array.
 * Query:  depth-first, near child first; a far child is visited only if the
 *         lower bound of its distance (per-axis offsets to the child's extent,
 *         as in Arya & Mount's incremental distance) does not exceed the current
 *         k-th distance. Results are kept sorted by (squared distance, index),
 *         so ties go to the lower index and the answer equals a brute force
 *         that computes dx*dx + dy*dy + dz*dz the same way.
 * Failure modes: n > INT32_MAX (INVALID_ARGUMENT), allocation (OUT_OF_MEMORY).
 * Queries never allocate and are safe from several threads at once. */
#include "dacpo_kdtree.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { KD_LEAF = 12 };

typedef struct kd_node {
  double low_max;  /* inner: largest coordinate on dim in the left child */
  double high_min; /* inner: smallest coordinate on dim in the right child */
  uint32_t begin;  /* points [begin, end) in tree order */
  uint32_t end;
  int32_t child; /* left child; right = child + 1; -1 for a leaf */
  int32_t dim;
} kd_node;

struct dacpo_kdtree {
  size_t n;
  double* pts;  /* 3n, tree order */
  int32_t* ids; /* n, original index of each tree-order point */
  kd_node* nodes;
  size_t num_nodes;
};

/* ---- build ------------------------------------------------------------- */

typedef struct kd_build {
  double* pts;
  int32_t* ids;
  kd_node* nodes;
  size_t num_nodes;
  size_t cap_nodes;
  uint64_t rng; /* pivot choice only; fixed seed keeps builds identical */
} kd_build;

static void
kd_swap(double* pts, int32_t* ids, size_t a, size_t b)
{
  double t0 = pts[3 * a], t1 = pts[3 * a + 1], t2 = pts[3 * a + 2];
  pts[3 * a] = pts[3 * b];
  pts[3 * a + 1] = pts[3 * b + 1];
  pts[3 * a + 2] = pts[3 * b + 2];
  pts[3 * b] = t0;
  pts[3 * b + 1] = t1;
  pts[3 * b + 2] = t2;
  int32_t ti = ids[a];
  ids[a] = ids[b];
  ids[b] = ti;
}

/* (coordinate, original index) order: all keys distinct, so quickselect needs
 * no special care for repeated coordinates and the split is by count. */
static int
kd_less(const double* pts, const int32_t* ids, int dim, size_t a, size_t b)
{
  double va = pts[3 * a + dim], vb = pts[3 * b + dim];
  return va < vb || (va == vb && ids[a] < ids[b]);
}

static uint64_t
kd_rand(uint64_t* s)
{
  /* xorshift64*: only spreads pivots so sorted inputs stay O(n) expected. */
  uint64_t x = *s;
  x ^= x >> 12;
  x ^= x << 25;
  x ^= x >> 27;
  *s = x;
  return x * 2685821657736338717ULL;
}

/* Puts the element of rank `nth` (by kd_less) at position nth, smaller ones
 * before it and larger ones after it, within [lo, hi). */
static void
kd_select(kd_build* b, int dim, size_t lo, size_t hi, size_t nth)
{
  double* pts = b->pts;
  int32_t* ids = b->ids;
  while (hi - lo > 2) {
    /* median of three random positions as the pivot */
    size_t m = hi - lo;
    size_t a = lo + (size_t)(kd_rand(&b->rng) % m);
    size_t c = lo + (size_t)(kd_rand(&b->rng) % m);
    size_t d = lo + (size_t)(kd_rand(&b->rng) % m);
    size_t piv;
    if (kd_less(pts, ids, dim, a, c))
      piv = kd_less(pts, ids, dim, c, d) ? c : (kd_less(pts, ids, dim, a, d) ? d : a);
    else
      piv = kd_less(pts, ids, dim, a, d) ? a : (kd_less(pts, ids, dim, c, d) ? d : c);
    /* Lomuto partition with the pivot parked at hi - 1 */
    kd_swap(pts, ids, piv, hi - 1);
    size_t store = lo;
    for (size_t i = lo; i < hi - 1; ++i) {
      if (kd_less(pts, ids, dim, i, hi - 1)) {
        if (i != store)
          kd_swap(pts, ids, i, store);
        ++store;
      }
    }
    kd_swap(pts, ids, store, hi - 1);
    if (store == nth)
      return;
    if (nth < store)
      hi = store;
    else
      lo = store + 1;
  }
  if (hi - lo == 2 && kd_less(pts, ids, dim, lo + 1, lo))
    kd_swap(pts, ids, lo, lo + 1);
}

/* Recursion depth is the tree depth, ceil(log2(n / KD_LEAF)) + 1 <= 29. */
static void
kd_build_node(kd_build* b, size_t node, size_t begin, size_t end)
{
  kd_node* nd = &b->nodes[node];
  nd->begin = (uint32_t)begin;
  nd->end = (uint32_t)end;
  nd->child = -1;
  nd->dim = 0;
  nd->low_max = nd->high_min = 0.0;
  if (end - begin <= KD_LEAF)
    return;

  const double* p = b->pts;
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d)
    lo[d] = hi[d] = p[3 * begin + d];
  for (size_t i = begin + 1; i < end; ++i) {
    for (int d = 0; d < 3; ++d) {
      double v = p[3 * i + d];
      if (v < lo[d])
        lo[d] = v;
      if (v > hi[d])
        hi[d] = v;
    }
  }
  int dim = 0;
  for (int d = 1; d < 3; ++d)
    if (hi[d] - lo[d] > hi[dim] - lo[dim])
      dim = d;

  size_t mid = begin + (end - begin) / 2;
  kd_select(b, dim, begin, end, mid);
  double low_max = p[3 * begin + dim];
  for (size_t i = begin + 1; i < mid; ++i)
    if (p[3 * i + dim] > low_max)
      low_max = p[3 * i + dim];

  size_t child = b->num_nodes;
  b->num_nodes += 2;
  nd->child = (int32_t)child;
  nd->dim = dim;
  nd->low_max = low_max;
  nd->high_min = p[3 * mid + dim];
  kd_build_node(b, child, begin, mid);
  kd_build_node(b, child + 1, mid, end);
}

dacpo_status
dacpo_kdtree_build(const double* xyz, size_t n, dacpo_kdtree** out, dacpo_err* err)
{
  DACPO_CHECK(err, out != NULL, DACPO_ERR_INVALID_ARGUMENT, "kdtree: out is NULL");
  *out = NULL;
  DACPO_CHECK(err, n == 0 || xyz != NULL, DACPO_ERR_INVALID_ARGUMENT, "kdtree: xyz is NULL");
  DACPO_CHECK(err, n <= (size_t)INT32_MAX, DACPO_ERR_INVALID_ARGUMENT,
              "kdtree: %zu points exceed the int32 index range", n);

  dacpo_kdtree* t = calloc(1, sizeof(*t));
  if (!t)
    return DACPO_OOM(err);
  t->n = n;
  /* Every leaf of a tree over n > KD_LEAF points holds >= KD_LEAF / 2 points
   * (a node with m > KD_LEAF splits into floor(m/2) and ceil(m/2)), so there
   * are at most 2n/KD_LEAF leaves and twice that many nodes. */
  size_t cap = 2 * (n / (KD_LEAF / 2)) + 3;
  t->pts = dacpo_malloc_array(n, 3 * sizeof(double));
  t->ids = dacpo_malloc_array(n, sizeof(int32_t));
  t->nodes = dacpo_malloc_array(cap, sizeof(kd_node));
  if (!t->pts || !t->ids || !t->nodes) {
    dacpo_kdtree_free(t);
    return DACPO_OOM(err);
  }
  if (n > 0)
    memcpy(t->pts, xyz, n * 3 * sizeof(double));
  for (size_t i = 0; i < n; ++i)
    t->ids[i] = (int32_t)i;

  if (n > 0) {
    kd_build b = {t->pts, t->ids, t->nodes, 1, cap, 0x9E3779B97F4A7C15ULL};
    kd_build_node(&b, 0, 0, n);
    t->num_nodes = b.num_nodes;
  }
  *out = t;
  return DACPO_OK;
}

void
dacpo_kdtree_free(dacpo_kdtree* tree)
{
  if (!tree)
    return;
  free(tree->pts);
  free(tree->ids);
  free(tree->nodes);
  free(tree);
}

/* ---- query ------------------------------------------------------------- */

typedef struct kd_result {
  size_t k, count;
  int32_t* idx;
  double* d;
} kd_result;

static double
kd_worst(const kd_result* r)
{
  return r->count < r->k ? INFINITY : r->d[r->k - 1];
}

/* Sorted insertion by (distance, index); k is small (tens), so shifting beats
 * a heap and leaves the output already ordered. */
static void
kd_push(kd_result* r, double d, int32_t id)
{
  size_t pos;
  if (r->count == r->k) {
    double wd = r->d[r->k - 1];
    if (d > wd || (d == wd && id > r->idx[r->k - 1]))
      return;
    pos = r->k - 1;
  }
  else {
    pos = r->count++;
  }
  while (pos > 0 && (r->d[pos - 1] > d || (r->d[pos - 1] == d && r->idx[pos - 1] > id))) {
    r->d[pos] = r->d[pos - 1];
    r->idx[pos] = r->idx[pos - 1];
    --pos;
  }
  r->d[pos] = d;
  r->idx[pos] = id;
}

/* off[d] is a lower bound of |q[d] - p[d]| for every point p of the node.
 * Squares and sums are formed exactly as for a point's distance, and rounding
 * is monotone, so the bound never exceeds a computed point distance: pruning
 * with "bound > k-th distance" cannot lose a tie. */
static void
kd_search(const dacpo_kdtree* t, size_t node, const double q[3], double off[3], kd_result* r)
{
  const kd_node* nd = &t->nodes[node];
  if (nd->child < 0) {
    const double* p = t->pts;
    for (uint32_t i = nd->begin; i < nd->end; ++i) {
      double dx = q[0] - p[3 * i], dy = q[1] - p[3 * i + 1], dz = q[2] - p[3 * i + 2];
      double d = dx * dx + dy * dy + dz * dz;
      if (d <= kd_worst(r))
        kd_push(r, d, t->ids[i]);
    }
    return;
  }
  int dim = nd->dim;
  double to_low = q[dim] - nd->low_max;   /* >= 0 when q is right of the left child */
  double to_high = nd->high_min - q[dim]; /* >= 0 when q is left of the right child */
  size_t near, far;
  double far_off;
  if (to_low < to_high) {
    near = (size_t)nd->child;
    far = near + 1;
    far_off = to_high;
  }
  else {
    far = (size_t)nd->child;
    near = far + 1;
    far_off = to_low;
  }
  kd_search(t, near, q, off, r);
  double saved = off[dim];
  if (far_off > saved)
    off[dim] = far_off;
  double bound = off[0] * off[0] + off[1] * off[1] + off[2] * off[2];
  if (bound <= kd_worst(r))
    kd_search(t, far, q, off, r);
  off[dim] = saved;
}

size_t
dacpo_kdtree_knn(const dacpo_kdtree* tree,
                 const double q[3],
                 size_t k,
                 int32_t* idx,
                 double* sq_dist)
{
  if (!tree || tree->n == 0 || k == 0 || !q || !idx || !sq_dist)
    return 0;
  kd_result r = {k < tree->n ? k : tree->n, 0, idx, sq_dist};
  double off[3] = {0.0, 0.0, 0.0};
  kd_search(tree, 0, q, off, &r);
  return r.count;
}
