/* SPDX-License-Identifier: BSD-3-Clause */
/* The sensors of a scan's frames, where its points come frame by frame:
 * the frames found in the order, cut into windows, each with the sensor its
 * own densities place (dacpo_window_sensor), for the last sign pass. */
#ifndef DACPO_FRAME_SENSORS_H
#define DACPO_FRAME_SENSORS_H

#include "dacpo_internal.h"

typedef struct dacpo_frame_windows {
  size_t count;   /* windows */
  size_t* first;  /* count: first point of each */
  size_t* end;    /* count: one past its last point */
  uint8_t* found; /* count: 1 where a sensor was found (with its side) */
  uint8_t* along; /* count: 1 where found and it also explains the density
                     along the window's surfaces (dacpo_window_sensor) */
  double* sensor; /* 3 count: its position where found */
  size_t frames;  /* frames found in the order (some may hold no window) */
} dacpo_frame_windows;

/* The frames of the order and their windows. A depth frame's points come
 * row by row: across any place inside it some point lies within 3 order
 * spacings (a point's distance to its nearest within the reach) of one at
 * most the reach before it, across the place between two frames next to
 * none (under a twentieth of the median place's pairs). The reach is two of
 * the order's rows (the median number of places back to the first point
 * near a sampled one beyond its own 8 last), 256 to 4,096 places and at most
 * an eighth of the cloud. Each frame of at least 1,024 points is cut into
 * windows of about the window length; every point is in at most two (a band
 * and the whole frame), of its own frame. A window whose densities fit a
 * sensor from both sides of its surfaces takes its side from the frame's
 * window (along) of most points where that one tells, else from the space
 * the frames saw through: the placement inside the cloud's box from which
 * other frames' points do not hide it (dacpo_window_sensor,
 * dacpo_free_space.c).
 * No cut: no frame, no window (out->count = 0).
 * Window length: 4096 points, or n / 256 for clouds over a million points.
 * xyz, axes: n points and unit axes (3n each). Deterministic, independent of
 * num_threads (0 = all cores). Failures: NULL argument (INVALID_ARGUMENT),
 * OUT_OF_MEMORY. */
dacpo_status
dacpo_frame_windows_find(const double* xyz,
                         const double* axes,
                         size_t n,
                         unsigned num_threads,
                         dacpo_frame_windows* out,
                         dacpo_err* err);

void
dacpo_frame_windows_free(dacpo_frame_windows* w);

#endif
