/* SPDX-License-Identifier: BSD-3-Clause */
/**
 * \file dacpo_param_table.h
 * \brief The parameters of dacpo_params as one table (an X-macro): kind, C
 *  type, name, default, who sets it, its command-line option and its
 *  contract. The struct dacpo_params itself (dacpo.h), dacpo_params_init(),
 *  dacpo_params_set(), the tools' options, the Python package's keywords and
 *  default_params() and the documents' parameter tables
 *  (scripts/param_table.py) are generated from it: adding a parameter is one
 *  row here (appended to DACPO_PARAMS_AFTER_VIEWPOINT, so the struct keeps its
 *  layout) plus the code that reads it.
 *
 * DACPO_PARAM(kind, type, name, default, min, max, audience, cli, flag, doc)
 * with
 *   kind      SIZE (size_t), REAL (double), FLAG (int 0/1), INT (int),
 *             ENUM (an enum, as int), U64 (uint64_t), UINT (unsigned): how
 *             the field is parsed and shown
 *   type      the field's C type
 *   min, max  the closed range dacpo_params_validate() accepts (DACPO_INF:
 *             no bound; a REAL must also be finite)
 *   audience  USER (the dozen a user sets) or EXPERT (method switches kept for
 *             measurement and ablation)
 *   cli       VALUE: the tools take "flag value" for it, generated from this
 *             row; SPECIAL: the tools spell it their own way (flag names it);
 *             NONE: no command-line option
 *   flag      the command-line option ("" for NONE)
 *   doc       its contract in one sentence (the tools' -h, the documents);
 *             a longer contract goes in a comment above the row
 * Not in the table: viewpoint (three reals, between the two halves of the
 * table in the struct), filled by each binding itself.
 *
 * Use: #define DACPO_PARAM(kind, type, name, def, min, max, who, cli, flag,
 * doc) ..., then DACPO_PARAMS(), then #undef DACPO_PARAM.
 */
#ifndef DACPO_PARAM_TABLE_H
#define DACPO_PARAM_TABLE_H

/* No bound, in the min and max columns. */
#define DACPO_INF 1e308

