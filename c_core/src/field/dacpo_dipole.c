/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 2: orientation initialisation of one block by a dipole-like field and a
 * randomized greedy propagation (paper §4.2, Eq. 1-4).
 *
 * Input:  n points of one block (xyz, unit normal axes nrm, 3n doubles each) and
 *         dacpo_dipole_params (c, M orders, K neighbours, BFS graph k, seed, stream).
 * Output: sign_out[i] in {+1, -1}; the block's normals are sign_out[i] * nrm[i].
 *         The overall sign of the block is arbitrary (stage 5 decides it).
 *
 * Method: each point's K nearest neighbours (local kd-tree, self excluded) are
 * listed once together with the pair energies e (Eq. 2) of the unflipped axes;
 * pairs recognised as the two faces of one thin part get an "opposite" energy
 * instead (two_sheet_pair below; params->two_sheet = 0 keeps Eq. 2), and in a
 * block seen from one side, stacked layers of one surface get c = 1 (layer_pair;
 * params->layers = 0 keeps Eq. 2). In blocks with parts thinner than the
 * spacing, the side cue (dacpo_sheet_side.c; params->sides > 0) makes pairs
 * on the two faces "opposite" and adds a field that turns each face away from
 * the other (side_field).
 * Since e((p,s n),(q,t m)) = s t e((p,n),(q,m)), every later decision is a signed
 * sum of these cached numbers. M randomized BFS orders over the (symmetrized)
 * graph_k-NN graph each give a greedy sign vector (Eq. 4); the M vectors are
 * aligned by an exhaustive search over relative flips (minimum total Hamming
 * disagreement) and majority-voted; Gauss-Seidel sweeps then let every point
 * re-decide with all its K neighbours placed, until none changes. The whole
 * run is repeated up to `restarts` times with other orders (voted runs stop
 * after DACPO_DIPOLE_AGREE that all agree); the runs are voted point
 * by point (dipole_vote below): one unlucky start no longer decides a block.
 *
 * Cost: kd-tree build O(n log n) + n queries of K+1 neighbours, then
 * restarts x (O(M n K) for the orders, O(M^2 n + 2^(M-1) M^2) for the alignment,
 * O(n K) per sweep), and O(restarts n) for the vote. Memory: n K (int32 + double) + O(M
 * n) bytes.
 *
 * Failures: INVALID_ARGUMENT (NULL pointers, orders outside [1, 16], neighbors
 * == 0, n too large for int32 indices), OUT_OF_MEMORY. Non-finite input is the
 * caller's business (checked in stage 0); near-coincident pairs contribute 0.
 * Deterministic for a given (seed, stream); no global state, callable from
 * several threads at once.
 */
#include "dacpo_dipole.h"

#include "dacpo_kdtree.h"
#include "dacpo_sheet_side.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DACPO_DIPOLE_MAX_ORDERS 16
#define DACPO_DIPOLE_MAX_RESTARTS 64
/* Voted restarts that, all giving one answer (up to the block's sign), end the
 * block's runs: more runs could only repeat it where they agree too
 * (docs/DESIGN.md, "Speed"). */
#define DACPO_DIPOLE_AGREE 4

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

/* Everything one call allocates; freed in one place. */
typedef struct dipole_work {
  int32_t* nb;         /* n*K nearest neighbours, padded with the point itself */
  double* w;           /* n*K e(p_j -> p_i) of the unflipped axes */
  double* unary;       /* n field of the thin-part side cue on i, or NULL */
  double* patch;       /* n confidence of the patch test on i, or NULL */
  double* patch_field; /* n trust in the patch test's side of i, or NULL */
  size_t* gstart;      /* n+1 CSR of the symmetrized graph_k-NN graph */
  int32_t* gnbr;       /* gstart[n] */
  int8_t* sign;        /* M*n sign vectors, 0 = not yet placed */
  int8_t* cand;        /* restarts * n: every restart's result */
  uint8_t* visited;    /* n */
  int32_t* queue;      /* n BFS queue = placement order */
  int32_t* order0;     /* n placement order of order 0 (final sweep) */
  int32_t* perm;       /* n random permutation: restart points */
  int32_t* buf;        /* max degree: shuffled neighbour row */
  int32_t* kbuf;       /* K+1 kd-tree answer */
  double* kd;          /* K+1 */
  dacpo_kdtree* tree;
  const double* xyz; /* the block's points and axes, for tree_start_field */
  const double* nrm;
  double c;
} dipole_work;

