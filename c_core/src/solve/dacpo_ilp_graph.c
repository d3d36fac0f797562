/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 5, part 1: the merged edge graph of the 0-1 block-flip program
 * (paper §5.2, Eq. 8) and its connected components.
 *
 * Eq. 8 only depends on each pair of blocks through the sum of its edge
 * weights, so parallel edges are merged (c_e = sum of w_diff - w_same) and self
 * loops, always "same", are constants left out. The components are solved one
 * by one (dacpo_ilp.c), each with its lowest node fixed to 0, so nodes and
 * edges are grouped by component, ascending inside each. The adjacency lists
 * are ascending too: the triangle enumeration of the lp_solve model intersects
 * them. Kept apart from the heuristic (dacpo_ilp_heuristic.c) and the lp_solve
 * model (dacpo_ilp.c), which both read this graph.
 *
 * Inputs: number of nodes and the caller's edges (checked by dacpo_ilp_solve).
 * Outputs: a dacpo_ilp_graph (dacpo_ilp_internal.h); the value of a component
 * at given flips.
 * Cost: O(m log m) for the sort of the edges, O(n + m) for the rest.
 * Failure modes: allocation failure (OUT_OF_MEMORY), the graph is left freed.
 */
#include "dacpo_ilp_internal.h"

#include <stdlib.h>
#include <string.h>

void
dacpo_ilp_graph_free(dacpo_ilp_graph* g)
{
  free(g->ea);
  free(g->eb);
  free(g->c);
  free(g->adj_start);
  free(g->adj_node);
  free(g->adj_edge);
  free(g->comp);
  free(g->comp_start);
  free(g->comp_nodes);
  free(g->cedge_start);
  free(g->cedges);
  memset(g, 0, sizeof(*g));
}

typedef struct ilp_pair {
  int32_t a, b; /* a < b */
  size_t idx;   /* input edge */
} ilp_pair;

static int
ilp_pair_cmp(const void* pa, const void* pb)
{
  const ilp_pair* x = (const ilp_pair*)pa;
  const ilp_pair* y = (const ilp_pair*)pb;
  if (x->a != y->a)
    return x->a < y->a ? -1 : 1;
  if (x->b != y->b)
    return x->b < y->b ? -1 : 1;
  return (x->idx > y->idx) - (x->idx < y->idx);
}

/* Sorts the non-loop edges by their ends and merges parallel ones into g->ea,
 * g->eb and g->c; also allocates the remaining per-node and adjacency arrays. */
static dacpo_status
ilp_merge_edges(size_t num_edges,
                const dacpo_ilp_edge* edges,
                dacpo_ilp_graph* g,
                dacpo_err* err)
{
  size_t n = g->n;
  size_t np = 0;
  for (size_t i = 0; i < num_edges; ++i)
    np += edges[i].a != edges[i].b;
  ilp_pair* pairs = dacpo_malloc_array(np, sizeof(*pairs));
  if (!pairs)
    return DACPO_OOM(err);
  np = 0;
  for (size_t i = 0; i < num_edges; ++i) {
    int32_t a = edges[i].a, b = edges[i].b;
    if (a == b)
      continue; /* a self loop is always "same": a constant of Eq. 8 */
    pairs[np].a = a < b ? a : b;
    pairs[np].b = a < b ? b : a;
    pairs[np].idx = i;
    ++np;
  }
  qsort(pairs, np, sizeof(*pairs), ilp_pair_cmp);
  size_t m = 0;
  for (size_t i = 0; i < np; ++i)
    m += i == 0 || pairs[i].a != pairs[i - 1].a || pairs[i].b != pairs[i - 1].b;

  g->m = m;
  g->ea = dacpo_malloc_array(m, sizeof(int32_t));
  g->eb = dacpo_malloc_array(m, sizeof(int32_t));
  g->c = dacpo_calloc_array(m, sizeof(double));
  g->adj_start = dacpo_calloc_array(n + 1, sizeof(size_t));
  g->adj_node = dacpo_malloc_array(2 * m, sizeof(int32_t));
  g->adj_edge = dacpo_malloc_array(2 * m, sizeof(int32_t));
  g->comp = dacpo_malloc_array(n, sizeof(int32_t));
  if (!g->ea || !g->eb || !g->c || !g->adj_start || !g->adj_node || !g->adj_edge ||
      !g->comp) {
    free(pairs);
    return DACPO_OOM(err);
  }
  size_t e = 0;
  for (size_t i = 0; i < np; ++i) {
    if (i > 0 && (pairs[i].a != pairs[i - 1].a || pairs[i].b != pairs[i - 1].b))
      ++e;
    const dacpo_ilp_edge* in = &edges[pairs[i].idx];
    g->ea[e] = pairs[i].a;
    g->eb[e] = pairs[i].b;
    g->c[e] += in->w_diff - in->w_same; /* parallel edges add up in Eq. 8 */
  }
  free(pairs);
  return DACPO_OK;
}

/* CSR adjacency. Filling in (a, b) order leaves every list ascending: the
 * smaller neighbours of v come from edges (x, v), x < v, which sort before the
 * edges (v, y). The intersection of triangle enumeration relies on it.
 * fill: n + 1 scratch entries. */
