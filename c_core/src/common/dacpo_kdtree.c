/* SPDX-License-Identifier: BSD-3-Clause */
/* Built-in exact k-nearest-neighbour search in 3-D (stage 0 of the pipeline,
 * the core has its own search so it runs and tests
 * without PCL; also used by later stages on block-local point sets).
 *
 * Input:  n points (3n doubles, copied). Output: a read-only tree.
 * Layout: the points are permuted into tree order (leaves are contiguous runs)
 * and the nodes live in one array; the children of a node are adjacent.
 * Build:  median split by COUNT (quickselect on (coordinate, index),
 *         dacpo_select.h) along the
 *         widest axis of the node's bounding box, until a node holds at most
 *         KD_LEAF points. Splitting by count keeps the depth at about log2(n/8)
 *         even when all points coincide, and fixes every subtree's size and
 *         node range in advance, so the subtrees below the top KD_TASK_DEPTH
 *         levels are built as parallel tasks into their own ranges (the same
 *         tree on any thread count). O(n log n) time, no extra memory beyond
 *         the copy and the node array.
 * Query:  depth-first, near child first; a far child is visited only if the
 *         lower bound of its distance (per-axis offsets to the child's extent,
 *         as in Arya & Mount's incremental distance) does not exceed the current
 *         k-th distance. Results are kept sorted by (squared distance, index),
 *         so ties go to the lower index and the answer equals a brute force
 *         that computes dx*dx + dy*dy + dz*dz the same way.
 * Failure modes: n >= INT32_MAX or a non-finite coordinate (INVALID_ARGUMENT),
 *   allocation (OUT_OF_MEMORY). A non-finite query gets 0 neighbours.
 * Queries never allocate and are safe from several threads at once. */
#include "dacpo_kdtree.h"

#include "dacpo_parallel.h"
#include "dacpo_select.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Leaves hold 8..16 points (median splits of a node with more than 16). 12 and
 * 16 cost the same instructions per 17-NN query; 16 touches fewer nodes. */
enum { KD_LEAF = 16 };

/* Tree depth bound: n < 2^31 points and leaves of > 8 points give <= 28 levels;
 * the build checks it, the query's explicit stack relies on it. */
enum { KD_MAX_DEPTH = 64 };

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
  dacpo_tree_point* pts; /* n, tree order, with their original index */
  kd_node* nodes;
  size_t num_nodes;
};

/* ---- build ------------------------------------------------------------- */

/* Subtrees below this depth are built as separate tasks (up to 2^KD_TASK_DEPTH
 * of them), each with its own pivot stream, whatever the thread count: the
 * tree is the same on 1 or 16 threads. */
enum { KD_TASK_DEPTH = 5 };

/* A subtree left for a task (its root at depth KD_TASK_DEPTH): its node,
 * points and the first index of its descendants; reached: the deepest level
 * the task built. */
typedef struct kd_task {
  size_t node, begin, end, next;
  size_t reached;
} kd_task;

typedef struct kd_build {
  dacpo_tree_point* pts; /* permuted into tree order by the build */
  kd_node* nodes;
  dacpo_rng rng; /* pivot choice only; fixed seed keeps builds identical */
  size_t max_depth;
  kd_task* tasks; /* NULL: build every level here */
  size_t num_tasks;
} kd_build;

/* Nodes below a node of m points (splits by count: floor(m/2), ceil(m/2)),
 * for m and m + 1 at once: each level needs two neighbouring sizes only. */
static void
kd_descendants(size_t m, size_t* dm, size_t* dm1)
{
  if (m + 1 <= KD_LEAF) {
    *dm = *dm1 = 0;
    return;
  }
  size_t a, b; /* D(h), D(h + 1) with h = m / 2 */
  kd_descendants(m / 2, &a, &b);
  if (m % 2 == 0) {
    *dm = m <= KD_LEAF ? 0 : 2 + 2 * a;
    *dm1 = 2 + a + b;
  }
  else {
    *dm = m <= KD_LEAF ? 0 : 2 + a + b;
    *dm1 = 2 + 2 * b;
  }
}

static size_t
kd_subtree_nodes(size_t m)
{
  size_t d, d1;
  kd_descendants(m, &d, &d1);
  return d;
}

/* Node `node` over points [begin, end); its children go to next and next + 1,
 * the left child's descendants from next + 2, the right child's after them
 * (the layout of a depth-first build). Recursion depth is the tree depth,
 * about log2(n / KD_LEAF) <= 28. */
