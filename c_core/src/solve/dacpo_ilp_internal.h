/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Private to the three files of stage 5 (dacpo_ilp.c, dacpo_ilp_graph.c,
 * dacpo_ilp_heuristic.c): the merged block graph they share and the functions
 * one calls in another. Nothing here includes lp_lib.h, so the graph and the
 * heuristic stay free of lp_solve's macros (TRUE, FALSE, LE, GE, ...).
 */
#ifndef DACPO_ILP_INTERNAL_H
#define DACPO_ILP_INTERNAL_H

#include "dacpo_ilp.h"

/* The edge graph of Eq. 8: parallel edges merged, self loops dropped, split
 * into connected components. */
typedef struct dacpo_ilp_graph {
  size_t n; /* nodes */
  size_t m; /* merged edges, ea < eb */
  int32_t* ea;
  int32_t* eb;
  double* c;         /* w_diff - w_same: what cutting the edge (y_e = 1) gains */
  size_t* adj_start; /* n + 1 */
  int32_t* adj_node; /* 2m, ascending within each node */
  int32_t* adj_edge; /* 2m, merged edge of each adjacency entry */
  int32_t* comp;     /* component of each node */
  size_t ncomp;
  size_t* comp_start;  /* ncomp + 1, into comp_nodes */
  int32_t* comp_nodes; /* ascending within a component: the lowest comes first */
  size_t* cedge_start; /* ncomp + 1, into cedges */
  int32_t* cedges;     /* merged edges grouped by component, ascending */
} dacpo_ilp_graph;

/* Builds g from the caller's edges (already checked: ends in [0, n)). On
 * failure g is left freed. */
dacpo_status
dacpo_ilp_graph_build(size_t n,
                      size_t num_edges,
                      const dacpo_ilp_edge* edges,
                      dacpo_ilp_graph* g,
                      dacpo_err* err);

/* Frees every array of g and zeroes it (safe on a zeroed graph). */
void
dacpo_ilp_graph_free(dacpo_ilp_graph* g);

/* sum over a component's edges of c_e y_e (Eq. 8 without its constant) */
double
dacpo_ilp_comp_value(const dacpo_ilp_graph* g, size_t ci, const uint8_t* o);

/* The heuristic incumbent for the whole graph: a maximum-confidence spanning
 * tree with local search, then random-tree restarts until stop_time. o (n
 * entries) gets the best per component; each component's lowest node is 0. */
dacpo_status
dacpo_ilp_heuristic(const dacpo_ilp_graph* g,
                    double stop_time,
                    uint8_t* o,
                    dacpo_err* err);

#endif
