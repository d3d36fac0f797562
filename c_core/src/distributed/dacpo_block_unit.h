/* SPDX-License-Identifier: BSD-3-Clause */
/* Stages 2-3 of one block from its points alone, and the byte format that
 * carries a block's or an edge's work to another process (dacpo_advanced.h). */
#ifndef DACPO_BLOCK_UNIT_H
#define DACPO_BLOCK_UNIT_H

#include <dacpo/dacpo.h>

#include "dacpo_internal.h"
#include "dacpo_ipsr.h"
#include "dacpo_vcr.h"

/* Blocks smaller than this are too small for a Poisson solve; they keep the
 * dipole orientation (stage 2). */
#define DACPO_MIN_IPSR_POINTS 32

/* What stages 2-3 give for one block of n points (own points first, then
 * ring). */
typedef struct dacpo_block_out {
  double* nrm;           /* 3n oriented normals: own points, then the ring */
  float* conf;           /* n_own: in-block confidence (halved where stage 3
                            turned the stage-2 sign over) */
  uint32_t cue_votes[2]; /* own points whose side cue agrees / disagrees */
  uint32_t restarts;     /* stage-2 restarts run */
  dacpo_mesh mesh;       /* stage-3 mesh (only when asked for) */
  dacpo_ipsr_stats ipsr;
  double seconds[2]; /* stage 2, stage 3 */
} dacpo_block_out;

/* Stages 2-3 of block `block` (its random stream) with p's dipole and iPSR
 * settings; xyz and axes hold 3n doubles, own points first. want_mesh: the
 * block's mesh is kept (VCR edge weights need it). */
dacpo_status
dacpo_block_unit_run(const dacpo_params* p,
                     size_t block,
                     const double* xyz,
                     const double* axes,
                     size_t n,
                     size_t n_own,
                     int want_mesh,
                     dacpo_block_out* out,
                     dacpo_err* err);

void
dacpo_block_out_free(dacpo_block_out* out); /* NULL-safe; zeroes the struct */

/* ---- byte format (same build on both ends: native byte order) ---------- */

/* A block's work: the run's parameters, the block id, its points. bytes NULL:
 * only *size is set (the same for the edge task). */
dacpo_status
dacpo_block_task_pack(const dacpo_params* p,
                      size_t block,
                      const double* xyz,
                      const double* axes,
                      size_t n,
                      size_t n_own,
                      int want_mesh,
                      void** bytes,
                      size_t* size,
                      dacpo_err* err);

/* A block's result; unpacking checks every size and index. */
dacpo_status
dacpo_block_result_pack(size_t block,
                        size_t n,
                        size_t n_own,
                        const dacpo_block_out* out,
                        int has_mesh,
                        void** bytes,
                        size_t* size,
                        dacpo_err* err);

dacpo_status
dacpo_block_result_unpack(const void* bytes,
                          size_t size,
                          size_t* block,
                          size_t* n,
                          size_t* n_own,
                          int* has_mesh,
                          dacpo_block_out* out,
                          dacpo_err* err);

/* An edge's work: the run's parameters and the meshes of its two blocks. */
dacpo_status
dacpo_edge_task_pack(const dacpo_params* p,
                     size_t edge,
                     const dacpo_mesh* a,
                     const dacpo_mesh* b,
                     void** bytes,
                     size_t* size,
                     dacpo_err* err);

/* A unit's status, its message copied into the caller's buffer (msg may be
 * NULL; "" on success). */
dacpo_status
dacpo_unit_message(const dacpo_err* err, char* msg, size_t msg_size);

/* VCR settings of the run (stage 4). */
void
dacpo_block_unit_vcr_params(const dacpo_params* p, dacpo_vcr_params* vp);

#endif
