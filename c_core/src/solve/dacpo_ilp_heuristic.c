/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 5, part 2: the heuristic incumbent of the 0-1 block-flip program
 * (paper §5.2, Eq. 8), a max-cut on the merged graph (dacpo_ilp_graph.c).
 *
 * Always computed for the whole graph: a maximum spanning tree on the
 * confidence |c_e| (Kruskal), flips propagated along it, then local search with
 * subtree flips (all subtrees of the tree scored at once via LCAs), single-node
 * flips (best gain first) and greedily grown connected cluster flips; then up to
 * 16 restarts from random spanning trees, the best per component kept. It is
 * exact on trees and on components whose edges can all be satisfied at once,
 * which then never reach lp_solve; elsewhere it is the answer lp_solve must
 * beat, and the answer left when lp_solve times out (dacpo_ilp.c). It needs
 * nothing of lp_solve, hence its own file.
 *
 * Inputs: the merged graph, a time at which restarts stop.
 * Outputs: flip per node, each component's lowest node 0.
 * Cost: per start O(m log m + passes * (moves * (n + m) + seeds * L *
 * frontier)) with cluster size L <= 48 (~0.01 s for 200 blocks).
 * Failure modes: allocation failure (OUT_OF_MEMORY).
 */
#include "dacpo_ilp_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Largest cluster grown by one cluster flip of the local search. */
#define ILP_CLUSTER_MAX 48
/* Cluster-flip passes over all seeds (each pass is followed by single flips). */
#define ILP_CLUSTER_PASSES 8
/* Random spanning trees tried after the maximum-confidence one. */
#define ILP_TREE_RESTARTS 16

typedef struct ilp_key {
  double key;
  int32_t e;
} ilp_key;

static int
ilp_key_desc(const void* pa, const void* pb)
{
  const ilp_key* x = (const ilp_key*)pa;
  const ilp_key* y = (const ilp_key*)pb;
  if (x->key != y->key)
    return x->key > y->key ? -1 : 1;
  return (x->e > y->e) - (x->e < y->e);
}

/* The term of edge e in the gain of flipping one of its ends. */
static double
ilp_term(const dacpo_ilp_graph* g, const uint8_t* o, int32_t e)
{
  return (o[g->ea[e]] != o[g->eb[e]]) ? -g->c[e] : g->c[e];
}

/* Flips node v and keeps gain[] (objective change of flipping each node) exact. */
static void
ilp_flip_node(const dacpo_ilp_graph* g, uint8_t* o, double* gain, int32_t v)
{
  for (size_t q = g->adj_start[v]; q < g->adj_start[v + 1]; ++q) {
    int32_t u = g->adj_node[q];
    gain[u] -= 2.0 * ilp_term(g, o, g->adj_edge[q]);
  }
  gain[v] = -gain[v];
  o[v] ^= 1u;
}

/* Flips the single node of best positive gain until none is left. */
static void
ilp_single_flips(const dacpo_ilp_graph* g, uint8_t* o, double* gain, double tol)
{
  size_t limit = 16 * g->n + 64; /* each flip gains > tol; this only guards rounding */
  for (size_t it = 0; it < limit; ++it) {
    int32_t best = -1;
    double bg = tol;
    for (size_t v = 0; v < g->n; ++v)
      if (gain[v] > bg) {
        bg = gain[v];
        best = (int32_t)v;
      }
    if (best < 0)
      return;
    ilp_flip_node(g, o, gain, best);
  }
}

typedef struct ilp_cluster_ws {
  uint8_t* in_s;    /* node is in the cluster */
  uint8_t* in_f;    /* node is on the frontier */
  double* inner;    /* sum of terms of edges from the node into the cluster */
  int32_t* members; /* cluster in growth order */
  int32_t* frontier;
  int32_t* touched; /* nodes whose in_f / inner must be reset */
} ilp_cluster_ws;

/* Grows a connected cluster from seed s, each step adding the frontier node
 * that raises the cluster's flip gain most, and flips the best prefix if it
 * gains. Flipping S changes exactly the edges leaving S; adding v to S turns
 * its edges into S from cut-changing to internal: delta = gain[v] - 2 inner[v]. */
