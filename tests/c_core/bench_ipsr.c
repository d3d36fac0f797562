/* SPDX-License-Identifier: BSD-3-Clause */
/* Benchmark of stage 3 (dacpo_ipsr_block) on ~2,500-point blocks: generated
 * open and thin surfaces, and (given PLY files with ground-truth normals: float
 * x y z nx ny nz) blocks cut from real scans as the k nearest points of a
 * random seed. Every block starts from its true normals with a share flipped at
 * random. One line per block: grid, Poisson domain cells, iterations ('*' =
 * stopped at max_iterations), CPU time of the block (this thread's clock, so
 * other processes on the machine do not count) and the wall-clock split
 * (setup, then per iteration: solve, marching cubes, vote), CPU per iteration,
 * faces, peak bytes, and the share of wrong normals before and after; then a
 * summary (iterations mean/max, block and per-iteration CPU mean/max).
 *
 * Not a test. Build (from the repository root):
 *   gcc -std=c11 -O2 -Ic_core/include -Ic_core/src -Iwrappers/support \
 *     tests/c_core/bench_ipsr.c c_core/src/dacpo_ipsr.c \
 *     c_core/src/dacpo_poisson.c c_core/src/dacpo_mcubes.c \
 *     c_core/src/dacpo_kdtree.c c_core/src/dacpo_context.c \
 *     wrappers/support/dacpo_ply.c wrappers/support/dacpo_ply_write.c \
 *     -lm -o bench_ipsr
 * Usage:
 *   bench_ipsr [-n points] [-flip share] [-blocks per_scan]
 *              [-cps cell_per_spacing] [-alpha point_weight] [-tol tolerance]
 *              [-maxres cells_per_axis] [-maxcells cells] [-band cells]
 *              [-trim spacings] [-iters max] [-noise sigma_in_spacings]
 *              [-gen kinds(0-5)] [-dump path_prefix] [file.ply ...]
 * e.g. bench_ipsr -blocks 4 scans/ *.ply (without the space). */
#define _POSIX_C_SOURCE 200809L
#include "dacpo_ipsr.h"
#include "dacpo_kdtree.h"
#include "dacpo_ply.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const double kPi = 3.14159265358979323846;

typedef struct block {
  char name[64];
  size_t n;
  double* p;
  double* gt;
} block;

typedef struct summary {
  size_t blocks, iters, iters_max, unconverged;
  double wall, wall_max, cpu, cpu_max, per_iter_cpu, per_iter_cpu_max;
  double wrong_before, wrong_after;
  size_t peak_max;
} summary;

