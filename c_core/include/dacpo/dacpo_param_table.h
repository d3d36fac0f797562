/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_param_table.h
 * \brief The parameters of dacpo_params as one table (an X-macro): name, kind,
 *  default, who sets it, its command-line option and its contract.
 *  dacpo_params_init(), dacpo_params_set(), the tools' options, the Python
 *  package's keywords and default_params() and the README's parameter table
 *  (scripts/param_table.py) are generated from it, so a parameter is written
 *  once.
 *
 * DACPO_PARAM(kind, name, default, audience, cli, flag, doc) with
 *   kind      SIZE (size_t), REAL (double), FLAG (int 0/1), INT (int),
 *             ENUM (an enum, as int), U64 (uint64_t), UINT (unsigned)
 *   audience  USER (the dozen a user sets) or EXPERT (method switches kept for
 *             measurement and ablation)
 *   cli       VALUE: the tools take "flag value" for it, generated from this
 *             row; SPECIAL: the tools spell it their own way (flag names it);
 *             NONE: no command-line option
 *   flag      the command-line option ("" for NONE)
 *   doc       its contract in one sentence (the tools' -h, the README table)
 * Not in the table: viewpoint (three reals), filled by each binding itself.
 *
 * Use: #define DACPO_PARAM(kind, name, def, who, cli, flag, doc) ..., then
 * DACPO_PARAMS(), then
 * #undef DACPO_PARAM.
 */
#ifndef DACPO_PARAM_TABLE_H
#define DACPO_PARAM_TABLE_H

/* clang-format off */
#define DACPO_PARAMS() \
  DACPO_PARAM(SIZE, k, 10, USER, VALUE, "-k",\
              "k-NN graph for segmentation and propagation (clamped to n-1, reported)") \
  DACPO_PARAM(SIZE, normal_k, 16, USER, VALUE, "-normal_k",\
              "PCA neighbourhood when normals are estimated") \
  DACPO_PARAM(FLAG, estimate_normals, 0, USER, SPECIAL, "-estimate",\
              "estimate PCA normals instead of using the given axes") \
  DACPO_PARAM(SIZE, num_blocks, 0, USER, VALUE, "-blocks",\
              "blocks of stage 1; 0 = n/625 in [1, 400] (paper: 200)") \
  DACPO_PARAM(SIZE, ring_hops, 3, EXPERT, VALUE, "-ring",\
              "overlap ring width around each block, in k-NN hops") \
  DACPO_PARAM(REAL, dipole_c, -1.0, EXPERT, VALUE, "-c",\
              "c of Eq. 1, >= 1 (paper: 4 clean, 2 noisy); negative: by the scan kind (1 for one depth view or a scan of offset copies, 1.5 otherwise)") \
  DACPO_PARAM(SIZE, dipole_orders, 5, EXPERT, VALUE, "-orders",\
              "M randomized orders per run of stage 2") \
  DACPO_PARAM(SIZE, dipole_neighbors, 32, EXPERT, NONE, "",\
              "K placed neighbours summed per decision of stage 2") \
  DACPO_PARAM(INT, dipole_final_sweep, 10, EXPERT, NONE, "",\
              "re-decision sweeps after the vote (until no point changes)") \
  DACPO_PARAM(FLAG, ipsr_enabled, 1, EXPERT, SPECIAL, "-no_ipsr",\
              "stage 3 (iPSR) on or off") \
  DACPO_PARAM(SIZE, ipsr_max_iterations, 20, EXPERT, NONE, "",\
              "iPSR iteration cap") \
  DACPO_PARAM(ENUM, edge_weight, DACPO_WEIGHT_VCR, EXPERT, SPECIAL, "-weights",\
              "block edge weights: vcr (the paper's visible connected regions), dipole, overlap") \
  DACPO_PARAM(REAL, solver_time_limit, 30.0, USER, VALUE, "-time_limit",\
              "seconds for the 0-1 program; on time-out the best answer is kept and marked not optimal") \
  DACPO_PARAM(U64, seed, 1, USER, VALUE, "-seed",\
              "all randomness") \
  DACPO_PARAM(UINT, num_threads, 0, USER, VALUE, "-threads",\
              "threads; 0 = all cores") \
  DACPO_PARAM(ENUM, disconnected, DACPO_DISCONNECTED_VIEWPOINT, USER, SPECIAL, "-separate, -bridge",\
              "disconnected parts: viewpoint (each faces the viewpoint the scene implies), separate (relative sign undefined), bridge (joined along their Euclidean MST), error") \
  DACPO_PARAM(FLAG, keep_mesh, 0, USER, SPECIAL, "-mesh F",\
              "also build one crack-free scene mesh from the final normals") \
  DACPO_PARAM(SIZE, vcr_image_size, 128, EXPERT, VALUE, "-vcr_size",\
              "VCR image side in pixels (paper: 400)") \
  DACPO_PARAM(SIZE, vcr_views, 12, EXPERT, VALUE, "-vcr_views",\
              "VCR views around each block pair (12: dodecahedron face centres)") \
  DACPO_PARAM(FLAG, vcr_perspective, 0, EXPERT, SPECIAL, "-vcr_perspective",\
              "perspective instead of orthographic VCR projection") \
  DACPO_PARAM(FLAG, vcr_boundary_factor, 1, EXPERT, SPECIAL, "-vcr_c1c2",\
              "VCR score C_B C1 C2 (paper); 0 = C1 C2") \
  DACPO_PARAM(SIZE, dipole_restarts, 16, EXPERT, VALUE, "-restarts",\
              "runs of the M orders per block, voted point by point; they stop once the first four agree") \
  DACPO_PARAM(REAL, weak_edge_fraction, 1.0, EXPERT, VALUE, "-weak",\
              "block edges with less evidence than this fraction of the median edge leave the sign of the groups they join to the viewpoint vote; 0 = components only") \
  DACPO_PARAM(ENUM, sign_policy, DACPO_SIGN_FREE_SPACE, USER, SPECIAL, "-sign, -vp",\
              "global sign: free_space (normals face the space the scan was seen from; closed objects outward), viewpoint (face the given viewpoint), keep (the method's own sign)") \
  DACPO_PARAM(REAL, dipole_two_sheet, -1.0, EXPERT, VALUE, "-two_sheet",\
              "thin two-sided parts: parallel neighbours off each other's plane by more than this x local noise face opposite ways; 0 = off; negative: by the scan kind (0 for one view or copies, 3 otherwise)") \
  DACPO_PARAM(REAL, dipole_layers, -1.0, EXPERT, VALUE, "-layers",\
              "one-sided layers: parallel neighbours off each other's plane by more than this x local spacing use c = 1; 0 = off; negative: 0.5 for one view, 2 otherwise") \
  DACPO_PARAM(REAL, dipole_sides, 0.001, EXPERT, VALUE, "-sides",\
              "side cue for parts thinner than the spacing (two copies of one surface face away from each other) and the weight of its field; 0 = off; left out on one view and on scans of offset copies") \
  DACPO_PARAM(REAL, cue_anchor, 1.0, EXPERT, VALUE, "-cue_anchor",\
              "weight that ties a block where the side cue fired to the sign its cue gives it (stage 5 and after stage 6); 0 = off") \
  DACPO_PARAM(REAL, seam_dipole, 0.5, EXPERT, VALUE, "-seam_dipole",\
              "weight of the dipole energy across each block seam added to the VCR evidence; 0 = VCR alone") \
  DACPO_PARAM(SIZE, surface_vote, 500, EXPERT, VALUE, "-surface_vote",\
              "smallest smooth surface whose majority turns over the points against it (unless they are over a fifth); 0 = off") \
  DACPO_PARAM(REAL, dipole_c_thin, 4.0, EXPERT, VALUE, "-c_thin",\
              "c of Eq. 1 for two-sheet pairs in blocks with thin two-sided parts; 0 = off") \
  DACPO_PARAM(FLAG, adaptive_normals, 1, EXPERT, VALUE, "-adaptive_normals",\
              "estimated normals: per point the flattest of 3/4, 1 and 3/2 x normal_k neighbours; 0 = normal_k alone") \
  DACPO_PARAM(ENUM, scan_kind, DACPO_SCAN_AUTO, USER, SPECIAL, "-scan",\
              "what the cloud is: auto (decided from the sampling density; many views also checked for offset copies), single (one depth view), multi")
/* clang-format on */

#endif /* DACPO_PARAM_TABLE_H */
