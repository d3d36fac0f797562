/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * pcl_dacpo_orient_mpi: dacpo_orient() with its block and edge units spread
 * over MPI ranks (dacpo_advanced.h). Plain C; MPI only here, never in the core.
 *
 *   mpirun -np R pcl_dacpo_orient_mpi in.ply|pcd out.ply|pcd [-estimate] [-whole]
 *          [-spread_knn] [-knn_halo H] [-tiles P | -memory X] [-tile_halo H]
 *          [-report F] [-q] [every "-flag X" of the parameter table: -k, -c, ...]
 *
 * Rank 0 reads the cloud and runs stages 0-1 (k-NN graph, normals, blocks;
 * -spread_knn: the k-NN search spread over the ranks, dacpo_mpi_knn.h: one
 * slab per rank with a halo) and 5-6 (the 0-1 program, parts, global sign);
 * the blocks (stages 2-3) and then
 * the edges (stage 4, VCR) are dealt out to all ranks, rank 0 included, by
 * estimated cost (a block: its own and ring points; an edge: the triangles of
 * its two meshes), longest first to the least loaded rank. A block travels as
 * its points and the run's parameters, its answer as normals, confidences and
 * mesh; an edge as its two meshes, its answer as two numbers. Every unit runs
 * the same code as in dacpo_orient() with the block's own random stream, so
 * the normals are the same bytes for any number of ranks (-whole: rank 0 runs
 * dacpo_orient() itself, for comparison).
 *
 * In this mode rank 0 holds the whole cloud (the other ranks hold only their
 * units, and their slab with -spread_knn), reads it alone, writes the output
 * alone and runs stages 0-1 past the neighbour search alone. -tiles P /
 * -memory X (dacpo_mpi_tiles.c) is the mode without a whole cloud anywhere:
 * spatial tiles, each oriented by dacpo_orient() on one rank, their signs
 * joined from the halos; the bytes of pcl_dacpo_orient -memory for any R.
 *
 * Input: PLY (ascii or binary) or PCD (ascii, binary or binary_compressed), by
 * extension (wrappers/support/dacpo_pcd.h). Output: binary PLY (float x y z nx
 * ny nz) or binary PCD (float x y z normal_x normal_y normal_z), by the
 * output's extension, in input order. -report F writes one JSON object per
 * rank (wall seconds per phase, peak RSS, bytes sent and received, units run).
 *
 * Exit status: 0 on success, 1 for bad arguments, 2 when reading, orienting or
 * writing fails (every rank exits with the same status; a unit that fails
 * during the exchange stops all ranks with MPI_Abort).
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */

#include <dacpo/dacpo.h>
#include <dacpo/dacpo_advanced.h>
#include <dacpo/dacpo_param_table.h>

#include "dacpo_mpi_comm.h"
#include "dacpo_mpi_knn.h"
#include "dacpo_mpi_tiles.h"
#include "dacpo_tiled.h"
#include "dacpo_cleanup.h"
#include "dacpo_paths.h"
#include "dacpo_pcd.h"
#include <sys/resource.h>

#include <errno.h>
#include <math.h>
#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

enum { TAG_BLOCK = 1, TAG_RESULT = 2, TAG_EDGE = 3 };

typedef struct options {
  const char* in;
  const char* out;
  const char* report;
  int estimate, whole, quiet, spread_knn;
  double knn_halo;
  uint64_t tile_points; /* -tiles P / -memory X: tiled mode, 0 = off */
  double tile_halo;
  dacpo_params p;
} options;

/* What each rank measures. */
typedef struct rank_report {
  double wall[5]; /* read + stages 0-1, blocks, edges, solve + finish, write */
  double peak_rss_mb;
  dacpo_mpi_traffic traffic;
  double blocks, edges; /* units run here */
  double busy;          /* seconds in this rank's units */
  double knn;           /* seconds in this rank's share of the k-NN search */
  double knn_rounds;    /* halo widths the search tried (rank 0; 0: rank 0 alone) */
} rank_report;

