/* SPDX-License-Identifier: BSD-3-Clause */
/* dacpo_orient(): runs the stages of the paper in order (Fig. 2):
 *   input (duplicates, checks) -> 0 k-NN graph, components, PCA normals
 *   -> 1 segmentation into blocks (§4.1) -> 2 dipole initialisation (§4.2)
 *   -> 3 iPSR with Neumann Poisson (§4.3) -> 4 block-pair weights (§5.1)
 *   -> 5 0-1 program over the block graph (§5.2) -> flips applied.
 * Stages 2-3 run per block and stage 4 per edge, in parallel. Only this file
 * touches the context; stages report through dacpo_err.
 * Failure modes: every stage's status is passed through unchanged; the caller's
 * normals are written only after everything succeeded. */
#include <dacpo/dacpo_advanced.h>

#include "dacpo_block_graph.h"
#include "dacpo_block_unit.h"
#include "dacpo_bridge.h"
#include "dacpo_context.h"
#include "dacpo_crease_axes.h"
#include "dacpo_dipole.h"
#include "dacpo_global_sign.h"
#include "dacpo_ilp.h"
#include "dacpo_input.h"
#include "dacpo_ipsr.h"
#include "dacpo_job_internal.h"
#include "dacpo_knn.h"
#include "dacpo_layered.h"
#include "dacpo_normals.h"
#include "dacpo_parallel.h"
#include "dacpo_part_sign.h"
#include "dacpo_scene_mesh.h"
#include "dacpo_segment.h"
#include "dacpo_sign_passes.h"
#include "dacpo_surface_vote.h"
#include "dacpo_vcr.h"
#include "dacpo_view_kind.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void
run_state_free(run_state* s)
{
  dacpo_cloud_free(&s->cloud);
  dacpo_knn_graph_free(&s->knn);
  dacpo_adjacency_free(&s->adj);
  free(s->component);
  free(s->input_component);
  free(s->curvature);
  if (s->meshes)
    for (size_t b = 0; b < s->blocks.num_blocks; ++b)
      dacpo_mesh_free(&s->meshes[b]);
  free(s->meshes);
  dacpo_mesh_free(&s->scene_mesh);
  dacpo_blocks_free(&s->blocks);
  dacpo_block_graph_free(&s->bgraph);
  free(s->oriented);
  free(s->point_conf);
  free(s->ring_oriented);
  free(s->ipsr);
  free(s->block_seconds);
  free(s->flips);
  free(s->cue_votes);
  free(s->restarts);
  free(s->block_conf);
  free(s->part);
  free(s->part_sign);
  free(s->part_conf);
  free(s->turned);
  free(s->block_done);
  free(s->edge_done);
}

/* Calls the progress callback; non-zero means the caller asked to stop. */
static dacpo_status
report(const run_state* s, dacpo_stage stage, double fraction, dacpo_err* err)
{
  if (s->progress && s->progress->fn &&
      s->progress->fn(s->progress->user, stage, fraction) != 0)
    return dacpo_err_set(err,
                         DACPO_ERR_CANCELLED,
                         "cancelled by the progress callback during %s",
                         dacpo_stage_name(stage));
  return DACPO_OK;
}

/* ---- stage 0 ----------------------------------------------------------- */

static dacpo_status
build_neighbors(run_state* s,
                dacpo_stats* st,
                const dacpo_search* search,
                dacpo_err* err)
{
  const size_t n = s->cloud.n;
  const size_t min_points = s->p.estimate_normals ? 3 : 2;
  DACPO_CHECK(err,
              n >= min_points,
              DACPO_ERR_TOO_FEW_POINTS,
              "%zu distinct point(s) among %zu given; at least %zu are needed%s",
              n,
              s->cloud.input_count,
              min_points,
              s->p.estimate_normals ? " to estimate normals" : "");
  st->k_used = s->p.k < n - 1 ? s->p.k : n - 1;
  st->k_clamped = st->k_used != s->p.k;
  size_t kmax = st->k_used;
  if (s->p.estimate_normals) {
    size_t nk = dacpo_normals_width(s->p.normal_k, s->p.adaptive_normals);
    if (nk > n - 1)
      nk = n - 1;
    if (nk > kmax)
      kmax = nk;
  }
  DACPO_TRY(dacpo_knn_build(
      &s->cloud, kmax, search, s->p.num_threads, s->progress, &s->knn, err));
  DACPO_TRY(dacpo_adjacency_build_threads(
      &s->knn, st->k_used, s->p.num_threads, &s->adj, err));
  s->component = dacpo_malloc_array(n, sizeof(int32_t));
  if (!s->component)
    return DACPO_OOM(err);
  DACPO_TRY(dacpo_components_label(&s->adj, s->component, &s->num_components, err));

  size_t* sizes = dacpo_calloc_array(s->num_components, sizeof(size_t));
  if (!sizes)
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i)
    sizes[s->component[i]]++;
  st->num_components = s->num_components;
  for (size_t c = 0; c < s->num_components; ++c)
    if (sizes[c] > st->largest_component) {
      st->largest_component = sizes[c];
      s->largest_component_id = (int32_t)c;
    }
  free(sizes);
  DACPO_CHECK(
      err,
      s->num_components == 1 || s->p.disconnected != DACPO_DISCONNECTED_ERROR,
      DACPO_ERR_DISCONNECTED,
      "the k-NN graph (k=%zu) has %zu connected components (largest: %zu of %zu "
      "points); their relative orientation is undefined",
      st->k_used,
      s->num_components,
      st->largest_component,
      n);
  s->input_component = dacpo_malloc_array(n, sizeof(int32_t));
  if (!s->input_component)
    return DACPO_OOM(err);
  memcpy(s->input_component, s->component, n * sizeof(int32_t));
  if (s->num_components > 1 && s->p.disconnected == DACPO_DISCONNECTED_BRIDGE) {
    /* Bridges change only the adjacency the later stages read (segmentation,
     * block graph, dipole weights); the k-NN lists and PCA normals are kept. */
    dacpo_adjacency bridged;
    DACPO_TRY(dacpo_bridge_components(&s->cloud,
                                      &s->adj,
                                      s->component,
                                      s->num_components,
                                      2,
                                      &bridged,
                                      &st->bridges_added,
                                      &st->longest_bridge,
                                      err));
    dacpo_adjacency_free(&s->adj);
    s->adj = bridged;
    s->num_components = 1;
  }
  return DACPO_OK;
}

