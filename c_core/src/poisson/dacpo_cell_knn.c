/* SPDX-License-Identifier: BSD-3-Clause */
/* Exact k nearest samples from per-cell candidate lists (see the header).
 * iPSR asks for the nearest samples of every face centre in every iteration;
 * the samples stay put and the surface moves little, so each cell's list,
 * found once, answers the cell's faces in all later iterations. */
#include "dacpo_cell_knn.h"

#include "dacpo_select.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct dacpo_cell_knn {
  const dacpo_kdtree* tree;
  const double* xyz;
  size_t n, k;
  size_t cand_k; /* candidates per list, 2k + 4 */
  dacpo_grid grid;
  int32_t* slot_of; /* per grid cell: its list, -1 until a query falls there */
  size_t num_cells;
  dacpo_tree_point* cand; /* cand_k per list */
  double* reach;          /* per list: r_K, or +inf when it holds every sample */
  uint8_t* count;         /* per list: candidates held */
  size_t num_lists, cap_lists;
  size_t listed, to_tree;
  int32_t* scratch_idx; /* cand_k: a new list's kd-tree answer */
  double* scratch_d2;
};

dacpo_status
dacpo_cell_knn_create(const dacpo_kdtree* tree,
                      const double* xyz,
                      size_t n,
                      const dacpo_grid* grid,
                      size_t k,
                      dacpo_cell_knn** out,
                      dacpo_err* err)
{
  if (out)
    *out = NULL;
  DACPO_CHECK(err,
              out && tree && grid && (n == 0 || xyz) && k >= 1 && k <= 64,
              DACPO_ERR_INVALID_ARGUMENT,
              "cell_knn: bad arguments (k = %zu, at most 64)",
              k);
  size_t cells = grid->dims[0] * grid->dims[1] * grid->dims[2];
  DACPO_CHECK(err,
              cells > 0 && grid->cell > 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "cell_knn: empty grid");
  dacpo_cell_knn* c = calloc(1, sizeof(*c));
  if (!c)
    return DACPO_OOM(err);
  c->cand_k = 2 * k + 4;
  c->slot_of = (int32_t*)dacpo_malloc_array(cells, sizeof(int32_t));
  c->scratch_idx = (int32_t*)dacpo_malloc_array(c->cand_k, sizeof(int32_t));
  c->scratch_d2 = (double*)dacpo_malloc_array(c->cand_k, sizeof(double));
  if (!c->slot_of || !c->scratch_idx || !c->scratch_d2) {
    dacpo_cell_knn_free(c);
    return DACPO_OOM(err);
  }
  memset(c->slot_of, 0xff, cells * sizeof(int32_t)); /* -1 */
  c->tree = tree, c->xyz = xyz, c->n = n, c->k = k;
  c->grid = *grid;
  c->num_cells = cells;
  *out = c;
  return DACPO_OK;
}

void
dacpo_cell_knn_free(dacpo_cell_knn* c)
{
  if (!c)
    return;
  free(c->slot_of);
  free(c->cand);
  free(c->reach);
  free(c->count);
  free(c->scratch_idx);
  free(c->scratch_d2);
  free(c);
}

size_t
dacpo_cell_knn_bytes(const dacpo_cell_knn* c)
{
  return c ? c->num_cells * sizeof(int32_t) +
                 c->cap_lists *
                     (c->cand_k * sizeof(dacpo_tree_point) + sizeof(double) + 1) +
                 c->cand_k * (sizeof(int32_t) + sizeof(double))
           : 0;
}

void
dacpo_cell_knn_counts(const dacpo_cell_knn* c, size_t* listed, size_t* tree)
{
  *listed = c ? c->listed : 0;
  *tree = c ? c->to_tree : 0;
}

/* Room for one more list; 0 if memory ran out (the caller uses the tree). */
static int
grow_lists(dacpo_cell_knn* c)
{
  if (c->num_lists < c->cap_lists)
    return 1;
  size_t cap = c->cap_lists ? 2 * c->cap_lists : 256;
  dacpo_tree_point* cand =
      (dacpo_tree_point*)dacpo_malloc_array(cap * c->cand_k, sizeof(dacpo_tree_point));
  if (!cand)
    return 0;
  if (c->num_lists)
    memcpy(cand, c->cand, c->num_lists * c->cand_k * sizeof(dacpo_tree_point));
  free(c->cand);
  c->cand = cand;
  double* reach = realloc(c->reach, cap * sizeof(double));
  if (!reach)
    return 0;
  c->reach = reach;
  uint8_t* count = realloc(c->count, cap);
  if (!count)
    return 0;
  c->count = count;
  c->cap_lists = cap;
  return 1;
}

