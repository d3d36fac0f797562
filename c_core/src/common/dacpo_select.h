/* SPDX-License-Identifier: BSD-3-Clause */
/* Points with their index, and a quickselect over them by one coordinate:
 * shared by the kd-tree build (dacpo_kdtree.c), the block split of stage 1
 * (dacpo_segment.c) and the bridge's tree (dacpo_bridge.c). Coordinates and
 * index travel together, so selections and scans read memory sequentially.
 * Keys are (coordinate, index) pairs, all distinct, so grids with many equal
 * coordinates split by count and never degrade. Header-only, not installed. */
#ifndef DACPO_SELECT_H
#define DACPO_SELECT_H

#include "dacpo_rng.h"

#include <string.h>

typedef struct dacpo_tree_point {
  double x[3];
  int32_t id; /* index of the point in the caller's cloud */
  int32_t pad;
} dacpo_tree_point;

/* p[i] = point ids[i] of xyz (3 doubles per point); ids NULL: point i. */
static inline void
dacpo_tree_points_fill(dacpo_tree_point* p,
                       const double* xyz,
                       const int32_t* ids,
                       size_t n)
{
  for (size_t i = 0; i < n; ++i) {
    const int32_t id = ids ? ids[i] : (int32_t)i;
    memcpy(p[i].x, xyz + 3 * (size_t)id, 3 * sizeof(double));
    p[i].id = id;
    p[i].pad = 0;
  }
}

/* Strict order by coordinate `axis`, ties by index. */
static inline int
dacpo_tree_point_less(const dacpo_tree_point* a, const dacpo_tree_point* b, int axis)
{
  return a->x[axis] < b->x[axis] || (a->x[axis] == b->x[axis] && a->id < b->id);
}

static inline void
dacpo_tree_point_swap(dacpo_tree_point* a, dacpo_tree_point* b)
{
  const dacpo_tree_point t = *a;
  *a = *b;
  *b = t;
}

/* Rearranges p[lo, hi) so that p[kth] is the point of rank kth there, the
 * smaller ones before it and the larger ones after it. One pivot drawn from
 * rng per round (Lomuto partition): expected O(hi - lo). */
static inline void
dacpo_select_points(
    dacpo_tree_point* p, size_t lo, size_t hi, size_t kth, int axis, dacpo_rng* rng)
{
  while (hi - lo > 1) {
    dacpo_tree_point_swap(&p[lo + dacpo_rng_below(rng, hi - lo)], &p[hi - 1]);
    const dacpo_tree_point* pivot = &p[hi - 1];
    size_t store = lo;
    for (size_t i = lo; i + 1 < hi; ++i)
      if (dacpo_tree_point_less(&p[i], pivot, axis))
        dacpo_tree_point_swap(&p[i], &p[store++]);
    dacpo_tree_point_swap(&p[store], &p[hi - 1]);
    if (store == kth)
      return;
    if (kth < store)
      hi = store;
    else
      lo = store + 1;
  }
}

#endif /* DACPO_SELECT_H */
