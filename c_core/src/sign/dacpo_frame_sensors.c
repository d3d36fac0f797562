/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * The sensors of a scan's frames (last sign pass, dacpo_sign_passes.c).
 *
 * Why: a user who concatenates registered depth frames (or scans) gets a
 * cloud whose points come frame by frame, each surface seen two or more times
 * with the pose errors' offsets. Whether two offset sheets are copies of one
 * surface or the two faces of a thin solid is what the geometry alone cannot
 * tell; the frames that saw them can: every point a sensor saw faces it.
 * Where the order shows where each frame ends, a window of one frame's points
 * places its sensor and its side from its own densities where it has one
 * (dacpo_window_sensor, dacpo_view_kind.c); a window that fits a sensor from
 * both sides of its surfaces takes the side of its frame's camera where
 * another window of the frame places it (tied_windows), or else the side
 * from which other frames' points do not hide it (a frame that sees only a
 * partition's far face: its mirror sensor would look through the near face
 * that other frames saw). A cloud whose order shows no
 * frame (one view, shuffled, sampled uniformly) has no window; one whose
 * order cuts often (voxel-merged) has windows of uniform density, and one
 * sampled surface by surface has windows whose sensor does not explain the
 * density along each surface: nothing changes there.
 *
 * Cost: two passes over the order, two rows' places each (256 to 4096); per
 * window a kd-tree over its points, 512 density terms for each of 512
 * candidates, and the sensor's placement (a compass search) where one fits;
 * a tied window once more, with a placement on each side and, where its
 * frame's camera does not tell, 512 segments walked through a hash of the
 * occupied cells (made once, O(n)); windows run in parallel.
 */
#include "dacpo_frame_sensors.h"

#include "dacpo_free_space.h"
#include "dacpo_parallel.h"
#include "dacpo_view_kind.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
  FRAME_WINDOW = 4096,    /* points per band of a frame (DACPO_VIEW_SAMPLE) */
  FRAME_MAX_WINDOWS = 256 /* longer bands beyond a million points */
};

/* Frames found in the order. A depth frame's points come row by row, so
 * across any place inside a frame some point lies within a few spacings of
 * a point at most `reach` places before it (the row above, the point
 * before); across the place where one frame ends and the next starts (the
 * last rows of one, the first rows of the other) next to none does. The
 * reach is two rows (order_row), at least FRAME_REACH places. */
enum {
  FRAME_REACH = 256,      /* least places looked back along the order */
  FRAME_MAX_REACH = 4096, /* most (and at most an eighth of the cloud) */
  FRAME_ROW_SKIP = 8,     /* places of one's own row passed over */
  FRAME_ROW_SAMPLE = 1024,
  FRAME_MIN = 1024,   /* points: a shorter frame gets no window */
  FRAME_SPACINGS = 3, /* "near": within 3 order spacings */
  FRAME_SAMPLE = 4096 /* places sampled for the median */
};
/* A cut: the pairs across it fall under a twentieth of the median place's. */
#define FRAME_CUT_SHARE 0.05
/* The free space of a tied window's side (dacpo_free_space.c): cells of 1.5
 * order spacings (the median distance to the nearest point along a frame's
 * rows), and 4 of them left out at either end of a segment: the surface's
 * own copies (a few millimetres of registration error) and noise. */
#define FRAME_SPACE_CELL 1.5
#define FRAME_SPACE_SKIP 4.0

/* The points as three float arrays about their centroid: the two passes
 * below run over them in order, `reach` places at a time. */
typedef struct order_points {
  float* x;
  float* y;
  float* z;
} order_points;

static int
order_points_make(const double* xyz, size_t n, order_points* p)
{
  p->x = dacpo_malloc_array(n ? 3 * n : 1, sizeof(float));
  if (!p->x)
    return 0;
  p->y = p->x + n;
  p->z = p->y + n;
  double c[3] = {0.0, 0.0, 0.0};
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d)
      c[d] += xyz[3 * i + d] / (double)n;
  for (size_t i = 0; i < n; ++i) {
    p->x[i] = (float)(xyz[3 * i] - c[0]);
    p->y[i] = (float)(xyz[3 * i + 1] - c[1]);
    p->z[i] = (float)(xyz[3 * i + 2] - c[2]);
  }
  return 1;
}