static void
ilp_fill_adjacency(dacpo_ilp_graph* g, size_t* fill)
{
  size_t n = g->n, m = g->m;
  for (size_t k = 0; k < m; ++k) {
    g->adj_start[g->ea[k] + 1]++;
    g->adj_start[g->eb[k] + 1]++;
  }
  for (size_t v = 0; v < n; ++v)
    g->adj_start[v + 1] += g->adj_start[v];
  memcpy(fill, g->adj_start, (n + 1) * sizeof(size_t));
  for (size_t k = 0; k < m; ++k) {
    int32_t a = g->ea[k], b = g->eb[k];
    g->adj_node[fill[a]] = b;
    g->adj_edge[fill[a]++] = (int32_t)k;
    g->adj_node[fill[b]] = a;
    g->adj_edge[fill[b]++] = (int32_t)k;
  }
}

/* Components by BFS from the lowest unvisited node; queue: n scratch entries.
 * Sets g->comp and g->ncomp. */
static void
ilp_label_components(dacpo_ilp_graph* g, size_t* queue)
{
  size_t n = g->n;
  for (size_t v = 0; v < n; ++v)
    g->comp[v] = -1;
  size_t ncomp = 0;
  for (size_t s = 0; s < n; ++s) {
    if (g->comp[s] >= 0)
      continue;
    size_t head = 0, tail = 0;
    queue[tail++] = s;
    g->comp[s] = (int32_t)ncomp;
    while (head < tail) {
      size_t v = queue[head++];
      for (size_t q = g->adj_start[v]; q < g->adj_start[v + 1]; ++q) {
        int32_t u = g->adj_node[q];
        if (g->comp[u] < 0) {
          g->comp[u] = (int32_t)ncomp;
          queue[tail++] = (size_t)u;
        }
      }
    }
    ++ncomp;
  }
  g->ncomp = ncomp;
}

/* Groups nodes and edges by component. Counting sorts keep them ascending
 * inside each component. */
static dacpo_status
ilp_group_components(dacpo_ilp_graph* g, dacpo_err* err)
{
  size_t n = g->n, m = g->m, ncomp = g->ncomp;
  g->comp_start = dacpo_calloc_array(ncomp + 1, sizeof(size_t));
  g->comp_nodes = dacpo_malloc_array(n, sizeof(int32_t));
  g->cedge_start = dacpo_calloc_array(ncomp + 1, sizeof(size_t));
  g->cedges = dacpo_malloc_array(m, sizeof(int32_t));
  size_t* cfill = dacpo_malloc_array(ncomp + 1, sizeof(size_t));
  if (!g->comp_start || !g->comp_nodes || !g->cedge_start || !g->cedges || !cfill) {
    free(cfill);
    return DACPO_OOM(err);
  }
  for (size_t v = 0; v < n; ++v)
    g->comp_start[g->comp[v] + 1]++;
  for (size_t c = 0; c < ncomp; ++c)
    g->comp_start[c + 1] += g->comp_start[c];
  memcpy(cfill, g->comp_start, (ncomp + 1) * sizeof(size_t));
  for (size_t v = 0; v < n; ++v)
    g->comp_nodes[cfill[g->comp[v]]++] = (int32_t)v;
  for (size_t k = 0; k < m; ++k)
    g->cedge_start[g->comp[g->ea[k]] + 1]++;
  for (size_t c = 0; c < ncomp; ++c)
    g->cedge_start[c + 1] += g->cedge_start[c];
  memcpy(cfill, g->cedge_start, (ncomp + 1) * sizeof(size_t));
  for (size_t k = 0; k < m; ++k)
    g->cedges[cfill[g->comp[g->ea[k]]]++] = (int32_t)k;
  free(cfill);
  return DACPO_OK;
}

dacpo_status
dacpo_ilp_graph_build(size_t n,
                      size_t num_edges,
                      const dacpo_ilp_edge* edges,
                      dacpo_ilp_graph* g,
                      dacpo_err* err)
{
  memset(g, 0, sizeof(*g));
  g->n = n;
  dacpo_status st = ilp_merge_edges(num_edges, edges, g, err);
  if (st != DACPO_OK) {
    dacpo_ilp_graph_free(g);
    return st;
  }
  size_t* fill = dacpo_malloc_array(n + 1, sizeof(size_t));
  if (!fill) {
    dacpo_ilp_graph_free(g);
    return DACPO_OOM(err);
  }
  ilp_fill_adjacency(g, fill);
  ilp_label_components(g, fill); /* the fill pointers are done: reused as queue */
  free(fill);
  st = ilp_group_components(g, err);
  if (st != DACPO_OK)
    dacpo_ilp_graph_free(g);
  return st;
}

/* sum over a component's edges of c_e y_e (Eq. 8 without its constant) */
double
dacpo_ilp_comp_value(const dacpo_ilp_graph* g, size_t ci, const uint8_t* o)
{
  double s = 0.0;
  for (size_t q = g->cedge_start[ci]; q < g->cedge_start[ci + 1]; ++q) {
    int32_t e = g->cedges[q];
    if (o[g->ea[e]] != o[g->eb[e]])
      s += g->c[e];
  }
  return s;
}
