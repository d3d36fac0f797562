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
 * Units in another process (a cluster rank): a block's or an edge's work
 * leaves the job as bytes and its answer comes back as bytes or two numbers,
 *
 *   dacpo_job_block_task  -> dacpo_block_task_run (anywhere) -> dacpo_job_put_block
 *   dacpo_job_edge_task   -> dacpo_edge_task_run  (anywhere) -> dacpo_job_put_edge
 *
 * A task carries the run's parameters and everything its unit reads (a
 * block's own and ring points; an edge's two block meshes), so the process
 * that runs it needs no job and no cloud. dacpo_job_orient_block() runs the
 * same code in the job's process: the answer is the same bytes either way.
 * The byte format is native (byte order, struct layout): both ends must run
 * the same build. A malformed, truncated or mismatched message is refused
 * with INVALID_ARGUMENT. Free the bytes with dacpo_unit_bytes_free().
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

/** \brief Block b's work as bytes (its points and the run's parameters),
 *  for dacpo_block_task_run() in any process. bytes NULL: only *size is set
 *  (a measure of the block's cost: 48 bytes per own or ring point). */
DACPO_API dacpo_status
dacpo_job_block_task(const dacpo_job* job,
                     size_t b,
                     void** bytes,
                     size_t* size,
                     char* msg,
                     size_t msg_size);

/** \brief Stages 2-3 of the block a task describes, without a job: the result
 *  as bytes for dacpo_job_put_block(). Thread-safe. */
DACPO_API dacpo_status
dacpo_block_task_run(const void* task,
                     size_t task_size,
                     void** result,
                     size_t* result_size,
                     char* msg,
                     size_t msg_size);

/** \brief A block's result into the job (the block is then oriented, as after
 *  dacpo_job_orient_block()); checks that it fits the block it names. Not
 *  thread-safe against other calls on the same job. */
DACPO_API dacpo_status
dacpo_job_put_block(
    dacpo_job* job, const void* bytes, size_t size, char* msg, size_t msg_size);

/** \brief Edge e's work as bytes (the two block meshes; VCR weights), after
 *  both its blocks. bytes NULL: only *size is set (grows with the meshes). */
DACPO_API dacpo_status
dacpo_job_edge_task(const dacpo_job* job,
                    size_t e,
                    void** bytes,
                    size_t* size,
                    char* msg,
                    size_t msg_size);

/** \brief Stage 4 (VCR) of the edge a task describes, without a job. */
DACPO_API dacpo_status
dacpo_edge_task_run(const void* task,
                    size_t task_size,
                    double* alpha,
                    double* alpha_bar,
                    char* msg,
                    size_t msg_size);

/** \brief Edge e's evidence into the job (as after dacpo_job_weigh_edge()). */
DACPO_API dacpo_status
dacpo_job_put_edge(dacpo_job* job,
                   size_t e,
                   double alpha,
                   double alpha_bar,
                   char* msg,
                   size_t msg_size);

/**
 * \brief Stage 0's neighbour search for one region of a cloud (a slab of a
 *  spatial split), so that processes can share it: the k nearest of every own
 *  point among the region's n points (its own points and a halo around them).
 *
 * xyz: 3n floats in the order of the caller's global point numbers (ascending),
 * so that ties go to the lower number as in a search over the whole cloud;
 * own[i] != 0 marks the points that want a row (m of them). For the j-th own
 * point: nbr[j k + t] (region indices, the point itself and its exact
 * duplicates included, nearest first, ties to the lower index, -1 past the
 * region's size) and, unless sqd is NULL, sqd[j k + t] (squared distances,
 * +inf for -1); complete[j]
 * = 1 when the row is certain: box_lo / box_hi bound the space in which the
 * region holds every point of the cloud (+-HUGE_VAL: unbounded), and the ball
 * through the k-th neighbour lies inside it. Rows of complete points joined
 * over regions equal the whole cloud's k nearest; for the others widen the halo
 * and ask again. Serve the joined rows to dacpo_job_create() through a
 * dacpo_search (pcl_dacpo_orient_mpi does). Thread-safe, no job needed.
 * Errors: INVALID_ARGUMENT (NULL arrays other than sqd, k = 0), NONFINITE_INPUT,
 * OUT_OF_MEMORY.
 */