/* The order's row: over FRAME_ROW_SAMPLE points spread along it, the median
 * number of places back to the first point beyond FRAME_ROW_SKIP places
 * that lies within FRAME_SPACINGS of the point's spacing along its row (the
 * nearest of the FRAME_ROW_SKIP before it), at most `most` back: in a depth
 * frame the pixels above, a row back. 0 if none. */
static size_t
order_row(const order_points* p, size_t n, size_t most)
{
  double gap[FRAME_ROW_SAMPLE];
  size_t m = 0;
  for (size_t s = 0; s < FRAME_ROW_SAMPLE; ++s) {
    const size_t j = most + (n - most) * s / FRAME_ROW_SAMPLE;
    float own = INFINITY;
    for (size_t g = 1; g <= most; ++g) {
      const float dx = p->x[j - g] - p->x[j], dy = p->y[j - g] - p->y[j],
                  dz = p->z[j - g] - p->z[j];
      const float d2 = dx * dx + dy * dy + dz * dz;
      if (g <= FRAME_ROW_SKIP)
        own = d2 < own ? d2 : own;
      else if (d2 <= (float)(FRAME_SPACINGS * FRAME_SPACINGS) * own) {
        gap[m++] = (double)g;
        break;
      }
    }
  }
  return m ? (size_t)dacpo_select_kth(gap, m, m / 2) : 0;
}

/* near2[i]: the squared distance from point i to its nearest point within
 * reach places along the order (either way), times FRAME_SPACINGS^2: a
 * frame's own spacing where i lies, along its row. */
static void
order_near(const order_points* p, size_t n, size_t reach, float* restrict near2)
{
  for (size_t i = 0; i < n; ++i)
    near2[i] = INFINITY;
  for (size_t i = 0; i + 1 < n; ++i) {
    const size_t hi = i + reach < n ? i + reach : n - 1;
    const float xi = p->x[i], yi = p->y[i], zi = p->z[i];
    float best = near2[i];
    for (size_t j = i + 1; j <= hi; ++j) {
      const float dx = p->x[j] - xi, dy = p->y[j] - yi, dz = p->z[j] - zi;
      const float d2 = dx * dx + dy * dy + dz * dz;
      best = d2 < best ? d2 : best;
      near2[j] = d2 < near2[j] ? d2 : near2[j];
    }
    near2[i] = best;
  }
  for (size_t i = 0; i < n; ++i)
    near2[i] *= (float)(FRAME_SPACINGS * FRAME_SPACINGS);
}

/* across[b] (b in 1..n-1): the pairs (i, j), i < b <= j <= i + reach,
 * across the place before point b that lie near (within either one's
 * near2). */
static void
order_crossings(const order_points* p,
                size_t n,
                size_t reach,
                const float* near2,
                int32_t* restrict across)
{
  memset(across, 0, (n + 1) * sizeof(int32_t));
  for (size_t i = 0; i + 1 < n; ++i) {
    const size_t hi = i + reach < n ? i + reach : n - 1;
    const float xi = p->x[i], yi = p->y[i], zi = p->z[i], ni = near2[i];
    int32_t pairs = 0;
    for (size_t j = i + 1; j <= hi; ++j) {
      const float dx = p->x[j] - xi, dy = p->y[j] - yi, dz = p->z[j] - zi;
      const float d2 = dx * dx + dy * dy + dz * dz;
      const int32_t near = d2 <= (ni > near2[j] ? ni : near2[j]);
      pairs += near;
      across[j + 1] -= near;
    }
    across[i + 1] += pairs;
  }
  for (size_t b = 1; b <= n; ++b)
    across[b] += across[b - 1];
}

