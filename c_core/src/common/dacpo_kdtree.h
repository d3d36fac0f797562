/* SPDX-License-Identifier: BSD-3-Clause */
/* Built-in kd-tree: exact k nearest neighbours in 3-D (used when the caller
 * gives no search, and inside stages on block-local point sets). */
#ifndef DACPO_KDTREE_H
#define DACPO_KDTREE_H

#include "dacpo_internal.h"

typedef struct dacpo_kdtree dacpo_kdtree;

/* Builds over n points (3n doubles, copied). n may be 0. */
dacpo_status
dacpo_kdtree_build(const double* xyz, size_t n, dacpo_kdtree** out, dacpo_err* err);

/* The same tree, its lower levels built on num_threads threads (0 = all
 * cores); the tree does not depend on the thread count. */
dacpo_status
dacpo_kdtree_build_threads(const double* xyz,
                           size_t n,
                           unsigned num_threads,
                           dacpo_kdtree** out,
                           dacpo_err* err);

void
dacpo_kdtree_free(dacpo_kdtree* tree);

/* Sorted insertion of (dist, id) into an answer of capacity k holding *count
 * entries, ordered by (squared distance, index) as every nearest-neighbour
 * answer of the core is; a candidate beyond a full answer is dropped. */
static inline void
dacpo_nearest_insert(
    int32_t* idx, double* d, size_t k, size_t* count, int32_t id, double dist)
{
  size_t pos;
  if (*count == k) {
    if (dist > d[k - 1] || (dist == d[k - 1] && id > idx[k - 1]))
      return;
    pos = k - 1;
  }
  else {
    pos = (*count)++;
  }
  while (pos > 0 && (d[pos - 1] > dist || (d[pos - 1] == dist && idx[pos - 1] > id))) {
    d[pos] = d[pos - 1];
    idx[pos] = idx[pos - 1];
    --pos;
  }
  d[pos] = dist;
  idx[pos] = id;
}

/* Up to k nearest points of q, nearest first (ties: lower index first); writes
 * indices and squared distances, returns how many were written (min(k, n)).
 * Read-only on the tree: safe to call from several threads at once. */
size_t
dacpo_kdtree_knn(const dacpo_kdtree* tree,
                 const double q[3],
                 size_t k,
                 int32_t* idx,
                 double* sq_dist);

/* The index of the point at tree position pos (0 <= pos < n): positions run
 * leaf by leaf, so consecutive ones are close in space. Querying in this order
 * keeps the tree's nodes and points in cache (about 1.7x faster than a random
 * order). */
int32_t
dacpo_kdtree_order_at(const dacpo_kdtree* tree, size_t pos);

/* Nearest points (q's own point among them) behind one sample's area. */
#define DACPO_SAMPLE_AREA_K 9

/* The surface area one sample covers: pi r^2 / (m - 1), r the distance to the
 * farthest of the up to DACPO_SAMPLE_AREA_K nearest points of q and m how many
 * were found; 0 when m < 2. sqrt of the median over a cloud is its spacing
 * (stage 3 per block, the scene mesh over the scene). */
double
dacpo_kdtree_sample_area(const dacpo_kdtree* tree, const double q[3]);

#endif
