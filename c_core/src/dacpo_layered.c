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
 * Cost: O(n) passes plus a kd-tree over the slab's points and the side test on
 * the sample (a few milliseconds on 100K points). Deterministic.
 */
#include "dacpo_layered.h"

#include "dacpo_kdtree.h"
#include "dacpo_sheet_side.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LAYERED_COS 0.985   /* parallel to a main direction: within ~10 degrees */
#define LAYERED_ORTHO 0.2   /* a later direction: |a.d| below this for the earlier ones */
#define LAYERED_DIRECTIONS 3
#define LAYERED_PROBE 4096  /* points sampled to find the band */
#define LAYERED_CANDIDATES 256
#define LAYERED_BAND 3.0    /* band thickness, spacings */
#define LAYERED_K 32        /* neighbours of the side test (as stage 2 on many views) */

static double
dot3(const double* a, const double* b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
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

dacpo_status
dacpo_layered_share(const double* xyz,
                    const double* axes,
                    size_t n,
                    const float* knn_sqd,
                    size_t knn_k,
                    double* share,
                    dacpo_err* err)
{
  DACPO_CHECK(err,
              xyz && axes && knn_sqd && share,
              DACPO_ERR_INVALID_ARGUMENT,
              "layered test: NULL argument");
  *share = 0.0;
  if (n <= LAYERED_K || knn_k == 0)
    return DACPO_OK;
  const size_t m = n < LAYERED_PROBE ? n : LAYERED_PROBE;
  size_t* probe = dacpo_malloc_array(m, sizeof(size_t));
  double* h = dacpo_malloc_array(m, sizeof(double));
  if (!probe || !h) {
    free(probe);
    free(h);
    return DACPO_OOM(err);
  }
  /* the spacing: median nearest-neighbour distance over the probe */
  size_t finite = 0;
  for (size_t t = 0; t < m; ++t) {
    probe[t] = (size_t)((double)t * (double)n / (double)m);
    const double d2 = (double)knn_sqd[probe[t] * knn_k];
    if (isfinite(d2))
      h[finite++] = sqrt(d2);
  }
  const double spacing = finite ? dacpo_select_kth(h, finite, finite / 2) : 0.0;
  const double width = LAYERED_BAND * spacing;
  double dir[3] = {0.0, 0.0, 0.0}, lo = 0.0;
  const size_t band =
      spacing > 0.0 ? find_band(xyz, axes, probe, m, width, h, dir, &lo) : 0;
  free(probe);
  free(h);
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
      nb_band += y >= lo && y <= lo + width && fabs(dot3(dir, axes + 3 * i)) > LAYERED_COS;
    }
  }
  /* Only a plane with the scene on one side of it, like a floor or a wall
   * seen from inside, cannot be a thin solid: a board or a partition has
   * things on both sides, or nothing at all (a scan of one board). */
  const size_t beyond = below + above;
  const size_t minority = below < above ? below : above;
  if (nb_band < DACPO_LAYERED_MIN_BAND ||
      (double)beyond < DACPO_LAYERED_MIN_BEYOND * (double)n ||
      (double)minority > DACPO_LAYERED_MAX_OTHER_SIDE * (double)beyond)
    return DACPO_OK;
  const size_t s = nb_band < DACPO_LAYERED_SAMPLE ? nb_band : DACPO_LAYERED_SAMPLE;
  const size_t nl = s * (LAYERED_K + 1);
  double* sxyz = dacpo_malloc_array(3 * ns, sizeof(double));
  double* saxes = dacpo_malloc_array(3 * ns, sizeof(double));
  size_t* pick = dacpo_malloc_array(s, sizeof(size_t)); /* slab index of sample t */
  double* lxyz = dacpo_malloc_array(3 * nl, sizeof(double));
  double* laxes = dacpo_malloc_array(3 * nl, sizeof(double));
  int32_t* lnb = dacpo_malloc_array(nl * LAYERED_K, sizeof(int32_t));
  double* side = dacpo_malloc_array(nl, sizeof(double));
  int32_t idx[LAYERED_K + 1];
  double d2[LAYERED_K + 1];
  dacpo_kdtree* tree = NULL;
  dacpo_status st = sxyz && saxes && pick && lxyz && laxes && lnb && side ? DACPO_OK
                                                                           : DACPO_OOM(err);
  size_t at = 0, seen = 0, taken = 0;
  for (size_t i = 0; i < n && st == DACPO_OK; ++i) {
    const double y = dot3(dir, xyz + 3 * i);
    if (y < lo - width || y > lo + 2.0 * width)
      continue;
    memcpy(sxyz + 3 * at, xyz + 3 * i, 3 * sizeof(double));
    memcpy(saxes + 3 * at, axes + 3 * i, 3 * sizeof(double));
    if (y >= lo && y <= lo + width && fabs(dot3(dir, axes + 3 * i)) > LAYERED_COS) {
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
  for (size_t t = 0; t < s && st == DACPO_OK; ++t) {
    const size_t got = dacpo_kdtree_knn(tree, sxyz + 3 * pick[t], LAYERED_K + 1, idx, d2);
    memcpy(lxyz + 3 * t, sxyz + 3 * pick[t], 3 * sizeof(double));
    memcpy(laxes + 3 * t, saxes + 3 * pick[t], 3 * sizeof(double));
    size_t row = 0;
    for (size_t j = 0; j < got && row < LAYERED_K; ++j) {
      if ((size_t)idx[j] == pick[t])
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
