/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 2, the cached pair energies (paper Eq. 1-2) that dacpo_dipole.c's
 * orders, restarts and vote sum: each point's K nearest, the two-sheet, layer
 * and c_thin rules that replace Eq. 2 for some pairs, and the side cue's field.
 * Built once per block before any order runs, hence a file of its own. */
#include "dacpo_dipole_internal.h"
#include "dacpo_kdtree.h"
#include "dacpo_sheet_side.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double
dacpo_dipole_energy(const double p[3],
                    const double n[3],
                    const double q[3],
                    const double m[3],
                    double c)
{
  const double r[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
  const double scale =
      p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
  /* |r| below 1e-12 of the coordinates' magnitude is a (near) duplicate whose
   * direction r^ is rounding noise; the absolute floor keeps 1/|r|^3 finite.
   * Written as !(a > b) so a NaN also gives 0. */
  if (!(rr > 1e-24 * scale) || rr < 1e-150)
    return 0.0;
  const double rn = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
  const double rm = r[0] * m[0] + r[1] * m[1] + r[2] * m[2];
  const double nm = n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
  /* Eq. 1-2: F.m = -(c (r^.n)(r^.m) - n.m) / |r|^3. Note the value is symmetric
   * under swapping (p,n) and (q,m): r -> -r leaves (r^.n)(r^.m) unchanged. */
  return (nm - c * rn * rm / rr) / (rr * sqrt(rr));
}

/* Signed offset of q from the plane through p with unit normal a. */
static inline double
plane_offset(const double p[3], const double a[3], const double q[3])
{
  return (q[0] - p[0]) * a[0] + (q[1] - p[1]) * a[1] + (q[2] - p[2]) * a[2];
}

/* Two sheets of one thin part (a table top, a shelf board, a partition) lie a
 * gap of about one spacing apart with parallel axes. Eq. 1 gives such a pair a
 * stacked term -c (r^.n)(r^.m) that only wins for neighbours nearly straight
 * across the gap; summed over a plane it is 2 pi / d (1 - c / 3), so for c < 3
 * the other sheet's K nearest align the sheets, a whole face comes out
 * reversed and the block energy prefers it (room: energy of the ground truth
 * 0.91 x that of the reversed face at c = 1.5). The pair is recognised
 * geometrically instead: axes within ~37 degrees, and each point off the
 * other's tangent plane by more than
 *   tau = max(factor x local noise, 0.5 x spacing) + lateral x sin(angle)
 * (the last term excuses the bend of one curved sheet: offset ~ lateral
 * distance x angle between its normals) but by less than 2 local spacings
 * (single depth frames have layers 3.5-4 spacings apart from depth
 * quantisation, all facing the sensor). The local noise of a point is the 25th
 * percentile of |offset| of its 16 nearest from its tangent plane: low enough
 * that the other sheet (up to half the neighbours) does not count as noise,
 * high enough to follow depth noise that grows across a frame. Measured on
 * ground truth, these pairs face opposite ways in 97-100 % of cases on rooms,
 * and 0-2 % on single depth frames before the point test below. */
typedef struct two_sheet_scale {
  double* noise;  /* n: local noise scale per point */
  double* local;  /* n: local spacing (mean distance of the 4 nearest) */
  uint8_t* sheet; /* n: 1 = the point has a second sheet beneath it */
  double spacing; /* block median nearest-neighbour distance */
  double factor;  /* dacpo_dipole_params.two_sheet */
  double layers;  /* dacpo_dipole_params.layers; 0 if the block is two-sided */
  double c_thin;  /* dacpo_dipole_params.c_thin if the block is two-sided, else 0 */
} two_sheet_scale;

#define DACPO_TWO_SHEET_NEAREST 16
#define DACPO_TWO_SHEET_MIN_COS 0.8
#define DACPO_TWO_SHEET_MIN_SPACING 0.5 /* x block spacing */
#define DACPO_TWO_SHEET_MAX_GAP 2.0     /* x local spacing */
#define DACPO_TWO_SHEET_WEIGHT 3.0
/* A block is seen from one side when under this share of its points has a
 * second sheet beneath it. Measured per block (on blocks of ~2,500 points;
 * today's default is ~625): single depth
 * frames 0-2.6 %, room blocks holding thin furniture mostly 3-53 %; blocks of
 * sparse rooms (10K points), whose thin parts lie closer than the two-sheet
 * test resolves, also stay below: there the rule keeps to offsets beyond the
 * two-sheet window (dacpo_params.dipole_layers = 2 by default). */
#define DACPO_ONE_SIDED_MAX_SHEET 0.03

double
dacpo_two_sheet_noise(const double p[3],
                      const double a[3],
                      const double* xyz,
                      const int32_t* row,
                      size_t m)
{
  double off[DACPO_TWO_SHEET_NEAREST];
  if (m > DACPO_TWO_SHEET_NEAREST)
    m = DACPO_TWO_SHEET_NEAREST;
  size_t got = 0;
  for (size_t t = 0; t < m; ++t)
    if (row[t] >= 0)
      off[got++] = fabs(plane_offset(p, a, xyz + 3 * (size_t)row[t]));
  return got ? dacpo_select_kth(off, got, got / 4) : 0.0;
}

static dacpo_status
two_sheet_scales(const double* xyz,
                 const double* nrm,
                 size_t n,
                 size_t K,
                 dipole_work* wk,
                 two_sheet_scale* ts,
                 dacpo_err* err)
{
  ts->noise = dacpo_malloc_array(n, sizeof(double));
  ts->local = dacpo_malloc_array(n, sizeof(double));
  ts->sheet = dacpo_calloc_array(n, sizeof(uint8_t));
  if (!ts->noise || !ts->local || !ts->sheet)
    return DACPO_OOM(err);
  double* tmp = wk->w; /* scratch until the energies are written */
  for (size_t i = 0; i < n; ++i) {
    const double* p = xyz + 3 * i;
    ts->noise[i] = dacpo_two_sheet_noise(p, nrm + 3 * i, xyz, wk->nb + i * K, K);
    double sum = 0.0;
    const size_t near = K < 4 ? K : 4;
    for (size_t t = 0; t < near; ++t) {
      const double* q = xyz + 3 * (size_t)wk->nb[i * K + t];
      const double d =
          sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
               (q[2] - p[2]) * (q[2] - p[2]));
      if (t == 0)
        tmp[i] = d;
      sum += d;
    }
    ts->local[i] = sum / (double)near;
  }
  ts->spacing = dacpo_select_kth(tmp, n, n / 2);
  return DACPO_OK;
}

