/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo.h
 * \brief The public C API of the DACPO normal-orientation core.
 *
 * DACPO (TOG 2025, "A Divide-and-Conquer Approach for Global Orientation of
 * Non-Watertight Scene-Level Point Clouds Using 0-1 Integer Optimization") gives
 * a point cloud globally consistent normal orientation without a viewpoint:
 * the cloud is cut into spatially connected blocks, each block is oriented on its
 * own, and a 0-1 program over the block graph decides which blocks to flip.
 *
 * Data crosses this boundary as packed float arrays (3 per point). The core keeps
 * no caller pointer after a call returns, never prints, exits or aborts, and
 * reports every failure through a ::dacpo_status plus a message in the context.
 *
 * Threads: there is no global mutable state. A context is used by one thread at a
 * time; with num_threads > 1 a caller-supplied neighbour callback must be
 * reentrant. Progress callbacks arrive on the calling thread.
 */
#ifndef DACPO_DACPO_H
#define DACPO_DACPO_H

#include <stddef.h>
#include <stdint.h>

#include "dacpo_param_table.h"

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32)
#define DACPO_API __declspec(dllexport)
#elif defined(__GNUC__)
#define DACPO_API __attribute__((visibility("default")))
#else
#define DACPO_API
#endif

#define DACPO_VERSION_MAJOR 0
#define DACPO_VERSION_MINOR 1
#define DACPO_VERSION_PATCH 0

/** \brief "MAJOR.MINOR.PATCH" of the library actually linked. */
DACPO_API const char*
dacpo_version_string(void);

/** \brief Status codes. Stable: values are never changed or reused. */
typedef enum dacpo_status {
  DACPO_OK = 0,
  DACPO_ERR_INVALID_ARGUMENT = 1, /**< NULL pointer, bad parameter value */
  DACPO_ERR_EMPTY_INPUT = 2,      /**< count == 0 */
  DACPO_ERR_NONFINITE_INPUT = 3,  /**< NaN/inf coordinate or normal, zero normal */
  DACPO_ERR_TOO_FEW_POINTS = 4,   /**< fewer distinct points than the method needs */
  DACPO_ERR_DISCONNECTED = 5,     /**< k-NN graph disconnected and policy is ERROR */
  DACPO_ERR_NEIGHBOR_SEARCH = 6,  /**< the neighbour callback failed */
  DACPO_ERR_SOLVER = 7,           /**< the 0-1 program could not be solved */
  DACPO_ERR_OUT_OF_MEMORY = 8,
  DACPO_ERR_CANCELLED = 9, /**< the progress callback asked to stop */
  DACPO_ERR_INTERNAL = 10
} dacpo_status;

/** \brief Fixed English text for a status code (never NULL). */
DACPO_API const char*
dacpo_status_string(dacpo_status status);

/** \brief Pipeline stages, in the order they run (used for progress and timings). */
typedef enum dacpo_stage {
  DACPO_STAGE_INPUT = 0,        /**< validation, duplicate removal */
  DACPO_STAGE_NEIGHBORS = 1,    /**< k-NN graph, connected components */
  DACPO_STAGE_NORMALS = 2,      /**< PCA normals (when none were given) */
  DACPO_STAGE_SEGMENT = 3,      /**< stage 1: block segmentation, block graph */
  DACPO_STAGE_DIPOLE = 4,       /**< stage 2: dipole-field initialisation per block */
  DACPO_STAGE_IPSR = 5,         /**< stage 3: iPSR with Neumann Poisson per block */
  DACPO_STAGE_EDGE_WEIGHTS = 6, /**< stage 4: block-pair consistency weights */
  DACPO_STAGE_ILP = 7,          /**< stage 5: 0-1 program over the block graph */
  DACPO_STAGE_MESH = 8, /**< scene mesh from the final normals (keep_mesh only) */
  DACPO_STAGE_COUNT = 9
} dacpo_stage;

/** \brief Short name of a stage ("segment", "dipole", ...), never NULL. */
DACPO_API const char*
dacpo_stage_name(dacpo_stage stage);

/** \brief Which consistency measure weights the block-graph edges. */
typedef enum dacpo_edge_weight {
  /** Dipole field (paper Eq. 1) summed over k-NN pairs that cross the boundary. */
  DACPO_WEIGHT_DIPOLE_BOUNDARY = 0,
  /** Visible connected regions (paper Sec. 5.1) on the stage 3 block meshes. */
  DACPO_WEIGHT_VCR = 1,
  /** Agreement of the normals two blocks computed for their shared overlap
   *  ring (each block is oriented together with its neighbours' nearby points). */
  DACPO_WEIGHT_OVERLAP = 2
} dacpo_edge_weight;

