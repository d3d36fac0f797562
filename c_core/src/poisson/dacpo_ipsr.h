/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3: iPSR with a Neumann screened Poisson solver, one block at a time
 * (paper §4.3). Implemented in dacpo_ipsr.c on top of
 * dacpo_poisson.h (solver) and dacpo_mcubes.h (iso-surface). */
#ifndef DACPO_IPSR_H
#define DACPO_IPSR_H

#include "dacpo_internal.h"

/* A trimming variant kept only for a comparison test (it also cuts the film
 * across holes inside the data, which the default keeps); not reachable from
 * dacpo_params or the tools. 0 by default. */
typedef struct dacpo_ipsr_experiment {
  int trim_interior; /* 1: trim every far face, also inside the data */
} dacpo_ipsr_experiment;

typedef struct dacpo_ipsr_params {
  size_t max_iterations; /* 20 */
  double convergence;    /* 0.1: mean of the largest max(ceil(n/1000),10) |dn| */
  size_t face_k;         /* 10 nearest samples per face */
  size_t trim_start;     /* iteration from which wings are trimmed (5, 0-based) */
  size_t settle_start;   /* iteration from which one that turns over at most
                            max(ceil(n/1000),10) samples is the last (2,
                            0-based) */
  double trim_spacings;  /* faces farther than this many spacings from the data (2.5) */
  double point_weight;   /* screening alpha, PSR convention (16) */
  double cell_per_spacing; /* cell size / median spacing (1.0) */
  size_t max_resolution;   /* cap on cells per axis (128) */
  /* Grid, solver and trimming details (defaults from dacpo_ipsr_params_default;
   * 0 selects the default for the first four): */
  double padding;   /* band 0 only: box grows by this share of its longest side (0.1) */
  size_t max_cells; /* cap on grid cells, bounds memory (1.5e6: <= 41 MB) */
  double tolerance; /* Poisson solve: relative residual (3e-2; the warm-started
                       loop refines chi across iterations) */
  size_t max_cg_iterations; /* Poisson solve: multigrid-CG steps (30) */
  size_t band;              /* Poisson domain: cells within this many cells of the
                               samples (>= 2); 0 = the whole padded box (2) */
  const uint8_t* fixed;     /* NULL, or n flags: samples whose normals the
                               iterations leave as given (parts thinner than
                               the grid, see dacpo_pipeline.c) (NULL) */
  dacpo_ipsr_experiment experiment; /* off (above) */
} dacpo_ipsr_params;

void
dacpo_ipsr_params_default(dacpo_ipsr_params* p);

typedef struct dacpo_ipsr_stats {
  size_t iterations;
  size_t resolution; /* cells per axis used */
  double seconds;
  size_t peak_bytes;
  /* Grid and timing details: */
  double spacing;         /* sample spacing (sqrt of the median area per sample) */
  double cell;            /* grid cell edge */
  size_t dims[3];         /* grid cells per axis */
  size_t cg_iterations;   /* summed over iterations */
  double solve_seconds;   /* Poisson solves */
  double extract_seconds; /* marching cubes */
  double vote_seconds;    /* face k-NN, trimming, normal update */
  size_t faces;           /* faces of the last iteration's mesh */
  size_t faces_total;     /* faces queried and voted, summed over iterations */
  size_t surfaces_reused; /* iterations whose solve left the surface as it was */
  double final_change;    /* last convergence measure */
  int converged;          /* 1 if it stopped on the convergence test or on an
                             iteration (from settle_start on) that turned
                             over few samples */
  size_t domain_cells;    /* cells the Poisson solve works on (<= dims product) */
} dacpo_ipsr_stats;

/* Refines the oriented normals nrm (3n, in/out) of a block's n samples; the
 * first n_own are the block's own points, the rest its ring. If mesh_out is
 * not NULL it receives the final trimmed mesh restricted to the own points,
 * wound to agree with the normals (caller frees it with dacpo_mesh_free; it is
 * zeroed first, and left empty on error or when no face remains).
 * max_iterations 0 leaves the normals alone but still builds mesh_out.
 * Blocks of fewer than 4 samples are left untouched (DACPO_OK, 0 iterations).
 * Errors: INVALID_ARGUMENT (NULL, n_own > n, a bad parameter: the message
 * names it), NONFINITE_INPUT (first bad sample's index), OUT_OF_MEMORY.
 * Reentrant: no shared state, callable from several threads at once. */
dacpo_status
dacpo_ipsr_block(const double* xyz,
                 double* nrm,
                 size_t n,
                 size_t n_own,
                 const dacpo_ipsr_params* params,
                 dacpo_mesh* mesh_out,
                 dacpo_ipsr_stats* stats,
                 dacpo_err* err);

#endif