/* The median of across[b] over sampled places b in [reach, n - reach). */
static double
median_crossing(const int32_t* across, size_t n, size_t reach)
{
  double v[FRAME_SAMPLE];
  const size_t span = n - 2 * reach;
  const size_t step = span / FRAME_SAMPLE + 1;
  size_t m = 0;
  for (size_t b = reach; b < n - reach && m < FRAME_SAMPLE; b += step)
    v[m++] = (double)across[b];
  return dacpo_select_kth(v, m, m / 2);
}

/* The cuts between frames, as frame starts: start[0] = 0, start[frames] =
 * n (n >= 8 reach; capacity n / FRAME_REACH + 3). A cut is the fewest-pairs place
 * of a run of places under FRAME_CUT_SHARE of the median (runs closer than reach
 * are one run). Returns the frames, or 0 where the order shows no cut (or too few near
 * pairs along it to tell). */
static size_t
frame_starts(const int32_t* across, size_t n, size_t reach, size_t* start)
{
  const double low = FRAME_CUT_SHARE * median_crossing(across, n, reach);
  if (low < 1.0)
    return 0;
  size_t frames = 0, best = 0, last_low = 0;
  start[0] = 0;
  for (size_t b = reach; b < n - reach; ++b) {
    if ((double)across[b] >= low)
      continue;
    if (best && b > last_low + reach) { /* the last run ended: its cut */
      start[++frames] = best;
      best = 0;
    }
    if (best == 0 || across[b] < across[best])
      best = b;
    last_low = b;
  }
  if (best == 0)
    return 0;
  start[++frames] = best;
  start[++frames] = n;
  return frames;
}

typedef struct frame_job {
  const double* xyz;
  const double* axes;
  dacpo_frame_windows* w;
  uint8_t* tied;        /* count: the window fits from both sides */
  const size_t* redo;   /* NULL: every window; else the tied ones, redone */
  const size_t* camera; /* count: the window of a tied one's frame whose
                           sensor says its side, or NO_CAMERA (redo only) */
  const size_t* frame_of;        /* count: each window's frame */
  const dacpo_free_space* space; /* redo only: where the frames saw through */
  double skip;                   /* left out at either end of a segment */
} frame_job;

#define NO_CAMERA ((size_t)-1)

static dacpo_status
frame_window_task(void* user, size_t t, unsigned thread_id, dacpo_err* err)
{
  (void)thread_id;
  const frame_job* job = user;
  dacpo_frame_windows* w = job->w;
  const size_t k = job->redo ? job->redo[t] : t;
  const size_t c = job->redo && job->camera[k] != NO_CAMERA ? job->camera[k] : k;
  const dacpo_window_points camera = {job->xyz + 3 * w->first[c],
                                      job->axes + 3 * w->first[c],
                                      w->end[c] - w->first[c],
                                      w->sensor + 3 * c};
  const dacpo_window_space space = {job->space, (uint32_t)job->frame_of[k], job->skip};
  dacpo_window_fit fit;
  DACPO_TRY(dacpo_window_sensor(job->xyz + 3 * w->first[k],
                                job->axes + 3 * w->first[k],
                                w->end[k] - w->first[k],
                                job->redo && c != k ? &camera : NULL,
                                job->redo && job->space ? &space : NULL,
                                &fit,
                                err));
  w->found[k] = (uint8_t)fit.found;
  w->along[k] = (uint8_t)fit.along;
  job->tied[k] = (uint8_t)fit.tied;
  memcpy(w->sensor + 3 * k, fit.sensor, sizeof(fit.sensor));
  return DACPO_OK;
}

/* One frame, one camera: a window that fits its sensor from both sides of
 * its surfaces (a band of rows that sees one wall fits the wall's mirror
 * image as well) takes the side of its frame's sensor where another window
 * of the frame placed one with its side (found and along; the one of most
 * points), else the side the frames' free space allows. Windows of one frame
 * are consecutive in the list (frame_windows). Writes the tied windows to
 * redo, their camera's window (or NO_CAMERA) to camera; returns how many. */
