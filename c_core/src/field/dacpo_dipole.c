/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * Stage 2: orientation initialisation of one block by a dipole-like field and a
 * randomized greedy propagation (paper §4.2, Eq. 1-4).
 *
 * Input:  n points of one block (xyz, unit normal axes nrm, 3n doubles each) and
 *         dacpo_dipole_params (c, M orders, K neighbours, BFS graph k, seed, stream).
 * Output: sign_out[i] in {+1, -1}; the block's normals are sign_out[i] * nrm[i].
 *         The overall sign of the block is arbitrary (stage 5 decides it).
 *
 * Method: each point's K nearest neighbours (local kd-tree, self excluded) are
 * listed once together with the pair energies e (Eq. 2) of the unflipped axes;
 * pairs recognised as the two faces of one thin part get an "opposite" energy
 * instead (two_sheet_pair; params->two_sheet = 0 keeps Eq. 2), and in a
 * block seen from one side, stacked layers of one surface get c = 1 (layer_pair;
 * params->layers = 0 keeps Eq. 2). In blocks with parts thinner than the
 * spacing, the side cue (dacpo_sheet_side.c; params->sides > 0) makes pairs
 * on the two faces "opposite" and adds a field that turns each face away from
 * the other (side_field).
 * The lists and energies are built in dacpo_dipole_pairs.c (one pass per
 * block, before any order runs).
 * Since e((p,s n),(q,t m)) = s t e((p,n),(q,m)), every later decision is a signed
 * sum of these cached numbers. M randomized BFS orders over the (symmetrized)
 * graph_k-NN graph each give a greedy sign vector (Eq. 4); the M vectors are
 * aligned by an exhaustive search over relative flips (minimum total Hamming
 * disagreement) and majority-voted; Gauss-Seidel sweeps then let every point
 * re-decide with all its K neighbours placed, until none changes. The whole
 * run is repeated up to `restarts` times with other orders (voted runs stop
 * after DACPO_DIPOLE_AGREE that all agree); the runs are voted point
 * by point (dipole_vote below): one unlucky start no longer decides a block.
 *
 * Cost: kd-tree build O(n log n) + n queries of K+1 neighbours, then
 * restarts x (O(M n K) for the orders, O(M^2 n + 2^(M-1) M^2) for the alignment,
 * O(n K) per sweep), and O(restarts n) for the vote. Memory: n K (int32 + double) + O(M
 * n) bytes.
 *
 * Failures: INVALID_ARGUMENT (NULL pointers, orders outside [1, 16], neighbors
 * == 0, n too large for int32 indices), OUT_OF_MEMORY. Non-finite input is the
 * caller's business (checked in stage 0); near-coincident pairs contribute 0.
 * Deterministic for a given (seed, stream); no global state, callable from
 * several threads at once.
 */
#include "dacpo_dipole_internal.h"
#include "dacpo_kdtree.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DACPO_DIPOLE_MAX_ORDERS 16
#define DACPO_DIPOLE_MAX_RESTARTS 64
/* Voted restarts that, all giving one answer (up to the block's sign), end the
 * block's runs: more runs could only repeat it where they agree too
 * (docs/DESIGN.md, "Speed"). */
#define DACPO_DIPOLE_AGREE 4

static void
dipole_work_free(dipole_work* wk)
{
  free(wk->nb);
  free(wk->w);
  free(wk->unary);
  free(wk->patch);
  free(wk->patch_field);
  free(wk->gstart);
  free(wk->gnbr);
  free(wk->sign);
  free(wk->cand);
  free(wk->visited);
  free(wk->queue);
  free(wk->order0);
  free(wk->perm);
  free(wk->buf);
  free(wk->kbuf);
  free(wk->kd);
  dacpo_kdtree_free(wk->tree);
}

/* Symmetrized graph over the first gk entries of each list (repeats allowed: the
 * BFS skips visited points anyway). */