static dacpo_status
estimate_normals(run_state* s, dacpo_err* err)
{
  const size_t n = s->cloud.n;
  size_t nk = s->p.normal_k < n - 1 ? s->p.normal_k : n - 1;
  s->curvature = dacpo_malloc_array(n, sizeof(float));
  if (!s->curvature)
    return DACPO_OOM(err);
  return dacpo_normals_pca_scaled(&s->cloud,
                                  &s->knn,
                                  nk,
                                  s->p.adaptive_normals,
                                  s->p.num_threads,
                                  s->cloud.nrm,
                                  s->curvature,
                                  err);
}

/* ---- stages 2-3: one block at a time ----------------------------------- */

/* Block b's points, own first, then its ring (the ring gives continuity to
 * propagation and Poisson but is not part of the output). */
void
dacpo_run_gather_block(const run_state* s, size_t b, double* xyz, double* axes)
{
  const dacpo_blocks* bl = &s->blocks;
  const size_t own0 = bl->own_start[b], no = bl->own_start[b + 1] - own0;
  const size_t ring0 = bl->ring_start[b], nr = bl->ring_start[b + 1] - ring0;
  for (size_t i = 0; i < no + nr; ++i) {
    int32_t q = i < no ? bl->own[own0 + i] : bl->ring[ring0 + (i - no)];
    memcpy(xyz + 3 * i, s->cloud.xyz + 3 * (size_t)q, 3 * sizeof(double));
    memcpy(axes + 3 * i, s->cloud.nrm + 3 * (size_t)q, 3 * sizeof(double));
  }
}

size_t
dacpo_run_block_own(const run_state* s, size_t b)
{
  return s->blocks.own_start[b + 1] - s->blocks.own_start[b];
}

size_t
dacpo_run_block_size(const run_state* s, size_t b)
{
  return dacpo_run_block_own(s, b) + s->blocks.ring_start[b + 1] -
         s->blocks.ring_start[b];
}

/* Block b's results into the run; its mesh moves into the run. */
void
dacpo_run_store_block(run_state* s, size_t b, dacpo_block_out* out)
{
  const dacpo_blocks* bl = &s->blocks;
  const size_t own0 = bl->own_start[b], no = dacpo_run_block_own(s, b);
  const size_t ring0 = bl->ring_start[b], nr = dacpo_run_block_size(s, b) - no;
  for (size_t i = 0; i < no; ++i) {
    const size_t q = (size_t)bl->own[own0 + i];
    memcpy(s->oriented + 3 * q, out->nrm + 3 * i, 3 * sizeof(double));
    s->point_conf[q] = out->conf[i];
  }
  if (s->ring_oriented)
    memcpy(s->ring_oriented + 3 * ring0, out->nrm + 3 * no, 3 * nr * sizeof(double));
  s->cue_votes[2 * b] = out->cue_votes[0];
  s->cue_votes[2 * b + 1] = out->cue_votes[1];
  s->restarts[b] = out->restarts;
  s->block_seconds[2 * b] = out->seconds[0];
  s->block_seconds[2 * b + 1] = out->seconds[1];
  s->ipsr[b] = out->ipsr;
  if (s->meshes) {
    s->meshes[b] = out->mesh;
    memset(&out->mesh, 0, sizeof(out->mesh));
  }
  s->block_done[b] = 1;
}

dacpo_status
dacpo_run_orient_block(void* user, size_t b, unsigned thread_id, dacpo_err* err)
{
  run_state* s = user;
  const size_t n = dacpo_run_block_size(s, b);
  double* xyz = dacpo_malloc_array(3 * n, sizeof(double));
  double* axes = dacpo_malloc_array(3 * n, sizeof(double));
  dacpo_block_out out;
  memset(&out, 0, sizeof(out));
  dacpo_status st = xyz && axes ? DACPO_OK : DACPO_OOM(err);
  if (st == DACPO_OK) {
    dacpo_run_gather_block(s, b, xyz, axes);
    st = dacpo_block_unit_run(&s->p,
                              b,
                              xyz,
                              axes,
                              n,
                              dacpo_run_block_own(s, b),
                              s->meshes != NULL,
                              &out,
                              err);
  }
  if (st == DACPO_OK)
    dacpo_run_store_block(s, b, &out);
  (void)thread_id;
  free(xyz);
  free(axes);
  dacpo_block_out_free(&out);
  return st;
}

