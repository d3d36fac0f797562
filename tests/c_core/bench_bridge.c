/* SPDX-License-Identifier: BSD-3-Clause */
/* Benchmark of the bridge policy (dacpo_bridge_components) on generated
 * clouds of C flat square patches (1 m sides, random positions and tilts in
 * a 10 m cube), n points in all, every patch one component. Prints per size
 * the wall time (best of 3), the number of bridge edges and the longest one.
 *
 * Build (from the repository root; not part of the test suite):
 *   gcc -std=c11 -O2 -Ic_core/include -Ic_core/src tests/c_core/bench_bridge.c \
 *       c_core/src/dacpo_bridge.c c_core/src/dacpo_kdtree.c c_core/src/dacpo_knn.c \
 *       c_core/src/dacpo_context.c c_core/src/dacpo_parallel.c -lm -lpthread \
 *       -o bench_bridge
 * Usage: bench_bridge            (the three sizes quoted in dacpo_bridge.c)
 *        SMALL=n COMPS=C bench_bridge   (one size) */
#define _POSIX_C_SOURCE 199309L
#include "dacpo_bridge.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double
wall(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void
run(size_t n, size_t C, uint64_t seed)
{
  dacpo_rng rng;
  dacpo_rng_seed(&rng, seed, 0);
  double* xyz = malloc(3 * n * sizeof(double));
  int32_t* comp = malloc(n * sizeof(int32_t));
  int32_t* comp0 = malloc(n * sizeof(int32_t));
  double* frame = malloc(C * 9 * sizeof(double));
  for (size_t c = 0; c < C; ++c) {
    double* f = frame + 9 * c; /* origin, two unit axes */
    double u[3], v[3];
    for (int d = 0; d < 3; ++d) {
      f[d] = 10.0 * dacpo_rng_uniform(&rng);
      u[d] = dacpo_rng_uniform(&rng) - 0.5;
      v[d] = dacpo_rng_uniform(&rng) - 0.5;
    }
    double lu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    double uv = (u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) / (lu * lu);
    for (int d = 0; d < 3; ++d)
      v[d] -= uv * u[d];
    double lv = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int d = 0; d < 3; ++d) {
      f[3 + d] = u[d] / lu;
      f[6 + d] = v[d] / lv;
    }
  }
  for (size_t i = 0; i < n; ++i) {
    size_t c = i % C;
    const double* f = frame + 9 * c;
    double a = dacpo_rng_uniform(&rng), b = dacpo_rng_uniform(&rng);
    for (int d = 0; d < 3; ++d)
      xyz[3 * i + d] = f[d] + a * f[3 + d] + b * f[6 + d];
    comp0[i] = (int32_t)c;
  }
  size_t* start = calloc(n + 1, sizeof(size_t));
  dacpo_cloud cloud;
  memset(&cloud, 0, sizeof(cloud));
  cloud.n = n;
  cloud.xyz = xyz;
  dacpo_adjacency adj = {n, start, NULL};
  double best = INFINITY, longest = 0.0;
  size_t added = 0;
  for (int rep = 0; rep < 3; ++rep) {
    for (size_t i = 0; i < n; ++i)
      comp[i] = comp0[i];
    dacpo_adjacency out;
    dacpo_err err = {DACPO_OK, ""};
    double t0 = wall();
    dacpo_status st =
        dacpo_bridge_components(&cloud, &adj, comp, C, 0, &out, &added, &longest, &err);
    double t = wall() - t0;
    if (st != DACPO_OK) {
      printf("error %d: %s\n", (int)st, err.msg);
      break;
    }
    dacpo_adjacency_free(&out);
    best = t < best ? t : best;
  }
  printf("%8zu points %5zu components: %.3f s  %zu bridges, longest %.4f\n",
         n,
         C,
         best,
         added,
         longest);
  free(xyz);
  free(comp);
  free(comp0);
  free(frame);
  free(start);
}

int
main(void)
{
  if (getenv("SMALL")) {
    run((size_t)atol(getenv("SMALL")), (size_t)atol(getenv("COMPS")), 1);
    return 0;
  }
  run(500000, 20, 1);
  run(200000, 2000, 2);
  run(4000000, 50, 3);
  return 0;
}
