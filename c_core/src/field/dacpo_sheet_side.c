/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 2 helper: the side of a thin two-sided part a point lies on.
 *
 * Why: on a board thinner than the sampling spacing (an 8 mm bookcase back,
 * an 18 mm shelf, a 2 cm table top at 2 cm spacing) the two faces' samples
 * interleave. The pair rules of the dipole stage need an offset of half a
 * spacing to call two points "two sheets", and Eq. 1's coplanar term then
 * aligns the faces: measured on a uniformly sampled room, 76 % of the energy
 * that made a half-wrong block beat the ground truth came from such pairs.
 *
 * The cue: take the neighbours whose axes are parallel to the point's, in the
 * point's tangent frame. On a single sheet their offsets from one smooth
 * height field (a quadric) are noise around zero; on a thin part they fall
 * into two groups, one per face, t apart. Two tests:
 *  1. one quadric through all of them, Otsu's two-group split of the residuals
 *     (the threshold with the largest separation |mu_hi - mu_lo| / sigma);
 *  2. from that split, two parallel copies of one quadric, t apart, fitted by
 *     alternation (fit surface and gap, move each point to the nearer copy).
 *     One quadric through both faces is tilted by whichever face has more
 *     points on one side; the two copies are not, so test 2 separates more
 *     thin-part points (on a clean uniform room 62 % against 46 % of the points
 *     within 3 cm of an opposite face) but also fires on more single depth
 *     frame points. Test 2 gives the labels; test 1's firing share decides
 *     whether a block has thin parts at all (the caller's gate).
 * The pairs across the two copies face opposite ways: true for a thin solid
 * and for a thin air gap alike (a radiator 4 cm off a wall). The point's own
 * copy also says which way its face looks if the slab between is solid (the
 * outward normal points away from the other face, along +axis for the upper
 * copy); that is wrong for an air gap, so the caller gives it a weight, not
 * the last word.
 *
 * Guards, each against a measured false cue: both groups hold >= 25 % of the
 * points and lie over each other (centroids laterally closer than half the
 * mean lateral distance; the depth-quantisation terraces of a single depth
 * frame lie beside each other), the gap exceeds 0.3 spacing (no upper cap:
 * capping it at 1.5 nearest-neighbour distances, where a uniform room's sides
 * turned mostly wrong - air gaps such as a radiator off a wall - cut off a
 * 2 cm partition sampled at random, 0.6 -> 10.9 % wrong), and the
 * separation exceeds 5 (noise alone reaches ~5 with 25 points); the
 * confidence ramps from separation 5 to 8. Measured with PCA axes (test 1): on
 * clean rooms the cue fires on 2.5-7 % of the points and its side is right on
 * 98-99 % of them; on the 15 single depth frames it fires on 0.1-1.2 % (at
 * most 3.5 % of a block) with no preference (50 %); blocks of rooms that hold
 * thin parts: 7-78 %.
 *
 * Cost: O(n K) plus four 6 x 6 / 7 x 7 solves per point. No allocation.
 */
#include "dacpo_sheet_side.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SIDE_NEIGHBORS 24  /* nearest considered by default (of the K given) */
#define SIDE_MIN_COS 0.8   /* parallel axes: |a.b| above this */
#define SIDE_MIN_POINTS 12 /* points needed for the 6-term fit */
#define SIDE_SEP_FULL 8.0
#define SIDE_FIT_ROUNDS 3

void
dacpo_tangent_frame(const double a[3], double e1[3], double e2[3])
{
  const double h[3] = {fabs(a[0]) < 0.9 ? 1.0 : 0.0, fabs(a[0]) < 0.9 ? 0.0 : 1.0, 0.0};
  e1[0] = a[1] * h[2] - a[2] * h[1];
  e1[1] = a[2] * h[0] - a[0] * h[2];
  e1[2] = a[0] * h[1] - a[1] * h[0];
  const double l = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  for (int d = 0; d < 3; ++d)
    e1[d] /= l;
  e2[0] = a[1] * e1[2] - a[2] * e1[1];
  e2[1] = a[2] * e1[0] - a[0] * e1[2];
  e2[2] = a[0] * e1[1] - a[1] * e1[0];
}

/* Offset d in the frame (e1, e2, a): lateral u, v and height z. */
static void
frame_coords(const double d[3],
             const double e1[3],
             const double e2[3],
             const double a[3],
             double* u,
             double* v,
             double* z)
{
  *u = d[0] * e1[0] + d[1] * e1[1] + d[2] * e1[2];
  *v = d[0] * e2[0] + d[1] * e2[1] + d[2] * e2[2];
  *z = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
}

/* Solves the symmetric positive definite N x N system A x = b (N <= 7) in
 * place (Cholesky; x overwrites b). Returns 0 if A is not positive definite. */
static int
solve_spd(double A[7][7], double* b, int N)
{
  for (int j = 0; j < N; ++j) {
    double d = A[j][j];
    for (int k = 0; k < j; ++k)
      d -= A[j][k] * A[j][k];
    if (!(d > 0.0))
      return 0;
    A[j][j] = sqrt(d);
    for (int i = j + 1; i < N; ++i) {
      double s = A[i][j];
      for (int k = 0; k < j; ++k)
        s -= A[i][k] * A[j][k];
      A[i][j] = s / A[j][j];
    }
  }
  for (int i = 0; i < N; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k)
      s -= A[i][k] * b[k];
    b[i] = s / A[i][i];
  }
  for (int i = N - 1; i >= 0; --i) {
    double s = b[i];
    for (int k = i + 1; k < N; ++k)
      s -= A[k][i] * b[k];
    b[i] = s / A[i][i];
  }
  return 1;
}

