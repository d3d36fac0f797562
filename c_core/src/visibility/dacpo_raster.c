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
  free(r->far_depth);
  free(r->far_owner);
  memset(r, 0, sizeof(*r));
}

dacpo_status
dacpo_raster_keep_far(dacpo_raster* r, dacpo_err* err)
{
  DACPO_CHECK(err,
              r != NULL && r->depth != NULL && r->x0 > r->x1,
              DACPO_ERR_INVALID_ARGUMENT,
              "dacpo_raster_keep_far: no empty image");
  if (r->far_depth != NULL)
    return DACPO_OK;
  size_t n = r->width * r->height;
  r->far_depth = (float*)dacpo_malloc_array(n, sizeof(float));
  r->far_owner = (int32_t*)dacpo_malloc_array(n, sizeof(int32_t));
  if (r->far_depth == NULL || r->far_owner == NULL) {
    free(r->far_depth);
    free(r->far_owner);
    r->far_depth = NULL;
    r->far_owner = NULL;
    return DACPO_OOM(err);
  }
  for (size_t i = 0; i < n; ++i) {
    r->far_depth[i] = -INFINITY;
    r->far_owner[i] = -1;
  }
  return DACPO_OK;
}

void
dacpo_raster_take_far(dacpo_raster* r, size_t x0, size_t y0, size_t x1, size_t y1)
{
  if (r == NULL || r->far_depth == NULL)
    return;
  /* empty the dirty rectangle (the caller may have grown it), then copy the
   * far image over the drawn one */
  const size_t dx0 = r->x0, dx1 = r->x1, dy0 = r->y0, dy1 = r->y1;
  for (size_t y = dy0; dx0 <= dx1 && y <= dy1; ++y)
    for (size_t x = dx0; x <= dx1; ++x) {
      r->depth[y * r->width + x] = INFINITY;
      r->owner[y * r->width + x] = -1;
    }
  for (size_t y = y0; x0 <= x1 && y <= y1; ++y)
    for (size_t x = x0; x <= x1; ++x) {
      const size_t p = y * r->width + x;
      const int32_t id = r->far_owner[p];
      r->depth[p] = id >= 0 ? -r->far_depth[p] : INFINITY;
      r->owner[p] = id;
      r->far_depth[p] = -INFINITY;
      r->far_owner[p] = -1;
    }
  r->x0 = x0;
  r->x1 = x1;
  r->y0 = y0;
  r->y1 = y1;
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
    if (r->far_depth != NULL)
      for (size_t x = r->x0; x <= r->x1; ++x) {
        r->far_depth[row + x] = -INFINITY;
        r->far_owner[row + x] = -1;
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

/* Snaps the vertices to the subpixel grid (X, Y) and orders them counter-
 * clockwise (positive edge functions inside). Returns twice the snapped area,
 * 0 for a non-finite, out-of-range or degenerate triangle. */
static int64_t
raster_snap_ccw(const double* const v[3], int64_t X[3], int64_t Y[3], double Z[3])
{
  for (int k = 0; k < 3; ++k) {
    if (!isfinite(v[k][0]) || !isfinite(v[k][1]) || !isfinite(v[k][2]) ||
        fabs(v[k][0]) > COORD_LIMIT || fabs(v[k][1]) > COORD_LIMIT)
      return 0;
    X[k] = snap(v[k][0]);
    Y[k] = snap(v[k][1]);
    Z[k] = v[k][2];
  }
  int64_t area = (X[1] - X[0]) * (Y[2] - Y[0]) - (Y[1] - Y[0]) * (X[2] - X[0]);
  if (area < 0) {
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
  return area;
}

/* Pixel range {px0, px1, py0, py1} whose centres (256 x + 128) can fall inside
 * the bounding box, clipped to the image. Returns 0 if it is empty. */
static int
raster_pixel_range(const dacpo_raster* r,
                   const int64_t X[3],
                   const int64_t Y[3],
                   int64_t range[4])
{
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
  range[0] = px0;
  range[1] = px1;
  range[2] = py0;
  range[3] = py1;
  return px0 <= px1 && py0 <= py1;
}

/* Incremental edge functions and depth over the pixel range. */
typedef struct raster_steps {
  int64_t step_x[3], step_y[3];
  int64_t row_start[3]; /* biased: inside iff all three are >= 0 */
  double z_row, dz_dx, dz_dy;
} raster_steps;

/* Edge i is opposite vertex i: e0 = (v1, v2), e1 = (v2, v0), e2 = (v0, v1);
 * E_i(p) = (b - a) x (p - a); on a step of one pixel it changes by constants.
 * Values at the centre of pixel (px0, py0). */
static void
raster_setup_steps(const int64_t X[3],
                   const int64_t Y[3],
                   const double Z[3],
                   int64_t area,
                   int64_t px0,
                   int64_t py0,
                   raster_steps* s)
{
  const int a_of[3] = {1, 2, 0}, b_of[3] = {2, 0, 1};
  int64_t bias[3];
  int64_t half = SUBPIXEL_ONE / 2;
  int64_t cx = px0 * SUBPIXEL_ONE + half, cy = py0 * SUBPIXEL_ONE + half;
  for (int i = 0; i < 3; ++i) {
    int a = a_of[i], b = b_of[i];
    s->step_x[i] = -(Y[b] - Y[a]) * SUBPIXEL_ONE;
    s->step_y[i] = (X[b] - X[a]) * SUBPIXEL_ONE;
    s->row_start[i] = (X[b] - X[a]) * (cy - Y[a]) - (Y[b] - Y[a]) * (cx - X[a]);
    bias[i] = edge_bias(X[a], Y[a], X[b], Y[b]);
  }
  /* z = sum_i E_i Z_i / area is affine in the pixel position: step it. */
  double inv_area = 1.0 / (double)area;
  s->z_row = ((double)s->row_start[0] * Z[0] + (double)s->row_start[1] * Z[1] +
              (double)s->row_start[2] * Z[2]) *
             inv_area;
  s->dz_dx = ((double)s->step_x[0] * Z[0] + (double)s->step_x[1] * Z[1] +
              (double)s->step_x[2] * Z[2]) *
             inv_area;
  s->dz_dy = ((double)s->step_y[0] * Z[0] + (double)s->step_y[1] * Z[1] +
              (double)s->step_y[2] * Z[2]) *
             inv_area;
  /* biased edge values: inside iff all three are >= 0, i.e. their OR is */
  for (int i = 0; i < 3; ++i)
    s->row_start[i] -= bias[i];
}

/* Depth test of every covered pixel centre of the range. Returns how many
 * centres the triangle covers. */
static size_t
raster_scan(dacpo_raster* r, const int64_t range[4], raster_steps* s, int32_t id)
{
  size_t covered = 0;
  for (int64_t py = range[2]; py <= range[3]; ++py) {
    int64_t e0 = s->row_start[0], e1 = s->row_start[1], e2 = s->row_start[2];
    double z = s->z_row;
    float* drow = r->depth + (size_t)py * r->width;
    int32_t* orow = r->owner + (size_t)py * r->width;
    float* frow = r->far_depth ? r->far_depth + (size_t)py * r->width : NULL;
    int32_t* forow = r->far_owner ? r->far_owner + (size_t)py * r->width : NULL;
    for (int64_t px = range[0]; px <= range[1]; ++px) {
      if ((e0 | e1 | e2) >= 0) {
        ++covered;
        float zf = (float)z;
        if (zf < drow[px]) {
          drow[px] = zf;
          orow[px] = id;
        }
        if (frow && zf > frow[px]) {
          frow[px] = zf;
          forow[px] = id;
        }
      }
      e0 += s->step_x[0];
      e1 += s->step_x[1];
      e2 += s->step_x[2];
      z += s->dz_dx;
    }
    s->row_start[0] += s->step_y[0];
    s->row_start[1] += s->step_y[1];
    s->row_start[2] += s->step_y[2];
    s->z_row += s->dz_dy;
  }
  return covered;
}

/* Grows the dirty rectangle [x0, x1] x [y0, y1] by the range. */
static void
raster_grow_box(dacpo_raster* r, const int64_t range[4])
{
  size_t px0 = (size_t)range[0], px1 = (size_t)range[1];
  size_t py0 = (size_t)range[2], py1 = (size_t)range[3];
  if (r->x0 > r->x1) {
    r->x0 = px0;
    r->x1 = px1;
    r->y0 = py0;
    r->y1 = py1;
  }
  else {
    r->x0 = px0 < r->x0 ? px0 : r->x0;
    r->x1 = px1 > r->x1 ? px1 : r->x1;
    r->y0 = py0 < r->y0 ? py0 : r->y0;
    r->y1 = py1 > r->y1 ? py1 : r->y1;
  }
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
  const double* const v[3] = {s0, s1, s2};
  int64_t X[3], Y[3];
  double Z[3];
  int64_t area = raster_snap_ccw(v, X, Y, Z);
  if (area == 0)
    return 0;
  int64_t range[4];
  if (!raster_pixel_range(r, X, Y, range))
    return 0;
  raster_steps steps;
  raster_setup_steps(X, Y, Z, area, range[0], range[2], &steps);
  size_t covered = raster_scan(r, range, &steps, id);
  if (covered > 0)
    raster_grow_box(r, range);
  return covered;
}
