/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stages 5-6 and the parts: every pass that decides a sign, in one place and
 * in one order (dacpo_sign_passes). The sign state they share lives in the
 * run (dacpo_job_internal.h): the block flips (s->flips), the part signs
 * (s->part_sign, when parts are related), the global sign (s->global_sign)
 * and the per-point turns of the surface vote (s->turned). Each pass says
 * below what it may change and why.
 *
 *   1 seam dipole      the block-graph weights (VCR blended with the seam's
 *                      dipole energy); no sign yet
 *   2 solve_flips      block flips: the 0-1 program (paper §5.2, Eq. 7-8),
 *                      block confidences, the cue's anchor edges
 *   3 relate_parts     part signs: parts = components (split at weak edges)
 *                      facing one viewpoint (DISCONNECTED_VIEWPOINT only)
 *   4 global sign      the one global sign: normals face the free space
 *   5 closed parts     part signs of closed parts: outward (overrides 3 for
 *                      those parts only: a closed part has an inside)
 *   6 parts follow cue part signs where the side cue is sure (overrides 3-5
 *                      for those parts only)
 *   7 cue vs space     block flips where the cue and the free space disagree
 *                      within a part (the only pass after 2 that flips blocks)
 *   8 surface vote     per-point turns: large smooth surfaces keep one
 *                      orientation
 *   9 sensor           per-point turns: in one depth view, every point its
 *                      sensor sees squarely faces it
 *  10 frame sensors    block and point turns: where the points come frame by frame,
 *                      every point its frame's sensor sees squarely faces it
 *                      (the last word)
 */
#include "dacpo_sign_passes.h"

#include <dacpo/dacpo_advanced.h>

#include "dacpo_block_graph.h"
#include "dacpo_context.h"
#include "dacpo_frame_sensors.h"
#include "dacpo_global_sign.h"
#include "dacpo_ilp.h"
#include "dacpo_job_internal.h"
#include "dacpo_part_sign.h"
#include "dacpo_surface_vote.h"
#include "dacpo_view_kind.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Stage 4, second measure: with VCR weights, the dipole energy across each
 * block seam (dacpo_block_graph_dipole_weights, Eq. 2 over the k-NN pairs that
 * join the two blocks) is added, each measure in units of its typical edge
 * (dacpo_block_graph_blend). The two fail on different edges: VCR needs a
 * depth-continuous contact in the rendered views, which a narrow face of a
 * noisy board (a strip one block wide) or a block joined by a few pairs lacks;
 * the seam energy needs pairs that are not stacked across a thin part. */
static dacpo_status
add_seam_dipole(run_state* s, dacpo_err* err)
{
  const size_t ne = s->bgraph.num_edges;
  if (s->p.edge_weight != DACPO_WEIGHT_VCR || !(s->p.seam_dipole > 0.0) || ne == 0)
    return DACPO_OK;
  dacpo_block_graph seam = {ne, dacpo_malloc_array(ne, sizeof(dacpo_block_edge))};
  if (!seam.edges)
    return DACPO_OOM(err);
  memcpy(seam.edges, s->bgraph.edges, ne * sizeof(dacpo_block_edge));
  dacpo_status st = dacpo_block_graph_dipole_weights(
      &seam, &s->cloud, &s->adj, &s->blocks, s->oriented, s->p.dipole_c, err);
  if (st == DACPO_OK)
    st = dacpo_block_graph_blend(&s->bgraph, &seam, s->p.seam_dipole, err);
  free(seam.edges);
  return st;
}

/* ---- stage 5 ----------------------------------------------------------- */

/* How firmly the 0-1 program's answer holds each block: flipping block b alone
 * would lose sum_e (w_kept - w_other) over its edges; divided by sum_e (w_kept +
 * w_other) this is 1 when every edge agrees with the answer, 0 when flipping b
 * costs nothing. A block without edges has nothing to decide: 1. */
static dacpo_status
block_confidence(run_state* s, const dacpo_ilp_edge* ie, size_t ne, dacpo_err* err)
{
  const size_t nb = s->blocks.num_blocks;
  double* lose = dacpo_calloc_array(nb, sizeof(double));
  double* total = dacpo_calloc_array(nb, sizeof(double));
  s->block_conf = dacpo_malloc_array(nb, sizeof(float));
  if (!lose || !total || !s->block_conf) {
    free(lose);
    free(total);
    return DACPO_OOM(err);
  }
  for (size_t e = 0; e < ne; ++e) {
    const int same = s->flips[ie[e].a] == s->flips[ie[e].b];
    const double kept = same ? ie[e].w_same : ie[e].w_diff;
    const double other = same ? ie[e].w_diff : ie[e].w_same;
    for (int side = 0; side < 2; ++side) {
      const size_t b = (size_t)(side ? ie[e].b : ie[e].a);
      if (b >= nb)
        continue; /* the cue's anchor node */
      lose[b] += kept - other;
      total[b] += kept + other;
    }
  }
  for (size_t b = 0; b < nb; ++b)
    s->block_conf[b] =
        total[b] > 0.0 ? (float)fmin(1.0, fmax(0.0, lose[b] / total[b])) : 1.0f;
  free(lose);
  free(total);
  return DACPO_OK;
}

#define DACPO_CUE_MIN_POINTS 20
#define DACPO_CUE_SCALE 100.0

