/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 2 helper: which face of a thin two-sided part a point lies on. */
#ifndef DACPO_SHEET_SIDE_H
#define DACPO_SHEET_SIDE_H

#include "dacpo_internal.h"

/* side[i] in [-1, 1] for n points of one block: the sign says along which
 * direction of the axis nrm[i] the point's face looks (+1: +nrm[i], away from
 * the other face), the magnitude how sure the test is (0: no second face seen,
 * or the offsets are not clearly two-valued).
 *
 * xyz, nrm: 3n doubles (unit axes); nb: n x K nearest neighbours of every point
 * (self excluded, nearest first; rows padded with the point itself are allowed);
 * fit_k: how many of the K nearest the surface fit considers (at most
 * DACPO_SIDE_MAX_NEIGHBORS; 0 = 24);
 * spacing: the block's typical nearest-neighbour distance.
 * face (n x K, may be NULL): where the cue fires, face[i K + t] = +1 if nb[i K + t]
 * lies on point i's own face, -1 on the other face, 0 if it was not part of the
 * fit (axis not parallel, beyond the first 24), SIDE_HIDDEN if it lies beyond
 * the other face (the part hides it from point i's face); 0 everywhere else.
 * strict (may be NULL): the number of points where the stricter first test
 * (one quadric) fires - the share that tells a block with thin parts from a
 * single depth frame's block.
 *
 * Failures: none beyond INVALID_ARGUMENT for NULL arrays (pure arithmetic). */
/* An orthonormal tangent pair (e1, e2) for unit axis a. */
void
dacpo_tangent_frame(const double a[3], double e1[3], double e2[3]);

#define SIDE_HIDDEN (-2)
/* A clear split into two faces (also the band's crossing test,
 * dacpo_sheets_cross.c): each group holds this share of the points ... */
#define DACPO_SIDE_MIN_CLUSTER 0.25
/* ... their lateral centroids lie closer than this many mean lateral
 * distances (over each other, not beside each other) ... */
#define DACPO_SIDE_MAX_LATERAL 0.5
/* ... the gap exceeds this many spacings ... */
#define DACPO_SIDE_MIN_GAP 0.3
/* ... and this many deviations of the residuals (noise alone reaches ~5
 * with 25 points). */
#define DACPO_SIDE_SEP_START 5.0

/* Otsu's two-group split of m sorted values s: the separation
 * (mu_hi - mu_lo) / sigma_within of the best split that leaves both groups
 * DACPO_SIDE_MIN_CLUSTER of the values, its threshold and mu_hi - mu_lo in
 * *threshold and *gap (not written, and 0 returned, if there is none). */
double
dacpo_otsu_sorted(const double* s, size_t m, double* threshold, double* gap);
#define DACPO_SIDE_MAX_NEIGHBORS 32

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
                 dacpo_err* err);

/* The same test pooled over planar patches (parallel axes grown over the first
 * 12 neighbours of nb, within 12 spacings) whose points are noisy (median of
 * noise[i], the point's local noise scale, at least 2.5 % of the spacing; clean
 * data is left to the test above): where a patch's offsets are clearly
 * two parallel copies of one quadric 0.25-1.5 spacings apart, each point of it
 * whose own cue is silent (side[i] == 0) gets conf[i] in [-1, 1] \ {0}, signed
 * as side[] (its face looks away from the other copy), and its face row (as
 * above: +1 own copy, -1 other copy, 0 outside the patch); every other point
 * conf[i] = 0 and its row untouched. field (may be NULL): where conf[i] != 0,
 * how far to trust its sign, in [0, 1] (the patch's separation on the point
 * test's ramp, 5 to 8: noisy copies relate their points, clear ones also say
 * which way a face looks); 0 elsewhere. fired: points given a conf.
 * Failures: OOM; INVALID_ARGUMENT for NULL arrays. */
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
                    dacpo_err* err);
#endif