static dacpo_status
dipole_graph(size_t n, size_t K, size_t gk, dipole_work* wk, dacpo_err* err)
{
  wk->gstart = dacpo_calloc_array(n + 1, sizeof(size_t));
  if (!wk->gstart)
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i)
    for (size_t t = 0; t < gk; ++t) {
      const int32_t j = wk->nb[i * K + t];
      if ((size_t)j == i)
        continue;
      wk->gstart[i + 1]++;
      wk->gstart[(size_t)j + 1]++;
    }
  size_t maxdeg = 0;
  for (size_t i = 0; i < n; ++i) {
    if (wk->gstart[i + 1] > maxdeg)
      maxdeg = wk->gstart[i + 1];
    wk->gstart[i + 1] += wk->gstart[i];
  }
  wk->gnbr = dacpo_malloc_array(wk->gstart[n], sizeof(int32_t));
  wk->buf = dacpo_malloc_array(maxdeg, sizeof(int32_t));
  size_t* fill = dacpo_malloc_array(n, sizeof(size_t));
  if (!wk->gnbr || !wk->buf || !fill) {
    free(fill);
    return DACPO_OOM(err);
  }
  memcpy(fill, wk->gstart, n * sizeof(size_t));
  for (size_t i = 0; i < n; ++i)
    for (size_t t = 0; t < gk; ++t) {
      const int32_t j = wk->nb[i * K + t];
      if ((size_t)j == i)
        continue;
      wk->gnbr[fill[i]++] = j;
      wk->gnbr[fill[(size_t)j]++] = (int32_t)i;
    }
  free(fill);
  return DACPO_OK;
}

/* sum_t s[row[t]] * w[t]; four partial sums break the add latency chain. */
static double
dipole_field_sum(const int32_t* row, const double* w, size_t K, const int8_t* s)
{
  double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
  size_t t = 0;
  for (; t + 4 <= K; t += 4) {
    a0 += (double)s[row[t]] * w[t];
    a1 += (double)s[row[t + 1]] * w[t + 1];
    a2 += (double)s[row[t + 2]] * w[t + 2];
    a3 += (double)s[row[t + 3]] * w[t + 3];
  }
  for (; t < K; ++t)
    a0 += (double)s[row[t]] * w[t];
  return (a0 + a1) + (a2 + a3);
}

/* Greedy sign of point i from its placed neighbours (Eq. 4). A point with no
 * placed neighbour, or an exact tie, takes +1. */
static int8_t
dipole_decide(const dipole_work* wk, size_t K, size_t i, const int8_t* s)
{
  const int32_t* row = wk->nb + i * K;
  const double* wrow = wk->w + i * K;
  /* Unplaced points have s == 0 and drop out without a branch: whether a
   * neighbour is placed is random, a branch on it would mispredict half the
   * time and cost more than the sum itself. */
  const double u = wk->unary ? wk->unary[i] : 0.0;
  return dipole_field_sum(row, wrow, K, s) + u >= 0.0 ? 1 : -1;
}

/* A BFS tree that starts where none of the point's K neighbours is placed yet
 * (an island of the block: a part beyond its neighbourhood, or a component
 * joined by a bridge) would take an arbitrary sign, and the restarts would
 * then vote on a coin. Instead it takes the Eq. 1 field of the points placed
 * so far (plain Eq. 2 pairs; every (placed / DACPO_DIPOLE_FAR_SAMPLES)-th
 * point of the placement order, so fewer than twice that many): the field
 * between parts that see each other only from afar still says which way round
 * they belong. */
#define DACPO_DIPOLE_FAR_SAMPLES 256

static double
tree_start_field(const dipole_work* wk, size_t placed, size_t i, const int8_t* s)
{
  const size_t step =
      placed > DACPO_DIPOLE_FAR_SAMPLES ? placed / DACPO_DIPOLE_FAR_SAMPLES : 1;
  double f = 0.0;
  for (size_t q = 0; q < placed; q += step) {
    const size_t j = (size_t)wk->queue[q];
    f += (double)s[j] *
         dacpo_dipole_energy(
             wk->xyz + 3 * j, wk->nrm + 3 * j, wk->xyz + 3 * i, wk->nrm + 3 * i, wk->c);
  }
  return f;
}

