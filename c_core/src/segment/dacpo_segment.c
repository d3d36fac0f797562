/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 1: block segmentation (paper §4.1).
 *
 * The paper cuts the cloud into about 200 spatially connected blocks, each small
 * enough for the local dipole/iPSR stages and large enough to carry a reliable
 * orientation. Here:
 *   1. each connected component c gets B_c = round(B * |c| / n) blocks, clamped to
 *      [1, max(1, |c| / 8)], so disconnected parts never share a block;
 *   2. the component's points are split kd-style into B_c subsets of (nearly)
 *      equal count: median splits on the widest bounding-box axis, a subset that
 *      must become m blocks is cut in the ratio floor(m/2) : ceil(m/2)
 *      (quickselect on an index array, O(|c| log B_c));
 *   3. every subset gives one seed: its point nearest the subset centroid;
 *   4. one multi-source BFS over the k-NN adjacency, started from all seeds at
 *      once, gives every point the block whose frontier reaches it first, so each
 *      block is connected in the graph by construction (O(n + E)). With crease
 *      axes (dacpo_segment_creased) the fronts advance by shortest paths instead,
 *      a step costing 1 + SEG_CREASE_COST (1 - |a_p . a_q|): about 21 hops across
 *      a right-angled crease, so block borders settle on creases and each block
 *      holds one smooth piece of surface (O(E log n), still connected);
 *   5. the overlap ring of a block (used by iPSR for continuity)
 *      is every point of another block within ring_hops hops of it, found by a
 *      depth-limited BFS per block with a shared visit stamp array (stamp = block
 *      id), so no n-array is cleared per block: O(E + sum ring * degree).
 *
 * Inputs: distinct cloud, symmetric adjacency, component labels.
 * Outputs: dacpo_blocks (block of each point, CSR of own points and ring points,
 * component of each block). Block ids are dense, numbered component by
 * component, within a component in seed order.
 * Failure modes: NULL or inconsistent arguments (INVALID_ARGUMENT naming the bad
 * index), allocation failure (OUT_OF_MEMORY). Points the seeded BFS cannot reach
 * (only if component labels disagree with the adjacency) get blocks of their own
 * grown the same way, so no point is ever left without a block.
 * Deterministic: no dependence on threads; quickselect pivots come from a fixed
 * seed and all keys are made distinct by the point index.
 */
#include "dacpo_segment.h"

#include "dacpo_select.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------
 * Argument checks
 * ------------------------------------------------------------------------- */

static dacpo_status
seg_check_cloud(const dacpo_cloud* cloud,
                const int32_t* component,
                size_t num_components,
                dacpo_blocks* out,
                dacpo_err* err)
{
  DACPO_CHECK(err,
              cloud != NULL && component != NULL && out != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "segment: NULL cloud, component or output");
  DACPO_CHECK(
      err, cloud->n > 0, DACPO_ERR_EMPTY_INPUT, "segment: the cloud has no points");
  DACPO_CHECK(err,
              cloud->n <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "segment: %zu points exceed int32 indices",
              cloud->n);
  DACPO_CHECK(err,
              num_components > 0 && num_components <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "segment: num_components is %zu",
              num_components);
  for (size_t i = 0; i < cloud->n; ++i)
    DACPO_CHECK(err,
                component[i] >= 0 && (size_t)component[i] < num_components,
                DACPO_ERR_INVALID_ARGUMENT,
                "segment: point %zu has component %ld, outside [0, %zu)",
                i,
                (long)component[i],
                num_components);
  return DACPO_OK;
}

