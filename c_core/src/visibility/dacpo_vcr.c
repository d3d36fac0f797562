/* SPDX-License-Identifier: BSD-3-Clause */
/* Stage 4b: visible connected regions (VCR) between two adjacent blocks
 * (paper §5.1 "Visible Connected Regions" and "Orientation Consistency
 * Evaluation", Eq. 6-7).
 *
 * In:  the trimmed meshes a and b of two adjacent blocks (face normal
 *      (v1-v0)x(v2-v0) agrees with the block's oriented normals), parameters.
 * Out: alpha  = sum over views j and sub-regions k of I(V_k^{S_j}) (Eq. 6) with
 *               both meshes as given;
 *      alpha_bar = the same with mesh b's facing inverted.
 *
 * Per view (12 directions = dodecahedron face centres around the centre of the
 * pair's bounding box):
 *  1. project every used vertex (orthographic, or a pinhole camera at distance
 *     2R from the centre) and fit the projection into image_size^2 square pixels;
 *  2. rasterize all triangles of both meshes once into one z-buffer (exact
 *     coverage, interpolated depth; dacpo_raster.c). Orthographic views come
 *     in opposite pairs (d, -d) that cover the same pixels: one pass keeps
 *     the nearest and the farthest triangle of every pixel, and view -d is
 *     the far image, mirrored (no pass below can tell a mirror image);
 *  3. eta = largest depth span max D(v) - min D(v) of a triangle that owns at
 *     least one pixel (params->experiment.eta_all: of every triangle, the paper's
 * formula); optional removal of partly visible triangles; seam closing: empty pixels
 *     within r = max(gap_fill, gap_fill_edges * median edge) pixels of drawn ones
 *     copy the nearest (two block meshes cut face by face meet with seams about
 *     one face wide, which would otherwise cut every VCR at the block boundary);
 *  4. one union-find pass over 4-neighbour pixel pairs joins pixels of the SAME
 *     mesh with |depth difference| <= eta (+ a float tolerance) and equal facing
 *     into "atoms". Facing within one mesh does not change when b is inverted,
 *     so atoms serve both labellings; a depth-continuous pair across the two
 *     meshes joins its atoms as given if the facings agree, and with b inverted
 *     if they differ. Each labelling's components of atoms are the view-aligned
 *     sub-regions of the VCRs (the VCR split by facing) in one pass;
 *  5. per sub-region C1, C2 = pixels of a, b; C_B = boundary pixels: pixels with
 *     a 4-neighbour of the other mesh in the SAME sub-region (depth-continuous
 *     and of equal facing under that labelling); I = C_B*C1*C2 (or C1*C2).
 * Counts are scaled (C1, C2 by 1/image_size^2, C_B by 1/image_size) so alpha does
 * not depend on the image size; omega (Eq. 7) is scale-free anyway.
 *
 * Cost: O(V + T) per rasterization (one per pair of opposite views) and
 * O(image area) per view; the rasterization's per-triangle setup dominates
 * (stage-3 triangles are a few pixels wide). Scratch (~58 bytes per pixel) is
 * allocated per call; no global state, so edges can run on several threads at
 * once.
 * Failures: bad parameters, out-of-range indices or non-finite vertices
 * (DACPO_ERR_INVALID_ARGUMENT), allocation (DACPO_ERR_OUT_OF_MEMORY). Empty
 * meshes or degenerate geometry give alpha = alpha_bar = 0 and DACPO_OK. */
#include "dacpo_vcr.h"

#include "dacpo_raster.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define VCR_MAX_IMAGE 4096
#define VCR_MAX_VIEWS 10000

/* per-pixel flags of pass 4 */
#define PF_SAME 1u      /* has a depth-continuous cross neighbour, equal facing */
#define PF_DIFF 2u      /* ... with different facing */
#define PF_LEFT_X 4u    /* cross pair with the left neighbour */
#define PF_LEFT_SAME 8u /* ... and its facing agrees */
#define PF_UP_X 16u
#define PF_UP_SAME 32u

/* cls value of a pixel waiting in the seam-closing front (above every round
 * stamp: rounds are at most 32 + 1) */
#define QUEUED 255u

void
dacpo_vcr_params_default(dacpo_vcr_params* p)
{
  if (p == NULL)
    return;
  memset(p, 0, sizeof(*p));
  p->image_size = 400;
  p->num_views = 12;
  p->perspective = 0;
  p->boundary_factor = 1;
  p->gap_fill = 2;
  p->gap_fill_edges = 0.75;
}

void
dacpo_vcr_view_directions(size_t num_views, double* dirs)
{
  if (dirs == NULL)
    return;
  if (num_views <= 12) {
    /* Icosahedron vertices (0, ±1, ±phi) and cyclic permutations; one of each
     * antipodal pair first, so that 6 views still cover 6 distinct axes. */
    const double phi = (1.0 + sqrt(5.0)) / 2.0;
    const double half[6][3] = {{0, 1, phi},
                               {0, -1, phi},
                               {1, phi, 0},
                               {-1, phi, 0},
                               {phi, 0, 1},
                               {phi, 0, -1}};
    double norm = sqrt(1.0 + phi * phi);
    for (size_t i = 0; i < num_views; ++i) {
      double sign = i < 6 ? 1.0 : -1.0;
      for (int k = 0; k < 3; ++k)
        dirs[3 * i + (size_t)k] = sign * half[i % 6][k] / norm;
    }
    return;
  }
  const double golden = 3.14159265358979323846 * (3.0 - sqrt(5.0));
  for (size_t i = 0; i < num_views; ++i) {
    double z = 1.0 - (2.0 * (double)i + 1.0) / (double)num_views;
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    double ang = golden * (double)i;
    dirs[3 * i + 0] = r * cos(ang);
    dirs[3 * i + 1] = r * sin(ang);
    dirs[3 * i + 2] = z;
  }
}