/* What the cue says about block b: +1 "as stage 3 left it", -1 "flipped", 0
 * nothing (cue off, under DACPO_CUE_MIN_POINTS cue points, or a tie);
 * *points = its cue points. A block whose cue points are split (half wrong
 * inside, or a noisy cue) still says what most of them say: dropping blocks
 * whose cue points agreed less than 90 % cost a 100K room 9.24 -> 13.16 %. */
static int
cue_sign(const run_state* s, size_t b, double* points)
{
  const double agree = (double)s->cue_votes[2 * b];
  const double against = (double)s->cue_votes[2 * b + 1];
  *points = agree + against;
  if (!(s->p.cue_anchor > 0.0) || !(s->p.dipole_sides > 0.0) ||
      !(*points >= DACPO_CUE_MIN_POINTS) || agree == against)
    return 0;
  return agree > against ? 1 : -1;
}

/* Stage 5 anchor: the side cue is an absolute sign (the faces of a thin part
 * look away from each other; its points keep their stage-2 sign through
 * stage 3), so a block where it fired gets an edge to a virtual node that
 * stands for "not flipped": w_same / w_diff = weight x g x the share of cue
 * points that agree / disagree, g = m / (m + DACPO_CUE_SCALE) for m cue points
 * (Eq. 7's ratio, scaled like an edge's amount of evidence). Returns the
 * number of anchor edges written after the ne block edges. */
static size_t
cue_anchor_edges(const run_state* s, dacpo_ilp_edge* ie, size_t ne)
{
  const size_t nb = s->blocks.num_blocks;
  size_t m = 0;
  for (size_t b = 0; b < nb; ++b) {
    double cue = 0.0;
    if (!cue_sign(s, b, &cue))
      continue;
    const double agree = (double)s->cue_votes[2 * b];
    const double against = (double)s->cue_votes[2 * b + 1];
    const double g = s->p.cue_anchor * cue / (cue + DACPO_CUE_SCALE);
    ie[ne + m].a = (int32_t)b;
    ie[ne + m].b = (int32_t)nb;
    ie[ne + m].w_same = g * agree / cue;
    ie[ne + m].w_diff = g * against / cue;
    m++;
  }
  return m;
}

/* The block-graph edges as 0-1 program edges (Eq. 7 weights, scaled by their
 * evidence: dacpo_edge_omega) in ie[0, num_edges); returns how many carry no
 * evidence at all. */
static size_t
block_edges(const run_state* s, dacpo_ilp_edge* ie)
{
  size_t zero = 0;
  for (size_t e = 0; e < s->bgraph.num_edges; ++e) {
    const dacpo_block_edge* be = &s->bgraph.edges[e];
    ie[e].a = be->a;
    ie[e].b = be->b;
    dacpo_edge_omega(
        be->alpha, be->alpha_bar, s->evidence_scale, &ie[e].w_same, &ie[e].w_diff);
    zero += be->alpha == 0.0 && be->alpha_bar == 0.0;
  }
  return zero;
}

/* The 0-1 program fixes the lowest node of each component, so the anchor node
 * can end at 1: then every block joined to it is read the other way round. */
static dacpo_status
read_anchor(run_state* s, const dacpo_ilp_edge* ie, size_t ne, dacpo_err* err)
{
  const size_t nb = s->blocks.num_blocks;
  if (!s->flips[nb])
    return DACPO_OK;
  int32_t* root = dacpo_malloc_array(nb + 1, sizeof(int32_t));
  if (!root)
    return DACPO_OOM(err);
  for (size_t b = 0; b <= nb; ++b)
    root[b] = (int32_t)b;
  for (size_t e = 0; e < ne; ++e)
    dacpo_uf_union(root, ie[e].a, ie[e].b);
  const int32_t ra = dacpo_uf_find(root, (int32_t)nb);
  for (size_t b = 0; b <= nb; ++b)
    if (dacpo_uf_find(root, (int32_t)b) == ra)
      s->flips[b] = (uint8_t)!s->flips[b];
  free(root);
  return DACPO_OK;
}

static dacpo_status
solve_flips(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  const size_t ne = s->bgraph.num_edges, nb = s->blocks.num_blocks;
  dacpo_ilp_edge* ie = dacpo_malloc_array(ne + nb, sizeof(dacpo_ilp_edge));
  s->flips = dacpo_calloc_array(nb + 1, sizeof(uint8_t));
  if (!ie || !s->flips) {
    free(ie);
    return DACPO_OOM(err);
  }
  s->evidence_scale = dacpo_edge_evidence_scale(&s->bgraph);
  st->zero_weight_edges += block_edges(s, ie);
  const size_t na = cue_anchor_edges(s, ie, ne);
  st->cue_anchored_blocks = na;
  dacpo_status r = dacpo_ilp_solve(nb + (na > 0),
                                   ne + na,
                                   ie,
                                   s->p.solver_time_limit,
                                   s->progress,
                                   s->flips,
                                   &s->ilp,
                                   err);
  if (r == DACPO_OK && na > 0)
    r = read_anchor(s, ie, ne + na, err);
  if (r == DACPO_OK)
    r = block_confidence(s, ie, ne + na, err);
  free(ie);
  return r;
}

/* ---- relative sign of disconnected parts -------------------------------- */

/* Evidence of block edge be for the relation stage 5 gave its blocks, minus
 * the evidence against it. */
static double
stage5_evidence(const run_state* s, const dacpo_block_edge* be)
{
  return s->flips[be->a] == s->flips[be->b] ? be->alpha - be->alpha_bar
                                            : be->alpha_bar - be->alpha;
}

