/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3b's face queries: the k nearest samples of many query points that
 * fall in the cells of one fixed grid (iPSR's face centres, every iteration
 * of a block), answered exactly from candidate lists kept per grid cell.
 *
 * A cell's list is the K nearest samples of its centre a (one kd-tree query,
 * the first time a query falls in the cell). For a query q in the cell with
 * delta = |q - a|, every sample left out lies at least r_K from a, hence at
 * least r_K - delta from q (triangle inequality); so when the k-th nearest
 * candidate of q is closer than r_K - delta (with a relative margin far above
 * rounding), the candidates hold q's exact k nearest. Otherwise, and where
 * memory for a list cannot be had, the query goes to the kd-tree. The answer
 * is always the kd-tree's: the same indices in the same order (distance, then
 * index) and the same squared distances, computed the same way. */
#ifndef DACPO_CELL_KNN_H
#define DACPO_CELL_KNN_H

#include "dacpo_internal.h"
#include "dacpo_kdtree.h"
#include "dacpo_poisson.h"

typedef struct dacpo_cell_knn dacpo_cell_knn;

/* For k nearest (1 <= k <= 64) among the tree's n points xyz (the tree's own
 * coordinates), over the cells of grid. Each list holds the 2k + 4 nearest of
 * its cell's centre: with cells about one sample spacing wide and k = 10, the
 * 24 nearest of the centre reach past the 10 nearest of any point in the cell
 * on a surface sampled about once per spacing. Borrows tree and xyz; copies
 * grid. Errors: INVALID_ARGUMENT, OUT_OF_MEMORY. */
dacpo_status
dacpo_cell_knn_create(const dacpo_kdtree* tree,
                      const double* xyz,
                      size_t n,
                      const dacpo_grid* grid,
                      size_t k,
                      dacpo_cell_knn** out,
                      dacpo_err* err);

void
dacpo_cell_knn_free(dacpo_cell_knn* c);

/* Same contract and answer as dacpo_kdtree_knn(tree, q, k, idx, sq_dist);
 * not thread-safe (it fills the cell lists). */
size_t
dacpo_cell_knn_query(dacpo_cell_knn* c,
                     const double q[3],
                     int32_t* idx,
                     double* sq_dist);

/* Bytes held (the cell map and the lists). */
size_t
dacpo_cell_knn_bytes(const dacpo_cell_knn* c);

/* Queries answered from a list, and sent to the kd-tree. */
void
dacpo_cell_knn_counts(const dacpo_cell_knn* c, size_t* listed, size_t* tree);

#endif