static double
cpu_now(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double
wrong_percent(const double* n, const double* gt, size_t count)
{
  size_t w = 0;
  for (size_t i = 0; i < count; ++i)
    w += n[3 * i] * gt[3 * i] + n[3 * i + 1] * gt[3 * i + 1] +
             n[3 * i + 2] * gt[3 * i + 2] <
         0;
  double pct = 100.0 * (double)w / (double)count;
  return pct < 50.0 ? pct : 100.0 - pct;
}

static int
block_alloc(block* b, const char* name, size_t n)
{
  snprintf(b->name, sizeof(b->name), "%s", name);
  b->n = n;
  b->p = malloc(3 * n * sizeof(double));
  b->gt = malloc(3 * n * sizeof(double));
  return b->p && b->gt;
}

static void
set_point(
    block* b, size_t i, double x, double y, double z, double nx, double ny, double nz)
{
  double l = sqrt(nx * nx + ny * ny + nz * nz);
  b->p[3 * i] = x, b->p[3 * i + 1] = y, b->p[3 * i + 2] = z;
  b->gt[3 * i] = nx / l, b->gt[3 * i + 1] = ny / l, b->gt[3 * i + 2] = nz / l;
}

/* The face of nf with areas a that the uniform draw w falls on. */
static int
face_by_area(const double* a, int nf, double w)
{
  double tot = 0;
  for (int f = 0; f < nf; ++f)
    tot += a[f];
  double r = w * tot;
  int f = 0;
  while (f < nf - 1 && r > a[f])
    r -= a[f++];
  return f;
}

/* Sets point i on the thin board (kind 2) from the uniform draws u, v, w. */
static void
thin_board_point(block* b, size_t i, double u, double v, double w)
{
  /* areas: top, bottom 0.12 each; sides 0.008 (x faces 0.006) */
  const double sx = 0.4, sy = 0.3, t = 0.02;
  const double a[6] = {sx * sy, sx * sy, sx * t, sx * t, sy * t, sy * t};
  const int f = face_by_area(a, 6, w);
  double s1 = u - 0.5, s2 = v - 0.5;
  if (f < 2)
    set_point(b, i, sx * s1, sy * s2, f == 0 ? t / 2 : -t / 2, 0, 0, f == 0 ? 1 : -1);
  else if (f < 4)
    set_point(b, i, sx * s1, f == 2 ? sy / 2 : -sy / 2, t * s2, 0, f == 2 ? 1 : -1, 0);
  else
    set_point(b, i, f == 4 ? sx / 2 : -sx / 2, sy * s1, t * s2, f == 4 ? 1 : -1, 0, 0);
}

/* Sets point i on the room corner (kind 3) from the uniform draws u, v, w. */
static void
room_corner_point(block* b, size_t i, double u, double v, double w)
{
  /* floor [0,1.2]^2 z=0 (+z), wall x=0 (+x), wall y=0 (+y), height 1;
   * box [0.5,0.8]^2 x [0,0.3] on the floor (top and 4 sides, outward) */
  const double a[7] = {1.44, 1.2, 1.2, 0.09, 0.09, 0.09, 0.09};
  const int f = face_by_area(a, 7, w);
  double x = 1.2 * u, y = 1.2 * v;
  if (f == 0) {
    if (x > 0.5 && x < 0.8 && y > 0.5 && y < 0.8) { /* under the box: top instead */
      set_point(b, i, x, y, 0.3, 0, 0, 1);
      return;
    }
    set_point(b, i, x, y, 0, 0, 0, 1);
  }
  else if (f == 1)
    set_point(b, i, 0, x, y / 1.2, 1, 0, 0);
  else if (f == 2)
    set_point(b, i, x, 0, y / 1.2, 0, 1, 0);
  else {
    double s = 0.5 + 0.3 * u, h = 0.3 * v;
    if (f == 3)
      set_point(b, i, 0.5, s, h, -1, 0, 0);
    else if (f == 4)
      set_point(b, i, 0.8, s, h, 1, 0, 0);
    else if (f == 5)
      set_point(b, i, s, 0.5, h, 0, -1, 0);
    else
      set_point(b, i, s, 0.8, h, 0, 1, 0);
  }
}

/* kind: 0 wavy sheet, 1 half cylinder, 2 thin board (2 cm, 40 x 30 cm), 3 room
 * corner (floor + two walls + a box on the floor), 4 S-shaped sheet. */
static int
generate(block* b, int kind, size_t n, dacpo_rng* rng)
{
  static const char* names[] = {
      "wavy_sheet", "half_cylinder", "thin_board", "room_corner", "s_sheet"};
  if (!block_alloc(b, names[kind], n))
    return 0;
  for (size_t i = 0; i < n; ++i) {
    double u = dacpo_rng_uniform(rng), v = dacpo_rng_uniform(rng),
           w = dacpo_rng_uniform(rng);
    switch (kind) {
    case 0: {
      double x = 2 * u - 1, y = 2 * v - 1;
      double dx = 0.45 * cos(3 * x) * cos(2 * y), dy = -0.3 * sin(3 * x) * sin(2 * y);
      set_point(b, i, x, y, 0.15 * sin(3 * x) * cos(2 * y), -dx, -dy, 1);
      break;
    }
    case 1: {
      double t = kPi * u;
      set_point(b, i, cos(t), 2 * v - 1, sin(t), cos(t), 0, sin(t));
      break;
    }
    case 2:
      thin_board_point(b, i, u, v, w);
      break;
    case 3:
      room_corner_point(b, i, u, v, w);
      break;
    default: {
      /* S: lower arc centre (0,0.5) r 0.5 from angle -90..90 (x>=0 side),
       * upper arc centre (0,1.5) 90..270; extruded along y in [-1,1] */
      double y = 2 * v - 1, t = kPi * u;
      if (w < 0.5) {
        double ang = -kPi / 2 + t;
        set_point(b, i, 0.5 * cos(ang), y, 0.5 + 0.5 * sin(ang), cos(ang), 0, sin(ang));
      }
      else {
        double ang = kPi / 2 + t;
        set_point(
            b, i, 0.5 * cos(ang), y, 1.5 + 0.5 * sin(ang), -cos(ang), 0, -sin(ang));
      }
      break;
    }
    }
  }
  return 1;
}

/* n nearest points of a random seed point of a scan. */
static int
cut_block(block* b,
          const char* name,
          const dacpo_ply_cloud* c,
          const dacpo_kdtree* tree,
          const double* pts,
          size_t n,
          dacpo_rng* rng)
{
  if (!block_alloc(b, name, n))
    return 0;
  size_t seed = dacpo_rng_below(rng, c->n);
  int32_t* idx = malloc(n * sizeof(int32_t));
  double* d2 = malloc(n * sizeof(double));
  if (!idx || !d2) {
    free(idx), free(d2);
    return 0;
  }
  size_t got = dacpo_kdtree_knn(tree, pts + 3 * seed, n, idx, d2);
  for (size_t i = 0; i < got; ++i) {
    size_t j = (size_t)idx[i];
    set_point(b,
              i,
              pts[3 * j],
              pts[3 * j + 1],
              pts[3 * j + 2],
              c->normals[3 * j],
              c->normals[3 * j + 1],
              c->normals[3 * j + 2]);
  }
  b->n = got;
  free(idx), free(d2);
  return 1;
}

static const char* g_dump = NULL; /* -dump prefix: write each block as PLY */

static void
dump_block(const block* b, const double* n, const dacpo_mesh* mesh)
{
  if (!g_dump)
    return;
  float* xyz = malloc(3 * b->n * sizeof(float));
  float* nf = malloc(6 * b->n * sizeof(float));
  if (xyz && nf) {
    char path[512], msg[128];
    for (size_t i = 0; i < 3 * b->n; ++i) {
      xyz[i] = (float)b->p[i];
      nf[i] = (float)b->gt[i];
      nf[3 * b->n + i] = (float)n[i];
    }
    snprintf(path, sizeof(path), "%s%s_gt.ply", g_dump, b->name);
    dacpo_ply_write(path, xyz, nf, b->n, NULL, msg, sizeof(msg));
    snprintf(path, sizeof(path), "%s%s_out.ply", g_dump, b->name);
    dacpo_ply_write(path, xyz, nf + 3 * b->n, b->n, NULL, msg, sizeof(msg));
    /* mesh vertices as points (faces are not needed for a look) */
    if (mesh->num_vertices) {
      float* mv = malloc(3 * mesh->num_vertices * sizeof(float));
      if (mv) {
        for (size_t i = 0; i < 3 * mesh->num_vertices; ++i)
          mv[i] = (float)mesh->vertices[i];
        snprintf(path, sizeof(path), "%s%s_mesh.ply", g_dump, b->name);
        dacpo_ply_write(path, mv, NULL, mesh->num_vertices, NULL, msg, sizeof(msg));
        free(mv);
      }
    }
  }
  free(xyz);
  free(nf);
}

static int
cmp_double(const void* a, const void* b)
{
  double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

/* Displaces every point by sigma * (block spacing) * N(0,1) along a random
 * direction (the paper's noise model), spacing = sqrt(median pi r_8^2 / 8). */
static void
add_noise(block* b, double sigma, dacpo_rng* rng)
{
  dacpo_kdtree* tree = NULL;
  dacpo_err err = {0};
  double* a = malloc(b->n * sizeof(double));
  if (!a || dacpo_kdtree_build(b->p, b->n, &tree, &err) != DACPO_OK) {
    free(a);
    return;
  }
  for (size_t i = 0; i < b->n; ++i) {
    int32_t idx[9];
    double d2[9];
    size_t got = dacpo_kdtree_knn(tree, b->p + 3 * i, 9, idx, d2);
    a[i] = got > 1 ? kPi * d2[got - 1] / (double)(got - 1) : 0.0;
  }
  qsort(a, b->n, sizeof(double), cmp_double);
  const double s = sigma * sqrt(a[b->n / 2]);
  dacpo_kdtree_free(tree);
  free(a);
  for (size_t i = 0; i < b->n; ++i) {
    double u1 = dacpo_rng_uniform(rng), u2 = dacpo_rng_uniform(rng);
    double g = sqrt(-2.0 * log(u1 > 1e-300 ? u1 : 1e-300)) * cos(2 * kPi * u2);
    double z = 2 * dacpo_rng_uniform(rng) - 1, ph = 2 * kPi * dacpo_rng_uniform(rng);
    double r = sqrt(1 - z * z);
    b->p[3 * i] += s * g * r * cos(ph);
    b->p[3 * i + 1] += s * g * r * sin(ph);
    b->p[3 * i + 2] += s * g * z;
  }
}

static void
run_block(const block* b,
          const dacpo_ipsr_params* prm,
          double flip,
          dacpo_rng* rng,
          summary* s)
{
  double* n = malloc(3 * b->n * sizeof(double));
  if (!n)
    return;
  for (size_t i = 0; i < b->n; ++i) {
    double sg = dacpo_rng_uniform(rng) < flip ? -1.0 : 1.0;
    for (int a = 0; a < 3; ++a)
      n[3 * i + a] = sg * b->gt[3 * i + a];
  }
  double before = wrong_percent(n, b->gt, b->n);
  dacpo_ipsr_stats st;
  dacpo_err err = {0};
  dacpo_mesh mesh;
  double c0 = cpu_now();
  dacpo_status rc = dacpo_ipsr_block(b->p, n, b->n, b->n, prm, &mesh, &st, &err);
  double cpu = cpu_now() - c0;
  if (rc != DACPO_OK) {
    printf("%-28s error %d: %s\n", b->name, (int)rc, err.msg);
    free(n);
    return;
  }
  double after = wrong_percent(n, b->gt, b->n);
  double it = st.iterations ? (double)st.iterations : 1.0;
  const double setup =
      st.seconds - st.solve_seconds - st.extract_seconds - st.vote_seconds;
  printf("%-28s n %5zu grid %3zux%3zux%3zu band %6zu it %2zu%s cg %3zu | cpu %5.0f ms"
         " (wall %5.0f: setup %4.1f, per it solve %4.1f mc %4.1f vote %4.1f) | per it "
         "cpu %5.1f"
         " ms | faces %6zu out %6zu | peak %5.1f MB | wrong %5.1f%% -> %5.2f%%\n",
         b->name,
         b->n,
         st.dims[0],
         st.dims[1],
         st.dims[2],
         st.domain_cells,
         st.iterations,
         st.converged ? " " : "*",
         st.cg_iterations,
         1e3 * cpu,
         1e3 * st.seconds,
         1e3 * setup,
         1e3 * st.solve_seconds / it,
         1e3 * st.extract_seconds / it,
         1e3 * st.vote_seconds / it,
         1e3 * cpu / it,
         st.faces,
         mesh.num_triangles,
         (double)st.peak_bytes / 1048576.0,
         before,
         after);
  fflush(stdout);
  dump_block(b, n, &mesh);
  s->blocks++;
  s->iters += st.iterations;
  if (st.iterations > s->iters_max)
    s->iters_max = st.iterations;
  s->unconverged += !st.converged;
  s->wall += st.seconds;
  if (st.seconds > s->wall_max)
    s->wall_max = st.seconds;
  s->cpu += cpu;
  if (cpu > s->cpu_max)
    s->cpu_max = cpu;
  s->per_iter_cpu += cpu / it;
  if (cpu / it > s->per_iter_cpu_max)
    s->per_iter_cpu_max = cpu / it;
  s->wrong_before += before;
  s->wrong_after += after;
  if (st.peak_bytes > s->peak_max)
    s->peak_max = st.peak_bytes;
  dacpo_mesh_free(&mesh);
  free(n);
}

static void
print_summary(const char* title, const summary* s)
{
  if (!s->blocks)
    return;
  double k = (double)s->blocks;
  printf("== %s: %zu blocks | iterations mean %.1f max %zu (not converged %zu) | block "
         "cpu "
         "mean %.0f ms max %.0f ms (wall mean %.0f max %.0f) | per-iteration cpu mean "
         "%.1f ms "
         "max %.1f ms | peak max %.1f MB | wrong mean %.2f%% -> %.2f%%\n",
         title,
         s->blocks,
         (double)s->iters / k,
         s->iters_max,
         s->unconverged,
         1e3 * s->cpu / k,
         1e3 * s->cpu_max,
         1e3 * s->wall / k,
         1e3 * s->wall_max,
         1e3 * s->per_iter_cpu / k,
         1e3 * s->per_iter_cpu_max,
         (double)s->peak_max / 1048576.0,
         s->wrong_before / k,
         s->wrong_after / k);
}

/* The command-line options (see Usage above) and where the files start. */
typedef struct options {
  size_t n, per_scan;
  int gen_kinds;
  double noise;
  double flip;
  dacpo_ipsr_params prm;
  int first_file;
} options;

/* Parses the command-line options (and -dump into g_dump); files start at
 * first_file. */
static void
parse_options(int argc, char** argv, options* o)
{
  size_t n = 2500, per_scan = 4;
  int gen_kinds = 5;
  double noise = 0.0;
  double flip = 0.3;
  dacpo_ipsr_params prm;
  dacpo_ipsr_params_default(&prm);
  int first_file = argc;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "-n") && i + 1 < argc)
      n = (size_t)atol(argv[++i]);
    else if (!strcmp(argv[i], "-flip") && i + 1 < argc)
      flip = atof(argv[++i]);
    else if (!strcmp(argv[i], "-blocks") && i + 1 < argc)
      per_scan = (size_t)atol(argv[++i]);
    else if (!strcmp(argv[i], "-cps") && i + 1 < argc)
      prm.cell_per_spacing = atof(argv[++i]);
    else if (!strcmp(argv[i], "-alpha") && i + 1 < argc)
      prm.point_weight = atof(argv[++i]);
    else if (!strcmp(argv[i], "-tol") && i + 1 < argc)
      prm.tolerance = atof(argv[++i]);
    else if (!strcmp(argv[i], "-maxres") && i + 1 < argc)
      prm.max_resolution = (size_t)atol(argv[++i]);
    else if (!strcmp(argv[i], "-maxcells") && i + 1 < argc)
      prm.max_cells = (size_t)atol(argv[++i]);
    else if (!strcmp(argv[i], "-noise") && i + 1 < argc)
      noise = atof(argv[++i]);
    else if (!strcmp(argv[i], "-dump") && i + 1 < argc)
      g_dump = argv[++i];
    else if (!strcmp(argv[i], "-band") && i + 1 < argc)
      prm.band = (size_t)atol(argv[++i]);
    else if (!strcmp(argv[i], "-trim") && i + 1 < argc)
      prm.trim_spacings = atof(argv[++i]);
    else if (!strcmp(argv[i], "-iters") && i + 1 < argc)
      prm.max_iterations = (size_t)atol(argv[++i]);
    else if (!strcmp(argv[i], "-gen") && i + 1 < argc)
      gen_kinds = atoi(argv[++i]);
    else {
      first_file = i;
      break;
    }
  }
  o->n = n;
  o->per_scan = per_scan;
  o->gen_kinds = gen_kinds;
  o->noise = noise;
  o->flip = flip;
  o->prm = prm;
  o->first_file = first_file;
}