static int
two_sheet_pair(const two_sheet_scale* ts,
               const double* p,
               const double* a,
               size_t i,
               const double* q,
               const double* b,
               size_t j);

/* A point has a second sheet when at least 3 of its K nearest pass the pair
 * test, >= 80 % of them on one side of its tangent plane (noise scatters to
 * both sides) and spread around it (|mean lateral vector| < half their mean
 * lateral distance). That rules out the layers of a single view - an object
 * in front of a wall, a step - whose far layer lies beside the near one's
 * edge, never beneath it, and which face the same way. */
static void
two_sheet_points(const double* xyz,
                 const double* nrm,
                 size_t n,
                 size_t K,
                 const int32_t* nb,
                 two_sheet_scale* ts)
{
  for (size_t i = 0; i < n; ++i) {
    const double* p = xyz + 3 * i;
    const double* a = nrm + 3 * i;
    size_t count = 0;
    double side = 0.0, lat_len = 0.0, lat[3] = {0.0, 0.0, 0.0};
    for (size_t t = 0; t < K; ++t) {
      const size_t j = (size_t)nb[i * K + t];
      const double* q = xyz + 3 * j;
      if (j == i || !two_sheet_pair(ts, p, a, i, q, nrm + 3 * j, j))
        continue;
      const double r[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
      const double o = r[0] * a[0] + r[1] * a[1] + r[2] * a[2];
      const double l[3] = {r[0] - o * a[0], r[1] - o * a[1], r[2] - o * a[2]};
      ++count;
      side += o > 0.0 ? 1.0 : -1.0;
      lat[0] += l[0];
      lat[1] += l[1];
      lat[2] += l[2];
      lat_len += sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    }
    const double mean_lat = sqrt(lat[0] * lat[0] + lat[1] * lat[1] + lat[2] * lat[2]);
    ts->sheet[i] =
        count >= 3 && fabs(side) >= 0.8 * (double)count && mean_lat < 0.5 * lat_len;
  }
}

int
dacpo_two_sheet_pair(const double p[3],
                     const double a[3],
                     const double q[3],
                     const double b[3],
                     double noise,
                     double local,
                     double factor,
                     double spacing)
{
  const double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  if (fabs(ab) < DACPO_TWO_SHEET_MIN_COS)
    return 0;
  const double r[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
  const double oa = fabs(r[0] * a[0] + r[1] * a[1] + r[2] * a[2]);
  const double ob = fabs(r[0] * b[0] + r[1] * b[1] + r[2] * b[2]);
  double tau = factor * noise;
  if (tau < DACPO_TWO_SHEET_MIN_SPACING * spacing)
    tau = DACPO_TWO_SHEET_MIN_SPACING * spacing;
  const double lateral = sqrt(rr - oa * oa > 0.0 ? rr - oa * oa : 0.0);
  const double sin_ab = sqrt(1.0 - ab * ab > 0.0 ? 1.0 - ab * ab : 0.0);
  tau += lateral * sin_ab;
  const double o = oa < ob ? oa : ob;
  return tau > 0.0 && o > tau && o < DACPO_TWO_SHEET_MAX_GAP * local;
}

/* 1 if (p, axis a, point index i) and (q, axis b, index j) are two sheets. */
static int
two_sheet_pair(const two_sheet_scale* ts,
               const double* p,
               const double* a,
               size_t i,
               const double* q,
               const double* b,
               size_t j)
{
  const double noise = ts->noise[i] > ts->noise[j] ? ts->noise[i] : ts->noise[j];
  const double local = ts->local[i] > ts->local[j] ? ts->local[i] : ts->local[j];
  return dacpo_two_sheet_pair(p, a, q, b, noise, local, ts->factor, ts->spacing);
}

/* Surfaces seen from one side (a single depth frame, a registered scan without
 * two-sided parts) come as layers: depth quantisation and misregistration stack
 * copies of one surface a few spacings apart along its normal. Eq. 1's stacked
 * term reads such a pair as "opposite"; measured with PCA axes, parallel pairs
 * offset by 0.5-2 spacings (two-sheet pairs aside) face the same way in
 * 98-99.8 % of cases on single depth frames, and the opposite way in 72-97 % on
 * dense rooms with thin parts (26-58 % on 10K-point rooms), so the rule is
 * applied only in blocks where the two-sheet test finds (almost) no thin part;
 * sparse rooms pass that test too, so by default only offsets beyond the
 * two-sheet window (2 spacings) count as layers.
 * For a layer pair c = 1: e becomes n.(I - r^r^T).m / |r|^3, the stacked
 * direction carries no vote. */
static int
layer_pair(const two_sheet_scale* ts,
           const double* p,
           const double* a,
           size_t i,
           const double* q,
           const double* b,
           size_t j)
{
  if (fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) <= DACPO_TWO_SHEET_MIN_COS)
    return 0;
  const double oa = fabs(plane_offset(p, a, q));
  const double ob = fabs(plane_offset(p, b, q));
  const double local = ts->local[i] > ts->local[j] ? ts->local[i] : ts->local[j];
  return (oa < ob ? oa : ob) > ts->layers * local;
}

/* Two sheets of one thin part face opposite ways: e = -3 (n.m)/|r|^3, three
 * times the coplanar magnitude of Eq. 1, so the other sheet outweighs the
 * far-field alignment of its remaining neighbours (measured: 1x gained half as
 * much on the rooms). Symmetric in (p, n) and (q, m). */
static double
two_sheet_energy(const double* p, const double* n, const double* q, const double* m)
{
  const double r[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
  const double nm = n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
  return -DACPO_TWO_SHEET_WEIGHT * nm / (rr * sqrt(rr));
}

/* Paper §4.2 sets c = 4 for clean and 2 for noisy data: a small c resists
 * noise, which moves points off each other's tangent plane and which Eq. 1
 * reads as "stacked" for large c; a large c keeps the faces of thin parts,
 * board edges and bends apart. Where a block holds thin two-sided parts, a
 * pair offset along both normals by more than two_sheet x the local noise of
 * either point (the two-sheet test's noise scale) is geometry, not noise, and
 * gets the clean-data constant. Measured (seeds 1-5, see docs/DESIGN.md): the
 * rooms' error falls most on their noisy variants; single depth frames, whose
 * blocks are almost all seen from one side, keep c (one of 15 moved 0.04). */
static int
beyond_noise(const two_sheet_scale* ts,
             const double* p,
             const double* nj,
             size_t j,
             const double* q,
             const double* ni,
             size_t i)
{
  const double noise = ts->noise[i] > ts->noise[j] ? ts->noise[i] : ts->noise[j];
  const double off_j = fabs(plane_offset(p, nj, q));
  const double off_i = fabs(plane_offset(p, ni, q));
  return (off_j < off_i ? off_j : off_i) > ts->factor * noise;
}

/* Eq. 4's cached energy of neighbour j acting on point i (axes unflipped):
 * Eq. 1-2 with constant c, except for two sheets of one thin part (opposite),
 * layers of a one-sided surface (c = 1) and, in a block with thin two-sided
 * parts, pairs off each other's tangent plane beyond the two-sheet noise test
 * (c_thin). */
static double
pair_energy(const two_sheet_scale* ts,
            const double* xyz,
            const double* nrm,
            size_t i,
            size_t j,
            double c)
{
  const double* p = xyz + 3 * j;
  const double* q = xyz + 3 * i;
  const double* nj = nrm + 3 * j;
  const double* ni = nrm + 3 * i;
  if (ts->sheet && ts->sheet[i] && ts->sheet[j] &&
      two_sheet_pair(ts, p, nj, j, q, ni, i)) {
    return two_sheet_energy(p, nj, q, ni);
  }
  if (ts->layers > 0.0 && layer_pair(ts, p, nj, j, q, ni, i))
    return dacpo_dipole_energy(p, nj, q, ni, 1.0);
  double ce = c;
  if (ts->c_thin > 0.0 && beyond_noise(ts, p, nj, j, q, ni, i))
    ce = ts->c_thin;
  /* Eq. 4: the field of the (earlier placed) neighbour j acting on i. */
  return dacpo_dipole_energy(p, nj, q, ni, ce);
}

/* Scales, two-sheet points and the one-sided test of a block (ts is filled,
 * its arrays freed by the caller). */
static dacpo_status
thin_part_setup(const double* xyz,
                const double* nrm,
                size_t n,
                size_t K,
                const dacpo_dipole_params* prm,
                dipole_work* wk,
                two_sheet_scale* ts,
                dacpo_err* err)
{
  ts->factor = prm->two_sheet;
  if (!(prm->two_sheet > 0.0 || prm->layers > 0.0) || n < 2)
    return DACPO_OK;
  DACPO_TRY(two_sheet_scales(xyz, nrm, n, K, wk, ts, err));
  size_t sheets = 0;
  if (prm->two_sheet > 0.0) {
    two_sheet_points(xyz, nrm, n, K, wk->nb, ts);
    for (size_t i = 0; i < n; ++i)
      sheets += ts->sheet[i];
  }
  if ((double)sheets < DACPO_ONE_SIDED_MAX_SHEET * (double)n)
    ts->layers = prm->layers;
  else if (prm->two_sheet > 0.0)
    ts->c_thin = prm->c_thin;
  if (prm->two_sheet <= 0.0) {
    free(ts->sheet); /* no point is on a thin part: the pair test is off */
    ts->sheet = NULL;
  }
  return DACPO_OK;
}

/* The side cue's first test fires on 0.1-3.5 % of the points of a single depth
 * frame's blocks (noise, no preference) and on 7-78 % of the points of room
 * blocks that hold thin parts; below this share a block gets no cue. */
#define DACPO_SIDE_MIN_SHARE 0.05

/* A pair that a sure side fit puts on two faces gets the two-sheet energy
 * (pair_energy), blended by the fit's confidence, in both rows that hold it. */
static void
side_pairs(const double* xyz,
           const double* nrm,
           size_t n,
           size_t K,
           dipole_work* wk,
           const int8_t* face,
           const double* patch)
{
  for (size_t i = 0; i < n; ++i) {
    const double own = fabs(wk->unary[i]);
    const double conf = patch && fabs(patch[i]) > own ? fabs(patch[i]) : own;
    for (size_t t = 0; conf > 0.0 && t < K; ++t) {
      if (face[i * K + t] >= 0)
        continue;
      const size_t j = (size_t)wk->nb[i * K + t];
      /* a hidden pair (the part lies between them) says nothing */
      const double opp =
          face[i * K + t] == SIDE_HIDDEN
              ? 0.0
              : two_sheet_energy(xyz + 3 * j, nrm + 3 * j, xyz + 3 * i, nrm + 3 * i);
      double* w = &wk->w[i * K + t];
      *w += conf * (opp - *w);
      for (size_t s = 0; s < K; ++s)
        if ((size_t)wk->nb[j * K + s] == i) {
          w = &wk->w[j * K + s];
          *w += conf * (opp - *w);
          break;
        }
    }
  }
}

/* Weight of the patch test's side as a field (x the point's total pair
 * energy), scaled by how clear its copies are (see side_field). Measured on
 * every patch point (no clearness ramp), seeds 1-5, mean % wrong of the four
 * 10K rooms: 0 (pairs only) 8.87, 0.02 8.45, 0.1 8.32, 0.5 8.36, 1 8.40; but
 * 0.1 took two sigma 8 mm rooms up by 0.3 points, 0.5 by up to 2. */
#define DACPO_PATCH_FIELD 0.1

/* The thin-part side cue as a field on every point (dacpo_sheet_side.c):
 * weight x side_i x sum_t |e_ti|, so a sure cue (|side| = 1) with weight >= 1
 * outweighs all of the point's pair energies. spacing 0 = not yet measured. */
static dacpo_status
side_field(const double* xyz,
           const double* nrm,
           size_t n,
           size_t K,
           size_t fit_k,
           int everywhere,
           double weight,
           double spacing,
           const double* noise,
           dipole_work* wk,
           dacpo_err* err)
{
  wk->unary = dacpo_malloc_array(n, sizeof(double));
  if (!wk->unary)
    return DACPO_OOM(err);
  if (!(spacing > 0.0)) {
    for (size_t i = 0; i < n; ++i) {
      const double* p = xyz + 3 * i;
      const double* q = xyz + 3 * (size_t)wk->nb[i * K];
      wk->unary[i] =
          sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
               (q[2] - p[2]) * (q[2] - p[2]));
    }
    spacing = dacpo_select_kth(wk->unary, n, n / 2);
  }
  int8_t* face = dacpo_malloc_array(n * K, sizeof(int8_t));
  if (!face)
    return DACPO_OOM(err);
  size_t fired = 0;
  dacpo_status st = dacpo_sheet_side(
      xyz, nrm, n, wk->nb, K, fit_k, spacing, wk->unary, face, &fired, err);
  /* Below the share the block may be one depth view's noise: no cue at all,
   * unless the scene is known to be seen from many places; then its pairs
   * still face opposite ways, but the cue neither fixes the points through
   * stage 3 nor anchors the block in stage 5 (a scanned room's air gaps, a
   * radiator off a wall, fire it wrongly on a few points of a block). */
  const int shared = (double)fired >= DACPO_SIDE_MIN_SHARE * (double)n;
  /* Many views: also the patch test, for noisy thin parts the point test
   * misses: its pairs, and a weak field where its copies are clear; no
   * stage-3 fixing, no anchor. */
  if (st == DACPO_OK && everywhere && noise) {
    wk->patch = dacpo_malloc_array(n, sizeof(double));
    wk->patch_field = dacpo_malloc_array(n, sizeof(double));
    st = wk->patch && wk->patch_field ? dacpo_sheet_patches(xyz,
                                                            nrm,
                                                            n,
                                                            wk->nb,
                                                            K,
                                                            spacing,
                                                            noise,
                                                            wk->unary,
                                                            wk->patch,
                                                            wk->patch_field,
                                                            face,
                                                            NULL,
                                                            err)
                                      : DACPO_OOM(err);
  }
  if (st == DACPO_OK && (shared || everywhere))
    side_pairs(xyz, nrm, n, K, wk, face, wk->patch);
  if (!shared)
    memset(wk->unary, 0, n * sizeof(double));
  free(face);
  for (size_t i = 0; st == DACPO_OK && i < n; ++i) {
    double mag = 0.0;
    for (size_t t = 0; t < K; ++t)
      mag += fabs(wk->w[i * K + t]);
    wk->unary[i] *= weight * mag;
    /* a patch point's face looks away from the other face (a thin solid;
     * air gaps lie beyond the patch test's gap cap): without this field the
     * patch's pairs hold a board's faces apart but leave it free to turn
     * inside out as a whole */
    if (wk->patch && wk->patch[i] != 0.0)
      wk->unary[i] = DACPO_PATCH_FIELD * wk->patch_field[i] * wk->patch[i] * mag;
  }
  return st;
}

/* K nearest of every point (self dropped) and the cached pair energies. */
dacpo_status
dacpo_dipole_neighbors(const double* xyz,
                       const double* nrm,
                       size_t n,
                       size_t K,
                       const dacpo_dipole_params* prm,
                       dipole_work* wk,
                       dacpo_err* err)
{
  const double c = prm->c;
  DACPO_TRY(dacpo_kdtree_build(xyz, n, &wk->tree, err));
  wk->nb = dacpo_malloc_array(n * K, sizeof(int32_t));
  wk->w = dacpo_malloc_array(n * K, sizeof(double));
  wk->kbuf = dacpo_malloc_array(K + 1, sizeof(int32_t));
  wk->kd = dacpo_malloc_array(K + 1, sizeof(double));
  if (!wk->nb || !wk->w || !wk->kbuf || !wk->kd)
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i) {
    const size_t found =
        dacpo_kdtree_knn(wk->tree, xyz + 3 * i, K + 1, wk->kbuf, wk->kd);
    int32_t* row = wk->nb + i * K;
    size_t t = 0;
    for (size_t f = 0; f < found && t < K; ++f) {
      const int32_t j = wk->kbuf[f];
      if (j < 0 || (size_t)j >= n || (size_t)j == i)
        continue;
      row[t++] = j;
    }
    /* Pad short rows (only with exact duplicates) with the point itself, which
     * gets a zero weight below, so the decision loops need no branch. */
    for (; t < K; ++t)
      row[t] = (int32_t)i;
  }
  two_sheet_scale ts = {NULL, NULL, NULL, 0.0, 0.0, 0.0, 0.0};
  dacpo_status st = thin_part_setup(xyz, nrm, n, K, prm, wk, &ts, err);
  for (size_t i = 0; st == DACPO_OK && i < n; ++i) {
    const int32_t* row = wk->nb + i * K;
    double* wrow = wk->w + i * K;
    for (size_t t = 0; t < K; ++t) {
      const size_t j = (size_t)row[t];
      wrow[t] = j == i ? 0.0 : pair_energy(&ts, xyz, nrm, i, j, c);
    }
  }
  if (st == DACPO_OK && prm->sides > 0.0)
    st = side_field(xyz,
                    nrm,
                    n,
                    K,
                    prm->sides_fit_k,
                    prm->sides_everywhere,
                    prm->sides,
                    ts.spacing,
                    ts.noise,
                    wk,
                    err);
  free(ts.noise);
  free(ts.local);
  free(ts.sheet);
  return st;
}
