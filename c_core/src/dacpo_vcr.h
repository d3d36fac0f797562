/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 4b: visible connected regions between two adjacent blocks' meshes
 * (paper §5.1, ALGORITHM.md §4). */
#ifndef DACPO_VCR_H
#define DACPO_VCR_H

#include "dacpo_internal.h"

typedef struct dacpo_vcr_params {
  size_t image_size;       /* 400 */
  size_t num_views;        /* 12 (dodecahedron face centres) */
  int perspective;         /* 0 orthographic, 1 perspective */
  int boundary_factor;     /* 1: I = C_B*C1*C2 (paper); 0: I = C1*C2 */
} dacpo_vcr_params;

void
dacpo_vcr_params_default(dacpo_vcr_params* p);

/* alpha: view-alignment evidence with both meshes as they are; alpha_bar: the
 * same with mesh b's facing inverted (same z-buffer, labelled twice). */
dacpo_status
dacpo_vcr_edge(const dacpo_mesh* a,
               const dacpo_mesh* b,
               const dacpo_vcr_params* params,
               double* alpha,
               double* alpha_bar,
               dacpo_err* err);

#endif
