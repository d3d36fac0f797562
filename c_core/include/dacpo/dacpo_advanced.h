/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_advanced.h
 * \brief dacpo_orient() as work units, for callers that schedule the work
 * themselves (a cluster, a queue, a progress view per block).
 *
 * A job holds one cloud's run. dacpo_orient() is exactly these calls in this
 * order, with the block and edge units run by its own threads:
 *
 *   dacpo_job_create                 input, k-NN graph, normals, blocks (stages 0-1)
 *   dacpo_job_orient_block  b = 0..  dipole field and iPSR of one block (stages 2-3)
 *   dacpo_job_weigh_edge    e = 0..  VCR evidence of one block edge (stage 4), or
 *   dacpo_job_weigh_edges            every edge at once (any edge_weight measure)
 *   dacpo_job_solve                  0-1 program, parts, global sign (stages 5-6)
 *   dacpo_job_finish                 normals in input order, results in the context
 *   dacpo_job_free
 *
 * Units depend only on what the steps before them produced: every block before
 * any edge (an edge reads the meshes of its two blocks, dacpo_job_edge_blocks),
 * every edge before the solve. Blocks may run in any order and at the same
 * time on different threads (each block writes only its own results); so may
 * edges. The answer does not depend on the order: every block draws its random
 * numbers from its own stream of params->seed.
 *
 * Errors: create, weigh_edges, solve and finish report like dacpo_orient()
 * (status, message in dacpo_ctx_last_error()); the units, which may run
 * concurrently, write their message into the caller's buffer (msg may be NULL).
 * The job uses the context for its results and messages: one job per context at
 * a time, the context outlives the job, and per-point results appear in the
 * context only after dacpo_job_finish(). Stage times: dacpo_orient() times
 * every stage; with the units, stats.stage_seconds holds stages 0-1, 5-6 and the
 * mesh, and the caller times the units.
 */
#ifndef DACPO_DACPO_ADVANCED_H
#define DACPO_DACPO_ADVANCED_H

#include <dacpo/dacpo.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dacpo_job dacpo_job;

/** \brief Input checks and stages 0-1 (as dacpo_orient()). normals: the
 *  given axes when params->estimate_normals is 0 (may be NULL otherwise); the
 *  job copies what it needs. On failure *out is NULL. */
DACPO_API dacpo_status
dacpo_job_create(dacpo_ctx* ctx,
                 const dacpo_params* params,
                 const dacpo_search* search,
                 const dacpo_progress* progress,
                 const float* xyz,
                 const float* normals,
                 size_t count,
                 dacpo_job** out);

/** \brief Number of blocks (valid block ids are 0 .. n-1). 0 for NULL. */
DACPO_API size_t
dacpo_job_num_blocks(const dacpo_job* job);

/** \brief Number of block-graph edges. 0 for NULL. */
DACPO_API size_t
dacpo_job_num_edges(const dacpo_job* job);

/** \brief The two blocks edge e joins. */
DACPO_API dacpo_status
dacpo_job_edge_blocks(const dacpo_job* job, size_t e, size_t* a, size_t* b);

/** \brief Stages 2-3 of block b. Thread-safe for distinct blocks. */
DACPO_API dacpo_status
dacpo_job_orient_block(dacpo_job* job, size_t b, char* msg, size_t msg_size);

/** \brief Stage 4 of edge e with VCR weights (edge_weight DACPO_WEIGHT_VCR),
 *  after both its blocks. Thread-safe for distinct edges. */
DACPO_API dacpo_status
dacpo_job_weigh_edge(dacpo_job* job, size_t e, char* msg, size_t msg_size);

/** \brief Stage 4 for every edge, with the measure of params->edge_weight, on
 *  params->num_threads threads; after every block. */
DACPO_API dacpo_status
dacpo_job_weigh_edges(dacpo_job* job);

/** \brief Stages 5-6: block flips, relative signs of parts, the global sign. */
DACPO_API dacpo_status
dacpo_job_solve(dacpo_job* job);

/** \brief Writes the oriented normals in input order and the per-point results
 *  into the context. normals: count * 3 floats; when the axes were given it
 *  must hold them (as in dacpo_orient(), it is read and overwritten). */
DACPO_API dacpo_status
dacpo_job_finish(dacpo_job* job, float* normals);

/** \brief NULL-safe. */
DACPO_API void
dacpo_job_free(dacpo_job* job);

#ifdef __cplusplus
}
#endif

#endif /* DACPO_DACPO_ADVANCED_H */