static void
kd_build_node(
    kd_build* b, size_t node, size_t begin, size_t end, size_t depth, size_t next)
{
  kd_node* nd = &b->nodes[node];
  if (depth > b->max_depth)
    b->max_depth = depth;
  nd->begin = (uint32_t)begin;
  nd->end = (uint32_t)end;
  nd->child = -1;
  nd->dim = 0;
  nd->low_max = nd->high_min = 0.0;
  if (end - begin <= KD_LEAF)
    return;
  if (b->tasks && depth == KD_TASK_DEPTH) {
    b->tasks[b->num_tasks++] = (kd_task){node, begin, end, next, depth};
    return;
  }

  const dacpo_tree_point* p = b->pts;
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d)
    lo[d] = hi[d] = p[begin].x[d];
  for (size_t i = begin + 1; i < end; ++i) {
    for (int d = 0; d < 3; ++d) {
      double v = p[i].x[d];
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
  dacpo_select_points(b->pts, begin, end, mid, dim, &b->rng);
  double low_max = p[begin].x[dim];
  for (size_t i = begin + 1; i < mid; ++i)
    if (p[i].x[dim] > low_max)
      low_max = p[i].x[dim];

  nd->child = (int32_t)next;
  nd->dim = dim;
  nd->low_max = low_max;
  nd->high_min = p[mid].x[dim];
  kd_build_node(b, next, begin, mid, depth + 1, next + 2);
  kd_build_node(
      b, next + 1, mid, end, depth + 1, next + 2 + kd_subtree_nodes(mid - begin));
}

/* One subtree left by the top levels, with a pivot stream of its own. */
static dacpo_status
kd_task_run(void* user, size_t task, unsigned thread_id, dacpo_err* err)
{
  kd_build* top = (kd_build*)user;
  const kd_task* t = &top->tasks[task];
  kd_build b = {top->pts, top->nodes, {{0}}, 0, NULL, 0};
  dacpo_rng_seed(&b.rng, 0x9E3779B97F4A7C15ULL, 1 + t->node);
  kd_build_node(&b, t->node, t->begin, t->end, KD_TASK_DEPTH, t->next);
  top->tasks[task].reached = b.max_depth;
  return DACPO_OK;
}

/* The top KD_TASK_DEPTH levels here, the subtrees below them on num_threads
 * threads; *max_depth gets the tree's depth. */
static dacpo_status
kd_build_all(dacpo_kdtree* t, unsigned num_threads, size_t* max_depth, dacpo_err* err)
{
  kd_task tasks[(size_t)1 << KD_TASK_DEPTH];
  kd_build b = {t->pts, t->nodes, {{0}}, 0, tasks, 0};
  dacpo_rng_seed(&b.rng, 0x9E3779B97F4A7C15ULL, 0);
  kd_build_node(&b, 0, 0, t->n, 0, 1);
  DACPO_TRY(dacpo_parallel_for(
      b.num_tasks, num_threads, kd_task_run, &b, NULL, DACPO_STAGE_NEIGHBORS, err));
  *max_depth = b.max_depth;
  for (size_t i = 0; i < b.num_tasks; ++i)
    if (tasks[i].reached > *max_depth)
      *max_depth = tasks[i].reached;
  return DACPO_OK;
}

dacpo_status
dacpo_kdtree_build(const double* xyz, size_t n, dacpo_kdtree** out, dacpo_err* err)
{
  return dacpo_kdtree_build_threads(xyz, n, 1, out, err);
}

dacpo_status
dacpo_kdtree_build_threads(const double* xyz,
                           size_t n,
                           unsigned num_threads,
                           dacpo_kdtree** out,
                           dacpo_err* err)
{
  DACPO_CHECK(err, out != NULL, DACPO_ERR_INVALID_ARGUMENT, "kdtree: out is NULL");
  *out = NULL;
  DACPO_CHECK(
      err, n == 0 || xyz != NULL, DACPO_ERR_INVALID_ARGUMENT, "kdtree: xyz is NULL");
  DACPO_CHECK(err,
              n < (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "kdtree: %zu points exceed the int32 index range",
              n);
  for (size_t i = 0; i < 3 * n; ++i)
    DACPO_CHECK(err,
                isfinite(xyz[i]),
                DACPO_ERR_INVALID_ARGUMENT,
                "kdtree: point %zu has a non-finite coordinate",
                i / 3);

  dacpo_kdtree* t = calloc(1, sizeof(*t));
  if (!t)
    return DACPO_OOM(err);
  t->n = n;
  /* splits by count: the node count follows from n alone */
  t->num_nodes = 1 + kd_subtree_nodes(n);
  t->pts = dacpo_malloc_array(n, sizeof(dacpo_tree_point));
  t->nodes = dacpo_malloc_array(t->num_nodes, sizeof(kd_node));
  if (!t->pts || !t->nodes) {
    dacpo_kdtree_free(t);
    return DACPO_OOM(err);
  }
  dacpo_tree_points_fill(t->pts, xyz, NULL, n);

  if (n > 0) {
    size_t depth = 0;
    dacpo_status st = kd_build_all(t, num_threads, &depth, err);
    if (st == DACPO_OK && depth >= KD_MAX_DEPTH)
      st = dacpo_err_set(err,
                         DACPO_ERR_INTERNAL,
                         "kdtree: depth %zu exceeds %d",
                         depth,
                         (int)KD_MAX_DEPTH);
    if (st != DACPO_OK) {
      dacpo_kdtree_free(t);
      return st;
    }
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
  free(tree->nodes);
  free(tree);
}

/* ---- query ------------------------------------------------------------- */

/* The answer so far, in the caller's arrays: k slots pre-filled with
 * (+inf, INT32_MAX), so the k-th distance is always d[k - 1]. */
typedef struct kd_result {
  size_t k, count;
  int32_t* idx;
  double* d;
} kd_result;

/* Insertion into r (dacpo_nearest_insert): k is small (tens), so shifting
 * beats a heap and leaves the output already ordered. */
static inline void
kd_push(kd_result* r, double d, int32_t id)
{
  dacpo_nearest_insert(r->idx, r->d, r->k, &r->count, id, d);
}

/* A subtree left for later: its node and the per-axis offsets (off[d] is a
 * lower bound of |q[d] - p[d]| for every point p below the node). */
typedef struct kd_pending {
  size_t node;
  double off[3];
} kd_pending;

/* Depth-first, near child first, with an explicit stack (at most one pending
 * entry per tree level). A pending subtree is entered only if its bound, formed
 * exactly like a point's squared distance, is <= the current k-th distance;
 * rounding is monotone, so the bound never exceeds a computed point distance
 * and pruning cannot lose a tie. */
static void
kd_search(const dacpo_kdtree* t, const double q[3], kd_result* r)
{
  /* copies: r's arrays are doubles too, so q would be reloaded after pushes */
  const double q0 = q[0], q1 = q[1], q2 = q[2];
  kd_pending stack[KD_MAX_DEPTH];
  size_t top = 0;
  size_t node = 0;
  double off[3] = {0.0, 0.0, 0.0};
  for (;;) {
    const kd_node* nd = &t->nodes[node];
    if (nd->child >= 0) {
      int dim = nd->dim;
      double qd = dim == 0 ? q0 : (dim == 1 ? q1 : q2);
      double to_low = qd - nd->low_max;   /* >= 0 when q is right of the left child */
      double to_high = nd->high_min - qd; /* >= 0 when q is left of the right child */
      kd_pending* pd = &stack[top++];
      pd->off[0] = off[0];
      pd->off[1] = off[1];
      pd->off[2] = off[2];
      double far_off;
      if (to_low < to_high) {
        node = (size_t)nd->child;
        pd->node = node + 1;
        far_off = to_high;
      }
      else {
        pd->node = (size_t)nd->child;
        node = pd->node + 1;
        far_off = to_low;
      }
      if (far_off > off[dim])
        pd->off[dim] = far_off;
      continue;
    }
    const dacpo_tree_point* p = t->pts + nd->begin;
    uint32_t m = nd->end - nd->begin;
    /* distances first (a branch-free loop the compiler vectorises), then the
     * few that may enter the answer */
    double dd[KD_LEAF];
    for (uint32_t i = 0; i < m; ++i) {
      const double dx = q0 - p[i].x[0], dy = q1 - p[i].x[1], dz = q2 - p[i].x[2];
      dd[i] = dx * dx + dy * dy + dz * dz;
    }
    double worst = r->d[r->k - 1];
    for (uint32_t i = 0; i < m; ++i)
      if (dd[i] <= worst) {
        kd_push(r, dd[i], p[i].id);
        worst = r->d[r->k - 1];
      }
    /* resume at the deepest pending subtree that may still hold a closer point */
    for (;;) {
      if (top == 0)
        return;
      const kd_pending* pd = &stack[--top];
      double bound =
          pd->off[0] * pd->off[0] + pd->off[1] * pd->off[1] + pd->off[2] * pd->off[2];
      if (bound <= r->d[r->k - 1]) {
        node = pd->node;
        off[0] = pd->off[0];
        off[1] = pd->off[1];
        off[2] = pd->off[2];
        break;
      }
    }
  }
}

int32_t
dacpo_kdtree_order_at(const dacpo_kdtree* tree, size_t pos)
{
  return tree->pts[pos].id;
}

double
dacpo_kdtree_sample_area(const dacpo_kdtree* tree, const double q[3])
{
  int32_t idx[DACPO_SAMPLE_AREA_K];
  double d2[DACPO_SAMPLE_AREA_K];
  const size_t got = dacpo_kdtree_knn(tree, q, DACPO_SAMPLE_AREA_K, idx, d2);
  return got > 1 ? 3.14159265358979323846 * d2[got - 1] / (double)(got - 1) : 0.0;
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
  if (!isfinite(q[0]) || !isfinite(q[1]) || !isfinite(q[2]))
    return 0;
  if (k > tree->n)
    k = tree->n;
  for (size_t j = 0; j < k; ++j) {
    idx[j] = INT32_MAX;
    sq_dist[j] = INFINITY;
  }
  kd_result r = {k, 0, idx, sq_dist};
  kd_search(tree, q, &r);
  /* Nothing is pruned while a slot is empty (its bound is +inf), so all
   * k <= n slots are filled. */
  return r.count;
}
