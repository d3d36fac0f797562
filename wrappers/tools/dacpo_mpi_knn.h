/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0's neighbour search spread over the ranks of pcl_dacpo_orient_mpi.
 *
 * Rank 0 cuts the cloud into one slab per rank along its longest axis (cuts at
 * the quantiles of a sample of that coordinate) and sends every rank its slab
 * with a halo around it; each rank runs dacpo_region_knn() (dacpo_advanced.h)
 * and sends back the rows of its slab's points. A row whose ball through its
 * k-th neighbour reaches past the halo is asked again with a halo four times
 * as wide, until none is left; the joined rows are then exactly the whole
 * cloud's k nearest (ties to the lower input index, as the built-in search),
 * and rank 0 serves them to dacpo_job_create() as a dacpo_search.
 *
 * Cost on rank 0: two passes over the cloud per rank and round to cut the
 * regions (a sort by the split coordinate would make it one for all ranks:
 * worth it past tens of ranks), and the gathered rows, n x width int32, held
 * until the job has its graph. Measured (10M points, 2 ranks on 2 cores):
 * slower than rank 0's own 2-thread search (60 s against 42 s for read and
 * stages 0-1), hence an option of the tool (-spread_knn). */
#ifndef DACPO_MPI_KNN_H
#define DACPO_MPI_KNN_H

#include "dacpo_mpi_comm.h"

#include <stddef.h>
#include <stdint.h>

/* Rank 0's joined rows: width input indices per point, nearest first (the
 * point itself or an exact duplicate first). */
typedef struct dacpo_knn_table {
  size_t n, width;
  int32_t* ids;     /* n * width */
  const float* xyz; /* the cloud (not owned) */
  size_t rounds;    /* halo widths tried */
} dacpo_knn_table;

/* Every rank calls it; xyz, n, width, first_halo matter on rank 0 only
 * (width: the nearest wanted per point, the point itself counted; first_halo:
 * the first halo's width in the cloud's units, <= 0: from the cloud's box and
 * size). On rank 0, *table gets
 * the rows (free with dacpo_knn_table_free). busy: seconds in this rank's own
 * searches. Returns 1 on success on every rank, 0 (message on stderr) if any
 * rank failed. */
int
dacpo_mpi_knn(const float* xyz,
              size_t n,
              size_t width,
              int rank,
              int ranks,
              double first_halo,
              dacpo_knn_table* table,
              double* busy,
              dacpo_mpi_traffic* traffic);

/* dacpo_knn_fn over the table (user = the table): a query for more than its
 * width fails (non-zero), and the caller falls back to the built-in search. */
int
dacpo_knn_table_search(void* user,
                       size_t query,
                       size_t k,
                       int32_t* indices,
                       float* sq_distances,
                       size_t* found);

void
dacpo_knn_table_free(dacpo_knn_table* table);

#endif