/* Least squares z = c . (1, u, v, u^2, uv, v^2 [, l]) over m points (u, v in
 * units of their mean lateral distance; l = face label +-1/2 when given, then
 * c[6] is the gap between two parallel copies of one quadric). Writes the
 * residuals of the quadric part alone (z minus the shared surface) to r and
 * returns the number of terms, 0 if the fit is degenerate (e.g. collinear
 * points). */
static int
surface_fit(const double* u,
            const double* v,
            const double* z,
            const double* l,
            int m,
            double* c,
            double* r)
{
  const int N = l ? 7 : 6;
  double A[7][7] = {{0.0}};
  for (int i = 0; i < N; ++i)
    c[i] = 0.0;
  for (int k = 0; k < m; ++k) {
    const double f[7] = {
        1.0, u[k], v[k], u[k] * u[k], u[k] * v[k], v[k] * v[k], l ? l[k] : 0.0};
    for (int i = 0; i < N; ++i) {
      c[i] += f[i] * z[k];
      for (int j = 0; j <= i; ++j)
        A[i][j] += f[i] * f[j];
    }
  }
  double trace = 0.0;
  for (int i = 0; i < N; ++i)
    trace += A[i][i];
  for (int i = 0; i < N; ++i) {
    A[i][i] += 1e-9 * trace; /* ridge: keeps a near-rank-deficient fit finite */
    for (int j = i + 1; j < N; ++j)
      A[i][j] = A[j][i];
  }
  if (!solve_spd(A, c, N))
    return 0;
  for (int k = 0; k < m; ++k)
    r[k] = z[k] - (c[0] + c[1] * u[k] + c[2] * v[k] + c[3] * u[k] * u[k] +
                   c[4] * u[k] * v[k] + c[5] * v[k] * v[k]);
  return N;
}

double
dacpo_otsu_sorted(const double* s, size_t m, double* threshold, double* gap)
{
  double tot = 0.0, tot2 = 0.0;
  for (size_t k = 0; k < m; ++k) {
    tot += s[k];
    tot2 += s[k] * s[k];
  }
  const size_t kmin = (size_t)ceil(DACPO_SIDE_MIN_CLUSTER * (double)m);
  double best = 0.0, s1 = 0.0, q1 = 0.0;
  for (size_t k = 1; k < m; ++k) {
    s1 += s[k - 1];
    q1 += s[k - 1] * s[k - 1];
    if (k < kmin || m - k < kmin)
      continue;
    const double n1 = (double)k, n2 = (double)(m - k);
    const double mu1 = s1 / n1, mu2 = (tot - s1) / n2;
    const double within =
        (q1 - n1 * mu1 * mu1 + (tot2 - q1) - n2 * mu2 * mu2) / (double)m;
    const double sep =
        within > 0.0 ? (mu2 - mu1) / sqrt(within) : (mu2 > mu1 ? HUGE_VAL : 0.0);
    if (sep > best) {
      best = sep;
      *threshold = 0.5 * (s[k - 1] + s[k]);
      *gap = mu2 - mu1;
    }
  }
  return best;
}