static dacpo_status
seg_check_adjacency(const dacpo_adjacency* adj, size_t n, dacpo_err* err)
{
  DACPO_CHECK(err,
              adj != NULL && adj->start != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "segment: NULL adjacency");
  DACPO_CHECK(err,
              adj->n == n,
              DACPO_ERR_INVALID_ARGUMENT,
              "segment: adjacency has %zu points, cloud has %zu",
              adj->n,
              n);
  DACPO_CHECK(err,
              adj->start[0] == 0 && (adj->start[n] == 0 || adj->nbr != NULL),
              DACPO_ERR_INVALID_ARGUMENT,
              "segment: malformed adjacency arrays");
  for (size_t i = 0; i < n; ++i) {
    DACPO_CHECK(err,
                adj->start[i] <= adj->start[i + 1],
                DACPO_ERR_INVALID_ARGUMENT,
                "segment: adjacency row %zu has a decreasing start",
                i);
    for (size_t e = adj->start[i]; e < adj->start[i + 1]; ++e)
      DACPO_CHECK(err,
                  adj->nbr[e] >= 0 && (size_t)adj->nbr[e] < n,
                  DACPO_ERR_INVALID_ARGUMENT,
                  "segment: adjacency row %zu lists point %ld, outside [0, %zu)",
                  i,
                  (long)adj->nbr[e],
                  n);
  }
  return DACPO_OK;
}

/* ---------------------------------------------------------------------------
 * kd-style split into equal-count subsets, one seed per subset
 * ------------------------------------------------------------------------- */

typedef struct seg_splitter {
  dacpo_tree_point* pts; /* the points grouped by component, permuted by the split */
  int32_t* seeds;        /* output, in recursion (left first) order */
  size_t num_seeds;
  dacpo_rng rng; /* quickselect pivots only; fixed seed, so deterministic */
} seg_splitter;

/* The seed of a subset: its point nearest the centroid (ties: lower index), a
 * point well inside the subset so the BFS fronts start evenly spread. */
static int32_t
seg_seed(const seg_splitter* s, size_t lo, size_t hi)
{
  double c[3] = {0.0, 0.0, 0.0};
  for (size_t i = lo; i < hi; ++i)
    for (int a = 0; a < 3; ++a)
      c[a] += s->pts[i].x[a];
  for (int a = 0; a < 3; ++a)
    c[a] /= (double)(hi - lo);
  int32_t best = -1;
  double best_d = INFINITY;
  for (size_t i = lo; i < hi; ++i) {
    const double* p = s->pts[i].x;
    double d = (p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) +
               (p[2] - c[2]) * (p[2] - c[2]);
    if (best < 0 || d < best_d || (d == best_d && s->pts[i].id < best)) {
      best = s->pts[i].id;
      best_d = d;
    }
  }
  return best;
}

/* Splits pts[lo, hi) into m subsets of nearly equal count and appends one seed
 * per subset. Requires hi - lo >= m >= 1. Recursion depth is log2(m). */
static void
seg_split(seg_splitter* s, size_t lo, size_t hi, size_t m)
{
  if (m <= 1) {
    s->seeds[s->num_seeds++] = seg_seed(s, lo, hi);
    return;
  }
  double mn[3] = {INFINITY, INFINITY, INFINITY};
  double mx[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = lo; i < hi; ++i) {
    const double* p = s->pts[i].x;
    for (int a = 0; a < 3; ++a) {
      if (p[a] < mn[a])
        mn[a] = p[a];
      if (p[a] > mx[a])
        mx[a] = p[a];
    }
  }
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (mx[a] - mn[a] > mx[axis] - mn[axis])
      axis = a;
  size_t cnt = hi - lo;
  size_t m1 = m / 2, m2 = m - m1;
  /* counts in the ratio of the block counts, so every final subset has ~cnt/m */
  size_t k = (size_t)floor((double)cnt * (double)m1 / (double)m + 0.5);
  if (k < m1)
    k = m1;
  if (k > cnt - m2)
    k = cnt - m2;
  dacpo_select_points(s->pts, lo, hi, lo + k, axis, &s->rng);
  seg_split(s, lo, lo + k, m1);
  seg_split(s, lo + k, hi, m2);
}

/* ---------------------------------------------------------------------------
 * Output assembly
 * ------------------------------------------------------------------------- */

