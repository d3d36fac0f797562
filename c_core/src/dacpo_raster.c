/* SPDX-License-Identifier: BSD-3-Clause */
/* Triangle rasterizer with a z-buffer (support for stage 4b, paper §5.1: "the
 * plane S is rasterized into pixels ... equipped with a z-buffer").
 *
 * In:  triangles in screen space (x, y in pixels, z linear in screen space).
 * Out: per pixel the smallest z and the id of the triangle that produced it.
 * Cost: O(bounding-box pixels) per triangle; clearing is O(dirty rectangle).
 * Failure modes: only allocation in dacpo_raster_init; drawing never fails
 * (non-finite, degenerate or absurdly far triangles draw nothing).
 *
 * Exactness: vertices are snapped to 1/256 pixel, edge functions are evaluated
 * in int64, and an edge owns the pixel centres lying exactly on it only if it is a
 * "top-left" edge in the sense below. Two triangles that share an edge traverse
 * it in opposite directions once both are made counter-clockwise, so exactly one
 * of them owns its centres: meshes rasterize without cracks or double coverage,
 * which the visible-connected-region counts rely on. */
#include "dacpo_raster.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SUBPIXEL_BITS 8
#define SUBPIXEL_ONE ((int64_t)1 << SUBPIXEL_BITS)
/* |coordinate| limit in pixels: (2^20 * 2^8)^2 * 4 stays below 2^63. */
#define COORD_LIMIT 1048576.0

dacpo_status
dacpo_raster_init(dacpo_raster* r, size_t width, size_t height, dacpo_err* err)
{
  DACPO_CHECK(
      err, r != NULL, DACPO_ERR_INVALID_ARGUMENT, "dacpo_raster_init: r is NULL");
  memset(r, 0, sizeof(*r));
  DACPO_CHECK(err,
              width >= 1 && height >= 1 && width <= DACPO_RASTER_MAX_SIZE &&
                  height <= DACPO_RASTER_MAX_SIZE,
              DACPO_ERR_INVALID_ARGUMENT,
              "raster size %zu x %zu outside [1, %d]",
              width,
              height,
              DACPO_RASTER_MAX_SIZE);
  size_t n = width * height;
  r->depth = (float*)dacpo_malloc_array(n, sizeof(float));
  r->owner = (int32_t*)dacpo_malloc_array(n, sizeof(int32_t));
  if (r->depth == NULL || r->owner == NULL) {
    dacpo_raster_free(r);
    return DACPO_OOM(err);
  }
  r->width = width;
  r->height = height;
  for (size_t i = 0; i < n; ++i) {
    r->depth[i] = INFINITY;
    r->owner[i] = -1;
  }
  r->x0 = 1;
  r->x1 = 0;
  r->y0 = 1;
  r->y1 = 0;
  return DACPO_OK;
}

void
dacpo_raster_free(dacpo_raster* r)
{
  if (r == NULL)
    return;
  free(r->depth);
  free(r->owner);
  memset(r, 0, sizeof(*r));
}

void
dacpo_raster_clear(dacpo_raster* r)
{
  if (r == NULL || r->x0 > r->x1 || r->y0 > r->y1)
    return;
  for (size_t y = r->y0; y <= r->y1; ++y) {
    size_t row = y * r->width;
    for (size_t x = r->x0; x <= r->x1; ++x) {
      r->depth[row + x] = INFINITY;
      r->owner[row + x] = -1;
    }
  }
  r->x0 = 1;
  r->x1 = 0;
  r->y0 = 1;
  r->y1 = 0;
}

/* floor(a / b) for b > 0 */
static int64_t
floor_div(int64_t a, int64_t b)
{
  int64_t q = a / b;
  if ((a % b != 0) && (a < 0))
    --q;
  return q;
}

/* Round to the nearest 1/256 pixel, halves away from zero (|x| <= COORD_LIMIT;
 * avoids a libm call per vertex). */
static int64_t
snap(double x)
{
  double s = x * (double)SUBPIXEL_ONE;
  return (int64_t)(s >= 0.0 ? s + 0.5 : s - 0.5);
}

/* Edge a->b of a counter-clockwise triangle owns the centres exactly on it iff
 * dy < 0, or dy == 0 and dx > 0. The reversed edge gets the opposite answer. */
static int64_t
edge_bias(int64_t ax, int64_t ay, int64_t bx, int64_t by)
{
  int64_t dx = bx - ax, dy = by - ay;
  return (dy < 0 || (dy == 0 && dx > 0)) ? 0 : 1;
}