typedef struct vcr_work {
  size_t N;        /* image side */
  size_t na_t, nt; /* triangles of a, of a + b */
  size_t na_v, nv; /* vertices of a, of a + b */
  double edge_len; /* median triangle edge length (sampled) */
  const dacpo_mesh* m[2];
  dacpo_raster r;
  double* tri_normal; /* 3 * nt: (v1-v0)x(v2-v0) */
  double* tri_centre; /* 3 * nt (perspective facing) */
  uint8_t* used;      /* nv: vertex referenced by a triangle */
  double* scr;        /* 3 * nv: pixel x, y, screen-linear z */
  double* vdepth;     /* nv: depth along the view direction */
  uint8_t* back;      /* nt: 1 if the face normal points away from the camera */
  int32_t* covered;   /* nt: pixel centres covered (experiment.drop_partial) */
  int32_t* owned;     /* nt: pixels won */
  int32_t* parent;    /* N^2: pixel union-find */
  uint8_t* cls;       /* N^2: 0 empty, else 1 + 2 * mesh + back */
  int32_t* atom;      /* N^2: compact atom id */
  uint8_t* flags;     /* N^2 */
  size_t drawn[4];    /* x0, y0, x1, y1 of the pixels drawn in this view */
  /* per atom (at most N^2) */
  uint8_t* a_blk;
  int32_t* a_cnt;
  int32_t* a_cbs;
  int32_t* a_cbd;
  int32_t* a_par[2];
  int32_t* acc_c1;
  int32_t* acc_c2;
  int32_t* acc_cb;
} vcr_work;

static void
work_free(vcr_work* w)
{
  dacpo_raster_free(&w->r);
  free(w->tri_normal);
  free(w->tri_centre);
  free(w->used);
  free(w->scr);
  free(w->vdepth);
  free(w->back);
  free(w->covered);
  free(w->owned);
  free(w->parent);
  free(w->cls);
  free(w->atom);
  free(w->flags);
  free(w->a_blk);
  free(w->a_cnt);
  free(w->a_cbs);
  free(w->a_cbd);
  free(w->a_par[0]);
  free(w->a_par[1]);
  free(w->acc_c1);
  free(w->acc_c2);
  free(w->acc_cb);
  memset(w, 0, sizeof(*w));
}

static const double*
vertex_of(const vcr_work* w, size_t gv)
{
  return gv < w->na_v ? &w->m[0]->vertices[3 * gv]
                      : &w->m[1]->vertices[3 * (gv - w->na_v)];
}

/* Global vertex index of corner k of global triangle t. */
static size_t
corner(const vcr_work* w, size_t t, int k)
{
  if (t < w->na_t)
    return (size_t)w->m[0]->triangles[3 * t + (size_t)k];
  return w->na_v + (size_t)w->m[1]->triangles[3 * (t - w->na_t) + (size_t)k];
}

static dacpo_status
check_mesh(const dacpo_mesh* m, const char* name, dacpo_err* err)
{
  DACPO_CHECK(err, m != NULL, DACPO_ERR_INVALID_ARGUMENT, "vcr: mesh %s is NULL", name);
  if (m->num_triangles == 0)
    return DACPO_OK;
  DACPO_CHECK(err,
              m->triangles != NULL && m->vertices != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "vcr: mesh %s has %zu triangles but NULL arrays",
              name,
              m->num_triangles);
  DACPO_CHECK(err,
              m->num_vertices < (size_t)INT32_MAX &&
                  m->num_triangles < (size_t)INT32_MAX / 2,
              DACPO_ERR_INVALID_ARGUMENT,
              "vcr: mesh %s too large (%zu vertices, %zu triangles)",
              name,
              m->num_vertices,
              m->num_triangles);
  for (size_t i = 0; i < 3 * m->num_triangles; ++i) {
    int32_t v = m->triangles[i];
    DACPO_CHECK(err,
                v >= 0 && (size_t)v < m->num_vertices,
                DACPO_ERR_INVALID_ARGUMENT,
                "vcr: mesh %s triangle %zu refers to vertex %d (mesh has %zu)",
                name,
                i / 3,
                (int)v,
                m->num_vertices);
    const double* p = &m->vertices[3 * (size_t)v];
    DACPO_CHECK(err,
                isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]),
                DACPO_ERR_INVALID_ARGUMENT,
                "vcr: mesh %s vertex %d is not finite",
                name,
                (int)v);
  }
  return DACPO_OK;
}

static dacpo_status
work_alloc(vcr_work* w, dacpo_err* err)
{
  size_t npix = w->N * w->N;
  DACPO_TRY(dacpo_raster_init(&w->r, w->N, w->N, err));
  w->tri_normal = (double*)dacpo_malloc_array(3 * w->nt, sizeof(double));
  w->tri_centre = (double*)dacpo_malloc_array(3 * w->nt, sizeof(double));
  w->used = (uint8_t*)dacpo_calloc_array(w->nv, 1);
  w->scr = (double*)dacpo_malloc_array(3 * w->nv, sizeof(double));
  w->vdepth = (double*)dacpo_malloc_array(w->nv, sizeof(double));
  w->back = (uint8_t*)dacpo_malloc_array(w->nt, 1);
  w->covered = (int32_t*)dacpo_malloc_array(w->nt, sizeof(int32_t));
  w->owned = (int32_t*)dacpo_malloc_array(w->nt, sizeof(int32_t));
  w->parent = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->atom = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->cls = (uint8_t*)dacpo_malloc_array(npix, 1);
  w->flags = (uint8_t*)dacpo_calloc_array(npix, 1);
  w->a_blk = (uint8_t*)dacpo_malloc_array(npix, 1);
  w->a_cnt = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->a_cbs = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->a_cbd = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->a_par[0] = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->a_par[1] = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->acc_c1 = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->acc_c2 = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  w->acc_cb = (int32_t*)dacpo_malloc_array(npix, sizeof(int32_t));
  if (!w->tri_normal || !w->tri_centre || !w->used || !w->scr || !w->vdepth ||
      !w->back || !w->covered || !w->owned || !w->parent || !w->cls || !w->atom ||
      !w->flags || !w->a_blk || !w->a_cnt || !w->a_cbs || !w->a_cbd || !w->a_par[0] ||
      !w->a_par[1] || !w->acc_c1 || !w->acc_c2 || !w->acc_cb)
    return DACPO_OOM(err);
  return DACPO_OK;
}

