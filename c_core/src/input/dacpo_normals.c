/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 0, normals: PCA normal axes when the caller gives none (paper §4.2
 * starts from unoriented normals "estimated by PCA", Hoppe et al. 1992).
 *
 * For each distinct point p: C = sum (x - m)(x - m)^T over x in {p} and its
 * first normal_k neighbours, m their mean (centring first keeps precision for
 * clouds far from the origin). With dacpo_params.adaptive_normals (the
 * default) each point takes the flattest of 3/4, 1 and 3/2 x normal_k
 * neighbours (pca_point_adaptive). The axis is the
 * eigenvector of C's smallest eigenvalue l0; the surface variation l0 / (l0 + l1 + l2)
 * (Pauly et al. 2002) is the curvature reported to PCL users. Eigen-solver: cyclic
 * Jacobi on the 3x3 matrix scaled to max |c_ij| = 1. It always returns an orthonormal
 * basis, so coincident or collinear neighbourhoods still yield a unit vector (its
 * direction is then arbitrary but deterministic), never NaN. Cost: O(n normal_k),
 * parallel over chunks of points. Failure modes: bad arguments (INVALID_ARGUMENT);
 * nothing else. Where the scan kind finds offset copies, the axes that turn
 * with the scale are taken again at a larger one (dacpo_normals_copy_scale:
 * its own kd-tree, 2 to 32 x normal_k neighbours; OOM besides). */
#include "dacpo_normals.h"

#include "dacpo_kdtree.h"
#include "dacpo_parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { NORMALS_CHUNK = 4096, JACOBI_MAX_SWEEPS = 50 };

/* Eigen-decomposition of a symmetric 3x3 matrix a (destroyed): eigenvalues in
 * w, eigenvectors in the columns of v (v[row][col]), unsorted. */
void
dacpo_jacobi3(double a[3][3], double w[3], double v[3][3])
{
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      v[i][j] = i == j ? 1.0 : 0.0;
  double fro = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      fro += a[i][j] * a[i][j];
  static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int sweep = 0; sweep < JACOBI_MAX_SWEEPS; ++sweep) {
    double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    /* off-diagonal at rounding level of the whole matrix: converged */
    if (off <= 1e-34 * fro)
      break;
    for (int r = 0; r < 3; ++r) {
      int p = pairs[r][0], q = pairs[r][1];
      double apq = a[p][q];
      if (apq == 0.0)
        continue;
      /* Rotation that zeroes a[p][q]: t = tan(phi) is the smaller root of
       * t^2 + 2 t theta - 1 = 0, which keeps the rotation angle <= pi/4. */
      double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
      double t;
      if (fabs(theta) > 1e150)
        t = 0.5 / theta;
      else
        t = (theta >= 0.0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
      double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
      a[p][p] -= t * apq;
      a[q][q] += t * apq;
      a[p][q] = a[q][p] = 0.0;
      int o = 3 - p - q; /* the remaining index */
      double aop = a[o][p], aoq = a[o][q];
      a[o][p] = a[p][o] = c * aop - s * aoq;
      a[o][q] = a[q][o] = s * aop + c * aoq;
      for (int i = 0; i < 3; ++i) {
        double vip = v[i][p], viq = v[i][q];
        v[i][p] = c * vip - s * viq;
        v[i][q] = s * vip + c * viq;
      }
    }
  }
  for (int i = 0; i < 3; ++i)
    w[i] = a[i][i];
}

/* Adds e e^T to the upper triangle (r <= s) of a covariance sum. */
static void
covariance_add(double c[3][3], const double e[3])
{
  for (int r = 0; r < 3; ++r)
    for (int s = r; s < 3; ++s)
      c[r][s] += e[r] * e[s];
}

/* The axis of least variance of the covariance c (its upper triangle filled,
 * mirrored here; unit; +z for a degenerate one), the surface variation
 * l0 / (l0 + l1 + l2) in *curv and, when elong is not NULL, l1 / l2 (middle
 * over largest eigenvalue). */