/* One randomized BFS order; signs placed in s (length n, zeroed here). */
static void
dipole_one_order(
    dipole_work* wk, size_t n, size_t K, dacpo_rng* rng, int8_t* s, int32_t* order_out)
{
  memset(s, 0, n);
  memset(wk->visited, 0, n);
  /* A random permutation supplies the start point and every restart: scanning it
   * for the next unvisited point picks a uniformly random unplaced point. */
  for (size_t i = 0; i < n; ++i)
    wk->perm[i] = (int32_t)i;
  for (size_t i = n; i > 1; --i) {
    const size_t r = dacpo_rng_below(rng, i);
    const int32_t tmp = wk->perm[i - 1];
    wk->perm[i - 1] = wk->perm[r];
    wk->perm[r] = tmp;
  }
  size_t head = 0, tail = 0, scan = 0;
  while (head < n) {
    int tree_start = 0;
    if (head == tail) {
      while (wk->visited[wk->perm[scan]])
        ++scan;
      const int32_t start = wk->perm[scan];
      wk->visited[start] = 1;
      wk->queue[tail++] = start;
      tree_start = head > 0;
    }
    const size_t i = (size_t)wk->queue[head++];
    s[i] = dipole_decide(wk, K, i, s);
    if (tree_start) {
      const double* row_w = wk->w + i * K;
      const int32_t* row = wk->nb + i * K;
      int placed_nb = 0;
      for (size_t t = 0; t < K && !placed_nb; ++t)
        placed_nb = s[row[t]] != 0 && row_w[t] != 0.0 && (size_t)row[t] != i;
      if (!placed_nb)
        s[i] =
            tree_start_field(wk, head - 1, i, s) + (wk->unary ? wk->unary[i] : 0.0) >=
                    0.0
                ? 1
                : -1;
    }
    /* Visit the neighbours in random order: the orders differ not only by their
     * start, which is what makes the vote informative. */
    const size_t b = wk->gstart[i], deg = wk->gstart[i + 1] - b;
    memcpy(wk->buf, wk->gnbr + b, deg * sizeof(int32_t));
    for (size_t d = deg; d > 1; --d) {
      const size_t r = dacpo_rng_below(rng, d);
      const int32_t tmp = wk->buf[d - 1];
      wk->buf[d - 1] = wk->buf[r];
      wk->buf[r] = tmp;
    }
    for (size_t d = 0; d < deg; ++d) {
      const int32_t j = wk->buf[d];
      if (!wk->visited[j]) {
        wk->visited[j] = 1;
        wk->queue[tail++] = j;
      }
    }
  }
  if (order_out)
    memcpy(order_out, wk->queue, n * sizeof(int32_t));
}

/* Relative flips of orders 1..M-1 against order 0 with the least total pairwise
 * disagreement (paper: exhaustive search over the alignments, M is small). */
/* Restarts that all gave the same signs as the first, or all its opposite. */
static int
restarts_agree(const int8_t* cand, size_t n, size_t R)
{
  for (size_t r = 1; r < R; ++r) {
    const int8_t* c = cand + r * n;
    const int same = c[0] == cand[0];
    for (size_t i = 1; i < n; ++i)
      if ((c[i] == cand[i]) != same)
        return 0;
  }
  return 1;
}

static unsigned
dipole_align(const int8_t* sign, size_t n, size_t M)
{
  size_t diff[DACPO_DIPOLE_MAX_ORDERS][DACPO_DIPOLE_MAX_ORDERS] = {{0}};
  for (size_t a = 0; a < M; ++a)
    for (size_t b = a + 1; b < M; ++b) {
      size_t d = 0;
      const int8_t* sa = sign + a * n;
      const int8_t* sb = sign + b * n;
      for (size_t i = 0; i < n; ++i)
        d += sa[i] != sb[i];
      diff[a][b] = d;
    }
  unsigned best = 0;
  size_t best_cost = (size_t)-1;
  for (unsigned mask = 0; mask < (1u << (M - 1)); ++mask) {
    const unsigned flip = mask << 1; /* bit m: order m flipped; order 0 fixed */
    size_t cost = 0;
    for (size_t a = 0; a < M; ++a)
      for (size_t b = a + 1; b < M; ++b)
        cost += (((flip >> a) ^ (flip >> b)) & 1u) ? n - diff[a][b] : diff[a][b];
    if (cost < best_cost) {
      best_cost = cost;
      best = flip;
    }
  }
  return best;
}

