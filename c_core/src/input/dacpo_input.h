/* SPDX-License-Identifier: BSD-3-Clause */
/* Input checks and duplicate merging. */
#ifndef DACPO_INPUT_H
#define DACPO_INPUT_H

#include "dacpo_internal.h"

/* The distinct points the stages work on. Exact duplicates (same x, y, z bits
 * after -0 == +0) are merged: the dipole field divides by |r|^3. Every input
 * point maps to one distinct point, so results go back to every input point. */
typedef struct dacpo_cloud {
  size_t n;                /* distinct points */
  size_t input_count;      /* points given */
  double* xyz;             /* 3n */
  double* nrm;             /* 3n unit axes; zero until normals are known */
  int32_t* rep_input;      /* n: lowest input index of distinct point i */
  int32_t* input_to_point; /* input_count: distinct point of input i */
} dacpo_cloud;

/* NULL pointers (INVALID_ARGUMENT), count == 0 (EMPTY_INPUT), count too large
 * for int32 indices (INVALID_ARGUMENT), non-finite coordinates, and, when
 * normals != NULL, non-finite or zero-length normals (NONFINITE_INPUT naming the
 * first bad index). */
dacpo_status
dacpo_input_check(const float* xyz, const float* normals, size_t count, dacpo_err* err);

/* Builds the distinct cloud. normals may be NULL (nrm left zero); given normals
 * are normalized (the representative's axis is used for a merged group). */
dacpo_status
dacpo_cloud_build(const float* xyz,
                  const float* normals,
                  size_t count,
                  dacpo_cloud* out,
                  dacpo_err* err);

void
dacpo_cloud_free(dacpo_cloud* cloud);

#endif
