/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 0 helper: is the cloud a single depth view?
 *
 * Why: two rules of stage 2 pull in opposite directions on the two kinds of
 * input the method sees. A single depth frame sees every surface from one
 * side: parallel layers a few spacings apart (depth quantisation) face the
 * same way, and a "second face" found by the side cue is noise. A room
 * sampled uniformly or scanned from several places has thin two-sided parts
 * whose faces look away from each other. Measured with stage 2 alone (blocks
 * of the default run, seed 1): the layer rule at 0.5 spacings instead of 2
 * cut the in-block error of five depth frames by 0.4-2.4 points and cost the
 * sparse rooms; the side cue in every block (not only those where >= 5 % of
 * the points show it) cut the uniform 10K rooms by 1.5 points and cost the
 * frames 0.6-3.1 points. The kind of input decides which applies.
 *
 * The test: a depth sensor samples equal solid angles, so the density of a
 * frame's points (1 / r_k^2) goes with cos(incidence) / distance^2 from the
 * sensor. The best correlation of the two logarithms over candidate sensor
 * positions (a sample point pushed along either side of its axis by 1/4 to 2
 * scene diameters) is 0.72-0.98 on the 15 single frames of our evaluation set
 * and 0.08-0.38 on its 18 rooms (uniform sampling, or several sensors whose
 * densities mix); a fused TSDF fragment 0.17. Only candidates whose
 * regression slope (log density on the model) is at least
 * DACPO_SINGLE_VIEW_SLOPE count: a sensor's density follows the model with
 * slope 1 (the frames' best candidates: 0.68-1.37), the rooms' best
 * candidates reach 0.08-0.11.
 * Limits: a frame thinned towards uniform density loses the signature (a
 * generated frame: 0.96, voxel grid 3 cm 0.83, 10 cm 0.16) and then counts as
 * many views; pass the kind explicitly (dacpo_params.scan_kind) for such data.
 *
 * Cost: O(C m) with C = DACPO_VIEW_KIND_CANDIDATES candidates, m <= 4096
 * sample points. Deterministic (the candidate sequence depends only on the
 * sample).
 */
#include "dacpo_view_kind.h"

#include "dacpo_kdtree.h"
#include "dacpo_rng.h"
#include "dacpo_surface_vote.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { DACPO_VIEW_KIND_CANDIDATES = 512 };

/* The sensor model's log density of sample point i for a sensor at v, up to a
 * constant: log cos(incidence) - log distance^2. */
static double
model_log_density(const dacpo_view_sample* s, size_t i, const double v[3])
{
  const double d[3] = {v[0] - s->p[3 * i], v[1] - s->p[3 * i + 1], v[2] - s->p[3 * i + 2]};
  const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const double* q = s->n + 3 * i;
  const double c = fabs(q[0] * d[0] + q[1] * d[1] + q[2] * d[2]) / sqrt(fmax(r2, 1e-300));
  return log(fmax(c, 0.05) / fmax(r2, 1e-300)); /* one log: the fits call it most */
}

double
dacpo_view_density_fit(const dacpo_view_sample* s,
                       const double* logd,
                       const double v[3],
                       double* slope)
{
  double sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (size_t i = 0; i < s->m; ++i) {
    const double x = model_log_density(s, i, v);
    const double y = logd[i];
    sx += x;
    sy += y;
    sxx += x * x;
    syy += y * y;
    sxy += x * y;
  }
  const double m = (double)s->m;
  const double cov = sxy - sx * sy / m;
  const double vx = sxx - sx * sx / m, vy = syy - sy * sy / m;
  if (slope)
    *slope = vx > 0.0 ? cov / vx : 0.0;
  return vx > 0.0 && vy > 0.0 ? cov / sqrt(vx * vy) : 0.0;
}

double*
dacpo_view_log_density(const dacpo_view_sample* s,
                       const float* knn_sqd,
                       size_t row_k,
                       size_t use_k)
{
  double* logd = dacpo_malloc_array(s->m > 0 ? s->m : 1, sizeof(double));
  if (!logd)
    return NULL;
  for (size_t i = 0; i < s->m; ++i) {
    const float* row = knn_sqd + i * s->stride * row_k;
    double far = 0.0;
    for (size_t j = 0; j < use_k; ++j) /* absent neighbours are +inf */
      if (isfinite(row[j]))
        far = fmax(far, (double)row[j]);
    logd[i] = -log(fmax(far, 1e-300)); /* -2 log r_k */
  }
  return logd;
}

/* Variance of log density minus the model's (slope 1: a sensor samples equal
 * solid angles, so density x distance^2 / cos is constant up to the k-th
 * neighbour's sampling noise). */
static double
sensor_spread(const dacpo_view_sample* s, const double* logd, const double v[3])
{
  double sum = 0.0, sq = 0.0;
  for (size_t i = 0; i < s->m; ++i) {
    const double e = logd[i] - model_log_density(s, i, v);
    sum += e;
    sq += e * e;
  }
  const double m = (double)(s->m ? s->m : 1);
  return sq / m - (sum / m) * (sum / m);
}

/* The sensor of a view that fits: the candidate (a coarse lattice of pushes
 * along sample normals) with the least spread, then a compass search around
 * it (steps along the axes, halved when none helps) down to 1e-4 scene
 * diameters. The correlation finds one view; the spread places its sensor
 * (on real frames a few decimetres from the true one, against up to 1.8 m for
 * the best-correlated candidate). */
#define DACPO_SENSOR_SEARCH_EVALS 600

/* Compass search from v (a candidate with the least spread). */
static void
refine_sensor(const dacpo_view_sample* s, const double* logd, double v[3])
{
  double cur = sensor_spread(s, logd, v);
  double h = s->diam / 8.0;
  for (size_t evals = 0; h > 1e-4 * s->diam && evals < DACPO_SENSOR_SEARCH_EVALS;) {
    int moved = 0;
    for (int d = 0; d < 3; ++d)
      for (int sgn = -1; sgn <= 1; sgn += 2) {
        double w[3] = {v[0], v[1], v[2]};
        w[d] += sgn * h;
        const double f = sensor_spread(s, logd, w);
        ++evals;
        if (f < cur) {
          cur = f;
          memcpy(v, w, sizeof(w));
          moved = 1;
        }
      }
    if (!moved)
      h *= 0.5;
  }
}

static void
place_sensor(const dacpo_view_sample* s, const double* logd, double v[3])
{
  dacpo_rng rng; /* the same candidates as the fit's */
  dacpo_view_rng_seed(&rng);
  double least = HUGE_VAL;
  for (size_t k = 0; k < DACPO_VIEW_KIND_CANDIDATES; ++k) {
    double c[3];
    dacpo_view_candidate(s, &rng, k, c);
    const double spread = sensor_spread(s, logd, c);
    if (spread < least) {
      least = spread;
      memcpy(v, c, sizeof(c));
    }
  }
  refine_sensor(s, logd, v);
}

dacpo_status
dacpo_single_view_sensor(const double* xyz,
                         const double* axes,
                         size_t n,
                         const float* knn_sqd,
                         size_t knn_k,
                         double* fit,
                         double* slope,
                         double sensor[3],
                         dacpo_err* err)
{
  DACPO_CHECK(err,
              xyz && axes && knn_sqd && fit,
              DACPO_ERR_INVALID_ARGUMENT,
              "single view: NULL argument");
  *fit = 0.0;
  if (slope)
    *slope = 0.0;
  if (sensor)
    sensor[0] = sensor[1] = sensor[2] = 0.0;
  if (n < 3 || knn_k == 0)
    return DACPO_OK;
  dacpo_view_sample vs;
  DACPO_TRY(dacpo_view_sample_take(xyz, axes, NULL, n, &vs, err));
  /* The 8th neighbour: on the 33 files of our two evaluation sets the 24th
   * smooths the rooms' densities towards the geometry (fits up to 0.48 on a
   * room against 0.38 with the 8th; frames 0.72-0.98 either way). */
  double* logd =
      dacpo_view_log_density(&vs, knn_sqd, knn_k, knn_k < 8 ? knn_k : 8);
  if (!logd) {
    dacpo_view_sample_free(&vs);
    return DACPO_OOM(err);
  }
  dacpo_rng rng;
  dacpo_view_rng_seed(&rng);
  double best = 0.0;
  for (size_t k = 0; k < DACPO_VIEW_KIND_CANDIDATES; ++k) {
    double v[3];
    dacpo_view_candidate(&vs, &rng, k, v);
    double b = 0.0;
    const double f = dacpo_view_density_fit(&vs, logd, v, &b);
    /* The density must follow the model, not only rise with it: on a small
     * evenly sampled patch the k-th neighbour reaches farther at the rim,
     * which correlates with any candidate above its middle (two parallel
     * 1 m sheets: 0.6), with a slope near 0. */
    if (b < DACPO_SINGLE_VIEW_SLOPE)
      continue;
    if (f > best) {
      best = f;
      if (slope)
        *slope = b;
    }
  }
  *fit = best;
  if (sensor && best >= DACPO_SENSOR_FIT)
    place_sensor(&vs, logd, sensor);
  free(logd);
  dacpo_view_sample_free(&vs);
  return DACPO_OK;
}

/* ---- One window of one frame --------------------------------------------
 *
 * Why: registered depth frames concatenated into one cloud keep their points
 * frame by frame. In the whole cloud the frames' densities add up and no one
 * sensor explains them, but a window of one frame's points (found in the
 * order, dacpo_frame_sensors.c), its densities taken among its own points
 * only, is one view again. Where the frame sees more than one plane, the
 * densities also say on which side of the surfaces the sensor stands: from a
 * candidate behind them the near surfaces are the far ones, so its fit falls
 * under DACPO_SINGLE_VIEW_FIT (or its slope under DACPO_SINGLE_VIEW_SLOPE).
 * A window whose best fit reaches DACPO_SINGLE_VIEW_FIT (as a whole cloud
 * counts as one view) while no candidate on the other side has the slope
 * has a sensor with a side; a flat window fits its sensor's mirror image as
 * well and has none, and a side that other candidates only fit less well
 * is not decisive (a band of a frame's top rows, ceiling and one wall, fit
 * 0.56 from the mirror against 0.48 from the camera's side). Such a tied
 * window takes its side from another window of its frame (the same camera)
 * where that window saw the surfaces that tell the two sides apart squarely
 * (tied_side); a band that sees a wall and a table top has the table's
 * mirror image, which the frame's walls, ceiling or furniture do not. */
enum {
  WINDOW_SAMPLE = 512,
  WINDOW_BASES = 64, /* sample points the candidates start from */
  WINDOW_CANDIDATES = 8 * WINDOW_BASES,
  WINDOW_MIN = 256, /* points: fewer give no density worth fitting */
  WINDOW_K = 8      /* the k-th neighbour of the densities, as for the cloud */
};
/* The fit of a candidate whose slope fails (below any fit). */
#define WINDOW_NO_SLOPE (-2.0)

/* Candidate k of a window: one of WINDOW_BASES evenly spread sample points
 * pushed along its axis by 1/4, 1/2, 1 or 2 diameters, both ways, so that
 * each side of every base point is searched alike (the other side's best fit
 * decides whether the window has a side). */
static void
window_candidate(const dacpo_view_sample* s, size_t k, double v[3])
{
  static const double push[4] = {0.25, 0.5, 1.0, 2.0};
  const size_t base = (k / 8) * s->m / WINDOW_BASES;
  const double t = (k & 4u ? -1.0 : 1.0) * push[k % 4] * s->diam;
  for (int d = 0; d < 3; ++d)
    v[d] = s->p[3 * base + d] + t * s->n[3 * base + d];
}

/* -2 log r_k of each sample point, r_k its WINDOW_K-th neighbour among the
 * window's m points (distinct points: the nearest is the point itself). */
static double*
window_log_density(const double* xyz,
                   size_t m,
                   const dacpo_view_sample* vs,
                   dacpo_err* err)
{
  dacpo_kdtree* tree = NULL;
  double* logd = dacpo_malloc_array(vs->m ? vs->m : 1, sizeof(double));
  if (!logd || dacpo_kdtree_build(xyz, m, &tree, err) != DACPO_OK) {
    free(logd);
    return NULL;
  }
  for (size_t i = 0; i < vs->m; ++i) {
    int32_t idx[WINDOW_K + 1];
    double d2[WINDOW_K + 1];
    const size_t got = dacpo_kdtree_knn(tree, vs->p + 3 * i, WINDOW_K + 1, idx, d2);
    logd[i] = -log(fmax(d2[got - 1], 1e-300));
  }
  dacpo_kdtree_free(tree);
  return logd;
}

/* 1 if most sample points see a and b from the same side of their plane. */
static int
same_side(const dacpo_view_sample* s, const double a[3], const double b[3])
{
  size_t same = 0;
  for (size_t i = 0; i < s->m; ++i) {
    const double* p = s->p + 3 * i;
    const double* q = s->n + 3 * i;
    const double fa =
        q[0] * (a[0] - p[0]) + q[1] * (a[1] - p[1]) + q[2] * (a[2] - p[2]);
    const double fb =
        q[0] * (b[0] - p[0]) + q[1] * (b[1] - p[1]) + q[2] * (b[2] - p[2]);
    same += (fa > 0.0) == (fb > 0.0);
  }
  return 2 * same >= s->m;
}

/* The best-fitting candidate (slope >= DACPO_SINGLE_VIEW_SLOPE): its index,
 * or -1 when no fit reaches DACPO_SINGLE_VIEW_FIT; *other: the best candidate
 * seen from the other side that has the slope, -1 if none (the side is
 * decisive). fit, cand: scratch for WINDOW_CANDIDATES. */
static long
window_best_fit(const dacpo_view_sample* s,
                const double* logd,
                double* fit,
                double* cand,
                long* other)
{
  size_t top = 0;
  for (size_t k = 0; k < WINDOW_CANDIDATES; ++k) {
    window_candidate(s, k, cand + 3 * k);
    double slope = 0.0;
    fit[k] = dacpo_view_density_fit(s, logd, cand + 3 * k, &slope);
    if (slope < DACPO_SINGLE_VIEW_SLOPE)
      fit[k] = WINDOW_NO_SLOPE;
    if (fit[k] > fit[top])
      top = k;
  }
  *other = -1;
  if (fit[top] < DACPO_SINGLE_VIEW_FIT)
    return -1;
  for (size_t k = 0; k < WINDOW_CANDIDATES; ++k)
    if (fit[k] > WINDOW_NO_SLOPE && (*other < 0 || fit[k] > fit[*other]) &&
        !same_side(s, cand + 3 * top, cand + 3 * k))
      *other = (long)k;
  return (long)top;
}

/* The candidate seen from the side of candidate `ref` with the least spread,
 * refined (refine_sensor): where a sensor on that side stands. */
static void
place_on_side(const dacpo_view_sample* s,
              const double* logd,
              const double* cand,
              size_t ref,
              double v[3])
{
  double least = HUGE_VAL;
  for (size_t k = 0; k < WINDOW_CANDIDATES; ++k) {
    if (!same_side(s, cand + 3 * ref, cand + 3 * k))
      continue;
    const double spread = sensor_spread(s, logd, cand + 3 * k);
    if (spread < least) {
      least = spread;
      memcpy(v, cand + 3 * k, 3 * sizeof(double));
    }
  }
  refine_sensor(s, logd, v);
}

/* Uncentred correlation, over the pairs of sample points that continue one
 * smooth surface (dacpo_smooth_pair at DACPO_SURFACE_VOTE_ANGLE), of the
 * pair's difference in log density with its difference in the model of a
 * sensor at v: how well the sensor explains the density along each surface,
 * not only its steps from one surface to the next. 0 without such pairs. */
static double
window_surface_fit(const dacpo_view_sample* s, const double* logd, const double v[3])
{
  const double rad = DACPO_SURFACE_VOTE_ANGLE * (3.14159265358979323846 / 180.0);
  const double cos_a = cos(rad), sin_a = sin(rad);
  double model[WINDOW_SAMPLE];
  for (size_t i = 0; i < s->m; ++i)
    model[i] = model_log_density(s, i, v);
  double sab = 0.0, saa = 0.0, sbb = 0.0;
  for (size_t i = 0; i < s->m; ++i)
    for (size_t j = i + 1; j < s->m; ++j) {
      if (!dacpo_smooth_pair(s->p, s->n, i, j, cos_a, sin_a))
        continue;
      const double a = logd[i] - logd[j], b = model[i] - model[j];
      sab += a * b;
      saa += a * a;
      sbb += b * b;
    }
  return saa > 0.0 && sbb > 0.0 ? sab / sqrt(saa * sbb) : 0.0;
}

/* A window's sample and the log densities of its points among its own. */
typedef struct window_density {
  dacpo_view_sample vs;
  double* logd;
} window_density;

static dacpo_status
window_density_make(
    const double* xyz, const double* axes, size_t m, window_density* d, dacpo_err* err)
{
  d->logd = NULL;
  DACPO_TRY(
      dacpo_view_sample_take_at_most(xyz, axes, NULL, m, WINDOW_SAMPLE, &d->vs, err));
  if (!(d->logd = window_log_density(xyz, m, &d->vs, err))) {
    dacpo_view_sample_free(&d->vs);
    return DACPO_OOM(err);
  }
  return DACPO_OK;
}

static void
window_density_free(window_density* d)
{
  free(d->logd);
  dacpo_view_sample_free(&d->vs);
}

/* Which of two sensors, a and b, the frame's camera window c (its sample,
 * its sensor t, placed with its side) stands with: over c's sample points
 * that t sees squarely (DACPO_SENSOR_SQUARE_COS) and that see a and b from
 * opposite sides of their plane, those on a's side and those on b's. Returns
 * 1 (a) or -1 (b) where one side holds DACPO_SIDE_MIN_POINTS of them and the
 * other under DACPO_SENSOR_MAX_AWAY of that, else 0: the camera window saw
 * no surface that tells a from b, or saw it at grazing. */
#define DACPO_SIDE_MIN_POINTS 10
static int
side_of_camera(const dacpo_view_sample* c,
               const double t[3],
               const double a[3],
               const double b[3])
{
  size_t with_a = 0, with_b = 0;
  for (size_t i = 0; i < c->m; ++i) {
    const double* p = c->p + 3 * i;
    const double* q = c->n + 3 * i;
    const double dt[3] = {t[0] - p[0], t[1] - p[1], t[2] - p[2]};
    const double ft = q[0] * dt[0] + q[1] * dt[1] + q[2] * dt[2];
    const double fa =
        q[0] * (a[0] - p[0]) + q[1] * (a[1] - p[1]) + q[2] * (a[2] - p[2]);
    const double fb =
        q[0] * (b[0] - p[0]) + q[1] * (b[1] - p[1]) + q[2] * (b[2] - p[2]);
    if ((fa > 0.0) == (fb > 0.0) ||
        fabs(ft) < DACPO_SENSOR_SQUARE_COS *
                       sqrt(dt[0] * dt[0] + dt[1] * dt[1] + dt[2] * dt[2]))
      continue;
    with_a += (ft > 0.0) == (fa > 0.0);
    with_b += (ft > 0.0) == (fb > 0.0);
  }
  if (with_a >= DACPO_SIDE_MIN_POINTS &&
      (double)with_b < DACPO_SENSOR_MAX_AWAY * (double)with_a)
    return 1;
  if (with_b >= DACPO_SIDE_MIN_POINTS &&
      (double)with_a < DACPO_SENSOR_MAX_AWAY * (double)with_b)
    return -1;
  return 0;
}

/* 1 if sensor v sees p (axis q) squarely (DACPO_SENSOR_SQUARE_COS). */
static int
sees_squarely(const double* p, const double* q, const double v[3])
{
  const double d[3] = {v[0] - p[0], v[1] - p[1], v[2] - p[2]};
  return fabs(q[0] * d[0] + q[1] * d[1] + q[2] * d[2]) >=
         DACPO_SENSOR_SQUARE_COS * sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* Which of two sensors, a and b, saw the window's sample s: over the points
 * both see squarely, those hidden from a behind points of other frames and
 * those hidden from b (dacpo_free_space_blocked). Returns 1 (a) or -1 (b)
 * where the other is hidden from DACPO_SIDE_MIN_POINTS and this one from
 * under DACPO_SENSOR_MAX_AWAY of that, and this one stands inside the
 * cloud's box; else 0. Out there nothing was scanned that could hide a
 * point, so a clear view says nothing: a wall's mirror sensor, outside the
 * room, sees it clearly, while the camera's placement, off by decimetres,
 * may look at it past a thing in the room. */
static int
free_side(const dacpo_view_sample* s,
          const double a[3],
          const double b[3],
          const dacpo_window_space* sp)
{
  size_t hid_a = 0, hid_b = 0;
  for (size_t i = 0; i < s->m; ++i) {
    const double* p = s->p + 3 * i;
    if (!sees_squarely(p, s->n + 3 * i, a) || !sees_squarely(p, s->n + 3 * i, b))
      continue;
    hid_a += (size_t)dacpo_free_space_blocked(sp->space, p, a, sp->skip, sp->frame);
    hid_b += (size_t)dacpo_free_space_blocked(sp->space, p, b, sp->skip, sp->frame);
  }
  if (hid_b >= DACPO_SIDE_MIN_POINTS &&
      (double)hid_a < DACPO_SENSOR_MAX_AWAY * (double)hid_b &&
      dacpo_free_space_inside(sp->space, a))
    return 1;
  if (hid_a >= DACPO_SIDE_MIN_POINTS &&
      (double)hid_b < DACPO_SENSOR_MAX_AWAY * (double)hid_a &&
      dacpo_free_space_inside(sp->space, b))
    return -1;
  return 0;
}

/* A tied window (w, its candidates cand, side and other the best on either
 * side): one camera sees the whole frame, so of the sensors placed on each
 * side the one on the side of the frame's camera window is the frame's
 * (side_of_camera); where that window cannot tell (or there is none), the
 * one the window's points are not hidden from (free_side); else none. */
static dacpo_status
tied_side(const window_density* w,
          const double* cand,
          long side,
          long other,
          const dacpo_window_points* camera,
          const dacpo_window_space* space,
          dacpo_window_fit* out,
          dacpo_err* err)
{
  double va[3], vb[3];
  place_on_side(&w->vs, w->logd, cand, (size_t)side, va);
  place_on_side(&w->vs, w->logd, cand, (size_t)other, vb);
  int with = 0;
  if (camera) {
    dacpo_view_sample c;
    DACPO_TRY(dacpo_view_sample_take_at_most(
        camera->xyz, camera->axes, NULL, camera->m, WINDOW_SAMPLE, &c, err));
    with = side_of_camera(&c, camera->sensor, va, vb);
    dacpo_view_sample_free(&c);
  }
  if (with == 0 && space)
    with = free_side(&w->vs, va, vb, space);
  if (with != 0) {
    memcpy(out->sensor, with > 0 ? va : vb, sizeof(va));
    out->found = same_side(&w->vs, cand + 3 * (with > 0 ? side : other), out->sensor);
  }
  return DACPO_OK;
}

dacpo_status
dacpo_window_sensor(const double* xyz,
                    const double* axes,
                    size_t m,
                    const dacpo_window_points* camera,
                    const dacpo_window_space* space,
                    dacpo_window_fit* out,
                    dacpo_err* err)
{
  DACPO_CHECK(err,
              xyz && axes && out,
              DACPO_ERR_INVALID_ARGUMENT,
              "window sensor: NULL argument");
  memset(out, 0, sizeof(*out));
  if (m < WINDOW_MIN)
    return DACPO_OK;
  window_density w;
  DACPO_TRY(window_density_make(xyz, axes, m, &w, err));
  double* fit = dacpo_malloc_array(WINDOW_CANDIDATES, sizeof(double));
  double* cand = dacpo_malloc_array(3 * WINDOW_CANDIDATES, sizeof(double));
  dacpo_status st = fit && cand ? DACPO_OK : DACPO_OOM(err);
  long other = -1;
  const long side =
      st == DACPO_OK ? window_best_fit(&w.vs, w.logd, fit, cand, &other) : -1;
  out->tied = side >= 0 && other >= 0;
  if (side >= 0 && !out->tied) {
    place_on_side(&w.vs, w.logd, cand, (size_t)side, out->sensor);
    out->found = same_side(&w.vs, cand + 3 * side, out->sensor);
  }
  else if (out->tied && (camera || space)) {
    st = tied_side(&w, cand, side, other, camera, space, out, err);
  }
  out->along = out->found && window_surface_fit(&w.vs, w.logd, out->sensor) >=
                                 3.0 / sqrt((double)w.vs.m);
  free(fit);
  free(cand);
  window_density_free(&w);
  return st;
}
