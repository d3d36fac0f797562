/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Spatial tiles: dacpo_orient() on clouds larger than one process may hold
 * (dacpo_advanced.h, "Tiles"). The paper divides a scene into blocks and
 * conquers their relative signs with a 0-1 program (§4); tiles apply the same
 * idea one level up, so that no process ever holds more than one tile:
 *
 *   plan   a kd-split of a sample of the cloud (every s-th point): each cut at
 *          the sample's median along the longest side of the cell, until the
 *          cell's estimated share (sample share x total) fits max_points. The
 *          leaves partition space (outer cells unbounded); each tile also
 *          reads a halo, the points within `halo` (per axis) of its cell.
 *   orient each tile's own + halo points, in input order, by dacpo_orient()
 *          (the caller's business: in one process, one tile at a time, or on
 *          cluster ranks). Own points keep that tile's normals.
 *   join   every halo point is oriented twice, by its owner and by the tile
 *          whose halo it lies in: sum_|n_a . n_b| over the agreeing and the
 *          disagreeing ones is the evidence that tiles a and b have the same or
 *          opposite sign (the role of Eq. 6-7 between blocks). The tiles'
 *          relative signs follow a maximum spanning tree of that evidence
 *          (Kruskal, strongest pair first: tiles are few and pairs are
 *          decisive, so no 0-1 program is needed); each connected group then
 *          keeps the sign that most of its points' tiles chose in their own
 *          stage 6.
 *
 * The plan depends only on the sample (its order included), the total and the
 * two numbers: processes that read the same sample build the same plan, which
 * is what makes a run's answer independent of how many processes share it.
 *
 * Cost: plan O(m log^2 m) for an m-point sample (one sort per level), O(m log
 * m) for the automatic halo (a kd-tree over the sample); locate O(depth +
 * halo tiles); join O(p log p) for p pairs. Memory O(m + tiles).
 */
#include "dacpo_block_unit.h"
#include "dacpo_internal.h"
#include "dacpo_kdtree.h"
#include "dacpo_select.h"

#include <dacpo/dacpo_advanced.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Automatic halo in spacings of the full cloud: half a block's width or more
 * (a 1,250-point block is ~35 spacings across, a 625-point one ~25), so that
 * the evidence between two tiles rests on whole blocks seen from both, and
 * the k-NN rows and normals of points near a cut are those of the whole
 * cloud. */
#define DACPO_TILE_HALO_SPACINGS 16.0
/* The split aims at this share of max_points for the own points, leaving
 * room for the halo. */
#define DACPO_TILE_OWN_SHARE 0.8
#define DACPO_TILE_MAX_TILES 65536
/* Neighbours searched for the nearest sample at another position. */
#define SPACING_K 16
/* The own share is lowered at most to this share of max_points before an
 * automatic halo is narrowed instead (tiles of mostly halo cost work). */
#define DACPO_TILE_MIN_OWN_SHARE 0.25

typedef struct tile_node {
  int axis;      /* -1: leaf */
  double value;  /* points with coordinate < value go left */
  int32_t left;  /* child node, or the tile id for a leaf */
  int32_t right;
} tile_node;

struct dacpo_tile_plan {
  tile_node* node;
  size_t num_nodes;
  size_t num_tiles;
  double halo;
  uint64_t* estimate; /* own + halo points per tile (from the sample) */
};

typedef struct plan_build {
  const float* xyz;
  int32_t* idx; /* sample indices, permuted per cell */
  uint64_t total;
  size_t m;
  double cap; /* own points per tile */
  tile_node* node;
  size_t num_nodes, cap_nodes, num_tiles;
} plan_build;

/* Ties by sample index: the order (and so the plan) does not depend on qsort. */
static int
cmp_axis(const float* xyz, int axis, int32_t a, int32_t b)
{
  const float u = xyz[3 * (size_t)a + (size_t)axis];
  const float v = xyz[3 * (size_t)b + (size_t)axis];
  return u < v ? -1 : u > v ? 1 : (a > b) - (a < b);
}

