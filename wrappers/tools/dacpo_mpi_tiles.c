/* SPDX-License-Identifier: BSD-3-Clause */
/*
 * pcl_dacpo_orient_mpi -tiles (dacpo_mpi_tiles.h): the passes of dacpo_tiled.c
 * with ranks in place of temporary files.
 *
 *   read    rank r reads input points [n r / R, n (r + 1) / R) of the binary PLY
 *           (its own byte range), checks them, and contributes every s-th one
 *           to the sample; the sample is gathered on every rank in input order,
 *           so every rank builds the same plan as dacpo_tiled.c would
 *   route   tiles are dealt to ranks by estimated size; in rounds of at most
 *           2^18 points per rank, every point goes (index + xyz) to the ranks
 *           of its own tile and of the tiles whose halo holds it (all-to-all)
 *   tiles   each rank sorts each of its tiles by input index and orients it
 *           with dacpo_orient(): the same points in the same order as in one
 *           process, so the same normals
 *   join    halo normals travel to the rank of their owner tile, which adds
 *           the evidence; the sums meet on rank 0 (dacpo_tile_join) and the
 *           flips go to every rank
 *   write   the own normals (flipped where told) travel to the rank whose input
 *           range holds them; it reads its range's xyz again and writes its
 *           records with MPI-IO at their input offsets; rank 0 writes the header
 *
 * Memory per rank: its tiles (own + halo points, 16 bytes each, plus one
 * dacpo_orient() at a time), its range's normals (12 bytes a point), a round's
 * messages and the evidence of its tiles' pairs; no rank holds the whole
 * cloud.
 */
#define _FILE_OFFSET_BITS 64
#define _POSIX_C_SOURCE 200809L

#include "dacpo_mpi_tiles.h"
#include "dacpo_cleanup.h"
#include "dacpo_paths.h"

#include "dacpo_ply.h"
#include "dacpo_tiled.h"
#include <sys/resource.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define ROUND_POINTS (1u << 18)
#define MAX_HALO 64

