/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 6: global sign.
 *
 * Stages 1-5 (and the part signs) make the normals consistent with each other;
 * the paper's metric forgives one global flip, a user does not: Poisson
 * reconstruction of a room whose floor normals point down is inside out. With
 * a viewpoint given (a sensor origin), the normals face it: the sign under
 * which most points face it, one bit for the whole cloud, so consistency is
 * kept (unlike a per-point flip towards the viewpoint).
 *
 * Without one, the scan's own geometry says where it was seen from. Every
 * sensed point faces free space that a sensor stood in, so there is a point v
 * that most normals face (score |facing - not facing| / m, as for the part
 * signs). Candidates are sample points pushed along either side of their
 * normal; the score is blind to a global flip, and several candidates tie
 * (a single depth frame is faced by its sensor and "un-faced" by a point
 * behind its surfaces). Among those within 0.01 of the best:
 *   1. the one whose position explains the sampling density: a depth sensor
 *      samples equal solid angles, so the density of a point (1 / r_k^2, r_k
 *      its k-th neighbour distance) goes with cos(incidence) / distance^2
 *      from the sensor. The candidate with the highest correlation of the two
 *      logarithms wins if it reaches 0.5 (single frames: 0.81-0.97 at the
 *      sensor's side; rooms sampled from many places: about 0, no decision);
 *   2. otherwise the one that sees most of the sample (z-buffer over direction
 *      cells of one sample spacing at the sample's median distance; a point is
 *      visible when nothing in its cell is more than 2 spacings nearer), then,
 *      within 0.01 of that, the one farther from the points (a sensor stands
 *      back).
 * The normals then face v, unless v is enclosed: when at least 90 % of 64
 * evenly spread rays from v, and from the sample's centroid, pass within 2
 * sample spacings of a sample point, v is inside a closed surface (an object
 * scanned all round), whose normals face outward, away from v. An open room
 * is never enclosed: its middle sees the open top (a point under a table,
 * which the search may choose, is enclosed alone). A room with a ceiling and
 * an object look alike, and outward is the convention for both.
 * A closed object too thin to hold a candidate (a 2 cm board) has no inside
 * viewpoint, nor does a closed object whose centroid lies outside it (a
 * torus): they get the sign the faced viewpoint implies, not always outward.
 *
 * Measured on the pipeline's output (estimated normals, seed 1): the right
 * sign on all 15 real depth frames and all 18 synthetic open rooms of our
 * evaluation sets; without cue 1 a flat table frame and a milk-carton frame,
 * which a point below the table sees as well as the sensor, came out wrong.
 * Generated scenes: a sphere gets outward normals, an open box inward ones.
 *
 * Cost: O(256 m) for the scores, O(t m log m) for t <= 64 tied candidates'
 * z-buffers and density fits, m <= 4096. Deterministic, independent of the
 * run's seed.
 */
#include "dacpo_global_sign.h"

#include "dacpo_part_sign.h"
#include "dacpo_view_kind.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
  GS_CANDIDATES = 256, /* viewpoints scored */
  GS_MAX_TIED = 64,    /* z-buffers at most */
  GS_RAYS = 64         /* enclosure test */
};
#define GS_PI 3.14159265358979323846
#define GS_TIE 0.01
#define GS_VIS_TIE 0.01
#define GS_ENCLOSED 0.9
#define GS_DENSITY_FIT DACPO_SINGLE_VIEW_FIT

typedef struct gs_candidate {
  double v[3];
  double score; /* |facing - not facing| / m */
  int facing;   /* +1: most sample normals face v */
  double dist;  /* mean distance to the sample */
} gs_candidate;

typedef struct gs_cell {
  int64_t key;
  double r;
} gs_cell;

static int
cmp_cell(const void* a, const void* b)
{
  const gs_cell* x = a;
  const gs_cell* y = b;
  if (x->key != y->key)
    return x->key < y->key ? -1 : 1;
  return (x->r > y->r) - (x->r < y->r);
}

static int
cmp_candidate(const void* a, const void* b)
{
  const gs_candidate* x = a;
  const gs_candidate* y = b;
  return (x->score < y->score) - (x->score > y->score); /* best first */
}

/* Direction of d as (polar, azimuth) in [0, pi] x [-pi, pi]. */
static void
direction(const double d[3], double r, double* polar, double* azimuth)
{
  *polar = acos(fmax(-1.0, fmin(1.0, d[2] / r)));
  *azimuth = atan2(d[1], d[0]);
}

