/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 4a: the block adjacency graph (paper §5, the graph the 0-1 program of
 * Eq. 8 runs on) and the dipole-boundary edge weight, a cheap alternative to the
 * visible-connected-region weight of §5.1 built from the same field as Eq. 1-2.
 *
 * Input:  the block of every distinct point, the symmetric k-NN adjacency, and
 *         for the weights the points with their current (per-block oriented)
 *         normals.
 * Output: one edge per pair of blocks joined by at least one adjacency pair,
 *         sorted by (a, b) with a < b, with the number of joining pairs and the
 *         evidence alpha (blocks agree as they are) / alpha_bar (one is flipped).
 *
 * Cost: O(P log P) for P crossing point pairs (sort of 64-bit block-pair keys);
 * the weights are O(P log E) (binary search of each pair's edge).
 *
 * Failures: INVALID_ARGUMENT (NULL, sizes that disagree, a block id or neighbour
 * index out of range, non-finite c), OUT_OF_MEMORY, INTERNAL (a crossing pair
 * whose blocks have no edge: graph and adjacency do not belong together).
 */
#include "dacpo_block_graph.h"

#include "dacpo_dipole.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int
compare_double(const void* a, const void* b)
{
  const double x = *(const double*)a, y = *(const double*)b;
  return x < y ? -1 : x > y;
}

static uint64_t
pair_key(int32_t a, int32_t b)
{
  return ((uint64_t)(uint32_t)a << 32) | (uint64_t)(uint32_t)b;
}

static int
cmp_u64(const void* x, const void* y)
{
  const uint64_t a = *(const uint64_t*)x, b = *(const uint64_t*)y;
  return (a > b) - (a < b);
}

/* Shared checks of the blocks/adjacency pair; every index is validated once here
 * so the loops below can trust them. */
static dacpo_status
check_inputs(const dacpo_blocks* blocks, const dacpo_adjacency* adj, dacpo_err* err)
{
  DACPO_CHECK(err,
              blocks && adj,
              DACPO_ERR_INVALID_ARGUMENT,
              "block graph: NULL blocks or adjacency");
  DACPO_CHECK(err,
              blocks->num_blocks <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "block graph: %zu blocks exceed int32 ids",
              blocks->num_blocks);
  if (adj->n == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              adj->n <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "block graph: %zu points exceed int32 indices",
              adj->n);
  DACPO_CHECK(err,
              blocks->block_of && adj->start && (adj->nbr || adj->start[adj->n] == 0),
              DACPO_ERR_INVALID_ARGUMENT,
              "block graph: NULL block_of or adjacency arrays");
  for (size_t i = 0; i < adj->n; ++i) {
    const int32_t b = blocks->block_of[i];
    DACPO_CHECK(err,
                b >= 0 && (size_t)b < blocks->num_blocks,
                DACPO_ERR_INVALID_ARGUMENT,
                "block graph: point %zu has block %d, outside [0, %zu)",
                i,
                (int)b,
                blocks->num_blocks);
    DACPO_CHECK(err,
                adj->start[i] <= adj->start[i + 1],
                DACPO_ERR_INVALID_ARGUMENT,
                "block graph: adjacency row %zu has a negative length",
                i);
    for (size_t e = adj->start[i]; e < adj->start[i + 1]; ++e)
      DACPO_CHECK(err,
                  adj->nbr[e] >= 0 && (size_t)adj->nbr[e] < adj->n,
                  DACPO_ERR_INVALID_ARGUMENT,
                  "block graph: neighbour %d of point %zu out of range",
                  (int)adj->nbr[e],
                  i);
  }
  return DACPO_OK;
}

dacpo_status
dacpo_block_graph_build(const dacpo_blocks* blocks,
                        const dacpo_adjacency* adj,
                        dacpo_block_graph* out,
                        dacpo_err* err)
{
  DACPO_CHECK(err, out != NULL, DACPO_ERR_INVALID_ARGUMENT, "block graph: out is NULL");
  memset(out, 0, sizeof(*out));
  DACPO_TRY(check_inputs(blocks, adj, err));
  const size_t n = adj->n;

  /* The adjacency is symmetric: taking j > i visits each unordered pair once. */
  size_t num_pairs = 0;
  for (size_t i = 0; i < n; ++i)
    for (size_t e = adj->start[i]; e < adj->start[i + 1]; ++e) {
      const size_t j = (size_t)adj->nbr[e];
      num_pairs += j > i && blocks->block_of[i] != blocks->block_of[j];
    }
  if (num_pairs == 0)
    return DACPO_OK;

  uint64_t* keys = dacpo_malloc_array(num_pairs, sizeof(uint64_t));
  if (!keys)
    return DACPO_OOM(err);
  size_t k = 0;
  for (size_t i = 0; i < n; ++i)
    for (size_t e = adj->start[i]; e < adj->start[i + 1]; ++e) {
      const size_t j = (size_t)adj->nbr[e];
      const int32_t a = blocks->block_of[i], b = blocks->block_of[j];
      if (j > i && a != b)
        keys[k++] = a < b ? pair_key(a, b) : pair_key(b, a);
    }
  /* Sorting the (a, b) keys groups each edge's pairs and orders the edges. */
  qsort(keys, num_pairs, sizeof(uint64_t), cmp_u64);

  size_t num_edges = 1;
  for (size_t p = 1; p < num_pairs; ++p)
    num_edges += keys[p] != keys[p - 1];
  dacpo_block_edge* edges = dacpo_calloc_array(num_edges, sizeof(dacpo_block_edge));
  if (!edges) {
    free(keys);
    return DACPO_OOM(err);
  }
  size_t m = 0;
  for (size_t p = 0; p < num_pairs; ++p) {
    if (p > 0 && keys[p] == keys[p - 1]) {
      edges[m - 1].crossing++;
      continue;
    }
    edges[m].a = (int32_t)(keys[p] >> 32);
    edges[m].b = (int32_t)(keys[p] & 0xffffffffu);
    edges[m].crossing = 1;
    ++m;
  }
  free(keys);
  out->num_edges = num_edges;
  out->edges = edges;
  return DACPO_OK;
}

void
dacpo_block_graph_free(dacpo_block_graph* g)
{
  if (!g)
    return;
  free(g->edges);
  g->edges = NULL;
  g->num_edges = 0;
}

ptrdiff_t
dacpo_block_graph_find(const dacpo_block_graph* g, int32_t a, int32_t b)
{
  if (!g || !g->edges)
    return -1;
  if (a > b) {
    const int32_t t = a;
    a = b;
    b = t;
  }
  size_t lo = 0, hi = g->num_edges;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    const dacpo_block_edge* e = &g->edges[mid];
    if (e->a < a || (e->a == a && e->b < b))
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo < g->num_edges && g->edges[lo].a == a && g->edges[lo].b == b)
    return (ptrdiff_t)lo;
  return -1;
}

