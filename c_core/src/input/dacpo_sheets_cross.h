/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0 helper: do the two sheets of a planar band cross each other? */
#ifndef DACPO_SHEETS_CROSS_H
#define DACPO_SHEETS_CROSS_H

#include "dacpo_internal.h"

/* uvy: m points of one planar band in its own frame (u, v across the plane, y
 * along its axis, 3m doubles); spacing: the cloud's typical nearest-neighbour
 * distance. *crossing: where the band holds two sheets that cross along a line
 * (copies of one surface tilted against each other), the share of its
 * two-sheet cells on the smaller side of that line, in (0, 0.5]; 0 where it
 * holds no such pair (one sheet, parallel sheets, sheets too noisy to tell).
 * A thin solid's two faces never cross, so a crossing says "copies".
 * Failures: OUT_OF_MEMORY; INVALID_ARGUMENT for NULL arrays. */
dacpo_status
dacpo_sheets_cross(
    const double* uvy, size_t m, double spacing, double* crossing, dacpo_err* err);

#endif
