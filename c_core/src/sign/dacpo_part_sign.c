/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Relative sign of parts (policy DACPO_DISCONNECTED_VIEWPOINT).
 *
 * Stages 1-5 orient each connected component of the k-NN graph on its own: no
 * neighbour relation joins two components, so their relative sign is not
 * decided by the paper's method. Nor is it, in practice, between two groups of
 * blocks that only a weak block-graph edge joins (a contact of a few pixels):
 * measured on real depth frames, such edges decided whole groups wrongly with
 * full Eq. 7 confidence. The pipeline hands both kinds of part to this step. Scans are
 * seen from somewhere: every surface point faces the free space it was observed from,
 * so there is a viewpoint v with n_i . (v - p_i) > 0 for most points of every part once
 * each part has its right sign (a sensor position for a single depth frame, the inside
 * of an open room for a fused scan). Each part is consistent on its own, so v is the
 * point that explains the parts best when each may still flip: score(v) =
 * sum over parts of |facing - not facing| / sample size. Every part then takes
 * the sign under which its points face v on the whole (their cosines with the
 * direction to v summed), relative to the largest part. The vote is per part: a
 * part need not face v point by point, only on the whole.
 *
 * v is searched among candidates p_i +- t n_i (sample points pushed to either
 * side of their normal by t = 1/4 .. 2 scene diameters); the best score is the
 * `view_score`. Below DACPO_VIEW_MIN_SCORE no viewpoint explains the parts
 * (e.g. closed objects with outward normals) and they are left unrelated
 * (confidence 0), as with the SEPARATE policy: reported, not guessed.
 * Measured (15 real depth frames and 18 synthetic rooms, seeds 1-5, median):
 * the part-sign share of the error fell from 4.29 % to 0.18 % (frames)
 * and from 0.39 % to 0.07 % (rooms).
 *
 * Cost: O(candidates x sample + n). Deterministic, the same for every seed.
 */
#include "dacpo_part_sign.h"

#include "dacpo_select.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { DACPO_VIEW_CANDIDATES = 1024 };
#define DACPO_VIEW_MIN_SCORE 0.75
#ifndef DACPO_VIEW_TIE
#define DACPO_VIEW_TIE 0.0005
#endif

double
dacpo_view_score(const double* sp,
                 const double* sn,
                 const int32_t* sc,
                 size_t m,
                 const double v[3],
                 double* vote,
                 size_t num_parts,
                 double* mean_dist)
{
  memset(vote, 0, num_parts * sizeof(double));
  double dist = 0.0;
  for (size_t s = 0; s < m; ++s) {
    const double* p = sp + 3 * s;
    const double* q = sn + 3 * s;
    const double d[3] = {v[0] - p[0], v[1] - p[1], v[2] - p[2]};
    const double f = q[0] * d[0] + q[1] * d[1] + q[2] * d[2];
    vote[sc ? sc[s] : 0] += f > 0.0 ? 1.0 : f < 0.0 ? -1.0 : 0.0;
    dist += sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  }
  double total = 0.0;
  for (size_t c = 0; c < num_parts; ++c)
    total += fabs(vote[c]);
  *mean_dist = m ? dist / (double)m : 0.0;
  return m ? total / (double)m : 0.0;
}

size_t
dacpo_part_largest(const int32_t* part, size_t n, size_t num_parts, size_t* size)
{
  for (size_t i = 0; i < n; ++i)
    size[part[i]]++;
  size_t big = 0;
  for (size_t c = 1; c < num_parts; ++c)
    if (size[c] > size[big])
      big = c;
  return big;
}

/* The candidates do not depend on the run's seed: the parts' relation is a
 * property of the scene, every seed should find the same one. Two stacked
 * parts (a table top over the floor) are explained as well by a viewpoint
 * above both as by one between them that the upper part hides; among
 * candidates that explain the sample equally well (within 0.05 %) the one
 * farther from the points is kept, since a sensor stands back from what it
 * scans. Returns the best score (-1 without sample), its viewpoint in best_v.
 * vote: num_parts scratch. */