dacpo_status
dacpo_block_graph_dipole_weights(dacpo_block_graph* g,
                                 const dacpo_cloud* cloud,
                                 const dacpo_adjacency* adj,
                                 const dacpo_blocks* blocks,
                                 const double* oriented_nrm,
                                 double c,
                                 dacpo_err* err)
{
  DACPO_CHECK(err,
              g && cloud,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole weights: NULL graph or cloud");
  DACPO_TRY(check_inputs(blocks, adj, err));
  DACPO_CHECK(err,
              cloud->n == adj->n,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole weights: cloud has %zu points, adjacency %zu",
              cloud->n,
              adj->n);
  DACPO_CHECK(
      err, isfinite(c), DACPO_ERR_INVALID_ARGUMENT, "dipole weights: c is not finite");
  DACPO_CHECK(err,
              g->num_edges == 0 || g->edges,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole weights: graph has %zu edges but no array",
              g->num_edges);
  for (size_t e = 0; e < g->num_edges; ++e) {
    g->edges[e].alpha = 0.0;
    g->edges[e].alpha_bar = 0.0;
  }
  const size_t n = adj->n;
  if (n == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              cloud->xyz && oriented_nrm,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole weights: NULL points or normals");
  for (size_t i = 0; i < n; ++i)
    for (size_t k = adj->start[i]; k < adj->start[i + 1]; ++k) {
      const size_t j = (size_t)adj->nbr[k];
      const int32_t a = blocks->block_of[i], b = blocks->block_of[j];
      if (j <= i || a == b)
        continue;
      const ptrdiff_t e = dacpo_block_graph_find(g, a, b);
      DACPO_CHECK(err,
                  e >= 0,
                  DACPO_ERR_INTERNAL,
                  "dipole weights: points %zu and %zu join blocks %d and %d, which "
                  "have no edge",
                  i,
                  j,
                  (int)a,
                  (int)b);
      /* Eq. 2 both ways; e is symmetric in its two arguments, so the sum is
       * twice one evaluation. Flipping one block negates s: its positive part is
       * evidence for "same", its negative part for "differ". */
      const double s = 2.0 * dacpo_dipole_energy(cloud->xyz + 3 * i,
                                                 oriented_nrm + 3 * i,
                                                 cloud->xyz + 3 * j,
                                                 oriented_nrm + 3 * j,
                                                 c);
      if (s > 0.0)
        g->edges[e].alpha += s;
      else
        g->edges[e].alpha_bar -= s;
    }
  return DACPO_OK;
}

void
dacpo_edge_omega(
    double alpha, double alpha_bar, double scale, double* w_same, double* w_diff)
{
  /* Eq. 7 gives every edge the same total weight, so a contact of a few pixels
   * or pairs outvotes a long shared wall around a cycle. The ratio is kept as
   * the edge's confidence, and the total is scaled by g = a / (1 + a), a = the
   * edge's evidence relative to a typical edge: about 1 for ordinary and strong
   * edges, proportional to the evidence for weak ones. No evidence, or evidence
   * that is not finite, gives (0, 0). */
  const double den = alpha + alpha_bar;
  double ws = 0.0, wd = 0.0;
  if (den > 0.0 && isfinite(den)) {
    const double amount = scale > 0.0 ? den / scale : HUGE_VAL;
    const double g = isinf(amount) ? 1.0 : amount / (1.0 + amount);
    ws = g * (alpha / den);
    wd = g * (alpha_bar / den);
  }
  if (w_same)
    *w_same = ws;
  if (w_diff)
    *w_diff = wd;
}

double
dacpo_edge_evidence_scale(const dacpo_block_graph* g)
{
  /* median of alpha + alpha_bar over the edges that carry evidence */
  size_t m = 0;
  double* v =
      g && g->num_edges ? dacpo_malloc_array(g->num_edges, sizeof(double)) : NULL;
  if (!v)
    return 0.0;
  for (size_t e = 0; e < g->num_edges; ++e) {
    const double t = g->edges[e].alpha + g->edges[e].alpha_bar;
    if (t > 0.0 && isfinite(t))
      v[m++] = t;
  }
  /* insertion into a sorted prefix would be O(m^2); m is the edge count
   * (hundreds to a few thousand), so a plain qsort is enough */
  qsort(v, m, sizeof(double), compare_double);
  const double med = m ? (m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2])) : 0.0;
  free(v);
  return med;
}