/* Two groups joined only by weak edges, but by enough of them that the net
 * evidence for the relation stage 5 gave them (per edge alpha if the blocks
 * kept their relative sign, alpha_bar if one turned, minus the other) reaches
 * what one edge needs to join them (weak x the typical evidence), are one
 * part: each seam is a few pixels of contact, together they are a contact.
 * Repeated until no two groups join (a join adds up the seams of the merged
 * groups). */
typedef struct group_pair {
  uint64_t key; /* smaller root << 32 | larger root */
  size_t edge;  /* ties in edge order: the sums do not depend on qsort */
  double net;   /* evidence for stage 5's relation, minus against it */
} group_pair;

static int
cmp_group_pair(const void* x, const void* y)
{
  const group_pair* a = x;
  const group_pair* b = y;
  if (a->key != b->key)
    return a->key < b->key ? -1 : 1;
  return (a->edge > b->edge) - (a->edge < b->edge);
}

static dacpo_status
merge_by_summed_evidence(run_state* s, double weak, int32_t* root, dacpo_err* err)
{
  const size_t ne = s->bgraph.num_edges;
  group_pair* gp = dacpo_malloc_array(ne ? ne : 1, sizeof(group_pair));
  if (!gp)
    return DACPO_OOM(err);
  for (int joined = 1; joined;) {
    joined = 0;
    size_t m = 0;
    for (size_t e = 0; e < ne; ++e) {
      const dacpo_block_edge* be = &s->bgraph.edges[e];
      const int32_t ra = dacpo_uf_find(root, be->a), rb = dacpo_uf_find(root, be->b);
      if (ra == rb)
        continue;
      const uint32_t lo = (uint32_t)(ra < rb ? ra : rb), hi = (uint32_t)(ra < rb ? rb : ra);
      gp[m].key = (uint64_t)lo << 32 | hi;
      gp[m].edge = e;
      gp[m++].net = stage5_evidence(s, be);
    }
    qsort(gp, m, sizeof(group_pair), cmp_group_pair);
    for (size_t i = 0; i < m;) {
      size_t j = i;
      double net = 0.0;
      for (; j < m && gp[j].key == gp[i].key; ++j)
        net += gp[j].net;
      if (net >= weak * s->evidence_scale) {
        dacpo_uf_union(root, (int32_t)(gp[i].key >> 32), (int32_t)(gp[i].key & 0xffffffffu));
        joined = 1;
      }
      i = j;
    }
  }
  free(gp);
  return DACPO_OK;
}

/* Parts whose sign the viewpoint vote decides: the blocks joined by block-graph
 * edges that carry at least `weak` times the typical evidence, or by weaker
 * ones whose net evidence adds up to as much (merge_by_summed_evidence; never
 * across components). With weak = 0 the parts are the k-NN components. */
static dacpo_status
label_parts(run_state* s, double weak, size_t* num_parts, dacpo_err* err)
{
  const size_t n = s->cloud.n, nb = s->blocks.num_blocks;
  s->part = dacpo_malloc_array(n, sizeof(int32_t));
  if (!s->part)
    return DACPO_OOM(err);
  if (!(weak > 0.0)) {
    memcpy(s->part, s->input_component, n * sizeof(int32_t));
    *num_parts = s->num_components;
    return DACPO_OK;
  }
  int32_t* root = dacpo_malloc_array(nb, sizeof(int32_t));
  int32_t* id = dacpo_malloc_array(nb, sizeof(int32_t));
  if (!root || !id) {
    free(root);
    free(id);
    return DACPO_OOM(err);
  }
  for (size_t b = 0; b < nb; ++b)
    root[b] = (int32_t)b;
  for (size_t e = 0; e < s->bgraph.num_edges; ++e) {
    const dacpo_block_edge* be = &s->bgraph.edges[e];
    if (!(be->alpha + be->alpha_bar >= weak * s->evidence_scale))
      continue;
    dacpo_uf_union(root, be->a, be->b);
  }
  const dacpo_status st = merge_by_summed_evidence(s, weak, root, err);
  if (st != DACPO_OK) {
    free(root);
    free(id);
    return st;
  }
  size_t m = 0;
  for (size_t b = 0; b < nb; ++b)
    id[b] = -1;
  for (size_t b = 0; b < nb; ++b) {
    const int32_t r = dacpo_uf_find(root, (int32_t)b);
    if (id[r] < 0)
      id[r] = (int32_t)m++;
    id[b] = id[r];
  }
  for (size_t i = 0; i < n; ++i)
    s->part[i] = id[s->blocks.block_of[i]];
  free(root);
  free(id);
  *num_parts = m;
  return DACPO_OK;
}

/* A part that weak edges join to others in its component keeps the relation
 * stage 5 gave it to the parts it touches unless its own viewpoint vote is
 * clear (margin >= DACPO_PART_MIN_MARGIN): weak evidence is still evidence, a
 * near tie of the vote is not. The component's largest part follows the vote
 * (it has no other relation to the rest of the scene). The undecided parts
 * are signed one at a time, the one whose seams to signed parts pull hardest
 * first: a neighbour that the vote turned takes the relation along (keeping
 * the relation to the largest part instead would break it at that seam). A
 * part with no seam to a signed part keeps stage 5's relation to the largest
 * part of its component. */
#define DACPO_PART_MIN_MARGIN 0.3

/* Signs the parts with decided[q] == 0 along their seams (see above) and
 * marks them 1 (decided[] != 0: signed); part_of[b]: the part of block b (-1:
 * a block without points). pull: np scratch. */
