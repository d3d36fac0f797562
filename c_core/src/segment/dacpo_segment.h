/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 1: block segmentation (paper §4.1). */
#ifndef DACPO_SEGMENT_H
#define DACPO_SEGMENT_H

#include "dacpo_knn.h"

typedef struct dacpo_blocks {
  size_t num_blocks;
  int32_t* block_of;           /* n: block of each distinct point */
  int32_t* component_of_block; /* num_blocks */
  size_t* own_start;           /* num_blocks + 1 */
  int32_t* own;       /* n: points of block b at own[own_start[b] ..], ascending */
  size_t* ring_start; /* num_blocks + 1 */
  int32_t* ring;      /* ring points of block b (owned by other blocks), ascending */
} dacpo_blocks;

/* Splits each component kd-style (median split on the widest axis) into about
 * target_blocks * |component| / n subsets of equal count (at least 1), takes the
 * point nearest each subset's centroid as seed, and grows all blocks at once by
 * multi-source BFS over adj: every block is connected in adj. The ring of a block
 * is every point of another block within ring_hops hops of it. Block ids are
 * numbered component by component. target_blocks 0 gives one block per
 * non-empty component (the paper's "no segmentation" ablation). */
dacpo_status
dacpo_segment(const dacpo_cloud* cloud,
              const dacpo_adjacency* adj,
              const int32_t* component,
              size_t num_components,
              size_t target_blocks,
              size_t ring_hops,
              dacpo_blocks* out,
              dacpo_err* err);

/* The same with the block fronts advancing by shortest paths in which a step
 * from p to q costs 1 + 20 (1 - |a_p . a_q|) hops (a_p: crease_axes[3p..],
 * unit; see dacpo_crease_axes()), so block borders settle on creases. Each
 * block is still connected in adj. crease_axes NULL is dacpo_segment().
 * O(E log n). */
dacpo_status
dacpo_segment_creased(const dacpo_cloud* cloud,
                      const dacpo_adjacency* adj,
                      const double* crease_axes,
                      const int32_t* component,
                      size_t num_components,
                      size_t target_blocks,
                      size_t ring_hops,
                      dacpo_blocks* out,
                      dacpo_err* err);

/* NULL-safe; frees every array and zeroes the struct. */
void
dacpo_blocks_free(dacpo_blocks* b);

#endif
