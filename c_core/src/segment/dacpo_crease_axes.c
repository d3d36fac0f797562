/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 1 helper: crease-preserving averaging of unsigned axes (see
 * dacpo_crease_axes.h). The block growth (dacpo_segment.c) charges a step
 * between two points by how far their axes differ; raw PCA axes of a scan
 * whose frames left two copies of a surface a few millimetres apart scatter
 * by 10-30 degrees, which would make every step look like a small crease.
 * Averaging with weights that fall with the axis difference (a bilateral
 * filter on the axis tensor) removes that scatter and keeps real creases. */
#include "dacpo_crease_axes.h"

#include "dacpo_parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { CREASE_CHUNK = 4096, CREASE_PASSES = 2 };

typedef struct crease_job {
  const dacpo_knn_graph* g;
  size_t n, k;
  const double* in;
  double* out;
} crease_job;

/* a[3] <- the eigenvector of the largest eigenvalue of t, with the sign of
 * ref; ref itself when t is degenerate. */
static void
principal_axis(double t[3][3], const double* ref, double* a)
{
  double w[3], v[3][3];
  dacpo_jacobi3(t, w, v);
  int hi = 0;
  for (int d = 1; d < 3; ++d)
    if (w[d] > w[hi])
      hi = d;
  const double len = sqrt(v[0][hi] * v[0][hi] + v[1][hi] * v[1][hi] + v[2][hi] * v[2][hi]);
  if (!(len > 0.0) || !isfinite(len)) {
    memcpy(a, ref, 3 * sizeof(double));
    return;
  }
  const double dot = v[0][hi] * ref[0] + v[1][hi] * ref[1] + v[2][hi] * ref[2];
  const double s = (dot < 0.0 ? -1.0 : 1.0) / len;
  for (int d = 0; d < 3; ++d)
    a[d] = s * v[d][hi];
}

static dacpo_status
crease_task(void* user, size_t task, unsigned thread_id, dacpo_err* err)
{
  (void)thread_id;
  (void)err;
  const crease_job* job = user;
  const size_t begin = task * CREASE_CHUNK;
  const size_t end = begin + CREASE_CHUNK < job->n ? begin + CREASE_CHUNK : job->n;
  for (size_t i = begin; i < end; ++i) {
    const double* ai = job->in + 3 * i;
    const int32_t* row = job->g->idx + i * job->g->k;
    double t[3][3] = {{0.0}};
    for (size_t j = 0; j <= job->k; ++j) {
      const double* aj = ai;
      if (j > 0) {
        const int32_t q = row[j - 1];
        if (q < 0 || (size_t)q >= job->n)
          continue;
        aj = job->in + 3 * (size_t)q;
      }
      const double c = ai[0] * aj[0] + ai[1] * aj[1] + ai[2] * aj[2];
      const double w = exp(-(1.0 - c * c) / DACPO_CREASE_AXIS_S2);
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s)
          t[r][s] += w * aj[r] * aj[s];
    }
    principal_axis(t, ai, job->out + 3 * i);
  }
  return DACPO_OK;
}

dacpo_status
dacpo_crease_axes(const dacpo_cloud* cloud,
                  const dacpo_knn_graph* g,
                  size_t k,
                  unsigned num_threads,
                  double* out,
                  dacpo_err* err)
{
  DACPO_CHECK(err,
              cloud != NULL && g != NULL && out != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "crease axes: NULL argument");
  DACPO_CHECK(err,
              g->n == cloud->n && k <= g->k,
              DACPO_ERR_INVALID_ARGUMENT,
              "crease axes: graph of %zu points and %zu columns for %zu points, k = %zu",
              g->n,
              g->k,
              cloud->n,
              k);
  const size_t n = cloud->n;
  if (n == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              cloud->nrm != NULL && (k == 0 || g->idx != NULL),
              DACPO_ERR_INVALID_ARGUMENT,
              "crease axes: NULL array");
  double* scratch = dacpo_malloc_array(3 * n, sizeof(double));
  if (scratch == NULL)
    return DACPO_OOM(err);
  /* the passes alternate between scratch and out, the last one into out */
  crease_job job = {g, n, k, cloud->nrm, NULL};
  const size_t tasks = (n + CREASE_CHUNK - 1) / CREASE_CHUNK;
  dacpo_status st = DACPO_OK;
  for (int pass = 0; pass < CREASE_PASSES && st == DACPO_OK; ++pass) {
    job.out = (CREASE_PASSES - pass) % 2 ? out : scratch;
    st = dacpo_parallel_for(
        tasks, num_threads, crease_task, &job, NULL, DACPO_STAGE_SEGMENT, err);
    job.in = job.out;
  }
  free(scratch);
  return st;
}