/* dacpo_otsu_sorted on m unsorted values (m <= DACPO_SIDE_MAX_NEIGHBORS + 1). */
static double
otsu_split(const double* r, int m, double* threshold, double* gap)
{
  double s[DACPO_SIDE_MAX_NEIGHBORS + 1];
  for (int k = 0; k < m; ++k) { /* insertion sort: m <= 25 */
    int j = k;
    while (j > 0 && s[j - 1] > r[k]) {
      s[j] = s[j - 1];
      --j;
    }
    s[j] = r[k];
  }
  return dacpo_otsu_sorted(s, (size_t)m, threshold, gap);
}

/* The faces lie over each other, not beside each other (the terraces of a
 * quantised depth image do): the lateral centroids of the two label groups
 * (l > 0 and l <= 0) are closer than DACPO_SIDE_MAX_LATERAL mean lateral distances
 * (u, v are in that unit). */
static int
faces_overlap(const double* u, const double* v, const double* l, int m)
{
  double c_hi[2] = {0.0, 0.0}, c_lo[2] = {0.0, 0.0};
  int n_hi = 0;
  for (int k = 0; k < m; ++k) {
    double* c = l[k] > 0.0 ? c_hi : c_lo;
    n_hi += l[k] > 0.0;
    c[0] += u[k];
    c[1] += v[k];
  }
  if (n_hi == 0 || n_hi == m)
    return 0;
  const double du = c_hi[0] / n_hi - c_lo[0] / (m - n_hi);
  const double dv = c_hi[1] / n_hi - c_lo[1] / (m - n_hi);
  return sqrt(du * du + dv * dv) < DACPO_SIDE_MAX_LATERAL;
}

/* First test: one quadric through all m points, Otsu's split of its residuals.
 * Writes labels l[k] = +-1/2 (+: the upper group) and returns 1 if the split is
 * clear (separation above DACPO_SIDE_SEP_START, gap above DACPO_SIDE_MIN_GAP spacings,
 * groups over each other), 0 if not, -1 if there is no split at all (degenerate
 * fit, or no split leaves both groups 25 % of the points; l is not written). */
static int
one_surface_split(
    const double* u, const double* v, const double* z, int m, double spacing, double* l)
{
  double r[DACPO_SIDE_MAX_NEIGHBORS + 1], c[7], thr = 0.0, gap = 0.0;
  if (!surface_fit(u, v, z, NULL, m, c, r))
    return -1;
  const double sep = otsu_split(r, m, &thr, &gap);
  if (!(sep > 0.0))
    return -1;
  for (int k = 0; k < m; ++k)
    l[k] = r[k] > thr ? 0.5 : -0.5;
  return sep > DACPO_SIDE_SEP_START && gap > DACPO_SIDE_MIN_GAP * spacing &&
         faces_overlap(u, v, l, m);
}

/* The alternation of the two-copy fit, rounds times: fit the shared quadric
 * and the gap to the labels l (+-1/2), move every point to the nearer copy.
 * Afterwards l[k] > 0 means the copy on the +axis side, *gap = |gap|, *sep =
 * gap / sigma of the residuals about the two copies, r = the residuals about
 * the shared surface. Returns the number of points on the +axis copy, -1 if a
 * fit is degenerate or a copy holds fewer than kmin points after a round. */