typedef struct view_result {
  double alpha, alpha_bar, eta;
  size_t gap;
  size_t pix[2], cross_same, cross_diff, regions[2];
} view_result;

/* Median edge length over an even sample of at most 341 triangles (1023 edges):
 * the scale of a face, hence of the seams between two meshes cut face by face. */
static double
median_edge_length(const vcr_work* w)
{
  double len[1023];
  size_t stride = w->nt / 341 + 1, n = 0;
  for (size_t t = 0; t < w->nt && n + 3 <= 1023; t += stride)
    for (int k = 0; k < 3; ++k) {
      const double* p = vertex_of(w, corner(w, t, k));
      const double* q = vertex_of(w, corner(w, t, (k + 1) % 3));
      double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
      len[n++] = sqrt(dx * dx + dy * dy + dz * dz);
    }
  if (n == 0)
    return 0.0;
  qsort(len, n, sizeof(double), dacpo_cmp_double);
  return len[n / 2];
}

static void
orthonormal_basis(const double d[3], double u[3], double v[3])
{
  /* helper axis: the one least aligned with d */
  double h[3] = {0, 0, 0};
  double ax = fabs(d[0]), ay = fabs(d[1]), az = fabs(d[2]);
  if (ax <= ay && ax <= az)
    h[0] = 1;
  else if (ay <= az)
    h[1] = 1;
  else
    h[2] = 1;
  u[0] = d[1] * h[2] - d[2] * h[1];
  u[1] = d[2] * h[0] - d[0] * h[2];
  u[2] = d[0] * h[1] - d[1] * h[0];
  double n = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  u[0] /= n;
  u[1] /= n;
  u[2] /= n;
  v[0] = d[1] * u[2] - d[2] * u[1];
  v[1] = d[2] * u[0] - d[0] * u[2];
  v[2] = d[0] * u[1] - d[1] * u[0];
}

/* The camera of one view: looks along d; perspective from eye. */
typedef struct view_camera {
  const double* d;
  double u[3], v[3], eye[3];
  double dist;
  int persp;
} view_camera;

/* Step 1: project the used vertices, fit the image to their 2D box and choose
 * the seam-closing radius. Returns 0 when the projection is degenerate. */