dacpo_status
dacpo_dipole_orient(const double* xyz,
                    const double* nrm,
                    size_t n,
                    const dacpo_dipole_params* params,
                    int8_t* sign_out,
                    dacpo_err* err)
{
  return dacpo_dipole_orient_confidence(xyz, nrm, n, params, sign_out, NULL, err);
}

/* Confidence of every point in the final signs s: the share of restarts that agree
 * with it (each restart aligned to s as a whole) times the margin of
 * its final decision, |sum_t s_j e_ji| / sum_t |e_ji| (1: every neighbour says
 * the same, 0: a tie). */
static void
dipole_confidence(const dipole_work* wk,
                  size_t n,
                  size_t K,
                  size_t R,
                  const int8_t* s,
                  float* confidence)
{
  for (size_t i = 0; i < n; ++i)
    confidence[i] = 0.0f;
  for (size_t r = 0; r < R; ++r) {
    const int8_t* c = wk->cand + r * n;
    size_t same = 0;
    for (size_t i = 0; i < n; ++i)
      same += c[i] == s[i];
    const int8_t f = 2 * same >= n ? 1 : -1;
    for (size_t i = 0; i < n; ++i)
      confidence[i] += (float)(f * c[i] == s[i]);
  }
  for (size_t i = 0; i < n; ++i) {
    const int32_t* row = wk->nb + i * K;
    const double* w = wk->w + i * K;
    double sum = wk->unary ? wk->unary[i] : 0.0;
    double mag = fabs(sum);
    for (size_t t = 0; t < K; ++t) {
      sum += (double)s[row[t]] * w[t];
      mag += fabs(w[t]);
    }
    const double margin = mag > 0.0 ? fabs(sum) / mag : 0.0;
    confidence[i] = (float)((double)confidence[i] / (double)R * margin);
  }
}

/* Gauss-Seidel sweeps in order 0's BFS order: every point now sees all K
 * neighbours placed; an exact tie keeps the current sign. Repeated (up to
 * `sweeps` times) until no point changes: each change raises the energy. */
static void
dipole_sweeps(dipole_work* wk, size_t n, size_t K, int sweeps, int8_t* cand)
{
  for (int sw = 0; sw < sweeps; ++sw) {
    size_t changed = 0;
    for (size_t o = 0; o < n; ++o) {
      const size_t i = (size_t)wk->order0[o];
      const double sum = dipole_field_sum(wk->nb + i * K, wk->w + i * K, K, cand) +
                         (wk->unary ? wk->unary[i] : 0.0);
      const int8_t v = sum > 0.0 ? 1 : sum < 0.0 ? -1 : cand[i];
      changed += v != cand[i];
      cand[i] = v;
    }
    if (changed == 0)
      break;
  }
}

/* The restarts voted point by point: each restart is flipped as a whole by
 * the same exhaustive alignment as the orders (minimum total pairwise
 * disagreement; beyond DACPO_DIPOLE_MAX_ORDERS restarts, each is aligned to
 * the first), every point takes the majority sign (a tie: the first
 * restart's), then the sweeps settle it. Measured against keeping the restart
 * with the highest block energy (6 real frames and 6 synthetic rooms, seeds
 * 1-3): that energy is not a reliable judge where parts are thin or noisy (16
 * restarts picked by it: rooms 7.11 -> 7.78 %, one frame 21.7 % on one seed),
 * the vote over 8 restarts gave rooms 7.11 -> 6.59 % and cut the largest
 * spread over seeds from 5.96 to 1.32 points. Aligning each restart to the
 * first alone instead of exhaustively gave one frame 20.7 % on one seed. */
