/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 0 helper: do the scene's surfaces come as offset copies of themselves?
 *
 * Why: views fused with a small registration error (a few millimetres, a
 * fraction of a degree) lay two or more copies of every surface side by side,
 * 0.3-1.5 spacings apart. The thin-part side cue (dacpo_sheet_side.c) reads
 * exactly that as the two faces of a thin solid and makes the copies face away
 * from each other, so one copy of every wall and floor turns inside out; its
 * anchors in stage 5 then flip whole blocks. Measured on generated rooms fused
 * from 3-4 views (100K points, 8-15 mm and 0.2-0.3 degrees apart; seed 1):
 * 10.5-41.1 % wrong with the cue, 5.6-7.2 % without it (CGAL's MST 7.2-10.1 %).
 * No share of the whole cloud tells the two apart (the cue fires on 15-20 % of
 * such a fused room and on 14-15 % of a clean uniform one), but where it fires
 * does: a room's largest plane is its floor, and nothing lies beneath a floor,
 * so a second face there is a copy.
 *
 * The test: the three main directions of the axes (each the most common one
 * among a sample, the next ones roughly perpendicular to those before), along
 * each the slab 3 spacings thick that holds most parallel points; the fullest
 * slab is the band. It must have the scene on one side (a floor, a wall seen
 * from inside). The side test runs on up to DACPO_LAYERED_SAMPLE band
 * points with their 32 nearest neighbours among all points near the band.
 *
 * The side test sees copies that split cleanly in two; real scans of 20 or
 * more frames stack them into a thick layer it does not split. The copy rate
 * counts instead the points of the band's surface that have any second
 * parallel sheet within two spacings (stage 2's two-sheet pair test): on a
 * room's floor that happens only where a thing rests a spacing above it, on a
 * fused floor everywhere. From DACPO_LAYERED_COPIES on the two-sheet rule goes
 * too.
 *
 * Cost: O(n) passes plus a kd-tree over the slab's points and the side test on
 * the sample (a few milliseconds on 100K points). Deterministic.
 */
#include "dacpo_layered.h"

#include "dacpo_dipole.h"
#include "dacpo_kdtree.h"
#include "dacpo_sheet_side.h"
#include "dacpo_sheets_cross.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LAYERED_COS 0.985 /* parallel to a main direction: within ~10 degrees */
/* a later direction: |a.d| below this for the earlier ones */
#define LAYERED_ORTHO 0.2
#define LAYERED_DIRECTIONS 3
#define LAYERED_PROBE 4096 /* points sampled to find the band */
#define LAYERED_CANDIDATES 256
#define LAYERED_BAND 3.0 /* band thickness, spacings */
#define LAYERED_K 32     /* neighbours of the side test (as stage 2 on many views) */
#define LAYERED_CROSS_POINTS 262144 /* slab points the crossing test reads */

#define LAYERED_PAIR_NOISE 3.0 /* stage 2's default two-sheet factor */
#define LAYERED_PAIRS 3
/* cells of the band's footprint along its longer side, at most */
#define LAYERED_GRID 2048.0
/* The band lies under the scene when this share of the points beyond its slab
 * lies over it (values and margins: docs/DESIGN.md, "Copies or thin
 * solids") ... */
#define LAYERED_UNDER 0.5
/* ... its box grown by this share of its smaller side. */
#define LAYERED_UNDER_MARGIN 0.1

static double
dot3(const double* a, const double* b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* 1 if point p (axis a) lies in the band [lo, lo + width] along dir and is
 * parallel to it. */
static int
in_band(const double dir[3], double lo, double width, const double* p, const double* a)
{
  const double y = dot3(dir, p);
  return y >= lo && y <= lo + width && fabs(dot3(dir, a)) > LAYERED_COS;
}

/* 1 if point p lies in the slab [lo - width, lo + 2 width] around the band
 * [lo, lo + width] along dir. */
static int
within_slab(const double dir[3], double lo, double width, const double* p)
{
  const double y = dot3(dir, p);
  return y >= lo - width && y <= lo + 2.0 * width;
}

/* 1 if point p (axis a) lies in the slab and is parallel to the band. */
static int
in_slab(const double dir[3], double lo, double width, const double* p, const double* a)
{
  return within_slab(dir, lo, width, p) && fabs(dot3(dir, a)) > LAYERED_COS;
}

/* The box of the band's points in its plane: frame e1, e2, box = u0, u1, v0,
 * v1 (empty: +inf, -inf). */
static void
band_box(const double* xyz,
         const double* axes,
         size_t n,
         const double dir[3],
         double lo,
         double width,
         double e1[3],
         double e2[3],
         double box[4])
{
  dacpo_tangent_frame(dir, e1, e2);
  box[0] = box[2] = INFINITY;
  box[1] = box[3] = -INFINITY;
  for (size_t i = 0; i < n; ++i) {
    if (!in_band(dir, lo, width, xyz + 3 * i, axes + 3 * i))
      continue;
    const double u = dot3(e1, xyz + 3 * i), v = dot3(e2, xyz + 3 * i);
    box[0] = fmin(box[0], u);
    box[1] = fmax(box[1], u);
    box[2] = fmin(box[2], v);
    box[3] = fmax(box[3], v);
  }
}

/* Stage 2's local noise scale of point i, from its k nearest. */
static double
local_noise(
    const double* xyz, const double* axes, const int32_t* idx, size_t k, size_t i)
{
  return dacpo_two_sheet_noise(xyz + 3 * i, axes + 3 * i, xyz, idx + i * k, k);
}

/* Mean distance of point i's 4 nearest. */
static double
local_spacing(const float* sqd, size_t k, size_t i)
{
  const size_t m = k < 4 ? k : 4;
  double sum = 0.0;
  size_t got = 0;
  for (size_t t = 0; t < m; ++t)
    if (isfinite(sqd[i * k + t])) {
      sum += sqrt((double)sqd[i * k + t]);
      got++;
    }
  return got ? sum / (double)got : 0.0;
}

/* 1 if point i has a second parallel sheet among the m candidates cand
 * (cloud indices; negative ones and i itself are skipped): stage 2's two-sheet
 * pair test, its window two local spacings (window 0: the larger of the two
 * points' own) or, given, two windows. idx, sqd, k: the k-NN rows the local
 * noise and spacing are read from. */
static int
sheet_among(const double* xyz,
            const double* axes,
            const int32_t* idx,
            const float* sqd,
            size_t k,
            size_t i,
            const int32_t* cand,
            size_t m,
            double window,
            double spacing)
{
  const double* p = xyz + 3 * i;
  const double* a = axes + 3 * i;
  const double noise_i = local_noise(xyz, axes, idx, k, i);
  const double local_i = local_spacing(sqd, k, i);
  size_t pairs = 0;
  for (size_t t = 0; t < m && pairs < LAYERED_PAIRS; ++t) {
    if (cand[t] < 0 || (size_t)cand[t] == i)
      continue;
    const size_t j = (size_t)cand[t];
    pairs += dacpo_two_sheet_pair(
        p,
        a,
        xyz + 3 * j,
        axes + 3 * j,
        fmax(noise_i, local_noise(xyz, axes, idx, k, j)),
        window > 0.0 ? window : fmax(local_i, local_spacing(sqd, k, j)),
        LAYERED_PAIR_NOISE,
        spacing);
  }
  return pairs >= LAYERED_PAIRS;
}

/* The densest window [lo, lo + width] of the m sorted values h: its count. */
static size_t
densest_window(const double* h, size_t m, double width, double* lo)
{
  size_t best = 0;
  for (size_t i = 0, j = 0; i < m; ++i) {
    while (j < m && h[j] <= h[i] + width)
      ++j;
    if (j - i > best) {
      best = j - i;
      *lo = h[i];
    }
  }
  return best;
}

/* The band: direction *dir, slab [*lo, *lo + width]; returns its probe count. */
static size_t
find_band(const double* xyz,
          const double* axes,
          const size_t* probe,
          size_t m,
          double width,
          double* h,
          double dir[3],
          double* lo)
{
  double dirs[LAYERED_DIRECTIONS][3];
  size_t best_band = 0;
  for (int r = 0; r < LAYERED_DIRECTIONS; ++r) {
    /* the most common axis among the probe points off the earlier directions */
    size_t best = 0, best_c = 0;
    const size_t step = m > LAYERED_CANDIDATES ? m / LAYERED_CANDIDATES : 1;
    for (size_t c = 0; c < m; c += step) {
      const double* a = axes + 3 * probe[c];
      int off = 1;
      for (int q = 0; q < r && off; ++q)
        off = fabs(dot3(a, dirs[q])) < LAYERED_ORTHO;
      if (!off)
        continue;
      size_t count = 0;
      for (size_t t = 0; t < m; ++t)
        count += fabs(dot3(a, axes + 3 * probe[t])) > LAYERED_COS;
      if (count > best) {
        best = count;
        best_c = c;
      }
    }
    if (best < DACPO_LAYERED_MIN_BAND)
      break;
    /* One point's axis can be a few degrees off the plane's, which tilts the
     * slab across a large floor (2 degrees: 21 cm over 6 m); the mean of the
     * parallel axes (twice) is not. */
    memcpy(dirs[r], axes + 3 * probe[best_c], sizeof(dirs[r]));
    for (int it = 0; it < 2; ++it) {
      double mean[3] = {0.0, 0.0, 0.0};
      for (size_t t = 0; t < m; ++t) {
        const double* a = axes + 3 * probe[t];
        const double d = dot3(a, dirs[r]);
        if (fabs(d) > LAYERED_COS)
          for (int k = 0; k < 3; ++k)
            mean[k] += d > 0.0 ? a[k] : -a[k];
      }
      const double len = sqrt(dot3(mean, mean));
      for (int k = 0; k < 3 && len > 0.0; ++k)
        dirs[r][k] = mean[k] / len;
    }
    size_t k = 0;
    for (size_t t = 0; t < m; ++t)
      if (fabs(dot3(dirs[r], axes + 3 * probe[t])) > LAYERED_COS)
        h[k++] = dot3(dirs[r], xyz + 3 * probe[t]);
    qsort(h, k, sizeof(double), dacpo_cmp_double);
    double at = 0.0;
    const size_t count = densest_window(h, k, width, &at);
    if (count > best_band) {
      best_band = count;
      memcpy(dir, dirs[r], 3 * sizeof(double));
      *lo = at;
    }
  }
  return best_band;
}

/* 1 if the band [lo, lo + width] along dir lies under the scene: at least
 * LAYERED_UNDER of the points beyond the slab lie over the band's box in its
 * plane, grown by LAYERED_UNDER_MARGIN of its smaller side (the walls stand
 * on a floor's edge). A floor lies under the room above it, a wall under the
 * room in front of it; a strip of an object's curved wall with the object on
 * one side (a tube seen from outside) does not: the object reaches past it. */
static int
under_scene(const double* xyz,
            const double* axes,
            size_t n,
            const double dir[3],
            double lo,
            double width)
{
  double e1[3], e2[3], box[4];
  band_box(xyz, axes, n, dir, lo, width, e1, e2, box);
  const double grow = LAYERED_UNDER_MARGIN * fmin(box[1] - box[0], box[3] - box[2]);
  size_t beyond = 0, over = 0;
  for (size_t i = 0; i < n; ++i) {
    if (within_slab(dir, lo, width, xyz + 3 * i))
      continue;
    beyond++;
    const double u = dot3(e1, xyz + 3 * i), v = dot3(e2, xyz + 3 * i);
    over += u >= box[0] - grow && u <= box[1] + grow && v >= box[2] - grow &&
            v <= box[3] + grow;
  }
  return beyond > 0 && (double)over >= LAYERED_UNDER * (double)beyond;
}

/* The slab around the band, [lo - width, lo + 2 width] along dir: its points
 * parallel to the band, projected onto the band's plane (third coordinate 0),
 * and their indices. */
typedef struct {
  dacpo_kdtree* tree; /* over the projected points */
  size_t* index;      /* slab point -> cloud index */
  double e1[3], e2[3];
} slab_plane;

static dacpo_status
slab_plane_build(const double* xyz,
                 const double* axes,
                 size_t n,
                 const double dir[3],
                 double lo,
                 double width,
                 slab_plane* sp,
                 dacpo_err* err)
{
  dacpo_tangent_frame(dir, sp->e1, sp->e2);
  size_t m = 0;
  for (size_t i = 0; i < n; ++i)
    m += in_slab(dir, lo, width, xyz + 3 * i, axes + 3 * i);
  double* uv = dacpo_malloc_array(3 * m, sizeof(double));
  sp->index = dacpo_malloc_array(m, sizeof(size_t));
  dacpo_status st = uv && sp->index ? DACPO_OK : DACPO_OOM(err);
  for (size_t i = 0, t = 0; i < n && st == DACPO_OK; ++i) {
    if (!in_slab(dir, lo, width, xyz + 3 * i, axes + 3 * i))
      continue;
    uv[3 * t] = dot3(sp->e1, xyz + 3 * i);
    uv[3 * t + 1] = dot3(sp->e2, xyz + 3 * i);
    uv[3 * t + 2] = 0.0;
    sp->index[t++] = i;
  }
  if (st == DACPO_OK)
    st = dacpo_kdtree_build(uv, m, &sp->tree, err);
  free(uv);
  return st;
}

/* 1 if point i has a second parallel sheet anywhere in the slab: among its
 * LAYERED_K nearest slab points in the plane (every copy stacked over it, where
 * its nearest in space all lie on its own copy), stage 2's pair test with the
 * window widened to the slab's reach beyond the band (2 x width). */
static int
has_sheet_in_slab(const double* xyz,
                  const double* axes,
                  const int32_t* idx,
                  const float* sqd,
                  size_t k,
                  const slab_plane* sp,
                  size_t i,
                  double width,
                  double spacing)
{
  const double* p = xyz + 3 * i;
  const double q[3] = {dot3(sp->e1, p), dot3(sp->e2, p), 0.0};
  int32_t nb[LAYERED_K + 1];
  double d2[LAYERED_K + 1];
  const size_t got = dacpo_kdtree_knn(sp->tree, q, LAYERED_K + 1, nb, d2);
  for (size_t t = 0; t < got; ++t)
    nb[t] = (int32_t)sp->index[nb[t]];
  return sheet_among(xyz, axes, idx, sqd, k, i, nb, got, width, spacing);
}

/* The surface itself: the densest slab one spacing thick within the band
 * [lo, lo + width] along dir (a thing resting a spacing above the floor is not
 * sampled; a copy of the floor within two spacings of it still counts). Its
 * start in *at, its count returned. */
static dacpo_status
band_surface(const double* xyz,
             const double* axes,
             size_t n,
             const double dir[3],
             double lo,
             double width,
             size_t nb_band,
             double spacing,
             double* at,
             size_t* on_surface,
             dacpo_err* err)
{
  double* y = dacpo_malloc_array(nb_band, sizeof(double));
  if (!y)
    return DACPO_OOM(err);
  size_t ny = 0;
  for (size_t i = 0; i < n && ny < nb_band; ++i) {
    if (in_band(dir, lo, width, xyz + 3 * i, axes + 3 * i))
      y[ny++] = dot3(dir, xyz + 3 * i);
  }
  qsort(y, ny, sizeof(double), dacpo_cmp_double);
  *at = lo;
  *on_surface = densest_window(y, ny, spacing, at);
  free(y);
  return DACPO_OK;
}

/* The copy rates of the band [lo, lo + width] along dir (nb_band points),
 * over up to DACPO_LAYERED_SAMPLE points of its surface: *rate, the share
 * with a second parallel sheet among their nearest (stage 2's two-sheet pair
 * test), and *doubled, the share with one anywhere in the slab. */
static dacpo_status
copy_rates(const double* xyz,
           const double* axes,
           size_t n,
           const int32_t* knn_idx,
           const float* knn_sqd,
           size_t knn_k,
           const double dir[3],
           double lo,
           double width,
           size_t nb_band,
           double spacing,
           double* rate,
           double* doubled,
           dacpo_err* err)
{
  double at = lo;
  size_t on_surface = 0;
  DACPO_TRY(band_surface(
      xyz, axes, n, dir, lo, width, nb_band, spacing, &at, &on_surface, err));
  slab_plane sp = {NULL, NULL, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
  dacpo_status st = slab_plane_build(xyz, axes, n, dir, lo, width, &sp, err);
  /* every (on_surface / s)-th point of it */
  const size_t s =
      on_surface < DACPO_LAYERED_SAMPLE ? on_surface : DACPO_LAYERED_SAMPLE;
  size_t seen = 0, taken = 0, copies = 0, stacked = 0;
  for (size_t i = 0; i < n && taken < s && st == DACPO_OK; ++i) {
    if (!in_band(dir, at, spacing, xyz + 3 * i, axes + 3 * i))
      continue;
    if (seen++ * s >= taken * on_surface) {
      taken++;
      copies += sheet_among(xyz,
                            axes,
                            knn_idx,
                            knn_sqd,
                            knn_k,
                            i,
                            knn_idx + i * knn_k,
                            knn_k,
                            0.0,
                            spacing);
      stacked +=
          has_sheet_in_slab(xyz, axes, knn_idx, knn_sqd, knn_k, &sp, i, width, spacing);
    }
  }
  dacpo_kdtree_free(sp.tree);
  free(sp.index);
  *rate = taken ? (double)copies / (double)taken : 0.0;
  *doubled = taken ? (double)stacked / (double)taken : 0.0;
  return st;
}

/* The cell of (u, v) in a grid of nv cells per row over box (u0, u1, v0, v1). */
static size_t
footprint_cell(double u, double v, const double box[4], double cell, size_t nv)
{
  return (size_t)((u - box[0]) / cell) * nv + (size_t)((v - box[2]) / cell);
}

/* The points beyond the slab [lo - width, lo + 2 width] along dir on the side
 * with fewer of them (below: the lower side) that lie under the band: in a
 * cell (width wide, in the band's plane) that holds a band point. A floor has
 * nothing beneath it; things beside it (a lower floor through a doorway) are
 * not beneath it. */
static dacpo_status
minority_under_band(const double* xyz,
                    const double* axes,
                    size_t n,
                    const double dir[3],
                    double lo,
                    double width,
                    int below,
                    size_t* count,
                    dacpo_err* err)
{
  double e1[3], e2[3], box[4];
  band_box(xyz, axes, n, dir, lo, width, e1, e2, box);
  const double u0 = box[0], u1 = box[1], v0 = box[2], v1 = box[3];
  /* at most LAYERED_GRID cells along either side */
  const double cell = fmax(width, fmax(u1 - u0, v1 - v0) / LAYERED_GRID);
  const size_t nu = (size_t)((u1 - u0) / cell) + 1, nv = (size_t)((v1 - v0) / cell) + 1;
  unsigned char* under = calloc(nu * nv, 1);
  if (!under)
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i) /* band points lie in the box by construction */
    if (in_band(dir, lo, width, xyz + 3 * i, axes + 3 * i))
      under[footprint_cell(
          dot3(e1, xyz + 3 * i), dot3(e2, xyz + 3 * i), box, cell, nv)] = 1;
  *count = 0;
  for (size_t i = 0; i < n; ++i) {
    const double y = dot3(dir, xyz + 3 * i);
    const double u = dot3(e1, xyz + 3 * i), v = dot3(e2, xyz + 3 * i);
    if ((below ? y < lo - width : y > lo + 2.0 * width) && u >= u0 && u <= u1 &&
        v >= v0 && v <= v1)
      *count += under[footprint_cell(u, v, box, cell, nv)];
  }
  free(under);
  return DACPO_OK;
}

/* The spacing (median nearest-neighbour distance over a probe of the points)
 * and the band of find_band, its probe count in *band (0: none). */
static dacpo_status
probe_band(const double* xyz,
           const double* axes,
           size_t n,
           const float* knn_sqd,
           size_t knn_k,
           double* spacing,
           double dir[3],
           double* lo,
           size_t* band,
           dacpo_err* err)
{
  const size_t m = n < LAYERED_PROBE ? n : LAYERED_PROBE;
  size_t* probe = dacpo_malloc_array(m, sizeof(size_t));
  double* h = dacpo_malloc_array(m, sizeof(double));
  if (!probe || !h) {
    free(probe);
    free(h);
    return DACPO_OOM(err);
  }
  size_t finite = 0;
  for (size_t t = 0; t < m; ++t) {
    probe[t] = (size_t)((double)t * (double)n / (double)m);
    const double d2 = (double)knn_sqd[probe[t] * knn_k];
    if (isfinite(d2))
      h[finite++] = sqrt(d2);
  }
  *spacing = finite ? dacpo_select_kth(h, finite, finite / 2) : 0.0;
  *band = *spacing > 0.0
              ? find_band(xyz, axes, probe, m, LAYERED_BAND * *spacing, h, dir, lo)
              : 0;
  free(probe);
  free(h);
  return DACPO_OK;
}

/* dacpo_sheets_cross on the points of the slab around the band parallel to
 * it (every step-th where there are more than LAYERED_CROSS_POINTS), in the
 * band's frame. */
static dacpo_status
slab_crossing(const double* xyz,
              const double* axes,
              size_t n,
              const double dir[3],
              double lo,
              double width,
              double spacing,
              double* crossing,
              dacpo_err* err)
{
  size_t in = 0;
  for (size_t i = 0; i < n; ++i)
    in += in_slab(dir, lo, width, xyz + 3 * i, axes + 3 * i);
  /* every step-th of them: at most LAYERED_CROSS_POINTS */
  const size_t step = in > LAYERED_CROSS_POINTS ? in / LAYERED_CROSS_POINTS + 1 : 1;
  double* uvy = dacpo_malloc_array(3 * (in / step + 1), sizeof(double));
  if (!uvy)
    return DACPO_OOM(err);
  double e1[3], e2[3];
  dacpo_tangent_frame(dir, e1, e2);
  size_t seen = 0, m = 0;
  for (size_t i = 0; i < n; ++i)
    if (in_slab(dir, lo, width, xyz + 3 * i, axes + 3 * i) && seen++ % step == 0) {
      uvy[3 * m] = dot3(e1, xyz + 3 * i);
      uvy[3 * m + 1] = dot3(e2, xyz + 3 * i);
      uvy[3 * m++ + 2] = dot3(dir, xyz + 3 * i);
    }
  const dacpo_status st = dacpo_sheets_cross(uvy, m, spacing, crossing, err);
  free(uvy);
  return st;
}

/* Row t of the side test's local set: sample point pick (slab index) at
 * position t, its LAYERED_K nearest slab points copied to positions
 * s + t LAYERED_K ..., padded with copies of itself. */
static void
local_rows(const dacpo_kdtree* tree,
           const double* sxyz,
           const double* saxes,
           size_t pick,
           size_t t,
           size_t s,
           double* lxyz,
           double* laxes,
           int32_t* lnb)
{
  int32_t idx[LAYERED_K + 1];
  double d2[LAYERED_K + 1];
  const size_t got = dacpo_kdtree_knn(tree, sxyz + 3 * pick, LAYERED_K + 1, idx, d2);
  memcpy(lxyz + 3 * t, sxyz + 3 * pick, 3 * sizeof(double));
  memcpy(laxes + 3 * t, saxes + 3 * pick, 3 * sizeof(double));
  size_t row = 0;
  for (size_t j = 0; j < got && row < LAYERED_K; ++j) {
    if ((size_t)idx[j] == pick)
      continue;
    const size_t l = s + t * LAYERED_K + row;
    memcpy(lxyz + 3 * l, sxyz + 3 * (size_t)idx[j], 3 * sizeof(double));
    memcpy(laxes + 3 * l, saxes + 3 * (size_t)idx[j], 3 * sizeof(double));
    lnb[t * LAYERED_K + row++] = (int32_t)l;
  }
  for (; row < LAYERED_K; ++row) {
    const size_t l = s + t * LAYERED_K + row;
    memcpy(lxyz + 3 * l, lxyz + 3 * t, 3 * sizeof(double));
    memcpy(laxes + 3 * l, laxes + 3 * t, 3 * sizeof(double));
    lnb[t * LAYERED_K + row] = (int32_t)t;
  }
}

/* The side test (dacpo_sheet_side, LAYERED_K neighbours) on up to
 * DACPO_LAYERED_SAMPLE of the nb_band band points, each with its neighbours
 * among the ns points of the slab around the band: *share is the share of
 * them where it finds a second face. */
static dacpo_status
side_share(const double* xyz,
           const double* axes,
           size_t n,
           const double dir[3],
           double lo,
           double width,
           size_t ns,
           size_t nb_band,
           double spacing,
           double* share,
           dacpo_err* err)
{
  const size_t s = nb_band < DACPO_LAYERED_SAMPLE ? nb_band : DACPO_LAYERED_SAMPLE;
  const size_t nl = s * (LAYERED_K + 1);
  double* sxyz = dacpo_malloc_array(3 * ns, sizeof(double));
  double* saxes = dacpo_malloc_array(3 * ns, sizeof(double));
  size_t* pick = dacpo_malloc_array(s, sizeof(size_t)); /* slab index of sample t */
  double* lxyz = dacpo_malloc_array(3 * nl, sizeof(double));
  double* laxes = dacpo_malloc_array(3 * nl, sizeof(double));
  int32_t* lnb = dacpo_malloc_array(nl * LAYERED_K, sizeof(int32_t));
  double* side = dacpo_malloc_array(nl, sizeof(double));
  dacpo_kdtree* tree = NULL;
  dacpo_status st =
      sxyz && saxes && pick && lxyz && laxes && lnb && side ? DACPO_OK : DACPO_OOM(err);
  size_t at = 0, seen = 0, taken = 0;
  for (size_t i = 0; i < n && st == DACPO_OK; ++i) {
    if (!within_slab(dir, lo, width, xyz + 3 * i))
      continue;
    memcpy(sxyz + 3 * at, xyz + 3 * i, 3 * sizeof(double));
    memcpy(saxes + 3 * at, axes + 3 * i, 3 * sizeof(double));
    if (in_band(dir, lo, width, xyz + 3 * i, axes + 3 * i)) {
      /* every (nb_band / s)-th band point */
      if (taken < s && seen * s >= taken * nb_band)
        pick[taken++] = at;
      seen++;
    }
    at++;
  }
  if (st == DACPO_OK)
    st = dacpo_kdtree_build(sxyz, ns, &tree, err);
  /* local set: the s sample points, then each one's neighbours (copies; their
   * own rows point at themselves, so the test stays silent on them) */
  for (size_t t = 0; t < s && st == DACPO_OK; ++t)
    local_rows(tree, sxyz, saxes, pick[t], t, s, lxyz, laxes, lnb);
  for (size_t l = s; l < s + s * LAYERED_K && st == DACPO_OK; ++l)
    for (size_t j = 0; j < LAYERED_K; ++j)
      lnb[l * LAYERED_K + j] = (int32_t)l;
  if (st == DACPO_OK)
    st = dacpo_sheet_side(lxyz,
                          laxes,
                          s + s * LAYERED_K,
                          lnb,
                          LAYERED_K,
                          LAYERED_K,
                          spacing,
                          side,
                          NULL,
                          NULL,
                          err);
  if (st == DACPO_OK) {
    size_t fired = 0;
    for (size_t t = 0; t < s; ++t)
      fired += side[t] != 0.0;
    *share = (double)fired / (double)s;
  }
  dacpo_kdtree_free(tree);
  free(sxyz);
  free(saxes);
  free(pick);
  free(lxyz);
  free(laxes);
  free(lnb);
  free(side);
  return st;
}

dacpo_status
dacpo_layered_share(const double* xyz,
                    const double* axes,
                    size_t n,
                    const int32_t* knn_idx,
                    const float* knn_sqd,
                    size_t knn_k,
                    double* share,
                    double* copies,
                    double* doubled,
                    double* crossing,
                    dacpo_err* err)
{
  DACPO_CHECK(err,
              xyz && axes && knn_idx && knn_sqd && share && copies && doubled &&
                  crossing,
              DACPO_ERR_INVALID_ARGUMENT,
              "layered test: NULL argument");
  *share = 0.0;
  *copies = 0.0;
  *doubled = 0.0;
  *crossing = 0.0;
  if (n <= LAYERED_K || knn_k < LAYERED_PAIRS)
    return DACPO_OK;
  double spacing = 0.0, dir[3] = {0.0, 0.0, 0.0}, lo = 0.0;
  size_t band = 0;
  DACPO_TRY(probe_band(xyz, axes, n, knn_sqd, knn_k, &spacing, dir, &lo, &band, err));
  const double width = LAYERED_BAND * spacing;
  if (band < DACPO_LAYERED_MIN_BAND)
    return DACPO_OK;

  /* the slab around the band (any axis: the neighbours), its band points, and
   * the points beyond the slab on either side */
  size_t ns = 0, nb_band = 0, below = 0, above = 0;
  for (size_t i = 0; i < n; ++i) {
    const double y = dot3(dir, xyz + 3 * i);
    if (y < lo - width)
      below++;
    else if (y > lo + 2.0 * width)
      above++;
    else {
      ns++;
      nb_band += in_band(dir, lo, width, xyz + 3 * i, axes + 3 * i);
    }
  }
  if (nb_band < DACPO_LAYERED_MIN_BAND)
    return DACPO_OK;
  /* Two sheets that cross are copies wherever the scene lies. Otherwise only
   * a plane with the scene on one side of it, like a floor or a wall seen
   * from inside, cannot be a thin solid: a board or a partition has things
   * on both sides, or nothing at all (a scan of one board). */
  DACPO_TRY(slab_crossing(xyz, axes, n, dir, lo, width, spacing, crossing, err));
  const size_t beyond = below + above;
  size_t minority = 0;
  if (*crossing == 0.0 && (double)beyond < DACPO_LAYERED_MIN_BEYOND * (double)n)
    return DACPO_OK;
  if (*crossing == 0.0)
    DACPO_TRY(minority_under_band(
        xyz, axes, n, dir, lo, width, below < above, &minority, err));
  if ((double)minority > DACPO_LAYERED_MAX_OTHER_SIDE * (double)beyond)
    return DACPO_OK;
  if (*crossing > 0.0 || under_scene(xyz, axes, n, dir, lo, width))
    DACPO_TRY(copy_rates(xyz,
                         axes,
                         n,
                         knn_idx,
                         knn_sqd,
                         knn_k,
                         dir,
                         lo,
                         width,
                         nb_band,
                         spacing,
                         copies,
                         doubled,
                         err));
  return side_share(xyz, axes, n, dir, lo, width, ns, nb_band, spacing, share, err);
}