static int
two_copy_rounds(const double* u,
                const double* v,
                const double* z,
                int m,
                int rounds,
                int kmin,
                double* l,
                double* r,
                double* gap,
                double* sep)
{
  double c[7];
  int n_hi = 0;
  for (int it = 0; it < rounds; ++it) {
    if (!surface_fit(u, v, z, l, m, c, r))
      return -1;
    const double g = c[6];
    double ss = 0.0;
    n_hi = 0;
    for (int k = 0; k < m; ++k) {
      /* the nearer copy: +g/2 or -g/2 */
      l[k] = fabs(r[k] - 0.5 * g) < fabs(r[k] + 0.5 * g) ? 0.5 : -0.5;
      n_hi += l[k] > 0.0;
      const double e = r[k] - l[k] * g;
      ss += e * e;
    }
    if (n_hi < kmin || m - n_hi < kmin)
      return -1;
    if (g < 0.0) { /* labels say which copy is on the +axis side */
      for (int k = 0; k < m; ++k)
        l[k] = -l[k];
      n_hi = m - n_hi;
    }
    *gap = fabs(g);
    const double sigma = sqrt(ss / (double)(m > 7 ? m - 7 : 1));
    *sep = sigma > 0.0 ? *gap / sigma : (*gap > 0.0 ? HUGE_VAL : 0.0);
  }
  return n_hi;
}

/* Second test: two parallel copies of one quadric, gap apart. Starting from
 * the labels l of the first test, alternate (fit the shared surface and the
 * gap, move every point to the nearer copy): one quadric through both faces is
 * tilted by whichever face has more points on one side, the shared surface
 * with its gap is not. Returns the confidence in [0, 1] from the separation
 * |gap| / sigma of the residuals about the two copies (0: no clear split, a
 * copy with under 25 % of the points, gap under DACPO_SIDE_MIN_GAP spacings, or
 * copies beside each other); l[k] > 0 then means the copy on the +axis side. */
static double
two_copy_fit(const double* u,
             const double* v,
             const double* z,
             int m,
             double spacing,
             double* l,
             double* gap_out)
{
  double r[DACPO_SIDE_MAX_NEIGHBORS + 1], gap = 0.0, sep = 0.0;
  const int kmin = (int)ceil(DACPO_SIDE_MIN_CLUSTER * (double)m);
  if (two_copy_rounds(u, v, z, m, SIDE_FIT_ROUNDS, kmin, l, r, &gap, &sep) < 0)
    return 0.0;
  if (!(sep > DACPO_SIDE_SEP_START) || !(gap > DACPO_SIDE_MIN_GAP * spacing) ||
      !faces_overlap(u, v, l, m))
    return 0.0;
  const double conf =
      (sep - DACPO_SIDE_SEP_START) / (SIDE_SEP_FULL - DACPO_SIDE_SEP_START);
  *gap_out = gap;
  return conf < 1.0 ? conf : 1.0;
}

/* A neighbour beyond the other face (not parallel, so not in the fit) is
 * hidden from point i's face by the part itself: a wall a shelf board stands
 * on, seen through the board. Its Eq. 1 pair would relate this face to the
 * other face's side of the wall, the wrong way round. look: +1 if the face
 * looks along +nrm[i]; gap: the distance between the two faces. */
static void
mark_hidden(const double* xyz,
            const double* nrm,
            size_t i,
            const int32_t* row,
            size_t K,
            double look,
            double gap,
            int8_t* face)
{
  const double* p = xyz + 3 * i;
  const double* a = nrm + 3 * i;
  for (size_t t = 0; t < K; ++t) {
    const size_t j = (size_t)row[t];
    const double* b = nrm + 3 * j;
    if (j == i || face[t] != 0 ||
        fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) > SIDE_MIN_COS)
      continue;
    const double* q = xyz + 3 * j;
    const double off =
        (q[0] - p[0]) * a[0] + (q[1] - p[1]) * a[1] + (q[2] - p[2]) * a[2];
    if (look * off < -gap)
      face[t] = SIDE_HIDDEN;
  }
}

/* The cue of one point (see the file comment); 0 if it does not fire. When it
 * fires and face is not NULL, face[t] = +1 / -1 for the neighbours row[t] on
 * the point's own / the other face, SIDE_HIDDEN beyond the other face
 * (mark_hidden), 0: not parallel and not hidden, or not considered.
 * *strict = 1 if the first test alone fires. */
