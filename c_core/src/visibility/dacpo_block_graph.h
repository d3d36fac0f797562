/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 4a: the block adjacency graph and the dipole-boundary edge weight. */
#ifndef DACPO_BLOCK_GRAPH_H
#define DACPO_BLOCK_GRAPH_H

#include "dacpo_segment.h"

typedef struct dacpo_block_edge {
  int32_t a, b;     /* a < b */
  size_t crossing;  /* adjacency pairs joining a and b */
  double alpha;     /* evidence for "same orientation" as the blocks are */
  double alpha_bar; /* evidence for "one block flipped" */
} dacpo_block_edge;

typedef struct dacpo_block_graph {
  size_t num_edges;
  dacpo_block_edge* edges; /* sorted by (a, b) */
} dacpo_block_graph;

/* Blocks a and b are adjacent if an edge of adj joins them. */
dacpo_status
dacpo_block_graph_build(const dacpo_blocks* blocks,
                        const dacpo_adjacency* adj,
                        dacpo_block_graph* out,
                        dacpo_err* err);

void
dacpo_block_graph_free(dacpo_block_graph* g);

/* Index of the edge joining blocks a and b (either order) by binary search,
 * or -1 when they are not adjacent. */
ptrdiff_t
dacpo_block_graph_find(const dacpo_block_graph* g, int32_t a, int32_t b);

/* Dipole-boundary weight: for every adjacency pair (p in a, q in b),
 * s = e((p,n_p),(q,n_q)) + e((q,n_q),(p,n_p)) with the current oriented normals
 * (Eq. 2); alpha sums max(s, 0), alpha_bar sums max(-s, 0) (flipping b negates
 * s, so the two are the evidence for "same" and "differ"). */
dacpo_status
dacpo_block_graph_dipole_weights(dacpo_block_graph* g,
                                 const dacpo_cloud* cloud,
                                 const dacpo_adjacency* adj,
                                 const dacpo_blocks* blocks,
                                 const double* oriented_nrm,
                                 double c,
                                 dacpo_err* err);

/* Overlap-agreement weight: block a was oriented together with its ring, whose
 * points belong to neighbouring blocks; where a's ring normal at a point q of
 * block b meets b's own normal at q, d = n_a(q) . n_b(q) votes "same"
 * (alpha += max(d, 0)) or "differ" (alpha_bar += max(-d, 0)). ring_nrm holds,
 * for block a, the oriented normals of blocks->ring[ring_start[a] ..] (3 per
 * ring entry); own_nrm the block-own normals of every point (3n). Ring points of
 * blocks that are not adjacent to a in g are skipped. */
dacpo_status
dacpo_block_graph_overlap_weights(dacpo_block_graph* g,
                                  const dacpo_blocks* blocks,
                                  const double* own_nrm,
                                  const double* ring_nrm,
                                  dacpo_err* err);

/* Paper Eq. 7 with the amount of evidence kept: w_same = g alpha/(alpha +
 * alpha_bar), w_diff = g alpha_bar/(alpha + alpha_bar), g = a/(1+a) with
 * a = (alpha + alpha_bar)/scale; scale <= 0 gives g = 1 (Eq. 7 as printed).
 * (0, 0) without evidence. NULL outputs are skipped. */
void
dacpo_edge_omega(
    double alpha, double alpha_bar, double scale, double* w_same, double* w_diff);

/* The typical evidence of an edge: the median of alpha + alpha_bar over the
 * edges that have any (0 when none has, or on allocation failure). */
double
dacpo_edge_evidence_scale(const dacpo_block_graph* g);

/* Two measures of the same edges as one: g's evidence becomes
 *   alpha = alpha_g / s_g + weight x alpha_o / s_o   (alpha_bar alike),
 * s the measure's typical edge evidence (dacpo_edge_evidence_scale), so each
 * counts in units of its own typical edge. A measure without evidence (s = 0)
 * adds nothing. other must list the same edges in the same order
 * (INVALID_ARGUMENT otherwise); weight must be finite and >= 0. */
dacpo_status
dacpo_block_graph_blend(dacpo_block_graph* g,
                        const dacpo_block_graph* other,
                        double weight,
                        dacpo_err* err);

#endif
