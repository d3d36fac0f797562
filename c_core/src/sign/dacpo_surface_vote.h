/* SPDX-License-Identifier: BSD-3-Clause */
/* After stages 5-6: large smooth surfaces keep one orientation. */
#ifndef DACPO_SURFACE_VOTE_H
#define DACPO_SURFACE_VOTE_H

#include "dacpo_internal.h"
#include "dacpo_knn.h"

/* Largest angle between neighbouring axes of one smooth surface, and between
 * a neighbour's direction and the tangent plane (degrees). */
#define DACPO_SURFACE_VOTE_ANGLE 8.0

/* 1 where points i and j (xyz, axes: points and unit axes, 3 per point)
 * continue one smooth surface: axes within acos(cos_a) of parallel, each
 * point within asin(sin_a) of the other's tangent plane as seen from it. */
int
dacpo_smooth_pair(const double* xyz,
                  const double* axes,
                  size_t i,
                  size_t j,
                  double cos_a,
                  double sin_a);

/* Smooth patches: connected regions of the k-NN graph adj whose neighbouring
 * axes are within max_angle_deg of parallel and lie within max_angle_deg of
 * each other's tangent plane (a point of the other face of a thin part lies
 * off it, a perpendicular face's axis is not parallel). Within a patch the
 * relative sign of two neighbours is that of their axes' dot product.
 *
 * xyz, axes: n points and unit axes (3n each); sign[i] in {+1, -1}: the
 * orientation decided so far (normal = sign[i] axes[i]). In every patch of at
 * least min_points points, the points whose sign disagrees with the patch's
 * majority (propagated over a breadth-first tree of the patch) are turned over
 * (sign[i] negated). *turned (may be NULL) gets their count, *patches (may be
 * NULL) the number of patches that large.
 * Failures: INVALID_ARGUMENT (NULL arrays, adjacency of another size, angle
 * outside (0, 90)), OUT_OF_MEMORY. */
dacpo_status
dacpo_surface_vote(const double* xyz,
                   const double* axes,
                   const dacpo_adjacency* adj,
                   double max_angle_deg,
                   size_t min_points,
                   int8_t* sign,
                   size_t* turned,
                   size_t* patches,
                   dacpo_err* err);

#endif