static double
point_side(const double* xyz,
           const double* nrm,
           size_t i,
           const int32_t* row,
           size_t K,
           size_t fit_k,
           double spacing,
           int8_t* face,
           int* strict)
{
  const double* p = xyz + 3 * i;
  const double* a = nrm + 3 * i;
  double e1[3], e2[3];
  dacpo_tangent_frame(a, e1, e2);
  double u[DACPO_SIDE_MAX_NEIGHBORS + 1], v[DACPO_SIDE_MAX_NEIGHBORS + 1],
      z[DACPO_SIDE_MAX_NEIGHBORS + 1];
  double l[DACPO_SIDE_MAX_NEIGHBORS + 1];
  size_t slot[DACPO_SIDE_MAX_NEIGHBORS + 1]; /* index t in row of fitted point k */
  int m = 1;
  u[0] = v[0] = z[0] = 0.0; /* the point itself */
  double lateral = 0.0;
  const size_t kk = K < fit_k ? K : fit_k;
  for (size_t t = 0; t < kk; ++t) {
    const size_t j = (size_t)row[t];
    const double* b = nrm + 3 * j;
    if (j == i || fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) <= SIDE_MIN_COS)
      continue;
    const double d[3] = {
        xyz[3 * j] - p[0], xyz[3 * j + 1] - p[1], xyz[3 * j + 2] - p[2]};
    frame_coords(d, e1, e2, a, u + m, v + m, z + m);
    lateral += sqrt(u[m] * u[m] + v[m] * v[m]);
    slot[m] = t;
    ++m;
  }
  *strict = 0;
  if (m < SIDE_MIN_POINTS || !(lateral > 0.0))
    return 0.0;
  lateral /= (double)m; /* mean over the m points, the point itself at 0 */
  for (int k = 0; k < m; ++k) {
    u[k] /= lateral;
    v[k] /= lateral;
  }
  const int split = one_surface_split(u, v, z, m, spacing, l);
  if (split < 0)
    return 0.0;
  *strict = split;
  double gap = 0.0;
  const double conf = two_copy_fit(u, v, z, m, spacing, l, &gap);
  if (conf > 0.0 && face) {
    for (int k = 1; k < m; ++k)
      face[slot[k]] = (l[k] > 0.0) == (l[0] > 0.0) ? 1 : -1;
    mark_hidden(xyz, nrm, i, row, K, l[0] > 0.0 ? 1.0 : -1.0, gap, face);
  }
  return l[0] > 0.0 ? conf : -conf;
}

dacpo_status
dacpo_sheet_side(const double* xyz,
                 const double* nrm,
                 size_t n,
                 const int32_t* nb,
                 size_t K,
                 size_t fit_k,
                 double spacing,
                 double* side,
                 int8_t* face,
                 size_t* strict,
                 dacpo_err* err)
{
  if (n == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              xyz && nrm && nb && side,
              DACPO_ERR_INVALID_ARGUMENT,
              "sheet side: NULL array for %zu points",
              n);
  if (fit_k == 0)
    fit_k = SIDE_NEIGHBORS;
  DACPO_CHECK(err,
              fit_k <= DACPO_SIDE_MAX_NEIGHBORS,
              DACPO_ERR_INVALID_ARGUMENT,
              "sheet side: fit_k %zu above %d",
              fit_k,
              DACPO_SIDE_MAX_NEIGHBORS);
  if (face)
    memset(face, 0, n * K);
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    int one = 0;
    side[i] = point_side(
        xyz, nrm, i, nb + i * K, K, fit_k, spacing, face ? face + i * K : NULL, &one);
    count += (size_t)one;
  }
  if (strict)
    *strict = count;
  return DACPO_OK;
}

/* ---- The same two-copy test pooled over a whole planar patch ----
 *
 * Why: under noise the per-point test above stays silent on most thin parts.
 * An 18 mm board with sigma = 8 mm noise in random directions (4.6 mm along
 * the axis) gives the two faces a separation of ~4 residual deviations, under
 * the per-point threshold of 5 that 25 noise samples alone reach. Over a patch
 * of a few hundred points the two groups are clear: the residuals of one
 * quadric through both faces are platykurtic (kurtosis ~1.8 for that board,
 * ~1 clean) while a single noisy sheet's are not (3 for Gaussian noise, ~4.4
 * for noise in random directions). Measured on four noisy uniform and scanned
 * rooms (sigma 4 and 8 mm; PCA axes): 8-57 patches fire per room, and 78-97 %
 * of the neighbour pairs they put across the two faces truly face opposite
 * ways. The patch grows over the k-NN graph from a seed through axes parallel
 * to the seed's (a planar part, both faces of a board together; rims and
 * joints have other axes), within PATCH_RADIUS spacings. */
