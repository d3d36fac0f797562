/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 6: the global sign (which of the two consistent orientations the
 * caller gets): towards a given viewpoint, or towards the free space the
 * scene was observed from. */
#ifndef DACPO_GLOBAL_SIGN_H
#define DACPO_GLOBAL_SIGN_H

#include "dacpo_internal.h"

typedef struct dacpo_global_sign_result {
  int flip;            /* 1: multiply every normal by -1 */
  double facing;       /* share of the points facing the viewpoint after the flip
                          (away from it when enclosed) */
  int enclosed;        /* 1: the viewpoint found lies inside a closed surface */
  double viewpoint[3]; /* the one used (given or inferred) */
} dacpo_global_sign_result;

/* xyz, nrm: n points with consistently oriented normals (3n each).
 * viewpoint: NULL to infer one, else normals are made to face it (majority of
 * all points). knn_sqd (may be NULL): per point, knn_k squared neighbour
 * distances (the k-NN graph's rows), for the sampling-density cue.
 * Deterministic, independent of the run's seed.
 * Failures: INVALID_ARGUMENT (NULL xyz/nrm/out, non-finite viewpoint),
 * OUT_OF_MEMORY. */
dacpo_status
dacpo_global_sign(const double* xyz,
                  const double* nrm,
                  size_t n,
                  const double* viewpoint,
                  const float* knn_sqd,
                  size_t knn_k,
                  dacpo_global_sign_result* out,
                  dacpo_err* err);

#endif