/* The list of the cell holding q (found now if q is the cell's first query),
 * and the cell's centre; -1 if no list could be made. */
static int32_t
list_of(dacpo_cell_knn* c, const double q[3], double centre[3])
{
  size_t at[3];
  for (int a = 0; a < 3; ++a) {
    double f = floor((q[a] - c->grid.origin[a]) / c->grid.cell);
    double top = (double)(c->grid.dims[a] - 1);
    f = f < 0.0 ? 0.0 : (f > top ? top : f);
    at[a] = (size_t)f;
    centre[a] = c->grid.origin[a] + (f + 0.5) * c->grid.cell;
  }
  size_t cell = (at[2] * c->grid.dims[1] + at[1]) * c->grid.dims[0] + at[0];
  if (c->slot_of[cell] >= 0)
    return c->slot_of[cell];
  if (c->num_lists >= (size_t)INT32_MAX || !grow_lists(c))
    return -1;
  const size_t want = c->cand_k;
  int32_t* idx = c->scratch_idx;
  double* d2 = c->scratch_d2;
  size_t got = dacpo_kdtree_knn(c->tree, centre, want, idx, d2);
  size_t s = c->num_lists++;
  dacpo_tree_point* p = c->cand + s * want;
  for (size_t j = 0; j < got; ++j) {
    memcpy(p[j].x, c->xyz + 3 * (size_t)idx[j], 3 * sizeof(double));
    p[j].id = idx[j];
    p[j].pad = 0;
  }
  c->count[s] = (uint8_t)got;
  c->reach[s] = got < want || got == c->n ? INFINITY : sqrt(d2[got - 1]);
  c->slot_of[cell] = (int32_t)s;
  return (int32_t)s;
}

/* The k nearest of q among one list, sorted by (squared distance, index) as
 * the kd-tree sorts them; returns how many (min(k, count)). dd: count
 * scratch. Distances first (a loop without branches), then the few that
 * may enter the answer. */
static size_t
nearest_in_list(const dacpo_tree_point* p,
                size_t count,
                size_t k,
                const double q[3],
                double* dd,
                int32_t* idx,
                double* d2)
{
  const double q0 = q[0], q1 = q[1], q2 = q[2];
  for (size_t i = 0; i < count; ++i) {
    const double dx = q0 - p[i].x[0], dy = q1 - p[i].x[1], dz = q2 - p[i].x[2];
    dd[i] = dx * dx + dy * dy + dz * dz;
  }
  size_t have = 0;
  for (size_t i = 0; i < count; ++i)
    dacpo_nearest_insert(idx, d2, k, &have, p[i].id, dd[i]);
  return have;
}

size_t
dacpo_cell_knn_query(dacpo_cell_knn* c,
                     const double q[3],
                     int32_t* idx,
                     double* sq_dist)
{
  if (!c || !q || c->n == 0)
    return 0;
  if (isfinite(q[0]) && isfinite(q[1]) && isfinite(q[2])) {
    double a[3];
    int32_t s = list_of(c, q, a);
    if (s >= 0) {
      size_t got = nearest_in_list(c->cand + (size_t)s * c->cand_k,
                                   c->count[s],
                                   c->k,
                                   q,
                                   c->scratch_d2,
                                   idx,
                                   sq_dist);
      const double dx = q[0] - a[0], dy = q[1] - a[1], dz = q[2] - a[2];
      const double delta = sqrt(dx * dx + dy * dy + dz * dz);
      /* margin 1e-9: far above the rounding of the distances, so a sample
       * left out cannot tie with the k-th */
      if (got > 0 && (sqrt(sq_dist[got - 1]) + delta) * (1.0 + 1e-9) <
                         c->reach[s] * (1.0 - 1e-9)) {
        c->listed++;
        return got;
      }
    }
  }
  c->to_tree++;
  return dacpo_kdtree_knn(c->tree, q, c->k, idx, sq_dist);
}