#define PATCH_GROW_K 12
#define PATCH_MIN_COS 0.95
#define PATCH_RADIUS 12.0 /* x spacing */
#define PATCH_MAX_POINTS 600
#define PATCH_MIN_POINTS 40
#define PATCH_MAX_KURTOSIS 2.2
#define PATCH_SEP_START 3.6
#define PATCH_SEP_FULL 5.0
#define PATCH_MIN_GAP 0.25 /* x spacing: below, a clean sheet's fit residue */
#define PATCH_MAX_GAP 1.5  /* x spacing: beyond, the two-sheet rule (and air gaps) */
#define PATCH_MIN_CLUSTER 0.2
/* graph pairs across the faces: a board interleaves them */
#define PATCH_MIN_MIXED 0.3
#define PATCH_MIN_NOISE 0.025 /* x spacing: clean data is left to the point test */
/* Two faces leave a dip at the mid-surface: few points lie within a quarter
 * gap of it (two Gaussian copies at the least separation 3.6: 18 %; measured
 * on the patches that fire in six noisy rooms: median 7-13 %, 8 of 416 at
 * 19 % or more). A spread of quantised offsets has none: the marching-cubes
 * vertices of a fused TSDF fragment gave 5 patches at 19-26 % (a uniform
 * spread: 25 %), whose faces were no better than chance. */
#define PATCH_MAX_MID 0.19

/* Grows the patch of seed s over unassigned points (pid < 0) and returns its
 * size; members in mem[0..m), pid set to id. */
static size_t
grow_patch(const double* xyz,
           const double* nrm,
           const int32_t* nb,
           size_t K,
           size_t s,
           double radius,
           int32_t id,
           int32_t* pid,
           int32_t* mem)
{
  const double* a = nrm + 3 * s;
  const double* p = xyz + 3 * s;
  const size_t gk = K < PATCH_GROW_K ? K : PATCH_GROW_K;
  size_t m = 0, head = 0;
  pid[s] = id;
  mem[m++] = (int32_t)s;
  while (head < m && m < PATCH_MAX_POINTS) {
    const size_t i = (size_t)mem[head++];
    for (size_t t = 0; t < gk && m < PATCH_MAX_POINTS; ++t) {
      const size_t j = (size_t)nb[i * K + t];
      if (pid[j] >= 0)
        continue;
      const double* b = nrm + 3 * j;
      const double* q = xyz + 3 * j;
      const double d2 = (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                        (q[2] - p[2]) * (q[2] - p[2]);
      if (fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) <= PATCH_MIN_COS ||
          d2 >= radius * radius)
        continue;
      pid[j] = id;
      mem[m++] = (int32_t)j;
    }
  }
  return m;
}

/* The two-copy test on one patch of m points (the seed's axis a): 0 if the
 * patch is one sheet, else the confidence in (0, 1]; then l[k] = +-1/2 (the
 * copy, +: along +a) and e[k] = the offset from the shared mid-surface. */