/* ---- stage 4: VCR weights, one edge at a time -------------------------- */

dacpo_status
dacpo_run_weigh_edge_vcr(void* user, size_t e, unsigned thread_id, dacpo_err* err)
{
  run_state* s = user;
  dacpo_block_edge* edge = &s->bgraph.edges[e];
  dacpo_vcr_params vp;
  dacpo_block_unit_vcr_params(&s->p, &vp);
  (void)thread_id;
  DACPO_TRY(dacpo_vcr_edge(&s->meshes[edge->a],
                           &s->meshes[edge->b],
                           &vp,
                           &edge->alpha,
                           &edge->alpha_bar,
                           NULL,
                           err));
  s->edge_done[e] = 1;
  return DACPO_OK;
}

/* ---- scene mesh ---------------------------------------------------------- */

/* keep_mesh: one surface over all blocks from the normals as they will be
 * returned (block flips, part signs, the global sign and the surface vote
 * applied). */
static dacpo_status
build_scene_mesh(run_state* s, dacpo_err* err)
{
  const size_t n = s->cloud.n, nb = s->blocks.num_blocks;
  double* nrm = dacpo_malloc_array(3 * n, sizeof(double));
  double* spacing = dacpo_calloc_array(nb ? nb : 1, sizeof(double));
  dacpo_status status = DACPO_OK;
  if (!nrm || !spacing)
    status = DACPO_OOM(err);
  for (size_t i = 0; i < n && status == DACPO_OK; ++i) {
    const double sign = dacpo_sign_point(s, i);
    for (int d = 0; d < 3; ++d)
      nrm[3 * i + d] = sign * s->oriented[3 * i + d];
  }
  for (size_t b = 0; b < nb && status == DACPO_OK && s->ipsr; ++b)
    spacing[b] = s->ipsr[b].spacing;
  if (status == DACPO_OK) {
    dacpo_scene_mesh_input in = {s->cloud.xyz,
                                 nrm,
                                 n,
                                 &s->blocks,
                                 spacing,
                                 DACPO_MIN_IPSR_POINTS,
                                 (unsigned)s->p.num_threads,
                                 s->progress};
    status = dacpo_scene_mesh(&in, &s->scene_mesh, err);
  }
  free(nrm);
  free(spacing);
  return status;
}

/* ---- results ----------------------------------------------------------- */

/* The scene mesh in the context's float arrays. */
static dacpo_status
publish_mesh(dacpo_ctx* ctx, const run_state* s, dacpo_err* err)
{
  const dacpo_mesh* m = &s->scene_mesh;
  ctx->mesh_vertices = dacpo_malloc_array(3 * m->num_vertices + 1, sizeof(float));
  ctx->mesh_triangles = dacpo_malloc_array(3 * m->num_triangles + 1, sizeof(int32_t));
  if (!ctx->mesh_vertices || !ctx->mesh_triangles)
    return DACPO_OOM(err);
  for (size_t i = 0; i < 3 * m->num_vertices; ++i)
    ctx->mesh_vertices[i] = (float)m->vertices[i];
  if (m->num_triangles)
    memcpy(ctx->mesh_triangles, m->triangles, 3 * m->num_triangles * sizeof(int32_t));
  ctx->mesh_num_vertices = m->num_vertices;
  ctx->mesh_num_triangles = m->num_triangles;
  return DACPO_OK;
}

/* Confidence in the sign of point i's part relative to the largest one: 1 with
 * one component (or bridged into one), the viewpoint vote margin under the
 * VIEWPOINT policy, 0 for every component but the largest under SEPARATE. */
static double
part_confidence(const run_state* s, size_t i)
{
  if (s->part_conf)
    return s->part_conf[s->part[i]];
  if (s->num_components <= 1)
    return 1.0;
  return s->input_component[i] == s->largest_component_id ? 1.0 : 0.0;
}