static void
sign_along_seams(
    run_state* s, size_t np, const int32_t* part_of, uint8_t* decided, double* pull)
{
  for (;;) {
    memset(pull, 0, np * sizeof(double));
    for (size_t e = 0; e < s->bgraph.num_edges; ++e) {
      const dacpo_block_edge* be = &s->bgraph.edges[e];
      const int32_t qa = part_of[be->a], qb = part_of[be->b];
      if (qa < 0 || qb < 0 || qa == qb || !decided[qa] == !decided[qb])
        continue;
      const int32_t q = decided[qa] ? qb : qa, r = decided[qa] ? qa : qb;
      pull[q] += stage5_evidence(s, be) * (double)s->part_sign[r];
    }
    size_t best = np;
    for (size_t q = 0; q < np; ++q)
      if (!decided[q] && pull[q] != 0.0 &&
          (best == np || fabs(pull[q]) > fabs(pull[best])))
        best = q;
    if (best == np)
      return;
    s->part_sign[best] = pull[best] > 0.0 ? 1 : -1;
    decided[best] = 1;
  }
}

static dacpo_status
keep_weak_evidence(run_state* s, size_t np, dacpo_err* err)
{
  const size_t n = s->cloud.n, nb = s->blocks.num_blocks;
  size_t* size = dacpo_calloc_array(np, sizeof(size_t));
  int32_t* comp = dacpo_malloc_array(np, sizeof(int32_t));
  int32_t* anchor = dacpo_malloc_array(s->num_components, sizeof(int32_t));
  int32_t* part_of = dacpo_malloc_array(nb ? nb : 1, sizeof(int32_t));
  uint8_t* decided = dacpo_calloc_array(np, sizeof(uint8_t));
  double* pull = dacpo_malloc_array(np, sizeof(double));
  dacpo_status r =
      size && comp && anchor && part_of && decided && pull ? DACPO_OK : DACPO_OOM(err);
  for (size_t b = 0; r == DACPO_OK && b < nb; ++b)
    part_of[b] = -1;
  for (size_t i = 0; r == DACPO_OK && i < n; ++i) {
    size[s->part[i]]++;
    comp[s->part[i]] = s->input_component[i];
    part_of[s->blocks.block_of[i]] = s->part[i];
  }
  for (size_t c = 0; r == DACPO_OK && c < s->num_components; ++c)
    anchor[c] = -1;
  for (size_t q = 0; r == DACPO_OK && q < np; ++q)
    if (size[q] > 0 && (anchor[comp[q]] < 0 || size[q] > size[anchor[comp[q]]]))
      anchor[comp[q]] = (int32_t)q;
  for (size_t q = 0; r == DACPO_OK && q < np; ++q) /* 2: the vote decides */
    decided[q] = size[q] == 0 || anchor[comp[q]] == (int32_t)q ||
                         s->part_conf[q] >= DACPO_PART_MIN_MARGIN
                     ? 2
                     : 0;
  if (r == DACPO_OK)
    sign_along_seams(s, np, part_of, decided, pull);
  for (size_t q = 0; r == DACPO_OK && q < np; ++q) {
    if (decided[q] == 2)
      continue;
    const int32_t a = anchor[comp[q]];
    if (!decided[q]) /* no seam to a signed part */
      s->part_sign[q] = s->part_sign[a];
    /* the block confidence speaks for its relation, the anchor's vote for the rest */
    s->part_conf[q] = s->part_conf[a];
  }
  free(size);
  free(comp);
  free(anchor);
  free(part_of);
  free(decided);
  free(pull);
  return r;
}

/* A part holding blocks the side cue anchored has an absolute sign (stage 5
 * made its blocks agree with the cue), which the viewpoint vote - a guess at
 * where the scan was seen from, relative to the largest part - does not
 * overrule: after stage 6, every other part takes the sign under which its
 * anchored blocks' cue points agree with it. The largest part keeps stage 6's
 * sign (free space decides the scene's sign). Measured on room3004 (σ 0.008,
 * seed 5): cue points right on 97 % of 2,258, yet two weakly joined blocks
 * holding 1,728 of them came out wrong when only stage 5 used the cue (the
 * vote and stage 6 related their part the other way): 9.51 -> 11.68 %.
 * Where the largest part's own cue points clearly disagree with the sign it
 * got (more than DACPO_CUE_REFERENCE_MARGIN of their weight net against:
 * a scene with no free space to tell, such as two sheets facing away, split
 * into one part per sheet by weak block edges), the others follow the cue
 * the way the largest part does, so the parts stay consistent with each
 * other (two sheets one spacing apart, blocks of 625 points: 49.7 -> 0 %) -
 * but only where those cue points are at least DACPO_CUE_MIN_SHARE of the
 * largest part: in a room its shell has free space to go by, and a few of its
 * blocks against their cue (a bookshelf against a wall: 3,347 of 89,481
 * points, 52 % net against) had turned a table and a partition in other
 * parts inside out (generated room, seed 12, run seed 1: 11.28 -> 5.00 %).
 * The same share bounds the parts that follow: a few cue points do not turn
 * a part the vote signed (where frames lie a few millimetres apart the cue
 * reads a wall's copies as faces; docs/DESIGN.md, "The other parts follow
 * the cue only where it covers a quarter of them too"). */
#define DACPO_CUE_REFERENCE_MARGIN 0.5
#define DACPO_CUE_MIN_SHARE 0.25

