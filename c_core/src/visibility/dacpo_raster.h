/* SPDX-License-Identifier: BSD-3-Clause */
/* Triangle rasterizer with a z-buffer, used by stage 4b (visible connected
 * regions, paper §5.1) and kept apart so it can be tested on its own.
 *
 * Screen convention: pixel (x, y) covers [x, x+1) x [y, y+1) and is sampled at its
 * centre (x + 0.5, y + 0.5). Vertex positions are snapped to 1/256 pixel and the
 * coverage test is exact integer arithmetic with a top-left style tie rule, so
 * triangles that share an edge cover every pixel centre on it exactly once (no
 * cracks, no double coverage). Depth is any value that is linear in screen space
 * (orthographic depth, or -1/depth for a perspective camera); the smaller value
 * wins, ties keep the triangle drawn first. */
#ifndef DACPO_RASTER_H
#define DACPO_RASTER_H

#include "dacpo_internal.h"

/* Largest image side accepted (keeps snapped coordinates and edge functions far
 * inside int64). */
#define DACPO_RASTER_MAX_SIZE 16384

typedef struct dacpo_raster {
  size_t width;
  size_t height;
  float* depth;   /* width * height, row-major; +INFINITY where empty */
  int32_t* owner; /* width * height; id of the nearest triangle, -1 where empty */
  /* Optional (dacpo_raster_keep_far): the farthest triangle of every pixel,
   * i.e. the image seen from the opposite direction; -INFINITY / -1 where
   * empty. NULL when not kept. */
  float* far_depth;
  int32_t* far_owner;
  /* Rectangle of pixels written since the last clear (x0 > x1 when none);
   * dacpo_raster_clear only resets this rectangle. */
  size_t x0, y0, x1, y1;
} dacpo_raster;

/* Allocates an empty width x height image (both in [1, DACPO_RASTER_MAX_SIZE]).
 * Returns DACPO_OK, DACPO_ERR_INVALID_ARGUMENT or DACPO_ERR_OUT_OF_MEMORY (r is
 * then zeroed and safe to free). */
dacpo_status
dacpo_raster_init(dacpo_raster* r, size_t width, size_t height, dacpo_err* err);

/* Frees the buffers and zeroes the struct. NULL-safe. */
void
dacpo_raster_free(dacpo_raster* r);

/* Empties the image (only the dirty rectangle is touched). */
void
dacpo_raster_clear(dacpo_raster* r);

/* Keeps the far image from now on as well (an orthographic view and its
 * opposite cover the same pixels: one rasterization serves both). The image
 * must be empty. Returns DACPO_OK or DACPO_ERR_OUT_OF_MEMORY. */
dacpo_status
dacpo_raster_keep_far(dacpo_raster* r, dacpo_err* err);

/* Replaces the image by the far one seen from the opposite side: depth -z of
 * the farthest triangle, its id (ties keep the triangle drawn first, as in
 * the near image). Pixels of the dirty rectangle outside the drawn rectangle
 * [x0, x1] x [y0, y1] (what the caller added after drawing) are emptied; the
 * dirty rectangle becomes the drawn one, and the far image is emptied. */
void
dacpo_raster_take_far(dacpo_raster* r, size_t x0, size_t y0, size_t x1, size_t y1);

/* Draws one triangle. s0, s1, s2 are (x, y, z) in pixel units with z linear in
 * screen space; either winding is accepted. Pixels whose centre is covered and
 * whose stored depth is larger than the interpolated z take (z, id) (and in
 * the far image, if kept, those whose far depth is smaller). Parts
 * outside the image are clipped; non-finite or degenerate (zero-area after
 * snapping) triangles draw nothing. Returns the number of pixel centres the
 * triangle covers inside the image, won or not. */
size_t
dacpo_raster_triangle(dacpo_raster* r,
                      const double s0[3],
                      const double s1[3],
                      const double s2[3],
                      int32_t id);

#endif /* DACPO_RASTER_H */