static dacpo_status
publish(dacpo_ctx* ctx, run_state* s, float* normals, dacpo_err* err)
{
  const dacpo_cloud* c = &s->cloud;
  const size_t count = c->input_count;
  dacpo_stats* st = &ctx->stats;
  ctx->point_component = dacpo_malloc_array(count, sizeof(int32_t));
  ctx->point_block = dacpo_malloc_array(count, sizeof(int32_t));
  ctx->block_flips = dacpo_malloc_array(s->blocks.num_blocks, sizeof(uint8_t));
  ctx->edges = dacpo_malloc_array(s->bgraph.num_edges, sizeof(dacpo_edge_info));
  ctx->point_confidence = dacpo_malloc_array(count, sizeof(float));
  if (s->curvature)
    ctx->point_curvature = dacpo_malloc_array(count, sizeof(float));
  if (!ctx->point_component || !ctx->point_block || !ctx->point_confidence ||
      !ctx->block_flips || !ctx->edges || (s->curvature && !ctx->point_curvature))
    return DACPO_OOM(err);

  memcpy(ctx->block_flips, s->flips, s->blocks.num_blocks);
  for (size_t b = 0; b < s->blocks.num_blocks; ++b)
    st->flipped_blocks += s->flips[b] != 0;
  for (size_t e = 0; e < s->bgraph.num_edges; ++e) {
    const dacpo_block_edge* be = &s->bgraph.edges[e];
    dacpo_edge_info* info = &ctx->edges[e];
    info->block_a = be->a;
    info->block_b = be->b;
    info->alpha = be->alpha;
    info->alpha_bar = be->alpha_bar;
    info->confidence =
        fabs(be->alpha - be->alpha_bar) / (be->alpha + be->alpha_bar + 1e-12);
  }

  /* Everything that can fail comes before the caller's normals are written:
   * they are written only on success. */
  if (s->p.keep_mesh)
    DACPO_TRY(publish_mesh(ctx, s, err));

  /* The output keeps each input point's own axis (given or PCA) and only takes
   * its sign from the refined, flipped block normal: orientation is what DACPO
   * decides, the axis is the caller's. */
  for (size_t j = 0; j < count; ++j) {
    const size_t i = (size_t)c->input_to_point[j];
    const double* o = s->oriented + 3 * i;
    double axis[3];
    if (normals && !s->p.estimate_normals) {
      double len = sqrt((double)normals[3 * j] * normals[3 * j] +
                        (double)normals[3 * j + 1] * normals[3 * j + 1] +
                        (double)normals[3 * j + 2] * normals[3 * j + 2]);
      for (int d = 0; d < 3; ++d)
        axis[d] = normals[3 * j + d] / len;
    }
    else {
      memcpy(axis, c->nrm + 3 * i, sizeof(axis));
    }
    double dot = axis[0] * o[0] + axis[1] * o[1] + axis[2] * o[2];
    const double sign = (dot >= 0.0 ? 1.0 : -1.0) * dacpo_sign_point(s, i);
    for (int d = 0; d < 3; ++d)
      normals[3 * j + d] = (float)(sign * axis[d]);
    ctx->point_component[j] = s->input_component[i];
    ctx->point_block[j] = s->blocks.block_of[i];
    ctx->point_confidence[j] = s->point_conf[i] * s->block_conf[s->blocks.block_of[i]] *
                               (float)part_confidence(s, i);
    if (ctx->point_curvature)
      ctx->point_curvature[j] = s->curvature[i];
  }
  st->solver_optimal = s->ilp.optimal;
  st->solver_objective = s->ilp.objective;
  st->ilp_constraints = s->ilp.constraints;
  return DACPO_OK;
}

static size_t
auto_blocks(size_t n)
{
  /* about 625 points per block, at most 400 (the paper: 200). Small blocks
   * move decisions a block got wrong inside (a chair inside out on the floor
   * block it stands on) to the block graph; they need the seam dipole energy
   * beside VCR (seam_dipole), or a noisy board's narrow face, a block of its
   * own with a few pixels of VCR evidence, gets flipped. Seeds 1-5, against
   * 1,250 points (cap 200) with VCR alone: frames 1.60 -> 1.51 % (worst 1.78
   * -> 1.74), rooms 4.70 -> 4.39 % (worst 5.01 -> 4.99); see docs/DESIGN.md. */
  size_t b = n / 625;
  if (b < 1)
    b = 1;
  if (b > 400)
    b = 400;
  return b;
}
/* Stage 1: blocks bordered by creases, overlap rings and the block graph.
 * The crease axes need the neighbour rows (the first normal_k of them, or all
 * there are), which are trimmed right after. */
static dacpo_status
segment_blocks(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  size_t target = s->p.num_blocks ? s->p.num_blocks : auto_blocks(s->cloud.n);
  /* one block per component (target 1) leaves the growth nothing to decide:
   * no crease axes then */
  double* axes = NULL;
  dacpo_status status = DACPO_OK;
  if (target > 1) {
    axes = dacpo_malloc_array(3 * s->cloud.n, sizeof(double));
    if (axes == NULL)
      return DACPO_OOM(err);
    const size_t k = s->p.normal_k < s->knn.k ? s->p.normal_k : s->knn.k;
    status = dacpo_crease_axes(&s->cloud, &s->knn, k, s->p.num_threads, axes, err);
  }
  /* the neighbour rows are done with (the adjacency holds the graph); the
   * global sign reads only each row's reach */
  dacpo_knn_graph_keep_farthest(&s->knn);
  if (status == DACPO_OK)
    status = dacpo_segment_creased(&s->cloud,
                                   &s->adj,
                                   axes,
                                   s->component,
                                   s->num_components,
                                   target,
                                   s->p.ring_hops,
                                   &s->blocks,
                                   err);
  free(axes);
  DACPO_TRY(status);
  DACPO_TRY(dacpo_block_graph_build(&s->blocks, &s->adj, &s->bgraph, err));
  st->num_blocks = s->blocks.num_blocks;
  st->num_block_edges = s->bgraph.num_edges;
  for (size_t b = 0; b < s->blocks.num_blocks; ++b) {
    size_t nb = s->blocks.own_start[b + 1] - s->blocks.own_start[b] +
                s->blocks.ring_start[b + 1] - s->blocks.ring_start[b];
    if (nb > st->peak_block_points)
      st->peak_block_points = nb;
  }
  return DACPO_OK;
}