static double
patch_two_faces(const double* xyz,
                const double* a,
                const int32_t* mem,
                size_t m,
                double spacing,
                double* u,
                double* v,
                double* z,
                double* l,
                double* r,
                double* sharp)
{
  double e1[3], e2[3], c0[3] = {0.0, 0.0, 0.0}, c[7];
  dacpo_tangent_frame(a, e1, e2);
  for (size_t k = 0; k < m; ++k)
    for (int d = 0; d < 3; ++d)
      c0[d] += xyz[3 * (size_t)mem[k] + d] / (double)m;
  double lateral = 0.0;
  for (size_t k = 0; k < m; ++k) {
    const double* q = xyz + 3 * (size_t)mem[k];
    const double d[3] = {q[0] - c0[0], q[1] - c0[1], q[2] - c0[2]};
    frame_coords(d, e1, e2, a, u + k, v + k, z + k);
    lateral += sqrt(u[k] * u[k] + v[k] * v[k]) / (double)m;
  }
  if (!(lateral > 0.0))
    return 0.0;
  for (size_t k = 0; k < m; ++k) {
    u[k] /= lateral;
    v[k] /= lateral;
  }
  /* one quadric through all: kurtosis of its residuals */
  if (!surface_fit(u, v, z, NULL, (int)m, c, r))
    return 0.0;
  double s2 = 0.0, s4 = 0.0;
  for (size_t k = 0; k < m; ++k) {
    s2 += r[k] * r[k];
    s4 += r[k] * r[k] * r[k] * r[k];
    l[k] = r[k] > 0.0 ? 0.5 : -0.5;
  }
  if (!(s2 > 0.0) || (double)m * s4 / (s2 * s2) >= PATCH_MAX_KURTOSIS)
    return 0.0;
  /* two parallel copies, by alternation */
  double gap = 0.0, sep = 0.0;
  const int n_hi =
      two_copy_rounds(u, v, z, (int)m, SIDE_FIT_ROUNDS + 2, 0, l, r, &gap, &sep);
  if (n_hi < 0)
    return 0.0;
  const double share = (double)n_hi / (double)m;
  if (share < PATCH_MIN_CLUSTER || share > 1.0 - PATCH_MIN_CLUSTER ||
      !(sep > PATCH_SEP_START) || !(gap > PATCH_MIN_GAP * spacing) ||
      gap > PATCH_MAX_GAP * spacing || !faces_overlap(u, v, l, (int)m))
    return 0.0;
  const double conf = (sep - PATCH_SEP_START) / (PATCH_SEP_FULL - PATCH_SEP_START);
  size_t mid = 0;
  for (size_t k = 0; k < m; ++k) { /* offset from the mid-surface, in half gaps */
    r[k] = fabs(r[k]) / (0.5 * gap);
    mid += r[k] < 0.5;
  }
  if ((double)mid >= PATCH_MAX_MID * (double)m)
    return 0.0;
  /* the side (a solid between the copies) only where the copies are as
   * clearly apart as the point test requires */
  const double clear =
      (sep - DACPO_SIDE_SEP_START) / (SIDE_SEP_FULL - DACPO_SIDE_SEP_START);
  *sharp = clear < 0.0 ? 0.0 : (clear < 1.0 ? clear : 1.0);
  return conf < 1.0 ? conf : 1.0;
}

/* A board interleaves its faces: many graph pairs inside the patch (the m
 * members mem of patch pid) cross them; the members' face labels are the
 * signs of lab. */
static int
patch_is_board(const int32_t* nb,
               size_t K,
               const int32_t* pid,
               const int32_t* mem,
               size_t m,
               const double* lab)
{
  size_t pairs = 0, across = 0;
  for (size_t k = 0; k < m; ++k) {
    const size_t i = (size_t)mem[k];
    for (size_t t = 0; t < K && t < PATCH_GROW_K; ++t) {
      const size_t j = (size_t)nb[i * K + t];
      if (j == i || pid[j] != pid[i])
        continue;
      ++pairs;
      across += (lab[j] > 0.0) != (lab[i] > 0.0);
    }
  }
  return pairs > 0 && (double)across >= PATCH_MIN_MIXED * (double)pairs;
}

/* The face rows of a board patch's members whose own cue is silent: +1 for a
 * neighbour on the same face (same sign of lab), -1 on the other, 0 outside
 * the patch. */
static void
patch_face_rows(const int32_t* nb,
                size_t K,
                const int32_t* pid,
                const int32_t* mem,
                size_t m,
                const double* side,
                const double* lab,
                int8_t* face)
{
  for (size_t k = 0; k < m; ++k) {
    const size_t i = (size_t)mem[k];
    if (side[i] != 0.0)
      continue;
    int8_t* row = face + i * K;
    for (size_t t = 0; t < K; ++t) {
      const size_t j = (size_t)nb[i * K + t];
      row[t] = (j == i || pid[j] != pid[i])
                   ? 0
                   : ((lab[j] > 0.0) == (lab[i] > 0.0) ? 1 : -1);
    }
  }
}

