/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 6 helper: the space other frames saw through, for a frame's sensor. */
#ifndef DACPO_FREE_SPACE_H
#define DACPO_FREE_SPACE_H

#include "dacpo_internal.h"

/* The cells (cubes of side `cell`) that hold points, each with the lowest and
 * highest frame among its points: a hash of the occupied cells only. */
typedef struct dacpo_free_space {
  double cell;
  double origin[3]; /* the points' box: lowest corner ... */
  double top[3];    /* ... and highest */
  size_t mask;   /* capacity - 1 (a power of two) */
  uint64_t* key; /* cell key + 1; 0: empty slot */
  uint32_t* lo;  /* lowest frame holding a point in the cell */
  uint32_t* hi;  /* highest */
} dacpo_free_space;

/* The cells of n points xyz (3n) of frames frame[i], side `cell` (> 0; made
 * larger where the cloud spans over 2^20 of them along an axis).
 * Failures: NULL argument or cell <= 0 (INVALID_ARGUMENT), OUT_OF_MEMORY. */
dacpo_status
dacpo_free_space_make(const double* xyz,
                      size_t n,
                      const uint32_t* frame,
                      double cell,
                      dacpo_free_space* out,
                      dacpo_err* err);

void
dacpo_free_space_free(dacpo_free_space* s);

/* 1 if v lies inside the box of the points the cells were made from. */
int
dacpo_free_space_inside(const dacpo_free_space* s, const double v[3]);

/* 1 if the segment from p to v, less `skip` at each end (a surface's own
 * copies and noise near p, the sensor's own surroundings), passes through a
 * cell holding a point of a frame other than `frame`: a sensor at v could not
 * have seen p past it. 0 if the segment is shorter than 2 skip. */
int
dacpo_free_space_blocked(const dacpo_free_space* s,
                         const double p[3],
                         const double v[3],
                         double skip,
                         uint32_t frame);

#endif
