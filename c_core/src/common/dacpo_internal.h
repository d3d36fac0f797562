/* SPDX-License-Identifier: BSD-3-Clause */
/* Private structures shared by several stages. Nothing here is installed. */
#ifndef DACPO_INTERNAL_H
#define DACPO_INTERNAL_H

#include <dacpo/dacpo.h>

#include "dacpo_rng.h"

#include <stddef.h>
#include <stdint.h>

/* An error as a stage reports it: stages run on worker threads, so they never
 * touch the context; the pipeline copies the first error into it. */
typedef struct dacpo_err {
  dacpo_status code;
  char msg[384];
} dacpo_err;

/* Records code + printf-style message in err (if not NULL); returns code. */
dacpo_status
dacpo_err_set(dacpo_err* err, dacpo_status code, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#define DACPO_CHECK(err, cond, code, ...)                                              \
  do {                                                                                 \
    if (!(cond))                                                                       \
      return dacpo_err_set((err), (code), __VA_ARGS__);                                \
  } while (0)

#define DACPO_TRY(expr)                                                                \
  do {                                                                                 \
    dacpo_status dacpo_try_status_ = (expr);                                           \
    if (dacpo_try_status_ != DACPO_OK)                                                 \
      return dacpo_try_status_;                                                        \
  } while (0)

#define DACPO_OOM(err)                                                                 \
  dacpo_err_set((err), DACPO_ERR_OUT_OF_MEMORY, "out of memory in %s", __func__)

/* Wall clock in seconds (monotonic). */
double
dacpo_now(void);

/* Eigen-decomposition of a symmetric 3x3 matrix a (destroyed): eigenvalues in
 * w, eigenvectors in the columns of v (v[row][col]), unsorted (Jacobi). */
void
dacpo_jacobi3(double a[3][3], double w[3], double v[3][3]);

/* Quickselect: the k-th smallest of v[0..n), n > 0, k < n (v is permuted). */
double
dacpo_select_kth(double* v, size_t n, size_t k);

/* qsort comparator for doubles, ascending. */
int
dacpo_cmp_double(const void* a, const void* b);

/* A triangle mesh. Winding is counter-clockwise seen from the side the
 * (oriented) normals point to: the face normal (v1-v0)x(v2-v0) agrees with the
 * block's point normals. */
typedef struct dacpo_mesh {
  size_t num_vertices;
  size_t num_triangles;
  double* vertices;   /* 3 * num_vertices */
  int32_t* triangles; /* 3 * num_triangles */
} dacpo_mesh;

void
dacpo_mesh_free(dacpo_mesh* mesh); /* frees arrays, zeroes the struct */

/* Checked allocation helpers: return NULL on overflow or failure. */
void*
dacpo_malloc_array(size_t count, size_t size);
void*
dacpo_calloc_array(size_t count, size_t size);

/* Union-find over int32 ids (parent[i] == i for a root), shared by the stages
 * that group things: VCR pixel regions, bridges between components, the 0-1
 * program's spanning forest, parts of the block graph. Find halves paths; union
 * makes the smaller root the root, so a root precedes its members in scan order
 * and one scan can hand out compact ids. */
static inline int32_t
dacpo_uf_find(int32_t* parent, int32_t x)
{
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

static inline void
dacpo_uf_union(int32_t* parent, int32_t x, int32_t y)
{
  x = dacpo_uf_find(parent, x);
  y = dacpo_uf_find(parent, y);
  if (x < y)
    parent[y] = x;
  else if (y < x)
    parent[x] = y;
}

#endif /* DACPO_INTERNAL_H */