/** \brief What to do when the k-NN graph has several connected components. */
typedef enum dacpo_disconnected_policy {
  /** Orient every component on its own; their relative sign is undefined
   *  (each component is left with the sign its first block got). */
  DACPO_DISCONNECTED_SEPARATE = 0,
  /** Fail with ::DACPO_ERR_DISCONNECTED. */
  DACPO_DISCONNECTED_ERROR = 1,
  /** Join the components by bridge edges along their Euclidean minimum spanning
   *  tree (closest point pairs, plus a few nearby pairs per bridge) and orient
   *  the whole cloud as one; the bridges are counted in dacpo_stats. */
  DACPO_DISCONNECTED_BRIDGE = 2,
  /** Orient every component on its own; then cut the cloud into parts (the
   *  components, split further where block-graph edges carry less than
   *  weak_edge_fraction of the typical evidence), find the viewpoint that the
   *  parts face best, each under its own sign, and give every part the sign
   *  under which most of its points face it. The vote margins enter the
   *  per-point confidence; when no viewpoint explains the scene (fewer than
   *  75 % of the points facing it) the parts keep the signs stage 5 gave them
   *  (components: undefined, as SEPARATE). */
  DACPO_DISCONNECTED_VIEWPOINT = 3
} dacpo_disconnected_policy;

/** \brief What kind of scan the cloud is; stage 2 reads thin parts and layers
 *  differently for each. */
typedef enum dacpo_scan_kind {
  /** Decide from the cloud: one depth view when a sensor position explains its
   *  sampling density (dacpo_stats::single_view_fit >= 0.5). */
  DACPO_SCAN_AUTO = 0,
  /** One depth view (an organized frame, a Kinect-class capture): every surface
   *  is seen from one side; layers a few spacings apart face the same way. */
  DACPO_SCAN_SINGLE_VIEW = 1,
  /** Seen from many places (a fused or registered scan, a sampled model, a room
   *  scanned from inside): thin parts show both faces, which look away from
   *  each other. */
  DACPO_SCAN_MULTI_VIEW = 2
} dacpo_scan_kind;

/** \brief Which of the two consistent orientations the run returns. */
typedef enum dacpo_sign_policy {
  /** Normals face the free space the scene was seen from: the viewpoint
   *  that most normals face and that sees most of the scene (normals face
   *  away from it when it lies inside a closed surface: objects come out
   *  with outward normals). No sensor position needed. In a single depth
   *  view whose sampling density places its sensor well (single_view_fit
   *  >= 0.7), every point the sensor sees within 60 degrees of its normal is
   *  turned to face it. */
  DACPO_SIGN_FREE_SPACE = 0,
  /** Most normals face dacpo_params::viewpoint (a sensor origin); one sign
   *  for the whole cloud, so consistency is kept. */
  DACPO_SIGN_VIEWPOINT = 1,
  /** Whatever sign stage 5 left (the paper's: arbitrary). */
  DACPO_SIGN_KEEP = 2
} dacpo_sign_policy;

/**
 * \brief Parameters. Always start from dacpo_params_init(); new fields are only
 * ever appended. One field per row of dacpo_param_table.h, whose rows give each
 * field's type, default and contract.
 */
typedef struct dacpo_params {
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc) type name;
  DACPO_PARAMS_BEFORE_VIEWPOINT()
  double viewpoint[3]; /**< DACPO_SIGN_VIEWPOINT: the point normals face, in the
                            input's frame (0, 0, 0) */
  DACPO_PARAMS_AFTER_VIEWPOINT()
#undef DACPO_PARAM
} dacpo_params;

/** \brief Fill \a params with the defaults documented above. NULL-safe. */
DACPO_API void
dacpo_params_init(dacpo_params* params);

/**
 * \brief Check every field. Returns DACPO_OK or DACPO_ERR_INVALID_ARGUMENT; on
 * error, if \a message is not NULL, writes a text naming the bad field.
 */
DACPO_API dacpo_status
dacpo_params_validate(const dacpo_params* params, char* message, size_t message_size);