/* own/own_start from block_of (counting sort over ascending points, so every
 * block's list is ascending). */
static dacpo_status
seg_build_own(size_t n, dacpo_blocks* b, dacpo_err* err)
{
  b->own_start = (size_t*)dacpo_calloc_array(b->num_blocks + 1, sizeof(size_t));
  b->own = (int32_t*)dacpo_malloc_array(n, sizeof(int32_t));
  if (b->own_start == NULL || b->own == NULL)
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i)
    b->own_start[(size_t)b->block_of[i] + 1]++;
  for (size_t k = 0; k < b->num_blocks; ++k)
    b->own_start[k + 1] += b->own_start[k];
  size_t* cur = (size_t*)dacpo_malloc_array(b->num_blocks, sizeof(size_t));
  if (cur == NULL)
    return DACPO_OOM(err);
  memcpy(cur, b->own_start, b->num_blocks * sizeof(size_t));
  for (size_t i = 0; i < n; ++i)
    b->own[cur[b->block_of[i]]++] = (int32_t)i;
  free(cur);
  return DACPO_OK;
}

static int
seg_cmp_i32(const void* a, const void* b)
{
  int32_t x = *(const int32_t*)a, y = *(const int32_t*)b;
  return (x > y) - (x < y);
}

/* The ring of block blk: BFS up to ring_hops hops from its own points into
 * points of the same component, into queue (sorted). Returns its length. */
static size_t
seg_block_ring(const dacpo_adjacency* adj,
               const int32_t* component,
               size_t ring_hops,
               const dacpo_blocks* b,
               size_t blk,
               int32_t* stamp,
               int32_t* queue)
{
  const int32_t tag = (int32_t)blk;
  const int32_t comp = b->component_of_block[blk];
  const int32_t* own = b->own + b->own_start[blk];
  const size_t num_own = b->own_start[blk + 1] - b->own_start[blk];
  for (size_t i = 0; i < num_own; ++i)
    stamp[own[i]] = tag;
  size_t qlen = 0;
  size_t layer_lo = 0, layer_hi = 0; /* queue range of the previous layer */
  for (size_t hop = 1; hop <= ring_hops; ++hop) {
    const int32_t* src = hop == 1 ? own : queue + layer_lo;
    size_t num_src = hop == 1 ? num_own : layer_hi - layer_lo;
    if (num_src == 0)
      break;
    for (size_t i = 0; i < num_src; ++i) {
      int32_t p = src[i];
      for (size_t e = adj->start[p]; e < adj->start[p + 1]; ++e) {
        int32_t q = adj->nbr[e];
        if (stamp[q] != tag && component[q] == comp) {
          stamp[q] = tag;
          queue[qlen++] = q;
        }
      }
    }
    layer_lo = hop == 1 ? 0 : layer_hi;
    layer_hi = qlen;
  }
  qsort(queue, qlen, sizeof(int32_t), seg_cmp_i32);
  return qlen;
}

/* Appends qlen ring points to b->ring (*len used of *cap), doubling the
 * capacity when needed. Returns 0 if it cannot grow. */
static int
seg_append_ring(
    dacpo_blocks* b, const int32_t* ring, size_t qlen, size_t* cap, size_t* len)
{
  if (qlen > *cap - *len) {
    size_t need = *len + qlen;
    size_t new_cap = *cap > SIZE_MAX / 2 ? need : *cap * 2;
    if (new_cap < need)
      new_cap = need;
    int32_t* grown = new_cap > SIZE_MAX / sizeof(int32_t)
                         ? NULL
                         : (int32_t*)realloc(b->ring, new_cap * sizeof(int32_t));
    if (grown == NULL)
      return 0;
    b->ring = grown;
    *cap = new_cap;
  }
  memcpy(b->ring + *len, ring, qlen * sizeof(int32_t));
  *len += qlen;
  return 1;
}