static double
now(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double
peak_rss_mb(void)
{
  struct rusage u;
  getrusage(RUSAGE_SELF, &u);
  return (double)u.ru_maxrss / 1024.0; /* Linux: kilobytes */
}

static int
parse_size(const char* s, size_t* out)
{
  char* end = NULL;
  errno = 0;
  const unsigned long long v = strtoull(s, &end, 10);
  if (errno || end == s || *end != '\0' || s[0] == '-')
    return 0;
  *out = (size_t)v;
  return 1;
}

/* A positive finite number for option name, or 0 with a message. */
static int
positive(const char* text, double* out, const char* name, char* msg, size_t msg_size)
{
  char* end = NULL;
  *out = strtod(text, &end);
  if (*end != '\0' || !(*out > 0.0) || !isfinite(*out)) {
    snprintf(msg, msg_size, "%s needs a positive number, got %s", name, text);
    return 0;
  }
  return 1;
}

/* Outputs are checked before the work: a known format, a writable folder. */
static int
check_outputs(const options* o, char* msg, size_t msg_size)
{
  if (!dacpo_is_pcd_path(o->out) && !dacpo_is_ply_path(o->out)) {
    snprintf(msg, msg_size, "the output must be a .ply or .pcd file, got %s", o->out);
    return 0;
  }
  return dacpo_output_path_check(o->out, msg, msg_size) == 0 &&
         (!o->report || dacpo_output_path_check(o->report, msg, msg_size) == 0);
}

/* The dacpo_params field an option of the parameter table sets (its VALUE
 * rows, as pcl_dacpo_orient takes them), or NULL. */
static const char*
param_option(const char* flag)
{
#define DACPO_MPI_VALUE(name, f)                                               \
  if (!strcmp(flag, f))                                                        \
    return #name;
#define DACPO_MPI_SPECIAL(name, f)
#define DACPO_MPI_NONE(name, f)
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, f, doc) DACPO_MPI_##cli(name, f)
  DACPO_PARAMS()
#undef DACPO_PARAM
  return NULL;
}

static int
parse_args(int argc, char** argv, options* o, char* msg, size_t msg_size)
{
  memset(o, 0, sizeof(*o));
  dacpo_params_init(&o->p);
  o->p.num_threads = 1;
  size_t v = 0;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const int has_value = i + 1 < argc;
    if (!strcmp(a, "-estimate"))
      o->estimate = 1;
    else if (!strcmp(a, "-whole"))
      o->whole = 1;
    else if (!strcmp(a, "-q"))
      o->quiet = 1;
    else if (!strcmp(a, "-spread_knn"))
      o->spread_knn = 1;
    else if (!strcmp(a, "-knn_halo") && has_value) {
      if (!positive(argv[++i], &o->knn_halo, "-knn_halo", msg, msg_size))
        return 0;
    }
    else if (!strcmp(a, "-memory") && has_value) {
      double x = 0.0;
      if (!dacpo_tiled_parse_size(argv[++i], &x)) {
        snprintf(msg, msg_size, "-memory needs a size such as 4G, got %s", argv[i]);
        return 0;
      }
      o->tile_points = dacpo_tiled_points_for_memory(x);
    }
    else if (!strcmp(a, "-tile_halo") && has_value) {
      if (!positive(argv[++i], &o->tile_halo, "-tile_halo", msg, msg_size))
        return 0;
    }
    else if (!strcmp(a, "-report") && has_value)
      o->report = argv[++i];
    else if (!strcmp(a, "-tiles") && has_value) {
      if (!parse_size(argv[++i], &v) || v < 16) {
        snprintf(msg, msg_size, "-tiles needs a point count >= 16, got %s", argv[i]);
        return 0;
      }
      o->tile_points = v;
    }
    else if (param_option(a) && has_value) {
      char why[200] = "";
      if (dacpo_params_set(&o->p, param_option(a), argv[++i], why, sizeof(why)) != DACPO_OK) {
        snprintf(msg, msg_size, "%s %s (%s)", a, argv[i], why);
        return 0;
      }
    }
    else if (a[0] == '-') {
      snprintf(msg, msg_size, "unknown option or missing number: %s", a);
      return 0;
    }
    else if (!o->in)
      o->in = a;
    else if (!o->out)
      o->out = a;
    else {
      snprintf(msg, msg_size, "one input and one output, got also %s", a);
      return 0;
    }
  }
  if (!o->in || !o->out) {
    snprintf(
        msg,
        msg_size,
        "usage: mpirun -np R pcl_dacpo_orient_mpi in.ply|pcd out.ply|pcd [-estimate] "
        "[-whole] [-spread_knn] [-knn_halo H] [-tiles P | -memory X] [-report F] [-q] "
        "[-k K -c C -seed S ...: -h lists them]");
    return 0;
  }
  if (dacpo_params_validate(&o->p, msg, msg_size) != DACPO_OK)
    return 0;
  return check_outputs(o, msg, msg_size);
}

/* ---- dealing out units ------------------------------------------------- */

/* A unit's task and result on a rank that is not rank 0. */
typedef struct unit_msg {
  void* task;
  size_t task_size;
  void* res;
  size_t res_size;
} unit_msg;