/**
 * \brief Set the field called \a name (a dacpo_params field, e.g. "dipole_c")
 * from its text \a value: a number for numeric fields, 0 or 1 for flags, the
 * value's name in lower case for enums (edge_weight: dipole, vcr, overlap;
 * disconnected: separate, error, bridge, viewpoint; sign_policy: free_space,
 * viewpoint, keep; scan_kind: auto, single, multi). Every field of
 * dacpo_param_table.h can be set this way (viewpoint cannot). The value must
 * fit the field's type; its range is checked by dacpo_params_validate().
 * Returns DACPO_OK, or DACPO_ERR_INVALID_ARGUMENT (unknown name, value that
 * does not parse; \a params unchanged) with a text naming both in \a message.
 */
DACPO_API dacpo_status
dacpo_params_set(dacpo_params* params,
                 const char* name,
                 const char* value,
                 char* message,
                 size_t message_size);

/**
 * \brief Neighbour search supplied by the caller (e.g. a PCL KdTree).
 *
 * Must write up to \a k nearest neighbours of point \a query (an index into the
 * arrays given to dacpo_orient()) into \a indices (local indices, nearest first,
 * the query itself may be included) and their squared distances into
 * \a sq_distances, and the number written into \a found. Return 0 on success; a
 * non-zero return stops the run with ::DACPO_ERR_NEIGHBOR_SEARCH.
 */
typedef int (*dacpo_knn_fn)(void* user,
                            size_t query,
                            size_t k,
                            int32_t* indices,
                            float* sq_distances,
                            size_t* found);

/** \brief A neighbour-search callback and its user pointer. */
typedef struct dacpo_search {
  dacpo_knn_fn knn;
  void* user;
} dacpo_search;

/**
 * \brief Progress callback: called on the calling thread at stage boundaries and
 * inside long loops with \a fraction in [0, 1]. Return non-zero to cancel
 * (the run then returns ::DACPO_ERR_CANCELLED).
 */
typedef int (*dacpo_progress_fn)(void* user, dacpo_stage stage, double fraction);

/** \brief A progress callback and its user pointer. */
typedef struct dacpo_progress {
  dacpo_progress_fn fn;
  void* user;
} dacpo_progress;

