/* SPDX-License-Identifier: BSD-3-Clause */
/* Relative sign of parts (components, or block groups joined only by weak
 * edges) from the viewpoint they imply (policy DACPO_DISCONNECTED_VIEWPOINT). */
#ifndef DACPO_PART_SIGN_H
#define DACPO_PART_SIGN_H

#include "dacpo_internal.h"

/* xyz, nrm: n points and their oriented normals (3n each); part[i] in
 * [0, num_parts) is the part of point i. Writes, per part, sign[c] in
 * {+1, -1} (multiply the part's normals by it; the largest part keeps +1) and
 * confidence[c] in [0, 1] (the vote margin: |mean cosine| between the part's
 * normals and the directions to the viewpoint; 1 for the largest part; 0 for
 * all others when no viewpoint explains the scene, then every sign stays +1).
 * *score_out (may be NULL) gets the share of a sample of the points that face the
 * chosen viewpoint under their part's best sign. The result does not depend on the
 * run's seed. Failures: NULL argument (INVALID_ARGUMENT), OUT_OF_MEMORY. */
dacpo_status
dacpo_part_signs(const double* xyz,
                 const double* nrm,
                 size_t n,
                 const int32_t* part,
                 size_t num_parts,
                 int8_t* sign,
                 double* confidence,
                 double* score_out,
                 dacpo_err* err);

/* Point count of every part added into size (num_parts entries, zeroed by the
 * caller); returns the largest part (the lowest index among equals). */
size_t
dacpo_part_largest(const int32_t* part, size_t n, size_t num_parts, size_t* size);

/* A strided sample of at most DACPO_VIEW_SAMPLE points (positions, normals,
 * part ids) and the cloud's bounding box: what the viewpoint searches score
 * (here and in dacpo_global_sign.c). part may be NULL (every id 0). */
enum { DACPO_VIEW_SAMPLE = 4096 };

typedef struct dacpo_view_sample {
  double* p;
  double* n;
  int32_t* part;
  size_t m;
  size_t stride; /* sample point s is cloud point s * stride */
  double lo[3], hi[3];
  double diam; /* bounding-box diagonal */
} dacpo_view_sample;

dacpo_status
dacpo_view_sample_take(const double* xyz,
                       const double* nrm,
                       const int32_t* part,
                       size_t n,
                       dacpo_view_sample* s,
                       dacpo_err* err);

/* The same with at most max_m points (1 <= max_m <= DACPO_VIEW_SAMPLE). */
dacpo_status
dacpo_view_sample_take_at_most(const double* xyz,
                               const double* nrm,
                               const int32_t* part,
                               size_t n,
                               size_t max_m,
                               dacpo_view_sample* s,
                               dacpo_err* err);

void
dacpo_view_sample_free(dacpo_view_sample* s);

/* How well v explains m points (sp, sn; 3m each): every part votes with its
 * points (+1 facing v, -1 not, into vote[part], num_parts entries; sc NULL =
 * all in part 0) and counts with the absolute value of its vote, since its sign
 * is what is being decided; divided by m (1: every point of every part faces v
 * under its part's best sign). *mean_dist gets the mean distance from v. */
double
dacpo_view_score(const double* sp,
                 const double* sn,
                 const int32_t* sc,
                 size_t m,
                 const double v[3],
                 double* vote,
                 size_t num_parts,
                 double* mean_dist);

/* Candidate viewpoint k of a sequence that depends only on the sample (rng
 * seeded with dacpo_view_rng_seed): a sample point pushed along either side
 * of its normal by 1/4 .. 2 scene diameters. */
void
dacpo_view_rng_seed(dacpo_rng* rng);
void
dacpo_view_candidate(const dacpo_view_sample* s, dacpo_rng* rng, size_t k, double v[3]);

/* Parts that wrap around their own centroid (closed objects, at most a
 * quarter of the widest part's size), and flat parts with two faces of any
 * size, however unequal (a free-standing board, a partition: its faces look
 * away from its mid-plane), the largest part included: outward[c] = +1 if
 * their normals (nrm, as they will be returned) face outward, -1 if inward,
 * 0 for every other part and where the evidence is not clear. Failures: NULL argument
 * (INVALID_ARGUMENT), OUT_OF_MEMORY. */
dacpo_status
dacpo_part_closed_outward(const double* xyz,
                          const double* nrm,
                          size_t n,
                          const int32_t* part,
                          size_t num_parts,
                          int8_t* outward,
                          dacpo_err* err);

#endif