static double
now_s(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A point on its way to a tile. */
typedef struct routed {
  uint64_t idx;
  float xyz[3];
  int32_t tile;
} routed;

/* A halo normal on its way to the owner tile's rank. */
typedef struct halo_msg {
  uint64_t idx;
  float n[3];
  int32_t a; /* the tile that had it in its halo */
  int32_t b; /* its owner tile */
  int32_t pad;
} halo_msg;

/* An own normal on its way to the rank of its input range. */
typedef struct out_msg {
  uint64_t idx;
  float n[3];
  int32_t pad;
} out_msg;

/* A growing array of one record type, per destination rank or tile. */
typedef struct vec {
  unsigned char* data;
  size_t size, cap; /* bytes */
} vec;

static int
vec_push(vec* v, const void* rec, size_t len)
{
  if (v->size + len > v->cap) {
    size_t cap = v->cap ? 2 * v->cap : 4096;
    while (cap < v->size + len)
      cap *= 2;
    unsigned char* d = realloc(v->data, cap);
    if (!d)
      return 0;
    v->data = d;
    v->cap = cap;
  }
  memcpy(v->data + v->size, rec, len);
  v->size += len;
  return 1;
}

/* All-to-all of byte vectors (out[d] to rank d); the received bytes are
 * appended to *in in rank order. Non-blocking collectives waited for without
 * spinning (a rank that finished early must not take a busy rank's core). */
static int
exchange(vec* out, int ranks, vec* in, dacpo_mpi_traffic* traffic)
{
  int* sc = calloc((size_t)ranks * 4, sizeof(int));
  if (!sc)
    return 0;
  int *rc = sc + ranks, *sd = sc + 2 * ranks, *rd = sc + 3 * ranks;
  int ok = 1;
  for (int d = 0; d < ranks; ++d) {
    if (out[d].size > (size_t)INT32_MAX / 2)
      ok = 0;
    sc[d] = (int)out[d].size;
  }
  if (!dacpo_mpi_all_ok(ok)) {
    free(sc);
    return 0;
  }
  MPI_Request req;
  MPI_Ialltoall(sc, 1, MPI_INT, rc, 1, MPI_INT, MPI_COMM_WORLD, &req);
  dacpo_mpi_wait(&req);
  size_t total_in = 0, total_out = 0;
  for (int d = 0; d < ranks; ++d) {
    sd[d] = (int)total_out;
    rd[d] = (int)total_in;
    total_out += (size_t)sc[d];
    total_in += (size_t)rc[d];
  }
  unsigned char* sbuf = malloc(total_out ? total_out : 1);
  ok = sbuf != NULL && total_out < (size_t)INT32_MAX && total_in < (size_t)INT32_MAX;
  if (ok && in->size + total_in > in->cap) {
    unsigned char* d = realloc(in->data, in->size + total_in + 1);
    ok = d != NULL;
    if (ok) {
      in->data = d;
      in->cap = in->size + total_in + 1;
    }
  }
  if (!dacpo_mpi_all_ok(ok)) {
    free(sbuf);
    free(sc);
    return 0;
  }
  for (int d = 0; d < ranks; ++d)
    if (out[d].size)
      memcpy(sbuf + sd[d], out[d].data, out[d].size);
  MPI_Ialltoallv(sbuf, sc, sd, MPI_BYTE, in->data + in->size, rc, rd, MPI_BYTE, MPI_COMM_WORLD, &req);
  dacpo_mpi_wait(&req);
  in->size += total_in;
  traffic->sent_mb += (double)total_out / 1048576.0;
  traffic->received_mb += (double)total_in / 1048576.0;
  free(sbuf);
  free(sc);
  for (int d = 0; d < ranks; ++d)
    out[d].size = 0;
  return 1;
}

static int
cmp_routed(const void* x, const void* y)
{
  const routed* a = x;
  const routed* b = y;
  return (a->idx > b->idx) - (a->idx < b->idx);
}

/* Everything one rank holds. */
typedef struct tiles_run {
  int rank, ranks;
  uint64_t n, lo, hi; /* this rank's input range [lo, hi) */
  dacpo_ply_rows rows;
  FILE* in;
  dacpo_tile_plan* plan;
  size_t T;
  int* tile_rank;
  vec* tile;        /* T: routed records of the tiles this rank runs */
  float* range_nrm; /* (hi - lo) * 3: the normals of this rank's input range */
  float* chunk;
} tiles_run;

static uint64_t
range_start(uint64_t n, int r, int ranks)
{
  /* n r / R without overflow: (n / R) r + (n mod R) r / R */
  const uint64_t R = (uint64_t)ranks, q = n / R, m = n % R;
  return q * (uint64_t)r + m * (uint64_t)r / R;
}

static int
rank_of_index(const tiles_run* t, uint64_t idx)
{
  /* the last rank r with range_start(r) <= idx */
  int lo = 0, hi = t->ranks - 1;
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (range_start(t->n, mid, t->ranks) <= idx)
      lo = mid;
    else
      hi = mid - 1;
  }
  return lo;
}

static int
plan_from_samples(tiles_run* t,
                  const float* sample,
                  size_t got,
                  uint64_t max_points,
                  double halo,
                  dacpo_mpi_tiles_report* rep);