static dacpo_status
parts_follow_the_cue(run_state* s, size_t np, size_t* turned, dacpo_err* err)
{
  const size_t nb = s->blocks.num_blocks, n = s->cloud.n;
  double* vote = dacpo_calloc_array(np, sizeof(double));
  double* weight = dacpo_calloc_array(np, sizeof(double));
  size_t* size = dacpo_calloc_array(np, sizeof(size_t));
  if (!vote || !weight || !size) {
    free(vote);
    free(weight);
    free(size);
    return DACPO_OOM(err);
  }
  for (size_t b = 0; b < nb; ++b) {
    double points = 0.0;
    const int says = cue_sign(s, b, &points);
    if (!says || s->blocks.own_start[b + 1] == s->blocks.own_start[b])
      continue;
    const size_t q = (size_t)s->part[s->blocks.own[s->blocks.own_start[b]]];
    vote[q] += (double)says * (s->flips[b] ? -1.0 : 1.0) * points;
    weight[q] += points;
  }
  const size_t big = dacpo_part_largest(s->part, n, np, size);
  const double big_agrees = (double)s->part_sign[big] * s->global_sign * vote[big];
  const double reference =
      big_agrees < -DACPO_CUE_REFERENCE_MARGIN * weight[big] &&
              weight[big] >= DACPO_CUE_MIN_SHARE * (double)size[big]
          ? -1.0
          : 1.0;
  for (size_t q = 0; q < np; ++q)
    if (q != big && weight[q] >= DACPO_CUE_MIN_SHARE * (double)size[q] &&
        (double)s->part_sign[q] * s->global_sign * vote[q] * reference < 0.0) {
      s->part_sign[q] = (int8_t)-s->part_sign[q];
      ++*turned;
    }
  free(vote);
  free(weight);
  free(size);
  return DACPO_OK;
}

/* After stage 6 the side cue and the free space are two absolute signs, and
 * stage 5 saw only the first: where it related a cue-anchored group of blocks
 * to the rest of the scene the wrong way, it made the group agree with its
 * cue and the room's shell disagree, and stage 6 (free space, decided by the
 * shell) then turned the whole scene, the group with it. On a generated 60K
 * room (sigma 8 mm, seed 4) a table top's three blocks came out inside out so:
 * 923 cue points all against their final sign, tied to the floor under it by
 * one seam through a leg (4.39 % wrong instead of 7.05 %). Now the rest of the
 * scene holds its final sign, and each group of joined blocks whose cue points
 * mostly disagree with their sign turns over if that gains in the objective of
 * stage 5: its anchors against the edges that join it to the rest. Solving
 * the 0-1 program again with only the shell pinned also undid the relations
 * the parts' signs had set (a generated room, seed 3: 5.56 -> 5.90 %).
 * *turned gets the number of blocks turned. */
static dacpo_status
reconcile_cue_with_free_space(run_state* s, size_t* turned, dacpo_err* err)
{
  const size_t nb = s->blocks.num_blocks, ne = s->bgraph.num_edges;
  *turned = 0;
  if (nb == 0 || s->p.sign_policy != DACPO_SIGN_FREE_SPACE)
    return DACPO_OK;
  /* the sign every block has now (flip x part sign x global sign) and
   * whether its cue points mostly disagree with it */
  int8_t* now = dacpo_malloc_array(nb, sizeof(int8_t));
  int32_t* root = dacpo_malloc_array(nb, sizeof(int32_t));
  double* gain = dacpo_calloc_array(nb, sizeof(double));
  dacpo_ilp_edge* ie = dacpo_malloc_array(ne + nb, sizeof(dacpo_ilp_edge));
  dacpo_status r = now && root && gain && ie ? DACPO_OK : DACPO_OOM(err);
  size_t against = 0;
  for (size_t b = 0; r == DACPO_OK && b < nb; ++b) {
    double f = (s->flips[b] ? -1.0 : 1.0) * s->global_sign;
    if (s->part_sign && s->blocks.own_start[b + 1] > s->blocks.own_start[b])
      f *= (double)s->part_sign[s->part[s->blocks.own[s->blocks.own_start[b]]]];
    now[b] = f > 0.0 ? 1 : -1;
    double points = 0.0;
    root[b] = cue_sign(s, b, &points) * now[b] < 0 ? (int32_t)b : -1;
    against += root[b] >= 0;
  }
  if (r == DACPO_OK && against > 0) {
    block_edges(s, ie);
    const size_t na = cue_anchor_edges(s, ie, ne);
    /* groups: blocks against their cue joined by block edges */
    for (size_t e = 0; e < ne; ++e)
      if (root[ie[e].a] >= 0 && root[ie[e].b] >= 0)
        dacpo_uf_union(root, ie[e].a, ie[e].b);
    /* what turning its group over gains, summed at the group's root: the
     * anchor (w_same rewards the sign stage 3 left) and every edge with one
     * end outside the group (its relation changes; inner ones keep theirs;
     * an edge between two groups counts for each as if the other stayed) */
    for (size_t t = ne; t < ne + na; ++t) {
      const size_t b = (size_t)ie[t].a;
      if (root[b] >= 0)
        gain[dacpo_uf_find(root, (int32_t)b)] +=
            now[b] > 0 ? ie[t].w_diff - ie[t].w_same : ie[t].w_same - ie[t].w_diff;
    }
    for (size_t e = 0; e < ne; ++e) {
      const int32_t a = ie[e].a, b = ie[e].b;
      const int32_t ra = root[a] >= 0 ? dacpo_uf_find(root, a) : -1;
      const int32_t rb = root[b] >= 0 ? dacpo_uf_find(root, b) : -1;
      if (ra == rb)
        continue;
      const double kept = now[a] == now[b] ? ie[e].w_same : ie[e].w_diff;
      const double other = now[a] == now[b] ? ie[e].w_diff : ie[e].w_same;
      if (ra >= 0)
        gain[ra] += other - kept;
      if (rb >= 0)
        gain[rb] += other - kept;
    }
    for (size_t b = 0; b < nb; ++b)
      if (root[b] >= 0 && gain[dacpo_uf_find(root, (int32_t)b)] > 0.0) {
        s->flips[b] = (uint8_t)!s->flips[b];
        ++*turned;
      }
  }
  free(now);
  free(root);
  free(gain);
  free(ie);
  return r;
}

