/* SPDX-License-Identifier: BSD-3-Clause */
/* The context's layout (private). */
#ifndef DACPO_CONTEXT_H
#define DACPO_CONTEXT_H

#include "dacpo_internal.h"

struct dacpo_ctx {
  char last_error[512];
  dacpo_stats stats;
  int32_t* point_component; /* input_points */
  int32_t* point_block;     /* input_points */
  float* point_curvature;   /* input_points, only when normals were estimated */
  float* point_confidence;  /* input_points */
  uint8_t* block_flips;     /* num_blocks */
  dacpo_edge_info* edges;   /* num_block_edges */
  float* mesh_vertices;     /* 3 * mesh_num_vertices (keep_mesh) */
  int32_t* mesh_triangles;  /* 3 * mesh_num_triangles */
  size_t mesh_num_vertices;
  size_t mesh_num_triangles;
};

/* Frees the per-run results and zeroes the stats. */
void
dacpo_ctx_clear_results(dacpo_ctx* ctx);

/* Copies err's message into the context; returns err->code. */
dacpo_status
dacpo_ctx_fail(dacpo_ctx* ctx, const dacpo_err* err);

#endif