static void
axis_of_covariance(double c[3][3], double nrm[3], double* curv, double* elong)
{
  c[1][0] = c[0][1];
  c[2][0] = c[0][2];
  c[2][1] = c[1][2];
  /* Scale to max |c_ij| = 1 so tiny or huge neighbourhoods neither underflow
   * nor overflow inside Jacobi; eigenvectors and l0/trace are scale-free. */
  double mx = 0.0;
  for (int r = 0; r < 3; ++r)
    for (int s = 0; s < 3; ++s)
      if (fabs(c[r][s]) > mx)
        mx = fabs(c[r][s]);
  double w[3] = {0.0, 0.0, 0.0};
  double v[3][3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
  if (mx > 0.0 && isfinite(mx)) {
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s)
        c[r][s] /= mx;
    dacpo_jacobi3(c, w, v);
  }
  int lo = 0;
  for (int d = 1; d < 3; ++d)
    if (w[d] < w[lo])
      lo = d;
  double len = sqrt(v[0][lo] * v[0][lo] + v[1][lo] * v[1][lo] + v[2][lo] * v[2][lo]);
  if (len > 0.0 && isfinite(len)) {
    for (int d = 0; d < 3; ++d)
      nrm[d] = v[d][lo] / len;
  }
  else {
    nrm[0] = 0.0;
    nrm[1] = 0.0;
    nrm[2] = 1.0;
  }
  /* covariance is positive semi-definite; clamp rounding below zero */
  double l[3], trace = 0.0;
  for (int d = 0; d < 3; ++d) {
    l[d] = w[d] > 0.0 ? w[d] : 0.0;
    trace += l[d];
  }
  *curv = trace > 0.0 ? l[lo] / trace : 0.0;
  if (elong) {
    const int hi = l[(lo + 1) % 3] >= l[(lo + 2) % 3] ? (lo + 1) % 3 : (lo + 2) % 3;
    const int mid = 3 - lo - hi;
    *elong = l[hi] > 0.0 ? l[mid] / l[hi] : 0.0;
  }
}

/* PCA axis and surface variation of one neighbourhood; elong (may be NULL)
 * gets l1 / l2, the middle over the largest eigenvalue (near 0: the
 * neighbours lie along a line or a narrow strip). */
static void
pca_point(const dacpo_cloud* cloud,
          const dacpo_knn_graph* g,
          size_t normal_k,
          size_t i,
          double nrm[3],
          double* curv,
          double* elong)
{
  const double* xyz = cloud->xyz;
  const int32_t* row = g->idx + i * g->k;
  double m[3] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
  double count = 1.0;
  for (size_t j = 0; j < normal_k; ++j) {
    int32_t v = row[j];
    if (v < 0 || (size_t)v >= cloud->n)
      continue;
    for (int d = 0; d < 3; ++d)
      m[d] += xyz[3 * (size_t)v + d];
    count += 1.0;
  }
  for (int d = 0; d < 3; ++d)
    m[d] /= count;

  double c[3][3] = {{0.0}};
  for (size_t j = 0; j <= normal_k; ++j) {
    size_t p;
    if (j == 0) {
      p = i;
    }
    else {
      int32_t v = row[j - 1];
      if (v < 0 || (size_t)v >= cloud->n)
        continue;
      p = (size_t)v;
    }
    const double e[3] = {
        xyz[3 * p] - m[0], xyz[3 * p + 1] - m[1], xyz[3 * p + 2] - m[2]};
    covariance_add(c, e);
  }
  axis_of_covariance(c, nrm, curv, elong);
}

/* Adaptive scale: per point the neighbourhood among 3/4, 1 and 3/2 x normal_k
 * with the lowest surface variation l0 / (l0 + l1 + l2) (Pauly et al. 2002:
 * the scale at which the points look most like one plane). At 16 neighbours a
 * sparse room's thin parts and corners mix two faces (the smaller scale is
 * flatter there), noise is averaged better by the larger one. A scale other
 * than normal_k must also see a neighbourhood that is not a strip (l1 / l2 >=
 * ADAPTIVE_MIN_SPREAD): single depth frames break into flat depth-quantisation
 * terraces whose narrow strips look perfectly planar with the wrong axis. */
#define ADAPTIVE_MIN_SPREAD 0.3