size_t
dacpo_raster_triangle(dacpo_raster* r,
                      const double s0[3],
                      const double s1[3],
                      const double s2[3],
                      int32_t id)
{
  if (r == NULL || r->depth == NULL)
    return 0;
  const double* v[3] = {s0, s1, s2};
  int64_t X[3], Y[3];
  double Z[3];
  for (int k = 0; k < 3; ++k) {
    if (!isfinite(v[k][0]) || !isfinite(v[k][1]) || !isfinite(v[k][2]) ||
        fabs(v[k][0]) > COORD_LIMIT || fabs(v[k][1]) > COORD_LIMIT)
      return 0;
    X[k] = snap(v[k][0]);
    Y[k] = snap(v[k][1]);
    Z[k] = v[k][2];
  }
  int64_t area = (X[1] - X[0]) * (Y[2] - Y[0]) - (Y[1] - Y[0]) * (X[2] - X[0]);
  if (area == 0)
    return 0;
  if (area < 0) { /* make it counter-clockwise (positive edge functions inside) */
    int64_t tx = X[1], ty = Y[1];
    double tz = Z[1];
    X[1] = X[2];
    Y[1] = Y[2];
    Z[1] = Z[2];
    X[2] = tx;
    Y[2] = ty;
    Z[2] = tz;
    area = -area;
  }

  /* Pixel range whose centres (256 x + 128) can fall inside the bounding box. */
  int64_t minX = X[0], maxX = X[0], minY = Y[0], maxY = Y[0];
  for (int k = 1; k < 3; ++k) {
    minX = X[k] < minX ? X[k] : minX;
    maxX = X[k] > maxX ? X[k] : maxX;
    minY = Y[k] < minY ? Y[k] : minY;
    maxY = Y[k] > maxY ? Y[k] : maxY;
  }
  int64_t half = SUBPIXEL_ONE / 2;
  int64_t px0 = floor_div(minX - half + SUBPIXEL_ONE - 1, SUBPIXEL_ONE);
  int64_t px1 = floor_div(maxX - half, SUBPIXEL_ONE);
  int64_t py0 = floor_div(minY - half + SUBPIXEL_ONE - 1, SUBPIXEL_ONE);
  int64_t py1 = floor_div(maxY - half, SUBPIXEL_ONE);
  if (px0 < 0)
    px0 = 0;
  if (py0 < 0)
    py0 = 0;
  if (px1 > (int64_t)r->width - 1)
    px1 = (int64_t)r->width - 1;
  if (py1 > (int64_t)r->height - 1)
    py1 = (int64_t)r->height - 1;
  if (px0 > px1 || py0 > py1)
    return 0;

  /* Edge i is opposite vertex i: e0 = (v1, v2), e1 = (v2, v0), e2 = (v0, v1);
   * E_i(p) = (b - a) x (p - a); on a step of one pixel it changes by constants. */
  const int a_of[3] = {1, 2, 0}, b_of[3] = {2, 0, 1};
  int64_t step_x[3], step_y[3], row_start[3], bias[3];
  int64_t cx = px0 * SUBPIXEL_ONE + half, cy = py0 * SUBPIXEL_ONE + half;
  for (int i = 0; i < 3; ++i) {
    int a = a_of[i], b = b_of[i];
    step_x[i] = -(Y[b] - Y[a]) * SUBPIXEL_ONE;
    step_y[i] = (X[b] - X[a]) * SUBPIXEL_ONE;
    row_start[i] = (X[b] - X[a]) * (cy - Y[a]) - (Y[b] - Y[a]) * (cx - X[a]);
    bias[i] = edge_bias(X[a], Y[a], X[b], Y[b]);
  }
  /* z = sum_i E_i Z_i / area is affine in the pixel position: step it. */
  double inv_area = 1.0 / (double)area;
  double z_row = ((double)row_start[0] * Z[0] + (double)row_start[1] * Z[1] +
                  (double)row_start[2] * Z[2]) *
                 inv_area;
  double dz_dx =
      ((double)step_x[0] * Z[0] + (double)step_x[1] * Z[1] + (double)step_x[2] * Z[2]) *
      inv_area;
  double dz_dy =
      ((double)step_y[0] * Z[0] + (double)step_y[1] * Z[1] + (double)step_y[2] * Z[2]) *
      inv_area;
  /* biased edge values: inside iff all three are >= 0, i.e. their OR is */
  for (int i = 0; i < 3; ++i)
    row_start[i] -= bias[i];

  size_t covered = 0;
  for (int64_t py = py0; py <= py1; ++py) {
    int64_t e0 = row_start[0], e1 = row_start[1], e2 = row_start[2];
    double z = z_row;
    float* drow = r->depth + (size_t)py * r->width;
    int32_t* orow = r->owner + (size_t)py * r->width;
    for (int64_t px = px0; px <= px1; ++px) {
      if ((e0 | e1 | e2) >= 0) {
        ++covered;
        float zf = (float)z;
        if (zf < drow[px]) {
          drow[px] = zf;
          orow[px] = id;
        }
      }
      e0 += step_x[0];
      e1 += step_x[1];
      e2 += step_x[2];
      z += dz_dx;
    }
    row_start[0] += step_y[0];
    row_start[1] += step_y[1];
    row_start[2] += step_y[2];
    z_row += dz_dy;
  }
  if (covered > 0) {
    if (r->x0 > r->x1) {
      r->x0 = (size_t)px0;
      r->x1 = (size_t)px1;
      r->y0 = (size_t)py0;
      r->y1 = (size_t)py1;
    }
    else {
      r->x0 = (size_t)px0 < r->x0 ? (size_t)px0 : r->x0;
      r->x1 = (size_t)px1 > r->x1 ? (size_t)px1 : r->x1;
      r->y0 = (size_t)py0 < r->y0 ? (size_t)py0 : r->y0;
      r->y1 = (size_t)py1 > r->y1 ? (size_t)py1 : r->y1;
    }
  }
  return covered;
}