static int
ilp_grow_cluster(const dacpo_ilp_graph* g,
                 uint8_t* o,
                 double* gain,
                 ilp_cluster_ws* w,
                 int32_t s,
                 double tol)
{
  size_t ns = 0, nf = 0, nt = 0;
  double cur = 0.0, best = tol;
  size_t bestk = 0;
  int32_t v = s;
  double delta = gain[s];
  for (;;) {
    cur += delta;
    w->in_s[v] = 1;
    w->members[ns++] = v;
    if (cur > best) {
      best = cur;
      bestk = ns;
    }
    for (size_t q = g->adj_start[v]; q < g->adj_start[v + 1]; ++q) {
      int32_t u = g->adj_node[q];
      if (w->in_s[u])
        continue;
      if (!w->in_f[u]) {
        w->in_f[u] = 1;
        w->inner[u] = 0.0;
        w->frontier[nf++] = u;
        w->touched[nt++] = u;
      }
      w->inner[u] += ilp_term(g, o, g->adj_edge[q]);
    }
    if (ns >= ILP_CLUSTER_MAX || nf == 0)
      break;
    size_t bi = 0;
    double bd = -INFINITY;
    for (size_t i = 0; i < nf; ++i) {
      double d = gain[w->frontier[i]] - 2.0 * w->inner[w->frontier[i]];
      if (d > bd) {
        bd = d;
        bi = i;
      }
    }
    v = w->frontier[bi];
    delta = bd;
    w->frontier[bi] = w->frontier[--nf];
    w->in_f[v] = 0;
  }
  for (size_t i = 0; i < nt; ++i)
    w->in_f[w->touched[i]] = 0;
  for (size_t i = 0; i < ns; ++i)
    w->in_s[w->members[i]] = 0;
  for (size_t i = 0; i < bestk; ++i)
    ilp_flip_node(g, o, gain, w->members[i]);
  return bestk > 0;
}

/* The maximum-confidence spanning forest, rooted at each component's lowest
 * node, in preorder (a subtree is a contiguous range of order[]). */
typedef struct ilp_tree {
  int32_t* order;  /* preorder of all nodes, component by component */
  int32_t* pos;    /* node -> index in order */
  int32_t* size;   /* subtree size */
  int32_t* parent; /* -1 at roots */
  int32_t* pedge;  /* edge to the parent, -1 at roots */
  int32_t* depth;
  int32_t* lca; /* per merged edge: lowest common ancestor of its ends */
  double* acc;  /* scratch: subtree-gain accumulation */
} ilp_tree;

static void
ilp_tree_free(ilp_tree* t)
{
  free(t->order);
  free(t->pos);
  free(t->size);
  free(t->parent);
  free(t->pedge);
  free(t->depth);
  free(t->lca);
  free(t->acc);
}

/* Kruskal on |c_e| (with rng, on |c_e| times a uniform random factor, for the
 * restarts): marks the edges of the maximum spanning forest in in_tree. */
static void
ilp_spanning_forest(const dacpo_ilp_graph* g,
                    dacpo_rng* rng,
                    ilp_key* keys,
                    int32_t* uf,
                    uint8_t* in_tree)
{
  size_t n = g->n, m = g->m;
  for (size_t k = 0; k < m; ++k) {
    keys[k].key = fabs(g->c[k]) * (rng ? dacpo_rng_uniform(rng) : 1.0);
    keys[k].e = (int32_t)k;
  }
  qsort(keys, m, sizeof(*keys), ilp_key_desc);
  for (size_t v = 0; v < n; ++v)
    uf[v] = (int32_t)v;
  for (size_t k = 0; k < m; ++k) {
    int32_t e = keys[k].e;
    if (dacpo_uf_find(uf, g->ea[e]) == dacpo_uf_find(uf, g->eb[e]))
      continue;
    dacpo_uf_union(uf, g->ea[e], g->eb[e]);
    in_tree[e] = 1;
  }
}

/* Iterative DFS preorder of the forest from each component's lowest node, with
 * parents, parent edges, depths and subtree sizes. stack: n scratch entries. */