/* Rings: depth-limited BFS from each block's own points into other blocks of the
 * same component. stamp[p] == b marks p as seen for block b; block ids are
 * distinct, so the array is never cleared. The BFS queue only ever holds ring
 * points (the own points are layer 0, read from own[]). */
static dacpo_status
seg_build_rings(const dacpo_adjacency* adj,
                const int32_t* component,
                size_t ring_hops,
                dacpo_blocks* b,
                dacpo_err* err)
{
  size_t n = adj->n;
  dacpo_status st = DACPO_OK;
  int32_t* stamp = NULL;
  int32_t* queue = NULL;
  size_t cap = 0, len = 0;

  b->ring_start = (size_t*)dacpo_calloc_array(b->num_blocks + 1, sizeof(size_t));
  if (b->ring_start == NULL)
    return DACPO_OOM(err);
  if (ring_hops == 0) {
    b->ring = (int32_t*)dacpo_malloc_array(0, sizeof(int32_t));
    return b->ring == NULL ? DACPO_OOM(err) : DACPO_OK;
  }

  stamp = (int32_t*)dacpo_malloc_array(n, sizeof(int32_t));
  queue = (int32_t*)dacpo_malloc_array(n, sizeof(int32_t));
  cap = n / 4 + 64;
  b->ring = (int32_t*)dacpo_malloc_array(cap, sizeof(int32_t));
  if (stamp == NULL || queue == NULL || b->ring == NULL) {
    st = DACPO_OOM(err);
    goto done;
  }
  for (size_t i = 0; i < n; ++i)
    stamp[i] = -1;

  for (size_t blk = 0; blk < b->num_blocks; ++blk) {
    size_t qlen = seg_block_ring(adj, component, ring_hops, b, blk, stamp, queue);
    if (!seg_append_ring(b, queue, qlen, &cap, &len)) {
      st = DACPO_OOM(err);
      goto done;
    }
    b->ring_start[blk + 1] = len;
  }

done:
  free(stamp);
  free(queue);
  return st;
}

/* ---------------------------------------------------------------------------
 * Block growing
 * ------------------------------------------------------------------------- */

/* Multi-source BFS from queue[0, qlen) (already labelled), restricted to each
 * source's component; points take the label of the first front reaching them.
 * Returns the new queue length. */
static size_t
seg_grow(const dacpo_adjacency* adj,
         const int32_t* component,
         int32_t* label,
         int32_t* queue,
         size_t head,
         size_t qlen)
{
  while (head < qlen) {
    int32_t p = queue[head++];
    for (size_t e = adj->start[p]; e < adj->start[p + 1]; ++e) {
      int32_t q = adj->nbr[e];
      if (label[q] < 0 && component[q] == component[p]) {
        label[q] = label[p];
        queue[qlen++] = q;
      }
    }
  }
  return qlen;
}

/* Points grouped by component (counting sort, ascending inside a component):
 * component c holds pts[comp_start[c] .. comp_start[c + 1]). */
static dacpo_status
seg_group_by_component(const dacpo_cloud* cloud,
                       const int32_t* component,
                       size_t num_components,
                       size_t* comp_start,
                       dacpo_tree_point* pts,
                       dacpo_err* err)
{
  const size_t n = cloud->n;
  for (size_t i = 0; i < n; ++i)
    comp_start[(size_t)component[i] + 1]++;
  for (size_t c = 0; c < num_components; ++c)
    comp_start[c + 1] += comp_start[c];
  size_t* cur = (size_t*)dacpo_malloc_array(num_components, sizeof(size_t));
  if (cur == NULL)
    return DACPO_OOM(err);
  memcpy(cur, comp_start, num_components * sizeof(size_t));
  for (size_t i = 0; i < n; ++i) {
    const int32_t id = (int32_t)i;
    dacpo_tree_points_fill(&pts[cur[component[i]]++], cloud->xyz, &id, 1);
  }
  free(cur);

  return DACPO_OK;
}