/* Runs per_scan blocks cut from the scan at path (skipped without normals or
 * with fewer than n points), adding them to s. */
static void
run_scan(const char* path, const options* o, dacpo_rng* rng, summary* s)
{
  const size_t n = o->n;
  dacpo_ply_cloud c;
  char msg[256];
  if (dacpo_ply_read(path, &c, msg, sizeof(msg)) != DACPO_PLY_OK || !c.normals ||
      c.n < n) {
    printf("%s: skipped (%s)\n", path, c.normals ? msg : "no normals or too small");
    dacpo_ply_cloud_free(&c);
    return;
  }
  double* pts = malloc(3 * c.n * sizeof(double));
  dacpo_kdtree* tree = NULL;
  dacpo_err err = {0};
  if (pts) {
    for (size_t i = 0; i < 3 * c.n; ++i)
      pts[i] = c.xyz[i];
    /* blocks depend on the file only, not on the options before it */
    dacpo_rng_seed(rng, 7, (uint64_t)c.n);
    if (dacpo_kdtree_build(pts, c.n, &tree, &err) == DACPO_OK) {
      const char* base = strrchr(path, '/');
      base = base ? base + 1 : path;
      for (size_t r = 0; r < o->per_scan; ++r) {
        block b = {{0}, 0, NULL, NULL};
        char name[64];
        snprintf(name, sizeof(name), "%.24s#%zu", base, r);
        if (cut_block(&b, name, &c, tree, pts, n, rng)) {
          if (o->noise > 0.0)
            add_noise(&b, o->noise, rng);
          run_block(&b, &o->prm, o->flip, rng, s);
        }
        free(b.p), free(b.gt);
      }
    }
    dacpo_kdtree_free(tree);
  }
  free(pts);
  dacpo_ply_cloud_free(&c);
}

