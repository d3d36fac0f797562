/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 5: the 0-1 block-flip program (paper §5.2, Eq. 8).
 *
 * Every block i gets a flip o_i in {0,1}; Eq. 8 maximizes
 *   sum_{(i,j) in E} omega_ij(o_i, o_j),
 * with omega(0,0) = omega(1,1) = w_same and omega(0,1) = omega(1,0) = w_diff.
 * With y_e = o_a XOR o_b this is  const + sum_e c_e y_e,  c_e = w_diff - w_same,
 * i.e. a max-cut problem. Here (steps 1-2 in dacpo_ilp_graph.c, 3 in
 * dacpo_ilp_heuristic.c, 4-5 in this file):
 *   1. parallel edges are merged (their weights add), self loops are constants;
 *   2. the edge graph is split into connected components; each is solved on its
 *      own with its lowest node fixed to 0 (a component's global sign is free),
 *      isolated nodes get 0;
 *   3. a heuristic incumbent for the whole graph, always: maximum spanning tree
 *      on the confidence |c_e| (Kruskal), flips propagated along it, then local
 *      search with subtree flips (all subtrees of the tree scored at once via
 *      LCAs), single-node flips (best gain first) and greedily grown connected
 *      cluster flips; then up to 16 restarts from random spanning trees, the
 *      best per component kept. It is exact on trees and on components whose
 *      edges can all be satisfied at once; those never reach lp_solve;
 *   4. every other component goes to lp_solve: binary o_i and y_e, all four XOR
 *      inequalities per edge, and the triangle inequalities of every 3-cycle
 *      (y_ab <= y_ac + y_bc and rotations, y_ab + y_ac + y_bc <= 2). Measured
 *      here: the XOR rows alone leave lp_solve slow and far from the
 *      optimum, while the triangle rows make the relaxation nearly integral.
 *      Where the relaxation is still fractional, violated odd-cycle inequalities
 *      (found by shortest paths in the doubled "parity" graph, Barahona &
 *      Mahjoub 1986) are added as cutting planes before branch and bound;
 *   5. the better of lp_solve's answer and the incumbent is kept per component;
 *      a relaxation bound the incumbent reaches proves it optimal directly.
 *
 * Inputs: number of blocks, edges with omega(0,0) and omega(0,1), a time limit,
 * an optional progress callback (wired to lp_solve's abort hook).
 * Outputs: flip per block; objective recomputed from the flips (the LP value is
 * not trusted), whether optimality was proven, rows given to lp_solve, cuts,
 * components where the incumbent beat lp_solve, wall time.
 * Cost: heuristic per start O(m log m + passes * (moves * (n + m) + seeds * L *
 * frontier)) with cluster size L <= 48 (~0.01 s for 200 blocks);
 * triangle enumeration O(sum_e min-degree) by intersecting sorted neighbour
 * lists; lp_solve is exponential in the worst case, bounded by the time limit.
 * Failure modes: bad arguments (INVALID_ARGUMENT naming the edge),
 * allocation failure (OUT_OF_MEMORY), cancellation (CANCELLED). A time-out or an
 * lp_solve failure is not an error: the incumbent is used and optimal = 0.
 *
 * This is the only file of the project that includes lp_lib.h (it defines TRUE,
 * FALSE, LE, GE, ... as macros); the graph and the heuristic, which need none
 * of lp_solve, live in their own files and share dacpo_ilp_internal.h.
 */
#include "dacpo_ilp_internal.h"

#include <limits.h>
#include <lp_lib.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Rounds of odd-cycle separation on the LP relaxation before branch and bound. */
#define ILP_CUT_ROUNDS 20
/* A relaxation value farther than this from 0 and 1 is fractional. */
#define ILP_FRAC_EPS 1e-6
/* Minimum violation of a cut worth adding. */
#define ILP_CUT_EPS 1e-4
/* Minimum time between two progress calls from inside lp_solve (seconds). */
#define ILP_PROGRESS_PERIOD 0.02

/* ---------------------------------------------------------------------------
 * lp_solve
 * ------------------------------------------------------------------------- */

typedef struct ilp_abort {
  const dacpo_progress* progress;
  double deadline;
  double fraction;
  double last_call;
  int cancelled;
  int timed_out;
} ilp_abort;

/* lp_solve's abort hook: the time limit in fractions of a second (set_timeout
 * only takes whole seconds) and the caller's cancel request. */
static int __WINAPI
ilp_abort_cb(lprec* lp, void* user)
{
  (void)lp;
  ilp_abort* ab = (ilp_abort*)user;
  /* lp_solve may poll again before it unwinds: the answer stays TRUE and the
   * caller's callback is not asked twice */
  if (ab->cancelled || ab->timed_out)
    return TRUE;
  double now = dacpo_now();
  if (now >= ab->deadline) {
    ab->timed_out = 1;
    return TRUE;
  }
  if (ab->progress && ab->progress->fn && now - ab->last_call >= ILP_PROGRESS_PERIOD) {
    ab->last_call = now;
    if (ab->progress->fn(ab->progress->user, DACPO_STAGE_ILP, ab->fraction) != 0) {
      ab->cancelled = 1;
      return TRUE;
    }
  }
  return FALSE;
}

/* Per-solve scratch, sized for the whole graph once. */
typedef struct ilp_lp_ws {
  int32_t* loc;  /* node -> local index in its component */
  int32_t* ecol; /* merged edge -> local edge index in its component */
  double* vars;  /* lp_solve variables */
  /* odd-cycle separation on the doubled graph (2 copies of each node) */
  double* dist;
  int32_t* pred; /* predecessor adjacency entry * 2 + parity of the predecessor */
  int32_t* heap;
  int32_t* heap_pos;
  uint8_t* mark;
  int32_t* cyc_e;
  uint64_t* cut_key; /* keys of the cuts added in the current round */
  double* row;
  int* col;
} ilp_lp_ws;

/* Adds one row. add_constraintex may reorder the arrays it is given, so the
 * caller refills them before every call. */
static int
ilp_add_row(
    lprec* lp, int count, double* row, int* col, int type, double rhs, size_t* rows)
{
  if (!add_constraintex(lp, count, row, col, type, rhs))
    return 0;
  ++*rows;
  return 1;
}

/* The four XOR rows of edge column ye between node columns ca, cb. */
static int
ilp_add_xor_rows(lprec* lp, int ye, int ca, int cb, size_t* rows)
{
  double r[3];
  int c[3];
  static const double sign[4][3] = {{1, -1, 1}, {1, 1, -1}, {1, -1, -1}, {1, 1, 1}};
  static const int type[4] = {GE, GE, LE, LE};
  static const double rhs[4] = {0, 0, 0, 2};
  /* y >= o_a - o_b, y >= o_b - o_a, y <= o_a + o_b, y <= 2 - o_a - o_b */
  for (int k = 0; k < 4; ++k) {
    r[0] = sign[k][0];
    r[1] = sign[k][1];
    r[2] = sign[k][2];
    c[0] = ye;
    c[1] = ca;
    c[2] = cb;
    if (!ilp_add_row(lp, 3, r, c, type[k], rhs[k], rows))
      return 0;
  }
  return 1;
}

/* The four triangle rows of edge columns y1, y2, y3 of one 3-cycle. */
static int
ilp_add_triangle_rows(lprec* lp, int y1, int y2, int y3, size_t* rows)
{
  double r[3];
  int c[3];
  static const double sign[4][3] = {{1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, 1, 1}};
  static const double rhs[4] = {0, 0, 0, 2};
  for (int k = 0; k < 4; ++k) {
    r[0] = sign[k][0];
    r[1] = sign[k][1];
    r[2] = sign[k][2];
    c[0] = y1;
    c[1] = y2;
    c[2] = y3;
    if (!ilp_add_row(lp, 3, r, c, LE, rhs[k], rows))
      return 0;
  }
  return 1;
}

static void
ilp_heap_up(int32_t* heap, int32_t* pos, const double* key, size_t i)
{
  int32_t v = heap[i];
  while (i > 0) {
    size_t p = (i - 1) / 2;
    if (key[heap[p]] <= key[v])
      break;
    heap[i] = heap[p];
    pos[heap[i]] = (int32_t)i;
    i = p;
  }
  heap[i] = v;
  pos[v] = (int32_t)i;
}

static void
ilp_heap_down(int32_t* heap, int32_t* pos, const double* key, size_t size, size_t i)
{
  int32_t v = heap[i];
  for (;;) {
    size_t l = 2 * i + 1;
    if (l >= size)
      break;
    size_t r = l + 1;
    size_t s = (r < size && key[heap[r]] < key[heap[l]]) ? r : l;
    if (key[heap[s]] >= key[v])
      break;
    heap[i] = heap[s];
    pos[heap[i]] = (int32_t)i;
    i = s;
  }
  heap[i] = v;
  pos[v] = (int32_t)i;
}

/* Dijkstra over the doubled local nodes 2 * loc + parity of component nodes
 * n0.., from src = (s, 0); stops at dst = (s, 1) or once every distance left is
 * >= 1 (no violated inequality beyond). y: edge values, local edge order. */
static void
ilp_parity_dijkstra(const dacpo_ilp_graph* g,
                    size_t n0,
                    size_t nn,
                    ilp_lp_ws* w,
                    const double* y,
                    int32_t src)
{
  int32_t dst = src + 1;
  for (size_t i = 0; i < 2 * nn; ++i) {
    w->dist[i] = INFINITY;
    w->heap_pos[i] = -1;
  }
  size_t hs = 0;
  w->dist[src] = 0.0;
  w->pred[src] = -1;
  w->heap[hs++] = src;
  w->heap_pos[src] = 0;
  while (hs > 0) {
    int32_t x = w->heap[0];
    w->heap_pos[x] = -2; /* settled */
    w->heap[0] = w->heap[--hs];
    if (hs > 0) {
      w->heap_pos[w->heap[0]] = 0;
      ilp_heap_down(w->heap, w->heap_pos, w->dist, hs, 0);
    }
    if (x == dst || w->dist[x] >= 1.0 - ILP_CUT_EPS)
      break;
    int32_t v = g->comp_nodes[n0 + (size_t)(x / 2)];
    int par = x & 1;
    for (size_t q = g->adj_start[v]; q < g->adj_start[v + 1]; ++q) {
      int32_t u = g->adj_node[q];
      double ye = y[w->ecol[g->adj_edge[q]]];
      ye = ye < 0.0 ? 0.0 : (ye > 1.0 ? 1.0 : ye);
      for (int sw = 0; sw < 2; ++sw) {
        int32_t z = 2 * w->loc[u] + (par ^ sw);
        if (w->heap_pos[z] == -2)
          continue;
        double d = w->dist[x] + (sw ? 1.0 - ye : ye);
        if (d < w->dist[z]) {
          w->dist[z] = d;
          w->pred[z] = (int32_t)(2 * q) + par;
          if (w->heap_pos[z] < 0) {
            w->heap[hs] = z;
            w->heap_pos[z] = (int32_t)hs;
            ++hs;
          }
          ilp_heap_up(w->heap, w->heap_pos, w->dist, (size_t)w->heap_pos[z]);
        }
      }
    }
  }
}

/* Walks the shortest path from (s, 1) back to (s, 0) into w->cyc_e (edge + 1,
 * negated where the parity switches). Sets *len and *nf (switching edges).
 * Returns 0 as soon as a node repeats: only simple cycles are kept. */
static int
ilp_walk_cycle(const dacpo_ilp_graph* g,
               size_t n0,
               ilp_lp_ws* w,
               int32_t s,
               size_t* len,
               size_t* nf)
{
  int32_t src = 2 * w->loc[s], dst = src + 1;
  *len = 0;
  *nf = 0;
  int simple = 1;
  int32_t x = dst;
  while (x != src && simple) {
    int32_t pq = w->pred[x];
    size_t q = (size_t)(pq / 2);
    int32_t ppar = pq & 1;
    int32_t e = g->adj_edge[q];
    /* q is in the predecessor's list: the predecessor is e's other end */
    int32_t cur = g->comp_nodes[n0 + (size_t)(x / 2)];
    int32_t owner = g->ea[e] == cur ? g->eb[e] : g->ea[e];
    if (w->mark[w->loc[owner]] && owner != s)
      simple = 0;
    w->mark[w->loc[owner]] = 1;
    int sw = (x & 1) != ppar;
    w->cyc_e[(*len)++] = sw ? -(e + 1) : (e + 1);
    *nf += (size_t)sw;
    x = 2 * w->loc[owner] + ppar;
  }
  /* clear marks along the walked part */
  for (size_t i = 0; i < *len; ++i) {
    int32_t e = w->cyc_e[i] > 0 ? w->cyc_e[i] - 1 : -w->cyc_e[i] - 1;
    w->mark[w->loc[g->ea[e]]] = 0;
    w->mark[w->loc[g->eb[e]]] = 0;
  }
  return simple;
}

/* Several sources find the same cycle: an order-free key drops repeats. */
static uint64_t
ilp_cycle_key(const int32_t* cyc_e, size_t len)
{
  uint64_t key = (uint64_t)len * 0x9e3779b97f4a7c15ull;
  for (size_t i = 0; i < len; ++i) {
    uint64_t z = (uint64_t)(int64_t)cyc_e[i] * 0xbf58476d1ce4e5b9ull;
    z ^= z >> 31;
    key += z * 0x94d049bb133111ebull;
  }
  return key;
}

/* Odd-cycle separation for one component (Barahona & Mahjoub): every cycle C
 * and odd F subset of C give  sum_{F} (1 - y_e) + sum_{C \ F} y_e >= 1.  In the
 * doubled graph, an edge keeps the parity with length y_e and switches it with
 * length 1 - y_e; a path from (s,0) to (s,1) shorter than 1 is a violated
 * inequality. Only simple cycles of length >= 4 are added (triangles are rows
 * already). Returns the number of cuts added, or -1 if lp_solve refused a row. */
static long
ilp_separate(const dacpo_ilp_graph* g,
             size_t ci,
             lprec* lp,
             ilp_lp_ws* w,
             int nc,
             size_t* rows,
             size_t max_cuts,
             double deadline)
{
  size_t n0 = g->comp_start[ci], n1 = g->comp_start[ci + 1];
  size_t nn = n1 - n0;
  const double* y = w->vars + nc; /* edge values, local edge order */
  long added = 0;
  for (size_t si = n0; si < n1 && (size_t)added < max_cuts; ++si) {
    if (dacpo_now() >= deadline)
      break;
    int32_t s = g->comp_nodes[si];
    int32_t src = 2 * w->loc[s], dst = src + 1;
    ilp_parity_dijkstra(g, n0, nn, w, y, src);
    if (!(w->dist[dst] < 1.0 - ILP_CUT_EPS))
      continue;
    size_t len, nf;
    int simple = ilp_walk_cycle(g, n0, w, s, &len, &nf);
    if (!simple || len < 4 || (nf & 1u) == 0)
      continue;
    uint64_t key = ilp_cycle_key(w->cyc_e, len);
    int seen = 0;
    for (long i = 0; i < added && !seen; ++i)
      seen = w->cut_key[i] == key;
    if (seen)
      continue;
    w->cut_key[added] = key;
    /* sum_{F} y_e - sum_{C \ F} y_e <= |F| - 1 */
    for (size_t i = 0; i < len; ++i) {
      int32_t e = w->cyc_e[i] > 0 ? w->cyc_e[i] - 1 : -w->cyc_e[i] - 1;
      w->row[i] = w->cyc_e[i] < 0 ? 1.0 : -1.0;
      w->col[i] = nc + 1 + w->ecol[e];
    }
    if (!ilp_add_row(lp, (int)len, w->row, w->col, LE, (double)nf - 1.0, rows))
      return -1;
    ++added;
  }
  return added;
}

/* Reads o for the component from lp_solve's variables (rounded; the fixed node
 * stays 0). Returns 1 if every node and edge value was integral. */
static int
ilp_read_flips(
    const dacpo_ilp_graph* g, size_t ci, const double* vars, int ncols, uint8_t* o)
{
  int integral = 1;
  for (int j = 0; j < ncols; ++j)
    if (fabs(vars[j] - floor(vars[j] + 0.5)) > ILP_FRAC_EPS)
      integral = 0;
  size_t n0 = g->comp_start[ci];
  for (size_t q = n0; q < g->comp_start[ci + 1]; ++q)
    o[g->comp_nodes[q]] = vars[q - n0] > 0.5;
  return integral;
}

typedef struct ilp_comp_out {
  int have;              /* o holds an assignment from lp_solve */
  int proven;            /* ... which lp_solve proved optimal */
  int incumbent_optimal; /* the relaxation's bound equals the incumbent's value */
} ilp_comp_out;

/* lp_solve's objective: max sum c_e y_e over the component's edges (columns
 * nc+1..nc+mc), normalized to max |c| = 1. Returns lp_solve's ok. */
static int
ilp_lp_objective(
    const dacpo_ilp_graph* g, size_t ci, size_t nc, lprec* lp, ilp_lp_ws* w)
{
  size_t e0 = g->cedge_start[ci], mc = g->cedge_start[ci + 1] - e0;
  double cmax = 0.0;
  for (size_t k = 0; k < mc; ++k)
    cmax = fmax(cmax, fabs(g->c[g->cedges[e0 + k]]));
  if (!(cmax > 0.0))
    cmax = 1.0;
  for (size_t k = 0; k < mc; ++k) {
    w->row[k] = g->c[g->cedges[e0 + k]] / cmax;
    w->col[k] = (int)(nc + 1 + k);
  }
  return set_obj_fnex(lp, (int)mc, w->row, w->col);
}

/* The four XOR rows of every edge of the component. Returns lp_solve's ok. */
static int
ilp_lp_xor_rows(const dacpo_ilp_graph* g,
                size_t ci,
                size_t nc,
                lprec* lp,
                const ilp_lp_ws* w,
                size_t* rows)
{
  size_t e0 = g->cedge_start[ci], mc = g->cedge_start[ci + 1] - e0;
  int ok = 1;
  for (size_t k = 0; k < mc && ok; ++k) {
    int32_t e = g->cedges[e0 + k];
    int ye = (int)(nc + 1 + k);
    ok = ilp_add_xor_rows(lp, ye, 1 + w->loc[g->ea[e]], 1 + w->loc[g->eb[e]], rows);
  }
  return ok;
}

/* Triangles a < b < x: intersect the ascending neighbour lists of a and b
 * above b, so each 3-cycle is found once, from its lowest edge. Returns 0 if
 * lp_solve refused a row or the deadline passed (then ab->timed_out is set). */
static int
ilp_lp_triangle_rows(const dacpo_ilp_graph* g,
                     size_t ci,
                     size_t nc,
                     lprec* lp,
                     const ilp_lp_ws* w,
                     ilp_abort* ab,
                     size_t* rows)
{
  size_t e0 = g->cedge_start[ci], mc = g->cedge_start[ci + 1] - e0;
  int ok = 1;
  for (size_t k = 0; k < mc && ok; ++k) {
    /* building is not interruptible by lp_solve: watch the clock here */
    if ((k & 255u) == 0 && dacpo_now() >= ab->deadline) {
      ab->timed_out = 1;
      ok = 0;
      break;
    }
    int32_t e = g->cedges[e0 + k];
    int32_t a = g->ea[e], b = g->eb[e];
    size_t pa = g->adj_start[a], qa = g->adj_start[a + 1];
    size_t pb = g->adj_start[b], qb = g->adj_start[b + 1];
    while (pa < qa && g->adj_node[pa] <= b)
      ++pa;
    while (pb < qb && g->adj_node[pb] <= b)
      ++pb;
    while (pa < qa && pb < qb && ok) {
      int32_t xa = g->adj_node[pa], xb = g->adj_node[pb];
      if (xa < xb)
        ++pa;
      else if (xb < xa)
        ++pb;
      else {
        ok = ilp_add_triangle_rows(lp,
                                   (int)(nc + 1 + k),
                                   (int)nc + 1 + w->ecol[g->adj_edge[pa]],
                                   (int)nc + 1 + w->ecol[g->adj_edge[pb]],
                                   rows);
        ++pa;
        ++pb;
      }
    }
  }
  return ok;
}

/* Cutting planes on the relaxation while it is fractional: each round adds
 * the violated odd-cycle inequalities and re-solves (warm-started). An
 * integral relaxation optimum is optimal for Eq. 8 (returns 1, o holds it); a
 * relaxation bound the incumbent reaches proves the incumbent optimal
 * (out->incumbent_optimal). *ok drops to 0 if lp_solve refused a cut. */
static int
ilp_cut_rounds(const dacpo_ilp_graph* g,
               size_t ci,
               lprec* lp,
               ilp_lp_ws* w,
               ilp_abort* ab,
               double incumbent,
               double tol,
               uint8_t* o,
               ilp_comp_out* out,
               dacpo_ilp_result* result,
               size_t* rows,
               int* ok)
{
  size_t nc = g->comp_start[ci + 1] - g->comp_start[ci];
  size_t e0 = g->cedge_start[ci], mc = g->cedge_start[ci + 1] - e0;
  int ncols = (int)(nc + mc);
  double prev_bound = INFINITY;
  for (int round = 0; round < ILP_CUT_ROUNDS; ++round) {
    double remaining = ab->deadline - dacpo_now();
    if (!(remaining > 0.0))
      break;
    set_timeout(lp, isfinite(remaining) ? (long)ceil(remaining) : 0);
    int ret = solve(lp);
    if (ab->cancelled || ret != OPTIMAL || !get_variables(lp, w->vars))
      break;
    if (ilp_read_flips(g, ci, w->vars, ncols, o))
      return 1;
    double bound = 0.0;
    for (size_t k = 0; k < mc; ++k)
      bound += g->c[g->cedges[e0 + k]] * w->vars[nc + k];
    if (incumbent >= bound - tol) {
      out->incumbent_optimal = 1;
      break;
    }
    if (prev_bound - bound < 1e-6 * (1.0 + fabs(bound)))
      break; /* tailing off: leave the rest to branch and bound */
    prev_bound = bound;
    long cuts = ilp_separate(g, ci, lp, w, (int)nc, rows, 2 * nc + 16, ab->deadline);
    if (cuts < 0) {
      *ok = 0;
      break;
    }
    if (cuts == 0)
      break;
    result->cuts_added += (size_t)cuts;
  }
  return 0;
}

/* Branch and bound on the strengthened model; on a usable answer o holds it
 * and out->have / out->proven are set. */
static void
ilp_branch_and_bound(const dacpo_ilp_graph* g,
                     size_t ci,
                     lprec* lp,
                     ilp_lp_ws* w,
                     const ilp_abort* ab,
                     int ncols,
                     uint8_t* o,
                     ilp_comp_out* out)
{
  for (int j = 1; j <= ncols; ++j)
    set_binary(lp, j, TRUE);
  set_upbo(lp, 1, 0.0);
  double remaining = ab->deadline - dacpo_now();
  set_timeout(lp, isfinite(remaining) ? (long)ceil(remaining) : 0);
  int ret = solve(lp);
  if (ab->cancelled)
    return;
  /* after an abort or time-out, lp_solve's variables are its best improved
   * solution, if it found any */
  int usable = ret == OPTIMAL || ret == SUBOPTIMAL || ret == PRESOLVED ||
               ((ret == USERABORT || ret == TIMEOUT || ret == FEASFOUND) &&
                get_solutioncount(lp) > 0);
  if (usable && get_variables(lp, w->vars)) {
    ilp_read_flips(g, ci, w->vars, ncols, o);
    out->have = 1;
    out->proven = ret == OPTIMAL;
  }
}

/* Solves one component with lp_solve; writes its flips into o. incumbent is
 * the heuristic's value of the component (sum of c_e y_e), tol the tolerance
 * of value comparisons. */
static dacpo_status
ilp_lp_component(const dacpo_ilp_graph* g,
                 size_t ci,
                 ilp_lp_ws* w,
                 ilp_abort* ab,
                 double incumbent,
                 double tol,
                 uint8_t* o,
                 ilp_comp_out* out,
                 dacpo_ilp_result* result,
                 dacpo_err* err)
{
  memset(out, 0, sizeof(*out));
  size_t n0 = g->comp_start[ci], n1 = g->comp_start[ci + 1];
  size_t e0 = g->cedge_start[ci], e1 = g->cedge_start[ci + 1];
  size_t nc = n1 - n0, mc = e1 - e0;
  if (nc + mc > (size_t)INT_MAX - 1)
    return DACPO_OK; /* too big for lp_solve's int columns: the incumbent stands */
  for (size_t q = n0; q < n1; ++q)
    w->loc[g->comp_nodes[q]] = (int32_t)(q - n0);
  for (size_t q = e0; q < e1; ++q)
    w->ecol[g->cedges[q]] = (int32_t)(q - e0);
  int ncols = (int)(nc + mc);
  /* columns: 1..nc nodes o_i (local order), nc+1..nc+mc edges y_e */
  lprec* lp = make_lp(0, ncols);
  if (!lp)
    return DACPO_OK; /* lp_solve out of memory: the incumbent stands */
  set_outputfile(lp, "");
  set_verbose(lp, NEUTRAL);
  /* The constraint matrix is all +-1, so lp_solve's scaling only costs time
   * (measured: about 2x faster without); the objective is normalized to
   * max |c| = 1 instead, so its tolerances mean the same for any weights.
   * Dantzig pricing measured at least as fast as the default Devex here. */
  set_scaling(lp, SCALE_NONE);
  set_pivoting(lp, PRICER_DANTZIG | PRICE_ADAPTIVE);
  int ok = ilp_lp_objective(g, ci, nc, lp, w);
  set_maxim(lp);
  set_add_rowmode(lp, TRUE); /* after the objective, as lp_solve requires */
  size_t rows = 0;
  ok = ok && ilp_lp_xor_rows(g, ci, nc, lp, w, &rows);
  ok = ok && ilp_lp_triangle_rows(g, ci, nc, lp, w, ab, &rows);
  set_add_rowmode(lp, FALSE);
  ok = ok && set_upbo(lp, 1, 0.0); /* the lowest node is the reference */
  if (!ok) { /* out of time, or lp_solve refused a row: the incumbent stands */
    result->constraints += rows;
    delete_lp(lp);
    return DACPO_OK;
  }
  put_abortfunc(lp, ilp_abort_cb, ab);

  if (ilp_cut_rounds(g, ci, lp, w, ab, incumbent, tol, o, out, result, &rows, &ok)) {
    out->have = 1;
    out->proven = 1;
  }
  else if (ok && !ab->cancelled && !out->incumbent_optimal &&
           ab->deadline - dacpo_now() > 0.0)
    ilp_branch_and_bound(g, ci, lp, w, ab, ncols, o, out);
  result->constraints += rows;
  delete_lp(lp);
  if (ab->cancelled)
    return dacpo_err_set(
        err, DACPO_ERR_CANCELLED, "ilp: cancelled by the progress callback");
  return DACPO_OK;
}

/* ---------------------------------------------------------------------------
 * Entry point
 * ------------------------------------------------------------------------- */

static dacpo_status
ilp_check(size_t num_nodes,
          size_t num_edges,
          const dacpo_ilp_edge* edges,
          double time_limit,
          const uint8_t* flip_out,
          const dacpo_ilp_result* result,
          dacpo_err* err)
{
  DACPO_CHECK(err, result != NULL, DACPO_ERR_INVALID_ARGUMENT, "ilp: NULL result");
  DACPO_CHECK(err,
              num_nodes == 0 || flip_out != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "ilp: NULL flip_out for %zu nodes",
              num_nodes);
  DACPO_CHECK(err,
              num_edges == 0 || edges != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "ilp: NULL edges for %zu edges",
              num_edges);
  DACPO_CHECK(err,
              num_nodes <= (size_t)INT32_MAX / 4 && num_edges <= (size_t)INT32_MAX / 4,
              DACPO_ERR_INVALID_ARGUMENT,
              "ilp: %zu nodes / %zu edges exceed int32 indices",
              num_nodes,
              num_edges);
  DACPO_CHECK(err,
              time_limit > 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "ilp: time_limit must be > 0 (got %g)",
              time_limit);
  for (size_t i = 0; i < num_edges; ++i) {
    const dacpo_ilp_edge* e = &edges[i];
    DACPO_CHECK(err,
                e->a >= 0 && (size_t)e->a < num_nodes && e->b >= 0 &&
                    (size_t)e->b < num_nodes,
                DACPO_ERR_INVALID_ARGUMENT,
                "ilp: edge %zu joins nodes %ld and %ld, outside [0, %zu)",
                i,
                (long)e->a,
                (long)e->b,
                num_nodes);
    DACPO_CHECK(err,
                isfinite(e->w_same) && isfinite(e->w_diff),
                DACPO_ERR_INVALID_ARGUMENT,
                "ilp: edge %zu has weights %g / %g",
                i,
                e->w_same,
                e->w_diff);
  }
  return DACPO_OK;
}

static int
ilp_progress(const dacpo_progress* progress, double fraction)
{
  return progress && progress->fn &&
         progress->fn(progress->user, DACPO_STAGE_ILP, fraction) != 0;
}

/* Allocates the lp_solve workspace for n nodes and m merged edges; returns 0
 * on allocation failure (what was allocated is left for ilp_ws_free). */
static int
ilp_ws_alloc(ilp_lp_ws* w, size_t n, size_t m)
{
  memset(w, 0, sizeof(*w));
  size_t nmax = n + m + 1;
  w->loc = dacpo_malloc_array(n + 1, sizeof(int32_t));
  w->ecol = dacpo_malloc_array(m + 1, sizeof(int32_t));
  w->vars = dacpo_calloc_array(nmax, sizeof(double));
  w->dist = dacpo_malloc_array(2 * n + 2, sizeof(double));
  w->pred = dacpo_malloc_array(2 * n + 2, sizeof(int32_t));
  w->heap = dacpo_malloc_array(2 * n + 2, sizeof(int32_t));
  w->heap_pos = dacpo_malloc_array(2 * n + 2, sizeof(int32_t));
  w->mark = dacpo_calloc_array(n + 1, 1);
  w->cyc_e = dacpo_malloc_array(2 * n + 2, sizeof(int32_t));
  w->cut_key = dacpo_malloc_array(2 * n + 16, sizeof(uint64_t));
  w->row = dacpo_malloc_array(nmax + 2 * n, sizeof(double));
  w->col = dacpo_malloc_array(nmax + 2 * n, sizeof(int));
  return w->loc && w->ecol && w->vars && w->dist && w->pred && w->heap && w->heap_pos &&
         w->mark && w->cyc_e && w->cut_key && w->row && w->col;
}

static void
ilp_ws_free(ilp_lp_ws* w)
{
  free(w->loc);
  free(w->ecol);
  free(w->vars);
  free(w->dist);
  free(w->pred);
  free(w->heap);
  free(w->heap_pos);
  free(w->mark);
  free(w->cyc_e);
  free(w->cut_key);
  free(w->row);
  free(w->col);
}

/* Gives every component the heuristic leaves frustrated to lp_solve and keeps
 * the better of the two answers in o. */
static dacpo_status
ilp_solve_components(const dacpo_ilp_graph* g,
                     ilp_lp_ws* w,
                     ilp_abort* ab,
                     double tol,
                     uint8_t* o,
                     uint8_t* o_lp,
                     dacpo_ilp_result* result,
                     dacpo_err* err)
{
  for (size_t ci = 0; ci < g->ncomp; ++ci) {
    size_t nc = g->comp_start[ci + 1] - g->comp_start[ci];
    size_t mc = g->cedge_start[ci + 1] - g->cedge_start[ci];
    if (mc + 1 <= nc)
      continue; /* single node or tree: the spanning-tree propagation is exact */
    double h = dacpo_ilp_comp_value(g, ci, o);
    double ub = 0.0; /* every edge at its preferred value */
    for (size_t q = g->cedge_start[ci]; q < g->cedge_start[ci + 1]; ++q)
      ub += g->c[g->cedges[q]] > 0.0 ? g->c[g->cedges[q]] : 0.0;
    if (h >= ub - tol)
      continue; /* nothing is frustrated: the incumbent reaches the bound */
    ab->fraction = (double)g->comp_start[ci] / (double)g->n;
    if (ilp_progress(ab->progress, ab->fraction))
      return dacpo_err_set(
          err, DACPO_ERR_CANCELLED, "ilp: cancelled by the progress callback");
    if (!(ab->deadline - dacpo_now() > 0.0)) {
      result->optimal = 0; /* out of time: the incumbent stands */
      result->heuristic_wins++;
      continue;
    }
    ilp_comp_out out;
    DACPO_TRY(ilp_lp_component(g, ci, w, ab, h, tol, o_lp, &out, result, err));
    if (out.incumbent_optimal)
      continue;
    double l = out.have ? dacpo_ilp_comp_value(g, ci, o_lp) : -INFINITY;
    if (out.have && l >= h) {
      for (size_t q = g->comp_start[ci]; q < g->comp_start[ci + 1]; ++q)
        o[g->comp_nodes[q]] = o_lp[g->comp_nodes[q]];
    }
    else
      result->heuristic_wins++;
    /* A "proven" optimum that the incumbent beats was a numerical accident. */
    if (!out.have || !out.proven || h > l + tol)
      result->optimal = 0;
  }
  return DACPO_OK;
}

dacpo_status
dacpo_ilp_solve(size_t num_nodes,
                size_t num_edges,
                const dacpo_ilp_edge* edges,
                double time_limit,
                const dacpo_progress* progress,
                uint8_t* flip_out,
                dacpo_ilp_result* result,
                dacpo_err* err)
{
  double t0 = dacpo_now();
  DACPO_TRY(ilp_check(num_nodes, num_edges, edges, time_limit, flip_out, result, err));
  memset(result, 0, sizeof(*result));
  result->optimal = 1;
  if (ilp_progress(progress, 0.0))
    return dacpo_err_set(
        err, DACPO_ERR_CANCELLED, "ilp: cancelled by the progress callback");

  dacpo_ilp_graph g;
  DACPO_TRY(dacpo_ilp_graph_build(num_nodes, num_edges, edges, &g, err));
  dacpo_status st = DACPO_OK;
  uint8_t* o = dacpo_calloc_array(num_nodes, 1);
  uint8_t* o_lp = dacpo_calloc_array(num_nodes, 1);
  ilp_lp_ws w;
  if (!ilp_ws_alloc(&w, num_nodes, g.m) || !o || !o_lp) {
    st = DACPO_OOM(err);
    goto done;
  }

  /* Restarts of the heuristic may use a quarter of the time limit. */
  st = dacpo_ilp_heuristic(&g, t0 + 0.25 * time_limit, o, err);
  if (st != DACPO_OK)
    goto done;

  double scale = 0.0;
  for (size_t k = 0; k < g.m; ++k)
    scale += fabs(g.c[k]);
  double tol = 1e-9 * (1.0 + scale);
  ilp_abort ab;
  memset(&ab, 0, sizeof(ab));
  ab.progress = progress;
  ab.deadline = t0 + time_limit; /* +inf: no limit */
  ab.last_call = -INFINITY;
  st = ilp_solve_components(&g, &w, &ab, tol, o, o_lp, result, err);
  if (st != DACPO_OK)
    goto done;
  if (ilp_progress(progress, 1.0)) {
    st = dacpo_err_set(
        err, DACPO_ERR_CANCELLED, "ilp: cancelled by the progress callback");
    goto done;
  }

  /* Eq. 8 at the returned flips, from the caller's own edges. */
  double obj = 0.0;
  for (size_t i = 0; i < num_edges; ++i)
    obj += o[edges[i].a] == o[edges[i].b] ? edges[i].w_same : edges[i].w_diff;
  result->objective = obj;
  if (num_nodes > 0)
    memcpy(flip_out, o, num_nodes);

done:
  result->seconds = dacpo_now() - t0;
  free(o);
  free(o_lp);
  ilp_ws_free(&w);
  dacpo_ilp_graph_free(&g);
  return st;
}