/* read: check this rank's range, contribute to the sample, build the plan. */
static int
read_and_plan(tiles_run* t,
              const char* path,
              uint64_t max_points,
              double halo,
              dacpo_mpi_tiles_report* rep)
{
  char err[512] = "";
  int ok = dacpo_ply_rows_open(path, &t->rows, err, sizeof(err)) == 0;
  if (ok && t->rows.n == 0) {
    snprintf(err, sizeof(err), "'%s' has no points", path);
    ok = 0;
  }
  if (ok && !(t->in = fopen(path, "rb"))) {
    snprintf(err, sizeof(err), "cannot open '%s': %s", path, strerror(errno));
    ok = 0;
  }
  /* double coordinates: every rank computes on offsets from vertex 0 */
  ok = ok && dacpo_ply_rows_set_origin(t->in, &t->rows, err, sizeof(err)) == 0;
  t->n = t->rows.n;
  t->lo = range_start(t->n, t->rank, t->ranks);
  t->hi = range_start(t->n, t->rank + 1, t->ranks);
  const uint64_t s = dacpo_tiled_sample_stride(t->n);
  /* sample points of this range: multiples of s in [lo, hi) */
  const uint64_t first_s = (t->lo + s - 1) / s * s;
  const size_t mine = first_s < t->hi ? (size_t)((t->hi - 1 - first_s) / s + 1) : 0;
  float* sample = malloc(3 * (mine + 1) * sizeof(float));
  t->chunk = malloc(3 * (size_t)ROUND_POINTS * sizeof(float));
  if (ok && (!sample || !t->chunk)) {
    snprintf(err, sizeof(err), "out of memory");
    ok = 0;
  }
  size_t got = 0;
  for (uint64_t first = t->lo; ok && first < t->hi; first += ROUND_POINTS) {
    const size_t take = (size_t)(t->hi - first < ROUND_POINTS ? t->hi - first : ROUND_POINTS);
    ok = dacpo_ply_rows_read(t->in, &t->rows, first, take, t->chunk, err, sizeof(err)) == 0;
    for (size_t i = 0; ok && i < take; ++i) {
      const float* p = t->chunk + 3 * i;
      if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
        snprintf(err,
                 sizeof(err),
                 "point %llu of '%s' is not finite (NaN or inf): remove such points first",
                 (unsigned long long)(first + i),
                 path);
        ok = 0;
      }
      else if ((first + i) % s == 0 && got < mine)
        memcpy(sample + 3 * got++, p, 3 * sizeof(float));
    }
  }
  if (!ok)
    fprintf(stderr, "Error (rank %d): %s\n", t->rank, err);
  if (!dacpo_mpi_all_ok(ok)) {
    free(sample);
    return 0;
  }
  ok = plan_from_samples(t, sample, got, max_points, halo, rep);
  free(sample);
  return ok;
}

/* The samples of every rank, gathered everywhere in rank (= input) order, give
 * the same plan on every rank; its tiles are dealt to the ranks by size. */
static int
plan_from_samples(tiles_run* t,
                  const float* sample,
                  size_t got,
                  uint64_t max_points,
                  double halo,
                  dacpo_mpi_tiles_report* rep)
{
  int ok = 1;
  int* cnt = malloc(2 * (size_t)t->ranks * sizeof(int));
  const int my = (int)(3 * got);
  MPI_Allgather(&my, 1, MPI_INT, cnt, 1, MPI_INT, MPI_COMM_WORLD);
  int* disp = cnt + t->ranks;
  size_t m3 = 0;
  for (int r = 0; r < t->ranks; ++r) {
    disp[r] = (int)m3;
    m3 += (size_t)cnt[r];
  }
  float* all = malloc((m3 ? m3 : 1) * sizeof(float));
  MPI_Allgatherv(sample, my, MPI_FLOAT, all, cnt, disp, MPI_FLOAT, MPI_COMM_WORLD);
  char msg[400];
  ok = dacpo_tile_plan_create(all, m3 / 3, t->n, max_points, halo, &t->plan, msg, sizeof(msg)) ==
       DACPO_OK;
  free(all);
  free(cnt);
  if (!ok && t->rank == 0)
    fprintf(stderr, "Error: %s\n", msg);
  if (!ok)
    return 0;
  t->T = dacpo_tile_plan_count(t->plan);
  rep->num_tiles = (double)t->T;
  rep->halo = dacpo_tile_plan_halo(t->plan);
  double* cost = malloc(t->T * sizeof(double));
  if (cost)
    for (size_t k = 0; k < t->T; ++k)
      cost[k] = (double)dacpo_tile_plan_estimate(t->plan, k);
  t->tile_rank = cost ? dacpo_mpi_deal(cost, t->T, t->ranks) : NULL;
  free(cost);
  t->tile = calloc(t->T, sizeof(vec));
  return dacpo_mpi_all_ok(t->tile_rank != NULL && t->tile != NULL);
}