static void
dipole_vote(dipole_work* wk, size_t n, size_t K, size_t R, int sweeps, int8_t* out)
{
  int8_t flip[DACPO_DIPOLE_MAX_RESTARTS];
  if (R <= DACPO_DIPOLE_MAX_ORDERS) {
    const unsigned mask = dipole_align(wk->cand, n, R);
    for (size_t r = 0; r < R; ++r)
      flip[r] = ((mask >> r) & 1u) ? -1 : 1;
  }
  else {
    for (size_t r = 0; r < R; ++r) {
      const int8_t* c = wk->cand + r * n;
      size_t same = 0;
      for (size_t i = 0; i < n; ++i)
        same += c[i] == wk->cand[i];
      flip[r] = 2 * same >= n ? 1 : -1;
    }
  }
  for (size_t i = 0; i < n; ++i) {
    int votes = 0;
    for (size_t r = 0; r < R; ++r)
      votes += flip[r] * wk->cand[r * n + i];
    out[i] = votes > 0 ? 1 : votes < 0 ? -1 : wk->cand[i];
  }
  dipole_sweeps(wk, n, K, sweeps, out);
}

/* One restart (paper Eq. 4 greedy + our vote and sweeps): M randomized orders,
 * aligned and majority-voted, then Gauss-Seidel sweeps in order 0's BFS order
 * until no point changes. Writes the signs to cand. */
static void
dipole_restart(dipole_work* wk,
               size_t n,
               size_t K,
               const dacpo_dipole_params* params,
               size_t r,
               int8_t* cand)
{
  const size_t M = params->orders;
  for (size_t m = 0; m < M; ++m) {
    dacpo_rng rng;
    dacpo_rng_seed(&rng, params->seed + 7919u * r, params->stream * 1000003u + m);
    dipole_one_order(wk, n, K, &rng, wk->sign + m * n, m == 0 ? wk->order0 : NULL);
  }
  /* Align, then majority vote; a tie keeps order 0's sign. */
  const unsigned flip = dipole_align(wk->sign, n, M);
  for (size_t i = 0; i < n; ++i) {
    int votes = 0;
    for (size_t m = 0; m < M; ++m)
      votes += ((flip >> m) & 1u) ? -wk->sign[m * n + i] : wk->sign[m * n + i];
    cand[i] = votes > 0 ? 1 : votes < 0 ? -1 : wk->sign[i];
  }
  dipole_sweeps(wk, n, K, params->final_sweep, cand);
}

