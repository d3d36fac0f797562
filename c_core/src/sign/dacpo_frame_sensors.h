/* SPDX-License-Identifier: BSD-3-Clause */
/* The sensors of a scan's frames, where its points come frame by frame:
 * windows of consecutive points, each with the sensor its own densities
 * place (dacpo_window_sensor), for the last sign pass. */
#ifndef DACPO_FRAME_SENSORS_H
#define DACPO_FRAME_SENSORS_H

#include "dacpo_internal.h"

typedef struct dacpo_frame_windows {
  size_t count;   /* windows, both tilings */
  size_t* first;  /* count: first point of each */
  size_t* end;    /* count: one past its last point */
  uint8_t* found; /* count: 1 where a sensor was found (with its side) */
  double* sensor; /* 3 count: its position where found */
} dacpo_frame_windows;

/* Windows of consecutive points in two tilings, the second shifted by half a
 * window: every point is in two windows, one of each tiling, which hold
 * different stretches of the order around it.
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