static int
view_project(vcr_work* w,
             const dacpo_vcr_params* prm,
             const double centre[3],
             double radius,
             const view_camera* cam,
             size_t* gap_out)
{
  const size_t N = w->N;
  const int persp = cam->persp;
  const double *u = cam->u, *v = cam->v, *d = cam->d;
  const double dist = cam->dist;
  const double* origin = persp ? cam->eye : centre;
  /* 1. project the used vertices and fit their 2D bounding box */
  double minx = INFINITY, maxx = -INFINITY, miny = INFINITY, maxy = -INFINITY;
  for (size_t i = 0; i < w->nv; ++i) {
    if (!w->used[i])
      continue;
    const double* p = vertex_of(w, i);
    double r[3] = {p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
    double x = r[0] * u[0] + r[1] * u[1] + r[2] * u[2];
    double y = r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
    double z = r[0] * d[0] + r[1] * d[1] + r[2] * d[2];
    if (persp) {
      /* z >= dist - radius = radius > 0: every vertex is in front of the camera */
      x /= z;
      y /= z;
    }
    w->scr[3 * i + 0] = x;
    w->scr[3 * i + 1] = y;
    w->scr[3 * i + 2] = z;
    w->vdepth[i] = z;
    minx = x < minx ? x : minx;
    maxx = x > maxx ? x : maxx;
    miny = y < miny ? y : miny;
    maxy = y > maxy ? y : maxy;
  }
  double ext = fmax(maxx - minx, maxy - miny);
  double rel = persp ? ext : ext / radius; /* perspective coords are already angles */
  if (!(rel > 1e-9) || !isfinite(ext))
    return 0;
  double margin = 1.0 + (double)prm->gap_fill;
  double scale = ((double)N - 2.0 * margin) / ext;
  /* seam closing radius: gap_fill pixels, or gap_fill_edges median edges */
  size_t gap = prm->gap_fill;
  if (prm->gap_fill_edges > 0.0) {
    double px_per_unit = persp ? scale / dist : scale; /* at the centre's depth */
    double want = ceil(prm->gap_fill_edges * w->edge_len * px_per_unit);
    if (want > (double)DACPO_VCR_GAP_MAX)
      want = (double)DACPO_VCR_GAP_MAX;
    if (want > (double)gap)
      gap = (size_t)want;
  }
  *gap_out = gap;
  double cx = 0.5 * (minx + maxx), cy = 0.5 * (miny + maxy);
  for (size_t i = 0; i < w->nv; ++i) {
    if (!w->used[i])
      continue;
    w->scr[3 * i + 0] = 0.5 * (double)N + (w->scr[3 * i + 0] - cx) * scale;
    w->scr[3 * i + 1] = 0.5 * (double)N + (w->scr[3 * i + 1] - cy) * scale;
    /* 1/depth is linear in screen space under a pinhole projection */
    if (persp)
      w->scr[3 * i + 2] = -1.0 / w->scr[3 * i + 2];
  }

  return 1;
}

/* cls (1 = drawn, 0 = empty: for the seam closing, pass 4 overwrites it) and
 * the pixels each triangle won; perspective depths back from -1/depth. */
static void
view_owned(vcr_work* w, int persp)
{
  const size_t N = w->N;
  dacpo_raster* R = &w->r;
  memset(w->owned, 0, w->nt * sizeof(int32_t));
  uint8_t* cls = w->cls;
  for (size_t y = R->y0; y <= R->y1; ++y)
    for (size_t x = R->x0; x <= R->x1; ++x) {
      size_t p = y * N + x;
      int32_t t = R->owner[p];
      cls[p] = t >= 0 ? 1 : 0;
      if (t >= 0) {
        w->owned[t]++;
        if (persp)
          R->depth[p] = (float)(-1.0 / (double)R->depth[p]);
      }
    }
}

/* Step 2: facing of every triangle and z-buffer rasterization (a first, then
 * b: exact depth ties keep a). Returns 0 when nothing was drawn. */
static int
view_rasterize(vcr_work* w, const view_camera* cam)
{
  const int persp = cam->persp;
  const double *d = cam->d, *eye = cam->eye;
  /* 2. facing and rasterization (a first, then b: exact depth ties keep a) */
  for (size_t t = 0; t < w->nt; ++t) {
    const double* n = &w->tri_normal[3 * t];
    double s;
    if (persp) {
      const double* c = &w->tri_centre[3 * t];
      s = (c[0] - eye[0]) * n[0] + (c[1] - eye[1]) * n[1] + (c[2] - eye[2]) * n[2];
    }
    else
      s = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
    w->back[t] = s > 0.0 ? 1 : 0;
    size_t i0 = corner(w, t, 0), i1 = corner(w, t, 1), i2 = corner(w, t, 2);
    w->covered[t] = (int32_t)dacpo_raster_triangle(
        &w->r, &w->scr[3 * i0], &w->scr[3 * i1], &w->scr[3 * i2], (int32_t)t);
  }
  dacpo_raster* R = &w->r;
  if (R->x0 > R->x1)
    return 0;
  w->drawn[0] = R->x0, w->drawn[1] = R->y0, w->drawn[2] = R->x1, w->drawn[3] = R->y1;
  view_owned(w, persp);
  return 1;
}

/* Step 3: eta, the largest depth span of the retained triangles (optionally
 * removing the pixels of partly visible ones first). */
static double
view_eta(vcr_work* w, const dacpo_vcr_params* prm)
{
  const size_t N = w->N;
  dacpo_raster* R = &w->r;
  uint8_t* cls = w->cls;
  /* 3. eta over the retained triangles; optional removal of partly visible ones */
  double eta = 0.0;
  for (size_t t = 0; t < w->nt; ++t) {
    int retained = w->owned[t] > 0;
    if (prm->experiment.drop_partial)
      retained = retained && w->owned[t] == w->covered[t];
    if (!retained && !prm->experiment.eta_all)
      continue;
    double z0 = w->vdepth[corner(w, t, 0)], z1 = w->vdepth[corner(w, t, 1)],
           z2 = w->vdepth[corner(w, t, 2)];
    double hi = z0 > z1 ? z0 : z1, lo = z0 < z1 ? z0 : z1;
    hi = z2 > hi ? z2 : hi;
    lo = z2 < lo ? z2 : lo;
    double span = hi - lo;
    eta = span > eta ? span : eta;
  }
  if (prm->experiment.drop_partial) {
    for (size_t y = R->y0; y <= R->y1; ++y)
      for (size_t x = R->x0; x <= R->x1; ++x) {
        size_t p = y * N + x;
        int32_t t = R->owner[p];
        if (t >= 0 && w->owned[t] != w->covered[t]) {
          R->owner[p] = -1;
          R->depth[p] = INFINITY;
          cls[p] = 0;
        }
      }
  }
  return eta;
}

/* Widens the rectangle by gap pixels (clipped to the image); the new border
 * strips are empty. dacpo_raster_clear then resets the filled pixels too. */
static void
seam_widen_rect(vcr_work* w, size_t g)
{
  dacpo_raster* R = &w->r;
  const size_t N = w->N;
  size_t x0 = R->x0 >= g ? R->x0 - g : 0;
  size_t y0 = R->y0 >= g ? R->y0 - g : 0;
  size_t x1 = R->x1 + g < N ? R->x1 + g : N - 1;
  size_t y1 = R->y1 + g < N ? R->y1 + g : N - 1;
  for (size_t y = y0; y <= y1; ++y)
    for (size_t x = x0; x <= x1; ++x)
      if (y < R->y0 || y > R->y1 || x < R->x0 || x > R->x1)
        w->cls[y * N + x] = 0;
  R->x0 = x0;
  R->y0 = y0;
  R->x1 = x1;
  R->y1 = y1;
}

/* The first front: empty pixels next to a drawn one, queued into cur. Returns
 * their number. */
static size_t
seam_first_front(vcr_work* w, int32_t* cur)
{
  const dacpo_raster* R = &w->r;
  uint8_t* cls = w->cls;
  const size_t N = w->N;
  const size_t x0 = R->x0, x1 = R->x1, y0 = R->y0, y1 = R->y1;
  size_t ncur = 0;
  for (size_t y = y0; y <= y1; ++y)
    for (size_t x = x0; x <= x1; ++x) {
      size_t p = y * N + x;
      if (cls[p] == 0 && ((x > x0 && cls[p - 1] == 1) || (x < x1 && cls[p + 1] == 1) ||
                          (y > y0 && cls[p - N] == 1) || (y < y1 && cls[p + N] == 1))) {
        cls[p] = QUEUED;
        cur[ncur++] = (int32_t)p;
      }
    }
  return ncur;
}

/* Every front pixel copies the nearest of its sources (drawn or filled in an
 * earlier round than stamp), then is marked filled in this round. */
static void
seam_fill_front(vcr_work* w, const int32_t* cur, size_t ncur, uint8_t stamp)
{
  dacpo_raster* R = &w->r;
  uint8_t* cls = w->cls;
  const size_t N = w->N;
  const size_t x0 = R->x0, x1 = R->x1, y0 = R->y0, y1 = R->y1;
  for (size_t i = 0; i < ncur; ++i) {
    size_t p = (size_t)cur[i], x = p % N, y = p / N;
    size_t nb[4];
    int nn = 0;
    if (x > x0 && cls[p - 1] != 0 && cls[p - 1] < stamp)
      nb[nn++] = p - 1;
    if (x < x1 && cls[p + 1] != 0 && cls[p + 1] < stamp)
      nb[nn++] = p + 1;
    if (y > y0 && cls[p - N] != 0 && cls[p - N] < stamp)
      nb[nn++] = p - N;
    if (y < y1 && cls[p + N] != 0 && cls[p + N] < stamp)
      nb[nn++] = p + N;
    size_t best = nb[0]; /* nn >= 1: p was queued next to a source */
    for (int k = 1; k < nn; ++k)
      if (R->depth[nb[k]] < R->depth[best])
        best = nb[k];
    R->owner[p] = R->owner[best];
    R->depth[p] = R->depth[best];
  }
  for (size_t i = 0; i < ncur; ++i)
    cls[cur[i]] = stamp;
}

/* The next front: the empty neighbours of the current one, queued into next.
 * Returns their number. */
static size_t
seam_next_front(vcr_work* w, const int32_t* cur, size_t ncur, int32_t* next)
{
  const dacpo_raster* R = &w->r;
  uint8_t* cls = w->cls;
  const size_t N = w->N;
  const size_t x0 = R->x0, x1 = R->x1, y0 = R->y0, y1 = R->y1;
  size_t nnext = 0;
  for (size_t i = 0; i < ncur; ++i) {
    size_t p = (size_t)cur[i], x = p % N, y = p / N;
    size_t nb[4];
    int nn = 0;
    if (x > x0)
      nb[nn++] = p - 1;
    if (x < x1)
      nb[nn++] = p + 1;
    if (y > y0)
      nb[nn++] = p - N;
    if (y < y1)
      nb[nn++] = p + N;
    for (int k = 0; k < nn; ++k)
      if (cls[nb[k]] == 0) {
        cls[nb[k]] = QUEUED;
        next[nnext++] = (int32_t)nb[k];
      }
  }
  return nnext;
}

/* Seam closing: each round, empty pixels next to drawn ones copy the nearest
 * of them. cls marks drawn pixels (1) and the round + 1 a pixel was filled
 * in; pixels outside the rectangle are empty and their cls is stale. */
static void
view_close_seams(vcr_work* w, size_t gap)
{
  if (gap == 0)
    return;
  seam_widen_rect(w, gap);
  /* breadth-first by rounds: only the pixels of the growing front are
   * visited (cls QUEUED while waiting in a list) */
  int32_t* cur = w->atom; /* both free until pass 4 */
  int32_t* next = w->a_par[0];
  size_t ncur = seam_first_front(w, cur);
  for (size_t round = 1; round <= gap && ncur > 0; ++round) {
    seam_fill_front(w, cur, ncur, (uint8_t)(round + 1));
    size_t nnext = round < gap ? seam_next_front(w, cur, ncur, next) : 0;
    int32_t* t = cur;
    cur = next;
    next = t;
    ncur = nnext;
  }
}

/* Step 4: atoms - pixels of the same mesh, depth-continuous (within thr), of
 * the same facing - and the cross pairs between the two meshes. */
static void
view_atoms(vcr_work* w, double thr, view_result* res)
{
  const size_t N = w->N;
  dacpo_raster* R = &w->r;
  uint8_t* cls = w->cls;
  const size_t x0 = R->x0, x1 = R->x1, y0 = R->y0, y1 = R->y1;
  /* 4. atoms: same mesh, depth-continuous, same facing; mark cross pairs.
   * cls = 0 empty, else 1 + 2 * mesh + back (one byte read per neighbour). */
  const int32_t nat = (int32_t)w->na_t;
  int32_t* parent = w->parent;
  const float* depth = R->depth;
  for (size_t y = y0; y <= y1; ++y)
    for (size_t x = x0; x <= x1; ++x) {
      size_t p = y * N + x;
      int32_t tp = R->owner[p];
      if (tp < 0) {
        cls[p] = 0;
        continue;
      }
      uint8_t cp = (uint8_t)(1 + 2 * (tp >= nat) + w->back[tp]);
      cls[p] = cp;
      res->pix[tp >= nat]++;
      parent[p] = (int32_t)p;
      double dp = (double)depth[p];
      /* left neighbour: p is still a singleton, so joining it is one store */
      if (x > x0 && cls[p - 1] != 0 && fabs(dp - (double)depth[p - 1]) <= thr) {
        uint8_t cq = cls[p - 1];
        if (cq == cp)
          parent[p] = parent[p - 1];
        else if (((cq - 1) >> 1) != ((cp - 1) >> 1)) {
          int same_face = ((cq - 1) & 1) == ((cp - 1) & 1);
          uint8_t side = same_face ? PF_SAME : PF_DIFF;
          w->flags[p] |= (uint8_t)(side | PF_LEFT_X | (same_face ? PF_LEFT_SAME : 0));
          w->flags[p - 1] |= side;
          res->cross_same += (size_t)same_face;
          res->cross_diff += (size_t)!same_face;
        }
      }
      if (y > y0 && cls[p - N] != 0 && fabs(dp - (double)depth[p - N]) <= thr) {
        uint8_t cq = cls[p - N];
        if (cq == cp) {
          if (parent[p] != parent[p - N]) /* cheap test first: usually one root */
            dacpo_uf_union(parent, (int32_t)p, (int32_t)(p - N));
        }
        else if (((cq - 1) >> 1) != ((cp - 1) >> 1)) {
          int same_face = ((cq - 1) & 1) == ((cp - 1) & 1);
          uint8_t side = same_face ? PF_SAME : PF_DIFF;
          w->flags[p] |= (uint8_t)(side | PF_UP_X | (same_face ? PF_UP_SAME : 0));
          w->flags[p - N] |= side;
          res->cross_same += (size_t)same_face;
          res->cross_diff += (size_t)!same_face;
        }
      }
    }
}

/* Compact atom ids (roots precede their members in scan order), atom sums and
 * the cross-pair unions of both labellings. Returns the number of atoms. */
static int32_t
view_compact_atoms(vcr_work* w, uint8_t* image)
{
  const size_t N = w->N;
  dacpo_raster* R = &w->r;
  uint8_t* cls = w->cls;
  int32_t* parent = w->parent;
  const size_t x0 = R->x0, x1 = R->x1, y0 = R->y0, y1 = R->y1;
  int32_t K = 0;
  for (size_t y = y0; y <= y1; ++y)
    for (size_t x = x0; x <= x1; ++x) {
      size_t p = y * N + x;
      uint8_t cp = cls[p];
      if (cp == 0)
        continue;
      int32_t root = dacpo_uf_find(parent, (int32_t)p);
      int32_t id;
      if (root == (int32_t)p) {
        id = K++;
        w->a_blk[id] = (uint8_t)((cp - 1) >> 1);
        w->a_cnt[id] = 0;
        w->a_cbs[id] = 0;
        w->a_cbd[id] = 0;
        w->a_par[0][id] = id;
        w->a_par[1][id] = id;
      }
      else
        id = w->atom[root];
      w->atom[p] = id;
      uint8_t f = w->flags[p];
      w->a_cnt[id]++;
      w->a_cbs[id] += (f & PF_SAME) ? 1 : 0;
      w->a_cbd[id] += (f & PF_DIFF) ? 1 : 0;
      if (f & PF_LEFT_X)
        dacpo_uf_union(w->a_par[(f & PF_LEFT_SAME) ? 0 : 1], id, w->atom[p - 1]);
      if (f & PF_UP_X)
        dacpo_uf_union(w->a_par[(f & PF_UP_SAME) ? 0 : 1], id, w->atom[p - N]);
      if (image != NULL) {
        uint8_t code = cp;
        if (f & (PF_SAME | PF_DIFF))
          code |= DACPO_VCR_PIXEL_BOUNDARY;
        image[p] = code;
      }
      w->flags[p] = 0;
    }

  return K;
}

/* Step 5: per labelling (as given / b inverted), the sub-regions holding both
 * meshes and their score I = C_B * C1 * C2 (Eq. 6). */
static void
view_regions(vcr_work* w, const dacpo_vcr_params* prm, int32_t K, view_result* res)
{
  const size_t N = w->N;
  /* 5. per labelling: sub-region sums, I = C_B * C1 * C2 (Eq. 6) */
  const double n1 = (double)N, n2 = (double)N * (double)N;
  for (int lab = 0; lab < 2; ++lab) {
    int32_t* par = w->a_par[lab];
    memset(w->acc_c1, 0, (size_t)K * sizeof(int32_t));
    memset(w->acc_c2, 0, (size_t)K * sizeof(int32_t));
    memset(w->acc_cb, 0, (size_t)K * sizeof(int32_t));
    for (int32_t k = 0; k < K; ++k) {
      int32_t r = dacpo_uf_find(par, k);
      if (w->a_blk[k])
        w->acc_c2[r] += w->a_cnt[k];
      else
        w->acc_c1[r] += w->a_cnt[k];
      w->acc_cb[r] += lab == 0 ? w->a_cbs[k] : w->a_cbd[k];
    }
    double sum = 0.0;
    size_t regions = 0;
    for (int32_t k = 0; k < K; ++k) {
      if (par[k] != k || w->acc_c1[k] == 0 || w->acc_c2[k] == 0)
        continue;
      ++regions;
      double I = ((double)w->acc_c1[k] / n2) * ((double)w->acc_c2[k] / n2);
      if (prm->boundary_factor)
        I *= (double)w->acc_cb[k] / n1;
      sum += I;
    }
    if (lab == 0) {
      res->alpha = sum;
      res->regions[0] = regions;
    }
    else {
      res->alpha_bar = sum;
      res->regions[1] = regions;
    }
  }
}

/* Steps 3-5 of one view on the drawn image. */
static void
view_passes(vcr_work* w,
            const dacpo_vcr_params* prm,
            double radius,
            view_result* res,
            uint8_t* image)
{
  const double eta = view_eta(w, prm);
  view_close_seams(w, res->gap);
  /* float depths: allow a few ulps of the scene size on top of eta */
  view_atoms(w, eta + 1e-5 * radius, res);
  const int32_t K = view_compact_atoms(w, image);
  view_regions(w, prm, K, res);
  res->eta = eta;
}

/* One view: steps 1-5 of the file comment. Returns 0 (and 0 contributions)
 * when the projection is degenerate or nothing is drawn. images: NULL or N*N
 * bytes. */
static int
run_view(vcr_work* w,
         const dacpo_vcr_params* prm,
         const double centre[3],
         double radius,
         const double d[3],
         view_result* res,
         uint8_t* image)
{
  memset(res, 0, sizeof(*res));
  view_camera cam;
  cam.d = d;
  cam.persp = prm->perspective != 0;
  cam.dist = 2.0 * radius;
  orthonormal_basis(d, cam.u, cam.v);
  for (int k = 0; k < 3; ++k)
    cam.eye[k] = cam.persp ? centre[k] - cam.dist * d[k] : 0.0;
  size_t gap = 0;
  if (!view_project(w, prm, centre, radius, &cam, &gap))
    return 0;
  res->gap = gap;
  if (!view_rasterize(w, &cam))
    return 0;
  view_passes(w, prm, radius, res, image);
  return 1;
}

/* The view opposite to the last one run_view drew (orthographic, with the far
 * image kept; near_drawn: what run_view returned): the same pixels, the
 * farthest triangle of each, facings turned. The image is the mirror of
 * what a camera looking along -d would see, which no pass can tell: they
 * count pixels and their 4-neighbours only. */
static void
run_opposite_view(vcr_work* w,
                  const dacpo_vcr_params* prm,
                  double radius,
                  const double d[3],
                  int near_drawn,
                  const view_result* near,
                  view_result* res,
                  uint8_t* image)
{
  memset(res, 0, sizeof(*res));
  res->gap = near->gap;
  if (!near_drawn)
    return; /* nothing to see from this side either */
  dacpo_raster_take_far(&w->r, w->drawn[0], w->drawn[1], w->drawn[2], w->drawn[3]);
  for (size_t t = 0; t < w->nt; ++t) {
    const double* n = &w->tri_normal[3 * t];
    w->back[t] = d[0] * n[0] + d[1] * n[1] + d[2] * n[2] > 0.0 ? 1 : 0;
  }
  for (size_t i = 0; i < w->nv; ++i)
    if (w->used[i])
      w->vdepth[i] = -w->vdepth[i];
  view_owned(w, 0);
  view_passes(w, prm, radius, res, image);
}

/* For orthographic views: opposite[j] = the view exactly opposite to j (j if
 * none). NULL for perspective views (their cameras see different sides of
 * the pair), beyond 12 views (the spiral's directions have no exact
 * opposites: only the icosahedron's come in pairs), when no view has an
 * opposite, or without memory (every view is then drawn on its own). */
static size_t*
opposite_views(const double* dirs, size_t num_views, int perspective)
{
  if (perspective || num_views > 12)
    return NULL;
  size_t* opposite = (size_t*)dacpo_malloc_array(num_views, sizeof(size_t));
  if (opposite == NULL)
    return NULL;
  int any = 0;
  for (size_t j = 0; j < num_views; ++j) {
    opposite[j] = j;
    for (size_t i = 0; i < num_views && opposite[j] == j; ++i) {
      const double* a = dirs + 3 * j;
      const double* b = dirs + 3 * i;
      if (a[0] == -b[0] && a[1] == -b[1] && a[2] == -b[2] && i != j)
        opposite[j] = i, any = 1;
    }
  }
  if (!any) {
    free(opposite);
    return NULL;
  }
  return opposite;
}

/* The parameters dacpo_vcr_edge accepts. */
static dacpo_status
vcr_check_params(const dacpo_vcr_params* p, dacpo_err* err)
{
  DACPO_CHECK(err,
              p->image_size >= 8 && p->image_size <= VCR_MAX_IMAGE,
              DACPO_ERR_INVALID_ARGUMENT,
              "vcr: image_size %zu outside [8, %d]",
              p->image_size,
              VCR_MAX_IMAGE);
  DACPO_CHECK(err,
              p->num_views >= 1 && p->num_views <= VCR_MAX_VIEWS,
              DACPO_ERR_INVALID_ARGUMENT,
              "vcr: num_views %zu outside [1, %d]",
              p->num_views,
              VCR_MAX_VIEWS);
  DACPO_CHECK(err,
              p->perspective == 0 || p->perspective == 1,
              DACPO_ERR_INVALID_ARGUMENT,
              "vcr: perspective must be 0 or 1 (got %d)",
              p->perspective);
  DACPO_CHECK(err,
              p->boundary_factor == 0 || p->boundary_factor == 1,
              DACPO_ERR_INVALID_ARGUMENT,
              "vcr: boundary_factor must be 0 or 1 (got %d)",
              p->boundary_factor);
  DACPO_CHECK(
      err,
      p->gap_fill <= 32 && 4 * (p->gap_fill + 1) < p->image_size,
      DACPO_ERR_INVALID_ARGUMENT,
      "vcr: gap_fill %zu too large for image_size %zu (max min(32, size/4 - 1))",
      p->gap_fill,
      p->image_size);
  DACPO_CHECK(err,
              p->gap_fill_edges >= 0.0 && p->gap_fill_edges <= 100.0,
              DACPO_ERR_INVALID_ARGUMENT,
              "vcr: gap_fill_edges %g outside [0, 100]",
              p->gap_fill_edges);
  return DACPO_OK;
}

/* Marks the used vertices, computes face normals and centres and the median
 * edge; centre and radius of the union bounding box. */
static void
vcr_prepare(vcr_work* w, double centre[3], double* radius_out)
{
  /* used vertices, union bounding box, face normals and centres */
  double lo[3] = {INFINITY, INFINITY, INFINITY},
         hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t t = 0; t < w->nt; ++t) {
    const double* p[3];
    for (int k = 0; k < 3; ++k) {
      size_t gv = corner(w, t, k);
      w->used[gv] = 1;
      p[k] = vertex_of(w, gv);
      for (int c = 0; c < 3; ++c) {
        lo[c] = p[k][c] < lo[c] ? p[k][c] : lo[c];
        hi[c] = p[k][c] > hi[c] ? p[k][c] : hi[c];
      }
    }
    double e1[3], e2[3];
    for (int c = 0; c < 3; ++c) {
      e1[c] = p[1][c] - p[0][c];
      e2[c] = p[2][c] - p[0][c];
      w->tri_centre[3 * t + (size_t)c] = (p[0][c] + p[1][c] + p[2][c]) / 3.0;
    }
    w->tri_normal[3 * t + 0] = e1[1] * e2[2] - e1[2] * e2[1];
    w->tri_normal[3 * t + 1] = e1[2] * e2[0] - e1[0] * e2[2];
    w->tri_normal[3 * t + 2] = e1[0] * e2[1] - e1[1] * e2[0];
  }
  w->edge_len = median_edge_length(w);
  double radius = 0.0;
  for (int c = 0; c < 3; ++c) {
    centre[c] = 0.5 * (lo[c] + hi[c]);
    radius += 0.25 * (hi[c] - lo[c]) * (hi[c] - lo[c]);
  }
  radius = sqrt(radius);

  *radius_out = radius;
}