/* route: rounds of this rank's range to the tiles' ranks. */
static int
route(tiles_run* t, dacpo_mpi_tiles_report* rep)
{
  vec* out = calloc((size_t)t->ranks, sizeof(vec));
  vec in = {NULL, 0, 0};
  int ok = out != NULL;
  const uint64_t per_rank = (t->n + (uint64_t)t->ranks - 1) / (uint64_t)t->ranks;
  const uint64_t rounds = (per_rank + ROUND_POINTS - 1) / ROUND_POINTS;
  char err[512] = "";
  for (uint64_t round = 0; round < rounds; ++round) {
    const uint64_t first = t->lo + round * ROUND_POINTS;
    const size_t take =
        first < t->hi ? (size_t)(t->hi - first < ROUND_POINTS ? t->hi - first : ROUND_POINTS) : 0;
    if (ok && take)
      ok = dacpo_ply_rows_read(t->in, &t->rows, first, take, t->chunk, err, sizeof(err)) == 0;
    for (size_t i = 0; ok && i < take; ++i) {
      int32_t halo[MAX_HALO];
      size_t nh = 0;
      routed rec;
      memset(&rec, 0, sizeof(rec));
      rec.idx = first + i;
      memcpy(rec.xyz, t->chunk + 3 * i, sizeof(rec.xyz));
      const int32_t own = dacpo_tile_locate(t->plan, rec.xyz, halo, MAX_HALO, &nh);
      if (nh > MAX_HALO) {
        snprintf(err, sizeof(err), "point %llu lies in the halo of %zu tiles (at most %d)",
                 (unsigned long long)rec.idx, nh, MAX_HALO);
        ok = 0;
        break;
      }
      for (size_t h = 0; ok && h <= nh; ++h) {
        rec.tile = h == 0 ? own : halo[h - 1];
        ok = vec_push(&out[t->tile_rank[rec.tile]], &rec, sizeof(rec));
      }
    }
    if (!ok)
      fprintf(stderr, "Error (rank %d): %s\n", t->rank, err[0] ? err : "out of memory");
    in.size = 0;
    if (!dacpo_mpi_all_ok(ok) || !exchange(out, t->ranks, &in, &rep->traffic)) {
      ok = 0;
      break;
    }
    for (size_t b = 0; ok && b < in.size; b += sizeof(routed)) {
      routed rec;
      memcpy(&rec, in.data + b, sizeof(rec));
      ok = vec_push(&t->tile[rec.tile], &rec, sizeof(rec));
    }
  }
  for (int d = 0; out && d < t->ranks; ++d)
    free(out[d].data);
  free(out);
  free(in.data);
  for (size_t k = 0; ok && k < t->T; ++k) {
    const size_t cnt = t->tile[k].size / sizeof(routed);
    qsort(t->tile[k].data, cnt, sizeof(routed), cmp_routed);
    rep->held_points += (double)cnt;
    if ((double)cnt > rep->largest_tile)
      rep->largest_tile = (double)cnt;
  }
  return dacpo_mpi_all_ok(ok);
}

/* Orients this rank's tiles one at a time: own records keep their normal (in
 * place of xyz), halo records leave as messages to the owner tile's rank. */