dacpo_status
dacpo_block_graph_blend(dacpo_block_graph* g,
                        const dacpo_block_graph* other,
                        double weight,
                        dacpo_err* err)
{
  DACPO_CHECK(
      err, g && other, DACPO_ERR_INVALID_ARGUMENT, "blend: NULL block graph");
  DACPO_CHECK(err,
              isfinite(weight) && weight >= 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "blend: weight must be finite and >= 0 (got %g)",
              weight);
  DACPO_CHECK(err,
              g->num_edges == other->num_edges,
              DACPO_ERR_INVALID_ARGUMENT,
              "blend: %zu edges against %zu",
              g->num_edges,
              other->num_edges);
  for (size_t e = 0; e < g->num_edges; ++e)
    DACPO_CHECK(err,
                g->edges[e].a == other->edges[e].a && g->edges[e].b == other->edges[e].b,
                DACPO_ERR_INVALID_ARGUMENT,
                "blend: edge %zu joins blocks %d-%d in one graph, %d-%d in the other",
                e,
                (int)g->edges[e].a,
                (int)g->edges[e].b,
                (int)other->edges[e].a,
                (int)other->edges[e].b);
  const double sg = dacpo_edge_evidence_scale(g);
  const double so = dacpo_edge_evidence_scale(other);
  const double fg = sg > 0.0 ? 1.0 / sg : 0.0;
  const double fo = so > 0.0 ? weight / so : 0.0;
  for (size_t e = 0; e < g->num_edges; ++e) {
    dacpo_block_edge* be = &g->edges[e];
    be->alpha = fg * be->alpha + fo * other->edges[e].alpha;
    be->alpha_bar = fg * be->alpha_bar + fo * other->edges[e].alpha_bar;
  }
  return DACPO_OK;
}

dacpo_status
dacpo_block_graph_overlap_weights(dacpo_block_graph* g,
                                  const dacpo_blocks* blocks,
                                  const double* own_nrm,
                                  const double* ring_nrm,
                                  dacpo_err* err)
{
  DACPO_CHECK(err,
              g && blocks && own_nrm,
              DACPO_ERR_INVALID_ARGUMENT,
              "overlap weights: NULL graph, blocks or normals");
  for (size_t e = 0; e < g->num_edges; ++e) {
    g->edges[e].alpha = 0.0;
    g->edges[e].alpha_bar = 0.0;
  }
  const size_t nb = blocks->num_blocks;
  if (nb == 0 || blocks->ring_start[nb] == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              ring_nrm != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "overlap weights: NULL ring normals");
  for (size_t a = 0; a < nb; ++a)
    for (size_t r = blocks->ring_start[a]; r < blocks->ring_start[a + 1]; ++r) {
      const int32_t q = blocks->ring[r];
      const int32_t b = blocks->block_of[q];
      const ptrdiff_t e = dacpo_block_graph_find(g, (int32_t)a, b);
      if (e < 0)
        continue;
      const double* na = ring_nrm + 3 * r;
      const double* nq = own_nrm + 3 * (size_t)q;
      const double d = na[0] * nq[0] + na[1] * nq[1] + na[2] * nq[2];
      if (!isfinite(d))
        continue;
      if (d > 0.0)
        g->edges[e].alpha += d;
      else
        g->edges[e].alpha_bar -= d;
    }
  return DACPO_OK;
}