/* Blocks per component: proportional to its size, at least 1, at most |c|/8
 * (blocks of a handful of points carry no reliable orientation). Returns the
 * total. */
static size_t
seg_blocks_per_component(const size_t* comp_start,
                         size_t num_components,
                         size_t n,
                         size_t target_blocks,
                         size_t* nblk)
{
  size_t total = 0;
  for (size_t c = 0; c < num_components; ++c) {
    size_t sz = comp_start[c + 1] - comp_start[c];
    if (sz == 0)
      continue;
    size_t want = 1;
    if (target_blocks > 0) {
      double w = floor((double)target_blocks * (double)sz / (double)n + 0.5);
      want = w < 1.0 ? 1 : (w > (double)sz ? sz : (size_t)w);
    }
    size_t cap = sz / 8 > 0 ? sz / 8 : 1;
    if (want > cap)
      want = cap;
    nblk[c] = want;
    total += want;
  }

  return total;
}

/* Dense block ids, component by component, seed order inside; empty raw
 * blocks get remap -1. Sets res->num_blocks and res->component_of_block. */
static dacpo_status
seg_renumber(size_t num_raw,
             const size_t* raw_size,
             const int32_t* raw_comp,
             size_t num_components,
             dacpo_blocks* res,
             int32_t* remap,
             dacpo_err* err)
{
  /* raw blocks are already grouped by component except the extra ones, which
   * come after all seeded blocks: a stable counting pass per component */
  size_t* per_comp = (size_t*)dacpo_calloc_array(num_components + 1, sizeof(size_t));
  if (per_comp == NULL)
    return DACPO_OOM(err);
  for (size_t r = 0; r < num_raw; ++r)
    if (raw_size[r] > 0)
      per_comp[(size_t)raw_comp[r] + 1]++;
  for (size_t c = 0; c < num_components; ++c)
    per_comp[c + 1] += per_comp[c];
  res->num_blocks = per_comp[num_components];
  res->component_of_block =
      (int32_t*)dacpo_malloc_array(res->num_blocks, sizeof(int32_t));
  if (res->component_of_block == NULL) {
    free(per_comp);
    return DACPO_OOM(err);
  }
  for (size_t r = 0; r < num_raw; ++r) {
    if (raw_size[r] == 0) {
      remap[r] = -1;
      continue;
    }
    size_t id = per_comp[raw_comp[r]]++;
    remap[r] = (int32_t)id;
    res->component_of_block[id] = raw_comp[r];
  }
  free(per_comp);
  return DACPO_OK;
}

/* Seeds, component by component (the kd split of step 2 and 3); raw_comp gets
 * the component of each seed's raw block. */
static dacpo_status
seg_place_seeds(seg_splitter* sp,
                const size_t* comp_start,
                const size_t* nblk,
                size_t num_components,
                size_t total,
                int32_t* raw_comp,
                dacpo_err* err)
{
  dacpo_rng_seed(&sp->rng, 0x5e9d0b10c5ULL, 1);
  for (size_t c = 0; c < num_components; ++c) {
    if (nblk[c] == 0)
      continue;
    size_t first = sp->num_seeds;
    seg_split(sp, comp_start[c], comp_start[c + 1], nblk[c]);
    for (size_t s = first; s < sp->num_seeds; ++s)
      raw_comp[s] = (int32_t)c;
  }
  if (sp->num_seeds != total)
    return dacpo_err_set(err,
                         DACPO_ERR_INTERNAL,
                         "segment: kd split produced %zu seeds, expected %zu",
                         sp->num_seeds,
                         total);
  return DACPO_OK;
}

/* A step across a crease costs 1 + SEG_CREASE_COST (1 - |a_p . a_q|) hops:
 * 21 at a right angle, 1.15 at 7 degrees and 1.03 at 3 degrees of axis
 * noise (a copy-laden scan's raw PCA axes, and the crease axes after
 * averaging).
 * Orienting a block across a crease is where stage 2 fails (the dipole field
 * of one face is nearly tangent to the other); between blocks, stage 4's
 * visibility decides it. */