static int
orient_own_tiles(tiles_run* t,
                 const dacpo_params* p,
                 vec* out,
                 uint64_t* own_count,
                 dacpo_mpi_tiles_report* rep)
{
  dacpo_ctx* ctx = NULL;
  int ok = dacpo_ctx_create(&ctx) == DACPO_OK;
  for (size_t k = 0; ok && k < t->T; ++k) {
    if (t->tile_rank[k] != t->rank || t->tile[k].size == 0)
      continue;
    routed* rec = (routed*)t->tile[k].data;
    const size_t cnt = t->tile[k].size / sizeof(routed);
    float* xyz = malloc(3 * cnt * sizeof(float));
    float* nrm = calloc(3 * cnt, sizeof(float));
    ok = xyz && nrm;
    for (size_t i = 0; ok && i < cnt; ++i)
      memcpy(xyz + 3 * i, rec[i].xyz, sizeof(rec[i].xyz));
    const double b0 = now_s();
    if (ok && dacpo_orient(ctx, p, NULL, NULL, xyz, nrm, cnt) != DACPO_OK) {
      fprintf(stderr, "Error (rank %d): tile %zu (%zu points): %s\n", t->rank, k, cnt,
              dacpo_ctx_last_error(ctx));
      ok = 0;
    }
    rep->busy += now_s() - b0;
    rep->tiles += 1.0;
    for (size_t i = 0; ok && i < cnt; ++i) {
      const int32_t owner = dacpo_tile_locate(t->plan, rec[i].xyz, NULL, 0, NULL);
      if (owner == (int32_t)k) {
        own_count[k]++;
        memcpy(rec[i].xyz, nrm + 3 * i, sizeof(rec[i].xyz)); /* now the normal */
        rec[i].tile = -1;                                    /* own */
      }
      else {
        halo_msg h;
        memset(&h, 0, sizeof(h));
        h.idx = rec[i].idx;
        memcpy(h.n, nrm + 3 * i, sizeof(h.n));
        h.a = (int32_t)k;
        h.b = owner;
        ok = vec_push(&out[t->tile_rank[owner]], &h, sizeof(h));
        rec[i].tile = -2; /* halo: dropped below */
      }
    }
    /* keep only the own records, now holding normals */
    size_t kept = 0;
    for (size_t i = 0; ok && i < cnt; ++i)
      if (rec[i].tile == -1)
        rec[kept++] = rec[i];
    t->tile[k].size = kept * sizeof(routed);
    free(xyz);
    free(nrm);
  }
  dacpo_ctx_free(ctx);
  return ok;
}

/* The halo messages this rank received, against its own tiles' normals: the
 * evidence of each tile pair (a, b), summed in the order tile a listed them. */
static int
halo_evidence(const tiles_run* t, const vec* in, dacpo_tile_pairs* ev)
{
  for (size_t b = 0; b < in->size; b += sizeof(halo_msg)) {
    halo_msg h;
    memcpy(&h, in->data + b, sizeof(h));
    /* the owner's normal: binary search in its tile (own records, by index) */
    const routed* rec = (const routed*)t->tile[h.b].data;
    size_t lo = 0, hi = t->tile[h.b].size / sizeof(routed);
    while (lo < hi) {
      const size_t mid = (lo + hi) / 2;
      if (rec[mid].idx < h.idx)
        lo = mid + 1;
      else
        hi = mid;
    }
    if (lo >= t->tile[h.b].size / sizeof(routed) || rec[lo].idx != h.idx) {
      fprintf(stderr, "Error (rank %d): internal: point %llu not in tile %d\n", t->rank,
              (unsigned long long)h.idx, h.b);
      return 0;
    }
    const float* o = rec[lo].xyz;
    const double d = (double)h.n[0] * o[0] + (double)h.n[1] * o[1] + (double)h.n[2] * o[2];
    dacpo_tile_overlap* e = dacpo_tile_pairs_get(ev, (uint32_t)h.a, (uint32_t)h.b);
    if (!e) {
      fprintf(stderr, "Error (rank %d): out of memory\n", t->rank);
      return 0;
    }
    if (d >= 0.0)
      e->same += fabs(d);
    else
      e->opposite += fabs(d);
  }
  return 1;
}

/* Each (a, b) comes from one rank (tile b's): rank 0 gathers the lists and
 * the own points per tile (each counted on its tile's rank), joins, and
 * sends every rank the flips. */