/* The per-point and per-block results stages 2 and 3 fill in, block by
 * block. */
static dacpo_status
alloc_block_results(run_state* s, dacpo_err* err)
{
  const size_t nb = s->blocks.num_blocks;
  s->oriented = dacpo_malloc_array(3 * s->cloud.n, sizeof(double));
  s->point_conf = dacpo_malloc_array(s->cloud.n, sizeof(float));
  s->ipsr = dacpo_calloc_array(nb, sizeof(dacpo_ipsr_stats));
  s->block_seconds = dacpo_calloc_array(2 * nb, sizeof(double));
  s->cue_votes = dacpo_calloc_array(2 * nb, sizeof(uint32_t));
  s->restarts = dacpo_calloc_array(nb, sizeof(uint32_t));
  const int want_meshes = s->p.edge_weight == DACPO_WEIGHT_VCR;
  if (want_meshes)
    s->meshes = dacpo_calloc_array(nb, sizeof(dacpo_mesh));
  const int want_ring = s->p.edge_weight == DACPO_WEIGHT_OVERLAP;
  if (want_ring)
    s->ring_oriented = dacpo_malloc_array(3 * s->blocks.ring_start[nb], sizeof(double));
  s->block_done = dacpo_calloc_array(nb + 1, 1);
  s->edge_done = dacpo_calloc_array(s->bgraph.num_edges + 1, 1);
  if (!s->oriented || !s->point_conf || !s->ipsr || !s->block_seconds ||
      !s->cue_votes || !s->restarts || (want_meshes && !s->meshes) ||
      (want_ring && !s->ring_oriented) || !s->block_done || !s->edge_done)
    return DACPO_OOM(err);
  return DACPO_OK;
}

/* Stages 2 and 3: one parallel pass over the blocks (independent per block). */
static dacpo_status
orient_blocks(run_state* s, dacpo_err* err)
{
  const size_t nb = s->blocks.num_blocks;
  DACPO_TRY(
      dacpo_parallel_for(nb,
                         s->p.num_threads,
                         dacpo_run_orient_block,
                         s,
                         s->progress,
                         s->p.ipsr_enabled ? DACPO_STAGE_IPSR : DACPO_STAGE_DIPOLE,
                         err));
  return DACPO_OK;
}

/* Stage 4: the block-graph edge weights of the chosen measure. */
static dacpo_status
weigh_edges(run_state* s, dacpo_err* err)
{
  /* by the measure asked for: a kept mesh (-mesh) must not switch it to VCR */
  if (s->p.edge_weight == DACPO_WEIGHT_VCR)
    DACPO_TRY(dacpo_parallel_for(s->bgraph.num_edges,
                                 s->p.num_threads,
                                 dacpo_run_weigh_edge_vcr,
                                 s,
                                 s->progress,
                                 DACPO_STAGE_EDGE_WEIGHTS,
                                 err));
  else if (s->p.edge_weight == DACPO_WEIGHT_OVERLAP)
    DACPO_TRY(dacpo_block_graph_overlap_weights(
        &s->bgraph, &s->blocks, s->oriented, s->ring_oriented, err));
  else
    DACPO_TRY(dacpo_block_graph_dipole_weights(
        &s->bgraph, &s->cloud, &s->adj, &s->blocks, s->oriented, s->p.dipole_c, err));
  memset(s->edge_done, 1, s->bgraph.num_edges);
  return DACPO_OK;
}

/* ---- the run as work units (dacpo_advanced.h) ---------------------------- */

/* Records the wall time of `stage` since the last one and asks the progress
 * callback whether to go on. */
static dacpo_status
stage_done(dacpo_job* job, dacpo_stage stage, dacpo_err* err)
{
  const double now = dacpo_now();
  job->ctx->stats.stage_seconds[stage] = now - job->t;
  job->t = now;
  return report(&job->s, stage, 1.0, err);
}

/* A failed step: the stats of the stages that ran stay, partial per-point
 * results go, the message goes to the context. */
static dacpo_status
job_fail(dacpo_ctx* ctx, dacpo_status status, dacpo_err* err)
{
  if (err->code != status || err->msg[0] == '\0')
    dacpo_err_set(err, status, "%s", dacpo_status_string(status));
  dacpo_stats keep = ctx->stats;
  dacpo_ctx_clear_results(ctx);
  ctx->stats = keep;
  return dacpo_ctx_fail(ctx, err);
}

/* Stage 0, a scan of many views (AUTO): whether its surfaces come as offset
 * copies (fused with a registration error, dacpo_layered.c). The thin-part
 * rules would read each pair of copies as a thin solid's two faces, so they
 * are left out; copies are layers of one surface seen from one side, so c = 1
 * as for a single view (Eq. 1's stacked vote reads them as opposite faces);
 * and estimated axes are taken at a larger scale where the copies make PCA's
 * noise (dacpo_normals_copy_scale). */