static void
dipole_work_free(dipole_work* wk)
{
  free(wk->nb);
  free(wk->w);
  free(wk->unary);
  free(wk->patch);
  free(wk->patch_field);
  free(wk->gstart);
  free(wk->gnbr);
  free(wk->sign);
  free(wk->cand);
  free(wk->visited);
  free(wk->queue);
  free(wk->order0);
  free(wk->perm);
  free(wk->buf);
  free(wk->kbuf);
  free(wk->kd);
  dacpo_kdtree_free(wk->tree);
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
static dacpo_status
dipole_neighbors(const double* xyz,
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

/* Symmetrized graph over the first gk entries of each list (repeats allowed: the
 * BFS skips visited points anyway). */
static dacpo_status
dipole_graph(size_t n, size_t K, size_t gk, dipole_work* wk, dacpo_err* err)
{
  wk->gstart = dacpo_calloc_array(n + 1, sizeof(size_t));
  if (!wk->gstart)
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i)
    for (size_t t = 0; t < gk; ++t) {
      const int32_t j = wk->nb[i * K + t];
      if ((size_t)j == i)
        continue;
      wk->gstart[i + 1]++;
      wk->gstart[(size_t)j + 1]++;
    }
  size_t maxdeg = 0;
  for (size_t i = 0; i < n; ++i) {
    if (wk->gstart[i + 1] > maxdeg)
      maxdeg = wk->gstart[i + 1];
    wk->gstart[i + 1] += wk->gstart[i];
  }
  wk->gnbr = dacpo_malloc_array(wk->gstart[n], sizeof(int32_t));
  wk->buf = dacpo_malloc_array(maxdeg, sizeof(int32_t));
  size_t* fill = dacpo_malloc_array(n, sizeof(size_t));
  if (!wk->gnbr || !wk->buf || !fill) {
    free(fill);
    return DACPO_OOM(err);
  }
  memcpy(fill, wk->gstart, n * sizeof(size_t));
  for (size_t i = 0; i < n; ++i)
    for (size_t t = 0; t < gk; ++t) {
      const int32_t j = wk->nb[i * K + t];
      if ((size_t)j == i)
        continue;
      wk->gnbr[fill[i]++] = j;
      wk->gnbr[fill[(size_t)j]++] = (int32_t)i;
    }
  free(fill);
  return DACPO_OK;
}

/* sum_t s[row[t]] * w[t]; four partial sums break the add latency chain. */
static double
dipole_field_sum(const int32_t* row, const double* w, size_t K, const int8_t* s)
{
  double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
  size_t t = 0;
  for (; t + 4 <= K; t += 4) {
    a0 += (double)s[row[t]] * w[t];
    a1 += (double)s[row[t + 1]] * w[t + 1];
    a2 += (double)s[row[t + 2]] * w[t + 2];
    a3 += (double)s[row[t + 3]] * w[t + 3];
  }
  for (; t < K; ++t)
    a0 += (double)s[row[t]] * w[t];
  return (a0 + a1) + (a2 + a3);
}

/* Greedy sign of point i from its placed neighbours (Eq. 4). A point with no
 * placed neighbour, or an exact tie, takes +1. */
static int8_t
dipole_decide(const dipole_work* wk, size_t K, size_t i, const int8_t* s)
{
  const int32_t* row = wk->nb + i * K;
  const double* wrow = wk->w + i * K;
  /* Unplaced points have s == 0 and drop out without a branch: whether a
   * neighbour is placed is random, a branch on it would mispredict half the
   * time and cost more than the sum itself. */
  const double u = wk->unary ? wk->unary[i] : 0.0;
  return dipole_field_sum(row, wrow, K, s) + u >= 0.0 ? 1 : -1;
}

/* A BFS tree that starts where none of the point's K neighbours is placed yet
 * (an island of the block: a part beyond its neighbourhood, or a component
 * joined by a bridge) would take an arbitrary sign, and the restarts would
 * then vote on a coin. Instead it takes the Eq. 1 field of the points placed
 * so far (plain Eq. 2 pairs; every (placed / DACPO_DIPOLE_FAR_SAMPLES)-th
 * point of the placement order, so fewer than twice that many): the field
 * between parts that see each other only from afar still says which way round
 * they belong. */
#define DACPO_DIPOLE_FAR_SAMPLES 256

static double
tree_start_field(const dipole_work* wk, size_t placed, size_t i, const int8_t* s)
{
  const size_t step =
      placed > DACPO_DIPOLE_FAR_SAMPLES ? placed / DACPO_DIPOLE_FAR_SAMPLES : 1;
  double f = 0.0;
  for (size_t q = 0; q < placed; q += step) {
    const size_t j = (size_t)wk->queue[q];
    f += (double)s[j] *
         dacpo_dipole_energy(
             wk->xyz + 3 * j, wk->nrm + 3 * j, wk->xyz + 3 * i, wk->nrm + 3 * i, wk->c);
  }
  return f;
}

/* One randomized BFS order; signs placed in s (length n, zeroed here). */
static void
dipole_one_order(
    dipole_work* wk, size_t n, size_t K, dacpo_rng* rng, int8_t* s, int32_t* order_out)
{
  memset(s, 0, n);
  memset(wk->visited, 0, n);
  /* A random permutation supplies the start point and every restart: scanning it
   * for the next unvisited point picks a uniformly random unplaced point. */
  for (size_t i = 0; i < n; ++i)
    wk->perm[i] = (int32_t)i;
  for (size_t i = n; i > 1; --i) {
    const size_t r = dacpo_rng_below(rng, i);
    const int32_t tmp = wk->perm[i - 1];
    wk->perm[i - 1] = wk->perm[r];
    wk->perm[r] = tmp;
  }
  size_t head = 0, tail = 0, scan = 0;
  while (head < n) {
    int tree_start = 0;
    if (head == tail) {
      while (wk->visited[wk->perm[scan]])
        ++scan;
      const int32_t start = wk->perm[scan];
      wk->visited[start] = 1;
      wk->queue[tail++] = start;
      tree_start = head > 0;
    }
    const size_t i = (size_t)wk->queue[head++];
    s[i] = dipole_decide(wk, K, i, s);
    if (tree_start) {
      const double* row_w = wk->w + i * K;
      const int32_t* row = wk->nb + i * K;
      int placed_nb = 0;
      for (size_t t = 0; t < K && !placed_nb; ++t)
        placed_nb = s[row[t]] != 0 && row_w[t] != 0.0 && (size_t)row[t] != i;
      if (!placed_nb)
        s[i] =
            tree_start_field(wk, head - 1, i, s) + (wk->unary ? wk->unary[i] : 0.0) >=
                    0.0
                ? 1
                : -1;
    }
    /* Visit the neighbours in random order: the orders differ not only by their
     * start, which is what makes the vote informative. */
    const size_t b = wk->gstart[i], deg = wk->gstart[i + 1] - b;
    memcpy(wk->buf, wk->gnbr + b, deg * sizeof(int32_t));
    for (size_t d = deg; d > 1; --d) {
      const size_t r = dacpo_rng_below(rng, d);
      const int32_t tmp = wk->buf[d - 1];
      wk->buf[d - 1] = wk->buf[r];
      wk->buf[r] = tmp;
    }
    for (size_t d = 0; d < deg; ++d) {
      const int32_t j = wk->buf[d];
      if (!wk->visited[j]) {
        wk->visited[j] = 1;
        wk->queue[tail++] = j;
      }
    }
  }
  if (order_out)
    memcpy(order_out, wk->queue, n * sizeof(int32_t));
}

/* Relative flips of orders 1..M-1 against order 0 with the least total pairwise
 * disagreement (paper: exhaustive search over the alignments, M is small). */
/* Restarts that all gave the same signs as the first, or all its opposite. */
static int
restarts_agree(const int8_t* cand, size_t n, size_t R)
{
  for (size_t r = 1; r < R; ++r) {
    const int8_t* c = cand + r * n;
    const int same = c[0] == cand[0];
    for (size_t i = 1; i < n; ++i)
      if ((c[i] == cand[i]) != same)
        return 0;
  }
  return 1;
}

static unsigned
dipole_align(const int8_t* sign, size_t n, size_t M)
{
  size_t diff[DACPO_DIPOLE_MAX_ORDERS][DACPO_DIPOLE_MAX_ORDERS] = {{0}};
  for (size_t a = 0; a < M; ++a)
    for (size_t b = a + 1; b < M; ++b) {
      size_t d = 0;
      const int8_t* sa = sign + a * n;
      const int8_t* sb = sign + b * n;
      for (size_t i = 0; i < n; ++i)
        d += sa[i] != sb[i];
      diff[a][b] = d;
    }
  unsigned best = 0;
  size_t best_cost = (size_t)-1;
  for (unsigned mask = 0; mask < (1u << (M - 1)); ++mask) {
    const unsigned flip = mask << 1; /* bit m: order m flipped; order 0 fixed */
    size_t cost = 0;
    for (size_t a = 0; a < M; ++a)
      for (size_t b = a + 1; b < M; ++b)
        cost += (((flip >> a) ^ (flip >> b)) & 1u) ? n - diff[a][b] : diff[a][b];
    if (cost < best_cost) {
      best_cost = cost;
      best = flip;
    }
  }
  return best;
}

dacpo_status
dacpo_dipole_orient(const double* xyz,
                    const double* nrm,
                    size_t n,
                    const dacpo_dipole_params* params,
                    int8_t* sign_out,
                    dacpo_err* err)
{
  return dacpo_dipole_orient_confidence(xyz, nrm, n, params, sign_out, NULL, err);
}

/* Confidence of every point in the final signs s: the share of restarts that agree
 * with it (each restart aligned to s as a whole) times the margin of
 * its final decision, |sum_t s_j e_ji| / sum_t |e_ji| (1: every neighbour says
 * the same, 0: a tie). */
static void
dipole_confidence(const dipole_work* wk,
                  size_t n,
                  size_t K,
                  size_t R,
                  const int8_t* s,
                  float* confidence)
{
  for (size_t i = 0; i < n; ++i)
    confidence[i] = 0.0f;
  for (size_t r = 0; r < R; ++r) {
    const int8_t* c = wk->cand + r * n;
    size_t same = 0;
    for (size_t i = 0; i < n; ++i)
      same += c[i] == s[i];
    const int8_t f = 2 * same >= n ? 1 : -1;
    for (size_t i = 0; i < n; ++i)
      confidence[i] += (float)(f * c[i] == s[i]);
  }
  for (size_t i = 0; i < n; ++i) {
    const int32_t* row = wk->nb + i * K;
    const double* w = wk->w + i * K;
    double sum = wk->unary ? wk->unary[i] : 0.0;
    double mag = fabs(sum);
    for (size_t t = 0; t < K; ++t) {
      sum += (double)s[row[t]] * w[t];
      mag += fabs(w[t]);
    }
    const double margin = mag > 0.0 ? fabs(sum) / mag : 0.0;
    confidence[i] = (float)((double)confidence[i] / (double)R * margin);
  }
}

/* Gauss-Seidel sweeps in order 0's BFS order: every point now sees all K
 * neighbours placed; an exact tie keeps the current sign. Repeated (up to
 * `sweeps` times) until no point changes: each change raises the energy. */
static void
dipole_sweeps(dipole_work* wk, size_t n, size_t K, int sweeps, int8_t* cand)
{
  for (int sw = 0; sw < sweeps; ++sw) {
    size_t changed = 0;
    for (size_t o = 0; o < n; ++o) {
      const size_t i = (size_t)wk->order0[o];
      const double sum = dipole_field_sum(wk->nb + i * K, wk->w + i * K, K, cand) +
                         (wk->unary ? wk->unary[i] : 0.0);
      const int8_t v = sum > 0.0 ? 1 : sum < 0.0 ? -1 : cand[i];
      changed += v != cand[i];
      cand[i] = v;
    }
    if (changed == 0)
      break;
  }
}

/* The restarts voted point by point: each restart is flipped as a whole by
 * the same exhaustive alignment as the orders (minimum total pairwise
 * disagreement; beyond DACPO_DIPOLE_MAX_ORDERS restarts, each is aligned to
 * the first), every point takes the majority sign (a tie: the first
 * restart's), then the sweeps settle it. Measured against keeping the restart
 * with the highest block energy (6 real frames and 6 synthetic rooms, seeds
 * 1-3): that energy is not a reliable judge where parts are thin or noisy (16
 * restarts picked by it: rooms 7.11 -> 7.78 %, one frame 21.7 % on one seed),
 * the vote over 8 restarts gave rooms 7.11 -> 6.59 % and cut the largest
 * spread over seeds from 5.96 to 1.32 points. Aligning each restart to the
 * first alone instead of exhaustively gave one frame 20.7 % on one seed. */
static void
dipole_vote(dipole_work* wk, size_t n, size_t K, size_t R, int sweeps, int8_t* out)
{
  int8_t flip[DACPO_DIPOLE_MAX_RESTARTS];
  if (R <= DACPO_DIPOLE_MAX_ORDERS) {
    const unsigned mask = dipole_align(wk->cand, n, R);
    for (size_t r = 0; r < R; ++r)
      flip[r] = ((mask >> r) & 1u) ? -1 : 1;
  }
  else {
    for (size_t r = 0; r < R; ++r) {
      const int8_t* c = wk->cand + r * n;
      size_t same = 0;
      for (size_t i = 0; i < n; ++i)
        same += c[i] == wk->cand[i];
      flip[r] = 2 * same >= n ? 1 : -1;
    }
  }
  for (size_t i = 0; i < n; ++i) {
    int votes = 0;
    for (size_t r = 0; r < R; ++r)
      votes += flip[r] * wk->cand[r * n + i];
    out[i] = votes > 0 ? 1 : votes < 0 ? -1 : wk->cand[i];
  }
  dipole_sweeps(wk, n, K, sweeps, out);
}

/* One restart (paper Eq. 4 greedy + our vote and sweeps): M randomized orders,
 * aligned and majority-voted, then Gauss-Seidel sweeps in order 0's BFS order
 * until no point changes. Writes the signs to cand. */
static void
dipole_restart(dipole_work* wk,
               size_t n,
               size_t K,
               const dacpo_dipole_params* params,
               size_t r,
               int8_t* cand)
{
  const size_t M = params->orders;
  for (size_t m = 0; m < M; ++m) {
    dacpo_rng rng;
    dacpo_rng_seed(&rng, params->seed + 7919u * r, params->stream * 1000003u + m);
    dipole_one_order(wk, n, K, &rng, wk->sign + m * n, m == 0 ? wk->order0 : NULL);
  }
  /* Align, then majority vote; a tie keeps order 0's sign. */
  const unsigned flip = dipole_align(wk->sign, n, M);
  for (size_t i = 0; i < n; ++i) {
    int votes = 0;
    for (size_t m = 0; m < M; ++m)
      votes += ((flip >> m) & 1u) ? -wk->sign[m * n + i] : wk->sign[m * n + i];
    cand[i] = votes > 0 ? 1 : votes < 0 ? -1 : wk->sign[i];
  }
  dipole_sweeps(wk, n, K, params->final_sweep, cand);
}

/* The arguments dacpo_dipole_orient_confidence accepts (n >= 1). */
static dacpo_status
dipole_check(size_t n, const dacpo_dipole_params* params, dacpo_err* err)
{
  DACPO_CHECK(err,
              n <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: %zu points exceed int32 indices",
              n);
  DACPO_CHECK(err,
              params->orders >= 1 && params->orders <= DACPO_DIPOLE_MAX_ORDERS,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: orders must be in [1, %d] (got %zu)",
              DACPO_DIPOLE_MAX_ORDERS,
              params->orders);
  DACPO_CHECK(err,
              params->neighbors >= 1,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: neighbors must be >= 1");
  DACPO_CHECK(err,
              params->restarts <= DACPO_DIPOLE_MAX_RESTARTS,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: restarts must be <= %d (got %zu)",
              DACPO_DIPOLE_MAX_RESTARTS,
              params->restarts);
  return DACPO_OK;
}

/* The order and vote buffers of M orders and R restarts. */
static dacpo_status
dipole_alloc(dipole_work* wk, size_t n, size_t M, size_t R, dacpo_err* err)
{
  wk->sign = dacpo_malloc_array(M * n, sizeof(int8_t));
  wk->visited = dacpo_malloc_array(n, sizeof(uint8_t));
  wk->queue = dacpo_malloc_array(n, sizeof(int32_t));
  wk->order0 = dacpo_malloc_array(n, sizeof(int32_t));
  wk->perm = dacpo_malloc_array(n, sizeof(int32_t));
  wk->cand = dacpo_malloc_array(n * R, sizeof(int8_t));
  if (!wk->sign || !wk->visited || !wk->queue || !wk->order0 || !wk->perm || !wk->cand)
    return DACPO_OOM(err);
  return DACPO_OK;
}

/* params->thin_out / cue_out (when given): where the point side cue fired
 * (not the patch test), and whether it agrees with the returned sign. */
static void
cue_outputs(const dipole_work* wk,
            size_t n,
            const dacpo_dipole_params* params,
            const int8_t* sign_out)
{
  if (params->thin_out)
    for (size_t i = 0; i < n; ++i)
      params->thin_out[i] =
          wk->unary && wk->unary[i] != 0.0 && (!wk->patch || wk->patch[i] == 0.0);
  if (params->cue_out)
    for (size_t i = 0; i < n; ++i)
      params->cue_out[i] =
          !wk->unary || wk->unary[i] == 0.0 || (wk->patch && wk->patch[i] != 0.0) ? 0
          : (wk->unary[i] > 0.0) == (sign_out[i] > 0)                             ? 1
                                                                                  : -1;
}

dacpo_status
dacpo_dipole_orient_confidence(const double* xyz,
                               const double* nrm,
                               size_t n,
                               const dacpo_dipole_params* params,
                               int8_t* sign_out,
                               float* confidence,
                               dacpo_err* err)
{
  DACPO_CHECK(
      err, params != NULL, DACPO_ERR_INVALID_ARGUMENT, "dipole: params is NULL");
  if (n == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              xyz && nrm && sign_out,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: NULL array for %zu points",
              n);
  DACPO_TRY(dipole_check(n, params, err));
  if (n == 1) {
    sign_out[0] = 1;
    if (confidence)
      confidence[0] = 0.0f;
    return DACPO_OK;
  }
  const size_t K = params->neighbors < n - 1 ? params->neighbors : n - 1;
  const size_t gk = (params->graph_k == 0 || params->graph_k > K) ? K : params->graph_k;
  const size_t M = params->orders;

  dipole_work wk;
  memset(&wk, 0, sizeof(wk));
  wk.xyz = xyz;
  wk.nrm = nrm;
  wk.c = params->c;
  dacpo_status st = dipole_neighbors(xyz, nrm, n, K, params, &wk, err);
  if (st == DACPO_OK)
    st = dipole_graph(n, K, gk, &wk, err);
  if (st == DACPO_OK)
    st = dipole_alloc(&wk, n, M, params->restarts ? params->restarts : 1, err);
  if (st != DACPO_OK) {
    dipole_work_free(&wk);
    return st;
  }

  /* Restarts (each: M orders, aligned, voted, then swept) are voted point by
   * point (dipole_vote): one unlucky start no longer decides the block. */
  size_t R = params->restarts ? params->restarts : 1;
  for (size_t r = 0; r < R; ++r) {
    dipole_restart(&wk, n, K, params, r, wk.cand + r * n);
    /* the first DACPO_DIPOLE_AGREE runs gave one answer (up to the block's
       sign): the vote of more could not change it where they agree too */
    if (r + 1 == DACPO_DIPOLE_AGREE && R > r + 1 && restarts_agree(wk.cand, n, r + 1))
      R = r + 1;
  }
  if (R > 1)
    dipole_vote(&wk, n, K, R, params->final_sweep, sign_out);
  else
    memcpy(sign_out, wk.cand, n);
  cue_outputs(&wk, n, params, sign_out);
  if (confidence)
    dipole_confidence(&wk, n, K, R, sign_out, confidence);
  dipole_work_free(&wk);
  return DACPO_OK;
}
