/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_param_table.h
 * \brief The parameters of dacpo_params as one table (an X-macro): name, kind,
 *  default and who sets it. dacpo_params_init() and the Python package's
 *  keywords and default_params() are generated from it, so a parameter's
 *  default is written once; the field's contract is its comment in dacpo.h.
 *
 * DACPO_PARAM(kind, name, default, audience) with
 *   kind      SIZE (size_t), REAL (double), FLAG (int 0/1), INT (int),
 *             ENUM (an enum, as int), U64 (uint64_t), UINT (unsigned)
 *   audience  USER (the dozen a user sets) or EXPERT (method switches kept for
 *             measurement and ablation)
 * Not in the table: viewpoint (three reals), filled by each binding itself.
 *
 * Use: #define DACPO_PARAM(kind, name, def, who) ..., then DACPO_PARAMS(), then
 * #undef DACPO_PARAM.
 */
#ifndef DACPO_PARAM_TABLE_H
#define DACPO_PARAM_TABLE_H

/* clang-format off */
#define DACPO_PARAMS()                                                          \
  DACPO_PARAM(SIZE, k, 10, USER)                                                \
  DACPO_PARAM(SIZE, normal_k, 16, USER)                                         \
  DACPO_PARAM(FLAG, estimate_normals, 0, USER)                                  \
  DACPO_PARAM(SIZE, num_blocks, 0, USER)                                        \
  DACPO_PARAM(SIZE, ring_hops, 3, EXPERT)                                       \
  DACPO_PARAM(REAL, dipole_c, -1.0, EXPERT)                                     \
  DACPO_PARAM(SIZE, dipole_orders, 5, EXPERT)                                   \
  DACPO_PARAM(SIZE, dipole_neighbors, 32, EXPERT)                               \
  DACPO_PARAM(INT, dipole_final_sweep, 10, EXPERT)                              \
  DACPO_PARAM(FLAG, ipsr_enabled, 1, EXPERT)                                    \
  DACPO_PARAM(SIZE, ipsr_max_iterations, 20, EXPERT)                            \
  DACPO_PARAM(ENUM, edge_weight, DACPO_WEIGHT_VCR, EXPERT)                      \
  DACPO_PARAM(REAL, solver_time_limit, 30.0, USER)                              \
  DACPO_PARAM(U64, seed, 1, USER)                                               \
  DACPO_PARAM(UINT, num_threads, 0, USER)                                       \
  DACPO_PARAM(ENUM, disconnected, DACPO_DISCONNECTED_VIEWPOINT, USER)           \
  DACPO_PARAM(FLAG, keep_mesh, 0, USER)                                         \
  DACPO_PARAM(SIZE, vcr_image_size, 200, EXPERT)                                \
  DACPO_PARAM(SIZE, vcr_views, 12, EXPERT)                                      \
  DACPO_PARAM(FLAG, vcr_perspective, 0, EXPERT)                                 \
  DACPO_PARAM(FLAG, vcr_boundary_factor, 1, EXPERT)                             \
  DACPO_PARAM(SIZE, dipole_restarts, 16, EXPERT)                                \
  DACPO_PARAM(INT, dipole_restart_vote, 1, EXPERT)                              \
  DACPO_PARAM(REAL, weak_edge_fraction, 1.0, EXPERT)                            \
  DACPO_PARAM(ENUM, sign_policy, DACPO_SIGN_FREE_SPACE, USER)                   \
  DACPO_PARAM(REAL, dipole_two_sheet, -1.0, EXPERT)                             \
  DACPO_PARAM(REAL, dipole_layers, -1.0, EXPERT)                                \
  DACPO_PARAM(REAL, dipole_sides, 0.001, EXPERT)                                \
  DACPO_PARAM(REAL, cue_anchor, 1.0, EXPERT)                                    \
  DACPO_PARAM(REAL, seam_dipole, 0.5, EXPERT)                                   \
  DACPO_PARAM(SIZE, surface_vote, 500, EXPERT)                                  \
  DACPO_PARAM(REAL, dipole_c_thin, 4.0, EXPERT)                                 \
  DACPO_PARAM(REAL, normal_weight, 0.0, EXPERT)                                 \
  DACPO_PARAM(FLAG, adaptive_normals, 1, EXPERT)                                \
  DACPO_PARAM(ENUM, scan_kind, DACPO_SCAN_AUTO, USER)
/* clang-format on */

#endif /* DACPO_PARAM_TABLE_H */