/* Sort of idx[0..n) by one axis: a merge sort with a buffer (qsort has no
 * context argument in C11). */
static void
sort_by_axis(const float* xyz, int axis, int32_t* idx, int32_t* tmp, size_t n)
{
  if (n < 2)
    return;
  const size_t h = n / 2;
  sort_by_axis(xyz, axis, idx, tmp, h);
  sort_by_axis(xyz, axis, idx + h, tmp, n - h);
  size_t i = 0, j = h, o = 0;
  while (i < h && j < n)
    tmp[o++] = cmp_axis(xyz, axis, idx[i], idx[j]) <= 0 ? idx[i++] : idx[j++];
  while (i < h)
    tmp[o++] = idx[i++];
  while (j < n)
    tmp[o++] = idx[j++];
  memcpy(idx, tmp, n * sizeof(int32_t));
}

static int32_t
plan_node(plan_build* b)
{
  if (b->num_nodes == b->cap_nodes) {
    const size_t cap = b->cap_nodes ? 2 * b->cap_nodes : 64;
    tile_node* nn = realloc(b->node, cap * sizeof(tile_node));
    if (!nn)
      return -1;
    b->node = nn;
    b->cap_nodes = cap;
  }
  return (int32_t)b->num_nodes++;
}

/* Cell of sample points idx[0..n): a leaf when its estimated share fits, else
 * cut at the median of its longest side. Returns the node, -1 out of memory,
 * -2 too many tiles. */
static int32_t
plan_cell(plan_build* b, int32_t* idx, size_t n, int32_t* tmp)
{
  const int32_t id = plan_node(b);
  if (id < 0)
    return -1;
  const double est = (double)n * (double)b->total / (double)b->m;
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const double v = b->xyz[3 * (size_t)idx[i] + (size_t)a];
      lo[a] = v < lo[a] ? v : lo[a];
      hi[a] = v > hi[a] ? v : hi[a];
    }
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[axis] - lo[axis])
      axis = a;
  /* A cell of one repeated position cannot be cut: it stays one tile. */
  if (est <= b->cap || n < 2 || !(hi[axis] > lo[axis])) {
    b->node[id].axis = -1;
    b->node[id].left = b->node[id].right = (int32_t)b->num_tiles++;
    return b->num_tiles > DACPO_TILE_MAX_TILES ? -2 : id;
  }
  sort_by_axis(b->xyz, axis, idx, tmp, n);
  size_t h = n / 2;
  const float cut = b->xyz[3 * (size_t)idx[h] + (size_t)axis];
  /* Points equal to the cut go right: move h down to the first of them (or up
   * past them when they start the cell) so both sides are non-empty. */
  while (h > 0 && b->xyz[3 * (size_t)idx[h - 1] + (size_t)axis] == cut)
    --h;
  if (h == 0) {
    while (h < n && b->xyz[3 * (size_t)idx[h] + (size_t)axis] == cut)
      ++h;
  }
  const double value = (double)b->xyz[3 * (size_t)idx[h] + (size_t)axis];
  const int32_t l = plan_cell(b, idx, h, tmp);
  if (l < 0)
    return l;
  const int32_t r = plan_cell(b, idx + h, n - h, tmp);
  if (r < 0)
    return r;
  b->node[id].axis = axis;
  b->node[id].value = value;
  b->node[id].left = l;
  b->node[id].right = r;
  return id;
}

/* The whole cloud's spacing from the sample's: the median distance to the
 * nearest other sample, times sqrt(m / total) (surfaces: spacing ~ density^-1/2). */