/* The arguments dacpo_dipole_orient_confidence accepts (n >= 1). */
static dacpo_status
dipole_check(size_t n, const dacpo_dipole_params* params, dacpo_err* err)
{
  DACPO_CHECK(err,
              n <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: %zu points exceed int32 indices",
              n);
  DACPO_CHECK(err,
              params->orders >= 1 && params->orders <= DACPO_DIPOLE_MAX_ORDERS,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: orders must be in [1, %d] (got %zu)",
              DACPO_DIPOLE_MAX_ORDERS,
              params->orders);
  DACPO_CHECK(err,
              params->neighbors >= 1,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: neighbors must be >= 1");
  DACPO_CHECK(err,
              params->restarts <= DACPO_DIPOLE_MAX_RESTARTS,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: restarts must be <= %d (got %zu)",
              DACPO_DIPOLE_MAX_RESTARTS,
              params->restarts);
  return DACPO_OK;
}

/* The order and vote buffers of M orders and R restarts. */
static dacpo_status
dipole_alloc(dipole_work* wk, size_t n, size_t M, size_t R, dacpo_err* err)
{
  wk->sign = dacpo_malloc_array(M * n, sizeof(int8_t));
  wk->visited = dacpo_malloc_array(n, sizeof(uint8_t));
  wk->queue = dacpo_malloc_array(n, sizeof(int32_t));
  wk->order0 = dacpo_malloc_array(n, sizeof(int32_t));
  wk->perm = dacpo_malloc_array(n, sizeof(int32_t));
  wk->cand = dacpo_malloc_array(n * R, sizeof(int8_t));
  if (!wk->sign || !wk->visited || !wk->queue || !wk->order0 || !wk->perm || !wk->cand)
    return DACPO_OOM(err);
  return DACPO_OK;
}

/* params->thin_out / cue_out (when given): where the point side cue fired
 * (not the patch test), and whether it agrees with the returned sign. */
static void
cue_outputs(const dipole_work* wk,
            size_t n,
            const dacpo_dipole_params* params,
            const int8_t* sign_out)
{
  if (params->thin_out)
    for (size_t i = 0; i < n; ++i)
      params->thin_out[i] =
          wk->unary && wk->unary[i] != 0.0 && (!wk->patch || wk->patch[i] == 0.0);
  if (params->cue_out)
    for (size_t i = 0; i < n; ++i)
      params->cue_out[i] =
          !wk->unary || wk->unary[i] == 0.0 || (wk->patch && wk->patch[i] != 0.0) ? 0
          : (wk->unary[i] > 0.0) == (sign_out[i] > 0)                             ? 1
                                                                                  : -1;
}

dacpo_status
dacpo_dipole_orient_confidence(const double* xyz,
                               const double* nrm,
                               size_t n,
                               const dacpo_dipole_params* params,
                               int8_t* sign_out,
                               float* confidence,
                               dacpo_err* err)
{
  DACPO_CHECK(
      err, params != NULL, DACPO_ERR_INVALID_ARGUMENT, "dipole: params is NULL");
  if (n == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              xyz && nrm && sign_out,
              DACPO_ERR_INVALID_ARGUMENT,
              "dipole: NULL array for %zu points",
              n);
  DACPO_TRY(dipole_check(n, params, err));
  if (n == 1) {
    sign_out[0] = 1;
    if (confidence)
      confidence[0] = 0.0f;
    return DACPO_OK;
  }
  const size_t K = params->neighbors < n - 1 ? params->neighbors : n - 1;
  const size_t gk = (params->graph_k == 0 || params->graph_k > K) ? K : params->graph_k;
  const size_t M = params->orders;

  dipole_work wk;
  memset(&wk, 0, sizeof(wk));
  wk.xyz = xyz;
  wk.nrm = nrm;
  wk.c = params->c;
  dacpo_status st = dacpo_dipole_neighbors(xyz, nrm, n, K, params, &wk, err);
  if (st == DACPO_OK)
    st = dipole_graph(n, K, gk, &wk, err);
  if (st == DACPO_OK)
    st = dipole_alloc(&wk, n, M, params->restarts ? params->restarts : 1, err);
  if (st != DACPO_OK) {
    dipole_work_free(&wk);
    return st;
  }

  /* Restarts (each: M orders, aligned, voted, then swept) are voted point by
   * point (dipole_vote): one unlucky start no longer decides the block. */
  size_t R = params->restarts ? params->restarts : 1;
  for (size_t r = 0; r < R; ++r) {
    dipole_restart(&wk, n, K, params, r, wk.cand + r * n);
    /* the first DACPO_DIPOLE_AGREE runs gave one answer (up to the block's
       sign): the vote of more could not change it where they agree too */
    if (r + 1 == DACPO_DIPOLE_AGREE && R > r + 1 && restarts_agree(wk.cand, n, r + 1))
      R = r + 1;
  }
  if (params->restarts_out)
    *params->restarts_out = R;
  if (R > 1)
    dipole_vote(&wk, n, K, R, params->final_sweep, sign_out);
  else
    memcpy(sign_out, wk.cand, n);
  cue_outputs(&wk, n, params, sign_out);
  if (confidence)
    dipole_confidence(&wk, n, K, R, sign_out, confidence);
  dipole_work_free(&wk);
  return DACPO_OK;
}
