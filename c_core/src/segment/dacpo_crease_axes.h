/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 1 helper: the axes the block growth reads to keep creases between
 * blocks (dacpo_segment_creased). */
#ifndef DACPO_CREASE_AXES_H
#define DACPO_CREASE_AXES_H

#include "dacpo_knn.h"

/* out (3n) gets, per point, the unsigned axis of cloud->nrm averaged over the
 * point and its first k neighbours in g, each weighted by how well its axis
 * agrees with the point's: two passes of
 *   T_i = sum_j exp(-(1 - (a_i . a_j)^2) / DACPO_CREASE_AXIS_S2) a_j a_j^T,
 *   a_i <- the eigenvector of T_i's largest eigenvalue,
 * so the scatter of PCA axes on a noisy or doubled surface is averaged out
 * while neighbours across a crease (about 90 degrees: weight e^-4) barely
 * count. Opposite axes (the two faces of a thin part) agree: the average is
 * of unsigned axes. Each output axis has the sign of the input one. Costs two
 * passes of O(n k), parallel over chunks of points. cloud->nrm must hold unit
 * axes. Failures: bad arguments (INVALID_ARGUMENT), OUT_OF_MEMORY. */
#define DACPO_CREASE_AXIS_S2 0.25

dacpo_status
dacpo_crease_axes(const dacpo_cloud* cloud,
                  const dacpo_knn_graph* g,
                  size_t k,
                  unsigned num_threads,
                  double* out,
                  dacpo_err* err);

#endif