static void
ilp_forest_preorder(const dacpo_ilp_graph* g,
                    const uint8_t* in_tree,
                    int32_t* stack,
                    ilp_tree* t)
{
  size_t n = g->n;
  for (size_t v = 0; v < n; ++v)
    t->pos[v] = -1;
  size_t no = 0;
  for (size_t ci = 0; ci < g->ncomp; ++ci) {
    int32_t root = g->comp_nodes[g->comp_start[ci]];
    size_t sp = 0;
    stack[sp++] = root;
    t->parent[root] = -1;
    t->pedge[root] = -1;
    t->depth[root] = 0;
    while (sp > 0) {
      int32_t v = stack[--sp];
      t->pos[v] = (int32_t)no;
      t->order[no++] = v;
      for (size_t q = g->adj_start[v]; q < g->adj_start[v + 1]; ++q) {
        int32_t u = g->adj_node[q], e = g->adj_edge[q];
        if (!in_tree[e] || u == t->parent[v])
          continue;
        t->parent[u] = v;
        t->pedge[u] = e;
        t->depth[u] = t->depth[v] + 1;
        stack[sp++] = u;
      }
    }
  }
  for (size_t i = n; i-- > 0;) {
    int32_t v = t->order[i];
    t->size[v] = 1;
  }
  for (size_t i = n; i-- > 0;) {
    int32_t v = t->order[i];
    if (t->parent[v] >= 0)
      t->size[t->parent[v]] += t->size[v];
  }
}

/* The LCA of every edge's ends by binary lifting: up[l * n + v] (levels * n
 * scratch entries) is the 2^l-th ancestor (roots map to self). */
static void
ilp_edge_lcas(const dacpo_ilp_graph* g, size_t levels, int32_t* up, ilp_tree* t)
{
  size_t n = g->n, m = g->m;
  for (size_t v = 0; v < n; ++v)
    up[v] = t->parent[v] >= 0 ? t->parent[v] : (int32_t)v;
  for (size_t l = 1; l < levels; ++l)
    for (size_t v = 0; v < n; ++v)
      up[l * n + v] = up[(l - 1) * n + up[(l - 1) * n + v]];
  for (size_t k = 0; k < m; ++k) {
    int32_t a = g->ea[k], b = g->eb[k];
    if (t->depth[a] < t->depth[b]) {
      int32_t x = a;
      a = b;
      b = x;
    }
    int32_t diff = t->depth[a] - t->depth[b];
    for (size_t l = 0; l < levels; ++l)
      if (diff & (1 << l))
        a = up[l * n + a];
    if (a != b) {
      for (size_t l = levels; l-- > 0;)
        if (up[l * n + a] != up[l * n + b]) {
          a = up[l * n + a];
          b = up[l * n + b];
        }
      a = up[a];
    }
    t->lca[k] = a;
  }
}

/* Kruskal on |c_e| (the most confident edges decide the relative flips; with
 * rng, on |c_e| times a uniform random factor, for the restarts), a preorder of
 * the forest, and the LCA of every edge's ends by binary lifting. */
static dacpo_status
ilp_tree_build(const dacpo_ilp_graph* g, dacpo_rng* rng, ilp_tree* t, dacpo_err* err)
{
  size_t n = g->n, m = g->m;
  dacpo_status st = DACPO_OK;
  memset(t, 0, sizeof(*t));
  t->order = dacpo_malloc_array(n, sizeof(int32_t));
  t->pos = dacpo_malloc_array(n, sizeof(int32_t));
  t->size = dacpo_malloc_array(n, sizeof(int32_t));
  t->parent = dacpo_malloc_array(n, sizeof(int32_t));
  t->pedge = dacpo_malloc_array(n, sizeof(int32_t));
  t->depth = dacpo_malloc_array(n, sizeof(int32_t));
  t->lca = dacpo_malloc_array(m, sizeof(int32_t));
  t->acc = dacpo_malloc_array(n, sizeof(double));
  ilp_key* keys = dacpo_malloc_array(m, sizeof(*keys));
  int32_t* uf = dacpo_malloc_array(n, sizeof(int32_t));
  uint8_t* in_tree = dacpo_calloc_array(m, 1);
  int32_t* stack = dacpo_malloc_array(n, sizeof(int32_t));
  size_t levels = 1;
  while (levels < 31 && ((size_t)1 << levels) < n)
    ++levels;
  int32_t* up = dacpo_malloc_array(n, levels * sizeof(int32_t));
  if (!t->order || !t->pos || !t->size || !t->parent || !t->pedge || !t->depth ||
      !t->lca || !t->acc || !keys || !uf || !in_tree || !stack || !up) {
    st = DACPO_OOM(err);
    goto done;
  }
  ilp_spanning_forest(g, rng, keys, uf, in_tree);
  ilp_forest_preorder(g, in_tree, stack, t);
  ilp_edge_lcas(g, levels, up, t);
done:
  free(keys);
  free(uf);
  free(in_tree);
  free(stack);
  free(up);
  if (st != DACPO_OK) {
    ilp_tree_free(t);
    memset(t, 0, sizeof(*t));
  }
  return st;
}