/* A unit that fails in the middle of the exchange leaves the other ranks
 * waiting for messages that will not come: the whole run stops (exit status 2). */
static void
unit_failed(int rank, const char* msg)
{
  fprintf(stderr, "Error (rank %d): %s\n", rank, msg);
  MPI_Abort(MPI_COMM_WORLD, 2);
}

/* ---- units ------------------------------------------------------------- */

/* One kind of unit (blocks, edges) as the exchange sees it: its task made on
 * rank 0, run in place on rank 0, run from its task on another rank (the
 * answer as bytes), the answer put into the job on rank 0. */
typedef struct unit_kind {
  const char* name;
  int tag;
  dacpo_status (*task)(const dacpo_job*, size_t, void**, size_t*, char*, size_t);
  dacpo_status (*local)(dacpo_job*, size_t, char*, size_t);
  dacpo_status (*run)(const void*, size_t, size_t, void**, size_t*, char*, size_t);
  void (*free_answer)(void*);
  dacpo_status (*put)(dacpo_job*, const void*, size_t, char*, size_t);
} unit_kind;

static dacpo_status
run_block(const void* task,
          size_t size,
          size_t unit,
          void** answer,
          size_t* answer_size,
          char* msg,
          size_t msg_size)
{
  (void)unit; /* the block's id travels in its result */
  return dacpo_block_task_run(task, size, answer, answer_size, msg, msg_size);
}

/* An edge's answer: its id, alpha and alpha_bar as three doubles. */
static dacpo_status
run_edge(const void* task,
         size_t size,
         size_t unit,
         void** answer,
         size_t* answer_size,
         char* msg,
         size_t msg_size)
{
  double* ab = malloc(3 * sizeof(double));
  if (!ab) {
    snprintf(msg, msg_size, "out of memory for an edge's answer");
    return DACPO_ERR_OUT_OF_MEMORY;
  }
  ab[0] = (double)unit;
  const dacpo_status st =
      dacpo_edge_task_run(task, size, &ab[1], &ab[2], msg, msg_size);
  if (st != DACPO_OK) {
    free(ab);
    return st;
  }
  *answer = ab;
  *answer_size = 3 * sizeof(double);
  return DACPO_OK;
}

static dacpo_status
put_edge(dacpo_job* job, const void* answer, size_t size, char* msg, size_t msg_size)
{
  double ab[3];
  if (size != sizeof(ab)) {
    snprintf(msg, msg_size, "an edge's answer of %zu bytes", size);
    return DACPO_ERR_INVALID_ARGUMENT;
  }
  memcpy(ab, answer, sizeof(ab));
  if (!(ab[0] >= 0.0 && ab[0] < (double)dacpo_job_num_edges(job))) {
    snprintf(msg, msg_size, "an edge's answer names edge %g", ab[0]);
    return DACPO_ERR_INVALID_ARGUMENT;
  }
  return dacpo_job_put_edge(job, (size_t)ab[0], ab[1], ab[2], msg, msg_size);
}

static const unit_kind blocks_kind = {"block",
                                      TAG_BLOCK,
                                      dacpo_job_block_task,
                                      dacpo_job_orient_block,
                                      run_block,
                                      dacpo_unit_bytes_free,
                                      dacpo_job_put_block};
static const unit_kind edges_kind = {"edge",
                                     TAG_EDGE,
                                     dacpo_job_edge_task,
                                     dacpo_job_weigh_edge,
                                     run_edge,
                                     free,
                                     put_edge};

/* Rank 0: the tasks out to their owners, its own units in place, the answers
 * back into the job. */
static int
deal_from_rank0(dacpo_job* job,
                const unit_kind* k,
                size_t count,
                const int* owner,
                rank_report* rep,
                double* ran,
                char* msg,
                size_t msg_size)
{
  int ok = 1;
  for (size_t u = 0; u < count && ok; ++u)
    if (owner[u] != 0) {
      void* task = NULL;
      size_t size = 0;
      ok = k->task(job, u, &task, &size, msg, msg_size) == DACPO_OK &&
           size <= (size_t)INT32_MAX;
      if (ok)
        dacpo_mpi_send(task, size, owner[u], k->tag, &rep->traffic);
      dacpo_unit_bytes_free(task);
    }
  for (size_t u = 0; u < count && ok; ++u)
    if (owner[u] == 0) {
      const double t = now();
      ok = k->local(job, u, msg, msg_size) == DACPO_OK;
      rep->busy += now() - t;
      *ran += 1.0;
    }
  for (size_t u = 0; u < count && ok; ++u)
    if (owner[u] != 0) {
      size_t size = 0;
      void* answer =
          dacpo_mpi_recv(MPI_ANY_SOURCE, TAG_RESULT, &size, NULL, &rep->traffic);
      ok = k->put(job, answer, size, msg, msg_size) == DACPO_OK;
      free(answer);
    }
  return ok;
}