static dacpo_status
resolve_copies(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  DACPO_TRY(dacpo_layered_share(s->cloud.xyz,
                                s->cloud.nrm,
                                s->cloud.n,
                                s->knn.idx,
                                s->knn.sqd,
                                s->knn.k,
                                &st->layered_share,
                                &st->layered_copies,
                                &st->layered_doubled,
                                &st->layered_crossing,
                                err));
  const int copies = st->layered_crossing > 0.0 ||
                     st->layered_copies >= DACPO_LAYERED_COPIES ||
                     st->layered_doubled >= DACPO_LAYERED_DOUBLED;
  if (st->layered_share >= DACPO_LAYERED_SHARE || copies)
    s->p.dipole_sides = 0.0;
  if (!copies)
    return DACPO_OK;
  s->p.dipole_two_sheet = 0.0;
  if (s->p.dipole_c < 0.0)
    s->p.dipole_c = 1.0;
  if (!s->p.estimate_normals)
    return DACPO_OK;
  return dacpo_normals_copy_scale(&s->cloud,
                                  s->p.normal_k,
                                  s->p.num_threads,
                                  s->cloud.nrm,
                                  s->curvature,
                                  &st->copy_scale_axes,
                                  err);
}

/* Stage 0: the scan kind (dacpo_view_kind.c) and the stage-2 setting it
 * implies. Resolved here, once, so that every work unit (in this process or
 * another) reads the same resolved parameters. */
static dacpo_status
resolve_scan_kind(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  st->single_view_fit = 0.0;
  st->layered_share = 0.0;
  st->layered_copies = 0.0;
  st->layered_doubled = 0.0;
  st->layered_crossing = 0.0;
  st->copy_scale_axes = 0;
  /* the sensor's fit and position: for the kind (AUTO) and, in one view, for
   * the last sign pass, which turns the points it sees squarely to face it */
  if (s->p.scan_kind != DACPO_SCAN_MULTI_VIEW)
    DACPO_TRY(dacpo_single_view_sensor(s->cloud.xyz,
                                       s->cloud.nrm,
                                       s->cloud.n,
                                       s->knn.sqd,
                                       s->knn.k,
                                       &st->single_view_fit,
                                       NULL,
                                       s->sensor,
                                       err));
  if (s->p.scan_kind == DACPO_SCAN_AUTO) {
    s->p.scan_kind = st->single_view_fit >= DACPO_SINGLE_VIEW_FIT ? DACPO_SCAN_SINGLE_VIEW
                                                                 : DACPO_SCAN_MULTI_VIEW;
    /* many views: are they offset copies? (a kind given by the caller is
     * taken as it is) */
    if (s->p.scan_kind == DACPO_SCAN_MULTI_VIEW)
      DACPO_TRY(resolve_copies(s, st, err));
  }
  const int single = s->p.scan_kind == DACPO_SCAN_SINGLE_VIEW;
  s->sensor_known = single && st->single_view_fit >= DACPO_SENSOR_FIT &&
                    s->p.sign_policy == DACPO_SIGN_FREE_SPACE;
  if (s->p.dipole_layers < 0.0) /* layers 0.5 spacings apart are depth steps */
    s->p.dipole_layers = single ? 0.5 : 2.0;
  /* One view shows no part from both sides: c = 1 drops Eq. 1's stacked vote
   * ("opposite"), which there is only ever noise or layers. */
  if (s->p.dipole_c < 0.0)
    s->p.dipole_c = single ? 1.0 : 1.5;
  /* ... and the two-sheet rule and the side cue, whose pairs there are
   * layers, noise, or the offset copies of views fused into a cloud that
   * passes for one view. */
  if (s->p.dipole_two_sheet < 0.0)
    s->p.dipole_two_sheet = single ? 0.0 : 3.0;
  if (single)
    s->p.dipole_sides = 0.0;
  st->dipole_two_sheet_used = s->p.dipole_two_sheet;
  st->dipole_c_used = s->p.dipole_c;
  st->dipole_layers_used = s->p.dipole_layers;
  st->dipole_sides_used = s->p.dipole_sides;
  st->scan_kind = s->p.scan_kind;
  return DACPO_OK;
}

/* Input and stages 0-1. normals: the given axes (estimate_normals 0); with
 * out_buffer set they are also the buffer the run writes to, which must exist
 * even when the normals are estimated. */
static dacpo_status
job_prepare(dacpo_job* job,
            const dacpo_search* search,
            const float* xyz,
            const float* normals,
            int out_buffer,
            size_t count,
            dacpo_err* err)
{
  run_state* s = &job->s;
  dacpo_stats* st = &job->ctx->stats;
  DACPO_TRY(report(s, DACPO_STAGE_INPUT, 0.0, err));
  /* count == 0 first: empty std::vectors hand over NULL pointers */
  if (out_buffer)
    DACPO_CHECK(err,
                count == 0 || normals != NULL,
                DACPO_ERR_INVALID_ARGUMENT,
                "normals is NULL: it is the buffer that receives the oriented normals");
  else
    DACPO_CHECK(err,
                count == 0 || s->p.estimate_normals || normals != NULL,
                DACPO_ERR_INVALID_ARGUMENT,
                "normals is NULL but estimate_normals is 0: give the axes");
  const float* given = s->p.estimate_normals ? NULL : normals;
  DACPO_TRY(dacpo_input_check(xyz, given, count, err));
  DACPO_TRY(dacpo_cloud_build(xyz, given, count, &s->cloud, err));
  st->input_points = count;
  st->unique_points = s->cloud.n;
  st->duplicate_points = count - s->cloud.n;
  DACPO_TRY(stage_done(job, DACPO_STAGE_INPUT, err));
  DACPO_TRY(build_neighbors(s, st, search, err));
  DACPO_TRY(stage_done(job, DACPO_STAGE_NEIGHBORS, err));
  if (s->p.estimate_normals)
    DACPO_TRY(estimate_normals(s, err));
  DACPO_TRY(resolve_scan_kind(s, st, err));
  DACPO_TRY(stage_done(job, DACPO_STAGE_NORMALS, err));
  DACPO_TRY(segment_blocks(s, st, err));
  DACPO_TRY(alloc_block_results(s, err));
  return stage_done(job, DACPO_STAGE_SEGMENT, err);
}

