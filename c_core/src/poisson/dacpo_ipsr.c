/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 3b: iterative Poisson surface reconstruction (iPSR, Hou et al. 2022)
 * with Neumann boundary conditions, one block at a time (paper §4.3).
 *
 * Input: a block's n samples (own points first, then the ring) and their
 * initial oriented normals (stage 2). Output: refined normals (in place), and
 * optionally the block's final trimmed mesh restricted to its own points (for
 * stage 4's visible connected regions).
 *
 * Each iteration: solve the screened Poisson indicator from the current
 * normals (dacpo_poisson.c, warm-started), extract its iso-surface
 * (dacpo_mcubes.c), let every face send its area-weighted normal (the
 * unnormalised cross product) to its face_k nearest samples, and take each
 * sample's normalised sum as its new normal (samples that receive nothing
 * keep theirs). Stop when the mean of the largest max(ceil(n/1000), 10)
 * changes |n_new - n_old| is below `convergence` (Hou et al.'s test), when an
 * iteration from settle_start on turned over (the sign of a normal against
 * its input normal) no more samples than that test averages, or after
 * max_iterations. The sign is all the pipeline keeps of a point's stage-3
 * normal; once the signs hold, further iterations turn rim normals by small
 * angles (Hou et al.'s test waits for the ten largest changes to fall under
 * 0.1, often for the whole run) and over a handful of noisy rim samples each.
 * The first settle_start iterations run in any case: the normals they refine
 * shape the mesh stage 4 weighs the blocks' contacts by. The tolerance is at
 * least 10 samples, so blocks of fewer than 100 samples (tiny parts only:
 * a part of n points gets about n/625 blocks, each with a ring) may stop with
 * more than one in ten turning.
 *
 * Wings: the Neumann surface runs on from the data's rim to the border of the
 * Poisson domain ("extended faces", paper Fig. 4): the box for band 0, a few
 * cells past the data for the default narrow band. They are kept in early
 * iterations and trimmed from iteration trim_start on (a run that settles
 * earlier stops there; the mesh it hands out is trimmed all the same): faces
 * farther than trim_spacings sample spacings from every sample are removed
 * when a chain of such far faces links them to the mesh rim (its boundary
 * edges, which lie on the domain's border), so gaps inside the data stay
 * covered. Trimmed faces do not vote.
 *
 * Defaults, measured with tests/c_core/bench_ipsr.c on 2,500-point blocks
 * (generated sheets, and 60 blocks cut from the 15 real scans with 30 % of the
 * true normals flipped): a narrow band of 2 cells instead of the whole box
 * (0.6 % wrong instead of 3-4 %: depth scans put surfaces one in front of the
 * other, and over the whole box the free space between them couples their
 * indicators so the smaller one flips; the band also makes the cost follow
 * the block's area), point_weight 16 (0.64 % vs 0.69 % at 4, fewer
 * iterations), cell = 1 spacing (0.75 costs 2x for 0.1 % less), solve
 * tolerance 3e-2 (as accurate as 1e-3, 1.5x faster).
 *
 * Spacing: sqrt of the median area per sample, the area of a sample being
 * pi r_8^2 / 8 with r_8 its 8th-neighbour distance (about 0.8 x the squared
 * step of grid-like sampling, 1/density for random sampling). The
 * per-sample areas (clamped to [1/4, 4] x the median) weight the Poisson splat
 * and screening.
 *
 * Cost per iteration: one warm-started multigrid-CG solve (O(band cells)),
 * one marching-cubes pass, the k nearest samples of every face (from the
 * candidate lists of dacpo_cell_knn.c, kept per grid cell for the block's
 * iterations: the kd-tree's answer at a fraction of its cost). Failure modes:
 * INVALID_ARGUMENT (bad params, n_own > n), NONFINITE_INPUT, OUT_OF_MEMORY.
 */
#include "dacpo_ipsr.h"

#include "dacpo_cell_knn.h"
#include "dacpo_kdtree.h"
#include "dacpo_mcubes.h"
#include "dacpo_poisson.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void
dacpo_ipsr_params_default(dacpo_ipsr_params* p)
{
  if (!p)
    return;
  memset(p, 0, sizeof(*p));
  p->max_iterations = 20;
  p->convergence = 0.1;
  p->face_k = 10;
  p->trim_start = 5;
  p->settle_start = 2;
  p->trim_spacings = 2.5;
  p->point_weight = 16.0;
  p->cell_per_spacing = 1.0;
  p->max_resolution = 128;
  p->padding = 0.1;
  p->max_cells = 1500000; /* about 27 bytes per cell: <= 41 MB of grids */
  /* loose: the loop refines chi across iterations (warm start); measured as
   * accurate as 1e-3 and 1.5x faster per block */
  p->tolerance = 3e-2;
  p->max_cg_iterations = 30;
  p->band = 2;
  p->fixed = NULL;
}

/* Scratch of one block run; every array is freed by ipsr_clear. */
typedef struct ipsr_work {
  dacpo_kdtree* tree;
  dacpo_cell_knn* faces_knn; /* the face queries, through tree */
  dacpo_poisson* ps;
  dacpo_mcubes* mc;
  double* area;   /* n */
  double* acc;    /* 3n vote sums */
  double* change; /* n */
  double* heap;   /* top-m changes */
  /* per face, capacity fcap */
  size_t fcap;
  int32_t* fknn;    /* face_k per face */
  double* fnrm;     /* 3 per face: unnormalised normal */
  double* fdist2;   /* squared distance to the nearest sample */
  uint8_t* removed; /* trimmed */
  int32_t* queue;
  /* vertex -> face incidence, capacity vcap */
  size_t vcap;
  int32_t* vstart; /* vcap + 1 */
  int32_t* vfaces; /* 3 * fcap */
  size_t bytes;    /* our own arrays (poisson and mcubes report theirs) */
} ipsr_work;

static void
ipsr_clear(ipsr_work* w)
{
  dacpo_cell_knn_free(w->faces_knn);
  dacpo_kdtree_free(w->tree);
  dacpo_poisson_free(w->ps);
  dacpo_mcubes_free(w->mc);
  free(w->area);
  free(w->acc);
  free(w->change);
  free(w->heap);
  free(w->fknn);
  free(w->fnrm);
  free(w->fdist2);
  free(w->removed);
  free(w->queue);
  free(w->vstart);
  free(w->vfaces);
  memset(w, 0, sizeof(*w));
}

static size_t
work_bytes(const ipsr_work* w, size_t k)
{
  return w->bytes +
         w->fcap *
             (k * sizeof(int32_t) + 4 * sizeof(double) + 1 + 4 * sizeof(int32_t)) +
         (w->vcap + 1) * sizeof(int32_t) + dacpo_poisson_bytes(w->ps) +
         dacpo_mcubes_bytes(w->mc) + dacpo_cell_knn_bytes(w->faces_knn);
}

static int
ensure_faces(ipsr_work* w, size_t nf, size_t k)
{
  if (nf <= w->fcap)
    return 1;
  size_t cap = w->fcap ? w->fcap : 1024;
  while (cap < nf)
    cap *= 2;
  int32_t* a = (int32_t*)dacpo_malloc_array(cap * k, sizeof(int32_t));
  double* b = (double*)dacpo_malloc_array(cap * 3, sizeof(double));
  double* c = (double*)dacpo_malloc_array(cap, sizeof(double));
  uint8_t* d = (uint8_t*)dacpo_malloc_array(cap, 1);
  int32_t* e = (int32_t*)dacpo_malloc_array(cap, sizeof(int32_t));
  int32_t* f = (int32_t*)dacpo_malloc_array(cap * 3, sizeof(int32_t));
  if (!a || !b || !c || !d || !e || !f) {
    free(a), free(b), free(c), free(d), free(e), free(f);
    return 0;
  }
  free(w->fknn), free(w->fnrm), free(w->fdist2), free(w->removed), free(w->queue),
      free(w->vfaces);
  w->fknn = a, w->fnrm = b, w->fdist2 = c, w->removed = d, w->queue = e, w->vfaces = f;
  w->fcap = cap;
  return 1;
}

static int
ensure_vertices(ipsr_work* w, size_t nv)
{
  if (nv <= w->vcap && w->vstart)
    return 1;
  size_t cap = w->vcap ? w->vcap : 1024;
  while (cap < nv)
    cap *= 2;
  int32_t* a = (int32_t*)dacpo_malloc_array(cap + 1, sizeof(int32_t));
  if (!a)
    return 0;
  free(w->vstart);
  w->vstart = a;
  w->vcap = cap;
  return 1;
}

/* Mean of the m largest values of v[0..n) (min-heap of size m). */
static double
mean_of_largest(const double* v, size_t n, size_t m, double* heap)
{
  if (m > n)
    m = n;
  if (m == 0)
    return 0.0;
  size_t h = 0;
  for (size_t i = 0; i < n; ++i) {
    double x = v[i];
    if (h < m) {
      size_t c = h++;
      heap[c] = x;
      while (c > 0 && heap[(c - 1) / 2] > heap[c]) {
        double t = heap[c];
        heap[c] = heap[(c - 1) / 2];
        heap[(c - 1) / 2] = t;
        c = (c - 1) / 2;
      }
    }
    else if (x > heap[0]) {
      heap[0] = x;
      size_t c = 0;
      for (;;) {
        size_t l = 2 * c + 1, r = l + 1, s = c;
        if (l < m && heap[l] < heap[s])
          s = l;
        if (r < m && heap[r] < heap[s])
          s = r;
        if (s == c)
          break;
        double t = heap[c];
        heap[c] = heap[s];
        heap[s] = t;
        c = s;
      }
    }
  }
  double sum = 0.0;
  for (size_t i = 0; i < m; ++i)
    sum += heap[i];
  return sum / (double)m;
}

/* Per-sample area pi r_k^2 / k and the block spacing. */
static dacpo_status
estimate_spacing(
    ipsr_work* w, const double* xyz, size_t n, double* spacing, dacpo_err* err)
{
  double* tmp = (double*)dacpo_malloc_array(n, sizeof(double));
  if (!tmp)
    return DACPO_OOM(err);
  for (size_t i = 0; i < n; ++i) {
    w->area[i] = dacpo_kdtree_sample_area(w->tree, xyz + 3 * i);
    tmp[i] = w->area[i];
  }
  double med = dacpo_select_kth(tmp, n, n / 2);
  free(tmp);
  if (!(med > 0.0) || !isfinite(med)) {
    /* Mostly coincident samples: fall back on the box diagonal. */
    double lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
    for (size_t i = 1; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        lo[a] = fmin(lo[a], xyz[3 * i + a]);
        hi[a] = fmax(hi[a], xyz[3 * i + a]);
      }
    double diag =
        sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
             (hi[2] - lo[2]) * (hi[2] - lo[2]));
    med = diag > 0.0 ? diag * diag / (double)n : 1.0;
  }
  for (size_t i = 0; i < n; ++i) {
    double a = w->area[i];
    w->area[i] = a < 0.25 * med ? 0.25 * med : (a > 4.0 * med ? 4.0 * med : a);
  }
  *spacing = sqrt(med);
  return DACPO_OK;
}

/* Marks the faces to trim: far from the data and joined to the mesh rim by
 * far faces (or every far face with experiment.trim_interior). */
static void
trim_faces(ipsr_work* w, const dacpo_mesh* m, double far2, int interior)
{
  const size_t nf = m->num_triangles, nv = m->num_vertices;
  const int32_t* tri = m->triangles;
  memset(w->removed, 0, nf);
  if (interior) {
    for (size_t f = 0; f < nf; ++f)
      w->removed[f] = w->fdist2[f] > far2;
    return;
  }
  /* vertex -> faces (CSR) */
  int32_t* start = w->vstart;
  memset(start, 0, (nv + 1) * sizeof(int32_t));
  for (size_t t = 0; t < 3 * nf; ++t)
    start[tri[t] + 1]++;
  for (size_t v = 0; v < nv; ++v)
    start[v + 1] += start[v];
  /* fill, advancing each start to its end, then shift back by one vertex */
  for (size_t f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c)
      w->vfaces[start[tri[3 * f + c]]++] = (int32_t)f;
  for (size_t v = nv; v > 0; --v)
    start[v] = start[v - 1];
  start[0] = 0;

  size_t head = 0, tail = 0;
  /* seeds: far faces with a boundary edge (an edge no other face shares) */
  for (size_t f = 0; f < nf; ++f) {
    if (!(w->fdist2[f] > far2))
      continue;
    int rim = 0;
    for (int c = 0; c < 3 && !rim; ++c) {
      int32_t a = tri[3 * f + c], b = tri[3 * f + (c + 1) % 3];
      int shared = 0;
      for (int32_t p = start[a]; p < start[a + 1] && !shared; ++p) {
        int32_t g = w->vfaces[p];
        if ((size_t)g == f)
          continue;
        const int32_t* tg = tri + 3 * (size_t)g;
        shared = tg[0] == b || tg[1] == b || tg[2] == b;
      }
      rim = !shared;
    }
    if (rim) {
      w->removed[f] = 1;
      w->queue[tail++] = (int32_t)f;
    }
  }
  /* flood across shared edges, through far faces only */
  while (head < tail) {
    size_t f = (size_t)w->queue[head++];
    for (int c = 0; c < 3; ++c) {
      int32_t a = tri[3 * f + c], b = tri[3 * f + (c + 1) % 3];
      for (int32_t p = start[a]; p < start[a + 1]; ++p) {
        size_t g = (size_t)w->vfaces[p];
        if (w->removed[g] || !(w->fdist2[g] > far2))
          continue;
        const int32_t* tg = tri + 3 * g;
        if (tg[0] == b || tg[1] == b || tg[2] == b) {
          w->removed[g] = 1;
          w->queue[tail++] = (int32_t)g;
        }
      }
    }
  }
}

/* Face normals, nearest samples and distances for the current mesh. */
static void
query_faces(ipsr_work* w, const dacpo_mesh* m, size_t k)
{
  double d2[64];
  for (size_t f = 0; f < m->num_triangles; ++f) {
    const int32_t* t = m->triangles + 3 * f;
    const double* p0 = m->vertices + 3 * (size_t)t[0];
    const double* p1 = m->vertices + 3 * (size_t)t[1];
    const double* p2 = m->vertices + 3 * (size_t)t[2];
    double e1[3], e2[3], c[3];
    for (int a = 0; a < 3; ++a) {
      e1[a] = p1[a] - p0[a];
      e2[a] = p2[a] - p0[a];
      c[a] = (p0[a] + p1[a] + p2[a]) / 3.0;
    }
    double* nf = w->fnrm + 3 * f;
    nf[0] = e1[1] * e2[2] - e1[2] * e2[1];
    nf[1] = e1[2] * e2[0] - e1[0] * e2[2];
    nf[2] = e1[0] * e2[1] - e1[1] * e2[0];
    size_t got = dacpo_cell_knn_query(w->faces_knn, c, w->fknn + k * f, d2);
    for (size_t j = got; j < k; ++j)
      w->fknn[k * f + j] = -1;
    w->fdist2[f] = got ? d2[0] : HUGE_VAL;
  }
}

/* Copies the kept faces whose nearest sample is an own point into out,
 * compacting vertices and winding them to agree with the normals. */
static dacpo_status
build_output(ipsr_work* w,
             const dacpo_mesh* m,
             const double* nrm,
             size_t n_own,
             size_t k,
             dacpo_mesh* out,
             dacpo_err* err)
{
  const size_t nf = m->num_triangles, nv = m->num_vertices;
  size_t keep = 0;
  double agree = 0.0;
  for (size_t f = 0; f < nf; ++f) {
    int32_t s = w->fknn[k * f];
    if (w->removed[f] || s < 0 || (size_t)s >= n_own) {
      w->removed[f] = 1;
      continue;
    }
    ++keep;
    const double* a = w->fnrm + 3 * f;
    const double* b = nrm + 3 * (size_t)s;
    agree += a[0] * b[0] + a[1] * b[1] + a[2] * b[2] > 0.0 ? 1.0 : -1.0;
  }
  if (keep == 0)
    return DACPO_OK;
  /* vstart doubles as the old -> new vertex map */
  int32_t* map = w->vstart;
  for (size_t v = 0; v < nv; ++v)
    map[v] = -1;
  size_t nvo = 0;
  for (size_t f = 0; f < nf; ++f)
    if (!w->removed[f])
      for (int c = 0; c < 3; ++c) {
        int32_t v = m->triangles[3 * f + c];
        if (map[v] < 0)
          map[v] = (int32_t)nvo++;
      }
  out->vertices = (double*)dacpo_malloc_array(3 * nvo, sizeof(double));
  out->triangles = (int32_t*)dacpo_malloc_array(3 * keep, sizeof(int32_t));
  if (!out->vertices || !out->triangles) {
    dacpo_mesh_free(out);
    return DACPO_OOM(err);
  }
  for (size_t v = 0; v < nv; ++v)
    if (map[v] >= 0)
      memcpy(
          out->vertices + 3 * (size_t)map[v], m->vertices + 3 * v, 3 * sizeof(double));
  /* The mesh is wound along +grad chi, which follows the normals; flip only
   * if the final normals disagree with most faces. */
  const int flip = agree < 0.0;
  size_t t = 0;
  for (size_t f = 0; f < nf; ++f)
    if (!w->removed[f]) {
      const int32_t* tri = m->triangles + 3 * f;
      out->triangles[3 * t] = map[tri[0]];
      out->triangles[3 * t + 1] = map[tri[flip ? 2 : 1]];
      out->triangles[3 * t + 2] = map[tri[flip ? 1 : 2]];
      ++t;
    }
  out->num_vertices = nvo;
  out->num_triangles = keep;
  return DACPO_OK;
}

static dacpo_status
check_params(const dacpo_ipsr_params* p, dacpo_err* err)
{
  DACPO_CHECK(err,
              p->max_iterations <= 1000,
              DACPO_ERR_INVALID_ARGUMENT,
              "ipsr: max_iterations must be <= 1000 (got %zu)",
              p->max_iterations);
  DACPO_CHECK(err,
              isfinite(p->convergence) && p->convergence >= 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "ipsr: convergence must be >= 0 (got %g)",
              p->convergence);
  DACPO_CHECK(err,
              p->face_k >= 1 && p->face_k <= 64,
              DACPO_ERR_INVALID_ARGUMENT,
              "ipsr: face_k must be in [1, 64] (got %zu)",
              p->face_k);
  DACPO_CHECK(err,
              isfinite(p->trim_spacings) && p->trim_spacings > 0.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "ipsr: trim_spacings must be > 0 (got %g)",
              p->trim_spacings);
  return DACPO_OK;
}

/* The arguments dacpo_ipsr_block accepts. */
static dacpo_status
ipsr_check_args(const double* xyz,
                const double* nrm,
                size_t n,
                size_t n_own,
                const dacpo_ipsr_params* params,
                dacpo_err* err)
{
  DACPO_CHECK(err, params, DACPO_ERR_INVALID_ARGUMENT, "ipsr: params is NULL");
  DACPO_CHECK(err,
              n == 0 || (xyz && nrm),
              DACPO_ERR_INVALID_ARGUMENT,
              "ipsr: xyz or nrm is NULL");
  DACPO_CHECK(
      err, n_own <= n, DACPO_ERR_INVALID_ARGUMENT, "ipsr: n_own %zu > n %zu", n_own, n);
  DACPO_CHECK(err,
              n <= (size_t)INT32_MAX,
              DACPO_ERR_INVALID_ARGUMENT,
              "ipsr: %zu samples exceed int32 indices",
              n);
  DACPO_TRY(check_params(params, err));
  for (size_t i = 0; i < 3 * n; ++i)
    DACPO_CHECK(err,
                isfinite(xyz[i]) && isfinite(nrm[i]),
                DACPO_ERR_NONFINITE_INPUT,
                "ipsr: sample %zu has a non-finite coordinate or normal",
                i / 3);
  return DACPO_OK;
}

/* The block's Poisson system (paper §4.3: Neumann screened Poisson on the
 * block's box) and marching-cubes extractor; grid figures into st. */
static dacpo_status
ipsr_setup(ipsr_work* w,
           const double* xyz,
           size_t n,
           double spacing,
           const dacpo_ipsr_params* params,
           dacpo_ipsr_stats* st,
           dacpo_err* err)
{
  dacpo_poisson_params pp;
  dacpo_poisson_params_default(&pp);
  pp.cell_per_spacing = params->cell_per_spacing;
  pp.max_resolution = params->max_resolution;
  pp.point_weight = params->point_weight;
  if (params->padding > 0.0)
    pp.padding = params->padding;
  if (params->max_cells > 0)
    pp.max_cells = params->max_cells;
  if (params->tolerance > 0.0)
    pp.tolerance = params->tolerance;
  if (params->max_cg_iterations > 0)
    pp.max_cg_iterations = params->max_cg_iterations;
  pp.band = params->band;
  DACPO_TRY(dacpo_poisson_create(xyz, w->area, n, spacing, &pp, &w->ps, err));
  DACPO_TRY(dacpo_mcubes_create(&w->mc, err));
  const dacpo_grid* grid = dacpo_poisson_grid(w->ps);
  st->resolution = grid->dims[0];
  for (int a = 1; a < 3; ++a)
    if (grid->dims[a] > st->resolution)
      st->resolution = grid->dims[a];
  st->spacing = spacing;
  st->cell = grid->cell;
  for (int a = 0; a < 3; ++a)
    st->dims[a] = grid->dims[a];
  st->domain_cells = dacpo_poisson_domain_cells(w->ps);
  return DACPO_OK;
}

/* Whether normal m points away from the input normal n0 (the sign the
 * pipeline takes from stage 3). */
static int
faces_away(const double* n0, const double* m)
{
  return n0[0] * m[0] + n0[1] * m[1] + n0[2] * m[2] < 0.0;
}

/* Every kept face sends its area-weighted normal to its k nearest samples;
 * each sample's new normal is the normalized sum (one that received nothing,
 * or is fixed, keeps its normal). change[s] = |n_new - n_old|. Returns how
 * many samples turned over (against their input normals `start`). */
static size_t
ipsr_vote(ipsr_work* w,
          const dacpo_mesh* mesh,
          size_t k,
          const uint8_t* fixed,
          const double* start,
          double* nrm,
          double* old,
          size_t n)
{
  memset(w->acc, 0, 3 * n * sizeof(double));
  for (size_t f = 0; f < mesh->num_triangles; ++f) {
    if (w->removed[f])
      continue;
    const double* nf = w->fnrm + 3 * f;
    const int32_t* nb = w->fknn + k * f;
    for (size_t j = 0; j < k; ++j) {
      if (nb[j] < 0)
        break;
      double* acc = w->acc + 3 * (size_t)nb[j];
      acc[0] += nf[0];
      acc[1] += nf[1];
      acc[2] += nf[2];
    }
  }
  memcpy(old, nrm, 3 * n * sizeof(double));
  size_t turned = 0;
  for (size_t s = 0; s < n; ++s) {
    double* a = w->acc + 3 * s;
    double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (len > 0.0 && isfinite(len) && !(fixed && fixed[s])) {
      nrm[3 * s] = a[0] / len;
      nrm[3 * s + 1] = a[1] / len;
      nrm[3 * s + 2] = a[2] / len;
    }
    double dx = nrm[3 * s] - old[3 * s], dy = nrm[3 * s + 1] - old[3 * s + 1],
           dz = nrm[3 * s + 2] - old[3 * s + 2];
    w->change[s] = sqrt(dx * dx + dy * dy + dz * dz);
    turned += faces_away(start + 3 * s, nrm + 3 * s) !=
              faces_away(start + 3 * s, old + 3 * s);
  }
  return turned;
}

/* Sizes of one block's iterations, and their last surface. */
typedef struct ipsr_run {
  size_t n;     /* samples */
  size_t k;     /* nearest samples a face votes for */
  size_t top_m; /* changes averaged by the convergence test */
  double far2;  /* squared trimming distance */
  int want_mesh;
  const double* start;    /* the input normals: the signs are taken against them */
  const dacpo_mesh* mesh; /* the last surface (points into the extractor) */
  int mesh_trimmed;       /* its wings were trimmed */
  int same;               /* the last solve left chi as it was: same surface */
} ipsr_run;

/* One surface from the current normals: Poisson solve, iso-surface
 * (run->mesh), each face's nearest samples, and the wings trimmed if trimming
 * (else every face kept). A solve that takes no CG step (the new normals moved
 * the right-hand side by less than the tolerance) leaves chi, hence the
 * surface, as it was: with the same trimming its votes would give the current
 * normals again, so run->same is set and nothing is extracted. t[0..2]: the
 * clock before the solve, after it, after the extraction. */
static dacpo_status
ipsr_surface(ipsr_work* w,
             const double* nrm,
             int trimming,
             const dacpo_ipsr_params* params,
             ipsr_run* run,
             double* t,
             dacpo_ipsr_stats* st,
             dacpo_err* err)
{
  t[0] = dacpo_now();
  dacpo_poisson_info info;
  DACPO_TRY(dacpo_poisson_solve(w->ps, nrm, &info, err));
  st->cg_iterations += info.iterations;
  t[1] = t[2] = dacpo_now();
  run->same = run->mesh != NULL && info.iterations == 0 && run->mesh_trimmed == trimming;
  if (run->same)
    return DACPO_OK;
  DACPO_TRY(dacpo_mcubes_extract(w->mc,
                                 dacpo_poisson_grid(w->ps),
                                 dacpo_poisson_values(w->ps),
                                 dacpo_poisson_domain(w->ps),
                                 info.iso_value,
                                 &run->mesh,
                                 err));
  t[2] = dacpo_now();
  const dacpo_mesh* mesh = run->mesh;
  if (!ensure_faces(w, mesh->num_triangles, run->k) ||
      !ensure_vertices(w, mesh->num_vertices))
    return DACPO_OOM(err);
  query_faces(w, mesh, run->k);
  if (trimming)
    trim_faces(w, mesh, run->far2, params->experiment.trim_interior);
  else
    memset(w->removed, 0, mesh->num_triangles);
  return DACPO_OK;
}

/* Timings, face count and peak memory of iteration it (t: its four clock
 * readings: start, solved, extracted, voted). */
static void
ipsr_iteration_stats(const ipsr_work* w,
                     const dacpo_mesh* mesh,
                     size_t k,
                     size_t it,
                     const double* t,
                     dacpo_ipsr_stats* st)
{
  st->solve_seconds += t[1] - t[0];
  st->extract_seconds += t[2] - t[1];
  st->vote_seconds += t[3] - t[2];
  st->iterations = it + 1;
  st->faces = mesh->num_triangles;
  size_t b = work_bytes(w, k);
  if (b > st->peak_bytes)
    st->peak_bytes = b;
}

/* The iterations: surface, vote, convergence test. With max_iterations == 0
 * the body still runs once without updating the normals, to give the mesh
 * (if wanted). old: 3n scratch. */
static dacpo_status
ipsr_iterate(ipsr_work* w,
             ipsr_run* run,
             const dacpo_ipsr_params* params,
             double* nrm,
             double* old,
             dacpo_ipsr_stats* st,
             dacpo_err* err)
{
  const size_t n = run->n, k = run->k;
  int trimming = 0;
  const size_t iters = params->max_iterations;
  for (size_t it = 0; it < (iters ? iters : (run->want_mesh ? 1u : 0u)); ++it) {
    if (it >= params->trim_start)
      trimming = 1;
    double t[4];
    DACPO_TRY(ipsr_surface(w, nrm, trimming, params, run, t, st, err));
    run->mesh_trimmed = trimming;
    if (iters == 0)
      break;
    size_t turned = 0;
    if (run->same) {
      memset(w->change, 0, n * sizeof(double)); /* the vote would repeat nrm */
      st->surfaces_reused++;
    }
    else {
      turned = ipsr_vote(w, run->mesh, k, params->fixed, run->start, nrm, old, n);
      st->faces_total += run->mesh->num_triangles;
    }
    t[3] = dacpo_now();
    ipsr_iteration_stats(w, run->mesh, k, it, t, st);
    double metric = mean_of_largest(w->change, n, run->top_m, w->heap);
    st->final_change = metric;
    if (metric < params->convergence ||
        (it >= params->settle_start && turned <= run->top_m)) {
      st->converged = 1;
      break;
    }
  }
  return DACPO_OK;
}

/* The per-sample arrays of the work, and old (the previous normals) and orig
 * (the input normals); returns 0 if one is missing (all freed by the caller). */
static int
ipsr_alloc(ipsr_work* w, size_t n, size_t top_m, double** old, double** orig)
{
  w->area = (double*)dacpo_malloc_array(n, sizeof(double));
  w->acc = (double*)dacpo_malloc_array(3 * n, sizeof(double));
  w->change = (double*)dacpo_malloc_array(n, sizeof(double));
  w->heap = (double*)dacpo_malloc_array(top_m, sizeof(double));
  *old = (double*)dacpo_malloc_array(3 * n, sizeof(double));
  *orig = (double*)dacpo_malloc_array(3 * n, sizeof(double));
  return w->area && w->acc && w->change && w->heap && *old && *orig;
}

/* Peak memory at the end, the output mesh included. */
static void
ipsr_final_peak(const ipsr_work* w,
                size_t k,
                const dacpo_mesh* mesh_out,
                dacpo_ipsr_stats* st)
{
  size_t b = work_bytes(w, k);
  if (mesh_out)
    b += mesh_out->num_vertices * 3 * sizeof(double) +
         mesh_out->num_triangles * 3 * sizeof(int32_t);
  if (b > st->peak_bytes)
    st->peak_bytes = b;
}

dacpo_status
dacpo_ipsr_block(const double* xyz,
                 double* nrm,
                 size_t n,
                 size_t n_own,
                 const dacpo_ipsr_params* params,
                 dacpo_mesh* mesh_out,
                 dacpo_ipsr_stats* stats,
                 dacpo_err* err)
{
  const double t_start = dacpo_now();
  dacpo_ipsr_stats st_local;
  dacpo_ipsr_stats* st = stats ? stats : &st_local;
  memset(st, 0, sizeof(*st));
  if (mesh_out)
    memset(mesh_out, 0, sizeof(*mesh_out));
  DACPO_TRY(ipsr_check_args(xyz, nrm, n, n_own, params, err));
  /* A block this small has no surface to speak of: leave it alone. */
  if (n < 4)
    return DACPO_OK;

  ipsr_run run;
  memset(&run, 0, sizeof(run));
  run.n = n;
  run.k = params->face_k < n ? params->face_k : n;
  const size_t top_m0 = (n + 999) / 1000;
  run.top_m = top_m0 > 10 ? top_m0 : 10;
  run.want_mesh = mesh_out != NULL;
  ipsr_work w;
  memset(&w, 0, sizeof(w));
  dacpo_status status = DACPO_OK;
  double* old = NULL;
  double* orig = NULL; /* the input normals, restored on error */
  int saved = 0;

  if (!ipsr_alloc(&w, n, run.top_m, &old, &orig)) {
    status = DACPO_OOM(err);
    goto done;
  }
  memcpy(orig, nrm, 3 * n * sizeof(double));
  run.start = orig;
  saved = 1;
  w.bytes = n * (11 * sizeof(double)) + run.top_m * sizeof(double);
  if ((status = dacpo_kdtree_build(xyz, n, &w.tree, err)) != DACPO_OK)
    goto done;
  double spacing = 0.0;
  if ((status = estimate_spacing(&w, xyz, n, &spacing, err)) != DACPO_OK)
    goto done;

  if ((status = ipsr_setup(&w, xyz, n, spacing, params, st, err)) != DACPO_OK)
    goto done;
  status = dacpo_cell_knn_create(
      w.tree, xyz, n, dacpo_poisson_grid(w.ps), run.k, &w.faces_knn, err);
  if (status != DACPO_OK)
    goto done;
  const double far = params->trim_spacings * spacing;
  run.far2 = far * far;
  if ((status = ipsr_iterate(&w, &run, params, nrm, old, st, err)) != DACPO_OK)
    goto done;
  if (mesh_out && run.mesh && run.mesh->num_triangles > 0) {
    if (!run.mesh_trimmed)
      trim_faces(&w, run.mesh, run.far2, params->experiment.trim_interior);
    status = build_output(&w, run.mesh, nrm, n_own, run.k, mesh_out, err);
    if (status != DACPO_OK)
      goto done;
  }
  ipsr_final_peak(&w, run.k, mesh_out, st);
done:
  if (status != DACPO_OK) {
    if (saved)
      memcpy(nrm, orig, 3 * n * sizeof(double));
    if (mesh_out)
      dacpo_mesh_free(mesh_out);
  }
  ipsr_clear(&w);
  free(old);
  free(orig);
  st->seconds = dacpo_now() - t_start;
  return status;
}