static size_t
tied_windows(const dacpo_frame_windows* w,
             const size_t* frame_of,
             const uint8_t* tied,
             size_t* redo,
             size_t* camera)
{
  size_t c = 0;
  for (size_t a = 0, b; a < w->count; a = b) {
    size_t best = w->count;
    for (b = a; b < w->count && frame_of[b] == frame_of[a]; ++b)
      if (w->along[b] && /* along implies found */
          (best == w->count || w->end[b] - w->first[b] > w->end[best] - w->first[best]))
        best = b;
    for (size_t k = a; k < b; ++k)
      if (tied[k]) {
        redo[c++] = k;
        camera[k] = best < w->count ? best : NO_CAMERA;
      }
  }
  return c;
}

/* The windows of each frame of FRAME_MIN points or more: its bands of about
 * len consecutive points (at least one), and the whole frame where it has
 * more than one band. A band of rows sees fewer planes than the frame, the
 * frame more views of itself in a mirror (a room's far walls): each finds
 * sensors the other misses. A shorter frame (a piece of an order by voxel)
 * has none. */
static size_t
frame_windows(const size_t* start,
              size_t frames,
              size_t len,
              size_t* first,
              size_t* end,
              size_t* frame_of)
{
  size_t c = 0;
  for (size_t f = 0; f < frames; ++f) {
    const size_t size = start[f + 1] - start[f];
    if (size < FRAME_MIN)
      continue;
    const size_t q = (size + len / 2) / len ? (size + len / 2) / len : 1;
    for (size_t j = 0; j < q; ++j, ++c) {
      first[c] = start[f] + size * j / q;
      end[c] = start[f] + size * (j + 1) / q;
      frame_of[c] = f;
    }
    if (q > 1) {
      first[c] = start[f];
      end[c] = start[f + 1];
      frame_of[c++] = f;
    }
  }
  return c;
}

/* The median of sqrt(near2) / FRAME_SPACINGS over sampled points: the order
 * spacing. */
static double
order_spacing(const float* near2, size_t n)
{
  double v[FRAME_SAMPLE];
  const size_t step = n / FRAME_SAMPLE + 1;
  size_t m = 0;
  for (size_t i = 0; i < n && m < FRAME_SAMPLE; i += step)
    if (isfinite(near2[i]))
      v[m++] = sqrt((double)near2[i]) / FRAME_SPACINGS;
  return m ? dacpo_select_kth(v, m, m / 2) : 0.0;
}

/* out->frames and their starts (capacity n / FRAME_REACH + 3); *spacing: the
 * order spacing (order_spacing). */
static dacpo_status
find_frames(const double* xyz,
            size_t n,
            dacpo_frame_windows* out,
            size_t* start,
            double* spacing,
            dacpo_err* err)
{
  out->frames = 0;
  *spacing = 0.0;
  if (n < 2 * FRAME_MIN)
    return DACPO_OK;
  order_points p = {NULL, NULL, NULL};
  int32_t* across = dacpo_malloc_array(n + 1, sizeof(int32_t));
  float* near2 = dacpo_malloc_array(n, sizeof(float));
  if (!across || !near2 || !order_points_make(xyz, n, &p)) {
    free(across);
    free(near2);
    free(p.x);
    return DACPO_OOM(err);
  }
  const size_t most = n / 8 < FRAME_MAX_REACH ? n / 8 : FRAME_MAX_REACH;
  const size_t row = order_row(&p, n, most);
  const size_t reach =
      2 * row < FRAME_REACH ? FRAME_REACH : (2 * row < most ? 2 * row : most);
  order_near(&p, n, reach, near2);
  order_crossings(&p, n, reach, near2, across);
  *spacing = order_spacing(near2, n);
  free(near2);
  free(p.x);
  out->frames = frame_starts(across, n, reach, start);
  free(across);
  return DACPO_OK;
}

/* The free space of the frames (start: frames + 1 starts) with cells of
 * FRAME_SPACE_CELL spacings. */