/* Subtree moves: flipping the subtree under v changes exactly the edges with
 * one end inside, i.e. the edges whose tree path passes the parent edge of v.
 * Adding each edge's term at both ends and -2x at their LCA, subtree sums give
 * every subtree's gain in O(n + m); the best is flipped until none gains. This
 * undoes a noisy but confident edge that the spanning tree trusted. */
static int
ilp_subtree_moves(
    const dacpo_ilp_graph* g, const ilp_tree* t, uint8_t* o, double* gain, double tol)
{
  int improved = 0;
  for (size_t it = 0; it < g->n; ++it) {
    memset(t->acc, 0, g->n * sizeof(double));
    for (size_t k = 0; k < g->m; ++k) {
      double x = ilp_term(g, o, (int32_t)k);
      t->acc[g->ea[k]] += x;
      t->acc[g->eb[k]] += x;
      t->acc[t->lca[k]] -= 2.0 * x;
    }
    int32_t best = -1;
    double bg = tol;
    for (size_t i = g->n; i-- > 0;) {
      int32_t v = t->order[i];
      if (t->parent[v] < 0)
        continue;
      if (t->acc[v] > bg) {
        bg = t->acc[v];
        best = v;
      }
      t->acc[t->parent[v]] += t->acc[v];
    }
    if (best < 0)
      break;
    for (int32_t i = t->pos[best]; i < t->pos[best] + t->size[best]; ++i)
      ilp_flip_node(g, o, gain, t->order[i]);
    improved = 1;
  }
  return improved;
}

/* Subtree, single and cluster moves until none gains (or the pass limit). */
static void
ilp_descend(const dacpo_ilp_graph* g,
            const ilp_tree* t,
            ilp_cluster_ws* w,
            uint8_t* o,
            double* gain,
            double tol)
{
  for (int pass = 0; pass < ILP_CLUSTER_PASSES; ++pass) {
    int improved = ilp_subtree_moves(g, t, o, gain, tol);
    ilp_single_flips(g, o, gain, tol);
    if (w) {
      /* A cluster can only gain across an unsatisfied edge (term > 0), so
       * seeds are the ends of unsatisfied edges. */
      for (size_t s = 0; s < g->n; ++s) {
        int seed = 0;
        for (size_t q = g->adj_start[s]; q < g->adj_start[s + 1] && !seed; ++q)
          seed = ilp_term(g, o, g->adj_edge[q]) > 0.0;
        if (seed)
          improved |= ilp_grow_cluster(g, o, gain, w, (int32_t)s, tol);
      }
      ilp_single_flips(g, o, gain, tol);
    }
    if (!improved)
      break;
  }
}

/* Flips along the tree (each tree edge at its preferred value), gains, then
 * local search. */