static void
pca_point_adaptive(const dacpo_cloud* cloud,
                   const dacpo_knn_graph* g,
                   size_t normal_k,
                   size_t i,
                   double nrm[3],
                   double* curv)
{
  size_t lo_k = (3 * normal_k + 2) / 4, hi_k = dacpo_normals_width(normal_k, 1);
  if (lo_k < 3)
    lo_k = 3 < normal_k ? 3 : normal_k;
  if (hi_k > g->k)
    hi_k = g->k;
  const size_t scale[3] = {lo_k, normal_k, hi_k};
  pca_point(cloud, g, normal_k, i, nrm, curv, NULL);
  for (int s = 0; s < 3; ++s) {
    if (scale[s] == normal_k)
      continue;
    double a[3], c, elong;
    pca_point(cloud, g, scale[s], i, a, &c, &elong);
    if (elong >= ADAPTIVE_MIN_SPREAD && c < *curv) {
      memcpy(nrm, a, sizeof(a));
      *curv = c;
    }
  }
}

typedef struct normals_job {
  const dacpo_cloud* cloud;
  const dacpo_knn_graph* g;
  size_t normal_k;
  int adaptive;
  double* nrm;
  float* curvature;
} normals_job;

static dacpo_status
normals_task(void* user, size_t task, unsigned thread_id, dacpo_err* err)
{
  (void)thread_id;
  (void)err;
  const normals_job* job = user;
  size_t n = job->cloud->n;
  size_t begin = task * NORMALS_CHUNK;
  size_t end = begin + NORMALS_CHUNK < n ? begin + NORMALS_CHUNK : n;
  for (size_t i = begin; i < end; ++i) {
    double curv;
    if (job->adaptive)
      pca_point_adaptive(job->cloud, job->g, job->normal_k, i, job->nrm + 3 * i, &curv);
    else
      pca_point(job->cloud, job->g, job->normal_k, i, job->nrm + 3 * i, &curv, NULL);
    if (job->curvature)
      job->curvature[i] = (float)curv;
  }
  return DACPO_OK;
}

dacpo_status
dacpo_normals_pca(const dacpo_cloud* cloud,
                  const dacpo_knn_graph* g,
                  size_t normal_k,
                  unsigned num_threads,
                  double* nrm_out,
                  float* curvature,
                  dacpo_err* err)
{
  return dacpo_normals_pca_scaled(cloud, g, normal_k, 0, num_threads, nrm_out, curvature, err);
}

size_t
dacpo_normals_width(size_t normal_k, int adaptive)
{
  return adaptive ? (3 * normal_k + 1) / 2 : normal_k;
}

dacpo_status
dacpo_normals_pca_scaled(const dacpo_cloud* cloud,
                         const dacpo_knn_graph* g,
                         size_t normal_k,
                         int adaptive,
                         unsigned num_threads,
                         double* nrm_out,
                         float* curvature,
                         dacpo_err* err)
{
  DACPO_CHECK(err,
              cloud != NULL && g != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "normals: cloud or graph is NULL");
  DACPO_CHECK(err,
              g->n == cloud->n,
              DACPO_ERR_INVALID_ARGUMENT,
              "normals: graph has %zu points, cloud has %zu",
              g->n,
              cloud->n);
  DACPO_CHECK(err,
              normal_k <= g->k,
              DACPO_ERR_INVALID_ARGUMENT,
              "normals: normal_k = %zu exceeds the graph's k = %zu",
              normal_k,
              g->k);
  if (cloud->n == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              nrm_out != NULL && cloud->xyz != NULL && (g->k == 0 || g->idx != NULL),
              DACPO_ERR_INVALID_ARGUMENT,
              "normals: NULL array");
  normals_job job = {cloud, g, normal_k, adaptive != 0, nrm_out, curvature};
  size_t tasks = (cloud->n + NORMALS_CHUNK - 1) / NORMALS_CHUNK;
  return dacpo_parallel_for(
      tasks, num_threads, normals_task, &job, NULL, DACPO_STAGE_NORMALS, err);
}

/* ---- axes of a scan of offset copies --------------------------------- */

/* Two axes agree within this angle (a neighbourhood twice as large turns a
 * flat layer's axis by a few degrees; copies' PCA noise turns it by tens). */
#define STABLE_COS 0.9396926207859084 /* cos 20 degrees */
/* Scales looked at: 2, 4, ..., 2^COPY_SCALES x normal_k neighbours (the
 * wider apart the copies, the larger the scale where their axis holds). */
#define COPY_SCALES 5

