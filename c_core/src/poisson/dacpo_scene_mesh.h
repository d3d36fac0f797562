/* SPDX-License-Identifier: BSD-3-Clause */
/* Scene mesh (keep_mesh): one surface over all blocks, without cracks along the
 * block seams, reconstructed from the final oriented normals. */
#ifndef DACPO_SCENE_MESH_H
#define DACPO_SCENE_MESH_H
#include "dacpo_internal.h"
#include "dacpo_segment.h"

typedef struct dacpo_scene_mesh_input {
  const double* xyz; /* 3n distinct points */
  const double* nrm; /* 3n final normals (the caller's signs; need not be unit) */
  size_t n;          /* at least 1 */
  const dacpo_blocks* blocks;  /* own points and rings per block */
  const double* block_spacing; /* per block spacing, 0 = unknown (may be NULL) */
  size_t min_points;           /* blocks with fewer own + ring points get no surface */
  unsigned num_threads;        /* 0 = all cores */
  const dacpo_progress* progress;
} dacpo_scene_mesh_input;

/* Every block solves one screened Poisson problem (paper §4.3, the same solver
 * as stage 3) over its own and ring points with the final normals; every
 * node of one scene-wide lattice near the samples takes the indicator (minus
 * that block's iso-value) of the block that owns its nearest sample. Marching
 * cubes over that one field gives one indexed, consistently wound mesh: faces
 * point along the normals, and triangles of neighbouring blocks share their
 * seam vertices.
 * Errors: INVALID_ARGUMENT, OUT_OF_MEMORY, CANCELLED (progress). */
dacpo_status
dacpo_scene_mesh(const dacpo_scene_mesh_input* in, dacpo_mesh* out, dacpo_err* err);

#endif