static dacpo_status
sample_spacing(const float* xyz, size_t m, uint64_t total, double* spacing, dacpo_err* err)
{
  *spacing = 0.0;
  if (m < 2)
    return DACPO_OK;
  double* p = dacpo_malloc_array(3 * m, sizeof(double));
  double* d = dacpo_malloc_array(m, sizeof(double));
  if (!p || !d) {
    free(p);
    free(d);
    return DACPO_OOM(err);
  }
  for (size_t i = 0; i < 3 * m; ++i)
    p[i] = xyz[i];
  dacpo_kdtree* tree = NULL;
  dacpo_status st = dacpo_kdtree_build(p, m, &tree, err);
  size_t nd = 0;
  /* the nearest sample at another position: copies of a point (a scan
     concatenated twice) are at distance 0 and say nothing of the spacing */
  for (size_t i = 0; st == DACPO_OK && i < m; ++i) {
    int32_t id[SPACING_K];
    double sq[SPACING_K];
    const size_t got = dacpo_kdtree_knn(tree, p + 3 * i, SPACING_K, id, sq);
    for (size_t j = 1; j < got; ++j)
      if (sq[j] > 0.0) {
        d[nd++] = sqrt(sq[j]);
        break;
      }
  }
  if (st == DACPO_OK && nd > 0)
    *spacing = dacpo_select_kth(d, nd, nd / 2) * sqrt((double)m / (double)total);
  dacpo_kdtree_free(tree);
  free(p);
  free(d);
  return st;
}

/* Lists the tiles (other than skip) whose cell grown by the halo holds p. */
static void
locate_node(const dacpo_tile_plan* plan,
            int32_t id,
            const float p[3],
            int32_t skip,
            int32_t* tiles,
            size_t max_tiles,
            size_t* count)
{
  const tile_node* nd = &plan->node[id];
  if (nd->axis < 0) {
    if (nd->left != skip) {
      if (*count < max_tiles)
        tiles[*count] = nd->left;
      ++*count;
    }
    return;
  }
  const double v = p[nd->axis];
  if (v - nd->value < plan->halo)
    locate_node(plan, nd->left, p, skip, tiles, max_tiles, count);
  if (nd->value - v <= plan->halo)
    locate_node(plan, nd->right, p, skip, tiles, max_tiles, count);
}

/* The cells for own points of at most cap (plan_cell), in plan->node. */
static dacpo_status
plan_cells(dacpo_tile_plan* plan,
           const float* sample,
           size_t m,
           uint64_t total,
           double cap,
           uint64_t max_points,
           int32_t* tmp,
           dacpo_err* err)
{
  plan_build b;
  memset(&b, 0, sizeof(b));
  b.xyz = sample;
  b.total = total;
  b.m = m;
  b.cap = cap;
  b.idx = dacpo_malloc_array(m, sizeof(int32_t));
  if (!b.idx)
    return DACPO_OOM(err);
  for (size_t i = 0; i < m; ++i)
    b.idx[i] = (int32_t)i;
  const int32_t root = plan_cell(&b, b.idx, m, tmp);
  free(b.idx);
  free(plan->node);
  plan->node = b.node;
  plan->num_nodes = b.num_nodes;
  plan->num_tiles = b.num_tiles;
  if (root == -1)
    return DACPO_OOM(err);
  if (root == -2)
    return dacpo_err_set(err,
                         DACPO_ERR_INVALID_ARGUMENT,
                         "tile plan: more than %d tiles (max_points %llu is too small "
                         "for %llu points)",
                         DACPO_TILE_MAX_TILES,
                         (unsigned long long)max_points,
                         (unsigned long long)total);
  return DACPO_OK;
}

/* Own + halo points per tile from the sample, scaled to the total. */
static dacpo_status
plan_estimates(dacpo_tile_plan* plan,
               const float* sample,
               size_t m,
               uint64_t total,
               int32_t* tmp,
               dacpo_err* err)
{
  free(plan->estimate);
  plan->estimate = calloc(plan->num_tiles, sizeof(uint64_t));
  if (!plan->estimate)
    return DACPO_OOM(err);
  for (size_t i = 0; i < m; ++i) {
    size_t c = 0;
    locate_node(plan, 0, sample + 3 * i, -1, tmp, m, &c);
    for (size_t t = 0; t < c && t < m; ++t)
      plan->estimate[tmp[t]]++;
  }
  for (size_t t = 0; t < plan->num_tiles; ++t)
    plan->estimate[t] = (uint64_t)((double)plan->estimate[t] * (double)total / (double)m + 0.5);
  return DACPO_OK;
}