/* Another rank: all its tasks in first (rank 0 sends them one after the
 * other and must not wait for this rank's computing), then run, then all
 * answers out. */
static int
work_for_rank0(const unit_kind* k,
               size_t count,
               const int* owner,
               int rank,
               rank_report* rep,
               double* ran,
               char* msg,
               size_t msg_size)
{
  unit_msg* m = calloc(count + 1, sizeof(unit_msg));
  int ok = m != NULL;
  for (size_t u = 0; u < count && ok; ++u)
    if (owner[u] == rank)
      m[u].task = dacpo_mpi_recv(0, k->tag, &m[u].task_size, NULL, &rep->traffic);
  for (size_t u = 0; u < count && ok; ++u)
    if (owner[u] == rank) {
      const double t = now();
      ok =
          k->run(
              m[u].task, m[u].task_size, u, &m[u].res, &m[u].res_size, msg, msg_size) ==
          DACPO_OK;
      rep->busy += now() - t;
      free(m[u].task);
      m[u].task = NULL;
      *ran += 1.0;
    }
  for (size_t u = 0; u < count && ok; ++u)
    if (owner[u] == rank) {
      /* MPI counts are int: a block of some 40M points would not fit */
      ok = m[u].res_size <= (size_t)INT32_MAX;
      if (ok)
        dacpo_mpi_send(m[u].res, m[u].res_size, 0, TAG_RESULT, &rep->traffic);
      else
        snprintf(msg,
                 msg_size,
                 "the answer of %s %zu has %zu bytes",
                 k->name,
                 u,
                 m[u].res_size);
    }
  for (size_t u = 0; u < count; ++u)
    if (m && owner[u] == rank)
      k->free_answer(m[u].res);
  free(m);
  return ok;
}

static int
run_units(dacpo_job* job,
          const unit_kind* k,
          size_t count,
          const int* owner,
          int rank,
          rank_report* rep,
          double* ran)
{
  char msg[512] = "";
  const int ok =
      rank == 0 ? deal_from_rank0(job, k, count, owner, rep, ran, msg, sizeof(msg))
                : work_for_rank0(k, count, owner, rank, rep, ran, msg, sizeof(msg));
  if (!ok) {
    char what[64];
    snprintf(what, sizeof(what), "a %s failed", k->name);
    unit_failed(rank, msg[0] ? msg : what);
  }
  return ok;
}

/* ---- the run ------------------------------------------------------------ */

/* From rank 0 to all: the number of units and each one's cost, the size of
 * its task (a block: 48 bytes per own or ring point; an edge: its two meshes,
 * known once the blocks are done). */