/* Share of the sample that v sees (see 1. above); cell is m scratch cells. */
static double
visible_share(const dacpo_view_sample* s,
              const double v[3],
              double spacing,
              gs_cell* cell)
{
  double* r = malloc(s->m * sizeof(double));
  if (!r)
    return -1.0;
  for (size_t i = 0; i < s->m; ++i) {
    const double d[3] = {
        s->p[3 * i] - v[0], s->p[3 * i + 1] - v[1], s->p[3 * i + 2] - v[2]};
    r[i] = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    cell[i].r = r[i];
  }
  /* median distance: the cells are one spacing wide there */
  double* tmp = malloc(s->m * sizeof(double));
  if (!tmp) {
    free(r);
    return -1.0;
  }
  memcpy(tmp, r, s->m * sizeof(double));
  qsort(tmp, s->m, sizeof(double), dacpo_cmp_double);
  const double median = tmp[s->m / 2];
  free(tmp);
  const double cell_angle = spacing / fmax(median, spacing);
  for (size_t i = 0; i < s->m; ++i) {
    const double d[3] = {
        s->p[3 * i] - v[0], s->p[3 * i + 1] - v[1], s->p[3 * i + 2] - v[2]};
    double polar = 0.0, azimuth = 0.0;
    if (r[i] > 0.0)
      direction(d, r[i], &polar, &azimuth);
    const int64_t a = (int64_t)floor(polar / cell_angle);
    const int64_t b = (int64_t)floor((azimuth + GS_PI) / cell_angle);
    cell[i].key = a * 1000003 + b;
  }
  qsort(cell, s->m, sizeof(gs_cell), cmp_cell);
  size_t visible = 0;
  for (size_t i = 0, first = 0; i < s->m; ++i) {
    if (i > 0 && cell[i].key != cell[i - 1].key)
      first = i;
    visible += cell[i].r <= cell[first].r + 2.0 * spacing;
  }
  free(r);
  return (double)visible / (double)s->m;
}

/* Share of GS_RAYS evenly spread rays from v that a sample point blocks
 * (passes within `radius` of the ray, farther than 2 radius from v, so that a
 * candidate lying on a surface does not count as enclosed): 1 inside a closed
 * surface, less where the scene opens (an open room's top). */
static double
ray_coverage(const dacpo_view_sample* s, const double v[3], double radius)
{
  const double golden = GS_PI * (3.0 - sqrt(5.0));
  size_t blocked = 0;
  for (size_t k = 0; k < GS_RAYS; ++k) {
    const double z = 1.0 - (2.0 * (double)k + 1.0) / (double)GS_RAYS;
    const double rho = sqrt(fmax(0.0, 1.0 - z * z));
    const double d[3] = {
        rho * cos(golden * (double)k), rho * sin(golden * (double)k), z};
    for (size_t i = 0; i < s->m; ++i) {
      const double q[3] = {
          s->p[3 * i] - v[0], s->p[3 * i + 1] - v[1], s->p[3 * i + 2] - v[2]};
      const double t = q[0] * d[0] + q[1] * d[1] + q[2] * d[2];
      if (t <= 2.0 * radius) /* points at v itself block every ray */
        continue;
      const double off2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] - t * t;
      if (off2 < radius * radius) {
        ++blocked;
        break;
      }
    }
  }
  return (double)blocked / (double)GS_RAYS;
}

/* Sample spacing: the two largest box extents spread over the sample. */
static double
gs_sample_spacing(const dacpo_view_sample* vs)
{
  double ext[3];
  for (int d = 0; d < 3; ++d)
    ext[d] = vs->hi[d] - vs->lo[d];
  const double emin = fmin(ext[0], fmin(ext[1], ext[2]));
  const double area = (ext[0] * ext[1] * ext[2]) / fmax(emin, 1e-300);
  double spacing = sqrt(fmax(area, 0.0) / (double)vs->m);
  if (!(spacing > 0.0))
    spacing = vs->diam > 0.0 ? vs->diam / sqrt((double)vs->m) : 1.0;

  return spacing;
}

/* Among the `tied` best-scoring candidates: the most visible (z-buffer), then
 * the farthest; the sampling density of a depth sensor overrides both when it
 * fits one of them (corr >= GS_DENSITY_FIT). Returns the index, or -1 when
 * out of memory. */