static void
ilp_start(const dacpo_ilp_graph* g,
          const ilp_tree* t,
          ilp_cluster_ws* w,
          uint8_t* o,
          double* gain,
          double tol)
{
  for (size_t i = 0; i < g->n; ++i) {
    int32_t v = t->order[i];
    o[v] =
        t->parent[v] < 0 ? 0 : (uint8_t)(o[t->parent[v]] ^ (g->c[t->pedge[v]] > 0.0));
  }
  memset(gain, 0, g->n * sizeof(double));
  for (size_t k = 0; k < g->m; ++k) {
    double x = ilp_term(g, o, (int32_t)k);
    gain[g->ea[k]] += x;
    gain[g->eb[k]] += x;
  }
  ilp_descend(g, t, w, o, gain, tol);
}

/* The incumbent: the maximum-confidence tree, then restarts from random
 * spanning trees (each a different basin for the local search; measured on the
 * bench graphs, 16 restarts reached lp_solve's optimum where the single start
 * stalled ~1 % below it). Restarts stop at stop_time, so a tiny time limit still
 * gets the first answer. o gets the best; each component's lowest node is 0. */
dacpo_status
dacpo_ilp_heuristic(const dacpo_ilp_graph* g,
                    double stop_time,
                    uint8_t* o,
                    dacpo_err* err)
{
  size_t n = g->n, m = g->m;
  dacpo_status st = DACPO_OK;
  ilp_tree t;
  DACPO_TRY(ilp_tree_build(g, NULL, &t, err));
  double* gain = dacpo_malloc_array(n, sizeof(double));
  uint8_t* o2 = dacpo_malloc_array(n, 1);
  double* best = dacpo_malloc_array(g->ncomp, sizeof(double));
  ilp_cluster_ws w;
  w.in_s = dacpo_calloc_array(n, 1);
  w.in_f = dacpo_calloc_array(n, 1);
  w.inner = dacpo_calloc_array(n, sizeof(double));
  w.members = dacpo_malloc_array(n, sizeof(int32_t));
  w.frontier = dacpo_malloc_array(n, sizeof(int32_t));
  w.touched = dacpo_malloc_array(n, sizeof(int32_t));
  if (!gain || !o2 || !best || !w.in_s || !w.in_f || !w.inner || !w.members ||
      !w.frontier || !w.touched) {
    st = DACPO_OOM(err);
    goto done;
  }
  /* tol is relative to the weights, so rounding cannot make moves cycle */
  double scale = 0.0;
  for (size_t k = 0; k < m; ++k)
    scale += fabs(g->c[k]);
  double tol = 1e-12 * (1.0 + scale);

  ilp_start(g, &t, &w, o, gain, tol);
  for (size_t ci = 0; ci < g->ncomp; ++ci)
    best[ci] = dacpo_ilp_comp_value(g, ci, o);
  dacpo_rng rng;
  dacpo_rng_seed(&rng, 0x1d3c5a7ull, (uint64_t)n);
  /* A forest (m = n - components) is solved exactly by the first tree. Each
   * component keeps its best restart: their relative sign does not matter. */
  for (int r = 0; r < ILP_TREE_RESTARTS && m + g->ncomp > n && dacpo_now() < stop_time;
       ++r) {
    ilp_tree_free(&t);
    st = ilp_tree_build(g, &rng, &t, err);
    if (st != DACPO_OK)
      goto done;
    ilp_start(g, &t, &w, o2, gain, tol);
    for (size_t ci = 0; ci < g->ncomp; ++ci) {
      double v = dacpo_ilp_comp_value(g, ci, o2);
      if (v > best[ci] + tol) {
        best[ci] = v;
        for (size_t q = g->comp_start[ci]; q < g->comp_start[ci + 1]; ++q)
          o[g->comp_nodes[q]] = o2[g->comp_nodes[q]];
      }
    }
  }
  /* A component's lowest node is the fixed reference (o = 0). */
  for (size_t ci = 0; ci < g->ncomp; ++ci)
    if (o[g->comp_nodes[g->comp_start[ci]]])
      for (size_t q = g->comp_start[ci]; q < g->comp_start[ci + 1]; ++q)
        o[g->comp_nodes[q]] ^= 1u;

done:
  ilp_tree_free(&t);
  free(gain);
  free(o2);
  free(best);
  free(w.in_s);
  free(w.in_f);
  free(w.inner);
  free(w.members);
  free(w.frontier);
  free(w.touched);
  return st;
}
