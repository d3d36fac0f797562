/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 0 helper: do the two sheets of a planar band cross each other?
 *
 * Why: the layered test (dacpo_layered.c) calls a band's second sheet a copy
 * only where the scene lies on one side of it, as a floor's; a plane seen
 * twice with nothing else around is the same points as a board without its
 * rim. But a thin solid's two faces never cross (a crossing would put one
 * face inside the solid), and copies of one surface from views with a
 * rotation error between them do, along the line where their offset passes
 * zero. There the side cue fires on both sides of the line and turns each
 * copy one way on one side, the other way on the other.
 *
 * The test: cells of about CROSS_CELL_POINTS band points over the band's
 * footprint; in each, two planes fitted by alternation from Otsu's split of
 * one plane's residuals, kept where the split is as clear as the side cue
 * asks (dacpo_sheet_side.h: both groups a quarter of the points, separation
 * over 5, gap over 0.3 spacing, the groups over each other). Each kept cell
 * gives its gap g (upper sheet minus lower at the cell's middle) and the
 * relative slope q (upper's minus lower's). Two copies crossing along a line
 * give g = |w.x + b| and q = sign(w.x + b) w: the cells' slopes share one
 * direction up to sign, the gaps signed by it are one linear function of the
 * position, cells of both signs lie on either side of its zero line, and its
 * gradient w is the cells' own mean signed slope: one tilt measured twice,
 * within the cells and across them. Parallel faces (a board, a thing resting
 * on a floor) have q of noise and signed gaps that fit no line.
 *
 * Cost: O(m log m) (a sort per cell). Deterministic.
 */
#include "dacpo_sheets_cross.h"

#include "dacpo_sheet_side.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CROSS_CELL_POINTS 64.0 /* band points a cell holds on average */
#define CROSS_MIN_POINTS 24    /* a cell fits its two planes from this many */
#define CROSS_MAX_CELLS 256.0  /* cells along the footprint's longer side */
#define CROSS_ROUNDS 3         /* alternation rounds of the two-plane fit */
#define CROSS_MIN_CELLS 8      /* two-sheet cells the line is fitted to */
/* the signed gaps fit one line: residual rms under this share of the gaps' */
#define CROSS_MAX_RESIDUAL 0.3
/* the cells' mean signed slope is the line's gradient within this share */
#define CROSS_MAX_SLOPE_MISS 0.5
/* the smaller side of the line holds this share of the cells (a wedge's
 * faces meet at its edge: every cell on one side, or a stray one beyond) */
#define CROSS_MIN_SIDE 0.1

typedef struct {
  double x[2]; /* the cell's middle in the band's frame */
  double g;    /* upper sheet minus lower at the middle (> 0) */
  double q[2]; /* upper sheet's slope minus the lower's */
} cell_sheets;

/* Least-squares plane y = c0 + c1 u + c2 v over the m points whose label
 * lab[k] equals want (all if lab is NULL); 0 if degenerate. */
static int
plane_fit(const double* u,
          const double* v,
          const double* y,
          const int8_t* lab,
          int want,
          size_t m,
          double c[3])
{
  double A[3][4] = {{0.0}};
  for (size_t k = 0; k < m; ++k) {
    if (lab && lab[k] != want)
      continue;
    const double f[3] = {1.0, u[k], v[k]};
    for (int r = 0; r < 3; ++r) {
      for (int s = 0; s < 3; ++s)
        A[r][s] += f[r] * f[s];
      A[r][3] += f[r] * y[k];
    }
  }
  const double scale = A[1][1] + A[2][2];
  for (int col = 0; col < 3; ++col) { /* Gaussian elimination, partial pivot */
    int piv = col;
    for (int r = col + 1; r < 3; ++r)
      if (fabs(A[r][col]) > fabs(A[piv][col]))
        piv = r;
    if (!(fabs(A[piv][col]) > 1e-12 * (scale > 0.0 ? scale : 1.0)))
      return 0;
    for (int s = 0; s < 4; ++s) {
      const double t = A[col][s];
      A[col][s] = A[piv][s];
      A[piv][s] = t;
    }
    for (int r = 0; r < 3; ++r) {
      if (r == col)
        continue;
      const double f = A[r][col] / A[col][col];
      for (int s = col; s < 4; ++s)
        A[r][s] -= f * A[col][s];
    }
  }
  for (int r = 0; r < 3; ++r)
    c[r] = A[r][3] / A[r][r];
  return 1;
}

static double
plane_at(const double c[3], double u, double v)
{
  return c[0] + c[1] * u + c[2] * v;
}

/* Otsu's split of the m residuals r (sorted copy in s, dacpo_otsu_sorted):
 * labels lab[k] = 1 above its threshold, 0 below; returns 0 if there is no
 * split. */
static int
otsu_labels(const double* r, size_t m, double* s, int8_t* lab)
{
  memcpy(s, r, m * sizeof(double));
  qsort(s, m, sizeof(double), dacpo_cmp_double);
  double thr = 0.0, gap = 0.0;
  if (!(dacpo_otsu_sorted(s, m, &thr, &gap) > 0.0))
    return 0;
  for (size_t k = 0; k < m; ++k)
    lab[k] = r[k] > thr;
  return 1;
}

/* The two groups' lateral centroids lie closer than DACPO_SIDE_MAX_LATERAL
 * mean lateral distances of the cell's points (u, v centred): over each
 * other, not beside each other as a depth image's terraces. */
static int
groups_overlap(const double* u, const double* v, const int8_t* lab, size_t m)
{
  double c[2][2] = {{0.0, 0.0}, {0.0, 0.0}}, lateral = 0.0;
  size_t n1 = 0;
  for (size_t k = 0; k < m; ++k) {
    c[lab[k]][0] += u[k];
    c[lab[k]][1] += v[k];
    n1 += (size_t)lab[k];
    lateral += sqrt(u[k] * u[k] + v[k] * v[k]);
  }
  if (n1 == 0 || n1 == m)
    return 0;
  const double du = c[1][0] / (double)n1 - c[0][0] / (double)(m - n1);
  const double dv = c[1][1] / (double)n1 - c[0][1] / (double)(m - n1);
  return sqrt(du * du + dv * dv) < DACPO_SIDE_MAX_LATERAL * lateral / (double)m;
}

/* Two planes through the m points of one cell (u, v centred on its middle),
 * by alternation from Otsu's split of one plane's residuals. Returns 1 and
 * fills *out (but its x) where both groups keep a quarter of the points and
 * the split is clear; r, s, lab: scratch of m. */
static int
two_planes(const double* u,
           const double* v,
           const double* y,
           size_t m,
           double spacing,
           double* r,
           double* s,
           int8_t* lab,
           cell_sheets* out)
{
  double c[2][3];
  if (!plane_fit(u, v, y, NULL, 0, m, c[0]))
    return 0;
  for (size_t k = 0; k < m; ++k)
    r[k] = y[k] - plane_at(c[0], u[k], v[k]);
  if (!otsu_labels(r, m, s, lab))
    return 0;
  const size_t kmin = (size_t)ceil(DACPO_SIDE_MIN_CLUSTER * (double)m);
  for (int round = 0; round < CROSS_ROUNDS; ++round) {
    if (!plane_fit(u, v, y, lab, 0, m, c[0]) || !plane_fit(u, v, y, lab, 1, m, c[1]))
      return 0;
    size_t n1 = 0;
    for (size_t k = 0; k < m; ++k) {
      lab[k] = fabs(y[k] - plane_at(c[1], u[k], v[k])) <
               fabs(y[k] - plane_at(c[0], u[k], v[k]));
      n1 += (size_t)lab[k];
    }
    if (n1 < kmin || m - n1 < kmin)
      return 0;
  }
  if (!plane_fit(u, v, y, lab, 0, m, c[0]) || !plane_fit(u, v, y, lab, 1, m, c[1]))
    return 0;
  double ss = 0.0;
  for (size_t k = 0; k < m; ++k) {
    const double e = y[k] - plane_at(c[lab[k]], u[k], v[k]);
    ss += e * e;
  }
  const int hi = c[1][0] > c[0][0];
  out->g = c[hi][0] - c[1 - hi][0];
  out->q[0] = c[hi][1] - c[1 - hi][1];
  out->q[1] = c[hi][2] - c[1 - hi][2];
  const double sigma = sqrt(ss / (double)(m > 6 ? m - 6 : 1));
  return out->g > DACPO_SIDE_MIN_GAP * spacing &&
         out->g > DACPO_SIDE_SEP_START * sigma && groups_overlap(u, v, lab, m);
}

/* The principal direction of the cells' relative slopes (sum of q q^T). */
static void
slope_direction(const cell_sheets* c, size_t k, double e[2])
{
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (size_t t = 0; t < k; ++t) {
    sxx += c[t].q[0] * c[t].q[0];
    sxy += c[t].q[0] * c[t].q[1];
    syy += c[t].q[1] * c[t].q[1];
  }
  const double tr = sxx + syy, det = sxx * syy - sxy * sxy;
  const double lam = 0.5 * tr + sqrt(fmax(0.25 * tr * tr - det, 0.0));
  e[0] = sxy;
  e[1] = lam - sxx;
  if (hypot(e[0], e[1]) <= 1e-12 * (tr > 0.0 ? tr : 1.0)) {
    e[0] = lam - syy;
    e[1] = sxy;
  }
  const double len = hypot(e[0], e[1]);
  e[0] = len > 0.0 ? e[0] / len : 1.0;
  e[1] = len > 0.0 ? e[1] / len : 0.0;
}

/* The share of the k two-sheet cells on the smaller side of the line where
 * the sheets cross, 0 if the cells show no crossing (file comment); u, v, y:
 * scratch of k. */
static double
crossing_line(const cell_sheets* c, size_t k, double* u, double* v, double* y)
{
  if (k < CROSS_MIN_CELLS)
    return 0.0;
  double e[2], mid[2] = {0.0, 0.0};
  slope_direction(c, k, e);
  for (size_t t = 0; t < k; ++t) {
    mid[0] += c[t].x[0] / (double)k;
    mid[1] += c[t].x[1] / (double)k;
  }
  size_t plus = 0;
  double qbar[2] = {0.0, 0.0}, g2 = 0.0;
  for (size_t t = 0; t < k; ++t) {
    const double sign = c[t].q[0] * e[0] + c[t].q[1] * e[1] >= 0.0 ? 1.0 : -1.0;
    plus += sign > 0.0;
    u[t] = c[t].x[0] - mid[0];
    v[t] = c[t].x[1] - mid[1];
    y[t] = sign * c[t].g;
    qbar[0] += sign * c[t].q[0] / (double)k;
    qbar[1] += sign * c[t].q[1] / (double)k;
    g2 += c[t].g * c[t].g;
  }
  double h[3];
  if (!plane_fit(u, v, y, NULL, 0, k, h))
    return 0.0;
  double res2 = 0.0;
  for (size_t t = 0; t < k; ++t) {
    const double d = y[t] - plane_at(h, u[t], v[t]);
    res2 += d * d;
  }
  const double slope = hypot(h[1], h[2]);
  const double miss = hypot(qbar[0] - h[1], qbar[1] - h[2]);
  const double minority = (double)(plus < k - plus ? plus : k - plus) / (double)k;
  if (!(res2 <= CROSS_MAX_RESIDUAL * CROSS_MAX_RESIDUAL * g2) ||
      !(miss <= CROSS_MAX_SLOPE_MISS * slope) || minority < CROSS_MIN_SIDE)
    return 0.0;
  return minority;
}

/* Counting sort of the m points into the nu x nv cells of side cell from
 * corner (box[0], box[1]): cell c holds order[start[c] .. start[c + 1]). */
static size_t
cell_of(const double* p, const double box[2], double cell, size_t nu, size_t nv)
{
  const size_t iu = (size_t)((p[0] - box[0]) / cell);
  const size_t iv = (size_t)((p[1] - box[1]) / cell);
  return (iu < nu ? iu : nu - 1) * nv + (iv < nv ? iv : nv - 1);
}

static void
bucket_points(const double* uvy,
              size_t m,
              const double box[2],
              double cell,
              size_t nu,
              size_t nv,
              size_t* start,
              size_t* order)
{
  const size_t nc = nu * nv;
  memset(start, 0, (nc + 1) * sizeof(size_t));
  for (size_t k = 0; k < m; ++k)
    start[cell_of(uvy + 3 * k, box, cell, nu, nv) + 1]++;
  for (size_t c = 0; c < nc; ++c)
    start[c + 1] += start[c];
  for (size_t k = 0; k < m; ++k) /* moves each start to the next cell's */
    order[start[cell_of(uvy + 3 * k, box, cell, nu, nv)]++] = k;
  for (size_t c = nc; c > 0; --c)
    start[c] = start[c - 1];
  start[0] = 0;
}

/* The footprint's cells of about CROSS_CELL_POINTS points: corner box[0..1],
 * side *cell, *nu x *nv of them. */
static void
cell_grid(
    const double* uvy, size_t m, double box[2], double* cell, size_t* nu, size_t* nv)
{
  double hi[2] = {-INFINITY, -INFINITY};
  box[0] = box[1] = INFINITY;
  for (size_t k = 0; k < m; ++k)
    for (int d = 0; d < 2; ++d) {
      box[d] = fmin(box[d], uvy[3 * k + d]);
      hi[d] = fmax(hi[d], uvy[3 * k + d]);
    }
  const double w = hi[0] - box[0], h = hi[1] - box[1];
  *cell =
      fmax(sqrt(w * h * CROSS_CELL_POINTS / (double)m), fmax(w, h) / CROSS_MAX_CELLS);
  if (!(*cell > 0.0))
    *cell = 1.0;
  *nu = (size_t)(w / *cell) + 1;
  *nv = (size_t)(h / *cell) + 1;
}

/* The two planes of every cell with CROSS_MIN_POINTS or more (cells[0..*k)). */
static void
fit_cells(const double* uvy,
          const size_t* start,
          const size_t* order,
          size_t nc,
          double spacing,
          double* scratch,
          int8_t* lab,
          cell_sheets* cells,
          size_t* k)
{
  *k = 0;
  for (size_t c = 0; c < nc; ++c) {
    const size_t n = start[c + 1] - start[c];
    if (n < CROSS_MIN_POINTS)
      continue;
    double *u = scratch, *v = u + n, *y = v + n, mid[2] = {0.0, 0.0};
    for (size_t t = 0; t < n; ++t)
      for (int d = 0; d < 2; ++d)
        mid[d] += uvy[3 * order[start[c] + t] + d] / (double)n;
    for (size_t t = 0; t < n; ++t) {
      const double* p = uvy + 3 * order[start[c] + t];
      u[t] = p[0] - mid[0];
      v[t] = p[1] - mid[1];
      y[t] = p[2];
    }
    if (two_planes(u, v, y, n, spacing, y + n, y + 2 * n, lab, cells + *k)) {
      cells[*k].x[0] = mid[0];
      cells[*k].x[1] = mid[1];
      ++*k;
    }
  }
}

dacpo_status
dacpo_sheets_cross(
    const double* uvy, size_t m, double spacing, double* crossing, dacpo_err* err)
{
  DACPO_CHECK(err,
              uvy && crossing,
              DACPO_ERR_INVALID_ARGUMENT,
              "sheets cross: NULL array for %zu points",
              m);
  *crossing = 0.0;
  if (m < CROSS_MIN_CELLS * CROSS_MIN_POINTS)
    return DACPO_OK;
  double box[2], cell = 0.0;
  size_t nu = 0, nv = 0, most = 0, k = 0;
  cell_grid(uvy, m, box, &cell, &nu, &nv);
  const size_t nc = nu * nv, most_cells = m / CROSS_MIN_POINTS;
  size_t* start = dacpo_malloc_array(nc + 1, sizeof(size_t));
  size_t* order = dacpo_malloc_array(m, sizeof(size_t));
  cell_sheets* cells = dacpo_malloc_array(most_cells, sizeof(cell_sheets));
  double* scratch = NULL;
  int8_t* lab = NULL;
  if (start && order && cells) {
    bucket_points(uvy, m, box, cell, nu, nv, start, order);
    for (size_t c = 0; c < nc; ++c)
      most = start[c + 1] - start[c] > most ? start[c + 1] - start[c] : most;
    scratch =
        dacpo_malloc_array(5 * (most > most_cells ? most : most_cells), sizeof(double));
    lab = dacpo_malloc_array(most, sizeof(int8_t));
  }
  const dacpo_status st =
      start && order && cells && scratch && lab ? DACPO_OK : DACPO_OOM(err);
  if (st == DACPO_OK) {
    fit_cells(uvy, start, order, nc, spacing, scratch, lab, cells, &k);
    *crossing = crossing_line(cells, k, scratch, scratch + k, scratch + 2 * k);
  }
  free(start);
  free(order);
  free(cells);
  free(scratch);
  free(lab);
  return st;
}