DACPO_API dacpo_status
dacpo_region_knn(const float* xyz,
                 const uint8_t* own,
                 size_t n,
                 size_t k,
                 const double box_lo[3],
                 const double box_hi[3],
                 int32_t* nbr,
                 float* sqd,
                 uint8_t* complete,
                 char* msg,
                 size_t msg_size);

/** \brief Frees bytes a task or result call returned. NULL-safe. */
/**
 * \name Tiles: clouds larger than one process holds
 *
 * A cloud too large for one dacpo_orient() (out-of-core on one machine, or
 * spread over cluster ranks) is cut into spatial tiles; each tile's own points
 * and a halo around them are oriented by dacpo_orient() on their own, and the
 * tiles' relative signs are then joined from the halo points, which two tiles
 * orient:
 *
 *   dacpo_tile_plan_create   from a sample (e.g. every s-th point of the file)
 *   dacpo_tile_locate        per point: its own tile and the tiles whose halo
 *                            holds it (so a streaming pass can route it)
 *   dacpo_orient             per tile, its own + halo points in input order
 *   dacpo_tile_join          overlap evidence -> which tiles to flip
 *
 * The plan depends only on the sample, total, max_points and halo: processes
 * that read the same sample agree on it without talking, and a tile's answer
 * does not depend on which process runs it. With one tile the result is
 * dacpo_orient()'s on the whole cloud.
 * @{
 */
typedef struct dacpo_tile_plan dacpo_tile_plan;

/** \brief A kd-split of the sample (m points, 3m floats, finite): cells cut
 *  at the sample's median along their longest side until each holds at most
 *  about 0.8 x max_points of the total points (the rest is room for its halo).
 *  halo: how far (per axis, in coordinate units) a tile reads beyond its cell;
 *  0 = automatic, 16 spacings of the whole cloud (spacing estimated from the
 *  sample). Errors: EMPTY_INPUT (m == 0 or m > total), INVALID_ARGUMENT
 *  (max_points < 16, halo < 0, more than 65,536 tiles), NONFINITE_INPUT,
 *  OUT_OF_MEMORY. */
DACPO_API dacpo_status
dacpo_tile_plan_create(const float* sample,
                       size_t m,
                       uint64_t total,
                       uint64_t max_points,
                       double halo,
                       dacpo_tile_plan** out,
                       char* msg,
                       size_t msg_size);

/** \brief Number of tiles (ids 0 .. count-1); 0 for NULL. */
DACPO_API size_t
dacpo_tile_plan_count(const dacpo_tile_plan* plan);

/** \brief The halo width in use (the automatic one when 0 was asked). */
DACPO_API double
dacpo_tile_plan_halo(const dacpo_tile_plan* plan);

/** \brief Estimated own + halo points of a tile (from the sample), for
 *  dealing tiles to processes by cost. */
DACPO_API uint64_t
dacpo_tile_plan_estimate(const dacpo_tile_plan* plan, size_t tile);

/** \brief The tile that owns p (-1 for NULL or a non-finite p). When num_halo
 *  is not NULL, *num_halo is the number of other tiles whose halo holds p; the
 *  first max_halo of them are written to halo_tiles (ascending cell order). */
DACPO_API int32_t
dacpo_tile_locate(const dacpo_tile_plan* plan,
                  const float p[3],
                  int32_t* halo_tiles,
                  size_t max_halo,
                  size_t* num_halo);

/** \brief NULL-safe. */
DACPO_API void
dacpo_tile_plan_free(dacpo_tile_plan* plan);

/** \brief Evidence between tiles a and b: over points one of them owns and the
 *  other holds in its halo, the sum of |n_a . n_b| where the two normals agree
 *  (same) and where they disagree (opposite). */
typedef struct dacpo_tile_overlap {
  uint32_t a, b;
  double same, opposite;
} dacpo_tile_overlap;

/** \brief Which tiles to flip (flip[t] = 1: negate the normals tile t gave its
 *  own points). Entries for the same pair (either order) are summed; the
 *  relative signs follow the maximum spanning forest of |same - opposite|, and
 *  each connected group keeps the sign that most of its points (tile_points,
 *  NULL: one per tile) got from their own tile. Errors: INVALID_ARGUMENT. */
DACPO_API dacpo_status
dacpo_tile_join(size_t num_tiles,
                const dacpo_tile_overlap* overlaps,
                size_t num_overlaps,
                const uint64_t* tile_points,
                uint8_t* flip,
                char* msg,
                size_t msg_size);
/** @} */

DACPO_API void
dacpo_unit_bytes_free(void* bytes);

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