/* The normals as they stand after stage 5 (block flips) and, once decided,
 * the part signs: 3n doubles the caller frees, NULL if out of memory. */
static double*
current_normals(const run_state* s)
{
  const size_t n = s->cloud.n;
  double* out = dacpo_malloc_array(3 * n, sizeof(double));
  if (!out)
    return NULL;
  for (size_t i = 0; i < n; ++i) {
    double f = s->flips[s->blocks.block_of[i]] ? -1.0 : 1.0;
    if (s->part_sign)
      f *= (double)s->part_sign[s->part[i]];
    for (int d = 0; d < 3; ++d)
      out[3 * i + d] = f * s->oriented[3 * i + d];
  }
  return out;
}

/* Stage 5 decides the relative sign of blocks joined by edges with evidence;
 * where the only evidence between two groups of blocks is weak (or there is
 * none: separate components), each group takes the sign under which it faces
 * the viewpoint the whole scene implies. */
static dacpo_status
relate_parts(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  const size_t n = s->cloud.n;
  size_t np = 0;
  DACPO_TRY(label_parts(s, s->p.weak_edge_fraction, &np, err));
  st->num_parts = np;
  double* final = current_normals(s); /* before s->part_sign exists */
  s->part_sign = dacpo_malloc_array(np, sizeof(int8_t));
  s->part_conf = dacpo_malloc_array(np, sizeof(double));
  if (!s->part_sign || !s->part_conf || !final) {
    free(final);
    return DACPO_OOM(err);
  }
  dacpo_status r = dacpo_part_signs(s->cloud.xyz,
                                    final,
                                    n,
                                    s->part,
                                    np,
                                    s->part_sign,
                                    s->part_conf,
                                    &st->view_score,
                                    err);
  free(final);
  if (r == DACPO_OK && np > s->num_components)
    r = keep_weak_evidence(s, np, err);
  /* the largest part has confidence 1 by definition; count the others */
  size_t related = 0;
  for (size_t c = 0; c < np; ++c)
    related += s->part_conf[c] > 0.0;
  st->parts_related = related > 0 ? related - 1 : 0;
  return r;
}

/* A part that wraps around its own centroid is a closed object seen from all
 * round, which the viewpoint vote cannot place (half its points face any
 * viewpoint), and so is a flat part with two faces (a free-standing board, a
 * partition): after stage 6 it takes the sign under which it faces outward
 * (dacpo_part_closed_outward). The largest part too: it is the reference the
 * vote relates the others to, and a partition seen from both sides can be the
 * largest part of a scan, its sign then only as right as the vote's guess.
 * The side cue, where it speaks, still has the last word
 * (parts_follow_the_cue runs after). */
static dacpo_status
closed_parts_outward(run_state* s, size_t np, dacpo_err* err)
{
  const size_t n = s->cloud.n;
  double* now = current_normals(s);
  int8_t* outward = dacpo_malloc_array(np, sizeof(int8_t));
  dacpo_status r = now && outward ? DACPO_OK : DACPO_OOM(err);
  for (size_t i = 0; r == DACPO_OK && i < 3 * n; ++i)
    now[i] *= s->global_sign;
  if (r == DACPO_OK)
    r = dacpo_part_closed_outward(s->cloud.xyz, now, n, s->part, np, outward, err);
  for (size_t q = 0; r == DACPO_OK && q < np; ++q)
    if (outward[q] < 0)
      s->part_sign[q] = (int8_t)-s->part_sign[q];
  free(now);
  free(outward);
  return r;
}

/* ---- stage 6: global sign ----------------------------------------------- */

static dacpo_status
choose_global_sign(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  s->global_sign = 1.0;
  if (s->p.sign_policy == DACPO_SIGN_KEEP)
    return DACPO_OK;
  double* now = current_normals(s);
  if (!now)
    return DACPO_OOM(err);
  dacpo_global_sign_result g;
  const dacpo_status r = dacpo_global_sign(
      s->cloud.xyz,
      now,
      s->cloud.n,
      s->p.sign_policy == DACPO_SIGN_VIEWPOINT ? s->p.viewpoint : NULL,
      s->knn.sqd,
      s->knn.k,
      &g,
      err);
  free(now);
  if (r != DACPO_OK)
    return r;
  s->global_sign = g.flip ? -1.0 : 1.0;
  st->sign_flipped = g.flip;
  st->sign_facing = g.facing;
  st->sign_enclosed = g.enclosed;
  memcpy(st->sign_viewpoint, g.viewpoint, sizeof(st->sign_viewpoint));
  return DACPO_OK;
}