static double
part_best_viewpoint(const dacpo_view_sample* vs,
                    double* vote,
                    size_t num_parts,
                    double best_v[3])
{
  dacpo_rng rng;
  dacpo_view_rng_seed(&rng);
  double facing = -1.0, best_dist = 0.0;
  for (size_t k = 0; k < DACPO_VIEW_CANDIDATES && vs->m > 0; ++k) {
    double v[3];
    dacpo_view_candidate(vs, &rng, k, v);
    double dist;
    const double score =
        dacpo_view_score(vs->p, vs->n, vs->part, vs->m, v, vote, num_parts, &dist);
    if (score > facing + DACPO_VIEW_TIE ||
        (score > facing - DACPO_VIEW_TIE && dist > best_dist)) {
      facing = fmax(score, facing);
      best_dist = dist;
      memcpy(best_v, v, 3 * sizeof(double));
    }
  }
  return facing;
}

/* Every point votes with the cosine between its normal and the direction to
 * v: a point v sees squarely counts fully, one it sees edge-on not at all. In
 * a scan seen from many places the one viewpoint can stand in the plane of a
 * part seen from elsewhere (a partition's face, v above its far edge): every
 * point of it then faces away from v by a hair, and a vote of signs would
 * turn the part over with a clear margin. By cosines the margin is the part's
 * mean cosine, near 0 there, so the part keeps stage 5's weak relation
 * (DACPO_PART_MIN_MARGIN, dacpo_sign_passes.c). The largest part keeps its
 * sign (the others follow it), so flip the votes when the largest one does
 * not face v. */
static void
part_signs_facing(const double* xyz,
                  const double* nrm,
                  size_t n,
                  const int32_t* part,
                  size_t num_parts,
                  const double v[3],
                  const size_t* size,
                  size_t big,
                  double* vote,
                  int8_t* sign,
                  double* confidence)
{
  memset(vote, 0, num_parts * sizeof(double));
  for (size_t i = 0; i < n; ++i) {
    const double* p = xyz + 3 * i;
    const double* q = nrm + 3 * i;
    const double d[3] = {v[0] - p[0], v[1] - p[1], v[2] - p[2]};
    const double len = sqrt((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) *
                            (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]));
    if (len > 0.0)
      vote[part[i]] += (q[0] * d[0] + q[1] * d[1] + q[2] * d[2]) / len;
  }
  const double ref = vote[big] < 0.0 ? -1.0 : 1.0;
  for (size_t c = 0; c < num_parts; ++c) {
    if (size[c] == 0)
      continue;
    sign[c] = vote[c] * ref < 0.0 ? -1 : 1;
    confidence[c] = fabs(vote[c]) / (double)size[c];
  }
  sign[big] = 1;
}

dacpo_status
dacpo_part_signs(const double* xyz,
                 const double* nrm,
                 size_t n,
                 const int32_t* part,
                 size_t num_parts,
                 int8_t* sign,
                 double* confidence,
                 double* score_out,
                 dacpo_err* err)
{
  DACPO_CHECK(err,
              xyz && nrm && part && sign && confidence,
              DACPO_ERR_INVALID_ARGUMENT,
              "part signs: NULL argument");
  for (size_t c = 0; c < num_parts; ++c) {
    sign[c] = 1;
    confidence[c] = c == 0 && num_parts == 1 ? 1.0 : 0.0;
  }
  if (score_out)
    *score_out = 0.0;
  if (num_parts <= 1 || n == 0)
    return DACPO_OK;

  size_t* size = dacpo_calloc_array(num_parts, sizeof(size_t));
  double* vote = dacpo_calloc_array(num_parts, sizeof(double));
  dacpo_view_sample vs;
  dacpo_status st = dacpo_view_sample_take(xyz, nrm, part, n, &vs, err);
  if (!size || !vote || st != DACPO_OK) {
    free(size);
    free(vote);
    if (st == DACPO_OK)
      dacpo_view_sample_free(&vs);
    return st == DACPO_OK ? DACPO_OOM(err) : st;
  }
  const size_t big = dacpo_part_largest(part, n, num_parts, size);
  double best_v[3] = {0.0, 0.0, 0.0};
  const double facing = part_best_viewpoint(&vs, vote, num_parts, best_v);
  if (score_out)
    *score_out = facing;
  if (facing >= DACPO_VIEW_MIN_SCORE)
    part_signs_facing(
        xyz, nrm, n, part, num_parts, best_v, size, big, vote, sign, confidence);
  confidence[big] = 1.0;
  free(size);
  free(vote);
  dacpo_view_sample_free(&vs);
  return DACPO_OK;
}