static int
join_on_rank0(tiles_run* t,
              const dacpo_tile_pairs* ev,
              const uint64_t* own_count,
              uint8_t* flip,
              dacpo_mpi_tiles_report* rep)
{
  const size_t T = t->T;
  int ok = 1;
  double* own = calloc(T ? T : 1, sizeof(double));
  double* own_sum = t->rank == 0 ? calloc(T ? T : 1, sizeof(double)) : NULL;
  for (size_t k = 0; own && k < T; ++k)
    own[k] = (double)own_count[k];
  MPI_Reduce(own, own_sum, (int)T, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  const int bytes = (int)(ev->used * sizeof(dacpo_tile_overlap));
  int* cnt = t->rank == 0 ? malloc(2 * (size_t)t->ranks * sizeof(int)) : NULL;
  MPI_Gather(&bytes, 1, MPI_INT, cnt, 1, MPI_INT, 0, MPI_COMM_WORLD);
  size_t total = 0;
  if (t->rank == 0)
    for (int r = 0; r < t->ranks; ++r) {
      cnt[t->ranks + r] = (int)total;
      total += (size_t)cnt[r];
    }
  dacpo_tile_overlap* all = t->rank == 0 ? malloc(total ? total : 1) : NULL;
  MPI_Gatherv(ev->entry, bytes, MPI_BYTE, all, cnt, cnt ? cnt + t->ranks : NULL, MPI_BYTE, 0,
              MPI_COMM_WORLD);
  if (t->rank == 0) {
    uint64_t* pts = malloc((T ? T : 1) * sizeof(uint64_t));
    ok = own_sum && all && pts;
    for (size_t k = 0; ok && k < T; ++k)
      pts[k] = (uint64_t)own_sum[k];
    char msg[400];
    if (ok && dacpo_tile_join(T, all, total / sizeof(dacpo_tile_overlap), pts, flip, msg,
                              sizeof(msg)) != DACPO_OK) {
      fprintf(stderr, "Error: %s\n", msg);
      ok = 0;
    }
    for (size_t k = 0; ok && k < T; ++k)
      rep->flipped_tiles += flip[k];
    free(pts);
  }
  free(all);
  free(cnt);
  free(own);
  free(own_sum);
  MPI_Bcast(flip, (int)T, MPI_BYTE, 0, MPI_COMM_WORLD);
  return ok;
}

/* tiles + join: orient this rank's tiles; halo normals to the owners' ranks;
 * evidence summed on rank 0; flips everywhere. Own normals stay in the
 * tiles' records (xyz replaced by the normal: the position is not needed
 * again). */
static int
orient_and_join(tiles_run* t,
                const dacpo_params* params,
                uint8_t* flip,
                dacpo_mpi_tiles_report* rep)
{
  vec* out = calloc((size_t)t->ranks, sizeof(vec));
  uint64_t* own_count = calloc(t->T, sizeof(uint64_t));
  const dacpo_params p = dacpo_tiled_params(params);
  double t0 = now_s();
  int ok = out && own_count && orient_own_tiles(t, &p, out, own_count, rep);
  rep->wall[2] = now_s() - t0;
  t0 = now_s();
  vec in = {NULL, 0, 0};
  ok = dacpo_mpi_all_ok(ok) && exchange(out, t->ranks, &in, &rep->traffic);
  dacpo_tile_pairs ev = {NULL, 0, 0, NULL};
  ok = dacpo_mpi_all_ok(ok && dacpo_tile_pairs_init(&ev, t->T));
  ok = ok && halo_evidence(t, &in, &ev);
  free(in.data);
  for (int d = 0; out && d < t->ranks; ++d)
    free(out[d].data);
  free(out);
  ok = dacpo_mpi_all_ok(ok);
  if (ok)
    ok = join_on_rank0(t, &ev, own_count, flip, rep);
  dacpo_tile_pairs_free(&ev);
  free(own_count);
  rep->wall[3] = now_s() - t0;
  return dacpo_mpi_all_ok(ok);
}

/* write: own normals to their range's rank; each rank writes its range. */
/* one MPI_File_write_at whose byte count is checked: a short write (a full
   disk, a file size limit) is an error, not a hole in the output */
static int
write_all_at(MPI_File fh, MPI_Offset at, const void* buf, size_t bytes, char* err, size_t cap)
{
  MPI_Status st;
  int count = -1;
  if (MPI_File_write_at(fh, at, buf, (int)bytes, MPI_BYTE, &st) != MPI_SUCCESS ||
      MPI_Get_count(&st, MPI_BYTE, &count) != MPI_SUCCESS || count != (int)bytes) {
    snprintf(err, cap, "(%d of %zu bytes written: disk full?)", count < 0 ? 0 : count, bytes);
    return 0;
  }
  return 1;
}

static int
write_file(tiles_run* t, const char* path);

/* The normals back to the ranks that own their rows, then the file. */
static int
write_output(tiles_run* t, const char* path, const uint8_t* flip, dacpo_mpi_tiles_report* rep)
{
  vec* out = calloc((size_t)t->ranks, sizeof(vec));
  int ok = out != NULL;
  for (size_t k = 0; ok && k < t->T; ++k) {
    const routed* rec = (const routed*)t->tile[k].data;
    const size_t cnt = t->tile[k].size / sizeof(routed);
    const float s = flip[k] ? -1.0f : 1.0f;
    for (size_t i = 0; ok && i < cnt; ++i) {
      out_msg m;
      memset(&m, 0, sizeof(m));
      m.idx = rec[i].idx;
      for (int c = 0; c < 3; ++c)
        m.n[c] = s * rec[i].xyz[c];
      ok = vec_push(&out[rank_of_index(t, m.idx)], &m, sizeof(m));
    }
    free(t->tile[k].data);
    t->tile[k].data = NULL;
    t->tile[k].size = t->tile[k].cap = 0;
  }
  vec in = {NULL, 0, 0};
  ok = dacpo_mpi_all_ok(ok) && exchange(out, t->ranks, &in, &rep->traffic);
  const size_t mine = (size_t)(t->hi - t->lo);
  t->range_nrm = malloc((3 * mine + 1) * sizeof(float));
  ok = dacpo_mpi_all_ok(ok && t->range_nrm && in.size == mine * sizeof(out_msg));
  for (size_t b = 0; ok && b < in.size; b += sizeof(out_msg)) {
    out_msg m;
    memcpy(&m, in.data + b, sizeof(m));
    memcpy(t->range_nrm + 3 * (m.idx - t->lo), m.n, sizeof(m.n));
  }
  free(in.data);
  for (int d = 0; out && d < t->ranks; ++d)
    free(out[d].data);
  free(out);
  return ok && write_file(t, path);
}

/* MPI-IO: every rank writes its range into a temporary file beside the
 * output, renamed by rank 0 at the end. */
static int
write_file(tiles_run* t, const char* path)
{
  int ok = 1;
  char tmp[4200];
  long pid = (long)getpid();
  MPI_Bcast(&pid, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  if (dacpo_temp_sibling(path, "tmp", pid, tmp, sizeof(tmp)) != 0) {
    if (t->rank == 0)
      fprintf(stderr, "Error: '%s': name too long for a temporary file beside it\n", path);
    return 0;
  }
  /* rows: the input's x y z bytes as stored (bit for bit), float normals */
  char header[600];
  const int hlen = dacpo_tiled_header_typed(header, sizeof(header), t->T, t->n, &t->rows);
  const size_t xb = dacpo_ply_rows_xyz_bytes(&t->rows), row = xb + 12;
  MPI_File fh;
  const int slot = dacpo_cleanup_add(tmp);
  ok = MPI_File_open(MPI_COMM_WORLD, tmp, MPI_MODE_CREATE | MPI_MODE_WRONLY, MPI_INFO_NULL, &fh) ==
       MPI_SUCCESS;
  if (!dacpo_mpi_all_ok(ok)) {
    if (t->rank == 0)
      fprintf(stderr, "Error: cannot create '%s'\n", tmp);
    dacpo_cleanup_drop(slot);
    return 0;
  }
  /* the whole size is allocated on disk first (not a sparse set_size): a full
     disk fails here, before any row, and every write's count is checked */
  const MPI_Offset total = (MPI_Offset)hlen + (MPI_Offset)(t->n * row);
  char err[512] = "";
  ok = MPI_File_preallocate(fh, total) == MPI_SUCCESS;
  if (!ok)
    snprintf(err, sizeof(err), "(no room for %lld bytes: disk full?)", (long long)total);
  ok = dacpo_mpi_all_ok(ok);
  if (ok && t->rank == 0)
    ok = write_all_at(fh, 0, header, (size_t)hlen, err, sizeof(err));
  unsigned char* rec = malloc((size_t)ROUND_POINTS * row);
  ok = ok && rec != NULL;
  for (uint64_t first = t->lo; ok && first < t->hi; first += ROUND_POINTS) {
    const size_t take = (size_t)(t->hi - first < ROUND_POINTS ? t->hi - first : ROUND_POINTS);
    ok = dacpo_ply_rows_read_raw(t->in, &t->rows, first, take, rec, err, sizeof(err)) == 0;
    if (ok)
      dacpo_tiled_append_normals(rec, xb, t->range_nrm + 3 * (first - t->lo), 3, take);
    ok = ok && write_all_at(fh,
                            (MPI_Offset)hlen + (MPI_Offset)(first * row),
                            rec,
                            take * row,
                            err,
                            sizeof(err));
  }
  free(rec);
  /* sync and close are collective: every rank calls them, failed or not */
  ok = MPI_File_sync(fh) == MPI_SUCCESS && ok;
  ok = MPI_File_close(&fh) == MPI_SUCCESS && ok;
  if (!ok)
    fprintf(stderr, "Error (rank %d): writing '%s' failed %s\n", t->rank, tmp, err);
  ok = dacpo_mpi_all_ok(ok);
  if (t->rank == 0) {
    if (ok && rename(tmp, path) != 0) {
      fprintf(stderr, "Error: cannot rename onto '%s': %s\n", path, strerror(errno));
      ok = 0;
    }
    if (!ok)
      remove(tmp);
  }
  dacpo_cleanup_drop(slot);
  return dacpo_mpi_all_ok(ok);
}

int
dacpo_mpi_tiles_orient(const char* in,
                       const char* out,
                       const dacpo_params* params,
                       uint64_t max_points,
                       double halo,
                       int rank,
                       int ranks,
                       dacpo_mpi_tiles_report* rep)
{
  tiles_run t;
  memset(&t, 0, sizeof(t));
  memset(rep, 0, sizeof(*rep));
  t.rank = rank;
  t.ranks = ranks;
  double t0 = now_s();
  int ok = read_and_plan(&t, in, max_points, halo, rep);
  rep->wall[0] = now_s() - t0;
  t0 = now_s();
  ok = ok && route(&t, rep);
  rep->wall[1] = now_s() - t0;
  uint8_t* flip = calloc(t.T ? t.T : 1, 1);
  ok = dacpo_mpi_all_ok(ok && flip != NULL) && orient_and_join(&t, params, flip, rep);
  t0 = now_s();
  ok = ok && write_output(&t, out, flip, rep);
  rep->wall[4] = now_s() - t0;
  free(flip);
  for (size_t k = 0; t.tile && k < t.T; ++k)
    free(t.tile[k].data);
  free(t.tile);
  free(t.tile_rank);
  free(t.range_nrm);
  free(t.chunk);
  if (t.in)
    fclose(t.in);
  dacpo_tile_plan_free(t.plan);
  return ok;
}