/* The sign the run gives stage 3's normal of distinct point i: its block's
 * flip, the global sign, its part's sign and the surface vote. */
double
dacpo_sign_point(const run_state* s, size_t i)
{
  double sign = (s->flips[s->blocks.block_of[i]] ? -1.0 : 1.0) * s->global_sign;
  if (s->part_sign)
    sign *= (double)s->part_sign[s->part[i]];
  if (s->turned && s->turned[i])
    sign = -sign;
  return sign;
}

/* After stages 5-6: large smooth surfaces keep one orientation
 * (dacpo_surface_vote.c; surface_vote = the smallest surface that votes, 0 =
 * off). s->turned marks the points it turned over against their block's,
 * part's and the global sign. */
static dacpo_status
surface_vote(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  const dacpo_cloud* c = &s->cloud;
  st->surface_vote_turned = 0;
  if (s->p.surface_vote == 0 || c->n == 0)
    return DACPO_OK;
  int8_t* sign = dacpo_malloc_array(c->n, sizeof(int8_t));
  int8_t* before = dacpo_malloc_array(c->n, sizeof(int8_t));
  s->turned = dacpo_calloc_array(c->n, sizeof(uint8_t));
  dacpo_status r = sign && before && s->turned ? DACPO_OK : DACPO_OOM(err);
  /* the sign of each point relative to its axis (c->nrm) */
  for (size_t i = 0; i < c->n && r == DACPO_OK; ++i) {
    const double* o = s->oriented + 3 * i;
    const double* a = c->nrm + 3 * i;
    const double dot = a[0] * o[0] + a[1] * o[1] + a[2] * o[2];
    sign[i] = before[i] = (dot >= 0.0 ? 1.0 : -1.0) * dacpo_sign_point(s, i) > 0.0 ? 1 : -1;
  }
  if (r == DACPO_OK)
    r = dacpo_surface_vote(c->xyz,
                           c->nrm,
                           &s->adj,
                           DACPO_SURFACE_VOTE_ANGLE,
                           s->p.surface_vote,
                           sign,
                           &st->surface_vote_turned,
                           NULL,
                           err);
  for (size_t i = 0; i < c->n && r == DACPO_OK; ++i)
    s->turned[i] = (uint8_t)(sign[i] != before[i]);
  free(sign);
  free(before);
  return r;
}

/* One depth view: its sensor saw every point from the side the point's
 * normal must face, so where stage 0 found the sensor (a depth frame whose
 * density fits it by DACPO_SENSOR_FIT, dacpo_view_kind.c) a point it sees
 * squarely takes that side, whatever stages 2-6 gave it. Stage 2 relates
 * neighbours, and where a frame is noisy or far its blocks can come out
 * partly reversed, square to the sensor as often as not. "Squarely":
 * incidence under 60 degrees (DACPO_SENSOR_SQUARE_COS); nearer grazing the
 * estimated axis and the estimated sensor decide less surely (docs/DESIGN.md,
 * "One view faces its sensor"). The density does not say on which side of the
 * surfaces the sensor stands: when most squarely seen points face away from
 * the position found, it is the mirror image and nothing turns. Where the
 * parts were signed by the viewpoint they imply (DISCONNECTED_VIEWPOINT) the
 * pass mends stragglers, and when those facing away reach
 * DACPO_SENSOR_MAX_AWAY of those facing, that viewpoint and the sensor
 * disagree about where the scan was seen from: a scan of a few frames whose
 * density fits one of them, the position found that frame's mirror image
 * (docs/DESIGN.md, "A few frames that pass for one"); nothing turns then
 * either. Under the other policies (SEPARATE, BRIDGE) no vote signed the
 * parts, and a reversed part is what the pass is there to mend.
 * (DACPO_SENSOR_SQUARE_COS, DACPO_SENSOR_MAX_AWAY: dacpo_view_kind.h.) */

/* +1 / -1: point i's output normal (its axis, signed as the run signs it now)
 * faces the sensor at v squarely / faces away squarely; 0: seen near grazing. */
static int
sensor_side(const run_state* s, size_t i, const double v[3])
{
  const double* p = s->cloud.xyz + 3 * i;
  const double* a = s->cloud.nrm + 3 * i;
  const double* o = s->oriented + 3 * i;
  const double r[3] = {v[0] - p[0], v[1] - p[1], v[2] - p[2]};
  const double along = a[0] * o[0] + a[1] * o[1] + a[2] * o[2] >= 0.0 ? 1.0 : -1.0;
  const double dot = along * dacpo_sign_point(s, i) * (a[0] * r[0] + a[1] * r[1] + a[2] * r[2]);
  const double len =
      sqrt((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]));
  return dot >= DACPO_SENSOR_SQUARE_COS * len ? 1 : (dot <= -DACPO_SENSOR_SQUARE_COS * len ? -1 : 0);
}

static dacpo_status
face_the_sensor(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  const size_t n = s->cloud.n;
  st->sensor_turned = 0;
  if (!s->sensor_known)
    return DACPO_OK;
  size_t facing = 0, away = 0;
  for (size_t i = 0; i < n; ++i) {
    const int side = sensor_side(s, i, s->sensor);
    facing += side > 0;
    away += side < 0;
  }
  const double most = s->p.disconnected == DACPO_DISCONNECTED_VIEWPOINT
                          ? DACPO_SENSOR_MAX_AWAY
                          : 1.0; /* the mirror image only */
  if ((double)away >= most * (double)facing)
    return DACPO_OK;
  if (!s->turned && !(s->turned = dacpo_calloc_array(n ? n : 1, sizeof(uint8_t))))
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i)
    if (sensor_side(s, i, s->sensor) < 0) {
      s->turned[i] = (uint8_t)!s->turned[i];
      ++st->sensor_turned;
    }
  return DACPO_OK;
}