static long
gs_pick(const dacpo_view_sample* vs,
        const gs_candidate* cand,
        size_t tied,
        double spacing,
        const float* knn_sqd,
        size_t knn_k,
        gs_cell* cell)
{
  size_t best = 0;
  double best_vis = -1.0;
  double* vis = malloc(tied * sizeof(double));
  double* logd =
      knn_sqd && knn_k > 0 ? dacpo_view_log_density(vs, knn_sqd, knn_k, knn_k) : NULL;
  if (!vis || (knn_sqd && knn_k > 0 && !logd)) {
    free(logd);
    free(vis);
    return -1;
  }
  for (size_t t = 0; t < tied; ++t) {
    vis[t] = visible_share(vs, cand[t].v, spacing, cell);
    if (vis[t] < 0.0) {
      free(logd);
      free(vis);
      return -1;
    }
    best_vis = fmax(best_vis, vis[t]);
  }
  double best_dist = -1.0;
  for (size_t t = 0; t < tied; ++t)
    if (vis[t] >= best_vis - GS_VIS_TIE && cand[t].dist > best_dist) {
      best_dist = cand[t].dist;
      best = t;
    }
  /* 3. sampling density, when it singles out a sensor */
  if (logd) {
    double best_fit = GS_DENSITY_FIT;
    for (size_t t = 0; t < tied; ++t) {
      const double fit = dacpo_view_density_fit(vs, logd, cand[t].v, NULL);
      if (fit > best_fit) {
        best_fit = fit;
        best = t;
      }
    }
  }
  free(logd);
  free(vis);
  return (long)best;
}

dacpo_status
dacpo_global_sign(const double* xyz,
                  const double* nrm,
                  size_t n,
                  const double* viewpoint,
                  const float* knn_sqd,
                  size_t knn_k,
                  dacpo_global_sign_result* out,
                  dacpo_err* err)
{
  DACPO_CHECK(
      err, xyz && nrm && out, DACPO_ERR_INVALID_ARGUMENT, "global sign: NULL argument");
  memset(out, 0, sizeof(*out));
  if (viewpoint) {
    DACPO_CHECK(err,
                isfinite(viewpoint[0]) && isfinite(viewpoint[1]) &&
                    isfinite(viewpoint[2]),
                DACPO_ERR_INVALID_ARGUMENT,
                "viewpoint is not finite");
    memcpy(out->viewpoint, viewpoint, sizeof(out->viewpoint));
    double vote, dist;
    (void)dacpo_view_score(xyz, nrm, NULL, n, viewpoint, &vote, 1, &dist);
    out->flip = vote < 0.0;
    out->facing = n ? 0.5 + 0.5 * fabs(vote) / (double)n : 0.0;
    return DACPO_OK;
  }
  if (n == 0)
    return DACPO_OK;

  dacpo_view_sample vs;
  DACPO_TRY(dacpo_view_sample_take(xyz, nrm, NULL, n, &vs, err));
  gs_candidate* cand = malloc(GS_CANDIDATES * sizeof(gs_candidate));
  gs_cell* cell = malloc(vs.m * sizeof(gs_cell));
  if (!cand || !cell) {
    free(cand);
    free(cell);
    dacpo_view_sample_free(&vs);
    return DACPO_OOM(err);
  }
  dacpo_rng rng;
  dacpo_view_rng_seed(&rng);
  for (size_t k = 0; k < GS_CANDIDATES; ++k) {
    gs_candidate* c = &cand[k];
    dacpo_view_candidate(&vs, &rng, k, c->v);
    double vote;
    (void)dacpo_view_score(vs.p, vs.n, NULL, vs.m, c->v, &vote, 1, &c->dist);
    c->score = fabs(vote) / (double)vs.m;
    c->facing = vote < 0.0 ? -1 : 1;
  }
  qsort(cand, GS_CANDIDATES, sizeof(gs_candidate), cmp_candidate);
  size_t tied = 1;
  while (tied < GS_MAX_TIED && cand[tied].score >= cand[0].score - GS_TIE)
    ++tied;

  const double spacing = gs_sample_spacing(&vs);
  const long best = gs_pick(&vs, cand, tied, spacing, knn_sqd, knn_k, cell);
  if (best < 0) {
    free(cand);
    free(cell);
    dacpo_view_sample_free(&vs);
    return DACPO_OOM(err);
  }
  const gs_candidate* c = &cand[best];
  memcpy(out->viewpoint, c->v, sizeof(out->viewpoint));
  /* enclosed: v and the sample's centroid both (a point under a table in a
   * room is enclosed, the middle of an open room is not) */
  double centroid[3] = {0.0, 0.0, 0.0};
  for (size_t i = 0; i < vs.m; ++i)
    for (int d = 0; d < 3; ++d)
      centroid[d] += vs.p[3 * i + d] / (double)vs.m;
  out->enclosed = ray_coverage(&vs, c->v, 2.0 * spacing) >= GS_ENCLOSED &&
                  ray_coverage(&vs, centroid, 2.0 * spacing) >= GS_ENCLOSED;
  /* facing: normals towards v; enclosed: away from it */
  out->flip = out->enclosed ? c->facing > 0 : c->facing < 0;
  out->facing = 0.5 + 0.5 * c->score;
  free(cand);
  free(cell);
  dacpo_view_sample_free(&vs);
  return DACPO_OK;
}
