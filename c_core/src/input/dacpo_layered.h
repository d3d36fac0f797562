/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0 helper: do the scene's surfaces come as offset copies of themselves
 * (views fused with registration error)? */
#ifndef DACPO_LAYERED_H
#define DACPO_LAYERED_H

#include "dacpo_internal.h"

/* *share: on the scene's largest planar band (points whose axes lie within
 * ~10 degrees of one of its three main directions, in the 3-spacing-thick slab
 * along it that holds most of them) if the scene lies on one side of it, the
 * share of up to
 * DACPO_LAYERED_SAMPLE of its points where the thin-part side test
 * (dacpo_sheet_side, 32 neighbours) finds a second face. In a room that band
 * is the floor, which nothing lies beneath (see DACPO_LAYERED_SHARE for the
 * values measured). 0 when no band holds DACPO_LAYERED_MIN_BAND
 * sampled points or the scene lies on both sides of it.
 *
 * *copies (the copy rate): on the same band, if it qualifies, the share of up
 * to DACPO_LAYERED_SAMPLE points of the surface itself (the densest slab one
 * spacing thick in the band) that have a second parallel sheet within two
 * spacings: stage 2's two-sheet pair test. *doubled: the share of the same
 * points with a second parallel sheet anywhere in the slab (up to two band
 * widths from them, among their nearest in the plane): copies wider apart
 * than the pair window, as whole frames off by 2 cm. Both 0 where *share is 0
 * for want of a band.
 *
 * *crossing: where the slab's parallel points hold two sheets that cross
 * along a line (dacpo_sheets_cross: copies tilted against each other, which
 * no thin solid's faces can be), the share of its two-sheet cells on the
 * smaller side of the line, else 0. A crossing band qualifies whatever lies
 * around it, so *share, *copies and *doubled are measured on it too.
 *
 * xyz, axes: n points and unit axes (3n each); knn_idx, knn_sqd: n x knn_k
 * nearest neighbours (self excluded, nearest first, -1 / inf padded) and their
 * squared distances.
 * Failures: NULL argument (INVALID_ARGUMENT), OUT_OF_MEMORY. */
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
                    dacpo_err* err);
/* From this copy rate on, the two-sheet rule (its pairs and c_thin) is left
 * out as well as the side cue: copies lie on the floor everywhere, not only
 * where a thing rests close above it. Values measured and margins:
 * docs/DESIGN.md ("Copies or thin solids"). */
#define DACPO_LAYERED_COPIES 0.04
/* ... or from this share of the floor in two sheets or more anywhere in the
 * slab: a fifth of it (things resting close above a room's floor cover up to
 * 0.091 of it; frames fused with 20 mm of pose error read 0.15-0.86). Values
 * measured and margins: docs/DESIGN.md ("Copies or thin solids"). */
#define DACPO_LAYERED_DOUBLED 0.2

/* From this share of the band the scene counts as layered and the side cue
 * is left out (dacpo_pipeline.c). Measured with PCA axes: 18 shared rooms and
 * 16 generated ones 0-0.024, except a uniform room downsampled to 10K points
 * (4.3 cm spacing: the gaps under furniture on feet lie within a spacing of
 * the floor) 0.050; eleven rooms fused from 3-6 views 6-15 mm and 0.15-0.3
 * degrees apart 0.078-0.348 (views 4 mm and 0.1 degrees apart: 0.025, and
 * there the cue does no harm). 0.03 (tried) turned that 10K room's cue off:
 * 9.88 -> 13.08 % (median of seeds 1-5). */
#define DACPO_LAYERED_SHARE 0.065
/* Band points the side test looks at. */
#define DACPO_LAYERED_SAMPLE 2000
/* Sampled points a band needs before it says anything. */
#define DACPO_LAYERED_MIN_BAND 64
/* The band must have the scene on one side: at least this share of all points
 * lies beyond its slab, and at most this share of those on its other side
 * under the band (a floor has none beneath it; two sheets alone, or a
 * partition in a room, do not qualify; things beside a floor, lower than it,
 * are not beneath it). */
#define DACPO_LAYERED_MIN_BEYOND 0.1
#define DACPO_LAYERED_MAX_OTHER_SIDE 0.02

#endif