dacpo_status
dacpo_view_sample_take(const double* xyz,
                       const double* nrm,
                       const int32_t* part,
                       size_t n,
                       dacpo_view_sample* s,
                       dacpo_err* err)
{
  return dacpo_view_sample_take_at_most(xyz, nrm, part, n, DACPO_VIEW_SAMPLE, s, err);
}

dacpo_status
dacpo_view_sample_take_at_most(const double* xyz,
                               const double* nrm,
                               const int32_t* part,
                               size_t n,
                               size_t max_m,
                               dacpo_view_sample* s,
                               dacpo_err* err)
{
  memset(s, 0, sizeof(*s));
  DACPO_CHECK(err,
              max_m >= 1 && max_m <= DACPO_VIEW_SAMPLE,
              DACPO_ERR_INVALID_ARGUMENT,
              "view sample: size out of range");
  s->p = dacpo_malloc_array(3 * max_m, sizeof(double));
  s->n = dacpo_malloc_array(3 * max_m, sizeof(double));
  s->part = dacpo_malloc_array(max_m, sizeof(int32_t));
  if (!s->p || !s->n || !s->part) {
    dacpo_view_sample_free(s);
    return DACPO_OOM(err);
  }
  /* Evenly strided sample of the whole cloud and its bounding box. */
  const size_t stride = n > max_m ? (n + max_m - 1) / max_m : 1;
  s->stride = stride;
  for (int d = 0; d < 3; ++d) {
    s->lo[d] = HUGE_VAL;
    s->hi[d] = -HUGE_VAL;
  }
  for (size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      s->lo[d] = fmin(s->lo[d], xyz[3 * i + d]);
      s->hi[d] = fmax(s->hi[d], xyz[3 * i + d]);
    }
    if (i % stride == 0 && s->m < max_m) {
      memcpy(s->p + 3 * s->m, xyz + 3 * i, 3 * sizeof(double));
      memcpy(s->n + 3 * s->m, nrm + 3 * i, 3 * sizeof(double));
      s->part[s->m++] = part ? part[i] : 0;
    }
  }
  double dd = 0.0;
  for (int d = 0; d < 3 && n > 0; ++d)
    dd += (s->hi[d] - s->lo[d]) * (s->hi[d] - s->lo[d]);
  s->diam = sqrt(dd);
  return DACPO_OK;
}

void
dacpo_view_sample_free(dacpo_view_sample* s)
{
  free(s->p);
  free(s->n);
  free(s->part);
  memset(s, 0, sizeof(*s));
}

void
dacpo_view_rng_seed(dacpo_rng* rng)
{
  dacpo_rng_seed(rng, 0x7669657770ull /* "viewp" */, 0);
}

void
dacpo_view_candidate(const dacpo_view_sample* s, dacpo_rng* rng, size_t k, double v[3])
{
  /* sign unknown: either side of the normal, by 1/4 .. 2 scene diameters */
  static const double push[4] = {0.25, 0.5, 1.0, 2.0};
  const size_t j = dacpo_rng_below(rng, s->m);
  const double t = (k & 4u ? -1.0 : 1.0) * push[k % 4] * s->diam;
  for (int d = 0; d < 3; ++d)
    v[d] = s->p[3 * j + d] + t * s->n[3 * j + d];
}

