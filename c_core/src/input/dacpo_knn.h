/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0: the k-NN graph over distinct points, from the caller's search or the
 * built-in kd-tree; its symmetrized form; connected components. */
#ifndef DACPO_KNN_H
#define DACPO_KNN_H

#include "dacpo_input.h"

/* k nearest distinct neighbours of every distinct point, nearest first, self
 * excluded; -1 / +inf pads rows with fewer than k. */
typedef struct dacpo_knn_graph {
  size_t n, k;
  int32_t* idx; /* n * k */
  float* sqd;   /* n * k squared distances */
} dacpo_knn_graph;

/* Keeps of each row only its farthest finite squared distance (+inf for a
 * row without one): g becomes one column (k = 1, idx freed). Stages after 1
 * read the neighbours' reach, not who they are (the global sign's density
 * model); the rows are the largest buffer of stages 0-1 (8 bytes per
 * neighbour and point). No allocation: the column is written into sqd's
 * first n slots, which shrink when realloc allows. */
void
dacpo_knn_graph_keep_farthest(dacpo_knn_graph* g);

/* search == NULL or search->knn == NULL: built-in kd-tree. A caller's search
 * answers in input indices; they are mapped to distinct points, the query and its
 * duplicates dropped, and asked again with a larger k when too few remain.
 * k must be < cloud->n (the pipeline clamps it). */
dacpo_status
dacpo_knn_build(const dacpo_cloud* cloud,
                size_t k,
                const dacpo_search* search,
                unsigned num_threads,
                const dacpo_progress* progress,
                dacpo_knn_graph* out,
                dacpo_err* err);

void
dacpo_knn_graph_free(dacpo_knn_graph* g);

/* Symmetric adjacency in CSR form: i ~ j if either lists the other among its
 * first k_use neighbours. Rows sorted ascending, no self, no repeats. */
typedef struct dacpo_adjacency {
  size_t n;
  size_t* start; /* n + 1 */
  int32_t* nbr;  /* start[n] */
} dacpo_adjacency;

dacpo_status
dacpo_adjacency_build(const dacpo_knn_graph* g,
                      size_t k_use,
                      dacpo_adjacency* out,
                      dacpo_err* err);

/* The same adjacency, its rows sorted on num_threads threads (0 = all cores);
 * the result does not depend on the thread count. */
dacpo_status
dacpo_adjacency_build_threads(const dacpo_knn_graph* g,
                              size_t k_use,
                              unsigned num_threads,
                              dacpo_adjacency* out,
                              dacpo_err* err);

void
dacpo_adjacency_free(dacpo_adjacency* a);

/* Connected components: label[i] in [0, *num_components), numbered in order of
 * each component's lowest point index. */
dacpo_status
dacpo_components_label(const dacpo_adjacency* a,
                       int32_t* label,
                       size_t* num_components,
                       dacpo_err* err);

#endif
