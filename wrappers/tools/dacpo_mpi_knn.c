/* SPDX-License-Identifier: BSD-3-Clause */
/* See dacpo_mpi_knn.h. Messages: a region (rank 0 -> rank q) is a header
 * (point count, width, the box it covers completely), then the points' input
 * indices (int32, ascending), coordinates (3 floats) and own flags (uint8); the
 * answer (rank q -> rank 0) is, per own point, its input index, a complete flag
 * and width input indices. */
#include "dacpo_mpi_knn.h"

#include <dacpo/dacpo_advanced.h>

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { TAG_REGION = 11, TAG_ROWS = 12 };

/* Sample of the split coordinate behind the slab cuts (quantiles). */
#define KNN_CUT_SAMPLE 20000
/* First halo: this many times sqrt(k) x the spacing a sheet as large as the
 * two longest box sides would have (rows that need more ask again). */
#define KNN_HALO_START 3.0
#define KNN_HALO_GROWTH 4.0

typedef struct region_header {
  uint64_t count, width;
  double lo[3], hi[3];
} region_header;

static int
cmp_double(const void* a, const void* b)
{
  const double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

/* Rank 0's plan: the split axis, the ranks - 1 cuts, the box. */
typedef struct knn_plan {
  int axis;
  double* cut; /* ranks + 1: -inf, cuts, +inf */
  double start_halo;
  double min[3], max[3];
} knn_plan;

static int
plan_slabs(const float* xyz, size_t n, size_t width, int ranks, knn_plan* pl)
{
  for (int a = 0; a < 3; ++a) {
    pl->min[a] = HUGE_VAL;
    pl->max[a] = -HUGE_VAL;
  }
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const double v = xyz[3 * i + (size_t)a];
      pl->min[a] = v < pl->min[a] ? v : pl->min[a];
      pl->max[a] = v > pl->max[a] ? v : pl->max[a];
    }
  double ext[3];
  for (int a = 0; a < 3; ++a)
    ext[a] = n ? pl->max[a] - pl->min[a] : 0.0;
  pl->axis = ext[1] > ext[0] ? 1 : 0;
  if (ext[2] > ext[pl->axis])
    pl->axis = 2;
  const double other =
      ext[0] + ext[1] + ext[2] - ext[pl->axis] - fmin(ext[0], fmin(ext[1], ext[2]));
  pl->start_halo = KNN_HALO_START * sqrt((double)width) *
                   sqrt(ext[pl->axis] * other / (double)(n ? n : 1));
  if (!(pl->start_halo > 0.0))
    pl->start_halo = 1e-6 + 1e-3 * ext[pl->axis];
  const size_t step = n / KNN_CUT_SAMPLE + 1, m = (n + step - 1) / step;
  double* s = malloc((m ? m : 1) * sizeof(double));
  pl->cut = malloc(((size_t)ranks + 1) * sizeof(double));
  if (!s || !pl->cut) {
    free(s);
    return 0;
  }
  for (size_t j = 0; j < m; ++j)
    s[j] = xyz[3 * (j * step) + (size_t)pl->axis];
  qsort(s, m, sizeof(double), cmp_double);
  pl->cut[0] = -HUGE_VAL;
  pl->cut[ranks] = HUGE_VAL;
  for (int q = 1; q < ranks; ++q)
    pl->cut[q] = m ? s[(size_t)q * m / (size_t)ranks] : 0.0;
  free(s);
  return 1;
}

/* Rank 0: the region of rank q for this round as one message (NULL if out of
 * memory): its slab's points that still want a row (want[i]) and every point
 * within the halo h of the slab, in input order. */
static void*
make_region(const float* xyz,
            size_t n,
            size_t width,
            const knn_plan* pl,
            int q,
            double h,
            const uint8_t* want,
            size_t* size)
{
  const double lo = pl->cut[q] - h, hi = pl->cut[q + 1] + h;
  const int a = pl->axis;
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    const double v = xyz[3 * i + (size_t)a];
    count += v >= lo && v < hi;
  }
  region_header hd;
  memset(&hd, 0, sizeof(hd));
  hd.count = count;
  hd.width = width;
  for (int d = 0; d < 3; ++d) {
    hd.lo[d] = -HUGE_VAL;
    hd.hi[d] = HUGE_VAL;
  }
  /* where the halo passes the cloud's end, nothing lies beyond it */
  hd.lo[a] = lo <= pl->min[a] ? -HUGE_VAL : lo;
  hd.hi[a] = hi > pl->max[a] ? HUGE_VAL : hi;
  *size = sizeof(hd) + count * (sizeof(int32_t) + 3 * sizeof(float) + 1);
  unsigned char* msg = malloc(*size);
  if (!msg)
    return NULL;
  memcpy(msg, &hd, sizeof(hd));
  int32_t* ids = (int32_t*)(msg + sizeof(hd));
  float* p = (float*)(ids + count);
  uint8_t* own = (uint8_t*)(p + 3 * count);
  size_t j = 0;
  for (size_t i = 0; i < n; ++i) {
    const double v = xyz[3 * i + (size_t)a];
    if (!(v >= lo && v < hi))
      continue;
    ids[j] = (int32_t)i;
    memcpy(p + 3 * j, xyz + 3 * i, 3 * sizeof(float));
    own[j] = want[i] && v >= pl->cut[q] && v < pl->cut[q + 1];
    ++j;
  }
  return msg;
}