static dacpo_status
job_start(dacpo_ctx* ctx,
          const dacpo_params* params,
          const dacpo_search* search,
          const dacpo_progress* progress,
          const float* xyz,
          const float* normals,
          int out_buffer,
          size_t count,
          dacpo_job** out)
{
  dacpo_ctx_clear_results(ctx);
  ctx->last_error[0] = '\0';
  dacpo_err err = {DACPO_OK, {0}};
  if (!out) {
    dacpo_err_set(&err, DACPO_ERR_INVALID_ARGUMENT, "job: out is NULL");
    return dacpo_ctx_fail(ctx, &err);
  }
  *out = NULL;
  dacpo_job* job = calloc(1, sizeof(*job));
  if (!job) {
    DACPO_OOM(&err);
    return dacpo_ctx_fail(ctx, &err);
  }
  job->ctx = ctx;
  if (params)
    job->s.p = *params;
  else
    dacpo_params_init(&job->s.p);
  job->s.progress = progress;
  char msg[256];
  dacpo_status status = dacpo_params_validate(&job->s.p, msg, sizeof(msg));
  if (status != DACPO_OK) {
    dacpo_err_set(&err, DACPO_ERR_INVALID_ARGUMENT, "%s", msg);
    free(job);
    return dacpo_ctx_fail(ctx, &err);
  }
  job->t0 = job->t = dacpo_now();
  status = job_prepare(job, search, xyz, normals, out_buffer, count, &err);
  if (status != DACPO_OK) {
    dacpo_job_free(job);
    return job_fail(ctx, status, &err);
  }
  *out = job;
  return DACPO_OK;
}

dacpo_status
dacpo_job_create(dacpo_ctx* ctx,
                 const dacpo_params* params,
                 const dacpo_search* search,
                 const dacpo_progress* progress,
                 const float* xyz,
                 const float* normals,
                 size_t count,
                 dacpo_job** out)
{
  if (!ctx)
    return DACPO_ERR_INVALID_ARGUMENT;
  return job_start(ctx, params, search, progress, xyz, normals, 0, count, out);
}

size_t
dacpo_job_num_blocks(const dacpo_job* job)
{
  return job ? job->s.blocks.num_blocks : 0;
}

size_t
dacpo_job_num_edges(const dacpo_job* job)
{
  return job ? job->s.bgraph.num_edges : 0;
}

dacpo_status
dacpo_job_edge_blocks(const dacpo_job* job, size_t e, size_t* a, size_t* b)
{
  if (!job || !a || !b || e >= job->s.bgraph.num_edges)
    return DACPO_ERR_INVALID_ARGUMENT;
  *a = (size_t)job->s.bgraph.edges[e].a;
  *b = (size_t)job->s.bgraph.edges[e].b;
  return DACPO_OK;
}

/* The first of the n flags that is 0, or n. */
static size_t
first_missing(const uint8_t* done, size_t n)
{
  size_t i = 0;
  while (i < n && done[i])
    ++i;
  return i;
}

/* Whether every block is oriented (and, with edges, every edge weighed);
 * names the first that is not. */
static dacpo_status
job_units_done(const run_state* s, int edges, const char* step, dacpo_err* err)
{
  const size_t b = first_missing(s->block_done, s->blocks.num_blocks);
  DACPO_CHECK(err,
              b == s->blocks.num_blocks,
              DACPO_ERR_INVALID_ARGUMENT,
              "job: %s before block %zu is oriented",
              step,
              b);
  const size_t e = edges ? first_missing(s->edge_done, s->bgraph.num_edges) : 0;
  DACPO_CHECK(err,
              !edges || e == s->bgraph.num_edges,
              DACPO_ERR_INVALID_ARGUMENT,
              "job: %s before edge %zu is weighed",
              step,
              e);
  return DACPO_OK;
}

dacpo_status
dacpo_job_weigh_edges(dacpo_job* job)
{
  if (!job)
    return DACPO_ERR_INVALID_ARGUMENT;
  dacpo_err err = {DACPO_OK, {0}};
  dacpo_status status = job_units_done(&job->s, 0, "weighing the edges", &err);
  if (status == DACPO_OK)
    status = weigh_edges(&job->s, &err);
  return status == DACPO_OK ? DACPO_OK : job_fail(job->ctx, status, &err);
}

