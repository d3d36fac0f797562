/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0 split in space: the k-NN rows of one region of a cloud (its own
 * points) searched among the region's points and a halo around them, for
 * callers that spread the neighbour search over processes
 * (dacpo_advanced.h: dacpo_region_knn; pcl_dacpo_orient_mpi).
 *
 * Why the rows join into the whole cloud's search exactly: the built-in
 * kd-tree answers by (squared distance, index), so a region whose points come
 * in the order of the caller's global numbering breaks ties as the whole-cloud
 * search does; and a row is complete when the ball through its k-th neighbour
 * lies inside the box in which the region holds every point of the cloud
 * (the own slab widened by the halo), since then no point outside the region
 * can be nearer. Incomplete rows are reported, not guessed: the caller widens
 * the halo and asks again.
 *
 * Cost: one kd-tree over the n region points, one k-NN query per own point.
 */
#include <dacpo/dacpo_advanced.h>

#include "dacpo_block_unit.h"
#include "dacpo_kdtree.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static dacpo_status
region_knn(const float* xyz,
           const uint8_t* own,
           size_t n,
           size_t k,
           const double box_lo[3],
           const double box_hi[3],
           int32_t* nbr,
           float* sqd,
           uint8_t* complete,
           dacpo_err* err)
{
  DACPO_CHECK(err,
              xyz && own && nbr && complete && box_lo && box_hi && k > 0,
              DACPO_ERR_INVALID_ARGUMENT,
              "region k-NN: NULL array or k = 0");
  DACPO_CHECK(err,
              n <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "region k-NN: %zu points exceed the int32 index range",
              n);
  double* p = dacpo_malloc_array(3 * (n ? n : 1), sizeof(double));
  int32_t* idx = dacpo_malloc_array(k, sizeof(int32_t));
  double* d2 = dacpo_malloc_array(k, sizeof(double));
  dacpo_kdtree* tree = NULL;
  dacpo_status st = DACPO_OK;
  if (!p || !idx || !d2)
    st = DACPO_OOM(err);
  for (size_t i = 0; st == DACPO_OK && i < 3 * n; ++i) {
    p[i] = (double)xyz[i];
    if (!isfinite(p[i]))
      st = dacpo_err_set(err,
                         DACPO_ERR_NONFINITE_INPUT,
                         "region k-NN: point %zu has a non-finite coordinate",
                         i / 3);
  }
  if (st == DACPO_OK)
    st = dacpo_kdtree_build(p, n, &tree, err);
  size_t row = 0;
  for (size_t i = 0; st == DACPO_OK && i < n; ++i) {
    if (!own[i])
      continue;
    const size_t found = dacpo_kdtree_knn(tree, p + 3 * i, k, idx, d2);
    int32_t* r = nbr + row * k;
    float* s = sqd ? sqd + row * k : NULL;
    for (size_t t = 0; t < k; ++t) {
      r[t] = t < found ? idx[t] : -1;
      if (s)
        s[t] = t < found ? (float)d2[t] : INFINITY;
    }
    /* the ball through the k-th neighbour (all of space if there are fewer
     * than k points) must lie inside the box the region covers completely */
    const double reach = found == k ? sqrt(d2[k - 1]) : INFINITY;
    int inside = 1;
    for (int a = 0; a < 3; ++a)
      inside &= p[3 * i + a] - reach >= box_lo[a] && p[3 * i + a] + reach <= box_hi[a];
    complete[row++] = (uint8_t)inside;
  }
  dacpo_kdtree_free(tree);
  free(p);
  free(idx);
  free(d2);
  return st;
}

dacpo_status
dacpo_region_knn(const float* xyz,
                 const uint8_t* own,
                 size_t n,
                 size_t k,
                 const double box_lo[3],
                 const double box_hi[3],
                 int32_t* nbr,
                 float* sqd,
                 uint8_t* complete,
                 char* msg,
                 size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  region_knn(xyz, own, n, k, box_lo, box_hi, nbr, sqd, complete, &err);
  return dacpo_unit_message(&err, msg, msg_size);
}