/* The frames' sensors (dacpo_frame_sensors.c), where the points come frame
 * by frame. A point's word is its own frame's windows': the sensor found
 * sees it squarely, facing or facing away, and explains the density along
 * the window's surfaces (a frame's density falls with range across each
 * surface; a cloud sampled surface by surface, a mesh's faces or a generated
 * scene's patches, has density steps between surfaces a far sensor explains
 * while each surface is flat). First whole blocks (what stage 2 made
 * consistent) turn where their points' word is decisive: facing away from at
 * least DACPO_FRAME_BLOCK_SHARE of the block, facing under
 * DACPO_SENSOR_MAX_AWAY of that (a flat or grazing frame finds no sensor, so
 * most of a block can go unseen by the pass); then every point its word says
 * faces away turns. */
#define DACPO_FRAME_BLOCK_SHARE 0.05

/* vote[i] < 0 / > 0 where point i's word is that it faces away / faces
 * (above): the sum of sensor_side over the windows of its frame that hold
 * it (a band and the whole frame: two at most), so where they disagree it
 * has none. */
static void
frame_votes(const run_state* s, const dacpo_frame_windows* w, int8_t* vote)
{
  for (size_t k = 0; k < w->count; ++k) {
    if (!w->along[k])
      continue;
    for (size_t i = w->first[k]; i < w->end[k]; ++i)
      vote[i] = (int8_t)(vote[i] + sensor_side(s, i, w->sensor + 3 * k));
  }
}

/* turn[b] = 1 where block b's points' word is decisive (above). */
static void
frame_blocks(const run_state* s, const int8_t* vote, uint8_t* turn)
{
  const dacpo_blocks* bl = &s->blocks;
  for (size_t b = 0; b < bl->num_blocks; ++b) {
    size_t away = 0, facing = 0;
    for (size_t j = bl->own_start[b]; j < bl->own_start[b + 1]; ++j) {
      away += vote[bl->own[j]] < 0;
      facing += vote[bl->own[j]] > 0;
    }
    const double size = (double)(bl->own_start[b + 1] - bl->own_start[b]);
    turn[b] = (uint8_t)((double)away >= DACPO_FRAME_BLOCK_SHARE * size &&
                        (double)facing < DACPO_SENSOR_MAX_AWAY * (double)away);
  }
}

static dacpo_status
face_the_frame_sensors(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  const size_t n = s->cloud.n;
  st->frame_sensors = 0;
  st->frame_turned = 0;
  if (s->p.sign_policy != DACPO_SIGN_FREE_SPACE || n == 0)
    return DACPO_OK;
  dacpo_frame_windows w;
  DACPO_TRY(dacpo_frame_windows_find(
      s->cloud.xyz, s->cloud.nrm, n, s->p.num_threads, &w, err));
  for (size_t k = 0; k < w.count; ++k)
    st->frame_sensors += w.along[k];
  if (st->frame_sensors == 0) { /* no frame with a sensor: no pass, no buffers */
    dacpo_frame_windows_free(&w);
    return DACPO_OK;
  }
  int8_t* vote = dacpo_calloc_array(n, sizeof(int8_t));
  uint8_t* turn_block = dacpo_calloc_array(s->blocks.num_blocks + 1, sizeof(uint8_t));
  dacpo_status r = vote && turn_block ? DACPO_OK : DACPO_OOM(err);
  if (r == DACPO_OK && !s->turned &&
      !(s->turned = dacpo_calloc_array(n, sizeof(uint8_t))))
    r = DACPO_OOM(err);
  if (r == DACPO_OK) {
    frame_votes(s, &w, vote);
    frame_blocks(s, vote, turn_block);
  }
  for (size_t i = 0; r == DACPO_OK && i < n; ++i) {
    /* its block's turn unless its own word is that it faces; else its word */
    const int turn = turn_block[s->blocks.block_of[i]] ? vote[i] <= 0 : vote[i] < 0;
    if (turn) {
      s->turned[i] = (uint8_t)!s->turned[i];
      ++st->frame_turned;
    }
  }
  free(vote);
  free(turn_block);
  dacpo_frame_windows_free(&w);
  return r;
}

dacpo_status
dacpo_sign_passes(run_state* s, dacpo_stats* st, dacpo_err* err)
{
  DACPO_TRY(add_seam_dipole(s, err));
  DACPO_TRY(solve_flips(s, st, err));
  if (s->p.disconnected == DACPO_DISCONNECTED_VIEWPOINT &&
      (s->num_components > 1 || s->p.weak_edge_fraction > 0.0))
    DACPO_TRY(relate_parts(s, st, err));
  DACPO_TRY(choose_global_sign(s, st, err));
  if (s->part_sign)
    DACPO_TRY(closed_parts_outward(s, st->num_parts, err));
  if (s->part_sign)
    DACPO_TRY(parts_follow_the_cue(s, st->num_parts, &st->parts_cue_signed, err));
  DACPO_TRY(reconcile_cue_with_free_space(s, &st->cue_reconciled_blocks, err));
  DACPO_TRY(surface_vote(s, st, err));
  DACPO_TRY(face_the_sensor(s, st, err));
  return face_the_frame_sensors(s, st, err);
}
