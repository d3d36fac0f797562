/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0, neighbours (the k-NN graph the paper's §4.1
 * segmentation and §4.2 propagation run on).
 *
 * dacpo_knn_build: the k nearest DISTINCT neighbours of every distinct point.
 *   Either the built-in kd-tree (query k+1, drop self), or the caller's search
 *   (dacpo_search), which answers in input indices: answers are mapped through
 *   input_to_point, the query's own distinct point and repeats are dropped,
 *   distances are recomputed in double from the distinct coordinates (so the
 *   order, ties to the lower index, is ours and not the callback's), and if
 *   duplicates left fewer than k, the callback is asked again with twice as
 *   many. Parallel over chunks of points; cost O(n k log n) built-in.
 *   Failures: callback non-zero / bad index / too many results
 *   (NEIGHBOR_SEARCH, naming the query's input index), cancel (CANCELLED),
 *   allocation (OUT_OF_MEMORY).
 * dacpo_adjacency_build: symmetric CSR (i~j if either lists the other);
 *   O(n k) memory and time (plus row sorts).
 * dacpo_components_label: BFS, labels in order of each component's lowest
 *   point index; O(n + edges). */
#include "dacpo_knn.h"

#include "dacpo_kdtree.h"
#include "dacpo_parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { KNN_CHUNK = 4096 };

/* Extra answers asked from a caller's search when duplicates exist, so one
 * round usually leaves k distinct neighbours. */
enum { KNN_DUP_SLACK = 4 };

typedef struct knn_job {
  const dacpo_cloud* cloud;
  size_t k;
  const dacpo_search* search; /* NULL: built-in */
  const dacpo_kdtree* tree;
  dacpo_knn_graph* out;
} knn_job;

static void
write_row(
    dacpo_knn_graph* g, size_t i, const int32_t* idx, const double* d, size_t count)
{
  int32_t* oi = g->idx + i * g->k;
  float* od = g->sqd + i * g->k;
  for (size_t j = 0; j < g->k; ++j) {
    oi[j] = j < count ? idx[j] : -1;
    od[j] = j < count ? (float)d[j] : INFINITY;
  }
}

static dacpo_status
knn_builtin_task(void* user, size_t task, unsigned thread_id, dacpo_err* err)
{
  (void)thread_id;
  const knn_job* job = user;
  size_t n = job->cloud->n, k = job->k;
  size_t begin = task * KNN_CHUNK;
  size_t end = begin + KNN_CHUNK < n ? begin + KNN_CHUNK : n;
  int32_t* idx = dacpo_malloc_array(k + 1, sizeof(int32_t));
  double* d = dacpo_malloc_array(k + 1, sizeof(double));
  if (!idx || !d) {
    free(idx);
    free(d);
    return DACPO_OOM(err);
  }
  /* Tasks walk the tree order: neighbouring queries share cached nodes. */
  for (size_t pos = begin; pos < end; ++pos) {
    size_t i = (size_t)dacpo_kdtree_order_at(job->tree, pos);
    size_t got = dacpo_kdtree_knn(job->tree, job->cloud->xyz + 3 * i, k + 1, idx, d);
    /* Points are distinct, so self is the only point at distance 0 and comes
     * first; drop it by index all the same. */
    size_t w = 0;
    for (size_t j = 0; j < got; ++j) {
      if ((size_t)idx[j] == i || w == k)
        continue;
      idx[w] = idx[j];
      d[w] = d[j];
      ++w;
    }
    write_row(job->out, i, idx, d, w);
  }
  free(idx);
  free(d);
  return DACPO_OK;
}

static dacpo_status
grow(size_t want, size_t* cap, int32_t** idx, float** d, dacpo_err* err)
{
  if (want <= *cap)
    return DACPO_OK;
  int32_t* ni = realloc(*idx, want * sizeof(int32_t));
  if (ni)
    *idx = ni;
  float* nd = ni ? realloc(*d, want * sizeof(float)) : NULL;
  if (nd)
    *d = nd;
  if (!ni || !nd)
    return DACPO_OOM(err);
  *cap = want;
  return DACPO_OK;
}

/* One distinct point through the caller's search. */
static dacpo_status
knn_callback_point(const knn_job* job,
                   size_t i,
                   size_t* cap,
                   int32_t** cb_idx,
                   float** cb_d,
                   int32_t* row_idx,
                   double* row_d,
                   dacpo_err* err)
{
  const dacpo_cloud* c = job->cloud;
  size_t k = job->k, m = c->input_count;
  size_t query = (size_t)c->rep_input[i];
  const double* q = c->xyz + 3 * i;
  size_t req = k + 1 + (c->n < m ? KNN_DUP_SLACK : 0);
  if (req > m)
    req = m;
  size_t count = 0;
  for (;;) {
    DACPO_TRY(grow(req, cap, cb_idx, cb_d, err));
    size_t found = 0;
    int rc = job->search->knn(job->search->user, query, req, *cb_idx, *cb_d, &found);
    if (rc != 0)
      return dacpo_err_set(err,
                           DACPO_ERR_NEIGHBOR_SEARCH,
                           "the neighbour search failed for point %zu (returned %d)",
                           query,
                           rc);
    if (found > req)
      return dacpo_err_set(err,
                           DACPO_ERR_NEIGHBOR_SEARCH,
                           "the neighbour search returned %zu neighbours of point %zu, "
                           "more than the %zu asked for",
                           found,
                           query,
                           req);
    count = 0;
    for (size_t j = 0; j < found; ++j) {
      int32_t in = (*cb_idx)[j];
      if (in < 0 || (size_t)in >= m)
        return dacpo_err_set(
            err,
            DACPO_ERR_NEIGHBOR_SEARCH,
            "the neighbour search returned index %d for point %zu, outside "
            "[0, %zu)",
            (int)in,
            query,
            m);
      int32_t p = c->input_to_point[in];
      if ((size_t)p == i)
        continue;
      int seen = 0;
      for (size_t r = 0; r < count && !seen; ++r)
        seen = row_idx[r] == p;
      if (seen)
        continue;
      const double* x = c->xyz + 3 * (size_t)p;
      double dx = q[0] - x[0], dy = q[1] - x[1], dz = q[2] - x[2];
      dacpo_nearest_insert(row_idx, row_d, k, &count, p, dx * dx + dy * dy + dz * dz);
    }
    /* Done when full, when the search has no more to give, or when it was
     * already asked for everything. */
    if (count == k || found < req || req == m)
      break;
    req = req > m / 2 ? m : 2 * req;
  }
  write_row(job->out, i, row_idx, row_d, count);
  return DACPO_OK;
}

static dacpo_status
knn_callback_task(void* user, size_t task, unsigned thread_id, dacpo_err* err)
{
  (void)thread_id;
  const knn_job* job = user;
  size_t n = job->cloud->n, k = job->k;
  size_t begin = task * KNN_CHUNK;
  size_t end = begin + KNN_CHUNK < n ? begin + KNN_CHUNK : n;
  size_t cap = 0;
  int32_t* cb_idx = NULL;
  float* cb_d = NULL;
  int32_t* row_idx = dacpo_malloc_array(k, sizeof(int32_t));
  double* row_d = dacpo_malloc_array(k, sizeof(double));
  dacpo_status s = DACPO_OK;
  if (!row_idx || !row_d)
    s = DACPO_OOM(err);
  for (size_t i = begin; i < end && s == DACPO_OK; ++i)
    s = knn_callback_point(job, i, &cap, &cb_idx, &cb_d, row_idx, row_d, err);
  free(cb_idx);
  free(cb_d);
  free(row_idx);
  free(row_d);
  return s;
}

dacpo_status
dacpo_knn_build(const dacpo_cloud* cloud,
                size_t k,
                const dacpo_search* search,
                unsigned num_threads,
                const dacpo_progress* progress,
                dacpo_knn_graph* out,
                dacpo_err* err)
{
  DACPO_CHECK(err, out != NULL, DACPO_ERR_INVALID_ARGUMENT, "knn: out is NULL");
  memset(out, 0, sizeof(*out));
  DACPO_CHECK(err,
              cloud != NULL && (cloud->n == 0 || cloud->xyz != NULL),
              DACPO_ERR_INVALID_ARGUMENT,
              "knn: cloud is NULL or empty");
  DACPO_CHECK(err,
              k < cloud->n,
              DACPO_ERR_INVALID_ARGUMENT,
              "knn: k = %zu must be smaller than the %zu distinct points",
              k,
              cloud->n);
  if (search && search->knn)
    DACPO_CHECK(err,
                cloud->rep_input && cloud->input_to_point,
                DACPO_ERR_INVALID_ARGUMENT,
                "knn: cloud has no input mapping");

  size_t n = cloud->n;
  out->n = n;
  out->k = k;
  out->idx = dacpo_malloc_array(n, k * sizeof(int32_t));
  out->sqd = dacpo_malloc_array(n, k * sizeof(float));
  if (!out->idx || !out->sqd) {
    dacpo_knn_graph_free(out);
    return DACPO_OOM(err);
  }
  if (k == 0)
    return DACPO_OK;

  knn_job job = {cloud, k, NULL, NULL, out};
  dacpo_kdtree* tree = NULL;
  dacpo_task_fn fn;
  if (search && search->knn) {
    job.search = search;
    fn = knn_callback_task;
  }
  else {
    dacpo_status s = dacpo_kdtree_build_threads(cloud->xyz, n, num_threads, &tree, err);
    if (s != DACPO_OK) {
      dacpo_knn_graph_free(out);
      return s;
    }
    job.tree = tree;
    fn = knn_builtin_task;
  }
  size_t tasks = (n + KNN_CHUNK - 1) / KNN_CHUNK;
  dacpo_status s = dacpo_parallel_for(
      tasks, num_threads, fn, &job, progress, DACPO_STAGE_NEIGHBORS, err);
  dacpo_kdtree_free(tree);
  if (s != DACPO_OK)
    dacpo_knn_graph_free(out);
  return s;
}

void
dacpo_knn_graph_free(dacpo_knn_graph* g)
{
  if (!g)
    return;
  free(g->idx);
  free(g->sqd);
  memset(g, 0, sizeof(*g));
}

void
dacpo_knn_graph_keep_farthest(dacpo_knn_graph* g)
{
  if (!g || !g->sqd || g->k <= 1)
    return;
  /* row i is read before slot i (part of an earlier row) is written */
  for (size_t i = 0; i < g->n; ++i) {
    float far = -1.0f;
    for (size_t j = 0; j < g->k; ++j)
      if (isfinite(g->sqd[i * g->k + j]) && g->sqd[i * g->k + j] > far)
        far = g->sqd[i * g->k + j];
    g->sqd[i] = far >= 0.0f ? far : INFINITY;
  }
  float* shrunk = realloc(g->sqd, (g->n ? g->n : 1) * sizeof(float));
  if (shrunk)
    g->sqd = shrunk;
  free(g->idx);
  g->idx = NULL;
  g->k = 1;
}

/* ---- symmetric adjacency ------------------------------------------------ */

static int
cmp_i32(const void* a, const void* b)
{
  int32_t x = *(const int32_t*)a, y = *(const int32_t*)b;
  return (x > y) - (x < y);
}

static void
sort_row(int32_t* v, size_t m)
{
  if (m > 32) {
    qsort(v, m, sizeof(int32_t), cmp_i32);
    return;
  }
  for (size_t i = 1; i < m; ++i) {
    int32_t x = v[i];
    size_t j = i;
    while (j > 0 && v[j - 1] > x) {
      v[j] = v[j - 1];
      --j;
    }
    v[j] = x;
  }
}

/* Row starts from the degrees, counting both directions of every listed pair.
 * Returns the first point listing a neighbour outside [0, n), or n if none
 * does (*bad gets that neighbour). */
static size_t
adj_count_degrees(const dacpo_knn_graph* g, size_t k_use, size_t* start, int32_t* bad)
{
  size_t n = g->n, k = g->k;
  for (size_t i = 0; i < n; ++i) {
    const int32_t* row = g->idx + i * k;
    for (size_t j = 0; j < k_use; ++j) {
      int32_t v = row[j];
      if (v < 0 || (size_t)v == i)
        continue;
      if ((size_t)v >= n) {
        *bad = v;
        return i;
      }
      ++start[i + 1];
      ++start[v + 1];
    }
  }
  for (size_t i = 0; i < n; ++i)
    start[i + 1] += start[i];
  return n;
}

/* Both directions of every listed pair into their rows; fill: n scratch. */
static void
adj_fill_rows(const dacpo_knn_graph* g,
              size_t k_use,
              dacpo_adjacency* out,
              size_t* fill)
{
  size_t n = g->n, k = g->k;
  memcpy(fill, out->start, n * sizeof(size_t));
  for (size_t i = 0; i < n; ++i) {
    const int32_t* row = g->idx + i * k;
    for (size_t j = 0; j < k_use; ++j) {
      int32_t v = row[j];
      if (v < 0 || (size_t)v == i)
        continue;
      out->nbr[fill[i]++] = v;
      out->nbr[fill[v]++] = (int32_t)i;
    }
  }
}

/* Rows [task * KNN_CHUNK, ...) sorted in place, repeats (mutual neighbours
 * appear twice) dropped; each row's length left in len. */
typedef struct adj_sort_job {
  dacpo_adjacency* out;
  size_t* len;
} adj_sort_job;

static dacpo_status
adj_sort_task(void* user, size_t task, unsigned thread_id, dacpo_err* err)
{
  adj_sort_job* job = (adj_sort_job*)user;
  const size_t n = job->out->n, begin = task * KNN_CHUNK;
  const size_t end = begin + KNN_CHUNK < n ? begin + KNN_CHUNK : n;
  for (size_t i = begin; i < end; ++i) {
    int32_t* r = job->out->nbr + job->out->start[i];
    const size_t m = job->out->start[i + 1] - job->out->start[i];
    sort_row(r, m);
    size_t w = 0;
    for (size_t j = 0; j < m; ++j)
      if (j == 0 || r[j] != r[w - 1])
        r[w++] = r[j];
    job->len[i] = w;
  }
  return DACPO_OK;
}

/* Sorts the rows (in parallel), then compacts them into place. len: n scratch. */
static dacpo_status
adj_sort_unique_rows(dacpo_adjacency* out,
                     size_t* len,
                     unsigned threads,
                     dacpo_err* err)
{
  const size_t n = out->n;
  adj_sort_job job = {out, len};
  DACPO_TRY(dacpo_parallel_for((n + KNN_CHUNK - 1) / KNN_CHUNK,
                               threads,
                               adj_sort_task,
                               &job,
                               NULL,
                               DACPO_STAGE_NEIGHBORS,
                               err));
  size_t w = 0;
  for (size_t i = 0; i < n; ++i) {
    const size_t from = out->start[i];
    out->start[i] = w;
    memmove(out->nbr + w, out->nbr + from, len[i] * sizeof(int32_t));
    w += len[i];
  }
  out->start[n] = w;
  if (w > 0) {
    int32_t* shrunk = realloc(out->nbr, w * sizeof(int32_t));
    if (shrunk)
      out->nbr = shrunk;
  }
  return DACPO_OK;
}

dacpo_status
dacpo_adjacency_build(const dacpo_knn_graph* g,
                      size_t k_use,
                      dacpo_adjacency* out,
                      dacpo_err* err)
{
  return dacpo_adjacency_build_threads(g, k_use, 1, out, err);
}

dacpo_status
dacpo_adjacency_build_threads(const dacpo_knn_graph* g,
                              size_t k_use,
                              unsigned num_threads,
                              dacpo_adjacency* out,
                              dacpo_err* err)
{
  DACPO_CHECK(err, out != NULL, DACPO_ERR_INVALID_ARGUMENT, "adjacency: out is NULL");
  memset(out, 0, sizeof(*out));
  DACPO_CHECK(err,
              g != NULL && (g->n == 0 || g->k == 0 || g->idx != NULL),
              DACPO_ERR_INVALID_ARGUMENT,
              "adjacency: graph is NULL");
  size_t n = g->n, k = g->k;
  if (k_use > k)
    k_use = k;

  out->n = n;
  out->start = dacpo_calloc_array(n + 1, sizeof(size_t));
  if (!out->start)
    return DACPO_OOM(err);
  int32_t bad = 0;
  size_t bad_point = adj_count_degrees(g, k_use, out->start, &bad);
  if (bad_point < n) {
    dacpo_adjacency_free(out);
    return dacpo_err_set(err,
                         DACPO_ERR_INTERNAL,
                         "adjacency: point %zu lists neighbour %d outside [0, %zu)",
                         bad_point,
                         (int)bad,
                         n);
  }
  out->nbr = dacpo_malloc_array(out->start[n], sizeof(int32_t));
  size_t* fill = dacpo_malloc_array(n, sizeof(size_t));
  if (!out->nbr || !fill) {
    free(fill);
    dacpo_adjacency_free(out);
    return DACPO_OOM(err);
  }
  adj_fill_rows(g, k_use, out, fill);
  /* fill is done with: it holds the row lengths after the sort */
  dacpo_status st = adj_sort_unique_rows(out, fill, num_threads, err);
  free(fill);
  if (st != DACPO_OK)
    dacpo_adjacency_free(out);
  return st;
}

void
dacpo_adjacency_free(dacpo_adjacency* a)
{
  if (!a)
    return;
  free(a->start);
  free(a->nbr);
  memset(a, 0, sizeof(*a));
}

/* ---- connected components ---------------------------------------------- */

dacpo_status
dacpo_components_label(const dacpo_adjacency* a,
                       int32_t* label,
                       size_t* num_components,
                       dacpo_err* err)
{
  DACPO_CHECK(err,
              a != NULL && num_components != NULL && (a->n == 0 || label != NULL),
              DACPO_ERR_INVALID_ARGUMENT,
              "components: NULL argument");
  DACPO_CHECK(err,
              a->n == 0 || a->start != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "components: adjacency has no rows");
  size_t n = a->n;
  *num_components = 0;
  if (n == 0)
    return DACPO_OK;
  int32_t* queue = dacpo_malloc_array(n, sizeof(int32_t));
  if (!queue)
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i)
    label[i] = -1;
  /* Seeds are visited in index order, so component ids follow each
   * component's lowest point index. */
  int32_t next = 0;
  for (size_t s = 0; s < n; ++s) {
    if (label[s] >= 0)
      continue;
    size_t head = 0, tail = 0;
    queue[tail++] = (int32_t)s;
    label[s] = next;
    while (head < tail) {
      size_t u = (size_t)queue[head++];
      for (size_t e = a->start[u]; e < a->start[u + 1]; ++e) {
        int32_t v = a->nbr[e];
        if (v < 0 || (size_t)v >= n) {
          free(queue);
          return dacpo_err_set(
              err,
              DACPO_ERR_INTERNAL,
              "components: point %zu has neighbour %d outside [0, %zu)",
              u,
              (int)v,
              n);
        }
        if (label[v] < 0) {
          label[v] = next;
          queue[tail++] = v;
        }
      }
    }
    ++next;
  }
  free(queue);
  *num_components = (size_t)next;
  return DACPO_OK;
}