/* clang-format off */
#define DACPO_PARAMS_BEFORE_VIEWPOINT() \
  DACPO_PARAM(SIZE, size_t, k, 10, 2, 1000, USER, VALUE, "-k", \
              "k-NN graph for segmentation and propagation (clamped to n-1, reported)") \
  DACPO_PARAM(SIZE, size_t, normal_k, 16, 3, 1000, USER, VALUE, "-normal_k", \
              "PCA neighbourhood when normals are estimated") \
  DACPO_PARAM(FLAG, int, estimate_normals, 0, 0, 1, USER, SPECIAL, "-estimate", \
              "estimate PCA normals instead of using the given axes") \
  DACPO_PARAM(SIZE, size_t, num_blocks, 0, 0, 100000, USER, VALUE, "-blocks", \
              "blocks of stage 1; 0 = n/625 in [1, 400] (paper: 200)") \
  DACPO_PARAM(SIZE, size_t, ring_hops, 3, 0, 64, EXPERT, VALUE, "-ring", \
              "overlap ring width around each block, in k-NN hops") \
  /* c of paper Eq. 1 (-1: by the scan kind, 1 for a single depth view or a scan \
   * of offset copies, 1.5 otherwise; values >= 1). The paper uses 4 for clean \
   * and 2 for noisy scans. Larger c keeps the two sides of thin structures \
   * apart, smaller c resists depth noise; c = 1 leaves only the tangential \
   * alignment n.(I - r r^T).m, no "stacked, so opposite" vote - right where no \
   * part is seen from both sides. */ \
  DACPO_PARAM(REAL, double, dipole_c, -1.0, -DACPO_INF, DACPO_INF, EXPERT, VALUE, "-c", \
              "c of Eq. 1, >= 1 (paper: 4 clean, 2 noisy); negative: by the scan kind (1 for one depth view or a scan of offset copies, 1.5 otherwise)") \
  DACPO_PARAM(SIZE, size_t, dipole_orders, 5, 1, 16, EXPERT, VALUE, "-orders", \
              "M randomized orders per run of stage 2") \
  DACPO_PARAM(SIZE, size_t, dipole_neighbors, 32, 1, 1024, EXPERT, NONE, "", \
              "K placed neighbours summed per decision of stage 2") \
  DACPO_PARAM(INT, int, dipole_final_sweep, 10, 0, 1000, EXPERT, NONE, "", \
              "re-decision sweeps after the vote (until no point changes)") \
  DACPO_PARAM(FLAG, int, ipsr_enabled, 1, 0, 1, EXPERT, SPECIAL, "-no_ipsr", \
              "stage 3 (iPSR) on or off") \
  DACPO_PARAM(SIZE, size_t, ipsr_max_iterations, 20, 0, 1000, EXPERT, NONE, "", \
              "iPSR iteration cap") \
  DACPO_PARAM(ENUM, dacpo_edge_weight, edge_weight, DACPO_WEIGHT_VCR, 0, 2, EXPERT, SPECIAL, "-weights", \
              "block edge weights: vcr (the paper's visible connected regions), dipole, overlap") \
  DACPO_PARAM(REAL, double, solver_time_limit, 30.0, 1e-3, DACPO_INF, USER, VALUE, "-time_limit", \
              "seconds for the 0-1 program; on time-out the best answer is kept and marked not optimal") \
  DACPO_PARAM(U64, uint64_t, seed, 1, 0, DACPO_INF, USER, VALUE, "-seed", \
              "all randomness") \
  DACPO_PARAM(UINT, unsigned, num_threads, 0, 0, 1024, USER, VALUE, "-threads", \
              "threads; 0 = all cores") \
  DACPO_PARAM(ENUM, dacpo_disconnected_policy, disconnected, DACPO_DISCONNECTED_VIEWPOINT, 0, 3, USER, SPECIAL, "-separate, -bridge", \
              "disconnected parts: viewpoint (each faces the viewpoint the scene implies), separate (relative sign undefined), bridge (joined along their Euclidean MST), error") \
  DACPO_PARAM(FLAG, int, keep_mesh, 0, 0, 1, USER, SPECIAL, "-mesh F", \
              "also build one crack-free scene mesh from the final normals") \
  DACPO_PARAM(SIZE, size_t, vcr_image_size, 128, 16, 4096, EXPERT, VALUE, "-vcr_size", \
              "VCR image side in pixels (paper: 400)") \
  DACPO_PARAM(SIZE, size_t, vcr_views, 12, 1, 256, EXPERT, VALUE, "-vcr_views", \
              "VCR views around each block pair (12: dodecahedron face centres)") \
  /* independent runs of stage 2 per block (M orders each, voted point by point), \
   * 1..64 (16); they stop after 4 that all agree */ \
  DACPO_PARAM(SIZE, size_t, dipole_restarts, 16, 1, 64, EXPERT, VALUE, "-restarts", \
              "runs of the M orders per block, voted point by point; they stop once the first four agree") \
  /* VIEWPOINT policy: block-graph edges whose alpha + alpha-bar is below this \
   * fraction of the median edge's do not join blocks into one part; 0 = parts \
   * are the k-NN components (1: every edge below the median) */ \
  DACPO_PARAM(REAL, double, weak_edge_fraction, 1.0, 0, 1, EXPERT, VALUE, "-weak", \
              "block edges with less evidence than this fraction of the median edge leave the sign of the groups they join to the viewpoint vote; 0 = components only") \
  DACPO_PARAM(ENUM, dacpo_sign_policy, sign_policy, DACPO_SIGN_FREE_SPACE, 0, 2, USER, SPECIAL, "-sign, -vp", \
              "global sign: free_space (normals face the space the scan was seen from; closed objects outward), viewpoint (face the given viewpoint), keep (the method's own sign)")

