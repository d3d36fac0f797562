/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 6 helper: the space other frames saw through.
 *
 * Why: a frame that sees one plane (a wall, a partition's far face) fits its
 * sensor's mirror image across the plane as well as the sensor itself, so
 * its densities do not say which way the plane faces. A sensor sees a point
 * only through free space: if a point of another frame lies on the segment
 * from a placement to a point of this frame (a partition's near face, seen by
 * other cameras, between the far face and the far face's mirror sensor),
 * the frame's camera did not stand there. Points of the frame itself do not
 * count (they are what its camera saw, nearest first), nor does anything
 * within `skip` of either end (the surface's own copies from other frames,
 * offset by the registration error, and noise).
 *
 * The cells are cubes of about a spacing, hashed (open addressing) so that
 * memory follows the points, not the cloud's box. A segment is walked in
 * half-cell steps. Cost: O(n) to make; O(length / cell) per segment.
 */
#include "dacpo_free_space.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SPACE_BITS 21 /* bits per axis of a cell key */
#define SPACE_SPAN ((double)(1u << (SPACE_BITS - 1)))

/* The key of the cell holding p; SPACE_OUTSIDE beyond the cells. */
#define SPACE_OUTSIDE UINT64_MAX
static uint64_t
cell_key(const dacpo_free_space* s, const double p[3])
{
  uint64_t key = 0;
  for (int d = 0; d < 3; ++d) {
    const double c = floor((p[d] - s->origin[d]) / s->cell);
    if (!(c >= 0.0 && c < 2.0 * SPACE_SPAN))
      return SPACE_OUTSIDE;
    key = (key << SPACE_BITS) | (uint64_t)c;
  }
  return key;
}

static size_t
slot_of(const dacpo_free_space* s, uint64_t key)
{
  uint64_t h = key * 0x9E3779B97F4A7C15ull;
  size_t at = (size_t)(h >> 17) & s->mask;
  while (s->key[at] != 0 && s->key[at] != key + 1)
    at = (at + 1) & s->mask;
  return at;
}

dacpo_status
dacpo_free_space_make(const double* xyz,
                      size_t n,
                      const uint32_t* frame,
                      double cell,
                      dacpo_free_space* out,
                      dacpo_err* err)
{
  DACPO_CHECK(err,
              xyz && frame && out && cell > 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "free space: NULL argument or cell %g",
              cell);
  memset(out, 0, sizeof(*out));
  for (int d = 0; d < 3; ++d) {
    out->origin[d] = INFINITY;
    out->top[d] = -INFINITY;
  }
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      out->origin[d] = fmin(out->origin[d], xyz[3 * i + d]);
      out->top[d] = fmax(out->top[d], xyz[3 * i + d]);
    }
  out->cell = cell;
  for (int d = 0; d < 3 && n; ++d)
    out->cell =
        fmax(out->cell, (out->top[d] - out->origin[d]) / (2.0 * SPACE_SPAN - 2.0));
  size_t cap = 1024;
  while (cap < 2 * n)
    cap *= 2;
  out->mask = cap - 1;
  out->key = dacpo_calloc_array(cap, sizeof(uint64_t));
  out->lo = dacpo_malloc_array(cap, sizeof(uint32_t));
  out->hi = dacpo_malloc_array(cap, sizeof(uint32_t));
  if (!out->key || !out->lo || !out->hi) {
    dacpo_free_space_free(out);
    return DACPO_OOM(err);
  }
  for (size_t i = 0; i < n; ++i) {
    const uint64_t key = cell_key(out, xyz + 3 * i);
    const size_t at = slot_of(out, key);
    if (out->key[at] == 0) {
      out->key[at] = key + 1;
      out->lo[at] = out->hi[at] = frame[i];
    }
    out->lo[at] = frame[i] < out->lo[at] ? frame[i] : out->lo[at];
    out->hi[at] = frame[i] > out->hi[at] ? frame[i] : out->hi[at];
  }
  return DACPO_OK;
}

void
dacpo_free_space_free(dacpo_free_space* s)
{
  if (!s)
    return;
  free(s->key);
  free(s->lo);
  free(s->hi);
  memset(s, 0, sizeof(*s));
}

int
dacpo_free_space_inside(const dacpo_free_space* s, const double v[3])
{
  for (int d = 0; d < 3; ++d)
    if (!(v[d] >= s->origin[d] && v[d] <= s->top[d]))
      return 0;
  return 1;
}

int
dacpo_free_space_blocked(const dacpo_free_space* s,
                         const double p[3],
                         const double v[3],
                         double skip,
                         uint32_t frame)
{
  const double d[3] = {v[0] - p[0], v[1] - p[1], v[2] - p[2]};
  const double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(len > 2.0 * skip) || !s->key)
    return 0;
  uint64_t last = SPACE_OUTSIDE;
  for (double t = skip; t <= len - skip; t += 0.5 * s->cell) {
    const double q[3] = {
        p[0] + d[0] * t / len, p[1] + d[1] * t / len, p[2] + d[2] * t / len};
    const uint64_t key = cell_key(s, q);
    if (key == last || key == SPACE_OUTSIDE)
      continue;
    last = key;
    const size_t at = slot_of(s, key);
    if (s->key[at] != 0 && (s->lo[at] != frame || s->hi[at] != frame))
      return 1;
  }
  return 0;
}