int
main(int argc, char** argv)
{
  options o;
  parse_options(argc, argv, &o);
  const size_t n = o.n;
  const int gen_kinds = o.gen_kinds;
  const double noise = o.noise, flip = o.flip;
  const dacpo_ipsr_params prm = o.prm;
  printf("bench_ipsr: n %zu, flipped %.0f%%, noise %g spacings, cell_per_spacing %g, "
         "point_weight %g, max_resolution %zu, band %zu, tolerance %g\n",
         n,
         100 * flip,
         noise,
         prm.cell_per_spacing,
         prm.point_weight,
         prm.max_resolution,
         prm.band,
         prm.tolerance);
  dacpo_rng rng;
  dacpo_rng_seed(&rng, 1, 3);
  summary gen = {0}, real = {0};
  for (int kind = 0; kind < gen_kinds; ++kind)
    for (int rep = 0; rep < 2; ++rep) {
      block b = {{0}, 0, NULL, NULL};
      if (generate(&b, kind, n, &rng)) {
        if (noise > 0.0)
          add_noise(&b, noise, &rng);
        run_block(&b, &prm, flip, &rng, &gen);
      }
      free(b.p), free(b.gt);
    }
  print_summary("generated", &gen);
  for (int f = o.first_file; f < argc; ++f)
    run_scan(argv[f], &o, &rng, &real);
  print_summary("real-scan blocks", &real);
  return 0;
}