/* conf (and field) of the m members of one patch: signed as side[] (the face
 * looks away from the other copy, the label l[k] along axis a), pc x the
 * distance from the mid-surface r[k] (capped at 1), where the patch is a board
 * and the point's own cue is silent (field: the patch's clearness sharp); 0
 * elsewhere. Returns how many got a conf. */
static size_t
patch_conf(const double* nrm,
           const int32_t* mem,
           size_t m,
           const double* a,
           const double* l,
           const double* r,
           double pc,
           int board,
           double sharp,
           const double* side,
           double* conf,
           double* field)
{
  size_t count = 0;
  for (size_t k = 0; k < m; ++k) {
    const size_t i = (size_t)mem[k];
    const double near = r[k] < 1.0 ? r[k] : 1.0; /* near the mid-surface: unsure */
    const double* b = nrm + 3 * i;
    const double look =
        (l[k] > 0.0) == (a[0] * b[0] + a[1] * b[1] + a[2] * b[2] > 0.0) ? 1.0 : -1.0;
    conf[i] = (board && side[i] == 0.0) ? look * pc * near : 0.0;
    if (field)
      field[i] = conf[i] != 0.0 ? sharp : 0.0;
    count += conf[i] != 0.0;
  }
  return count;
}

dacpo_status
dacpo_sheet_patches(const double* xyz,
                    const double* nrm,
                    size_t n,
                    const int32_t* nb,
                    size_t K,
                    double spacing,
                    const double* noise,
                    const double* side,
                    double* conf,
                    double* field,
                    int8_t* face,
                    size_t* fired,
                    dacpo_err* err)
{
  if (fired)
    *fired = 0;
  if (n == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              xyz && nrm && nb && noise && side && conf && face,
              DACPO_ERR_INVALID_ARGUMENT,
              "sheet patches: NULL array for %zu points",
              n);
  size_t count = 0;
  memset(conf, 0, n * sizeof(double));
  if (field)
    memset(field, 0, n * sizeof(double));
  if (!(spacing > 0.0))
    return DACPO_OK;
  int32_t* pid = dacpo_malloc_array(n, sizeof(int32_t));
  int32_t* mem = dacpo_malloc_array(PATCH_MAX_POINTS, sizeof(int32_t));
  double* buf = dacpo_malloc_array(5 * PATCH_MAX_POINTS, sizeof(double));
  if (!pid || !mem || !buf) {
    free(pid);
    free(mem);
    free(buf);
    return DACPO_OOM(err);
  }
  double *u = buf, *v = buf + PATCH_MAX_POINTS, *z = buf + 2 * PATCH_MAX_POINTS;
  double *l = buf + 3 * PATCH_MAX_POINTS, *r = buf + 4 * PATCH_MAX_POINTS;
  for (size_t i = 0; i < n; ++i)
    pid[i] = -1;
  int32_t id = 0;
  for (size_t s = 0; s < n; ++s) {
    if (pid[s] >= 0)
      continue;
    const size_t m =
        grow_patch(xyz, nrm, nb, K, s, PATCH_RADIUS * spacing, id, pid, mem);
    ++id;
    if (m < PATCH_MIN_POINTS)
      continue;
    /* noise is what the patch test reads: clean data is left to the point
     * test (on clean rooms a patch's misfit alone made it fire across joints) */
    for (size_t k = 0; k < m; ++k)
      r[k] = noise[mem[k]];
    if (dacpo_select_kth(r, m, m / 2) < PATCH_MIN_NOISE * spacing)
      continue;
    const double* a = nrm + 3 * s;
    double sharp = 0.0;
    const double pc = patch_two_faces(xyz, a, mem, m, spacing, u, v, z, l, r, &sharp);
    if (!(pc > 0.0))
      continue;
    /* The members' labels are kept in conf's sign while the board test and
     * the face rows read them (conf is rewritten for these points after). */
    for (size_t k = 0; k < m; ++k)
      conf[mem[k]] = l[k];
    const int board = patch_is_board(nb, K, pid, mem, m, conf);
    if (board)
      patch_face_rows(nb, K, pid, mem, m, side, conf, face);
    count += patch_conf(nrm, mem, m, a, l, r, pc, board, sharp, side, conf, field);
  }
  free(pid);
  free(mem);
  free(buf);
  if (fired)
    *fired = count;
  return DACPO_OK;
}
