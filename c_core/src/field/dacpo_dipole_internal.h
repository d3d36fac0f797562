/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 2: the per-call work of the dipole orientation (dacpo_dipole.c) and
 * the neighbour lists with cached pair energies it builds first
 * (dacpo_dipole_pairs.c). Private to them. */
#ifndef DACPO_DIPOLE_INTERNAL_H
#define DACPO_DIPOLE_INTERNAL_H

#include "dacpo_dipole.h"
#include "dacpo_kdtree.h"

#include <stddef.h>
#include <stdint.h>

/* Everything one call allocates; freed in one place. */
typedef struct dipole_work {
  int32_t* nb;         /* n*K nearest neighbours, padded with the point itself */
  double* w;           /* n*K e(p_j -> p_i) of the unflipped axes */
  double* unary;       /* n field of the thin-part side cue on i, or NULL */
  double* patch;       /* n confidence of the patch test on i, or NULL */
  double* patch_field; /* n trust in the patch test's side of i, or NULL */
  size_t* gstart;      /* n+1 CSR of the symmetrized graph_k-NN graph */
  int32_t* gnbr;       /* gstart[n] */
  int8_t* sign;        /* M*n sign vectors, 0 = not yet placed */
  int8_t* cand;        /* restarts * n: every restart's result */
  uint8_t* visited;    /* n */
  int32_t* queue;      /* n BFS queue = placement order */
  int32_t* order0;     /* n placement order of order 0 (final sweep) */
  int32_t* perm;       /* n random permutation: restart points */
  int32_t* buf;        /* max degree: shuffled neighbour row */
  int32_t* kbuf;       /* K+1 kd-tree answer */
  double* kd;          /* K+1 */
  dacpo_kdtree* tree;
  const double* xyz; /* the block's points and axes, for tree_start_field */
  const double* nrm;
  double c;
} dipole_work;

/* K nearest of every point (self dropped) into wk->nb and the cached pair
 * energies into wk->w (with the side cue's field in wk->unary when
 * params->sides > 0); builds wk->tree and wk->kbuf, wk->kd. */
dacpo_status
dacpo_dipole_neighbors(const double* xyz,
                       const double* nrm,
                       size_t n,
                       size_t K,
                       const dacpo_dipole_params* prm,
                       dipole_work* wk,
                       dacpo_err* err);

#endif