static dacpo_status
tile_plan_create(const float* sample,
                 size_t m,
                 uint64_t total,
                 uint64_t max_points,
                 double halo,
                 dacpo_tile_plan** out,
                 dacpo_err* err)
{
  DACPO_CHECK(err,
              out && (sample || m == 0),
              DACPO_ERR_INVALID_ARGUMENT,
              "tile plan: NULL argument");
  *out = NULL;
  DACPO_CHECK(err,
              m > 0 && total >= m && m <= (size_t)INT32_MAX,
              DACPO_ERR_EMPTY_INPUT,
              "tile plan: the sample must hold 1 .. total points (got %zu of %llu)",
              m,
              (unsigned long long)total);
  DACPO_CHECK(err,
              max_points >= 16,
              DACPO_ERR_INVALID_ARGUMENT,
              "tile plan: max_points must be >= 16 (got %llu)",
              (unsigned long long)max_points);
  DACPO_CHECK(err,
              !(halo < 0.0) && halo < HUGE_VAL,
              DACPO_ERR_INVALID_ARGUMENT,
              "tile plan: halo must be >= 0 and finite (0: automatic)");
  for (size_t i = 0; i < 3 * m; ++i)
    DACPO_CHECK(err,
                isfinite(sample[i]),
                DACPO_ERR_NONFINITE_INPUT,
                "tile plan: sample point %zu is not finite",
                i / 3);
  dacpo_tile_plan* plan = calloc(1, sizeof(*plan));
  int32_t* tmp = dacpo_malloc_array(m, sizeof(int32_t));
  double spacing = 0.0;
  dacpo_status st = plan && tmp ? DACPO_OK : DACPO_OOM(err);
  if (st == DACPO_OK && !(halo > 0.0))
    st = sample_spacing(sample, m, total, &spacing, err);
  if (st == DACPO_OK) {
    plan->halo = halo > 0.0 ? halo : DACPO_TILE_HALO_SPACINGS * spacing;
    st = plan_cells(
        plan, sample, m, total, DACPO_TILE_OWN_SHARE * (double)max_points, max_points, tmp, err);
  }
  if (st == DACPO_OK)
    st = plan_estimates(plan, sample, m, total, tmp, err);
  free(tmp);
  if (st != DACPO_OK) {
    dacpo_tile_plan_free(plan);
    return st;
  }
  *out = plan;
  return DACPO_OK;
}

dacpo_status
dacpo_tile_plan_create(const float* sample,
                       size_t m,
                       uint64_t total,
                       uint64_t max_points,
                       double halo,
                       dacpo_tile_plan** out,
                       char* msg,
                       size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  tile_plan_create(sample, m, total, max_points, halo, out, &err);
  return dacpo_unit_message(&err, msg, msg_size);
}

size_t
dacpo_tile_plan_count(const dacpo_tile_plan* plan)
{
  return plan ? plan->num_tiles : 0;
}

double
dacpo_tile_plan_halo(const dacpo_tile_plan* plan)
{
  return plan ? plan->halo : 0.0;
}

uint64_t
dacpo_tile_plan_estimate(const dacpo_tile_plan* plan, size_t tile)
{
  return plan && tile < plan->num_tiles ? plan->estimate[tile] : 0;
}