/* PCA axis and surface variation of the first m points of a k-NN answer. */
static void
pca_rows(const double* xyz, const int32_t* idx, size_t m, double nrm[3], double* curv)
{
  double mean[3] = {0.0, 0.0, 0.0};
  for (size_t j = 0; j < m; ++j)
    for (int d = 0; d < 3; ++d)
      mean[d] += xyz[3 * (size_t)idx[j] + d];
  for (int d = 0; d < 3; ++d)
    mean[d] /= (double)m;
  double c[3][3] = {{0.0}};
  for (size_t j = 0; j < m; ++j) {
    const double* p = xyz + 3 * (size_t)idx[j];
    const double e[3] = {p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]};
    covariance_add(c, e);
  }
  axis_of_covariance(c, nrm, curv, NULL);
}

static int
axes_agree(const double a[3], const double b[3])
{
  return fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) >= STABLE_COS;
}

typedef struct copy_axes_job {
  const dacpo_cloud* cloud;
  const dacpo_kdtree* tree;
  size_t base_k; /* neighbours of the first larger scale (2 x normal_k) */
  double* nrm;
  float* curvature;
  uint8_t* changed;
} copy_axes_job;

/* One point: the axis of the first of 2, 4, 8, 16 x normal_k neighbours
 * that agrees with twice as many, if the given axis does not agree with the
 * first. Each larger answer is asked for only when the smaller one did not
 * settle it (the first m of k nearest are the m nearest: ties go to the lower
 * index). */
static void
copy_axis_point(const copy_axes_job* job, size_t i, int32_t* idx, double* d2)
{
  const double* xyz = job->cloud->xyz;
  double a[COPY_SCALES][3], curv[COPY_SCALES];
  const double* prev = job->nrm + 3 * i;
  for (int s = 0; s < COPY_SCALES; ++s) {
    const size_t k = job->base_k << s;
    if (dacpo_kdtree_knn(job->tree, xyz + 3 * i, k, idx, d2) < k)
      return;
    pca_rows(xyz, idx, k, a[s], &curv[s]);
    if (axes_agree(prev, a[s])) {
      if (s == 0) /* the given axis holds */
        return;
      memcpy(job->nrm + 3 * i, a[s - 1], sizeof(a[s - 1]));
      if (job->curvature)
        job->curvature[i] = (float)curv[s - 1];
      job->changed[i] = 1;
      return;
    }
    prev = a[s];
  }
}

static dacpo_status
copy_axes_task(void* user, size_t task, unsigned thread_id, dacpo_err* err)
{
  (void)thread_id;
  const copy_axes_job* job = user;
  const size_t n = job->cloud->n;
  const size_t begin = task * NORMALS_CHUNK;
  const size_t end = begin + NORMALS_CHUNK < n ? begin + NORMALS_CHUNK : n;
  const size_t most = job->base_k << (COPY_SCALES - 1);
  int32_t* idx = dacpo_malloc_array(most, sizeof(int32_t));
  double* d2 = dacpo_malloc_array(most, sizeof(double));
  dacpo_status st = idx && d2 ? DACPO_OK : DACPO_OOM(err);
  for (size_t i = begin; st == DACPO_OK && i < end; ++i)
    copy_axis_point(job, i, idx, d2);
  free(idx);
  free(d2);
  return st;
}

dacpo_status
dacpo_normals_copy_scale(const dacpo_cloud* cloud,
                         size_t normal_k,
                         unsigned num_threads,
                         double* nrm,
                         float* curvature,
                         size_t* changed,
                         dacpo_err* err)
{
  *changed = 0;
  const size_t k = normal_k > 0 ? normal_k : 1;
  if (k > cloud->n >> COPY_SCALES) /* too few points for the largest scale */
    return DACPO_OK;
  const size_t base_k = 2 * k;
  dacpo_kdtree* tree = NULL;
  DACPO_TRY(dacpo_kdtree_build_threads(cloud->xyz, cloud->n, num_threads, &tree, err));
  uint8_t* flag = dacpo_calloc_array(cloud->n, sizeof(uint8_t));
  dacpo_status st = flag ? DACPO_OK : DACPO_OOM(err);
  if (st == DACPO_OK) {
    copy_axes_job job = {cloud, tree, base_k, nrm, curvature, flag};
    st = dacpo_parallel_for((cloud->n + NORMALS_CHUNK - 1) / NORMALS_CHUNK,
                            num_threads,
                            copy_axes_task,
                            &job,
                            NULL,
                            DACPO_STAGE_NORMALS,
                            err);
  }
  for (size_t i = 0; st == DACPO_OK && i < cloud->n; ++i)
    *changed += flag[i];
  free(flag);
  dacpo_kdtree_free(tree);
  return st;
}