#define SEG_CREASE_COST 20.0

/* Indexed binary min-heap of points keyed by their path cost (ties: lower
 * index first, so the growth is deterministic). pos[p] = slot + 1, 0 = not in. */
typedef struct seg_heap {
  int32_t* item;
  size_t* pos;
  double* cost;
  size_t len;
} seg_heap;

static int
seg_heap_less(const seg_heap* h, int32_t a, int32_t b)
{
  return h->cost[a] < h->cost[b] || (h->cost[a] == h->cost[b] && a < b);
}

static void
seg_heap_place(seg_heap* h, size_t slot, int32_t p)
{
  h->item[slot] = p;
  h->pos[p] = slot + 1;
}

/* Inserts p or moves it up after its cost fell. */
static void
seg_heap_raise(seg_heap* h, int32_t p)
{
  size_t i = h->pos[p] ? h->pos[p] - 1 : h->len++;
  while (i > 0 && seg_heap_less(h, p, h->item[(i - 1) / 2])) {
    seg_heap_place(h, i, h->item[(i - 1) / 2]);
    i = (i - 1) / 2;
  }
  seg_heap_place(h, i, p);
}

static int32_t
seg_heap_pop(seg_heap* h)
{
  const int32_t top = h->item[0];
  const int32_t last = h->item[--h->len];
  h->pos[top] = 0;
  size_t i = 0;
  for (;;) {
    size_t c = 2 * i + 1;
    if (c >= h->len)
      break;
    if (c + 1 < h->len && seg_heap_less(h, h->item[c + 1], h->item[c]))
      ++c;
    if (!seg_heap_less(h, h->item[c], last))
      break;
    seg_heap_place(h, i, h->item[c]);
    i = c;
  }
  if (h->len > 0)
    seg_heap_place(h, i, last);
  return top;
}

/* Multi-source shortest paths from the labelled seeds (step 4 with crease
 * axes): a point takes the label of the neighbour its cheapest path comes
 * from, so every block stays connected. Returns the number labelled. */
static size_t
seg_grow_creased(const dacpo_adjacency* adj,
                 const double* axes,
                 const int32_t* component,
                 const int32_t* seeds,
                 size_t total,
                 int32_t* label,
                 seg_heap* h)
{
  const size_t n = adj->n;
  for (size_t i = 0; i < n; ++i) {
    h->cost[i] = HUGE_VAL;
    h->pos[i] = 0;
  }
  h->len = 0;
  for (size_t s = 0; s < total; ++s) {
    h->cost[seeds[s]] = 0.0;
    seg_heap_raise(h, seeds[s]);
  }
  size_t labelled = 0;
  while (h->len > 0) {
    const int32_t p = seg_heap_pop(h);
    ++labelled;
    const double* ap = axes + 3 * (size_t)p;
    for (size_t e = adj->start[p]; e < adj->start[p + 1]; ++e) {
      const int32_t q = adj->nbr[e];
      if (component[q] != component[p])
        continue;
      const double* aq = axes + 3 * (size_t)q;
      const double c = fabs(ap[0] * aq[0] + ap[1] * aq[1] + ap[2] * aq[2]);
      const double via = h->cost[p] + 1.0 + SEG_CREASE_COST * (1.0 - (c < 1.0 ? c : 1.0));
      if (via < h->cost[q]) {
        h->cost[q] = via;
        label[q] = label[p];
        seg_heap_raise(h, q);
      }
    }
  }
  return labelled;
}

/* Grows all blocks at once: the queue starts with every seed in block order
 * (by BFS, or by crease-charged shortest paths when axes is not NULL, with h
 * as scratch). block_of gets the raw block of every point. Returns the number
 * of raw blocks. */