static double*
share_costs(dacpo_job* job, int rank, int edges, size_t* count)
{
  uint64_t c = 0;
  if (rank == 0)
    c = edges ? dacpo_job_num_edges(job) : dacpo_job_num_blocks(job);
  MPI_Bcast(&c, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
  *count = (size_t)c;
  double* cost = malloc((*count + 1) * sizeof(double));
  int ok = cost != NULL;
  for (size_t u = 0; ok && rank == 0 && u < *count; ++u) {
    size_t size = 0;
    ok = (edges ? dacpo_job_edge_task(job, u, NULL, &size, NULL, 0)
                : dacpo_job_block_task(job, u, NULL, &size, NULL, 0)) == DACPO_OK;
    cost[u] = (double)size;
  }
  if (!dacpo_mpi_all_ok(ok)) {
    free(cost);
    return NULL;
  }
  MPI_Bcast(cost, (int)*count, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  return cost;
}

/* Rank 0: read the cloud; the run's parameters. */
static int
read_input(const options* o, dacpo_ply_cloud* cloud, dacpo_params* p)
{
  char msg[512];
  const int rc = dacpo_is_pcd_path(o->in) ? dacpo_points_read(o->in, cloud, msg, sizeof(msg))
                                          : dacpo_ply_read_exact(o->in, cloud, msg, sizeof(msg));
  if (rc != DACPO_PLY_OK) {
    fprintf(stderr, "Error: %s\n", msg);
    return 0;
  }
  *p = o->p;
  p->estimate_normals = o->estimate || cloud->normals == NULL;
  if (!cloud->normals) {
    cloud->normals = calloc(3 * cloud->n + 1, sizeof(float));
    if (!cloud->normals)
      return 0;
  }
  return 1;
}

/* The nearest per point the distributed search gathers: stage 0's largest k,
 * the point itself, and 4 for exact duplicates (with more, dacpo_job_create
 * asks for more than the table holds and rank 0 searches alone). */
static size_t
table_width(const dacpo_params* p, size_t n)
{
  size_t k = p->k;
  /* the core's widest PCA neighbourhood (3/2 x normal_k when adaptive) */
  const size_t nk = p->adaptive_normals ? (3 * p->normal_k + 1) / 2 : p->normal_k;
  if (p->estimate_normals && nk > k)
    k = nk;
  return k + 5 < n ? k + 5 : n;
}

/* Rank 0: stages 0-1, over the gathered rows when there are any. */
static int
create_job(dacpo_ctx* ctx,
           const dacpo_params* p,
           dacpo_ply_cloud* cloud,
           dacpo_knn_table* table,
           dacpo_job** job)
{
  dacpo_search search = {dacpo_knn_table_search, table};
  dacpo_status st = dacpo_job_create(ctx,
                                     p,
                                     table->ids ? &search : NULL,
                                     NULL,
                                     cloud->xyz,
                                     cloud->normals,
                                     cloud->n,
                                     job);
  if (st == DACPO_ERR_NEIGHBOR_SEARCH && table->ids) {
    fprintf(stderr, "Note: %s: rank 0 searches alone\n", dacpo_ctx_last_error(ctx));
    st =
        dacpo_job_create(ctx, p, NULL, NULL, cloud->xyz, cloud->normals, cloud->n, job);
  }
  dacpo_knn_table_free(table);
  if (st != DACPO_OK) {
    fprintf(stderr, "Error: %s\n", dacpo_ctx_last_error(ctx));
    return 0;
  }
  return 1;
}

static int
write_report(const options* o, const rank_report* all, int ranks)
{
  FILE* f = o->report ? fopen(o->report, "w") : NULL;
  if (o->report && !f) {
    fprintf(stderr, "Error: cannot write %s: %s\n", o->report, strerror(errno));
    return 0;
  }
  if (!o->quiet)
    printf("rank  read+0-1    knn  blocks   edges  solve  write   busy  peak RSS MB  "
           "sent MB  recv MB  blocks edges\n");
  for (int r = 0; r < ranks; ++r) {
    const rank_report* x = all + r;
    if (!o->quiet)
      printf("%4d %9.2f %6.2f %7.2f %7.2f %6.2f %6.2f %6.2f %12.1f %8.1f %8.1f %7.0f "
             "%5.0f\n",
             r,
             x->wall[0],
             x->knn,
             x->wall[1],
             x->wall[2],
             x->wall[3],
             x->wall[4],
             x->busy,
             x->peak_rss_mb,
             x->traffic.sent_mb,
             x->traffic.received_mb,
             x->blocks,
             x->edges);
    if (f)
      fprintf(
          f,
          "{\"rank\": %d, \"ranks\": %d, \"read_stages01_s\": %.3f, \"knn_s\": %.3f, "
          "\"knn_rounds\": %.0f, \"blocks_s\": "
          "%.3f, \"edges_s\": %.3f, \"solve_s\": %.3f, \"write_s\": %.3f, "
          "\"busy_s\": %.3f, \"peak_rss_mb\": %.1f, \"sent_mb\": %.3f, "
          "\"received_mb\": %.3f, "
          "\"blocks\": %.0f, \"edges\": %.0f}\n",
          r,
          ranks,
          x->wall[0],
          x->knn,
          x->knn_rounds,
          x->wall[1],
          x->wall[2],
          x->wall[3],
          x->wall[4],
          x->busy,
          x->peak_rss_mb,
          x->traffic.sent_mb,
          x->traffic.received_mb,
          x->blocks,
          x->edges);
  }
  if (f && fclose(f) != 0) {
    fprintf(stderr, "Error: cannot write %s: %s\n", o->report, strerror(errno));
    return 0;
  }
  return 1;
}

/* Stages 2-6 over the ranks (or dacpo_orient() on rank 0 with -whole). */
static int
orient(const options* o,
       dacpo_ctx* ctx,
       dacpo_job* job,
       dacpo_ply_cloud* cloud,
       const dacpo_params* p,
       int rank,
       int ranks,
       rank_report* rep,
       double* t)
{
  if (o->whole) {
    int ok = rank != 0 ||
             dacpo_orient(ctx, p, NULL, NULL, cloud->xyz, cloud->normals, cloud->n) ==
                 DACPO_OK;
    if (!ok)
      fprintf(stderr, "Error: %s\n", dacpo_ctx_last_error(ctx));
    return dacpo_mpi_all_ok(ok);
  }
  size_t nb = 0, ne = 0;
  double* bcost = share_costs(job, rank, 0, &nb);
  int* bowner = bcost ? dacpo_mpi_deal(bcost, nb, ranks) : NULL;
  int ok = dacpo_mpi_all_ok(bowner != NULL) &&
           dacpo_mpi_all_ok(
               run_units(job, &blocks_kind, nb, bowner, rank, rep, &rep->blocks));
  rep->wall[1] = now() - *t;
  *t = now();
  double* ecost = ok ? share_costs(job, rank, 1, &ne) : NULL;
  int* eowner = ecost ? dacpo_mpi_deal(ecost, ne, ranks) : NULL;
  ok =
      ok && dacpo_mpi_all_ok(eowner != NULL) &&
      dacpo_mpi_all_ok(run_units(job, &edges_kind, ne, eowner, rank, rep, &rep->edges));
  rep->wall[2] = now() - *t;
  *t = now();
  if (ok && rank == 0) {
    ok = dacpo_job_solve(job) == DACPO_OK &&
         dacpo_job_finish(job, cloud->normals) == DACPO_OK;
    if (!ok)
      fprintf(stderr, "Error: %s\n", dacpo_ctx_last_error(ctx));
  }
  free(bcost);
  free(ecost);
  free(bowner);
  free(eowner);
  return dacpo_mpi_all_ok(ok);
}

/* The output goes to a file beside the target first and is renamed over it
 * only when complete: a failed run never leaves half a file under its name. */
static int
write_output(const char* path, dacpo_ply_cloud* cloud)
{
  char msg[512];
  const size_t len = strlen(path) + 64;
  char* tmp = malloc(len);
  int ok = tmp != NULL && dacpo_temp_sibling(path, "tmp", (long)getpid(), tmp, len) == 0;
  if (tmp && !ok)
    fprintf(stderr, "Error: '%s': name too long for a temporary file beside it\n", path);
  const int slot = ok ? dacpo_cleanup_add(tmp) : -1;
  if (ok) {
    /* the format of the target's name, not of the temporary one */
    const int pcd = dacpo_is_pcd_path(path);
    /* coordinates float cannot hold: written back as read into PLY; a PCD
       (float fields) gets the nearest floats, not the offsets computed on */
    for (size_t i = 0; pcd && cloud->xyz_exact && i < 3 * cloud->n; ++i)
      cloud->xyz[i] = (float)cloud->xyz_exact[i];
    if (!pcd && cloud->xyz_exact)
      ok = dacpo_ply_write_exact(tmp, cloud->xyz_exact, cloud->normals, cloud->n,
                                 "pcl_dacpo_orient_mpi", msg, sizeof(msg)) == DACPO_PLY_OK;
    else
      ok = (pcd ? dacpo_pcd_write : dacpo_ply_write)(tmp, cloud->xyz, cloud->normals, cloud->n,
                                                     "pcl_dacpo_orient_mpi", msg,
                                                     sizeof(msg)) == DACPO_PLY_OK;
    if (!ok)
      fprintf(stderr, "Error: %s\n", msg);
    else if (rename(tmp, path) != 0) {
      fprintf(
          stderr, "Error: cannot rename %s to %s: %s\n", tmp, path, strerror(errno));
      ok = 0;
    }
    if (!ok)
      remove(tmp);
  }
  dacpo_cleanup_drop(slot);
  free(tmp);
  return ok;
}

/* -tiles / -memory: dacpo_mpi_tiles.c, then the rank table. */
static int
tiled_main(const options* o, int rank, int ranks)
{
  if (!dacpo_is_ply_path(o->out)) {
    if (rank == 0)
      fprintf(stderr, "Error: -tiles / -memory write a .ply, got %s\n", o->out);
    MPI_Finalize();
    return 1;
  }
  dacpo_mpi_tiles_report rep;
  const double t0 = now();
  int ok =
      dacpo_mpi_tiles_orient(o->in, o->out, &o->p, o->tile_points, o->tile_halo, rank, ranks, &rep);
  const double wall = now() - t0;
  const double rss = peak_rss_mb();
  double mine[12] = {rep.wall[0], rep.wall[1], rep.wall[2], rep.wall[3], rep.wall[4], rep.busy,
                     rep.tiles, rep.held_points, rss, rep.traffic.sent_mb,
                     rep.traffic.received_mb, wall};
  double* all = rank == 0 ? malloc(12 * (size_t)ranks * sizeof(double)) : NULL;
  MPI_Gather(mine, 12, MPI_DOUBLE, all, 12, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  if (rank == 0 && ok && all) {
    FILE* f = o->report ? fopen(o->report, "w") : NULL;
    if (!o->quiet)
      printf("tiles=%.0f halo=%.4g flipped_tiles=%.0f\n"
             "rank  read+plan  route  tiles   join  write   busy  tiles  held points  "
             "peak RSS MB  sent MB  recv MB\n",
             rep.num_tiles, rep.halo, rep.flipped_tiles);
    for (int r = 0; r < ranks; ++r) {
      const double* x = all + 12 * r;
      if (!o->quiet)
        printf("%4d %10.2f %6.2f %6.2f %6.2f %6.2f %6.2f %6.0f %12.0f %12.1f %8.1f %8.1f\n",
               r, x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], x[9], x[10]);
      if (f)
        fprintf(f,
                "{\"rank\": %d, \"ranks\": %d, \"mode\": \"tiles\", \"num_tiles\": %.0f, "
                "\"halo\": %.6g, \"read_plan_s\": %.3f, \"route_s\": %.3f, \"tiles_s\": %.3f, "
                "\"join_s\": %.3f, \"write_s\": %.3f, \"busy_s\": %.3f, \"tiles\": %.0f, "
                "\"held_points\": %.0f, \"peak_rss_mb\": %.1f, \"sent_mb\": %.3f, "
                "\"received_mb\": %.3f, \"wall_s\": %.3f}\n",
                r, ranks, rep.num_tiles, rep.halo, x[0], x[1], x[2], x[3], x[4], x[5], x[6],
                x[7], x[8], x[9], x[10], x[11]);
    }
    if (o->report && (!f || fclose(f) != 0)) {
      fprintf(stderr, "Error: cannot write %s: %s\n", o->report, strerror(errno));
      ok = 0;
    }
  }
  free(all);
  MPI_Finalize();
  return ok ? 0 : 2;
}

/* "  -flag X  doc (default: v)" for every VALUE row of the parameter table,
 * the doc wrapped at 64 columns. */
#define DACPO_MPI_FMT_SIZE(v) "%zu", (v)
#define DACPO_MPI_FMT_REAL(v) "%g", (v)
#define DACPO_MPI_FMT_FLAG(v) "%d", (v)
#define DACPO_MPI_FMT_INT(v) "%d", (v)
#define DACPO_MPI_FMT_UINT(v) "%u", (v)
#define DACPO_MPI_FMT_U64(v) "%llu", (unsigned long long)(v)

static void
print_param_line(const char* flag, const char* doc, const char* def)
{
  printf("  %-18s", flag);
  size_t col = 20;
  const char* w = doc;
  while (*w) {
    size_t len = strcspn(w, " ");
    if (col + len > 78) {
      printf("\n%20s", "");
      col = 20;
    }
    printf("%.*s%s", (int)len, w, w[len] ? " " : "");
    col += len + 1;
    w += len + (w[len] ? 1 : 0);
  }
  printf(" (default: %s)\n", def);
}

static void
print_param_options(const dacpo_params* d)
{
  char def[64];
#define DACPO_MPI_HELP_VALUE(kind, name, f, doc)                               \
  snprintf(def, sizeof(def), DACPO_MPI_FMT_##kind(d->name));                   \
  print_param_line(f " X", doc, def);
#define DACPO_MPI_HELP_SPECIAL(kind, name, f, doc)
#define DACPO_MPI_HELP_NONE(kind, name, f, doc)
#define DACPO_PARAM(kind, type, name, def_, lo, hi, who, cli, f, doc)                        \
  DACPO_MPI_HELP_##cli(kind, name, f, doc)
  DACPO_PARAMS()
#undef DACPO_PARAM
}

static void
print_help(void)
{
  dacpo_params d;
  dacpo_params_init(&d);
  printf(
      "Orient the normals of a PLY or PCD point cloud with DACPO, its blocks and\n"
      "edges spread over MPI ranks; the output is byte-identical to one process.\n\n"
      "Usage: mpirun -np R pcl_dacpo_orient_mpi in.ply|pcd out.ply|pcd [options]\n\n"
      "Options:\n"
      "  -estimate     estimate PCA normals even when the file has nx ny nz (without\n"
      "                them they are always estimated)\n"
      "  -whole        rank 0 runs dacpo_orient() alone (for comparison)\n"
      "  -spread_knn   stage 0's neighbour search spread over the ranks (one slab of\n"
      "                the cloud per rank, with a halo); default: rank 0 alone with\n"
      "                -threads (10M points, 2 cores: 42 s alone, 60 s spread)\n"
      "  -knn_halo H   -spread_knn's first halo width, in the cloud's units (default:\n"
      "                from its box and size; rows it does not cover ask again 4x "
      "wider)\n"
      "  -tiles P      tiled mode: no rank holds the whole cloud; every rank reads its\n"
      "                own byte range of a binary PLY, points go to spatial tiles of\n"
      "                at most P points (own + halo) dealt to the ranks by size, each\n"
      "                tile is oriented by dacpo_orient(), their signs are joined on\n"
      "                rank 0 from the halos, and every rank writes its range (MPI-IO).\n"
      "                Same bytes as pcl_dacpo_orient -memory with the same tile size,\n"
      "                for any number of ranks. Output .ply only.\n"
      "  -memory X     tiled mode with the tile size of pcl_dacpo_orient -memory X\n"
      "                (X bytes per rank, e.g. 4G)\n"
      "  -tile_halo H  tiled mode: how far a tile reads beyond its cell (default: 16\n"
      "                spacings of the cloud)\n"
      "  -report F     one JSON line per rank: wall time per phase, time in its "
      "units,\n"
      "                peak RSS, MB sent and received\n"
      "  -q            no rank table on stdout\n\n"
      "Input: PLY (ascii or binary) or PCD (ascii, binary or binary_compressed), by\n"
      "extension. Output: binary PLY (x y z nx ny nz) or binary PCD (x y z\n"
      "normal_x normal_y normal_z) by the output's extension, in input order.\n"
      "As root, Open MPI needs --allow-run-as-root (or OMPI_ALLOW_RUN_AS_ROOT=1\n"
      "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1).\n"
      "Exit status: 0 success, 1 bad arguments, 2 reading, orienting or writing "
      "failed.\n");
  d.num_threads = 1; /* rank 0's stages 0-1; the units run one per rank */
  printf("\nThe method's parameters (as pcl_dacpo_orient takes them):\n");
  print_param_options(&d);
}

int
main(int argc, char** argv)
{
  MPI_Init(&argc, &argv);
  dacpo_cleanup_install();
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  options o;
  char msg[512];
  for (int i = 1; i < argc; ++i)
    if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
      if (rank == 0)
        print_help();
      MPI_Finalize();
      return 0;
    }
  if (!parse_args(argc, argv, &o, msg, sizeof(msg))) {
    if (rank == 0)
      fprintf(stderr, "Error: %s\n", msg);
    MPI_Finalize();
    return 1;
  }
  if (o.tile_points)
    return tiled_main(&o, rank, ranks);
  rank_report rep;
  memset(&rep, 0, sizeof(rep));
  double t = now();
  dacpo_ctx* ctx = NULL;
  dacpo_job* job = NULL;
  dacpo_ply_cloud cloud;
  memset(&cloud, 0, sizeof(cloud));
  dacpo_params p = o.p;
  int ok = 1;
  if (rank == 0)
    ok = dacpo_ctx_create(&ctx) == DACPO_OK && read_input(&o, &cloud, &p);
  ok = dacpo_mpi_all_ok(ok);
  dacpo_knn_table table;
  memset(&table, 0, sizeof(table));
  if (ok && !o.whole && o.spread_knn)
    ok = dacpo_mpi_knn(cloud.xyz,
                       cloud.n,
                       table_width(&p, cloud.n),
                       rank,
                       ranks,
                       o.knn_halo,
                       &table,
                       &rep.knn,
                       &rep.traffic);
  rep.knn_rounds = (double)table.rounds;
  if (ok && rank == 0 && !o.whole)
    ok = create_job(ctx, &p, &cloud, &table, &job);
  ok = dacpo_mpi_all_ok(ok);
  rep.wall[0] = now() - t;
  t = now();
  ok = ok && orient(&o, ctx, job, &cloud, &p, rank, ranks, &rep, &t);
  rep.wall[3] = now() - t;
  t = now();
  if (ok && rank == 0)
    ok = write_output(o.out, &cloud);
  ok = dacpo_mpi_all_ok(ok);
  rep.wall[4] = now() - t;
  rep.peak_rss_mb = peak_rss_mb();
  rank_report* all = rank == 0 ? calloc((size_t)ranks, sizeof(rank_report)) : NULL;
  MPI_Gather(&rep,
             (int)sizeof(rep),
             MPI_BYTE,
             all,
             (int)sizeof(rep),
             MPI_BYTE,
             0,
             MPI_COMM_WORLD);
  if (rank == 0 && all && ok)
    ok = write_report(&o, all, ranks);
  free(all);
  dacpo_job_free(job);
  dacpo_ctx_free(ctx);
  dacpo_ply_cloud_free(&cloud);
  MPI_Finalize();
  return ok ? 0 : 2;
}