#define DACPO_PARAMS_AFTER_VIEWPOINT() \
  /* stage 2, thin two-sided parts: a neighbour pair with near-parallel axes, \
   * each point lying off the other's tangent plane by more than this many times \
   * the local noise and 0.5 to 2 spacings, on one side of a point and all around \
   * beneath it, is the two faces of one thin part and must face opposite ways \
   * (Eq. 1 alone aligns them for c < 3). 0 = off, the paper's field; < 0 = by \
   * the scan kind: 0 for a single depth view (no part of one view shows two \
   * faces), 3 otherwise (-1) */ \
  DACPO_PARAM(REAL, double, dipole_two_sheet, -1.0, -DACPO_INF, DACPO_INF, EXPERT, VALUE, "-two_sheet", \
              "thin two-sided parts: parallel neighbours off each other's plane by more than this x local noise face opposite ways; 0 = off; negative: by the scan kind (0 for one view or copies, 3 otherwise)") \
  /* stage 2, layered surfaces seen from one side: neighbours with near-parallel \
   * axes lying off each other's tangent plane by more than this many local \
   * spacings are layers of one surface (depth quantisation, registration) and \
   * get Eq. 1 with c = 1 - the stacked term no longer says "opposite" - in a \
   * block where under 3 % of the points have a second sheet beneath them \
   * (dipole_two_sheet). < 0 = by the scan kind: 0.5 for a single view, 2 \
   * otherwise (-1); 0 = off */ \
  DACPO_PARAM(REAL, double, dipole_layers, -1.0, -DACPO_INF, DACPO_INF, EXPERT, VALUE, "-layers", \
              "one-sided layers: parallel neighbours off each other's plane by more than this x local spacing use c = 1; 0 = off; negative: 0.5 for one view, 2 otherwise") \
  /* stage 2, parts thinner than the spacing (a board 0.3-1 spacing thick): where \
   * a point's parallel neighbours lie on two copies of one smooth surface, one \
   * over the other, the pairs across them face opposite ways, the point's normal \
   * leans away from the other copy with this weight (against the sum of its pair \
   * energies), and stage 3 keeps the point's normal (its grid cannot resolve the \
   * part). Only in blocks where >= 5 % of the points show it. Any value > 0 \
   * turns the cue on; 0.001 (default) is pairs and stage 3 only (the field just \
   * breaks ties). Left out where the scan kind resolves to one depth view or the \
   * floor shows offset copies (dacpo_stats::layered_share, layered_copies). 0 = \
   * off (0.001) */ \
  DACPO_PARAM(REAL, double, dipole_sides, 0.001, 0, DACPO_INF, EXPERT, VALUE, "-sides", \
              "side cue for parts thinner than the spacing (two copies of one surface face away from each other) and the weight of its field; 0 = off; left out on one view and on scans of offset copies") \
  /* stage 5: the side cue (dipole_sides) is an absolute sign - the two faces of \
   * a thin part look away from each other - so a block where it fired on >= 20 \
   * of its points is tied to "as stage 3 left it" (or "flipped", where the cue \
   * disagrees) with this weight times the share of its cue points that agree, \
   * scaled like an edge of Eq. 7 (n / (n + 100) for n cue points). 0 = off (1) */ \
  DACPO_PARAM(REAL, double, cue_anchor, 1.0, 0, DACPO_INF, EXPERT, VALUE, "-cue_anchor", \
              "weight that ties a block where the side cue fired to the sign its cue gives it (stage 5 and after stage 6); 0 = off") \
  /* stage 2, blocks with thin two-sided parts (>= 3 % of the points have a \
   * second sheet beneath them, dipole_two_sheet > 0): a neighbour pair lying off \
   * each other's tangent plane by more than dipole_two_sheet x the local noise \
   * is geometry, not noise, and gets Eq. 1 with this c (the paper's clean-data \
   * value) instead of dipole_c. Blocks seen from one side keep dipole_c. 0 = off \
   * (4) */ \
  DACPO_PARAM(REAL, double, dipole_c_thin, 4.0, 0, DACPO_INF, EXPERT, VALUE, "-c_thin", \
              "c of Eq. 1 for two-sheet pairs in blocks with thin two-sided parts; 0 = off") \
  /* estimated normals: 1 = per point the neighbourhood among 3/4, 1 and 3/2 x \
   * normal_k that is flattest (lowest surface variation; another scale than \
   * normal_k only where its neighbours do not form a strip); the k-NN graph then \
   * keeps 3/2 x normal_k neighbours. 0 = normal_k alone (1) */ \
  DACPO_PARAM(FLAG, int, adaptive_normals, 1, 0, 1, EXPERT, VALUE, "-adaptive_normals", \
              "estimated normals: per point the flattest of 3/4, 1 and 3/2 x normal_k neighbours; 0 = normal_k alone") \
  /* single depth view or many views (AUTO: decided from the sampling density, \
   * see dacpo_stats::scan_kind). A single view gets c = 1, layers at 0.5 \
   * spacings, no two-sheet rule and no side cue where those are left at -1 / \
   * default; many views get c = 1.5, layers at 2 spacings and the thin-part \
   * rules, unless the floor shows offset copies (then c = 1 and no two-sheet \
   * rule or side cue) (AUTO) */ \
  DACPO_PARAM(ENUM, dacpo_scan_kind, scan_kind, DACPO_SCAN_AUTO, 0, 2, USER, SPECIAL, "-scan", \
              "what the cloud is: auto (decided from the sampling density; many views also checked for offset copies), single (one depth view), multi") \
  /* stage 4 with VCR weights: the dipole energy across each block seam (Eq. 2 \
   * over the k-NN pairs joining the two blocks) is added as a second measure, \
   * this x its evidence over its typical edge's, VCR over its own. 0 = VCR alone \
   * (0.5) */ \
  DACPO_PARAM(REAL, double, seam_dipole, 0.5, 0, DACPO_INF, EXPERT, VALUE, "-seam_dipole", \
              "weight of the dipole energy across each block seam added to the VCR evidence; 0 = VCR alone") \
  /* after the 0-1 program: on every smooth surface of at least this many points \
   * (neighbours with axes within 8 degrees of parallel, each in the other's \
   * tangent plane), points against the surface's majority are turned over, \
   * unless they are over a fifth of it (two faces of a thin part merged). Mends \
   * blocks a junction left half or wholly inside out. 0 = off (500) */ \
  DACPO_PARAM(SIZE, size_t, surface_vote, 500, 0, DACPO_INF, EXPERT, VALUE, "-surface_vote", \
              "smallest smooth surface whose majority turns over the points against it (unless they are over a fifth); 0 = off")

#define DACPO_PARAMS() DACPO_PARAMS_BEFORE_VIEWPOINT() DACPO_PARAMS_AFTER_VIEWPOINT()
/* clang-format on */

#endif /* DACPO_PARAM_TABLE_H */
