/* SPDX-License-Identifier: BSD-3-Clause */
/* Timing of stage 4b (dacpo_vcr_edge): two adjacent ~5K-triangle block meshes
 * (what ~2.5K-point blocks give), default parameters and variants.
 * Usage: bench_vcr [repeats [variant]]   (prints the fastest CPU ms per edge; with a
 * variant index 0-5 only that variant runs) */
#define _POSIX_C_SOURCE 200112L
#include "dacpo_vcr.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

/* CPU time of this thread: on a shared machine wall time mostly measures the
 * other jobs. */
static double
cpu_now(void)
{
  struct timespec ts;
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0)
    return dacpo_now();
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* nu x nw grid on x in [x0, x0 + 1], y in [0, 1], z = bumps + noise. */
static int
make_sheet(dacpo_mesh* m, int nu, int nw, double x0, double noise, unsigned seed)
{
  m->num_vertices = (size_t)(nu + 1) * (size_t)(nw + 1);
  m->num_triangles = 2 * (size_t)nu * (size_t)nw;
  m->vertices = (double*)malloc(3 * m->num_vertices * sizeof(double));
  m->triangles = (int32_t*)malloc(3 * m->num_triangles * sizeof(int32_t));
  if (m->vertices == NULL || m->triangles == NULL)
    return 0;
  srand(seed);
  for (int j = 0; j <= nw; ++j)
    for (int i = 0; i <= nu; ++i) {
      double x = x0 + (double)i / nu, y = (double)j / nw;
      double* p = &m->vertices[3 * ((size_t)j * (size_t)(nu + 1) + (size_t)i)];
      p[0] = x;
      p[1] = y;
      p[2] = 0.15 * sin(3.0 * x) * cos(2.0 * y) + 0.3 * x * y +
             noise * ((double)rand() / RAND_MAX - 0.5);
    }
  size_t k = 0;
  for (int j = 0; j < nw; ++j)
    for (int i = 0; i < nu; ++i) {
      int32_t a = j * (nu + 1) + i, b = a + 1, c = a + nu + 1, d = c + 1;
      int32_t tri[6] = {a, b, d, a, d, c};
      for (int q = 0; q < 6; ++q)
        m->triangles[k++] = tri[q];
    }
  return 1;
}

static double
time_edge(const dacpo_mesh* a,
          const dacpo_mesh* b,
          const dacpo_vcr_params* p,
          int reps,
          double* alpha,
          double* alpha_bar)
{
  /* the fastest of the repeats, in thread CPU time */
  dacpo_err err;
  double best = INFINITY;
  for (int r = 0; r < reps; ++r) {
    double t0 = cpu_now();
    if (dacpo_vcr_edge(a, b, p, alpha, alpha_bar, NULL, &err) != DACPO_OK) {
      fprintf(stderr, "error: %s\n", err.msg);
      return -1;
    }
    double t = cpu_now() - t0;
    best = t < best ? t : best;
  }
  return best * 1e3;
}

int
main(int argc, char** argv)
{
  int reps = argc > 1 ? atoi(argv[1]) : 10;
  int only = argc > 2 ? atoi(argv[2]) : -1;
  if (reps < 1)
    reps = 1;
  dacpo_mesh a = {0}, b = {0}, an = {0}, bn = {0};
  /* 50 x 50 cells x 2 = 5000 triangles per block */
  if (!make_sheet(&a, 50, 50, -1.0, 0.0, 1) || !make_sheet(&b, 50, 50, 0.0, 0.0, 2) ||
      !make_sheet(&an, 50, 50, -1.0, 0.03, 3) ||
      !make_sheet(&bn, 50, 50, 0.0, 0.03, 4)) {
    fprintf(stderr, "out of memory\n");
    return 1;
  }
  printf("meshes: %zu + %zu triangles, %d repeats\n",
         a.num_triangles,
         b.num_triangles,
         reps);
  struct {
    const char* name;
    dacpo_vcr_params p;
  } v[6];
  for (int i = 0; i < 6; ++i)
    dacpo_vcr_params_default(&v[i].p);
  v[0].name = "default (400 px, 12 views, ortho, C_B*C1*C2)";
  v[1].name = "image 200";
  v[1].p.image_size = 200;
  v[2].name = "perspective";
  v[2].p.perspective = 1;
  v[3].name = "no seam closing (gap_fill 0, gap_fill_edges 0)";
  v[3].p.gap_fill = 0;
  v[3].p.gap_fill_edges = 0.0;
  v[4].name = "drop_partial";
  v[4].p.experiment.drop_partial = 1;
  v[5].name = "image 800";
  v[5].p.image_size = 800;
  for (int i = 0; i < 6; ++i) {
    if (only >= 0 && i != only)
      continue;
    double al, ab, al2, ab2;
    double ms = time_edge(&a, &b, &v[i].p, reps, &al, &ab);
    double msn = time_edge(&an, &bn, &v[i].p, reps, &al2, &ab2);
    printf("%-52s smooth %7.2f ms/edge (alpha %.3g, bar %.3g) | noisy %7.2f ms/edge "
           "(alpha %.3g, bar %.3g)\n",
           v[i].name,
           ms,
           al,
           ab,
           msn,
           al2,
           ab2);
  }
  dacpo_mesh_free(&a);
  dacpo_mesh_free(&b);
  dacpo_mesh_free(&an);
  dacpo_mesh_free(&bn);
  return 0;
}
