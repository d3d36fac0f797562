/* SPDX-License-Identifier: BSD-3-Clause */
/* Benchmark of stage 5 (dacpo_ilp_solve) on random grid-like block graphs:
 * a W x H grid whose cells get a diagonal with probability p_diag (so the block
 * graph has 3-cycles, as the adjacency of a surface segmentation does), planted
 * flips, confidence-weighted edges consistent with the plant except for a share
 * of noisy edges whose preference is reversed. Prints one line per size:
 * wall time, whether optimality was proven, rows, cuts, and the objective and
 * agreement with the planted flips.
 *
 * The first series (diagonals in 70 % of the cells) is the one to quote; the
 * fully triangulated and the diagonal-free grids show the two extremes (no
 * cutting planes needed / many needed).
 *
 * Build (from the repository root; not part of the test suite):
 *   gcc -std=c11 -O2 -Ic_core/include -Ic_core/src -I/usr/include/lpsolve \
 *       tests/c_core/bench_ilp.c c_core/src/dacpo_ilp.c c_core/src/dacpo_ilp_graph.c \
 *       c_core/src/dacpo_ilp_heuristic.c c_core/src/dacpo_context.c \
 *       -L/usr/lib/lp_solve -llpsolve55 -Wl,-rpath,/usr/lib/lp_solve -lm -o bench_ilp
 * Usage: bench_ilp [time_limit_seconds] [noise] */
#include "dacpo_ilp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct bench_graph {
  size_t n, m;
  dacpo_ilp_edge* edges;
  uint8_t* planted;
} bench_graph;

/* Appends edge a-b with a confidence in [0.55, 1] for the planted relation,
 * reversed with probability noise. */
static void
bench_add(bench_graph* g, dacpo_rng* rng, size_t a, size_t b, double noise)
{
  dacpo_ilp_edge* e = &g->edges[g->m++];
  double conf = 0.55 + 0.45 * dacpo_rng_uniform(rng);
  int same = g->planted[a] == g->planted[b];
  if (dacpo_rng_uniform(rng) < noise)
    same = !same;
  e->a = (int32_t)a;
  e->b = (int32_t)b;
  e->w_same = same ? conf : 1.0 - conf;
  e->w_diff = same ? 1.0 - conf : conf;
}

static int
bench_make(size_t n, double p_diag, double noise, uint64_t seed, bench_graph* g)
{
  size_t w = (size_t)floor(sqrt((double)n) + 0.5);
  size_t h = (n + w - 1) / w;
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, n);
  g->n = n;
  g->m = 0;
  g->edges = malloc(3 * n * sizeof(*g->edges));
  g->planted = malloc(n);
  if (!g->edges || !g->planted)
    return 0;
  for (size_t i = 0; i < n; ++i)
    g->planted[i] = (uint8_t)(dacpo_rng_next(&rng) >> 63);
  for (size_t y = 0; y < h; ++y)
    for (size_t x = 0; x < w; ++x) {
      size_t v = y * w + x;
      if (v >= n)
        continue;
      if (x + 1 < w && v + 1 < n)
        bench_add(g, &rng, v, v + 1, noise);
      if (v + w < n)
        bench_add(g, &rng, v, v + w, noise);
      if (x + 1 < w && v + w + 1 < n && dacpo_rng_uniform(&rng) < p_diag) {
        if (dacpo_rng_next(&rng) >> 63)
          bench_add(g, &rng, v, v + w + 1, noise);
        else
          bench_add(g, &rng, v + 1, v + w, noise);
      }
    }
  return 1;
}

static double
bench_objective(const bench_graph* g, const uint8_t* o)
{
  double s = 0.0;
  for (size_t i = 0; i < g->m; ++i)
    s += o[g->edges[i].a] == o[g->edges[i].b] ? g->edges[i].w_same : g->edges[i].w_diff;
  return s;
}

static void
bench_run(size_t n, double p_diag, double noise, double limit, uint64_t seed)
{
  bench_graph g;
  if (!bench_make(n, p_diag, noise, seed, &g)) {
    fprintf(stderr, "out of memory\n");
    exit(1);
  }
  uint8_t* flips = malloc(n);
  dacpo_ilp_result r;
  dacpo_err err = {DACPO_OK, ""};
  dacpo_status st = dacpo_ilp_solve(n, g.m, g.edges, limit, NULL, flips, &r, &err);
  if (st != DACPO_OK) {
    printf("%5zu blocks: error %d: %s\n", n, (int)st, err.msg);
  }
  else {
    size_t agree = 0;
    for (size_t i = 0; i < n; ++i)
      agree += (flips[i] ^ flips[0]) == (g.planted[i] ^ g.planted[0]);
    printf(
        "%5zu blocks %5zu edges diag %.1f: %8.4f s  optimal %d  rows %6zu  cuts %4zu  "
        "heur_wins %zu  obj %.4f (planted %.4f)  agree %zu/%zu\n",
        n,
        g.m,
        p_diag,
        r.seconds,
        r.optimal,
        r.constraints,
        r.cuts_added,
        r.heuristic_wins,
        r.objective,
        bench_objective(&g, g.planted),
        agree,
        n);
  }
  free(flips);
  free(g.edges);
  free(g.planted);
}

int
main(int argc, char** argv)
{
  double limit = argc > 1 ? atof(argv[1]) : 30.0;
  double noise = argc > 2 ? atof(argv[2]) : 0.05;
  static const size_t sizes[4] = {100, 200, 400, 800};
  printf("noise %.3f, time limit %g s\n", noise, limit);
  for (int k = 0; k < 4; ++k)
    bench_run(sizes[k], 0.7, noise, limit, 1);
  for (int k = 0; k < 4; ++k)
    bench_run(sizes[k], 1.0, noise, limit, 2);
  for (int k = 0; k < 3; ++k)
    bench_run(sizes[k], 0.0, noise, limit, 3);
  return 0;
}