/* Stages 5-6 and the parts. */
static dacpo_status
job_solve(dacpo_job* job, dacpo_err* err)
{
  run_state* s = &job->s;
  dacpo_stats* st = &job->ctx->stats;
  DACPO_TRY(job_units_done(s, 1, "the solve", err));
  DACPO_CHECK(
      err, !s->solved, DACPO_ERR_INVALID_ARGUMENT, "job: the flips are solved already");
  s->solved = 1;
  st->ipsr_iterations_total = st->ipsr_iterations_max = 0;
  st->dipole_restarts_total = st->dipole_blocks_all_restarts = 0;
  st->ipsr_cg_iterations_total = st->ipsr_faces_total = st->ipsr_surfaces_reused = 0;
  for (size_t b = 0; b < s->blocks.num_blocks; ++b) {
    st->ipsr_iterations_total += s->ipsr[b].iterations;
    if (s->ipsr[b].iterations > st->ipsr_iterations_max)
      st->ipsr_iterations_max = s->ipsr[b].iterations;
    st->ipsr_cg_iterations_total += s->ipsr[b].cg_iterations;
    st->ipsr_faces_total += s->ipsr[b].faces_total;
    st->ipsr_surfaces_reused += s->ipsr[b].surfaces_reused;
    st->dipole_restarts_total += s->restarts[b];
    st->dipole_blocks_all_restarts +=
        s->restarts[b] > 0 && s->restarts[b] >= s->p.dipole_restarts;
  }
  DACPO_TRY(dacpo_sign_passes(s, st, err));
  return stage_done(job, DACPO_STAGE_ILP, err);
}

dacpo_status
dacpo_job_solve(dacpo_job* job)
{
  if (!job)
    return DACPO_ERR_INVALID_ARGUMENT;
  job->t = dacpo_now();
  dacpo_err err = {DACPO_OK, {0}};
  dacpo_status status = job_solve(job, &err);
  return status == DACPO_OK ? DACPO_OK : job_fail(job->ctx, status, &err);
}

/* The scene mesh (keep_mesh) and the results. */
static dacpo_status
job_finish(dacpo_job* job, float* normals, dacpo_err* err)
{
  DACPO_CHECK(err,
              job->s.solved && !job->s.finished,
              DACPO_ERR_INVALID_ARGUMENT,
              "job: finish %s",
              job->s.finished ? "was called already" : "before the solve");
  job->s.finished = 1;
  if (job->s.p.keep_mesh) {
    DACPO_TRY(build_scene_mesh(&job->s, err));
    DACPO_TRY(stage_done(job, DACPO_STAGE_MESH, err));
  }
  DACPO_TRY(publish(job->ctx, &job->s, normals, err));
  job->ctx->stats.total_seconds = dacpo_now() - job->t0;
  return DACPO_OK;
}

dacpo_status
dacpo_job_finish(dacpo_job* job, float* normals)
{
  if (!job)
    return DACPO_ERR_INVALID_ARGUMENT;
  dacpo_err err = {DACPO_OK, {0}};
  DACPO_CHECK(&err,
              job->s.cloud.input_count == 0 || normals != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "normals is NULL: it is the buffer that receives the oriented normals");
  job->t = dacpo_now();
  dacpo_status status = job_finish(job, normals, &err);
  return status == DACPO_OK ? DACPO_OK : job_fail(job->ctx, status, &err);
}

void
dacpo_job_free(dacpo_job* job)
{
  if (!job)
    return;
  run_state_free(&job->s);
  free(job);
}

/* Stages 2-4 of a whole job: the blocks and then the edges in parallel, with
 * the wall time of the block pass split between stages 2 and 3 in proportion
 * to their summed per-block times. */
static dacpo_status
job_orient_and_weigh(dacpo_job* job, dacpo_err* err)
{
  run_state* s = &job->s;
  dacpo_stats* st = &job->ctx->stats;
  DACPO_TRY(orient_blocks(s, err));
  double now = dacpo_now(), sum2 = 0.0, sum3 = 0.0;
  for (size_t b = 0; b < s->blocks.num_blocks; ++b) {
    sum2 += s->block_seconds[2 * b];
    sum3 += s->block_seconds[2 * b + 1];
  }
  double share2 = sum2 + sum3 > 0.0 ? sum2 / (sum2 + sum3) : 1.0;
  st->stage_seconds[DACPO_STAGE_DIPOLE] = (now - job->t) * share2;
  st->stage_seconds[DACPO_STAGE_IPSR] = (now - job->t) * (1.0 - share2);
  job->t = now;
  DACPO_TRY(weigh_edges(s, err));
  return stage_done(job, DACPO_STAGE_EDGE_WEIGHTS, err);
}

dacpo_status
dacpo_orient(dacpo_ctx* ctx,
             const dacpo_params* params,
             const dacpo_search* search,
             const dacpo_progress* progress,
             const float* xyz,
             float* normals,
             size_t count)
{
  if (!ctx)
    return DACPO_ERR_INVALID_ARGUMENT;
  dacpo_job* job = NULL;
  DACPO_TRY(job_start(ctx, params, search, progress, xyz, normals, 1, count, &job));
  dacpo_err err = {DACPO_OK, {0}};
  dacpo_status status = job_orient_and_weigh(job, &err);
  if (status == DACPO_OK)
    status = job_solve(job, &err);
  if (status == DACPO_OK)
    status = job_finish(job, normals, &err);
  dacpo_job_free(job);
  return status == DACPO_OK ? DACPO_OK : job_fail(ctx, status, &err);
}
