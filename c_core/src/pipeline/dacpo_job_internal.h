/* SPDX-License-Identifier: BSD-3-Clause */
/* What dacpo_pipeline.c (the run and its order) and dacpo_job_units.c (the
 * units of dacpo_advanced.h one by one, in this process or as bytes for
 * another) share: the state of one run and the steps of one block or edge. */
#ifndef DACPO_JOB_INTERNAL_H
#define DACPO_JOB_INTERNAL_H

#include <dacpo/dacpo_advanced.h>

#include "dacpo_block_graph.h"
#include "dacpo_block_unit.h"
#include "dacpo_context.h"
#include "dacpo_ilp.h"
#include "dacpo_input.h"
#include "dacpo_ipsr.h"
#include "dacpo_knn.h"
#include "dacpo_segment.h"

typedef struct run_state {
  dacpo_params p;
  const dacpo_progress* progress;
  dacpo_cloud cloud;
  dacpo_knn_graph knn;
  dacpo_adjacency adj;
  int32_t* component;       /* component the stages work with (0 after bridging) */
  int32_t* input_component; /* component of the k-NN graph, as reported */
  size_t num_components;
  int32_t largest_component_id; /* input component with the most points */
  float* curvature;             /* per distinct point, only when estimated */
  dacpo_blocks blocks;
  dacpo_block_graph bgraph;
  double* oriented; /* 3n: normals after stages 2-3, before flips */
  float*
      point_conf; /* n: in-block confidence (stage 2, halved where stage 3 disagreed) */
  double* ring_oriented;  /* 3 per ring entry: each block's normals of its ring */
  dacpo_mesh* meshes;     /* per block, only for VCR weights */
  dacpo_mesh scene_mesh;  /* keep_mesh: one surface from the final normals */
  dacpo_ipsr_stats* ipsr; /* per block */
  double* block_seconds;  /* per block: [2b] dipole, [2b+1] iPSR */
  uint8_t* flips;         /* per block */
  uint32_t* cue_votes;   /* 2 per block: own points whose side cue agrees / disagrees */
  uint32_t* restarts;    /* per block: stage-2 restarts run */
  float* block_conf;     /* per block: how firmly stage 5 holds its flip */
  double evidence_scale; /* median alpha + alpha-bar of the block edges (stage 5) */
  int32_t* part;         /* n: part of each point (VIEWPOINT policy) */
  int8_t* part_sign;     /* per part */
  double* part_conf;     /* per part */
  double global_sign;    /* +1 or -1: stage 6 */
  uint8_t* turned;       /* n: 1 where the surface vote or the sensor turned the
                            point over, or NULL */
  int sensor_known;      /* 1: one depth view whose sensor stage 0 found */
  double sensor[3];      /* that sensor's position (either side of the surfaces) */
  dacpo_ilp_result ilp;
  /* what the work units have done (dacpo_advanced.h checks the order) */
  uint8_t* block_done; /* per block: stages 2-3 */
  uint8_t* edge_done;  /* per edge: stage 4 */
  int solved, finished;
} run_state;

struct dacpo_job {
  dacpo_ctx* ctx;
  run_state s;
  double t0; /* start of the run */
  double t;  /* end of the last stage timed */
};

/* Block b's own points, then its ring: xyz and axes, 3 doubles per point. */
void
dacpo_run_gather_block(const run_state* s, size_t b, double* xyz, double* axes);

size_t
dacpo_run_block_own(const run_state* s, size_t b); /* own points of block b */

size_t
dacpo_run_block_size(const run_state* s, size_t b); /* own + ring points */

/* Block b's results into the run; its mesh moves into the run. */
void
dacpo_run_store_block(run_state* s, size_t b, dacpo_block_out* out);

/* Stages 2-3 of block b / stage 4 (VCR) of edge e, in the run's process
 * (dacpo_parallel_for callbacks: user is the run_state). */
dacpo_status
dacpo_run_orient_block(void* user, size_t b, unsigned thread_id, dacpo_err* err);

dacpo_status
dacpo_run_weigh_edge_vcr(void* user, size_t e, unsigned thread_id, dacpo_err* err);

#endif