int32_t
dacpo_tile_locate(const dacpo_tile_plan* plan,
                  const float p[3],
                  int32_t* halo_tiles,
                  size_t max_halo,
                  size_t* num_halo)
{
  if (num_halo)
    *num_halo = 0;
  if (!plan || !p || !isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
    return -1;
  int32_t id = 0;
  while (plan->node[id].axis >= 0) {
    const tile_node* nd = &plan->node[id];
    id = p[nd->axis] < nd->value ? nd->left : nd->right;
  }
  const int32_t own = plan->node[id].left;
  if (num_halo)
    locate_node(plan, 0, p, own, halo_tiles, halo_tiles ? max_halo : 0, num_halo);
  return own;
}

void
dacpo_tile_plan_free(dacpo_tile_plan* plan)
{
  if (!plan)
    return;
  free(plan->node);
  free(plan->estimate);
  free(plan);
}

/* ---- join ---------------------------------------------------------------- */

typedef struct join_edge {
  uint32_t a, b;
  double same, opposite;
} join_edge;

static int
cmp_pair(const void* x, const void* y)
{
  const join_edge* u = x;
  const join_edge* v = y;
  if (u->a != v->a)
    return u->a < v->a ? -1 : 1;
  return (u->b > v->b) - (u->b < v->b);
}

/* strongest evidence first; ties by the pair, so the tree is deterministic */
static int
cmp_strength(const void* x, const void* y)
{
  const join_edge* u = x;
  const join_edge* v = y;
  const double su = fabs(u->same - u->opposite), sv = fabs(v->same - v->opposite);
  if (su != sv)
    return su > sv ? -1 : 1;
  return cmp_pair(x, y);
}

/* The overlaps as undirected pairs (a < b) into ed, (a, b) and (b, a) - the
 * same pair seen from either owner - merged; returns their count. */
static size_t
merge_pairs(const dacpo_tile_overlap* ov, size_t num_ov, join_edge* ed)
{
  size_t ne = 0;
  for (size_t e = 0; e < num_ov; ++e) {
    if (ov[e].a == ov[e].b)
      continue;
    join_edge x = {ov[e].a < ov[e].b ? ov[e].a : ov[e].b,
                   ov[e].a < ov[e].b ? ov[e].b : ov[e].a,
                   ov[e].same,
                   ov[e].opposite};
    ed[ne++] = x;
  }
  qsort(ed, ne, sizeof(join_edge), cmp_pair);
  size_t u = 0;
  for (size_t e = 0; e < ne; ++e) {
    if (u > 0 && ed[u - 1].a == ed[e].a && ed[u - 1].b == ed[e].b) {
      ed[u - 1].same += ed[e].same;
      ed[u - 1].opposite += ed[e].opposite;
    }
    else
      ed[u++] = ed[e];
  }
  return u;
}

/* The spanning forest as adjacency lists: arcs of tile t from head[t] along
 * next[], each to tile to[a] with relation rel[a] (+1 same sign, -1 opposite). */
typedef struct tree_arcs {
  const int32_t* head;
  const int32_t* next;
  const int32_t* to;
  const int8_t* rel;
} tree_arcs;

/* Signs along each tree from its lowest tile; then the group keeps the sign
 * most of its points' tiles chose themselves (flip in: 0; out: the flips). */
static void
sign_trees(size_t num_tiles,
           const tree_arcs* g,
           const uint64_t* tile_points,
           int32_t* queue,
           uint8_t* seen,
           uint8_t* flip)
{
  for (size_t s = 0; s < num_tiles; ++s) {
    if (seen[s])
      continue;
    size_t qh = 0, qt = 0;
    queue[qt++] = (int32_t)s;
    seen[s] = 1;
    double kept = 0.0, flipped = 0.0;
    while (qh < qt) {
      const int32_t t = queue[qh++];
      const double w = tile_points ? (double)tile_points[t] : 1.0;
      if (flip[t])
        flipped += w;
      else
        kept += w;
      for (int32_t a = g->head[t]; a >= 0; a = g->next[a])
        if (!seen[g->to[a]]) {
          seen[g->to[a]] = 1;
          flip[g->to[a]] = (uint8_t)(g->rel[a] > 0 ? flip[t] : !flip[t]);
          queue[qt++] = g->to[a];
        }
    }
    if (flipped > kept)
      for (size_t q = 0; q < qt; ++q)
        flip[queue[q]] = (uint8_t)!flip[queue[q]];
  }
}

static dacpo_status
tile_join(size_t num_tiles,
          const dacpo_tile_overlap* ov,
          size_t num_ov,
          const uint64_t* tile_points,
          uint8_t* flip,
          dacpo_err* err)
{
  DACPO_CHECK(err,
              flip && (ov || num_ov == 0) && num_tiles <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "tile join: NULL argument");
  for (size_t e = 0; e < num_ov; ++e)
    DACPO_CHECK(err,
                ov[e].a < num_tiles && ov[e].b < num_tiles && isfinite(ov[e].same) &&
                    isfinite(ov[e].opposite) && ov[e].same >= 0.0 &&
                    ov[e].opposite >= 0.0,
                DACPO_ERR_INVALID_ARGUMENT,
                "tile join: overlap %zu is invalid (tiles %u, %u of %zu, or evidence "
                "negative / not finite)",
                e,
                ov[e].a,
                ov[e].b,
                num_tiles);
  memset(flip, 0, num_tiles);
  if (num_tiles == 0)
    return DACPO_OK;
  join_edge* ed = dacpo_malloc_array(num_ov ? num_ov : 1, sizeof(join_edge));
  int32_t* parent = dacpo_malloc_array(num_tiles, sizeof(int32_t));
  int32_t* head = dacpo_malloc_array(num_tiles, sizeof(int32_t));
  int32_t* next = dacpo_malloc_array(2 * (num_ov ? num_ov : 1), sizeof(int32_t));
  int32_t* to = dacpo_malloc_array(2 * (num_ov ? num_ov : 1), sizeof(int32_t));
  int8_t* rel = dacpo_malloc_array(2 * (num_ov ? num_ov : 1), sizeof(int8_t));
  int32_t* queue = dacpo_malloc_array(num_tiles, sizeof(int32_t));
  uint8_t* seen = dacpo_calloc_array(num_tiles, sizeof(uint8_t));
  if (!ed || !parent || !head || !next || !to || !rel || !queue || !seen) {
    free(ed), free(parent), free(head), free(next), free(to), free(rel), free(queue);
    free(seen);
    return DACPO_OOM(err);
  }
  const size_t ne = merge_pairs(ov, num_ov, ed);
  qsort(ed, ne, sizeof(join_edge), cmp_strength);
  /* Kruskal: the maximum spanning forest of |same - opposite| */
  for (size_t t = 0; t < num_tiles; ++t) {
    parent[t] = (int32_t)t;
    head[t] = -1;
  }
  size_t na = 0;
  for (size_t e = 0; e < ne; ++e) {
    if (ed[e].same == ed[e].opposite)
      continue; /* no evidence either way */
    const int32_t ra = dacpo_uf_find(parent, (int32_t)ed[e].a);
    const int32_t rb = dacpo_uf_find(parent, (int32_t)ed[e].b);
    if (ra == rb)
      continue;
    dacpo_uf_union(parent, ra, rb);
    const int8_t r = ed[e].same > ed[e].opposite ? 1 : -1;
    to[na] = (int32_t)ed[e].b, rel[na] = r, next[na] = head[ed[e].a], head[ed[e].a] = (int32_t)na, ++na;
    to[na] = (int32_t)ed[e].a, rel[na] = r, next[na] = head[ed[e].b], head[ed[e].b] = (int32_t)na, ++na;
  }
  const tree_arcs arcs = {head, next, to, rel};
  sign_trees(num_tiles, &arcs, tile_points, queue, seen, flip);
  free(ed), free(parent), free(head), free(next), free(to), free(rel), free(queue);
  free(seen);
  return DACPO_OK;
}

dacpo_status
dacpo_tile_join(size_t num_tiles,
                const dacpo_tile_overlap* overlaps,
                size_t num_overlaps,
                const uint64_t* tile_points,
                uint8_t* flip,
                char* msg,
                size_t msg_size)
{
  dacpo_err err = {DACPO_OK, {0}};
  tile_join(num_tiles, overlaps, num_overlaps, tile_points, flip, &err);
  return dacpo_unit_message(&err, msg, msg_size);
}