static size_t
seg_grow_blocks(const dacpo_adjacency* adj,
                const int32_t* component,
                const double* axes,
                seg_heap* h,
                const int32_t* seeds,
                size_t total,
                int32_t* block_of,
                int32_t* raw_comp,
                int32_t* queue)
{
  const size_t n = adj->n;
  for (size_t i = 0; i < n; ++i)
    block_of[i] = -1;
  for (size_t s = 0; s < total; ++s) {
    block_of[seeds[s]] = (int32_t)s;
    queue[s] = seeds[s];
  }
  /* the fill below reads only queue positions from qlen on */
  size_t qlen = axes ? seg_grow_creased(adj, axes, component, seeds, total, block_of, h)
                     : seg_grow(adj, component, block_of, queue, 0, total);

  /* A point no seed reached means its labelled component is not connected in
   * adj. Give each such piece its own block, grown the same way, so every block
   * stays connected and no point is left unlabelled. */
  size_t num_raw = total;
  if (qlen < n) {
    for (size_t i = 0; i < n; ++i) {
      if (block_of[i] >= 0)
        continue;
      block_of[i] = (int32_t)num_raw;
      raw_comp[num_raw] = component[i];
      ++num_raw;
      size_t head = qlen;
      queue[qlen++] = (int32_t)i;
      qlen = seg_grow(adj, component, block_of, queue, head, qlen);
    }
  }
  return num_raw;
}

/* Dense ids, component by component, seed order inside; empty blocks dropped
 * (a seed always owns itself, so none is expected). */
static dacpo_status
seg_dense_ids(size_t n,
              size_t num_raw,
              const int32_t* raw_comp,
              size_t num_components,
              dacpo_blocks* res,
              dacpo_err* err)
{
  dacpo_status st = DACPO_OK;
  size_t* raw_size = (size_t*)dacpo_calloc_array(num_raw, sizeof(size_t));
  int32_t* remap = (int32_t*)dacpo_malloc_array(num_raw, sizeof(int32_t));
  if (raw_size == NULL || remap == NULL) {
    st = DACPO_OOM(err);
    goto done;
  }
  for (size_t i = 0; i < n; ++i)
    raw_size[res->block_of[i]]++;
  st = seg_renumber(num_raw, raw_size, raw_comp, num_components, res, remap, err);
  if (st != DACPO_OK)
    goto done;
  for (size_t i = 0; i < n; ++i)
    res->block_of[i] = remap[res->block_of[i]];
done:
  free(raw_size);
  free(remap);
  return st;
}

/* seg_grow_blocks with the shortest-path scratch it needs for crease axes. */
static dacpo_status
seg_grow_all(const dacpo_adjacency* adj,
             const int32_t* component,
             const double* axes,
             const int32_t* seeds,
             size_t total,
             int32_t* block_of,
             int32_t* raw_comp,
             int32_t* queue,
             size_t* num_raw,
             dacpo_err* err)
{
  seg_heap h = {NULL, NULL, NULL, 0};
  if (axes != NULL) {
    h.item = dacpo_malloc_array(adj->n, sizeof(int32_t));
    h.pos = dacpo_malloc_array(adj->n, sizeof(size_t));
    h.cost = dacpo_malloc_array(adj->n, sizeof(double));
  }
  dacpo_status st = DACPO_OK;
  if (axes != NULL && (h.item == NULL || h.pos == NULL || h.cost == NULL))
    st = DACPO_OOM(err);
  else
    *num_raw = seg_grow_blocks(
        adj, component, axes, &h, seeds, total, block_of, raw_comp, queue);
  free(h.item);
  free(h.pos);
  free(h.cost);
  return st;
}

dacpo_status
dacpo_segment(const dacpo_cloud* cloud,
              const dacpo_adjacency* adj,
              const int32_t* component,
              size_t num_components,
              size_t target_blocks,
              size_t ring_hops,
              dacpo_blocks* out,
              dacpo_err* err)
{
  return dacpo_segment_creased(
      cloud, adj, NULL, component, num_components, target_blocks, ring_hops, out, err);
}