/* ---- Closed parts face outward ------------------------------------------
 *
 * Why: the viewpoint vote relates a part to the scene by which way most of its
 * points face one viewpoint. An object seen from all round (a plant's crown
 * standing free in a room scanned from several places) faces every viewpoint
 * with half its points: the vote cannot place it (room3001: a 642-point crown
 * came out inside out on every seed, 0.6 % of the room). Such a part wraps
 * around its own centroid, and a closed surface's normals face outward, the
 * convention the global sign keeps for an enclosed scene: sign = that of the
 * mean cosine between the normal and the direction from the centroid.
 * "Wraps around": its points, seen from the centroid, fall in at least
 * CLOSED_MIN_CELLS of the 26 direction cells (each direction component
 * rounded to -1, 0, 1; a cap seen from one side fills at most ~17) and
 * |mean cosine| >= CLOSED_MIN_COS (a thin-walled open tube, inner and outer
 * wall together, is near 0). Measured on the parts of 18 rooms and a depth
 * frame: the crown 22 cells, cosine -0.94 (inward) on all three of its
 * rooms; every other part below 20 cells or 0.45, except one of 24 cells at
 * +0.95 (already outward). Only object-sized parts (bounding box diagonal at
 * most CLOSED_MAX_EXTENT of the widest part's, the room they stand in): a
 * room seen from inside (a closet with a ceiling, disconnected from the rest;
 * an open room) wraps around its centroid too, with its normals rightly
 * facing in. Against the whole cloud's box, two rooms scanned 100 m apart
 * were each small, and the second came out inside out. */
#define CLOSED_MIN_CELLS 20
#define CLOSED_MIN_COS 0.7
#define CLOSED_MAX_EXTENT 0.25

/* Squared diagonal of part q's bounding box (0 for an empty part). */
static double
part_extent2(const double* lo, const double* hi, const double* count, size_t q)
{
  double e = 0.0;
  for (int d = 0; count[q] > 0.0 && d < 3; ++d)
    e += (hi[3 * q + d] - lo[3 * q + d]) * (hi[3 * q + d] - lo[3 * q + d]);
  return e;
}

/* A flat part with two faces (a partition, a board standing free) is not
 * closed in the sense above (seen from its centroid it fills ~8 of the 26
 * cells, its mean cosine is ~0), yet its faces look away from its mid-plane.
 * Along the part's thinnest principal axis t (its spread at most
 * SLAB_MAX_THIN of the next one), every face point (|n.t| >= SLAB_FACE_COS)
 * votes +1 if it looks away from the plane midway between the part's ends
 * (robust ends: the SLAB_END quantiles of the offsets), -1 if towards it.
 * Both faces must be there: the face points looking along -t and those
 * looking along +t each hold a face's worth (SLAB_MIN_POINTS, or on a small
 * part SLAB_MIN_SIDE of them), of any sizes beyond, so a partition seen
 * mostly from one side is still two-faced; a surface seen from one side, its
 * points' offsets however skewed, is not. The part faces out (+1) or in (-1)
 * where the vote is clear (|mean| >= SLAB_MIN_SCORE) over all its face
 * points, each of its two outer layers (offsets within SLAB_LAYER of the
 * span from either end) votes the same way, and the band between them, where
 * it holds a face's worth, is as clear as the whole. A wall with things on it
 * (its back layer looks into the part, the things' fronts out of it) and a
 * surface seen several times (its copies spread over the span: after a
 * two-sheet reading the outer ones may face each other, the middle ones
 * split) give no answer. Any size: a room is never this thin (its least
 * spread, the height, is about half the next one), and a partition 1.8 m
 * high in a 6 x 5 m room spans more than a quarter of the room, the size up
 * to which a closed part counts as an object. */
#define SLAB_MAX_THIN 0.25
#define SLAB_FACE_COS 0.7
#define SLAB_LAYER 0.25
#define SLAB_END 0.02
#define SLAB_MIN_SCORE 0.6
#define SLAB_MIN_POINTS 100
#define SLAB_MIN_SIDE 0.25