/* Any rank: the rows of a region's own points as the answer message (NULL and
 * a message in msg on failure). */
static void*
answer_region(
    const void* region, size_t rsize, size_t* size, char* msg, size_t msg_size)
{
  region_header hd;
  if (rsize < sizeof(hd)) {
    snprintf(msg, msg_size, "distributed k-NN: short region message");
    return NULL;
  }
  memcpy(&hd, region, sizeof(hd));
  const size_t n = (size_t)hd.count, w = (size_t)hd.width;
  if (rsize != sizeof(hd) + n * (sizeof(int32_t) + 3 * sizeof(float) + 1) || w == 0) {
    snprintf(msg, msg_size, "distributed k-NN: malformed region message");
    return NULL;
  }
  const unsigned char* b = (const unsigned char*)region + sizeof(hd);
  const int32_t* ids = (const int32_t*)b;
  const float* p = (const float*)(ids + n);
  const uint8_t* own = (const uint8_t*)(p + 3 * n);
  size_t m = 0;
  for (size_t i = 0; i < n; ++i)
    m += own[i] != 0;
  const size_t rec = sizeof(int32_t) + 1 + w * sizeof(int32_t);
  *size = sizeof(uint64_t) + m * rec;
  unsigned char* out = malloc(*size);
  int32_t* nbr = malloc((m ? m : 1) * w * sizeof(int32_t));
  uint8_t* complete = malloc(m ? m : 1);
  if (!out || !nbr || !complete) {
    snprintf(msg, msg_size, "distributed k-NN: out of memory");
    free(out);
    out = NULL;
  }
  else if (dacpo_region_knn(
               p, own, n, w, hd.lo, hd.hi, nbr, NULL, complete, msg, msg_size) !=
           DACPO_OK) {
    free(out);
    out = NULL;
  }
  else {
    const uint64_t mm = m;
    memcpy(out, &mm, sizeof(mm));
    unsigned char* o = out + sizeof(mm);
    size_t j = 0;
    for (size_t i = 0; i < n; ++i) {
      if (!own[i])
        continue;
      memcpy(o, &ids[i], sizeof(int32_t));
      o[sizeof(int32_t)] = complete[j];
      int32_t* row = (int32_t*)(o + sizeof(int32_t) + 1);
      for (size_t t = 0; t < w; ++t) { /* region index -> input index */
        const int32_t r = nbr[j * w + t];
        const int32_t g = r >= 0 ? ids[r] : -1;
        memcpy(row + t, &g, sizeof(g));
      }
      o += rec;
      ++j;
    }
  }
  free(nbr);
  free(complete);
  return out;
}

/* Rank 0: an answer's complete rows into the table; *open counts the rest. */
static int
take_rows(dacpo_knn_table* t, uint8_t* want, const void* ans, size_t size, size_t* open)
{
  uint64_t m = 0;
  const size_t rec = sizeof(int32_t) + 1 + t->width * sizeof(int32_t);
  if (size < sizeof(m))
    return 0;
  memcpy(&m, ans, sizeof(m));
  if (size != sizeof(m) + (size_t)m * rec)
    return 0;
  const unsigned char* o = (const unsigned char*)ans + sizeof(m);
  for (uint64_t j = 0; j < m; ++j, o += rec) {
    int32_t id;
    memcpy(&id, o, sizeof(id));
    if (id < 0 || (size_t)id >= t->n)
      return 0;
    if (!o[sizeof(int32_t)]) {
      ++*open;
      continue;
    }
    memcpy(t->ids + (size_t)id * t->width,
           o + sizeof(int32_t) + 1,
           t->width * sizeof(int32_t));
    want[id] = 0;
  }
  return 1;
}

/* A rank other than 0 for one round: its region's rows back to rank 0. A
 * failed rank still answers (empty), so rank 0 is not left waiting. */