dacpo_status
dacpo_segment_creased(const dacpo_cloud* cloud,
                      const dacpo_adjacency* adj,
                      const double* crease_axes,
                      const int32_t* component,
                      size_t num_components,
                      size_t target_blocks,
                      size_t ring_hops,
                      dacpo_blocks* out,
                      dacpo_err* err)
{
  if (out != NULL)
    memset(out, 0, sizeof(*out));
  DACPO_TRY(seg_check_cloud(cloud, component, num_components, out, err));
  const size_t n = cloud->n;
  DACPO_TRY(seg_check_adjacency(adj, n, err));
  DACPO_CHECK(err,
              cloud->xyz != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "segment: cloud has no coordinates");

  dacpo_status st = DACPO_OK;
  dacpo_blocks res;
  memset(&res, 0, sizeof(res));
  seg_splitter sp;
  memset(&sp, 0, sizeof(sp));
  int32_t* raw_comp = NULL; /* component of each raw (pre-renumbering) block */
  int32_t* queue = NULL;
  /* points of each component (see seg_group_by_component), blocks wanted */
  size_t* comp_start = (size_t*)dacpo_calloc_array(num_components + 1, sizeof(size_t));
  size_t* nblk = (size_t*)dacpo_calloc_array(num_components, sizeof(size_t));
  sp.pts = (dacpo_tree_point*)dacpo_malloc_array(n, sizeof(dacpo_tree_point));
  if (comp_start == NULL || nblk == NULL || sp.pts == NULL) {
    st = DACPO_OOM(err);
    goto fail;
  }

  if ((st = seg_group_by_component(
           cloud, component, num_components, comp_start, sp.pts, err)) != DACPO_OK)
    goto fail;

  const size_t total =
      seg_blocks_per_component(comp_start, num_components, n, target_blocks, nblk);

  /* Unreached points (see seg_grow_blocks) may add at most n - total further
   * blocks, so n slots are enough for all raw blocks. */
  sp.seeds = (int32_t*)dacpo_malloc_array(total, sizeof(int32_t));
  raw_comp = (int32_t*)dacpo_malloc_array(n, sizeof(int32_t));
  res.block_of = (int32_t*)dacpo_malloc_array(n, sizeof(int32_t));
  queue = (int32_t*)dacpo_malloc_array(n, sizeof(int32_t));
  if (sp.seeds == NULL || raw_comp == NULL || res.block_of == NULL || queue == NULL) {
    st = DACPO_OOM(err);
    goto fail;
  }
  st = seg_place_seeds(&sp, comp_start, nblk, num_components, total, raw_comp, err);
  if (st != DACPO_OK)
    goto fail;
  size_t num_raw = 0;
  if ((st = seg_grow_all(adj,
                         component,
                         crease_axes,
                         sp.seeds,
                         total,
                         res.block_of,
                         raw_comp,
                         queue,
                         &num_raw,
                         err)) != DACPO_OK)
    goto fail;
  if ((st = seg_dense_ids(n, num_raw, raw_comp, num_components, &res, err)) != DACPO_OK)
    goto fail;
  if ((st = seg_build_own(n, &res, err)) != DACPO_OK)
    goto fail;
  if ((st = seg_build_rings(adj, component, ring_hops, &res, err)) != DACPO_OK)
    goto fail;

  *out = res;
  goto done;

fail:
  dacpo_blocks_free(&res);
done:
  free(comp_start);
  free(nblk);
  free(sp.pts);
  free(sp.seeds);
  free(raw_comp);
  free(queue);
  return st;
}

void
dacpo_blocks_free(dacpo_blocks* b)
{
  if (b == NULL)
    return;
  free(b->block_of);
  free(b->component_of_block);
  free(b->own_start);
  free(b->own);
  free(b->ring_start);
  free(b->ring);
  memset(b, 0, sizeof(*b));
}