/* What one view contributed, for a dacpo_vcr_trace. */
static void
view_stats(const view_result* res, const double dir[3], dacpo_vcr_view_stats* vs)
{
  for (int c = 0; c < 3; ++c)
    vs->direction[c] = dir[c];
  vs->eta = res->eta;
  vs->pixels_a = res->pix[0];
  vs->pixels_b = res->pix[1];
  vs->cross_same = res->cross_same;
  vs->cross_diff = res->cross_diff;
  vs->regions = res->regions[0];
  vs->regions_bar = res->regions[1];
  vs->alpha = res->alpha;
  vs->alpha_bar = res->alpha_bar;
  vs->gap_pixels = res->gap;
}

/* Every view's contributions summed into sum_a, sum_b (and its statistics
 * and image in views, images when given); views j and opposite[j] > j share
 * one rasterization. Without memory for the far image, every view is drawn
 * on its own (the same result up to the mirror's pixel grid). */
static void
vcr_views(vcr_work* w,
          const dacpo_vcr_params* prm,
          const double* dirs,
          const double centre[3],
          double radius,
          dacpo_vcr_view_stats* views,
          uint8_t* images,
          double* sum_a,
          double* sum_b)
{
  size_t* opposite = opposite_views(dirs, prm->num_views, prm->perspective);
  dacpo_err ignored;
  if (opposite != NULL && dacpo_raster_keep_far(&w->r, &ignored) != DACPO_OK) {
    free(opposite);
    opposite = NULL;
  }
  const size_t npix = w->N * w->N;
  for (size_t j = 0; j < prm->num_views; ++j) {
    if (opposite != NULL && opposite[j] < j)
      continue; /* drawn with its opposite */
    view_result res;
    dacpo_raster_clear(&w->r);
    const int drawn = run_view(
        w, prm, centre, radius, &dirs[3 * j], &res, images ? images + j * npix : NULL);
    *sum_a += res.alpha;
    *sum_b += res.alpha_bar;
    if (views != NULL)
      view_stats(&res, &dirs[3 * j], &views[j]);
    const size_t o = opposite != NULL ? opposite[j] : j;
    if (o == j)
      continue;
    view_result ores;
    run_opposite_view(w,
                      prm,
                      radius,
                      &dirs[3 * o],
                      drawn,
                      &res,
                      &ores,
                      images ? images + o * npix : NULL);
    *sum_a += ores.alpha;
    *sum_b += ores.alpha_bar;
    if (views != NULL)
      view_stats(&ores, &dirs[3 * o], &views[o]);
  }
  free(opposite);
}