static int
answer_rank0(double* busy, dacpo_mpi_traffic* traffic, char* msg, size_t msg_size)
{
  size_t size = 0, asize = 0;
  void* region = dacpo_mpi_recv(0, TAG_REGION, &size, NULL, traffic);
  const double t0 = MPI_Wtime();
  void* ans = region ? answer_region(region, size, &asize, msg, msg_size) : NULL;
  *busy += MPI_Wtime() - t0;
  dacpo_mpi_send(ans ? ans : "", ans ? asize : 0, 0, TAG_ROWS, traffic);
  const int ok = ans != NULL;
  free(region);
  free(ans);
  return ok;
}

int
dacpo_mpi_knn(const float* xyz,
              size_t n,
              size_t width,
              int rank,
              int ranks,
              double first_halo,
              dacpo_knn_table* table,
              double* busy,
              dacpo_mpi_traffic* traffic)
{
  char msg[512] = "";
  int ok = 1, more = 1;
  knn_plan pl;
  memset(&pl, 0, sizeof(pl));
  uint8_t* want = NULL;
  if (rank == 0) {
    memset(table, 0, sizeof(*table));
    table->n = n;
    table->width = width;
    table->xyz = xyz;
    table->ids = malloc((n ? n : 1) * width * sizeof(int32_t));
    want = malloc(n ? n : 1);
    ok = table->ids && want && plan_slabs(xyz, n, width, ranks, &pl) &&
         n <= (size_t)INT32_MAX;
    if (want)
      memset(want, 1, n);
    if (!ok)
      snprintf(msg, sizeof(msg), "distributed k-NN: out of memory or too many points");
  }
  double h = first_halo > 0.0 ? first_halo : pl.start_halo;
  while (dacpo_mpi_all_ok(ok) && more) {
    size_t open = 0, size = 0;
    if (rank == 0) {
      table->rounds++;
      for (int q = 1; q < ranks; ++q) { /* every other rank gets a message */
        void* region = ok ? make_region(xyz, n, width, &pl, q, h, want, &size) : NULL;
        ok = region && size <= (size_t)INT_MAX;
        dacpo_mpi_send(ok ? region : "", ok ? size : 0, q, TAG_REGION, traffic);
        free(region);
      }
      void* region = ok ? make_region(xyz, n, width, &pl, 0, h, want, &size) : NULL;
      const double t0 = MPI_Wtime();
      void* ans = region ? answer_region(region, size, &size, msg, sizeof(msg)) : NULL;
      *busy += MPI_Wtime() - t0;
      ok = ok && ans && take_rows(table, want, ans, size, &open);
      free(region);
      free(ans);
      for (int q = 1; q < ranks; ++q) { /* every other rank answers once */
        void* a = dacpo_mpi_recv(q, TAG_ROWS, &size, NULL, traffic);
        if (ok && !(a && size > 0 && take_rows(table, want, a, size, &open))) {
          ok = 0;
          if (!msg[0])
            snprintf(msg, sizeof(msg), "distributed k-NN: rank %d failed", q);
        }
        free(a);
      }
      more = ok && open > 0;
      h *= KNN_HALO_GROWTH;
    }
    else
      ok = answer_rank0(busy, traffic, msg, sizeof(msg));
    MPI_Request req;
    MPI_Ibcast(&more, 1, MPI_INT, 0, MPI_COMM_WORLD, &req);
    dacpo_mpi_wait(&req);
  }
  if (msg[0])
    fprintf(stderr, "Error (rank %d): %s\n", rank, msg);
  free(pl.cut);
  free(want);
  ok = dacpo_mpi_all_ok(ok);
  if (!ok && rank == 0)
    dacpo_knn_table_free(table);
  return ok;
}

int
dacpo_knn_table_search(void* user,
                       size_t query,
                       size_t k,
                       int32_t* indices,
                       float* sq_distances,
                       size_t* found)
{
  const dacpo_knn_table* t = user;
  if (query >= t->n || k > t->width)
    return 1;
  const int32_t* row = t->ids + query * t->width;
  const float* q = t->xyz + 3 * query;
  size_t m = 0;
  for (; m < k && row[m] >= 0; ++m) {
    const float* p = t->xyz + 3 * (size_t)row[m];
    const double dx = (double)p[0] - q[0], dy = (double)p[1] - q[1],
                 dz = (double)p[2] - q[2];
    indices[m] = row[m];
    sq_distances[m] = (float)(dx * dx + dy * dy + dz * dz);
  }
  *found = m;
  return 0;
}

void
dacpo_knn_table_free(dacpo_knn_table* table)
{
  if (!table)
    return;
  free(table->ids);
  memset(table, 0, sizeof(*table));
}