/** \brief What the last run did. Valid until the next run or dacpo_ctx_free(). */
typedef struct dacpo_stats {
  size_t input_points;      /**< count given */
  size_t unique_points;     /**< after merging exact duplicates */
  size_t duplicate_points;  /**< input_points - unique_points */
  size_t k_used;            /**< k after clamping to unique_points - 1 */
  int k_clamped;            /**< 1 if k was clamped */
  size_t num_components;    /**< connected components of the k-NN graph */
  size_t largest_component; /**< points in the largest component */
  size_t num_blocks;
  size_t num_block_edges;
  size_t zero_weight_edges; /**< edges with alpha = alpha-bar = 0 (no information) */
  size_t flipped_blocks;    /**< blocks the 0-1 program flipped */
  int solver_optimal;      /**< 1 if every component's 0-1 program was proven optimal */
  double solver_objective; /**< sum of omega over edges at the chosen flips */
  size_t ilp_constraints;  /**< rows given to lp_solve (all components) */
  size_t ipsr_iterations_total; /**< summed over blocks */
  size_t ipsr_iterations_max;
  /** Wall time per stage. Stages 2 and 3 run in one parallel pass over the
   *  blocks; its wall time is split between them in proportion to their
   *  summed per-block times. */
  double stage_seconds[DACPO_STAGE_COUNT];
  double total_seconds;
  size_t peak_block_points;   /**< largest block incl. ring */
  size_t bridges_added;       /**< bridge edges added (DACPO_DISCONNECTED_BRIDGE) */
  double longest_bridge;      /**< length of the longest bridge edge */
  size_t num_parts;           /**< DACPO_DISCONNECTED_VIEWPOINT: parts whose sign the
                                   viewpoint vote set (components, split further at
                                   weak block edges); 0 if the vote did not run */
  double view_score;          /**< share of the points that face the inferred viewpoint
                                   under their part's sign (0 if unused) */
  size_t parts_related;       /**< parts other than the largest whose sign the vote
                                   set (confidence > 0) */
  int sign_flipped;           /**< 1 if the sign policy turned every normal over */
  double sign_facing;         /**< share of the points facing the viewpoint the sign
                                   policy used (away from it if enclosed), 0 if KEEP */
  int sign_enclosed;          /**< FREE_SPACE: 1 if that viewpoint lies inside a
                                   closed surface (normals point away from it) */
  double sign_viewpoint[3];   /**< the viewpoint the sign policy used */
  size_t cue_anchored_blocks; /**< blocks tied to the side cue's sign in stage 5
                                   (dacpo_params.cue_anchor) */
  size_t parts_cue_signed;    /**< parts (not the largest) whose sign the cue
                                   turned after the viewpoint vote and stage 6
                                   (only parts whose cue points are at least a
                                   quarter of their points) */
  size_t surface_vote_turned; /**< distinct points the surface vote turned over
                                   (dacpo_params.surface_vote) */
  size_t sensor_turned;       /**< FREE_SPACE, one depth view whose density places
                                   its sensor (single_view_fit >= 0.7): distinct
                                   points turned to face it (those it sees within
                                   60 degrees of their normal), after every other
                                   pass; 0 when most of those face away (the
                                   sensor's mirror image) or, with parts signed
                                   by their viewpoint, a fifth of them does */
  size_t cue_reconciled_blocks; /**< blocks turned after stage 6 where their side
                                     cue and the free space disagreed (groups of
                                     blocks against their cue whose anchors
                                     outweigh the edges joining them to the rest) */
  dacpo_scan_kind scan_kind;  /**< the kind the run used (never AUTO) */
  double single_view_fit;     /**< AUTO or SINGLE_VIEW: how well one sensor position
                                   explains the sampling density (correlation,
                                   -1..1; >= 0.5: single view; >= 0.7: the last
                                   sign pass uses its sensor); 0 when MULTI_VIEW
                                   was given */
  double dipole_c_used;       /**< dipole_c the run used (resolved when < 0) */
  double dipole_layers_used;  /**< dipole_layers the run used (resolved when < 0) */
  double dipole_two_sheet_used; /**< dipole_two_sheet the run used (resolved when < 0) */
  double layered_share;       /**< AUTO resolved to many views: share of the largest
                                   plane's sampled points where the side test finds
                                   a second face (>= 0.065: the surfaces come as
                                   offset copies, the side cue is left out); 0
                                   when the test did not run */
  double dipole_sides_used;   /**< dipole_sides the run used (0 when the layered
                                   test left the side cue out, or the scan
                                   resolved to one depth view) */
  double layered_copies;      /**< AUTO resolved to many views: on the same plane,
                                   the share of its surface points with a second
                                   parallel sheet within two spacings (>= 0.04:
                                   copies all over it, the two-sheet rule is left
                                   out too and c is 1); 0 when the test did not
                                   run */
  /** Where stages 2 and 3 spend their work, summed over blocks: stage-2
   *  restarts run (a block stops after the first four when they agree, else
   *  runs dipole_restarts) and the blocks that ran them all; stage-3 CG steps,
   *  faces queried and voted, and iterations that kept the last surface (the
   *  solve took no step). */
  size_t dipole_restarts_total;
  size_t dipole_blocks_all_restarts;
  size_t ipsr_cg_iterations_total;
  size_t ipsr_faces_total;
  size_t ipsr_surfaces_reused;
  double layered_doubled;     /**< AUTO resolved to many views: on the same plane,
                                   the share of its surface points with a second
                                   parallel sheet anywhere within two band widths
                                   (>= 0.2: copies wider apart than the pair
                                   window, handled as layered_copies >= 0.04);
                                   0 when the test did not run */
  double layered_crossing;    /**< AUTO resolved to many views: where the same
                                   plane holds two sheets that cross along a line
                                   (copies tilted against each other, which no
                                   thin solid's faces can be), the share of its
                                   two-sheet cells on the smaller side of that
                                   line, and the scan is handled as copies (as
                                   layered_copies >= 0.04); 0 when none cross or
                                   the test did not run */
  size_t copy_scale_axes;     /**< estimated axes taken at a larger scale because
                                   the floor shows copies (layered_copies or
                                   layered_doubled fired): points whose PCA axis
                                   turned by over 20 degrees at twice the
                                   neighbours and held at a larger scale */
  size_t frame_sensors;       /**< FREE_SPACE: windows (about 4096 points) of the
                                   frames found in the point order (registered
                                   depth frames concatenated, each row by row)
                                   whose own sampling density places a depth
                                   sensor and its side and falls with range along
                                   each surface; 0 for a cloud whose order shows
                                   no frame */
  size_t frame_turned;        /**< distinct points turned to face their frame's
                                   sensor, the last sign pass: its frame's
                                   window counts in frame_sensors and sees it
                                   within 60 degrees of its normal, facing away; or
                                   its block turned whole, where at least 5 %
                                   of its points say so and under a quarter
                                   as many say the opposite */
} dacpo_stats;

/** \brief Diagnostics of one block-graph edge. */
typedef struct dacpo_edge_info {
  int32_t block_a, block_b; /**< block_a < block_b */
  double alpha;             /**< consistency with both blocks as they are */
  double alpha_bar;         /**< consistency with one block flipped */
  double confidence; /**< |alpha - alpha_bar| / (alpha + alpha_bar + eps) in [0,1] */
} dacpo_edge_info;