/* Per part its thinnest principal axis t (axis, 3 per part) where it is a
 * slab (use[q] = 1), from the points' scatter about the centroids. cov: 6
 * doubles per part, zeroed by the caller. */
static void
slab_axes(const double* xyz,
          size_t n,
          const int32_t* part,
          size_t num_parts,
          const double* centre,
          const double* count,
          const int8_t* outward,
          double* cov,
          double* axis,
          double* use)
{
  for (size_t i = 0; i < n; ++i) {
    const size_t q = (size_t)part[i];
    const double* c = centre + 3 * q;
    const double r[3] = {xyz[3 * i] - c[0], xyz[3 * i + 1] - c[1], xyz[3 * i + 2] - c[2]};
    double* m = cov + 6 * q;
    m[0] += r[0] * r[0];
    m[1] += r[0] * r[1];
    m[2] += r[0] * r[2];
    m[3] += r[1] * r[1];
    m[4] += r[1] * r[2];
    m[5] += r[2] * r[2];
  }
  for (size_t q = 0; q < num_parts; ++q) {
    if (outward[q] != 0 || count[q] < SLAB_MIN_POINTS)
      continue;
    const double* m = cov + 6 * q;
    double a[3][3] = {{m[0], m[1], m[2]}, {m[1], m[3], m[4]}, {m[2], m[4], m[5]}}, w[3],
           v[3][3];
    dacpo_jacobi3(a, w, v);
    int k0 = 0; /* the thinnest axis, against the middle one */
    for (int k = 1; k < 3; ++k)
      if (w[k] < w[k0])
        k0 = k;
    const double middle = fmin(w[(k0 + 1) % 3], w[(k0 + 2) % 3]);
    if (!(middle > 0.0) || !(w[k0] <= SLAB_MAX_THIN * SLAB_MAX_THIN * middle))
      continue;
    for (int d = 0; d < 3; ++d)
      axis[3 * q + d] = v[d][k0];
    use[q] = 1.0;
  }
}

/* The slab parts' frames: per part its centroid, its thinnest axis t and
 * whether it is a slab (use[q] != 0). */
typedef struct slab_frames {
  const double* centre;
  const double* axis;
  double* use;
} slab_frames;

/* Offset of point i along its part's axis t, and n.t; 0 if i is not a face
 * point of a slab part. */
static int
slab_face_point(const double* xyz,
                const double* nrm,
                size_t i,
                size_t q,
                const slab_frames* fr,
                double* off,
                double* nt)
{
  if (fr->use[q] == 0.0)
    return 0;
  const double* t = fr->axis + 3 * q;
  const double* c = fr->centre + 3 * q;
  *nt = nrm[3 * i] * t[0] + nrm[3 * i + 1] * t[1] + nrm[3 * i + 2] * t[2];
  *off = (xyz[3 * i] - c[0]) * t[0] + (xyz[3 * i + 1] - c[1]) * t[1] +
         (xyz[3 * i + 2] - c[2]) * t[2];
  return fabs(*nt) >= SLAB_FACE_COS;
}

/* The robust ends lo[q], hi[q] of the slab parts' face point offsets along
 * their axes (the SLAB_END quantiles); use[q] = 0 for a part without face
 * points. */
