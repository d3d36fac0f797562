/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0: PCA normals (paper §4.2, Hoppe 1992) when the caller gives none. */
#ifndef DACPO_NORMALS_H
#define DACPO_NORMALS_H

#include "dacpo_knn.h"

/* For each distinct point: the eigenvector of the smallest eigenvalue of the
 * covariance of the point and its first normal_k neighbours in g (normal_k <=
 * g->k). Sign is arbitrary. curvature (may be NULL) gets l0/(l0+l1+l2), 0 for
 * a degenerate neighbourhood. Degenerate (collinear, coincident) neighbourhoods
 * still give a unit vector, never NaN. */
dacpo_status
dacpo_normals_pca(const dacpo_cloud* cloud,
                  const dacpo_knn_graph* g,
                  size_t normal_k,
                  unsigned num_threads,
                  double* nrm_out,
                  float* curvature,
                  dacpo_err* err);

/* The same, with adaptive != 0 choosing per point among 3/4, 1 and 3/2 x
 * normal_k neighbours the scale whose neighbourhood is flattest
 * (dacpo_params.adaptive_normals); g needs dacpo_normals_width() columns for
 * the largest scale, fewer clamp it. adaptive 0 is dacpo_normals_pca(). */
dacpo_status
dacpo_normals_pca_scaled(const dacpo_cloud* cloud,
                         const dacpo_knn_graph* g,
                         size_t normal_k,
                         int adaptive,
                         unsigned num_threads,
                         double* nrm_out,
                         float* curvature,
                         dacpo_err* err);

/* Neighbours per point the normals need: normal_k, or 3/2 x normal_k when
 * adaptive. */
size_t
dacpo_normals_width(size_t normal_k, int adaptive);

/* Axes of a scan of offset copies (views fused with a registration error,
 * after the scan kind says so): where a point's axis turns by more than 20
 * degrees between its neighbourhood and 2 x normal_k neighbours, it takes the
 * axis of the first of 2, 4, 8 and 16 x normal_k neighbours that agrees
 * within 20 degrees with twice as many (the copies make a neighbourhood about
 * as thick as it is wide at normal_k, so PCA's axis is noise there; a flat
 * layer's axis holds as the neighbourhood grows). Where none agrees (corners, rims)
 * the axis stays. curvature (may be NULL) follows the chosen scale; *changed
 * gets the number of points whose axis was replaced. Builds its own kd-tree
 * (neighbours up to 32 x normal_k for the points that need them); a cloud
 * of fewer than 32 x normal_k points is left as it is. */
dacpo_status
dacpo_normals_copy_scale(const dacpo_cloud* cloud,
                         size_t normal_k,
                         unsigned num_threads,
                         double* nrm,
                         float* curvature,
                         size_t* changed,
                         dacpo_err* err);

#endif
