/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 5: the 0-1 block-flip program (paper §5.2, Eq. 8) with lp_solve. */
#ifndef DACPO_ILP_H
#define DACPO_ILP_H

#include "dacpo_internal.h"

typedef struct dacpo_ilp_edge {
  int32_t a, b;
  double w_same; /* omega(0,0) of Eq. 7 */
  double w_diff; /* omega(0,1) */
} dacpo_ilp_edge;

typedef struct dacpo_ilp_result {
  int optimal;           /* 1 if every component was proven optimal */
  double objective;      /* sum of omega at the returned flips */
  size_t constraints;    /* rows given to lp_solve */
  size_t cuts_added;     /* odd-cycle cuts added beyond the triangles */
  size_t heuristic_wins; /* components where the heuristic incumbent was kept */
  double seconds;
} dacpo_ilp_result;

/* Maximizes sum_e omega_e(o_a, o_b) over o in {0,1}^num_nodes, solving every
 * connected component of the edge graph separately with its lowest node fixed
 * to 0 (isolated nodes get 0). With y_e = o_a XOR o_b (four inequalities per
 * edge) and the triangle inequalities of every 3-cycle. A heuristic incumbent
 * (maximum-confidence spanning tree + local search) is always computed; if
 * lp_solve times out, the better of its best answer and the incumbent is used
 * and optimal = 0. The progress callback is wired to lp_solve's abort hook. */
dacpo_status
dacpo_ilp_solve(size_t num_nodes,
                size_t num_edges,
                const dacpo_ilp_edge* edges,
                double time_limit,
                const dacpo_progress* progress,
                uint8_t* flip_out,
                dacpo_ilp_result* result,
                dacpo_err* err);

#endif