static dacpo_status
slab_ends(const double* xyz,
          const double* nrm,
          size_t n,
          const int32_t* part,
          size_t num_parts,
          const slab_frames* fr,
          double* lo,
          double* hi,
          dacpo_err* err)
{
  double* offs = dacpo_malloc_array(n ? n : 1, sizeof(double));
  size_t* start = dacpo_calloc_array(num_parts + 1, sizeof(size_t));
  size_t* fill = dacpo_calloc_array(num_parts + 1, sizeof(size_t));
  if (!offs || !start || !fill) {
    free(offs);
    free(start);
    free(fill);
    return DACPO_OOM(err);
  }
  double off, nt;
  for (size_t i = 0; i < n; ++i) /* face points per part, then their offsets by part */
    start[part[i] + 1] +=
        (size_t)slab_face_point(xyz, nrm, i, (size_t)part[i], fr, &off, &nt);
  for (size_t q = 0; q < num_parts; ++q)
    fill[q + 1] = start[q + 1] += start[q];
  for (size_t i = 0; i < n; ++i)
    if (slab_face_point(xyz, nrm, i, (size_t)part[i], fr, &off, &nt))
      offs[fill[part[i]]++] = off;
  for (size_t q = 0; q < num_parts; ++q) {
    const size_t m = start[q + 1] - start[q];
    if (m == 0) {
      fr->use[q] = 0.0;
      continue;
    }
    const size_t k = (size_t)(SLAB_END * (double)m);
    lo[q] = dacpo_select_kth(offs + start[q], m, k);
    hi[q] = dacpo_select_kth(offs + start[q], m, m - 1 - k);
  }
  free(offs);
  free(start);
  free(fill);
  return DACPO_OK;
}

/* doubles of work per part, zeroed by the caller */
enum { SLAB_TALLY = 8, SLAB_WORK = 12 + SLAB_TALLY };

static dacpo_status
slab_parts_outward(const double* xyz,
                   const double* nrm,
                   size_t n,
                   const int32_t* part,
                   size_t num_parts,
                   const double* centre,
                   const double* count,
                   double* acc,
                   int8_t* outward,
                   dacpo_err* err)
{
  double *cov = acc, *axis = acc + 6 * num_parts, *use = acc + 9 * num_parts,
         *lo = acc + 10 * num_parts, *hi = acc + 11 * num_parts,
         *tally = acc + 12 * num_parts;
  slab_axes(xyz, n, part, num_parts, centre, count, outward, cov, axis, use);
  const slab_frames fr = {centre, axis, use};
  DACPO_TRY(slab_ends(xyz, nrm, n, part, num_parts, &fr, lo, hi, err));
  /* every face point votes +1 if it looks away from the mid-plane between the
   * ends; per part, by band (0 the low outer layer, 1 the high one, 2 between
   * them) the votes t[0..2] and the points t[3..5], and the points whose
   * normals look along -t and +t, t[6..7] */
  double off, nt;
  for (size_t i = 0; i < n; ++i) {
    const size_t q = (size_t)part[i];
    if (!slab_face_point(xyz, nrm, i, q, &fr, &off, &nt))
      continue;
    double* t = tally + SLAB_TALLY * q;
    const double layer = SLAB_LAYER * (hi[q] - lo[q]);
    const int band = off <= lo[q] + layer ? 0 : (off >= hi[q] - layer ? 1 : 2);
    const int above = off > 0.5 * (lo[q] + hi[q]);
    t[band] += above == (nt > 0.0) ? 1.0 : -1.0;
    t[3 + band] += 1.0;
    t[6 + (nt > 0.0)] += 1.0;
  }
  for (size_t q = 0; q < num_parts; ++q) {
    const double* t = tally + SLAB_TALLY * q;
    const double all = t[3] + t[4] + t[5], vote = t[0] + t[1] + t[2];
    /* a face's worth: SLAB_MIN_POINTS, or SLAB_MIN_SIDE of a small part's */
    const double face = fmin(SLAB_MIN_POINTS, SLAB_MIN_SIDE * all);
    if (use[q] == 0.0 || !(hi[q] > lo[q]) || t[6] < face || t[7] < face ||
        fabs(vote) < SLAB_MIN_SCORE * all)
      continue;
    const double way = vote > 0.0 ? 1.0 : -1.0;
    /* each face agrees, and the band between them, where it holds a face's
     * worth, is as clear as the whole */
    int agree = way * t[0] > 0.0 && way * t[1] > 0.0;
    agree &= t[5] < face || way * t[2] >= SLAB_MIN_SCORE * t[5];
    if (agree)
      outward[q] = (int8_t)way;
  }
  return DACPO_OK;
}