dacpo_status
dacpo_vcr_edge(const dacpo_mesh* a,
               const dacpo_mesh* b,
               const dacpo_vcr_params* params,
               double* alpha,
               double* alpha_bar,
               dacpo_vcr_trace* trace,
               dacpo_err* err)
{
  DACPO_CHECK(err,
              alpha != NULL && alpha_bar != NULL,
              DACPO_ERR_INVALID_ARGUMENT,
              "vcr: alpha and alpha_bar must not be NULL");
  dacpo_vcr_view_stats* views = trace ? trace->views : NULL;
  uint8_t* images = trace ? trace->images : NULL;
  dacpo_vcr_params prm;
  if (params != NULL)
    prm = *params;
  else
    dacpo_vcr_params_default(&prm);
  *alpha = 0.0;
  *alpha_bar = 0.0;
  DACPO_TRY(vcr_check_params(&prm, err));
  DACPO_TRY(check_mesh(a, "a", err));
  DACPO_TRY(check_mesh(b, "b", err));
  if (views != NULL)
    memset(views, 0, prm.num_views * sizeof(*views));
  if (images != NULL)
    memset(images, 0, prm.num_views * prm.image_size * prm.image_size);
  if (a->num_triangles == 0 || b->num_triangles == 0)
    return DACPO_OK; /* no region can span both blocks */

  vcr_work w;
  memset(&w, 0, sizeof(w));
  w.N = prm.image_size;
  w.m[0] = a;
  w.m[1] = b;
  w.na_t = a->num_triangles;
  w.nt = a->num_triangles + b->num_triangles;
  w.na_v = a->num_vertices;
  w.nv = a->num_vertices + b->num_vertices;
  double* dirs = (double*)dacpo_malloc_array(3 * prm.num_views, sizeof(double));
  dacpo_status st = dirs == NULL ? DACPO_OOM(err) : work_alloc(&w, err);
  if (st != DACPO_OK) {
    free(dirs);
    work_free(&w);
    return st;
  }
  dacpo_vcr_view_directions(prm.num_views, dirs);

  double centre[3], radius;
  vcr_prepare(&w, centre, &radius);

  double sum_a = 0.0, sum_b = 0.0;
  if (radius > 0.0 && isfinite(radius))
    vcr_views(&w, &prm, dirs, centre, radius, views, images, &sum_a, &sum_b);
  free(dirs);
  work_free(&w);
  *alpha = sum_a;
  *alpha_bar = sum_b;
  return DACPO_OK;
}