/** \brief Opaque context: scratch, last error, stats and per-point results. */
typedef struct dacpo_ctx dacpo_ctx;

/** \brief Create a context. Returns DACPO_OK, INVALID_ARGUMENT or OUT_OF_MEMORY. */
DACPO_API dacpo_status
dacpo_ctx_create(dacpo_ctx** ctx);

/** \brief Free a context and everything it owns. NULL-safe. */
DACPO_API void
dacpo_ctx_free(dacpo_ctx* ctx);

/** \brief Message of the last failure ("point 1042 has a NaN coordinate"), or "". */
DACPO_API const char*
dacpo_ctx_last_error(const dacpo_ctx* ctx);

/** \brief Stats of the last run (zeroed before the first). NULL if ctx is NULL. */
DACPO_API const dacpo_stats*
dacpo_ctx_stats(const dacpo_ctx* ctx);

/**
 * \brief Per-point results of the last successful run, in input order, each an
 * array of dacpo_stats.input_points entries owned by the context, or NULL.
 * - component: connected component id; ids follow the order of each
 *   component's first input point, so the component of point 0 is 0.
 * - block: block id of the point.
 * - curvature: PCA surface variation lambda0/(l0+l1+l2) when normals were
 *   estimated, else NULL.
 * - confidence: how sure the run is of the point's sign, in [0, 1]: the
 *   product of (a) the share of stage-2 restarts that agree with it times the
 *   margin of its last dipole decision (halved where stage 3 turned it over),
 *   (b) how firmly the 0-1 program holds its block's flip, (c) the confidence
 *   in its component's sign (1 with one component). Low values mark weak or
 *   contradicted edges, blocks that disagree with themselves, restarts that
 *   disagree and parts that could not be related.
 */
DACPO_API const int32_t*
dacpo_ctx_point_components(const dacpo_ctx* ctx);
DACPO_API const int32_t*
dacpo_ctx_point_blocks(const dacpo_ctx* ctx);
DACPO_API const float*
dacpo_ctx_point_curvature(const dacpo_ctx* ctx);
DACPO_API const float*
dacpo_ctx_point_confidence(const dacpo_ctx* ctx);

/**
 * \brief Scene mesh of the last successful run with params.keep_mesh = 1: one
 * surface over all blocks, reconstructed after the signs are final (a screened
 * Poisson indicator per block, joined on one lattice, one marching cubes), so
 * it has no cracks along block seams and its face normals agree with the
 * output normals. Open at the scene's rims and holes; blocks of fewer than 32
 * points add no surface. Arrays are owned by the context.
 * \param[out] vertices     3 floats per vertex (may be NULL)
 * \param[out] num_vertices (may be NULL)
 * \param[out] triangles    3 vertex indices per triangle (may be NULL)
 * \return the number of triangles (0 without a mesh).
 */
DACPO_API size_t
dacpo_ctx_mesh(const dacpo_ctx* ctx,
               const float** vertices,
               size_t* num_vertices,
               const int32_t** triangles);

/** \brief Per-block flip decided by the 0-1 program (num_blocks entries), or NULL. */
DACPO_API const uint8_t*
dacpo_ctx_block_flips(const dacpo_ctx* ctx);

/** \brief Block-graph edges with their weights (num_block_edges entries), or NULL. */
DACPO_API const dacpo_edge_info*
dacpo_ctx_edges(const dacpo_ctx* ctx);

/**
 * \brief Orient normals.
 *
 * \param[in,out] ctx      context (results are stored there)
 * \param[in]     params   parameters, NULL = defaults
 * \param[in]     search   neighbour callback, NULL = built-in kd-tree
 * \param[in]     progress progress/cancel callback, NULL = none
 * \param[in]     xyz      3*count floats, finite
 * \param[in,out] normals  3*count floats. In: normal axes (sign ignored) unless
 *                         params->estimate_normals; out: oriented unit normals.
 *                         Left untouched on any error.
 * \param[in]     count    number of points
 * \return DACPO_OK, or a status; details in dacpo_ctx_last_error().
 */
DACPO_API dacpo_status
dacpo_orient(dacpo_ctx* ctx,
             const dacpo_params* params,
             const dacpo_search* search,
             const dacpo_progress* progress,
             const float* xyz,
             float* normals,
             size_t count);

#ifdef __cplusplus
}
#endif

#endif /* DACPO_DACPO_H */