/* Per part its centroid, point count and bounding box. */
static void
part_boxes(const double* xyz,
           size_t n,
           const int32_t* part,
           size_t num_parts,
           double* centre,
           double* count,
           double* lo,
           double* hi)
{
  for (size_t i = 0; i < n; ++i) {
    const size_t q = (size_t)part[i];
    for (int d = 0; d < 3; ++d) {
      const double x = xyz[3 * i + d];
      centre[3 * q + d] += x;
      lo[3 * q + d] = fmin(lo[3 * q + d], x);
      hi[3 * q + d] = fmax(hi[3 * q + d], x);
    }
    count[q] += 1.0;
  }
  for (size_t q = 0; q < num_parts; ++q)
    for (int d = 0; count[q] > 0.0 && d < 3; ++d)
      centre[3 * q + d] /= count[q];
}

dacpo_status
dacpo_part_closed_outward(const double* xyz,
                          const double* nrm,
                          size_t n,
                          const int32_t* part,
                          size_t num_parts,
                          int8_t* outward,
                          dacpo_err* err)
{
  DACPO_CHECK(err,
              (xyz && nrm && part && outward) || n == 0 || num_parts == 0,
              DACPO_ERR_INVALID_ARGUMENT,
              "closed parts: NULL argument");
  if (num_parts == 0)
    return DACPO_OK;
  memset(outward, 0, num_parts);
  double* acc = dacpo_calloc_array((11 + SLAB_WORK) * num_parts, sizeof(double));
  uint32_t* cells = dacpo_calloc_array(num_parts, sizeof(uint32_t));
  if (!acc || !cells) {
    free(acc);
    free(cells);
    return DACPO_OOM(err);
  }
  double *centre = acc, *cosine = acc + 3 * num_parts, *count = acc + 4 * num_parts;
  double *lo = acc + 5 * num_parts, *hi = acc + 8 * num_parts;
  for (size_t q = 0; q < 3 * num_parts; ++q) {
    lo[q] = HUGE_VAL;
    hi[q] = -HUGE_VAL;
  }
  part_boxes(xyz, n, part, num_parts, centre, count, lo, hi);
  for (size_t i = 0; i < n; ++i) {
    const size_t q = (size_t)part[i];
    const double* c = centre + 3 * q;
    const double r[3] = {xyz[3 * i] - c[0], xyz[3 * i + 1] - c[1], xyz[3 * i + 2] - c[2]};
    const double len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(len > 0.0))
      continue;
    cosine[q] += (r[0] * nrm[3 * i] + r[1] * nrm[3 * i + 1] + r[2] * nrm[3 * i + 2]) / len;
    int cell = 0; /* base-3 digits of the rounded direction */
    for (int d = 0; d < 3; ++d)
      cell = 3 * cell + (r[d] > 0.5 * len ? 2 : (r[d] < -0.5 * len ? 0 : 1));
    cells[q] |= 1u << cell;
  }
  /* "object-sized" against the widest part, not the cloud's box: two rooms
   * far apart make a box in which either room is small */
  double all = 0.0;
  for (size_t q = 0; q < num_parts; ++q)
    all = fmax(all, part_extent2(lo, hi, count, q));
  for (size_t q = 0; q < num_parts; ++q) {
    int filled = 0;
    for (uint32_t m = cells[q]; m; m &= m - 1)
      ++filled;
    const double extent = part_extent2(lo, hi, count, q);
    const double mc = count[q] > 0.0 ? cosine[q] / count[q] : 0.0;
    if (filled >= CLOSED_MIN_CELLS && fabs(mc) >= CLOSED_MIN_COS &&
        extent <= CLOSED_MAX_EXTENT * CLOSED_MAX_EXTENT * all)
      outward[q] = mc > 0.0 ? 1 : -1;
  }
  const dacpo_status r = slab_parts_outward(
      xyz, nrm, n, part, num_parts, centre, count, acc + 11 * num_parts, outward, err);
  free(acc);
  free(cells);
  return r;
}