static dacpo_status
frames_space(const double* xyz,
             size_t n,
             const size_t* start,
             size_t frames,
             double spacing,
             dacpo_free_space* space,
             dacpo_err* err)
{
  uint32_t* frame = dacpo_malloc_array(n ? n : 1, sizeof(uint32_t));
  if (!frame)
    return DACPO_OOM(err);
  for (size_t f = 0; f < frames; ++f)
    for (size_t i = start[f]; i < start[f + 1]; ++i)
      frame[i] = (uint32_t)f;
  const dacpo_status st =
      dacpo_free_space_make(xyz, n, frame, FRAME_SPACE_CELL * spacing, space, err);
  free(frame);
  return st;
}

/* The windows of the frames (start: out->frames + 1 starts; freed here)
 * and their sensors: every window, then the tied ones with their frame's
 * side (tied_windows). out is freed on failure. */
static dacpo_status
frame_sensors(const double* xyz,
              const double* axes,
              size_t n,
              unsigned num_threads,
              size_t* start,
              double spacing,
              size_t len,
              size_t most,
              dacpo_frame_windows* out,
              dacpo_err* err)
{
  size_t* frame_of = dacpo_malloc_array(3 * most, sizeof(size_t));
  uint8_t* tied = dacpo_calloc_array(most, sizeof(uint8_t));
  dacpo_status st = frame_of && tied ? DACPO_OK : DACPO_OOM(err);
  if (st == DACPO_OK)
    out->count = frame_windows(start, out->frames, len, out->first, out->end, frame_of);
  dacpo_free_space space = {0};
  frame_job job = {
      xyz, axes, out, tied, NULL, NULL, frame_of, NULL, FRAME_SPACE_SKIP * spacing};
  if (st == DACPO_OK)
    st = dacpo_parallel_for(
        out->count, num_threads, frame_window_task, &job, NULL, DACPO_STAGE_ILP, err);
  size_t* redo = frame_of + most;
  size_t* camera = redo + most;
  const size_t again =
      st == DACPO_OK ? tied_windows(out, frame_of, tied, redo, camera) : 0;
  if (again && spacing > 0.0)
    st = frames_space(xyz, n, start, out->frames, spacing, &space, err);
  job.redo = redo;
  job.camera = camera;
  job.space = space.key ? &space : NULL;
  if (st == DACPO_OK && again)
    st = dacpo_parallel_for(
        again, num_threads, frame_window_task, &job, NULL, DACPO_STAGE_ILP, err);
  dacpo_free_space_free(&space);
  free(start);
  free(frame_of);
  free(tied);
  if (st != DACPO_OK)
    dacpo_frame_windows_free(out);
  return st;
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
  const size_t most = n / len + 2 * (n / FRAME_MIN) + 2;
  size_t* start = dacpo_malloc_array(n / FRAME_REACH + 3, sizeof(size_t));
  out->first = dacpo_malloc_array(most, sizeof(size_t));
  out->end = dacpo_malloc_array(most, sizeof(size_t));
  out->found = dacpo_calloc_array(most, sizeof(uint8_t));
  out->along = dacpo_calloc_array(most, sizeof(uint8_t));
  out->sensor = dacpo_calloc_array(3 * most, sizeof(double));
  dacpo_status st = DACPO_OK;
  double spacing = 0.0;
  if (!start || !out->first || !out->end || !out->found || !out->along || !out->sensor)
    st = DACPO_OOM(err);
  if (st == DACPO_OK)
    st = find_frames(xyz, n, out, start, &spacing, err);
  if (st != DACPO_OK) {
    free(start);
    dacpo_frame_windows_free(out);
    return st;
  }
  return frame_sensors(xyz, axes, n, num_threads, start, spacing, len, most, out, err);
}

void
dacpo_frame_windows_free(dacpo_frame_windows* w)
{
  if (!w)
    return;
  free(w->first);
  free(w->end);
  free(w->found);
  free(w->along);
  free(w->sensor);
  memset(w, 0, sizeof(*w));
}
