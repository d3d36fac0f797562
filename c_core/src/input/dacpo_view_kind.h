/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0 helper: one depth view, or a scene sampled from many places? */
#ifndef DACPO_VIEW_KIND_H
#define DACPO_VIEW_KIND_H

#include "dacpo_free_space.h"
#include "dacpo_internal.h"
#include "dacpo_part_sign.h"

/* A depth sensor samples equal solid angles, so near it a point's density
 * (1 / r_k^2) follows cos(incidence) / distance^2. Correlation of the two
 * logarithms over the sample s for a sensor at v (the axes' sign does not
 * matter). logd: s->m log densities (dacpo_view_log_density). */
double
dacpo_view_density_fit(const dacpo_view_sample* s,
                       const double* logd,
                       const double v[3],
                       double* slope);

/* logd[i] = -2 log r_k of sample point i, r_k the farthest of its first use_k
 * neighbours (knn_sqd: the cloud's n x row_k squared distances, nearest first,
 * absent ones +inf; use_k <= row_k). Returns NULL when out of memory. */
double*
dacpo_view_log_density(const dacpo_view_sample* s,
                       const float* knn_sqd,
                       size_t row_k,
                       size_t use_k);

/* *fit: the best density fit over DACPO_VIEW_KIND_CANDIDATES candidate sensors
 * (sample points pushed along either side of their axis, as the part signs'
 * viewpoints), densities from the 8th neighbour (knn_sqd: n x knn_k, nearest
 * first; fewer if knn_k < 8). A single depth frame has a sensor that explains
 * it: 0.72-0.98 on the 15 real frames of our evaluation set; rooms sampled
 * uniformly or from several places inside correlate at 0.08-0.38 (18 rooms), a
 * fused TSDF fragment at 0.17, but with slopes of 0.08-0.11, so they get 0:
 * candidates whose density follows the model with a regression slope under
 * DACPO_SINGLE_VIEW_SLOPE do not count. *slope (may be NULL) gets the chosen
 * one's. sensor (may be NULL) gets, when *fit reaches DACPO_SENSOR_FIT,
 * where the sensor stands: the position whose model explains the densities
 * best (least variance of log density minus the model: the candidate with
 * the least, refined); else (0, 0, 0). It may lie on either side of the
 * surfaces: the densities do not say which way they face. xyz, axes: n
 * points and unit axes (3n each).
 * Failures: NULL argument (INVALID_ARGUMENT), OUT_OF_MEMORY. */
dacpo_status
dacpo_single_view_sensor(const double* xyz,
                         const double* axes,
                         size_t n,
                         const float* knn_sqd,
                         size_t knn_k,
                         double* fit,
                         double* slope,
                         double sensor[3],
                         dacpo_err* err);

/* What dacpo_window_sensor finds in a window. */
typedef struct dacpo_window_fit {
  int found;        /* a sensor placed, with its side */
  int along;        /* found, and it explains the density along the surfaces */
  int tied;         /* a sensor fits from both sides of the surfaces */
  double sensor[3]; /* where found */
} dacpo_window_fit;

/* A window of a frame whose sensor has its side: m points and unit axes
 * (3m each), and the sensor. */
typedef struct dacpo_window_points {
  const double* xyz;
  const double* axes;
  size_t m;
  const double* sensor;
} dacpo_window_points;

/* The space the window's frame and the other frames saw through
 * (dacpo_free_space.c): `frame` is the window's own, `skip` the length left
 * out at either end of a segment. */
typedef struct dacpo_window_space {
  const dacpo_free_space* space;
  uint32_t frame;
  double skip;
} dacpo_window_space;

/* The sensor of one window of one frame's points (xyz, axes: m points and
 * unit axes, 3m each), as registered depth frames concatenated keep them:
 * out->found = 1 and out->sensor set when the window's own densities (its 8th
 * neighbours among its m points) place one sensor (fit >=
 * DACPO_SINGLE_VIEW_FIT) and say on which side of the surfaces it stands (no
 * candidate seen from the other side has the density fall with range as
 * seen from it); else found = 0 (a window of many views or of uniform
 * density, fewer than 256 points). A window that fits from both sides (a
 * flat one fits its sensor's mirror image as well) has out->tied = 1 and no
 * sensor unless `camera` (not NULL: another window of the same frame, whose
 * sensor has its side) says which: of the sensors placed on either side, the
 * one on the camera's side of the surfaces that tell them apart; or, where
 * it does not tell, `space` (not NULL): of the two, the one inside the
 * cloud's box from which the window's points are not hidden behind points of
 * other frames while they are from the other. out->along = 1
 * where found and the sensor also explains the density along the window's smooth
 * surfaces (correlation of the differences over pairs on one surface at
 * least 3 / sqrt(sample size): three standard errors above none): a frame,
 * whose density falls with range across each surface, not a cloud sampled
 * surface by surface, whose density steps between surfaces a far sensor can
 * explain while each surface is uniform.
 * Deterministic. Failures: NULL argument (INVALID_ARGUMENT), OUT_OF_MEMORY. */
dacpo_status
dacpo_window_sensor(const double* xyz,
                    const double* axes,
                    size_t m,
                    const dacpo_window_points* camera,
                    const dacpo_window_space* space,
                    dacpo_window_fit* out,
                    dacpo_err* err);

/* The fit from which a cloud counts as one depth view (the global sign uses the
 * same threshold to single out a sensor). */
#define DACPO_SINGLE_VIEW_FIT 0.5
/* The fit from which the sensor found is trusted point by point (the last
 * sign pass turns the points it sees squarely to face it): a view the density
 * explains well, not a scan of many views that passes for one (their sensor
 * found is a compromise, and other cameras saw surfaces that face away from
 * it). Below it the view keeps the pipeline's signs (docs/DESIGN.md, "One
 * view faces its sensor"). */
#define DACPO_SENSOR_FIT 0.7
/* The least slope of log density on the sensor model for a candidate to count
 * (dacpo_single_view_sensor). */
#define DACPO_SINGLE_VIEW_SLOPE 0.4
/* A sensor sees a point squarely where the incidence is under 60 degrees
 * (|cos| of the axis to the ray at least this): nearer grazing the estimated
 * axis and the estimated sensor decide less surely. */
#define DACPO_SENSOR_SQUARE_COS 0.5
/* A side is decisive where those against it are under this share of those
 * for it (the sensor passes, the frames' block turns, a tied window's side). */
#define DACPO_SENSOR_MAX_AWAY 0.25

#endif
