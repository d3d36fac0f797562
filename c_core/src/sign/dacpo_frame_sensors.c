/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * The sensors of a scan's frames (last sign pass, dacpo_sign_passes.c).
 *
 * Why: a user who concatenates registered depth frames (or scans) gets a
 * cloud whose points come frame by frame, each surface seen two or more times
 * with the pose errors' offsets. Whether two offset sheets are copies of one
 * surface or the two faces of a thin solid is what the geometry alone cannot
 * tell; the frames that saw them can: every point a sensor saw faces it. A
 * window of consecutive points is one frame, or the end of one and the start
 * of the next, and its own densities place its sensor and its side where it
 * has one (dacpo_window_sensor, dacpo_view_kind.c). A cloud whose order says
 * nothing (voxel-merged, shuffled, sampled from a mesh) has windows of many
 * views or uniform density: none is found and nothing changes.
 *
 * Cost: per window a kd-tree over its points, 512 density terms for each of
 * 512 candidates, and the sensor's placement (a compass search) where one
 * fits; windows run in parallel.
 */
#include "dacpo_frame_sensors.h"

#include "dacpo_parallel.h"
#include "dacpo_view_kind.h"

#include <stdlib.h>
#include <string.h>

enum {
  FRAME_WINDOW = 4096,    /* points per window (DACPO_VIEW_SAMPLE) */
  FRAME_MAX_WINDOWS = 256 /* per tiling: longer windows beyond a million points */
};

typedef struct frame_job {
  const double* xyz;
  const double* axes;
  dacpo_frame_windows* w;
} frame_job;

static dacpo_status
frame_window_task(void* user, size_t k, unsigned thread_id, dacpo_err* err)
{
  (void)thread_id;
  const frame_job* job = user;
  dacpo_frame_windows* w = job->w;
  int found = 0;
  DACPO_TRY(dacpo_window_sensor(job->xyz + 3 * w->first[k],
                                job->axes + 3 * w->first[k],
                                w->end[k] - w->first[k],
                                &found,
                                w->sensor + 3 * k,
                                err));
  w->found[k] = (uint8_t)found;
  return DACPO_OK;
}

/* The windows' bounds: tiling 0 at multiples of len, tiling 1 at len / 2
 * plus multiples of len (with the head [0, len / 2) as its first window). */
static size_t
frame_bounds(size_t n, size_t len, size_t* first, size_t* end)
{
  size_t c = 0;
  for (size_t a = 0; a < n; a += len, ++c) {
    first[c] = a;
    end[c] = a + len < n ? a + len : n;
  }
  for (size_t a = 0; a < n; ++c) {
    const size_t b = a == 0 ? len / 2 : a + len;
    first[c] = a;
    end[c] = b < n ? b : n;
    a = end[c];
  }
  return c;
}

dacpo_status
dacpo_frame_windows_find(const double* xyz,
                         const double* axes,
                         size_t n,
                         unsigned num_threads,
                         dacpo_frame_windows* out,
                         dacpo_err* err)
{
  DACPO_CHECK(err,
              xyz && axes && out,
              DACPO_ERR_INVALID_ARGUMENT,
              "frame windows: NULL argument");
  memset(out, 0, sizeof(*out));
  const size_t by_count = (n + FRAME_MAX_WINDOWS - 1) / FRAME_MAX_WINDOWS;
  const size_t len = by_count > FRAME_WINDOW ? by_count : FRAME_WINDOW;
  const size_t most = 2 * (n / len + 2);
  out->first = dacpo_malloc_array(most, sizeof(size_t));
  out->end = dacpo_malloc_array(most, sizeof(size_t));
  out->found = dacpo_calloc_array(most, sizeof(uint8_t));
  out->sensor = dacpo_calloc_array(3 * most, sizeof(double));
  if (!out->first || !out->end || !out->found || !out->sensor) {
    dacpo_frame_windows_free(out);
    return DACPO_OOM(err);
  }
  out->count = n ? frame_bounds(n, len, out->first, out->end) : 0;
  frame_job job = {xyz, axes, out};
  const dacpo_status st = dacpo_parallel_for(
      out->count, num_threads, frame_window_task, &job, NULL, DACPO_STAGE_ILP, err);
  if (st != DACPO_OK)
    dacpo_frame_windows_free(out);
  return st;
}

void
dacpo_frame_windows_free(dacpo_frame_windows* w)
{
  if (!w)
    return;
  free(w->first);
  free(w->end);
  free(w->found);
  free(w->sensor);
  memset(w, 0, sizeof(*w));
}
